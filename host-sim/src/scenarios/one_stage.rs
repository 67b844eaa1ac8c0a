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

use super::signal::cn0_loss_db;
use super::{Outcome, RunContext, Scenario, Variant, Variants};
use crate::report::progress;
use crate::synth::quantize::Quantizer;
use runs::{monte_carlo, sample_level, summarize, Summary, RUNS};
use samples::{record, record_source, Recording};
use sim::{RunConfig, RunResult};
use source::IqFastPath;
use truth::Motion;

/// The paper's cases and the two stress tests, each run from samples or on the I/Q path only.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Case {
    /// 8 satellites, Δf = 2 Hz, zero initial error.
    EightSat2Hz,
    /// 8 satellites, Δf = 0.5 Hz.
    EightSatHalfHz,
    /// The first 2 satellites, Δf = 2 Hz.
    TwoSat2Hz,
    /// 8 satellites, Δf = 2 Hz, 5° initial error.
    Init5Deg,
    /// 8 satellites, Δf = 2 Hz, motion A.
    Dynamic,
    /// 8 satellites, Δf = 2 Hz, unknown line biases.
    LineBias,
}

/// What a variant runs: a case, and whether only on the I/Q fast path.
#[derive(Clone, Copy, Debug)]
pub struct Plan {
    /// The case.
    pub case: Case,
    /// Only the I/Q fast path (the `-iq` variants).
    pub iq_only: bool,
}

const fn plan(case: Case, iq_only: bool) -> Plan {
    Plan { case, iq_only }
}

/// The `-iq` twin of a case: the I/Q fast path only.
const fn iq(name: &'static str, case: Case) -> Variant<Plan> {
    Variant::new(
        name,
        "the same case on the I/Q fast path only",
        plan(case, true),
    )
}

/// The scenario.
pub const SCENARIO: Scenario = Scenario {
    name: "one-stage",
    about: "Paper 003: one-stage attitude filter from three-antenna samples (β about Y_c, geometry G1); `-iq` variants: I/Q fast path only",
    variants: &Variants {
        list: &[
            Variant::new("8sat-2hz", "8 satellites, Δf = 2 Hz, zero initial error (paper: 0.75′)", plan(Case::EightSat2Hz, false)),
            Variant::new("8sat-0.5hz", "8 satellites, Δf = 0.5 Hz (paper: 0.34′)", plan(Case::EightSatHalfHz, false)),
            Variant::new("2sat-2hz", "first 2 satellites (el 10°, 20°), Δf = 2 Hz (paper: 5.48′)", plan(Case::TwoSat2Hz, false)),
            Variant::new("8sat-2hz-init5deg", "8 satellites, Δf = 2 Hz, 5° initial error (paper: 0.77′ steady state)", plan(Case::Init5Deg, false)),
            Variant::new("dynamic", "8 satellites, Δf = 2 Hz, motion A: β̇ = (a0/V0) sin νt (stress test)", plan(Case::Dynamic, false)),
            Variant::new("linebias", "8 satellites, Δf = 2 Hz, unknown line biases, with and without bias states", plan(Case::LineBias, false)),
            iq("8sat-2hz-iq", Case::EightSat2Hz),
            iq("8sat-0.5hz-iq", Case::EightSatHalfHz),
            iq("2sat-2hz-iq", Case::TwoSat2Hz),
            iq("8sat-2hz-init5deg-iq", Case::Init5Deg),
            iq("dynamic-iq", Case::Dynamic),
            iq("linebias-iq", Case::LineBias),
        ],
        run: |plan, ctx| run(*plan, ctx),
    },
};

/// True line biases of antennas A, B, C in the `linebias` variant, rad (B−A = 0.35,
/// C−A = −0.25).
pub const LINE_BIAS: [f64; 3] = [0.2, 0.55, -0.05];

/// Initial attitude error (and prior σ) of [`Case::Init5Deg`], degrees.
const INIT_ERROR_DEG: f64 = 5.0;

