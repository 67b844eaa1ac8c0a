//! `gyro-cal`: in-flight gyro calibration by sequential least squares against a reference
//! attitude (paper 001, Tkachenko), with the core's `gyro` module.
//!
//! Variants `exact`, `quantized`, `centered-5.5`, `centered-5.6` reproduce the paper's §6
//! experiment as the seed specification gives it: 30 s of piecewise-constant rates, gyro
//! samples every `h = 0.02 s`, two-sample propagation over `H = 0.04 s`, a drifting
//! gyrostabilizer as the reference, 131 epochs of equations at `t = 4.0, 4.2, …, 30 s`
//! (393 rows, 15 unknowns), pulses of `σ = 2·10⁻⁵ rad` in the quantized variants. The truth is
//! f64 ([`crate::truth::gyro::section6`]); the calibrator runs in f32 with the Givens
//! accumulator, as on the target. The same equations are also solved by the f32 normal
//! equations (the paper's eq. (5.8)) and by an f64 Givens solve (the reference), and the whole
//! pipeline is run once more in f64.
//!
//! Variant `gnss-ref` ([`super::gyro_cal_gnss`]): a tumbling microsatellite, a MEMS gyro and a
//! GNSS-like reference attitude (white noise 0.05° per axis at 10 Hz) over 10 minutes.
//!
//! Metrics (§6 variants): `dc` (9), `dd` (3), `w_post` (3) (the post-correction attitude error,
//! half-angle vector), `rank`, `cond` of the f32 Givens solve; `dc_f64`, `dd_f64`,
//! `w_post_f64` of the f64 solve of the same equations; `*_normal_f32` of the f32 normal
//! equations; `givens_f32_dev_ratio` and `normal_f32_dev_ratio`, the largest over the groups
//! (c₁…₆, c₇…₉, d, w_post) of ‖f32 − f64‖ / ‖f64 − truth‖; `*_f64_pipeline` of the all-f64
//! run.

use gnss_attitude::geometry::{Euler321, Quaternion};
use gnss_attitude::gyro::{
    CalibrationEstimate, CalibratorConfig, EpochEquations, EpochOutcome, LeastSquaresAccumulator,
    LsqSolution, NormalEquations, ObservabilityReport, PaperCalibrator, ResidualCentering,
    SqrtInformation,
};
use gnss_attitude::Real;
use nalgebra::SVector;
use serde_json::{json, Value};

use super::{Outcome, RunContext, Scenario, Variant, Variants};
use crate::report::{plot_lines, write_csv, Series};
use crate::truth::gyro::section6::{self, Truth, FIRST_EPOCH, H_SAMPLE, SIGMA};

/// What a variant runs.
#[derive(Clone, Copy, Debug)]
pub enum Plan {
    /// The paper's §6 experiment, the gyro read as given.
    Section6(Input),
    /// The tumbling microsatellite against a GNSS reference ([`super::gyro_cal_gnss`]).
    GnssReference,
}

/// The scenario.
pub const SCENARIO: Scenario = Scenario {
    name: "gyro-cal",
    about: "Gyro calibration by sequential least squares against a reference attitude (paper 001)",
    variants: &Variants {
        list: &[
            Variant::new(
                "exact",
                "§6: float increments, no quantization",
                Plan::Section6(Input::Exact),
            ),
            Variant::new(
                "quantized",
                "§6: pulses of σ = 2e-5 rad, no centering",
                Plan::Section6(Input::Pulses(ResidualCentering::None)),
            ),
            Variant::new(
                "centered-5.5",
                "§6: pulses, residual centered in the equations, eq. (5.5)",
                Plan::Section6(Input::Pulses(ResidualCentering::MeanResidual)),
            ),
            Variant::new(
                "centered-5.6",
                "§6: pulses, increments centered before integration, eq. (5.6)",
                Plan::Section6(Input::Pulses(ResidualCentering::IncrementCorrection)),
            ),
            Variant::new(
                "gnss-ref",
                "tumbling microsatellite, MEMS gyro, 0.05° GNSS attitude at 10 Hz, 10 min",
                Plan::GnssReference,
            ),
        ],
        run: |plan, ctx| match *plan {
            Plan::Section6(input) => run_section6(ctx, input),
            Plan::GnssReference => super::gyro_cal_gnss::run(ctx),
        },
    },
};

