//! The fine attitude stage: the gyro-aided filter when the gyro is usable, paper 003's loop
//! when there is none (or it is excluded), behind one type.

use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

use crate::attitude::gyro_aided::{
    GyroAidedConfig, GyroAidedError, GyroAidedFilter, GyroAidedPrior, GyroAidedReport,
    PhaseDifferenceBlock,
};
use crate::attitude::one_stage::{LockStatus, OneStageError};
use crate::ekf::GateConfidence;
use crate::geometry::Quaternion;

use super::config::{GyroConfig, ReceiverConfig};
use super::fine_loop::LoopFine;
use super::{AttitudeSource, LineBias};

#[cfg(doc)]
use super::ReceiverEvent;

/// Blocks without an update after which the gyro-aided attitude counts as coasting.
const FRESH_BLOCKS: u64 = 2;

/// Epochs without an observation after which the loop's attitude is no longer fresh.
const FRESH_EPOCHS: u64 = 2;

/// The gyro-aided filter and the epoch it stands at.
#[derive(Clone, Debug)]
pub(crate) struct GyroFine {
    filter: GyroAidedFilter<f32>,
    /// Epoch (its centre) the filter's state belongs to.
    epoch: u64,
    /// `M` at that epoch.
    m: Quaternion<f32>,
    /// Last epoch with an accepted update.
    pub last_update: u64,
    /// Whether an update has been accepted since the start ([`ReceiverEvent::FineLocked`]
    /// then).
    pub locked: bool,
}

/// The fine stage.
// (one of the two filters lives in the receiver at a time; without an allocator the larger
// sets its size either way)
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub(crate) enum FineStage {
    /// With the gyro.
    Gyro(GyroFine),
    /// Without it.
    Loop(LoopFine),
}

/// The gyro-aided filter's configuration from the receiver's.
fn gyro_aided_config(config: &ReceiverConfig, gyro: &GyroConfig) -> GyroAidedConfig<f32> {
    GyroAidedConfig {
        wavelength_m: config.wavelength_m(),
        angle_random_walk: gyro.angle_random_walk,
        bias_random_walk: gyro.bias_random_walk,
        line_bias_random_walk: config.line_bias_random_walk,
        gate: Some(GateConfidence::P999),
    }
}

impl FineStage {
    /// The gyro-aided stage from an attitude at `epoch` (gyro attitude `m` there).
    #[allow(clippy::too_many_arguments)]
    pub fn start_gyro(
        config: &ReceiverConfig,
        gyro: &GyroConfig,
        baselines: [Vector3<f32>; 2],
        q_rb: &Quaternion<f32>,
        covariance: &Matrix3<f32>,
        bias_sigma: f32,
        line_bias: &LineBias,
        m: &Quaternion<f32>,
        epoch: u64,
    ) -> Result<Self, GyroAidedError> {
        let prior = GyroAidedPrior {
            q_rb: *q_rb,
            attitude_covariance: *covariance,
            bias_sigma,
            line_bias: Vector2::from(line_bias.rad),
            line_bias_covariance: Matrix2::from_diagonal(&Vector2::from(
                line_bias.sigma_rad.map(|s| s * s),
            )),
        };
        let filter = GyroAidedFilter::new(gyro_aided_config(config, gyro), baselines, &prior, m)?;
        Ok(Self::Gyro(GyroFine {
            filter,
            epoch,
            m: *m,
            last_update: epoch,
            locked: false,
        }))
    }

