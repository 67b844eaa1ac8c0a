//! `#[repr(C)]` mirrors of the receiver's inputs and outputs, each with its conversion.
//!
//! Adding a field to a core type: add it here (a plain integer or float field; C → Rust
//! mirrors use `u8` for flags and codes, never `bool` or an enum, so that any bytes C writes
//! are a valid value) and one line in the conversion below it; `cbindgen` regenerates the
//! header. Matrices are row-major, quaternions scalar first (`w, x, y, z`).

use gnss_attitude::attitude::one_stage::{FilterMode, LockStatus, PromptIq, SatelliteObservation};
use gnss_attitude::geometry::{Euler321, Quaternion};
use gnss_attitude::receiver::{
    AttitudeSource, GyroConfig, Integrity, LineBiasCalibration, LossReason, ReceiverAttitude,
    ReceiverConfig, ReceiverEvent, ReceiverHealth, SatelliteAiding,
};
use nalgebra::Matrix3;

use crate::status::GaStatus;

fn flag(v: bool) -> u8 {
    u8::from(v)
}

fn rows(m: &Matrix3<f32>) -> [[f32; 3]; 3] {
    [
        [m.m11, m.m12, m.m13],
        [m.m21, m.m22, m.m23],
        [m.m31, m.m32, m.m33],
    ]
}

fn matrix(r: &[[f32; 3]; 3]) -> Matrix3<f32> {
    let [[a, b, c], [d, e, f], [g, h, i]] = *r;
    Matrix3::new(a, b, c, d, e, f, g, h, i)
}

// ------------------------------------------------------------------------------ configuration

/// Mirror of [`GyroConfig`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaGyroConfig {
    /// Sample interval `h` of the increments, s.
    pub sample_interval_s: f32,
    /// Pulse weight, rad, when `has_pulse_weight` is non-zero (pulse-count gyros).
    pub pulse_weight_rad: f32,
    /// Non-zero: the gyro delivers pulse counts of `pulse_weight_rad`.
    pub has_pulse_weight: u8,
    /// Angle random walk, rad/√s.
    pub angle_random_walk: f32,
    /// Rate error left after calibration (1σ), rad/s.
    pub residual_rate_sigma: f32,
    /// Calibration window, s.
    pub calibration_window_s: f32,
    /// Largest σ (rad/s) of a calibration window's bias estimate that counts.
    pub calibration_max_sigma: f32,
    /// Random walk of the gyro bias, rad/s/√s.
    pub bias_random_walk: f32,
    /// σ of the turn-on bias, rad/s.
    pub turn_on_bias_sigma: f32,
    /// Largest plausible body rate, rad/s (above: a gyro fault).
    pub max_rate_rad_s: f32,
}

impl From<&GyroConfig> for GaGyroConfig {
    fn from(g: &GyroConfig) -> Self {
        Self {
            sample_interval_s: g.sample_interval_s,
            pulse_weight_rad: g.pulse_weight_rad.unwrap_or(0.0),
            has_pulse_weight: flag(g.pulse_weight_rad.is_some()),
            angle_random_walk: g.angle_random_walk,
            residual_rate_sigma: g.residual_rate_sigma,
            calibration_window_s: g.calibration_window_s,
            calibration_max_sigma: g.calibration_max_sigma,
            bias_random_walk: g.bias_random_walk,
            turn_on_bias_sigma: g.turn_on_bias_sigma,
            max_rate_rad_s: g.max_rate_rad_s,
        }
    }
}

impl GaGyroConfig {
    /// The core configuration.
    pub fn to_core(&self) -> GyroConfig {
        GyroConfig {
            sample_interval_s: self.sample_interval_s,
            pulse_weight_rad: (self.has_pulse_weight != 0).then_some(self.pulse_weight_rad),
            angle_random_walk: self.angle_random_walk,
            residual_rate_sigma: self.residual_rate_sigma,
            calibration_window_s: self.calibration_window_s,
            calibration_max_sigma: self.calibration_max_sigma,
            bias_random_walk: self.bias_random_walk,
            turn_on_bias_sigma: self.turn_on_bias_sigma,
            max_rate_rad_s: self.max_rate_rad_s,
        }
    }
}

