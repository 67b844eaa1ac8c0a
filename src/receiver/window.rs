//! The window-level stages of [`AttitudeReceiver`]: every window closes with the cold start
//! (until the first fix), the ambiguity upkeep (slips, rising satellites, returning antennas),
//! the snapshot monitor, the integrity check and the rigid-body filter.

use heapless::Vec;
use nalgebra::{Matrix3, Vector3};

use crate::attitude::array::AntennaArray;
use crate::attitude::rigid_body::{RigidBodyConfig, RigidBodyFilter};
use crate::ekf::GateConfidence;
use crate::geometry::Quaternion;

use super::carrier::{
    baseline_epoch, baselines_and_velocities, cold_start, predicted_sd, snapshot, unbiased,
    FixedWindow, Windowed,
};
use super::deferred::WindowWork;
use super::fine::FineStage;
use super::{
    AttitudeReceiver, AttitudeSource, LineBias, ReceiverEvent, SnapshotFix, StageEstimate,
    MAX_SATELLITES,
};

/// Largest SD error (cycles, 3σ) the trusted attitude may cause for the upkeep to fix
/// integers from it.
const MAX_UPKEEP_SD_ERROR: f32 = 0.15;

/// A window SD within this of a whole number of cycles from the prediction is clean.
const CLEAN_FRACTION: f32 = 0.2;

/// Fixed satellites the snapshot monitor needs.
const MIN_SNAPSHOT_SATELLITES: usize = 3;

/// Fixed satellites the rigid-body filter needs.
const MIN_RIGID_SATELLITES: usize = 4;

/// Variance (rad²) added to a stage's covariance when another stage starts from it: the
/// restart happens because something went wrong.
const RESTART_VARIANCE: f32 = 1e-6;

impl AttitudeReceiver {
    /// The window that ends with epoch `k`: every slot's window single differences (the
    /// capture), then the window-level stages, now or deferred ([`super::deferred`]).
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub(super) fn close_window(&mut self, k: u64) {
        if self.deferred.window.is_some() {
            self.flush_overrun();
        }
        self.windows = self.windows.saturating_add(1);
        let half = u64::from(self.config.window_epochs / 2);
        let centre = k.saturating_add(1).saturating_sub(half);
        let windows = self.collect_windows(k, centre);
        self.health.satellites_tracked = windows.len() as u8;
        let m_centre = self.gyro_attitude(centre);
        self.schedule_window(WindowWork {
            k,
            number: self.windows,
            centre,
            m_centre,
            windows,
        });
    }

    /// The window's stages: the cold start until the first fix, then the ambiguity upkeep,
    /// the snapshot monitor and the integrity check when due, and the rigid-body filter.
    // (not inlined: each stage's locals get a frame of their own, so the stack is the
    // largest stage's, not the sum of all)
    #[inline(never)]
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub(super) fn run_window(&mut self, work: &WindowWork) {
        let (k, centre, windows, m_centre) = (work.k, work.centre, &work.windows, &work.m_centre);
        if !self.fixed {
            self.try_cold_start(k, centre, windows, m_centre);
        } else {
            self.maintain_ambiguities(k, centre, windows, m_centre);
            let due = |every: u32, windows: u64| windows % u64::from(every.max(1)) == 0;
            let snapshot_due = due(self.config.snapshot_windows, work.number);
            let integrity_due = due(self.config.integrity_windows, work.number);
            if snapshot_due {
                self.run_snapshot(k, centre, windows, m_centre);
            }
            if integrity_due {
                self.check_integrity(k, centre, windows, m_centre);
            }
            self.run_rigid_body(k, windows);
        }
        self.review_excluded_gyro(k);
        self.health.satellites_fixed = crate::count(self.slots.iter().filter(|s| s.fixed())) as u8;
        self.health.line_bias_rad = self.line_bias.rad;
        self.health.line_bias_sigma_rad = self.line_bias.sigma_rad;
    }

