//! The gyro inside the receiver: propagation of the computed attitude `M(t)` (paper 001, eq.
//! (1.1), two-sample coning update), extrapolated between propagation steps with the last
//! step's rate, and the sequential least-squares calibration of the gyro biases against the
//! fine GNSS attitude (paper 001 with `D = E₃` and no reference drift), whose estimate corrects
//! every later increment.
//!
//! `M` maps gyro (body) axes to the computed inertial frame `K`; with a perfect gyro `K` is
//! fixed, so the fine filter works in the frame `F(t) = C_rK₀ M(t)`, in which the body's
//! attitude is constant up to the gyro's errors (see the `fine` stage).

use nalgebra::{SMatrix, SVector, Vector3};

use crate::geometry::Quaternion;
use crate::gyro::CalibrationError;
use crate::gyro::{
    AttitudePropagator, BiasOnly, CalibratorConfig, EpochOutcome, GyroCalibrator,
    LeastSquaresAccumulator, PulseDecoder, ReferenceDriftModel, ResidualCentering, SqrtInformation,
};
use crate::receiver::ReceiverError;
use crate::Real;

use super::config::GyroConfig;

/// The reference (GNSS attitude) does not drift: no drift unknowns (`n = 0`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NoReferenceDrift;

impl<T: Real> ReferenceDriftModel<T, 0> for NoReferenceDrift {
    fn g(&self, _elapsed: T) -> SMatrix<T, 3, 0> {
        SMatrix::zeros()
    }
}

/// Weight of the prior rows `w₀ = 0` relative to one calibration equation: `w₀` is taken as
/// twice as uncertain as one equation's noise (the reference's error at a single epoch).
const W0_PRIOR_WEIGHT: f32 = 0.5;

/// The calibrator the receiver runs: `x = [w₀; c₇..₉]`, 6 unknowns, Givens accumulator.
pub type BiasCalibrator =
    GyroCalibrator<BiasOnly, NoReferenceDrift, SqrtInformation<6>, 3, 0, 6, f32>;

/// Longest extrapolation of `M` beyond the last propagation step, s.
pub(crate) const MAX_EXTRAPOLATION_S: f32 = 1.0;

/// Largest increment (rad, any axis) a sample may hold: beyond, it is refused as an input
/// error (below, above the maximum rate, it is a gyro fault).
const MAX_INCREMENT_RAD: f32 = 1.0;

/// The receiver's gyro.
#[derive(Clone, Debug)]
pub(crate) struct GyroFrame {
    pub config: GyroConfig,
    propagator: AttitudePropagator<f32>,
    decoder: Option<PulseDecoder<f32>>,
    /// Increments received.
    samples: u64,
    /// Rate of the last completed step (corrected), rad/s, gyro axes.
    rate: Vector3<f32>,
    /// Bias correction applied to the increments, rad/s.
    pub bias: Vector3<f32>,
    calibrator: Option<BiasCalibrator>,
    /// Samples at the start of the calibration window.
    window_start: u64,
    /// The sample interval in whole nanoseconds (the 1 ms path's integer clock).
    interval_ns: u64,
    /// Calibrations applied.
    pub calibrations: u32,
    /// What the calibration windows gave.
    pub report: CalibrationReport,
}

/// What the gyro calibration windows have given so far (statistics counters: they saturate at
/// `u32::MAX` rather than wrap).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CalibrationReport {
    /// Windows started.
    pub started: u32,
    /// Windows solved.
    pub solved: u32,
    /// Windows whose estimate was determined well enough to count (σ below the configured
    /// limit); the estimate is reported and compared, the fine filter applies its own.
    pub applied: u32,
    /// Windows abandoned (a reference or an increment the calibrator refused, or a solve
    /// that failed: rank deficient, not converged).
    pub failed: u32,
    /// The last estimate of the biases, rad/s (gyro axes).
    pub last_bias: [f32; 3],
    /// Its formal standard deviations, rad/s.
    pub last_sigma: [f32; 3],
}

impl GyroFrame {
    pub fn new(config: GyroConfig) -> Result<Self, CalibrationError> {
        let decoder = match config.pulse_weight_rad {
            Some(s) => Some(PulseDecoder::new(
                s,
                ResidualCentering::IncrementCorrection,
            )?),
            None => None,
        };
        Ok(Self {
            config,
            propagator: AttitudePropagator::new(Quaternion::identity())?,
            decoder,
            samples: 0,
            rate: Vector3::zeros(),
            bias: Vector3::zeros(),
            calibrator: None,
            window_start: 0,
            interval_ns: nanoseconds(config.sample_interval_s),
            calibrations: 0,
            report: CalibrationReport::default(),
        })
    }

