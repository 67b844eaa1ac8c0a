//! Gyro-aided fine attitude from carrier-phase single differences: a multiplicative extended
//! Kalman filter whose process model is the gyro itself.
//!
//! # Model
//!
//! The attitude is `C_rb(t) = A M(t)`: `M(t)` is the gyro's propagated attitude (paper 001,
//! eq. (1.1)) from increments corrected by the current bias estimate, `A` (the *anchor*) maps
//! the gyro's computed frame to the reference frame and changes only at updates. The error
//! state, body frame, is
//!
//! ```text
//! x = [δθ (3), δb (3), β (2)]     C_true = Ĉ exp([δθ]×),  b_true = b̂ + δb,  β = (β_B, β_C)
//! ```
//!
//! with `b̂` the gyro bias the caller applies (rad/s) and `β` the line biases of antennas B
//! and C against A (rad, the phase their RF chains add). Between updates (`Δ = M(t₁)ᵀ M(t₂)`,
//! the body rotation the corrected gyro measured over `τ = t₂ − t₁`):
//!
//! ```text
//! δθ₂ = Δᵀ δθ₁ − τ δb + w_θ,   δb₂ = δb₁ + w_b,   β₂ = β₁ + w_β
//! Q_θθ = (σ_ARW² τ + σ_b² τ³/3) I,  Q_θb = −σ_b² τ²/2 I,  Q_bb = σ_b² τ I,  Q_ββ = σ_β² τ I
//! ```
//!
//! (`σ_ARW` the angle random walk, `σ_b` the bias random walk, `σ_β` the line biases' walk).
//! No loop bandwidth is chosen anywhere: the gyro's own noise sets how much the attitude may
//! move between measurements, so the filter weighs the carrier phase against the gyro as the
//! two deserve.
//!
//! # Measurement
//!
//! Per satellite and block (a few milliseconds), the arguments of the summed products
//! `Σ z_P z_A*` of antenna `P ∈ {B, C}` against the reference A (the common carrier phase and
//! the data bit cancel):
//!
//! ```text
//! φ_P = k μᵀ C_rb b_P + β_P   (mod 2π),   k = 2π/λ,   b_P = r_P − r_A (body)
//! ∂φ_P/∂δθ = k (b_P × s)ᵀ,   s = Ĉᵀ μ (body line of sight),   ∂φ_P/∂β_P = 1
//! ```
//!
//! The residual `φ_P − φ̂_P` is wrapped to `(−π, π]`: once the attitude is known to a fraction
//! of a cycle on the longest baseline (the cold start's integer fix), the whole cycles follow
//! from the prediction and no per-satellite integer is kept. The two differences of a
//! satellite share antenna A's noise, so each satellite is one 2-D update with its full 2×2
//! covariance (gated by its NIS, χ² with 2 degrees of freedom).
//!
//! After each update `δθ` is folded into the anchor and `δb` handed back to the caller (who
//! adds it to the bias it applies), and both are reset to zero: the filter runs closed loop.
//!
//! # Cost
//!
//! One 8-state Joseph update per satellite and block, one prediction per block; nothing per
//! millisecond.

use nalgebra::{Matrix2, Matrix3, SMatrix, SVector, Vector2, Vector3};

use crate::ekf::{Ekf, FilterError, GateConfidence, NisGate};
use crate::error::{Error, ErrorKind};
use crate::geometry::{wrap_angle, GeometryError, Quaternion};
use crate::{real, Real};

/// State dimension: attitude error (3), gyro bias error (3), line biases (2).
pub const GYRO_AIDED_STATES: usize = 8;

/// Satellites one update takes.
pub const MAX_BLOCK_SATELLITES: usize = 12;

/// Noise model of the filter.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GyroAidedConfig<T = f32> {
    /// Carrier wavelength, m.
    pub wavelength_m: T,
    /// Angle random walk of the gyro, rad/√s.
    pub angle_random_walk: T,
    /// Random walk of the gyro bias (bias instability), rad/s/√s.
    pub bias_random_walk: T,
    /// Random walk of the line biases (temperature drift), rad/√s.
    pub line_bias_random_walk: T,
    /// Gate of each satellite's 2-D update (χ², 2 degrees of freedom); `None` accepts all.
    pub gate: Option<GateConfidence>,
}