    /// Every slot's window; slots that stopped delivering are released (events).
    fn collect_windows(&mut self, k: u64, centre: u64) -> Vec<Windowed, MAX_SATELLITES> {
        let cfg = self.config;
        let window = u64::from(cfg.window_epochs);
        let mut windows = Vec::new();
        // (indices from a range, not `enumerate`: its counter keeps an overflow check)
        for (i, s) in (0..self.slots.len()).zip(self.slots.iter_mut()) {
            let stale = s.last_epoch.is_some_and(|e| e.saturating_add(window) <= k);
            if let Some(w) = s.close_window(centre, &cfg) {
                // (one window per slot: at most MAX_SATELLITES)
                if windows.push((i, w)).is_err() {
                    break;
                }
            } else if stale {
                self.events.push(ReceiverEvent::SatelliteLost {
                    epoch: k,
                    prn: s.aiding.prn,
                });
                *s = s.restarted();
            }
        }
        windows
    }

    /// The line biases in cycles, as the window-level stages remove them.
    pub(super) fn beta_cycles(&self) -> [f32; 2] {
        self.line_bias
            .rad
            .map(|b| b * 0.5 * core::f32::consts::FRAC_1_PI)
    }

    // (not inlined: each stage's locals get a frame of their own)
    #[inline(never)]
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    fn try_cold_start(
        &mut self,
        k: u64,
        centre: u64,
        windows: &[Windowed],
        m_centre: &Quaternion<f32>,
    ) {
        let cfg = self.config;
        let candidates = crate::count(windows.iter().filter(|(_, w)| w.valid == [true, true]));
        if candidates < usize::from(cfg.min_cold_start_satellites) || self.any_blocked() {
            return;
        }
        let sigma_ref = cfg.ambiguity.phase_sigma_m / cfg.wavelength_m();
        let known = self.line_bias.known.then(|| self.beta_cycles());
        let Some(fix) = cold_start(&self.solvers.resolver, windows, sigma_ref, known) else {
            self.events.push(ReceiverEvent::FixRefused { epoch: k });
            return;
        };
        if let Some((bias, sigma)) = fix.line_bias {
            self.line_bias = LineBias::from_cycles(bias, sigma);
        }
        let (solution, ks) = (fix.solution, fix.slots);
        for (slot, kk) in &ks {
            if let Some(s) = self.slots.get_mut(*slot) {
                s.ambiguity = [Some(kk[0]), Some(kk[1])];
            }
        }
        self.fixed = true;
        self.health.ambiguities_fixed = true;
        self.snapshot = Some(SnapshotFix {
            estimate: StageEstimate {
                epoch: centre,
                q_rb: solution.q_rb,
                covariance: solution.covariance,
            },
            m: *m_centre,
        });
        self.events.push(ReceiverEvent::FirstFix {
            epoch: k,
            satellites: ks.len() as u8,
        });
        self.start_fine(k, centre, &solution.q_rb, &solution.covariance, m_centre);
    }

    /// Starts the fine stage from a fix at the window's centre: gyro-aided when the gyro is
    /// usable, else the loop (at the current epoch).
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub(super) fn start_fine(
        &mut self,
        k: u64,
        centre: u64,
        q_rb: &Quaternion<f32>,
        covariance: &Matrix3<f32>,
        m_centre: &Quaternion<f32>,
    ) {
        let cov = covariance + Matrix3::identity() * RESTART_VARIANCE;
        let started = match (&self.gyro, self.health.gyro_excluded) {
            (Some(g), false) => {
                let bias_sigma = g.config.turn_on_bias_sigma;
                FineStage::start_gyro(
                    &self.config,
                    &g.config,
                    self.geometry.baselines,
                    q_rb,
                    &cov,
                    bias_sigma,
                    &self.line_bias,
                    m_centre,
                    centre,
                )
                .ok()
            }
            _ => {
                // the body's rotation from the centre to now is unknown without the gyro: the
                // loop starts at the fix, its prior rates zero
                FineStage::start_loop(
                    &self.config,
                    q_rb,
                    &cov,
                    &self.line_bias,
                    Vector3::zeros(),
                    k,
                )
                .ok()
            }
        };
        self.fine = started;
    }

