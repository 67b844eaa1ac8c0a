//! What keeps the receiver honest: continuity (losing the attitude and starting cold), the
//! fine filter's residuals (a covariance inflated when they exceed it), the independent
//! integrity check (a fresh integer fix against the fine attitude), and the gyro's fault
//! handling (implausible samples, exclusion, re-admission after it agrees with the signals).

use nalgebra::{Matrix3, Vector3};

use crate::attitude::gyro_aided::GyroAidedReport;
use crate::attitude::one_stage::LockStatus;
use crate::geometry::Quaternion;

use super::carrier::{cold_start, ColdFix, Windowed};
use super::gyro_frame::{nanoseconds, seconds};
use super::{
    AttitudeReceiver, Integrity, IntegrityCheck, LossReason, ReceiverEvent, SnapshotFix,
    StageEstimate,
};

/// Smoothing gain of the residual statistics over blocks.
const NIS_GAIN: f32 = 0.1;

/// Smoothed NIS per degree of freedom above which the residuals are inconsistent with the
/// covariance (a consistent filter gives 1).
const NIS_DEGRADED: f32 = 3.0;

/// Smoothed fraction of satellites the gate rejects above which the prediction itself is
/// wrong (a gyro fault), not one satellite.
const REJECTED_ALARM: f32 = 0.5;

/// χ² with 3 degrees of freedom at 99.9 %: the integrity check's threshold on
/// `dᵀ (P_fine + P_fix)⁻¹ d`.
const CHI2_3_P999: f32 = 16.27;

/// χ² with 3 degrees of freedom at 99.99 %: the threshold of the gyro's correction test.
const CHI2_3_P9999: f32 = 21.11;

/// Fine blocks the gyro's correction test waits for after a (re)start.
const CORRECTION_BLOCKS: u32 = 5;

/// Blocks in a row whose correction test failed that exclude the gyro.
const CORRECTION_FAILURES_TO_EXCLUDE: u32 = 3;

/// Forgetting factor of the gyro's correction test per block (a memory of about five blocks,
/// 100 ms).
const CORRECTION_MEMORY: f32 = 0.8;

/// χ² with 3 degrees of freedom at 99 %: the snapshot check's threshold (it runs every window
/// and needs [`SNAPSHOT_FAILURES_TO_ALARM`] failures in a row, so its false alarms are 1e-6
/// per window).
const CHI2_3_P99: f32 = 11.34;

/// Snapshot checks in a row that fail before the alarm.
const SNAPSHOT_FAILURES_TO_ALARM: u32 = 3;

/// Longest lag (s) of the gyro's samples behind the epochs before it counts as silent (and is
/// excluded).
const GYRO_SILENCE_S: f32 = 0.5;

/// Consecutive gross failures of the fresh-fix check that raise the alarm. A failure (the
/// fix's own tail makes about 3 % of the checks fail in the default flight) degrades the
/// integrity and inflates the covariance by the check's NEES until the next check.
const CHECKS_TO_ALARM: u32 = 2;

/// NEES of a gross disagreement (about ten standard deviations).
const GROSS_NEES: f32 = 100.0;

/// Implausible gyro samples within one window that exclude the gyro.
const FAULTS_TO_EXCLUDE: u32 = 3;

/// Windows between two comparisons of an excluded gyro with the loop (1 s: a stuck gyro on a
/// body turning at 0.6 °/s is 10 mrad off by then).
const REVIEW_WINDOWS: u64 = 10;

/// Largest bias (in turn-on σ) an excluded gyro may imply to be used again.
const MAX_BIAS_SIGMAS: f32 = 5.0;

/// Consecutive agreeing comparisons before an excluded gyro is used again.
const REVIEWS_TO_RESTORE: u32 = 3;

/// Largest change (rad over one review interval) of the bias error an excluded gyro shows
/// from one review to the next for agreement (the loop's noise is about 0.6 mrad).
const GYRO_AGREEMENT_RAD: f32 = 2.5e-3;

