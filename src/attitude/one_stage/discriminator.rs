//! The per-satellite statistics of paper 003: the coherent sum over the antennas (eq. (18)),
//! its squared magnitude `X_i²` (eq. (20)), the phase discriminators `∂F_i/∂ψ_{P,i}`
//! (eqs. (22)/(23)) and the curvature `−∂²F_i/∂ψ∂ψᵀ` the Gaussian-approximation filter needs
//! for eq. (12).
//!
//! # Sign convention of the correlator outputs
//!
//! This module takes the prompt correlator outputs in the usual receiver convention,
//! `Z_P = I_P + jQ_P ≈ A d e^{j(φ + ψ_P + b_P)} + noise`: the carrier phase of antenna `P`
//! (common phase `φ`, data bit `d = ±1`, geometric phase `ψ_P`, line bias `b_P`) appears with
//! a **plus** sign. The paper's correlators (19) multiply by `cos` and `sin` of the replica
//! phase, which gives the conjugate, `Z_P^{(19)} = I_P − jQ_P`. Its eq. (18),
//! `X_c + jX_s = Σ_P Z_P^{(19)} e^{jψ_P}`, is therefore computed here as the conjugate of
//! `S = Σ_P Z_P e^{−jψ_P}`, and `X² = |S|²` is the same number. A receiver whose `Q` has the
//! other sign negates it in its adapter (see [`super::SatelliteObservation`]).
//!
//! # Units
//!
//! The inputs are normalized by the noise: `z_P = Z_P/σ` with `σ²` the noise variance of each
//! of `I` and `Q`, so that the likelihood's scale `a = A/σ²` of eq. (15) becomes
//! `a σ = √(2 q_T)` with `q_T = (C/N0)·T` (the post-correlation SNR `A²/(2σ²)`). In these units
//! `F_i = ln I₀(√(2q_T) X_i)`.
//!
//! # Derivatives (verified by finite differences in the tests)
//!
//! With `w_P = z_P e^{−jψ_P}`, `S = Σ w_P`, `s = |S|² = X²`, `x = √(2q_T) X`, `r = I₁/I₀(x)`:
//!
//! * `∂s/∂ψ_P = 2 Im(S* w_P)`, and `Σ_P ∂s/∂ψ_P = 0` (a common phase does not change `X`);
//! * eq. (23): `∂F/∂ψ_P = r(x) · a · ∂X/∂ψ_P = 2q_T (r/x) Im(S* w_P)`;
//! * `∂²s/∂ψ_P∂ψ_Q = 2 Re(w_P w_Q*) − 2 δ_PQ Re(S* w_P)`;
//! * `−∂²F/∂ψ∂ψᵀ = q_T² g(x) ∇s ∇sᵀ − q_T (r/x) ∇²s`, with `g = (2r/x + r² − 1)/x²` from
//!   [`BesselRatio`]. No step divides by `X`, so `X → 0` is harmless.

use nalgebra::{Complex, Matrix2, Matrix3, Vector2, Vector3};

use crate::{real, Real};

use super::bessel::BesselRatio;
use super::trig::sin_cos;

/// Prompt correlator outputs of one satellite on antennas A, B, C: `Z_P = I_P + jQ_P`, any
/// consistent unit (counts of a fixed-point correlator, volts).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PromptIq<T = f32> {
    /// In-phase outputs of A, B, C.
    pub i: [T; 3],
    /// Quadrature outputs of A, B, C (receiver convention, see the module documentation).
    pub q: [T; 3],
}

impl<T: Real> PromptIq<T> {
    /// The outputs as complex numbers `Z_P = I_P + jQ_P`, each divided by `sigma` (the noise
    /// standard deviation per component).
    pub fn normalized(&self, sigma: T) -> [Complex<T>; 3] {
        let inv = sigma.recip();
        let [ia, ib, ic] = self.i;
        let [qa, qb, qc] = self.q;
        [
            Complex::new(ia * inv, qa * inv),
            Complex::new(ib * inv, qb * inv),
            Complex::new(ic * inv, qc * inv),
        ]
    }
}

