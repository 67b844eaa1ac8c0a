//! The snapshot (single-epoch) attitude solver of paper 002, in the form a receiver can fly.
//!
//! The printed algorithm needs `G = BBᵀ` invertible, which three antennas (two coplanar
//! baselines) never give, and its polar factor can be a reflection (seed specification, Paper
//! 002, errata 1 and 4). [`SnapshotSolver`] follows the corrected procedure of the
//! specification, Paper 002 (a):
//!
//! 1. Reference-frame baselines by weighted least squares, `a_i = (S W Sᵀ)⁻¹ S W r_i`
//!    (step 1; `W = diag(1/σ_j²)`; with the Kronecker noise `σ_j² Σ_B` this per-baseline LS is
//!    also the generalized LS of all baselines together).
//! 2. The cross-product pair `b_1 × b_2 ↔ a_1 × a_2` is appended (step 2).
//! 3. Wahba's problem gives the starting rotation (step 3; [`super::wahba`], never a
//!    reflection).
//! 4. Gauss–Newton on SO(3) minimizes the exact negative log-likelihood
//!    `J(C) = Σ_ik (Σ_B⁻¹)_ik (a_i − C b_i)ᵀ N (a_k − C b_k)`, `N = S W Sᵀ`, which equals the
//!    range-domain cost (4) weighted by `(Σ_B ⊗ W⁻¹)⁻¹` up to a constant (step 4). The update is
//!    `C ← C exp([δ]×)`, i.e. paper 002's `A ← exp(−[δθ]×) A` with `A = Cᵀ`; the Jacobian of
//!    `Δr_ij` with respect to `δ` is `b_i × (A s_j)`. At most [`GAUSS_NEWTON_MAX_ITERATIONS`]
//!    iterations; two or three reach the rounding level. This runs twice: first on the LS
//!    baselines (cheap, also the candidate fit of the ambiguity search), then on the range
//!    residuals themselves, which stay exact in `f32` when a poor sky makes `N` ill-conditioned;
//!    each stage is bounded by [`GAUSS_NEWTON_MAX_ITERATIONS`].
//!
//! The covariance is the inverse Gauss–Newton Hessian: the Cramér–Rao bound of the linearized
//! model, in the body-frame rotation vector `δ` with `C_true = Ĉ exp([δ]×)`.

use nalgebra::{Matrix3, Vector3};

use crate::ekf::{chi_square_quantile, GateConfidence};
use crate::geometry::{skew, Euler321, Quaternion};
use crate::{real, Real};

use super::range_model::{
    los_normal_matrix, BaselineCorrelation, Baselines, RangeDifferences, SatelliteRanges,
};
use super::wahba::{WahbaPair, WahbaProblem};
use crate::error::{Error, ErrorKind};
use crate::geometry::GeometryError;

/// Upper bound on the Gauss–Newton iterations of [`SnapshotSolver`].
pub const GAUSS_NEWTON_MAX_ITERATIONS: usize = 8;

/// How much to trust a [`SnapshotSolution`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SnapshotQuality {
    /// Converged, and the weighted residuals pass the χ² test at 99.9 %.
    Good,
    /// Converged, but the weighted residuals exceed the 99.9 % χ² quantile: a wrong integer
    /// ambiguity, a cycle slip, multipath or a wrong noise level. Do not feed a filter with it.
    ResidualHigh,
    /// The Gauss–Newton iteration reached its bound; the estimate is the last iterate.
    NotConverged,
}