impl Case {
    /// The run configuration of the case for one filter form.
    pub fn config(self, mode: FilterMode) -> RunConfig {
        let mut cfg = RunConfig::paper(mode);
        match self {
            Case::EightSat2Hz => {}
            Case::EightSatHalfHz => cfg.loop_bandwidth_hz = 0.5,
            Case::TwoSat2Hz => cfg.satellites = 2,
            Case::Init5Deg => {
                cfg.initial_error_rad = INIT_ERROR_DEG.to_radians();
                cfg.prior_sigma_rad = INIT_ERROR_DEG.to_radians();
            }
            Case::Dynamic => cfg.motion = Motion::MotionA,
            Case::LineBias => {
                cfg.line_bias = LINE_BIAS;
                cfg.line_bias_states = true;
            }
        }
        cfg
    }

    /// The paper's σ_β for the case, arc-minutes (`None`: not a case of the paper).
    pub fn paper_sigma_arcmin(self) -> Option<f64> {
        match self {
            Case::EightSat2Hz => Some(0.75),
            Case::EightSatHalfHz => Some(0.34),
            Case::TwoSat2Hz => Some(5.48),
            Case::Init5Deg => Some(0.77),
            Case::Dynamic | Case::LineBias => None,
        }
    }

    /// The paper's figure as JSON (`null` when it has none).
    fn paper_figure(self) -> Value {
        self.paper_sigma_arcmin()
            .map_or(Value::Null, |s| json!({ "sigma_arcmin": s }))
    }

    /// The filter configurations: Gaussian, constant gain, then (paper cases) the three-angle
    /// Gaussian filter, or ([`Case::LineBias`]) both forms without bias states.
    fn configurations(self) -> Vec<RunConfig> {
        let gauss = self.config(FilterMode::GaussianApproximation);
        let cg = self.config(FilterMode::ConstantGain);
        let mut configs = vec![gauss, cg];
        if self.paper_sigma_arcmin().is_some() {
            configs.push(RunConfig {
                estimate: EstimatedAngles::ALL,
                ..gauss
            });
        }
        if self == Case::LineBias {
            for base in [gauss, cg] {
                configs.push(RunConfig {
                    line_bias_states: false,
                    ..base
                });
            }
        }
        configs
    }
}

fn never(v: Option<f64>) -> String {
    v.map_or("never".into(), |v| format!("{v:.3} s"))
}

