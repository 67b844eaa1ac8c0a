//! The block-level steps of [`AttitudeReceiver`]: every [`ReceiverConfig::block_epochs`] the
//! satellites' summed single differences update the gyro-aided fine filter (and advance the
//! counters the windows use); every epoch, without a gyro, the loop steps on the prompts.

use heapless::Vec;

use crate::attitude::gyro_aided::{GyroAidedReport, PhaseDifferenceBlock};
use crate::attitude::one_stage::{LockStatus, SatelliteObservation};

use crate::geometry::Quaternion;

use super::deferred::BlockWork;
use super::satellite::BlockSd;
use super::{AttitudeReceiver, ReceiverEvent, MAX_SATELLITES};

#[cfg(doc)]
use super::ReceiverConfig;

impl AttitudeReceiver {
    /// Closes the block that ends with epoch `k`: every slot's sums into phase differences
    /// (the capture), then the fine update, now or deferred ([`super::deferred`]).
    pub(super) fn close_block(&mut self, k: u64) {
        self.flush_overrun();
        let block = self.config.block_epochs;
        let start = k.saturating_add(1).saturating_sub(u64::from(block));
        // the block's centre (epoch units; a half epoch when the block is odd is rounded down)
        let centre = start.saturating_add(u64::from(block / 2));
        let min_epochs = (block / 2).max(1);
        let blocked = self.health.antenna_blocked;
        let mut blocks = Vec::<PhaseDifferenceBlock<f32>, MAX_SATELLITES>::new();
        for slot in self.slots.iter_mut() {
            let Some(sd) = slot.close_block(centre, min_epochs, &blocked, &self.config) else {
                continue;
            };
            if let Some(b) = usable(&sd) {
                // (one block per slot: at most MAX_SATELLITES)
                if blocks.push(b).is_err() {
                    break;
                }
            }
        }
        let m_centre = self.gyro_attitude(centre);
        self.schedule_block(BlockWork {
            k,
            centre,
            m_centre,
            blocks,
        });
    }

    /// The block's stage: the fine update with its phase differences.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub(super) fn run_block(&mut self, work: &BlockWork) {
        self.update_gyro_fine(work.k, work.centre, &work.m_centre, &work.blocks);
    }

    /// The gyro-aided update with the block's phase differences (a prediction only when
    /// there are too few, or an antenna is blocked).
    fn update_gyro_fine(
        &mut self,
        k: u64,
        centre: u64,
        m: &Quaternion<f32>,
        blocks: &[PhaseDifferenceBlock<f32>],
    ) {
        let epoch_s = self.config.epoch_s;
        let enough = blocks.len() >= usize::from(self.config.min_fine_satellites);
        let input: &[PhaseDifferenceBlock<f32>] = if enough && !self.any_blocked() {
            blocks
        } else {
            &[]
        };
        let window = u64::from(self.config.window_epochs);
        let max_sigma = self.config.max_resume_sigma_rad;
        let too_uncertain = match self.fine.as_mut().and_then(|f| f.gyro_mut()) {
            None => return,
            Some(stage) => {
                let resuming =
                    !input.is_empty() && centre.saturating_sub(stage.last_update) > window;
                resuming && stage.sigma_at(centre, m, epoch_s) > max_sigma
            }
        };
        if too_uncertain {
            self.lose_attitude(k, super::LossReason::TooUncertainToResume);
            return;
        }
        let Some(stage) = self.fine.as_mut().and_then(|f| f.gyro_mut()) else {
            return;
        };
        match stage.update(centre, m, input, epoch_s) {
            Ok(report) => {
                if report.accepted > 0 && !stage.locked {
                    stage.locked = true;
                    self.events.push(ReceiverEvent::FineLocked { epoch: k });
                }
                self.after_gyro_update(k, &report, input.len());
            }
            Err(_) => self.restart_fine(k),
        }
    }

    /// Feeds the bias correction back to the gyro, the line biases and the satellites used to
    /// the health, and the residuals to the integrity monitor.
    fn after_gyro_update(&mut self, k: u64, report: &GyroAidedReport<f32>, offered: usize) {
        if let Some(g) = self.gyro.as_mut() {
            g.bias += report.bias_correction;
        }
        let gyro_wrong = self.integrity.add_block(report);
        if offered > 0 {
            self.health.satellites_used = report.accepted;
        }
        if let Some(f) = &self.fine {
            self.line_bias = f.line_bias();
        }
        if (gyro_wrong || self.integrity.residuals_inconsistent()) && !self.health.gyro_excluded {
            self.exclude_gyro(k);
        }
    }

    /// Without a gyro (or with it excluded) the loop steps every epoch on the prompts.
    pub(super) fn step_loop(&mut self, k: u64, observations: &[SatelliteObservation<f32>]) {
        let cfg = self.config;
        let usable =
            !self.any_blocked() && observations.len() >= usize::from(cfg.min_fine_satellites);
        let input: &[SatelliteObservation<f32>] = if usable { observations } else { &[] };
        let Some(stage) = self.fine.as_mut().and_then(|f| f.loop_mut()) else {
            return;
        };
        let before = stage.lock();
        let mut next = stage.clone();
        match next.step(input, k) {
            Ok(report) => {
                let after = next.lock();
                *stage = next;
                if usable {
                    self.health.satellites_used = report.satellites;
                }
                if after == LockStatus::Locked && before != LockStatus::Locked {
                    self.events.push(ReceiverEvent::FineLocked { epoch: k });
                }
                if after == LockStatus::FalseLock && before != LockStatus::FalseLock {
                    self.events.push(ReceiverEvent::FineLockLost { epoch: k });
                    self.restart_fine(k);
                    return;
                }
                if stage.largest_angle() > cfg.reanchor_angle_rad && stage.reanchor(&cfg).is_ok() {
                    self.events.push(ReceiverEvent::Reanchored { epoch: k });
                }
                self.line_bias = stage.line_bias();
            }
            Err(_) => {
                self.events.push(ReceiverEvent::FineLockLost { epoch: k });
                self.restart_fine(k);
            }
        }
    }
}

/// A block's single differences as the gyro-aided filter takes them, when usable.
fn usable(sd: &BlockSd) -> Option<PhaseDifferenceBlock<f32>> {
    sd.valid.then_some(PhaseDifferenceBlock {
        id: sd.prn,
        los: sd.los,
        phase_rad: sd.phase_rad,
        covariance: sd.covariance,
    })
}
