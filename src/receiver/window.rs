//! The window-level stages of [`AttitudeReceiver`]: every 100 ms window closes with the cold
//! start (until the first fix), the ambiguity upkeep (slips, rising satellites, returning
//! antennas), the snapshot monitor and the rigid-body filter.

use heapless::Vec;
use nalgebra::{Matrix3, Vector3};

use crate::attitude::array::AntennaArray;
use crate::attitude::rigid_body::{RigidBodyConfig, RigidBodyFilter};
use crate::ekf::GateConfidence;
use crate::geometry::Quaternion;

use super::carrier::{
    baseline_epoch, baselines_and_velocities, cold_start, predicted_sd, snapshot, Windowed,
};
use super::fine::FineStage;
use super::output::{AttitudeSource, ReceiverEvent, StageEstimate};
use super::satellite::{Slot, WindowSd};
use super::AttitudeReceiver;
use super::MAX_SATELLITES;

impl AttitudeReceiver {
    /// The window that ends with epoch `k`.
    // (not inlined: each stage's locals get a frame of their own, so the stack is the
    // largest stage's, not the sum of all)
    #[inline(never)]
    pub(super) fn close_window(&mut self, k: u64, m_now: &Quaternion<f32>) {
        let cfg = self.config;
        self.windows += 1;
        let centre = k + 1 - u64::from(cfg.window_epochs / 2);
        let mut windows = Vec::<Windowed, MAX_SATELLITES>::new();
        let mut lost = Vec::<u8, MAX_SATELLITES>::new();
        for (i, s) in self.slots.iter_mut().enumerate() {
            let stale = s
                .last_epoch
                .is_some_and(|e| e + u64::from(cfg.window_epochs) <= k);
            if let Some(w) = s.close_window(centre, &cfg) {
                let _ = windows.push((i, w));
            } else if stale {
                let _ = lost.push(s.aiding.prn);
                *s = Slot::new(s.aiding);
            }
        }
        for &prn in lost.iter() {
            self.event(ReceiverEvent::SatelliteLost { epoch: k, prn });
        }
        self.health.satellites_tracked = windows.len() as u8;
        let m_centre = self.gyro_attitude(centre);
        if !self.fixed {
            self.try_cold_start(k, centre, &windows, &m_centre, m_now);
        } else {
            self.maintain_ambiguities(k, &windows, &m_centre, m_now);
            if self.windows.checked_rem(u64::from(cfg.snapshot_windows)) == Some(0) {
                self.run_snapshot(centre, &windows, &m_centre);
            }
            self.run_rigid_body(k, &windows);
        }
        self.health.satellites_fixed = self
            .slots
            .iter()
            .filter(|s| s.ambiguity.iter().all(Option::is_some))
            .count() as u8;
    }

    // (not inlined: each stage's locals get a frame of their own, so the stack is the
    // largest stage's, not the sum of all)
    #[inline(never)]
    pub(super) fn try_cold_start(
        &mut self,
        k: u64,
        centre: u64,
        windows: &[Windowed],
        m_centre: &Quaternion<f32>,
        m_now: &Quaternion<f32>,
    ) {
        let cfg = self.config;
        let candidates = windows
            .iter()
            .filter(|(_, w)| w.valid == [true, true])
            .count();
        if candidates < usize::from(cfg.min_cold_start_satellites) || self.any_blocked() {
            return;
        }
        let sigma_ref = cfg.ambiguity.phase_sigma_m / cfg.wavelength_m();
        let Some((solution, ks)) = cold_start(&self.resolver, windows, sigma_ref) else {
            self.event(ReceiverEvent::FixRefused { epoch: k });
            return;
        };
        for (slot, kk) in &ks {
            if let Some(s) = self.slots.get_mut(*slot) {
                s.ambiguity = [Some(kk[0]), Some(kk[1])];
            }
        }
        self.fixed = true;
        self.health.ambiguities_fixed = true;
        let est = StageEstimate {
            epoch: centre,
            q_rb: solution.q_rb,
            covariance: solution.covariance,
        };
        self.snapshot = Some((est, *m_centre));
        self.event(ReceiverEvent::FirstFix {
            epoch: k,
            satellites: ks.len() as u8,
        });
        // the fine filter starts at the current epoch
        let q_now = solution.q_rb * m_centre.conjugate() * *m_now;
        self.fine = FineStage::start(
            &cfg,
            &q_now,
            &solution.covariance,
            m_now,
            Vector3::zeros(),
            k,
        )
        .ok();
    }

