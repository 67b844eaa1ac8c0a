//! Wahba's problem by Davenport's q-method, solved with a bounded Jacobi eigen-decomposition.
//!
//! Find the rotation `C_rb` minimizing `Σ w_i |r_i − C_rb b_i|²` for vector pairs seen in body
//! axes (`b_i`) and in the reference frame (`r_i`). With the Hamilton quaternion
//! `q_rb = (w, v)` the gain `Σ w_i r_iᵀ C b_i` is the quadratic form `xᵀ K x`, `x = (v, w)`:
//!
//! ```text
//! B = Σ w_i r_i b_iᵀ,  σ = tr B,  S = B + Bᵀ,  z = Σ w_i b_i × r_i,
//! K = | S − σ I   z |
//!     |   zᵀ      σ |
//! ```
//!
//! The optimal quaternion is the eigenvector of the largest eigenvalue of `K` (Davenport).
//! This is the same optimum as the SVD solution `C = U diag(1, 1, det U det V) Vᵀ` of the seed
//! specification, but the answer is a unit quaternion, so it is a proper rotation by
//! construction: the q-method cannot return `det C = −1`. It is exact for rank-2 profile
//! matrices (two vector pairs), where `B` has a zero singular value: the top eigenvalue of `K`
//! stays separated from the next by `2 σ₂(B)`. The eigen-decomposition is the bounded cyclic
//! Jacobi of [`crate::linalg::symmetric_eigen`] (at most [`crate::linalg::EIGEN_MAX_SWEEPS`] sweeps).

use nalgebra::{Matrix3, Matrix4, Vector3};

use crate::attitude::snapshot::SnapshotError;
use crate::geometry::Quaternion;
use crate::{real, Real};

use crate::linalg::symmetric_eigen;

/// One vector pair of Wahba's problem.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WahbaPair<T = f32> {
    /// The vector in body axes (any length; it is used as given).
    pub body: Vector3<T>,
    /// The same vector in the reference frame.
    pub reference: Vector3<T>,
    /// Its weight, `> 0`.
    pub weight: T,
}

/// The solution of Wahba's problem.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WahbaSolution<T = f32> {
    /// The optimal attitude `q_rb` (body to reference), unit, scalar part `≥ 0`.
    pub q_rb: Quaternion<T>,
    /// Wahba's loss at the optimum, `Σ w_i (|r_i|² + |b_i|²)/2 − λ_max`.
    pub loss: T,
    /// The gap between the two largest eigenvalues of `K` (a measure of observability).
    pub eigen_gap: T,
}

/// Wahba's problem being accumulated: the profile matrix `B`, the vector `z` and the scale of
/// the gain. Add pairs with [`WahbaProblem::add`], then [`WahbaProblem::solve`]. No buffer of
/// pairs is kept.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WahbaProblem<T = f32> {
    b: Matrix3<T>,
    z: Vector3<T>,
    total: T,
    lengths: T,
}

impl<T: Real> Default for WahbaProblem<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real> WahbaProblem<T> {
    /// An empty problem.
    pub fn new() -> Self {
        Self {
            b: Matrix3::zeros(),
            z: Vector3::zeros(),
            total: T::zero(),
            lengths: T::zero(),
        }
    }

    /// Adds one pair.
    ///
    /// # Errors
    /// [`SnapshotError::NonFinite`] for non-finite input; [`SnapshotError::InvalidNoise`] for a
    /// weight `≤ 0`. The problem is unchanged on error.
    pub fn add(&mut self, pair: &WahbaPair<T>) -> Result<(), SnapshotError> {
        let p = pair;
        if !(p.body.iter().all(|v| v.is_finite())
            && p.reference.iter().all(|v| v.is_finite())
            && p.weight.is_finite())
        {
            return Err(SnapshotError::NonFinite);
        }
        if !(p.weight > T::zero()) {
            return Err(SnapshotError::InvalidNoise);
        }
        // B = Σ w r bᵀ ; z = Σ w b × r
        self.b += p.reference * p.body.transpose() * p.weight;
        self.z += p.body.cross(&p.reference) * p.weight;
        self.total += p.weight * p.body.norm() * p.reference.norm();
        self.lengths += p.weight * (p.body.norm_squared() + p.reference.norm_squared());
        Ok(())
    }

    /// The optimal attitude.
    ///
    /// # Errors
    /// [`SnapshotError::CollinearBaselines`] when the pairs do not determine the attitude
    /// (fewer than two non-parallel vectors: the top eigenvalue is not separated);
    /// [`SnapshotError::NotConverged`] if the Jacobi bound is reached;
    /// [`SnapshotError::NonFinite`] if the accumulated sums overflowed.
    pub fn solve(&self) -> Result<WahbaSolution<T>, SnapshotError> {
        if !(self.total > T::zero()) {
            return Err(SnapshotError::CollinearBaselines);
        }
        let sigma = self.b.trace();
        let s = self.b + self.b.transpose();
        // K = [[S − σI, z], [zᵀ, σ]]  (Davenport)
        let mut k = Matrix4::<T>::zeros();
        k.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(s - Matrix3::identity() * sigma));
        k.fixed_view_mut::<3, 1>(0, 3).copy_from(&self.z);
        k.fixed_view_mut::<1, 3>(3, 0)
            .copy_from(&self.z.transpose());
        k[(3, 3)] = sigma;
        if !k.iter().all(|v| v.is_finite()) {
            return Err(SnapshotError::NonFinite);
        }
        let (values, vectors) = symmetric_eigen(&k).ok_or(SnapshotError::NotConverged)?;
        let gap = values[0] - values[1];
        // The attitude is unique only if λ₁ > λ₂; relative to Σ w |b||r| (the gain of a perfect
        // fit) a gap below ~100 ε means the vectors are parallel.
        if !(gap > self.total * T::default_epsilon() * real(100.0)) {
            return Err(SnapshotError::CollinearBaselines);
        }
        let x = vectors.column(0);
        let q = Quaternion::new(x[3], x[0], x[1], x[2])
            .normalize()?
            .canonical();
        let half: T = real(0.5);
        Ok(WahbaSolution {
            q_rb: q,
            loss: self.lengths * half - values[0],
            eigen_gap: gap,
        })
    }
}

