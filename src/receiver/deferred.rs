//! Block and window work out of the 1 ms path: what a closing epoch captured, kept until
//! [`AttitudeReceiver::run_deferred`] (see the module docs of [`super`], "Stages out of the
//! 1 ms path").

use heapless::Vec;

use crate::attitude::gyro_aided::PhaseDifferenceBlock;
use crate::geometry::Quaternion;

use super::carrier::Windowed;
use super::{AttitudeReceiver, MAX_SATELLITES};

/// A closed block's phase differences, waiting for the fine update.
#[derive(Clone, Debug)]
pub(super) struct BlockWork {
    /// Epoch that closed the block.
    pub k: u64,
    /// The block's centre epoch.
    pub centre: u64,
    /// The gyro attitude `M` at the centre.
    pub m_centre: Quaternion<f32>,
    /// The usable satellites' phase differences.
    pub blocks: Vec<PhaseDifferenceBlock<f32>, MAX_SATELLITES>,
}

/// A closed window's single differences, waiting for the window-level stages.
#[derive(Clone, Debug)]
pub(super) struct WindowWork {
    /// Epoch that closed the window.
    pub k: u64,
    /// Windows closed, this one included (the snapshot and integrity schedules count them).
    pub number: u64,
    /// The window's centre epoch.
    pub centre: u64,
    /// The gyro attitude `M` at the centre.
    pub m_centre: Quaternion<f32>,
    /// Every slot's window (slot index, single differences).
    pub windows: Vec<Windowed, MAX_SATELLITES>,
}

/// The work captured and not yet run (at most one block and one window: a window closes
/// with a block).
#[derive(Clone, Debug, Default)]
pub(super) struct Deferred {
    /// Capture only, in the epoch path (else capture and run).
    pub enabled: bool,
    pub block: Option<BlockWork>,
    pub window: Option<WindowWork>,
    /// Closings that found work still waiting (run then, in the epoch path).
    pub overruns: u32,
}

impl AttitudeReceiver {
    /// Moves the block and window stages out of the epoch path (`true`): the epoch that
    /// closes a block or a window only captures its single differences, and
    /// [`Self::run_deferred`] runs the stages. `false` (the default) runs them inside the
    /// epoch; switching to it runs any waiting work at once.
    pub fn set_deferred_stages(&mut self, deferred: bool) {
        self.deferred.enabled = deferred;
        if !deferred {
            self.run_deferred();
        }
    }

    /// Whether block or window work waits for [`Self::run_deferred`].
    pub fn has_deferred_work(&self) -> bool {
        self.deferred.block.is_some() || self.deferred.window.is_some()
    }

    /// Runs the waiting block work, then the waiting window work; returns whether there was
    /// any. Call it after every closed block (within 20 ms of it) from a context the 1 ms
    /// epochs may interrupt, in deferred mode ([`Self::set_deferred_stages`]).
    pub fn run_deferred(&mut self) -> bool {
        if !self.has_deferred_work() {
            return false;
        }
        let block = self.deferred.block.take();
        let window = self.deferred.window.take();
        if let Some(work) = block {
            self.run_block(&work);
        }
        if let Some(work) = window {
            self.run_window(&work);
        }
        true
    }

    /// Closings (blocks or windows) that found the previous work still waiting, so that the
    /// epoch path ran it (deferred mode: [`Self::run_deferred`] was called too late).
    pub fn deferred_overruns(&self) -> u32 {
        self.deferred.overruns
    }

    /// Before a capture: work still waiting runs now (counted).
    pub(super) fn flush_overrun(&mut self) {
        if self.has_deferred_work() {
            self.deferred.overruns = self.deferred.overruns.saturating_add(1);
            self.run_deferred();
        }
    }

    /// A captured block: kept for [`Self::run_deferred`], or run now.
    pub(super) fn schedule_block(&mut self, work: BlockWork) {
        if self.deferred.enabled {
            self.deferred.block = Some(work);
        } else {
            self.run_block(&work);
        }
    }

