//! The filter's initial condition: a mean and a covariance, given by the caller or converted
//! from a snapshot solver's attitude and its rotation-vector covariance.

use nalgebra::{Cholesky, Matrix3, Vector3};

use crate::attitude::one_stage::OneStageError;
use crate::attitude::snapshot::{SnapshotQuality, SnapshotSolution};
use crate::geometry::{vee, Paper003Angles};
use crate::{real, Real};

use super::phase::paper003_partials;

/// Mean and covariance the filter starts from.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Prior<T = f32> {
    /// The attitude angles α, β, γ of eq. (2), rad.
    pub angles: Paper003Angles<T>,
    /// Covariance of (α, β, γ), rad².
    pub angle_covariance: Matrix3<T>,
    /// Rates (α̇, β̇, γ̇), rad/s.
    pub rates: Vector3<T>,
    /// Covariance of the rates, (rad/s)².
    pub rate_covariance: Matrix3<T>,
    /// Line biases `b_B`, `b_C` (phase of B and C relative to A), rad.
    pub line_bias: [T; 2],
    /// Variances of the line biases, rad².
    pub line_bias_variance: [T; 2],
}

impl<T: Real> Prior<T> {
    /// Independent angles and rates: standard deviations `angle_sigma` (rad) and `rate_sigma`
    /// (rad/s) on each axis, zero rates, zero line biases with standard deviation π/2.
    pub fn new(angles: Paper003Angles<T>, angle_sigma: T, rate_sigma: T) -> Self {
        let bias_var = real::<T>(core::f64::consts::FRAC_PI_2 * core::f64::consts::FRAC_PI_2);
        Self {
            angles,
            angle_covariance: Matrix3::identity() * (angle_sigma * angle_sigma),
            rates: Vector3::zeros(),
            rate_covariance: Matrix3::identity() * (rate_sigma * rate_sigma),
            line_bias: [T::zero(); 2],
            line_bias_variance: [bias_var; 2],
        }
    }

    /// A prior from an attitude solution: the body-to-reference DCM `c_rb` and the covariance
    /// (rad²) of its error as a **body-frame** rotation vector `δ`, `C_true = C_rb exp([δ]×)`
    /// (the form `attitude::snapshot::SnapshotSolution` reports: pass its `c_rb` and
    /// `covariance`). The covariance is taken to the reference frame, `δθ = C_rb δ`, and mapped
    /// onto the angles through `δθ = E(α) δα`, `E`'s columns being `vee(∂U/∂α_j Uᵀ)`. Rates
    /// and biases as in [`Self::new`] with `rate_sigma`.
    ///
    /// # Errors
    /// [`OneStageError::NonFiniteInput`]; [`OneStageError::GimbalLock`] when `|cos β| < 1e-3`
    /// (`E` is singular there); [`OneStageError::InvalidCovariance`] when `rotvec_covariance`
    /// is not positive definite.
    pub fn from_attitude(
        c_rb: &Matrix3<T>,
        rotvec_covariance: &Matrix3<T>,
        rate_sigma: T,
    ) -> Result<Self, OneStageError> {
        if !c_rb
            .iter()
            .chain(rotvec_covariance.iter())
            .all(|v| v.is_finite())
            || !rate_sigma.is_finite()
        {
            return Err(OneStageError::NonFiniteInput);
        }
        let angles = Paper003Angles::from_dcm(c_rb)?;
        if angles.beta.cos().abs() < real(1e-3) {
            return Err(OneStageError::GimbalLock);
        }
        let sym = (rotvec_covariance + rotvec_covariance.transpose()) * real::<T>(0.5);
        if Cholesky::new(sym).is_none() {
            return Err(OneStageError::InvalidCovariance);
        }
        let u = angles.to_dcm();
        // body-frame δ to reference-frame δθ = U δ
        let sym = u * sym * u.transpose();
        let [da, db, dg] = paper003_partials(&angles);
        let e = Matrix3::from_columns(&[
            vee(&(da * u.transpose())),
            vee(&(db * u.transpose())),
            vee(&(dg * u.transpose())),
        ]);
        // |det E| = |cos β| ≥ 1e-3, checked above; 3×3 closed-form inverse
        let e_inv = e.try_inverse().ok_or(OneStageError::GimbalLock)?;
        let cov = e_inv * sym * e_inv.transpose();
        let mut prior = Self::new(angles, T::zero(), rate_sigma);
        prior.angle_covariance = (cov + cov.transpose()) * real::<T>(0.5);
        Ok(prior)
    }

