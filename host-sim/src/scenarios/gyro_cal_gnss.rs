//! `gyro-cal --variant gnss-ref`: in-flight calibration of a MEMS gyro on a tumbling
//! microsatellite against a GNSS-like attitude reference, 10 minutes.
//!
//! Truth (f64, [`crate::truth::tumble`]): a torque-free asymmetric body tumbling at about
//! 7°/s; a MEMS gyro (100 Hz increments) with scale factors, symmetric misalignments and
//! biases (the paper's model `D = [D_I D_II E₃]`), angle random walk 0.3°/√h and a bias
//! random walk of 2°/h/√h; a reference attitude of the antenna frame (mounted at an angle
//! unknown to the calibrator) with white noise 0.05° per axis at 10 Hz, no drift.
//!
//! Calibration (core, f32): one calibrator over the 10 minutes, anchored on the first reference
//! sample, whose own noise is estimated (drift model [`AnchorErrorAndDrift`], 18 unknowns).
//! Every [`RELINEARIZE_S`] the accumulated equations are solved and the estimate `ĉ` is
//! applied to the following increments ([`GyroCalibrator::set_gyro_correction`]): the
//! computed attitude stays close to the truth and the first-order model stays valid. A weak
//! prior (datasheet bounds) makes the first solves, over which the rate hardly changes
//! direction, well posed. The same run is repeated in f64, and over a small Monte Carlo.
//!
//! What limits it: the motion (a tumble about the major axis: ω₃ varies by ±10 % only, so the
//! scale factor c₃ and the bias c₉ are nearly collinear) and the angle random walk (the
//! equations' errors are then a random walk, not white: the formal standard deviations of the
//! least squares are optimistic). The figure that matters for dead reckoning, the rate error
//! `D(ω) (ĉ − c)` along the actual motion, is reported next to the parameter errors.

use gnss_attitude::geometry::Quaternion;
use gnss_attitude::gyro::{
    AnchorErrorAndDrift, AttitudePropagator, CalibratorConfig, GyroCalibrator,
    LeastSquaresAccumulator, ScaleMisalignmentBias, SqrtInformation,
};
use gnss_attitude::Real;
use nalgebra::{SVector, Vector3};
use rayon::prelude::*;

use super::gyro_cal::{c, quat, quat64, to_f64};
use super::{Outcome, RunContext};
use crate::outcome::Suffixed;
use crate::report::{plot_panels, progress, write_csv, Panel, Series};
use crate::stats;
use crate::truth::gyro::paper_d;
use crate::truth::tumble::{generate_tumble_run, MemsGyro, TumbleRun as Truth, TumbleSetup};

/// Gyro sample interval (s): 100 Hz.
const H: f64 = 0.01;
/// Reference epochs every this many gyro samples (10 Hz).
const REF_EVERY: usize = 10;
/// Calibration span (s).
const DURATION_S: f64 = 600.0;
/// Interval between re-linearizations (solve, then correct the gyro with `ĉ`), s.
pub const RELINEARIZE_S: f64 = 30.0;
/// Dead reckoning after the calibration, to show what it buys (s).
const COAST_S: f64 = 60.0;
/// RK4 sub-steps of the truth per gyro sample.
const SUBSTEPS: usize = 5;
/// Monte Carlo runs.
const RUNS: usize = 12;
/// Reference noise, rad per axis (0.05°).
const SIGMA_REF: f64 = 0.05 * std::f64::consts::PI / 180.0;
/// Angle random walk, rad/√s (0.3°/√h).
const ARW: f64 = 0.3 * std::f64::consts::PI / 180.0 / 60.0;
/// Bias random walk, rad/s/√s (2°/h/√h).
const BIAS_RW: f64 = 2.0 * std::f64::consts::PI / 180.0 / 3600.0 / 60.0;

/// The gyro's errors: scale factors, symmetric misalignments (rad), initial biases (rad/s).
fn c_true() -> SVector<f64, 9> {
    SVector::from([8e-4, -5e-4, 1.2e-3, 1e-3, -7e-4, 5e-4, 1e-4, -1.5e-4, 6e-5])
}