/// How the §6 gyro is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    /// Float increments.
    Exact,
    /// Quantized pulses, with this residual centering.
    Pulses(ResidualCentering),
}

pub(crate) fn c<T: Real>(v: f64) -> T {
    nalgebra::convert(v)
}

pub(crate) fn to_f64<T: Real>(v: T) -> f64 {
    nalgebra::try_convert(v).unwrap_or(f64::NAN)
}

pub(crate) fn quat<T: Real>(q: &Quaternion<f64>) -> Quaternion<T> {
    Quaternion::new(c(q.w), c(q.x), c(q.y), c(q.z))
}

pub(crate) fn quat64<T: Real>(q: &Quaternion<T>) -> Quaternion<f64> {
    Quaternion::new(to_f64(q.w), to_f64(q.x), to_f64(q.y), to_f64(q.z))
}

type Cal<T> = PaperCalibrator<SqrtInformation<15, T>, T>;

/// One epoch's equations in f64 (exact copies of what the calibrator formed).
#[derive(Clone)]
struct Epoch {
    t: f64,
    eq: EpochEquations<15, f64>,
}

/// Runs the core calibrator in `T` over the §6 truth.
fn run_core<T: Real>(truth: &Truth, input: Input) -> anyhow::Result<(Cal<T>, Vec<Epoch>)> {
    let mut config = CalibratorConfig::<T>::new(c(H_SAMPLE));
    if let Input::Pulses(centering) = input {
        config = config.with_pulses(c(SIGMA), centering);
    }
    let mut cal = Cal::<T>::paper(
        config,
        SqrtInformation::new(),
        quat(&truth.m0),
        quat(&truth.reference0),
    )?;
    let first = (FIRST_EPOCH / H_SAMPLE).round() as usize;
    let every = (section6::EPOCH_SPACING / H_SAMPLE).round() as usize;
    let mut epochs = Vec::new();
    for (i, s) in truth.samples.iter().enumerate() {
        match input {
            Input::Exact => cal.push_increment(&s.theta.map(c::<T>))?,
            Input::Pulses(_) => cal.push_pulses(s.counts)?,
        }
        let k = i + 1;
        if k >= first && (k - first) % every == 0 {
            // the gyrostabilizer delivers yaw, pitch, roll of J relative to L
            let e = Euler321::from_quaternion(&s.reference)?;
            let angles = Euler321::new(c::<T>(e.yaw), c(e.pitch), c(e.roll));
            if let EpochOutcome::Used(eq) = cal.add_reference_euler(&angles)? {
                epochs.push(Epoch {
                    t: s.t,
                    eq: EpochEquations {
                        rows: eq.rows.map(to_f64),
                        rhs: eq.rhs.map(to_f64),
                        p0: to_f64(eq.p0),
                    },
                });
            }
        }
    }
    Ok((cal, epochs))
}

/// Solves the stored equations in accumulator `A` (scalar `T`).
fn solve_with<T: Real, A: LeastSquaresAccumulator<T, 15>>(
    mut acc: A,
    epochs: &[Epoch],
    tolerance: T,
) -> anyhow::Result<LsqSolution<15, T>> {
    for e in epochs {
        for i in 0..3 {
            acc.add_row(&e.eq.rows.row(i).transpose().map(c::<T>), c(e.eq.rhs[i]))?;
        }
    }
    Ok(acc.solve(tolerance)?)
}

