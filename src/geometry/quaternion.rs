//! Hamilton unit quaternions.

use core::ops::Mul;

use nalgebra::{Matrix3, Vector3};

use crate::geometry::GeometryError;
use crate::{real, Real};

use super::orthonormality_error;

/// A Hamilton quaternion `w + x i + y j + z k`, scalar first.
///
/// As an attitude, the unit quaternion `q_ab` represents the DCM `C_ab` (frame `b` components to
/// frame `a` components, see [`crate::geometry`]): `v_a = q_ab ⊗ v_b ⊗ q_ab*`.
///
/// The fields are public so that the type can be built and read without ceremony; the methods
/// that need a unit quaternion say so.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Quaternion<T = f32> {
    /// Scalar part.
    pub w: T,
    /// Vector part, i component.
    pub x: T,
    /// Vector part, j component.
    pub y: T,
    /// Vector part, k component.
    pub z: T,
}

impl<T: Real> Quaternion<T> {
    /// The quaternion from its four components, scalar first.
    pub fn new(w: T, x: T, y: T, z: T) -> Self {
        Self { w, x, y, z }
    }

    /// The identity rotation `1 + 0i + 0j + 0k`.
    pub fn identity() -> Self {
        Self::new(T::one(), T::zero(), T::zero(), T::zero())
    }

    /// The quaternion with scalar part `w` and vector part `v`.
    pub fn from_parts(w: T, v: Vector3<T>) -> Self {
        Self::new(w, v.x, v.y, v.z)
    }

    /// The vector part `(x, y, z)`.
    pub fn vector(&self) -> Vector3<T> {
        Vector3::new(self.x, self.y, self.z)
    }

    /// The conjugate `w − x i − y j − z k` (the inverse of a unit quaternion).
    pub fn conjugate(&self) -> Self {
        Self::new(self.w, -self.x, -self.y, -self.z)
    }

    /// The Euclidean norm.
    pub fn norm(&self) -> T {
        (self.w * self.w + self.x * self.x + self.y * self.y + self.z * self.z).sqrt()
    }

    /// True when all four components are finite.
    pub fn is_finite(&self) -> bool {
        self.w.is_finite() && self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }

    /// The unit quaternion in the same direction.
    ///
    /// # Errors
    /// [`GeometryError::NonFinite`] for a non-finite component, [`GeometryError::ZeroLength`]
    /// when the norm is below `1e-12` (f64) or about `1e-6` (f32).
    pub fn normalize(&self) -> Result<Self, GeometryError> {
        if !self.is_finite() {
            return Err(GeometryError::NonFinite);
        }
        // scaled by the largest component first: the squares of huge components would
        // overflow (and of tiny ones underflow) before the square root
        let largest = [self.x, self.y, self.z]
            .iter()
            .fold(self.w.abs(), |m, c| m.max(c.abs()));
        if !(largest > T::zero()) {
            return Err(GeometryError::ZeroLength);
        }
        let s = T::one() / largest;
        let scaled = Self::new(self.w * s, self.x * s, self.y * s, self.z * s);
        let n = scaled.norm();
        // the norm is `largest · n` (n in [1, 2]); it may overflow to +∞, which passes
        if !(largest * n > T::default_epsilon().sqrt() * real(0.01)) {
            return Err(GeometryError::ZeroLength);
        }
        let inv = T::one() / n;
        Ok(Self::new(
            scaled.w * inv,
            scaled.x * inv,
            scaled.y * inv,
            scaled.z * inv,
        ))
    }

    /// The same rotation with a non-negative scalar part (`q` and `−q` are the same rotation).
    pub fn canonical(&self) -> Self {
        if self.w < T::zero() {
            Self::new(-self.w, -self.x, -self.y, -self.z)
        } else {
            *self
        }
    }

    /// Rotates `v` by this unit quaternion: `q ⊗ v ⊗ q*`, i.e. `C(q) · v`.
    pub fn rotate(&self, v: &Vector3<T>) -> Vector3<T> {
        // t = 2 q_v × v ;  v' = v + w t + q_v × t   (two cross products instead of a matrix)
        let qv = self.vector();
        let t = qv.cross(v) * real::<T>(2.0);
        v + t * self.w + qv.cross(&t)
    }