/// Prior standard deviations (datasheet bounds) of `c` and of the drift `d`.
fn prior_sigma() -> SVector<f64, 12> {
    SVector::from([
        2e-3, 2e-3, 2e-3, 2e-3, 2e-3, 2e-3, 1e-3, 1e-3, 1e-3, 1e-5, 1e-5, 1e-5,
    ])
}

type GnssCal<T> =
    GyroCalibrator<ScaleMisalignmentBias, AnchorErrorAndDrift, SqrtInformation<18, T>, 9, 6, 18, T>;

/// The estimate at one re-linearization, for the convergence plot.
#[derive(Clone, Copy)]
struct Snapshot {
    t: f64,
    c: SVector<f64, 9>,
    c_std: SVector<f64, 9>,
}

struct CalResult {
    c: SVector<f64, 9>,
    d: Vector3<f64>,
    c_std: SVector<f64, 9>,
    d_std: Vector3<f64>,
    w_post: Vector3<f64>,
    rank: usize,
    cond: f64,
    cond_equilibrated: f64,
    epochs_used: u32,
    epochs_skipped: u32,
    history: Vec<Snapshot>,
}

fn calibrate<T: Real>(truth: &Truth) -> anyhow::Result<CalResult> {
    let sigma_z = SIGMA_REF / 2.0; // half-angle noise of one reference component
    let mut acc = SqrtInformation::<18, T>::new();
    let prior = prior_sigma();
    for (j, i) in (3..12).chain(15..18).enumerate() {
        let row = SVector::<T, 18>::from_fn(|r, _| {
            if r == i {
                c(sigma_z / prior[j])
            } else {
                T::zero()
            }
        });
        acc.add_row(&row, T::zero())?;
    }
    let per_solve = (RELINEARIZE_S / H).round() as usize;
    let n_cal = (DURATION_S / H).round() as usize;
    let mut cal = GnssCal::<T>::new(
        CalibratorConfig::new(c(H)),
        ScaleMisalignmentBias,
        AnchorErrorAndDrift,
        acc,
        quat::<T>(&truth.m0),
        quat(&truth.reference[0]),
    )?;
    let mut history = Vec::new();
    let mut last = None;
    for k in 1..=n_cal {
        cal.push_increment(&truth.gyro[k].map(c::<T>))?;
        if k % REF_EVERY == 0 {
            cal.add_reference(&quat(&truth.reference[k]))?;
        }
        if k % per_solve == 0 {
            // re-linearize: integrate the following increments with the latest estimate
            let est = cal.solve()?;
            cal.set_gyro_correction(est.c)?;
            history.push(Snapshot {
                t: k as f64 * H,
                c: est.c.map(to_f64),
                c_std: est.c_std.map(to_f64),
            });
            last = Some(est);
        }
    }
    let est = last.ok_or_else(|| anyhow::anyhow!("no solve"))?;
    let m_end = cal.corrected_attitude(&est);
    let (used, skipped) = (cal.counters().used, cal.counters().skipped_small_p0);
    let mut w = truth.lambda[n_cal] * quat64(&m_end).conjugate();
    if w.w < 0.0 {
        w = Quaternion::new(-w.w, -w.x, -w.y, -w.z);
    }
    Ok(CalResult {
        c: est.c.map(to_f64),
        d: est.d.fixed_rows::<3>(3).map(to_f64),
        c_std: est.c_std.map(to_f64),
        d_std: est.d_std.fixed_rows::<3>(3).map(to_f64),
        w_post: w.vector(),
        rank: est.solution.observability.rank,
        cond: to_f64(est.solution.observability.condition),
        cond_equilibrated: to_f64(est.solution.observability.equilibrated_condition),
        epochs_used: used,
        epochs_skipped: skipped,
        history,
    })
}

