//! The receiver's configuration: the antenna array and its calibration, the epoch and window
//! lengths, and the settings of every stage.

use nalgebra::Vector3;

use crate::attitude::ambiguity::AmbiguityConfig;
use crate::attitude::ambiguity::AmbiguityError;
use crate::attitude::array::ArrayError;
use crate::attitude::one_stage::OneStageError;
use crate::attitude::one_stage::{FilterMode, OneStageConfig};
use crate::attitude::snapshot::SnapshotError;
use crate::error::{Error, ErrorKind};
use crate::gyro::CalibrationError;
use crate::tracking::{AcquisitionError, TrackingError};

/// The gyro the receiver propagates with and calibrates.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GyroConfig {
    /// Sample interval `h` of the increments, s. The window
    /// ([`ReceiverConfig::window_epochs`] × [`ReceiverConfig::epoch_s`]) must be a whole number
    /// of propagation steps `2h`.
    pub sample_interval_s: f32,
    /// Pulse weight σ (rad) when the gyro delivers pulse counts, `None` for float increments.
    pub pulse_weight_rad: Option<f32>,
    /// Angle random walk, rad/√s: grows the covariance while the receiver coasts on the gyro.
    pub angle_random_walk: f32,
    /// Rate error left after calibration (1σ, rad/s): grows the coasting covariance
    /// quadratically.
    pub residual_rate_sigma: f32,
    /// Length of one calibration window, s: the paper-001 calibrator estimates the biases over
    /// it against the fine attitude and the estimate corrects the following increments.
    pub calibration_window_s: f32,
    /// Largest formal standard deviation (rad/s) of a calibration window's bias estimate
    /// that counts as a calibration (reported; the fine filter estimates the bias itself).
    pub calibration_max_sigma: f32,
    /// Random walk of the gyro bias (bias instability), rad/s/√s: the fine filter's bias
    /// states follow it.
    pub bias_random_walk: f32,
    /// Standard deviation of the turn-on bias, rad/s, per axis: the fine filter's first
    /// uncertainty of the bias.
    pub turn_on_bias_sigma: f32,
    /// Largest plausible body rate, rad/s: a sample above it is a gyro fault, not motion (it
    /// is not propagated, and repeated faults exclude the gyro).
    pub max_rate_rad_s: f32,
}

impl GyroConfig {
    /// A MEMS gyro sampled every `sample_interval_s`: ARW 0.3 °/√h, a bias walking 5e-6
    /// rad/s/√s (about 1 °/h in a minute) from a turn-on bias of 100 °/h (1σ), 20 °/h residual
    /// after calibration, 60 s calibration windows, estimates counted when their σ is below
    /// 10 °/h, body rates up to 1 rad/s.
    pub fn mems(sample_interval_s: f32, pulse_weight_rad: Option<f32>) -> Self {
        let deg_h = core::f32::consts::PI / 180.0 / 3600.0;
        Self {
            sample_interval_s,
            pulse_weight_rad,
            angle_random_walk: 0.3 * core::f32::consts::PI / 180.0 / 60.0,
            residual_rate_sigma: 20.0 * deg_h,
            calibration_window_s: 60.0,
            calibration_max_sigma: 10.0 * deg_h,
            bias_random_walk: 5e-6,
            turn_on_bias_sigma: 100.0 * deg_h,
            max_rate_rad_s: 1.0,
        }
    }
}

/// A bench calibration of the line biases.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LineBiasCalibration {
    /// Line biases of B and C relative to A, rad.
    pub rad: [f32; 2],
    /// Its standard deviation (both), rad.
    pub sigma_rad: f32,
}

