//! The square-root information accumulator: sequential Givens QR of the rows.

use nalgebra::{SMatrix, SVector};

use crate::gyro::CalibrationError;
use crate::linalg::singular_values;
use crate::Real;

use super::{
    check_row, check_tolerance, inverse_scales, sigma0, LeastSquaresAccumulator, LsqSolution,
    ObservabilityReport,
};

/// Sequential least squares in square-root information form.
///
/// Holds the upper-triangular `R` (`X × X`) and `y = QᵀZ` of the QR factorization
/// `U = Q [R; 0]`, and the residual sum of squares: every new row `(u, z)` is rotated into
/// `[R | y]` by `X` Givens rotations (the row `u` is zeroed one element at a time), and what is
/// left of `z` is the new residual. `RᵀR = UᵀU` and `Rᵀy = UᵀZ`, the quantities of the paper's
/// eq. (5.8), are never formed, so the accuracy is that of QR (`κ(U) ε`), not of the normal
/// equations (`κ(U)² ε`). Same memory as [`super::NormalEquations`].
///
/// The information it holds on some unknowns can be carried from one estimation window to the
/// next with [`Self::marginalize`] (for example the gyro errors `c`, when a long calibration is
/// re-anchored on a new reference epoch and `w₀` starts afresh).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SqrtInformation<const X: usize, T = f32> {
    r: SMatrix<T, X, X>,
    y: SVector<T, X>,
    rss: T,
    rows: u32,
}

impl<const X: usize, T: Real> Default for SqrtInformation<X, T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const X: usize, T: Real> SqrtInformation<X, T> {
    /// An empty accumulator (no information).
    pub fn new() -> Self {
        Self {
            r: SMatrix::zeros(),
            y: SVector::zeros(),
            rss: T::zero(),
            rows: 0,
        }
    }

    /// The upper-triangular square-root information matrix `R` (`RᵀR = UᵀU`).
    pub fn factor(&self) -> &SMatrix<T, X, X> {
        &self.r
    }

    /// The rotated right-hand side `y = QᵀZ` (`R x̂ = y`).
    pub fn rhs(&self) -> &SVector<T, X> {
        &self.y
    }

    /// Residual sum of squares of the rows accumulated so far.
    pub fn residual_sum_of_squares(&self) -> T {
        self.rss
    }

    /// Rotates the row `(u, z)` into `[R | y]` (eq. (5.8) in square-root form). No checks.
    fn rotate_in(&mut self, mut u: SVector<T, X>, mut z: T) {
        for i in 0..X {
            let b = u[i];
            if b == T::zero() {
                continue;
            }
            let a = self.r[(i, i)];
            // Givens rotation [c s; −s c] zeroing u_i against R_ii: ρ = √(R_ii² + u_i²). The
            // inputs are bounded by MAX_ROW_ENTRY, so the squares cannot overflow; a ρ that
            // underflows to 0 means u_i is negligible, and it is dropped.
            let rho = (a * a + b * b).sqrt();
            if !(rho > T::zero()) {
                continue;
            }
            let (c, s) = (a / rho, b / rho);
            self.r[(i, i)] = rho;
            for j in (i + 1)..X {
                let (rij, uj) = (self.r[(i, j)], u[j]);
                self.r[(i, j)] = c * rij + s * uj;
                u[j] = c * uj - s * rij;
            }
            let yi = self.y[i];
            self.y[i] = c * yi + s * z;
            z = c * z - s * yi;
        }
        // What is left of z is orthogonal to the range of U: one residual component.
        self.rss += z * z;
    }

    /// Keeps only the information on the unknowns flagged in `keep`; the others are
    /// marginalized (their information is dropped; they become free unknowns again, determined
    /// only by rows added later).
    ///
    /// The factor is re-triangularized with the dropped unknowns first, and the rows of the
    /// kept block are rotated into a fresh accumulator in the original order. With rows
    /// involving the dropped unknowns only before the call, solving after new rows gives
    /// exactly the least-squares solution of all rows. The residual sum of squares is kept;
    /// the row count loses one row per dropped unknown (degrees of freedom are preserved).
    pub fn marginalize(&self, keep: &[bool; X]) -> Self {
        // perm[k] = original index of the k-th unknown in the order (dropped…, kept…)
        let mut perm = [0usize; X];
        let mut k = 0usize;
        for want in [false, true] {
            for (i, flag) in keep.iter().enumerate() {
                if *flag == want {
                    if let Some(slot) = perm.get_mut(k) {
                        *slot = i;
                    }
                    k = k.saturating_add(1); // (at most 2X: never saturates)
                }
            }
        }
        let dropped = crate::count(keep.iter().filter(|f| !**f));
        let mut permuted = Self::new();
        for i in 0..X {
            let row = SVector::<T, X>::from_fn(|j, _| {
                let col = perm.get(j).copied().unwrap_or(j);
                self.r.get((i, col)).copied().unwrap_or(T::zero())
            });
            permuted.rotate_in(row, self.y[i]);
        }
        let mut out = Self::new();
        for i in dropped..X {
            let mut row = SVector::<T, X>::zeros();
            for (j, &orig) in perm.iter().enumerate() {
                if let Some(slot) = row.get_mut(orig) {
                    *slot = permuted.r[(i, j)];
                }
            }
            out.rotate_in(row, permuted.y[i]);
        }
        out.rss = self.rss;
        out.rows = self.rows.saturating_sub(dropped as u32);
        out
    }
}