/// `fine_mode`: the Gaussian-approximation filter.
pub const GA_FINE_GAUSSIAN: u8 = 0;
/// `fine_mode`: the constant-gain tracker.
pub const GA_FINE_CONSTANT_GAIN: u8 = 1;

/// Mirror of [`ReceiverConfig`]: every top-level field, and of the stages' settings the ones
/// flight software tunes (the rest keep the values of [`ReceiverConfig::gps_l1`]). Start from
/// [`crate::ga_config_gps_l1`] and change fields.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaConfig {
    /// Phase centres of antennas A, B, C, body axes, m (`[antenna][axis]`).
    pub antennas_m: [[f32; 3]; 3],
    /// A bench calibration of the line biases of B and C relative to A, rad, used when
    /// `has_line_bias` is non-zero (else they are resolved and estimated in flight).
    pub line_bias_rad: [f32; 2],
    /// σ of that calibration, rad.
    pub line_bias_sigma_rad: f32,
    /// Non-zero: `line_bias_rad` holds a bench calibration.
    pub has_line_bias: u8,
    /// Coherent integration per epoch, s (also the fine filter's step).
    pub epoch_s: f32,
    /// Epochs per carrier-phase window.
    pub window_epochs: u32,
    /// Windows between two snapshot solutions.
    pub snapshot_windows: u32,
    /// Epochs per fine-filter block.
    pub block_epochs: u32,
    /// Windows between two fresh-fix integrity checks.
    pub integrity_windows: u32,
    /// Random walk of the line biases, rad/√s.
    pub line_bias_random_walk: f32,
    /// Longest gap without updates and without a gyro before the attitude is lost, s.
    pub max_gap_without_gyro_s: f32,
    /// Largest attitude σ from which the fine filter resumes after a coast, rad.
    pub max_resume_sigma_rad: f32,
    /// Satellites needed for the cold start.
    pub min_cold_start_satellites: u8,
    /// Satellites needed for a fine-filter update.
    pub min_fine_satellites: u8,
    /// Non-zero: a gyro is fitted (`gyro` holds its settings).
    pub has_gyro: u8,
    /// `GA_FINE_*`: the fine filter's mode.
    pub fine_mode: u8,
    /// Prior σ of the fine filter's angular rates, rad/s.
    pub prior_rate_sigma: f32,
    /// Cycle-slip threshold, cycles.
    pub slip_threshold_cycles: f32,
    /// Re-anchoring angle of the fine filter's frame, rad.
    pub reanchor_angle_rad: f32,
    /// Blocked-antenna power ratio.
    pub blocked_power_ratio: f32,
    /// σ of one baseline component in the rigid-body filter, m.
    pub baseline_sigma_m: f32,
    /// σ of one velocity-difference component in the rigid-body filter, m/s.
    pub velocity_sigma_m_s: f32,
    /// Longest gyro coast before the attitude is declared unavailable, s.
    pub max_coast_s: f32,
    /// Loop bandwidth of the fine filter, Hz.
    pub fine_loop_bandwidth_hz: f32,
    /// σ of one single difference at the resolver's reference, m.
    pub ambiguity_phase_sigma_m: f32,
    /// Code σ of the resolver (at least the longest baseline), m.
    pub ambiguity_code_sigma_m: f32,
    /// Ratio test threshold of the resolver (> 1).
    pub ambiguity_ratio_threshold: f32,
    /// Node budget of the integer search.
    pub ambiguity_max_nodes: u32,
    /// The gyro (read when `has_gyro` is non-zero).
    pub gyro: GaGyroConfig,
}