/// Settings of the receiver.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ReceiverConfig {
    /// Phase centres of antennas A (the reference antenna, correlator input 0), B and C in
    /// body axes, metres.
    pub antennas_m: [[f32; 3]; 3],
    /// A bench calibration of the line biases of B and C relative to A (cables, RF channels),
    /// if there is one: the cold start then starts from it. `None` (the default): unknown at
    /// switch-on, resolved by the cold start together with the integers and estimated in
    /// flight by the fine filter.
    pub line_bias: Option<LineBiasCalibration>,
    /// Random walk of the line biases (temperature drift), rad/√s.
    pub line_bias_random_walk: f32,
    /// Coherent integration per epoch `T`, s (1 ms for GPS C/A): the fine filter's step.
    pub epoch_s: f32,
    /// Epochs per carrier-phase window: single differences are averaged over a window for the
    /// cold start, the snapshot monitor, the baselines and velocity differences of the
    /// rigid-body filter, and the references of the gyro calibration.
    pub window_epochs: u32,
    /// Epochs per fine-filter block: with a gyro the fine filter updates once per block with
    /// the block's summed single differences.
    pub block_epochs: u32,
    /// Windows between two snapshot (monitor) solutions.
    pub snapshot_windows: u32,
    /// Windows between two integrity checks: a fresh integer fix (independent of the fine
    /// attitude) compared with the fine attitude.
    pub integrity_windows: u32,
    /// The fine filter without a gyro (or with the gyro excluded): paper 003's one-stage
    /// loop on three angles with rates and the two line biases, Gaussian approximation.
    pub fine: OneStageConfig<f32>,
    /// The cold-start ambiguity resolver. Its `phase_sigma_m` is the reference noise of one
    /// single difference (each satellite is weighed by its own C/N0 relative to it); its
    /// `code_sigma_m` must be at least the longest baseline: the slaved antennas have no code
    /// measurement of their own, so the code single differences are zero and the known
    /// baseline lengths and angle fix the integers.
    pub ambiguity: AmbiguityConfig<f32>,
    /// Satellites needed for the cold start.
    pub min_cold_start_satellites: u8,
    /// Satellites needed for a fine-filter update (fewer: the filter only predicts).
    pub min_fine_satellites: u8,
    /// Prior standard deviation of the fine filter's angular rates, rad/s: the gyro's rate
    /// errors when it runs in the gyro frame, the body's rates without a gyro.
    pub prior_rate_sigma: f32,
    /// A fixed single difference whose residual against the fine attitude exceeds this (cycles)
    /// is a cycle slip; the slip is repaired by the nearest integer.
    pub slip_threshold_cycles: f32,
    /// Largest angle (rad) of the fine filter's estimate relative to its gyro-propagated frame
    /// before the frame is re-anchored (the filter is then re-initialized around zero).
    pub reanchor_angle_rad: f32,
    /// An antenna whose mean signal power over a window falls below this fraction of the
    /// reference antenna's is declared blocked (and restored above twice it).
    pub blocked_power_ratio: f32,
    /// Standard deviation of one baseline component (m) the rigid-body filter assumes.
    pub baseline_sigma_m: f32,
    /// Standard deviation of one velocity-difference component (m/s) the rigid-body filter
    /// assumes.
    pub velocity_sigma_m_s: f32,
    /// Longest coast on the gyro (s) after the fine filter lost its input before the attitude
    /// is declared lost: the receiver then drops its fixes and starts cold.
    pub max_coast_s: f32,
    /// Longest gap (s) without fine updates and without a gyro before the attitude is
    /// declared lost.
    pub max_gap_without_gyro_s: f32,
    /// Largest attitude standard deviation (rad, per axis) from which the fine filter may
    /// resume after a coast: beyond it the single differences can no longer be predicted to
    /// a fraction of a cycle, and the receiver starts cold.
    pub max_resume_sigma_rad: f32,
    /// The gyro, if one is fitted.
    pub gyro: Option<GyroConfig>,
}

impl ReceiverConfig {
    /// GPS L1 C/A with 1 ms epochs, 20 ms fine blocks, 100 ms windows, a snapshot check every
    /// window and a fresh-fix integrity check every second, unknown line biases, a 1 Hz loop when there is no gyro,
    /// 0.6 mm single differences at the resolver's reference, a ratio test of 3, and the given
    /// antennas and gyro.
    pub fn gps_l1(antennas_m: [[f32; 3]; 3], gyro: Option<GyroConfig>) -> Self {
        let longest = longest_baseline(&antennas_m);
        let mut ambiguity = AmbiguityConfig::gps_l1(6e-4, longest.max(0.1) * 1.2);
        ambiguity.ratio_threshold = 3.0;
        let mut fine = OneStageConfig::gps_l1(FilterMode::GaussianApproximation, 1.0);
        fine.line_bias_states = true;
        Self {
            antennas_m,
            line_bias: None,
            // a few degrees per hour of drift is ~1e-5 rad/s; a walk of 2e-4 rad/√s covers it
            line_bias_random_walk: 2e-4,
            epoch_s: 1e-3,
            window_epochs: 100,
            block_epochs: 20,
            snapshot_windows: 1,
            integrity_windows: 10,
            fine,
            ambiguity,
            min_cold_start_satellites: 5,
            min_fine_satellites: 2,
            // in the gyro frame the rates are the gyro's errors; without a gyro, the body's
            prior_rate_sigma: if gyro.is_some() { 2e-3 } else { 0.05 },
            slip_threshold_cycles: 0.3,
            reanchor_angle_rad: 0.2,
            blocked_power_ratio: 0.2,
            baseline_sigma_m: 1.5e-3,
            velocity_sigma_m_s: 0.02,
            max_coast_s: 120.0,
            max_gap_without_gyro_s: 2.0,
            max_resume_sigma_rad: 0.02,
            gyro,
        }
    }