/// An f64 solution as the f32 estimate type (to correct the f32 calibrator's attitude).
fn solution_as<T: Real, U: Real>(s: &LsqSolution<15, U>) -> LsqSolution<15, T> {
    LsqSolution {
        x: s.x.map(|v| c(to_f64(v))),
        std_dev: s.std_dev.map(|v| c(to_f64(v))),
        sigma0: c(to_f64(s.sigma0)),
        residual_sum_of_squares: c(to_f64(s.residual_sum_of_squares)),
        rows: s.rows,
        observability: ObservabilityReport {
            singular_values: s.observability.singular_values.map(|v| c(to_f64(v))),
            rank: s.observability.rank,
            condition: c(to_f64(s.observability.condition)),
            equilibrated_condition: c(to_f64(s.observability.equilibrated_condition)),
        },
    }
}

/// Errors of one solve against the truth.
#[derive(Clone, Debug)]
struct Errors {
    dc: [f64; 9],
    dd: [f64; 3],
    w_post: [f64; 3],
    x: SVector<f64, 15>,
    std: SVector<f64, 15>,
    rank: usize,
    cond: f64,
    singular_values: Vec<f64>,
}

fn errors<T: Real>(cal: &Cal<T>, sol: &LsqSolution<15, T>, truth: &Truth) -> Errors {
    let est = CalibrationEstimate::<9, 3, 15, T>::from_solution(*sol);
    let corrected = quat64(&cal.corrected_attitude(&est));
    let lambda_f = truth.samples.last().map(|s| s.lambda).unwrap_or(truth.m0);
    // w° = vector part of Λ(t_f) ∘ Λ̂⁻¹ (half-angle vector)
    let mut w = lambda_f * corrected.conjugate();
    if w.w < 0.0 {
        w = Quaternion::new(-w.w, -w.x, -w.y, -w.z);
    }
    let x = sol.x.map(to_f64);
    let (c_true, d_true) = (section6::c(), section6::d());
    Errors {
        dc: std::array::from_fn(|i| x[3 + i] - c_true[i]),
        dd: std::array::from_fn(|i| x[12 + i] - d_true[i]),
        w_post: [w.x, w.y, w.z],
        x,
        std: sol.std_dev.map(to_f64),
        rank: sol.observability.rank,
        cond: to_f64(sol.observability.condition),
        singular_values: sol
            .observability
            .singular_values
            .iter()
            .map(|v| to_f64(*v))
            .collect(),
    }
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|a| a * a).sum::<f64>().sqrt()
}

/// Largest over the groups (c₁…₆, c₇…₉, d, w_post) of ‖a − ref‖ / ‖ref − truth‖.
fn deviation_ratio(a: &Errors, reference: &Errors) -> f64 {
    let groups: [(Vec<f64>, Vec<f64>); 4] = [
        (a.dc[..6].to_vec(), reference.dc[..6].to_vec()),
        (a.dc[6..].to_vec(), reference.dc[6..].to_vec()),
        (a.dd.to_vec(), reference.dd.to_vec()),
        (a.w_post.to_vec(), reference.w_post.to_vec()),
    ];
    groups
        .iter()
        .map(|(x, r)| {
            let diff: Vec<f64> = x.iter().zip(r).map(|(p, q)| p - q).collect();
            norm(&diff) / norm(r)
        })
        .fold(0.0, f64::max)
}

