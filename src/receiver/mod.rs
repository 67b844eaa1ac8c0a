//! The attitude receiver: every estimator of the crate tied into the one type flight software
//! uses, [`AttitudeReceiver`].
//!
//! # Data path
//!
//! ```text
//!  tracking epochs ──► prompts in noise units ──► per satellite: block sums (20 ms) ──► fine
//!  (prompts A, B, C     antenna power monitor      data-bit monitor      │    filter
//!   per satellite,                                                       ▼
//!   1 ms)                                          block counters ──► window (100 ms)
//!                                                                        │
//!        cold start (paper 002 + integers + line biases) ◄───────────────┤
//!        ambiguity upkeep, snapshot monitor (1 Hz) ◄─────────────────────┤
//!        integrity: a fresh integer fix against the fine attitude ◄──────┤
//!        baselines + velocity differences ──► rigid-body filter (000) ◄──┘
//!  gyro increments ──► propagation M(t) (paper 001) ──► fine filter's process model
//!                  └─► calibration against the fine attitude (paper 001), reported
//! ```
//!
//! * **Inputs.** [`AttitudeReceiver::push_observation`]: per satellite and 1 ms epoch, the
//!   three antennas' prompt I/Q from one replica (a [`SatelliteObservation`] in any unit with
//!   its noise variance and C/N0), from the crate's tracking channels (through
//!   [`SampleReceiver`]) or from a hardware correlator.
//!   [`AttitudeReceiver::push_gyro_increment`] / [`AttitudeReceiver::push_gyro_pulses`]: the
//!   gyro, in time order with the epochs. [`AttitudeReceiver::set_aiding`]: the lines of sight
//!   of the satellites, in the frame the attitude is wanted in, from the onboard navigation
//!   solution. A line-of-sight error `δμ` enters the single differences as `bᵀδμ`: 1e-4 rad
//!   on a 0.5 m baseline is 0.05 mm, far below the carrier-phase noise.
//! * **Output.** [`AttitudeReceiver::attitude`]: quaternion, DCM, 3-2-1 angles, the
//!   body-frame rotation-vector covariance, the [`AttitudeSource`] and [`ReceiverHealth`]
//!   (including the [`Integrity`] verdict and the estimated line biases); per-stage estimates;
//!   [`ReceiverEvent`]s ([`AttitudeReceiver::pop_event`]) for what was detected and done.
//!
//! # Stages
//!
//! 1. **Single differences** ([`satellite`]): `z_P z_A*` summed per block and window, with
//!    their covariance from the measured signal-to-noise ratios, and counters that keep whole
//!    cycles.
//! 2. **Cold start**: when at least [`ReceiverConfig::min_cold_start_satellites`] satellites
//!    have clean windows, paper 002's snapshot solver with the constrained integer ambiguity
//!    resolution fixes the integers — on double differences across satellites, so that the
//!    unknown line biases cancel — and gives the first attitude and the line biases (modulo a
//!    cycle, together with the integers), or refuses and the next window tries again.
//! 3. **Fine attitude** (`fine`): with a gyro, the gyro-aided filter
//!    ([`crate::attitude::gyro_aided`]): the gyro is the process model with its own noise,
//!    the block single differences the measurements, the gyro bias and the line biases
//!    states. Without a gyro (or with the gyro excluded), paper 003's one-stage loop on the
//!    per-epoch prompts with its line-bias states.
//! 4. **Ambiguity upkeep**: every window each fixed single difference is compared with the
//!    fine attitude's prediction (slips repaired, new satellites and returning antennas
//!    fixed) for the window-level stages.
//! 5. **Snapshot monitor** every [`ReceiverConfig::snapshot_windows`] windows, and an
//!    **integrity check** every [`ReceiverConfig::integrity_windows`] windows: a fresh integer
//!    fix, independent of the fine attitude, compared with it; a disagreement beyond their
//!    covariances raises [`ReceiverEvent::IntegrityAlarm`] and restarts the fine filter from
//!    the fix.
//! 6. **Rigid-body filter** (paper 000) on the baselines and velocity differences of the
//!    windows.
//! 7. **Gyro** ([`gyro_frame`]): propagation (paper 001 eq. (1.1)) corrected by the fine
//!    filter's bias estimate, and paper 001's sequential least-squares calibration against
//!    the fine attitude, reported and used as a cross-check. Implausible samples (above
//!    [`GyroConfig::max_rate_rad_s`]) are refused; repeated ones, or fine-filter residuals
//!    that only a wrong gyro explains, exclude the gyro until it agrees with the signals
//!    again.
//!
//! # Losing and finding the attitude
//!
//! When the attitude is lost — the gyro carried it longer than [`ReceiverConfig::max_coast_s`],
//! no update for [`ReceiverConfig::max_gap_without_gyro_s`] without a gyro, an epoch jump, or
//! an attitude too uncertain to resume from — the receiver drops its fixes, reports
//! [`ReceiverEvent::AttitudeLost`] and runs the cold start again on the next clean window.
//!
//! # Memory and time
//!
//! Fixed size (see the README's budgets); per epoch only sums and monitors, per block one
//! fine update, per window the least squares, the snapshot solver or the ambiguity search
//! (bounded by the resolver's node budget).
//!
//! # Stages out of the 1 ms path
//!
//! The epoch that closes a block or a window *captures* the satellites' sums into single
//! differences (a few hundred instructions per satellite) and *runs* the stages on them (tens
//! to hundreds of thousands of instructions on a Cortex-M4F). Inline, the default, both
//! happen inside [`AttitudeReceiver::push_observation`]. With
//! [`AttitudeReceiver::set_deferred_stages`] the epoch only captures, and the work waits
//! (with the gyro attitude at its centre) for [`AttitudeReceiver::run_deferred`], which flight
//! software calls from a lower-priority context (the main loop, an RTOS task) while the 1 ms
//! interrupt keeps feeding epochs:
//!
//! ```text
//!  1 ms interrupt: push_observation ... block ends: capture ──► waiting (≤ 1 block + 1 window)
//!  main loop:      run_deferred() ◄─────────────────────────────────┘
//! ```
//!
//! The work must run before the next block closes (20 ms later); if it still waits then, that
//! epoch runs it first and counts an overrun ([`AttitudeReceiver::deferred_overruns`]): nothing
//! is dropped. Run right after the epoch that captured it, the deferred work gives the inline
//! attitude; run later, the stages' outputs and events come that much later.