impl From<&ReceiverConfig> for GaConfig {
    fn from(c: &ReceiverConfig) -> Self {
        let gyro = c.gyro.unwrap_or(GyroConfig::mems(0.01, None));
        Self {
            antennas_m: c.antennas_m,
            line_bias_rad: c.line_bias.map_or([0.0; 2], |b| b.rad),
            line_bias_sigma_rad: c.line_bias.map_or(0.0, |b| b.sigma_rad),
            has_line_bias: flag(c.line_bias.is_some()),
            epoch_s: c.epoch_s,
            window_epochs: c.window_epochs,
            snapshot_windows: c.snapshot_windows,
            block_epochs: c.block_epochs,
            integrity_windows: c.integrity_windows,
            line_bias_random_walk: c.line_bias_random_walk,
            max_gap_without_gyro_s: c.max_gap_without_gyro_s,
            max_resume_sigma_rad: c.max_resume_sigma_rad,
            min_cold_start_satellites: c.min_cold_start_satellites,
            min_fine_satellites: c.min_fine_satellites,
            has_gyro: flag(c.gyro.is_some()),
            fine_mode: match c.fine.mode {
                FilterMode::ConstantGain => GA_FINE_CONSTANT_GAIN,
                _ => GA_FINE_GAUSSIAN,
            },
            prior_rate_sigma: c.prior_rate_sigma,
            slip_threshold_cycles: c.slip_threshold_cycles,
            reanchor_angle_rad: c.reanchor_angle_rad,
            blocked_power_ratio: c.blocked_power_ratio,
            baseline_sigma_m: c.baseline_sigma_m,
            velocity_sigma_m_s: c.velocity_sigma_m_s,
            max_coast_s: c.max_coast_s,
            fine_loop_bandwidth_hz: c.fine.loop_bandwidth_hz,
            ambiguity_phase_sigma_m: c.ambiguity.phase_sigma_m,
            ambiguity_code_sigma_m: c.ambiguity.code_sigma_m,
            ambiguity_ratio_threshold: c.ambiguity.ratio_threshold,
            ambiguity_max_nodes: c.ambiguity.max_nodes,
            gyro: GaGyroConfig::from(&gyro),
        }
    }
}

impl GaConfig {
    /// The core configuration: [`ReceiverConfig::gps_l1`] for the antennas and gyro, with
    /// every mirrored field set from `self`.
    ///
    /// # Errors
    /// [`GaStatus::InvalidConfig`] for an unknown `fine_mode` (the receiver checks values).
    pub fn to_core(&self) -> Result<ReceiverConfig, GaStatus> {
        let gyro = (self.has_gyro != 0).then(|| self.gyro.to_core());
        let mut c = ReceiverConfig::gps_l1(self.antennas_m, gyro);
        c.line_bias = (self.has_line_bias != 0).then_some(LineBiasCalibration {
            rad: self.line_bias_rad,
            sigma_rad: self.line_bias_sigma_rad,
        });
        c.epoch_s = self.epoch_s;
        c.window_epochs = self.window_epochs;
        c.snapshot_windows = self.snapshot_windows;
        c.block_epochs = self.block_epochs;
        c.integrity_windows = self.integrity_windows;
        c.line_bias_random_walk = self.line_bias_random_walk;
        c.max_gap_without_gyro_s = self.max_gap_without_gyro_s;
        c.max_resume_sigma_rad = self.max_resume_sigma_rad;
        c.min_cold_start_satellites = self.min_cold_start_satellites;
        c.min_fine_satellites = self.min_fine_satellites;
        c.fine.mode = match self.fine_mode {
            GA_FINE_GAUSSIAN => FilterMode::GaussianApproximation,
            GA_FINE_CONSTANT_GAIN => FilterMode::ConstantGain,
            _ => return Err(GaStatus::InvalidConfig),
        };
        c.fine.epoch_s = self.epoch_s;
        c.fine.loop_bandwidth_hz = self.fine_loop_bandwidth_hz;
        c.prior_rate_sigma = self.prior_rate_sigma;
        c.slip_threshold_cycles = self.slip_threshold_cycles;
        c.reanchor_angle_rad = self.reanchor_angle_rad;
        c.blocked_power_ratio = self.blocked_power_ratio;
        c.baseline_sigma_m = self.baseline_sigma_m;
        c.velocity_sigma_m_s = self.velocity_sigma_m_s;
        c.max_coast_s = self.max_coast_s;
        c.ambiguity.phase_sigma_m = self.ambiguity_phase_sigma_m;
        c.ambiguity.code_sigma_m = self.ambiguity_code_sigma_m;
        c.ambiguity.ratio_threshold = self.ambiguity_ratio_threshold;
        c.ambiguity.max_nodes = self.ambiguity_max_nodes;
        Ok(c)
    }
}

