//! The modified Bessel ratio `r(x) = I₁(x)/I₀(x)` and the derived factors that the coherent–
//! noncoherent likelihood `ln I₀(a X)` of eq. (15) needs, evaluated without ever forming
//! `I₀` or `I₁` (which overflow `f32` above `x ≈ 88`).
//!
//! Three regimes, each a ratio of bounded quantities:
//!
//! | `x` | `r` | Source |
//! |---|---|---|
//! | `[0, 3.75)` | `x · (x⁻¹I₁)/I₀`, both polynomials in `(x/3.75)²` | Abramowitz & Stegun 9.8.1, 9.8.3 |
//! | `[3.75, 20)` | `(√x e⁻ˣ I₁)/(√x e⁻ˣ I₀)`, both polynomials in `3.75/x` | A&S 9.8.2, 9.8.4 |
//! | `[20, ∞]` | `1 − 1/(2x) − 1/(8x²) − 1/(8x³) − 25/(128x⁴) − 13/(32x⁵) − 1073/(1024x⁶)` | asymptotic series (Hankel), truncation error < 5e-9 |
//!
//! The exponential scale factors cancel in the ratio, so no regime overflows; `x = +∞` gives
//! `r = 1`. Measured against an `f64` reference (power series in log space, high-order
//! asymptotic series above 200; `tests` below): `|r − r_ref| ≤ 1.8e-7` in `f64` arithmetic and
//! `≤ 2.5e-7` in `f32` for every `x ≥ 0` (worst near `x = 20`), the A&S polynomials being the
//! limit; relative to the discriminator's own noise this is nothing.
//!
//! The curvature factor `g(x) = (2r/x + r² − 1)/x²` (see [`BesselRatio::curvature`]) is a
//! small difference of terms near 1 at both ends, so it has its own series there:
//! `1/8 − x²/24 + 11x⁴/1024 − 19x⁶/7680 + 473x⁸/884736` below `x = 0.5` and
//! `u − u² − 3u³/8 − u⁴/2 − 125u⁵/128 − 39u⁶/16` (`u = 1/x`, times `u²`) from 20 on; relative
//! error below 1e-4 everywhere in `f32` (measured).

use crate::{real, Real};

/// `r = I₁(x)/I₀(x)` and the two factors of the likelihood's derivatives, at one argument
/// `x ≥ 0` (dimensionless: `x = a X`, amplitude over noise variance times the coherent sum).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BesselRatio<T = f32> {
    /// `r(x) = I₁(x)/I₀(x)`, in `[0, 1)`: the discriminator weight of eq. (23).
    pub ratio: T,
    /// `r(x)/x`, in `(0, 1/2]` (`1/2` at `x = 0`): the weight of `∂X²/∂ψ` in `∂ ln I₀/∂ψ`.
    pub ratio_over_x: T,
    /// `g(x) = (2r/x + r² − 1)/x²`, in `(0, 1/8]`: `−d²(ln I₀(√s))/ds² · 4`, the weight of the
    /// rank-one term of the curvature (see [`super::discriminator`]).
    pub curvature: T,
}

impl<T: Real> BesselRatio<T> {
    /// The ratio and its factors at `x`. Negative `x` is taken as `|x|` (`r` is odd; the
    /// callers only use `x ≥ 0`). A NaN argument gives NaN fields, which the filter rejects.
    pub fn at(x: T) -> Self {
        let x = x.abs();
        let (ratio, ratio_over_x) = ratio_and_ratio_over_x(x);
        Self {
            ratio,
            ratio_over_x,
            curvature: curvature(x, ratio, ratio_over_x),
        }
    }
}

/// Horner evaluation of `c[0] + c[1] y + c[2] y² + …`.
fn horner<T: Real>(y: T, coefficients: &[f64]) -> T {
    coefficients
        .iter()
        .rev()
        .fold(T::zero(), |acc, &c| acc * y + real::<T>(c))
}

