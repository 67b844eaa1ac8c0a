//! `snapshot --variant ambiguity`: single-epoch integer ambiguity resolution on a real GPS sky.
//!
//! Each epoch: a random time within ±3.5 days of the bundled almanac's time of applicability
//! (GPS week 2195) for a receiver at Kyiv (50.45° N, 30.52° E), 6–10 healthy satellites above
//! 10° picked at random from those in view, a uniformly random attitude of the paper's 1 m
//! triangle, random integer ambiguities, and noise drawn **per antenna** (3 mm/√2 phase,
//! 0.3 m/√2 code), so that each single difference has 3 mm / 0.3 m and the two baselines'
//! differences are correlated 0.5 through the shared base antenna. The reference frame is the
//! local NED frame.
//!
//! Three methods see the same data:
//! * the core's constrained resolver (f32; MC-LAMBDA objective, ratio test 3, χ² test);
//! * the core's unconstrained LAMBDA integer least squares (same ratio and χ² tests);
//! * float-then-round (host f64): code-only float baselines, rounded float ambiguities, the
//!   core's snapshot solver on the fixed phases, accepted when its χ² test passes.
//!
//! Metrics (constrained): `success_rate`, `wrong_fix_rate`, `refusal_rate`, `err_deg_rms`
//! (rotation-angle error of fixed epochs); the same prefixed `lambda_` and `round_` for the
//! comparison methods; search effort (`nodes_mean`, `nodes_max`, `candidates_mean`).

use gnss_attitude::attitude::ambiguity::AmbiguityError;
use gnss_attitude::attitude::ambiguity::{
    AmbiguityConfig, AmbiguityResolver, PhaseObservations, PhaseSatellite, SearchMode,
    GPS_L1_WAVELENGTH_M,
};
use gnss_attitude::attitude::range_model::{
    BaselineCorrelation, Baselines, RangeDifferences, SatelliteRanges,
};
use gnss_attitude::attitude::snapshot::{
    SnapshotError, SnapshotQuality, SnapshotSolution, SnapshotSolver,
};
use gnss_attitude::geometry::rotation_angle;
use nalgebra::{Matrix3, Vector3};
use rand::seq::SliceRandom;
use rayon::prelude::*;

use super::common::{epoch_rng, normal, random_rotation, triangle, uniform_int};
use crate::report::{progress, write_csv};
use crate::scenarios::{Outcome, RunContext};
use crate::stats;
use crate::truth::gps::{Almanac, Geodetic, SatelliteView};

/// Monte Carlo epochs.
pub const EPOCHS: usize = 5000;
/// Phase and code noise per single difference, m.
pub const SIGMA_PHASE: f64 = 0.003;
/// Code noise per single difference, m.
pub const SIGMA_CODE: f64 = 0.3;
/// Elevation mask, degrees.
pub const MASK_DEG: f64 = 10.0;

/// What one method did with one epoch.
#[derive(Clone, Copy, Debug)]
enum Verdict {
    Correct(f64),
    Wrong(f64),
    Refused(&'static str),
}

struct EpochResult {
    satellites: usize,
    constrained: Verdict,
    lambda: Verdict,
    round: Verdict,
    nodes: u32,
    candidates: u32,
    ratio: f64,
}

fn refusal_name(e: &AmbiguityError) -> &'static str {
    match e {
        AmbiguityError::Ambiguous => "ambiguous",
        AmbiguityError::ModelRejected => "model_rejected",
        AmbiguityError::NoCandidate => "no_candidate",
        AmbiguityError::SearchBudgetExhausted => "budget",
        _ => "input",
    }
}

/// Attempts at finding a time with enough satellites in view.
const SKY_ATTEMPTS: usize = 100;
/// Fewest and most satellites of an epoch.
const SATELLITES: (usize, usize) = (6, 10);
/// Spread of the epochs' times around the almanac's time of applicability, s (one week).
const TIME_SPREAD_S: f64 = 7.0 * 86_400.0;
/// Range of the true integer ambiguities, cycles.
const AMBIGUITY_RANGE: i64 = 40;

