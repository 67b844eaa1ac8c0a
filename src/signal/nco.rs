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
        div_ceil_by_estimate(remaining, self.step).max(1)
    }
}

/// `⌈n/d⌉` (`u64::MAX` for `d = 0`), without a 64-bit division (a library call of about 150 instructions
/// on the Cortex-M4, twice per channel and code period) where the code NCO lives: for
/// `n < 2⁴²` (a code period is `CODE_WRAP < 2⁴²`) and `2²⁶ ≤ d < 2⁴²` (steps of at most
/// 2¹⁶ samples per period) a 32-bit division of the operands' top bits gives `⌊n/d⌋`
/// within one, which multiplications correct. Elsewhere, and should the correction not
/// settle, the 64-bit division.
fn div_ceil_by_estimate(n: u64, d: u64) -> u64 {
    const SHIFT: u32 = 10;
    if d == 0 {
        return u64::MAX;
    }
    if n >> (32 + SHIFT) == 0 && d >> (16 + SHIFT) != 0 && d >> (32 + SHIFT) == 0 {
        // n' = ⌊n/2¹⁰⌋ < 2³², d' = ⌊d/2¹⁰⌋ ≥ 2¹⁶: n/d lies in (n'/d' − 1, n'/d' + 2⁻¹⁶)
        let (n32, d32) = ((n >> SHIFT) as u32, (d >> SHIFT) as u32);
        if let Some(estimate) = n32.checked_div(d32) {
            // (q ≤ 2¹⁶ + 4 and d < 2⁴²: the products stay below 2⁵⁹)
            let mut q = u64::from(estimate);
            for _ in 0..4 {
                if q.wrapping_mul(d) >= n {
                    break;
                }
                q = q.saturating_add(1);
            }
            for _ in 0..4 {
                if q == 0 || (q - 1).wrapping_mul(d) < n {
                    break;
                }
                q -= 1;
            }
            if q.wrapping_mul(d) >= n && (q == 0 || (q - 1).wrapping_mul(d) < n) {
                return q;
            }
        }
    }
    n.div_ceil(d)
}

/// The largest Doppler [`NcoSteering::carrier_step`] accepts, Hz (2¹⁹: ten times a LEO's).
pub const MAX_STEERED_DOPPLER_HZ: f32 = 524_288.0;

/// The smallest code step a correlator accepts: one code period in at most
/// `MAX_SAMPLES_PER_EPOCH − 1` samples.
pub const MIN_CODE_STEP: u64 =
    CODE_WRAP.div_ceil(crate::signal::correlator::MAX_SAMPLES_PER_EPOCH - 1);

/// The NCO words for the tracking loops' f32 outputs, in integer arithmetic: what a channel
/// computes every code period (the 1 ms path has no f64, which is soft float on the M4F, and no
/// division). The constants are computed once, in f64, from the sample rate and the IF.
///
/// Against [`CarrierNco::step_for`] / [`CodeNco::step_for`] on the same f32 inputs the words
/// differ by at most one unit (a carrier step of 2⁻³² cycle per sample, 0.6 mHz at 2.6 Msps;
/// a code step of 2⁻³² chip per sample) at 2.1 Msps and above: the Doppler is rounded to
/// 2⁻¹¹ Hz and the code-rate offset to 2⁻¹⁶ chip/s before the fixed-point products (below
/// 2.1 Msps the Doppler's rounding, at most 0.25 mHz, can add a unit).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NcoSteering {
    /// Carrier word of the intermediate frequency.
    if_step: u32,
    /// Carrier word per Hz, 2⁻²¹ units: `round(2⁵³ / f_s)`.
    carrier_per_hz_q21: i64,
    /// Hz per carrier-word unit, `f_s / 2³²`.
    hz_per_carrier_unit: f32,
    /// Intermediate frequency, Hz.
    if_hz: f32,
    /// Half the sample rate, Hz.
    nyquist_hz: f32,
    /// Code word of the nominal chip rate.
    nominal_code_step: u64,
    /// Code word per chip/s, 2⁻¹⁶ units: `round(2⁴⁸ / f_s)`.
    code_per_chip_rate_q16: i64,
}

/// A steering setting [`NcoSteering`] refuses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SteeringError {
    /// A non-finite input.
    NonFinite,
    /// A sample rate or IF that gives no steering (rate not positive, `|IF| ≥ f_s/2`).
    InvalidConfig,
    /// A carrier beyond Nyquist or a Doppler beyond [`MAX_STEERED_DOPPLER_HZ`].
    CarrierOutOfRange,
    /// A code rate more than 1 % off nominal, or one period longer than a correlator holds.
    CodeRateOutOfRange,
}

