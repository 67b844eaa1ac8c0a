//! [`AttitudeReceiver`]: the stages put together, epoch by epoch.

use heapless::{Deque, Vec};
use nalgebra::{Complex, Matrix3, Vector3};

use crate::attitude::ambiguity::AmbiguityResolver;
use crate::attitude::array::AntennaArray;
use crate::attitude::one_stage::{LockStatus, SatelliteObservation};
use crate::attitude::range_model::{BaselineCorrelation, Baselines};
use crate::attitude::rigid_body::RigidBodyFilter;
use crate::attitude::snapshot::SnapshotSolver;
use crate::geometry::{Euler321, Quaternion};

use super::antenna::AntennaMonitor;
use super::carrier::body_baselines;
use super::config::ConfigError;
use super::config::ReceiverConfig;
use super::fine::FineStage;
use super::gyro_frame::{seconds, CalibrationReport, GyroFrame};
use super::output::{
    AttitudeSource, ReceiverAttitude, ReceiverEvent, ReceiverHealth, StageEstimate,
};
use super::satellite::{SatelliteAiding, Slot};
use super::MAX_SATELLITES;
use crate::attitude::one_stage::OneStageError;
use crate::error::{Error, ErrorKind};
use crate::gyro::CalibrationError;
use crate::tracking::{AcquisitionError, TrackingError};

/// Events kept until read.
pub const EVENT_QUEUE: usize = 32;

/// Where a coast on the gyro starts: the last locked fine attitude.
#[derive(Clone, Copy, Debug)]
pub(super) struct Coast {
    pub(super) epoch: u64,
    pub(super) q_rb: Quaternion<f32>,
    pub(super) covariance: Matrix3<f32>,
    pub(super) m: Quaternion<f32>,
}

/// The observations of one epoch.
#[derive(Clone, Debug, Default)]
struct Bucket {
    epoch: u64,
    observations: Vec<SatelliteObservation<f32>, MAX_SATELLITES>,
}

/// The attitude receiver: tracking epochs in, attitude with covariance and health out.
///
/// See the [module documentation](super) for the data path. Fixed memory (7 224 B on the
/// Cortex-M4F), no allocation, no panics; every input is validated and a refused input leaves
/// the receiver unchanged.
#[derive(Clone, Debug)]
pub struct AttitudeReceiver {
    pub(super) config: ReceiverConfig,
    pub(super) antennas: [Vector3<f32>; 3],
    pub(super) baselines: [Vector3<f32>; 2],
    pub(super) slots: Vec<Slot, MAX_SATELLITES>,
    /// The oldest open epoch; epochs `open` and `open + 1` are buffered.
    pub(super) open: u64,
    pub(super) started: bool,
    buckets: [Bucket; 2],
    /// The last closed epoch.
    pub(super) closed: Option<u64>,
    pub(super) resolver: AmbiguityResolver<2, f32>,
    pub(super) solver: SnapshotSolver<2, f32>,
    pub(super) fixed: bool,
    pub(super) fine: Option<FineStage>,
    /// Latest snapshot and the gyro attitude at its epoch.
    pub(super) snapshot: Option<(StageEstimate, Quaternion<f32>)>,
    pub(super) rigid: Option<RigidBodyFilter<f32>>,
    pub(super) rigid_estimate: Option<StageEstimate>,
    /// Epoch of the rigid-body filter's last step.
    pub(super) rigid_last: u64,
    pub(super) gyro: Option<GyroFrame>,
    pub(super) monitor: AntennaMonitor,
    pub(super) events: Deque<ReceiverEvent, EVENT_QUEUE>,
    pub(super) events_dropped: u32,
    pub(super) health: ReceiverHealth,
    pub(super) windows: u64,
    /// The fine attitude's covariance when it last updated (start of a coast).
    /// The last locked fine attitude: epoch, `q_rb`, covariance, and the gyro's `M` then.
    pub(super) coast_start: Option<Coast>,
}