/// One satellite's phase differences over one block.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PhaseDifferenceBlock<T = f32> {
    /// Satellite id (PRN).
    pub id: u8,
    /// Unit line of sight at the block's centre, reference frame.
    pub los: Vector3<T>,
    /// `arg Σ z_P z_A*` of B and C, rad.
    pub phase_rad: Vector2<T>,
    /// Covariance of the two phases, rad².
    pub covariance: Matrix2<T>,
}

/// What one update did.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GyroAidedReport<T = f32> {
    /// Satellites offered.
    pub offered: u8,
    /// Satellites accepted by the gate.
    pub accepted: u8,
    /// Sum of the accepted satellites' NIS (χ² with `2 · accepted` degrees of freedom when
    /// the filter is consistent).
    pub nis_sum: T,
    /// Sum of the rejected satellites' NIS.
    pub rejected_nis_sum: T,
    /// The gyro bias correction the caller must add to the bias it applies, rad/s.
    pub bias_correction: Vector3<T>,
    /// The attitude correction the update applied (body frame, rad).
    pub attitude_correction: Vector3<T>,
    /// Its covariance when the filter is consistent, `P⁻_θθ − P⁺_θθ`, rad². A gyro that
    /// errs beyond its noise model forces corrections far larger than this (the test of
    /// the gyro against the carrier phase).
    pub correction_covariance: Matrix3<T>,
}

/// Error returned by the operations of [`GyroAidedFilter`]; the filter is then unchanged.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum GyroAidedError {
    /// An input (configuration, prior, rotation, phase, covariance, line of sight) was NaN
    /// or infinite.
    #[error("non-finite gyro-aided filter input")]
    NonFinite,
    /// A configuration or prior value is outside its domain (a non-positive wavelength, a
    /// negative noise density, a prior covariance that is not positive definite), or a
    /// baseline is shorter than 1 mm.
    #[error("invalid gyro-aided filter configuration or prior")]
    InvalidConfig,
    /// A line of sight is not a unit vector, or more satellites than
    /// [`MAX_BLOCK_SATELLITES`].
    #[error("unusable phase-difference block")]
    InvalidObservation,
    /// The Kalman filter toolkit refused a step.
    #[error("filter step refused")]
    Filter(#[from] FilterError),
    /// The anchor could not be renormalized.
    #[error("anchor not a rotation")]
    Geometry(#[from] GeometryError),
}

impl Error for GyroAidedError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::InvalidConfig | Self::InvalidObservation => ErrorKind::InvalidInput,
            Self::Filter(e) => e.kind(),
            Self::Geometry(e) => e.kind(),
        }
    }
}

/// Where the filter starts.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GyroAidedPrior<T = f32> {
    /// Attitude `C_rb` at the start.
    pub q_rb: Quaternion<T>,
    /// Covariance of the body-frame rotation-vector error, rad².
    pub attitude_covariance: Matrix3<T>,
    /// Standard deviation of the gyro bias the caller applies, rad/s, per axis.
    pub bias_sigma: T,
    /// Line biases of B and C, rad.
    pub line_bias: Vector2<T>,
    /// Their covariance, rad².
    pub line_bias_covariance: Matrix2<T>,
}

/// The gyro-aided fine attitude filter (module docs).
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GyroAidedFilter<T = f32> {
    config: GyroAidedConfig<T>,
    /// Body baselines `b_B`, `b_C`, m.
    baselines: [Vector3<T>; 2],
    /// `A`: the attitude is `A M(t)`.
    anchor: Quaternion<T>,
    /// `[δθ, δb, β]` and their covariance; `δθ = δb = 0` between updates.
    ekf: Ekf<GYRO_AIDED_STATES, T>,
}

/// Attitude rows of the state.
fn attitude_rows<T: Real>() -> SMatrix<T, 3, GYRO_AIDED_STATES> {
    SMatrix::from_fn(|r, c| if r == c { T::one() } else { T::zero() })
}

impl<T: Real> GyroAidedConfig<T> {
    fn is_valid(&self) -> bool {
        let values = [
            self.wavelength_m,
            self.angle_random_walk,
            self.bias_random_walk,
            self.line_bias_random_walk,
        ];
        values.iter().all(|v| v.is_finite())
            && self.wavelength_m > T::zero()
            && values.iter().skip(1).all(|&v| v >= T::zero())
    }

