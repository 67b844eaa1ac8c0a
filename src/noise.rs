//! Seeded noise and test-signal generators.
//!
//! Every generator takes any [`RngCore`], so the same code draws the noise of host-sim's
//! Monte Carlo runs (seeded `rand` generators) and of the built-in self-test on the target
//! ([`SplitMix64`], which needs no entropy source). All arithmetic is `f32`.

use nalgebra::SVector;
use rand_core::{impls, RngCore, SeedableRng};

/// A uniform sample in `(0, 1]` with 24 random bits (the full `f32` mantissa).
pub fn uniform_open01<R: RngCore + ?Sized>(rng: &mut R) -> f32 {
    // (k + 1) / 2²⁴ for k uniform in [0, 2²⁴): never 0, so ln() below is finite.
    ((rng.next_u32() >> 8) + 1) as f32 * (1.0 / 16_777_216.0)
}

/// Standard normal samples by the Box–Muller transform, keeping the second sample of each pair.
///
/// Tails are cut at `√(−2 ln 2⁻²⁴) ≈ 5.77 σ` by the 24-bit uniform, which no test here can tell
/// from a true Gaussian.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StandardNormal {
    spare: Option<f32>,
}

impl StandardNormal {
    /// A sampler with no stored sample.
    pub const fn new() -> Self {
        Self { spare: None }
    }

    /// One sample of N(0, 1).
    pub fn sample<R: RngCore + ?Sized>(&mut self, rng: &mut R) -> f32 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let u1 = uniform_open01(rng);
        let u2 = uniform_open01(rng);
        let radius = crate::sqrtf(-2.0 * libm::logf(u1));
        let (s, c) = libm::sincosf(core::f32::consts::TAU * u2);
        self.spare = Some(radius * s);
        radius * c
    }

    /// A vector of independent N(0, σ²) samples.
    pub fn vector<const N: usize, R: RngCore + ?Sized>(
        &mut self,
        rng: &mut R,
        sigma: f32,
    ) -> SVector<f32, N> {
        SVector::from_fn(|_, _| sigma * self.sample(rng))
    }
}

/// `SplitMix64` (Steele, Lea, Flood 2014): a tiny, fast, statistically sound generator with a
/// 64-bit state. For reproducible test signals on the target, where no entropy source is
/// needed; not for anything that must be unpredictable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator started at `seed`.
    pub const fn new(seed: u64) -> Self {
        Self { state: seed }
    }
}

impl RngCore for SplitMix64 {
    fn next_u32(&mut self) -> u32 {
        (self.next_u64() >> 32) as u32
    }

    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn fill_bytes(&mut self, dst: &mut [u8]) {
        impls::fill_bytes_via_next(self, dst);
    }
}

impl SeedableRng for SplitMix64 {
    type Seed = [u8; 8];

    fn from_seed(seed: Self::Seed) -> Self {
        Self::new(u64::from_le_bytes(seed))
    }

    fn seed_from_u64(state: u64) -> Self {
        Self::new(state)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix64_matches_the_reference_sequence() {
        // First outputs of the reference C implementation seeded with 1234567.
        let mut rng = SplitMix64::new(1_234_567);
        assert_eq!(rng.next_u64(), 6_457_827_717_110_365_317);
        assert_eq!(rng.next_u64(), 3_203_168_211_198_807_973);
        assert_eq!(rng.next_u64(), 9_817_491_932_198_370_423);
    }

    #[test]
    fn standard_normal_has_unit_moments() {
        let mut rng = SplitMix64::new(42);
        let mut n = StandardNormal::new();
        let count = 200_000;
        let (mut sum, mut sum2, mut sum4) = (0.0f64, 0.0f64, 0.0f64);
        for _ in 0..count {
            let z = f64::from(n.sample(&mut rng));
            assert!(z.is_finite());
            sum += z;
            sum2 += z * z;
            sum4 += z * z * z * z;
        }
        let c = f64::from(count);
        let mean = sum / c;
        let var = sum2 / c - mean * mean;
        // 5σ of the sampling error: mean 1/√n, variance √(2/n), kurtosis √(96/n)
        assert!(mean.abs() < 5.0 / c.sqrt(), "mean {mean}");
        assert!((var - 1.0).abs() < 5.0 * (2.0 / c).sqrt(), "variance {var}");
        assert!(
            (sum4 / c - 3.0).abs() < 5.0 * (96.0 / c).sqrt(),
            "fourth moment"
        );
    }
}