/// The result of one snapshot solve.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SnapshotSolution<T = f32> {
    /// Attitude `C_rb`, body to reference (paper 002's `A` is its transpose).
    pub c_rb: Matrix3<T>,
    /// The same attitude as the unit quaternion `q_rb` (scalar part `≥ 0`).
    pub q_rb: Quaternion<T>,
    /// The same attitude as 3-2-1 Euler angles (heading = yaw), radians.
    pub euler: Euler321<T>,
    /// Covariance of the body-frame rotation-vector error `δ` (`C_true = Ĉ exp([δ]×)`), rad².
    pub covariance: Matrix3<T>,
    /// RMS of the range-difference residuals, metres.
    pub residual_rms: T,
    /// Weighted sum of squared residuals (χ² with `dof` degrees of freedom if the model holds).
    pub chi_square: T,
    /// Degrees of freedom `m n − 3`.
    pub dof: u16,
    /// Gauss–Newton iterations used.
    pub iterations: u8,
    /// Quality flag.
    pub quality: SnapshotQuality,
}

impl<T: Real> SnapshotSolution<T> {
    /// Standard deviations of the 3-2-1 angles `(yaw, pitch, roll)`, radians, from
    /// [`Self::covariance`] (`δ_body = E · (δroll, δpitch, δyaw)`, kinematic matrix of the
    /// 3-2-1 sequence). `None` within 1e-3 rad of gimbal lock (pitch ±90°).
    pub fn euler_std(&self) -> Option<[T; 3]> {
        let (sr, cr) = self.euler.roll.sin_cos();
        let (sp, cp) = self.euler.pitch.sin_cos();
        if !(cp.abs() > real(1e-3)) {
            return None;
        }
        // (δroll, δpitch, δyaw) = E⁻¹ δ_body
        let e_inv = Matrix3::new(
            T::one(),
            sr * sp / cp,
            cr * sp / cp,
            T::zero(),
            cr,
            -sr,
            T::zero(),
            sr / cp,
            cr / cp,
        );
        let p = e_inv * self.covariance * e_inv.transpose();
        Some([p.m33.sqrt(), p.m22.sqrt(), p.m11.sqrt()])
    }
}

/// The fit of a rotation to reference-frame baseline estimates (internal to the snapshot and
/// ambiguity solvers).
#[derive(Clone, Copy, Debug)]
pub(crate) struct BaselineFit<T> {
    pub q_rb: Quaternion<T>,
    /// `J(C)` at the optimum (dimensionless when `info` is an information matrix).
    pub cost: T,
    /// Gauss–Newton Hessian `H` (information of `δ`).
    pub hessian: Matrix3<T>,
    pub iterations: u8,
    pub converged: bool,
}

/// Single-epoch maximum-likelihood attitude from range differences on `M ≥ 2` baselines.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SnapshotSolver<const M: usize, T = f32> {
    baselines: Baselines<M, T>,
    correlation: BaselineCorrelation<M, T>,
}

impl<const M: usize, T: Real> SnapshotSolver<M, T> {
    /// A solver for the given body baselines and baseline noise correlation `Σ_B`.
    pub fn new(baselines: Baselines<M, T>, correlation: BaselineCorrelation<M, T>) -> Self {
        Self {
            baselines,
            correlation,
        }
    }

    /// The body baselines.
    pub fn baselines(&self) -> &Baselines<M, T> {
        &self.baselines
    }

    /// The baseline noise correlation.
    pub fn correlation(&self) -> &BaselineCorrelation<M, T> {
        &self.correlation
    }