/// Variance (rad²) the attitude gains when the fine filter is restarted from a coast.
const RESTART_VARIANCE: f32 = 1e-6;

/// The integrity monitor's state.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub(crate) struct IntegrityMonitor {
    /// Smoothed NIS per degree of freedom of the fine updates.
    nis: f32,
    /// Smoothed fraction of satellites rejected.
    rejected: f32,
    primed: bool,
    /// Implausible gyro samples in the current window.
    window_faults: u32,
    /// Implausible samples since the last review of an excluded gyro.
    faults_since_review: u32,
    /// Windows in a row in which an excluded gyro agreed with the signals.
    agreeing_windows: u32,
    /// The loop's attitude and the gyro's at the last review (gyro excluded).
    last: Option<(Quaternion<f32>, Quaternion<f32>)>,
    /// The bias error (rad/s) the last review showed.
    last_bias_error: Option<Vector3<f32>>,
    /// Last verdict of the independent check.
    checked: Integrity,
    /// The last check's figures.
    pub last_check: Option<IntegrityCheck>,
    /// Checks in a row that failed.
    failed_checks: u32,
    /// Covariance inflation from the last failed check (1 when it passed).
    check_inflation: f32,
    /// Snapshots in a row that disagreed with the fine attitude, and the inflation the last
    /// one implies.
    snapshot_failures: u32,
    snapshot_inflation: f32,
    /// Attitude corrections of the fine updates since the last test, their covariance, and
    /// the blocks they cover.
    correction_sum: Vector3<f32>,
    correction_covariance: Matrix3<f32>,
    correction_blocks: u32,
    /// Tests in a row that failed, the last statistic, and the covariance inflation it
    /// implies (1 when it passed).
    correction_failures: u32,
    correction_inflation: f32,
    pub last_correction_statistic: f32,
    /// The gyro bias applied at the last snapshot that agreed with the gyro-aided attitude,
    /// rad/s: where a restored gyro starts from (a fault may have corrupted the later ones).
    trusted_bias: Option<Vector3<f32>>,
}

impl IntegrityMonitor {
    /// Adds a fine update's residuals and its attitude correction; true when the corrections
    /// of the last [`CORRECTION_BLOCKS`] blocks exceeded what the gyro's noise allows, twice
    /// in a row (the gyro is then wrong).
    pub fn add_block(&mut self, report: &GyroAidedReport<f32>) -> bool {
        let gyro_wrong = self.add_correction(report);
        if report.offered == 0 {
            return gyro_wrong;
        }
        let dof = 2.0 * f32::from(report.offered);
        let nis = (report.nis_sum + report.rejected_nis_sum) / dof;
        // (accepted ≤ offered: the saturation never acts)
        let rejected =
            f32::from(report.offered.saturating_sub(report.accepted)) / f32::from(report.offered);
        if self.primed {
            self.nis += NIS_GAIN * (nis - self.nis);
            self.rejected += NIS_GAIN * (rejected - self.rejected);
        } else {
            self.nis = nis;
            self.rejected = rejected;
            self.primed = true;
        }
        gyro_wrong
    }

    /// The test of the gyro against the carrier phase, every block: `wᵀ C⁻¹ w` of the
    /// attitude corrections `w = Σ ρᵏ δθ_k` over the last blocks (forgetting factor
    /// [`CORRECTION_MEMORY`], about five blocks) with their covariance `C = Σ ρ²ᵏ C_k`.
    fn add_correction(&mut self, report: &GyroAidedReport<f32>) -> bool {
        let rho = CORRECTION_MEMORY;
        self.correction_sum = self.correction_sum * rho + report.attitude_correction;
        self.correction_covariance =
            self.correction_covariance * (rho * rho) + report.correction_covariance;
        self.correction_blocks = self.correction_blocks.saturating_add(1);
        if self.correction_blocks < CORRECTION_BLOCKS {
            return false;
        }
        let (w, c) = (self.correction_sum, self.correction_covariance);
        let statistic = c.cholesky().map_or(0.0, |f| w.dot(&f.solve(&w)));
        self.last_correction_statistic = statistic;

        if statistic > CHI2_3_P9999 {
            // doubt at once: the attitude is reported with the covariance the excess implies
            self.correction_failures = self.correction_failures.saturating_add(1);
            self.correction_inflation = statistic / 3.0;
        } else {
            self.correction_failures = 0;
            self.correction_inflation = 1.0;
        }
        // two blocks in a row would be the same evidence twice: the alarm needs the excess
        // to persist over the memory
        self.correction_failures >= CORRECTION_FAILURES_TO_EXCLUDE
    }

