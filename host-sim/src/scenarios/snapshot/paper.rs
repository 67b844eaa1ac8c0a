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

/// Runs the variant.
pub fn run(ctx: &RunContext) -> anyhow::Result<Outcome> {
    let b = triangle();
    let solver = SnapshotSolver::<2, f32>::new(
        Baselines::new(b.map(|v| v.cast::<f32>())).map_err(|e| anyhow::anyhow!("{e}"))?,
        BaselineCorrelation::independent(),
    );
    let truth = Euler321::new(std::f64::consts::PI, 0.0, 0.0);
    let c_rb = truth.to_dcm();
    let sky = paper_sky();
    let identity = SMatrix::<f64, 2, 2>::identity();
    let crb = crb_body(&b, &c_rb, &sky, SIGMA, &identity)
        .ok_or_else(|| anyhow::anyhow!("CRB: singular Fisher information"))?;
    let crb_deg = euler_sigma_deg(&crb, &truth);

    let bar = progress(EPOCHS as u64, "snapshot paper");
    let results: Vec<EpochResult> = (0..EPOCHS)
        .into_par_iter()
        .map(|k| {
            let mut rng = epoch_rng(ctx.seed, 2, k);
            let obs = noisy_ranges(&b, &c_rb, &sky, SIGMA, &identity, &mut rng)?;
            let ranges: Vec<[f64; 2]> = obs
                .satellites()
                .iter()
                .map(|s| s.range_diff.map(f64::from))
                .collect();
            let pinv = pinv_paper(&b, &sky, &ranges);
            let (pinv_err, pinv_reflection) = match pinv {
                Some((c, reflected)) => (euler_errors_deg(&c, &truth), reflected),
                None => ([f64::NAN; 3], false),
            };
            bar.inc(1);
            Ok(match solver.solve(&obs) {
                Ok(sol) => {
                    let c = sol.c_rb.cast::<f64>();
                    let sigma = euler_sigma_deg(&sol.covariance.cast::<f64>(), &truth);
                    EpochResult {
                        err: euler_errors_deg(&c, &truth),
                        sigma,
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
        })
        .collect::<anyhow::Result<_>>()?;
    bar.finish_and_clear();

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
    let predicted = mean(&sigmas);
    let reflections = results.iter().filter(|r| r.reflection).count();
    let failures = results.len() - ok.len();
    let std_over_crb = [0, 1, 2].map(|a| std_err[a] / crb_deg[a]);
    let beats = [0, 1, 2].map(|a| PAPER_MEAN_ERR_DEG[a] / mean_err[a].abs().max(1e-12));
    let pinv_mean = mean(&pinv);
    let pinv_reflections = results.iter().filter(|r| r.pinv_reflection).count();
    let chi2: Vec<f64> = ok.iter().map(|r| r.chi_square).collect();

    let mut outcome = Outcome::default();
    outcome
        .metric("mean_err_deg", json!(mean_err))
        .metric("std_err_deg", json!(std_err))
        .metric("crb_deg", json!(crb_deg))
        .metric("reflections", reflections)
        .metric("epochs", EPOCHS)
        .metric("failures", failures)
        .metric("std_over_crb", json!(std_over_crb))
        .metric("predicted_std_deg", json!(predicted))
        .metric("paper_over_mean_err", json!(beats))
        .metric("chi_square_mean", stats::mean(&chi2))
        .metric("pinv_mean_err_deg", json!(pinv_mean))
        .metric("pinv_std_err_deg", json!(std(&pinv)))
        .metric("pinv_reflections", pinv_reflections);
    outcome.paper = json!({
        "mean_err_deg": PAPER_MEAN_ERR_DEG,
        "test1_err_deg": [0.708, 0.877, 0.552],
        "test2_err_deg": [1.608, 1.570, 0.467],
        "spec_crb_deg": [0.19, 0.24, 0.19],
        "note": "[heading, roll, pitch]; the printed means do not follow from the two tests (spec erratum 5)"
    });
    let f = |v: [f64; 3]| format!("{:.4} / {:.4} / {:.4}", v[0], v[1], v[2]);
    outcome.summary = vec![
        format!("{EPOCHS} epochs, 1 m triangle, 3 satellites (el 60/45/30), heading 180°, {} mm per single difference; [heading / roll / pitch] in degrees", SIGMA * 1e3),
        format!("mean error   {}   (paper: {})", f(mean_err), f(PAPER_MEAN_ERR_DEG)),
        format!("std error    {}   CRB {}   ratio {}", f(std_err), f(crb_deg), f(std_over_crb)),
        format!("predicted σ  {}   mean χ² {:.2} (3 dof)", f(predicted), stats::mean(&chi2)),
        format!("reflections {reflections}, failures {failures}; paper / |our mean| ≥ {:.0}x", beats.iter().fold(f64::INFINITY, |a, &b| a.min(b))),
        format!("printed algorithm with a pseudo-inverse (det-corrected): mean error {}; its polar factor (16) is a reflection in {} epochs", f(pinv_mean), pinv_reflections),
    ];

    if let Some(dir) = &ctx.out_dir {
        let csv = dir.join("snapshot_paper_errors.csv");
        write_csv(
            &csv,
            &["epoch", "heading_err_deg", "roll_err_deg", "pitch_err_deg"],
            errs.iter()
                .enumerate()
                .map(|(k, e)| [k as f64, e[0], e[1], e[2]]),
        )?;
        let shown = errs.len().min(500);
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
                    Series::bound(
                        "+3 CRB",
                        vec![(0.0, 3.0 * crb_deg[a]), (shown as f64, 3.0 * crb_deg[a])],
                        1,
                    ),
                    Series::bound(
                        "-3 CRB",
                        vec![(0.0, -3.0 * crb_deg[a]), (shown as f64, -3.0 * crb_deg[a])],
                        1,
                    ),
                    Series::bound(
                        "paper mean error",
                        vec![
                            (0.0, PAPER_MEAN_ERR_DEG[a]),
                            (shown as f64, PAPER_MEAN_ERR_DEG[a]),
                        ],
                        2,
                    ),
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
        outcome.files = vec![csv, png];
    }
    Ok(outcome)
}