    /// The attitude to check the single differences against at the window's centre, and the
    /// largest SD error (cycles) it can cause.
    pub(super) fn trusted_attitude(
        &self,
        centre: u64,
        m_centre: &Quaternion<f32>,
    ) -> Option<(Matrix3<f32>, f32)> {
        let (q, cov, source) = self.best_attitude(centre, m_centre);
        if source == AttitudeSource::None {
            return None;
        }
        let sigma = libm::sqrtf(cov.trace().max(0.0));
        let longest = self.baselines[0].norm().max(self.baselines[1].norm());
        Some((
            q.to_dcm(),
            3.0 * sigma * longest / self.config.wavelength_m(),
        ))
    }

    // (not inlined: each stage's locals get a frame of their own, so the stack is the
    // largest stage's, not the sum of all)
    #[inline(never)]
    pub(super) fn maintain_ambiguities(
        &mut self,
        k: u64,
        windows: &[Windowed],
        m_centre: &Quaternion<f32>,
        _m_now: &Quaternion<f32>,
    ) {
        let cfg = self.config;
        let centre = k + 1 - u64::from(cfg.window_epochs / 2);
        let Some((c_rb, sd_error)) = self.trusted_attitude(centre, m_centre) else {
            return;
        };
        if sd_error > 0.15 {
            return;
        }
        let lambda = cfg.wavelength_m();
        let mut events = Vec::<ReceiverEvent, 24>::new();
        for (slot, w) in windows {
            let Some(s) = self.slots.get_mut(*slot) else {
                continue;
            };
            let had_all = s.ambiguity.iter().all(Option::is_some);
            for p in 0..2 {
                let (Some(&valid), Some(&phase), Some(amb)) =
                    (w.valid.get(p), w.phase.get(p), s.ambiguity.get_mut(p))
                else {
                    continue;
                };
                if !valid {
                    continue;
                }
                let predicted = predicted_sd(&c_rb, &self.baselines, p, &w.los, lambda);
                let offset = phase - predicted; // = K if the window is clean
                let nearest = libm::roundf(offset);
                let clean = (offset - nearest).abs() < 0.2;
                let dropped = s.dropped.get_mut(p);
                match amb {
                    Some(kk) => {
                        let residual = offset - *kk as f32;
                        if residual.abs() > cfg.slip_threshold_cycles {
                            if clean {
                                let cycles = (nearest as i32 - *kk).clamp(-127, 127) as i8;
                                *amb = Some(nearest as i32);
                                let _ = events.push(ReceiverEvent::CycleSlip {
                                    epoch: k,
                                    prn: w.prn,
                                    antenna: (p + 1) as u8,
                                    cycles,
                                });
                            } else {
                                *amb = None;
                            }
                        }
                    }
                    None if clean => {
                        *amb = Some(nearest as i32);
                        // a window that dropped the integer because the counter jumped: the
                        // re-fix tells whether whole cycles were lost
                        if let Some(d) = dropped {
                            if let Some(old) = d.take() {
                                let cycles = (nearest as i32 - old).clamp(-127, 127) as i8;
                                if cycles != 0 {
                                    let _ = events.push(ReceiverEvent::CycleSlip {
                                        epoch: k,
                                        prn: w.prn,
                                        antenna: (p + 1) as u8,
                                        cycles,
                                    });
                                }
                            }
                        }
                    }
                    None => {}
                }
            }
            if !had_all && s.ambiguity.iter().all(Option::is_some) {
                let _ = events.push(ReceiverEvent::AmbiguityFixed {
                    epoch: k,
                    prn: w.prn,
                });
            }
        }
        for &e in events.iter() {
            self.event(e);
        }
    }

