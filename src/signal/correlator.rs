//! The three-antenna fixed-point correlator: carrier wipe-off and code correlation with
//! integer accumulators, Early/Prompt/Late taps and a noise tap, **one replica per satellite
//! applied to every antenna in the same pass**.
//!
//! The antennas share one sample clock, so one carrier NCO and one code NCO (the reference
//! antenna's, steered by its tracking loops) generate the replica, and every antenna's samples
//! are correlated with that same replica over the same sample instants. The antennas' prompt
//! outputs `Z_P = I_P + jQ_P` (paper 003, eq. (19)) are therefore in one time scale, and their
//! phase differences are the carrier-phase differences paper 003 estimates.
//!
//! # Integration period
//! An integration ends where the prompt code phase completes a code period (1023 chips), so
//! each output covers exactly one C/A code period (1 ms, data-bit edges fall between outputs),
//! whatever the block boundaries are: [`Correlator::run`] stops at the code epoch and resumes
//! in the next call.
//!
//! # Arithmetic (the hot path is integer only)
//! Per chunk of up to [`CHUNK`] samples the replica is generated once: the carrier
//! `(c_k, s_k)` from the 256-entry table (`|c|, |s| ≤ 127`), the code `±1` at the prompt phase
//! with early and late copies shifted by `d` samples, and a noise code (the prompt code delayed
//! by a *quiet offset*, where the PRN's autocorrelation is −1/1023 on both sides, see
//! [`quiet_offset_chips`](super::ca_code::quiet_offset_chips)). Then for each antenna
//!
//! ```text
//! m_I = x_I c + x_Q s,   m_Q = x_Q c − x_I s            (x · e^{−jφ}, i16)
//! I_T += m_I · code_T,   Q_T += m_Q · code_T             (T = E, P, L, N; i32)
//! ```
//! (real samples: `m_I = x c`, `m_Q = −x s`).
//!
//! # Overflow analysis
//! Decoded samples are `i8`, so `|x| ≤ 128`; the table has `|c| + |s| ≤ 180` (checked by a
//! test over all 256 entries). Hence `|m_I|, |m_Q| ≤ 128 · 180 = 23 040 < 2¹⁵`: the mixed
//! values fit `i16` (complex and real). An accumulator adds at most
//! [`MAX_SAMPLES_PER_EPOCH`] `= 65 536` of them: `|I_T| ≤ 65 536 · 23 040 = 1.51·10⁹ < 2³¹`.
//! The correlator refuses code rates that would make an epoch longer than that (which caps the
//! sample rate at [`MAX_SAMPLE_RATE_HZ`] = 64 MHz), so no accumulator can overflow on any
//! input. A test drives the worst-case sample sequence through a 65 536-sample epoch and
//! compares with 64-bit sums.
//!
//! # Scale
//! An output is `127 · Σ x_k e^{−jφ_k} c_k` in sample units (127 is the carrier table's
//! amplitude, [`CARRIER_AMPLITUDE`](super::nco::CARRIER_AMPLITUDE)). Its difference from the
//! exact `Σ x_k e^{−jφ_k} c_k` (f64) is at most
//! [`CARRIER_REPLICA_MAX_ERROR`](super::nco::CARRIER_REPLICA_MAX_ERROR) `· Σ|x_k|` (the code
//! is exact: it uses the same 32.32 phase).

use super::block::SampleBlock;
use super::ca_code::{Prn, CA_CHIP_RATE_HZ, QUIET_OFFSET_CHIPS};
use super::kernels::{
    correlate_antenna, correlate_prompt, fill_carrier, fill_code, Replica, Scratch,
};
use super::nco::{CarrierNco, CodeNco, CODE_WRAP};
use crate::error::{Error, ErrorKind};

/// Samples per replica chunk (the replica buffers live on the stack: about 2.5 KiB).
pub const CHUNK: usize = 256;

/// Largest early/late offset, samples.
pub const MAX_EARLY_LATE_OFFSET: usize = 128;

/// Largest number of samples in one integration (one code period); see the overflow analysis.
pub const MAX_SAMPLES_PER_EPOCH: u64 = 65_536;

/// Largest sample rate the correlator accepts, Hz.
pub const MAX_SAMPLE_RATE_HZ: f64 = 64.0e6;

