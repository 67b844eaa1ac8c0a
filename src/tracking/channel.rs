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
//! Lock windows (100 ms) drive the lock detector (C/N0, phase-lock indicator and correlation
//! shape, with hysteresis: see [`super::lock::LockDetector`]); C/N0 is reported from longer
//! windows (1 s), from the lock windows until the first of those ([`Channel::cn0_estimate`]
//! says which, and whether the noise estimate hit the quantization floor).
//!
//! # Cross-correlation
//! A channel handed a strong satellite's cross-correlation (a false detection) tracks it as it
//! would a signal. Its supervisor, which has all channels, passes the other channels'
//! [`Channel::probe`]s to [`Channel::check_cross_correlation`] after each block: a channel
//! whose prompt power the stronger channels' cross-correlation explains (at their code lags
//! and Doppler offsets, [`super::xcorr`]) for
//! [`ChannelConfig::cross_correlation_windows`] lock windows in a row releases itself before
//! its lock detector (which needs [`ChannelConfig::lock_windows_to_declare`] good windows)
//! declares a lock.

use super::acquisition::{KnownSignal, SearchResult};
use super::cn0::{PowerWindow, WindowEstimate};
pub use super::config::ChannelConfig;
use super::lock::{BitSync, LockDetector};
use super::loops::{costas_cycles, dll_chips, dll_correction, fll_hz, CarrierLoop};
pub use super::refine::{
    refine_frequency, refine_frequency_and_rate, REFINEMENT_EPOCHS, REFINEMENT_RANGE_HZ,
};
use super::xcorr::{cross_correlation_source, CrossCorrelationTest, SignalProbe};
use crate::error::{Error, ErrorKind};
use crate::signal::bitwise::BitCorrelatorError;
use crate::signal::ca_code::{Prn, CA_CHIP_RATE_HZ, GPS_L1_HZ};
use crate::signal::correlator::{Correlator, EpochCorrelations, Iq, Taps};
use crate::signal::nco::{NcoSteering, SteeringError};
use crate::signal::SignalError;
use crate::signal::{Correlate, CorrelationBlock};

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
    /// Signal present, code tracked: C/N0 above threshold on a correlation peak for
    /// [`ChannelConfig::lock_windows_to_declare`] lock windows (and not released as a
    /// cross-correlation).
    pub code: bool,
    /// Carrier phase tracked (modulo the data-bit half cycle), with the code lock.
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

/// The channel's C/N0 estimate and what it rests on.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Cn0Estimate {
    /// C/N0, dB-Hz (0 before the first window).
    pub cn0_dbhz: f32,
    /// Seconds of samples the estimate rests on (a lock window before the first long window).
    pub window_s: f32,
    /// From a long (C/N0) window rather than a short lock window.
    pub long_window: bool,
    /// The noise tap read no more than the samples' quantization explains (a noise-free
    /// recording): the C/N0 is the signal over the rounding noise, the floor used when the
    /// tap read less ([`super::cn0::QUANTIZATION_MARGIN`]).
    pub quantization_limited: bool,
}

/// Cross-correlation bookkeeping of a channel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct CrossCorrelationWatch {
    /// Lock windows completed since the hand-over.
    windows: u32,
    /// The last completed lock window's estimate.
    last: Option<WindowEstimate>,
    /// Window last judged by [`Channel::check_cross_correlation`].
    judged: u32,
    /// Windows in a row explained as a cross-correlation.
    explained: u8,
}

/// Lock windows after the hand-over in which every window is judged for cross-correlation
/// (a channel handed a false detection tracks the cross-correlation from the start).
const CROSS_CORRELATION_SETTLING_WINDOWS: u32 = 10;
/// After settling, one lock window in this many is judged (the test costs about a million
/// instructions per channel on a Cortex-M4F: judging every 100 ms window was a sixth of the
/// whole receiver's time).
const CROSS_CORRELATION_SETTLED_EVERY: u32 = 10;

/// Doppler uncertainty of a tracking channel for the cross-correlation test, Hz.
const TRACKING_DOPPLER_TOLERANCE_HZ: f32 = 25.0;

/// Code-phase uncertainty of a tracking channel for the cross-correlation test (the DLL sits
/// within a fraction of a chip of the correlation's peak), chips.
const TRACKING_LAG_TOLERANCE_CHIPS: f64 = 0.25;