/// Attitude error (deg) after coasting from the true attitude at the end of the calibration
/// span for [`COAST_S`] on the gyro corrected with `c_hat` (zero: the raw gyro).
fn coast_error_deg(truth: &Truth, c_hat: &SVector<f64, 9>) -> anyhow::Result<f64> {
    let n_cal = (DURATION_S / H).round() as usize;
    let mut prop = AttitudePropagator::new(truth.lambda[n_cal])?;
    for k in (n_cal + 1)..truth.gyro.len() {
        let theta = truth.gyro[k];
        let mut d = paper_d(&theta);
        for i in 0..3 {
            d[(i, 6 + i)] = H;
        }
        prop.push(&(theta - d * c_hat))?;
    }
    let end = truth.lambda.last().copied().unwrap_or(truth.m0);
    Ok(prop.attitude().angle_to(&end).to_degrees())
}

struct RunOutput {
    truth_c: SVector<f64, 9>,
    r32: CalResult,
    r64: CalResult,
    coast_raw: f64,
    coast_cal: f64,
    rate_err_raw: f64,
    rate_err_cal: f64,
}

/// RMS over the calibration span of the rate error `|D(ω) e|` (rad/s) left by a gyro-error
/// error `e` (the whole `c` without calibration, `ĉ − c` after it), along the actual motion.
fn rate_error_rms(truth: &Truth, e: &SVector<f64, 9>) -> f64 {
    let n_cal = (DURATION_S / H).round() as usize;
    let v: Vec<f64> = (1..=n_cal)
        .step_by(10)
        .map(|k| (paper_d(&(truth.gyro[k] / H)) * e).norm())
        .collect();
    stats::rms(&v)
}

/// The set-up of one run; `random_walks = false` switches the angle and bias random walks off
/// (the white reference noise stays), to show what limits the calibration.
fn setup(random_walks: bool) -> TumbleSetup {
    let rw = if random_walks { 1.0 } else { 0.0 };
    TumbleSetup {
        sample_interval: H,
        substeps: SUBSTEPS,
        samples: ((DURATION_S + COAST_S) / H).round() as usize,
        mean_over: (DURATION_S / H).round() as usize,
        reference_noise: SIGMA_REF,
        gyro: MemsGyro {
            c: c_true(),
            arw: rw * ARW,
            bias_rw: rw * BIAS_RW,
        },
    }
}

fn one_run(seed: u64, run: usize, random_walks: bool) -> anyhow::Result<RunOutput> {
    let truth = generate_tumble_run(seed, run, &setup(random_walks));
    let r32 = calibrate::<f32>(&truth)?;
    let r64 = calibrate::<f64>(&truth)?;
    Ok(RunOutput {
        truth_c: truth.c_mean,
        coast_raw: coast_error_deg(&truth, &SVector::zeros())?,
        coast_cal: coast_error_deg(&truth, &r32.c)?,
        rate_err_raw: rate_error_rms(&truth, &truth.c_mean),
        rate_err_cal: rate_error_rms(&truth, &(r32.c - truth.c_mean)),
        r32,
        r64,
    })
}

/// rad/s to °/h.
const DEG_PER_H: f64 = 180.0 / std::f64::consts::PI * 3600.0;