impl<const X: usize, T: Real> LeastSquaresAccumulator<T, X> for SqrtInformation<X, T> {
    fn add_row(&mut self, u: &SVector<T, X>, z: T) -> Result<(), CalibrationError> {
        check_row(u, z)?;
        self.rotate_in(*u, z);
        self.rows = self.rows.saturating_add(1);
        Ok(())
    }

    fn rows(&self) -> u32 {
        self.rows
    }

    fn observability(
        &self,
        rank_tolerance: T,
    ) -> Result<ObservabilityReport<X, T>, CalibrationError> {
        check_tolerance(rank_tolerance)?;
        // The singular values of U are those of R (U = Q [R; 0]); ‖u_j‖ = ‖r_j‖.
        let s = singular_values(&self.r)?;
        let scale = inverse_scales(&SVector::<T, X>::from_fn(|j, _| self.r.column(j).norm()));
        let s_eq = singular_values(&(self.r * SMatrix::from_diagonal(&scale)))?;
        Ok(ObservabilityReport::new(s, s_eq, rank_tolerance))
    }

    fn solve(&self, rank_tolerance: T) -> Result<LsqSolution<X, T>, CalibrationError> {
        let sigma0 = sigma0::<T, X>(self.rss, self.rows)?;
        let observability = self.observability(rank_tolerance)?;
        if !observability.full_rank() || (0..X).any(|i| self.r[(i, i)] == T::zero()) {
            return Err(CalibrationError::Unobservable {
                rank: observability.rank as u16,
            });
        }
        // R x̂ = y by back substitution
        let x = back_substitute(&self.r, &self.y);
        // (UᵀU)⁻¹ = R⁻¹ R⁻ᵀ: var_i = Σ_k (R⁻¹)_ik², column k of R⁻¹ from R v = e_k
        let mut var = SVector::<T, X>::zeros();
        for k in 0..X {
            let e = SVector::<T, X>::from_fn(|i, _| if i == k { T::one() } else { T::zero() });
            let v = back_substitute(&self.r, &e);
            for i in 0..X {
                var[i] += v[i] * v[i];
            }
        }
        let std_dev = var.map(|v| sigma0 * v.sqrt());
        if !x.iter().chain(std_dev.iter()).all(|v| v.is_finite()) {
            return Err(CalibrationError::Unobservable {
                rank: observability.rank as u16,
            });
        }
        Ok(LsqSolution {
            x,
            std_dev,
            sigma0,
            residual_sum_of_squares: self.rss,
            rows: self.rows,
            observability,
        })
    }

    fn clear(&mut self) {
        *self = Self::new();
    }
}

/// Solves `R x = y` for upper-triangular `R` with a non-zero diagonal.
fn back_substitute<T: Real, const X: usize>(
    r: &SMatrix<T, X, X>,
    y: &SVector<T, X>,
) -> SVector<T, X> {
    let mut x = SVector::<T, X>::zeros();
    for i in (0..X).rev() {
        let mut acc = y[i];
        for j in (i + 1)..X {
            acc -= r[(i, j)] * x[j];
        }
        x[i] = acc / r[(i, i)];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SVector;

    fn row(seed: u32) -> SVector<f64, 4> {
        // a small LCG: rows in general position
        SVector::from_fn(|i, _| {
            let x = (seed * 4 + i as u32)
                .wrapping_mul(1_103_515_245)
                .wrapping_add(12_345);
            f64::from(x >> 8) / f64::from(1u32 << 24) - 0.5
        })
    }

    #[test]
    fn marginalizing_a_nuisance_gives_the_joint_solution() {
        // Unknowns [a, b, c, d]; window 1 involves all four; window 2 only b, c, d plus a new
        // nuisance that re-uses slot a. Marginalizing a after window 1 must give exactly the
        // least-squares solution of both windows with two separate nuisances.
        let truth = SVector::<f64, 4>::new(0.5, -1.0, 2.0, 0.25);
        let a2 = -0.75; // the second window's nuisance
        let mut joint = SqrtInformation::<5, f64>::new(); // [a1, b, c, d, a2]
        let mut first = SqrtInformation::<4, f64>::new();
        for k in 0..20 {
            let u = row(k);
            let z = u.dot(&truth) + 1e-3 * f64::from(k).cos();
            first.add_row(&u, z).unwrap();
            let uj = SVector::<f64, 5>::new(u[0], u[1], u[2], u[3], 0.0);
            joint.add_row(&uj, z).unwrap();
        }
        let mut second = first.marginalize(&[false, true, true, true]);
        for k in 20..40 {
            let u = row(k);
            let z = u[0] * a2
                + u[1] * truth[1]
                + u[2] * truth[2]
                + u[3] * truth[3]
                + 1e-3 * f64::from(k).sin();
            second.add_row(&u, z).unwrap();
            let uj = SVector::<f64, 5>::new(0.0, u[1], u[2], u[3], u[0]);
            joint.add_row(&uj, z).unwrap();
        }
        let s = second.solve(1e-10).unwrap();
        let j = joint.solve(1e-10).unwrap();
        for i in 1..4 {
            assert!(
                (s.x[i] - j.x[i]).abs() < 1e-12,
                "{i}: {} vs {}",
                s.x[i],
                j.x[i]
            );
            assert!((s.std_dev[i] - j.std_dev[i]).abs() < 1e-12 * j.std_dev[i].max(1.0));
        }
        assert!((s.x[0] - j.x[4]).abs() < 1e-12);
    }
}
