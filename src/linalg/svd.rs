//! Singular values of a small square matrix by the one-sided (Hestenes) Jacobi method, with a
//! fixed sweep bound.

use nalgebra::{SMatrix, SVector};

use super::LinalgError;
use crate::Real;

/// Upper bound on the sweeps of the one-sided Jacobi iteration. One sweep rotates every pair of
/// columns once (`X (X − 1) / 2` rotations of `O(X)` work); the iteration converges
/// quadratically and needs 6–10 sweeps for `X = 15` in practice.
pub const SVD_MAX_SWEEPS: u32 = 30;

/// The singular values of `a` in descending order.
///
/// One-sided Jacobi: plane rotations of column pairs `(p, q)` until every pair is orthogonal to
/// `X ε` relative (`|a_pᵀ a_q| ≤ X ε ‖a_p‖ ‖a_q‖`); the singular values are then the column
/// norms. Columns shorter than `ε ‖A‖_F` count as zero. At most [`SVD_MAX_SWEEPS`] sweeps.
///
/// # Errors
/// [`LinalgError::NonFinite`] for a non-finite element;
/// [`LinalgError::NotConverged`] when the sweep bound is reached.
pub fn singular_values<T: Real, const X: usize>(
    a: &SMatrix<T, X, X>,
) -> Result<SVector<T, X>, LinalgError> {
    if !a.iter().all(|v| v.is_finite()) {
        return Err(LinalgError::NonFinite);
    }
    let mut a = *a;
    let tol = T::default_epsilon() * nalgebra::convert::<f64, T>(X as f64);
    let two: T = nalgebra::convert(2.0);
    // A column shorter than ε‖A‖ is zero to working precision: its direction is rounding
    // noise that no rotation can make orthogonal, so it is left alone.
    let negligible = {
        let e = T::default_epsilon() * a.norm();
        e * e
    };
    for _sweep in 0..SVD_MAX_SWEEPS {
        let mut rotated = false;
        for p in 0..X {
            for q in (p + 1)..X {
                let (mut alpha, mut beta, mut gamma) = (T::zero(), T::zero(), T::zero());
                for (ap, aq) in a.column(p).iter().zip(a.column(q).iter()) {
                    alpha += *ap * *ap;
                    beta += *aq * *aq;
                    gamma += *ap * *aq;
                }
                // Skip pairs already orthogonal to the tolerance, and negligible columns.
                if !(gamma.abs() > tol * alpha.sqrt() * beta.sqrt())
                    || alpha <= negligible
                    || beta <= negligible
                {
                    continue;
                }
                // ζ = (β − α) / 2γ ; t = sign ζ / (|ζ| + √(1 + ζ²)) makes the pair orthogonal.
                // A ζ so large that ζ² overflows gives t = 0: a rotation below resolution.
                let zeta = (beta - alpha) / (two * gamma);
                let t = zeta.signum() / (zeta.abs() + (T::one() + zeta * zeta).sqrt());
                if !(t.abs() > T::zero()) {
                    continue;
                }
                rotated = true;
                let c = T::one() / (T::one() + t * t).sqrt();
                let s = c * t;
                for i in 0..X {
                    let (x, y) = (a[(i, p)], a[(i, q)]);
                    a[(i, p)] = c * x - s * y;
                    a[(i, q)] = s * x + c * y;
                }
            }
        }
        if !rotated {
            let mut s = SVector::<T, X>::from_fn(|j, _| a.column(j).norm());
            sort_descending(&mut s);
            return Ok(s);
        }
    }
    Err(LinalgError::NotConverged)
}

/// Insertion sort, descending (`X²/2` comparisons at most).
fn sort_descending<T: Real, const X: usize>(s: &mut SVector<T, X>) {
    let v = s.as_mut_slice();
    for i in 1..v.len() {
        let mut j = i;
        while j > 0 && v[j - 1] < v[j] {
            v.swap(j - 1, j);
            j -= 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    #[test]
    fn singular_values_of_a_known_matrix() {
        // U diag(5, 2, 0.5) Vᵀ with rotations U, V
        let u = crate::geometry::rot_x(0.3) * crate::geometry::rot_z(-1.1);
        let v = crate::geometry::rot_y(0.7) * crate::geometry::rot_x(2.0);
        let a: Matrix3<f64> =
            u * Matrix3::from_diagonal(&nalgebra::Vector3::new(0.5, 5.0, 2.0)) * v.transpose();
        let s = singular_values(&a).unwrap();
        assert!(
            (s[0] - 5.0).abs() < 1e-12 && (s[1] - 2.0).abs() < 1e-12 && (s[2] - 0.5).abs() < 1e-12
        );
    }

    #[test]
    fn a_singular_matrix_has_a_zero_singular_value() {
        let a = Matrix3::<f32>::new(1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.5, -1.0, 2.0);
        let s = singular_values(&a).unwrap();
        assert!(s[2] < 1e-5 * s[0]);
    }
}