fn paper_figures(input: Input) -> Value {
    let (case, paper, repro) = match input {
        Input::Exact => (
            "no quantization",
            json!({"w_post": [-0.67e-5, 0.32e-5, -1.3e-5],
                   "dc": [-5.9e-7, -5.8e-6, -1.4e-5, 6e-6, -3.7e-6, -2.4e-8, -4.1e-7, 1.4e-7, -1.5e-7],
                   "dd": [-2.2e-7, 2.1e-7, -2.5e-7]}),
            json!({"w_post": [-0.34e-5, -0.58e-5, -0.18e-5],
                   "dc": [-5.2e-6, -6.2e-6, -5.7e-6, -2.0e-6, 6.0e-7, 3.0e-6, 2.7e-8, 1.6e-7, -5.7e-8],
                   "dd": [-2.0e-8, -2.8e-8, 4.5e-8]}),
        ),
        Input::Pulses(ResidualCentering::None) => (
            "sigma = 2e-5, no centering",
            json!({"w_post": [-2e-5, 0.5e-5, -3.2e-5],
                   "dc": [9.6e-6, -2.7e-6, -9.7e-6, 1.8e-5, -1.6e-5, -2.8e-6, -1.2e-6, -2.1e-6, 1.9e-6],
                   "dd": [-6.7e-8, 2e-7, -1.4e-6]}),
            json!({"w_post": [-1.6e-5, -0.18e-5, -2.1e-5],
                   "dc": [6.0e-6, -4.8e-7, 7.4e-7, 1.1e-5, -1.5e-5, -1.1e-6, -8.5e-7, -2.5e-6, 2.3e-6],
                   "dd": [8.2e-8, -1.4e-7, 1.5e-6]}),
        ),
        Input::Pulses(_) => (
            "sigma = 2e-5, centering by (5.5) or (5.6)",
            json!({"w_post": [1.7e-5, 0.83e-5, -1.4e-5],
                   "dc": [4.5e-6, -9.4e-6, -1.8e-5, 4.9e-6, -5.1e-6, 8.7e-7, -3.8e-7, -1.6e-7, -1.8e-7],
                   "dd": [2.9e-7, -1.4e-7, -1.4e-7]}),
            json!({"w_post": [-1.4e-5, 0.14e-5, -0.27e-5],
                   "dc": [6.3e-7, -7.5e-6, -8.0e-6, -2.3e-6, -4.4e-6, 2.6e-6, 3.4e-8, -1.8e-7, 2.1e-7],
                   "dd": [4.6e-7, -4.5e-7, 2.0e-7]}),
        ),
    };
    json!({
        "source": "Tkachenko, paper 001, section 6",
        "case": case,
        "paper": paper,
        "independent_reproduction_seed_spec": repro,
        "rank": 15,
        "singular_values_spec": [129.0, 0.41],
    })
}

crate::metrics! {
    /// Metrics of the §6 variants of `gyro-cal` (errors are estimate − truth).
    pub struct Section6Metrics {
        /// Error of the gyro parameters c₁…₉ (scale factors, misalignments, biases), f32 Givens.
        #[metric(unit = "1, 1, 1, rad, rad, rad, 1/s, 1/s, 1/s")] pub dc: Vec<f64>,
        /// Error of the reference drift d.
        #[metric(unit = "1/s")] pub dd: Vec<f64>,
        /// Post-correction attitude error (half-angle vector).
        #[metric(unit = "")] pub w_post: Vec<f64>,
        /// Rank of the f32 Givens solve.
        #[metric(unit = "")] pub rank: usize,
        /// Condition number of the f32 Givens solve.
        #[metric(unit = "")] pub cond: f64,
        /// c error of the f64 solve of the same equations.
        #[metric(unit = "as dc")] pub dc_f64: Vec<f64>,
        /// d error of the f64 solve.
        #[metric(unit = "1/s")] pub dd_f64: Vec<f64>,
        /// Attitude error of the f64 solve.
        #[metric(unit = "")] pub w_post_f64: Vec<f64>,
        /// Largest over the groups (c₁…₆, c₇…₉, d, w_post) of ‖f32 Givens − f64‖ / ‖f64 − truth‖.
        #[metric(unit = "")] pub givens_f32_dev_ratio: f64,
        /// The same for the f32 normal equations (the paper's eq. (5.8)).
        #[metric(unit = "")] pub normal_f32_dev_ratio: f64,
        /// c error of the f32 normal equations.
        #[metric(unit = "as dc")] pub dc_normal_f32: Vec<f64>,
        /// d error of the f32 normal equations.
        #[metric(unit = "1/s")] pub dd_normal_f32: Vec<f64>,
        /// Attitude error of the f32 normal equations.
        #[metric(unit = "")] pub w_post_normal_f32: Vec<f64>,
        /// Rank of the f32 normal equations.
        #[metric(unit = "")] pub rank_normal_f32: usize,
        /// Condition number of the f32 normal equations.
        #[metric(unit = "")] pub cond_normal_f32: f64,
        /// c error of the whole pipeline run in f64.
        #[metric(unit = "as dc")] pub dc_f64_pipeline: Vec<f64>,
        /// d error of the f64 pipeline.
        #[metric(unit = "1/s")] pub dd_f64_pipeline: Vec<f64>,
        /// Attitude error of the f64 pipeline.
        #[metric(unit = "")] pub w_post_f64_pipeline: Vec<f64>,
        /// Formal standard deviations of c (f32 Givens).
        #[metric(unit = "as dc")] pub c_std: Vec<f64>,
        /// Formal standard deviations of d.
        #[metric(unit = "1/s")] pub d_std: Vec<f64>,
        /// Unit-weight standard deviation of the fit.
        #[metric(unit = "")] pub sigma0: f64,
        /// Singular values of the equilibrated design.
        #[metric(unit = "")] pub singular_values: Vec<f64>,
        /// Reference epochs whose equations were used.
        #[metric(unit = "")] pub epochs_used: u32,
        /// Reference epochs skipped (small p₀ or gimbal lock).
        #[metric(unit = "")] pub epochs_skipped: u32,
        /// Equation rows accumulated.
        #[metric(unit = "")] pub rows: u32,
    }
}