    /// The DCM `C(q)` of a unit quaternion, such that `q ⊗ v ⊗ q* = C(q) v`.
    pub fn to_dcm(&self) -> Matrix3<T> {
        let (w, x, y, z) = (self.w, self.x, self.y, self.z);
        let two: T = real(2.0);
        let (xx, yy, zz) = (x * x, y * y, z * z);
        let (xy, xz, yz) = (x * y, x * z, y * z);
        let (wx, wy, wz) = (w * x, w * y, w * z);
        Matrix3::new(
            T::one() - two * (yy + zz),
            two * (xy - wz),
            two * (xz + wy),
            two * (xy + wz),
            T::one() - two * (xx + zz),
            two * (yz - wx),
            two * (xz - wy),
            two * (yz + wx),
            T::one() - two * (xx + yy),
        )
    }

    /// The unit quaternion (scalar part `≥ 0`) of a DCM, by Shepperd's method: the largest of
    /// `w², x², y², z²` is found from the trace and diagonal, so no branch divides by a small
    /// number, including at 180° rotations.
    ///
    /// For a matrix that is only close to a rotation, the result is the normalized quaternion of
    /// its nearest rotation to first order; use [`super::nearest_rotation`] first for a matrix
    /// that is far from orthonormal.
    ///
    /// # Errors
    /// [`GeometryError::NonFinite`] for a non-finite element, [`GeometryError::NotARotation`] if
    /// the matrix is far from a rotation: `det ≤ 0` or `‖CᵀC − I‖_F > 0.5`.
    pub fn from_dcm(c: &Matrix3<T>) -> Result<Self, GeometryError> {
        if !c.iter().all(|v| v.is_finite()) {
            return Err(GeometryError::NonFinite);
        }
        if !(c.determinant() > T::zero()) || !(orthonormality_error(c) <= real(0.5)) {
            return Err(GeometryError::NotARotation);
        }
        let (m00, m01, m02) = (c.m11, c.m12, c.m13);
        let (m10, m11, m12) = (c.m21, c.m22, c.m23);
        let (m20, m21, m22) = (c.m31, c.m32, c.m33);
        let trace = m00 + m11 + m22;
        let one = T::one();
        let quarter: T = real(0.25);
        // 4w² = 1 + tr, 4x² = 1 + 2 m00 − tr, ...; pick the largest.
        let candidates = [
            one + trace,
            one + m00 * real(2.0) - trace,
            one + m11 * real(2.0) - trace,
            one + m22 * real(2.0) - trace,
        ];
        let mut best = 0usize;
        let mut best_value = one + trace;
        // (indices from `0..4`, not `enumerate`: its counter keeps an overflow check)
        for (i, &v) in (0..4).zip(candidates.iter()).skip(1) {
            if v > best_value {
                best = i;
                best_value = v;
            }
        }
        if best_value <= T::default_epsilon() {
            return Err(GeometryError::NotARotation);
        }
        let s = best_value.sqrt() * real(2.0); // s = 4 |largest component|
        let q = match best {
            0 => Self::new(
                s * quarter,
                (m21 - m12) / s,
                (m02 - m20) / s,
                (m10 - m01) / s,
            ),
            1 => Self::new(
                (m21 - m12) / s,
                s * quarter,
                (m01 + m10) / s,
                (m02 + m20) / s,
            ),
            2 => Self::new(
                (m02 - m20) / s,
                (m01 + m10) / s,
                s * quarter,
                (m12 + m21) / s,
            ),
            _ => Self::new(
                (m10 - m01) / s,
                (m02 + m20) / s,
                (m12 + m21) / s,
                s * quarter,
            ),
        };
        Ok(q.normalize()?.canonical())
    }

    /// The unit quaternion of the rotation vector `θ` (axis × angle, radians): the exponential
    /// map. Uses the series of `sin(|θ|/2)/|θ|` below 1e-3 rad (f32) so that small and zero
    /// rotations are exact.
    pub fn from_rotation_vector(theta: &Vector3<T>) -> Self {
        let angle2 = theta.norm_squared();
        let angle = angle2.sqrt();
        let half: T = real(0.5);
        let small = T::default_epsilon().sqrt().sqrt(); // f32: 0.018, f64: 1.2e-4
        let (w, k) = if angle < small {
            // cos(a/2) = 1 − a²/8 + a⁴/384 ;  sin(a/2)/a = 1/2 − a²/48 + a⁴/3840
            (
                T::one() - angle2 / real(8.0) + angle2 * angle2 / real(384.0),
                half - angle2 / real(48.0) + angle2 * angle2 / real(3840.0),
            )
        } else {
            let (s, c) = (angle * half).sin_cos();
            (c, s / angle)
        };
        Self::from_parts(w, theta * k)
    }

