//! The calibrator: equations (2.7)/(5.4) at chosen epochs, accumulated as in (5.7)–(5.8),
//! solved for `x = [w₀; c; d]`.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::geometry::{skew, Euler321, Quaternion};
use crate::{real, Real};

use super::calibration_types::{
    CalibrationEstimate, CalibratorConfig, EpochCounters, EpochEquations, EpochOutcome, SkipReason,
};
use super::error_model::{ErrorQuadratures, GyroErrorModel, ReferenceDriftModel};
use super::lsq::{check_row, LeastSquaresAccumulator};
use super::propagation::{AttitudePropagator, PulseDecoder, ResidualCentering};
use crate::error::{Error, ErrorKind};
use crate::linalg::LinalgError;

/// In-flight gyro calibration against a reference attitude (paper 001).
///
/// Feed it the gyro's increments (or pulse counts) every `h`, and at chosen epochs the
/// reference attitude `N(t_j)` of a body-fixed frame `J` (any fixed, unknown mounting relative
/// to the gyro axes) in the reference frame `L`. At each epoch it forms
/// `P = N(t_j) ∘ N̄(t₀)` and `P* = M(t_j) ∘ M̄(t₀)` and the three equations (2.7) in the
/// unknowns `x = [w₀; c; d]` (`X = 3 + CM + DN`), which it accumulates in `A` without storing
/// them. [`Self::solve`] returns the estimate, and [`Self::corrected_attitude`] the attitude
/// corrected with it.
///
/// Type parameters: the gyro model `G` (`D` is `3 × CM`), the reference drift model `R`
/// (`3 × DN`), the accumulator `A` ([`super::SqrtInformation`] or
/// [`super::NormalEquations`]). `X = 3 + CM + DN` is checked at compile time.
///
/// The caller keeps the reference and the gyro synchronized: a reference passed to
/// [`Self::add_reference`] belongs to the time of the last increment, which must complete a
/// propagation step (an even number of samples since `t₀`).
#[derive(Clone, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GyroCalibrator<G, R, A, const CM: usize, const DN: usize, const X: usize, T = f32> {
    config: CalibratorConfig<T>,
    model: G,
    drift: R,
    accumulator: A,
    propagator: AttitudePropagator<T>,
    decoder: Option<PulseDecoder<T>>,
    quadratures: ErrorQuadratures<CM, DN, T>,
    m0: Quaternion<T>,
    reference0: Quaternion<T>,
    correction: SVector<T, CM>,
    samples: u32,
    counters: EpochCounters,
}

impl<G, R, A, const CM: usize, const DN: usize, const X: usize, T>
    GyroCalibrator<G, R, A, CM, DN, X, T>
