//! `one-stage`: paper 003's one-stage coherent–noncoherent attitude filter (the core's
//! [`gnss_attitude::attitude::one_stage`]) on the paper's simulation, geometry G1 of the spec.
//!
//! Set-up (spec 003 (c)): GPS L1 (λ = 0.1903 m; the paper's GLONASS λ = 0.1871 m would give
//! 1.7 % smaller errors), 40 dB-Hz, T = 1 ms, the equilateral triangle of side 1.5 m with `O_c`
//! at the middle of AB, rotation about `Y_c` only (β, the paper's simplified variant; α and γ
//! held), G1 (8 satellites at azimuth 45°(i−1), elevation 10°·i; "first 2" = 10° and 20°),
//! 60 s runs with the first 25 % discarded, both filter forms on the same data.
//!
//! # Two input paths
//!
//! * **Samples** ([`samples`]): the three antennas' samples (2.6 Msps CS8) through the core's
//!   acquisition, fixed-point correlators, tracking channels and adapter: samples →
//!   correlators → filter. One 60 s recording per variant (seed `--seed`), replayed through
//!   every filter configuration. **The headline metrics come from this path.**
//! * **I/Q fast path** ([`source::IqFastPath`]): the correlator outputs synthesized directly,
//!   a Monte Carlo of [`runs::RUNS`] runs per configuration; its figures carry the suffix
//!   `_iq`. Variant names ending in `-iq` run only this path (and report it as the headline).
//!
//! Metrics: `sigma_arcmin` (RMS of β̂ − β, default filter = Gaussian approximation),
//! `bound_arcmin` (√(2Δf/J_β) for the same geometry, computed here), `pull_in_s` (time after
//! which |β̂ − β| stays within 5 × bound; worst run), `false_lock` (a run not pulled in or not
//! locked at the end), `input_path` (`samples` or `iq`), the same per filter form, the I/Q
//! Monte Carlo's (`*_iq`), their ratio, and the information each path delivers
//! ([`loss`]: the effective Fisher information of β per epoch against the ideal one).

pub mod bound;
mod files;
pub mod loss;
pub mod runs;
pub mod samples;
pub mod sim;
pub mod source;
pub mod truth;

use std::sync::Arc;

use gnss_attitude::attitude::one_stage::{EstimatedAngles, FilterMode};
use serde_json::{json, Value};

use super::{Outcome, RunContext, Scenario, Variant};
use runs::{monte_carlo, sample_level, summarize, Summary, RUNS};
use samples::{record_source, Recording};
use sim::{RunConfig, RunResult};
use source::IqFastPath;
use truth::Motion;

/// The scenario.
pub const SCENARIO: Scenario = Scenario {
    name: "one-stage",
    about: "Paper 003: one-stage attitude filter from three-antenna samples (β about Y_c, geometry G1); `-iq` variants: I/Q fast path only",
    variants: &[
        Variant { name: "8sat-2hz", about: "8 satellites, Δf = 2 Hz, zero initial error (paper: 0.75′)" },
        Variant { name: "8sat-0.5hz", about: "8 satellites, Δf = 0.5 Hz (paper: 0.34′)" },
        Variant { name: "2sat-2hz", about: "first 2 satellites (el 10°, 20°), Δf = 2 Hz (paper: 5.48′)" },
        Variant { name: "8sat-2hz-init5deg", about: "8 satellites, Δf = 2 Hz, 5° initial error (paper: 0.77′ steady state)" },
        Variant { name: "dynamic", about: "8 satellites, Δf = 2 Hz, motion A: β̇ = (a0/V0) sin νt (stress test)" },
        Variant { name: "linebias", about: "8 satellites, Δf = 2 Hz, unknown line biases, with and without bias states" },
        Variant { name: "8sat-2hz-iq", about: "8sat-2hz on the I/Q fast path only" },
        Variant { name: "8sat-0.5hz-iq", about: "8sat-0.5hz on the I/Q fast path only" },
        Variant { name: "2sat-2hz-iq", about: "2sat-2hz on the I/Q fast path only" },
        Variant { name: "8sat-2hz-init5deg-iq", about: "8sat-2hz-init5deg on the I/Q fast path only" },
        Variant { name: "dynamic-iq", about: "dynamic on the I/Q fast path only" },
        Variant { name: "linebias-iq", about: "linebias on the I/Q fast path only" },
    ],
    run,
};

