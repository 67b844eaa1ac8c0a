//! What the receiver reports: the attitude with its covariance, source and health, the
//! per-stage estimates, and the events of a run (faults detected, stages changing state).

use nalgebra::Matrix3;

use crate::attitude::one_stage::LockStatus;
use crate::geometry::{Euler321, Quaternion};

/// Which stage produced an attitude.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AttitudeSource {
    /// No attitude yet (before the first fix) or no longer (coasted too long).
    #[default]
    None,
    /// The snapshot solution of the latest window with fixed ambiguities (paper 002),
    /// propagated by the gyro to the current epoch.
    Snapshot,
    /// The fine filter: the gyro-aided filter while it updates, or paper 003's one-stage
    /// loop (without a gyro) while it is locked.
    Fine,
    /// The gyro (paper 001) carrying the last fine attitude while the fine filter has no
    /// usable input (an antenna blocked, too few satellites, false lock); the covariance
    /// grows with the gyro's noise and the uncertainty of its bias.
    GyroCoast,
}

/// Why the receiver dropped its attitude and started cold.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LossReason {
    /// The gyro carried the attitude longer than [`ReceiverConfig::max_coast_s`](super::ReceiverConfig::max_coast_s).
    CoastTooLong,
    /// No fine update for longer than
    /// [`ReceiverConfig::max_gap_without_gyro_s`](super::ReceiverConfig::max_gap_without_gyro_s)
    /// without a gyro (or with the gyro excluded).
    GapWithoutGyro,
    /// The signals returned, but the attitude had become too uncertain to predict the single
    /// differences to a fraction of a cycle.
    TooUncertainToResume,
    /// The epochs jumped ahead (a gap in the input longer than the coast limit).
    EpochJump,
    /// An integrity check found the fine attitude inconsistent with the signals and no
    /// independent fix was available to restart it from.
    IntegrityFailure,
}

/// The last independent integrity check: a fresh integer fix against the fine attitude.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IntegrityCheck {
    /// Epoch (the window's centre).
    pub epoch: u64,
    /// Angle between the fix and the fine attitude, rad.
    pub angle_rad: f32,
    /// `dᵀ (P_fine + P_fix)⁻¹ d` (χ², 3 degrees of freedom, when both are consistent).
    pub nees: f32,
    /// Largest 1σ axis of the fix, rad.
    pub fix_sigma_rad: f32,
    /// Largest 1σ axis of the fine attitude, rad.
    pub fine_sigma_rad: f32,
    /// Whether it raised an alarm.
    pub alarm: bool,
}

/// The receiver's judgement of its own output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Integrity {
    /// No attitude, or none checked yet.
    #[default]
    Unknown,
    /// The last independent check agreed with the attitude and the fine filter's residuals
    /// are consistent with its noise model.
    Consistent,
    /// The fine filter's residuals exceed what its covariance allows: the reported
    /// covariance is inflated by the excess until the next independent check.
    Degraded,
    /// An independent check disagreed with the attitude: it is being restarted; do not use
    /// the attitude for control.
    Alarm,
}

/// The receiver's view of its own state.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ReceiverHealth {
    /// Satellites with aiding and observations in the last window.
    pub satellites_tracked: u8,
    /// Satellites in the fine filter's last epoch.
    pub satellites_used: u8,
    /// Satellites whose single-difference ambiguities are fixed on both baselines.
    pub satellites_fixed: u8,
    /// The cold start has succeeded.
    pub ambiguities_fixed: bool,
    /// The fine filter's lock verdict (`None` before the first fix).
    pub fine_lock: Option<LockStatus>,
    /// Antennas (A, B, C) currently declared blocked.
    pub antenna_blocked: [bool; 3],
    /// Gyro increments are arriving.
    pub gyro_running: bool,
    /// A gyro calibration has been applied.
    pub gyro_calibrated: bool,
    /// Time since the fine filter's last update, s (0 while it updates).
    pub coasting_s: f32,
    /// The gyro is excluded (faulty samples, or inconsistent with the carrier phase): the
    /// fine filter runs without it until it agrees with the signals again.
    pub gyro_excluded: bool,
    /// Gyro samples refused as implausible (above the configured maximum rate) since the
    /// start.
    pub gyro_faults: u32,
    /// The receiver's judgement of its attitude.
    pub integrity: Integrity,
    /// Cold starts after a loss of the attitude since the receiver was created.
    pub cold_restarts: u32,
    /// Estimated line biases of B and C, rad (zero before the first fix).
    pub line_bias_rad: [f32; 2],
    /// Their standard deviations, rad (zero before the first fix).
    pub line_bias_sigma_rad: [f32; 2],
}

/// An attitude with its uncertainty.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StageEstimate {
    /// Epoch the estimate belongs to.
    pub epoch: u64,
    /// Attitude `q_rb`, body to the aiding's reference frame (ECI in host-sim).
    pub q_rb: Quaternion<f32>,
    /// Covariance of the body-frame rotation-vector error `δ`, `C_true = Ĉ exp([δ]×)`, rad².
    pub covariance: Matrix3<f32>,
}