where
    T: Real,
    G: GyroErrorModel<T, CM>,
    R: ReferenceDriftModel<T, DN>,
    A: LeastSquaresAccumulator<T, X>,
{
    /// Compile-time check of `X = 3 + CM + DN`.
    const DIMENSIONS_AGREE: () = assert!(X == 3 + CM + DN, "X must be 3 + CM + DN");

    /// A calibration window starting at `t₀` with the computed attitude `m0 = M(t₀)` (gyro
    /// axes to `K`) and the reference attitude `reference0 = N(t₀)` (frame `J` to `L`).
    /// `accumulator` may already hold information (a prior, see
    /// [`super::SqrtInformation::marginalize`]).
    ///
    /// # Errors
    /// [`CalibrationError::InvalidConfig`], [`CalibrationError::NonFiniteInput`],
    /// [`CalibrationError::InputOutOfRange`] (a quaternion far from unit norm).
    pub fn new(
        config: CalibratorConfig<T>,
        model: G,
        drift: R,
        accumulator: A,
        m0: Quaternion<T>,
        reference0: Quaternion<T>,
    ) -> Result<Self, CalibrationError> {
        let () = Self::DIMENSIONS_AGREE;
        config.validate()?;
        let decoder = match config.pulse_weight {
            Some(sigma) => Some(PulseDecoder::new(sigma, config.centering)?),
            None => None,
        };
        let m0 = unit(&m0)?;
        let reference0 = unit(&reference0)?;
        let propagator = AttitudePropagator::new(m0)?;
        let quadratures = ErrorQuadratures::new(m0.to_dcm(), drift.g(T::zero()));
        Ok(Self {
            config,
            model,
            drift,
            accumulator,
            propagator,
            decoder,
            quadratures,
            m0,
            reference0,
            correction: SVector::zeros(),
            samples: 0,
            counters: EpochCounters::default(),
        })
    }

    /// Starts with the gyro correction `c_applied` (see [`Self::set_gyro_correction`]).
    ///
    /// # Errors
    /// [`CalibrationError::NonFiniteInput`].
    pub fn with_gyro_correction(
        mut self,
        c_applied: SVector<T, CM>,
    ) -> Result<Self, CalibrationError> {
        self.set_gyro_correction(c_applied)?;
        Ok(self)
    }

    /// Corrects every following increment with the gyro error `c_applied` before integration:
    /// `θ ← θ* − D(θ*/h) h c_applied` (first order in `c`). May be called at any step boundary,
    /// typically with the latest estimate `ĉ` ("re-linearization"): the computed attitude then
    /// stays close to the truth, so that the first-order model (2.4) stays valid over long
    /// windows. The unknown remains the *total* gyro error `c`: the calibrator integrates the
    /// applied correction, `K(t) = ∫ Bᵀ D c_applied dt`, and the equations become
    /// `U x = z + Γ K` (from `w = w₀ − ½ Θ c + ½ K`).
    ///
    /// # Errors
    /// [`CalibrationError::NonFiniteInput`]; [`CalibrationError::MidStep`] between the two
    /// samples of a step. The calibrator is then unchanged.
    pub fn set_gyro_correction(
        &mut self,
        c_applied: SVector<T, CM>,
    ) -> Result<(), CalibrationError> {
        if !c_applied.iter().all(|v| v.is_finite()) {
            return Err(CalibrationError::NonFiniteInput);
        }
        if self.propagator.mid_step() {
            return Err(CalibrationError::MidStep);
        }
        self.correction = c_applied;
        Ok(())
    }

    /// Takes one float gyro increment `θ` (rad, gyro axes) over the sample interval `h`.
    ///
    /// # Errors
    /// [`CalibrationError::NonFiniteInput`]; [`CalibrationError::InputOutOfRange`] for an
    /// increment above 1 rad or after `2³² − 1` samples. The calibrator is then unchanged.
    pub fn push_increment(&mut self, theta: &Vector3<T>) -> Result<(), CalibrationError> {
        if self.samples == u32::MAX {
            return Err(CalibrationError::InputOutOfRange);
        }
        let h = self.config.sample_interval;
        let corrected = theta - self.model.increment_error_matrix(theta, h) * self.correction;
        if let Some(step) = self.propagator.push(&corrected)? {
            let big_h = h + h;
            let elapsed = real::<T>(f64::from(self.samples) + 1.0) * h;
            // eq. (2.4) integrand at the step's end: Bᵀ = DCM of M, D(ω*) H from the increments
            let d_dt = self.model.increment_error_matrix(&step.increment, big_h);
            let g = self.drift.g(elapsed);
            self.quadratures.step(
                &self.propagator.attitude().to_dcm(),
                &d_dt,
                &g,
                big_h,
                &self.correction,
            );
        }
        // (below u32::MAX: refused above)
        self.samples = self.samples.saturating_add(1);
        Ok(())
    }

    /// Takes one sample of pulse counts (signed, per axis) of weight `σ`, decoded by
    /// [`PulseDecoder`] with the configured centering.
    ///
    /// # Errors
    /// [`CalibrationError::InvalidConfig`] when no pulse weight is configured; the errors of
    /// [`PulseDecoder::decode`] and [`Self::push_increment`]. The calibrator is then unchanged.
    pub fn push_pulses(&mut self, counts: [i32; 3]) -> Result<(), CalibrationError> {
        let mut decoder = self.decoder.ok_or(CalibrationError::InvalidConfig)?;
        let theta = decoder.decode(counts)?;
        self.push_increment(&theta)?;
        self.decoder = Some(decoder);
        Ok(())
    }

    /// The equations of the current epoch for the reference attitude `reference` (frame `J` to
    /// `L`), without accumulating them.
    ///
    /// # Errors
    /// [`CalibrationError::MidStep`] between the two samples of a step;
    /// [`CalibrationError::NonFiniteInput`]; [`CalibrationError::InputOutOfRange`] for a
    /// quaternion far from unit norm or rows beyond [`super::MAX_ROW_ENTRY`].
    pub fn equations(
        &self,
        reference: &Quaternion<T>,
    ) -> Result<EpochOutcome<X, T>, CalibrationError> {
        if self.propagator.mid_step() {
            return Err(CalibrationError::MidStep);
        }
        let n = unit(reference)?;
        let m = self.propagator.attitude();
        // P = N(t) ∘ N̄(t₀) (reference, §2), P* = M(t) ∘ M̄(t₀) (gyro, eq. (2.4))
        let p_star = m * self.m0.conjugate();
        let mut p = n * self.reference0.conjugate();
        // q and −q are the same rotation: take P in the hemisphere of P* (they differ by O(w))
        if p.w * p_star.w + p.x * p_star.x + p.y * p_star.y + p.z * p_star.z < T::zero() {
            p = Quaternion::new(-p.w, -p.x, -p.y, -p.z);
        }
        let p0 = p.w;
        let pv = p.vector();
        if !(p0.abs() >= self.config.min_abs_p0) {
            return Ok(EpochOutcome::Skipped(SkipReason::SmallP0));
        }
        let phi = skew(&pv); // Φ(p): Φ(p) r = p × r
        let two: T = real(2.0);
        let half: T = real(0.5);
        let p0_minus_phi = Matrix3::identity() * p0 - phi; // [p₀E₃ − Φ(p)]
        let gamma = p0_minus_phi * half; // Γ = ½ [p₀E₃ − Φ(p)], eq. (5.7)
                                         // z = p* − p (eq. (2.7) right-hand side), plus Γ K for the gyro correction applied
        let mut rhs = p_star.vector() - pv + gamma * self.quadratures.correction_integral();
        if let Some(dec) = &self.decoder {
            if dec.centering() == ResidualCentering::MeanResidual {
                // eq. (5.5): z' = p' − p + ¼ σ [p₀E₃ − Φ(p)] Bᵀ ρ*
                let rho = Vector3::from_fn(|i, _| real::<T>(f64::from(dec.last_signs()[i])));
                rhs += p0_minus_phi * (m.to_dcm() * rho) * (real::<T>(0.25) * dec.sigma());
            }
        }
        // U_j = [2Φ(p), Γ Θ(t), Γ Ψ(t, t₀)], eq. (5.7); Ψ = Ψ_anchor + ∫G dt
        let psi = self.drift.psi_anchor() + self.quadratures.g_integral();
        let mut rows = SMatrix::<T, 3, X>::zeros();
        rows.fixed_view_mut::<3, 3>(0, 0).copy_from(&(phi * two));
        rows.fixed_view_mut::<3, CM>(0, 3)
            .copy_from(&(gamma * self.quadratures.theta()));
        rows.fixed_view_mut::<3, DN>(0, 3 + CM)
            .copy_from(&(gamma * psi));
        for i in 0..3 {
            check_row(&rows.row(i).transpose(), rhs[i])?;
        }
        Ok(EpochOutcome::Used(EpochEquations { rows, rhs, p0 }))
    }

    /// Forms and accumulates the equations of the current epoch for the reference attitude
    /// `reference` (frame `J` to `L`, unit quaternion), or skips the epoch.
    ///
    /// # Errors
    /// Those of [`Self::equations`]; the calibrator is then unchanged.
    pub fn add_reference(
        &mut self,
        reference: &Quaternion<T>,
    ) -> Result<EpochOutcome<X, T>, CalibrationError> {
        let outcome = self.equations(reference)?;
        match &outcome {
            EpochOutcome::Used(eq) => {
                // the rows passed check_row, so add_row cannot fail: the three go in together
                for i in 0..3 {
                    self.accumulator
                        .add_row(&eq.rows.row(i).transpose(), eq.rhs[i])?;
                }
                // (statistics counters: they saturate rather than wrap)
                self.counters.used = self.counters.used.saturating_add(1);
            }
            EpochOutcome::Skipped(_) => {
                self.counters.skipped_small_p0 = self.counters.skipped_small_p0.saturating_add(1);
            }
        }
        Ok(outcome)
    }

    /// As [`Self::add_reference`] for a reference given as yaw–pitch–roll angles (rad, the
    /// paper's "aircraft" angles φ₁, φ₂, φ₃ of `J` relative to `L`); epochs within the
    /// gimbal-lock margin of pitch ±90° are skipped.
    ///
    /// # Errors
    /// Those of [`Self::equations`].
    pub fn add_reference_euler(
        &mut self,
        angles: &Euler321<T>,
    ) -> Result<EpochOutcome<X, T>, CalibrationError> {
        if !(angles.yaw.is_finite() && angles.pitch.is_finite() && angles.roll.is_finite()) {
            return Err(CalibrationError::NonFiniteInput);
        }
        if self.propagator.mid_step() {
            return Err(CalibrationError::MidStep);
        }
        if angles.pitch.cos() < self.config.gimbal_lock_margin.sin() {
            self.counters.skipped_gimbal_lock = self.counters.skipped_gimbal_lock.saturating_add(1);
            return Ok(EpochOutcome::Skipped(SkipReason::NearGimbalLock));
        }
        self.add_reference(&angles.to_quaternion())
    }

    /// Solves the accumulated equations.
    ///
    /// # Errors
    /// [`CalibrationError::Unobservable`] when the window does not determine every unknown
    /// (numerical rank below `X`), [`CalibrationError::TooFewRows`], and the other errors of
    /// [`LeastSquaresAccumulator::solve`].
    pub fn solve(&self) -> Result<CalibrationEstimate<CM, DN, X, T>, CalibrationError> {
        let () = Self::DIMENSIONS_AGREE;
        let solution = self.accumulator.solve(self.config.rank_tolerance)?;
        Ok(CalibrationEstimate::from_solution(solution))
    }

    /// The attitude at the current step corrected with `estimate` (gyro axes to the inertial
    /// frame `I`, the reference frame at `t₀`): `Λ̂ = (1 + ŵ) ∘ M` with
    /// `ŵ = ŵ₀ − ½ Ψ_anchor d̂ − ½ (Θ(t) ĉ − K(t))` (eq. (2.4); `K` the integral of the gyro
    /// correction already applied, the anchor term refers the attitude back to the reference
    /// frame when the drift model has one).
    ///
    /// `M` is the computed attitude as integrated, also with the centering of eq. (5.5): the
    /// quantization lag of `M` is not the local `−¼ σ Bᵀ(t) ρ*` that (5.5) removes from the
    /// equations but, without sign changes of the rates, the lag `a = −¼ σ Bᵀ(t₁) ρ*` fixed
    /// in `K` at the first sample (the "accumulated non-commutativity" the paper neglects).
    /// The difference leaves in each equation `[p₀E₃ − Φ(p)](E₃ − C(P)) a = −2 Φ(p) a`, exactly
    /// a `w₀` column: ĉ and d̂ are unaffected and `ŵ₀` absorbs `−a`, which cancels the lag of
    /// `M`, so `(1 + ŵ) ∘ M` is the corrected attitude.
    pub fn corrected_attitude(
        &self,
        estimate: &CalibrationEstimate<CM, DN, X, T>,
    ) -> Quaternion<T> {
        let half: T = real(0.5);
        let w = estimate.w0 - self.drift.psi_anchor() * estimate.d * half
            + (self.quadratures.correction_integral() - self.quadratures.theta() * estimate.c)
                * half;
        let q =
            Quaternion::from_rotation_vector(&(w * real::<T>(2.0))) * self.propagator.attitude();
        q.normalize().unwrap_or(q)
    }

    /// The computed (uncorrected) attitude `M` at the last completed step (gyro axes to `K`).
    pub fn attitude(&self) -> Quaternion<T> {
        self.propagator.attitude()
    }

    /// Time since `t₀` (s): samples × `h`.
    pub fn elapsed(&self) -> T {
        real::<T>(f64::from(self.samples)) * self.config.sample_interval
    }

    /// `Θ(t)` of eq. (2.4) at the last completed step (`3 × CM`).
    pub fn theta(&self) -> &SMatrix<T, 3, CM> {
        self.quadratures.theta()
    }

    /// `Ψ(t, t₀) = Ψ_anchor + ∫G dt` at the last completed step (`3 × DN`).
    pub fn psi(&self) -> SMatrix<T, 3, DN> {
        self.drift.psi_anchor() + self.quadratures.g_integral()
    }

    /// The accumulator.
    pub fn accumulator(&self) -> &A {
        &self.accumulator
    }

    /// Consumes the calibrator and returns its accumulator (to carry information to the next
    /// window).
    pub fn into_accumulator(self) -> A {
        self.accumulator
    }

    /// `K(t)`, the integral of the gyro correction applied so far (see
    /// [`Self::set_gyro_correction`]).
    pub fn correction_integral(&self) -> &Vector3<T> {
        self.quadratures.correction_integral()
    }

    /// The gyro correction applied to the increments.
    pub fn gyro_correction(&self) -> &SVector<T, CM> {
        &self.correction
    }

    /// Epoch counters.
    pub fn counters(&self) -> EpochCounters {
        self.counters
    }

    /// The configuration.
    pub fn config(&self) -> &CalibratorConfig<T> {
        &self.config
    }
}