    /// `Q` of a prediction over `tau` seconds (module docs).
    fn process_noise(&self, tau: T) -> SMatrix<T, GYRO_AIDED_STATES, GYRO_AIDED_STATES> {
        let arw2 = self.angle_random_walk * self.angle_random_walk;
        let b2 = self.bias_random_walk * self.bias_random_walk;
        let beta2 = self.line_bias_random_walk * self.line_bias_random_walk;
        let q_tt = arw2 * tau + b2 * tau * tau * tau / real(3.0);
        let q_tb = -b2 * tau * tau / real(2.0);
        let q_bb = b2 * tau;
        SMatrix::from_fn(|r, c| match (r, c) {
            (r, c) if r < 3 && c < 3 && r == c => q_tt,
            (r, c) if r < 3 && c == r + 3 => q_tb,
            (r, c) if c < 3 && r == c + 3 => q_tb,
            (r, c) if (3..6).contains(&r) && r == c => q_bb,
            (r, c) if r >= 6 && r == c => beta2 * tau,
            _ => T::zero(),
        })
    }
}

impl<T: Real> GyroAidedFilter<T> {
    /// A filter on the body baselines `baselines` (`b_B`, `b_C`, m) started from `prior` at
    /// the epoch where the gyro's attitude is `m`.
    ///
    /// # Errors
    /// [`GyroAidedError::NonFinite`], [`GyroAidedError::InvalidConfig`] (see the variant),
    /// [`GyroAidedError::Geometry`] for a prior attitude that cannot be normalized.
    pub fn new(
        config: GyroAidedConfig<T>,
        baselines: [Vector3<T>; 2],
        prior: &GyroAidedPrior<T>,
        m: &Quaternion<T>,
    ) -> Result<Self, GyroAidedError> {
        let finite = baselines.iter().all(|b| b.iter().all(|v| v.is_finite()))
            && prior.q_rb.is_finite()
            && m.is_finite()
            && prior.attitude_covariance.iter().all(|v| v.is_finite())
            && prior.line_bias.iter().all(|v| v.is_finite())
            && prior.line_bias_covariance.iter().all(|v| v.is_finite())
            && prior.bias_sigma.is_finite();
        if !finite {
            return Err(GyroAidedError::NonFinite);
        }
        let min_baseline: T = real(1e-3);
        if !config.is_valid()
            || !baselines.iter().all(|b| b.norm() >= min_baseline)
            || !(prior.bias_sigma > T::zero())
        {
            return Err(GyroAidedError::InvalidConfig);
        }
        let anchor = (prior.q_rb.normalize()? * m.normalize()?.conjugate()).normalize()?;
        let x = SVector::<T, GYRO_AIDED_STATES>::from_fn(|r, _| match r {
            6 => wrap_angle(prior.line_bias.x),
            7 => wrap_angle(prior.line_bias.y),
            _ => T::zero(),
        });
        let bias_var = prior.bias_sigma * prior.bias_sigma;
        let p = SMatrix::<T, GYRO_AIDED_STATES, GYRO_AIDED_STATES>::from_fn(|r, c| match (r, c) {
            (r, c) if r < 3 && c < 3 => prior.attitude_covariance[(r, c)],
            (r, c) if (3..6).contains(&r) && r == c => bias_var,
            (r, c) if r >= 6 && c >= 6 => prior.line_bias_covariance[(r - 6, c - 6)],
            _ => T::zero(),
        });
        let ekf = Ekf::new(x, p).map_err(|e| match e {
            FilterError::InvalidCovariance => GyroAidedError::InvalidConfig,
            e => GyroAidedError::Filter(e),
        })?;
        Ok(Self {
            config,
            baselines,
            anchor,
            ekf,
        })
    }

    /// The attitude `C_rb = A M` when the gyro's attitude is `m`.
    pub fn attitude(&self, m: &Quaternion<T>) -> Quaternion<T> {
        let q = self.anchor * *m;
        q.normalize().unwrap_or(q)
    }

    /// Covariance of the body-frame attitude error at the filter's last update or
    /// prediction, rad².
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub fn attitude_covariance(&self) -> Matrix3<T> {
        let s = attitude_rows::<T>();
        s * self.ekf.covariance() * s.transpose()
    }