/// One satellite's channel, on the correlator `C` ([`Correlate`]: the `i8` [`Correlator`] by
/// default, or the bit-parallel
/// [`BitCorrelator`](crate::signal::bitwise::BitCorrelator) for 1- and 2-bit samples; the
/// loops, windows and lock detectors are the same for both).
#[derive(Clone, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Channel<const A: usize, C = Correlator<A>> {
    config: ChannelConfig,
    correlator: C,
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
    cn0: Cn0Estimate,
    acquired_doppler: f32,
    squares: [[f32; 2]; REFINEMENT_EPOCHS],
    /// Receiver sample the correlator processes next.
    next_sample: u64,
    /// The blocks carry complex samples.
    complex: bool,
    watch: CrossCorrelationWatch,
    /// The 1 ms path's constants, f32 and integer (f64 is soft float on the M4F).
    rates: Rates,
}

/// What the loops need of the sample rate every period, computed once.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct Rates {
    /// Loop outputs → NCO words.
    steering: NcoSteering,
    /// Sample rate, Hz.
    sample_rate_hz: f32,
    /// The early/late offset, chips (the correlator's whole samples at the nominal rate).
    early_late_offset_chips: f32,
}

/// The discriminator outputs of one epoch (reference antenna).
#[derive(Clone, Copy, Debug)]
struct Discriminators {
    /// Costas phase error, cycles.
    phase: f32,
    /// FLL frequency error, Hz.
    frequency: f32,
    /// DLL code error, chips.
    code: f32,
}

impl<const A: usize> Channel<A> {
    /// An idle channel for `prn` on the `i8` correlator.
    ///
    /// # Errors
    /// [`TrackingError::InvalidConfig`] / [`TrackingError::NonFinite`] for bad loop
    /// parameters, [`TrackingError::Signal`] for a bad front-end configuration.
    pub fn new(prn: Prn, config: &ChannelConfig) -> Result<Self, TrackingError> {
        Self::with_settings(prn, config, &())
    }
}

