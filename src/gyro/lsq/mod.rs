//! Sequential linear least squares `U x ≈ Z` without storing the rows: the paper's normal
//! equations (5.8) and a square-root information (Givens QR) accumulator of the same size.
//!
//! Both accumulate one scalar row `(u_s, z_s)` at a time and keep `X (X + 1)` numbers plus a
//! few scalars, whatever the number of rows:
//!
//! | | [`NormalEquations`] (paper eq. (5.8)) | [`SqrtInformation`] (Givens QR) |
//! |---|---|---|
//! | keeps | `UᵀU`, `UᵀZ`, `ZᵀZ` | `R` (upper triangular, `RᵀR = UᵀU`), `QᵀZ`, residual `‖·‖²` |
//! | one row | `X (X + 1)/2` multiply-adds | `X` Givens rotations of a shrinking row |
//! | solve | Cholesky of `UᵀU` | back substitution on `R` |
//! | accuracy | loses `κ(U)²` (the condition number is squared) | loses `κ(U)` |
//!
//! In `f32` with `κ(U) ≈ 300` (the paper's §6 experiment) the normal equations lose about
//! `κ² ε ≈ 1 %` of the solution, the square-root form `κ ε ≈ 4·10⁻⁵`.
//!
//! Each accumulator reports the **observability** of what it holds
//! ([`ObservabilityReport`]: singular values of `U`, numerical rank, condition number, from a
//! bounded one-sided Jacobi iteration), and [`LeastSquaresAccumulator::solve`] returns
//! [`CalibrationError::Unobservable`] instead of an answer when the rank is deficient.

mod normal_equations;
mod sqrt_information;

use nalgebra::SVector;

use crate::gyro::CalibrationError;
use crate::{real, Real};

pub use normal_equations::NormalEquations;
pub use sqrt_information::SqrtInformation;

/// Largest magnitude accepted for an element of a row `u_s` or a right-hand side `z_s`.
///
/// With every input bounded by `10⁶`, the accumulated sums stay below `10¹² × rows`, so no
/// accumulator can overflow in `f32` for any realistic number of rows: a step never produces a
/// non-finite number from accepted input.
pub const MAX_ROW_ENTRY: f64 = 1e6;

/// A sequential least-squares accumulator of `X` unknowns.
pub trait LeastSquaresAccumulator<T: Real, const X: usize> {
    /// Adds the scalar equation `u · x = z` (one row of `U x = Z`).
    ///
    /// # Errors
    /// [`CalibrationError::NonFiniteInput`] or [`CalibrationError::InputOutOfRange`] (an element
    /// beyond [`MAX_ROW_ENTRY`]); the accumulator is then unchanged.
    fn add_row(&mut self, u: &SVector<T, X>, z: T) -> Result<(), CalibrationError>;

    /// Number of rows accumulated (including carried information, see
    /// [`SqrtInformation::marginalize`]).
    fn rows(&self) -> u32;

    /// Singular values of `U`, numerical rank and condition number of what is accumulated.
    /// `rank_tolerance` is relative to the largest singular value (see
    /// [`default_rank_tolerance`]).
    ///
    /// # Errors
    /// [`CalibrationError::InvalidConfig`] for a tolerance outside `(0, 1)`;
    /// [`CalibrationError::NotConverged`] from the bounded Jacobi iteration.
    fn observability(
        &self,
        rank_tolerance: T,
    ) -> Result<ObservabilityReport<X, T>, CalibrationError>;

    /// The least-squares solution with its formal standard deviations.
    ///
    /// # Errors
    /// [`CalibrationError::TooFewRows`] with `rows ≤ X`; [`CalibrationError::Unobservable`] when
    /// the numerical rank is below `X`; [`CalibrationError::NotPositiveDefinite`] (normal
    /// equations only) when rounding destroyed the definiteness of `UᵀU`; the errors of
    /// [`Self::observability`].
    fn solve(&self, rank_tolerance: T) -> Result<LsqSolution<X, T>, CalibrationError>;

    /// Forgets everything accumulated.
    fn clear(&mut self);
}

/// The default relative rank tolerance, `√ε` of the scalar type: `3.5·10⁻⁴` in `f32` (systems
/// whose column-equilibrated condition number exceeds about 2900 are called rank deficient),
/// `1.5·10⁻⁸` in `f64`.
pub fn default_rank_tolerance<T: Real>() -> T {
    T::default_epsilon().sqrt()
}