/// Solves Wahba's problem for the given pairs (see [`WahbaProblem`]).
///
/// # Errors
/// As [`WahbaProblem::add`] and [`WahbaProblem::solve`].
pub fn solve_wahba<T: Real>(pairs: &[WahbaPair<T>]) -> Result<WahbaSolution<T>, SnapshotError> {
    let mut problem = WahbaProblem::new();
    for p in pairs {
        problem.add(p)?;
    }
    problem.solve()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{rot_x, rot_y, rot_z, rotation_angle};

    fn pairs_for<const K: usize>(
        c_rb: &Matrix3<f64>,
        body: &[Vector3<f64>; K],
        w: &[f64; K],
    ) -> [WahbaPair<f64>; K] {
        core::array::from_fn(|i| WahbaPair {
            body: body[i],
            reference: c_rb * body[i],
            weight: w[i],
        })
    }

    fn to32<const K: usize>(p: &[WahbaPair<f64>; K]) -> [WahbaPair<f32>; K] {
        core::array::from_fn(|i| WahbaPair {
            body: p[i].body.cast(),
            reference: p[i].reference.cast(),
            weight: p[i].weight as f32,
        })
    }

    #[test]
    fn rank_two_profile_matrix_is_solved_exactly_in_f32_at_180_degrees() {
        // Two baselines of the paper's triangle, heading 180°: B has rank 2.
        let c = rot_z(core::f64::consts::PI);
        let body = [
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.5, 0.75f64.sqrt(), 0.0),
        ];
        let pairs = pairs_for(&c, &body, &[1.0, 1.0]);
        let f64_sol = solve_wahba(&pairs).unwrap();
        assert!(rotation_angle(&(f64_sol.q_rb.to_dcm().transpose() * c)) < 1e-12);
        let f32_sol = solve_wahba(&to32(&pairs)).unwrap();
        let err = rotation_angle(&(f32_sol.q_rb.to_dcm().cast::<f64>().transpose() * c));
        assert!(err < 1e-6, "f32 error {err}");
        assert!(f32_sol.loss.abs() < 1e-5);
    }

    #[test]
    fn very_unequal_weights_match_the_f64_reference() {
        let c = rot_z(0.4) * rot_y(-1.1) * rot_x(2.5);
        let body = [
            Vector3::new(1.0, 0.2, -0.1),
            Vector3::new(-0.3, 1.0, 0.4),
            Vector3::new(0.1, -0.2, 1.0),
        ];
        let mut pairs = pairs_for(&c, &body, &[1e4, 1.0, 1e-3]);
        // perturb the observations so that the weights matter
        pairs[0].reference += Vector3::new(1e-3, -2e-3, 0.5e-3);
        pairs[1].reference += Vector3::new(-3e-2, 1e-2, 2e-2);
        pairs[2].reference += Vector3::new(0.1, -0.05, 0.02);
        let reference = solve_wahba(&pairs).unwrap();
        let single = solve_wahba(&to32(&pairs)).unwrap();
        // f32 accuracy of an eigenvector: ε ‖K‖ / gap. The weights span 1e7, so the rotation
        // about the heavy vector (set by the unit-weight pair) is known to ~1e-4 rad in f32;
        // the snapshot solver's Gauss–Newton polish on residuals removes this (tested there).
        let bound = f64::from(f32::EPSILON) * 1.0e4 / reference.eigen_gap * 8.0;
        let err = reference.q_rb.angle_to(&single.q_rb.cast_f64());
        assert!(err < bound, "{err} {bound}");
        // The heavy pair is fitted almost exactly: its residual is far below the others'.
        let fit = reference.q_rb.to_dcm();
        let r0 = (pairs[0].reference - fit * pairs[0].body).norm();
        let r2 = (pairs[2].reference - fit * pairs[2].body).norm();
        assert!(r0 < 3e-3 && r2 > 2e-2, "{r0} {r2}");
    }

    #[test]
    fn refuses_parallel_vectors_and_bad_weights() {
        let v = Vector3::new(1.0f32, 2.0, 3.0);
        let p = WahbaPair {
            body: v,
            reference: v,
            weight: 1.0,
        };
        let q = WahbaPair {
            body: v * 2.0,
            reference: v * 2.0,
            weight: 1.0,
        };
        assert_eq!(
            solve_wahba(&[p, q]).map(|_| ()),
            Err(SnapshotError::CollinearBaselines)
        );
        let bad = WahbaPair { weight: 0.0, ..p };
        assert_eq!(
            solve_wahba(&[p, bad]).map(|_| ()),
            Err(SnapshotError::InvalidNoise)
        );
    }

    trait CastF64 {
        fn cast_f64(&self) -> Quaternion<f64>;
    }
    impl CastF64 for Quaternion<f32> {
        fn cast_f64(&self) -> Quaternion<f64> {
            Quaternion::new(self.w.into(), self.x.into(), self.y.into(), self.z.into())
        }
    }
}