// ------------------------------------------------------------------------------ inputs

/// Mirror of [`SatelliteAiding`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct GaAiding {
    /// Epoch at which `los` holds.
    pub epoch: u64,
    /// Unit line of sight to the satellite, reference frame.
    pub los: [f32; 3],
    /// Its time derivative, 1/s.
    pub los_rate: [f32; 3],
    /// PRN.
    pub prn: u8,
}

impl From<&SatelliteAiding> for GaAiding {
    fn from(a: &SatelliteAiding) -> Self {
        Self {
            epoch: a.epoch,
            los: a.los,
            los_rate: a.los_rate,
            prn: a.prn,
        }
    }
}

impl GaAiding {
    /// The core aiding.
    pub fn to_core(&self) -> SatelliteAiding {
        SatelliteAiding {
            prn: self.prn,
            epoch: self.epoch,
            los: self.los,
            los_rate: self.los_rate,
        }
    }
}

/// Mirror of [`SatelliteObservation`] (`f32`): one satellite's prompts of one epoch.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct GaObservation {
    /// In-phase prompts of antennas A, B, C.
    pub prompt_i: [f32; 3],
    /// Quadrature prompts of antennas A, B, C.
    pub prompt_q: [f32; 3],
    /// Noise variance of each of I and Q (prompt units squared), > 0.
    pub noise_var: f32,
    /// C/N0, dB-Hz, in 0..=90.
    pub cn0_dbhz: f32,
    /// PRN.
    pub prn: u8,
}

impl From<&SatelliteObservation<f32>> for GaObservation {
    fn from(o: &SatelliteObservation<f32>) -> Self {
        Self {
            prompt_i: o.prompt.i,
            prompt_q: o.prompt.q,
            noise_var: o.noise_var,
            cn0_dbhz: o.cn0_dbhz,
            prn: o.id,
        }
    }
}

impl GaObservation {
    /// The core observation (its line of sight comes from the aiding).
    pub fn to_core(&self) -> SatelliteObservation<f32> {
        SatelliteObservation {
            id: self.prn,
            los: [0.0, 0.0, 1.0],
            prompt: PromptIq {
                i: self.prompt_i,
                q: self.prompt_q,
            },
            noise_var: self.noise_var,
            cn0_dbhz: self.cn0_dbhz,
        }
    }
}

// ------------------------------------------------------------------------------ outputs

/// `source`: no attitude.
pub const GA_SOURCE_NONE: u8 = 0;
/// `source`: the snapshot solution carried by the gyro.
pub const GA_SOURCE_SNAPSHOT: u8 = 1;
/// `source`: the fine filter (gyro-aided, or the one-stage loop without a gyro).
pub const GA_SOURCE_FINE: u8 = 2;
/// `source`: the gyro carrying the last fine attitude.
pub const GA_SOURCE_GYRO_COAST: u8 = 3;

fn source_code(s: AttitudeSource) -> u8 {
    match s {
        AttitudeSource::None => GA_SOURCE_NONE,
        AttitudeSource::Snapshot => GA_SOURCE_SNAPSHOT,
        AttitudeSource::Fine => GA_SOURCE_FINE,
        AttitudeSource::GyroCoast => GA_SOURCE_GYRO_COAST,
    }
}

fn source_from(code: u8) -> Result<AttitudeSource, GaStatus> {
    Ok(match code {
        GA_SOURCE_NONE => AttitudeSource::None,
        GA_SOURCE_SNAPSHOT => AttitudeSource::Snapshot,
        GA_SOURCE_FINE => AttitudeSource::Fine,
        GA_SOURCE_GYRO_COAST => AttitudeSource::GyroCoast,
        _ => return Err(GaStatus::InvalidInput),
    })
}