/// True line biases of antennas A, B, C in the `linebias` variant, rad (B−A = 0.35,
/// C−A = −0.25).
pub const LINE_BIAS: [f64; 3] = [0.2, 0.55, -0.05];

/// The run configuration of a variant (without the `-iq` suffix) for one filter form.
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

fn never(v: Option<f64>) -> String {
    v.map_or("never".into(), |v| format!("{v:.3} s"))
}

/// The filter configurations of a variant: Gaussian, constant gain, then (paper variants) the
/// three-angle Gaussian filter, or (`linebias`) both forms without bias states.
fn configurations(variant: &str) -> Vec<RunConfig> {
    let gauss = variant_config(variant, FilterMode::GaussianApproximation);
    let cg = variant_config(variant, FilterMode::ConstantGain);
    let mut configs = vec![gauss, cg];
    if paper_figure(variant) != Value::Null {
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
    configs
}

fn run(ctx: &RunContext) -> anyhow::Result<Outcome> {
    let (variant, iq_only) = match ctx.variant.strip_suffix("-iq") {
        Some(v) => (v, true),
        None => (ctx.variant.as_str(), false),
    };
    let configs = configurations(variant);
    let gauss = configs[0];
    let bound = gauss.bound_arcmin();
    let iq_results = monte_carlo(&configs, ctx.seed, "one-stage: I/Q fast path")?;
    let iq: Vec<Summary> = iq_results.iter().map(|r| summarize(r)).collect();
    let sampled = if iq_only {
        None
    } else {
        Some(sample_level(&configs, ctx.seed)?)
    };
    let (sums, path, runs) = match &sampled {
        Some((_, res)) => (
            res.iter()
                .map(|r| summarize(std::slice::from_ref(r)))
                .collect(),
            "samples",
            1,
        ),
        None => (iq.clone(), "iq", RUNS),
    };
    let (g, c) = (&sums[0], &sums[1]);
    // how much one 60 s run's σ scatters (relative standard deviation over the I/Q runs)
    let per_run: Vec<f64> = iq_results[0].iter().map(|r| r.rms_arcmin).collect();
    let spread = crate::stats::std_dev(&per_run) / crate::stats::mean(&per_run);

    let mut outcome = Outcome::default();
    outcome
        .metric("sigma_arcmin", g.sigma_arcmin)
        .metric("bound_arcmin", bound)
        .metric("pull_in_s", json_opt(g.pull_in_s))
        .metric("false_lock", g.false_lock)
        .metric("input_path", path)
        .metric("runs", runs)
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
        .metric("sigma_arcmin_iq", iq[0].sigma_arcmin)
        .metric("sigma_arcmin_constant_gain_iq", iq[1].sigma_arcmin)
        .metric("pull_in_s_iq", json_opt(iq[0].pull_in_s))
        .metric("false_lock_iq", iq[0].false_lock || iq[1].false_lock)
        .metric("runs_iq", RUNS)
        .metric("sigma_run_spread_iq", spread)
        .metric("wavelength_m", truth::WAVELENGTH_M);
    let mut summary = vec![format!(
        "{} satellites of G1, {} dB-Hz, Δf = {} Hz, λ = {:.4} m, {} s runs, first {:.0} % discarded; headline: {}",
        gauss.satellites,
        gauss.cn0_dbhz,
        gauss.loop_bandwidth_hz,
        truth::WAVELENGTH_M,
        gauss.duration_s,
        100.0 * gauss.discard,
        if iq_only {
            format!("I/Q fast path, {RUNS} runs")
        } else {
            "samples (2.6 Msps CS8 → core acquisition, correlators, tracking, adapter), one run".into()
        }
    )];
    summary.push(format!(
        "σ_β: Gaussian approximation {:.3}′, constant gain {:.3}′; bound √(2Δf/J_β) {:.3}′; I/Q fast path ({RUNS} runs) {:.3}′ / {:.3}′ (one run's σ scatters by ±{:.1} %)",
        g.sigma_arcmin, c.sigma_arcmin, bound, iq[0].sigma_arcmin, iq[1].sigma_arcmin, 100.0 * spread
    ));
    summary.push(format!(
        "pull-in (worst run): Gaussian {}, constant gain {}; false lock: {} / {} (I/Q: {} / {})",
        never(g.pull_in_s),
        never(c.pull_in_s),
        g.false_lock,
        c.false_lock,
        iq[0].false_lock,
        iq[1].false_lock
    ));
    if let Some((rec, _)) = &sampled {
        compare_paths(
            &mut outcome,
            &mut summary,
            &gauss,
            rec,
            g,
            &iq[0],
            bound,
            ctx.seed,
        )?;
    }
    if sums.len() > 2 && variant != "linebias" {
        let three = configs[2];
        let b3 = three.bound_arcmin();
        outcome
            .metric("sigma_arcmin_3axis", sums[2].sigma_arcmin)
            .metric("sigma_arcmin_3axis_iq", iq[2].sigma_arcmin)
            .metric("bound_arcmin_3axis", b3)
            .metric("false_lock_3axis", sums[2].false_lock);
        summary.push(format!(
            "all three angles estimated (Gaussian): σ_β {:.3}′ (I/Q {:.3}′), bound √(2Δf (J⁻¹)_ββ) {:.3}′ (β shares information with γ)",
            sums[2].sigma_arcmin, iq[2].sigma_arcmin, b3
        ));
    }
    if variant == "linebias" {
        line_bias_metrics(&mut outcome, &mut summary, &gauss, &sums, &iq, bound);
    }
    outcome.paper = paper_figure(variant);
    outcome.summary = summary;

    if let Some(dir) = &ctx.out_dir {
        let first = |r: &[RunResult]| r.first().cloned();
        let (hg, hc): (Option<RunResult>, Option<RunResult>) = match &sampled {
            Some((_, res)) => (res.first().cloned(), res.get(1).cloned()),
            None => (first(&iq_results[0]), first(&iq_results[1])),
        };
        if let (Some(hg), Some(hc)) = (hg, hc) {
            let iq_g = sampled.as_ref().and_then(|_| iq_results[0].first());
            outcome.files = files::write_files(dir, &ctx.variant, path, &hg, &hc, iq_g, bound)?;
        }
    }
    Ok(outcome)
}

/// The sample-level path against the I/Q fast path: σ ratio, the information each delivers,
/// wall time.
#[allow(clippy::too_many_arguments)]
fn compare_paths(
    outcome: &mut Outcome,
    summary: &mut Vec<String>,
    gauss: &RunConfig,
    rec: &Arc<Recording>,
    g: &Summary,
    iq: &Summary,
    bound: f64,
    seed: u64,
) -> anyhow::Result<()> {
    let sky = truth::sky_g1(gauss.satellites);
    let mut iq_source = IqFastPath::new(&sky, gauss.cn0_dbhz, gauss.line_bias, seed);
    let iq_epochs = record_source(gauss, &mut iq_source)?;
    let loss_iq = loss::measure(gauss, &iq_epochs)?;
    let loss_s = loss::measure(gauss, &rec.epochs)?;
    let st = &rec.stats;
    // the other satellites' cross-correlation: (n − 1)(C/N0)T/1023 of the noise (signal scenario)
    let snr = 10f64.powf(gauss.cn0_dbhz / 10.0) * source::EPOCH_S;
    let mai_db = 10.0 * (1.0 + (st.satellites as f64 - 1.0) * snr / 1023.0).log10();
    outcome
        .metric(
            "sigma_ratio_samples_to_iq",
            g.sigma_arcmin / iq.sigma_arcmin,
        )
        .metric("information_loss_db_samples", loss_s.loss_db)
        .metric("information_loss_db_iq", loss_iq.loss_db)
        .metric("chain_loss_db", loss_s.loss_db - loss_iq.loss_db)
        .metric(
            "chain_loss_db_low_frequency",
            10.0 * (loss_iq.ratio_low_frequency / loss_s.ratio_low_frequency).log10(),
        )
        .metric("cross_correlation_loss_db_predicted", mai_db)
        .metric("loop_gain_factor_samples", loss_s.slope_over_expected)
        .metric("loop_gain_factor_iq", loss_iq.slope_over_expected)
        .metric(
            "bound_arcmin_measured_information",
            loss_s.bound_arcmin(bound),
        )
        .metric("mean_cn0_reported_dbhz", st.mean_cn0_dbhz)
        .metric("satellites_tracked", st.tracked)
        .metric("empty_epochs", st.empty_epochs)
        .metric("late_epochs", st.late)
        .metric("sample_wall_s", rec.wall_s)
        .metric("sample_synthesis_s", st.synthesis_s)
        .metric("sample_tracking_s", st.tracking_s)
        .metric("sample_acquisition_s", st.acquisition_s);
    summary.push(format!(
        "samples vs I/Q fast path: σ ratio {:.3}; information per epoch vs ideal (slope²/var of u_β at the truth, {} epochs): samples −{:.2} dB, I/Q −{:.2} dB → chain loss {:.2} dB (cross-correlation of the other satellites: {:.2} dB predicted), below 10 Hz {:.2} ± 0.2 dB; loop gain factor {:.3} / {:.3}; C/N0 reported {:.2} dB-Hz; bound at the measured information {:.3}′",
        g.sigma_arcmin / iq.sigma_arcmin,
        loss_s.epochs,
        loss_s.loss_db,
        loss_iq.loss_db,
        loss_s.loss_db - loss_iq.loss_db,
        mai_db,
        10.0 * (loss_iq.ratio_low_frequency / loss_s.ratio_low_frequency).log10(),
        loss_s.slope_over_expected,
        loss_iq.slope_over_expected,
        st.mean_cn0_dbhz,
        loss_s.bound_arcmin(bound)
    ));
    summary.push(format!(
        "sample path: {}/{} satellites tracked, {} empty and {} late filter epochs; wall time {:.1} s (synthesis {:.1} s, tracking {:.1} s, acquisition {:.1} s; release, {} threads)",
        st.tracked,
        st.satellites,
        st.empty_epochs,
        st.late,
        rec.wall_s,
        st.synthesis_s,
        st.tracking_s,
        st.acquisition_s,
        rayon::current_num_threads()
    ));
    Ok(())
}

/// The `linebias` variant's extra figures (configurations 2 and 3: without bias states).
fn line_bias_metrics(
    outcome: &mut Outcome,
    summary: &mut Vec<String>,
    gauss: &RunConfig,
    sums: &[Summary],
    iq: &[Summary],
    bound: f64,
) {
    let (g, c, gn, cn) = (&sums[0], &sums[1], &sums[2], &sums[3]);
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
        .metric("sigma_arcmin_without_bias_states_iq", iq[2].sigma_arcmin)
        .metric("false_lock_without_bias_states", gn.false_lock)
        .metric("bias_cost_percent", 100.0 * (g.sigma_arcmin / bound - 1.0))
        .metric(
            "bias_cost_percent_iq",
            100.0 * (iq[0].sigma_arcmin / bound - 1.0),
        )
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