impl NcoSteering {
    /// The steering for samples at `sample_rate_hz` with the intermediate frequency
    /// `intermediate_frequency_hz` (f64, once).
    ///
    /// # Errors
    /// [`SteeringError::NonFinite`], or [`SteeringError::InvalidConfig`] for a sample rate
    /// not in 100 kHz–100 MHz or an IF at or beyond Nyquist.
    pub fn new(sample_rate_hz: f64, intermediate_frequency_hz: f64) -> Result<Self, SteeringError> {
        if !(sample_rate_hz.is_finite() && intermediate_frequency_hz.is_finite()) {
            return Err(SteeringError::NonFinite);
        }
        if !((1e5..=1e8).contains(&sample_rate_hz)
            && intermediate_frequency_hz.abs() < 0.5 * sample_rate_hz)
        {
            return Err(SteeringError::InvalidConfig);
        }
        let two32 = 4_294_967_296.0;
        Ok(Self {
            if_step: CarrierNco::step_for(intermediate_frequency_hz, sample_rate_hz),
            carrier_per_hz_q21: libm::round(two32 * 2_097_152.0 / sample_rate_hz) as i64,
            hz_per_carrier_unit: (sample_rate_hz / two32) as f32,
            if_hz: intermediate_frequency_hz as f32,
            nyquist_hz: (0.5 * sample_rate_hz) as f32,
            nominal_code_step: CodeNco::step_for(super::CA_CHIP_RATE_HZ, sample_rate_hz),
            code_per_chip_rate_q16: libm::round(two32 * 65_536.0 / sample_rate_hz) as i64,
        })
    }

    /// The carrier word for IF + `doppler_hz`.
    ///
    /// # Errors
    /// [`SteeringError::NonFinite`]; [`SteeringError::CarrierOutOfRange`] for
    /// `|doppler| > MAX_STEERED_DOPPLER_HZ` or `|IF + doppler| ≥ f_s/2`.
    pub fn carrier_step(&self, doppler_hz: f32) -> Result<u32, SteeringError> {
        if !doppler_hz.is_finite() {
            return Err(SteeringError::NonFinite);
        }
        if !(doppler_hz.abs() <= MAX_STEERED_DOPPLER_HZ
            && (self.if_hz + doppler_hz).abs() < self.nyquist_hz)
        {
            return Err(SteeringError::CarrierOutOfRange);
        }
        // |q| ≤ 2³⁰; |q · K| < 2⁶³ since K = 2⁵³/f_s and |q| ≤ 2¹¹ · f_s/2.
        let q = i64::from(libm::roundf(doppler_hz * 2048.0) as i32);
        let delta = q
            .wrapping_mul(self.carrier_per_hz_q21)
            .wrapping_add(1 << 31)
            >> 32;
        Ok(self.if_step.wrapping_add(delta as u32))
    }

    /// The Doppler a carrier word steers to (carrier frequency − IF), Hz, f32 (rounded to
    /// f32's 24 bits: 4 mHz at 50 kHz).
    pub fn doppler_hz(&self, carrier_step: u32) -> f32 {
        carrier_step.wrapping_sub(self.if_step) as i32 as f32 * self.hz_per_carrier_unit
    }

    /// The code word for the nominal chip rate + `offset_chips_per_second`.
    ///
    /// # Errors
    /// [`SteeringError::NonFinite`]; [`SteeringError::CodeRateOutOfRange`] for an offset of
    /// more than 1 % of the chip rate or a period longer than [`MIN_CODE_STEP`] allows.
    pub fn code_step(&self, offset_chips_per_second: f32) -> Result<u64, SteeringError> {
        if !offset_chips_per_second.is_finite() {
            return Err(SteeringError::NonFinite);
        }
        if !(offset_chips_per_second.abs() <= 0.01 * super::CA_CHIP_RATE_HZ as f32) {
            return Err(SteeringError::CodeRateOutOfRange);
        }
        // |q| ≤ 10 230 · 2¹⁶ < 2³⁰, K < 2³²: the product fits.
        let q = i64::from(libm::roundf(offset_chips_per_second * 65_536.0) as i32);
        let delta = q
            .wrapping_mul(self.code_per_chip_rate_q16)
            .wrapping_add(1 << 31)
            >> 32;
        let step = self.nominal_code_step.wrapping_add_signed(delta);
        if step < MIN_CODE_STEP {
            return Err(SteeringError::CodeRateOutOfRange);
        }
        Ok(step)
    }
}

#[cfg(test)]
mod steering_tests {
    use super::*;
    use crate::signal::{CA_CHIP_RATE_HZ, GPS_L1_HZ};