/// `fine_lock`: no fine filter yet.
pub const GA_LOCK_NONE: u8 = 0;
/// `fine_lock`: pulling in.
pub const GA_LOCK_PULL_IN: u8 = 1;
/// `fine_lock`: locked.
pub const GA_LOCK_LOCKED: u8 = 2;
/// `fine_lock`: false lock (the attitude must not be used).
pub const GA_LOCK_FALSE_LOCK: u8 = 3;

fn lock_code(l: Option<LockStatus>) -> u8 {
    match l {
        None => GA_LOCK_NONE,
        Some(LockStatus::PullIn) => GA_LOCK_PULL_IN,
        Some(LockStatus::Locked) => GA_LOCK_LOCKED,
        Some(LockStatus::FalseLock) => GA_LOCK_FALSE_LOCK,
    }
}

fn lock_from(code: u8) -> Result<Option<LockStatus>, GaStatus> {
    Ok(match code {
        GA_LOCK_NONE => None,
        GA_LOCK_PULL_IN => Some(LockStatus::PullIn),
        GA_LOCK_LOCKED => Some(LockStatus::Locked),
        GA_LOCK_FALSE_LOCK => Some(LockStatus::FalseLock),
        _ => return Err(GaStatus::InvalidInput),
    })
}

/// Mirror of [`ReceiverHealth`] (flags: 0 false, non-zero true).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct GaHealth {
    /// Time since the fine filter's last update, s.
    pub coasting_s: f32,
    /// Satellites with aiding and observations in the last window.
    pub satellites_tracked: u8,
    /// Satellites in the fine filter's last epoch.
    pub satellites_used: u8,
    /// Satellites with fixed ambiguities on both baselines.
    pub satellites_fixed: u8,
    /// The cold start has succeeded.
    pub ambiguities_fixed: u8,
    /// `GA_LOCK_*`.
    pub fine_lock: u8,
    /// Antennas A, B, C declared blocked.
    pub antenna_blocked: [u8; 3],
    /// Gyro increments are arriving.
    pub gyro_running: u8,
    /// A gyro calibration has been applied.
    pub gyro_calibrated: u8,
    /// The gyro is excluded (faulty).
    pub gyro_excluded: u8,
    /// `GA_INTEGRITY_*`.
    pub integrity: u8,
    /// Implausible gyro samples since the start.
    pub gyro_faults: u32,
    /// Cold starts after a loss of the attitude.
    pub cold_restarts: u32,
    /// Estimated line biases of B and C, rad.
    pub line_bias_rad: [f32; 2],
    /// Their σ, rad.
    pub line_bias_sigma_rad: [f32; 2],
}

/// `integrity`: not checked.
pub const GA_INTEGRITY_UNKNOWN: u8 = 0;
/// `integrity`: consistent.
pub const GA_INTEGRITY_CONSISTENT: u8 = 1;
/// `integrity`: degraded (the covariance is inflated).
pub const GA_INTEGRITY_DEGRADED: u8 = 2;
/// `integrity`: alarm (do not use the attitude).
pub const GA_INTEGRITY_ALARM: u8 = 3;

fn integrity_code(i: Integrity) -> u8 {
    match i {
        Integrity::Unknown => GA_INTEGRITY_UNKNOWN,
        Integrity::Consistent => GA_INTEGRITY_CONSISTENT,
        Integrity::Degraded => GA_INTEGRITY_DEGRADED,
        Integrity::Alarm => GA_INTEGRITY_ALARM,
    }
}

fn integrity_from(code: u8) -> Result<Integrity, GaStatus> {
    Ok(match code {
        GA_INTEGRITY_UNKNOWN => Integrity::Unknown,
        GA_INTEGRITY_CONSISTENT => Integrity::Consistent,
        GA_INTEGRITY_DEGRADED => Integrity::Degraded,
        GA_INTEGRITY_ALARM => Integrity::Alarm,
        _ => return Err(GaStatus::InvalidInput),
    })
}