    pub(super) fn fixed_windows(
        &self,
        windows: &[Windowed],
    ) -> Vec<(WindowSd, [i32; 2], Vector3<f32>), MAX_SATELLITES> {
        let mut out = Vec::new();
        for (slot, w) in windows {
            let Some(s) = self.slots.get(*slot) else {
                continue;
            };
            if let ([Some(kb), Some(kc)], [true, true]) = (s.ambiguity, w.valid) {
                let _ = out.push((*w, [kb, kc], Vector3::from(s.aiding.los_rate)));
            }
        }
        out
    }

    // (not inlined: each stage's locals get a frame of their own, so the stack is the
    // largest stage's, not the sum of all)
    #[inline(never)]
    pub(super) fn run_snapshot(
        &mut self,
        centre: u64,
        windows: &[Windowed],
        m_centre: &Quaternion<f32>,
    ) {
        let fixed = self.fixed_windows(windows);
        let mut pairs = Vec::<(WindowSd, [i32; 2]), MAX_SATELLITES>::new();
        for (w, k, _) in &fixed {
            let _ = pairs.push((*w, *k));
        }
        if pairs.len() < 3 {
            return;
        }
        if let Some(s) = snapshot(&self.solver, &pairs, self.config.wavelength_m()) {
            self.snapshot = Some((
                StageEstimate {
                    epoch: centre,
                    q_rb: s.q_rb,
                    covariance: s.covariance,
                },
                *m_centre,
            ));
        }
    }

    // (not inlined: each stage's locals get a frame of their own, so the stack is the
    // largest stage's, not the sum of all)
    #[inline(never)]
    pub(super) fn run_rigid_body(&mut self, k: u64, windows: &[Windowed]) {
        let cfg = self.config;
        let fixed = self.fixed_windows(windows);
        if fixed.len() < 4 || self.any_blocked() {
            return;
        }
        let Some((a, v)) = baselines_and_velocities(&fixed, cfg.wavelength_m()) else {
            return;
        };
        let half = 0.5 * cfg.window_s();
        let epoch = baseline_epoch(&a, &v, half);
        // a gap (blocked antenna, too few satellites) leaves the filter behind the body: it
        // has no gyro, so it starts again from the receiver's attitude
        if self.rigid_last + u64::from(cfg.window_epochs) < k {
            self.rigid = None;
        }
        if self.rigid.is_none() {
            let m_now = self.gyro_attitude(k);
            let (q0, cov, source) = self.best_attitude(k, &m_now);
            if source == AttitudeSource::None {
                return;
            }
            let rb_config = RigidBodyConfig {
                dt: cfg.window_s(),
                sigma_baseline: cfg.baseline_sigma_m,
                sigma_velocity: cfg.velocity_sigma_m_s,
                gate: Some(GateConfidence::P999),
            };
            let Ok(array) = AntennaArray::new(self.antennas) else {
                return;
            };
            let p0 = cov + Matrix3::identity() * 1e-6;
            self.rigid = RigidBodyFilter::new(&array, rb_config, &q0, &p0).ok();
            self.rigid_last = k;
            return;
        }
        if let Some(r) = self.rigid.as_mut() {
            match r.step(&epoch) {
                Ok(e) => {
                    self.rigid_last = k;
                    self.rigid_estimate = Some(StageEstimate {
                        epoch: k,
                        q_rb: e.q_rb,
                        covariance: e.covariance,
                    });
                }
                Err(_) => self.rigid = None,
            }
        }
    }
}
