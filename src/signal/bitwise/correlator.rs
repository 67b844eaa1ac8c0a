//! The bit-parallel correlator of one satellite over `A` antennas: one carrier NCO and one
//! code NCO (the reference antenna's, steered by its loops) shared by every antenna, E/P/L and
//! noise taps on the reference antenna, the prompt (or all four taps) on the others.
//!
//! Same interface and output as [`Correlator`](crate::signal::Correlator): the integration
//! ends where the prompt code phase completes a code period, whatever the block boundaries;
//! [`BitCorrelator::run`] stops there and resumes in the next call; the output is an
//! [`EpochCorrelations`] with the same stamps (first sample, code and carrier phase at it,
//! sample count, completeness).

use super::block::BitBlock;
use super::carrier::{self, CarrierLevels, CarrierStep, CarrierWords};
use super::code::{self, CodeCursor, CodeTable, EXT_BYTES, MIN_TABLE_SAMPLE_RATE_HZ};
use super::kernel::{self, ChunkPlanes, StreamWords, CHUNK_WORDS, MAX_STREAMS};
use super::planes::{PlaneFormat, WORD_SAMPLES};
use crate::signal::ca_code::{Prn, CA_CHIP_RATE_HZ, QUIET_OFFSET_CHIPS};
use crate::signal::correlator::{
    CorrelatorConfig, EpochCorrelations, Iq, SlaveTaps, Taps, MAX_EARLY_LATE_OFFSET,
};
use crate::signal::nco::{CarrierNco, CodeNco, CODE_WRAP};
use crate::signal::SignalError;

/// Largest noise-tap delay, samples (the quiet offsets of all PRNs stay below it up to
/// 60 Msps).
pub const MAX_NOISE_DELAY_SAMPLES: usize = 1024;

/// Prompt words kept before a chunk for the delayed taps.
const BACK_WORDS: usize = MAX_NOISE_DELAY_SAMPLES / WORD_SAMPLES;
/// Prompt words kept after a chunk for the early tap.
const FORWARD_WORDS: usize = MAX_EARLY_LATE_OFFSET.div_ceil(WORD_SAMPLES);
/// Prompt words generated per chunk at most.
const PROMPT_WORDS: usize = CHUNK_WORDS + BACK_WORDS + FORWARD_WORDS + 1;

/// Index of the early tap in the replica words and accumulators.
const EARLY: usize = 0;
/// Index of the prompt tap.
const PROMPT: usize = 1;
/// Index of the late tap.
const LATE: usize = 2;
/// Index of the noise tap.
const NOISE: usize = 3;

/// Error returned by [`BitCorrelator`] and [`CodeTable::new`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum BitCorrelatorError {
    /// The correlator configuration is refused by its validation (see
    /// [`CorrelatorConfig::validate`]).
    #[error("correlator configuration refused")]
    Config(#[source] SignalError),
    /// A value is out of the bit-parallel correlator's range: a sample rate below
    /// [`MIN_TABLE_SAMPLE_RATE_HZ`] (two samples per chip), a noise delay above
    /// [`MAX_NOISE_DELAY_SAMPLES`], a carrier frequency beyond ±`f_s`/2, a code rate more than
    /// 1 % off nominal, or no antennas.
    #[error("value out of the bit-parallel correlator's range")]
    InvalidConfig,
    /// A frequency, rate or phase was NaN or infinite.
    #[error("non-finite NCO input")]
    NonFinite,
    /// The cursor lies beyond the end of the block.
    #[error("cursor beyond the end of the block")]
    CursorOutOfRange,
    /// The block's planes are not of the correlator's format.
    #[error("block planes of another format")]
    FormatMismatch,
    /// The block's code table is of another sample rate.
    #[error("code table of another sample rate")]
    TableMismatch,
    /// The format and carrier levels asked for are not among the kernels this correlator type
    /// was built with (its `KERNELS` parameter, [`kernel_bit`]).
    #[error("no kernel built for this plane format and carrier")]
    KernelNotBuilt,
}

impl crate::error::Error for BitCorrelatorError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::Config(e) => crate::error::Error::kind(e),
            Self::NonFinite => crate::error::ErrorKind::NonFinite,
            _ => crate::error::ErrorKind::InvalidInput,
        }
    }
}

/// Configuration of a bit-parallel correlator.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BitCorrelatorConfig {
    /// Front end and tap placement, as for the `i8` correlator.
    pub correlator: CorrelatorConfig,
    /// The planes the blocks will carry.
    pub format: PlaneFormat,
    /// Quantization of the carrier replica.
    pub carrier: CarrierLevels,
}