impl From<&ReceiverHealth> for GaHealth {
    fn from(h: &ReceiverHealth) -> Self {
        Self {
            coasting_s: h.coasting_s,
            satellites_tracked: h.satellites_tracked,
            satellites_used: h.satellites_used,
            satellites_fixed: h.satellites_fixed,
            ambiguities_fixed: flag(h.ambiguities_fixed),
            fine_lock: lock_code(h.fine_lock),
            antenna_blocked: h.antenna_blocked.map(flag),
            gyro_running: flag(h.gyro_running),
            gyro_calibrated: flag(h.gyro_calibrated),
            gyro_excluded: flag(h.gyro_excluded),
            integrity: integrity_code(h.integrity),
            gyro_faults: h.gyro_faults,
            cold_restarts: h.cold_restarts,
            line_bias_rad: h.line_bias_rad,
            line_bias_sigma_rad: h.line_bias_sigma_rad,
        }
    }
}

impl GaHealth {
    /// The core health.
    ///
    /// # Errors
    /// [`GaStatus::InvalidInput`] for an unknown `fine_lock` code.
    pub fn to_core(&self) -> Result<ReceiverHealth, GaStatus> {
        Ok(ReceiverHealth {
            satellites_tracked: self.satellites_tracked,
            satellites_used: self.satellites_used,
            satellites_fixed: self.satellites_fixed,
            ambiguities_fixed: self.ambiguities_fixed != 0,
            fine_lock: lock_from(self.fine_lock)?,
            antenna_blocked: self.antenna_blocked.map(|b| b != 0),
            gyro_running: self.gyro_running != 0,
            gyro_calibrated: self.gyro_calibrated != 0,
            coasting_s: self.coasting_s,
            gyro_excluded: self.gyro_excluded != 0,
            gyro_faults: self.gyro_faults,
            integrity: integrity_from(self.integrity)?,
            cold_restarts: self.cold_restarts,
            line_bias_rad: self.line_bias_rad,
            line_bias_sigma_rad: self.line_bias_sigma_rad,
        })
    }
}

/// Mirror of [`ReceiverAttitude`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct GaAttitude {
    /// Epoch the attitude belongs to.
    pub epoch: u64,
    /// `q_rb`, body to the aiding's reference frame, `w, x, y, z`.
    pub q_rb: [f32; 4],
    /// The same as `C_rb`, row-major.
    pub c_rb: [[f32; 3]; 3],
    /// 3-2-1 angles yaw, pitch, roll, rad.
    pub euler_321_rad: [f32; 3],
    /// Covariance of the body-frame rotation-vector error, rad², row-major.
    pub covariance: [[f32; 3]; 3],
    /// Health flags.
    pub health: GaHealth,
    /// `GA_SOURCE_*`.
    pub source: u8,
}

impl From<&ReceiverAttitude> for GaAttitude {
    fn from(a: &ReceiverAttitude) -> Self {
        let q = a.q_rb;
        Self {
            epoch: a.epoch,
            q_rb: [q.w, q.x, q.y, q.z],
            c_rb: rows(&a.c_rb),
            euler_321_rad: [a.euler.yaw, a.euler.pitch, a.euler.roll],
            covariance: rows(&a.covariance),
            health: GaHealth::from(&a.health),
            source: source_code(a.source),
        }
    }
}

impl GaAttitude {
    /// The core attitude (for the formatters).
    ///
    /// # Errors
    /// [`GaStatus::InvalidInput`] for an unknown source or lock code.
    pub fn to_core(&self) -> Result<ReceiverAttitude, GaStatus> {
        let [w, x, y, z] = self.q_rb;
        let [yaw, pitch, roll] = self.euler_321_rad;
        Ok(ReceiverAttitude {
            epoch: self.epoch,
            q_rb: Quaternion::new(w, x, y, z),
            c_rb: matrix(&self.c_rb),
            euler: Euler321::new(yaw, pitch, roll),
            covariance: matrix(&self.covariance),
            source: source_from(self.source)?,
            health: self.health.to_core()?,
        })
    }
}

