//! LAMBDA decorrelation of an integer ambiguity covariance (Teunissen's LAMBDA method, in the
//! MLAMBDA formulation of Chang, Yang and Zhou 2005).
//!
//! Given the covariance `Q` of float ambiguities, it finds an integer unimodular `Z` and the
//! factorization `Zᵀ Q Z = Lᵀ D L` (`L` unit lower triangular, `D` diagonal) such that the
//! transformed ambiguities `ẑ' = Zᵀ ẑ` are as decorrelated as integer transforms allow and the
//! conditional variances `D` decrease towards the last index, where the integer search starts.
//! Integer Gauss transformations make `|L_ik| ≤ 1/2`; neighbouring indices are swapped when
//! that lowers the later conditional variance. Every step is an exact change of integer basis,
//! so stopping early (after [`LAMBDA_MAX_ITERATIONS`]) still gives a valid, only less
//! decorrelated, factorization.
//!
//! The matrices have the compile-time capacity `N`; only the leading `n × n` block is used.

use nalgebra::{SMatrix, SVector};

use crate::attitude::snapshot::SnapshotError;
use crate::{real, Real};

/// Upper bound on the reduction loop's iterations (Gauss sweeps and swaps).
pub const LAMBDA_MAX_ITERATIONS: usize = 512;

/// The decorrelated factorization `Zᵀ Q Z = Lᵀ D L`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Decorrelation<const N: usize, T = f32> {
    /// Dimension in use (`≤ N`).
    pub n: usize,
    /// Unit lower triangular `L`.
    pub l: SMatrix<T, N, N>,
    /// Conditional variances `D` (the variance of `z'_k` given `z'_{k+1..n}`).
    pub d: SVector<T, N>,
    /// The integer unimodular transform `Z` (integers stored exactly in `T`): `ẑ' = Zᵀ ẑ`.
    pub z: SMatrix<T, N, N>,
    /// `Z⁻ᵀ` (also integer): `z = Z⁻ᵀ z'` maps transformed integers back.
    pub z_inv_t: SMatrix<T, N, N>,
}

/// Factorizes and decorrelates the leading `n × n` block of `q` (symmetric positive definite).
///
/// # Errors
/// [`SnapshotError::NonFinite`]; [`SnapshotError::Numerical`] if `q` is not positive definite
/// or `n` is 0 or larger than `N`.
pub fn decorrelate<const N: usize, T: Real>(
    q: &SMatrix<T, N, N>,
    n: usize,
) -> Result<Decorrelation<N, T>, SnapshotError> {
    if n == 0 || n > N {
        return Err(SnapshotError::Numerical);
    }
    if !q.iter().all(|v| v.is_finite()) {
        return Err(SnapshotError::NonFinite);
    }
    // (`min` lets the compiler see the indices in range.) Built in place (the caller's stack
    // holds one copy of the matrices): `z` serves as the factorization's workspace before it
    // becomes the transform.
    let n = n.min(N);
    let mut dec = Decorrelation {
        n,
        l: SMatrix::identity(),
        d: SVector::from_element(T::one()),
        z: *q,
        z_inv_t: SMatrix::identity(),
    };
    ltdl(&mut dec.z, &mut dec.l, &mut dec.d, n)?;
    dec.z.fill_with_identity();
    if n < 2 {
        return Ok(dec);
    }
    let Decorrelation {
        l, d, z, z_inv_t, ..
    } = &mut dec;
    let mut k = n - 2;
    let mut k1 = k;
    for _ in 0..LAMBDA_MAX_ITERATIONS {
        if k <= k1 && !integer_gauss_column(l, z, z_inv_t, k, n) {
            break;
        }
        if swap_if_it_lowers_variance(l, d, z, z_inv_t, k, n) {
            k1 = k;
            k = n - 2;
        } else if k == 0 {
            break;
        } else {
            k -= 1;
        }
    }
    if !(l.iter().all(|v| v.is_finite()) && d.iter().all(|v| v.is_finite())) {
        return Err(SnapshotError::Numerical);
    }
    Ok(dec)
}

/// Integer entries of `Z` must stay exact in `T` (2^22 leaves margin in f32).
const LAMBDA_INTEGER_LIMIT: f64 = 4_194_304.0;

/// Integer Gauss transformations of column `k`: `L(i:n, k) −= μ L(i:n, i)`,
/// `Z(:, k) −= μ Z(:, i)` for `i > k`, `μ = round(L(i, k))`. Returns false (and stops) when an
/// integer entry would leave the range where `T` holds it exactly.
fn integer_gauss_column<T: Real, const N: usize>(
    l: &mut SMatrix<T, N, N>,
    z: &mut SMatrix<T, N, N>,
    z_inv_t: &mut SMatrix<T, N, N>,
    k: usize,
    n: usize,
) -> bool {
    let limit: T = real(LAMBDA_INTEGER_LIMIT);
    for i in (k + 1)..n {
        let mu = at(l, i, k).round();
        if mu == T::zero() {
            continue;
        }
        for r in i..n {
            let v = at(l, r, k) - mu * at(l, r, i);
            set(l, r, k, v);
        }
        for r in 0..n {
            let zk = at(z, r, k) - mu * at(z, r, i);
            let zi = at(z_inv_t, r, i) + mu * at(z_inv_t, r, k);
            set(z, r, k, zk);
            set(z_inv_t, r, i, zi);
            if !(zk.abs() < limit && zi.abs() < limit) {
                return false;
            }
        }
    }
    true
}

