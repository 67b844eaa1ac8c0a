//! The filter state and its predict and update steps.

use nalgebra::{Cholesky, RowSVector, SMatrix, SVector};

use crate::{real, Real};

use super::NisGate;
use crate::error::{Error, ErrorKind};

/// A Gaussian estimate — state `x` and covariance `P` — with the steps of a (extended) Kalman
/// filter on it.
///
/// `N` is the state dimension, fixed at compile time; `T` is `f32` on the target and `f64` in
/// reference runs. The model lives with the caller: an EKF computes the predicted state and the
/// Jacobians itself and hands them to [`Ekf::predict_to`] and [`Ekf::update`]. The toolkit owns
/// the numerics that every filter needs and that are easy to get wrong in `f32`:
///
/// * covariance updates in **Joseph form** `P⁺ = (I − KH) P (I − KH)ᵀ + K R Kᵀ`, which stays
///   symmetric positive semi-definite under rounding, where `(I − KH) P` does not;
/// * **hygiene** after every step: `P ← (P + Pᵀ)/2` and a **variance floor** on the diagonal,
///   so that a long run cannot collapse a variance to zero or below;
/// * the innovation covariance factored by **Cholesky** (no general inverse), with a typed error
///   when it is not positive definite;
/// * **NIS gating** ([`NisGate`]) before anything is changed;
/// * **transactional steps**: every input is checked for finiteness and every result is checked
///   before it is committed, so a step that fails leaves the filter exactly as it was.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ekf<const N: usize, T = f32> {
    x: SVector<T, N>,
    p: SMatrix<T, N, N>,
    variance_floor: T,
}

/// Result of a vector update.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct UpdateReport<const M: usize, T = f32> {
    /// The innovation `y = z − h(x̂)` that was offered, in measurement units.
    pub innovation: SVector<T, M>,
    /// Innovation covariance `S = H P Hᵀ + R` before the update.
    pub innovation_covariance: SMatrix<T, M, M>,
    /// Normalized innovation squared `yᵀ S⁻¹ y` (dimensionless; χ² with `M` degrees of freedom
    /// when the filter is consistent).
    pub nis: T,
    /// False when the gate rejected the measurement; the filter is then unchanged.
    pub accepted: bool,
}

/// Result of a scalar update.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScalarUpdateReport<T = f32> {
    /// The innovation `y = z − h(x̂)` that was offered, in measurement units.
    pub innovation: T,
    /// Innovation variance `s = h P hᵀ + r` before the update.
    pub innovation_variance: T,
    /// `y² / s` (χ² with one degree of freedom when consistent).
    pub nis: T,
    /// False when the gate rejected the measurement; the filter is then unchanged.
    pub accepted: bool,
}

/// Result of a sequential update of `M` scalar measurements.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SequentialUpdateReport<const M: usize, T = f32> {
    /// NIS of each scalar measurement at the moment it was processed.
    pub nis: SVector<T, M>,
    /// Bit `i` set when measurement `i` was accepted (`M ≤ 32`).
    pub accepted_mask: u32,
}

impl<const M: usize, T> SequentialUpdateReport<M, T> {
    /// Number of accepted scalar measurements.
    pub fn accepted_count(&self) -> u32 {
        self.accepted_mask.count_ones()
    }
}

fn all_finite<T: Real, const R: usize, const C: usize>(m: &SMatrix<T, R, C>) -> bool {
    m.iter().all(|v| v.is_finite())
}