    /// The attitude to check the single differences against at the window's centre, and the
    /// largest SD error (cycles) it can cause.
    fn trusted_attitude(&self, centre: u64) -> Option<(Matrix3<f32>, f32)> {
        let (q, cov, source) = self.best_attitude(centre);
        if source == AttitudeSource::None {
            return None;
        }
        let sigma = crate::sqrtf(cov.trace().max(0.0));
        let [b, c] = self.geometry.baselines;
        let longest = b.norm().max(c.norm());
        Some((
            q.to_dcm(),
            3.0 * sigma * longest / self.config.wavelength_m(),
        ))
    }

    // (not inlined: each stage's locals get a frame of their own)
    #[inline(never)]
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    fn maintain_ambiguities(
        &mut self,
        k: u64,
        centre: u64,
        windows: &[Windowed],
        _m_centre: &Quaternion<f32>,
    ) {
        let Some((c_rb, sd_error)) = self.trusted_attitude(centre) else {
            return;
        };
        if sd_error > MAX_UPKEEP_SD_ERROR {
            return;
        }
        let lambda = self.config.wavelength_m();
        let slip_threshold = self.config.slip_threshold_cycles;
        let beta = self.beta_cycles();
        let baselines = self.geometry.baselines;
        for (slot, w) in windows {
            let Some(s) = self.slots.get_mut(*slot) else {
                continue;
            };
            let had_all = s.fixed();
            for p in 0..2 {
                if !w.valid[p] {
                    continue;
                }
                let predicted = predicted_sd(&c_rb, &baselines, p, &w.los, lambda);
                let offset = unbiased(w, &beta)[p] - predicted; // = K if the window is clean
                let nearest = libm::roundf(offset);
                let clean = (offset - nearest).abs() < CLEAN_FRACTION;
                let slip = match s.ambiguity[p] {
                    Some(kk) if (offset - kk as f32).abs() > slip_threshold => {
                        s.ambiguity[p] = clean.then_some(nearest as i32);
                        // (saturating: the event clamps the count to ±127 anyway)
                        clean.then_some((nearest as i32).saturating_sub(kk))
                    }
                    Some(_) => None,
                    None if clean => {
                        s.ambiguity[p] = Some(nearest as i32);
                        // a window that dropped the integer because the counter jumped: the
                        // re-fix tells whether whole cycles were lost
                        s.dropped[p]
                            .take()
                            .map(|old| (nearest as i32).saturating_sub(old))
                            .filter(|&c| c != 0)
                    }
                    None => None,
                };
                if let Some(cycles) = slip {
                    self.events.push(ReceiverEvent::CycleSlip {
                        epoch: k,
                        prn: w.prn,
                        antenna: (p + 1) as u8,
                        cycles: cycles.clamp(-127, 127) as i8,
                    });
                }
            }
            if !had_all && s.fixed() {
                self.events.push(ReceiverEvent::AmbiguityFixed {
                    epoch: k,
                    prn: w.prn,
                });
            }
        }
    }

    /// The windows whose integers are fixed on both baselines.
    pub(super) fn fixed_windows(&self, windows: &[Windowed]) -> Vec<FixedWindow, MAX_SATELLITES> {
        let mut out = Vec::new();
        for (slot, w) in windows {
            let Some(s) = self.slots.get(*slot) else {
                continue;
            };
            if let ([Some(kb), Some(kc)], [true, true]) = (s.ambiguity, w.valid) {
                // (one per window: at most MAX_SATELLITES)
                if out
                    .push((*w, [kb, kc], Vector3::from(s.aiding.los_rate)))
                    .is_err()
                {
                    break;
                }
            }
        }
        out
    }

    // (not inlined: each stage's locals get a frame of their own)
    #[inline(never)]
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    fn run_snapshot(
        &mut self,
        k: u64,
        centre: u64,
        windows: &[Windowed],
        m_centre: &Quaternion<f32>,
    ) {
        let fixed = self.fixed_windows(windows);
        if fixed.len() < MIN_SNAPSHOT_SATELLITES {
            return;
        }
        let beta = self.beta_cycles();
        let Some(s) = snapshot(
            &self.solvers.snapshot,
            &fixed,
            self.config.wavelength_m(),
            &beta,
        ) else {
            return;
        };
        // the snapshot takes the line biases as known: their uncertainty enters its covariance
        let covariance = s.covariance + self.line_bias_attitude_covariance(&s.c_rb, &fixed);
        let estimate = StageEstimate {
            epoch: centre,
            q_rb: s.q_rb,
            covariance,
        };
        self.snapshot = Some(SnapshotFix {
            estimate,
            m: *m_centre,
        });
        self.compare_with_snapshot(k, &estimate, m_centre);
    }