/// The satellites of epoch `rng`: a random time within the week around the almanac's
/// reference, then a random subset of those in view.
fn draw_sky(
    rng: &mut rand_chacha::ChaCha8Rng,
    almanac: &Almanac,
    site: &Geodetic,
) -> anyhow::Result<Vec<SatelliteView>> {
    let t0 = almanac.reference_time_s();
    let mut views = Vec::new();
    for _ in 0..SKY_ATTEMPTS {
        let t = t0 + (rand::Rng::random::<f64>(rng) - 0.5) * TIME_SPREAD_S;
        views = almanac.visible(site, t, MASK_DEG.to_radians());
        if views.len() >= SATELLITES.0 {
            break;
        }
    }
    anyhow::ensure!(
        views.len() >= SATELLITES.0,
        "fewer than 6 satellites in view"
    );
    let n = uniform_int(
        rng,
        SATELLITES.0 as i64,
        views.len().min(SATELLITES.1) as i64,
    ) as usize;
    views.shuffle(rng);
    views.truncate(n);
    Ok(views)
}

/// One epoch's measurements: phases (cycles) and codes (m) per satellite and baseline, with
/// the true integers, and the same as the resolvers' input.
struct Measured {
    obs: PhaseObservations<2, 12, f32>,
    truth_z: [[i64; 12]; 2],
    phases: Vec<[f64; 2]>,
    codes: Vec<[f64; 2]>,
}

/// Phases and codes of the array at attitude `c_rb` with per-antenna noise.
fn measure(
    rng: &mut rand_chacha::ChaCha8Rng,
    views: &[SatelliteView],
    c_rb: &Matrix3<f64>,
) -> anyhow::Result<Measured> {
    let a = triangle().map(|bi| c_rb * bi);
    let lambda = GPS_L1_WAVELENGTH_M;
    let ant_phase = SIGMA_PHASE / 2f64.sqrt();
    let ant_code = SIGMA_CODE / 2f64.sqrt();
    let mut m = Measured {
        obs: PhaseObservations::new(),
        truth_z: [[0i64; 12]; 2],
        phases: Vec::with_capacity(views.len()),
        codes: Vec::with_capacity(views.len()),
    };
    for (j, v) in views.iter().enumerate() {
        // per-antenna noise: antenna 0 is shared by both single differences
        let phase_noise: [f64; 3] = std::array::from_fn(|_| normal(rng) * ant_phase);
        let code_noise: [f64; 3] = std::array::from_fn(|_| normal(rng) * ant_code);
        let mut phase = [0f64; 2];
        let mut code = [0f64; 2];
        for i in 0..2 {
            let z = uniform_int(rng, -AMBIGUITY_RANGE, AMBIGUITY_RANGE);
            m.truth_z[i][j] = z;
            let geometric = a[i].dot(&v.los_ned);
            phase[i] = (geometric + phase_noise[0] - phase_noise[i + 1]) / lambda + z as f64;
            code[i] = geometric + code_noise[0] - code_noise[i + 1];
        }
        m.phases.push(phase);
        m.codes.push(code);
        m.obs
            .push(PhaseSatellite {
                id: v.prn,
                los: v.los_ned.cast::<f32>(),
                phase_cycles: phase.map(|x| x as f32),
                code_m: code.map(|x| x as f32),
                cofactor: 1.0,
            })
            .map_err(|e| anyhow::anyhow!("{e}"))?;
    }
    Ok(m)
}

/// Integer ambiguities per baseline and satellite.
type Integers = [[i32; 12]; 2];