impl BitCorrelatorConfig {
    /// The noise tap's delay, samples: the PRN's quiet offset plus half a chip,
    /// `round((q + ½)·f_s/f_chip)` (a delay in `[q, q + 1]` chips: the autocorrelation is
    /// `−1/1023` there).
    pub fn noise_delay_samples(&self, prn: Prn) -> usize {
        let quiet = QUIET_OFFSET_CHIPS.get(prn.index()).copied().unwrap_or(6);
        let d = libm::round(
            (f64::from(quiet) + 0.5) * self.correlator.sample_rate_hz / CA_CHIP_RATE_HZ,
        );
        if d.is_finite() && d >= 1.0 {
            d as usize
        } else {
            1
        }
    }

    /// Checks the configuration for `prn`.
    ///
    /// # Errors
    /// [`BitCorrelatorError::Config`] from [`CorrelatorConfig::validate`];
    /// [`BitCorrelatorError::InvalidConfig`] for a sample rate below two samples per chip or a
    /// noise delay beyond [`MAX_NOISE_DELAY_SAMPLES`].
    pub fn validate(&self, prn: Prn) -> Result<(), BitCorrelatorError> {
        self.correlator
            .validate()
            .map_err(BitCorrelatorError::Config)?;
        if !(self.correlator.sample_rate_hz >= MIN_TABLE_SAMPLE_RATE_HZ)
            || self.noise_delay_samples(prn) > MAX_NOISE_DELAY_SAMPLES
        {
            return Err(BitCorrelatorError::InvalidConfig);
        }
        Ok(())
    }
}

/// The bit of [`BitCorrelator`]'s `KERNELS` parameter that builds the kernel of `format` with
/// the `carrier` replica: one of eight (complex or real IF × 1- or 2-bit × 2- or 3-level).
pub const fn kernel_bit(format: PlaneFormat, carrier: CarrierLevels) -> u8 {
    let three = matches!(carrier, CarrierLevels::Three);
    kernel_bit_of(format.complex, format.two_bit(), three)
}

/// [`kernel_bit`] from the kernel's three switches.
const fn kernel_bit_of(complex: bool, two_bit: bool, three: bool) -> u8 {
    1 << ((complex as u8) * 4 + (two_bit as u8) * 2 + three as u8)
}

/// Every kernel: the default of [`BitCorrelator`]'s `KERNELS`.
pub const ALL_KERNELS: u8 = u8::MAX;

/// The kernels of a complex front end with the 2-level carrier, 1- and 2-bit (the flight
/// configuration of firmware `realtime`: 11 KB less flash than [`ALL_KERNELS`]).
pub const COMPLEX_TWO_LEVEL_KERNELS: u8 =
    kernel_bit_of(true, false, false) | kernel_bit_of(true, true, false);

/// The kernel bits of the 3-level carrier.
const THREE_LEVEL_KERNELS: u8 = kernel_bit_of(false, false, true)
    | kernel_bit_of(false, true, true)
    | kernel_bit_of(true, false, true)
    | kernel_bit_of(true, true, true);

/// The bit-parallel correlator of one satellite over `A` antennas.
///
/// `KERNELS` is the set of kernels compiled in, as [`kernel_bit`]s (default: all). A firmware
/// that knows its front end names its own (e.g. [`COMPLEX_TWO_LEVEL_KERNELS`]) and the others
/// are left out of the program; [`BitCorrelator::new`] refuses a format and carrier outside
/// the set ([`BitCorrelatorError::KernelNotBuilt`]). The results of a kernel are the same in
/// every set.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BitCorrelator<const A: usize, const KERNELS: u8 = ALL_KERNELS> {
    prn: Prn,
    sample_rate_hz: f64,
    format: PlaneFormat,
    levels: CarrierLevels,
    carrier: CarrierNco,
    /// Total carrier phase, 2⁻³² cycle (low 32 bits = `carrier.phase`).
    carrier_total: i64,
    code: CodeNco,
    offset: usize,
    noise_delay: usize,
    slave_taps: SlaveTaps,
    table_step: u64,
    ext: [u8; EXT_BYTES],
    /// Population counts per antenna, tap (E, P, L, N) and stream.
    acc: [[[u32; MAX_STREAMS]; 4]; A],
    /// Samples of the `c` streams' and of the `s` streams' support.
    support: [u32; 2],
    samples: u32,
    epoch_first_sample: u64,
    epoch_code_phase: u64,
    epoch_carrier_phase: i64,
    partial: bool,
}

