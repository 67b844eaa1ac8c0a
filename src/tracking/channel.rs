//! One satellite's tracking channel over `A` antennas: acquisition hand-over → pull-in →
//! tracking, with the loops closed on the reference antenna (index 0) and every antenna
//! correlated with the reference NCOs' replica in the same pass (the slaved antennas need no
//! loops: they share the clock, and their carrier-phase offsets are what paper 003 estimates).
//!
//! Every complete code period (1 ms) yields a [`TrackingEpoch`]: the E/P/L/noise I/Q of each
//! antenna, stamped with the receiver sample index, the replica's code and carrier phase, the
//! Doppler, C/N0, lock flags and (after bit sync) the data bit.
//!
//! Schedule:
//! 1. **Frequency refinement** ([`REFINEMENT_EPOCHS`] = 256 ms): the carrier NCO stays at the
//!    acquired Doppler (off by up to ±250 Hz), the DLL runs (wide), and the prompts `Z_k` are
//!    stored. Squaring removes the data bits, `Z_k² ∝ e^{j2π(2δ)kT}`, and the peak of
//!    `|Σ_k Z_k² e^{−j2π(2δ)kT}|` over `δ ∈ ±250 Hz` (1 Hz grid, parabolic peak) gives the
//!    residual Doppler `δ` to about 1 Hz. A 1 ms FLL cannot do this at 35 dB-Hz: its
//!    discriminator noise is ~90 Hz rms per update, far above the PLL's ±6 Hz lock-in range.
//!    With [`ChannelConfig::max_doppler_rate_hz_s`] > 0 (LEO, [`ChannelConfig::leo`]) the
//!    same squares also give the Doppler rate ([`refine_frequency_and_rate`]): the loop then
//!    starts with that rate and the Doppler extrapolated to the next epoch.
//! 2. **Pull-in** (`pull_in_ms`): the FLL-assisted PLL starts at the refined Doppler (FLL
//!    assist and DLL wide).
//! 3. **Tracking**: FLL assist and DLL narrow (by default a pure PLL).
//!
//! Lock windows (100 ms) drive the lock detector; C/N0 is reported from longer windows (1 s).

use super::acquisition::SearchResult;
use super::cn0::PowerWindow;
pub use super::config::ChannelConfig;
use super::lock::{BitSync, LockDetector};
use super::loops::{costas_cycles, dll_chips, dll_correction, fll_hz, CarrierLoop};
pub use super::refine::{
    refine_frequency, refine_frequency_and_rate, REFINEMENT_EPOCHS, REFINEMENT_RANGE_HZ,
};

use crate::error::{Error, ErrorKind};
use crate::signal::ca_code::{Prn, CA_CHIP_RATE_HZ, GPS_L1_HZ};
use crate::signal::correlator::{Correlator, EpochCorrelations, Iq};
use crate::signal::SampleBlock;
use crate::signal::SignalError;

/// Where a channel is in its life.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ChannelState {
    /// Not started.
    Idle,
    /// Refining the acquired Doppler (carrier loop open).
    Refining,
    /// Pulling in after the refinement.
    PullIn,
    /// Tracking with phase lock.
    Tracking,
    /// Code lock lost (the loops keep running; a supervisor may re-acquire).
    Lost,
}

/// Lock flags of an epoch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LockFlags {
    /// Signal present, code tracked (C/N0 above threshold).
    pub code: bool,
    /// Carrier phase tracked (modulo the data-bit half cycle).
    pub phase: bool,
    /// Data-bit edges known.
    pub bit_sync: bool,
}

/// The output of one code period.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TrackingEpoch<const A: usize> {
    /// The satellite.
    pub prn: Prn,
    /// Complete code periods since the hand-over (this one included is `index + 1`).
    pub index: u32,
    /// E/P/L/noise I/Q of every antenna, receiver sample stamp, replica code and carrier phase
    /// at the first sample.
    pub correlations: EpochCorrelations<A>,
    /// Doppler of the replica during this epoch, Hz.
    pub doppler_hz: f32,
    /// Latest C/N0 estimate, dB-Hz (the short lock window's until the first long window).
    pub cn0_dbhz: f32,
    /// Lock flags.
    pub lock: LockFlags,
    /// Channel state after this epoch.
    pub state: ChannelState,
    /// Costas phase error of the reference antenna's prompt, cycles.
    pub phase_error_cycles: f32,
    /// DLL code error of the reference antenna, chips.
    pub code_error_chips: f32,
    /// A data bit (±1) completed with this epoch (after bit sync).
    pub data_bit: Option<i8>,
}