mod adapter;
#[cfg(test)]
mod adapter_tests;
mod antenna;
mod block;
mod carrier;
mod config;
mod deferred;
mod epoch;
pub mod example;
mod fine;
mod fine_loop;
pub mod gyro_frame;
mod integrity;
mod output;
pub mod samples;
pub mod satellite;
mod window;

#[cfg(test)]
mod tests;

pub use adapter::{
    observation_from_epoch, AdapterConfig, AntennaMapping, EpochClock, NoiseFloor,
    ObservationAdapter, QuadratureSign,
};
pub use config::{ConfigError, GyroConfig, LineBiasCalibration, ReceiverConfig};
pub use fine_loop::LOOP_STATES;
pub use gyro_frame::{BiasCalibrator, CalibrationReport, NoReferenceDrift};
pub use output::{
    AttitudeSource, Integrity, IntegrityCheck, LossReason, ReceiverAttitude, ReceiverEvent,
    ReceiverHealth, StageEstimate,
};
pub use samples::{ChannelStatus, SampleFrontConfig, SampleReceiver, SampleReport};
pub use satellite::SatelliteAiding;

use heapless::{Deque, Vec};
use nalgebra::{Matrix3, Vector3};

use crate::attitude::ambiguity::AmbiguityResolver;
use crate::attitude::array::AntennaArray;
use crate::attitude::one_stage::{OneStageError, SatelliteObservation};
use crate::attitude::range_model::{BaselineCorrelation, Baselines};
use crate::attitude::rigid_body::RigidBodyFilter;
use crate::attitude::snapshot::SnapshotSolver;
use crate::error::{Error, ErrorKind};
use crate::geometry::{Euler321, Quaternion};
use crate::gyro::CalibrationError;
use crate::tracking::{AcquisitionError, TrackingError};