impl<const A: usize, const KERNELS: u8> BitCorrelator<A, KERNELS> {
    /// Whether the 3-level carrier's kernels are built (if not, the 3-level paths of the
    /// replica are left out too).
    const THREE_LEVEL_BUILT: bool = KERNELS & THREE_LEVEL_KERNELS != 0;

    /// A correlator for `prn` with the NCOs at zero phase, the configured IF and the nominal
    /// code rate.
    ///
    /// # Errors
    /// As [`BitCorrelatorConfig::validate`]; [`BitCorrelatorError::InvalidConfig`] for
    /// `A = 0`; [`BitCorrelatorError::KernelNotBuilt`] for a format and carrier outside
    /// `KERNELS`.
    pub fn new(prn: Prn, config: &BitCorrelatorConfig) -> Result<Self, BitCorrelatorError> {
        config.validate(prn)?;
        if A == 0 {
            return Err(BitCorrelatorError::InvalidConfig);
        }
        if KERNELS & kernel_bit(config.format, config.carrier) == 0 {
            return Err(BitCorrelatorError::KernelNotBuilt);
        }
        let c = &config.correlator;
        let step = CodeNco::step_for(CA_CHIP_RATE_HZ, c.sample_rate_hz);
        code::step_supported(step)?;
        Ok(Self {
            prn,
            sample_rate_hz: c.sample_rate_hz,
            format: config.format,
            levels: config.carrier,
            carrier: CarrierNco {
                phase: 0,
                step: CarrierNco::step_for(c.intermediate_frequency_hz, c.sample_rate_hz),
            },
            carrier_total: 0,
            code: CodeNco { phase: 0, step },
            offset: c.early_late_offset_samples().min(MAX_EARLY_LATE_OFFSET),
            noise_delay: config.noise_delay_samples(prn),
            slave_taps: c.slave_taps,
            table_step: step,
            ext: code::extended_code(prn),
            acc: [[[0; MAX_STREAMS]; 4]; A],
            support: [0; 2],
            samples: 0,
            epoch_first_sample: 0,
            epoch_code_phase: 0,
            epoch_carrier_phase: 0,
            partial: true,
        })
    }

    /// The satellite.
    pub fn prn(&self) -> Prn {
        self.prn
    }