    /// The loop stage from an attitude at `epoch`.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub fn start_loop(
        config: &ReceiverConfig,
        q_rb: &Quaternion<f32>,
        covariance: &Matrix3<f32>,
        line_bias: &LineBias,
        rates: Vector3<f32>,
        epoch: u64,
    ) -> Result<Self, OneStageError> {
        Ok(Self::Loop(LoopFine::start(
            config, q_rb, covariance, line_bias, rates, epoch,
        )?))
    }

    /// Whether this is the gyro-aided stage.
    pub fn is_gyro(&self) -> bool {
        matches!(self, Self::Gyro(_))
    }

    /// The attitude when the gyro's attitude is `m` (the loop ignores `m`).
    pub fn attitude(&self, m: &Quaternion<f32>) -> Quaternion<f32> {
        match self {
            Self::Gyro(g) => g.filter.attitude(m),
            Self::Loop(l) => l.attitude(),
        }
    }

    /// The body-frame covariance at `epoch` (a gyro-aided coast grows it with the gyro's
    /// noise up to that epoch), rad².
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub fn covariance_at(
        &self,
        epoch: u64,
        m: &Quaternion<f32>,
        config: &ReceiverConfig,
    ) -> Matrix3<f32> {
        match self {
            Self::Gyro(g) => {
                let tau = epoch.saturating_sub(g.epoch) as f32 * config.epoch_s;
                g.filter
                    .predicted_attitude_covariance(&(g.m.conjugate() * *m), tau)
            }
            Self::Loop(l) => l.covariance(),
        }
    }

    /// Last epoch the stage had an update.
    pub fn last_update(&self) -> u64 {
        match self {
            Self::Gyro(g) => g.last_update,
            Self::Loop(l) => l.last_update,
        }
    }

    /// What the attitude at `epoch` counts as: the fine attitude while it updates, a coast
    /// on the gyro while it does not (gyro-aided only), `None` when it is not usable (the
    /// loop before lock, or coasting without a gyro).
    pub fn source_at(&self, epoch: u64, config: &ReceiverConfig) -> Option<AttitudeSource> {
        match self {
            Self::Gyro(g) => {
                let block = u64::from(config.block_epochs);
                let fresh = epoch.saturating_sub(g.last_update)
                    <= FRESH_BLOCKS.saturating_mul(block).saturating_add(block);
                Some(if fresh {
                    AttitudeSource::Fine
                } else {
                    AttitudeSource::GyroCoast
                })
            }
            Self::Loop(l) => {
                let fresh = epoch.saturating_sub(l.last_update) <= FRESH_EPOCHS;
                (l.lock() == LockStatus::Locked && fresh).then_some(AttitudeSource::Fine)
            }
        }
    }

    /// The line biases the stage holds.
    pub fn line_bias(&self) -> LineBias {
        match self {
            Self::Gyro(g) => {
                let b = g.filter.line_bias();
                let p = g.filter.line_bias_covariance();
                LineBias {
                    rad: [b.x, b.y],
                    sigma_rad: [
                        crate::sqrtf(p[(0, 0)].max(0.0)),
                        crate::sqrtf(p[(1, 1)].max(0.0)),
                    ],
                    known: true,
                }
            }
            Self::Loop(l) => l.line_bias(),
        }
    }

    /// The loop's lock verdict (the gyro-aided stage has no lock detector: it is locked by
    /// construction once started from a fix, and checked by the integrity monitor).
    pub fn lock(&self) -> Option<LockStatus> {
        match self {
            Self::Gyro(_) => None,
            Self::Loop(l) => Some(l.lock()),
        }
    }

    /// The gyro-aided filter, if that is the stage.
    pub fn gyro_mut(&mut self) -> Option<&mut GyroFine> {
        match self {
            Self::Gyro(g) => Some(g),
            Self::Loop(_) => None,
        }
    }

    /// The loop, if that is the stage.
    pub fn loop_mut(&mut self) -> Option<&mut LoopFine> {
        match self {
            Self::Gyro(_) => None,
            Self::Loop(l) => Some(l),
        }
    }
}

impl GyroFine {
    /// Predicts to `epoch` (gyro attitude `m` there) and updates with the block's phase
    /// differences; returns the report (its bias correction for the gyro).
    pub fn update(
        &mut self,
        epoch: u64,
        m: &Quaternion<f32>,
        blocks: &[PhaseDifferenceBlock<f32>],
        epoch_s: f32,
    ) -> Result<GyroAidedReport<f32>, GyroAidedError> {
        let mut next = self.filter.clone();
        let tau = epoch.saturating_sub(self.epoch) as f32 * epoch_s;
        next.predict(&(self.m.conjugate() * *m), tau)?;
        let report = next.update(m, blocks)?;
        self.filter = next;
        self.epoch = epoch;
        self.m = *m;
        if report.accepted > 0 {
            self.last_update = epoch;
        }
        Ok(report)
    }

    /// Standard deviation of the attitude at `epoch` (largest axis), rad.
    pub fn sigma_at(&self, epoch: u64, m: &Quaternion<f32>, epoch_s: f32) -> f32 {
        let tau = epoch.saturating_sub(self.epoch) as f32 * epoch_s;
        let p = self
            .filter
            .predicted_attitude_covariance(&(self.m.conjugate() * *m), tau);
        crate::sqrtf(p[(0, 0)].max(p[(1, 1)]).max(p[(2, 2)]).max(0.0))
    }

    /// Standard deviation of the gyro bias error, rad/s.
    pub fn bias_sigma(&self) -> Vector3<f32> {
        self.filter.bias_sigma()
    }
}
