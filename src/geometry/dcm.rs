//! Direction cosine matrices: elementary rotations, the skew matrix, the SO(3) logarithm and
//! a bounded projection onto the rotation group.

use nalgebra::{Matrix3, Vector3};

use crate::geometry::GeometryError;
use crate::{real, Real};

use super::Quaternion;

/// The skew (cross-product) matrix `[v]×`, such that `[v]× · u = v × u`.
pub fn skew<T: Real>(v: &Vector3<T>) -> Matrix3<T> {
    let z = T::zero();
    Matrix3::new(z, -v.z, v.y, v.z, z, -v.x, -v.y, v.x, z)
}

/// The vector of a skew matrix, inverse of [`skew`]: `vee([v]×) = v`. For a general matrix it
/// returns the vector of its skew-symmetric part.
pub fn vee<T: Real>(m: &Matrix3<T>) -> Vector3<T> {
    let half: T = real(0.5);
    Vector3::new(
        (m.m32 - m.m23) * half,
        (m.m13 - m.m31) * half,
        (m.m21 - m.m12) * half,
    )
}

/// Active rotation by `angle` radians about the x axis (turns y towards z).
pub fn rot_x<T: Real>(angle: T) -> Matrix3<T> {
    let (s, c) = angle.sin_cos();
    let (o, l) = (T::zero(), T::one());
    Matrix3::new(l, o, o, o, c, -s, o, s, c)
}

/// Active rotation by `angle` radians about the y axis (turns z towards x).
pub fn rot_y<T: Real>(angle: T) -> Matrix3<T> {
    let (s, c) = angle.sin_cos();
    let (o, l) = (T::zero(), T::one());
    Matrix3::new(c, o, s, o, l, o, -s, o, c)
}

/// Active rotation by `angle` radians about the z axis (turns x towards y).
pub fn rot_z<T: Real>(angle: T) -> Matrix3<T> {
    let (s, c) = angle.sin_cos();
    let (o, l) = (T::zero(), T::one());
    Matrix3::new(c, -s, o, s, c, o, o, o, l)
}

/// `‖CᵀC − I‖_F`: how far a matrix is from orthonormal.
pub fn orthonormality_error<T: Real>(c: &Matrix3<T>) -> T {
    (c.transpose() * c - Matrix3::identity()).norm()
}

/// True when `c` is finite, `‖CᵀC − I‖_F ≤ tolerance` and `det C > 0`.
pub fn is_rotation<T: Real>(c: &Matrix3<T>, tolerance: T) -> bool {
    c.iter().all(|v| v.is_finite())
        && orthonormality_error(c) <= tolerance
        && c.determinant() > T::zero()
}

/// Rotation angle of a rotation matrix, radians in `[0, π]`, computed as
/// `atan2(|vee(C)|, (tr C − 1)/2)`, accurate at small angles where `acos` is not.
pub fn rotation_angle<T: Real>(c: &Matrix3<T>) -> T {
    let half: T = real(0.5);
    let s = vee(c).norm();
    let co = (c.trace() - T::one()) * half;
    s.atan2(co)
}

/// The rotation vector (axis × angle, radians) of a rotation matrix: the SO(3) logarithm.
///
/// # Errors
/// As [`Quaternion::from_dcm`].
pub fn log_so3<T: Real>(c: &Matrix3<T>) -> Result<Vector3<T>, GeometryError> {
    Ok(Quaternion::from_dcm(c)?.to_rotation_vector())
}

/// Upper bound on the iterations of [`nearest_rotation`].
pub const NEAREST_ROTATION_MAX_ITERATIONS: usize = 16;