    /// The cold-start prior from the snapshot solver (paper 002): its attitude and its
    /// covariance (body-frame rotation vector, the Cramér–Rao bound of that epoch) through
    /// [`Self::from_attitude`]; rates zero with `rate_sigma` (rad/s); line biases zero with
    /// variance (π/2)² (the snapshot's phases contain the biases unless they were calibrated).
    ///
    /// # Errors
    /// [`OneStageError::UnusableSnapshot`] unless the solution's quality is
    /// [`SnapshotQuality::Good`]; otherwise as [`Self::from_attitude`].
    pub fn from_snapshot(
        solution: &SnapshotSolution<T>,
        rate_sigma: T,
    ) -> Result<Self, OneStageError> {
        if solution.quality != SnapshotQuality::Good {
            return Err(OneStageError::UnusableSnapshot);
        }
        Self::from_attitude(&solution.c_rb, &solution.covariance, rate_sigma)
    }

    /// Checks finiteness and definiteness of the parts the filter will use.
    pub(crate) fn check(&self, with_bias: bool) -> Result<(), OneStageError> {
        let finite = [self.angles.alpha, self.angles.beta, self.angles.gamma]
            .iter()
            .chain(self.angle_covariance.iter())
            .chain(self.rates.iter())
            .chain(self.rate_covariance.iter())
            .chain(self.line_bias.iter())
            .chain(self.line_bias_variance.iter())
            .all(|v| v.is_finite());
        if !finite {
            return Err(OneStageError::NonFiniteInput);
        }
        let definite = Cholesky::new(self.angle_covariance).is_some()
            && Cholesky::new(self.rate_covariance).is_some()
            && (!with_bias || self.line_bias_variance.iter().all(|&v| v > T::zero()));
        if definite {
            Ok(())
        } else {
            Err(OneStageError::InvalidCovariance)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::rot_x;

    #[test]
    fn rotation_vector_covariance_maps_onto_the_angles() {
        let angles = Paper003Angles::<f64>::new(0.2, -0.4, 1.0);
        let u = angles.to_dcm();
        // an error of 1e-3 rad about the reference Z (body axis Uᵀ z) changes only γ
        let cov_ref = Matrix3::from_diagonal(&Vector3::new(1e-10, 1e-10, 1e-6));
        let cov = u.transpose() * cov_ref * u;
        let p = Prior::from_attitude(&u, &cov, 0.01).unwrap();
        assert!((p.angles.beta - angles.beta).abs() < 1e-12);
        assert!((p.angle_covariance.m33 - 1e-6).abs() < 1e-8);
        // δθ = E δα checked by perturbing the angles
        let h = 1e-7;
        let mut b = angles;
        b.alpha += h;
        let dtheta = vee(&(b.to_dcm() * u.transpose())) / h;
        let e_col = vee(&(paper003_partials(&angles)[0] * u.transpose()));
        assert!((dtheta - e_col).norm() < 1e-6);
        // gimbal lock is refused
        let gl = Paper003Angles::<f64>::new(0.0, core::f64::consts::FRAC_PI_2, 0.0).to_dcm();
        assert_eq!(
            Prior::from_attitude(&gl, &cov, 0.01),
            Err(OneStageError::GimbalLock)
        );
        assert_eq!(
            Prior::from_attitude(&rot_x(0.1), &(-cov), 0.01),
            Err(OneStageError::InvalidCovariance)
        );
    }

    #[test]
    fn a_snapshot_solution_is_a_prior_only_when_good() {
        let u = Paper003Angles::<f64>::new(0.1, 0.2, -0.3).to_dcm();
        let mut s = SnapshotSolution {
            c_rb: u,
            q_rb: crate::geometry::Quaternion::identity(),
            euler: crate::geometry::Euler321::default(),
            covariance: Matrix3::identity() * 1e-4,
            residual_rms: 0.001,
            chi_square: 10.0,
            dof: 13,
            iterations: 3,
            quality: SnapshotQuality::Good,
        };
        let p = Prior::from_snapshot(&s, 0.01).unwrap();
        assert_eq!(p, Prior::from_attitude(&u, &s.covariance, 0.01).unwrap());
        assert!((p.angles.gamma + 0.3).abs() < 1e-12);
        for q in [SnapshotQuality::ResidualHigh, SnapshotQuality::NotConverged] {
            s.quality = q;
            assert_eq!(
                Prior::from_snapshot(&s, 0.01),
                Err(OneStageError::UnusableSnapshot)
            );
        }
    }
}