    /// The rotation vector (axis × angle, radians, angle in `[0, π]`) of a unit quaternion: the
    /// logarithmic map, inverse of [`Self::from_rotation_vector`].
    pub fn to_rotation_vector(&self) -> Vector3<T> {
        let q = self.canonical();
        let v = q.vector();
        let n = v.norm();
        if n < T::default_epsilon().sqrt().sqrt() {
            // angle = 2 atan2(n, w) ≈ 2 n / w (1 − n²/(3 w²)) ; scale = angle / n
            let w = if q.w > T::zero() { q.w } else { T::one() };
            v * (real::<T>(2.0) / w * (T::one() - n * n / (real::<T>(3.0) * w * w)))
        } else {
            v * (real::<T>(2.0) * n.atan2(q.w) / n)
        }
    }

    /// Rotation angle in `[0, π]` radians between two attitudes: the angle of `self* ⊗ other`.
    pub fn angle_to(&self, other: &Self) -> T {
        (self.conjugate() * *other).to_rotation_vector().norm()
    }

    /// Converts to nalgebra's unit quaternion (same Hamilton convention).
    pub fn to_nalgebra(&self) -> nalgebra::UnitQuaternion<T> {
        nalgebra::UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(
            self.w, self.x, self.y, self.z,
        ))
    }
}

impl<T: Real> Mul for Quaternion<T> {
    type Output = Self;

    /// The Hamilton product `self ⊗ rhs`.
    fn mul(self, r: Self) -> Self {
        let l = self;
        Self::new(
            l.w * r.w - l.x * r.x - l.y * r.y - l.z * r.z,
            l.w * r.x + l.x * r.w + l.y * r.z - l.z * r.y,
            l.w * r.y - l.x * r.z + l.y * r.w + l.z * r.x,
            l.w * r.z + l.x * r.y - l.y * r.x + l.z * r.w,
        )
    }
}