    /// The next word of a xorshift.
    fn xorshift(state: &mut u64) -> u64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        *state
    }

    /// Random f32 in `[−1, 1)` from a xorshift.
    fn uniform(state: &mut u64) -> f32 {
        ((xorshift(state) >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }

    #[test]
    fn the_integer_words_are_within_one_unit_of_the_f64_ones() {
        for (fs, f_if) in [
            (2.6e6, 0.0),
            (4.092e6, 1.023e6),
            (16.368e6, -4.092e6),
            (1.2e6, 1e3),
        ] {
            let s = NcoSteering::new(fs, f_if).unwrap();
            let mut state = 0x9e37_79b9_7f4a_7c15u64;
            for _ in 0..20_000 {
                let doppler = 50_000.0 * uniform(&mut state);
                let dll = 2.0 * uniform(&mut state);
                let carrier = s.carrier_step(doppler).unwrap();
                let exact = CarrierNco::step_for(f_if + f64::from(doppler), fs);
                // One unit, plus the Doppler's rounding (2⁻¹² Hz) below 2.1 Msps.
                let tolerance = 1 + libm::ceil(1_048_576.0 / fs) as i32;
                let diff = (carrier.wrapping_sub(exact) as i32).abs();
                assert!(diff <= tolerance, "carrier {doppler} Hz at {fs}: {diff}");
                let offset = doppler / 1540.0 + dll;
                let code = s.code_step(offset).unwrap();
                let rate =
                    CA_CHIP_RATE_HZ * (1.0 + f64::from(doppler) / GPS_L1_HZ) + f64::from(dll);
                let exact = CodeNco::step_for(rate, fs);
                assert!(code.abs_diff(exact) <= 1, "code {offset} chip/s at {fs}");
                let back = s.doppler_hz(carrier);
                // The word's rounding, then f32's 24 bits.
                let unit = (fs / 4_294_967_296.0) as f32;
                assert!(
                    (back - doppler).abs() <= tolerance as f32 * unit + 2e-7 * doppler.abs(),
                    "{back} vs {doppler} at {fs}"
                );
            }
        }
    }

    #[test]
    fn out_of_range_and_non_finite_settings_are_refused() {
        let s = NcoSteering::new(2.6e6, 0.0).unwrap();
        assert_eq!(s.carrier_step(f32::NAN), Err(SteeringError::NonFinite));
        assert_eq!(s.carrier_step(1.3e6), Err(SteeringError::CarrierOutOfRange));
        assert_eq!(s.carrier_step(-6e5), Err(SteeringError::CarrierOutOfRange));
        assert_eq!(s.code_step(f32::INFINITY), Err(SteeringError::NonFinite));
        assert_eq!(
            s.code_step(10_300.0),
            Err(SteeringError::CodeRateOutOfRange)
        );
        assert!(s.code_step(10_000.0).is_ok());
        assert_eq!(
            NcoSteering::new(2.6e6, 1.3e6),
            Err(SteeringError::InvalidConfig)
        );
        assert_eq!(
            NcoSteering::new(f64::NAN, 0.0),
            Err(SteeringError::NonFinite)
        );
    }

    #[test]
    fn samples_to_wrap_is_the_exact_ceiling_across_the_estimates_range() {
        // The estimate's range (periods up to 2¹⁶ samples and the phases of one period), its
        // edges, and beyond them (the 64-bit division): always ⌈remaining/step⌉.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || xorshift(&mut state);
        let edges = [
            1,
            (1 << 26) - 1,
            1 << 26,
            MIN_CODE_STEP,
            (1 << 42) - 1,
            1 << 42,
        ];
        for k in 0..200_000 {
            let step = match k % 4 {
                0 => (1 << 26) + next() % (1 << 32),
                1 => edges[(next() % 6) as usize],
                2 => 1 + next() % (1 << 44),
                _ => CodeNco::step_for(CA_CHIP_RATE_HZ * 1.001, 2.6e6) - next() % (1 << 24),
            };
            let phase = match k % 3 {
                0 => next() % CODE_WRAP,
                1 => CODE_WRAP - next() % (1 << 20),
                _ => next(),
            };
            let nco = CodeNco { phase, step };
            let remaining = CODE_WRAP.saturating_sub(phase);
            assert_eq!(
                nco.samples_to_wrap(),
                remaining.div_ceil(step).max(1),
                "phase {phase} step {step}"
            );
        }
        let stopped = CodeNco { phase: 0, step: 0 };
        assert_eq!(stopped.samples_to_wrap(), u64::MAX);
    }
}