/// `kind` of [`GaEvent`], one per [`ReceiverEvent`] variant.
#[repr(u8)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum GaEventKind {
    /// No event (the value [`crate::ga_receiver_pop_event`] leaves on an empty queue).
    #[default]
    None = 0,
    /// The cold start resolved the ambiguities (`satellites`).
    FirstFix = 1,
    /// The cold start was refused.
    FixRefused = 2,
    /// The fine filter declared lock.
    FineLocked = 3,
    /// The fine filter lost lock.
    FineLockLost = 4,
    /// The fine filter's frame was re-anchored.
    Reanchored = 5,
    /// A satellite started to deliver observations (`prn`).
    SatelliteAcquired = 6,
    /// A satellite stopped delivering observations (`prn`).
    SatelliteLost = 7,
    /// A satellite's ambiguities were fixed from the fine attitude (`prn`).
    AmbiguityFixed = 8,
    /// A cycle slip was repaired (`prn`, `antenna` 1 = B / 2 = C, `cycles`).
    CycleSlip = 9,
    /// An antenna was declared blocked (`antenna` 0–2).
    AntennaBlocked = 10,
    /// A blocked antenna returned (`antenna`).
    AntennaRestored = 11,
    /// The reference prompt changed sign away from a bit edge (`prn`).
    BitAnomaly = 12,
    /// A gyro calibration window was solved.
    GyroCalibrated = 13,
    /// The attitude was lost; the cold start runs again (`reason`: `GA_LOSS_*`).
    AttitudeLost = 14,
    /// An integrity alarm restarted the fine filter (`angle_mrad`).
    IntegrityAlarm = 15,
    /// The gyro was excluded.
    GyroExcluded = 16,
    /// The gyro is used again.
    GyroRestored = 17,
    /// An event this version of the ABI has no kind for.
    Other = 255,
}

/// Mirror of [`ReceiverEvent`]: the kind and the fields that kind uses (others 0).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct GaEvent {
    /// Epoch the event was noticed in.
    pub epoch: u64,
    /// What happened.
    pub kind: GaEventKind,
    /// PRN, for satellite events.
    pub prn: u8,
    /// Antenna, for antenna and cycle-slip events.
    pub antenna: u8,
    /// Whole cycles of a cycle slip.
    pub cycles: i8,
    /// Satellites in a first fix.
    pub satellites: u8,
    /// `GA_LOSS_*`, for a lost attitude.
    pub reason: u8,
    /// Angle of an integrity alarm, mrad.
    pub angle_mrad: u16,
}

/// `reason`: coasted on the gyro too long.
pub const GA_LOSS_COAST_TOO_LONG: u8 = 1;
/// `reason`: no update for too long without a gyro.
pub const GA_LOSS_GAP_WITHOUT_GYRO: u8 = 2;
/// `reason`: too uncertain to resume after a coast.
pub const GA_LOSS_TOO_UNCERTAIN: u8 = 3;
/// `reason`: the epochs jumped ahead.
pub const GA_LOSS_EPOCH_JUMP: u8 = 4;
/// `reason`: an integrity failure without an attitude to restart from.
pub const GA_LOSS_INTEGRITY: u8 = 5;

fn loss_code(r: LossReason) -> u8 {
    match r {
        LossReason::CoastTooLong => GA_LOSS_COAST_TOO_LONG,
        LossReason::GapWithoutGyro => GA_LOSS_GAP_WITHOUT_GYRO,
        LossReason::TooUncertainToResume => GA_LOSS_TOO_UNCERTAIN,
        LossReason::EpochJump => GA_LOSS_EPOCH_JUMP,
        LossReason::IntegrityFailure => GA_LOSS_INTEGRITY,
    }
}