/// Float-then-round (host f64): code-only float baseline per baseline, rounded float
/// ambiguities, the snapshot solver on the fixed phases. Returns the integers and the solve.
fn float_then_round(
    views: &[SatelliteView],
    m: &Measured,
    snapshot: &SnapshotSolver<2, f32>,
) -> anyhow::Result<(Integers, Result<SnapshotSolution<f32>, SnapshotError>)> {
    let lambda = GPS_L1_WAVELENGTH_M;
    let n = views.len();
    let los: Vec<Vector3<f64>> = views.iter().map(|v| v.los_ned).collect();
    let nmat = los
        .iter()
        .fold(Matrix3::zeros(), |m, s| m + s * s.transpose());
    let ninv = nmat
        .try_inverse()
        .ok_or_else(|| anyhow::anyhow!("singular sky"))?;
    let mut fixed = [[0i32; 12]; 2];
    for i in 0..2 {
        let rhs = los
            .iter()
            .zip(&m.codes)
            .fold(Vector3::zeros(), |r, (s, p)| r + s * p[i]);
        let a_float = ninv * rhs;
        for j in 0..n {
            fixed[i][j] = (m.phases[j][i] - los[j].dot(&a_float) / lambda).round() as i32;
        }
    }
    let mut ranges = RangeDifferences::<2, 12, f32>::new();
    for j in 0..n {
        ranges
            .push(SatelliteRanges {
                id: views[j].prn,
                los: los[j].cast(),
                range_diff: std::array::from_fn(|i| {
                    ((m.phases[j][i] - f64::from(fixed[i][j])) * lambda) as f32
                }),
                sigma: SIGMA_PHASE as f32,
            })
            .map_err(|e| anyhow::anyhow!("{e}"))?;
    }
    Ok((fixed, snapshot.solve(&ranges)))
}

fn one_epoch(
    ctx_seed: u64,
    k: usize,
    almanac: &Almanac,
    site: &Geodetic,
    constrained: &AmbiguityResolver<2, f32>,
    unconstrained: &AmbiguityResolver<2, f32>,
    snapshot: &SnapshotSolver<2, f32>,
) -> anyhow::Result<EpochResult> {
    let mut rng = epoch_rng(ctx_seed, 3, k);
    let views = draw_sky(&mut rng, almanac, site)?;
    let n = views.len();
    let c_rb = random_rotation(&mut rng);
    let m = measure(&mut rng, &views, &c_rb)?;
    let judge = |fixed: &[[i32; 12]; 2], c: &Matrix3<f64>| -> Verdict {
        let err = rotation_angle(&(c.transpose() * c_rb)).to_degrees();
        let correct = (0..2).all(|i| (0..n).all(|j| i64::from(fixed[i][j]) == m.truth_z[i][j]));
        if correct {
            Verdict::Correct(err)
        } else {
            Verdict::Wrong(err)
        }
    };
    let (constrained_verdict, nodes, candidates, ratio) = match constrained.resolve(&m.obs) {
        Ok(fix) => (
            judge(&fix.ambiguities, &fix.solution.c_rb.cast()),
            fix.nodes,
            fix.candidates,
            f64::from(fix.ratio),
        ),
        Err(e) => (Verdict::Refused(refusal_name(&e)), 0, 0, f64::NAN),
    };
    let lambda_verdict = match unconstrained.resolve(&m.obs) {
        Ok(fix) => judge(&fix.ambiguities, &fix.solution.c_rb.cast()),
        Err(e) => Verdict::Refused(refusal_name(&e)),
    };
    let (fixed, solved) = float_then_round(&views, &m, snapshot)?;
    let round_verdict = match solved {
        Ok(sol) if sol.quality == SnapshotQuality::Good => judge(&fixed, &sol.c_rb.cast()),
        Ok(_) => Verdict::Refused("model_rejected"),
        Err(_) => Verdict::Refused("input"),
    };
    Ok(EpochResult {
        satellites: n,
        constrained: constrained_verdict,
        lambda: lambda_verdict,
        round: round_verdict,
        nodes,
        candidates,
        ratio,
    })
}