/// The rotation nearest to `m` in the Frobenius norm: the orthogonal polar factor of `m`.
///
/// Uses Higham's scaled Newton iteration `X ← (γX + γ⁻¹X⁻ᵀ)/2` with closed-form 3×3 inverses.
/// It converges quadratically; a matrix within 10 % of a rotation converges in 3–5 iterations,
/// and the loop stops after [`NEAREST_ROTATION_MAX_ITERATIONS`].
///
/// This is what paper 000's six direction cosines need before they are reported as an attitude:
/// the estimated `M̂` is close to, but not exactly, a rotation.
///
/// # Errors
/// [`GeometryError::NonFinite`] for a non-finite element; [`GeometryError::NotARotation`] when
/// `det m ≤ 0` or `m` is numerically singular (its polar factor is then a reflection or is not
/// unique); [`GeometryError::NotConverged`] if the bound is reached.
pub fn nearest_rotation<T: Real>(m: &Matrix3<T>) -> Result<Matrix3<T>, GeometryError> {
    if !m.iter().all(|v| v.is_finite()) {
        return Err(GeometryError::NonFinite);
    }
    let scale = m.norm();
    if scale <= T::zero() {
        return Err(GeometryError::NotARotation);
    }
    // Work on m / ‖m‖ so that the determinant test does not depend on the scale of m.
    let mut x = m / scale;
    let det_min = T::default_epsilon() * real(100.0);
    if x.determinant() <= det_min {
        return Err(GeometryError::NotARotation);
    }
    let half: T = real(0.5);
    let tolerance = T::default_epsilon() * real(16.0);
    for _ in 0..NEAREST_ROTATION_MAX_ITERATIONS {
        let det = x.determinant();
        if det <= det_min || !det.is_finite() {
            return Err(GeometryError::NotARotation);
        }
        // X⁻ᵀ = cof(X) / det X (closed form, no pivoting)
        let inv_t = cofactor(&x) / det;
        // Frobenius scaling γ = (‖X⁻¹‖ / ‖X‖)^{1/2} accelerates the first steps.
        let gamma = (inv_t.norm() / x.norm()).sqrt();
        let next = (x * gamma + inv_t / gamma) * half;
        let change = (next - x).norm();
        x = next;
        if change <= tolerance {
            return Ok(x);
        }
    }
    // The iteration stalls at the rounding level in f32; accept it if it is a rotation there.
    if orthonormality_error(&x) <= tolerance * real(8.0) {
        Ok(x)
    } else {
        Err(GeometryError::NotConverged)
    }
}

/// The cofactor matrix of a 3×3 matrix (`cof(X) = det(X) · X⁻ᵀ`).
fn cofactor<T: Real>(x: &Matrix3<T>) -> Matrix3<T> {
    let c0 = x.column(0);
    let c1 = x.column(1);
    let c2 = x.column(2);
    // Columns of cof(X): c1 × c2, c2 × c0, c0 × c1.
    Matrix3::from_columns(&[c1.cross(&c2), c2.cross(&c0), c0.cross(&c1)])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_rotation() -> Matrix3<f64> {
        rot_z(0.7) * rot_y(-0.4) * rot_x(2.1)
    }

    #[test]
    fn skew_is_the_cross_product_and_vee_inverts_it() {
        let a = Vector3::new(0.3, -1.0, 2.0);
        let b = Vector3::new(-0.5, 0.25, 4.0);
        assert_eq!(skew(&a) * b, a.cross(&b));
        assert_eq!(vee(&skew(&a)), a);
    }

    #[test]
    fn elementary_rotations_are_proper_and_right_handed() {
        for r in [rot_x(0.3), rot_y(0.3), rot_z(0.3)] {
            assert!(is_rotation(&r, 1e-14));
        }
        assert!(
            (rot_x(1.0_f64) * Vector3::y() - Vector3::new(0.0, 1.0f64.cos(), 1.0f64.sin())).norm()
                < 1e-15
        );
        assert!(
            (rot_y(1.0_f64) * Vector3::z() - Vector3::new(1.0f64.sin(), 0.0, 1.0f64.cos())).norm()
                < 1e-15
        );
    }

    #[test]
    fn rotation_angle_and_log_agree() {
        let c = sample_rotation();
        let theta = log_so3(&c).unwrap();
        assert!((theta.norm() - rotation_angle(&c)).abs() < 1e-12);
        assert!((Quaternion::from_rotation_vector(&theta).to_dcm() - c).norm() < 1e-12);
        let tiny = rot_x(1e-9_f64);
        assert!((rotation_angle(&tiny) - 1e-9).abs() < 1e-20);
    }

    #[test]
    fn nearest_rotation_repairs_a_perturbed_rotation_like_svd_would() {
        let r = sample_rotation();
        // Symmetric perturbation: the polar factor of R (I + S) with S symmetric is R exactly.
        let s = Matrix3::new(0.05, 0.02, -0.01, 0.02, -0.03, 0.04, -0.01, 0.04, 0.06);
        let m = r * (Matrix3::identity() + s);
        let p = nearest_rotation(&m).unwrap();
        assert!((p - r).norm() < 1e-13);
        // f32 reaches the rounding level of f32.
        let p32 = nearest_rotation(&m.cast::<f32>()).unwrap();
        assert!((p32.cast::<f64>() - r).norm() < 2e-6);
        assert!(orthonormality_error(&p32) < 1e-6);
    }

    #[test]
    fn nearest_rotation_refuses_reflections_and_singular_and_nan() {
        let reflection = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
        assert_eq!(
            nearest_rotation(&reflection),
            Err(GeometryError::NotARotation)
        );
        let rank2 = Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0);
        assert_eq!(nearest_rotation(&rank2), Err(GeometryError::NotARotation));
        assert_eq!(
            nearest_rotation(&Matrix3::<f32>::zeros()),
            Err(GeometryError::NotARotation)
        );
        let mut nan = Matrix3::<f32>::identity();
        nan.m12 = f32::NAN;
        assert_eq!(nearest_rotation(&nan), Err(GeometryError::NonFinite));
    }
}