crate::metrics! {
    /// Monte Carlo figures of one set of runs (RMS over the runs unless named otherwise).
    pub struct Summary {
        /// RMS error of c₁…₉ per parameter.
        #[metric(unit = "1, 1, 1, rad, rad, rad, rad/s, rad/s, rad/s", rename = "dc_rms_mc")] pub dc_rms: Vec<f64>,
        /// RMS of the estimated drift d per axis.
        #[metric(unit = "rad/s", rename = "dd_rms_mc")] pub dd_rms: Vec<f64>,
        /// Mean formal standard deviation of c₁…₉.
        #[metric(unit = "as dc_rms_mc", rename = "c_std_mean_mc")] pub c_std_mean: Vec<f64>,
        /// Scale-factor error.
        #[metric(unit = "ppm", rename = "scale_err_ppm_rms")] pub scale_ppm: f64,
        /// Misalignment error.
        #[metric(unit = "µrad", rename = "misalignment_err_urad_rms")] pub misalign_urad: f64,
        /// Bias error.
        #[metric(unit = "°/h", rename = "bias_err_deg_per_h_rms")] pub bias_deg_h: f64,
        /// Drift error.
        #[metric(unit = "°/h", rename = "drift_err_deg_per_h_rms")] pub drift_deg_h: f64,
        /// Rate error along the motion without calibration.
        #[metric(unit = "°/h", rename = "rate_err_deg_per_h_raw_rms")] pub rate_raw: f64,
        /// Rate error along the motion after calibration.
        #[metric(unit = "°/h", rename = "rate_err_deg_per_h_calibrated_rms")] pub rate_cal: f64,
        /// Attitude error after a 60 s coast on the raw gyro.
        #[metric(unit = "deg", rename = "coast60_err_deg_raw_rms")] pub coast_raw: f64,
        /// Attitude error after a 60 s coast on the calibrated gyro.
        #[metric(unit = "deg", rename = "coast60_err_deg_calibrated_rms")] pub coast_cal: f64,
        /// Attitude error at the end of the calibration span.
        #[metric(unit = "rad", rename = "w_post_rms")] pub w_post: f64,
        /// Largest over the runs of max|ĉ₃₂ − ĉ₆₄| / max|ĉ₆₄ − c|.
        #[metric(unit = "", rename = "f32_vs_f64_over_error_max")] pub f32_vs_f64: f64,
    }
}

crate::metrics! {
    /// Metrics of `gyro-cal --variant gnss-ref` (run 0 unless named `_mc` or `_rms`).
    pub struct Metrics {
        /// Error of c₁…₉ (scale factors, misalignments, biases), f32.
        #[metric(unit = "1, 1, 1, rad, rad, rad, rad/s, rad/s, rad/s")] pub dc: Vec<f64>,
        /// Estimated drift d of the reference.
        #[metric(unit = "rad/s")] pub dd: Vec<f64>,
        /// Attitude error at the end of the span (half-angle vector).
        #[metric(unit = "")] pub w_post: Vec<f64>,
        /// Rank of the last solve.
        #[metric(unit = "")] pub rank: usize,
        /// Condition number of the last solve.
        #[metric(unit = "")] pub cond: f64,
        /// Condition number after equilibration.
        #[metric(unit = "")] pub cond_equilibrated: f64,
        /// c error of the f64 run.
        #[metric(unit = "as dc")] pub dc_f64: Vec<f64>,
        /// d of the f64 run.
        #[metric(unit = "rad/s")] pub dd_f64: Vec<f64>,
        /// Attitude error of the f64 run.
        #[metric(unit = "")] pub w_post_f64: Vec<f64>,
        /// True c averaged over the span (the biases walk).
        #[metric(unit = "as dc")] pub c_true_mean: Vec<f64>,
        /// Formal standard deviations of c.
        #[metric(unit = "as dc")] pub c_std: Vec<f64>,
        /// Formal standard deviations of d.
        #[metric(unit = "rad/s")] pub d_std: Vec<f64>,
        /// Monte Carlo runs.
        #[metric(unit = "")] pub runs: usize,
        /// The Monte Carlo with the MEMS random walks.
        #[metric(flatten)] #[serde(flatten)] pub mc: Summary,
        /// The Monte Carlo without the angle and bias random walks.
        #[metric(suffixed = "_no_random_walk")] #[serde(flatten)] pub mc_no_random_walk: Suffixed<Summary>,
        /// Solves over the span (one per re-linearization).
        #[metric(unit = "")] pub solves: usize,
        /// Interval between re-linearizations.
        #[metric(unit = "s")] pub relinearize_s: f64,
        /// Reference epochs used.
        #[metric(unit = "")] pub epochs_used: u32,
        /// Reference epochs skipped.
        #[metric(unit = "")] pub epochs_skipped: u32,
    }
}

