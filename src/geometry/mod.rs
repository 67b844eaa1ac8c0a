//! Frames, rotations and attitude parameterizations.
//!
//! # Conventions (used by every module of the crate)
//!
//! * A **direction cosine matrix** (DCM) `C_ab` maps the components of a vector in frame `b` to
//!   its components in frame `a`: `v_a = C_ab · v_b`. Then `C_ba = C_abᵀ` and
//!   `C_ac = C_ab · C_bc`. The crate's *attitude* is `C_rb`, body to reference (the matrix `M` of
//!   paper 000, `U` of paper 003); paper 002's `A` is its transpose `C_br`.
//! * A **quaternion** is Hamilton's (`i² = j² = k² = ijk = −1`), scalar first. The unit
//!   quaternion `q_ab` represents `C_ab`: `v_a = q_ab ⊗ v_b ⊗ q_ab*`, and
//!   `q_ac = q_ab ⊗ q_bc`. See [`Quaternion`].
//! * A **rotation vector** `θ` (axis times angle, radians) maps to a quaternion by
//!   `q = (cos|θ|/2, sin(|θ|/2) θ/|θ|)`. For a small rotation `q ≈ 1 + θ/2`: the vector part of a
//!   small quaternion is **half** the rotation vector.
//! * **Euler angles**, radians. [`Euler321`] are the aerospace (Euler–Krylov, "aircraft")
//!   angles yaw–pitch–roll: `C_rb = R_z(yaw) · R_y(pitch) · R_x(roll)`. [`Paper003Angles`] are
//!   the angles of paper 003, eq. (2), implemented exactly as printed.
//! * `R_x`, `R_y`, `R_z` ([`rot_x`], [`rot_y`], [`rot_z`]) are the active right-handed
//!   elementary rotations (`R_z(a)` turns the x axis towards the y axis by `a`).
//!
//! # Frames named in the crate
//!
//! | Frame | Symbol | Definition |
//! |---|---|---|
//! | Body | `b` | Fixed to the spacecraft structure; antenna positions and baselines are given in it |
//! | Reference | `r` | The frame the attitude is expressed in: ECEF (paper 000), a local-level orbital frame (paper 002: z to nadir), the local `OXYZ` of paper 003, or inertial (paper 001) |
//! | ECEF | `e` | Earth-centred, Earth-fixed (WGS-84) |
//! | Inertial | `i` | Earth-centred inertial |
//!
//! # Robustness
//!
//! Pure maths on finite numbers (products, [`Quaternion::rotate`], [`Quaternion::from_rotation_vector`])
//! is total: finite input gives finite output. Conversions from data that may be corrupt
//! ([`Quaternion::from_dcm`], [`Euler321::from_dcm`], [`nearest_rotation`]) check their input and
//! return [`GeometryError`]. No conversion produces NaN at a singularity:
//! gimbal lock and the 180° rotation are handled explicitly.

mod dcm;
mod euler;
mod quaternion;

use crate::error::{Error, ErrorKind};
pub use dcm::{
    is_rotation, log_so3, nearest_rotation, orthonormality_error, rot_x, rot_y, rot_z,
    rotation_angle, skew, vee, NEAREST_ROTATION_MAX_ITERATIONS,
};
pub use euler::{Euler321, Paper003Angles};
pub use quaternion::Quaternion;

/// `angle` (rad) wrapped to `(−π, π]`.
pub fn wrap_angle<T: crate::Real>(angle: T) -> T {
    let pi = T::pi();
    if angle > -pi && angle <= pi {
        return angle;
    }
    let two_pi = T::two_pi();
    let w = angle - two_pi * ((angle + pi) / two_pi).floor();
    if w <= -pi {
        w + two_pi
    } else {
        w
    }
}

/// Errors of the geometry routines ([`crate::geometry`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum GeometryError {
    /// An angle, vector, quaternion or matrix element was NaN or infinite.
    #[error("non-finite geometry input")]
    NonFinite,
    /// A vector or quaternion that must be normalized has (near) zero length.
    #[error("vector or quaternion of zero length")]
    ZeroLength,
    /// A matrix is too far from a rotation to be repaired: its determinant is not positive, or
    /// it is (near) singular.
    #[error("matrix is not close to a proper rotation")]
    NotARotation,
    /// The bounded orthonormalization did not converge within its iteration bound.
    #[error("orthonormalization did not converge")]
    NotConverged,
}

impl Error for GeometryError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::ZeroLength | Self::NotARotation => ErrorKind::InvalidInput,
            Self::NotConverged => ErrorKind::NotConverged,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::wrap_angle as wrap;

    #[test]
    fn wrap_maps_onto_minus_pi_to_pi() {
        use core::f64::consts::PI;
        for (a, w) in [
            (0.5, 0.5),
            (PI, PI),
            (-PI, PI),
            (3.0 * PI, PI),
            (7.0, 7.0 - 2.0 * PI),
        ] {
            assert!((wrap(a) - w).abs() < 1e-12, "{a}");
        }
    }
}