crate::metrics! {
    /// Metrics of `one-stage`. Unsuffixed figures come from the headline path (`input_path`);
    /// `*_iq` from the I/Q fast path's Monte Carlo.
    pub struct Metrics {
        /// RMS of β̂ − β, Gaussian-approximation filter.
        #[metric(unit = "arcmin")] pub sigma_arcmin: f64,
        /// Loop-limited bound √(2Δf/J_β) for the same geometry.
        #[metric(unit = "arcmin")] pub bound_arcmin: f64,
        /// Time after which |β̂ − β| stays within 5 × bound (worst run; null: never).
        #[metric(unit = "s")] pub pull_in_s: Option<f64>,
        /// A run that did not pull in or was not locked at the end.
        #[metric(unit = "")] pub false_lock: bool,
        /// Where the headline comes from: `samples` or `iq`.
        #[metric(unit = "")] pub input_path: &'static str,
        /// Runs behind the headline.
        #[metric(unit = "")] pub runs: usize,
        /// σ_β of the Gaussian-approximation filter.
        #[metric(unit = "arcmin")] pub sigma_arcmin_gaussian: f64,
        /// σ_β of the constant-gain filter.
        #[metric(unit = "arcmin")] pub sigma_arcmin_constant_gain: f64,
        /// Pull-in time, Gaussian.
        #[metric(unit = "s")] pub pull_in_s_gaussian: Option<f64>,
        /// Pull-in time, constant gain.
        #[metric(unit = "s")] pub pull_in_s_constant_gain: Option<f64>,
        /// When the lock detector declared lock, Gaussian (worst run).
        #[metric(unit = "s")] pub lock_declared_s_gaussian: Option<f64>,
        /// When the lock detector declared lock, constant gain.
        #[metric(unit = "s")] pub lock_declared_s_constant_gain: Option<f64>,
        /// False lock of the constant-gain filter.
        #[metric(unit = "")] pub false_lock_constant_gain: bool,
        /// Runs in which the detector flagged a false lock, Gaussian.
        #[metric(unit = "")] pub flagged_runs_gaussian: usize,
        /// Runs in which the detector flagged a false lock, constant gain.
        #[metric(unit = "")] pub flagged_runs_constant_gain: usize,
        /// σ_β over the bound.
        #[metric(unit = "")] pub sigma_over_bound: f64,
        /// σ_β on the I/Q fast path, Gaussian.
        #[metric(unit = "arcmin")] pub sigma_arcmin_iq: f64,
        /// σ_β on the I/Q fast path, constant gain.
        #[metric(unit = "arcmin")] pub sigma_arcmin_constant_gain_iq: f64,
        /// Pull-in time on the I/Q fast path (worst run).
        #[metric(unit = "s")] pub pull_in_s_iq: Option<f64>,
        /// False lock of either filter form on the I/Q fast path.
        #[metric(unit = "")] pub false_lock_iq: bool,
        /// I/Q Monte Carlo runs per configuration.
        #[metric(unit = "")] pub runs_iq: usize,
        /// Relative standard deviation of one run's σ over the I/Q runs.
        #[metric(unit = "")] pub sigma_run_spread_iq: f64,
        /// Carrier wavelength (GPS L1).
        #[metric(unit = "m")] pub wavelength_m: f64,
        /// The front end of the sample-level path (`--front-end`): `i8` (CS8), `sm2`, `bit1`.
        #[metric(unit = "")] pub front_end: &'static str,
        /// C/N0 loss of the front end: the channels' C/N0 averaged over each satellite's
        /// observations, from an `i8` recording of the same synthesized signals (same seed)
        /// minus from this one, averaged over the satellites both delivered (null for `i8`,
        /// the reference, and on the I/Q path).
        #[metric(unit = "dB")] pub cn0_loss_db: Option<f64>,
        /// The sample-level path against the I/Q fast path (sample-level variants).
        #[metric(flatten)] #[serde(flatten)] pub paths: Option<PathComparison>,
        /// All three angles estimated (the paper's cases).
        #[metric(flatten)] #[serde(flatten)] pub three_axis: Option<ThreeAxis>,
        /// Without line-bias states (`linebias`).
        #[metric(flatten)] #[serde(flatten)] pub line_bias: Option<LineBiasFigures>,
    }
}

crate::metrics! {
    /// The sample-level path against the I/Q fast path: σ ratio, the information each
    /// delivers, wall time.
    pub struct PathComparison {
        /// σ_β from samples over σ_β on the I/Q path.
        #[metric(unit = "")] pub sigma_ratio_samples_to_iq: f64,
        /// Fisher information of β per epoch from samples against the ideal `J_β T`.
        #[metric(unit = "dB")] pub information_loss_db_samples: f64,
        /// The same on the I/Q fast path.
        #[metric(unit = "dB")] pub information_loss_db_iq: f64,
        /// What the fixed-point chain loses against the I/Q path.
        #[metric(unit = "dB")] pub chain_loss_db: f64,
        /// The chain's loss below 10 Hz (50-epoch means), where the loop lives.
        #[metric(unit = "dB")] pub chain_loss_db_low_frequency: f64,
        /// Loss predicted from the other satellites' cross-correlation.
        #[metric(unit = "dB")] pub cross_correlation_loss_db_predicted: f64,
        /// Measured discriminator slope over the slope the filter expects, samples.
        #[metric(unit = "")] pub loop_gain_factor_samples: f64,
        /// The same on the I/Q path.
        #[metric(unit = "")] pub loop_gain_factor_iq: f64,
        /// The bound at the information the samples delivered.
        #[metric(unit = "arcmin")] pub bound_arcmin_measured_information: f64,
        /// Mean C/N0 the channels reported.
        #[metric(unit = "dB-Hz")] pub mean_cn0_reported_dbhz: f64,
        /// Satellites tracked from samples.
        #[metric(unit = "")] pub satellites_tracked: usize,
        /// Filter epochs without observations.
        #[metric(unit = "")] pub empty_epochs: usize,
        /// Observations that arrived after their filter epoch.
        #[metric(unit = "")] pub late_epochs: usize,
        /// Wall time of the sample-level run.
        #[metric(wall = "s")] pub sample_wall_s: f64,
        /// Wall time of the sample synthesis.
        #[metric(wall = "s")] pub sample_synthesis_s: f64,
        /// Wall time of the sample-level tracking.
        #[metric(wall = "s")] pub sample_tracking_s: f64,
        /// Wall time of the sample-level acquisition.
        #[metric(wall = "s")] pub sample_acquisition_s: f64,
    }
}