/// Swaps `k` and `k + 1` when that lowers the conditional variance at `k + 1` (by more than
/// rounding), updating `L`, `D`, `Z` and `Z⁻ᵀ`. Returns whether it swapped.
fn swap_if_it_lowers_variance<T: Real, const N: usize>(
    l: &mut SMatrix<T, N, N>,
    d: &mut SVector<T, N>,
    z: &mut SMatrix<T, N, N>,
    z_inv_t: &mut SMatrix<T, N, N>,
    k: usize,
    n: usize,
) -> bool {
    let lk = at(l, k + 1, k);
    let (dk, dk1) = (get(d, k), get(d, k + 1));
    let del = dk + lk * lk * dk1;
    if !(del < dk1 * (T::one() - T::default_epsilon() * real(64.0))) {
        return false;
    }
    let eta = dk / del;
    let lam = dk1 * lk / del;
    if let Some(x) = d.get_mut(k) {
        *x = eta * dk1;
    }
    if let Some(x) = d.get_mut(k + 1) {
        *x = del;
    }
    for c in 0..k {
        let a0 = at(l, k, c);
        let a1 = at(l, k + 1, c);
        set(l, k, c, -lk * a0 + a1);
        set(l, k + 1, c, eta * a0 + lam * a1);
    }
    set(l, k + 1, k, lam);
    for r in (k + 2)..n {
        swap_entries(l, (r, k), (r, k + 1));
    }
    for r in 0..n {
        swap_entries(z, (r, k), (r, k + 1));
        swap_entries(z_inv_t, (r, k), (r, k + 1));
    }
    true
}

/// Swaps two entries of `m` (in range by construction).
fn swap_entries<T: Real, const N: usize>(
    m: &mut SMatrix<T, N, N>,
    a: (usize, usize),
    b: (usize, usize),
) {
    let (va, vb) = (at(m, a.0, a.1), at(m, b.0, b.1));
    set(m, a.0, a.1, vb);
    set(m, b.0, b.1, va);
}

/// Checked element read (0 outside the matrix; indices are in range by construction, the
/// check only keeps panics out of the compiled code).
fn at<T: Real, const N: usize>(m: &SMatrix<T, N, N>, i: usize, j: usize) -> T {
    m.get((i, j)).copied().unwrap_or_else(T::zero)
}

/// Checked element write (ignored outside the matrix).
fn set<T: Real, const N: usize>(m: &mut SMatrix<T, N, N>, i: usize, j: usize, v: T) {
    if let Some(x) = m.get_mut((i, j)) {
        *x = v;
    }
}

/// Checked vector read.
fn get<T: Real, const N: usize>(v: &SVector<T, N>, i: usize) -> T {
    v.get(i).copied().unwrap_or_else(T::zero)
}

/// `Q = Lᵀ D L` for the leading `n × n` block (eliminating from the last index).
fn ltdl<const N: usize, T: Real>(
    a: &mut SMatrix<T, N, N>,
    l: &mut SMatrix<T, N, N>,
    d: &mut SVector<T, N>,
    n: usize,
) -> Result<(), SnapshotError> {
    let n = n.min(N); // (lets the compiler see the indices in range)
    for j in (0..n).rev() {
        let djj = a[(j, j)];
        if !(djj > T::zero()) {
            return Err(SnapshotError::Numerical);
        }
        d[j] = djj;
        let root = djj.sqrt();
        for c in 0..=j {
            l[(j, c)] = a[(j, c)] / root;
        }
        for i in 0..j {
            for c in 0..=i {
                a[(i, c)] -= l[(j, c)] * l[(j, i)];
            }
        }
        let ljj = l[(j, j)];
        for c in 0..=j {
            l[(j, c)] /= ljj;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SMatrix;

    fn sample_q() -> SMatrix<f64, 5, 5> {
        // A code-dominated float covariance: rank-3 large part plus small diagonal.
        let g = SMatrix::<f64, 5, 3>::from_row_slice(&[
            0.3, -0.5, -0.81, 0.7, 0.1, -0.7, -0.2, 0.6, -0.77, -0.4, -0.6, -0.69, 0.1, 0.05, -0.99,
        ]);
        let n = g.transpose() * g;
        let proj = g * n.try_inverse().unwrap() * g.transpose();
        proj * 2.5 + SMatrix::<f64, 5, 5>::identity() * 2.5e-4
    }

    #[test]
    fn factorization_is_exact_and_transform_unimodular() {
        let q = sample_q();
        let dec = decorrelate(&q, 5).unwrap();
        let lhs = dec.z.transpose() * q * dec.z;
        let rhs = dec.l.transpose() * SMatrix::from_diagonal(&dec.d) * dec.l;
        assert!(
            (lhs - rhs).norm() < 1e-9 * q.norm(),
            "{}",
            (lhs - rhs).norm()
        );
        assert!((dec.z.determinant().abs() - 1.0).abs() < 1e-9);
        assert!(dec.z.iter().all(|v| v.fract() == 0.0));
        assert!((dec.z_inv_t.transpose() * dec.z - SMatrix::<f64, 5, 5>::identity()).norm() < 1e-9);
        // decorrelation: the first conditional variances no longer carry the code-level 2.5
        assert!(dec.d[4] < 0.1, "{:?}", dec.d);
    }

    #[test]
    fn uses_only_the_leading_block() {
        let mut q = SMatrix::<f64, 6, 6>::identity();
        q.fixed_view_mut::<5, 5>(0, 0).copy_from(&sample_q());
        q[(5, 5)] = f64::MAX; // ignored
        let dec = decorrelate(&q, 5).unwrap();
        assert_eq!(dec.z[(5, 5)], 1.0);
        assert!(decorrelate(&q, 7).is_err());
        let mut bad = sample_q();
        bad[(2, 2)] = -1.0;
        assert!(decorrelate(&bad, 5).is_err());
    }
}