/// One satellite's channel.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Channel<const A: usize> {
    config: ChannelConfig,
    correlator: Correlator<A>,
    carrier: CarrierLoop,
    state: ChannelState,
    pending: Option<SearchResult>,
    index: u32,
    previous_prompt: Option<Iq>,
    lock_window: PowerWindow,
    cn0_window: PowerWindow,
    lock: LockDetector,
    bit_sync: BitSync,
    bit_sum: i64,
    cn0_dbhz: f32,
    long_estimate: bool,
    acquired_doppler: f32,
    squares: [[f32; 2]; REFINEMENT_EPOCHS],
}

impl<const A: usize> Channel<A> {
    /// An idle channel for `prn`.
    ///
    /// # Errors
    /// [`TrackingError::InvalidConfig`] / [`TrackingError::NonFinite`] for bad loop
    /// parameters, [`TrackingError::Signal`] for a bad front-end configuration.
    pub fn new(prn: Prn, config: &ChannelConfig) -> Result<Self, TrackingError> {
        config.validate()?;
        let correlator = Correlator::new(prn, &config.correlator())?;
        Ok(Self {
            config: *config,
            correlator,
            carrier: CarrierLoop::default(),
            state: ChannelState::Idle,
            pending: None,
            index: 0,
            previous_prompt: None,
            lock_window: PowerWindow::default(),
            cn0_window: PowerWindow::default(),
            lock: LockDetector::new(config.cn0_lock_threshold_dbhz, config.pld_threshold, 3),
            bit_sync: BitSync::default(),
            bit_sum: 0,
            cn0_dbhz: 0.0,
            long_estimate: false,
            acquired_doppler: 0.0,
            squares: [[0.0; 2]; REFINEMENT_EPOCHS],
        })
    }

    /// The satellite.
    pub fn prn(&self) -> Prn {
        self.correlator.prn()
    }

    /// The state.
    pub fn state(&self) -> ChannelState {
        self.state
    }

    /// The correlator (NCO state).
    pub fn correlator(&self) -> &Correlator<A> {
        &self.correlator
    }

    /// Hands over an acquisition: tracking starts at the first sample of the next block given
    /// to [`Channel::process`], with the code phase propagated from the acquisition's first
    /// sample at the acquired Doppler.
    ///
    /// # Errors
    /// [`TrackingError::WrongPrn`] for another PRN's result, [`TrackingError::NonFinite`].
    pub fn start(&mut self, acquisition: &SearchResult) -> Result<(), TrackingError> {
        if acquisition.prn != self.prn() {
            return Err(TrackingError::WrongPrn);
        }
        if !(acquisition.doppler_hz.is_finite() && acquisition.code_phase_chips.is_finite()) {
            return Err(TrackingError::NonFinite);
        }
        self.pending = Some(*acquisition);
        self.state = ChannelState::Refining;
        Ok(())
    }

    /// Correlates `block` from `*cursor` to the end of the block or of the current code
    /// period, runs the loops at a period's end and returns its epoch. Call repeatedly until
    /// the cursor reaches the block's end; the next call must pass the stream's next block.
    /// Partial periods (right after the hand-over) return `None`.
    ///
    /// # Errors
    /// [`TrackingError::NotStarted`] before [`Channel::start`]; [`TrackingError::Signal`] for a
    /// cursor beyond the block (the channel is then unchanged).
    pub fn process(
        &mut self,
        block: &SampleBlock<'_, A>,
        cursor: &mut usize,
    ) -> Result<Option<TrackingEpoch<A>>, TrackingError> {
        if self.state == ChannelState::Idle {
            return Err(TrackingError::NotStarted);
        }
        if *cursor > block.len() {
            return Err(TrackingError::Signal(
                crate::signal::SignalError::CursorOutOfRange,
            ));
        }
        if let Some(acq) = self.pending {
            let now = block.first_sample().wrapping_add(*cursor as u64);
            self.hand_over(&acq, now)?;
            self.pending = None;
        }
        let Some(c) = self.correlator.run(block, cursor)? else {
            return Ok(None);
        };
        if !c.complete {
            return Ok(None);
        }
        Ok(Some(self.close_loops(c)))
    }