/// Smallest sample rate the correlator accepts, Hz (one sample per chip).
pub const MIN_SAMPLE_RATE_HZ: f64 = CA_CHIP_RATE_HZ;

/// One complex correlator output, `I + jQ`, in the scale described in the module docs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Iq {
    /// In-phase sum.
    pub i: i32,
    /// Quadrature sum.
    pub q: i32,
}

impl Iq {
    /// `I² + Q²` as f32.
    pub fn power(&self) -> f32 {
        let (i, q) = (self.i as f32, self.q as f32);
        i * i + q * q
    }

    /// `|I + jQ|` as f32.
    pub fn magnitude(&self) -> f32 {
        crate::sqrtf(self.power())
    }
}

/// The four taps of one antenna.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Taps {
    /// Early tap (replica advanced by the early/late offset).
    pub early: Iq,
    /// Prompt tap.
    pub prompt: Iq,
    /// Late tap (replica delayed by the early/late offset).
    pub late: Iq,
    /// Noise tap (replica delayed by the PRN's quiet offset: noise only).
    pub noise: Iq,
}

impl Taps {
    fn from_acc(a: &[i32; 8]) -> Self {
        Self {
            early: Iq { i: a[0], q: a[1] },
            prompt: Iq { i: a[2], q: a[3] },
            late: Iq { i: a[4], q: a[5] },
            noise: Iq { i: a[6], q: a[7] },
        }
    }
}

/// The correlations of one code period, all antennas.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EpochCorrelations<const A: usize> {
    /// Taps per antenna, index = antenna (0 is the reference).
    pub taps: [Taps; A],
    /// Samples integrated.
    pub samples: u32,
    /// Receiver sample index of the first sample integrated.
    pub first_sample: u64,
    /// Prompt code phase at the first sample, 2⁻³² chip.
    pub code_phase_at_first: u64,
    /// Total carrier phase of the replica at the first sample, 2⁻³² cycle (the low 32 bits are
    /// the NCO phase; the high bits count whole cycles since the channel started).
    pub carrier_phase_at_first: i64,
    /// Whether the integration covered a whole code period (the first one after a start or a
    /// code-phase jump may be partial).
    pub complete: bool,
}

/// Which taps the slaved antennas (index 1 and up) compute.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SlaveTaps {
    /// Early, prompt, late and noise on every antenna.
    #[default]
    All,
    /// Prompt only on the slaved antennas (their other taps read 0). Paper 003's filter needs
    /// only the slaved antennas' prompts; this more than halves their cost on the target.
    Prompt,
}

/// Configuration of a correlator (front end and tap placement).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CorrelatorConfig {
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Intermediate frequency of the samples, Hz (0 for complex baseband centred on L1; may be
    /// negative for spectrally inverted front ends).
    pub intermediate_frequency_hz: f64,
    /// Offset of the early and late taps from prompt, chips (half the early-late spacing);
    /// realized as the nearest whole number of samples (at least one).
    pub early_late_offset_chips: f32,
    /// Taps of the slaved antennas.
    pub slave_taps: SlaveTaps,
}

impl CorrelatorConfig {
    /// The early/late offset in samples this configuration realizes.
    pub fn early_late_offset_samples(&self) -> usize {
        let d = libm::round(
            f64::from(self.early_late_offset_chips) * self.sample_rate_hz / CA_CHIP_RATE_HZ,
        );
        if d.is_finite() && d >= 1.0 {
            d as usize
        } else {
            1
        }
    }

    /// The early/late offset actually realized, chips.
    pub fn realized_offset_chips(&self) -> f32 {
        (self.early_late_offset_samples() as f64 * CA_CHIP_RATE_HZ / self.sample_rate_hz) as f32
    }

    /// Checks the configuration.
    ///
    /// # Errors
    /// [`SignalError::InvalidConfig`] for a sample rate outside
    /// `[MIN_SAMPLE_RATE_HZ, MAX_SAMPLE_RATE_HZ]`, a non-finite or out-of-band IF, or an
    /// early/late offset outside (0, 1] chip or above [`MAX_EARLY_LATE_OFFSET`] samples.
    pub fn validate(&self) -> Result<(), SignalError> {
        let fs = self.sample_rate_hz;
        if !(MIN_SAMPLE_RATE_HZ..=MAX_SAMPLE_RATE_HZ).contains(&fs) {
            return Err(SignalError::InvalidConfig);
        }
        if !(self.intermediate_frequency_hz.abs() < fs) {
            return Err(SignalError::InvalidConfig);
        }
        let d = self.early_late_offset_chips;
        if !(d > 0.0 && d <= 1.0) || self.early_late_offset_samples() > MAX_EARLY_LATE_OFFSET {
            return Err(SignalError::InvalidConfig);
        }
        Ok(())
    }
}

