//! Euler angle sequences of the papers.

use nalgebra::Matrix3;

use crate::geometry::GeometryError;
use crate::{real, Real};

use super::{rot_x, rot_y, rot_z, Quaternion};

/// Aerospace 3-2-1 (Euler–Krylov, "aircraft") angles, radians:
/// `C_rb = R_z(yaw) · R_y(pitch) · R_x(roll)` (body to reference).
///
/// From a body-to-reference DCM `M`: `yaw = atan2(M₂₁, M₁₁)`, `pitch = −asin(M₃₁)`,
/// `roll = atan2(M₃₂, M₃₃)`, the angles α, β, γ that paper 000's specification reports.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Euler321<T = f32> {
    /// Rotation about the reference z axis, radians, `(−π, π]`.
    pub yaw: T,
    /// Rotation about the once-rotated y axis, radians, `[−π/2, π/2]`.
    pub pitch: T,
    /// Rotation about the body x axis, radians, `(−π, π]`.
    pub roll: T,
}

impl<T: Real> Euler321<T> {
    /// Angles from yaw, pitch, roll in radians.
    pub fn new(yaw: T, pitch: T, roll: T) -> Self {
        Self { yaw, pitch, roll }
    }

    /// The body-to-reference DCM `C_rb = R_z(yaw) R_y(pitch) R_x(roll)`.
    pub fn to_dcm(&self) -> Matrix3<T> {
        rot_z(self.yaw) * rot_y(self.pitch) * rot_x(self.roll)
    }

    /// The unit quaternion `q_rb` of [`Self::to_dcm`].
    pub fn to_quaternion(&self) -> Quaternion<T> {
        let half = T::one() / (T::one() + T::one());
        let (sy, cy) = (self.yaw * half).sin_cos();
        let (sp, cp) = (self.pitch * half).sin_cos();
        let (sr, cr) = (self.roll * half).sin_cos();
        // q = q_z(yaw) ⊗ q_y(pitch) ⊗ q_x(roll)
        Quaternion::new(
            cy * cp * cr + sy * sp * sr,
            cy * cp * sr - sy * sp * cr,
            cy * sp * cr + sy * cp * sr,
            sy * cp * cr - cy * sp * sr,
        )
        .canonical()
    }

    /// The angles of a body-to-reference DCM.
    ///
    /// Pitch is computed as `atan2(−M₃₁, √(M₁₁² + M₂₁²))`, accurate near ±90° where `asin` is
    /// not; roll as `atan2(M₃₂, M₃₃)`; yaw from what is left, `M · (R_y(pitch) R_x(roll))ᵀ`,
    /// which absorbs the rounding of the other two. The angles therefore reproduce the DCM to
    /// rounding at every attitude, gimbal lock included. At gimbal lock (`cos pitch` at the
    /// rounding level) only `yaw ∓ roll` is defined: roll is then set to 0 and the whole
    /// rotation about the vertical is reported as yaw. No input produces NaN.
    ///
    /// # Errors
    /// [`GeometryError::NonFinite`] when an element is NaN or infinite.
    pub fn from_dcm(c: &Matrix3<T>) -> Result<Self, GeometryError> {
        if !c.iter().all(|v| v.is_finite()) {
            return Err(GeometryError::NonFinite);
        }
        let cos_pitch = (c.m11 * c.m11 + c.m21 * c.m21).sqrt();
        let pitch = (-c.m31).atan2(cos_pitch);
        let roll = if cos_pitch > T::default_epsilon() * real(4.0) {
            c.m32.atan2(c.m33)
        } else {
            T::zero()
        };
        // Residual R_z(yaw) = M (R_y(θ) R_x(φ))ᵀ; first row of R_y(θ) R_x(φ) is
        // (cos θ, sin θ sin φ, sin θ cos φ).
        let (sp, cp) = pitch.sin_cos();
        let (sr, cr) = roll.sin_cos();
        let (b1, b2, b3) = (cp, sp * sr, sp * cr);
        let cos_yaw = c.m11 * b1 + c.m12 * b2 + c.m13 * b3;
        let sin_yaw = c.m21 * b1 + c.m22 * b2 + c.m23 * b3;
        Ok(Self::new(sin_yaw.atan2(cos_yaw), pitch, roll))
    }

    /// The angles of a unit quaternion `q_rb`.
    ///
    /// # Errors
    /// As [`Self::from_dcm`].
    pub fn from_quaternion(q: &Quaternion<T>) -> Result<Self, GeometryError> {
        Self::from_dcm(&q.to_dcm())
    }
}

/// The attitude angles of paper 003, eq. (2), radians, implemented exactly as printed:
///
/// ```text
///        | cos γ  −sin γ  0 |   |  cos β  0  sin β |   | 1    0      0    |
/// U(α) = | sin γ   cos γ  0 | · |    0    1    0   | · | 0   cos α  sin α |
///        |   0       0    1 |   | −sin β  0  cos β |   | 0  −sin α  cos α |
/// ```
///
/// `U` maps the antenna-triangle frame `O_c X_c Y_c Z_c` (body) to the local frame `OXYZ`
/// (reference). The first two factors are active rotations, the last is the *passive* one,
/// `R_x(−α)`; the product is a proper rotation. So `U = Euler321(yaw = γ, pitch = β,
/// roll = −α)`. With `α = γ = 0`, `U = R_y(β)`: the rotation about `Y_c` of the paper's
/// simulation.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Paper003Angles<T = f32> {
    /// α: the angle of the third (x) factor, radians.
    pub alpha: T,
    /// β: the angle of the second (y) factor, radians.
    pub beta: T,
    /// γ: the angle of the first (z) factor, radians.
    pub gamma: T,
}