    fn hand_over(&mut self, acq: &SearchResult, now: u64) -> Result<(), TrackingError> {
        let fs = self.config.sample_rate_hz;
        let doppler = f64::from(acq.doppler_hz);
        let dt = (now as i64).wrapping_sub(acq.first_sample as i64) as f64 / fs;
        let rate = CA_CHIP_RATE_HZ * (1.0 + doppler / GPS_L1_HZ);
        // On a copy: a refused setting leaves the channel unchanged.
        let mut correlator = self.correlator.clone();
        correlator.set_code_phase(f64::from(acq.code_phase_chips) + dt * rate)?;
        correlator.set_code_rate(rate)?;
        correlator.set_carrier_frequency(self.config.intermediate_frequency_hz + doppler)?;
        self.correlator = correlator;
        info!(
            "channel: PRN {=u8} handed over at {=f32} Hz",
            acq.prn.number(),
            acq.doppler_hz
        );
        self.carrier = CarrierLoop::new(acq.doppler_hz);
        self.acquired_doppler = acq.doppler_hz;
        self.index = 0;
        self.previous_prompt = None;
        self.lock_window = PowerWindow::default();
        self.cn0_window = PowerWindow::default();
        self.lock.reset();
        self.bit_sync.reset();
        self.bit_sum = 0;
        self.long_estimate = false;
        Ok(())
    }

