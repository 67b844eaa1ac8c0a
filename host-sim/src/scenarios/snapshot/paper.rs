//! `snapshot --variant paper`: the paper's three-antenna case with known ambiguities.
//!
//! Truth: heading 180°, roll 0, pitch 0; `b1 = (1, 0, 0)`, `b2 = (0.5, √3/2, 0)` m; lines of
//! sight at elevation 60/45/30°, azimuth 0/120/240° in a local-level frame (z to nadir);
//! i.i.d. 4 mm per single difference. Each epoch is solved independently by the core's f32
//! [`SnapshotSolver`]. Host-sim computes the Cramér–Rao bound for the same geometry (f64), and
//! runs the algorithm as printed with `G⁻¹` replaced by a pseudo-inverse (the only way it runs
//! on three antennas), whose bias explains the paper's figures.
//!
//! Metrics: `mean_err_deg`, `std_err_deg`, `crb_deg` (each `[heading, roll, pitch]`),
//! `reflections`, plus the solver's own predicted σ, the failures, and the pseudo-inverse run.

use gnss_attitude::attitude::range_model::{BaselineCorrelation, Baselines};
use gnss_attitude::attitude::snapshot::SnapshotSolver;
use gnss_attitude::geometry::Euler321;
use nalgebra::{Matrix3, SMatrix, Vector3};
use rayon::prelude::*;
use serde_json::json;

use super::common::{
    column, crb_body, epoch_rng, euler_errors_deg, euler_sigma_deg, noisy_ranges, paper_sky,
    triangle,
};
use crate::report::{plot_panels, progress, write_csv, Panel, Series};
use crate::scenarios::{Outcome, RunContext};
use crate::stats;

/// Monte Carlo epochs.
pub const EPOCHS: usize = 4000;
/// Range-difference noise, m (per single difference, i.i.d.).
pub const SIGMA: f64 = 0.004;
/// The paper's "mean errors" (heading, roll, pitch), degrees.
pub const PAPER_MEAN_ERR_DEG: [f64; 3] = [0.282, 1.234, 0.851];

struct EpochResult {
    err: [f64; 3],
    sigma: [f64; 3],
    reflection: bool,
    failed: bool,
    pinv_err: [f64; 3],
    pinv_reflection: bool,
    chi_square: f64,
}

/// The algorithm as printed with `G⁻¹ → G⁺` (f64): `K = G⁺ B R`, `Q = S Kᵀ`,
/// `A = polar(Qᵀ)` (SVD `U Vᵀ`, a reflection when `det Q < 0`). Returns `C_rb = Aᵀ` after the
/// determinant correction, and whether the printed polar factor was a reflection.
fn pinv_paper(
    b: &[Vector3<f64>; 2],
    sky: &[Vector3<f64>],
    ranges: &[[f64; 2]],
) -> Option<(Matrix3<f64>, bool)> {
    let g = b
        .iter()
        .fold(Matrix3::zeros(), |g, bi| g + bi * bi.transpose());
    let g_pinv = g.pseudo_inverse(1e-9).ok()?;
    let mut q = Matrix3::zeros();
    for (s, r) in sky.iter().zip(ranges) {
        let k = g_pinv * (b[0] * r[0] + b[1] * r[1]);
        q += s * k.transpose();
    }
    let svd = q.transpose().svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let polar = u * v_t;
    // (16) as printed is the polar factor; report it when it is a reflection, and use the
    // determinant-corrected rotation U diag(1, 1, det) Vᵀ for the error statistics.
    let d = polar.determinant().signum();
    let a = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * v_t;
    Some((a.transpose(), d < 0.0))
}

crate::metrics! {
    /// Metrics of `snapshot --variant paper` (each triple `[heading, roll, pitch]`).
    pub struct Metrics {
        /// Mean error of the core's solver.
        #[metric(unit = "deg")] pub mean_err_deg: [f64; 3],
        /// Standard deviation of its error.
        #[metric(unit = "deg")] pub std_err_deg: [f64; 3],
        /// Cramér–Rao bound for the same geometry and noise.
        #[metric(unit = "deg")] pub crb_deg: [f64; 3],
        /// Solutions that were reflections (`det C < 0`).
        #[metric(unit = "epochs")] pub reflections: usize,
        /// Monte Carlo epochs.
        #[metric(unit = "")] pub epochs: usize,
        /// Epochs the solver refused.
        #[metric(unit = "epochs")] pub failures: usize,
        /// Standard deviation over the CRB.
        #[metric(unit = "")] pub std_over_crb: [f64; 3],
        /// Mean of the solver's own predicted σ.
        #[metric(unit = "deg")] pub predicted_std_deg: [f64; 3],
        /// The paper's mean error over ours (how much better the core is).
        #[metric(unit = "")] pub paper_over_mean_err: [f64; 3],
        /// Mean χ² of the solutions (3 degrees of freedom).
        #[metric(unit = "")] pub chi_square_mean: f64,
        /// The printed algorithm with a pseudo-inverse (determinant-corrected): mean error.
        #[metric(unit = "deg")] pub pinv_mean_err_deg: [f64; 3],
        /// The printed algorithm (pseudo-inverse): error standard deviation.
        #[metric(unit = "deg")] pub pinv_std_err_deg: [f64; 3],
        /// Epochs in which its polar factor (16) was a reflection.
        #[metric(unit = "epochs")] pub pinv_reflections: usize,
    }
}