/// How well the accumulated system determines the unknowns.
///
/// The unknowns have different units (rad, s⁻¹, dimensionless), so the rank is decided on the
/// column-equilibrated system `U D⁻¹` (`D = diag ‖u_j‖`, each column scaled to unit norm),
/// which does not depend on the units; the condition number of `U` itself is reported too
/// (the paper's §6 figure).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ObservabilityReport<const X: usize, T = f32> {
    /// Singular values of `U` in descending order (units of the rows).
    pub singular_values: SVector<T, X>,
    /// Number of singular values of `U D⁻¹` above `rank_tolerance × σ_max(U D⁻¹)`.
    pub rank: usize,
    /// Condition number `σ_max / σ_min` of `U` (the largest finite value of `T` when
    /// `σ_min = 0`).
    pub condition: T,
    /// Condition number of the column-equilibrated `U D⁻¹`.
    pub equilibrated_condition: T,
}

impl<const X: usize, T: Real> ObservabilityReport<X, T> {
    /// The report for the singular values `s` of `U` and `s_eq` of `U D⁻¹`.
    pub(crate) fn new(s: SVector<T, X>, s_eq: SVector<T, X>, rank_tolerance: T) -> Self {
        let rank = crate::count(s_eq.iter().filter(|v| **v > rank_tolerance * s_eq.max()));
        Self {
            singular_values: s,
            rank,
            condition: condition(&s),
            equilibrated_condition: condition(&s_eq),
        }
    }

    /// True when every unknown is determined (`rank = X`).
    pub fn full_rank(&self) -> bool {
        self.rank == X
    }
}

fn condition<T: Real, const X: usize>(s: &SVector<T, X>) -> T {
    let s_min = s.min();
    if s_min > T::zero() {
        s.max() / s_min
    } else {
        T::max_value().unwrap_or_else(|| real(f64::from(f32::MAX)))
    }
}

/// `1 / d` for the column scales `d` (1 for a zero column, which stays zero).
pub(crate) fn inverse_scales<T: Real, const X: usize>(d: &SVector<T, X>) -> SVector<T, X> {
    d.map(|v| {
        if v > T::zero() {
            T::one() / v
        } else {
            T::one()
        }
    })
}

/// A least-squares solution.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LsqSolution<const X: usize, T = f32> {
    /// The estimate `x̂` minimizing `‖U x − Z‖²`.
    pub x: SVector<T, X>,
    /// Formal standard deviations of `x̂`: `σ₀ √diag((UᵀU)⁻¹)`.
    pub std_dev: SVector<T, X>,
    /// A-posteriori standard deviation of one row's residual, `σ₀ = √(rss / (rows − X))`.
    pub sigma0: T,
    /// Residual sum of squares `‖U x̂ − Z‖²`.
    pub residual_sum_of_squares: T,
    /// Rows accumulated.
    pub rows: u32,
    /// Rank and conditioning of the system.
    pub observability: ObservabilityReport<X, T>,
}

/// Checks a row before it is accumulated.
pub(crate) fn check_row<T: Real, const X: usize>(
    u: &SVector<T, X>,
    z: T,
) -> Result<(), CalibrationError> {
    if !z.is_finite() || !u.iter().all(|v| v.is_finite()) {
        return Err(CalibrationError::NonFiniteInput);
    }
    let limit: T = real(MAX_ROW_ENTRY);
    if z.abs() > limit || u.iter().any(|v| v.abs() > limit) {
        return Err(CalibrationError::InputOutOfRange);
    }
    Ok(())
}

/// Checks a relative rank tolerance.
pub(crate) fn check_tolerance<T: Real>(rank_tolerance: T) -> Result<(), CalibrationError> {
    if rank_tolerance > T::zero() && rank_tolerance < T::one() {
        Ok(())
    } else {
        Err(CalibrationError::InvalidConfig)
    }
}

/// `σ₀ = √(rss / (rows − X))`, or [`CalibrationError::TooFewRows`].
pub(crate) fn sigma0<T: Real, const X: usize>(rss: T, rows: u32) -> Result<T, CalibrationError> {
    if (rows as usize) <= X {
        return Err(CalibrationError::TooFewRows { rows });
    }
    let dof: T = real(f64::from(rows) - X as f64);
    Ok((rss.max(T::zero()) / dof).sqrt())
}
