//! Bounded cyclic Jacobi eigen-decomposition of small symmetric matrices.
//!
//! nalgebra's `SymmetricEigen::new` iterates without a bound; this one stops after
//! [`EIGEN_MAX_SWEEPS`] sweeps. Jacobi rotations converge quadratically and keep the
//! eigenvectors orthonormal to rounding, with high relative accuracy; 3×3 and 4×4 matrices
//! converge in 3–6 sweeps in `f32` and `f64`.

use nalgebra::{SMatrix, SVector};

use crate::{real, Real};

/// Upper bound on the sweeps of [`symmetric_eigen`] (each sweep is `D(D−1)/2` rotations).
pub const EIGEN_MAX_SWEEPS: usize = 12;

/// Eigenvalues and orthonormal eigenvectors (as columns) of the symmetric part of `a`, sorted
/// by decreasing eigenvalue.
///
/// Returns `None` when an element is non-finite or the sweep bound is reached before the
/// off-diagonal mass falls below `8 ε ‖A‖_F`.
pub fn symmetric_eigen<T: Real, const D: usize>(
    a: &SMatrix<T, D, D>,
) -> Option<(SVector<T, D>, SMatrix<T, D, D>)> {
    if !a.iter().all(|v| v.is_finite()) {
        return None;
    }
    let half: T = real(0.5);
    let mut m = (a + a.transpose()) * half;
    let mut v = SMatrix::<T, D, D>::identity();
    let scale = m.norm();
    let tolerance = T::default_epsilon() * real(8.0) * scale;
    let mut converged = false;
    for _ in 0..EIGEN_MAX_SWEEPS {
        if off_diagonal_norm(&m) <= tolerance {
            converged = true;
            break;
        }
        for p in 0..D {
            for q in (p + 1)..D {
                rotate(&mut m, &mut v, p, q);
            }
        }
    }
    if !converged && off_diagonal_norm(&m) > tolerance {
        return None;
    }
    // Sort by decreasing eigenvalue (selection sort, D ≤ 4 in practice).
    let mut values = m.diagonal();
    for i in 0..D {
        let mut best = i;
        for j in (i + 1)..D {
            if values[j] > values[best] {
                best = j;
            }
        }
        if best != i {
            values.swap_rows(i, best);
            v.swap_columns(i, best);
        }
    }
    Some((values, v))
}

fn off_diagonal_norm<T: Real, const D: usize>(m: &SMatrix<T, D, D>) -> T {
    let mut s = T::zero();
    for i in 0..D {
        for j in 0..D {
            if i != j {
                s += m[(i, j)] * m[(i, j)];
            }
        }
    }
    s.sqrt()
}

/// One Jacobi rotation zeroing `m[p][q]` (Golub & Van Loan, Alg. 8.5.1), accumulated in `v`.
fn rotate<T: Real, const D: usize>(
    m: &mut SMatrix<T, D, D>,
    v: &mut SMatrix<T, D, D>,
    p: usize,
    q: usize,
) {
    let apq = m[(p, q)];
    if apq == T::zero() {
        return;
    }
    let two: T = real(2.0);
    // θ = (a_qq − a_pp) / (2 a_pq);  t = sign(θ) / (|θ| + √(θ² + 1))
    let theta = (m[(q, q)] - m[(p, p)]) / (two * apq);
    let t = if theta >= T::zero() {
        T::one() / (theta + (theta * theta + T::one()).sqrt())
    } else {
        -T::one() / (-theta + (theta * theta + T::one()).sqrt())
    };
    if !t.is_finite() {
        return;
    }
    let c = T::one() / (t * t + T::one()).sqrt();
    let s = t * c;
    // M ← Jᵀ M J with J the rotation in the (p, q) plane.
    for k in 0..D {
        let mkp = m[(k, p)];
        let mkq = m[(k, q)];
        m[(k, p)] = c * mkp - s * mkq;
        m[(k, q)] = s * mkp + c * mkq;
    }
    for k in 0..D {
        let mpk = m[(p, k)];
        let mqk = m[(q, k)];
        m[(p, k)] = c * mpk - s * mqk;
        m[(q, k)] = s * mpk + c * mqk;
    }
    m[(p, q)] = T::zero();
    m[(q, p)] = T::zero();
    for k in 0..D {
        let vkp = v[(k, p)];
        let vkq = v[(k, q)];
        v[(k, p)] = c * vkp - s * vkq;
        v[(k, q)] = s * vkp + c * vkq;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Matrix4};

    #[test]
    fn reconstructs_symmetric_matrices_with_orthonormal_vectors() {
        let a = Matrix4::new(
            4.0, 1.0, -2.0, 0.5, 1.0, 2.0, 0.0, 1.0, -2.0, 0.0, 3.0, -1.5, 0.5, 1.0, -1.5, -1.0,
        );
        let (w, v) = symmetric_eigen(&a).unwrap();
        let rebuilt = v * Matrix4::from_diagonal(&w) * v.transpose();
        assert!((rebuilt - a).norm() < 1e-12);
        assert!((v.transpose() * v - Matrix4::identity()).norm() < 1e-13);
        assert!(w[0] >= w[1] && w[1] >= w[2] && w[2] >= w[3]);
        // f32 to rounding
        let (w32, v32) = symmetric_eigen(&a.cast::<f32>()).unwrap();
        let r32 = v32 * Matrix4::from_diagonal(&w32) * v32.transpose();
        assert!((r32 - a.cast::<f32>()).norm() < 1e-5);
    }

    #[test]
    fn handles_diagonal_repeated_and_rank_deficient_input() {
        let d = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 3.0, 2.0));
        let (w, _) = symmetric_eigen(&d).unwrap();
        assert_eq!(w, nalgebra::Vector3::new(3.0, 2.0, 1.0));
        let u = nalgebra::Vector3::new(1.0f32, 2.0, 3.0);
        let rank1 = u * u.transpose();
        let (w, v) = symmetric_eigen(&rank1).unwrap();
        assert!((w[0] - 14.0).abs() < 1e-5 && w[1].abs() < 1e-5 && w[2].abs() < 1e-5);
        assert!((v.column(0).dot(&u.normalize())).abs() > 1.0 - 1e-6);
        let mut nan = Matrix3::<f32>::identity();
        nan.m23 = f32::NAN;
        assert!(symmetric_eigen(&nan).is_none());
    }
}
