//! The calibrator's configuration and results: settings, the equations of one epoch, what
//! became of an epoch, and the estimate.

use nalgebra::{SMatrix, SVector, Vector3};

use crate::gyro::CalibrationError;
use crate::{real, Real};

use super::lsq::{default_rank_tolerance, LsqSolution};
use super::propagation::ResidualCentering;
#[cfg(doc)]
use super::GyroCalibrator;

/// Settings of a [`GyroCalibrator`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CalibratorConfig<T = f32> {
    /// Gyro sample interval `h` (s). The attitude is propagated over `H = 2h`.
    pub sample_interval: T,
    /// Epochs whose relative reference quaternion has `|p₀| <` this value (a rotation near
    /// 180° since `t₀`) are skipped, as the paper requires `p₀(t_j) ≠ 0` (§5).
    pub min_abs_p0: T,
    /// Reference attitudes given as Euler angles ([`GyroCalibrator::add_reference_euler`]) are
    /// skipped when `|pitch|` is within this margin (rad) of 90°, where the angles are singular
    /// and small angle errors become large attitude errors (§3).
    pub gimbal_lock_margin: T,
    /// Relative rank tolerance of the solve (see
    /// [`default_rank_tolerance`](super::lsq::default_rank_tolerance)).
    pub rank_tolerance: T,
    /// Pulse weight `σ` (rad) when the gyro delivers pulse counts, `None` for float increments.
    pub pulse_weight: Option<T>,
    /// Centering of the quantization residual (pulse counts only).
    pub centering: ResidualCentering,
}

impl<T: Real> CalibratorConfig<T> {
    /// Float increments every `sample_interval` seconds; `min_abs_p0 = 0.05`, a 5° gimbal-lock
    /// margin and the default rank tolerance.
    pub fn new(sample_interval: T) -> Self {
        Self {
            sample_interval,
            min_abs_p0: real(0.05),
            gimbal_lock_margin: real(5f64.to_radians()),
            rank_tolerance: default_rank_tolerance(),
            pulse_weight: None,
            centering: ResidualCentering::None,
        }
    }

    /// The same with pulse counts of weight `sigma` (rad) and the given centering.
    pub fn with_pulses(mut self, sigma: T, centering: ResidualCentering) -> Self {
        self.pulse_weight = Some(sigma);
        self.centering = centering;
        self
    }

    pub(crate) fn validate(&self) -> Result<(), CalibrationError> {
        let h_ok = self.sample_interval.is_finite() && self.sample_interval > T::zero();
        let p0_ok = self.min_abs_p0 >= T::zero() && self.min_abs_p0 < T::one();
        let gl_ok =
            self.gimbal_lock_margin >= T::zero() && self.gimbal_lock_margin < T::frac_pi_2();
        let tol_ok = self.rank_tolerance > T::zero() && self.rank_tolerance < T::one();
        if h_ok && p0_ok && gl_ok && tol_ok {
            Ok(())
        } else {
            Err(CalibrationError::InvalidConfig)
        }
    }
}

/// The three equations (2.7) of one epoch `t_j`: `U_j x = z_j` with
/// `U_j = [2Φ(p_j), Γ_j Θ(t_j), Γ_j Ψ(t_j, t₀)]`, `Γ_j = ½ [p₀ⱼ E₃ − Φ(p_j)]` (eq. (5.7)).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EpochEquations<const X: usize, T = f32> {
    /// The rows `U_j` (`3 × X`), columns ordered as `x = [w₀; c; d]`.
    pub rows: SMatrix<T, 3, X>,
    /// Right-hand side `z_j = p* − p` (plus the centering of eq. (5.5) if configured),
    /// dimensionless (quaternion components).
    pub rhs: Vector3<T>,
    /// Scalar part `p₀` of the relative reference quaternion `P = N(t_j) ∘ N̄(t₀)`.
    pub p0: T,
}

/// Why an epoch was not used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SkipReason {
    /// `|p₀| <` [`CalibratorConfig::min_abs_p0`]: rotated by nearly 180° since `t₀`.
    SmallP0,
    /// The reference Euler angles are within [`CalibratorConfig::gimbal_lock_margin`] of
    /// their singularity.
    NearGimbalLock,
}

/// What became of one reference epoch.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EpochOutcome<const X: usize, T = f32> {
    /// The epoch's three equations were accumulated.
    Used(EpochEquations<X, T>),
    /// The epoch was skipped.
    Skipped(SkipReason),
}

/// Epoch counters of a calibration window.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EpochCounters {
    /// Epochs whose equations were accumulated.
    pub used: u32,
    /// Epochs skipped for `|p₀|` below the threshold.
    pub skipped_small_p0: u32,
    /// Epochs skipped near the Euler-angle singularity.
    pub skipped_gimbal_lock: u32,
}

/// The calibration result: `x̂ = [ŵ₀; ĉ; d̂]` with formal standard deviations.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CalibrationEstimate<const CM: usize, const DN: usize, const X: usize, T = f32> {
    /// `ŵ₀`: error of the initial computed attitude `M(t₀)` (half-angle vector, rad, frame
    /// `K ≈ I`): `Λ(t₀) ≈ (1 + w₀) ∘ M(t₀)`.
    pub w0: Vector3<T>,
    /// `ĉ`: gyro error parameters of the model `D` (units per element, see the model).
    pub c: SVector<T, CM>,
    /// `d̂`: reference drift parameters (units per element, see the drift model).
    pub d: SVector<T, DN>,
    /// Formal standard deviation of `ŵ₀` (rad).
    pub w0_std: Vector3<T>,
    /// Formal standard deviations of `ĉ`.
    pub c_std: SVector<T, CM>,
    /// Formal standard deviations of `d̂`.
    pub d_std: SVector<T, DN>,
    /// The least-squares solution it came from (rank, condition, residual).
    pub solution: LsqSolution<X, T>,
}

impl<const CM: usize, const DN: usize, const X: usize, T: Real> CalibrationEstimate<CM, DN, X, T> {
    /// Compile-time check of `X = 3 + CM + DN`.
    const DIMENSIONS_AGREE: () = assert!(X == 3 + CM + DN, "X must be 3 + CM + DN");

    /// Splits a least-squares solution of `x = [w₀; c; d]` (from any accumulator holding a
    /// calibrator's equations) into its parts.
    pub fn from_solution(solution: LsqSolution<X, T>) -> Self {
        let () = Self::DIMENSIONS_AGREE;
        let (x, s) = (&solution.x, &solution.std_dev);
        // element-wise copies (no view-to-owned conversion, whose length check could panic)
        let part =
            |v: &SVector<T, X>, at: usize, i: usize| v.get(at + i).copied().unwrap_or(T::zero());
        Self {
            w0: Vector3::from_fn(|i, _| part(x, 0, i)),
            c: SVector::from_fn(|i, _| part(x, 3, i)),
            d: SVector::from_fn(|i, _| part(x, 3 + CM, i)),
            w0_std: Vector3::from_fn(|i, _| part(s, 0, i)),
            c_std: SVector::from_fn(|i, _| part(s, 3, i)),
            d_std: SVector::from_fn(|i, _| part(s, 3 + CM, i)),
            solution,
        }
    }
}
