//! The 1 ms path of [`AttitudeReceiver`]: observations buffered for two epochs, then each epoch
//! closed in named steps — prompts into the satellites' sums, the antenna power monitor, the
//! loop filter's step (without a gyro), the block's fine update, the continuity checks, the
//! window.
//!
//! Epoch numbers are the caller's `u64`s; every sum on them is checked or saturating, and an
//! epoch within [`EPOCH_HEADROOM`] of `u64::MAX` is refused
//! ([`ReceiverError::EpochOutOfRange`]), so no arithmetic on them can wrap.

use heapless::Vec;
use nalgebra::Complex;

use crate::attitude::one_stage::SatelliteObservation;

use super::{AttitudeReceiver, ReceiverError, ReceiverEvent, MAX_SATELLITES};

/// Epochs above `u64::MAX − EPOCH_HEADROOM` are refused: the receiver adds at most a few
/// windows to an epoch.
pub(crate) const EPOCH_HEADROOM: u64 = 1 << 40;

/// The last epoch the receiver accepts or closes ([`AttitudeReceiver::close_through`] stops
/// there), so that `open = closed + 1` never saturates and a closed epoch is never opened
/// again.
pub(crate) const MAX_EPOCH: u64 = u64::MAX - EPOCH_HEADROOM;

/// Largest C/N0 an observation may claim, dB-Hz.
const MAX_CN0_DBHZ: f32 = 90.0;

/// The observations of one epoch, in noise units or as received.
pub(crate) type Observations = Vec<SatelliteObservation<f32>, MAX_SATELLITES>;

/// The observations of one epoch.
#[derive(Clone, Debug, Default)]
struct Bucket {
    epoch: u64,
    observations: Observations,
}

/// The two open epochs and what has been closed.
#[derive(Clone, Debug)]
pub(crate) struct EpochBuffer {
    started: bool,
    /// The oldest open epoch; epochs `open` and `open + 1` are buffered.
    open: u64,
    closed: Option<u64>,
    buckets: [Bucket; 2],
    /// Most epochs one [`AttitudeReceiver::close_through`] call steps (a window), so that a
    /// jump cannot stall the caller.
    max_per_call: u64,
}

/// Checks an observation's values (the receiver's state is not touched).
pub(crate) fn check_observation(o: &SatelliteObservation<f32>) -> Result<(), ReceiverError> {
    let finite = o
        .prompt
        .i
        .iter()
        .chain(o.prompt.q.iter())
        .all(|v| v.is_finite())
        && o.noise_var.is_finite()
        && o.cn0_dbhz.is_finite();
    if !finite {
        return Err(ReceiverError::NonFinite);
    }
    if !(o.noise_var > 0.0) || !(0.0..=MAX_CN0_DBHZ).contains(&o.cn0_dbhz) {
        return Err(ReceiverError::InvalidInput);
    }
    Ok(())
}

impl EpochBuffer {
    pub fn new(window_epochs: u32) -> Self {
        Self {
            started: false,
            open: 0,
            closed: None,
            buckets: [Bucket::default(), Bucket::default()],
            max_per_call: u64::from(window_epochs.max(1)),
        }
    }

    /// The last closed epoch.
    pub fn last_closed(&self) -> Option<u64> {
        self.closed
    }

    /// Whether an observation of `epoch` is accepted, and through which epoch the receiver
    /// must close first.
    pub fn admit(&self, epoch: u64) -> Result<Option<u64>, ReceiverError> {
        if epoch > MAX_EPOCH {
            return Err(ReceiverError::EpochOutOfRange);
        }
        if !self.started {
            return Ok(None);
        }
        if epoch < self.open {
            return Err(ReceiverError::StaleEpoch);
        }
        // epochs open ..= epoch − 2 are complete
        Ok(epoch.checked_sub(2).filter(|&e| e >= self.open))
    }

    /// Stores an admitted observation (replacing an earlier one of the same satellite and
    /// epoch).
    pub fn insert(
        &mut self,
        epoch: u64,
        observation: &SatelliteObservation<f32>,
    ) -> Result<(), ReceiverError> {
        if !self.started {
            self.started = true;
            self.open = epoch;
            self.reset(epoch);
        }
        let bucket = &mut self.buckets[(epoch % 2) as usize];
        if bucket.epoch != epoch {
            // (only after a skip that left this bucket for another epoch)
            *bucket = Bucket {
                epoch,
                observations: Vec::new(),
            };
        }
        match bucket
            .observations
            .iter_mut()
            .find(|b| b.id == observation.id)
        {
            Some(existing) => *existing = *observation,
            // (one observation per satellite with aiding: at most MAX_SATELLITES)
            None => bucket
                .observations
                .push(*observation)
                .map_err(|_| ReceiverError::TooManySatellites)?,
        }
        Ok(())
    }

    /// The last epoch one close call steps: `epoch`, capped at a window past the oldest open
    /// one; `None` before the first observation or when nothing is due.
    pub fn plan_close(&self, epoch: u64) -> Option<u64> {
        let epoch = epoch.min(MAX_EPOCH);
        if !self.started || epoch < self.open {
            return None;
        }
        Some(epoch.min(self.open.saturating_add(self.max_per_call)))
    }