    /// The antennas as vectors (body axes, m).
    pub fn antenna_positions(&self) -> [Vector3<f32>; 3] {
        self.antennas_m.map(Vector3::from)
    }

    /// The carrier wavelength the fine filter and the resolver use, m.
    pub fn wavelength_m(&self) -> f32 {
        self.fine.wavelength_m
    }

    /// Window length, s.
    pub fn window_s(&self) -> f32 {
        self.window_epochs as f32 * self.epoch_s
    }

    /// Checks every value the receiver itself uses (the stages check their own when the
    /// receiver builds them): finite, and inside the range that keeps the arithmetic finite.
    pub(crate) fn validate(&self) -> Result<(), ConfigError> {
        for (i, p) in self.antennas_m.iter().enumerate() {
            for &v in p {
                in_range(
                    ANTENNA_FIELDS.get(i).copied().unwrap_or("antennas_m"),
                    v,
                    -100.0,
                    100.0,
                )?;
            }
        }
        if let Some(c) = &self.line_bias {
            for &b in &c.rad {
                in_range("line_bias.rad", b, -1e3, 1e3)?;
            }
            in_range("line_bias.sigma_rad", c.sigma_rad, 1e-6, 10.0)?;
        }
        in_range(
            "line_bias_random_walk",
            self.line_bias_random_walk,
            0.0,
            1.0,
        )?;
        in_range("epoch_s", self.epoch_s, 1e-4, 0.1)?;
        in_range("prior_rate_sigma", self.prior_rate_sigma, 1e-9, 10.0)?;
        in_range(
            "slip_threshold_cycles",
            self.slip_threshold_cycles,
            0.01,
            0.49,
        )?;
        in_range("reanchor_angle_rad", self.reanchor_angle_rad, 1e-3, 1.0)?;
        in_range("blocked_power_ratio", self.blocked_power_ratio, 1e-3, 0.49)?;
        in_range("baseline_sigma_m", self.baseline_sigma_m, 1e-6, 1.0)?;
        in_range("velocity_sigma_m_s", self.velocity_sigma_m_s, 1e-6, 10.0)?;
        in_range("max_coast_s", self.max_coast_s, 1e-3, 86_400.0)?;
        in_range(
            "max_gap_without_gyro_s",
            self.max_gap_without_gyro_s,
            1e-3,
            3_600.0,
        )?;
        in_range("max_resume_sigma_rad", self.max_resume_sigma_rad, 1e-5, 0.5)?;
        whole(
            "window_epochs",
            self.window_epochs >= 10 && self.window_epochs <= 10_000,
        )?;
        whole(
            "snapshot_windows",
            (1..=10_000).contains(&self.snapshot_windows),
        )?;
        whole(
            "min_cold_start_satellites",
            self.min_cold_start_satellites >= 4,
        )?;
        whole("min_fine_satellites", self.min_fine_satellites >= 1)?;
        whole(
            "fine.epoch_s",
            (self.fine.epoch_s - self.epoch_s).abs() <= 1e-6 * self.epoch_s,
        )?;
        if let Some(g) = &self.gyro {
            g.validate(self.window_s())?;
        }
        Ok(())
    }
}