    /// Solves one epoch.
    ///
    /// # Errors
    /// [`SnapshotError::TooFewSatellites`], [`SnapshotError::CoplanarLineOfSight`] for
    /// geometry that cannot separate the baseline components; [`SnapshotError::NotConverged`]
    /// if Wahba's eigen-decomposition fails; [`SnapshotError::CollinearBaselines`] if the
    /// estimated reference baselines are parallel; [`SnapshotError::Numerical`] if the
    /// Gauss–Newton normal matrix is singular, or when χ² or the covariance is not finite
    /// or the covariance not positive on its diagonal; [`SnapshotError::InvalidNoise`] when
    /// the smallest σ squares to zero or infinity in `T` (σ below about 4e-23 m in `f32`). Input values
    /// were validated on insertion. Never `Ok` with a non-finite statistic.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub fn solve<const N: usize>(
        &self,
        obs: &RangeDifferences<M, N, T>,
    ) -> Result<SnapshotSolution<T>, SnapshotError> {
        let sats = obs.satellites();
        // Weights relative to the most precise satellite, so that N and H stay in range in f32
        // whatever the units of σ; the absolute scale σ_min² returns in the covariance and χ².
        let sigma_min =
            sats.iter()
                .map(|s| s.sigma)
                .fold(T::max_value().unwrap_or(T::one()), |a, b| {
                    if b < a {
                        b
                    } else {
                        a
                    }
                });
        let scale = sigma_min * sigma_min;
        // σ_min² must be positive and finite: a σ of 1e-30 m squares to 0 in f32, and χ² and
        // the covariance would then be ∞ and 0 (a σ² that is barely positive is caught by the
        // checks of the outputs below).
        if !(scale > T::zero() && scale.is_finite()) {
            return Err(SnapshotError::InvalidNoise);
        }
        let weight = |sigma: T| {
            let r = sigma_min / sigma;
            r * r
        };
        let (info, info_inv) = los_normal_matrix(sats.iter().map(|s| (s.los, weight(s.sigma))))?;
        let a = least_squares_baselines(sats, &weight, &info_inv);
        // Steps 2–4 in the baseline domain (the start), then step 4 on the ranges themselves:
        // in f32 the LS baselines a_i inherit cond(N) ε of rounding with a poor sky, the range
        // residuals do not.
        let start = self.fit_reference_baselines(&a, &info)?;
        let fit = self.range_gauss_newton(start.q_rb, sats, &weight, scale)?;
        let c_rb = fit.q_rb.to_dcm();
        let (chi_square, residual_rms) = self.residuals(&c_rb, sats, &weight, scale);
        let count = M.saturating_mul(sats.len());
        let covariance = fit
            .hessian
            .cholesky()
            .map(|c| c.inverse() * scale)
            .ok_or(SnapshotError::Numerical)?;
        let dof = count.saturating_sub(3);
        let gate = chi_square_quantile(dof, GateConfidence::P999).unwrap_or(f64::INFINITY);
        let quality = if !fit.converged {
            SnapshotQuality::NotConverged
        } else if dof > 0 && !(chi_square <= real(gate)) {
            SnapshotQuality::ResidualHigh
        } else {
            SnapshotQuality::Good
        };
        let euler = Euler321::from_dcm(&c_rb)?;
        let positive = covariance.diagonal().iter().all(|&v| v > T::zero());
        let finite = covariance.iter().all(|v| v.is_finite())
            && residual_rms.is_finite()
            && chi_square.is_finite();
        if !(positive && finite) {
            return Err(SnapshotError::Numerical);
        }
        Ok(SnapshotSolution {
            c_rb,
            q_rb: fit.q_rb,
            euler,
            covariance,
            residual_rms,
            chi_square,
            dof: u16::try_from(dof).unwrap_or(u16::MAX),
            iterations: fit.iterations,
            quality,
        })
    }

    /// The residuals of eq. (4) at the solution `c_rb`: χ² weighted by `(σ_j² Σ_B)⁻¹` (in the
    /// units of σ², through `scale = σ_min²`) and the RMS range-difference residual, m.
    fn residuals(
        &self,
        c_rb: &Matrix3<T>,
        sats: &[SatelliteRanges<M, T>],
        weight: &impl Fn(T) -> T,
        scale: T,
    ) -> (T, T) {
        let w_b = self.correlation.inverse();
        let mut chi_square = T::zero();
        let mut sum_sq = T::zero();
        for s in sats {
            let predicted = self.baselines.range_differences(c_rb, &s.los);
            let mut e = [T::zero(); M];
            for ((ei, &r), &p) in e.iter_mut().zip(s.range_diff.iter()).zip(predicted.iter()) {
                *ei = r - p;
                sum_sq += *ei * *ei;
            }
            let mut q = T::zero();
            for (i, &ei) in (0..e.len()).zip(e.iter()) {
                for (k, &ek) in (0..e.len()).zip(e.iter()) {
                    q += ei * w_b[(i, k)] * ek;
                }
            }
            chi_square += q * weight(s.sigma);
        }
        let count = M.saturating_mul(sats.len());
        (chi_square / scale, (sum_sq / real(count as f64)).sqrt())
    }

    /// Steps 2–4: the rotation that best fits reference-frame baseline estimates `a_i` whose
    /// errors have information `Σ_B⁻¹ ⊗ info` (`info = S W Sᵀ`, or any SPD 3×3 metric).
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub(crate) fn fit_reference_baselines(
        &self,
        a: &[Vector3<T>; M],
        info: &Matrix3<T>,
    ) -> Result<BaselineFit<T>, SnapshotError> {
        let b = self.baselines.as_array();
        // Wahba start: each baseline direction weighted alike, plus b1 × b2 ↔ a1 × a2.
        let mut wahba = WahbaProblem::new();
        for (bi, ai) in b.iter().zip(a.iter()) {
            wahba.add(&WahbaPair {
                body: *bi,
                reference: *ai,
                weight: T::one() / bi.norm_squared(),
            })?;
        }
        if let (Some(b1), Some(b2), Some(a1), Some(a2)) = (b.first(), b.get(1), a.first(), a.get(1))
        {
            let bc = b1.cross(b2);
            wahba.add(&WahbaPair {
                body: bc,
                reference: a1.cross(a2),
                weight: T::one() / bc.norm_squared(),
            })?;
        }
        let mut q = wahba.solve()?.q_rb;
        // Gauss–Newton on SO(3)
        let tolerance = T::default_epsilon() * real(64.0);
        let mut iterations = 0u8;
        let mut converged = false;
        for _ in 0..GAUSS_NEWTON_MAX_ITERATIONS {
            let (h, g, _) = self.normal_equations(&q.to_dcm(), a, info);
            let delta = -h.cholesky().ok_or(SnapshotError::Numerical)?.solve(&g);
            if !delta.iter().all(|v| v.is_finite()) {
                return Err(SnapshotError::Numerical);
            }
            // C ← C exp([δ]×)
            q = (q * Quaternion::from_rotation_vector(&delta)).normalize()?;
            iterations = iterations.saturating_add(1);
            if delta.norm() <= tolerance {
                converged = true;
                break;
            }
        }
        // In f32 the step stalls at the rounding level (~1e-6 rad) rather than below
        // 64 ε; accept a final step that is small against the attitude uncertainty.
        let (hessian, g, cost) = self.normal_equations(&q.to_dcm(), a, info);
        if !converged {
            if let Some(ch) = hessian.cholesky() {
                let last = ch.solve(&g);
                let sigma2 = ch.inverse().trace();
                converged = last.norm_squared() <= sigma2 * real(1e-4);
            }
        }
        Ok(BaselineFit {
            q_rb: q.canonical(),
            cost,
            hessian,
            iterations,
            converged,
        })
    }

    /// Gauss–Newton on cost (4) in the range domain: rows `h_ij = b_i × (C_rbᵀ s_j)`,
    /// `H = Σ_j w_j Σ_ik W_ik h_ij h_kjᵀ`, `g = Σ_j w_j Σ_ik W_ik h_ij e_kj`, `δ = H⁻¹ g`,
    /// `C ← C exp([δ]×)`; at most [`GAUSS_NEWTON_MAX_ITERATIONS`] iterations.
    fn range_gauss_newton(
        &self,
        start: Quaternion<T>,
        sats: &[super::range_model::SatelliteRanges<M, T>],
        weight: &impl Fn(T) -> T,
        scale: T,
    ) -> Result<BaselineFit<T>, SnapshotError> {
        let w = self.correlation.inverse();
        let b = self.baselines.as_array();
        let mut q = start;
        let mut iterations = 0u8;
        let mut converged = false;
        let tolerance = T::default_epsilon() * real(4.0);
        let mut hessian = Matrix3::zeros();
        for _ in 0..GAUSS_NEWTON_MAX_ITERATIONS {
            let c = q.to_dcm();
            let mut h = Matrix3::<T>::zeros();
            let mut g = Vector3::<T>::zeros();
            for s in sats {
                let u = c.transpose() * s.los;
                let wj = weight(s.sigma);
                let rows: [Vector3<T>; M] = core::array::from_fn(|i| b[i].cross(&u));
                let mut e = [T::zero(); M];
                for ((ei, bi), &r) in e.iter_mut().zip(b.iter()).zip(s.range_diff.iter()) {
                    *ei = r - bi.dot(&u);
                }
                for (i, hi) in (0..rows.len()).zip(rows.iter()) {
                    for (k, hk) in (0..rows.len()).zip(rows.iter()) {
                        let wik = w[(i, k)] * wj;
                        h += hi * hk.transpose() * wik;
                        g += hi * (e[k] * wik);
                    }
                }
            }
            hessian = h;
            let chol = h.cholesky().ok_or(SnapshotError::Numerical)?;
            let delta = chol.solve(&g);
            if !delta.iter().all(|v| v.is_finite()) {
                return Err(SnapshotError::Numerical);
            }
            // H is in relative weights: the attitude variance is tr(H⁻¹) σ_min².
            let small = delta.norm() <= tolerance
                || delta.norm_squared() <= chol.inverse().trace() * scale * real(1e-6);
            q = (q * Quaternion::from_rotation_vector(&delta)).normalize()?;
            iterations = iterations.saturating_add(1);
            if small {
                // the step was below rounding or far below the attitude uncertainty
                converged = true;
                break;
            }
        }
        Ok(BaselineFit {
            q_rb: q.canonical(),
            cost: T::zero(),
            hessian,
            iterations,
            converged,
        })
    }

    /// `H = Σ W_ik J_iᵀ N J_k`, `g = Σ W_ik J_iᵀ N e_k`, `J(C)`, with `J_i = C [b_i]×`,
    /// `e_i = a_i − C b_i`, `W = Σ_B⁻¹`.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    fn normal_equations(
        &self,
        c: &Matrix3<T>,
        a: &[Vector3<T>; M],
        info: &Matrix3<T>,
    ) -> (Matrix3<T>, Vector3<T>, T) {
        let w = self.correlation.inverse();
        let b = self.baselines.as_array();
        let mut h = Matrix3::zeros();
        let mut g = Vector3::zeros();
        let mut cost = T::zero();
        // (indices from `0..M`, not `enumerate`: its counter keeps an overflow check)
        for (i, (bi, ai)) in (0..M).zip(b.iter().zip(a.iter())) {
            let ji = c * skew(bi);
            let ei = ai - c * bi;
            for (k, (bk, ak)) in (0..M).zip(b.iter().zip(a.iter())) {
                let wik = w[(i, k)];
                let nj = info * (c * skew(bk));
                let ne = info * (ak - c * bk);
                h += ji.transpose() * nj * wik;
                g += ji.transpose() * ne * wik;
                cost += ei.dot(&ne) * wik;
            }
        }
        (h, g, cost)
    }
}

