//! Numerically controlled oscillators: the carrier NCO (32-bit phase accumulator and a
//! 256-entry sine/cosine table) and the code NCO (code phase in 32.32 fixed-point chips).
//!
//! # Carrier
//! The phase is a `u32` in units of 2⁻³² cycle; the frequency word is the phase step per
//! sample, `round(f / f_s · 2³²)` (two's complement for negative frequencies), so the
//! frequency resolution is `f_s / 2³²` (0.6 mHz at 2.6 Msps). The table index is the top 8
//! bits of the phase; entry `k` holds `round(127 · cos(2π(k + ½)/256))` and the same for sine
//! (the mid-point of the phase interval the index selects), so the table's phase error is at
//! most `π/256` rad and its amplitude error at most ½ LSB in each component: the replica
//! `(c − j s)/127` differs from `e^{−jφ}` by at most [`CARRIER_REPLICA_MAX_ERROR`] in
//! magnitude. The correlation loss of this replica is 0.0004 dB.
//!
//! # Code
//! The code phase is a `u64` in units of 2⁻³² chip (32.32 fixed point) and the code rate a
//! `u64` step per sample in the same unit, so the chip index is the upper word and the rate
//! resolution is `f_s · 2⁻³²` chips/s (6·10⁻⁴ chip/s at 2.6 Msps, a range-rate of 0.2 mm/s).

use core::f64::consts::PI;

/// Number of entries of the carrier table (a power of two).
pub const CARRIER_TABLE_SIZE: usize = 256;

/// Amplitude of the carrier table: a table entry is `round(CARRIER_AMPLITUDE · cos φ)`.
pub const CARRIER_AMPLITUDE: i16 = 127;

/// Upper bound of `|(c_k − j s_k)/127 − e^{−jφ}|` over all phases `φ` of table bin `k`:
/// `2 sin(π/512) + √2 · 0.5/127` (phase truncation to the bin mid-point, then rounding).
pub const CARRIER_REPLICA_MAX_ERROR: f64 = 0.012_271_8 + 0.005_567_8;

const fn taylor_sin(x: f64) -> f64 {
    // x in [−π, π]: 15 terms of the Taylor series give < 1e-15 error there.
    let x2 = x * x;
    let mut term = x;
    let mut sum = x;
    let mut n = 1;
    while n < 15 {
        term = -term * x2 / ((2 * n) as f64 * (2 * n + 1) as f64);
        sum += term;
        n += 1;
    }
    sum
}

const fn round_const(x: f64) -> i16 {
    if x >= 0.0 {
        (x + 0.5) as i16
    } else {
        -((-x + 0.5) as i16)
    }
}

const fn carrier_table(cosine: bool) -> [i16; CARRIER_TABLE_SIZE] {
    let mut t = [0i16; CARRIER_TABLE_SIZE];
    let mut k = 0;
    while k < CARRIER_TABLE_SIZE {
        let mut phase = 2.0 * PI * (k as f64 + 0.5) / CARRIER_TABLE_SIZE as f64;
        if cosine {
            phase += PI / 2.0;
        }
        // Reduce to [−π, π] for the series.
        while phase > PI {
            phase -= 2.0 * PI;
        }
        t[k] = round_const(CARRIER_AMPLITUDE as f64 * taylor_sin(phase));
        k += 1;
    }
    t
}

/// `round(127 · cos(2π(k + ½)/256))`, computed at compile time.
pub static COS_TABLE: [i16; CARRIER_TABLE_SIZE] = carrier_table(true);
/// `round(127 · sin(2π(k + ½)/256))`, computed at compile time.
pub static SIN_TABLE: [i16; CARRIER_TABLE_SIZE] = carrier_table(false);

/// The table index of a carrier phase (top 8 bits).
#[inline(always)]
pub const fn carrier_index(phase: u32) -> usize {
    (phase >> 24) as usize
}

/// Carrier NCO: phase accumulator and frequency word.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CarrierNco {
    /// Phase, 2⁻³² cycle.
    pub phase: u32,
    /// Phase step per sample, 2⁻³² cycle (two's complement: negative frequencies wrap).
    pub step: u32,
}

impl CarrierNco {
    /// The frequency word for `frequency_hz` at `sample_rate_hz` (`round(f/f_s · 2³²)`
    /// modulo 2³²). f64 because the word needs 32 significant bits.
    pub fn step_for(frequency_hz: f64, sample_rate_hz: f64) -> u32 {
        let cycles_per_sample = frequency_hz / sample_rate_hz;
        let word = libm::round(cycles_per_sample * 4_294_967_296.0);
        // Reduce to one cycle first (floor, not fmod: libm's fmod keeps panic paths): any
        // finite value maps to a defined word; non-finite gives 0.
        if !word.is_finite() {
            return 0;
        }
        let word = word - libm::floor(word / 4_294_967_296.0) * 4_294_967_296.0;
        (word as u64) as u32
    }

    /// The frequency, Hz, that the current step represents.
    pub fn frequency_hz(&self, sample_rate_hz: f64) -> f64 {
        f64::from(self.step as i32) / 4_294_967_296.0 * sample_rate_hz
    }

    /// Phase in cycles, `[0, 1)`.
    pub fn phase_cycles(&self) -> f64 {
        f64::from(self.phase) / 4_294_967_296.0
    }
}

/// One code period in the code NCO's unit (1023 chips · 2³²).
pub const CODE_WRAP: u64 = 1023u64 << 32;

/// Code NCO: prompt code phase and rate, 32.32 fixed-point chips.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CodeNco {
    /// Prompt code phase, 2⁻³² chip, in `[0, CODE_WRAP)`.
    pub phase: u64,
    /// Code phase step per sample, 2⁻³² chip.
    pub step: u64,
}

impl CodeNco {
    /// The step for a code rate `chips_per_second` at `sample_rate_hz` (f64: 64-bit word).
    /// Negative or non-finite rates give 0.
    pub fn step_for(chips_per_second: f64, sample_rate_hz: f64) -> u64 {
        let step = libm::round(chips_per_second / sample_rate_hz * 4_294_967_296.0);
        if step.is_finite() && step > 0.0 && step < 1.8e19 {
            step as u64
        } else {
            0
        }
    }

    /// A phase word for `chips` (reduced modulo 1023; non-finite gives 0).
    pub fn phase_for(chips: f64) -> u64 {
        if !chips.is_finite() {
            return 0;
        }
        let c = chips - libm::floor(chips / 1023.0) * 1023.0;
        let word = libm::round(c * 4_294_967_296.0) as u64;
        if word >= CODE_WRAP {
            word - CODE_WRAP
        } else {
            word
        }
    }

    /// Code phase, chips, `[0, 1023)`.
    pub fn phase_chips(&self) -> f64 {
        self.phase as f64 / 4_294_967_296.0
    }

    /// Code rate, chips/s.
    pub fn rate_chips_per_second(&self, sample_rate_hz: f64) -> f64 {
        self.step as f64 / 4_294_967_296.0 * sample_rate_hz
    }

    /// Samples until the prompt phase reaches the end of the period (at least 1 when the step
    /// is positive; `u64::MAX` for a zero step).
    pub fn samples_to_wrap(&self) -> u64 {
        if self.step == 0 {
            return u64::MAX;
        }
        let remaining = CODE_WRAP.saturating_sub(self.phase);
        remaining.div_ceil(self.step).max(1)
    }
}