/// Success, wrong-fix and refusal rates and the RMS error of fixed epochs.
fn rates(verdicts: &[Verdict]) -> (f64, f64, f64, f64) {
    let total = verdicts.len().max(1) as f64;
    let correct = verdicts
        .iter()
        .filter(|v| matches!(v, Verdict::Correct(_)))
        .count() as f64;
    let wrong = verdicts
        .iter()
        .filter(|v| matches!(v, Verdict::Wrong(_)))
        .count() as f64;
    let errors: Vec<f64> = verdicts
        .iter()
        .filter_map(|v| match v {
            Verdict::Correct(e) | Verdict::Wrong(e) => Some(*e),
            Verdict::Refused(_) => None,
        })
        .collect();
    (
        correct / total,
        wrong / total,
        (total - correct - wrong) / total,
        stats::rms(&errors),
    )
}

/// How one method fared (success, wrong fix, refusal).
struct MethodRates {
    success_rate: f64,
    wrong_fix_rate: f64,
    refusal_rate: f64,
}

crate::metrics! {
    /// Refusals of the constrained resolver by cause.
    pub struct Refusals {
        /// Ratio test failed.
        #[metric(unit = "epochs")] pub ambiguous: usize,
        /// χ² test failed.
        #[metric(unit = "epochs")] pub model_rejected: usize,
        /// No candidate in the search space.
        #[metric(unit = "epochs")] pub no_candidate: usize,
        /// Search budget exhausted.
        #[metric(unit = "epochs")] pub budget: usize,
        /// Input refused.
        #[metric(unit = "epochs")] pub input: usize,
    }
}

crate::metrics! {
    /// The constrained resolver's rates for one number of satellites.
    pub struct BySatellites {
        /// Satellites in the epoch.
        #[metric(unit = "")] pub satellites: usize,
        /// Epochs with that many satellites.
        #[metric(unit = "")] pub epochs: usize,
        /// Epochs fixed to the true integers.
        #[metric(unit = "")] pub success_rate: f64,
        /// Epochs fixed to wrong integers.
        #[metric(unit = "")] pub wrong_fix_rate: f64,
        /// Epochs refused.
        #[metric(unit = "")] pub refusal_rate: f64,
    }
}

crate::metrics! {
    /// Metrics of `snapshot --variant ambiguity`.
    pub struct Metrics {
        /// Constrained resolver: epochs fixed to the true integers.
        #[metric(unit = "")] pub success_rate: f64,
        /// Constrained resolver: epochs fixed to wrong integers.
        #[metric(unit = "")] pub wrong_fix_rate: f64,
        /// Constrained resolver: epochs refused.
        #[metric(unit = "")] pub refusal_rate: f64,
        /// Constrained resolver: RMS rotation-angle error of the fixed epochs.
        #[metric(unit = "deg")] pub err_deg_rms: f64,
        /// Unconstrained LAMBDA: epochs fixed to the true integers.
        #[metric(unit = "")] pub lambda_success_rate: f64,
        /// Unconstrained LAMBDA: epochs fixed to wrong integers.
        #[metric(unit = "")] pub lambda_wrong_fix_rate: f64,
        /// Unconstrained LAMBDA: epochs refused.
        #[metric(unit = "")] pub lambda_refusal_rate: f64,
        /// Unconstrained LAMBDA: RMS rotation-angle error of the fixed epochs.
        #[metric(unit = "deg")] pub lambda_err_deg_rms: f64,
        /// Float-then-round: epochs fixed to the true integers.
        #[metric(unit = "")] pub round_success_rate: f64,
        /// Float-then-round: epochs fixed to wrong integers.
        #[metric(unit = "")] pub round_wrong_fix_rate: f64,
        /// Float-then-round: epochs refused.
        #[metric(unit = "")] pub round_refusal_rate: f64,
        /// Float-then-round: RMS rotation-angle error of the fixed epochs.
        #[metric(unit = "deg")] pub round_err_deg_rms: f64,
        /// Monte Carlo epochs.
        #[metric(unit = "")] pub epochs: usize,
        /// Mean number of satellites per epoch.
        #[metric(unit = "")] pub satellites_mean: f64,
        /// Mean search-tree nodes of the constrained resolver.
        #[metric(unit = "")] pub nodes_mean: f64,
        /// Largest search-tree node count.
        #[metric(unit = "")] pub nodes_max: f64,
        /// Mean candidates fitted per epoch.
        #[metric(unit = "")] pub candidates_mean: f64,
        /// Median ratio-test value.
        #[metric(unit = "")] pub ratio_median: f64,
        /// Refusals by cause.
        #[metric(nested)] pub refusals: Refusals,
        /// The constrained resolver by number of satellites.
        #[metric(nested)] pub by_satellites: Vec<BySatellites>,
    }
}