use antenna::AntennaMonitor;
use carrier::body_baselines;
use deferred::Deferred;
use epoch::EpochBuffer;
use fine::FineStage;
use gyro_frame::{seconds, GyroFrame};
use integrity::IntegrityMonitor;
use satellite::Slot;

/// Satellites the receiver tracks at once (its slots).
pub const MAX_SATELLITES: usize = 12;

/// Events kept until read.
pub const EVENT_QUEUE: usize = 32;

/// Error returned by the operations of [`AttitudeReceiver`] and [`SampleReceiver`]; the
/// receiver is then unchanged.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ReceiverError {
    /// An input (observation, line of sight, gyro increment) was NaN or infinite.
    #[error("non-finite receiver input")]
    NonFinite,
    /// The configuration was refused: the field at fault or the stage that refused it.
    #[error("invalid receiver configuration")]
    InvalidConfig(#[from] ConfigError),
    /// An input is finite but unusable: a line of sight that is not a unit vector, a noise
    /// variance that is not positive, a C/N0 outside 0..=90 dB-Hz.
    #[error("receiver input out of range")]
    InvalidInput,
    /// A gyro sample arrived, but the configuration has no gyro.
    #[error("no gyro configured")]
    NoGyro,
    /// The gyro stage refused a sample (non-finite, above one radian per sample, pulses
    /// without a pulse weight).
    #[error("gyro sample refused")]
    Gyro(#[source] CalibrationError),
    /// An observation arrived for a satellite without navigation aiding (no line of sight):
    /// call [`AttitudeReceiver::set_aiding`] first.
    #[error("no line of sight for this satellite")]
    NoAiding,
    /// More satellites than the receiver has slots for.
    #[error("no free satellite slot")]
    TooManySatellites,
    /// An observation arrived for an epoch the receiver has already closed.
    #[error("observation for an epoch already closed")]
    StaleEpoch,
    /// An epoch number so large that the receiver's epoch arithmetic could overflow (within
    /// a few windows of `u64::MAX`).
    #[error("epoch number out of range")]
    EpochOutOfRange,
    /// The observation adapter refused a tracking epoch.
    #[error("observation adapter refused")]
    Adapter(#[source] OneStageError),
    /// A software tracking channel refused a hand-over or a sample block.
    #[error("tracking channel refused")]
    Tracking(#[from] TrackingError),
    /// The acquisition engine refused a search (too few samples, bad configuration).
    #[error("acquisition refused")]
    Acquisition(#[from] AcquisitionError),
}

impl Error for ReceiverError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::InvalidConfig(e) => e.kind(),
            Self::Gyro(e) => e.kind(),
            Self::Adapter(e) => e.kind(),
            Self::Tracking(e) => e.kind(),
            Self::Acquisition(e) => e.kind(),
            Self::InvalidInput
            | Self::NoGyro
            | Self::NoAiding
            | Self::TooManySatellites
            | Self::StaleEpoch
            | Self::EpochOutOfRange => ErrorKind::InvalidInput,
        }
    }
}

/// The antenna array in body axes: positions, and the baselines `A→B`, `A→C`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct ArrayGeometry {
    antennas: [Vector3<f32>; 3],
    baselines: [Vector3<f32>; 2],
}

/// The window-level solvers (built once from the array).
#[derive(Clone, Debug)]
struct Solvers {
    resolver: AmbiguityResolver<2, f32>,
    snapshot: SnapshotSolver<2, f32>,
}