    /// The loops at the end of a complete code period (reference antenna = index 0).
    fn close_loops(&mut self, c: EpochCorrelations<A>) -> TrackingEpoch<A> {
        let cfg = self.config;
        let t = c.samples as f32 / cfg.sample_rate_hz as f32;
        let doppler_now = self.carrier_frequency_hz();
        let reference = c.taps.first().copied().unwrap_or_default();
        let p = reference.prompt;
        let refining = self.state == ChannelState::Refining;
        let since = (self.index as usize).saturating_sub(REFINEMENT_EPOCHS) as u32;
        let pulling = refining || since < cfg.pull_in_ms;
        // Discriminators.
        let phase_err = costas_cycles(&p);
        let freq_err = self
            .previous_prompt
            .map_or(0.0, |prev| fll_hz(&prev, &p, t));
        let offset = self.correlator.early_late_offset_samples() as f32
            * (CA_CHIP_RATE_HZ / cfg.sample_rate_hz) as f32;
        let code_err = dll_chips(&reference.early, &reference.late, offset);
        // Loop filters → NCOs for the next period.
        let fll_bw = if pulling {
            cfg.fll_pull_in_bandwidth_hz
        } else {
            cfg.fll_bandwidth_hz
        };
        let dll_bw = if pulling {
            cfg.dll_pull_in_bandwidth_hz
        } else {
            cfg.dll_bandwidth_hz
        };
        let doppler = if refining {
            // Carrier loop open: keep the acquired Doppler, store the prompt's square.
            let (i, q) = (p.i as f32 / 65_536.0, p.q as f32 / 65_536.0);
            if let Some(z) = self.squares.get_mut(self.index as usize) {
                *z = [i * i - q * q, 2.0 * i * q];
            }
            if self.index as usize + 1 >= REFINEMENT_EPOCHS {
                // Residual at the window's centre (epoch (n − 1)/2) and rate; the next epoch is
                // n − (n − 1)/2 epochs after the centre.
                let (delta, rate) =
                    refine_frequency_and_rate(&self.squares, t, cfg.max_doppler_rate_hz_s);
                let ahead = 0.5 * (REFINEMENT_EPOCHS as f32 + 1.0) * t;
                self.carrier =
                    CarrierLoop::with_rate(self.acquired_doppler + delta + rate * ahead, rate);
                self.state = ChannelState::PullIn;
                self.carrier.frequency_hz()
            } else {
                self.acquired_doppler
            }
        } else {
            self.carrier
                .update(phase_err, freq_err, t, cfg.pll_bandwidth_hz, fll_bw)
        };
        let code_rate = CA_CHIP_RATE_HZ * (1.0 + f64::from(doppler) / GPS_L1_HZ)
            + f64::from(dll_correction(code_err, dll_bw));
        let steered = self
            .correlator
            .set_carrier_frequency(cfg.intermediate_frequency_hz + f64::from(doppler))
            .and_then(|()| self.correlator.set_code_rate(code_rate));
        self.previous_prompt = Some(p);
        // Lock and C/N0 windows.
        self.lock_window.add(&p, &reference.noise);
        self.cn0_window.add(&p, &reference.noise);
        if self.lock_window.count() >= u32::from(cfg.lock_window) {
            if let Some(e) = self.lock_window.finish(t) {
                self.lock.update(e.cn0_dbhz, e.phase_lock_indicator);
                if !self.long_estimate {
                    self.cn0_dbhz = e.cn0_dbhz;
                }
            }
        }
        if self.cn0_window.count() >= u32::from(cfg.cn0_window) {
            if let Some(e) = self.cn0_window.finish(t) {
                self.cn0_dbhz = e.cn0_dbhz;
                self.long_estimate = true;
            }
        }
        // State.
        if steered.is_err() {
            self.lock.reset();
            self.state = ChannelState::Lost;
        } else {
            self.state = match self.state {
                ChannelState::PullIn if !pulling && self.lock.phase_lock() => {
                    ChannelState::Tracking
                }
                ChannelState::Tracking if !self.lock.code_lock() => ChannelState::Lost,
                s => s,
            };
        }
        // Bit sync and data bits (phase-locked only: the sign of I is the bit's).
        let _ = refining;
        let mut data_bit = None;
        if self.lock.phase_lock() {
            self.bit_sync.add(self.index, p.i);
            if let Some(edge) = self.bit_sync.edge() {
                let position = (self.index + 20 - u32::from(edge)) % 20;
                if position == 0 {
                    self.bit_sum = 0;
                }
                self.bit_sum += i64::from(p.i);
                if position == 19 {
                    data_bit = Some(if self.bit_sum >= 0 { 1 } else { -1 });
                }
            }
        }
        let out = TrackingEpoch {
            prn: self.prn(),
            index: self.index,
            correlations: c,
            doppler_hz: doppler_now,
            cn0_dbhz: self.cn0_dbhz,
            lock: LockFlags {
                code: self.lock.code_lock(),
                phase: self.lock.phase_lock(),
                bit_sync: self.bit_sync.edge().is_some(),
            },
            state: self.state,
            phase_error_cycles: phase_err,
            code_error_chips: code_err,
            data_bit,
        };
        self.index = self.index.saturating_add(1);
        out
    }

    /// The replica's current Doppler (carrier NCO frequency minus IF), Hz.
    #[allow(clippy::misnamed_getters)]
    pub fn carrier_frequency_hz(&self) -> f32 {
        (self
            .correlator
            .carrier()
            .frequency_hz(self.config.sample_rate_hz)
            - self.config.intermediate_frequency_hz) as f32
    }
}

/// Errors of the tracking channel ([`crate::tracking::channel`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum TrackingError {
    /// A loop parameter or a hand-over value was NaN or infinite.
    #[error("non-finite tracking input")]
    NonFinite,
    /// A loop parameter is out of range (a bandwidth outside 0–100 Hz, an empty window).
    #[error("tracking configuration out of range")]
    InvalidConfig,
    /// The channel was asked to process samples before an acquisition was handed over.
    #[error("channel not started")]
    NotStarted,
    /// The acquisition handed over is for another PRN.
    #[error("acquisition result is for another PRN")]
    WrongPrn,
    /// The correlator refused a configuration, NCO setting or block.
    #[error("correlator refused")]
    Signal(#[from] SignalError),
}

impl Error for TrackingError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::InvalidConfig | Self::NotStarted | Self::WrongPrn => ErrorKind::InvalidInput,
            Self::Signal(e) => e.kind(),
        }
    }
}
