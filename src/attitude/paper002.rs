//! Paper 002's own least-squares formula, kept as the reference for `m ≥ 3` non-coplanar
//! baselines (four non-coplanar antennas).
//!
//! Eq. (6): `K = G⁻¹ B R` with `G = B Bᵀ` (needs three non-coplanar baselines); eq. (10)–(11):
//! maximize `tr(A Q)` with `Q = S Kᵀ` (the paper says "minimize": erratum 3); eq. (16):
//! `A = Qᵀ (Q Qᵀ)^{-1/2}`, the orthogonal polar factor of `Qᵀ`. It is exact without noise
//! (`Qᵀ = A N`, `N = S Sᵀ`), but it is a *reflection* when `det Q < 0` (erratum 4), and it is
//! not the maximum-likelihood estimate: it weighs the satellites and baselines as the algebra
//! happens to, not by their noise. [`paper_formula`] detects the reflection and reports it as
//! [`SnapshotError::Reflection`]; it never returns one. Use
//! [`super::snapshot::SnapshotSolver`] in flight.

use nalgebra::{Matrix3, Vector3};

use crate::attitude::snapshot::SnapshotError;
use crate::geometry::is_rotation;
use crate::{real, Real};

use super::range_model::{Baselines, RangeDifferences};
use crate::linalg::symmetric_eigen;

/// Eq. (16) on one epoch: returns `C_rb = Aᵀ` (the paper's `A = C_br` transposed into the
/// crate's convention). The per-satellite `sigma` are ignored, as in the paper.
///
/// `(Q Qᵀ)^{-1/2}` is computed from the bounded Jacobi eigen-decomposition
/// `Q Qᵀ = V Λ Vᵀ` as `V Λ^{-1/2} Vᵀ`.
///
/// # Errors
/// [`SnapshotError::TooFewBaselines`] for `M < 3`; [`SnapshotError::CoplanarBaselines`] when
/// `det G / (tr G / 3)³ < 1e-5`; [`SnapshotError::TooFewSatellites`] for fewer than 3
/// satellites; [`SnapshotError::CoplanarLineOfSight`] when `Q` is (near) singular;
/// [`SnapshotError::Reflection`] when `det Q < 0`; [`SnapshotError::NotConverged`] if the
/// eigen-decomposition reaches its bound; [`SnapshotError::Numerical`] when the result is not
/// orthonormal to `512 ε` (an ill-conditioned `Q`).
pub fn paper_formula<const M: usize, const N: usize, T: Real>(
    baselines: &Baselines<M, T>,
    obs: &RangeDifferences<M, N, T>,
) -> Result<Matrix3<T>, SnapshotError> {
    if M < 3 {
        return Err(SnapshotError::TooFewBaselines);
    }
    let sats = obs.satellites();
    if sats.len() < 3 {
        return Err(SnapshotError::TooFewSatellites);
    }
    let b = baselines.as_array();
    // G = B Bᵀ, eq. (3)
    let g = baselines.gram();
    let mean = g.trace() / real(3.0);
    if !(mean > T::zero()) || !(g.determinant() / (mean * mean * mean) >= real(1e-5)) {
        return Err(SnapshotError::CoplanarBaselines);
    }
    let g_inv = g
        .cholesky()
        .map(|c| c.inverse())
        .ok_or(SnapshotError::CoplanarBaselines)?;
    // Q = S Kᵀ = Σ_j s_j k_jᵀ with k_j = G⁻¹ Σ_i b_i Δr_ij (column j of K, eq. (6))
    let mut q = Matrix3::<T>::zeros();
    for s in sats {
        let mut bk = Vector3::zeros();
        for (bi, &r) in b.iter().zip(s.range_diff.iter()) {
            bk += bi * r;
        }
        let k = g_inv * bk;
        q += s.los * k.transpose();
    }
    let det = q.determinant();
    let scale = q.norm();
    if !(scale > T::zero()) || !(det.abs() > scale * scale * scale * real(1e-6)) {
        return Err(SnapshotError::CoplanarLineOfSight);
    }
    if det < T::zero() {
        // eq. (16) would return the improper polar factor: det A = sign det Q = −1
        return Err(SnapshotError::Reflection);
    }
    // (Q Qᵀ)^{-1/2} = V Λ^{-1/2} Vᵀ
    let (values, v) = symmetric_eigen(&(q * q.transpose())).ok_or(SnapshotError::NotConverged)?;
    if !(values[2] > T::zero()) {
        return Err(SnapshotError::CoplanarLineOfSight);
    }
    let inv_sqrt = Vector3::new(
        T::one() / values[0].sqrt(),
        T::one() / values[1].sqrt(),
        T::one() / values[2].sqrt(),
    );
    let root_inv = v * Matrix3::from_diagonal(&inv_sqrt) * v.transpose();
    let a = q.transpose() * root_inv; // eq. (16): A = Qᵀ (QQᵀ)^{-1/2}, reference → body
                                      // With an ill-conditioned Q the eigen route loses orthonormality (∝ cond(QQᵀ) ε): refuse
                                      // rather than return a matrix that is not a rotation to rounding.
    if !is_rotation(&a, T::default_epsilon() * real(512.0)) {
        return Err(SnapshotError::Numerical);
    }
    Ok(a.transpose())
}