/// The latest snapshot solution and the gyro's attitude at its epoch.
#[derive(Clone, Copy, Debug, PartialEq)]
struct SnapshotFix {
    estimate: StageEstimate,
    m: Quaternion<f32>,
}

/// The rigid-body filter (paper 000) and its last step.
#[derive(Clone, Debug, Default)]
struct RigidStage {
    filter: Option<RigidBodyFilter<f32>>,
    estimate: Option<StageEstimate>,
    last_step: u64,
}

/// The line biases the window-level stages remove: the cold start's, then the fine filter's.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
struct LineBias {
    rad: [f32; 2],
    sigma_rad: [f32; 2],
    known: bool,
}

impl LineBias {
    /// Resolved biases and σ in cycles, as radians.
    fn from_cycles(bias: [f32; 2], sigma: [f32; 2]) -> Self {
        let tau = core::f32::consts::TAU;
        Self {
            rad: bias.map(|b| crate::geometry::wrap_angle(b * tau)),
            sigma_rad: sigma.map(|s| s * tau),
            known: true,
        }
    }
}

/// The event queue: the oldest event is dropped (and counted) when it is full.
#[derive(Clone, Debug, Default)]
struct Events {
    queue: Deque<ReceiverEvent, EVENT_QUEUE>,
    dropped: u32,
}

impl Events {
    fn push(&mut self, e: ReceiverEvent) {
        if let Err(e) = self.queue.push_back(e) {
            // full: the oldest goes, the newest stays
            let _oldest = self.queue.pop_front();
            self.dropped = self.dropped.saturating_add(1);
            if self.queue.push_back(e).is_err() {
                self.dropped = self.dropped.saturating_add(1);
            }
        }
    }
}

/// The attitude receiver: tracking epochs in, attitude with covariance and health out.
///
/// See the [module documentation](self) for the data path. Fixed memory, no allocation, no
/// panics; every input is validated and a refused input leaves the receiver unchanged.
#[derive(Clone, Debug)]
pub struct AttitudeReceiver {
    config: ReceiverConfig,
    geometry: ArrayGeometry,
    slots: Vec<Slot, MAX_SATELLITES>,
    epochs: EpochBuffer,
    solvers: Solvers,
    /// The cold start has fixed the integers.
    fixed: bool,
    fine: Option<FineStage>,
    snapshot: Option<SnapshotFix>,
    rigid: RigidStage,
    gyro: Option<GyroFrame>,
    monitor: AntennaMonitor,
    integrity: IntegrityMonitor,
    line_bias: LineBias,
    events: Events,
    health: ReceiverHealth,
    /// Windows closed.
    windows: u64,
    /// Block and window work captured and waiting, in deferred mode.
    deferred: Deferred,
    /// The epoch in whole nanoseconds (the 1 ms path's integer clock).
    epoch_ns: u64,
}