/// A&S 9.8.1: `I₀(x)` for `|x| ≤ 3.75`, in `t = (x/3.75)²`; `|ε| < 1.6e-7`.
const I0_SMALL: [f64; 7] = [
    1.0,
    3.515_622_9,
    3.089_942_4,
    1.206_749_2,
    0.265_973_2,
    0.036_076_8,
    0.004_581_3,
];
/// A&S 9.8.3: `x⁻¹ I₁(x)` for `|x| ≤ 3.75`, in `t = (x/3.75)²`; `|ε| < 8e-9`.
const I1_OVER_X_SMALL: [f64; 7] = [
    0.5,
    0.878_905_94,
    0.514_988_69,
    0.150_849_34,
    0.026_587_33,
    0.003_015_32,
    0.000_324_11,
];
/// A&S 9.8.2: `√x e⁻ˣ I₀(x)` for `x ≥ 3.75`, in `y = 3.75/x`; `|ε| < 1.9e-7`.
const I0_LARGE: [f64; 9] = [
    0.398_942_28,
    0.013_285_92,
    0.002_253_19,
    -0.001_575_65,
    0.009_162_81,
    -0.020_577_06,
    0.026_355_37,
    -0.016_476_33,
    0.003_923_77,
];
/// A&S 9.8.4: `√x e⁻ˣ I₁(x)` for `x ≥ 3.75`, in `y = 3.75/x`; `|ε| < 2.2e-7`.
const I1_LARGE: [f64; 9] = [
    0.398_942_28,
    -0.039_880_24,
    -0.003_620_18,
    0.001_638_01,
    -0.010_315_55,
    0.022_829_67,
    -0.028_953_12,
    0.017_876_54,
    -0.004_200_59,
];
/// Asymptotic `I₁/I₀ = 1 − Σ cₖ uᵏ`, `u = 1/x` (from the Hankel expansions of I₀, I₁).
const RATIO_ASYMPTOTIC: [f64; 7] = [
    1.0,
    -0.5,
    -0.125,
    -0.125,
    -25.0 / 128.0,
    -13.0 / 32.0,
    -1073.0 / 1024.0,
];
/// Asymptotic `2r/x + r² − 1` in `u = 1/x` (coefficient of `u⁰` first).
const C1_ASYMPTOTIC: [f64; 7] = [0.0, 1.0, -1.0, -0.375, -0.5, -125.0 / 128.0, -39.0 / 16.0];
/// Small-`x` series of `g(x) = (2r/x + r² − 1)/x²` in `x²`.
const G_SMALL: [f64; 5] = [
    0.125,
    -1.0 / 24.0,
    11.0 / 1024.0,
    -19.0 / 7680.0,
    473.0 / 884_736.0,
];

/// Where the A&S small-argument polynomials end.
const SMALL_END: f64 = 3.75;
/// Where the asymptotic series take over.
const ASYMPTOTIC_START: f64 = 20.0;
/// Below this, `g` comes from its own series (the direct formula cancels).
const G_SERIES_END: f64 = 0.5;

fn ratio_and_ratio_over_x<T: Real>(x: T) -> (T, T) {
    if x < real(SMALL_END) {
        let t = x * x * real(1.0 / (SMALL_END * SMALL_END));
        // r/x = (x⁻¹ I₁)/I₀ (A&S 9.8.3 over 9.8.1): no division by x
        let rox = horner::<T>(t, &I1_OVER_X_SMALL) / horner::<T>(t, &I0_SMALL);
        (x * rox, rox)
    } else if x < real(ASYMPTOTIC_START) {
        let y = real::<T>(SMALL_END) / x;
        // r = (√x e⁻ˣ I₁)/(√x e⁻ˣ I₀) (A&S 9.8.4 over 9.8.2): the scale factors cancel
        let r = horner::<T>(y, &I1_LARGE) / horner::<T>(y, &I0_LARGE);
        (r, r / x)
    } else {
        // x = +∞ gives u = 0 and r = 1 exactly
        let u = x.recip();
        let r = horner::<T>(u, &RATIO_ASYMPTOTIC);
        (r, r * u)
    }
}