impl<const N: usize, T: Real> Ekf<N, T> {
    /// A filter at state `x0` (state units) with covariance `p0` (state units squared).
    ///
    /// `p0` is symmetrized. The default variance floor is zero (no floor); set one with
    /// [`Self::with_variance_floor`].
    ///
    /// # Errors
    /// [`FilterError::NonFiniteInput`] for a non-finite element;
    /// [`FilterError::InvalidCovariance`] when `p0` is not positive definite.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub fn new(x0: SVector<T, N>, p0: SMatrix<T, N, N>) -> Result<Self, FilterError> {
        if !all_finite(&x0) || !all_finite(&p0) {
            return Err(FilterError::NonFiniteInput);
        }
        let p = symmetrize(&p0);
        if !positive_definite(&p) {
            return Err(FilterError::InvalidCovariance);
        }
        Ok(Self {
            x: x0,
            p,
            variance_floor: T::zero(),
        })
    }

    /// Sets the variance floor (state units squared) applied to every diagonal element of `P`
    /// after each step. Raising a diagonal element keeps `P` positive semi-definite. A negative
    /// or non-finite value is ignored.
    pub fn with_variance_floor(mut self, floor: T) -> Self {
        if floor.is_finite() && floor >= T::zero() {
            self.variance_floor = floor;
            self.p = self.hygiene(self.p);
        }
        self
    }

    /// The state estimate `x̂`.
    pub fn state(&self) -> &SVector<T, N> {
        &self.x
    }

    /// The covariance `P` of the estimate.
    pub fn covariance(&self) -> &SMatrix<T, N, N> {
        &self.p
    }

    /// The standard deviation of state element `i` (`√P_ii`), or `None` for `i ≥ N`.
    pub fn std_dev(&self, i: usize) -> Option<T> {
        self.p.get((i, i)).map(|v| v.sqrt())
    }

    /// Replaces the state, keeping the covariance (used by error-state filters to fold the
    /// estimated error into the nominal state and reset it to zero).
    ///
    /// # Errors
    /// [`FilterError::NonFiniteInput`] for a non-finite element (the filter is unchanged).
    pub fn set_state(&mut self, x: SVector<T, N>) -> Result<(), FilterError> {
        if !all_finite(&x) {
            return Err(FilterError::NonFiniteInput);
        }
        self.x = x;
        Ok(())
    }

    /// Replaces the covariance (symmetrized, floored).
    ///
    /// # Errors
    /// [`FilterError::NonFiniteInput`] or [`FilterError::InvalidCovariance`] as in
    /// [`Self::new`]; the filter is then unchanged.
    pub fn set_covariance(&mut self, p: SMatrix<T, N, N>) -> Result<(), FilterError> {
        if !all_finite(&p) {
            return Err(FilterError::NonFiniteInput);
        }
        let p = self.hygiene(p);
        if !positive_definite(&p) {
            return Err(FilterError::InvalidCovariance);
        }
        self.p = p;
        Ok(())
    }

    /// Linear prediction: `x ← F x`, `P ← F P Fᵀ + Q`.
    ///
    /// # Errors
    /// As [`Self::predict_to`].
    pub fn predict(
        &mut self,
        f: &SMatrix<T, N, N>,
        q: &SMatrix<T, N, N>,
    ) -> Result<(), FilterError> {
        let x_pred = f * self.x;
        self.predict_to(&x_pred, f, q)
    }

    /// Extended prediction: the caller has propagated the state through its nonlinear model to
    /// `x_pred` and linearized the model to the transition Jacobian `F`;
    /// `x ← x_pred`, `P ← F P Fᵀ + Q`.
    ///
    /// # Errors
    /// [`FilterError::NonFiniteInput`] for a non-finite input; [`FilterError::InvalidCovariance`]
    /// when `Q` has a negative diagonal element; [`FilterError::Numerical`] when the result
    /// overflows. The filter is unchanged on error.
    pub fn predict_to(
        &mut self,
        x_pred: &SVector<T, N>,
        f: &SMatrix<T, N, N>,
        q: &SMatrix<T, N, N>,
    ) -> Result<(), FilterError> {
        if !all_finite(x_pred) || !all_finite(f) || !all_finite(q) {
            return Err(FilterError::NonFiniteInput);
        }
        if q.diagonal().iter().any(|&v| v < T::zero()) {
            return Err(FilterError::InvalidCovariance);
        }
        // P⁻ = F P Fᵀ + Q
        self.commit(*x_pred, self.hygiene(f * self.p * f.transpose() + q))
    }

    /// Vector measurement update with innovation `y = z − h(x̂)`, Jacobian `H = ∂h/∂x` and
    /// measurement noise covariance `R`, in Joseph form, optionally gated.
    ///
    /// # Errors
    /// [`FilterError::NonFiniteInput`] for a non-finite input;
    /// [`FilterError::InnovationNotPositiveDefinite`] when `S = H P Hᵀ + R` has no Cholesky
    /// factor; [`FilterError::Numerical`] when the result overflows. The filter is unchanged on
    /// error and when the gate rejects the measurement.
    pub fn update<const M: usize>(
        &mut self,
        y: &SVector<T, M>,
        h: &SMatrix<T, M, N>,
        r: &SMatrix<T, M, M>,
        gate: Option<NisGate<T>>,
    ) -> Result<UpdateReport<M, T>, FilterError> {
        if !all_finite(y) || !all_finite(h) || !all_finite(r) {
            return Err(FilterError::NonFiniteInput);
        }
        let ph_t = self.p * h.transpose(); // P Hᵀ (N×M)
        let s = symmetrize(&(h * ph_t + r)); // S = H P Hᵀ + R
        let chol = Cholesky::new(s).ok_or(FilterError::InnovationNotPositiveDefinite)?;
        let nis = y.dot(&chol.solve(y)); // yᵀ S⁻¹ y
        let mut report = UpdateReport {
            innovation: *y,
            innovation_covariance: s,
            nis,
            accepted: false,
        };
        if gate.is_some_and(|g| !g.accepts(nis)) {
            return Ok(report);
        }
        // K = P Hᵀ S⁻¹ = (S⁻¹ H P)ᵀ, S symmetric
        let k = chol.solve(&ph_t.transpose()).transpose();
        self.commit(self.x + k * y, self.joseph(&k, h, &(k * r * k.transpose())))?;
        report.accepted = true;
        Ok(report)
    }

    /// Scalar measurement update: innovation `y`, Jacobian row `h`, noise variance `r > 0`.
    /// No matrix is factored: `s = h P hᵀ + r`, `K = P hᵀ / s`, then the Joseph form.
    ///
    /// # Errors
    /// [`FilterError::NonFiniteInput`]; [`FilterError::NonPositiveNoise`] for `r ≤ 0`;
    /// [`FilterError::InnovationNotPositiveDefinite`] for `s ≤ 0`; [`FilterError::Numerical`].
    /// The filter is unchanged on error and when the gate rejects.
    pub fn update_scalar(
        &mut self,
        y: T,
        h: &RowSVector<T, N>,
        r: T,
        gate: Option<NisGate<T>>,
    ) -> Result<ScalarUpdateReport<T>, FilterError> {
        if !y.is_finite() || !r.is_finite() || !all_finite(h) {
            return Err(FilterError::NonFiniteInput);
        }
        if r <= T::zero() {
            return Err(FilterError::NonPositiveNoise);
        }
        let ph_t = self.p * h.transpose(); // P hᵀ
        let s = (h * ph_t).x + r; // s = h P hᵀ + r
        if !(s > T::zero()) || !s.is_finite() {
            return Err(FilterError::InnovationNotPositiveDefinite);
        }
        let nis = y * y / s;
        let mut report = ScalarUpdateReport {
            innovation: y,
            innovation_variance: s,
            nis,
            accepted: false,
        };
        if gate.is_some_and(|g| !g.accepts(nis)) {
            return Ok(report);
        }
        let k = ph_t / s; // K = P hᵀ / s
        self.commit(self.x + k * y, self.joseph(&k, h, &(k * k.transpose() * r)))?;
        report.accepted = true;
        Ok(report)
    }

    /// `M` scalar updates in sequence, for measurements with independent noise (diagonal `R`,
    /// variances `r_diag`): no matrix inverse, each row gated on its own (χ²₁), and a rejected
    /// row does not block the others.
    ///
    /// Rows are linearized once, at the prior: after each accepted row the innovations of the
    /// rows still to come are corrected by `−H_j Δx`, so that for a linear model the result
    /// equals the batch update with the same `R`.
    ///
    /// # Errors
    /// As [`Self::update_scalar`], checked for all rows before any is applied, and
    /// [`FilterError::Numerical`] if a row fails midway (the filter then returns to its state
    /// before the call). `M` is at most 32 (the report's mask), checked at compile time.
    pub fn update_sequential<const M: usize>(
        &mut self,
        y: &SVector<T, M>,
        h: &SMatrix<T, M, N>,
        r_diag: &SVector<T, M>,
        gate: Option<NisGate<T>>,
    ) -> Result<SequentialUpdateReport<M, T>, FilterError> {
        const { assert!(M <= 32, "update_sequential takes at most 32 rows") };
        if !all_finite(y) || !all_finite(h) || !all_finite(r_diag) {
            return Err(FilterError::NonFiniteInput);
        }
        if r_diag.iter().any(|&r| r <= T::zero()) {
            return Err(FilterError::NonPositiveNoise);
        }
        let saved = self.clone();
        let x0 = self.x;
        let mut report = SequentialUpdateReport {
            nis: SVector::<T, M>::zeros(),
            accepted_mask: 0,
        };
        // (row indices from `0..M`, not `enumerate`: its counter keeps an overflow check)
        for (i, (row, (&yi, &ri))) in (0..M).zip(h.row_iter().zip(y.iter().zip(r_diag.iter()))) {
            // innovation of row i, corrected for what the earlier rows already moved x
            let yi = yi - (row * (self.x - x0)).x;
            let row = row.into_owned();
            match self.update_scalar(yi, &row, ri, gate) {
                Ok(r) => {
                    if let Some(n) = report.nis.get_mut(i) {
                        *n = r.nis;
                    }
                    if r.accepted {
                        report.accepted_mask |= 1 << i;
                    }
                }
                Err(e) => {
                    *self = saved;
                    return Err(match e {
                        FilterError::InnovationNotPositiveDefinite => e,
                        _ => FilterError::Numerical,
                    });
                }
            }
        }
        Ok(report)
    }

    /// Normalized estimation error squared `(x̂ − x)ᵀ P⁻¹ (x̂ − x)` against a known truth `x`
    /// (χ² with `N` degrees of freedom for a consistent filter). For Monte Carlo consistency
    /// tests.
    ///
    /// # Errors
    /// [`FilterError::NonFiniteInput`]; [`FilterError::InvalidCovariance`] if `P` has no
    /// Cholesky factor.
    pub fn nees(&self, truth: &SVector<T, N>) -> Result<T, FilterError> {
        if !all_finite(truth) {
            return Err(FilterError::NonFiniteInput);
        }
        let e = self.x - truth;
        let chol = Cholesky::new(self.p).ok_or(FilterError::InvalidCovariance)?;
        Ok(e.dot(&chol.solve(&e)))
    }

    /// Stores a new estimate if it is finite; otherwise leaves the filter as it was.
    fn commit(&mut self, x: SVector<T, N>, p: SMatrix<T, N, N>) -> Result<(), FilterError> {
        if !all_finite(&x) || !all_finite(&p) {
            return Err(FilterError::Numerical);
        }
        self.x = x;
        self.p = p;
        Ok(())
    }

    /// Joseph form `(I − K H) P (I − K H)ᵀ + K R Kᵀ` (the last term passed in), then hygiene.
    fn joseph<const M: usize>(
        &self,
        k: &SMatrix<T, N, M>,
        h: &SMatrix<T, M, N>,
        krk_t: &SMatrix<T, N, N>,
    ) -> SMatrix<T, N, N> {
        let a = SMatrix::<T, N, N>::identity() - k * h;
        self.hygiene(a * self.p * a.transpose() + krk_t)
    }

    /// Symmetrize and apply the variance floor.
    fn hygiene(&self, p: SMatrix<T, N, N>) -> SMatrix<T, N, N> {
        let mut p = symmetrize(&p);
        for i in 0..N {
            if let Some(v) = p.get_mut((i, i)) {
                if *v < self.variance_floor {
                    *v = self.variance_floor;
                }
            }
        }
        p
    }
}

