//! A positive semi-definite factorization, a regularized solve and marginal information: the
//! information-form helpers of the one-stage filter. Every loop runs over the matrices' own
//! dimensions, so every index is in range.

use nalgebra::{Cholesky, SMatrix, SVector};

use crate::{real, Real};

/// `L̃` with `W = L̃ L̃ᵀ` for a symmetric positive semi-definite `W` (`LDLᵀ` without pivoting,
/// pivots below `1e-6 · max diag` taken as zero, so a singular `W` gives zero columns):
/// `N` outer steps, bounded.
pub(crate) fn psd_factor<T: Real, const N: usize>(w: &SMatrix<T, N, N>) -> SMatrix<T, N, N> {
    let max_diag = w.diagonal().iter().fold(T::zero(), |m, &v| m.max(v));
    let tol = max_diag * real(1e-6);
    // unit lower triangle L and pivots D, column by column (all indices below N)
    let mut l = SMatrix::<T, N, N>::zeros();
    let mut d = SVector::<T, N>::zeros();
    for j in 0..N {
        let dj = w[(j, j)] - (0..j).fold(T::zero(), |s, k| s + l[(j, k)] * l[(j, k)] * d[k]);
        if !(dj > tol) {
            continue;
        }
        d[j] = dj;
        l[(j, j)] = T::one();
        for i in (j + 1)..N {
            let s = (0..j).fold(w[(i, j)], |s, k| s - l[(i, k)] * l[(j, k)] * d[k]);
            l[(i, j)] = s / dj;
        }
    }
    l * SMatrix::from_diagonal(&d.map(|v| v.sqrt()))
}

/// `J + εI` with `ε = 1e-4 · max diag`, and the identity on rows and columns without
/// information (`J_kk = 0`).
fn regularized<T: Real, const N: usize>(j: &SMatrix<T, N, N>) -> SMatrix<T, N, N> {
    let max_diag = j.diagonal().iter().fold(T::zero(), |m, &v| m.max(v));
    let mut m = *j + SMatrix::<T, N, N>::identity() * (max_diag * real(1e-4));
    for k in 0..N {
        if !(j[(k, k)] > T::zero()) {
            m.row_mut(k).fill(T::zero());
            m.column_mut(k).fill(T::zero());
            m[(k, k)] = T::one();
        }
    }
    m
}

/// Solves `(J + εI) x = b` by Cholesky (see [`regularized`]): a pseudo-inverse for the
/// unobservable directions of a singular `J`; zero when even that fails.
pub(crate) fn regularized_solve<T: Real, const N: usize>(
    j: &SMatrix<T, N, N>,
    b: &SVector<T, N>,
) -> SVector<T, N> {
    Cholesky::new(regularized(j)).map_or_else(SVector::zeros, |c| c.solve(b))
}

/// `1/(J⁻¹)_kk` for every parameter with information, zero for the others.
pub(crate) fn marginal_information<T: Real, const N: usize>(j: &SMatrix<T, N, N>) -> SVector<T, N> {
    let Some(chol) = Cholesky::new(regularized(j)) else {
        return SVector::zeros();
    };
    let inv = chol.inverse();
    SVector::from_fn(|k, _| {
        let d = inv[(k, k)];
        if j[(k, k)] > T::zero() && d > T::zero() {
            d.recip()
        } else {
            T::zero()
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Matrix4, Vector3};

    #[test]
    fn psd_factor_reproduces_definite_and_singular_matrices() {
        let a = nalgebra::Matrix4x2::new(1.0, 2.0, -1.0, 0.5, 3.0, 0.0, 0.2, -2.0);
        let singular: Matrix4<f64> = a * a.transpose(); // rank 2
        let definite = singular + Matrix4::identity() * 0.3;
        for w in [singular, definite, Matrix4::zeros()] {
            let l = psd_factor(&w);
            assert!((l * l.transpose() - w).norm() < 1e-9 * (1.0 + w.norm()));
        }
    }

    #[test]
    fn solve_and_marginal_information_skip_empty_rows() {
        let j = Matrix3::<f64>::new(4.0, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 0.0);
        let x = regularized_solve(&j, &Vector3::new(1.0, 1.0, 0.0));
        assert!((j * x - Vector3::new(1.0, 1.0, 0.0)).norm() < 1e-3);
        let m = marginal_information(&j);
        // 1/(J⁻¹)₁₁ = 4 − 1/2 (Schur complement), to the 1e-4 regularization
        assert!((m.x - 3.5).abs() < 3.5e-3 && (m.y - 1.75).abs() < 2e-3 && m.z == 0.0);
    }
}