fn curvature<T: Real>(x: T, r: T, rox: T) -> T {
    if x < real(G_SERIES_END) {
        horner::<T>(x * x, &G_SMALL)
    } else if x < real(ASYMPTOTIC_START) {
        // g = (2r/x + r² − 1)/x²
        (rox + rox + r * r - T::one()) / (x * x)
    } else {
        let u = x.recip();
        horner::<T>(u, &C1_ASYMPTOTIC) * u * u
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ln of `e⁻ˣ I_ν(x)` by the power series summed in log space (exact to ~1e-14 for the
    /// arguments used), an implementation independent of the one under test.
    fn ln_scaled_bessel_series(nu: u32, x: f64) -> f64 {
        let ln_half_x = (0.5 * x).ln();
        // ln of term k = (x/2)^(2k+ν) / (k! (k+ν)!), generated twice (max, then the sum)
        let terms = || {
            let mut ln_fact_k = 0.0f64;
            let mut ln_fact_k_nu: f64 = (1..=nu).map(|i| f64::from(i).ln()).sum();
            (0..4000u32).map(move |k| {
                if k > 0 {
                    ln_fact_k += f64::from(k).ln();
                    ln_fact_k_nu += f64::from(k + nu).ln();
                }
                f64::from(2 * k + nu) * ln_half_x - ln_fact_k - ln_fact_k_nu
            })
        };
        let m = terms().fold(f64::NEG_INFINITY, f64::max);
        m + terms().map(|t| (t - m).exp()).sum::<f64>().ln() - x
    }

    /// Hankel's asymptotic expansion of `√(2πx) e⁻ˣ I_ν(x)` to `n` terms.
    fn hankel(nu: f64, x: f64, n: usize) -> f64 {
        let mu = 4.0 * nu * nu;
        let mut term = 1.0;
        let mut sum = 1.0;
        for k in 1..n {
            let odd = (2 * k - 1) as f64;
            term *= -(mu - odd * odd) / (k as f64 * 8.0 * x);
            sum += term;
        }
        sum
    }

    /// `g = (2 (I₁/x) I₀ + I₁² − I₀²) / (x² I₀²)` with the numerator's power series formed
    /// from the products of the series of `I₀` and `I₁/x` (no cancellation at small `x`).
    fn small_g_by_series_products(x: f64) -> f64 {
        const K: usize = 30;
        let mut a = [0.0f64; K]; // I₀ = Σ a_k x^{2k}
        let mut b = [0.0f64; K]; // I₁/x = Σ b_k x^{2k}
        let (mut fk, mut fk1) = (1.0f64, 1.0f64); // k!, (k+1)!
        for k in 0..K {
            if k > 0 {
                fk *= k as f64;
                fk1 *= (k + 1) as f64;
            }
            let p4 = 4f64.powi(k as i32);
            a[k] = 1.0 / (p4 * fk * fk);
            b[k] = 1.0 / (2.0 * p4 * fk * fk1);
        }
        let conv =
            |u: &[f64; K], v: &[f64; K], k: usize| (0..=k).map(|i| u[i] * v[k - i]).sum::<f64>();
        // numerator / x² = Σ_{k≥1} (2(a*b)_k + (b*b)_{k−1} − (a*a)_k) x^{2(k−1)}
        let x2 = x * x;
        let mut num = 0.0;
        let mut p = 1.0;
        for k in 1..K {
            num += (2.0 * conv(&a, &b, k) + conv(&b, &b, k - 1) - conv(&a, &a, k)) * p;
            p *= x2;
        }
        let i0: f64 = a.iter().rev().fold(0.0, |acc, &c| acc * x2 + c);
        num / (i0 * i0)
    }

    fn reference(x: f64) -> (f64, f64) {
        let r = if x == 0.0 {
            0.0
        } else if x <= 200.0 {
            (ln_scaled_bessel_series(1, x) - ln_scaled_bessel_series(0, x)).exp()
        } else {
            hankel(1.0, x, 12) / hankel(0.0, x, 12)
        };
        let g = if x <= 2.0 {
            small_g_by_series_products(x)
        } else {
            // in f64 the direct formula is good to ~1e-16/g relative; fine above 2
            (2.0 * r / x + r * r - 1.0) / (x * x)
        };
        (r, g)
    }

    fn arguments() -> impl Iterator<Item = f64> {
        let special = [0.0, 1e-6, 0.499, 0.5, 3.7499, 3.75, 19.999, 20.0, 60.0];
        let sweep = (0..=400).map(|k| 10f64.powf(-2.0 + 8.0 * f64::from(k) / 400.0)); // 1e-2 … 1e6
        special.into_iter().chain(sweep)
    }

    #[test]
    fn ratio_matches_the_f64_reference_for_all_arguments() {
        let mut worst64 = 0.0f64;
        let mut worst32 = 0.0f64;
        for x in arguments() {
            let (r_ref, _) = reference(x);
            let b64 = BesselRatio::<f64>::at(x);
            let b32 = BesselRatio::<f32>::at(x as f32);
            worst64 = worst64.max((b64.ratio - r_ref).abs());
            worst32 = worst32.max((f64::from(b32.ratio) - r_ref).abs());
            assert!(b32.ratio >= 0.0 && b32.ratio < 1.0 + 1e-7, "x {x}");
            if x > 0.0 {
                let rox = f64::from(b32.ratio_over_x);
                assert!(
                    (rox - r_ref / x).abs() <= 1e-6 * (r_ref / x) + 1e-30,
                    "x {x}"
                );
            }
        }
        assert!(worst64 < 2.5e-7, "f64 arithmetic: {worst64:e}");
        assert!(worst32 < 4e-7, "f32 arithmetic: {worst32:e}");
    }

    #[test]
    fn curvature_matches_the_f64_reference_to_1e_4_relative() {
        for x in arguments() {
            if x > 1e4 {
                continue; // the reference's direct formula loses digits there
            }
            let (_, g_ref) = reference(x);
            let g32 = f64::from(BesselRatio::<f32>::at(x as f32).curvature);
            assert!(g32 > 0.0, "x {x}");
            assert!(
                (g32 - g_ref).abs() <= 1e-4 * g_ref,
                "x {x}: {g32} vs {g_ref}"
            );
        }
        // beyond, against the asymptotic g ≈ 1/x³ − 1/x⁴
        for &x in &[1e5f64, 1e6, 1e7] {
            let g = f64::from(BesselRatio::<f32>::at(x as f32).curvature);
            let g_ref = 1.0 / (x * x * x) - 1.0 / (x * x * x * x);
            assert!((g - g_ref).abs() <= 1e-4 * g_ref, "x {x}");
        }
    }

    #[test]
    fn huge_and_edge_arguments_stay_finite() {
        for x in [
            0.0f32,
            f32::MIN_POSITIVE,
            88.0,
            89.0,
            1e20,
            f32::MAX,
            f32::INFINITY,
        ] {
            let b = BesselRatio::at(x);
            assert!(b.ratio.is_finite() && b.ratio_over_x.is_finite() && b.curvature.is_finite());
            assert!(b.ratio <= 1.0 && b.ratio_over_x <= 0.5 && b.curvature <= 0.125);
        }
        assert_eq!(BesselRatio::at(f32::INFINITY).ratio, 1.0);
        assert!((BesselRatio::at(0.0f32).ratio_over_x - 0.5).abs() < 1e-7);
        assert!(BesselRatio::at(f32::NAN).ratio.is_nan());
    }
}