/// `w_P = z_P e^{−jψ_P}`: each antenna's output rotated back by its predicted phase.
fn derotate<T: Real>(z: &[Complex<T>; 3], psi: &Vector3<T>) -> [Complex<T>; 3] {
    let [za, zb, zc] = *z;
    let rot = |zp: Complex<T>, p: T| {
        let (s, c) = sin_cos(p);
        zp * Complex::new(c, -s)
    };
    [rot(za, psi.x), rot(zb, psi.y), rot(zc, psi.z)]
}

/// The coherent sum of eq. (18) in the receiver convention, `S = Σ_P Z_P e^{−jψ_P}`
/// (the paper's `X_c + jX_s` is its conjugate). `X² = |S|²` is eq. (20).
pub fn coherent_sum<T: Real>(z: &[Complex<T>; 3], psi: &Vector3<T>) -> Complex<T> {
    let [a, b, c] = derotate(z, psi);
    a + b + c
}

/// Everything one satellite contributes at one predicted phase vector `ψ`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SatelliteTerms<T = f32> {
    /// `X_i²` of eq. (20), in noise units (`σ = 1`).
    pub x_squared: T,
    /// `Σ_P |z_P|²`, the non-coherent power of the three antennas, noise units.
    pub antenna_power: T,
    /// The Bessel factors at `x = √(2q_T) X_i`.
    pub bessel: BesselRatio<T>,
    /// `∂F_i/∂ψ_{P,i}` for P = A, B, C (eq. (23)), 1/rad. Sums to zero.
    pub gradient: Vector3<T>,
    /// `−∂²F_i/∂ψ∂ψᵀ` (the observed information in ψ), 1/rad². Rows sum to zero.
    pub curvature: Matrix3<T>,
}

/// The statistics of one satellite: normalized outputs `z` (see [`PromptIq::normalized`]),
/// predicted phases `psi` (radians, eq. (24) plus line biases) and the post-correlation SNR
/// `q_t = (C/N0)·T` (linear).
pub fn satellite_terms<T: Real>(
    z: &[Complex<T>; 3],
    psi: &Vector3<T>,
    q_t: T,
) -> SatelliteTerms<T> {
    let w = derotate(z, psi);
    let [wa, wb, wc] = w;
    let s = wa + wb + wc; // eq. (18), conjugated
    let x_squared = s.norm_sqr(); // eq. (20)
    let antenna_power = wa.norm_sqr() + wb.norm_sqr() + wc.norm_sqr();
    let two = real::<T>(2.0);
    let x = (two * q_t * x_squared).sqrt();
    let bessel = BesselRatio::at(x);
    // ∂s/∂ψ_P = 2 Im(S* w_P)
    let im = |wp: Complex<T>| (s.conj() * wp).im;
    let ds = Vector3::new(im(wa), im(wb), im(wc)) * two;
    // eq. (23): ∂F/∂ψ_P = (I₁/I₀)(x) a ∂X/∂ψ_P = q_T (r/x) ∂s/∂ψ_P
    let gradient = ds * (q_t * bessel.ratio_over_x);
    // ∂²s/∂ψ_P∂ψ_Q = 2 Re(w_P w_Q*) − 2 δ_PQ Re(S* w_P)
    let re = |p: Complex<T>, q: Complex<T>| (p * q.conj()).re;
    let mut d2s = Matrix3::new(
        re(wa, wa),
        re(wa, wb),
        re(wa, wc),
        re(wb, wa),
        re(wb, wb),
        re(wb, wc),
        re(wc, wa),
        re(wc, wb),
        re(wc, wc),
    );
    d2s.m11 -= (s.conj() * wa).re;
    d2s.m22 -= (s.conj() * wb).re;
    d2s.m33 -= (s.conj() * wc).re;
    d2s *= two;
    // −∂²F = q_T² g ∇s∇sᵀ − q_T (r/x) ∇²s
    let curvature =
        ds * ds.transpose() * (q_t * q_t * bessel.curvature) - d2s * (q_t * bessel.ratio_over_x);
    SatelliteTerms {
        x_squared,
        antenna_power,
        bessel,
        gradient,
        curvature,
    }
}