/// The three resolvers the epochs are solved by (constrained, unconstrained, round).
fn resolvers() -> anyhow::Result<(
    AmbiguityResolver<2, f32>,
    AmbiguityResolver<2, f32>,
    SnapshotSolver<2, f32>,
)> {
    let baselines =
        Baselines::new(triangle().map(|v| v.cast::<f32>())).map_err(|e| anyhow::anyhow!("{e}"))?;
    let solver = SnapshotSolver::new(baselines, BaselineCorrelation::shared_base_antenna());
    let config = AmbiguityConfig::gps_l1(SIGMA_PHASE as f32, SIGMA_CODE as f32);
    let constrained = AmbiguityResolver::new(solver, config).map_err(|e| anyhow::anyhow!("{e}"))?;
    let unconstrained = AmbiguityResolver::new(
        solver,
        AmbiguityConfig {
            mode: SearchMode::Unconstrained,
            ..config
        },
    )
    .map_err(|e| anyhow::anyhow!("{e}"))?;
    let round_solver = SnapshotSolver::new(baselines, BaselineCorrelation::shared_base_antenna());
    Ok((constrained, unconstrained, round_solver))
}

/// Runs the variant.
pub fn run(ctx: &RunContext) -> anyhow::Result<Outcome> {
    let almanac = Almanac::bundled();
    anyhow::ensure!(!almanac.entries.is_empty(), "bundled almanac did not parse");
    let site = Geodetic::from_degrees(50.45, 30.52, 180.0);
    let (constrained, unconstrained, round_solver) = resolvers()?;
    let bar = progress(EPOCHS as u64, "snapshot ambiguity");
    let results: Vec<EpochResult> = (0..EPOCHS)
        .into_par_iter()
        .map(|k| {
            let r = one_epoch(
                ctx.seed,
                k,
                &almanac,
                &site,
                &constrained,
                &unconstrained,
                &round_solver,
            );
            bar.inc(1);
            r
        })
        .collect::<anyhow::Result<_>>()?;
    bar.finish_and_clear();
    let m = metrics(&results);
    let mut outcome = Outcome::new(&m)?;
    outcome.summary = summary(&m);
    if let Some(dir) = &ctx.out_dir {
        outcome.files = vec![write_csv_file(dir, &results)?];
    }
    Ok(outcome)
}

fn method(verdicts: &[Verdict]) -> (MethodRates, f64) {
    let (success_rate, wrong_fix_rate, refusal_rate, err) = rates(verdicts);
    (
        MethodRates {
            success_rate,
            wrong_fix_rate,
            refusal_rate,
        },
        err,
    )
}