/// Rank tolerance of the f64 reference solve.
const F64_RANK_TOLERANCE: f64 = 1e-8;

/// The §6 solves: the f32 calibrator's Givens solve, the f32 normal equations and an f64
/// Givens solve of the same equations, and the whole pipeline in f64, each against the truth.
struct Solves {
    cal32: Cal<f32>,
    epochs: Vec<Epoch>,
    givens32: LsqSolution<15, f32>,
    e32: Errors,
    ene: Errors,
    e64: Errors,
    epipe: Errors,
}

impl Solves {
    fn run(input: Input) -> anyhow::Result<Self> {
        let truth = section6::generate();
        let (cal32, epochs) = run_core::<f32>(&truth, input)?;
        let (cal64, _) = run_core::<f64>(&truth, input)?;
        let tol32 = cal32.config().rank_tolerance;
        let givens32 = cal32.solve()?.solution;
        let normal32 = solve_with(NormalEquations::<15, f32>::new(), &epochs, tol32)?;
        let givens64 = solve_with(
            SqrtInformation::<15, f64>::new(),
            &epochs,
            F64_RANK_TOLERANCE,
        )?;
        let pipeline64 = cal64.solve()?.solution;
        Ok(Self {
            e32: errors(&cal32, &givens32, &truth),
            ene: errors(&cal32, &normal32, &truth),
            e64: errors(&cal32, &solution_as::<f32, f64>(&givens64), &truth),
            epipe: errors(&cal64, &pipeline64, &truth),
            cal32,
            epochs,
            givens32,
        })
    }

    fn metrics(&self) -> Section6Metrics {
        let (e32, ene, e64, epipe) = (&self.e32, &self.ene, &self.e64, &self.epipe);
        let counters = self.cal32.counters();
        Section6Metrics {
            dc: e32.dc.to_vec(),
            dd: e32.dd.to_vec(),
            w_post: e32.w_post.to_vec(),
            rank: e32.rank,
            cond: e32.cond,
            dc_f64: e64.dc.to_vec(),
            dd_f64: e64.dd.to_vec(),
            w_post_f64: e64.w_post.to_vec(),
            givens_f32_dev_ratio: deviation_ratio(e32, e64),
            normal_f32_dev_ratio: deviation_ratio(ene, e64),
            dc_normal_f32: ene.dc.to_vec(),
            dd_normal_f32: ene.dd.to_vec(),
            w_post_normal_f32: ene.w_post.to_vec(),
            rank_normal_f32: ene.rank,
            cond_normal_f32: ene.cond,
            dc_f64_pipeline: epipe.dc.to_vec(),
            dd_f64_pipeline: epipe.dd.to_vec(),
            w_post_f64_pipeline: epipe.w_post.to_vec(),
            c_std: e32.std.as_slice()[3..12].to_vec(),
            d_std: e32.std.as_slice()[12..].to_vec(),
            sigma0: to_f64(self.givens32.sigma0),
            singular_values: e32.singular_values.clone(),
            epochs_used: counters.used,
            epochs_skipped: counters.skipped_small_p0 + counters.skipped_gimbal_lock,
            rows: self.givens32.rows,
        }
    }