/// The correlator of one satellite over `A` antennas.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Correlator<const A: usize> {
    prn: Prn,
    sample_rate_hz: f64,
    carrier: CarrierNco,
    /// Total carrier phase, 2⁻³² cycle (low 32 bits = `carrier.phase`).
    carrier_total: i64,
    code: CodeNco,
    offset: usize,
    slave_taps: SlaveTaps,
    noise_delay: u64,
    acc: [[i32; 8]; A],
    samples: u32,
    epoch_first_sample: u64,
    epoch_code_phase: u64,
    epoch_carrier_phase: i64,
    partial: bool,
}

impl<const A: usize> Correlator<A> {
    /// A correlator for `prn` with the NCOs at zero phase, zero carrier frequency offset and
    /// the nominal code rate.
    ///
    /// # Errors
    /// [`SignalError::InvalidConfig`] (see [`CorrelatorConfig::validate`]) or `A = 0`.
    pub fn new(prn: Prn, config: &CorrelatorConfig) -> Result<Self, SignalError> {
        config.validate()?;
        if A == 0 {
            return Err(SignalError::InvalidConfig);
        }
        let quiet = QUIET_OFFSET_CHIPS.get(prn.index()).copied().unwrap_or(6);
        // Half-way between the two quiet integer shifts.
        let noise_delay = ((u64::from(quiet) << 1) + 1) << 31;
        let mut c = Self {
            prn,
            sample_rate_hz: config.sample_rate_hz,
            carrier: CarrierNco::default(),
            carrier_total: 0,
            code: CodeNco {
                phase: 0,
                step: CodeNco::step_for(CA_CHIP_RATE_HZ, config.sample_rate_hz),
            },
            offset: config.early_late_offset_samples(),
            slave_taps: config.slave_taps,
            noise_delay,
            acc: [[0; 8]; A],
            samples: 0,
            epoch_first_sample: 0,
            epoch_code_phase: 0,
            epoch_carrier_phase: 0,
            partial: true,
        };
        c.carrier.step =
            CarrierNco::step_for(config.intermediate_frequency_hz, config.sample_rate_hz);
        Ok(c)
    }

    /// The satellite.
    pub fn prn(&self) -> Prn {
        self.prn
    }

