//! Small bounded matrix helpers of the filter: element access without panics, angle wrapping,
//! a positive semi-definite factorization, a regularized solve and marginal information.

use nalgebra::{Cholesky, SMatrix, SVector};

use crate::{real, Real};

/// Element `(i, j)`, zero when out of range.
pub(crate) fn el<T: Real, const R: usize, const C: usize>(
    m: &SMatrix<T, R, C>,
    i: usize,
    j: usize,
) -> T {
    m.get((i, j)).copied().unwrap_or_else(T::zero)
}

/// Sets element `(i, j)`; ignored when out of range.
pub(crate) fn set<T: Real, const R: usize, const C: usize>(
    m: &mut SMatrix<T, R, C>,
    i: usize,
    j: usize,
    v: T,
) {
    if let Some(e) = m.get_mut((i, j)) {
        *e = v;
    }
}

/// Adds `v` to element `i` of a vector; ignored when out of range.
pub(crate) fn add<T: Real, const N: usize>(x: &mut SVector<T, N>, i: usize, v: T) {
    if let Some(e) = x.get_mut(i) {
        *e += v;
    }
}

/// `angle` wrapped to `(−π, π]`.
pub(crate) fn wrap<T: Real>(angle: T) -> T {
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

/// `L̃` with `W = L̃ L̃ᵀ` for a symmetric positive semi-definite `W` (`LDLᵀ` without pivoting,
/// pivots below `1e-6 · max diag` taken as zero, so a singular `W` gives zero columns):
/// `N` outer steps, bounded.
pub(crate) fn psd_factor<T: Real, const N: usize>(w: &SMatrix<T, N, N>) -> SMatrix<T, N, N> {
    let max_diag = w.diagonal().iter().fold(T::zero(), |m, &v| m.max(v));
    let tol = max_diag * real(1e-6);
    let mut l = SMatrix::<T, N, N>::zeros();
    let mut d = SVector::<T, N>::zeros();
    let dk = |d: &SVector<T, N>, k: usize| d.get(k).copied().unwrap_or_else(T::zero);
    for j in 0..N {
        let mut dj = el(w, j, j);
        for k in 0..j {
            let ljk = el(&l, j, k);
            dj -= ljk * ljk * dk(&d, k);
        }
        if !(dj > tol) {
            continue;
        }
        if let Some(v) = d.get_mut(j) {
            *v = dj;
        }
        set(&mut l, j, j, T::one());
        for i in (j + 1)..N {
            let mut s = el(w, i, j);
            for k in 0..j {
                s -= el(&l, i, k) * el(&l, j, k) * dk(&d, k);
            }
            set(&mut l, i, j, s / dj);
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
        if !(el(j, k, k) > T::zero()) {
            m.row_mut(k).fill(T::zero());
            m.column_mut(k).fill(T::zero());
            set(&mut m, k, k, T::one());
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
        let d = el(&inv, k, k);
        if el(j, k, k) > T::zero() && d > T::zero() {
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