/// The receiver's attitude, as [`super::AttitudeReceiver::attitude`] reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ReceiverAttitude {
    /// Epoch the attitude belongs to.
    pub epoch: u64,
    /// Attitude `q_rb`, body to the reference frame of the aiding (ECI in host-sim).
    pub q_rb: Quaternion<f32>,
    /// The same attitude as `C_rb`.
    pub c_rb: Matrix3<f32>,
    /// The same attitude as 3-2-1 angles, rad.
    pub euler: Euler321<f32>,
    /// Covariance of the body-frame rotation-vector error, rad².
    pub covariance: Matrix3<f32>,
    /// The stage it came from.
    pub source: AttitudeSource,
    /// Health flags.
    pub health: ReceiverHealth,
}

/// Something that happened in the receiver, stamped with the epoch it was noticed in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ReceiverEvent {
    /// The cold start resolved the ambiguities (`satellites` used).
    FirstFix {
        /// Epoch.
        epoch: u64,
        /// Satellites in the fix.
        satellites: u8,
    },
    /// The cold start was refused (ratio test, χ² test, too few satellites).
    FixRefused {
        /// Epoch.
        epoch: u64,
    },
    /// The fine filter declared lock.
    FineLocked {
        /// Epoch.
        epoch: u64,
    },
    /// The fine filter lost lock or was flagged false lock; it is re-initialized from the
    /// snapshot.
    FineLockLost {
        /// Epoch.
        epoch: u64,
    },
    /// The fine filter's frame was re-anchored on its estimate.
    Reanchored {
        /// Epoch.
        epoch: u64,
    },
    /// A satellite started to deliver observations.
    SatelliteAcquired {
        /// Epoch.
        epoch: u64,
        /// PRN.
        prn: u8,
    },
    /// A satellite stopped delivering observations (set, lost lock, aiding withdrawn).
    SatelliteLost {
        /// Epoch.
        epoch: u64,
        /// PRN.
        prn: u8,
    },
    /// A satellite's single-difference ambiguities were fixed from the fine attitude.
    AmbiguityFixed {
        /// Epoch.
        epoch: u64,
        /// PRN.
        prn: u8,
    },
    /// A fixed single difference jumped by whole cycles; repaired.
    CycleSlip {
        /// Epoch.
        epoch: u64,
        /// PRN.
        prn: u8,
        /// Antenna (1 = B, 2 = C) whose single difference slipped.
        antenna: u8,
        /// Whole cycles of the slip.
        cycles: i8,
    },
    /// An antenna's signal power dropped: declared blocked, left out of every stage.
    AntennaBlocked {
        /// Epoch.
        epoch: u64,
        /// Antenna (0 = A, 1 = B, 2 = C).
        antenna: u8,
    },
    /// A blocked antenna's signal returned.
    AntennaRestored {
        /// Epoch.
        epoch: u64,
        /// Antenna.
        antenna: u8,
    },
    /// The reference prompt changed sign away from a data-bit edge (a bit transition at the
    /// wrong moment, or a half-cycle slip of the reference loop).
    BitAnomaly {
        /// Epoch.
        epoch: u64,
        /// PRN.
        prn: u8,
    },
    /// A gyro calibration window (paper 001) was solved with a σ below the configured
    /// limit.
    GyroCalibrated {
        /// Epoch.
        epoch: u64,
    },
    /// The attitude was lost: fixes dropped, the cold start runs again.
    AttitudeLost {
        /// Epoch.
        epoch: u64,
        /// Why.
        reason: LossReason,
    },
    /// An independent integer fix disagreed with the fine attitude beyond their covariances;
    /// the fine filter was restarted from the fix.
    IntegrityAlarm {
        /// Epoch.
        epoch: u64,
        /// Angle between the two attitudes, mrad (saturating).
        angle_mrad: u16,
    },
    /// The gyro was excluded.
    GyroExcluded {
        /// Epoch.
        epoch: u64,
    },
    /// The gyro agrees with the signals again and is used.
    GyroRestored {
        /// Epoch.
        epoch: u64,
    },
}

impl ReceiverEvent {
    /// The epoch of the event.
    pub fn epoch(&self) -> u64 {
        match *self {
            Self::FirstFix { epoch, .. }
            | Self::FixRefused { epoch }
            | Self::FineLocked { epoch }
            | Self::FineLockLost { epoch }
            | Self::Reanchored { epoch }
            | Self::SatelliteAcquired { epoch, .. }
            | Self::SatelliteLost { epoch, .. }
            | Self::AmbiguityFixed { epoch, .. }
            | Self::CycleSlip { epoch, .. }
            | Self::AntennaBlocked { epoch, .. }
            | Self::AntennaRestored { epoch, .. }
            | Self::BitAnomaly { epoch, .. }
            | Self::GyroCalibrated { epoch }
            | Self::AttitudeLost { epoch, .. }
            | Self::IntegrityAlarm { epoch, .. }
            | Self::GyroExcluded { epoch }
            | Self::GyroRestored { epoch } => epoch,
        }
    }
}