crate::metrics! {
    /// All three angles estimated by the Gaussian filter.
    pub struct ThreeAxis {
        /// σ_β with α, β, γ estimated.
        #[metric(unit = "arcmin")] pub sigma_arcmin_3axis: f64,
        /// The same on the I/Q path.
        #[metric(unit = "arcmin")] pub sigma_arcmin_3axis_iq: f64,
        /// Bound √(2Δf (J⁻¹)_ββ) (β shares information with γ).
        #[metric(unit = "arcmin")] pub bound_arcmin_3axis: f64,
        /// False lock of the three-angle filter.
        #[metric(unit = "")] pub false_lock_3axis: bool,
    }
}

crate::metrics! {
    /// The `linebias` variant's figures (configurations 2 and 3: without bias states).
    pub struct LineBiasFigures {
        /// σ_β without bias states, Gaussian.
        #[metric(unit = "arcmin")] pub sigma_arcmin_without_bias_states: f64,
        /// σ_β without bias states, constant gain.
        #[metric(unit = "arcmin")] pub sigma_arcmin_without_bias_states_constant_gain: f64,
        /// σ_β without bias states on the I/Q path.
        #[metric(unit = "arcmin")] pub sigma_arcmin_without_bias_states_iq: f64,
        /// False lock without bias states.
        #[metric(unit = "")] pub false_lock_without_bias_states: bool,
        /// What estimating the biases costs: σ_β over the bound − 1.
        #[metric(unit = "%")] pub bias_cost_percent: f64,
        /// The same on the I/Q path.
        #[metric(unit = "%")] pub bias_cost_percent_iq: f64,
        /// Bound if the biases were re-learned every epoch.
        #[metric(unit = "arcmin")] pub bound_arcmin_biases_unknown_per_epoch: f64,
        /// RMS of the final line-bias errors, Gaussian (null without bias states).
        #[metric(unit = "rad")] pub line_bias_error_rms_rad: f64,
        /// The same, constant gain.
        #[metric(unit = "rad")] pub line_bias_error_rms_rad_constant_gain: f64,
    }
}

/// The runs behind a variant's figures.
struct Runs {
    configs: Vec<RunConfig>,
    iq_results: Vec<Vec<RunResult>>,
    iq: Vec<Summary>,
    sampled: Option<(Arc<Recording>, Vec<RunResult>)>,
    /// The front end's C/N0 loss against an `i8` recording of the same signals.
    cn0_loss_db: Option<f64>,
    front_end: Quantizer,
    /// The headline summaries (samples, or the I/Q path), per configuration.
    sums: Vec<Summary>,
    bound: f64,
}

impl Runs {
    fn run(plan: Plan, seed: u64, front_end: Quantizer) -> anyhow::Result<Self> {
        if plan.iq_only && front_end != Quantizer::I8 {
            anyhow::bail!("the -iq variants have no samples: --front-end {front_end} needs a sample-level variant");
        }
        let configs = plan.case.configurations();
        let bound = configs[0].bound_arcmin();
        let iq_results = monte_carlo(&configs, seed, "one-stage: I/Q fast path")?;
        let iq: Vec<Summary> = iq_results.iter().map(|r| summarize(r)).collect();
        let sampled = if plan.iq_only {
            None
        } else {
            Some(sample_level(&configs, seed, front_end)?)
        };
        let cn0_loss_db = match &sampled {
            Some((rec, _)) if front_end != Quantizer::I8 => {
                let bar = progress(1, "one-stage: the i8 reference recording");
                let reference = record(&configs[0], seed, Quantizer::I8)?;
                bar.finish_and_clear();
                cn0_loss_db(&reference.cn0_by_satellite(), &rec.cn0_by_satellite())
            }
            _ => None,
        };
        let sums = match &sampled {
            Some((_, res)) => res
                .iter()
                .map(|r| summarize(std::slice::from_ref(r)))
                .collect(),
            None => iq.clone(),
        };
        Ok(Self {
            configs,
            iq_results,
            iq,
            sampled,
            cn0_loss_db,
            front_end,
            sums,
            bound,
        })
    }