    /// Takes the oldest open epoch for closing when it is at most `limit`: its observations
    /// (none when it had none), and the buffer moves on.
    pub fn next_to_close(&mut self, limit: u64) -> Option<(u64, Observations)> {
        if !self.started || self.open > limit {
            return None;
        }
        let k = self.open;
        let bucket = core::mem::take(&mut self.buckets[(k % 2) as usize]);
        let observations = if bucket.epoch == k {
            bucket.observations
        } else {
            Vec::new()
        };
        self.buckets[(k % 2) as usize] = Bucket {
            epoch: k.saturating_add(2),
            observations: Vec::new(),
        };
        self.open = k.saturating_add(1);
        self.closed = Some(k);
        Some((k, observations))
    }

    /// After a close call: when `epoch` is still ahead (the jump exceeded a window), the empty
    /// epochs in between are skipped; returns the length of the skip, in epochs.
    pub fn skip_to(&mut self, epoch: u64) -> Option<u64> {
        let epoch = epoch.min(MAX_EPOCH);
        if !self.started || epoch < self.open {
            return None;
        }
        // (epoch ≥ open, and open ≥ 1 once an epoch was closed: no overflow either way)
        let skipped = (epoch - self.open).saturating_add(1);
        self.open = epoch.saturating_add(1);
        self.closed = Some(epoch);
        self.reset(self.open);
        Some(skipped)
    }

    /// Empty buckets for epochs `first` and `first + 1`.
    fn reset(&mut self, first: u64) {
        for (i, b) in (0..2).zip(self.buckets.iter_mut()) {
            let epoch = if (first % 2) as usize == i {
                first
            } else {
                first.saturating_add(1)
            };
            *b = Bucket {
                epoch,
                observations: Vec::new(),
            };
        }
    }
}

/// Per antenna `Σ_i (|z_P,i|² − 2)` over the satellites of an epoch (noise units): the signal
/// power the antenna monitor watches.
type Powers = [f32; 3];

impl AttitudeReceiver {
    /// Steps every stage for epoch `k` with its observations.
    pub(super) fn close_epoch(&mut self, k: u64, observations: &[SatelliteObservation<f32>]) {
        let (normalized, powers) = self.ingest(k, observations);
        if !normalized.is_empty() {
            self.update_antennas(k, &powers);
        }
        self.step_loop(k, &normalized);
        // (the configuration makes both counts positive; checked so that no division by
        // zero is compiled in)
        let ends = |every: u32| k.saturating_add(1).checked_rem(u64::from(every)) == Some(0);
        if ends(self.config.block_epochs) {
            self.close_block(k);
        }
        self.check_continuity(k);
        if ends(self.config.window_epochs) {
            self.close_window(k);
        }
    }

    /// The prompts in noise units into each satellite's sums (and its bit monitor); returns
    /// them (lines of sight from the aiding) and the antennas' powers.
    fn ingest(
        &mut self,
        k: u64,
        observations: &[SatelliteObservation<f32>],
    ) -> (Observations, Powers) {
        let epoch_s = self.config.epoch_s;
        let mut normalized = Observations::new();
        let mut powers = [0.0f32; 3];
        for o in observations {
            let z = o.prompt.normalized(crate::sqrtf(o.noise_var));
            for (p, zp) in powers.iter_mut().zip(z.iter()) {
                *p += zp.norm_sqr() - 2.0;
            }
            let Some(slot) = self.slots.iter_mut().find(|s| s.aiding.prn == o.id) else {
                continue;
            };
            let first = slot.last_epoch.is_none();
            let anomaly = slot.add_epoch(k, &z, o.cn0_dbhz);
            let los = slot.los_at(k, epoch_s);
            if first {
                self.events.push(ReceiverEvent::SatelliteAcquired {
                    epoch: k,
                    prn: o.id,
                });
            }
            if anomaly {
                self.events.push(ReceiverEvent::BitAnomaly {
                    epoch: k,
                    prn: o.id,
                });
            }
            let mut n = *o;
            n.prompt.i = z.map(|c: Complex<f32>| c.re);
            n.prompt.q = z.map(|c: Complex<f32>| c.im);
            n.noise_var = 1.0;
            n.los = [los.x, los.y, los.z];
            // (one observation per slot: at most MAX_SATELLITES)
            if normalized.push(n).is_err() {
                break;
            }
        }
        (normalized, powers)
    }

    /// The antenna power monitor: blocked antennas are left out (their counters and integers
    /// invalidated) until their signal returns.
    fn update_antennas(&mut self, k: u64, powers: &Powers) {
        for (antenna, blocked) in self.monitor.update(powers, self.config.blocked_power_ratio) {
            let Some(flag) = self.health.antenna_blocked.get_mut(antenna) else {
                continue;
            };
            let was = *flag;
            *flag = blocked;
            let antenna_id = antenna as u8;
            if blocked && !was {
                for s in self.slots.iter_mut() {
                    s.invalidate(antenna);
                }
                self.events.push(ReceiverEvent::AntennaBlocked {
                    epoch: k,
                    antenna: antenna_id,
                });
            } else if !blocked && was {
                self.events.push(ReceiverEvent::AntennaRestored {
                    epoch: k,
                    antenna: antenna_id,
                });
            }
        }
    }
}
