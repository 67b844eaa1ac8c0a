//! Sine and cosine for the per-satellite phases, fast in `f32` on the Cortex-M4F.
//!
//! libm's `sinf`/`cosf` reduce the argument and evaluate their kernels in `f64`, which the
//! M4F's single-precision FPU emulates in software: about 3 000 instructions per call, more
//! than everything else a satellite costs. Here single-precision types use a Cody–Waite
//! reduction by π/2 in three parts (exact products for `|n| < 2¹⁶`) and the Cephes minimax
//! polynomials on `[−π/4, π/4]`; measured error below 1.2e-7 (2 ulp of 1) for `|x| ≤ 8192`
//! (tests below). Larger arguments, and `f64`, use the type's own `sin_cos`.

use crate::{real, Real};

/// Largest `|x|` the fast path takes (beyond, the reduction loses digits).
const FAST_LIMIT: f64 = 8192.0;

/// `(sin x, cos x)`.
#[inline]
pub fn sin_cos<T: Real>(x: T) -> (T, T) {
    // f32-like precision: the fast path (the test folds at compile time)
    let single = T::default_epsilon() > real(1e-10);
    if !single || !(x.abs() <= real(FAST_LIMIT)) {
        return x.sin_cos();
    }
    // n = nearest integer to x/(π/2); r = x − n π/2 in three parts (P1 has 8 significant
    // bits, so n·P1 is exact)
    let n = (x * real(core::f64::consts::FRAC_2_PI)).round();
    let r = ((x - n * real(1.570_312_5)) - n * real(4.837_512_969_970_703e-4))
        - n * real(7.549_789_954_891_882e-8);
    let z = r * r;
    // Cephes sinf / cosf kernels on [−π/4, π/4]
    let s = r + r
        * z
        * (real::<T>(-1.666_665_461_1e-1)
            + z * (real::<T>(8.332_160_873_6e-3) + z * real(-1.951_529_589_1e-4)));
    let c = T::one() - z * real(0.5)
        + z * z
            * (real::<T>(4.166_664_568_298_827e-2)
                + z * (real::<T>(-1.388_731_625_493_765e-3) + z * real(2.443_315_711_809_948e-5)));
    // quadrant q = n mod 4
    let q = n - (n * real(0.25)).floor() * real(4.0);
    if q < real(0.5) {
        (s, c)
    } else if q < real(1.5) {
        (c, -s)
    } else if q < real(2.5) {
        (-s, -c)
    } else {
        (-c, s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_f32_sin_cos_matches_f64_to_two_ulp() {
        let mut worst = 0.0f64;
        for k in -200_000..=200_000 {
            let x = k as f32 * 0.040_96; // ±8192
            let (s, c) = sin_cos(x);
            let (s64, c64) = f64::from(x).sin_cos();
            worst = worst
                .max((f64::from(s) - s64).abs())
                .max((f64::from(c) - c64).abs());
        }
        assert!(worst < 1.2e-7, "worst {worst:e}");
        // beyond the fast range and for f64: the library's
        let (s, c) = sin_cos(1e6f32);
        assert!((f64::from(s) - 1e6f64.sin()).abs() < 1e-3 && c.is_finite());
        assert_eq!(sin_cos(0.3f64), 0.3f64.sin_cos());
        assert!(sin_cos(f32::NAN).0.is_nan());
    }
}