impl<T: Real> Default for Quaternion<T> {
    fn default() -> Self {
        Self::identity()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{rot_x, rot_z};
    use core::f64::consts::PI;

    /// Components whose squares overflow (or underflow) f32 still give the unit quaternion.
    #[test]
    fn huge_and_tiny_quaternions_normalize() {
        let huge = Quaternion::<f32>::new(3e30, -4e30, 0.0, 0.0)
            .normalize()
            .unwrap();
        assert!(
            (huge.w - 0.6).abs() < 1e-6 && (huge.x + 0.8).abs() < 1e-6,
            "{huge:?}"
        );
        let max = Quaternion::<f32>::new(f32::MAX, f32::MAX, 0.0, 0.0)
            .normalize()
            .unwrap();
        assert!((max.norm() - 1.0).abs() < 1e-6, "{max:?}");
        assert_eq!(
            Quaternion::<f32>::new(1e-20, 0.0, 0.0, 0.0).normalize(),
            Err(GeometryError::ZeroLength)
        );
        assert_eq!(
            Quaternion::<f32>::new(0.0, 0.0, 0.0, 0.0).normalize(),
            Err(GeometryError::ZeroLength)
        );
    }

    fn q(w: f64, x: f64, y: f64, z: f64) -> Quaternion<f64> {
        Quaternion::new(w, x, y, z).normalize().unwrap()
    }

    #[test]
    fn hamilton_units_multiply_as_ijk() {
        let i = Quaternion::new(0.0, 1.0, 0.0, 0.0);
        let j = Quaternion::new(0.0, 0.0, 1.0, 0.0);
        let k = Quaternion::new(0.0, 0.0, 0.0, 1.0);
        assert_eq!(i * j, k);
        assert_eq!(j * k, i);
        assert_eq!(k * i, j);
        assert_eq!(i * j * k, Quaternion::new(-1.0, 0.0, 0.0, 0.0));
    }

    #[test]
    fn rotate_agrees_with_sandwich_product_and_dcm() {
        let a = q(0.64, 0.48, 0.36, -0.48);
        let v = Vector3::new(0.3, -1.2, 2.5);
        let sandwich = a * Quaternion::from_parts(0.0, v) * a.conjugate();
        assert!((sandwich.vector() - a.rotate(&v)).norm() < 1e-14);
        assert!((a.to_dcm() * v - a.rotate(&v)).norm() < 1e-14);
    }

    #[test]
    fn composition_order_matches_dcm_product() {
        let a = q(0.9, 0.1, -0.3, 0.2);
        let b = q(0.2, 0.7, 0.1, -0.6);
        assert!(((a * b).to_dcm() - a.to_dcm() * b.to_dcm()).norm() < 1e-14);
    }

    #[test]
    fn positive_rotation_about_z_turns_x_towards_y() {
        let qz = Quaternion::from_rotation_vector(&Vector3::new(0.0, 0.0, PI / 2.0));
        let x = qz.rotate(&Vector3::x());
        assert!((x - Vector3::y()).norm() < 1e-15);
        assert!((qz.to_dcm() - rot_z(PI / 2.0)).norm() < 1e-15);
    }

    #[test]
    fn dcm_round_trip_including_180_degree_rotations() {
        let cases = [
            q(1.0, 0.0, 0.0, 0.0),
            q(0.0, 1.0, 0.0, 0.0),
            q(0.0, 0.0, 1.0, 0.0),
            q(0.0, 0.0, 0.0, 1.0),
            q(0.0, 0.6, 0.8, 0.0),
            q(0.64, 0.48, 0.36, -0.48),
            q(1e-9, -0.3, 0.2, 0.9),
        ];
        for a in cases {
            let back = Quaternion::from_dcm(&a.to_dcm()).unwrap();
            assert!(back.angle_to(&a) < 1e-7, "{a:?} -> {back:?}");
        }
        let half_turn_x = Quaternion::<f64>::from_dcm(&rot_x(PI)).unwrap();
        assert!((half_turn_x.x.abs() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn rotation_vector_round_trip_small_and_large() {
        for &angle in &[0.0, 1e-12, 1e-7, 1e-3, 0.5, 3.0, PI - 1e-9] {
            let axis = Vector3::new(1.0, -2.0, 0.5).normalize();
            let theta = axis * angle;
            let back = Quaternion::from_rotation_vector(&theta).to_rotation_vector();
            assert!(
                (back - theta).norm() <= 1e-12 * (1.0 + angle),
                "angle {angle}"
            );
        }
    }

    #[test]
    fn small_quaternion_vector_part_is_half_the_rotation_vector() {
        let theta = Vector3::new(1e-4, -2e-4, 3e-4);
        let qs = Quaternion::from_rotation_vector(&theta);
        assert!((qs.vector() * 2.0 - theta).norm() < 1e-11);
    }

    #[test]
    fn f32_exponential_is_accurate_across_the_series_switch() {
        // f64 reference vs f32 on both sides of the small-angle threshold.
        for &angle in &[0.0f64, 1e-6, 0.0179, 0.0181, 0.3, 3.1] {
            let axis = Vector3::new(0.2, 0.9, -0.4).normalize() * angle;
            let r64 = Quaternion::from_rotation_vector(&axis);
            let r32 = Quaternion::from_rotation_vector(&axis.cast::<f32>());
            let err = ((f64::from(r32.w) - r64.w).abs())
                .max((r32.vector().cast::<f64>() - r64.vector()).norm());
            assert!(err < 2e-7, "angle {angle}: {err}");
        }
    }

    #[test]
    fn normalize_rejects_zero_and_nan() {
        assert_eq!(
            Quaternion::<f32>::new(0.0, 0.0, 0.0, 0.0).normalize(),
            Err(GeometryError::ZeroLength)
        );
        assert_eq!(
            Quaternion::<f32>::new(f32::NAN, 0.0, 0.0, 1.0).normalize(),
            Err(GeometryError::NonFinite)
        );
        let mut bad = Matrix3::<f32>::identity();
        bad.m23 = f32::INFINITY;
        assert_eq!(Quaternion::from_dcm(&bad), Err(GeometryError::NonFinite));
        assert_eq!(
            Quaternion::from_dcm(&Matrix3::<f32>::zeros()),
            Err(GeometryError::NotARotation)
        );
    }
}