/// Errors of the snapshot attitude solvers ([`crate::attitude`]): input validation, the
/// paper's formula and the bounded numerical routines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SnapshotError {
    /// A baseline, line of sight, range difference, phase, code or noise value was NaN or
    /// infinite.
    #[error("non-finite snapshot input")]
    NonFinite,
    /// Fewer than 3 satellites: the reference-frame baselines `a_i = (SSᵀ)⁻¹ S r_i` need three
    /// independent lines of sight.
    #[error("fewer than 3 satellites")]
    TooFewSatellites,
    /// More satellites than the compile-time capacity `N` of the observation set.
    #[error("more satellites than the capacity")]
    TooManySatellites,
    /// The same satellite id was given twice in one epoch.
    #[error("satellite listed twice")]
    DuplicateSatellite,
    /// A line-of-sight vector is not a unit vector (its norm is off 1 by more than 1e-3).
    #[error("line of sight is not a unit vector")]
    InvalidLineOfSight,
    /// The lines of sight are (nearly) coplanar or collinear: `N = S W Sᵀ` is singular, so the
    /// three components of a baseline cannot be separated.
    #[error("lines of sight are coplanar or collinear")]
    CoplanarLineOfSight,
    /// A noise standard deviation, cofactor or wavelength is zero or negative.
    #[error("noise, cofactor or wavelength is not positive")]
    InvalidNoise,
    /// A body baseline is shorter than 1 mm.
    #[error("baseline of zero length")]
    ZeroBaseline,
    /// The first two body baselines are (nearly) parallel: the attitude about their common
    /// direction is not observable.
    #[error("baselines are collinear")]
    CollinearBaselines,
    /// The paper's formula (16) needs `G = BBᵀ` invertible: at least three non-coplanar
    /// baselines (four non-coplanar antennas).
    #[error("baselines are coplanar (paper formula needs 3 non-coplanar)")]
    CoplanarBaselines,
    /// Fewer baselines than the method needs (two for the snapshot solver, three for the
    /// paper's formula).
    #[error("too few baselines")]
    TooFewBaselines,
    /// The baseline noise correlation matrix is not symmetric positive definite.
    #[error("baseline correlation is not positive definite")]
    InvalidCorrelation,
    /// The paper's formula (16) would return a reflection (`det Q < 0`), not a rotation.
    #[error("paper formula (16) gives a reflection (det Q < 0)")]
    Reflection,
    /// A bounded iteration (Jacobi eigen-decomposition) reached its bound without converging.
    #[error("eigen-decomposition did not converge")]
    NotConverged,
    /// A computation produced a non-finite or degenerate result from finite input.
    #[error("snapshot computation failed numerically")]
    Numerical,
    /// An attitude could not be formed from the solution (normalization, angles).
    #[error("attitude of the solution refused")]
    Geometry(#[from] GeometryError),
}