/// Epochs shown in the plot.
const PLOTTED_EPOCHS: usize = 500;
/// Floor of |mean error| in the paper/ours ratio, deg (no division by zero).
const MEAN_ERR_FLOOR_DEG: f64 = 1e-12;

/// The case: the solver, the truth, the sky and the CRB.
struct Case {
    b: [Vector3<f64>; 2],
    solver: SnapshotSolver<2, f32>,
    truth: Euler321<f64>,
    c_rb: Matrix3<f64>,
    sky: [Vector3<f64>; 3],
    crb_deg: [f64; 3],
}

impl Case {
    fn paper() -> anyhow::Result<Self> {
        let b = triangle();
        let solver = SnapshotSolver::<2, f32>::new(
            Baselines::new(b.map(|v| v.cast::<f32>())).map_err(|e| anyhow::anyhow!("{e}"))?,
            BaselineCorrelation::independent(),
        );
        let truth = Euler321::new(std::f64::consts::PI, 0.0, 0.0);
        let c_rb = truth.to_dcm();
        let sky = paper_sky();
        let crb = crb_body(&b, &c_rb, &sky, SIGMA, &SMatrix::identity())
            .ok_or_else(|| anyhow::anyhow!("CRB: singular Fisher information"))?;
        Ok(Self {
            crb_deg: euler_sigma_deg(&crb, &truth),
            b,
            solver,
            truth,
            c_rb,
            sky,
        })
    }

    /// Epoch `k`: the core's solver and the printed algorithm on the same ranges.
    fn epoch(&self, seed: u64, k: usize) -> anyhow::Result<EpochResult> {
        let identity = SMatrix::<f64, 2, 2>::identity();
        let mut rng = epoch_rng(seed, 2, k);
        let obs = noisy_ranges(&self.b, &self.c_rb, &self.sky, SIGMA, &identity, &mut rng)?;
        let ranges: Vec<[f64; 2]> = obs
            .satellites()
            .iter()
            .map(|s| s.range_diff.map(f64::from))
            .collect();
        let (pinv_err, pinv_reflection) = match pinv_paper(&self.b, &self.sky, &ranges) {
            Some((c, reflected)) => (euler_errors_deg(&c, &self.truth), reflected),
            None => ([f64::NAN; 3], false),
        };
        Ok(match self.solver.solve(&obs) {
            Ok(sol) => {
                let c = sol.c_rb.cast::<f64>();
                EpochResult {
                    err: euler_errors_deg(&c, &self.truth),
                    sigma: euler_sigma_deg(&sol.covariance.cast::<f64>(), &self.truth),
                    reflection: c.determinant() < 0.0,
                    failed: false,
                    pinv_err,
                    pinv_reflection,
                    chi_square: f64::from(sol.chi_square),
                }
            }
            Err(_) => EpochResult {
                err: [f64::NAN; 3],
                sigma: [f64::NAN; 3],
                reflection: false,
                failed: true,
                pinv_err,
                pinv_reflection,
                chi_square: f64::NAN,
            },
        })
    }
}

/// Runs the variant.
pub fn run(ctx: &RunContext) -> anyhow::Result<Outcome> {
    let case = Case::paper()?;
    let bar = progress(EPOCHS as u64, "snapshot paper");
    let results: Vec<EpochResult> = (0..EPOCHS)
        .into_par_iter()
        .map(|k| {
            let r = case.epoch(ctx.seed, k);
            bar.inc(1);
            r
        })
        .collect::<anyhow::Result<_>>()?;
    bar.finish_and_clear();
    let errs: Vec<[f64; 3]> = results
        .iter()
        .filter(|r| !r.failed)
        .map(|r| r.err)
        .collect();
    let m = metrics(&results, case.crb_deg);
    let mut outcome = Outcome::new(&m)?;
    outcome.paper = json!({
        "mean_err_deg": PAPER_MEAN_ERR_DEG,
        "test1_err_deg": [0.708, 0.877, 0.552],
        "test2_err_deg": [1.608, 1.570, 0.467],
        "spec_crb_deg": [0.19, 0.24, 0.19],
        "note": "[heading, roll, pitch]; the printed means do not follow from the two tests (spec erratum 5)"
    });
    outcome.summary = summary(&m);
    if let Some(dir) = &ctx.out_dir {
        outcome.files = write_files(dir, &errs, case.crb_deg)?;
    }
    Ok(outcome)
}