    fn path(&self) -> (&'static str, usize) {
        match self.sampled {
            Some(_) => ("samples", 1),
            None => ("iq", RUNS),
        }
    }

    /// How much one 60 s run's σ scatters (relative standard deviation over the I/Q runs).
    fn spread(&self) -> f64 {
        let per_run: Vec<f64> = self.iq_results[0].iter().map(|r| r.rms_arcmin).collect();
        crate::stats::std_dev(&per_run) / crate::stats::mean(&per_run)
    }

    fn metrics(&self, case: Case, paths: Option<PathComparison>) -> Metrics {
        let (g, c, iq, bound) = (&self.sums[0], &self.sums[1], &self.iq, self.bound);
        let (path, runs) = self.path();
        let three_axis = (self.sums.len() > 2 && case != Case::LineBias).then(|| ThreeAxis {
            sigma_arcmin_3axis: self.sums[2].sigma_arcmin,
            sigma_arcmin_3axis_iq: iq[2].sigma_arcmin,
            bound_arcmin_3axis: self.configs[2].bound_arcmin(),
            false_lock_3axis: self.sums[2].false_lock,
        });
        Metrics {
            sigma_arcmin: g.sigma_arcmin,
            bound_arcmin: bound,
            pull_in_s: g.pull_in_s,
            false_lock: g.false_lock,
            input_path: path,
            runs,
            sigma_arcmin_gaussian: g.sigma_arcmin,
            sigma_arcmin_constant_gain: c.sigma_arcmin,
            pull_in_s_gaussian: g.pull_in_s,
            pull_in_s_constant_gain: c.pull_in_s,
            lock_declared_s_gaussian: g.locked_s,
            lock_declared_s_constant_gain: c.locked_s,
            false_lock_constant_gain: c.false_lock,
            flagged_runs_gaussian: g.flagged_runs,
            flagged_runs_constant_gain: c.flagged_runs,
            sigma_over_bound: g.sigma_arcmin / bound,
            sigma_arcmin_iq: iq[0].sigma_arcmin,
            sigma_arcmin_constant_gain_iq: iq[1].sigma_arcmin,
            pull_in_s_iq: iq[0].pull_in_s,
            false_lock_iq: iq[0].false_lock || iq[1].false_lock,
            runs_iq: RUNS,
            sigma_run_spread_iq: self.spread(),
            wavelength_m: truth::WAVELENGTH_M,
            front_end: self.front_end.name(),
            cn0_loss_db: self.cn0_loss_db,
            paths,
            three_axis,
            line_bias: (case == Case::LineBias)
                .then(|| line_bias_metrics(&self.configs[0], &self.sums, iq, bound)),
        }
    }

    fn summary(&self, plan: Plan) -> Vec<String> {
        let gauss = &self.configs[0];
        let (g, c, iq, bound) = (&self.sums[0], &self.sums[1], &self.iq, self.bound);
        vec![
            format!(
                "{} satellites of G1, {} dB-Hz, Δf = {} Hz, λ = {:.4} m, {} s runs, first {:.0} % discarded; headline: {}",
                gauss.satellites,
                gauss.cn0_dbhz,
                gauss.loop_bandwidth_hz,
                truth::WAVELENGTH_M,
                gauss.duration_s,
                100.0 * gauss.discard,
                if plan.iq_only {
                    format!("I/Q fast path, {RUNS} runs")
                } else {
                    format!("samples (2.6 Msps, front end {} → core acquisition, correlators, tracking, adapter), one run", self.front_end)
                }
            ),
            format!(
                "σ_β: Gaussian approximation {:.3}′, constant gain {:.3}′; bound √(2Δf/J_β) {:.3}′; I/Q fast path ({RUNS} runs) {:.3}′ / {:.3}′ (one run's σ scatters by ±{:.1} %)",
                g.sigma_arcmin, c.sigma_arcmin, bound, iq[0].sigma_arcmin, iq[1].sigma_arcmin, 100.0 * self.spread()
            ),
            format!(
                "pull-in (worst run): Gaussian {}, constant gain {}; false lock: {} / {} (I/Q: {} / {})",
                never(g.pull_in_s),
                never(c.pull_in_s),
                g.false_lock,
                c.false_lock,
                iq[0].false_lock,
                iq[1].false_lock
            ),
        ]
    }

