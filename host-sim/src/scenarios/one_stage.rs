//! `one-stage`: paper 003's one-stage coherent–noncoherent attitude filter (the core's
//! [`gnss_attitude::attitude::one_stage`]) on the paper's simulation, geometry G1 of the spec.
//!
//! Set-up (spec 003 (c)): GPS L1 (λ = 0.1903 m; the paper's GLONASS λ = 0.1871 m would give
//! 1.7 % smaller errors), 40 dB-Hz, T = 1 ms, the equilateral triangle of side 1.5 m with `O_c`
//! at the middle of AB, rotation about `Y_c` only (β, the paper's simplified variant; α and γ
//! held), G1 (8 satellites at azimuth 45°(i−1), elevation 10°·i; "first 2" = 10° and 20°),
//! 60 s runs with the first 25 % discarded, Monte Carlo over [`RUNS`] runs per filter form,
//! both forms on the same data. Input: the I/Q fast path ([`source::IqFastPath`]); the
//! sample-level path will be another [`source::EpochSource`].
//!
//! Metrics: `sigma_arcmin` (RMS of β̂ − β pooled over the runs, default filter = Gaussian
//! approximation), `bound_arcmin` (√(2Δf/J_β) for the same geometry, computed here),
//! `pull_in_s` (worst run: time after which |β̂ − β| stays within 5 × bound), `false_lock`
//! (any run not pulled in or flagged at the end), and the same for each filter form.

pub mod bound;
pub mod sim;
pub mod source;
pub mod truth;

use gnss_attitude::attitude::one_stage::{EstimatedAngles, FilterMode, LockStatus};
use rayon::prelude::*;
use serde_json::{json, Value};

use super::{Outcome, RunContext, Scenario, Variant};
use crate::report::{plot_panels, progress, write_csv, Panel, Series};
use sim::{simulate, RunConfig, RunResult};
use truth::Motion;

/// The scenario.
pub const SCENARIO: Scenario = Scenario {
    name: "one-stage",
    about: "Paper 003: one-stage attitude filter from three-antenna I/Q (β about Y_c, geometry G1)",
    variants: &[
        Variant {
            name: "8sat-2hz",
            about: "8 satellites, Δf = 2 Hz, zero initial error (paper: 0.75′)",
        },
        Variant {
            name: "8sat-0.5hz",
            about: "8 satellites, Δf = 0.5 Hz (paper: 0.34′)",
        },
        Variant {
            name: "2sat-2hz",
            about: "first 2 satellites (el 10°, 20°), Δf = 2 Hz (paper: 5.48′)",
        },
        Variant {
            name: "8sat-2hz-init5deg",
            about: "8 satellites, Δf = 2 Hz, 5° initial error (paper: 0.77′ steady state)",
        },
        Variant {
            name: "dynamic",
            about: "8 satellites, Δf = 2 Hz, motion A: β̇ = (a0/V0) sin νt (stress test)",
        },
        Variant {
            name: "linebias",
            about: "8 satellites, Δf = 2 Hz, unknown line biases, with and without bias states",
        },
    ],
    run,
};

/// Monte Carlo runs per filter form.
pub const RUNS: usize = 8;
/// True line biases of antennas A, B, C in the `linebias` variant, rad (B−A = 0.35,
/// C−A = −0.25).
pub const LINE_BIAS: [f64; 3] = [0.2, 0.55, -0.05];

/// The run configuration of a variant for one filter form.
pub fn variant_config(variant: &str, mode: FilterMode) -> RunConfig {
    let mut cfg = RunConfig::paper(mode);
    match variant {
        "8sat-0.5hz" => cfg.loop_bandwidth_hz = 0.5,
        "2sat-2hz" => cfg.satellites = 2,
        "8sat-2hz-init5deg" => {
            cfg.initial_error_rad = 5f64.to_radians();
            cfg.prior_sigma_rad = 5f64.to_radians();
        }
        "dynamic" => cfg.motion = Motion::MotionA,
        "linebias" => {
            cfg.line_bias = LINE_BIAS;
            cfg.line_bias_states = true;
        }
        _ => {}
    }
    cfg
}

/// Summary of the runs of one configuration.
struct Summary {
    sigma_arcmin: f64,
    pull_in_s: Option<f64>,
    locked_s: Option<f64>,
    false_lock: bool,
    flagged_runs: usize,
    bias_error_rms_rad: f64,
}

fn summarize(results: &[RunResult]) -> Summary {
    let n = results.len().max(1) as f64;
    let ms = results.iter().map(|r| r.rms_arcmin.powi(2)).sum::<f64>() / n;
    let worst = |f: fn(&RunResult) -> Option<f64>| {
        results
            .iter()
            .map(f)
            .try_fold(0.0f64, |m, v| v.map(|v| m.max(v)))
    };
    let bias_sq: Vec<f64> = results
        .iter()
        .flat_map(|r| r.line_bias_error_rad)
        .filter(|v| v.is_finite())
        .map(|v| v * v)
        .collect();
    Summary {
        sigma_arcmin: ms.sqrt(),
        pull_in_s: worst(|r| r.pull_in_s),
        locked_s: worst(|r| r.locked_at_s),
        false_lock: results
            .iter()
            .any(|r| r.pull_in_s.is_none() || r.final_status != LockStatus::Locked),
        flagged_runs: results.iter().filter(|r| r.flagged_at_s.is_some()).count(),
        bias_error_rms_rad: if bias_sq.is_empty() {
            f64::NAN
        } else {
            (bias_sq.iter().sum::<f64>() / bias_sq.len() as f64).sqrt()
        },
    }
}