    /// Time of the last increment's end, s since the receiver started.
    pub fn time_s(&self) -> f64 {
        self.samples as f64 * seconds(self.config.sample_interval_s)
    }

    /// Time of the last increment's end, ns since the receiver started (integer: no soft
    /// float in the 1 ms path).
    pub fn time_ns(&self) -> u128 {
        u128::from(self.samples) * u128::from(self.interval_ns)
    }

    /// Re-anchors the gyro's clock at `t` seconds (after an epoch jump: the samples in between
    /// never came) with `M` restarted at the identity; the bias and calibration report stay.
    pub fn resync(&mut self, t: f64) {
        let h = seconds(self.config.sample_interval_s);
        let samples = if h > 0.0 { libm::floor(t / h) } else { 0.0 };
        // an even count: the propagator starts on a step boundary
        let samples = (samples.max(0.0) as u64) & !1;
        self.samples = samples;
        self.window_start = samples;
        self.propagator =
            AttitudePropagator::new(Quaternion::identity()).unwrap_or(self.propagator);
        self.rate = Vector3::zeros();
        self.calibrator = None;
    }

    /// The corrected rate of the last propagation step, rad/s, gyro axes (an implausible
    /// sample repeats the last good one).
    pub fn rate(&self) -> Vector3<f32> {
        self.rate
    }

    /// Increments received.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// True when the last increment completed a propagation step.
    pub fn at_step(&self) -> bool {
        self.samples > 0 && !self.propagator.mid_step()
    }

    /// Decodes pulse counts into an increment (rad, gyro axes).
    pub fn decode(&mut self, counts: [i32; 3]) -> Result<Vector3<f32>, ReceiverError> {
        let mut d = self
            .decoder
            .ok_or(ReceiverError::Gyro(CalibrationError::InvalidConfig))?;
        let theta = d.decode(counts).map_err(map_calibration)?;
        self.decoder = Some(d);
        Ok(theta)
    }

    /// Takes one increment (rad, gyro axes): corrected by the bias estimate, propagated, and
    /// passed (uncorrected; the calibrator applies the correction itself) to the calibrator.
    /// An increment above the maximum rate is a fault: the last good rate is propagated
    /// instead, the calibration window is abandoned, and `false` is returned. Unchanged on
    /// error (every refusal comes before the first change).
    pub fn push(&mut self, theta: &Vector3<f32>) -> Result<bool, ReceiverError> {
        if !theta.iter().all(|v| v.is_finite()) {
            return Err(ReceiverError::NonFinite);
        }
        if theta.amax() > MAX_INCREMENT_RAD {
            return Err(ReceiverError::Gyro(CalibrationError::InputOutOfRange));
        }
        let h = self.config.sample_interval_s;
        let plausible = theta.amax() <= self.config.max_rate_rad_s * h;
        let corrected = if plausible {
            theta - self.bias * h
        } else {
            self.rate * h
        };
        let mut propagator = self.propagator;
        let step = propagator.push(&corrected).map_err(map_calibration)?;
        let mut calibrator = self.calibrator.clone();
        if let Some(c) = calibrator.as_mut() {
            if !plausible || c.push_increment(theta).is_err() {
                calibrator = None;
                self.report.failed = self.report.failed.saturating_add(1);
            }
        }
        self.propagator = propagator;
        self.calibrator = calibrator;
        if let Some(s) = step {
            self.rate = s.rotation_vector / (2.0 * h);
        }
        self.samples = self.samples.saturating_add(1);
        Ok(plausible)
    }

    /// `M(t)` at `t` seconds: the last step's attitude extrapolated with its rate (for at
    /// most [`MAX_EXTRAPOLATION_S`] either way: a gyro that stopped delivering is excluded by
    /// the receiver, not extrapolated).
    pub fn attitude_at(&self, t: f64) -> Quaternion<f32> {
        let h = seconds(self.config.sample_interval_s);
        // the propagator holds M at the last completed step
        let step_samples = self.samples & !1; // (the last even count)
        let t_step = step_samples as f64 * h;
        let dt = ((t - t_step) as f32).clamp(-MAX_EXTRAPOLATION_S, MAX_EXTRAPOLATION_S);
        let m = self.propagator.attitude() * Quaternion::from_rotation_vector(&(self.rate * dt));
        m.normalize().unwrap_or(m)
    }