    /// Sample rate, Hz.
    pub fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }

    /// The planes this correlator reads.
    pub fn format(&self) -> PlaneFormat {
        self.format
    }

    /// The carrier replica's levels.
    pub fn carrier_levels(&self) -> CarrierLevels {
        self.levels
    }

    /// The carrier NCO.
    pub fn carrier(&self) -> CarrierNco {
        self.carrier
    }

    /// The code NCO.
    pub fn code(&self) -> CodeNco {
        self.code
    }

    /// The early/late offset, samples (early = prompt advanced by it, late = delayed).
    pub fn early_late_offset_samples(&self) -> usize {
        self.offset
    }

    /// The noise tap's delay behind the prompt, samples.
    pub fn noise_delay_samples(&self) -> usize {
        self.noise_delay
    }

    /// The code step of the table the blocks must carry (the nominal step), 2⁻³² chip.
    pub fn table_step(&self) -> u64 {
        self.table_step
    }

    /// Total carrier phase of the replica now, 2⁻³² cycle.
    pub fn carrier_phase_total(&self) -> i64 {
        self.carrier_total
    }

    /// Sets the carrier NCO frequency (IF + Doppler), Hz.
    ///
    /// # Errors
    /// [`BitCorrelatorError::NonFinite`]; [`BitCorrelatorError::InvalidConfig`] for
    /// `|f| ≥ f_s/2`.
    pub fn set_carrier_frequency(&mut self, frequency_hz: f64) -> Result<(), BitCorrelatorError> {
        if !frequency_hz.is_finite() {
            return Err(BitCorrelatorError::NonFinite);
        }
        if !(frequency_hz.abs() < 0.5 * self.sample_rate_hz) {
            return Err(BitCorrelatorError::InvalidConfig);
        }
        self.carrier.step = CarrierNco::step_for(frequency_hz, self.sample_rate_hz);
        Ok(())
    }

    /// Sets the code rate, chips/s.
    ///
    /// # Errors
    /// [`BitCorrelatorError::NonFinite`]; [`BitCorrelatorError::InvalidConfig`] for a rate
    /// more than 1 % off nominal.
    pub fn set_code_rate(&mut self, chips_per_second: f64) -> Result<(), BitCorrelatorError> {
        if !chips_per_second.is_finite() {
            return Err(BitCorrelatorError::NonFinite);
        }
        if !((chips_per_second / CA_CHIP_RATE_HZ - 1.0).abs() <= 0.01) {
            return Err(BitCorrelatorError::InvalidConfig);
        }
        self.set_nco_steps(
            self.carrier.step,
            CodeNco::step_for(chips_per_second, self.sample_rate_hz),
        )
    }

    /// Sets both NCO steps from their words (an [`NcoSteering`](crate::signal::nco::NcoSteering)'s):
    /// integer only, for the tracking loops.
    ///
    /// # Errors
    /// [`BitCorrelatorError::InvalidConfig`] for a code step below
    /// [`MIN_CODE_STEP`](crate::signal::nco::MIN_CODE_STEP) or beyond the code table's reach
    /// (4/7 chip per sample); the correlator is then unchanged.
    pub fn set_nco_steps(
        &mut self,
        carrier_step: u32,
        code_step: u64,
    ) -> Result<(), BitCorrelatorError> {
        code::step_supported(code_step)?;
        if code_step < crate::signal::nco::MIN_CODE_STEP {
            return Err(BitCorrelatorError::InvalidConfig);
        }
        self.carrier.step = carrier_step;
        self.code.step = code_step;
        Ok(())
    }

    /// Sets the prompt code phase, chips (modulo 1023), discarding the integration in
    /// progress (the next output is marked partial).
    ///
    /// # Errors
    /// [`BitCorrelatorError::NonFinite`].
    pub fn set_code_phase(&mut self, chips: f64) -> Result<(), BitCorrelatorError> {
        if !chips.is_finite() {
            return Err(BitCorrelatorError::NonFinite);
        }
        self.code.phase = CodeNco::phase_for(chips);
        self.reset_integration();
        Ok(())
    }

    /// Sets the carrier NCO phase, cycles, keeping the whole-cycle count.
    ///
    /// # Errors
    /// [`BitCorrelatorError::NonFinite`].
    pub fn set_carrier_phase(&mut self, cycles: f64) -> Result<(), BitCorrelatorError> {
        if !cycles.is_finite() {
            return Err(BitCorrelatorError::NonFinite);
        }
        let frac = cycles - libm::floor(cycles);
        let word = (libm::round(frac * 4_294_967_296.0) as u64 & 0xffff_ffff) as u32;
        self.carrier_total = (self.carrier_total & !0xffff_ffff) | i64::from(word);
        self.carrier.phase = word;
        Ok(())
    }

    /// Discards the integration in progress; the next output is marked partial.
    pub fn reset_integration(&mut self) {
        self.clear_accumulators();
        self.support = [0; 2];
        self.samples = 0;
        self.partial = true;
    }

    /// [`Self::run_in`] with a scratch of its own, made (and zeroed: 3.3 KB) for this call.
    /// Where correlators run in turn (a receiver's channels), one [`BitScratch`] passed to
    /// [`Self::run_in`] serves them all.
    ///
    /// # Errors
    /// As [`Self::run_in`].
    pub fn run(
        &mut self,
        block: &BitBlock<'_, A>,
        cursor: &mut usize,
    ) -> Result<Option<EpochCorrelations<A>>, BitCorrelatorError> {
        self.run_in(block, cursor, &mut BitScratch::new())
    }

    /// Correlates `block` from sample `*cursor` until the end of the block or the end of the
    /// current code period, whichever comes first, and advances `*cursor`. Returns the
    /// correlations when a code period completed, `None` when the block ended first (the
    /// integration continues in the next call, which must pass the next block of the same
    /// sample stream).
    ///
    /// Bounded: at most one code period of samples per call. `scratch` holds only the chunk
    /// loop's words between their writing and their reading: any correlator's scratch serves
    /// (the result does not depend on what it held).
    ///
    /// # Errors
    /// [`BitCorrelatorError::CursorOutOfRange`] when `*cursor > block.len()`,
    /// [`BitCorrelatorError::FormatMismatch`] or [`BitCorrelatorError::TableMismatch`] for a
    /// block that does not fit this correlator; the correlator is then unchanged.
    pub fn run_in(
        &mut self,
        block: &BitBlock<'_, A>,
        cursor: &mut usize,
        scratch: &mut BitScratch,
    ) -> Result<Option<EpochCorrelations<A>>, BitCorrelatorError> {
        let start = *cursor;
        if start > block.len() {
            return Err(BitCorrelatorError::CursorOutOfRange);
        }
        if block.format() != self.format {
            return Err(BitCorrelatorError::FormatMismatch);
        }
        if block.table().step() != self.table_step {
            return Err(BitCorrelatorError::TableMismatch);
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
        self.correlate_span(block, start, n, scratch);
        *cursor = start.saturating_add(n); // (n ≤ len − start: never saturates)
        if (n as u64) < to_wrap {
            return Ok(None);
        }
        self.code.phase = self.code.phase.wrapping_sub(CODE_WRAP);
        let out = EpochCorrelations {
            taps: self.taps(),
            samples: self.samples,
            first_sample: self.epoch_first_sample,
            code_phase_at_first: self.epoch_code_phase,
            carrier_phase_at_first: self.epoch_carrier_phase,
            complete: !self.partial,
        };
        self.clear_accumulators();
        self.support = [0; 2];
        self.samples = 0;
        self.partial = false;
        Ok(Some(out))
    }

    /// Zeroes the accumulators of the format's streams, once per code period. The others
    /// stay zero: the format and the carrier levels are fixed at construction, and the
    /// kernels write only the format's streams (a 1-bit format's two of the eight: 96 of
    /// 384 bytes, stores in place of a `memset` call).
    fn clear_accumulators(&mut self) {
        let used = kernel::stream_count(
            self.format.complex,
            self.format.two_bit(),
            self.levels == CarrierLevels::Three,
        );
        match used {
            0..=2 => zero_streams::<2, A>(&mut self.acc),
            3..=4 => zero_streams::<4, A>(&mut self.acc),
            _ => zero_streams::<MAX_STREAMS, A>(&mut self.acc),
        }
    }

    /// The taps of the integration so far.
    fn taps(&self) -> [Taps; A] {
        let (cx, tb) = (self.format.complex, self.format.two_bit());
        let l3 = self.three_level();
        let [nc, ns] = self.support;
        let mut out = [Taps::default(); A];
        // (indices from `0..A`, not `enumerate`: its counter keeps an overflow check)
        for (a, (t, acc)) in (0..A).zip(out.iter_mut().zip(self.acc.iter())) {
            let tap = |k: usize| {
                let p = acc.get(k).copied().unwrap_or_default();
                let (i, q) = kernel::combine(cx, tb, l3, &p, nc, ns);
                Iq { i, q }
            };
            t.prompt = tap(PROMPT);
            if a == 0 || self.slave_taps == SlaveTaps::All {
                t.early = tap(EARLY);
                t.late = tap(LATE);
                t.noise = tap(NOISE);
            }
        }
        out
    }

    /// Correlates `n` samples from `start` (all within one code period), chunk by chunk.
    fn correlate_span(
        &mut self,
        block: &BitBlock<'_, A>,
        start: usize,
        n: usize,
        work: &mut BitScratch,
    ) {
        let end = start.saturating_add(n);
        let mut s = start;
        // Bounded: every pass but the last covers a whole chunk (at most 70 passes for the
        // largest epoch of 65 536 samples).
        while s < end {
            let w0 = s / WORD_SAMPLES;
            // (s < end: w1 > w0 and stop > s; saturating forms make the bounds visible)
            let w1 = (end.saturating_sub(1) / WORD_SAMPLES + 1).min(w0 + CHUNK_WORDS);
            let stop = end.min(w1.saturating_mul(WORD_SAMPLES));
            self.chunk(block, (w0, w1), (s, stop), work);
            let m = stop.saturating_sub(s) as u64;
            // (the code phase is modular: wrapped at every code period, far from 2⁶⁴)
            self.code.phase = self.code.phase.wrapping_add(m.wrapping_mul(self.code.step));
            self.carrier.phase = self
                .carrier
                .phase
                .wrapping_add(self.carrier.step.wrapping_mul(m as u32));
            let advance = i64::from(self.carrier.step as i32).wrapping_mul(m as i64);
            self.carrier_total = self.carrier_total.wrapping_add(advance);
            self.samples = self.samples.saturating_add(m as u32);
            s = stop;
        }
    }

    /// One chunk: the words `w0..w1` of the block, samples `s..stop` of them.
    fn chunk(
        &mut self,
        block: &BitBlock<'_, A>,
        (w0, w1): (usize, usize),
        (s, stop): (usize, usize),
        work: &mut BitScratch,
    ) {
        // (w0 = s / WORD_SAMPLES < w1, stop ≤ w1·WORD_SAMPLES: the saturations never act)
        let nw = w1.saturating_sub(w0).min(CHUNK_WORDS);
        let lead = s.saturating_sub(w0.saturating_mul(WORD_SAMPLES));
        let tail = w1.saturating_mul(WORD_SAMPLES).saturating_sub(stop);
        let l3 = self.three_level();
        self.carrier_words(nw, lead, tail, work);
        self.code_words(block.table(), nw, lead, tail, work);
        if l3 {
            for c in work.carrier.iter().take(nw) {
                // (support counts of one epoch, at most 2¹⁶: the saturation never acts)
                self.support[0] = self.support[0].saturating_add(kernel::popcount(c.nzc));
                self.support[1] = self.support[1].saturating_add(kernel::popcount(c.nzs));
            }
        } else {
            let m = stop.saturating_sub(s) as u32;
            self.support[0] = self.support[0].saturating_add(m);
            self.support[1] = self.support[1].saturating_add(m);
        }
        let (cx, tb) = (self.format.complex, self.format.two_bit());
        let edges = [u32::MAX << (lead & 31), u32::MAX >> (tail & 31)];
        for (a, acc) in (0..A).zip(self.acc.iter_mut()) {
            let Some(planes) = block.planes(a) else {
                continue;
            };
            let Some(p) = chunk_planes(planes, w0, w0.saturating_add(nw), self.format) else {
                continue;
            };
            let all = a == 0 || self.slave_taps == SlaveTaps::All;
            let n = (nw, edges);
            // (each arm's guard is a constant: the kernels not built are not compiled in)
            match (cx, tb, l3) {
                (true, false, false) if Self::built(true, false, false) => {
                    antenna::<true, false, false>(p, work, n, all, acc);
                }
                (true, true, false) if Self::built(true, true, false) => {
                    antenna::<true, true, false>(p, work, n, all, acc);
                }
                (true, false, true) if Self::built(true, false, true) => {
                    antenna::<true, false, true>(p, work, n, all, acc);
                }
                (true, true, true) if Self::built(true, true, true) => {
                    antenna::<true, true, true>(p, work, n, all, acc);
                }
                (false, false, false) if Self::built(false, false, false) => {
                    antenna::<false, false, false>(p, work, n, all, acc);
                }
                (false, true, false) if Self::built(false, true, false) => {
                    antenna::<false, true, false>(p, work, n, all, acc);
                }
                (false, false, true) if Self::built(false, false, true) => {
                    antenna::<false, false, true>(p, work, n, all, acc);
                }
                (false, true, true) if Self::built(false, true, true) => {
                    antenna::<false, true, true>(p, work, n, all, acc);
                }
                // (a kernel not built: `new` refused its format and carrier)
                _ => {}
            }
        }
    }

    /// Whether the kernel of `(complex, two_bit, three)` is built.
    #[inline(always)]
    const fn built(complex: bool, two_bit: bool, three: bool) -> bool {
        KERNELS & kernel_bit_of(complex, two_bit, three) != 0
    }

    /// Whether the replica is 3-level (always `false` when no 3-level kernel is built).
    #[inline(always)]
    fn three_level(&self) -> bool {
        Self::THREE_LEVEL_BUILT && self.levels == CarrierLevels::Three
    }

    /// The carrier words of the chunk's `nw` words into the workspace, with the span's edges
    /// masked out (`lead` samples before the span in the first word, `tail` after it in the
    /// last).
    fn carrier_words(&self, nw: usize, lead: usize, tail: usize, work: &mut BitScratch) {
        let phase = self
            .carrier
            .phase
            .wrapping_sub(self.carrier.step.wrapping_mul(lead as u32));
        let step = CarrierStep::new(self.carrier.step);
        let words = work.carrier.get_mut(..nw).unwrap_or_default();
        // (a call per level: each inlines `fill` with its level a constant)
        if self.three_level() {
            carrier::fill(words, CarrierLevels::Three, phase, &step);
        } else {
            carrier::fill(words, CarrierLevels::Two, phase, &step);
        }
        if let Some(first) = words.first_mut() {
            let mask = u32::MAX << (lead & 31);
            first.nzc &= mask;
            first.nzs &= mask;
        }
        if let Some(last) = words.last_mut() {
            let mask = u32::MAX >> (tail & 31);
            last.nzc &= mask;
            last.nzs &= mask;
        }
    }

    /// The code words of the chunk's four taps (E, P, L, N) into the workspace: the prompt
    /// string with margins for the shifted taps, the taps as 32-bit windows of it, masked with
    /// the carrier supports (3-level) or the span's edges (2-level).
    fn code_words(
        &self,
        table: &CodeTable,
        nw: usize,
        lead: usize,
        tail: usize,
        work: &mut BitScratch,
    ) {
        let d = self.offset;
        let back = self.noise_delay.max(d).div_ceil(WORD_SAMPLES);
        let forward = d.div_ceil(WORD_SAMPLES);
        let words = nw
            .saturating_add(back)
            .saturating_add(forward)
            .saturating_add(1);
        let step = self.code.step;
        // Code phase at the first sample of the first prompt word.
        // (lead < 32, back a few words, the step below 2³³: no product wraps)
        let behind =
            ((lead.saturating_add(back.saturating_mul(WORD_SAMPLES))) as u64).wrapping_mul(step);
        let behind = code::wrap_code(behind);
        let first = code::wrap_code(code::wrap_code(self.code.phase) + CODE_WRAP - behind);
        let mut at = CodeCursor::from_phase(first);
        let word_step = (WORD_SAMPLES as u64).wrapping_mul(step);
        let (chips, frac) = ((word_step >> 32) as u32, word_step as u32);
        let step4 = (step >> 2) as u32;
        // Two passes (the word starts, then the words) keep each loop's state in registers.
        for c in work.cursors.iter_mut().take(words) {
            *c = at;
            at.advance(chips, frac);
        }
        for (p, &c) in work.prompt.iter_mut().zip(work.cursors.iter()).take(words) {
            *p = code::prompt_word(&self.ext, table, c, step4);
        }
        // (base ≥ d and ≥ the noise delay, both a few words: the saturations never act)
        let base = back.saturating_mul(WORD_SAMPLES);
        let offsets = [
            base.saturating_add(d),
            base,
            base.saturating_sub(d),
            base.saturating_sub(self.noise_delay),
        ];
        for (taps, offset) in work.taps.iter_mut().zip(offsets) {
            window_words(taps.get_mut(..nw).unwrap_or_default(), &work.prompt, offset);
        }
        if self.three_level() {
            let carrier = work.carrier.iter().take(nw);
            for (tc, ts) in work.taps.iter_mut().zip(work.taps_s.iter_mut()) {
                for ((c, s), r) in tc.iter_mut().zip(ts.iter_mut()).zip(carrier.clone()) {
                    *s = *c & r.nzs;
                    *c &= r.nzc;
                }
            }
        } else {
            let masks = [u32::MAX << (lead & 31), u32::MAX >> (tail & 31)];
            for taps in work.taps.iter_mut() {
                if let Some(w) = taps.first_mut() {
                    *w &= masks[0];
                }
                if let Some(w) = taps.get_mut(nw.wrapping_sub(1)) {
                    *w &= masks[1];
                }
            }
        }
    }
}