fn json_opt(v: Option<f64>) -> Value {
    v.map_or(Value::Null, |x| json!(x))
}

fn json_num(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

fn paper_figure(variant: &str) -> Value {
    match variant {
        "8sat-2hz" => json!({ "sigma_arcmin": 0.75 }),
        "8sat-0.5hz" => json!({ "sigma_arcmin": 0.34 }),
        "2sat-2hz" => json!({ "sigma_arcmin": 5.48 }),
        "8sat-2hz-init5deg" => json!({ "sigma_arcmin": 0.77 }),
        _ => Value::Null,
    }
}

/// Runs `RUNS` runs of each configuration in parallel (the same seeds for every
/// configuration, so the comparison is paired).
fn monte_carlo(
    configs: &[RunConfig],
    seed: u64,
    label: &str,
) -> anyhow::Result<Vec<Vec<RunResult>>> {
    let jobs: Vec<(usize, usize)> = (0..configs.len())
        .flat_map(|c| (0..RUNS).map(move |r| (c, r)))
        .collect();
    let bar = progress(jobs.len() as u64, label);
    let results: Vec<((usize, usize), RunResult)> = jobs
        .par_iter()
        .map(|&(c, r)| {
            let out = simulate(
                &configs[c],
                seed.wrapping_mul(1_000_003).wrapping_add(r as u64),
            );
            bar.inc(1);
            out.map(|o| ((c, r), o))
        })
        .collect::<anyhow::Result<_>>()?;
    bar.finish_and_clear();
    let mut by_config: Vec<Vec<RunResult>> = vec![Vec::new(); configs.len()];
    for ((c, _), res) in results {
        by_config[c].push(res);
    }
    Ok(by_config)
}

fn run(ctx: &RunContext) -> anyhow::Result<Outcome> {
    let variant = ctx.variant.as_str();
    let gauss = variant_config(variant, FilterMode::GaussianApproximation);
    let cg = variant_config(variant, FilterMode::ConstantGain);
    let mut configs = vec![gauss, cg];
    let three_axis = paper_figure(variant) != Value::Null;
    if three_axis {
        configs.push(RunConfig {
            estimate: EstimatedAngles::ALL,
            ..gauss
        });
    }
    if variant == "linebias" {
        for base in [gauss, cg] {
            configs.push(RunConfig {
                line_bias_states: false,
                ..base
            });
        }
    }
    let results = monte_carlo(&configs, ctx.seed, "one-stage")?;
    let sums: Vec<Summary> = results.iter().map(|r| summarize(r)).collect();
    let bound = gauss.bound_arcmin();
    let (g, c) = (&sums[0], &sums[1]);

    let mut outcome = Outcome::default();
    outcome
        .metric("sigma_arcmin", g.sigma_arcmin)
        .metric("bound_arcmin", bound)
        .metric("pull_in_s", json_opt(g.pull_in_s))
        .metric("false_lock", g.false_lock)
        .metric("sigma_arcmin_gaussian", g.sigma_arcmin)
        .metric("sigma_arcmin_constant_gain", c.sigma_arcmin)
        .metric("pull_in_s_gaussian", json_opt(g.pull_in_s))
        .metric("pull_in_s_constant_gain", json_opt(c.pull_in_s))
        .metric("lock_declared_s_gaussian", json_opt(g.locked_s))
        .metric("lock_declared_s_constant_gain", json_opt(c.locked_s))
        .metric("false_lock_constant_gain", c.false_lock)
        .metric("flagged_runs_gaussian", g.flagged_runs)
        .metric("flagged_runs_constant_gain", c.flagged_runs)
        .metric("sigma_over_bound", g.sigma_arcmin / bound)
        .metric("runs", RUNS)
        .metric("wavelength_m", truth::WAVELENGTH_M);
    let mut summary = vec![
        format!(
            "{RUNS} runs × {} s per filter form, {} satellites of G1, {} dB-Hz, Δf = {} Hz, λ = {:.4} m, first {:.0} % discarded, I/Q fast path",
            gauss.duration_s,
            gauss.satellites,
            gauss.cn0_dbhz,
            gauss.loop_bandwidth_hz,
            truth::WAVELENGTH_M,
            100.0 * gauss.discard
        ),
        format!(
            "σ_β: Gaussian approximation {:.3}′, constant gain {:.3}′; bound √(2Δf/J_β) {:.3}′",
            g.sigma_arcmin, c.sigma_arcmin, bound
        ),
        format!(
            "pull-in (worst run): Gaussian {}, constant gain {}; false lock: {} / {}",
            g.pull_in_s.map_or("never".into(), |v| format!("{v:.3} s")),
            c.pull_in_s.map_or("never".into(), |v| format!("{v:.3} s")),
            g.false_lock,
            c.false_lock
        ),
    ];
    if three_axis {
        let three = RunConfig {
            estimate: EstimatedAngles::ALL,
            ..gauss
        };
        let b3 = three.bound_arcmin();
        outcome
            .metric("sigma_arcmin_3axis", sums[2].sigma_arcmin)
            .metric("bound_arcmin_3axis", b3)
            .metric("false_lock_3axis", sums[2].false_lock);
        summary.push(format!(
            "all three angles estimated (Gaussian): σ_β {:.3}′, bound √(2Δf (J⁻¹)_ββ) {:.3}′ (β shares information with γ)",
            sums[2].sigma_arcmin, b3
        ));
    }
    if variant == "linebias" {
        let (gn, cn) = (&sums[2], &sums[3]);
        let sky = truth::sky_g1(gauss.satellites);
        let marginal = bound::loop_bound_arcmin(
            gauss.loop_bandwidth_hz,
            bound::information_rate_biases_unknown(0.0, &sky, gauss.cn0_dbhz),
        );
        outcome
            .metric("sigma_arcmin_without_bias_states", gn.sigma_arcmin)
            .metric(
                "sigma_arcmin_without_bias_states_constant_gain",
                cn.sigma_arcmin,
            )
            .metric("false_lock_without_bias_states", gn.false_lock)
            .metric("bias_cost_percent", 100.0 * (g.sigma_arcmin / bound - 1.0))
            .metric("bound_arcmin_biases_unknown_per_epoch", marginal)
            .metric("line_bias_error_rms_rad", json_num(g.bias_error_rms_rad))
            .metric(
                "line_bias_error_rms_rad_constant_gain",
                json_num(c.bias_error_rms_rad),
            );
        summary.push(format!(
            "line biases B−A = {:.2} rad, C−A = {:.2} rad: with bias states σ_β {:.3}′ (Gaussian) / {:.3}′ (constant gain), without {:.3}′ / {:.3}′; bound if the biases were re-learned every epoch {:.3}′",
            LINE_BIAS[1] - LINE_BIAS[0],
            LINE_BIAS[2] - LINE_BIAS[0],
            g.sigma_arcmin,
            c.sigma_arcmin,
            gn.sigma_arcmin,
            cn.sigma_arcmin,
            marginal
        ));
    }
    outcome.paper = paper_figure(variant);
    outcome.summary = summary;

    if let Some(dir) = &ctx.out_dir {
        outcome.files = write_files(dir, variant, &results[0][0], &results[1][0], bound)?;
    }
    Ok(outcome)
}

fn write_files(
    dir: &std::path::Path,
    variant: &str,
    gauss: &RunResult,
    cg: &RunResult,
    bound: f64,
) -> anyhow::Result<Vec<std::path::PathBuf>> {
    let stem = format!("one_stage_{}", variant.replace('.', "_"));
    let csv = dir.join(format!("{stem}_run0.csv"));
    write_csv(
        &csv,
        &[
            "t_s",
            "err_gaussian_arcmin",
            "sigma_gaussian_arcmin",
            "alignment_gaussian",
            "status_gaussian",
            "err_constant_gain_arcmin",
            "alignment_constant_gain",
            "status_constant_gain",
        ],
        gauss.samples.iter().zip(&cg.samples).map(|(a, b)| {
            [
                a.t,
                a.error_arcmin,
                a.sigma_arcmin,
                a.alignment,
                f64::from(a.status),
                b.error_arcmin,
                b.alignment,
                f64::from(b.status),
            ]
        }),
    )?;
    let pts = |r: &RunResult, f: fn(&sim::Sample) -> f64| -> Vec<(f64, f64)> {
        r.samples.iter().map(|s| (s.t, f(s))).collect()
    };
    let t_end = gauss.samples.last().map_or(0.0, |s| s.t);
    let panels = vec![
        Panel {
            y_label: "β̂ − β (arc-min)".into(),
            series: vec![
                Series::line("Gaussian approximation", pts(gauss, |s| s.error_arcmin), 0),
                Series::line("constant gain", pts(cg, |s| s.error_arcmin), 2),
                Series::bound("± bound", vec![(0.0, bound), (t_end, bound)], 1),
                Series::bound("", vec![(0.0, -bound), (t_end, -bound)], 1),
            ],
        },
        Panel {
            y_label: "alignment η̄".into(),
            series: vec![
                Series::line("Gaussian approximation", pts(gauss, |s| s.alignment), 0),
                Series::line("constant gain", pts(cg, |s| s.alignment), 2),
            ],
        },
    ];
    let png = dir.join(format!("{stem}_error.png"));
    plot_panels(
        &png,
        &format!("one-stage {variant}: tracking error of β, run 0"),
        "time (s)",
        &panels,
    )?;
    Ok(vec![csv, png])
}
