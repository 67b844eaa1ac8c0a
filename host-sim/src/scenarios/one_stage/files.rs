//! The scenario's files: run 0's time series (CSV) and the plot of its errors.

use super::sim::{RunResult, Sample};
use crate::report::{plot_panels, write_csv, Dash, Panel, Series};

/// Line widths of the curve drawn beneath and of the one drawn on top of it, px.
const WIDE_PX: u32 = 3;
const THIN_PX: u32 = 1;

/// Run 0 of each filter form on the headline path, and the I/Q fast path's run 0 of the
/// Gaussian form when the headline is sample-level.
pub struct Run0<'a> {
    /// Where the headline comes from (`samples` or `iq`).
    pub path: &'a str,
    /// The Gaussian-approximation filter.
    pub gauss: &'a RunResult,
    /// The constant-gain filter.
    pub cg: &'a RunResult,
    /// The Gaussian filter on the I/Q fast path beside a sample-level headline.
    pub iq_gauss: Option<&'a RunResult>,
}

/// The CSV of run 0 and the plot of its errors against the bound (arc-minutes).
pub fn write_files(
    dir: &std::path::Path,
    variant: &str,
    run0: &Run0<'_>,
    bound: f64,
) -> anyhow::Result<Vec<std::path::PathBuf>> {
    let stem = format!("one_stage_{}", variant.replace('.', "_"));
    let csv = dir.join(format!("{stem}_run0.csv"));
    write_run0_csv(&csv, run0.gauss, run0.cg)?;
    let png = dir.join(format!("{stem}_error.png"));
    plot_run0(&png, variant, run0, bound)?;
    Ok(vec![csv, png])
}

/// Run 0 of both filter forms, epoch by epoch.
fn write_run0_csv(csv: &std::path::Path, gauss: &RunResult, cg: &RunResult) -> anyhow::Result<()> {
    write_csv(
        csv,
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
    )
}

/// The errors of run 0 against the bound, and the alignment.
fn plot_run0(
    png: &std::path::Path,
    variant: &str,
    run0: &Run0<'_>,
    bound: f64,
) -> anyhow::Result<()> {
    let (path, gauss, cg, iq_gauss) = (run0.path, run0.gauss, run0.cg, run0.iq_gauss);
    let pts = |r: &RunResult, f: fn(&Sample) -> f64| -> Vec<(f64, f64)> {
        r.samples.iter().map(|s| (s.t, f(s))).collect()
    };
    let t_end = gauss.samples.last().map_or(0.0, |s| s.t);
    let mut errors = vec![
        // the two forms nearly coincide: the Gaussian one wide beneath, constant gain thin on top
        Series::line(
            format!("Gaussian approximation ({path})"),
            pts(gauss, |s| s.error_arcmin),
            0,
        )
        .styled(Dash::Solid, WIDE_PX),
        Series::line(
            format!("constant gain ({path})"),
            pts(cg, |s| s.error_arcmin),
            1,
        )
        .styled(Dash::Solid, THIN_PX),
    ];
    if let Some(iq) = iq_gauss {
        errors.push(
            Series::line(
                "Gaussian approximation (I/Q fast path)",
                pts(iq, |s| s.error_arcmin),
                2,
            )
            .styled(Dash::Solid, THIN_PX),
        );
    }
    errors.push(Series::bound(
        "± bound",
        vec![(0.0, bound), (t_end, bound)],
        3,
    ));
    errors.push(Series::bound("", vec![(0.0, -bound), (t_end, -bound)], 3));
    let panels = vec![
        Panel {
            y_label: "β̂ − β (arc-min)".into(),
            series: errors,
        },
        Panel {
            y_label: "alignment η̄".into(),
            series: vec![
                Series::line("Gaussian approximation", pts(gauss, |s| s.alignment), 0)
                    .styled(Dash::Solid, WIDE_PX),
                Series::line("constant gain", pts(cg, |s| s.alignment), 1)
                    .styled(Dash::Solid, THIN_PX),
            ],
        },
    ];
    plot_panels(
        png,
        &format!("one-stage {variant}: tracking error of β ({path}), run 0"),
        "time (s)",
        &panels,
    )
}