impl<const A: usize, C: Correlate<A>> Channel<A, C> {
    /// An idle channel for `prn` on the correlator `C` with its front-end `settings` (`()`
    /// for the `i8` correlator, a [`BitSettings`](crate::signal::BitSettings) for the
    /// bit-parallel one).
    ///
    /// # Errors
    /// [`TrackingError::InvalidConfig`] / [`TrackingError::NonFinite`] for bad loop
    /// parameters; the correlator's error ([`TrackingError::Signal`],
    /// [`TrackingError::Bitwise`]) for a front-end configuration it refuses.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub fn with_settings(
        prn: Prn,
        config: &ChannelConfig,
        settings: &C::Settings,
    ) -> Result<Self, TrackingError> {
        config.validate()?;
        let correlator = C::new(prn, &config.correlator(), settings).map_err(Into::into)?;
        let steering = NcoSteering::new(config.sample_rate_hz, config.intermediate_frequency_hz)
            .map_err(|e| match e {
                SteeringError::NonFinite => TrackingError::NonFinite,
                _ => TrackingError::InvalidConfig,
            })?;
        let rates = Rates {
            steering,
            sample_rate_hz: config.sample_rate_hz as f32,
            early_late_offset_chips: correlator.early_late_offset_samples() as f32
                * (CA_CHIP_RATE_HZ / config.sample_rate_hz) as f32,
        };
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
            lock: LockDetector::new(&config.lock_thresholds()),
            bit_sync: BitSync::default(),
            bit_sum: 0,
            cn0: Cn0Estimate::default(),
            acquired_doppler: 0.0,
            squares: [[0.0; 2]; REFINEMENT_EPOCHS],
            next_sample: 0,
            complex: true,
            watch: CrossCorrelationWatch::default(),
            rates,
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
    pub fn correlator(&self) -> &C {
        &self.correlator
    }

    /// The C/N0 estimate with what it rests on.
    pub fn cn0_estimate(&self) -> Cn0Estimate {
        self.cn0
    }

    /// Whether the channel released itself as another satellite's cross-correlation (it
    /// reports no lock until the next hand-over).
    pub fn is_cross_correlation(&self) -> bool {
        self.lock.held()
    }

    /// Hands over an acquisition: tracking starts at the first sample of the next block given
    /// to [`Channel::process`], with the code phase propagated from the acquisition's first
    /// sample at the acquired Doppler.
    ///
    /// # Errors
    /// [`TrackingError::WrongPrn`] for another PRN's result, [`TrackingError::NonFinite`],
    /// [`TrackingError::DopplerOutOfRange`] beyond [`MAX_HANDOVER_DOPPLER_HZ`].
    pub fn start(&mut self, acquisition: &SearchResult) -> Result<(), TrackingError> {
        if acquisition.prn != self.prn() {
            return Err(TrackingError::WrongPrn);
        }
        if !(acquisition.doppler_hz.is_finite() && acquisition.code_phase_chips.is_finite()) {
            return Err(TrackingError::NonFinite);
        }
        if !(acquisition.doppler_hz.abs() <= MAX_HANDOVER_DOPPLER_HZ) {
            return Err(TrackingError::DopplerOutOfRange);
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
    /// cursor beyond the block (the channel is then unchanged); the correlator's error for a
    /// block it cannot read (bit planes of another format or code table:
    /// [`TrackingError::Bitwise`]).
    pub fn process(
        &mut self,
        block: &C::Block<'_>,
        cursor: &mut usize,
    ) -> Result<Option<TrackingEpoch<A>>, TrackingError> {
        self.process_in(block, cursor, &mut C::Scratch::default())
    }

    /// [`Self::process`] with the correlator's working memory `scratch`
    /// ([`Correlate::run_in`]), which channels that run in turn share.
    ///
    /// # Errors
    /// As [`Self::process`].
    pub fn process_in(
        &mut self,
        block: &C::Block<'_>,
        cursor: &mut usize,
        scratch: &mut C::Scratch,
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
        self.complex = block.is_complex();
        let run = self.correlator.run_in(block, cursor, scratch);
        self.next_sample = block.first_sample().wrapping_add(*cursor as u64);
        let Some(c) = run.map_err(Into::into)? else {
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
        correlator
            .set_code_phase(f64::from(acq.code_phase_chips) + dt * rate)
            .and_then(|()| correlator.set_code_rate(rate))
            .and_then(|()| {
                correlator.set_carrier_frequency(self.config.intermediate_frequency_hz + doppler)
            })
            .map_err(Into::into)?;
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
        self.cn0 = Cn0Estimate::default();
        self.next_sample = now;
        self.watch = CrossCorrelationWatch::default();
        Ok(())
    }

    /// The loops at the end of a complete code period (reference antenna = index 0): the
    /// discriminators, the loop filters steering the NCOs, the lock and C/N0 windows, the
    /// state, the data bit.
    fn close_loops(&mut self, c: EpochCorrelations<A>) -> TrackingEpoch<A> {
        let t = c.samples as f32 / self.rates.sample_rate_hz;
        let doppler_now = self.carrier_frequency_hz();
        let reference = c.taps.first().copied().unwrap_or_default();
        let p = reference.prompt;
        let d = self.discriminators(&reference, t);
        let since = (self.index as usize).saturating_sub(REFINEMENT_EPOCHS) as u32;
        let pulling = self.state == ChannelState::Refining || since < self.config.pull_in_ms;
        let steered = self.steer(&p, &d, t, pulling);
        self.previous_prompt = Some(p);
        self.update_windows(&reference, c.samples, t);
        self.update_state(steered, pulling);
        let data_bit = self.data_bit(p.i);
        let out = TrackingEpoch {
            prn: self.prn(),
            index: self.index,
            correlations: c,
            doppler_hz: doppler_now,
            cn0_dbhz: self.cn0.cn0_dbhz,
            lock: LockFlags {
                code: self.lock.code_lock(),
                phase: self.lock.phase_lock(),
                bit_sync: self.bit_sync.edge().is_some(),
            },
            state: self.state,
            phase_error_cycles: d.phase,
            code_error_chips: d.code,
            data_bit,
        };
        self.index = self.index.saturating_add(1);
        out
    }

    /// Costas, FLL and DLL discriminators of the reference antenna's taps.
    fn discriminators(&self, reference: &Taps, t: f32) -> Discriminators {
        let p = reference.prompt;
        let offset = self.rates.early_late_offset_chips;
        Discriminators {
            phase: costas_cycles(&p),
            frequency: self
                .previous_prompt
                .map_or(0.0, |prev| fll_hz(&prev, &p, t)),
            code: dll_chips(&reference.early, &reference.late, offset),
        }
    }

    /// Loop filters → NCOs for the next period (during the refinement the carrier loop stays
    /// open). `false` when the correlator refused a setting.
    fn steer(&mut self, p: &Iq, d: &Discriminators, t: f32, pulling: bool) -> bool {
        let cfg = self.config;
        let (fll_bw, dll_bw) = if pulling {
            (cfg.fll_pull_in_bandwidth_hz, cfg.dll_pull_in_bandwidth_hz)
        } else {
            (cfg.fll_bandwidth_hz, cfg.dll_bandwidth_hz)
        };
        let doppler = if self.state == ChannelState::Refining {
            self.refinement_step(p, t)
        } else {
            self.carrier
                .update(d.phase, d.frequency, t, cfg.pll_bandwidth_hz, fll_bw)
        };
        // Code Doppler (the carrier Doppler over f_L1 / f_chip = 1540) plus the DLL correction.
        let code_rate_offset =
            doppler * (CA_CHIP_RATE_HZ / GPS_L1_HZ) as f32 + dll_correction(d.code, dll_bw);
        let steering = &self.rates.steering;
        match (
            steering.carrier_step(doppler),
            steering.code_step(code_rate_offset),
        ) {
            (Ok(carrier), Ok(code)) => self.correlator.set_nco_steps(carrier, code).is_ok(),
            _ => false,
        }
    }

    /// One epoch of the refinement stage: stores the prompt's square; at the last one, the
    /// residual Doppler and rate start the carrier loop. Returns the Doppler to steer to.
    fn refinement_step(&mut self, p: &Iq, t: f32) -> f32 {
        let (i, q) = (p.i as f32 * PROMPT_SCALE, p.q as f32 * PROMPT_SCALE);
        if let Some(z) = self.squares.get_mut(self.index as usize) {
            *z = [i * i - q * q, 2.0 * i * q];
        }
        if (self.index as usize) < REFINEMENT_EPOCHS - 1 {
            return self.acquired_doppler;
        }
        // Residual at the window's centre (epoch (n − 1)/2) and rate; the next epoch is
        // n − (n − 1)/2 epochs after the centre.
        let (delta, rate) =
            refine_frequency_and_rate(&self.squares, t, self.config.max_doppler_rate_hz_s);
        let ahead = 0.5 * (REFINEMENT_EPOCHS as f32 + 1.0) * t;
        self.carrier = CarrierLoop::with_rate(self.acquired_doppler + delta + rate * ahead, rate);
        self.state = ChannelState::PullIn;
        self.carrier.frequency_hz()
    }

    /// Adds the epoch to the lock and C/N0 windows; a completed lock window updates the lock
    /// detector (and the C/N0 until the first long window).
    fn update_windows(&mut self, reference: &Taps, samples: u32, t: f32) {
        let cfg = self.config;
        let floor = self.correlator.rounding_noise_per_sample(self.complex);
        self.lock_window
            .add_taps_with_floor(reference, samples, floor);
        self.cn0_window
            .add_taps_with_floor(reference, samples, floor);
        if self.lock_window.count() >= u32::from(cfg.lock_window) {
            if let Some(e) = self.lock_window.finish(t) {
                self.lock.update(&e);
                self.watch.windows = self.watch.windows.saturating_add(1);
                self.watch.last = Some(e);
                if !self.cn0.long_window {
                    self.cn0 = cn0_of(&e, t, false);
                }
            }
        }
        if self.cn0_window.count() >= u32::from(cfg.cn0_window) {
            if let Some(e) = self.cn0_window.finish(t) {
                self.cn0 = cn0_of(&e, t, true);
            }
        }
    }

    /// The state after the epoch (`steered`: the NCOs took the loops' settings).
    fn update_state(&mut self, steered: bool, pulling: bool) {
        if !steered {
            self.lock.reset();
            self.state = ChannelState::Lost;
            return;
        }
        self.state = match self.state {
            ChannelState::PullIn if !pulling && self.lock.phase_lock() => ChannelState::Tracking,
            ChannelState::Tracking if !self.lock.code_lock() => ChannelState::Lost,
            s => s,
        };
    }

    /// Bit sync and data bits (phase-locked only: the sign of I is the bit's).
    fn data_bit(&mut self, prompt_i: i32) -> Option<i8> {
        if !self.lock.phase_lock() {
            return None;
        }
        self.bit_sync.add(self.index, prompt_i);
        let edge = self.bit_sync.edge()?;
        // (each term reduced first: the sum's bound visible, the same value mod 20)
        let position = (self.index % EPOCHS_PER_BIT + EPOCHS_PER_BIT
            - u32::from(edge) % EPOCHS_PER_BIT)
            % EPOCHS_PER_BIT;
        if position == 0 {
            self.bit_sum = 0;
        }
        // (20 prompts of i32: far inside i64, the saturation never acts)
        self.bit_sum = self.bit_sum.saturating_add(i64::from(prompt_i));
        (position == EPOCHS_PER_BIT - 1).then_some(if self.bit_sum >= 0 { 1 } else { -1 })
    }

    /// The replica's current Doppler (carrier NCO frequency minus IF), Hz.
    #[allow(clippy::misnamed_getters)]
    pub fn carrier_frequency_hz(&self) -> f32 {
        self.rates
            .steering
            .doppler_hz(self.correlator.carrier().step)
    }

    /// The channel as the cross-correlation test sees it: code phase and rate at the next
    /// sample, Doppler, and the prompt's signal power over the last lock window (2⁻²⁰ units:
    /// the same for every channel on the same samples). `None` before the first window.
    pub fn probe(&self) -> Option<SignalProbe> {
        let e = self.watch.last?;
        if self.state == ChannelState::Idle {
            return None;
        }
        let code = self.correlator.code();
        Some(SignalProbe {
            prn: self.prn(),
            sample: self.next_sample,
            code_phase_chips: code.phase_chips(),
            code_chips_per_sample: code.step as f64 / 4_294_967_296.0,
            doppler_hz: self.carrier_frequency_hz(),
            power: e.signal_power,
        })
    }

    /// The satellite as a known signal for a search whose first sample is `sample` (code
    /// phase extrapolated at the current code rate), while the channel has code lock.
    pub fn known_signal_at(&self, sample: u64) -> Option<KnownSignal> {
        let probe = self.probe()?;
        self.lock.code_lock().then(|| KnownSignal {
            prn: probe.prn,
            doppler_hz: probe.doppler_hz,
            code_phase_chips: probe.code_phase_at(sample),
        })
    }

    /// Whether the lock window just completed is judged: every window while the channel
    /// settles ([`CROSS_CORRELATION_SETTLING_WINDOWS`] after the hand-over, where a false
    /// detection shows) or while windows in a row are explained, then every
    /// [`CROSS_CORRELATION_SETTLED_EVERY`]th window, staggered by PRN so that channels started
    /// together do not all run the test in the same millisecond.
    fn cross_correlation_due(&self) -> bool {
        let w = self.watch.windows;
        let stagger = u32::from(self.prn().number());
        w <= CROSS_CORRELATION_SETTLING_WINDOWS
            || self.watch.explained > 0
            || w.wrapping_add(stagger) % CROSS_CORRELATION_SETTLED_EVERY == 0
    }

    /// Whether [`Channel::check_cross_correlation`] would run its test now: a lock window
    /// completed since the last judgement, the channel is not held, and the window is due
    /// (every window while the channel settles, then one in ten). Makes no probe (no soft float on the M4F):
    /// a receiver gathers the others' [`Channel::probe`]s only when some channel needs them.
    pub fn cross_correlation_test_pending(&self) -> bool {
        self.watch.last.is_some()
            && self.state != ChannelState::Idle
            && self.watch.windows != self.watch.judged
            && !self.lock.held()
            && self.cross_correlation_due()
    }

    /// Tests the channel's last lock window against the cross-correlation of the stronger
    /// `others` (the other channels' [`Channel::probe`]s on the same samples;
    /// [`crate::tracking::xcorr`]). Once
    /// [`ChannelConfig::cross_correlation_windows`] windows in a row are explained, the
    /// channel releases itself: state [`ChannelState::Lost`], no lock until the next hand-over;
    /// returns the strongest source then. Each window is judged once.
    pub fn check_cross_correlation(&mut self, others: &[SignalProbe]) -> Option<Prn> {
        if !self.cross_correlation_test_pending() {
            return None;
        }
        let me = self.probe()?;
        self.watch.judged = self.watch.windows;
        let epoch_s = 1e-3 * f32::from(self.config.lock_window);
        let test = CrossCorrelationTest {
            epoch_aligned: true,
            doppler_tolerance_hz: TRACKING_DOPPLER_TOLERANCE_HZ,
            lag_tolerance_chips: TRACKING_LAG_TOLERANCE_CHIPS,
            coherence_hz: 1.0 / epoch_s,
            margin: self.config.cross_correlation_margin,
        };
        let verdict = cross_correlation_source(&me, others, &test);
        self.watch.explained = if verdict.explained {
            self.watch.explained.saturating_add(1)
        } else {
            0
        };
        if self.watch.explained < self.config.cross_correlation_windows {
            return None;
        }
        info!(
            "channel: PRN {=u8} released as a cross-correlation",
            self.prn().number()
        );
        self.lock.hold();
        self.state = ChannelState::Lost;
        verdict.strongest_source
    }
}

/// Scale of the prompts in the refinement's squares.
const PROMPT_SCALE: f32 = 1.0 / 65_536.0;

/// Code epochs per navigation data bit.
const EPOCHS_PER_BIT: u32 = 20;

/// The C/N0 estimate of a finished window of epochs of `t` seconds.
fn cn0_of(e: &WindowEstimate, t: f32, long_window: bool) -> Cn0Estimate {
    Cn0Estimate {
        cn0_dbhz: e.cn0_dbhz,
        window_s: e.epochs as f32 * t,
        long_window,
        quantization_limited: e.quantization_limited,
    }
}

/// Largest Doppler a hand-over ([`Channel::start`]) may carry, Hz: twice the ±50 kHz a
/// receiver in low Earth orbit sees.
pub const MAX_HANDOVER_DOPPLER_HZ: f32 = 100_000.0;

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
    /// The bit-parallel correlator refused a configuration, NCO setting or block (planes of
    /// another format, a code table of another sample rate).
    #[error("bit-parallel correlator refused")]
    Bitwise(#[from] BitCorrelatorError),
    /// A hand-over's Doppler is beyond [`MAX_HANDOVER_DOPPLER_HZ`] (no GNSS signal seen from
    /// a satellite in orbit has it; the NCOs could not be set).
    #[error("hand-over Doppler out of range")]
    DopplerOutOfRange,
}

impl Error for TrackingError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::InvalidConfig | Self::NotStarted | Self::WrongPrn | Self::DopplerOutOfRange => {
                ErrorKind::InvalidInput
            }
            Self::Signal(e) => e.kind(),
            Self::Bitwise(e) => e.kind(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The receiver gathers probes only when [`Channel::cross_correlation_test_pending`]: it
    /// must hold exactly for the windows the check judges (every window while settling, then
    /// one in ten staggered by PRN), once per window, and never for a held channel.
    #[test]
    fn a_test_is_pending_exactly_for_the_windows_the_check_judges() {
        let prn = Prn::new(23).unwrap();
        let mut channel = Channel::<3>::new(prn, &ChannelConfig::new(2.6e6, 0.0)).unwrap();
        let start = SearchResult {
            prn,
            detected: true,
            metric: 10.0,
            threshold: 2.0,
            doppler_hz: 1200.0,
            code_phase_chips: 100.0,
            first_sample: 0,
        };
        channel.start(&start).unwrap();
        assert!(!channel.cross_correlation_test_pending(), "no window yet");
        let mut judged = [false; 61];
        for (w, judged) in judged.iter_mut().enumerate().skip(1) {
            channel.watch.windows = w as u32;
            channel.watch.last = Some(WindowEstimate {
                signal_power: 1.0,
                ..WindowEstimate::default()
            });
            *judged = channel.cross_correlation_test_pending();
            // alone, nothing explains the window: the channel is kept
            assert_eq!(channel.check_cross_correlation(&[]), None);
            assert!(
                !channel.cross_correlation_test_pending(),
                "window {w} judged twice"
            );
        }
        for (w, &judged) in judged.iter().enumerate().skip(1) {
            assert_eq!(judged, w <= 10 || (w + 23) % 10 == 0, "window {w}");
        }
        channel.watch.windows += 1;
        channel.lock.hold();
        assert!(
            !channel.cross_correlation_test_pending(),
            "a held channel is never tested"
        );
    }
}