/// The bit-parallel correlators' scratch: the words of one chunk's replica, shared by the
/// antennas, and of the streams of the antenna being correlated, written and read within one
/// call of [`BitCorrelator::run_in`] (3,324 B). One serves every correlator that runs in turn:
/// a receiver's channels share one instead of carrying one each.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BitScratch {
    carrier: [CarrierWords; CHUNK_WORDS],
    /// The prompt string of the chunk and its margins.
    prompt: [u32; PROMPT_WORDS],
    /// The code phase at the start of every prompt word.
    cursors: [CodeCursor; PROMPT_WORDS],
    /// Code words per tap (E, P, L, N), masked with the `c ≠ 0` support (and the span).
    taps: [[u32; CHUNK_WORDS]; 4],
    /// The same masked with the `s ≠ 0` support (3-level carrier only).
    taps_s: [[u32; CHUNK_WORDS]; 4],
    streams: StreamWords,
}

impl BitScratch {
    /// A scratch (all zeros).
    pub const fn new() -> Self {
        Self {
            carrier: [CarrierWords {
                c: 0,
                s: 0,
                d: 0,
                nzc: 0,
                nzs: 0,
            }; CHUNK_WORDS],
            prompt: [0; PROMPT_WORDS],
            cursors: [CodeCursor { chip: 0, frac: 0 }; PROMPT_WORDS],
            taps: [[0; CHUNK_WORDS]; 4],
            taps_s: [[0; CHUNK_WORDS]; 4],
            streams: [[0; CHUNK_WORDS]; MAX_STREAMS],
        }
    }
}