fn metrics(results: &[EpochResult]) -> Metrics {
    let pick = |f: fn(&EpochResult) -> Verdict| results.iter().map(f).collect::<Vec<_>>();
    let (c, e) = method(&pick(|x| x.constrained));
    let (l, le) = method(&pick(|x| x.lambda));
    let (r, re) = method(&pick(|x| x.round));
    let searched = || results.iter().filter(|x| x.nodes > 0);
    let nodes: Vec<f64> = searched().map(|x| f64::from(x.nodes)).collect();
    let cands: Vec<f64> = searched().map(|x| f64::from(x.candidates)).collect();
    let sats: Vec<f64> = results.iter().map(|x| x.satellites as f64).collect();
    let ratios: Vec<f64> = results
        .iter()
        .map(|x| x.ratio)
        .filter(|v| v.is_finite())
        .collect();
    let count = |name: &str| {
        results
            .iter()
            .filter(|x| matches!(x.constrained, Verdict::Refused(n) if n == name))
            .count()
    };
    let by_satellites = (6..=10)
        .map(|n| {
            let v: Vec<Verdict> = results
                .iter()
                .filter(|x| x.satellites == n)
                .map(|x| x.constrained)
                .collect();
            let (rates, _) = method(&v);
            BySatellites {
                satellites: n,
                epochs: v.len(),
                success_rate: rates.success_rate,
                wrong_fix_rate: rates.wrong_fix_rate,
                refusal_rate: rates.refusal_rate,
            }
        })
        .collect();
    Metrics {
        success_rate: c.success_rate,
        wrong_fix_rate: c.wrong_fix_rate,
        refusal_rate: c.refusal_rate,
        err_deg_rms: e,
        lambda_success_rate: l.success_rate,
        lambda_wrong_fix_rate: l.wrong_fix_rate,
        lambda_refusal_rate: l.refusal_rate,
        lambda_err_deg_rms: le,
        round_success_rate: r.success_rate,
        round_wrong_fix_rate: r.wrong_fix_rate,
        round_refusal_rate: r.refusal_rate,
        round_err_deg_rms: re,
        epochs: EPOCHS,
        satellites_mean: stats::mean(&sats),
        nodes_mean: stats::mean(&nodes),
        nodes_max: nodes.iter().fold(0.0f64, |a, &b| a.max(b)),
        candidates_mean: stats::mean(&cands),
        ratio_median: stats::quantile(&ratios, 0.5),
        refusals: Refusals {
            ambiguous: count("ambiguous"),
            model_rejected: count("model_rejected"),
            no_candidate: count("no_candidate"),
            budget: count("budget"),
            input: count("input"),
        },
        by_satellites,
    }
}

fn summary(m: &Metrics) -> Vec<String> {
    vec![
        format!("{EPOCHS} single epochs, real GPS sky (week 2195, Kyiv, mask {MASK_DEG}°), 6-10 satellites (mean {:.1}), 1 m triangle, {} mm / {} m per SD, random attitude", m.satellites_mean, SIGMA_PHASE * 1e3, SIGMA_CODE),
        format!("constrained (MC-LAMBDA objective): success {:.4}, wrong fix {:.4}, refused {:.4}, error RMS {:.3}°", m.success_rate, m.wrong_fix_rate, m.refusal_rate, m.err_deg_rms),
        format!("unconstrained LAMBDA:              success {:.4}, wrong fix {:.4}, refused {:.4}, error RMS {:.3}°", m.lambda_success_rate, m.lambda_wrong_fix_rate, m.lambda_refusal_rate, m.lambda_err_deg_rms),
        format!("float-then-round:                  success {:.4}, wrong fix {:.4}, refused {:.4}, error RMS {:.3}°", m.round_success_rate, m.round_wrong_fix_rate, m.round_refusal_rate, m.round_err_deg_rms),
        format!("search: {:.0} nodes mean ({:.0} max), {:.1} candidates fitted mean", m.nodes_mean, m.nodes_max, m.candidates_mean),
    ]
}

/// Per-epoch verdicts (1 correct, −1 wrong, 0 refused) as CSV.
fn write_csv_file(
    dir: &std::path::Path,
    results: &[EpochResult],
) -> anyhow::Result<std::path::PathBuf> {
    let csv = dir.join("snapshot_ambiguity.csv");
    let code = |v: &Verdict| match v {
        Verdict::Correct(_) => 1.0,
        Verdict::Wrong(_) => -1.0,
        Verdict::Refused(_) => 0.0,
    };
    write_csv(
        &csv,
        &[
            "epoch",
            "satellites",
            "constrained",
            "lambda",
            "round",
            "nodes",
            "ratio",
        ],
        results.iter().enumerate().map(|(k, x)| {
            [
                k as f64,
                x.satellites as f64,
                code(&x.constrained),
                code(&x.lambda),
                code(&x.round),
                f64::from(x.nodes),
                x.ratio,
            ]
        }),
    )?;
    Ok(csv)
}