    /// A captured window: kept for [`Self::run_deferred`], or run now.
    pub(super) fn schedule_window(&mut self, work: WindowWork) {
        if self.deferred.enabled {
            self.deferred.window = Some(work);
        } else {
            self.run_window(&work);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::example::ExampleFlight;
    use super::super::{AttitudeReceiver, AttitudeSource, ReceiverEvent};

    /// Flies `from..to` as [`ExampleFlight::fly`] does (with the gyro) and calls
    /// `after(k, receiver)` after each epoch's observations.
    fn fly(
        f: &mut ExampleFlight,
        r: &mut AttitudeReceiver,
        epochs: core::ops::Range<u64>,
        mut after: impl FnMut(u64, &mut AttitudeReceiver),
    ) {
        for k in epochs {
            if k % 100 == 0 {
                r.set_aiding(&f.aiding(k)).unwrap();
            }
            if k > 0 && k % 10 == 0 {
                r.push_gyro_increment(&f.gyro_increment(k / 10 - 1))
                    .unwrap();
            }
            for o in f.observations(k).iter() {
                r.push_observation(k, o).unwrap();
            }
            after(k, r);
        }
    }

    fn first_fix(r: &mut AttitudeReceiver) -> Option<u64> {
        let mut fix = None;
        while let Some(e) = r.pop_event() {
            if let ReceiverEvent::FirstFix { epoch, .. } = e {
                fix = Some(epoch);
            }
        }
        fix
    }

    #[test]
    fn the_closing_epoch_only_captures_and_run_deferred_runs_the_stages() {
        let mut f = ExampleFlight::new(3);
        let mut r = AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
        r.set_deferred_stages(true);
        // the observations of epoch 101 close epoch 99, the end of the first window; the
        // blocks before it are run as they close
        fly(&mut f, &mut r, 0..102, |k, r| {
            if k < 101 {
                r.run_deferred();
            }
        });
        assert_eq!(r.epoch(), Some(99));
        assert!(r.has_deferred_work());
        assert_eq!(first_fix(&mut r), None, "the cold start waits");
        assert!(r.run_deferred());
        assert!(!r.has_deferred_work() && !r.run_deferred());
        assert_eq!(first_fix(&mut r), Some(99));
        assert_eq!(r.deferred_overruns(), 0);
    }

    #[test]
    fn deferred_work_run_after_every_epoch_gives_the_inline_attitude() {
        let (mut f_inline, mut f_deferred) = (ExampleFlight::new(5), ExampleFlight::new(5));
        let mut inline = AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
        let mut deferred = inline.clone();
        deferred.set_deferred_stages(true);
        fly(&mut f_inline, &mut inline, 0..3000, |_, _| {});
        fly(&mut f_deferred, &mut deferred, 0..3000, |_, r| {
            r.run_deferred();
        });
        let (a, b) = (inline.attitude(), deferred.attitude());
        assert_eq!(a.source, AttitudeSource::Fine);
        assert_eq!((a.epoch, a.source), (b.epoch, b.source));
        assert_eq!(a.q_rb, b.q_rb);
        assert_eq!(deferred.deferred_overruns(), 0);
    }

    #[test]
    fn late_work_delays_the_stages_and_missed_work_runs_in_the_epoch_path_counted() {
        for (every, overruns) in [(15u64, false), (u64::MAX, true)] {
            let mut f = ExampleFlight::new(7);
            let mut r = AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
            r.set_deferred_stages(true);
            fly(&mut f, &mut r, 0..3000, |k, r| {
                if k % every == 0 {
                    r.run_deferred();
                }
            });
            let a = r.attitude();
            let err_deg = a.q_rb.angle_to(&f.attitude(a.epoch)).to_degrees();
            assert_eq!(a.source, AttitudeSource::Fine, "every {every}");
            assert!(err_deg < 0.1, "every {every}: {err_deg}°");
            assert_eq!(r.deferred_overruns() > 0, overruns, "every {every}");
        }
    }
}