    /// Sample rate, Hz.
    pub fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }

    /// The carrier NCO.
    pub fn carrier(&self) -> CarrierNco {
        self.carrier
    }

    /// The code NCO.
    pub fn code(&self) -> CodeNco {
        self.code
    }

    /// The early/late offset, samples.
    pub fn early_late_offset_samples(&self) -> usize {
        self.offset
    }

    /// Total carrier phase of the replica now, 2⁻³² cycle.
    pub fn carrier_phase_total(&self) -> i64 {
        self.carrier_total
    }

    /// Sets the carrier NCO frequency (IF + Doppler), Hz.
    ///
    /// # Errors
    /// [`SignalError::NonFinite`] or [`SignalError::InvalidConfig`] for `|f| ≥ f_s/2`.
    pub fn set_carrier_frequency(&mut self, frequency_hz: f64) -> Result<(), SignalError> {
        if !frequency_hz.is_finite() {
            return Err(SignalError::NonFinite);
        }
        if !(frequency_hz.abs() < 0.5 * self.sample_rate_hz) {
            return Err(SignalError::InvalidConfig);
        }
        self.carrier.step = CarrierNco::step_for(frequency_hz, self.sample_rate_hz);
        Ok(())
    }

    /// Sets the code rate, chips/s.
    ///
    /// # Errors
    /// [`SignalError::NonFinite`], or [`SignalError::InvalidConfig`] for a rate off the nominal
    /// chip rate by more than 1 % (which also keeps every epoch below
    /// [`MAX_SAMPLES_PER_EPOCH`]).
    pub fn set_code_rate(&mut self, chips_per_second: f64) -> Result<(), SignalError> {
        if !chips_per_second.is_finite() {
            return Err(SignalError::NonFinite);
        }
        if !((chips_per_second / CA_CHIP_RATE_HZ - 1.0).abs() <= 0.01) {
            return Err(SignalError::InvalidConfig);
        }
        self.set_nco_steps(
            self.carrier.step,
            CodeNco::step_for(chips_per_second, self.sample_rate_hz),
        )
    }

    /// Sets both NCO steps from their words (an [`NcoSteering`](super::nco::NcoSteering)'s):
    /// integer only, for the tracking loops.
    ///
    /// # Errors
    /// [`SignalError::InvalidConfig`] for a code step below
    /// [`MIN_CODE_STEP`](super::nco::MIN_CODE_STEP) (a period over
    /// [`MAX_SAMPLES_PER_EPOCH`] samples); the correlator is then unchanged.
    pub fn set_nco_steps(&mut self, carrier_step: u32, code_step: u64) -> Result<(), SignalError> {
        if code_step < super::nco::MIN_CODE_STEP {
            return Err(SignalError::InvalidConfig);
        }
        self.carrier.step = carrier_step;
        self.code.step = code_step;
        Ok(())
    }

    /// Sets the prompt code phase, chips (modulo 1023), discarding the integration in
    /// progress (the next output is marked partial).
    ///
    /// # Errors
    /// [`SignalError::NonFinite`].
    pub fn set_code_phase(&mut self, chips: f64) -> Result<(), SignalError> {
        if !chips.is_finite() {
            return Err(SignalError::NonFinite);
        }
        self.code.phase = CodeNco::phase_for(chips);
        self.reset_integration();
        Ok(())
    }

    /// Sets the carrier NCO phase, cycles, keeping the whole-cycle count.
    ///
    /// # Errors
    /// [`SignalError::NonFinite`].
    pub fn set_carrier_phase(&mut self, cycles: f64) -> Result<(), SignalError> {
        if !cycles.is_finite() {
            return Err(SignalError::NonFinite);
        }
        let frac = cycles - libm::floor(cycles);
        let word = (libm::round(frac * 4_294_967_296.0) as u64 & 0xffff_ffff) as u32;
        self.carrier_total = (self.carrier_total & !0xffff_ffff) | i64::from(word);
        self.carrier.phase = word;
        Ok(())
    }

    /// Discards the integration in progress; the next output is marked partial.
    pub fn reset_integration(&mut self) {
        self.acc = [[0; 8]; A];
        self.samples = 0;
        self.partial = true;
    }

    /// Correlates `block` from sample `*cursor` until the end of the block or the end of the
    /// current code period, whichever comes first, and advances `*cursor`. Returns the
    /// correlations when a code period completed (then the loops may steer the NCOs before
    /// the next call), `None` when the block ended first (the integration continues in the
    /// next call, which must pass the next block of the same sample stream).
    ///
    /// Bounded: at most one code period of samples per call.
    ///
    /// # Errors
    /// [`SignalError::CursorOutOfRange`] when `*cursor > block.len()`; the correlator is then
    /// unchanged.
    pub fn run(
        &mut self,
        block: &SampleBlock<'_, A>,
        cursor: &mut usize,
    ) -> Result<Option<EpochCorrelations<A>>, SignalError> {
        let start = *cursor;
        if start > block.len() {
            return Err(SignalError::CursorOutOfRange);
        }
        let available = (block.len() - start) as u64;
        let to_wrap = self.code.samples_to_wrap();
        let n = available.min(to_wrap) as usize;
        if n == 0 {
            return Ok(None);
        }
        if self.samples == 0 {
            self.epoch_first_sample = block.first_sample().wrapping_add(start as u64);
            self.epoch_code_phase = self.code.phase;
            self.epoch_carrier_phase = self.carrier_total;
        }
        self.correlate_span(block, start, n);
        *cursor = start.saturating_add(n); // (n ≤ len − start: never saturates)
        if (n as u64) < to_wrap {
            return Ok(None);
        }
        self.code.phase = self.code.phase.wrapping_sub(CODE_WRAP);
        let mut taps = [Taps::default(); A];
        for (t, a) in taps.iter_mut().zip(self.acc.iter()) {
            *t = Taps::from_acc(a);
        }
        let out = EpochCorrelations {
            taps,
            samples: self.samples,
            first_sample: self.epoch_first_sample,
            code_phase_at_first: self.epoch_code_phase,
            carrier_phase_at_first: self.epoch_carrier_phase,
            complete: !self.partial,
        };
        self.acc = [[0; 8]; A];
        self.samples = 0;
        self.partial = false;
        Ok(Some(out))
    }

    /// Correlates `n` samples from `start` (all within one code period).
    fn correlate_span(&mut self, block: &SampleBlock<'_, A>, start: usize, n: usize) {
        let d = self.offset.min(MAX_EARLY_LATE_OFFSET);
        let mut cos = [0i16; CHUNK];
        let mut sin = [0i16; CHUNK];
        let mut code = [0i16; CHUNK + 2 * MAX_EARLY_LATE_OFFSET];
        let mut noise = [0i16; CHUNK];
        let mut scratch = Scratch::new();
        let step = self.code.step;
        let mut done = 0usize;
        while done < n {
            let m = (n - done).min(CHUNK);
            // Shared replica: carrier, prompt code with early/late margins, noise code.
            self.carrier.phase = fill_carrier(
                cos.get_mut(..m).unwrap_or_default(),
                sin.get_mut(..m).unwrap_or_default(),
                self.carrier.phase,
                self.carrier.step,
            );
            let back = (d as u64).wrapping_mul(step) % CODE_WRAP;
            // (the phase stays below CODE_WRAP + CHUNK steps, far from 2⁶⁴: the wrapping forms
            // never wrap; a phase arithmetic modulo CODE_WRAP, as in release)
            let code_start = self.code.phase.wrapping_add(CODE_WRAP).wrapping_sub(back) % CODE_WRAP;
            fill_code(
                code.get_mut(..m + 2 * d).unwrap_or_default(),
                self.prn,
                code_start,
                step,
            );
            let noise_start = self
                .code
                .phase
                .wrapping_add(CODE_WRAP)
                .wrapping_sub(self.noise_delay % CODE_WRAP)
                % CODE_WRAP;
            fill_code(
                noise.get_mut(..m).unwrap_or_default(),
                self.prn,
                noise_start,
                step,
            );
            let replica = Replica {
                cos: cos.get(..m).unwrap_or_default(),
                sin: sin.get(..m).unwrap_or_default(),
                early: code.get(2 * d..2 * d + m).unwrap_or_default(),
                prompt: code.get(d..d + m).unwrap_or_default(),
                late: code.get(..m).unwrap_or_default(),
                noise: noise.get(..m).unwrap_or_default(),
            };
            for (a, acc) in self.acc.iter_mut().enumerate() {
                let Some((i, q)) = block.span(a, start.saturating_add(done), m) else {
                    continue;
                };
                let part = if a > 0 && self.slave_taps == SlaveTaps::Prompt {
                    correlate_prompt(i, q, &replica)
                } else {
                    correlate_antenna(i, q, &replica, &mut scratch)
                };
                for (x, p) in acc.iter_mut().zip(part.iter()) {
                    *x = x.wrapping_add(*p);
                }
            }
            self.code.phase = self.code.phase.wrapping_add((m as u64).wrapping_mul(step));
            let advance = i64::from(self.carrier.step as i32) * m as i64;
            self.carrier_total = self.carrier_total.wrapping_add(advance);
            self.samples = self.samples.saturating_add(m as u32);
            done = done.saturating_add(m);
        }
    }
}

/// Errors of the correlators and NCOs ([`crate::signal`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SignalError {
    /// A frequency, rate or phase was NaN or infinite.
    #[error("non-finite NCO input")]
    NonFinite,
    /// A configuration value is out of range: sample rate outside 1.023–64 MHz, IF beyond the
    /// sample rate, early/late offset outside (0, 1] chip, a carrier frequency beyond ±`f_s`/2,
    /// a code rate more than 1 % off nominal, or no antennas.
    #[error("correlator configuration out of range")]
    InvalidConfig,
    /// The antennas' sample slices of a block differ in length.
    #[error("antenna sample slices differ in length")]
    BlockLengthMismatch,
    /// The cursor passed to the correlator lies beyond the end of the block.
    #[error("cursor beyond the end of the sample block")]
    CursorOutOfRange,
}

impl Error for SignalError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::InvalidConfig | Self::BlockLengthMismatch | Self::CursorOutOfRange => {
                ErrorKind::InvalidInput
            }
        }
    }
}