impl<T: Real> Paper003Angles<T> {
    /// Angles α, β, γ in radians.
    pub fn new(alpha: T, beta: T, gamma: T) -> Self {
        Self { alpha, beta, gamma }
    }

    /// `U(α)` of eq. (2): body (triangle frame) to reference (`OXYZ`).
    pub fn to_dcm(&self) -> Matrix3<T> {
        let (sa, ca) = self.alpha.sin_cos();
        let (o, l) = (T::zero(), T::one());
        // The printed third factor: rows (1 0 0), (0 cos α sin α), (0 −sin α cos α).
        let third = Matrix3::new(l, o, o, o, ca, sa, o, -sa, ca);
        rot_z(self.gamma) * rot_y(self.beta) * third
    }

    /// The same rotation as 3-2-1 angles: `yaw = γ`, `pitch = β`, `roll = −α`.
    pub fn to_euler321(&self) -> Euler321<T> {
        Euler321::new(self.gamma, self.beta, -self.alpha)
    }

    /// The angles of a body-to-reference DCM, inverse of [`Self::to_dcm`] (gimbal lock at
    /// `β = ±90°` handled as in [`Euler321::from_dcm`]).
    ///
    /// # Errors
    /// [`GeometryError::NonFinite`] when an element is NaN or infinite.
    pub fn from_dcm(u: &Matrix3<T>) -> Result<Self, GeometryError> {
        let e = Euler321::from_dcm(u)?;
        Ok(Self::new(-e.roll, e.pitch, e.yaw))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{is_rotation, rotation_angle};
    use core::f64::consts::FRAC_PI_2;

    #[test]
    fn euler321_matches_the_element_formulas_of_the_spec() {
        let e = Euler321::<f64>::new(0.4, -0.3, 1.1);
        let m = e.to_dcm();
        assert!((m.m21.atan2(m.m11) - 0.4_f64).abs() < 1e-15);
        assert!((-m.m31.asin() - -0.3_f64).abs() < 1e-15);
        assert!((m.m32.atan2(m.m33) - 1.1_f64).abs() < 1e-15);
        let back = Euler321::from_dcm(&m).unwrap();
        assert!((back.yaw - e.yaw).abs() < 1e-14);
        assert!((back.pitch - e.pitch).abs() < 1e-14);
        assert!((back.roll - e.roll).abs() < 1e-14);
        assert!(
            e.to_quaternion()
                .angle_to(&Quaternion::from_dcm(&m).unwrap())
                < 1e-14
        );
    }

    #[test]
    fn gimbal_lock_gives_no_nan_and_reproduces_the_dcm() {
        for &pitch in &[FRAC_PI_2, -FRAC_PI_2, FRAC_PI_2 - 1e-9, -FRAC_PI_2 + 1e-4] {
            let e = Euler321::new(0.8, pitch, -0.5);
            let m = e.to_dcm();
            let back = Euler321::from_dcm(&m).unwrap();
            assert!(back.yaw.is_finite() && back.pitch.is_finite() && back.roll.is_finite());
            assert!(
                rotation_angle(&(m.transpose() * back.to_dcm())) < 1e-14,
                "pitch {pitch}"
            );
        }
    }

    #[test]
    fn f32_round_trip_error_is_bounded_over_all_pitches() {
        // Sweep pitch through ±90° in f32; the DCM must come back to rounding level and the
        // angles must never be NaN.
        let mut worst = 0.0f64;
        for k in 0..=2000 {
            let pitch = -FRAC_PI_2 + core::f64::consts::PI * f64::from(k) / 2000.0;
            let e = Euler321::new(2.0f32, pitch as f32, -1.0f32);
            let m = e.to_dcm();
            let back = Euler321::from_dcm(&m).unwrap();
            let err = f64::from(rotation_angle(&(m.transpose() * back.to_dcm())));
            assert!(err.is_finite());
            worst = worst.max(err);
        }
        assert!(worst < 1e-6, "worst f32 round-trip error {worst}");
    }

    #[test]
    fn paper003_eq2_is_a_proper_rotation_and_equals_321_with_negated_alpha() {
        let a = Paper003Angles::<f64>::new(0.3, -0.7, 1.9);
        let u = a.to_dcm();
        assert!(is_rotation(&u, 1e-14));
        assert!((u - a.to_euler321().to_dcm()).norm() < 1e-15);
        let back = Paper003Angles::from_dcm(&u).unwrap();
        assert!((back.alpha - a.alpha).abs() < 1e-14);
        assert!((back.beta - a.beta).abs() < 1e-14);
        assert!((back.gamma - a.gamma).abs() < 1e-14);
    }

    #[test]
    fn paper003_with_only_beta_is_rotation_about_y() {
        let u = Paper003Angles::<f64>::new(0.0, 0.25, 0.0).to_dcm();
        assert!((u - rot_y(0.25_f64)).norm() < 1e-16);
    }

    #[test]
    fn non_finite_dcm_is_rejected() {
        let mut m = Matrix3::<f32>::identity();
        m.m33 = f32::NAN;
        assert_eq!(Euler321::from_dcm(&m), Err(GeometryError::NonFinite));
        assert_eq!(Paper003Angles::from_dcm(&m), Err(GeometryError::NonFinite));
    }
}