    /// Whether the residuals say the prediction is wrong (most satellites rejected).
    pub fn residuals_inconsistent(&self) -> bool {
        self.primed && self.rejected > REJECTED_ALARM
    }

    /// The factor the reported covariance is inflated by: the residuals' excess over their
    /// covariance when it is significant, else 1.
    pub fn inflation(&self) -> f32 {
        let residuals = if self.primed && self.nis > NIS_DEGRADED {
            self.nis
        } else {
            1.0
        };
        residuals
            .max(self.check_inflation)
            .max(self.snapshot_inflation)
            .max(self.correction_inflation)
    }

    /// The verdict: the last independent check, degraded by inconsistent residuals.
    pub fn verdict(&self) -> Integrity {
        match self.checked {
            Integrity::Consistent if self.inflation() > 1.0 => Integrity::Degraded,
            v => v,
        }
    }

    /// A monitor whose covariance inflation is 1.
    pub fn new() -> Self {
        Self {
            check_inflation: 1.0,
            snapshot_inflation: 1.0,
            correction_inflation: 1.0,
            ..Self::default()
        }
    }

    /// Forgets everything (a cold start).
    pub fn reset(&mut self) {
        *self = Self {
            window_faults: self.window_faults,
            last_check: self.last_check,
            ..Self::new()
        };
    }
}

impl AttitudeReceiver {
    /// After each epoch: the health's view of the fine stage, and the loss of the attitude
    /// when it has coasted too long.
    pub(super) fn check_continuity(&mut self, k: u64) {
        let cfg = self.config;
        let Some(f) = &self.fine else {
            self.health.coasting_s = 0.0;
            self.health.fine_lock = None;
            return;
        };
        let coasting = k.saturating_sub(f.last_update()) as f32 * cfg.epoch_s;
        self.health.coasting_s = coasting;
        self.health.fine_lock = f.lock().or(Some(LockStatus::Locked));
        let limit = if f.is_gyro() {
            cfg.max_coast_s
        } else {
            cfg.max_gap_without_gyro_s
        };
        if f.is_gyro() && self.gyro_silent(k) && !self.health.gyro_excluded {
            self.health.gyro_running = false;
            self.exclude_gyro(k);
            return;
        }
        if coasting > limit {
            let reason = if f.is_gyro() {
                LossReason::CoastTooLong
            } else {
                LossReason::GapWithoutGyro
            };
            self.lose_attitude(k, reason);
        }
        self.health.integrity = if self.fine.is_some() {
            self.integrity.verdict()
        } else {
            Integrity::Unknown
        };
    }

    /// Whether the gyro's samples lag the epochs by more than [`GYRO_SILENCE_S`].
    // (every epoch: integer nanoseconds, no soft float in the 1 ms path)
    fn gyro_silent(&self, k: u64) -> bool {
        let end_ns = (u128::from(k) + 1) * u128::from(self.epoch_ns);
        let silence_ns = u128::from(nanoseconds(GYRO_SILENCE_S));
        self.gyro
            .as_ref()
            .is_some_and(|g| end_ns.saturating_sub(g.time_ns()) > silence_ns)
    }

