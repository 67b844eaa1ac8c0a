//! Inverse of a small square matrix by Givens QR, with its pivot ratio (used for `Φ⁻¹` of the
//! six-state model: nalgebra's LU and general inverse are not used in the core).

use nalgebra::SMatrix;

use crate::{real, Real};

/// The inverse of a square matrix by Givens QR (no pivoting, `N(N−1)/2` rotations) and back
/// substitution, and the pivot ratio `min |R_ii| / max |R_ii|` (1 for an orthogonal matrix, 0
/// for a singular one). `None` when a pivot is below `N · ε · max |R_ii|` or the result is not
/// finite. Bounded: `O(N³)` operations, no iteration.
pub(crate) fn givens_inverse<T: Real, const N: usize>(
    a: &SMatrix<T, N, N>,
) -> Option<(SMatrix<T, N, N>, T)> {
    // Row-major working copies: R (becomes upper triangular) and Qᵀ (starts as I).
    let mut r = [[T::zero(); N]; N];
    let mut qt = [[T::zero(); N]; N];
    // (indices from `0..N`, not `enumerate`: its counter keeps an overflow check)
    for (i, (row_r, row_q)) in (0..N).zip(r.iter_mut().zip(qt.iter_mut())) {
        for (j, (vr, vq)) in (0..N).zip(row_r.iter_mut().zip(row_q.iter_mut())) {
            *vr = a[(i, j)];
            if i == j {
                *vq = T::one();
            }
        }
    }
    for j in 0..N {
        for i in (j + 1)..N {
            let (top_r, bottom_r) = r.split_at_mut_checked(i)?;
            let (row_j, row_i) = (top_r.get_mut(j)?, bottom_r.first_mut()?);
            let (x, y) = (*row_j.get(j)?, *row_i.get(j)?);
            if y == T::zero() {
                continue;
            }
            let h = x.hypot(y);
            let (c, s) = (x / h, y / h);
            rotate(row_j, row_i, c, s);
            let (top_q, bottom_q) = qt.split_at_mut_checked(i)?;
            rotate(top_q.get_mut(j)?, bottom_q.first_mut()?, c, s);
        }
    }
    let pivots = || {
        (0..N)
            .zip(r.iter())
            .filter_map(|(i, row)| row.get(i))
            .map(|p| p.abs())
    };
    let max = pivots().fold(T::zero(), |m, p| m.max(p));
    let min = pivots().fold(max, |m, p| m.min(p));
    if !(max > T::zero()) || !(min > max * T::default_epsilon() * real(N as f64)) {
        return None;
    }
    // Back substitution R X = Qᵀ, last row first.
    let mut x = SMatrix::<T, N, N>::zeros();
    for i in (0..N).rev() {
        let row = r.get(i)?;
        let pivot = *row.get(i)?;
        for col in 0..N {
            let mut acc = *qt.get(i)?.get(col)?;
            for (kk, &rik) in (0..N).zip(row.iter()).skip(i + 1) {
                acc -= rik * *x.get((kk, col))?;
            }
            *x.get_mut((i, col))? = acc / pivot;
        }
    }
    if !x.iter().all(|v| v.is_finite()) {
        return None;
    }
    Some((x, min / max))
}

/// Applies the Givens rotation `[c s; −s c]` to two rows.
fn rotate<T: Real, const N: usize>(row_j: &mut [T; N], row_i: &mut [T; N], c: T, s: T) {
    for (a, b) in row_j.iter_mut().zip(row_i.iter_mut()) {
        let (u, v) = (*a, *b);
        *a = c * u + s * v;
        *b = c * v - s * u;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{rot_x, rot_y, rot_z};

    #[test]
    fn givens_inverse_inverts_and_refuses_singular_matrices() {
        let a = SMatrix::<f64, 6, 6>::from_fn(|i, j| {
            ((i * 13 + j * 7 + i * j * 5) % 11) as f64 * 0.1 + if i == j { 2.0 } else { 0.0 }
        });
        let (inv, ratio) = givens_inverse(&a).unwrap();
        assert!((inv * a - SMatrix::<f64, 6, 6>::identity()).norm() < 1e-10);
        assert!(ratio > 0.0 && ratio <= 1.0);
        let mut s = a;
        let r0 = s.row(0).into_owned();
        s.set_row(3, &(r0 * 2.0));
        assert!(givens_inverse(&s).is_none());
        let rot = rot_z(0.21f64) * rot_y(-0.1) * rot_x(2.0);
        let (inv, ratio) = givens_inverse(&rot).unwrap();
        assert!((inv - rot.transpose()).norm() < 1e-14);
        assert!((ratio - 1.0).abs() < 1e-12);
    }
}