/// A finite quaternion of norm in `[0.9, 1.1]`, normalized.
fn unit<T: Real>(q: &Quaternion<T>) -> Result<Quaternion<T>, CalibrationError> {
    if !q.is_finite() {
        return Err(CalibrationError::NonFiniteInput);
    }
    let n = q.norm();
    if !(n >= real(0.9) && n <= real(1.1)) {
        return Err(CalibrationError::InputOutOfRange);
    }
    // (a norm within 10 % of one normalizes unless it is non-finite, checked by the caller)
    q.normalize().map_err(|_| CalibrationError::InputOutOfRange)
}

/// Errors of the gyro propagation and calibration ([`crate::gyro`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum CalibrationError {
    /// A gyro increment, pulse weight, reference attitude, measurement row or right-hand side
    /// was NaN or infinite.
    #[error("non-finite calibration input")]
    NonFiniteInput,
    /// A finite input is outside the accepted range: a measurement row or right-hand side
    /// element larger than [`crate::gyro::MAX_ROW_ENTRY`] in magnitude (so that the accumulators
    /// can never overflow), a pulse count whose angle exceeds one radian per sample, or a
    /// reference quaternion far from unit norm.
    #[error("calibration input out of range")]
    InputOutOfRange,
    /// A configuration value is invalid: a non-positive sample interval or pulse weight, a
    /// negative threshold, or a rank tolerance outside `(0, 1)`.
    #[error("invalid calibration configuration")]
    InvalidConfig,
    /// A reference attitude arrived between the two samples of a propagation step `H = 2h`: the
    /// computed attitude exists only at step boundaries. Deliver references at even sample
    /// counts.
    #[error("reference epoch between the two samples of a step")]
    MidStep,
    /// Fewer rows were accumulated than there are unknowns (`rows`): no estimate and no
    /// formal standard deviation can be formed.
    #[error("only {rows} rows accumulated")]
    TooFewRows {
        /// Rows accumulated so far.
        rows: u32,
    },
    /// The accumulated system is rank deficient: the window does not determine every unknown
    /// (for example a constant angular rate, which cannot separate scale factors,
    /// misalignments and biases). `rank` is the numerical rank found; retry with a window of
    /// richer motion.
    #[error("calibration window not observable (numerical rank {rank})")]
    Unobservable {
        /// Numerical rank of the accumulated system (less than the number of unknowns).
        rank: u16,
    },
    /// The one-sided Jacobi singular-value iteration did not converge within
    /// [`crate::linalg::SVD_MAX_SWEEPS`] sweeps.
    #[error("Jacobi singular values did not converge")]
    NotConverged,
    /// The normal matrix passed the rank test but has no Cholesky factor: rounding destroyed
    /// its definiteness (normal equations square the condition number).
    #[error("normal matrix lost positive definiteness")]
    NotPositiveDefinite,
}

impl From<LinalgError> for CalibrationError {
    fn from(e: LinalgError) -> Self {
        match e {
            LinalgError::NonFinite => Self::NonFiniteInput,
            LinalgError::NotConverged => Self::NotConverged,
        }
    }
}

impl Error for CalibrationError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFiniteInput => ErrorKind::NonFinite,
            Self::InputOutOfRange | Self::InvalidConfig | Self::MidStep => ErrorKind::InvalidInput,
            Self::TooFewRows { .. } | Self::Unobservable { .. } => ErrorKind::Unobservable,
            Self::NotConverged => ErrorKind::NotConverged,
            Self::NotPositiveDefinite => ErrorKind::NotPositiveDefinite,
        }
    }
}