    /// The attitude covariance the line biases' uncertainty gives a snapshot, to first order:
    /// a common offset `δ` on baseline `i` moves its least-squares baseline by
    /// `N⁻¹ (Σ w s) λδ`, and the attitude by the rotation that moves `b_i` so.
    fn line_bias_attitude_covariance(
        &self,
        c_rb: &Matrix3<f32>,
        fixed: &[FixedWindow],
    ) -> Matrix3<f32> {
        let lambda = self.config.wavelength_m();
        let mut info = Matrix3::zeros();
        let mut sum = Vector3::zeros();
        for (w, _, _) in fixed {
            let s = w.sigma_cycles.max(1e-4);
            let weight = 1.0 / (s * s);
            info += w.los * w.los.transpose() * weight;
            sum += w.los * weight;
        }
        let Some(chol) = info.cholesky() else {
            return Matrix3::zeros();
        };
        let shift = chol.solve(&sum); // δa per cycle of common offset, reference frame
        let mut cov = Matrix3::zeros();
        for (b, sigma_rad) in self
            .geometry
            .baselines
            .iter()
            .zip(self.line_bias.sigma_rad.iter())
        {
            let da = c_rb.transpose()
                * shift
                * (lambda * sigma_rad * 0.5 * core::f32::consts::FRAC_1_PI);
            let dtheta = b.cross(&da) / b.norm_squared().max(1e-6);
            cov += dtheta * dtheta.transpose();
        }
        cov
    }

    // (not inlined: each stage's locals get a frame of their own)
    #[inline(never)]
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    fn run_rigid_body(&mut self, k: u64, windows: &[Windowed]) {
        let cfg = self.config;
        let fixed = self.fixed_windows(windows);
        if fixed.len() < MIN_RIGID_SATELLITES || self.any_blocked() {
            return;
        }
        let beta = self.beta_cycles();
        let Some((a, v)) = baselines_and_velocities(&fixed, cfg.wavelength_m(), &beta) else {
            return;
        };
        let epoch = baseline_epoch(&a, &v, 0.5 * cfg.window_s());
        // a gap (blocked antenna, too few satellites) leaves the filter behind the body: it
        // has no gyro, so it starts again from the receiver's attitude
        if self
            .rigid
            .last_step
            .saturating_add(u64::from(cfg.window_epochs))
            < k
        {
            self.rigid.filter = None;
        }
        match self.rigid.filter.as_mut() {
            Some(r) => match r.step(&epoch) {
                Ok(e) => {
                    self.rigid.last_step = k;
                    self.rigid.estimate = Some(StageEstimate {
                        epoch: k,
                        q_rb: e.q_rb,
                        covariance: e.covariance,
                    });
                }
                Err(_) => self.rigid.filter = None,
            },
            None => self.start_rigid_body(k),
        }
    }

    /// Starts the rigid-body filter from the receiver's attitude at `k`.
    fn start_rigid_body(&mut self, k: u64) {
        let cfg = self.config;
        let (q0, cov, source) = self.best_attitude(k);
        if source == AttitudeSource::None {
            return;
        }
        let rb_config = RigidBodyConfig {
            dt: cfg.window_s(),
            sigma_baseline: cfg.baseline_sigma_m,
            sigma_velocity: cfg.velocity_sigma_m_s,
            gate: Some(GateConfidence::P999),
        };
        let Ok(array) = AntennaArray::new(self.geometry.antennas) else {
            return;
        };
        let p0 = cov + Matrix3::identity() * RESTART_VARIANCE;
        self.rigid.filter = RigidBodyFilter::new(&array, rb_config, &q0, &p0).ok();
        self.rigid.last_step = k;
    }
}