    /// The headline runs' time series (and the I/Q run beside the sample-level one).
    fn write_files(
        &self,
        dir: &std::path::Path,
        variant: &str,
    ) -> anyhow::Result<Vec<std::path::PathBuf>> {
        let first = |r: &[RunResult]| r.first().cloned();
        let (hg, hc): (Option<RunResult>, Option<RunResult>) = match &self.sampled {
            Some((_, res)) => (res.first().cloned(), res.get(1).cloned()),
            None => (first(&self.iq_results[0]), first(&self.iq_results[1])),
        };
        let (Some(hg), Some(hc)) = (hg, hc) else {
            return Ok(Vec::new());
        };
        let iq_g = self
            .sampled
            .as_ref()
            .and_then(|_| self.iq_results[0].first());
        let run0 = files::Run0 {
            path: self.path().0,
            gauss: &hg,
            cg: &hc,
            iq_gauss: iq_g,
        };
        files::write_files(dir, variant, &run0, self.bound)
    }
}

fn run(plan: Plan, ctx: &RunContext) -> anyhow::Result<Outcome> {
    let runs = Runs::run(plan, ctx.seed, ctx.front_end)?;
    let mut summary = runs.summary(plan);
    if let Some(loss) = runs.cn0_loss_db {
        summary.push(format!(
            "front end {}: C/N0 loss against CS8 on the same signals {loss:.2} dB",
            ctx.front_end
        ));
    }
    let paths = match &runs.sampled {
        Some((rec, _)) => Some(compare_paths(
            &mut summary,
            &runs.configs[0],
            rec,
            &runs.sums[0],
            &runs.iq[0],
            runs.bound,
            ctx.seed,
        )?),
        None => None,
    };
    let m = runs.metrics(plan.case, paths);
    if let Some(t) = &m.three_axis {
        summary.push(format!(
            "all three angles estimated (Gaussian): σ_β {:.3}′ (I/Q {:.3}′), bound √(2Δf (J⁻¹)_ββ) {:.3}′ (β shares information with γ)",
            t.sigma_arcmin_3axis, t.sigma_arcmin_3axis_iq, t.bound_arcmin_3axis
        ));
    }
    if let Some(lb) = &m.line_bias {
        summary.push(line_bias_summary(&runs.sums, lb));
    }
    let mut outcome = Outcome::new(&m)?;
    outcome.paper = plan.case.paper_figure();
    outcome.summary = summary;
    if let Some(dir) = &ctx.out_dir {
        outcome.files = runs.write_files(dir, &ctx.variant)?;
    }
    Ok(outcome)
}