fn metrics(results: &[EpochResult], crb_deg: [f64; 3]) -> Metrics {
    let ok: Vec<&EpochResult> = results.iter().filter(|r| !r.failed).collect();
    let errs: Vec<[f64; 3]> = ok.iter().map(|r| r.err).collect();
    let sigmas: Vec<[f64; 3]> = ok.iter().map(|r| r.sigma).collect();
    let pinv: Vec<[f64; 3]> = results
        .iter()
        .map(|r| r.pinv_err)
        .filter(|e| e[0].is_finite())
        .collect();
    let mean = |v: &[[f64; 3]]| [0, 1, 2].map(|a| stats::mean(&column(v, a)));
    let std = |v: &[[f64; 3]]| [0, 1, 2].map(|a| stats::std_dev(&column(v, a)));
    let mean_err = mean(&errs);
    let std_err = std(&errs);
    let chi2: Vec<f64> = ok.iter().map(|r| r.chi_square).collect();
    Metrics {
        mean_err_deg: mean_err,
        std_err_deg: std_err,
        crb_deg,
        reflections: results.iter().filter(|r| r.reflection).count(),
        epochs: EPOCHS,
        failures: results.len() - ok.len(),
        std_over_crb: [0, 1, 2].map(|a| std_err[a] / crb_deg[a]),
        predicted_std_deg: mean(&sigmas),
        paper_over_mean_err: [0, 1, 2]
            .map(|a| PAPER_MEAN_ERR_DEG[a] / mean_err[a].abs().max(MEAN_ERR_FLOOR_DEG)),
        chi_square_mean: stats::mean(&chi2),
        pinv_mean_err_deg: mean(&pinv),
        pinv_std_err_deg: std(&pinv),
        pinv_reflections: results.iter().filter(|r| r.pinv_reflection).count(),
    }
}

fn summary(m: &Metrics) -> Vec<String> {
    let f = |v: [f64; 3]| format!("{:.4} / {:.4} / {:.4}", v[0], v[1], v[2]);
    vec![
        format!("{EPOCHS} epochs, 1 m triangle, 3 satellites (el 60/45/30), heading 180°, {} mm per single difference; [heading / roll / pitch] in degrees", SIGMA * 1e3),
        format!("mean error   {}   (paper: {})", f(m.mean_err_deg), f(PAPER_MEAN_ERR_DEG)),
        format!("std error    {}   CRB {}   ratio {}", f(m.std_err_deg), f(m.crb_deg), f(m.std_over_crb)),
        format!("predicted σ  {}   mean χ² {:.2} (3 dof)", f(m.predicted_std_deg), m.chi_square_mean),
        format!("reflections {}, failures {}; paper / |our mean| ≥ {:.0}x", m.reflections, m.failures, m.paper_over_mean_err.iter().fold(f64::INFINITY, |a, &b| a.min(b))),
        format!("printed algorithm with a pseudo-inverse (det-corrected): mean error {}; its polar factor (16) is a reflection in {} epochs", f(m.pinv_mean_err_deg), m.pinv_reflections),
    ]
}

/// The errors as CSV, and the first epochs against ±3 CRB and the paper's mean error.
fn write_files(
    dir: &std::path::Path,
    errs: &[[f64; 3]],
    crb_deg: [f64; 3],
) -> anyhow::Result<Vec<std::path::PathBuf>> {
    let csv = dir.join("snapshot_paper_errors.csv");
    write_csv(
        &csv,
        &["epoch", "heading_err_deg", "roll_err_deg", "pitch_err_deg"],
        errs.iter()
            .enumerate()
            .map(|(k, e)| [k as f64, e[0], e[1], e[2]]),
    )?;
    let shown = errs.len().min(PLOTTED_EPOCHS);
    let level = |y: f64| vec![(0.0, y), (shown as f64, y)];
    let panels: Vec<Panel> = ["heading", "roll", "pitch"]
        .iter()
        .enumerate()
        .map(|(a, name)| Panel {
            y_label: format!("{name} error (deg)"),
            series: vec![
                Series::line(
                    format!("{name} error"),
                    errs[..shown]
                        .iter()
                        .enumerate()
                        .map(|(k, e)| (k as f64, e[a]))
                        .collect(),
                    0,
                ),
                Series::bound("+3 CRB", level(3.0 * crb_deg[a]), 1),
                Series::bound("-3 CRB", level(-3.0 * crb_deg[a]), 1),
                Series::bound("paper mean error", level(PAPER_MEAN_ERR_DEG[a]), 2),
            ],
        })
        .collect();
    let png = dir.join("snapshot_paper_errors.png");
    plot_panels(
        &png,
        "snapshot paper: single-epoch errors, ±3 CRB, paper's mean error",
        "epoch",
        &panels,
    )?;
    Ok(vec![csv, png])
}