impl Error for SnapshotError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::TooFewSatellites
            | Self::TooManySatellites
            | Self::DuplicateSatellite
            | Self::InvalidLineOfSight
            | Self::InvalidNoise
            | Self::ZeroBaseline
            | Self::CollinearBaselines
            | Self::TooFewBaselines
            | Self::InvalidCorrelation => ErrorKind::InvalidInput,
            Self::CoplanarLineOfSight | Self::CoplanarBaselines | Self::Reflection => {
                ErrorKind::Unobservable
            }
            Self::NotConverged => ErrorKind::NotConverged,
            Self::Numerical => ErrorKind::Numerical,
            Self::Geometry(e) => e.kind(),
        }
    }
}

/// Step 1: the reference-frame baselines by weighted least squares,
/// `a_i = (S W Sᵀ)⁻¹ S W r_i`, m.
fn least_squares_baselines<const M: usize, T: Real>(
    sats: &[SatelliteRanges<M, T>],
    weight: &impl Fn(T) -> T,
    info_inv: &Matrix3<T>,
) -> [Vector3<T>; M] {
    let mut a = [Vector3::<T>::zeros(); M];
    for (i, ai) in (0..M).zip(a.iter_mut()) {
        let mut rhs = Vector3::zeros();
        for s in sats {
            if let Some(&r) = s.range_diff.get(i) {
                rhs += s.los * (r * weight(s.sigma));
            }
        }
        *ai = info_inv * rhs;
    }
    a
}