    /// The attitude covariance `τ` seconds after the last update or prediction, for a body
    /// rotation `delta` (`M(t₁)ᵀ M(t₂)`) over that time, without changing the filter (what
    /// a coast on the gyro reports).
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub fn predicted_attitude_covariance(&self, delta: &Quaternion<T>, tau: T) -> Matrix3<T> {
        let (f, q) = self.transition(delta, tau);
        let s = attitude_rows::<T>();
        let p = f * self.ekf.covariance() * f.transpose() + q;
        let c: Matrix3<T> = s * p * s.transpose();
        (c + c.transpose()) * real::<T>(0.5)
    }

    /// Standard deviation of the gyro bias error, rad/s, per axis.
    pub fn bias_sigma(&self) -> Vector3<T> {
        let p = self.ekf.covariance();
        Vector3::new(p[(3, 3)].sqrt(), p[(4, 4)].sqrt(), p[(5, 5)].sqrt())
    }

    /// The line biases of B and C, rad, in `(−π, π]`.
    pub fn line_bias(&self) -> Vector2<T> {
        let x = self.ekf.state();
        Vector2::new(x[6], x[7])
    }

    /// Their covariance, rad².
    pub fn line_bias_covariance(&self) -> Matrix2<T> {
        let p = self.ekf.covariance();
        Matrix2::new(p[(6, 6)], p[(6, 7)], p[(7, 6)], p[(7, 7)])
    }

    /// The full state covariance (`[δθ, δb, β]`).
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub fn covariance(&self) -> &SMatrix<T, GYRO_AIDED_STATES, GYRO_AIDED_STATES> {
        self.ekf.covariance()
    }

    /// `Φ` and `Q` of a prediction over `tau` for the body rotation `delta`.
    fn transition(
        &self,
        delta: &Quaternion<T>,
        tau: T,
    ) -> (
        SMatrix<T, GYRO_AIDED_STATES, GYRO_AIDED_STATES>,
        SMatrix<T, GYRO_AIDED_STATES, GYRO_AIDED_STATES>,
    ) {
        let rt = delta.to_dcm().transpose();
        let f = SMatrix::<T, GYRO_AIDED_STATES, GYRO_AIDED_STATES>::from_fn(|r, c| match (r, c) {
            (r, c) if r < 3 && c < 3 => rt[(r, c)],
            (r, c) if r < 3 && c == r + 3 => -tau,
            (r, c) if r >= 3 && r == c => T::one(),
            _ => T::zero(),
        });
        (f, self.config.process_noise(tau))
    }

    /// Prediction over `tau` seconds (≥ 0) during which the corrected gyro measured the body
    /// rotation `delta = M(t₁)ᵀ M(t₂)`.
    ///
    /// # Errors
    /// [`GyroAidedError::NonFinite`]; [`GyroAidedError::InvalidConfig`] for a negative `tau`;
    /// [`GyroAidedError::Filter`]. The filter is unchanged on error.
    pub fn predict(&mut self, delta: &Quaternion<T>, tau: T) -> Result<(), GyroAidedError> {
        if !delta.is_finite() || !tau.is_finite() {
            return Err(GyroAidedError::NonFinite);
        }
        if tau < T::zero() {
            return Err(GyroAidedError::InvalidConfig);
        }
        let (f, q) = self.transition(delta, tau);
        let x = *self.ekf.state();
        self.ekf.predict_to(&x, &f, &q)?;
        Ok(())
    }

    /// Updates with one block's phase differences, at the epoch where the gyro's attitude is
    /// `m` (the block's centre; predict to it first). Each satellite is one gated 2-D update;
    /// then the attitude error is folded into the anchor and the bias error returned.
    ///
    /// # Errors
    /// [`GyroAidedError::NonFinite`], [`GyroAidedError::InvalidObservation`] (checked for
    /// every satellite before any is used), [`GyroAidedError::Filter`]. The filter is
    /// unchanged on error.
    pub fn update(
        &mut self,
        m: &Quaternion<T>,
        blocks: &[PhaseDifferenceBlock<T>],
    ) -> Result<GyroAidedReport<T>, GyroAidedError> {
        check_blocks(m, blocks)?;
        let c_rb = self.attitude(m).to_dcm();
        let gate = self.config.gate.map(|g| NisGate::chi_square(2, g));
        let mut next = self.clone();
        let prior_attitude = next.attitude_covariance();
        let mut report = GyroAidedReport {
            offered: 0,
            accepted: 0,
            nis_sum: T::zero(),
            rejected_nis_sum: T::zero(),
            bias_correction: Vector3::zeros(),
            attitude_correction: Vector3::zeros(),
            correction_covariance: Matrix3::zeros(),
        };
        for block in blocks {
            let (y, h) = next.linearize(&c_rb, block);
            let r = next.ekf.update(&y, &h, &block.covariance, gate)?;
            report.offered = report.offered.saturating_add(1); // (counts: saturate)
            if r.accepted {
                report.accepted = report.accepted.saturating_add(1);
                report.nis_sum += r.nis;
            } else {
                report.rejected_nis_sum += r.nis;
            }
        }
        let x = next.ekf.state();
        report.attitude_correction = Vector3::new(x[0], x[1], x[2]);
        let c = prior_attitude - next.attitude_covariance();
        report.correction_covariance = (c + c.transpose()) * real::<T>(0.5);
        report.bias_correction = next.fold(m)?;
        *self = next;
        Ok(report)
    }