impl AttitudeReceiver {
    /// A receiver with no satellites, no fix.
    ///
    /// # Errors
    /// [`ReceiverError::InvalidConfig`] with the field or the stage that refused it.
    pub fn new(config: ReceiverConfig) -> Result<Self, ReceiverError> {
        config.validate()?;
        let antennas = config.antenna_positions();
        AntennaArray::new(antennas).map_err(ConfigError::from)?;
        let baselines = body_baselines(&antennas);
        let b = Baselines::new(baselines).map_err(ConfigError::from)?;
        let snapshot = SnapshotSolver::new(b, BaselineCorrelation::shared_base_antenna());
        let resolver =
            AmbiguityResolver::new(snapshot, config.ambiguity).map_err(ConfigError::from)?;
        if !config.fine.is_valid() || config.fine.state_dimension() != LOOP_STATES {
            return Err(ConfigError::Fine(OneStageError::InvalidConfig).into());
        }
        let gyro = match config.gyro {
            Some(g) => Some(GyroFrame::new(g).map_err(ConfigError::from)?),
            None => None,
        };
        let line_bias = config
            .line_bias
            .map_or_else(LineBias::default, |c| LineBias {
                rad: c.rad,
                sigma_rad: [c.sigma_rad; 2],
                known: true,
            });
        Ok(Self {
            config,
            geometry: ArrayGeometry {
                antennas,
                baselines,
            },
            slots: Vec::new(),
            epochs: EpochBuffer::new(config.window_epochs),
            solvers: Solvers { resolver, snapshot },
            fixed: false,
            fine: None,
            snapshot: None,
            rigid: RigidStage::default(),
            gyro,
            monitor: AntennaMonitor::default(),
            integrity: IntegrityMonitor::new(),
            line_bias,
            events: Events::default(),
            health: ReceiverHealth::default(),
            windows: 0,
            deferred: Deferred::default(),
            epoch_ns: gyro_frame::nanoseconds(config.epoch_s),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &ReceiverConfig {
        &self.config
    }

    // ---------------------------------------------------------------- inputs

    /// Replaces the navigation aiding: the satellites listed get (or keep) a slot with the
    /// new line of sight; slots of satellites no longer listed are released
    /// ([`ReceiverEvent::SatelliteLost`] if they had observations).
    ///
    /// # Errors
    /// [`ReceiverError::NonFinite`], [`ReceiverError::InvalidInput`] (a line of sight that is
    /// not a unit vector to 1e-3), [`ReceiverError::TooManySatellites`] (more than
    /// [`MAX_SATELLITES`]); the receiver is then unchanged.
    pub fn set_aiding(&mut self, aiding: &[SatelliteAiding]) -> Result<(), ReceiverError> {
        if aiding.len() > MAX_SATELLITES {
            return Err(ReceiverError::TooManySatellites);
        }
        for a in aiding {
            if !a.los.iter().chain(a.los_rate.iter()).all(|v| v.is_finite()) {
                return Err(ReceiverError::NonFinite);
            }
            if !((Vector3::from(a.los).norm() - 1.0).abs() <= 1e-3) {
                return Err(ReceiverError::InvalidInput);
            }
        }
        let epoch = self.epochs.last_closed().unwrap_or(0);
        let mut slots = Vec::<Slot, MAX_SATELLITES>::new();
        for a in aiding {
            let mut slot = match self.slots.iter().find(|s| s.aiding.prn == a.prn) {
                Some(s) => *s,
                None => Slot::new(*a),
            };
            slot.aiding = *a;
            // (at most MAX_SATELLITES aidings, checked above: the push cannot fail)
            slots
                .push(slot)
                .map_err(|_| ReceiverError::TooManySatellites)?;
        }
        let released = core::mem::replace(&mut self.slots, slots);
        for s in released.iter() {
            if s.last_epoch.is_some() && !aiding.iter().any(|a| a.prn == s.aiding.prn) {
                self.events.push(ReceiverEvent::SatelliteLost {
                    epoch,
                    prn: s.aiding.prn,
                });
            }
        }
        Ok(())
    }

    /// One gyro increment (rad, gyro = body axes) over the configured sample interval. The
    /// increments must arrive in time order with the epochs: the increment covering
    /// `[t − h, t]` before the observations of the epoch starting at `t`.
    ///
    /// An increment above [`GyroConfig::max_rate_rad_s`] is a fault, not motion: it is
    /// counted ([`ReceiverHealth::gyro_faults`]) and replaced by the last good rate, and the
    /// fine filter is told the gyro can no longer be trusted for that sample.
    ///
    /// # Errors
    /// [`ReceiverError::NoGyro`] without a gyro; [`ReceiverError::NonFinite`];
    /// [`ReceiverError::Gyro`] (above one radian). Unchanged on error.
    pub fn push_gyro_increment(&mut self, theta: &[f32; 3]) -> Result<(), ReceiverError> {
        let gyro = self.gyro.as_mut().ok_or(ReceiverError::NoGyro)?;
        let mut g = gyro.clone();
        let plausible = g.push(&Vector3::from(*theta))?;
        *gyro = g;
        self.after_gyro_sample(plausible);
        Ok(())
    }

    /// One gyro sample as pulse counts (signed, per axis) of the configured pulse weight.
    ///
    /// # Errors
    /// As [`Self::push_gyro_increment`]; [`ReceiverError::Gyro`] when the gyro has no pulse
    /// weight.
    pub fn push_gyro_pulses(&mut self, counts: [i32; 3]) -> Result<(), ReceiverError> {
        let gyro = self.gyro.as_mut().ok_or(ReceiverError::NoGyro)?;
        let mut g = gyro.clone();
        let theta = g.decode(counts)?;
        let plausible = g.push(&theta)?;
        *gyro = g;
        self.after_gyro_sample(plausible);
        Ok(())
    }

    /// One satellite's observation of `epoch` (prompts of A, B, C; noise variance; C/N0). Its
    /// line of sight is taken from the aiding (the `los` field is ignored). Epochs are closed
    /// (and the stages stepped) when an observation two epochs later arrives, or by
    /// [`Self::close_through`].
    ///
    /// # Errors
    /// [`ReceiverError::NoAiding`] for a satellite without aiding; [`ReceiverError::StaleEpoch`]
    /// for an epoch already closed; [`ReceiverError::EpochOutOfRange`] near `u64::MAX`;
    /// [`ReceiverError::NonFinite`] / [`ReceiverError::InvalidInput`] for unusable prompts,
    /// noise or C/N0. Unchanged on error.
    pub fn push_observation(
        &mut self,
        epoch: u64,
        observation: &SatelliteObservation<f32>,
    ) -> Result<(), ReceiverError> {
        epoch::check_observation(observation)?;
        if !self.slots.iter().any(|s| s.aiding.prn == observation.id) {
            return Err(ReceiverError::NoAiding);
        }
        let due = self.epochs.admit(epoch)?;
        if let Some(through) = due {
            self.close_through(through);
        }
        self.epochs.insert(epoch, observation)
    }

    /// Closes every open epoch up to and including `epoch`: steps the stages. Epochs without
    /// observations are stepped too (the fine filter predicts). A jump of more than a window
    /// skips the empty epochs in between; a jump longer than the coast limit loses the
    /// attitude ([`LossReason::EpochJump`]). An epoch beyond the last one
    /// [`Self::push_observation`] accepts (within 2⁴⁰ of `u64::MAX`) closes through that one:
    /// a closed epoch is never opened again.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub fn close_through(&mut self, epoch: u64) {
        let Some(limit) = self.epochs.plan_close(epoch) else {
            return;
        };
        while let Some((k, observations)) = self.epochs.next_to_close(limit) {
            self.close_epoch(k, &observations);
        }
        if let Some(skipped) = self.epochs.skip_to(epoch) {
            self.after_jump(epoch, skipped);
        }
    }

    // ---------------------------------------------------------------- outputs

    /// The attitude now: the fine filter's while it updates, the gyro carrying it (with the
    /// covariance grown by the gyro's noise) while it has no input, else the latest snapshot
    /// carried by the gyro, else none ([`AttitudeSource::None`], identity, zero covariance).
    pub fn attitude(&self) -> ReceiverAttitude {
        let epoch = self.epochs.last_closed().unwrap_or(0);
        let (q, covariance, source) = self.best_attitude(epoch);
        ReceiverAttitude {
            epoch,
            q_rb: q,
            c_rb: q.to_dcm(),
            euler: Euler321::from_quaternion(&q).unwrap_or_default(),
            covariance,
            source,
            health: self.health,
        }
    }

    /// The fine filter's estimate now (whatever its state), `None` before the first fix.
    pub fn fine_estimate(&self) -> Option<StageEstimate> {
        let epoch = self.epochs.last_closed().unwrap_or(0);
        let m = self.gyro_attitude(epoch);
        let f = self.fine.as_ref()?;
        Some(StageEstimate {
            epoch,
            q_rb: f.attitude(&m),
            covariance: f.covariance_at(epoch, &m, &self.config),
        })
    }

    /// The latest snapshot solution (at its window's centre epoch).
    pub fn snapshot_estimate(&self) -> Option<StageEstimate> {
        self.snapshot.map(|s| s.estimate)
    }

    /// The rigid-body filter's latest estimate (at its window's end).
    pub fn rigid_body_estimate(&self) -> Option<StageEstimate> {
        self.rigid.estimate
    }

    /// The gyro bias correction applied, rad/s (gyro axes); zero without a gyro.
    pub fn gyro_bias(&self) -> [f32; 3] {
        self.gyro
            .as_ref()
            .map_or([0.0; 3], |g| [g.bias.x, g.bias.y, g.bias.z])
    }

    /// Standard deviation of the fine filter's gyro bias estimate, rad/s (gyro axes); `None`
    /// without the gyro-aided filter.
    pub fn gyro_bias_sigma(&self) -> Option<[f32; 3]> {
        match &self.fine {
            Some(FineStage::Gyro(g)) => {
                let s = g.bias_sigma();
                Some([s.x, s.y, s.z])
            }
            _ => None,
        }
    }

    /// What the gyro calibration (paper 001) has given (`None` without a gyro).
    pub fn gyro_calibration(&self) -> Option<CalibrationReport> {
        self.gyro.as_ref().map(|g| g.report)
    }

    /// The last integrity check (a fresh integer fix against the fine attitude).
    pub fn last_integrity_check(&self) -> Option<IntegrityCheck> {
        self.integrity.last_check
    }

    /// Health flags.
    pub fn health(&self) -> ReceiverHealth {
        self.health
    }

    /// The oldest unread event.
    pub fn pop_event(&mut self) -> Option<ReceiverEvent> {
        self.events.queue.pop_front()
    }

    /// Events dropped because the queue was full.
    pub fn events_dropped(&self) -> u32 {
        self.events.dropped
    }

    /// The last closed epoch.
    pub fn epoch(&self) -> Option<u64> {
        self.epochs.last_closed()
    }

    // ---------------------------------------------------------------- shared internals

    /// `M(t)` at the centre of `epoch` (identity without a gyro, or with it excluded).
    fn gyro_attitude(&self, epoch: u64) -> Quaternion<f32> {
        let t = (epoch as f64 + 0.5) * seconds(self.config.epoch_s);
        match &self.gyro {
            Some(g) if !self.health.gyro_excluded => g.attitude_at(t),
            _ => Quaternion::identity(),
        }
    }

    /// Whether any antenna is declared blocked.
    fn any_blocked(&self) -> bool {
        self.health.antenna_blocked.iter().any(|&b| b)
    }

    /// The best attitude at `epoch`: fine (fresh), coasting, snapshot, or none.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    fn best_attitude(&self, epoch: u64) -> (Quaternion<f32>, Matrix3<f32>, AttitudeSource) {
        let m = self.gyro_attitude(epoch);
        if let Some(f) = &self.fine {
            if let Some(source) = f.source_at(epoch, &self.config) {
                let cov = f.covariance_at(epoch, &m, &self.config) * self.integrity.inflation();
                return (f.attitude(&m), cov, source);
            }
        }
        if let Some(s) = &self.snapshot {
            let age = epoch.saturating_sub(s.estimate.epoch) as f32 * self.config.epoch_s;
            let max_age = 2.0 * self.config.window_s() * self.config.snapshot_windows as f32;
            if age <= max_age {
                // C_rb(t) = C_rb(t_s) M(t_s)ᵀ M(t)
                let q = s.estimate.q_rb * s.m.conjugate() * m;
                return (
                    q.normalize().unwrap_or(q),
                    s.estimate.covariance,
                    AttitudeSource::Snapshot,
                );
            }
        }
        (
            Quaternion::identity(),
            Matrix3::zeros(),
            AttitudeSource::None,
        )
    }
}