impl From<&ReceiverEvent> for GaEvent {
    fn from(e: &ReceiverEvent) -> Self {
        use GaEventKind as K;
        let mut out = Self {
            epoch: e.epoch(),
            ..Self::default()
        };
        out.kind = match *e {
            ReceiverEvent::FirstFix { satellites, .. } => {
                out.satellites = satellites;
                K::FirstFix
            }
            ReceiverEvent::FixRefused { .. } => K::FixRefused,
            ReceiverEvent::FineLocked { .. } => K::FineLocked,
            ReceiverEvent::FineLockLost { .. } => K::FineLockLost,
            ReceiverEvent::Reanchored { .. } => K::Reanchored,
            ReceiverEvent::SatelliteAcquired { prn, .. } => {
                out.prn = prn;
                K::SatelliteAcquired
            }
            ReceiverEvent::SatelliteLost { prn, .. } => {
                out.prn = prn;
                K::SatelliteLost
            }
            ReceiverEvent::AmbiguityFixed { prn, .. } => {
                out.prn = prn;
                K::AmbiguityFixed
            }
            ReceiverEvent::CycleSlip {
                prn,
                antenna,
                cycles,
                ..
            } => {
                out.prn = prn;
                out.antenna = antenna;
                out.cycles = cycles;
                K::CycleSlip
            }
            ReceiverEvent::AntennaBlocked { antenna, .. } => {
                out.antenna = antenna;
                K::AntennaBlocked
            }
            ReceiverEvent::AntennaRestored { antenna, .. } => {
                out.antenna = antenna;
                K::AntennaRestored
            }
            ReceiverEvent::BitAnomaly { prn, .. } => {
                out.prn = prn;
                K::BitAnomaly
            }
            ReceiverEvent::GyroCalibrated { .. } => K::GyroCalibrated,
            ReceiverEvent::AttitudeLost { reason, .. } => {
                out.reason = loss_code(reason);
                K::AttitudeLost
            }
            ReceiverEvent::IntegrityAlarm { angle_mrad, .. } => {
                out.angle_mrad = angle_mrad;
                K::IntegrityAlarm
            }
            ReceiverEvent::GyroExcluded { .. } => K::GyroExcluded,
            ReceiverEvent::GyroRestored { .. } => K::GyroRestored,
            #[allow(unreachable_patterns)]
            _ => K::Other,
        };
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gnss_attitude::receiver::example::ExampleFlight;

    #[test]
    fn config_round_trips() {
        for gyro in [false, true] {
            let core = ExampleFlight::config(gyro);
            assert_eq!(GaConfig::from(&core).to_core().unwrap(), core);
        }
        let mut pulses = ExampleFlight::config(true);
        if let Some(g) = pulses.gyro.as_mut() {
            g.pulse_weight_rad = Some(1e-5);
        }
        assert_eq!(GaConfig::from(&pulses).to_core().unwrap(), pulses);
        let mut bad = GaConfig::from(&pulses);
        bad.fine_mode = 7;
        assert_eq!(bad.to_core(), Err(GaStatus::InvalidConfig));
    }

    #[test]
    fn attitude_round_trips() {
        let mut flight = ExampleFlight::new(3);
        let mut r =
            gnss_attitude::receiver::AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
        flight.fly(&mut r, 0, 300).unwrap();
        let a = r.attitude();
        let back = GaAttitude::from(&a).to_core().unwrap();
        assert_eq!(back.q_rb, a.q_rb);
        assert_eq!(back.c_rb, a.c_rb);
        assert_eq!(back.covariance, a.covariance);
        assert_eq!(back.health, a.health);
        assert_eq!(back.source, a.source);
        let mut bad = GaAttitude::from(&a);
        bad.source = 9;
        assert_eq!(bad.to_core(), Err(GaStatus::InvalidInput));
    }

    #[test]
    fn observation_and_event_mirrors() {
        let mut flight = ExampleFlight::new(3);
        let o = flight.observations(0)[0];
        let back = GaObservation::from(&o).to_core();
        assert_eq!(
            (back.id, back.prompt, back.noise_var),
            (o.id, o.prompt, o.noise_var)
        );
        let e = GaEvent::from(&ReceiverEvent::CycleSlip {
            epoch: 9,
            prn: 4,
            antenna: 2,
            cycles: -1,
        });
        assert_eq!(
            (e.kind, e.epoch, e.prn, e.antenna, e.cycles),
            (GaEventKind::CycleSlip, 9, 4, 2, -1)
        );
    }
}