    /// Innovation and Jacobian of one satellite at the attitude `c_rb` (all linearized at the
    /// same attitude: the updates of one block are one batch).
    fn linearize(
        &self,
        c_rb: &Matrix3<T>,
        block: &PhaseDifferenceBlock<T>,
    ) -> (Vector2<T>, SMatrix<T, 2, GYRO_AIDED_STATES>) {
        let k = T::two_pi() / self.config.wavelength_m;
        let s = c_rb.transpose() * block.los;
        let x = self.ekf.state();
        let beta = [x[6], x[7]];
        let mut y = Vector2::zeros();
        let mut h = SMatrix::<T, 2, GYRO_AIDED_STATES>::zeros();
        for (p, b) in self.baselines.iter().enumerate() {
            // φ̂ = k sᵀ b + β (+ δθ·k (b × s), δθ = x[0..3]: zero between updates, but the
            // earlier satellites of this block have moved it)
            let grad = b.cross(&s) * k;
            let dtheta = Vector3::new(x[0], x[1], x[2]);
            let predicted = s.dot(b) * k + beta[p] + grad.dot(&dtheta);
            y[p] = wrap_angle(block.phase_rad[p] - predicted);
            for c in 0..3 {
                h[(p, c)] = grad[c];
            }
            h[(p, 6 + p)] = T::one();
        }
        (y, h)
    }

    /// Folds `δθ` into the anchor, wraps the line biases, zeroes `δθ` and `δb`; returns `δb`.
    fn fold(&mut self, m: &Quaternion<T>) -> Result<Vector3<T>, GyroAidedError> {
        let x = *self.ekf.state();
        let dtheta = Vector3::new(x[0], x[1], x[2]);
        let db = Vector3::new(x[3], x[4], x[5]);
        // C_new = Ĉ exp([δθ]×) = A M exp([δθ]×)  ⇒  A_new = A M exp([δθ]×) Mᵀ
        let q = self.anchor * *m * Quaternion::from_rotation_vector(&dtheta) * m.conjugate();
        self.anchor = q.normalize()?;
        let reset = SVector::<T, GYRO_AIDED_STATES>::from_fn(|r, _| match r {
            6 => wrap_angle(x[6]),
            7 => wrap_angle(x[7]),
            _ => T::zero(),
        });
        self.ekf.set_state(reset)?;
        Ok(db)
    }
}

/// Checks every block before any is used.
fn check_blocks<T: Real>(
    m: &Quaternion<T>,
    blocks: &[PhaseDifferenceBlock<T>],
) -> Result<(), GyroAidedError> {
    if !m.is_finite() {
        return Err(GyroAidedError::NonFinite);
    }
    if blocks.len() > MAX_BLOCK_SATELLITES {
        return Err(GyroAidedError::InvalidObservation);
    }
    let unit_tolerance: T = real(1e-3);
    for b in blocks {
        let finite = b.los.iter().all(|v| v.is_finite())
            && b.phase_rad.iter().all(|v| v.is_finite())
            && b.covariance.iter().all(|v| v.is_finite());
        if !finite {
            return Err(GyroAidedError::NonFinite);
        }
        let positive = b.covariance[(0, 0)] > T::zero()
            && b.covariance[(1, 1)] > T::zero()
            && b.covariance[(0, 0)] * b.covariance[(1, 1)]
                > b.covariance[(0, 1)] * b.covariance[(1, 0)];
        if !((b.los.norm() - T::one()).abs() <= unit_tolerance) || !positive {
            return Err(GyroAidedError::InvalidObservation);
        }
    }
    Ok(())
}