/// The sample-level path against the I/Q fast path: σ ratio, the information each delivers,
/// wall time.
fn compare_paths(
    summary: &mut Vec<String>,
    gauss: &RunConfig,
    rec: &Arc<Recording>,
    g: &Summary,
    iq: &Summary,
    bound: f64,
    seed: u64,
) -> anyhow::Result<PathComparison> {
    let sky = truth::sky_g1(gauss.satellites);
    let mut iq_source = IqFastPath::new(&sky, gauss.cn0_dbhz, gauss.line_bias, seed);
    let iq_epochs = record_source(gauss, &mut iq_source)?;
    let loss_iq = loss::measure(gauss, &iq_epochs)?;
    let loss_s = loss::measure(gauss, &rec.epochs)?;
    let st = &rec.stats;
    // the other satellites' cross-correlation: (n − 1)(C/N0)T/1023 of the noise (signal scenario)
    let snr = 10f64.powf(gauss.cn0_dbhz / 10.0) * source::EPOCH_S;
    let mai_db = 10.0 * (1.0 + (st.satellites as f64 - 1.0) * snr / 1023.0).log10();
    let m = PathComparison {
        sigma_ratio_samples_to_iq: g.sigma_arcmin / iq.sigma_arcmin,
        information_loss_db_samples: loss_s.loss_db,
        information_loss_db_iq: loss_iq.loss_db,
        chain_loss_db: loss_s.loss_db - loss_iq.loss_db,
        chain_loss_db_low_frequency: 10.0
            * (loss_iq.ratio_low_frequency / loss_s.ratio_low_frequency).log10(),
        cross_correlation_loss_db_predicted: mai_db,
        loop_gain_factor_samples: loss_s.slope_over_expected,
        loop_gain_factor_iq: loss_iq.slope_over_expected,
        bound_arcmin_measured_information: loss_s.bound_arcmin(bound),
        mean_cn0_reported_dbhz: st.mean_cn0_dbhz,
        satellites_tracked: st.tracked,
        empty_epochs: st.empty_epochs,
        late_epochs: st.late,
        sample_wall_s: rec.wall_s,
        sample_synthesis_s: st.synthesis_s,
        sample_tracking_s: st.tracking_s,
        sample_acquisition_s: st.acquisition_s,
    };
    summary.push(format!(
        "samples vs I/Q fast path: σ ratio {:.3}; information per epoch vs ideal (slope²/var of u_β at the truth, {} epochs): samples −{:.2} dB, I/Q −{:.2} dB → chain loss {:.2} dB (cross-correlation of the other satellites: {:.2} dB predicted), below 10 Hz {:.2} ± 0.2 dB; loop gain factor {:.3} / {:.3}; C/N0 reported {:.2} dB-Hz; bound at the measured information {:.3}′",
        m.sigma_ratio_samples_to_iq,
        loss_s.epochs,
        loss_s.loss_db,
        loss_iq.loss_db,
        m.chain_loss_db,
        mai_db,
        m.chain_loss_db_low_frequency,
        loss_s.slope_over_expected,
        loss_iq.slope_over_expected,
        st.mean_cn0_dbhz,
        m.bound_arcmin_measured_information
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
    Ok(m)
}

/// The `linebias` variant's extra figures (configurations 2 and 3: without bias states).
fn line_bias_metrics(
    gauss: &RunConfig,
    sums: &[Summary],
    iq: &[Summary],
    bound: f64,
) -> LineBiasFigures {
    let (g, c, gn, cn) = (&sums[0], &sums[1], &sums[2], &sums[3]);
    let sky = truth::sky_g1(gauss.satellites);
    LineBiasFigures {
        sigma_arcmin_without_bias_states: gn.sigma_arcmin,
        sigma_arcmin_without_bias_states_constant_gain: cn.sigma_arcmin,
        sigma_arcmin_without_bias_states_iq: iq[2].sigma_arcmin,
        false_lock_without_bias_states: gn.false_lock,
        bias_cost_percent: 100.0 * (g.sigma_arcmin / bound - 1.0),
        bias_cost_percent_iq: 100.0 * (iq[0].sigma_arcmin / bound - 1.0),
        bound_arcmin_biases_unknown_per_epoch: bound::loop_bound_arcmin(
            gauss.loop_bandwidth_hz,
            bound::information_rate_biases_unknown(0.0, &sky, gauss.cn0_dbhz),
        ),
        line_bias_error_rms_rad: g.bias_error_rms_rad,
        line_bias_error_rms_rad_constant_gain: c.bias_error_rms_rad,
    }
}

fn line_bias_summary(sums: &[Summary], lb: &LineBiasFigures) -> String {
    format!(
        "line biases B−A = {:.2} rad, C−A = {:.2} rad: with bias states σ_β {:.3}′ (Gaussian) / {:.3}′ (constant gain), without {:.3}′ / {:.3}′; bound if the biases were re-learned every epoch {:.3}′",
        LINE_BIAS[1] - LINE_BIAS[0],
        LINE_BIAS[2] - LINE_BIAS[0],
        sums[0].sigma_arcmin,
        sums[1].sigma_arcmin,
        lb.sigma_arcmin_without_bias_states,
        lb.sigma_arcmin_without_bias_states_constant_gain,
        lb.bound_arcmin_biases_unknown_per_epoch
    )
}