/// `(P + Pᵀ) / 2`, halved before the sum so that it cannot overflow.
fn symmetrize<T: Real, const N: usize>(p: &SMatrix<T, N, N>) -> SMatrix<T, N, N> {
    let half = real::<T>(0.5);
    p * half + p.transpose() * half
}

/// True when `p` has a Cholesky factor and every element of it is finite.
fn positive_definite<T: Real, const N: usize>(p: &SMatrix<T, N, N>) -> bool {
    Cholesky::new(*p).is_some_and(|c| all_finite(&c.l()))
}

/// Errors of the Kalman filter toolkit ([`crate::ekf`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FilterError {
    /// A state, covariance, transition, measurement, Jacobian or noise value was NaN or infinite.
    #[error("non-finite filter input")]
    NonFiniteInput,
    /// A covariance given to the filter (initial covariance, process noise) is not symmetric
    /// positive semi-definite with a positive diagonal.
    #[error("covariance is not symmetric positive semi-definite")]
    InvalidCovariance,
    /// A measurement noise variance is zero or negative.
    #[error("measurement noise variance is not positive")]
    NonPositiveNoise,
    /// The innovation covariance `S = H P Hᵀ + R` is not positive definite, so the update cannot
    /// be weighed. Happens when `R` is not PD or `P` has lost definiteness.
    #[error("innovation covariance is not positive definite")]
    InnovationNotPositiveDefinite,
    /// The step produced non-finite numbers from finite input (overflow). The state is
    /// unchanged.
    #[error("filter step overflowed")]
    Numerical,
}

impl Error for FilterError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFiniteInput => ErrorKind::NonFinite,
            Self::InvalidCovariance | Self::NonPositiveNoise => ErrorKind::InvalidInput,
            Self::InnovationNotPositiveDefinite => ErrorKind::NotPositiveDefinite,
            Self::Numerical => ErrorKind::Numerical,
        }
    }
}