impl AttitudeReceiver {
    /// A receiver with no satellites, no fix.
    ///
    /// # Errors
    /// [`ReceiverError::InvalidConfig`] / [`ReceiverError::NonFinite`] for a configuration
    /// that the receiver or one of its stages refuses (degenerate array, bad noise levels,
    /// a window that is not a whole number of gyro steps).
    pub fn new(config: ReceiverConfig) -> Result<Self, ReceiverError> {
        config.validate()?;
        let antennas = config.antenna_positions();
        AntennaArray::new(antennas).map_err(ConfigError::from)?;
        let baselines = body_baselines(&antennas);
        let b = Baselines::new(baselines).map_err(ConfigError::from)?;
        let solver = SnapshotSolver::new(b, BaselineCorrelation::shared_base_antenna());
        let resolver =
            AmbiguityResolver::new(solver, config.ambiguity).map_err(ConfigError::from)?;
        // the stages that check their own configuration later are checked now
        if !config.fine.is_valid() {
            return Err(ConfigError::Fine(OneStageError::InvalidConfig).into());
        }
        let gyro = match config.gyro {
            Some(g) => Some(GyroFrame::new(g).map_err(ConfigError::from)?),
            None => None,
        };
        Ok(Self {
            config,
            antennas,
            baselines,
            slots: Vec::new(),
            open: 0,
            started: false,
            buckets: [Bucket::default(), Bucket::default()],
            closed: None,
            resolver,
            solver,
            fixed: false,
            fine: None,
            snapshot: None,
            rigid: None,
            rigid_estimate: None,
            rigid_last: 0,
            gyro,
            monitor: AntennaMonitor::default(),
            events: Deque::new(),
            events_dropped: 0,
            health: ReceiverHealth::default(),
            windows: 0,
            coast_start: None,
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
        let epoch = self.closed.unwrap_or(0);
        let mut lost = Vec::<u8, MAX_SATELLITES>::new();
        let mut slots = Vec::<Slot, MAX_SATELLITES>::new();
        for a in aiding {
            let slot = match self.slots.iter().find(|s| s.aiding.prn == a.prn) {
                Some(s) => {
                    let mut s = *s;
                    s.aiding = *a;
                    s
                }
                None => Slot::new(*a),
            };
            slots
                .push(slot)
                .map_err(|_| ReceiverError::TooManySatellites)?;
        }
        for s in &self.slots {
            if s.last_epoch.is_some() && !aiding.iter().any(|a| a.prn == s.aiding.prn) {
                let _ = lost.push(s.aiding.prn);
            }
        }
        self.slots = slots;
        // (by reference: a by-value heapless iterator keeps a bounds check in its drop)
        for &prn in lost.iter() {
            self.event(ReceiverEvent::SatelliteLost { epoch, prn });
        }
        Ok(())
    }

    /// One gyro increment (rad, gyro = body axes) over the configured sample interval. The
    /// increments must arrive in time order with the epochs: the increment covering
    /// `[t − h, t]` before the observations of the epoch starting at `t`.
    ///
    /// # Errors
    /// [`ReceiverError::InvalidConfig`] without a gyro; [`ReceiverError::NonFinite`],
    /// [`ReceiverError::InvalidInput`] (above one radian). Unchanged on error.
    pub fn push_gyro_increment(&mut self, theta: &[f32; 3]) -> Result<(), ReceiverError> {
        let gyro = self.gyro.as_mut().ok_or(ReceiverError::NoGyro)?;
        gyro.push(&Vector3::from(*theta))?;
        self.after_gyro_sample();
        Ok(())
    }

    /// One gyro sample as pulse counts (signed, per axis) of the configured pulse weight.
    ///
    /// # Errors
    /// As [`Self::push_gyro_increment`]; [`ReceiverError::InvalidInput`] when the gyro has no
    /// pulse weight.
    pub fn push_gyro_pulses(&mut self, counts: [i32; 3]) -> Result<(), ReceiverError> {
        let gyro = self.gyro.as_mut().ok_or(ReceiverError::NoGyro)?;
        let mut g = gyro.clone();
        let theta = g.decode(counts)?;
        g.push(&theta)?;
        *gyro = g;
        self.after_gyro_sample();
        Ok(())
    }

    /// One satellite's observation of `epoch` (prompts of A, B, C; noise variance; C/N0). Its
    /// line of sight is taken from the aiding (the `los` field is ignored). Epochs are closed
    /// (and the stages stepped) when an observation two epochs later arrives, or by
    /// [`Self::close_through`].
    ///
    /// # Errors
    /// [`ReceiverError::NoAiding`] for a satellite without aiding; [`ReceiverError::StaleEpoch`]
    /// for an epoch already closed; [`ReceiverError::NonFinite`] / [`ReceiverError::InvalidInput`]
    /// for unusable prompts, noise or C/N0. Unchanged on error.
    pub fn push_observation(
        &mut self,
        epoch: u64,
        observation: &SatelliteObservation<f32>,
    ) -> Result<(), ReceiverError> {
        let o = observation;
        if !o
            .prompt
            .i
            .iter()
            .chain(o.prompt.q.iter())
            .all(|v| v.is_finite())
            || !o.noise_var.is_finite()
            || !o.cn0_dbhz.is_finite()
        {
            return Err(ReceiverError::NonFinite);
        }
        if !(o.noise_var > 0.0) || !(0.0..=90.0).contains(&o.cn0_dbhz) {
            return Err(ReceiverError::InvalidInput);
        }
        let Some(slot) = self.slots.iter().find(|s| s.aiding.prn == o.id) else {
            return Err(ReceiverError::NoAiding);
        };
        let los = slot.los_at(epoch, self.config.epoch_s);
        if !self.started {
            self.started = true;
            self.open = epoch;
            self.reset_buckets(epoch);
        }
        if epoch < self.open {
            return Err(ReceiverError::StaleEpoch);
        }
        if epoch > self.open + 1 {
            self.close_through(epoch - 2);
        }
        let mut obs = *o;
        obs.los = [los.x, los.y, los.z];
        let Some(bucket) = self.buckets.get_mut((epoch % 2) as usize) else {
            return Err(ReceiverError::StaleEpoch);
        };
        bucket.epoch = epoch;
        if let Some(existing) = bucket.observations.iter_mut().find(|b| b.id == obs.id) {
            *existing = obs;
        } else {
            bucket
                .observations
                .push(obs)
                .map_err(|_| ReceiverError::TooManySatellites)?;
        }
        Ok(())
    }

    /// Closes every open epoch up to and including `epoch`: steps the stages. Epochs without
    /// observations are stepped too (the fine filter predicts).
    pub fn close_through(&mut self, epoch: u64) {
        if !self.started {
            return;
        }
        // bound: at most two buffered epochs plus the empty ones in between, capped at one
        // window per call so that a huge jump cannot stall the caller
        let limit = epoch.min(self.open + u64::from(self.config.window_epochs));
        while self.open <= limit {
            let k = self.open;
            let slot = self.buckets.get_mut((k % 2) as usize);
            let bucket = slot.map(core::mem::take).unwrap_or_default();
            let observations = if bucket.epoch == k {
                bucket.observations
            } else {
                Vec::new()
            };
            self.close_epoch(k, &observations);
            if let Some(b) = self.buckets.get_mut((k % 2) as usize) {
                *b = Bucket {
                    epoch: k + 2,
                    observations: Vec::new(),
                };
            }
            self.open = k + 1;
        }
        if epoch >= self.open {
            // the jump was larger than a window: skip the empty epochs in between
            self.open = epoch + 1;
            self.reset_buckets(self.open);
        }
    }

    // ---------------------------------------------------------------- outputs

    /// The attitude now: the fine filter's when it is locked, else the gyro carrying the last
    /// fine attitude (for at most [`ReceiverConfig::max_coast_s`]), else the latest snapshot
    /// carried by the gyro, else none ([`AttitudeSource::None`], identity, zero covariance).
    pub fn attitude(&self) -> ReceiverAttitude {
        let epoch = self.closed.unwrap_or(0);
        let m = self.gyro_attitude(epoch);
        let (q, cov, source) = self.best_attitude(epoch, &m);
        let c = q.to_dcm();
        ReceiverAttitude {
            epoch,
            q_rb: q,
            c_rb: c,
            euler: Euler321::from_quaternion(&q).unwrap_or_default(),
            covariance: cov,
            source,
            health: self.health,
        }
    }

    /// The fine filter's estimate (whatever its lock status), `None` before the first fix.
    pub fn fine_estimate(&self) -> Option<(StageEstimate, LockStatus)> {
        let f = self.fine.as_ref()?;
        let epoch = self.closed.unwrap_or(0);
        let m = self.gyro_attitude(epoch);
        Some((
            StageEstimate {
                epoch,
                q_rb: f.attitude(&m),
                covariance: f.covariance(),
            },
            f.lock(),
        ))
    }

    /// The latest snapshot solution (at its window's centre epoch).
    pub fn snapshot_estimate(&self) -> Option<StageEstimate> {
        self.snapshot.map(|(s, _)| s)
    }

    /// The rigid-body filter's latest estimate (at its window's end).
    pub fn rigid_body_estimate(&self) -> Option<StageEstimate> {
        self.rigid_estimate
    }

    /// The gyro bias correction applied, rad/s (gyro axes); zero without calibration.
    pub fn gyro_bias(&self) -> [f32; 3] {
        self.gyro
            .as_ref()
            .map_or([0.0; 3], |g| [g.bias.x, g.bias.y, g.bias.z])
    }

    /// What the gyro calibration has given (`None` without a gyro).
    pub fn gyro_calibration(&self) -> Option<CalibrationReport> {
        self.gyro.as_ref().map(|g| g.report)
    }

    /// Health flags.
    pub fn health(&self) -> ReceiverHealth {
        self.health
    }

    /// The oldest unread event.
    pub fn pop_event(&mut self) -> Option<ReceiverEvent> {
        self.events.pop_front()
    }

    /// Events dropped because the queue was full.
    pub fn events_dropped(&self) -> u32 {
        self.events_dropped
    }

    /// The last closed epoch.
    pub fn epoch(&self) -> Option<u64> {
        self.closed
    }

    // ---------------------------------------------------------------- internals

    /// Empty buckets for epochs `first` and `first + 1`.
    pub(super) fn reset_buckets(&mut self, first: u64) {
        for (i, b) in self.buckets.iter_mut().enumerate() {
            *b = Bucket::default();
            // the bucket of epoch e is e % 2
            b.epoch = if (first % 2) as usize == i {
                first
            } else {
                first + 1
            };
        }
    }

    pub(super) fn event(&mut self, e: ReceiverEvent) {
        if self.events.is_full() {
            let _ = self.events.pop_front();
            self.events_dropped = self.events_dropped.saturating_add(1);
        }
        let _ = self.events.push_back(e);
    }

    /// `M(t)` at the centre of `epoch` (identity without a gyro).
    pub(super) fn gyro_attitude(&self, epoch: u64) -> Quaternion<f32> {
        let t = (epoch as f64 + 0.5) * seconds(self.config.epoch_s);
        self.gyro
            .as_ref()
            .map_or_else(Quaternion::identity, |g| g.attitude_at(t))
    }

    pub(super) fn best_attitude(
        &self,
        epoch: u64,
        m: &Quaternion<f32>,
    ) -> (Quaternion<f32>, Matrix3<f32>, AttitudeSource) {
        if let Some(f) = &self.fine {
            let fresh = epoch.saturating_sub(f.last_update) <= 2;
            if f.lock() == LockStatus::Locked && fresh && !self.any_blocked() {
                return (f.attitude(m), f.covariance(), AttitudeSource::OneStage);
            }
            if let (Some(c0), Some(g)) = (self.coast_start, &self.gyro) {
                let dt = epoch.saturating_sub(c0.epoch) as f32 * self.config.epoch_s;
                if dt <= self.config.max_coast_s {
                    let c = &g.config;
                    let grow = c.angle_random_walk * c.angle_random_walk * dt
                        + c.residual_rate_sigma * c.residual_rate_sigma * dt * dt;
                    // the body's rotation since then, from the gyro: C_rb(t) = C_rb(t₀) M(t₀)ᵀ M(t)
                    let q = c0.q_rb * c0.m.conjugate() * *m;
                    return (
                        q.normalize().unwrap_or(q),
                        c0.covariance + Matrix3::identity() * grow,
                        AttitudeSource::GyroCoast,
                    );
                }
            }
        }
        if let Some((s, m_s)) = &self.snapshot {
            let age = epoch.saturating_sub(s.epoch) as f32 * self.config.epoch_s;
            if age <= 2.0 * self.config.window_s() * self.config.snapshot_windows as f32 {
                // C_rb(t) = C_rb(t_s) M(t_s)ᵀ M(t)
                let q = s.q_rb * m_s.conjugate() * *m;
                return (
                    q.normalize().unwrap_or(q),
                    s.covariance,
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

    pub(super) fn any_blocked(&self) -> bool {
        self.health.antenna_blocked.iter().any(|&b| b)
    }

    pub(super) fn after_gyro_sample(&mut self) {
        let Some(g) = self.gyro.as_ref() else {
            return;
        };
        self.health.gyro_running = true;
        if !g.at_step() {
            return;
        }
        // references for the calibration at the window boundaries, from the locked fine
        // attitude
        let t = g.time_s();
        // samples per window: a whole number of steps (checked by the configuration)
        let per_window =
            libm::round(seconds(self.config.window_s()) / seconds(g.config.sample_interval_s));
        if !(per_window >= 1.0) || g.samples().checked_rem(per_window as u64) != Some(0) {
            return;
        }
        let Some(f) = &self.fine else {
            return;
        };
        if f.lock() != LockStatus::Locked || self.any_blocked() {
            return;
        }
        let m = g.attitude_at(t);
        let q = f.attitude(&m);
        let epoch = self.closed.unwrap_or(0);
        let Some(g) = self.gyro.as_mut() else {
            return;
        };
        if !g.calibrating() {
            g.start_calibration(&q);
        } else if g.add_reference(&q) {
            self.health.gyro_calibrated = true;
            self.event(ReceiverEvent::GyroCalibrated { epoch });
        }
    }

    /// Steps everything for epoch `k` with its observations.
    pub(super) fn close_epoch(&mut self, k: u64, observations: &[SatelliteObservation<f32>]) {
        let cfg = self.config;
        let m = self.gyro_attitude(k);
        // prompts in noise units with the line biases removed
        let rot = |b: f32| Complex::new(libm::cosf(b), -libm::sinf(b));
        let (rb, rc) = (rot(cfg.line_bias_rad[0]), rot(cfg.line_bias_rad[1]));
        let mut fine_obs = Vec::<SatelliteObservation<f32>, MAX_SATELLITES>::new();
        let mut powers = [0.0f32; 3];
        let mut n_obs = 0u8;
        for o in observations {
            let [za, zb, zc] = o.prompt.normalized(libm::sqrtf(o.noise_var));
            let z = [za, zb * rb, zc * rc];
            for (p, zp) in powers.iter_mut().zip(z.iter()) {
                *p += zp.norm_sqr() - 2.0;
            }
            n_obs += 1;
            let blocked = self.health.antenna_blocked;
            let Some(slot) = self.slots.iter_mut().find(|s| s.aiding.prn == o.id) else {
                continue;
            };
            let first = slot.last_epoch.is_none();
            let anomaly =
                slot.add_epoch(k, &z, o.cn0_dbhz, cfg.epoch_s, cfg.window_epochs, &blocked);
            if first {
                self.event(ReceiverEvent::SatelliteAcquired {
                    epoch: k,
                    prn: o.id,
                });
            }
            if anomaly {
                self.event(ReceiverEvent::BitAnomaly {
                    epoch: k,
                    prn: o.id,
                });
            }
            let mut f = *o;
            f.prompt.i = z.map(|c| c.re);
            f.prompt.q = z.map(|c| c.im);
            f.noise_var = 1.0;
            let _ = fine_obs.push(f);
        }
        // antennas
        if n_obs > 0 {
            for (antenna, blocked) in self.monitor.update(&powers, cfg.blocked_power_ratio) {
                let was = self
                    .health
                    .antenna_blocked
                    .get(antenna)
                    .copied()
                    .unwrap_or(false);
                if let Some(b) = self.health.antenna_blocked.get_mut(antenna) {
                    *b = blocked;
                }
                if blocked && !was {
                    for s in self.slots.iter_mut() {
                        s.invalidate(antenna);
                    }
                    self.event(ReceiverEvent::AntennaBlocked {
                        epoch: k,
                        antenna: antenna as u8,
                    });
                } else if !blocked && was {
                    self.event(ReceiverEvent::AntennaRestored {
                        epoch: k,
                        antenna: antenna as u8,
                    });
                }
            }
        }
        // the fine filter: stepped while it has usable input; frozen while the gyro carries
        // the attitude (its own rate estimate, a loop's, is far noisier than the calibrated
        // gyro), and restarted from the coasted attitude with the grown covariance when the
        // input returns after more than a moment
        let usable = !self.any_blocked() && fine_obs.len() >= usize::from(cfg.min_fine_satellites);
        if usable {
            let coasted = self
                .fine
                .as_ref()
                .map_or(0, |f| k.saturating_sub(f.last_update));
            if self.gyro.is_some() && coasted > u64::from(cfg.window_epochs) {
                self.restart_fine(k, &m);
            }
        }
        let input: &[SatelliteObservation<f32>] = if usable { &fine_obs } else { &[] };
        let step_now = usable || self.gyro.is_none();
        if let (Some(mut f), true) = (self.fine.clone(), step_now) {
            let before = f.lock();
            match f.step(input, &m, k) {
                Ok(report) => {
                    self.health.satellites_used = report.satellites;
                    let after = f.lock();
                    if after == LockStatus::Locked && before != LockStatus::Locked {
                        self.event(ReceiverEvent::FineLocked { epoch: k });
                    }
                    if usable && after == LockStatus::Locked {
                        self.coast_start = Some(Coast {
                            epoch: k,
                            q_rb: f.attitude(&m),
                            covariance: f.covariance(),
                            m,
                        });
                    }
                    self.fine = Some(f);
                    if after == LockStatus::FalseLock && before != LockStatus::FalseLock {
                        self.event(ReceiverEvent::FineLockLost { epoch: k });
                        self.restart_fine(k, &m);
                    }
                }
                Err(_) => {
                    self.event(ReceiverEvent::FineLockLost { epoch: k });
                    self.restart_fine(k, &m);
                }
            }
            if let Some(f) = self.fine.as_mut() {
                if f.largest_angle() > cfg.reanchor_angle_rad && f.reanchor(&cfg, &m).is_ok() {
                    self.event(ReceiverEvent::Reanchored { epoch: k });
                }
            }
        } else {
            self.health.satellites_used = 0;
        }
        self.health.fine_lock = self.fine.as_ref().map(FineStage::lock);
        self.health.coasting_s = self.fine.as_ref().map_or(0.0, |f| {
            k.saturating_sub(f.last_update) as f32 * cfg.epoch_s
        });
        self.closed = Some(k);
        if (k + 1).checked_rem(u64::from(cfg.window_epochs)) == Some(0) {
            self.close_window(k, &m);
        }
    }

    /// Restarts the fine filter from the best attitude available (or drops it).
    // (not inlined: each stage's locals get a frame of their own, so the stack is the
    // largest stage's, not the sum of all)
    #[inline(never)]
    pub(super) fn restart_fine(&mut self, k: u64, m: &Quaternion<f32>) {
        let (q, cov, source) = self.best_attitude(k, m);
        let rates = self
            .fine
            .as_ref()
            .map_or_else(Vector3::zeros, |f| f.filter.rates());
        self.fine = match source {
            AttitudeSource::None => None,
            _ => {
                // open the prior a little: the restart happens because something went wrong
                let cov = cov + Matrix3::identity() * 1e-6;
                FineStage::start(&self.config, &q, &cov, m, rates, k).ok()
            }
        };
    }
}

/// Errors of the attitude receiver ([`crate::receiver`]).
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
    /// call [`crate::receiver::AttitudeReceiver::set_aiding`] first.
    #[error("no line of sight for this satellite")]
    NoAiding,
    /// More satellites than the receiver has slots for.
    #[error("no free satellite slot")]
    TooManySatellites,
    /// An observation arrived for an epoch the receiver has already closed.
    #[error("observation for an epoch already closed")]
    StaleEpoch,
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
            Self::InvalidInput
            | Self::NoGyro
            | Self::NoAiding
            | Self::TooManySatellites
            | Self::StaleEpoch => ErrorKind::InvalidInput,
            Self::Adapter(e) => e.kind(),
            Self::Tracking(e) => e.kind(),
            Self::Acquisition(e) => e.kind(),
        }
    }
}