impl Default for BitScratch {
    fn default() -> Self {
        Self::new()
    }
}

/// Zeroes the first `N` streams of every tap's accumulators (a size known at compile time:
/// stores, not a `memset` call per tap).
fn zero_streams<const N: usize, const A: usize>(acc: &mut [[[u32; MAX_STREAMS]; 4]; A]) {
    for taps in acc.iter_mut() {
        for streams in taps.iter_mut() {
            if let Some(head) = streams.get_mut(..N) {
                head.fill(0);
            }
        }
    }
}

/// 32-bit windows of the prompt string: `out[i]` is bits `offset + 32·i …` of `prompt`.
/// `#[inline]` because a lower inline threshold (firmware `realtime`'s build) would otherwise
/// leave it out of line, where its copy becomes a `memcpy` call: +13 k instructions per 1 ms.
#[inline]
fn window_words(out: &mut [u32], prompt: &[u32; PROMPT_WORDS], offset: usize) {
    let sh = (offset % WORD_SAMPLES) as u32;
    let src = prompt.get(offset / WORD_SAMPLES..).unwrap_or_default();
    if sh == 0 {
        // A whole-word offset (the prompt tap): a copy.
        for (o, &w) in out.iter_mut().zip(src) {
            *o = w;
        }
        return;
    }
    for (o, pair) in out.iter_mut().zip(src.windows(2)) {
        if let &[lo, hi] = pair {
            *o = (lo >> sh) | ((hi << 1) << (31 - sh));
        }
    }
}