    /// After a jump of `skipped` epochs to `epoch`: a gap longer than the coast limit loses
    /// the attitude (the fine stage would otherwise resume from a prediction that long).
    pub(super) fn after_jump(&mut self, epoch: u64, skipped: u64) {
        let gap_s = skipped as f64 * seconds(self.config.epoch_s);
        let limit = match &self.fine {
            Some(f) if f.is_gyro() => self.config.max_coast_s,
            _ => self.config.max_gap_without_gyro_s,
        };
        if self.fixed && gap_s > f64::from(limit) {
            self.lose_attitude(epoch, LossReason::EpochJump);
        }
        // the gyro's samples of the gap never came: its clock restarts at the new epoch
        if gap_s > f64::from(GYRO_SILENCE_S) {
            let t = (epoch as f64 + 1.0) * seconds(self.config.epoch_s);
            if let Some(g) = self.gyro.as_mut() {
                g.resync(t);
            }
        }
    }

    /// Drops every fix and stage; the cold start runs again on the next clean window, which
    /// resolves the line biases again too.
    pub(super) fn lose_attitude(&mut self, k: u64, reason: LossReason) {
        self.fine = None;
        // whatever went wrong may have corrupted the estimated line biases: the cold start
        // resolves them again (a bench calibration stays)
        if self.config.line_bias.is_none() {
            self.line_bias.known = false;
        }
        self.fixed = false;
        self.snapshot = None;
        self.rigid = super::RigidStage::default();
        for s in self.slots.iter_mut() {
            s.forget_ambiguities();
        }
        self.integrity.reset();
        self.health.ambiguities_fixed = false;
        self.health.integrity = Integrity::Unknown;
        self.health.cold_restarts = self.health.cold_restarts.saturating_add(1);
        self.events
            .push(ReceiverEvent::AttitudeLost { epoch: k, reason });
    }

    /// The fine stage failed (a refused step, false lock): restarted from the best attitude
    /// there is, or dropped (and the attitude lost) when there is none.
    pub(super) fn restart_fine(&mut self, k: u64) {
        let (q, cov, source) = self.best_attitude(k);
        if source == super::AttitudeSource::None {
            self.lose_attitude(k, LossReason::IntegrityFailure);
            return;
        }
        let m = self.gyro_attitude(k);
        let cov = cov + Matrix3::identity() * RESTART_VARIANCE;
        self.start_fine(k, k, &q, &cov, &m);
        if self.fine.is_none() {
            self.lose_attitude(k, LossReason::IntegrityFailure);
        }
    }

    /// The independent check: a fresh integer fix on this window compared with the fine
    /// attitude at the window's centre. A disagreement restarts the fine filter from the fix
    /// (and replaces the integers); an agreement marks the attitude consistent.
    pub(super) fn check_integrity(
        &mut self,
        k: u64,
        centre: u64,
        windows: &[Windowed],
        m_centre: &Quaternion<f32>,
    ) {
        if self.any_blocked() {
            return;
        }
        let cfg = self.config;
        let sigma_ref = cfg.ambiguity.phase_sigma_m / cfg.wavelength_m();
        // double differences: the fix depends neither on the fine attitude nor on the line
        // biases it estimated
        let Some(cold) = cold_start(&self.solvers.resolver, windows, sigma_ref, None) else {
            return;
        };
        let fix = &cold.solution;
        let (q_fine, p_fine, source) = self.best_attitude(centre);
        if source == super::AttitudeSource::None {
            return;
        }
        let d = (q_fine.conjugate() * fix.q_rb).to_rotation_vector();
        let s = p_fine + fix.covariance;
        let nees = s.cholesky().map_or(f32::INFINITY, |c| d.dot(&c.solve(&d)));
        let largest = |p: &Matrix3<f32>| crate::sqrtf(p.diagonal().max().max(0.0));
        self.integrity.last_check = Some(IntegrityCheck {
            epoch: centre,
            angle_rad: d.norm(),
            nees,
            fix_sigma_rad: largest(&fix.covariance),
            fine_sigma_rad: largest(&p_fine),
            alarm: false,
        });
        if nees <= CHI2_3_P999 {
            self.integrity.checked = Integrity::Consistent;
            self.integrity.failed_checks = 0;
            self.integrity.check_inflation = 1.0;
            return;
        }
        // doubt: the attitude is reported with the covariance the disagreement implies; only
        // a gross disagreement that persists restarts (the fix is the less precise of the two,
        // and its tail is heavier than its covariance says)
        self.integrity.checked = Integrity::Degraded;
        self.integrity.check_inflation = nees / 3.0;
        if nees <= GROSS_NEES {
            self.integrity.failed_checks = 0;
            return;
        }
        self.integrity.failed_checks = self.integrity.failed_checks.saturating_add(1);
        if self.integrity.failed_checks < CHECKS_TO_ALARM {
            return;
        }
        self.raise_integrity_alarm(k, centre, d.norm(), cold, m_centre);
    }