impl GyroConfig {
    /// Checks the gyro's values, and that a window of `window_s` seconds ends on a
    /// propagation step `2h`.
    pub(crate) fn validate(&self, window_s: f32) -> Result<(), ConfigError> {
        in_range("gyro.sample_interval_s", self.sample_interval_s, 1e-6, 1.0)?;
        if let Some(w) = self.pulse_weight_rad {
            in_range("gyro.pulse_weight_rad", w, 1e-12, 0.1)?;
        }
        in_range("gyro.angle_random_walk", self.angle_random_walk, 0.0, 0.1)?;
        in_range(
            "gyro.residual_rate_sigma",
            self.residual_rate_sigma,
            0.0,
            1.0,
        )?;
        in_range(
            "gyro.calibration_window_s",
            self.calibration_window_s,
            1.0,
            86_400.0,
        )?;
        in_range(
            "gyro.calibration_max_sigma",
            self.calibration_max_sigma,
            1e-9,
            1.0,
        )?;
        let steps = window_s / (2.0 * self.sample_interval_s);
        whole(
            "window_epochs",
            (steps - libm::roundf(steps)).abs() < 1e-3 && steps >= 1.0,
        )
    }
}

const ANTENNA_FIELDS: [&str; 3] = ["antennas_m[0]", "antennas_m[1]", "antennas_m[2]"];

/// `Ok` when `value` is finite and in `[min, max]`, else the error naming `field`.
fn in_range(field: &'static str, value: f32, min: f32, max: f32) -> Result<(), ConfigError> {
    if !value.is_finite() {
        return Err(ConfigError::NonFinite { field });
    }
    if !(value >= min && value <= max) {
        return Err(ConfigError::OutOfRange { field });
    }
    Ok(())
}

/// `Ok` when a condition on a count (or a relation between fields) holds.
fn whole(field: &'static str, ok: bool) -> Result<(), ConfigError> {
    if ok {
        Ok(())
    } else {
        Err(ConfigError::OutOfRange { field })
    }
}

/// Error returned by [`AttitudeReceiver::new`](super::AttitudeReceiver::new) and
/// [`SampleReceiver::new`](super::SampleReceiver::new) for a configuration they refuse: the
/// field at fault, or the stage that refused its part and why.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ConfigError {
    /// The field is NaN or infinite.
    #[error("`{field}` is not finite")]
    NonFinite {
        /// The field's name in [`ReceiverConfig`] (`gyro.` for [`GyroConfig`] fields).
        field: &'static str,
    },
    /// The field is outside its physical range (see the field's documentation), or a count
    /// or relation between fields does not hold (a window that is not a whole number of gyro
    /// steps, an epoch that differs from the fine filter's).
    #[error("`{field}` is out of range")]
    OutOfRange {
        /// The field's name in [`ReceiverConfig`] (`gyro.` for [`GyroConfig`] fields).
        field: &'static str,
    },
    /// The antenna array is degenerate.
    #[error("antenna array refused")]
    Array(#[from] ArrayError),
    /// The snapshot solver refused the baselines.
    #[error("snapshot solver refused the baselines")]
    Baselines(#[from] SnapshotError),
    /// The ambiguity resolver refused its configuration.
    #[error("ambiguity resolver refused its configuration")]
    Ambiguity(#[from] AmbiguityError),
    /// The fine (one-stage) filter refused its configuration.
    #[error("fine filter refused its configuration")]
    Fine(#[from] OneStageError),
    /// The gyro propagation refused its configuration.
    #[error("gyro refused its configuration")]
    Gyro(#[from] CalibrationError),
    /// The acquisition engine refused its configuration.
    #[error("acquisition engine refused its configuration")]
    Acquisition(#[from] AcquisitionError),
    /// The observation adapter or the epoch clock refused its configuration.
    #[error("observation adapter refused its configuration")]
    Adapter(#[source] OneStageError),
    /// The tracking channels refused their configuration.
    #[error("tracking channel refused its configuration")]
    Tracking(#[from] TrackingError),
}

impl Error for ConfigError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite { .. } => ErrorKind::NonFinite,
            Self::OutOfRange { .. } => ErrorKind::InvalidInput,
            Self::Array(e) => e.kind(),
            Self::Baselines(e) => e.kind(),
            Self::Ambiguity(e) => e.kind(),
            Self::Fine(e) => e.kind(),
            Self::Gyro(e) => e.kind(),
            Self::Acquisition(e) => e.kind(),
            Self::Adapter(e) => e.kind(),
            Self::Tracking(e) => e.kind(),
        }
    }
}

fn longest_baseline(antennas: &[[f32; 3]; 3]) -> f32 {
    let p = antennas.map(Vector3::from);
    let [a, b, c] = p;
    (b - a).norm().max((c - a).norm()).max((c - b).norm())
}