/// An orthonormal basis of the phase differences, the plane orthogonal to `(1, 1, 1)`:
/// columns `(1, −1, 0)/√2` and `(1, 1, −2)/√6`. The likelihood does not change along
/// `(1, 1, 1)` (a common phase), so its curvature lives in this plane.
pub fn difference_basis<T: Real>() -> nalgebra::Matrix3x2<T> {
    let a = real::<T>(core::f64::consts::FRAC_1_SQRT_2); // 1/√2
    let b = real::<T>(0.408_248_290_463_863); // 1/√6
    nalgebra::Matrix3x2::new(a, b, -a, b, T::zero(), -(b + b))
}

/// The curvature restricted to the difference plane with its eigenvalues floored at `floor`
/// (1/rad²): the definiteness guard of eq. (12). Returns the floored 2×2 matrix in the basis of
/// [`difference_basis`] and whether the floor was active.
///
/// The symmetric 2×2 eigen-decomposition is closed form (no iteration).
pub fn floored_plane_curvature<T: Real>(curvature: &Matrix3<T>, floor: T) -> (Matrix2<T>, bool) {
    let e = difference_basis::<T>();
    let h = e.transpose() * curvature * e;
    let half = real::<T>(0.5);
    let (a, b, c) = (h.m11, (h.m12 + h.m21) * half, h.m22);
    let mean = (a + c) * half;
    let d = (a - c) * half;
    let dev = (d * d + b * b).sqrt(); // not hypot: libm's hypotf computes in f64
    let (l1, l2) = (mean + dev, mean - dev);
    if l2 >= floor {
        return (Matrix2::new(a, b, b, c), false);
    }
    // eigenvector of l1: (b, l1 − a) or (l1 − c, b), whichever is longer (closed form)
    let v1 = Vector2::new(b, l1 - a);
    let v2 = Vector2::new(l1 - c, b);
    let v = if v1.norm_squared() >= v2.norm_squared() {
        v1
    } else {
        v2
    };
    let n = v.norm();
    let v = if n > T::zero() { v / n } else { Vector2::x() };
    let w = Vector2::new(-v.y, v.x);
    let (l1, l2) = (l1.max(floor), l2.max(floor));
    (v * v.transpose() * l1 + w * w.transpose() * l2, true)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> ([Complex<f64>; 3], Vector3<f64>, f64) {
        // a noisy, partly misaligned satellite
        let z = [
            Complex::new(3.1, -1.2),
            Complex::new(-0.7, 4.0),
            Complex::new(2.2, 2.9),
        ];
        (z, Vector3::new(0.4, -1.3, 2.2), 10.0)
    }

    fn log_likelihood(z: &[Complex<f64>; 3], psi: &Vector3<f64>, q_t: f64) -> f64 {
        // ln I₀(x) by the series (x is moderate here)
        let x = (2.0 * q_t).sqrt() * coherent_sum(z, psi).norm();
        let mut term = 1.0;
        let mut sum = 1.0;
        for k in 1..200 {
            term *= (x / 2.0) * (x / 2.0) / (f64::from(k) * f64::from(k));
            sum += term;
        }
        sum.ln()
    }

    #[test]
    fn x_squared_equals_eq_20_written_out() {
        let (z, psi, _) = sample();
        // eq. (20) with the paper's correlators I, Q⁽¹⁹⁾ = −Q
        let i = z.map(|c| c.re);
        let q = z.map(|c| -c.im);
        let p = [psi.x, psi.y, psi.z];
        let mut x2: f64 = (0..3).map(|k| i[k] * i[k] + q[k] * q[k]).sum();
        for (m, n) in [(0, 1), (0, 2), (1, 2)] {
            let d = p[m] - p[n];
            x2 += 2.0 * d.cos() * (i[m] * i[n] + q[m] * q[n])
                + 2.0 * d.sin() * (i[m] * q[n] - q[m] * i[n]);
        }
        let s = coherent_sum(&z, &psi);
        assert!((s.norm_sqr() - x2).abs() < 1e-12 * x2);
        // and eq. (18) itself: X_c + jX_s = Σ Z⁽¹⁹⁾ e^{jψ} is the conjugate of S
        let paper: Complex<f64> = (0..3)
            .map(|k| Complex::new(i[k], q[k]) * Complex::new(p[k].cos(), p[k].sin()))
            .sum();
        assert!((paper - s.conj()).norm() < 1e-12);
    }

    #[test]
    fn gradient_and_curvature_match_finite_differences() {
        let (z, psi, q_t) = sample();
        let t = satellite_terms(&z, &psi, q_t);
        let h = 1e-5;
        for p in 0..3 {
            let mut up = psi;
            let mut dn = psi;
            up[p] += h;
            dn[p] -= h;
            let fd = (log_likelihood(&z, &up, q_t) - log_likelihood(&z, &dn, q_t)) / (2.0 * h);
            assert!(
                (fd - t.gradient[p]).abs() < 1e-6 * t.gradient.norm(),
                "∂F/∂ψ_{p}"
            );
            let fd2 = (satellite_terms(&z, &up, q_t).gradient
                - satellite_terms(&z, &dn, q_t).gradient)
                / (2.0 * h);
            // curvature is −∂²F
            assert!((fd2 + t.curvature.column(p)).norm() < 1e-6 * t.curvature.norm());
        }
        assert!(t.gradient.sum().abs() < 1e-12 * t.gradient.norm());
        for row in t.curvature.row_iter() {
            assert!(row.sum().abs() < 1e-10 * t.curvature.norm());
        }
    }

    #[test]
    fn noise_free_discriminator_slope_is_2_q_t_times_the_projector() {
        // at the truth, −∂²F → 2 q_T Π · (slightly less at finite SNR) and the gradient for a
        // small phase error δ is ≈ 2 q_T Π δ (spec: J_T = 2 q_T Σ gᵀ Π g)
        let q_t: f64 = 10.0;
        let amp = (2.0 * q_t).sqrt();
        let truth = Vector3::new(0.3, -0.5, 1.1);
        let phi = 0.7;
        let z = [0, 1, 2].map(|p| Complex::from_polar(amp, phi + truth[p]));
        let delta = Vector3::new(1e-4, -2e-4, 0.5e-4);
        let t = satellite_terms(&z, &(truth - delta), q_t);
        let proj = Matrix3::identity() - Matrix3::repeat(1.0 / 3.0);
        let expected = proj * delta * (2.0 * q_t);
        // non-coherent factor r(x) at x = 3·2q_T = 60: 0.9916
        assert!((t.gradient - expected * t.bessel.ratio).norm() < 1e-3 * expected.norm());
        let c = satellite_terms(&z, &truth, q_t).curvature;
        assert!((c - proj * (2.0 * q_t)).norm() < 0.02 * 2.0 * q_t);
    }

    #[test]
    fn floor_keeps_eigenvectors_and_raises_only_small_eigenvalues() {
        let e = difference_basis::<f64>();
        assert!((e.transpose() * e - Matrix2::identity()).norm() < 1e-15);
        assert!((e.transpose() * Vector3::repeat(1.0)).norm() < 1e-15);
        let (z, psi, q_t) = sample();
        let c = satellite_terms(&z, &psi, q_t).curvature;
        let (h, _) = floored_plane_curvature(&c, -1e9);
        assert!(
            (h - e.transpose() * c * e).norm() < 1e-9 * c.norm(),
            "no floor: unchanged"
        );
        // an indefinite matrix: eigenvalues 3 and −1 along known directions
        let v = Vector2::new(0.6, 0.8);
        let w = Vector2::new(-0.8, 0.6);
        let m2 = v * v.transpose() * 3.0 - w * w.transpose();
        let m3 = e * m2 * e.transpose();
        let (h, floored) = floored_plane_curvature(&m3, 0.5);
        assert!(floored);
        let expect = v * v.transpose() * 3.0 + w * w.transpose() * 0.5;
        assert!((h - expect).norm() < 1e-12);
    }
}