impl Summary {
    fn of(runs: &[RunOutput]) -> Self {
        let rms_of =
            |f: &dyn Fn(&RunOutput) -> f64| stats::rms(&runs.iter().map(f).collect::<Vec<_>>());
        let group = |lo: usize, hi: usize| {
            let v: Vec<f64> = runs
                .iter()
                .flat_map(|r| (lo..hi).map(move |i| (r.r32.c - r.truth_c)[i]))
                .collect();
            stats::rms(&v)
        };
        let dd_rms: Vec<f64> = (0..3).map(|i| rms_of(&|r| r.r32.d[i])).collect();
        Self {
            dc_rms: (0..9)
                .map(|i| rms_of(&|r| (r.r32.c - r.truth_c)[i]))
                .collect(),
            c_std_mean: (0..9)
                .map(|i| runs.iter().map(|r| r.r32.c_std[i]).sum::<f64>() / runs.len() as f64)
                .collect(),
            scale_ppm: group(0, 3) * 1e6,
            misalign_urad: group(3, 6) * 1e6,
            bias_deg_h: group(6, 9) * DEG_PER_H,
            drift_deg_h: stats::rms(&dd_rms) * DEG_PER_H,
            dd_rms,
            rate_raw: rms_of(&|r| r.rate_err_raw) * DEG_PER_H,
            rate_cal: rms_of(&|r| r.rate_err_cal) * DEG_PER_H,
            coast_raw: rms_of(&|r| r.coast_raw),
            coast_cal: rms_of(&|r| r.coast_cal),
            w_post: rms_of(&|r| r.r32.w_post.norm()),
            f32_vs_f64: runs
                .iter()
                .map(|r| (r.r32.c - r.r64.c).amax() / (r.r64.c - r.truth_c).amax())
                .fold(0.0, f64::max),
        }
    }
}

fn vec(v: impl IntoIterator<Item = f64>) -> Vec<f64> {
    v.into_iter().collect()
}

pub(crate) fn run(ctx: &RunContext) -> anyhow::Result<Outcome> {
    let bar = progress(2 * RUNS as u64, "gyro-cal gnss");
    let mc = |random_walks: bool| {
        (0..RUNS)
            .into_par_iter()
            .map(|r| {
                let out = one_run(ctx.seed, r, random_walks);
                bar.inc(1);
                out
            })
            .collect::<anyhow::Result<Vec<RunOutput>>>()
    };
    let runs = mc(true)?;
    let quiet = mc(false)?;
    bar.finish_and_clear();
    let r0 = &runs[0];
    let m = metrics(r0, Summary::of(&runs), Summary::of(&quiet));
    let mut outcome = Outcome::new(&m)?;
    outcome.summary = summary(r0, &m);
    if let Some(dir) = &ctx.out_dir {
        outcome.files = write_files(dir, r0)?;
    }
    Ok(outcome)
}

fn metrics(r0: &RunOutput, all: Summary, rwfree: Summary) -> Metrics {
    Metrics {
        dc: vec((r0.r32.c - r0.truth_c).iter().copied()),
        dd: vec(r0.r32.d.iter().copied()),
        w_post: vec(r0.r32.w_post.iter().copied()),
        rank: r0.r32.rank,
        cond: r0.r32.cond,
        cond_equilibrated: r0.r32.cond_equilibrated,
        dc_f64: vec((r0.r64.c - r0.truth_c).iter().copied()),
        dd_f64: vec(r0.r64.d.iter().copied()),
        w_post_f64: vec(r0.r64.w_post.iter().copied()),
        c_true_mean: vec(r0.truth_c.iter().copied()),
        c_std: vec(r0.r32.c_std.iter().copied()),
        d_std: vec(r0.r32.d_std.iter().copied()),
        runs: RUNS,
        mc: all,
        mc_no_random_walk: Suffixed {
            suffix: "_no_random_walk",
            inner: rwfree,
        },
        solves: r0.r32.history.len(),
        relinearize_s: RELINEARIZE_S,
        epochs_used: r0.r32.epochs_used,
        epochs_skipped: r0.r32.epochs_skipped,
    }
}

