//! The receiver's configuration: the antenna array and its calibration, the epoch and window
//! lengths, and the settings of every stage.

use nalgebra::Vector3;

use crate::attitude::ambiguity::AmbiguityConfig;
use crate::attitude::one_stage::{FilterMode, OneStageConfig};
use crate::ReceiverError;

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
    /// Largest formal standard deviation (rad/s) of a bias estimate that is applied.
    pub calibration_max_sigma: f32,
}

impl GyroConfig {
    /// A MEMS gyro sampled every `sample_interval_s`: ARW 0.3 °/√h, 20 °/h residual after
    /// calibration, 60 s calibration windows, estimates applied when their σ is below 10 °/h.
    pub fn mems(sample_interval_s: f32, pulse_weight_rad: Option<f32>) -> Self {
        let deg_h = core::f32::consts::PI / 180.0 / 3600.0;
        Self {
            sample_interval_s,
            pulse_weight_rad,
            angle_random_walk: 0.3 * core::f32::consts::PI / 180.0 / 60.0,
            residual_rate_sigma: 20.0 * deg_h,
            calibration_window_s: 60.0,
            calibration_max_sigma: 10.0 * deg_h,
        }
    }
}

/// Settings of the receiver.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ReceiverConfig {
    /// Phase centres of antennas A (the reference antenna, correlator input 0), B and C in
    /// body axes, metres.
    pub antennas_m: [[f32; 3]; 3],
    /// Calibrated line biases of B and C relative to A (cables, RF channels), rad: removed
    /// from the prompts before any stage sees them.
    pub line_bias_rad: [f32; 2],
    /// Coherent integration per epoch `T`, s (1 ms for GPS C/A): the fine filter's step.
    pub epoch_s: f32,
    /// Epochs per carrier-phase window: single differences are averaged over a window for the
    /// cold start, the snapshot monitor, the baselines and velocity differences of the
    /// rigid-body filter, and the references of the gyro calibration.
    pub window_epochs: u32,
    /// Windows between two snapshot (monitor) solutions.
    pub snapshot_windows: u32,
    /// The fine (one-stage, paper 003) filter: three angles with rates, no line-bias states
    /// (the biases are calibrated), Gaussian approximation.
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
    /// is declared unavailable.
    pub max_coast_s: f32,
    /// The gyro, if one is fitted.
    pub gyro: Option<GyroConfig>,
}

impl ReceiverConfig {
    /// GPS L1 C/A with 1 ms epochs, 100 ms windows, a snapshot every second, a 1 Hz fine
    /// loop, 0.6 mm single differences at the resolver's reference, a ratio test of 3, and the
    /// given antennas and gyro.
    pub fn gps_l1(antennas_m: [[f32; 3]; 3], gyro: Option<GyroConfig>) -> Self {
        let longest = longest_baseline(&antennas_m);
        let mut ambiguity = AmbiguityConfig::gps_l1(6e-4, longest.max(0.1) * 1.2);
        ambiguity.ratio_threshold = 3.0;
        Self {
            antennas_m,
            line_bias_rad: [0.0; 2],
            epoch_s: 1e-3,
            window_epochs: 100,
            snapshot_windows: 10,
            fine: OneStageConfig::gps_l1(FilterMode::GaussianApproximation, 1.0),
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

    /// Checks the values the receiver itself uses (the stages check their own).
    pub(crate) fn validate(&self) -> Result<(), ReceiverError> {
        let scalars = [
            self.epoch_s,
            self.prior_rate_sigma,
            self.slip_threshold_cycles,
            self.reanchor_angle_rad,
            self.blocked_power_ratio,
            self.baseline_sigma_m,
            self.velocity_sigma_m_s,
            self.max_coast_s,
        ];
        let finite = self
            .antennas_m
            .iter()
            .flatten()
            .chain(self.line_bias_rad.iter())
            .chain(scalars.iter())
            .all(|v| v.is_finite());
        if !finite {
            return Err(ReceiverError::NonFinite);
        }
        let positive = scalars.iter().all(|&v| v > 0.0);
        let counts = self.window_epochs >= 10
            && self.snapshot_windows >= 1
            && self.min_cold_start_satellites >= 4
            && self.min_fine_satellites >= 1
            && self.slip_threshold_cycles < 0.5
            && self.blocked_power_ratio < 0.5
            && (self.fine.epoch_s - self.epoch_s).abs() <= 1e-6 * self.epoch_s;
        if !(positive && counts) {
            return Err(ReceiverError::InvalidConfig);
        }
        if let Some(g) = &self.gyro {
            let h = g.sample_interval_s;
            let ok = h.is_finite()
                && h > 0.0
                && g.angle_random_walk >= 0.0
                && g.residual_rate_sigma >= 0.0
                && g.calibration_window_s > 0.0
                && g.calibration_max_sigma > 0.0;
            // the window must end on a propagation step (2h)
            let steps = self.window_s() / (2.0 * h);
            if !(ok && (steps - libm::roundf(steps)).abs() < 1e-3 && steps >= 1.0) {
                return Err(ReceiverError::InvalidConfig);
            }
        }
        Ok(())
    }
}

fn longest_baseline(antennas: &[[f32; 3]; 3]) -> f32 {
    let p = antennas.map(Vector3::from);
    let [a, b, c] = p;
    (b - a).norm().max((c - a).norm()).max((c - b).norm())
}