/// The chunk's words of an antenna's planes (absent planes replaced by the sign plane).
fn chunk_planes<'a>(
    p: &super::planes::AntennaPlanes<'a>,
    w0: usize,
    w1: usize,
    format: PlaneFormat,
) -> Option<ChunkPlanes<'a>> {
    let a = p.sign_i().get(w0..w1)?;
    let two = format.two_bit();
    let ma = if two { p.mag_i().get(w0..w1)? } else { a };
    let b = if format.complex {
        p.sign_q().get(w0..w1)?
    } else {
        a
    };
    let mb = if two && format.complex {
        p.mag_q().get(w0..w1)?
    } else {
        a
    };
    Some(ChunkPlanes { a, ma, b, mb })
}

/// One antenna over one chunk: its stream words, then the population counts of every
/// stream against the code words of every tap it computes (all four for the reference antenna,
/// or for every antenna with [`SlaveTaps::All`]; the prompt otherwise). `chunk` is the word
/// count and the span's masks of the first and last word.
#[inline(never)]
fn antenna<const CX: bool, const TB: bool, const L3: bool>(
    p: ChunkPlanes<'_>,
    work: &mut BitScratch,
    chunk: (usize, [u32; 2]),
    all_taps: bool,
    acc: &mut [[u32; MAX_STREAMS]; 4],
) {
    let (n, [lead_mask, tail_mask]) = chunk;
    let n = n.min(CHUNK_WORDS);
    let j_count = kernel::stream_count(CX, TB, L3);

    let scratch = &mut work.streams;
    kernel::prepare::<CX, TB, L3>(p, work.carrier.get(..n).unwrap_or_default(), scratch);
    if !L3 {
        // The 2-level streams are masked at the span's edges only.
        for stream in scratch.iter_mut().take(j_count) {
            if let Some(w) = stream.first_mut() {
                *w &= lead_mask;
            }
            if let Some(w) = stream.get_mut(n.wrapping_sub(1)) {
                *w &= tail_mask;
            }
        }
    }
    let taps: &[usize] = if all_taps {
        &[EARLY, PROMPT, LATE, NOISE]
    } else {
        &[PROMPT]
    };
    for &t in taps {
        let (Some(code_c), Some(code_s), Some(sums)) =
            (work.taps.get(t), work.taps_s.get(t), acc.get_mut(t))
        else {
            continue;
        };
        let code_s = if L3 { code_s } else { code_c };
        let code = |j: usize| {
            let code = if kernel::stream_uses_s(CX, TB, L3, j) {
                code_s
            } else {
                code_c
            };
            code.get(..n).unwrap_or_default()
        };
        let x = |j: usize| scratch.get(j).and_then(|s| s.get(..n)).unwrap_or_default();
        for (j, sum) in (0..j_count).zip(sums.iter_mut()) {
            // (at most the epoch's samples, 2¹⁶: never wraps; as the integer correlator's)
            *sum = sum.wrapping_add(kernel::xor_count(x(j), code(j)));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_is_as_documented() {
        // The module documentation quotes these sizes.
        assert_eq!(core::mem::size_of::<BitScratch>(), 3324);
        let size = core::mem::size_of::<BitCorrelator<3>>();
        assert!((600..800).contains(&size), "{size}");
        assert_eq!(core::mem::size_of::<CodeTable>(), 8192 + 8);
    }
}