fn summary(r0: &RunOutput, m: &Metrics) -> Vec<String> {
    let deg_h = DEG_PER_H;
    let c = c_true();
    let mut lines = vec![
        format!(
            "tumbling microsatellite (~7°/s), MEMS gyro at 100 Hz (ARW 0.3°/√h, bias RW 2°/h/√h), reference 0.05°/axis at 10 Hz; {DURATION_S} s, {} solves (re-linearized every {RELINEARIZE_S} s); {RUNS} runs",
            r0.r32.history.len()
        ),
        format!(
            "true errors: scale factors {:.0}…{:.0} ppm, misalignments {:.0}…{:.0} µrad, biases {:.0}…{:.0}°/h",
            c[1] * 1e6, c[2] * 1e6, c[4] * 1e6, c[3] * 1e6, c[8] * deg_h, c[7].abs() * deg_h
        ),
    ];
    for (name, s) in [
        ("MEMS gyro", &m.mc),
        ("without angle/bias random walk", &m.mc_no_random_walk.inner),
    ] {
        lines.push(format!(
            "{name}: recovered to scale {:.0} ppm, misalignment {:.0} µrad, bias {:.2}°/h, drift d {:.2}°/h (RMS; formal σ of bias {:.2}°/h)",
            s.scale_ppm, s.misalign_urad, s.bias_deg_h, s.drift_deg_h,
            stats::rms(&s.c_std_mean[6..]) * deg_h
        ));
        lines.push(format!(
            "    rate error along the motion {:.2}°/h (raw {:.1}°/h); 60 s coast {:.3}° (raw {:.3}°); attitude at 600 s {:.1e} rad; f32 vs f64 ≤ {:.1e} of the error",
            s.rate_cal, s.rate_raw, s.coast_cal, s.coast_raw, s.w_post, s.f32_vs_f64
        ));
    }
    lines
}

/// Run 0's calibration error after each solve, with the formal σ, as CSV and plot.
fn write_files(dir: &std::path::Path, r0: &RunOutput) -> anyhow::Result<Vec<std::path::PathBuf>> {
    let h = &r0.r32.history;
    let csv = dir.join("gyro_cal_gnss_ref_convergence.csv");
    let header = [
        "t_s", "dc1", "dc2", "dc3", "dc4", "dc5", "dc6", "dc7", "dc8", "dc9", "std1", "std2",
        "std3", "std4", "std5", "std6", "std7", "std8", "std9",
    ];
    write_csv(
        &csv,
        &header,
        h.iter().map(|s| {
            let mut row = vec![s.t];
            row.extend((s.c - r0.truth_c).iter());
            row.extend(s.c_std.iter());
            row
        }),
    )?;
    let panel = |name: &str, range: std::ops::Range<usize>, scale: f64| Panel {
        y_label: name.to_string(),
        series: range
            .clone()
            .map(|i| {
                Series::line(
                    format!("δc{}", i + 1),
                    h.iter()
                        .map(|s| (s.t, (s.c - r0.truth_c)[i] * scale))
                        .collect(),
                    i - range.start,
                )
            })
            .chain(range.clone().map(|i| {
                Series::bound(
                    format!("σ{}", i + 1),
                    h.iter().map(|s| (s.t, s.c_std[i] * scale)).collect(),
                    i - range.start,
                )
            }))
            .collect(),
    };
    let png = dir.join("gyro_cal_gnss_ref_convergence.png");
    plot_panels(
        &png,
        "gyro-cal gnss-ref: calibration error after each solve, with formal σ",
        "time (s)",
        &[
            panel("scale error (ppm)", 0..3, 1e6),
            panel("misalignment error (µrad)", 3..6, 1e6),
            panel("bias error (°/h)", 6..9, DEG_PER_H),
        ],
    )?;
    Ok(vec![csv, png])
}