    fn summary(&self, variant: &str, m: &Section6Metrics) -> Vec<String> {
        let (e32, e64, epipe) = (&self.e32, &self.e64, &self.epipe);
        let fmt = |v: &[f64]| {
            v.iter()
                .map(|a| format!("{a:+.1e}"))
                .collect::<Vec<_>>()
                .join(" ")
        };
        vec![
            format!(
                "paper 001 §6, variant {variant}: {} epochs, {} rows, rank {}, cond {:.0} (singular values {:.1} … {:.3})",
                m.epochs_used,
                m.rows,
                e32.rank,
                e32.cond,
                e32.singular_values.first().copied().unwrap_or(f64::NAN),
                e32.singular_values.last().copied().unwrap_or(f64::NAN)
            ),
            format!("f32 Givens  δc1..6 {}", fmt(&e32.dc[..6])),
            format!("            δc7..9 {}  δd {}", fmt(&e32.dc[6..]), fmt(&e32.dd)),
            format!("            w° {}", fmt(&e32.w_post)),
            format!("f64 solve   δc {}  δd {}", fmt(&e64.dc), fmt(&e64.dd)),
            format!(
                "f32 vs f64 (largest group ‖Δ‖/‖error‖): Givens {:.2e}, normal equations {:.2e}",
                m.givens_f32_dev_ratio, m.normal_f32_dev_ratio
            ),
            format!(
                "all-f64 pipeline: δc7..9 {}  δd {}  w° {}",
                fmt(&epipe.dc[6..]),
                fmt(&epipe.dd),
                fmt(&epipe.w_post)
            ),
        ]
    }

    /// Post-fit residuals of the f32 Givens estimate per epoch, as CSV and plot.
    fn write_files(
        &self,
        dir: &std::path::Path,
        variant: &str,
    ) -> anyhow::Result<Vec<std::path::PathBuf>> {
        let x = self.e32.x;
        let rows: Vec<[f64; 5]> = self
            .epochs
            .iter()
            .map(|e| {
                let r = e.eq.rhs - e.eq.rows * x;
                [e.t, e.eq.p0, r.x, r.y, r.z]
            })
            .collect();
        let stem = format!("gyro_cal_{}", variant.replace('.', "_"));
        let csv = dir.join(format!("{stem}_residuals.csv"));
        write_csv(
            &csv,
            &["t_s", "p0", "res_x", "res_y", "res_z"],
            rows.iter().copied(),
        )?;
        let png = dir.join(format!("{stem}_residuals.png"));
        let series = (0..3)
            .map(|i| {
                Series::line(
                    ["x", "y", "z"][i],
                    rows.iter().map(|r| (r[0], r[2 + i])).collect(),
                    i,
                )
            })
            .collect();
        plot_lines(
            &png,
            &format!("gyro-cal {variant}: post-fit residuals z − U x̂"),
            "time (s)",
            "residual (quaternion units)",
            series,
        )?;
        Ok(vec![csv, png])
    }
}

fn run_section6(ctx: &RunContext, input: Input) -> anyhow::Result<Outcome> {
    let solves = Solves::run(input)?;
    let m = solves.metrics();
    let mut outcome = Outcome::new(&m)?;
    outcome.paper = paper_figures(input);
    outcome.summary = solves.summary(&ctx.variant, &m);
    if let Some(dir) = &ctx.out_dir {
        outcome.files = solves.write_files(dir, &ctx.variant)?;
    }
    Ok(outcome)
}
