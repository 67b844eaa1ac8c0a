//! The per-epoch output of the baseline filters.

use nalgebra::Matrix3;

use crate::attitude::dcm_filter::DcmError;
use crate::geometry::{Euler321, Quaternion};
use crate::Real;

/// What the filter thinks of its own estimate after a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FilterHealth {
    /// The innovation is consistent with the covariance (NIS inside its 99.9 % χ² gate) and the
    /// geometry is well conditioned.
    Nominal,
    /// The innovation failed its 99.9 % χ² gate: a bad measurement, or an estimate that has
    /// drifted away from the data. The rigid-body filter did not apply the rejected baselines.
    InnovationOutlier,
    /// The observation Jacobian `Φ(Ŷ)` is poorly conditioned (its smallest to largest QR
    /// pivot ratio is below the warning level): the estimate is usable but errors are strongly
    /// amplified along one direction.
    WeakGeometry,
    /// Six-state filter only: the direction cosines violate the rotation constraints
    /// (`|c₂|² = |c₃|² = 1`, `c₂·c₃ = 0`) by more than their own covariance allows (χ²₃ at
    /// 99.9 %): the state has left SO(3) beyond its stated uncertainty, so its covariance (and
    /// the attitude derived from it) is not to be trusted.
    ConstraintViolated,
    /// Multi-structure filter only: fewer than three structures entered the combination.
    StructuresDisagree,
}

/// An attitude estimate with its uncertainty, as every baseline filter reports it per epoch.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FilterEstimate<T = f32> {
    /// Attitude `C_rb`, body to reference frame (ECEF), a proper rotation (the six-state
    /// filter's direction cosines are orthonormalized by [`crate::geometry::nearest_rotation`]).
    pub c_rb: Matrix3<T>,
    /// The same attitude as the unit quaternion `q_rb` (Hamilton, scalar first, `w ≥ 0`).
    pub q_rb: Quaternion<T>,
    /// The same attitude as 3-2-1 (Euler–Krylov) angles α (yaw), β (pitch), γ (roll), radians.
    pub euler: Euler321<T>,
    /// Covariance of the attitude error `δθ`, body axes, rad², where the true attitude is
    /// `C_rb · exp([δθ]×)`.
    pub covariance: Matrix3<T>,
    /// Normalized innovation squared of the epoch's baselines (dimensionless; χ² with
    /// [`Self::nis_dof`] degrees of freedom for a consistent filter).
    pub nis: T,
    /// Degrees of freedom of [`Self::nis`] (3 per baseline used).
    pub nis_dof: u8,
    /// The filter's own verdict on the estimate.
    pub health: FilterHealth,
}

impl<T: Real> FilterEstimate<T> {
    /// An estimate from a proper rotation `c_rb`; computes the quaternion and the angles.
    ///
    /// # Errors
    /// [`DcmError::NonFinite`] or [`DcmError::NotARotation`] from the conversions.
    pub fn from_rotation(
        c_rb: Matrix3<T>,
        covariance: Matrix3<T>,
        nis: T,
        nis_dof: u8,
        health: FilterHealth,
    ) -> Result<Self, DcmError> {
        let q_rb = Quaternion::from_dcm(&c_rb)?;
        let euler = Euler321::from_dcm(&c_rb)?;
        if !covariance.iter().all(|v| v.is_finite()) || !nis.is_finite() {
            return Err(DcmError::Numerical);
        }
        Ok(Self {
            c_rb,
            q_rb,
            euler,
            covariance,
            nis,
            nis_dof,
            health,
        })
    }

    /// Standard deviations of the attitude error about the body axes, radians (`√P_ii`).
    pub fn sigma(&self) -> nalgebra::Vector3<T> {
        self.covariance.diagonal().map(|v| v.max(T::zero()).sqrt())
    }
}