    /// Starts a calibration window at the current step with the reference attitude `q_rb`.
    pub fn start_calibration(&mut self, q_rb: &Quaternion<f32>) {
        if !self.at_step() {
            return;
        }
        let cfg = CalibratorConfig::new(self.config.sample_interval_s);
        // A prior on w₀: the window starts at the reference itself (M(t₀) = N(t₀)), so w₀ is
        // the reference's own error, about the noise of one equation. Without it the
        // component of w₀ along a steady spin axis is unobservable (Φ(p) w₀ = p × w₀ = 0)
        // and every solve of a slowly spinning body is rank deficient.
        let mut prior = SqrtInformation::new();
        for i in 0..3 {
            let mut row = SVector::<f32, 6>::zeros();
            if let Some(r) = row.get_mut(i) {
                *r = W0_PRIOR_WEIGHT;
            }
            let _ = prior.add_row(&row, 0.0);
        }
        let c = BiasCalibrator::new(
            cfg,
            BiasOnly,
            NoReferenceDrift,
            prior,
            // the calibrator integrates from the reference itself: both attitudes must be
            // relative to the same (inertial) frame, which the receiver's own `M` is not
            *q_rb,
            *q_rb,
        )
        .and_then(|c| c.with_gyro_correction(self.bias));
        match c {
            Ok(c) => {
                self.calibrator = Some(c);
                self.report.started = self.report.started.saturating_add(1);
            }
            Err(_) => {
                self.calibrator = None;
                self.report.failed = self.report.failed.saturating_add(1);
            }
        }
        self.window_start = self.samples;
    }

    /// Whether a calibration window is open.
    pub fn calibrating(&self) -> bool {
        self.calibrator.is_some()
    }

    /// Adds the reference attitude `q_rb` at the current step; at the end of the window solves
    /// and, when the estimate is well determined, applies it. Returns true when a calibration
    /// was applied.
    pub fn add_reference(&mut self, q_rb: &Quaternion<f32>) -> bool {
        let Some(mut c) = self.calibrator.clone() else {
            return false;
        };
        match c.add_reference(q_rb) {
            Ok(EpochOutcome::Used(_)) | Ok(EpochOutcome::Skipped(_)) => {}
            Err(_) => {
                self.calibrator = None;
                self.report.failed = self.report.failed.saturating_add(1);
                return false;
            }
        }
        let elapsed =
            self.samples.saturating_sub(self.window_start) as f32 * self.config.sample_interval_s;
        if elapsed < self.config.calibration_window_s {
            self.calibrator = Some(c);
            return false;
        }
        let applied = match c.solve() {
            Ok(est) => {
                self.report.solved = self.report.solved.saturating_add(1);
                self.report.last_bias = [est.c.x, est.c.y, est.c.z];
                self.report.last_sigma = [est.c_std.x, est.c_std.y, est.c_std.z];
                let usable = est.c.iter().all(|v| v.is_finite())
                    && est
                        .c_std
                        .iter()
                        .all(|&s| s <= self.config.calibration_max_sigma);
                if usable {
                    // reported (the fine filter estimates the bias it applies itself)
                    self.calibrations = self.calibrations.saturating_add(1);
                    self.report.applied = self.report.applied.saturating_add(1);
                }
                usable
            }
            Err(_) => {
                self.report.failed = self.report.failed.saturating_add(1);
                false
            }
        };
        // next window, from the current reference
        self.calibrator = None;
        self.start_calibration(q_rb);
        applied
    }
}

/// A time step given in `f32` seconds as the `f64` it stands for (rounded to the nanosecond:
/// `0.01f32` is 0.009 999 999 776 s, whose error would add up to milliseconds over hours).
pub(crate) fn seconds(step: f32) -> f64 {
    libm::round(f64::from(step) * 1e9) * 1e-9
}

/// A time step given in `f32` seconds in whole nanoseconds, as [`seconds`] rounds it (0 for a
/// negative or non-finite step).
pub(crate) fn nanoseconds(step: f32) -> u64 {
    // (`as` saturates: NaN and negatives to 0)
    libm::round(f64::from(step) * 1e9) as u64
}

fn map_calibration(e: CalibrationError) -> ReceiverError {
    match e {
        CalibrationError::NonFiniteInput => ReceiverError::NonFinite,
        e => ReceiverError::Gyro(e),
    }
}