    /// A gross disagreement that persisted: the alarm (health, event), then the fresh fix's
    /// integers, line biases and attitude replace the fine filter's.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    fn raise_integrity_alarm(
        &mut self,
        k: u64,
        centre: u64,
        angle_rad: f32,
        cold: ColdFix,
        m_centre: &Quaternion<f32>,
    ) {
        if let Some(c) = self.integrity.last_check.as_mut() {
            c.alarm = true;
        }
        self.integrity.failed_checks = 0;
        self.integrity.check_inflation = 1.0;
        self.integrity.checked = Integrity::Alarm;
        self.health.integrity = Integrity::Alarm;
        let angle_mrad = (angle_rad * 1e3).min(f32::from(u16::MAX)) as u16;
        self.events.push(ReceiverEvent::IntegrityAlarm {
            epoch: k,
            angle_mrad,
        });
        for (slot, kk) in &cold.slots {
            if let Some(s) = self.slots.get_mut(*slot) {
                s.ambiguity = [Some(kk[0]), Some(kk[1])];
            }
        }
        if let Some((bias, sigma)) = cold.line_bias {
            self.line_bias = super::LineBias::from_cycles(bias, sigma);
        }
        let fix = cold.solution;
        self.snapshot = Some(SnapshotFix {
            estimate: StageEstimate {
                epoch: centre,
                q_rb: fix.q_rb,
                covariance: fix.covariance,
            },
            m: *m_centre,
        });
        self.start_fine(k, centre, &fix.q_rb, &fix.covariance, m_centre);
    }

    /// The fast check, every snapshot: the snapshot (gyro-free, integers kept by the upkeep)
    /// against the fine attitude at its epoch. One disagreement degrades and inflates, a
    /// second in a row restarts the fine filter from the snapshot — without the gyro when it
    /// was gyro-aided (the gyro is the suspect; it is reviewed and re-admitted when it agrees
    /// with the signals again).
    pub(super) fn compare_with_snapshot(
        &mut self,
        k: u64,
        snapshot: &StageEstimate,
        m_centre: &Quaternion<f32>,
    ) {
        let Some(f) = &self.fine else {
            return;
        };
        if f.source_at(snapshot.epoch, &self.config).is_none() {
            return;
        }
        let q_fine = f.attitude(m_centre);
        let p_fine = f.covariance_at(snapshot.epoch, m_centre, &self.config);
        let d = (q_fine.conjugate() * snapshot.q_rb).to_rotation_vector();
        let s = p_fine + snapshot.covariance;
        let nees = s.cholesky().map_or(f32::INFINITY, |c| d.dot(&c.solve(&d)));
        if nees <= CHI2_3_P99 {
            self.integrity.snapshot_failures = 0;
            self.integrity.snapshot_inflation = 1.0;
            if f.is_gyro() {
                self.integrity.trusted_bias = self.gyro.as_ref().map(|g| g.bias);
            }
            return;
        }
        self.integrity.snapshot_inflation = nees / 3.0;
        // the loop's covariance is its design noise, not an error bound under dynamics: it
        // is only restarted on a gross disagreement
        let gyro_stage = f.is_gyro();
        if !gyro_stage && nees <= GROSS_NEES {
            self.integrity.snapshot_failures = 0;
            return;
        }
        self.integrity.snapshot_failures = self.integrity.snapshot_failures.saturating_add(1);
        if self.integrity.snapshot_failures < SNAPSHOT_FAILURES_TO_ALARM {
            return;
        }
        self.integrity.snapshot_failures = 0;
        self.integrity.snapshot_inflation = 1.0;
        let angle_mrad = (d.norm() * 1e3).min(f32::from(u16::MAX)) as u16;
        self.events.push(ReceiverEvent::IntegrityAlarm {
            epoch: k,
            angle_mrad,
        });
        self.health.integrity = Integrity::Alarm;
        self.integrity.checked = Integrity::Alarm;
        // the gyro-aided attitude ran away from a gyro-free one: the gyro is the suspect
        // (it is re-admitted within seconds when it agrees with the signals again)
        if self.fine.as_ref().is_some_and(|f| f.is_gyro()) && !self.health.gyro_excluded {
            self.exclude_gyro(k);
        }
        let q = snapshot.q_rb * m_centre.conjugate() * self.gyro_attitude(k);
        let q = q.normalize().unwrap_or(q);
        self.start_fine(k, k, &q, &snapshot.covariance, &self.gyro_attitude(k));
    }

    /// After every gyro sample: health, fault counting and exclusion, and the calibration
    /// references (paper 001) at the window boundaries from the fine attitude.
    pub(super) fn after_gyro_sample(&mut self, plausible: bool) {
        self.health.gyro_running = true;
        if !plausible {
            self.health.gyro_faults = self.health.gyro_faults.saturating_add(1);
            self.integrity.window_faults = self.integrity.window_faults.saturating_add(1);
            if self.integrity.window_faults >= FAULTS_TO_EXCLUDE && !self.health.gyro_excluded {
                let k = self.epochs.last_closed().unwrap_or(0);
                self.exclude_gyro(k);
            }
        }
        self.calibration_reference();
    }

    /// At a window boundary of the gyro's samples, the fine attitude as the calibrator's
    /// reference.
    fn calibration_reference(&mut self) {
        let Some(g) = self.gyro.as_ref() else {
            return;
        };
        let per_window =
            libm::round(seconds(self.config.window_s()) / seconds(g.config.sample_interval_s));
        let at_window = g.at_step()
            && per_window >= 1.0
            && g.samples().checked_rem(per_window as u64) == Some(0);
        let fine_ok = self
            .fine
            .as_ref()
            .is_some_and(|f| f.is_gyro() && !self.health.gyro_excluded);
        if !at_window || !fine_ok || self.any_blocked() {
            return;
        }
        let m = g.attitude_at(g.time_s());
        let Some(q) = self.fine.as_ref().map(|f| f.attitude(&m)) else {
            return;
        };
        let epoch = self.epochs.last_closed().unwrap_or(0);
        let Some(g) = self.gyro.as_mut() else {
            return;
        };
        if !g.calibrating() {
            g.start_calibration(&q);
        } else if g.add_reference(&q) {
            self.health.gyro_calibrated = true;
            self.events.push(ReceiverEvent::GyroCalibrated { epoch });
        }
    }

    /// Excludes the gyro: the fine stage continues as the loop from its current attitude.
    pub(super) fn exclude_gyro(&mut self, k: u64) {
        let (q, cov, source) = self.best_attitude(k);
        // the bias the fault may have dragged along is not kept: the reviews compare the gyro
        // corrected by the last trusted one
        if let (Some(g), Some(b)) = (self.gyro.as_mut(), self.integrity.trusted_bias) {
            g.bias = b;
        }
        self.health.gyro_excluded = true;
        self.integrity.agreeing_windows = 0;
        self.integrity.last = None;
        self.events.push(ReceiverEvent::GyroExcluded { epoch: k });
        // the snapshot can no longer be carried by the gyro
        self.snapshot = None;
        if source == super::AttitudeSource::None {
            self.fine = None;
            return;
        }
        let cov = cov * self.integrity.inflation() + Matrix3::identity() * RESTART_VARIANCE;
        // the body's rate as the gyro last saw it plausibly (the loop's frame is the body's)
        let rates = self.gyro.as_ref().map_or_else(Vector3::zeros, |g| g.rate());
        self.fine =
            super::fine::FineStage::start_loop(&self.config, &q, &cov, &self.line_bias, rates, k)
                .ok();
        self.integrity.reset();
    }

    /// At each window end: counts the gyro's implausible samples; with the gyro excluded, every
    /// [`REVIEW_WINDOWS`] compares the rotation the gyro measured since the last review with
    /// the loop's, as the bias error it implies. After [`REVIEWS_TO_RESTORE`] reviews in a
    /// row without implausible samples, with that bias error steady (a fault changes it) and
    /// the bias it implies plausible (within [`MAX_BIAS_SIGMAS`] turn-on σ: a stuck gyro on a
    /// turning body implies the body's rate), the gyro is used again with that bias, and the
    /// fine stage restarts gyro-aided from the loop's attitude.
    pub(super) fn review_excluded_gyro(&mut self, k: u64) {
        let faults = core::mem::take(&mut self.integrity.window_faults);
        self.integrity.faults_since_review =
            self.integrity.faults_since_review.saturating_add(faults);
        if !self.health.gyro_excluded || self.windows % REVIEW_WINDOWS != 0 {
            return;
        }
        let faulty = core::mem::take(&mut self.integrity.faults_since_review) > 0;
        let t = (k as f64 + 0.5) * seconds(self.config.epoch_s);
        let (Some(g), Some(f)) = (&self.gyro, &self.fine) else {
            return;
        };
        let m = g.attitude_at(t);
        let q = f.attitude(&Quaternion::identity());
        let locked = f.lock() == Some(LockStatus::Locked);
        let bias = g.bias;
        let previous = self.integrity.last.replace((q, m));
        let interval = (REVIEW_WINDOWS as f32) * self.config.window_s();
        // the bias error the gyro shows against the loop: (gnssᵀ gyro) ≈ exp([(b − b̂)τ]×)
        let apparent = match previous {
            Some((q0, m0)) if locked && !faulty => {
                let gnss = q0.conjugate() * q;
                let gyro = m0.conjugate() * m;
                Some((gnss.conjugate() * gyro).to_rotation_vector() / interval)
            }
            _ => None,
        };
        let max_bias = self
            .gyro
            .as_ref()
            .map_or(0.0, |g| g.config.turn_on_bias_sigma)
            * MAX_BIAS_SIGMAS;
        let consistent = match (apparent, self.integrity.last_bias_error) {
            (Some(e), Some(e0)) => {
                (e - e0).norm() * interval <= GYRO_AGREEMENT_RAD && (bias + e).amax() <= max_bias
            }
            _ => false,
        };
        self.integrity.last_bias_error = apparent;
        self.integrity.agreeing_windows = if consistent {
            self.integrity.agreeing_windows.saturating_add(1)
        } else {
            0
        };
        if self.integrity.agreeing_windows >= REVIEWS_TO_RESTORE {
            if let (Some(g), Some(e)) = (self.gyro.as_mut(), apparent) {
                g.bias += e;
            }
            self.restore_gyro(k);
        }
    }

    /// The gyro is used again: the fine stage restarts gyro-aided from the loop's attitude.
    fn restore_gyro(&mut self, k: u64) {
        self.health.gyro_excluded = false;
        self.integrity.last_bias_error = None;
        self.integrity.agreeing_windows = 0;
        self.integrity.last = None;
        self.events.push(ReceiverEvent::GyroRestored { epoch: k });
        let Some(f) = &self.fine else {
            return;
        };
        let q = f.attitude(&Quaternion::identity());
        let cov = f.covariance_at(k, &Quaternion::identity(), &self.config)
            + Matrix3::identity() * RESTART_VARIANCE;
        let m = self.gyro_attitude(k);
        self.start_fine(k, k, &q, &cov, &m);
    }
}
