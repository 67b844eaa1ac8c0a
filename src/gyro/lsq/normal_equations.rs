//! The paper's sequential normal equations, eq. (5.8).

use nalgebra::{Cholesky, SMatrix, SVector};

use crate::gyro::CalibrationError;
use crate::linalg::singular_values;
use crate::Real;

use super::{
    check_row, check_tolerance, inverse_scales, sigma0, LeastSquaresAccumulator, LsqSolution,
    ObservabilityReport,
};

/// Sequential least squares by the normal equations, as the paper accumulates them (eq. (5.8)):
/// `(UᵀU)_s = (UᵀU)_{s−1} + u_sᵀu_s`, `(UᵀZ)_s = (UᵀZ)_{s−1} + u_sᵀz_s`, plus `ZᵀZ` for the
/// residual. Solved by Cholesky.
///
/// Cheap (`X (X + 1)/2` multiply-adds per row) but forming `UᵀU` squares the condition number:
/// in `f32` a system with `κ(U) ≈ 300` loses about 1 % of its solution, and a rank deficiency
/// below `√ε` relative cannot be told from rounding. Kept next to [`super::SqrtInformation`]
/// (same memory) to show that difference.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NormalEquations<const X: usize, T = f32> {
    /// `UᵀU`, upper triangle maintained (the lower one is filled at solve time).
    n: SMatrix<T, X, X>,
    b: SVector<T, X>,
    zz: T,
    rows: u32,
}

impl<const X: usize, T: Real> Default for NormalEquations<X, T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const X: usize, T: Real> NormalEquations<X, T> {
    /// An empty accumulator.
    pub fn new() -> Self {
        Self {
            n: SMatrix::zeros(),
            b: SVector::zeros(),
            zz: T::zero(),
            rows: 0,
        }
    }

    /// The normal matrix `UᵀU` (symmetric).
    pub fn normal_matrix(&self) -> SMatrix<T, X, X> {
        let mut n = self.n;
        for i in 0..X {
            for j in 0..i {
                n[(i, j)] = n[(j, i)];
            }
        }
        n
    }

    /// The right-hand side `UᵀZ`.
    pub fn rhs(&self) -> &SVector<T, X> {
        &self.b
    }
}

impl<const X: usize, T: Real> LeastSquaresAccumulator<T, X> for NormalEquations<X, T> {
    fn add_row(&mut self, u: &SVector<T, X>, z: T) -> Result<(), CalibrationError> {
        check_row(u, z)?;
        // eq. (5.8): (UᵀU) += uᵀu (upper triangle), (UᵀZ) += uᵀz
        for i in 0..X {
            let ui = u[i];
            for j in i..X {
                self.n[(i, j)] += ui * u[j];
            }
            self.b[i] += ui * z;
        }
        self.zz += z * z;
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
        // singular values of the symmetric UᵀU are |eigenvalues| = σ_i(U)²; ‖u_j‖² = N_jj
        let n = self.normal_matrix();
        let s = singular_values(&n)?.map(|v| v.sqrt());
        let scale = SMatrix::from_diagonal(&inverse_scales(
            &n.diagonal().map(|v| v.max(T::zero()).sqrt()),
        ));
        let s_eq = singular_values(&(scale * n * scale))?.map(|v| v.sqrt());
        Ok(ObservabilityReport::new(s, s_eq, rank_tolerance))
    }

    fn solve(&self, rank_tolerance: T) -> Result<LsqSolution<X, T>, CalibrationError> {
        if (self.rows as usize) <= X {
            return Err(CalibrationError::TooFewRows { rows: self.rows });
        }
        let observability = self.observability(rank_tolerance)?;
        if !observability.full_rank() {
            return Err(CalibrationError::Unobservable {
                rank: observability.rank as u16,
            });
        }
        let chol =
            Cholesky::new(self.normal_matrix()).ok_or(CalibrationError::NotPositiveDefinite)?;
        // UᵀU x̂ = UᵀZ
        let x = chol.solve(&self.b);
        // rss = ZᵀZ − x̂ᵀUᵀZ at the solution (suffers cancellation in f32; clamped at 0)
        let rss = (self.zz - x.dot(&self.b)).max(T::zero());
        let sigma0 = sigma0::<T, X>(rss, self.rows)?;
        let std_dev = chol
            .inverse()
            .diagonal()
            .map(|v| sigma0 * v.max(T::zero()).sqrt());
        if !x.iter().chain(std_dev.iter()).all(|v| v.is_finite()) {
            return Err(CalibrationError::NotPositiveDefinite);
        }
        Ok(LsqSolution {
            x,
            std_dev,
            sigma0,
            residual_sum_of_squares: rss,
            rows: self.rows,
            observability,
        })
    }

    fn clear(&mut self) {
        *self = Self::new();
    }
}
