//! The files of a run: CSV time series, PNG plots (attitude error with 3σ bounds, satellites
//! and C/N0, a sky plot) and a Markdown report that links them.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, Result};
use gnss_attitude::receiver::AttitudeSource;
use plotters::prelude::*;

use super::metrics::{deg, FlightMetrics};
use super::run::FlightRecord;
use crate::report::{plot_panels, write_csv, Dash, Panel, Series};

fn source_code(s: AttitudeSource) -> f64 {
    match s {
        AttitudeSource::None => 0.0,
        AttitudeSource::Snapshot => 1.0,
        AttitudeSource::Fine => 2.0,
        AttitudeSource::GyroCoast => 3.0,
    }
}

/// Writes every file into `dir`; returns their paths.
pub fn write_all(
    dir: &Path,
    record: &FlightRecord,
    metrics: &FlightMetrics,
    title: &str,
    summary: &[String],
) -> Result<Vec<PathBuf>> {
    let mut files = vec![write_attitude_csv(dir, record)?];
    files.extend(write_stage_csvs(dir, record)?);
    files.push(write_sky_csv(dir, record)?);
    // CSV: events
    let path = dir.join("microsat_events.csv");
    let mut text = String::from("t_s,event\n");
    for (t, e) in &record.events {
        let _ = writeln!(text, "{t:.4},\"{e:?}\"");
    }
    std::fs::write(&path, text)?;
    files.push(path);
    // PNG: attitude error with 3σ
    let path = dir.join("microsat_attitude_error.png");
    plot_error(&path, record, metrics, title)?;
    files.push(path);
    // PNG: satellites and C/N0
    let path = dir.join("microsat_satellites.png");
    plot_satellites(&path, record, title)?;
    files.push(path);
    // PNG: sky
    let path = dir.join("microsat_sky.png");
    plot_sky(&path, record, title)?;
    files.push(path);
    // Markdown report
    let path = dir.join("microsat_report.md");
    std::fs::write(&path, markdown(record, metrics, title, summary))?;
    files.push(path);
    Ok(files)
}

/// The receiver every 0.1 s.
fn write_attitude_csv(dir: &Path, record: &FlightRecord) -> Result<PathBuf> {
    let path = dir.join("microsat_attitude.csv");
    let header = [
        "t_s",
        "source",
        "err_x_deg",
        "err_y_deg",
        "err_z_deg",
        "sigma_x_deg",
        "sigma_y_deg",
        "sigma_z_deg",
        "fine_err_x_deg",
        "fine_err_y_deg",
        "fine_err_z_deg",
        "loop_noise_x_deg",
        "loop_noise_y_deg",
        "loop_noise_z_deg",
        "limit_x_deg",
        "limit_y_deg",
        "limit_z_deg",
        "line_bias_err_b_deg",
        "line_bias_err_c_deg",
        "tracked",
        "used",
        "fixed",
        "visible",
        "blocked_b",
        "bias_err_x_deg_h",
        "bias_err_y_deg_h",
        "bias_err_z_deg_h",
    ];
    let to_deg_h = 180.0 / std::f64::consts::PI * 3600.0;
    write_csv(
        &path,
        &header,
        record.samples.iter().map(|s| {
            let e = deg(&s.error);
            let g = deg(&s.sigma);
            let f = deg(&s.fine_error);
            let b = deg(&s.loop_noise);
            let l = deg(&s.limit);
            vec![
                s.t,
                source_code(s.source),
                e[0],
                e[1],
                e[2],
                g[0],
                g[1],
                g[2],
                f[0],
                f[1],
                f[2],
                b[0],
                b[1],
                b[2],
                l[0],
                l[1],
                l[2],
                s.line_bias_error[0].to_degrees(),
                s.line_bias_error[1].to_degrees(),
                s.tracked as f64,
                s.used as f64,
                s.fixed as f64,
                s.visible as f64,
                if s.blocked[1] { 1.0 } else { 0.0 },
                s.bias_error.x * to_deg_h,
                s.bias_error.y * to_deg_h,
                s.bias_error.z * to_deg_h,
            ]
        }),
    )?;
    Ok(path)
}

/// The stages at their own epochs.
fn write_stage_csvs(dir: &Path, record: &FlightRecord) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for (name, samples) in [
        ("snapshot", &record.snapshots),
        ("rigid_body", &record.rigid),
    ] {
        let path = dir.join(format!("microsat_{name}.csv"));
        write_csv(
            &path,
            &[
                "t_s",
                "err_x_deg",
                "err_y_deg",
                "err_z_deg",
                "sigma_x_deg",
                "sigma_y_deg",
                "sigma_z_deg",
            ],
            samples.iter().map(|s| {
                let e = deg(&s.error);
                let g = deg(&s.sigma);
                vec![s.t, e[0], e[1], e[2], g[0], g[1], g[2]]
            }),
        )?;
        files.push(path);
    }
    Ok(files)
}

/// The sky every second.
fn write_sky_csv(dir: &Path, record: &FlightRecord) -> Result<PathBuf> {
    let path = dir.join("microsat_sky.csv");
    write_csv(
        &path,
        &[
            "t_s",
            "prn",
            "azimuth_deg",
            "elevation_deg",
            "cn0_dbhz",
            "tracked",
        ],
        record.sky.iter().map(|p| {
            vec![
                p.t,
                f64::from(p.prn),
                p.azimuth.to_degrees(),
                p.elevation.to_degrees(),
                p.cn0_dbhz,
                if p.tracked { 1.0 } else { 0.0 },
            ]
        }),
    )?;
    Ok(path)
}

fn plot_error(
    path: &Path,
    record: &FlightRecord,
    metrics: &FlightMetrics,
    title: &str,
) -> Result<()> {
    let axes = ["x (roll)", "y (pitch)", "z (yaw)"];
    let mut panels = Vec::new();
    let from = metrics.ttff_s;
    for (a, name) in axes.iter().enumerate() {
        let pts = |f: &dyn Fn(&super::run::Sample) -> f64| -> Vec<(f64, f64)> {
            // no attitude: a gap in the line
            record
                .samples
                .iter()
                .filter(|s| s.t >= from)
                .map(|s| match s.source {
                    AttitudeSource::None => (s.t, f64::NAN),
                    _ => (s.t, f(s)),
                })
                .collect()
        };
        let mut series = vec![
            Series::line("receiver − truth", pts(&|s| s.error[a].to_degrees()), 0),
            Series::bound("±3σ (receiver)", pts(&|s| 3.0 * s.sigma[a].to_degrees()), 1),
            Series::bound("", pts(&|s| -3.0 * s.sigma[a].to_degrees()), 1),
            Series::bound("±3× limit", pts(&|s| 3.0 * s.limit[a].to_degrees()), 2),
            Series::bound("", pts(&|s| -3.0 * s.limit[a].to_degrees()), 2),
        ];
        if record.sample_level_s > 0.0 {
            let lim = series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.1.abs()))
                .fold(0.0, f64::max);
            let t = record.sample_level_s;
            series.push(Series::line(
                format!("end of the sample-level chain ({t:.0} s), then I/Q fast path"),
                vec![(t, -lim), (t, lim)],
                5,
            ));
        }
        panels.push(Panel {
            y_label: format!("error about {name}, deg"),
            series,
        });
    }
    plot_panels(
        path,
        &format!("{title}: attitude error (body axes)"),
        "time, s",
        &panels,
    )
}

/// Colours of the plot palette.
const PALETTE_SIZE: usize = 10;
/// Gap between two sky points of one satellite (1 s apart) that breaks its C/N0 line, s.
const SKY_GAP_S: f64 = 1.5;

/// The four satellite counts as nested stripes, widest and palest at the bottom, so that
/// counts that coincide (they often do) all stay visible: above the mask ⊇ tracked ⊇ in the
/// fine filter ⊇ ambiguities fixed.
fn count_series(record: &FlightRecord) -> Vec<Series> {
    let s = &record.samples;
    let pts = |f: fn(&super::run::Sample) -> usize| -> Vec<(f64, f64)> {
        s.iter().map(|x| (x.t, f(x) as f64)).collect()
    };
    vec![
        Series::steps("above the mask", &pts(|x| x.visible), 7).styled(Dash::Solid, 12),
        Series::steps("tracked", &pts(|x| x.tracked), 0).styled(Dash::Solid, 7),
        Series::steps("in the fine filter", &pts(|x| x.used), 1).styled(Dash::Solid, 3),
        Series::steps("ambiguities fixed", &pts(|x| x.fixed), 3).styled(Dash::Dashed, 2),
    ]
}

/// Each satellite's reported C/N0 while it is tracked; a gap (NaN) where it is not tracked or
/// not in view, so that the line breaks instead of joining across.
fn cn0_series(record: &FlightRecord) -> Vec<Series> {
    let mut prns: Vec<u8> = record.sky.iter().map(|p| p.prn).collect();
    prns.sort_unstable();
    prns.dedup();
    let mut cn0 = Vec::new();
    for (i, prn) in prns.iter().enumerate() {
        let mut pts: Vec<(f64, f64)> = Vec::new();
        let mut last_t = f64::NEG_INFINITY;
        for p in record.sky.iter().filter(|p| p.prn == *prn) {
            if p.t - last_t > SKY_GAP_S {
                pts.push((p.t, f64::NAN));
            }
            last_t = p.t;
            pts.push((p.t, if p.tracked { p.cn0_dbhz } else { f64::NAN }));
        }
        if pts.iter().filter(|p| p.1.is_finite()).count() > 1 {
            // the palette's ten colours, then the same dashed
            let dash = if i < PALETTE_SIZE {
                Dash::Solid
            } else {
                Dash::Dashed
            };
            cn0.push(Series::line(format!("PRN {prn}"), pts, i).styled(dash, 2));
        }
    }
    cn0
}

fn plot_satellites(path: &Path, record: &FlightRecord, title: &str) -> Result<()> {
    plot_panels(
        path,
        &format!("{title}: satellites and C/N0"),
        "time, s",
        &[
            Panel {
                y_label: "satellites".into(),
                series: count_series(record),
            },
            Panel {
                y_label: "C/N0 reported, dB-Hz".into(),
                series: cn0_series(record),
            },
        ],
    )
}

/// A circle of radius `r` about the sky plot's centre, 2° steps.
fn circle(r: f64) -> Vec<(f64, f64)> {
    (0..=180)
        .map(|i| {
            let a = f64::from(i) * std::f64::consts::TAU / 180.0;
            (r * a.sin(), r * a.cos())
        })
        .collect()
}

fn plot_sky(path: &Path, record: &FlightRecord, title: &str) -> Result<()> {
    let err = |e: DrawingAreaErrorKind<_>| anyhow!("plot {}: {e:?}", path.display());
    let root = BitMapBackend::new(path, (900, 900)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let root = root
        .titled(
            &format!("{title}: sky of the antennas (1 s steps)"),
            ("sans-serif", 22),
        )
        .map_err(err)?;
    let mut chart = ChartBuilder::on(&root)
        .margin(20)
        .build_cartesian_2d(-SKY_EXTENT..SKY_EXTENT, -SKY_EXTENT..SKY_EXTENT)
        .map_err(err)?;
    draw_sky_grid(&mut chart).map_err(err)?;
    draw_sky_tracks(&mut chart, record).map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// Half-width of the sky plot's square (the horizon is at radius 1).
const SKY_EXTENT: f64 = 1.15;
/// Elevation mask drawn on the sky plot, degrees.
const SKY_MASK_DEG: f64 = 10.0;

type SkyChart<'a, 'b> = ChartContext<
    'a,
    BitMapBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;
type SkyResult = std::result::Result<
    (),
    DrawingAreaErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>,
>;

/// Rings every 30° of elevation, the 10° mask, spokes every 90° of azimuth with labels.
fn draw_sky_grid(chart: &mut SkyChart<'_, '_>) -> SkyResult {
    for el in [0.0f64, 30.0, 60.0] {
        let r = 1.0 - el / 90.0;
        chart.draw_series(LineSeries::new(circle(r), BLACK.mix(0.3)))?;
        chart.draw_series(std::iter::once(Text::new(
            format!("{el:.0}°"),
            (0.02, r - 0.04),
            ("sans-serif", 14),
        )))?;
    }
    let r_mask = 1.0 - SKY_MASK_DEG / 90.0;
    chart.draw_series(LineSeries::new(circle(r_mask), RED.mix(0.5)))?;
    for (az, label) in [(0.0f64, "+x"), (90.0, "+y"), (180.0, "−x"), (270.0, "−y")] {
        let a = az.to_radians();
        chart.draw_series(LineSeries::new(
            vec![(0.0, 0.0), (a.sin(), a.cos())],
            BLACK.mix(0.15),
        ))?;
        chart.draw_series(std::iter::once(Text::new(
            label.to_string(),
            (1.07 * a.sin() - 0.03, 1.07 * a.cos() + 0.02),
            ("sans-serif", 16),
        )))?;
    }
    Ok(())
}

/// Each satellite's track: bright dots while tracked, faint ones otherwise, its PRN at the
/// end.
fn draw_sky_tracks(chart: &mut SkyChart<'_, '_>, record: &FlightRecord) -> SkyResult {
    let mut prns: Vec<u8> = record.sky.iter().map(|p| p.prn).collect();
    prns.sort_unstable();
    prns.dedup();
    for (i, prn) in prns.iter().enumerate() {
        let color = crate::report::palette(i);
        let pts: Vec<(f64, f64, bool)> = record
            .sky
            .iter()
            .filter(|p| p.prn == *prn)
            .map(|p| {
                let r = 1.0 - p.elevation.to_degrees() / 90.0;
                (r * p.azimuth.sin(), r * p.azimuth.cos(), p.tracked)
            })
            .collect();
        chart.draw_series(pts.iter().map(|&(x, y, tracked)| {
            if tracked {
                Circle::new((x, y), 2, color.filled())
            } else {
                Circle::new((x, y), 1, color.mix(0.4).filled())
            }
        }))?;
        if let Some(&(x, y, _)) = pts.last() {
            chart.draw_series(std::iter::once(Text::new(
                format!("{prn}"),
                (x + 0.01, y + 0.01),
                ("sans-serif", 13),
            )))?;
        }
    }
    Ok(())
}

fn markdown(record: &FlightRecord, m: &FlightMetrics, title: &str, summary: &[String]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# {title}\n");
    let _ = writeln!(
        s,
        "Time to first fix {:.2} s; fine attitude locked at {:.2} s; converged from {:.1} s.\n",
        m.ttff_s, m.fine_lock_s, m.converged_from_s
    );
    let _ = writeln!(s, "| stage | first output, s | RMS error x / y / z, deg | max error x / y / z, deg | availability | satellites |");
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for st in m.stages.iter().chain(std::iter::once(&m.receiver)) {
        let r = deg(&st.rms);
        let x = deg(&st.max);
        let _ = writeln!(
            s,
            "| {} | {:.2} | {:.4} / {:.4} / {:.4} | {:.4} / {:.4} / {:.4} | {:.3} | {:.1} |",
            st.name,
            st.first_s.unwrap_or(f64::NAN),
            r[0],
            r[1],
            r[2],
            x[0],
            x[1],
            x[2],
            st.availability,
            st.satellites
        );
    }
    let (b, l) = (deg(&m.loop_noise), deg(&m.limit));
    let _ = writeln!(
        s,
        "\nPhysical limit (posterior Cramér–Rao bound with the gyro's error model and unknown line biases): {:.4} / {:.4} / {:.4} deg; the 1 Hz loop's noise √(2Δf (J⁻¹)_aa): {:.4} / {:.4} / {:.4} deg.\n",
        l[0], l[1], l[2], b[0], b[1], b[2]
    );
    let _ = writeln!(s, "## Faults\n");
    let _ = writeln!(
        s,
        "| fault | at, s | detected | recovered after, s | what happened |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    for f in &m.faults {
        let _ = writeln!(
            s,
            "| {} | {:.1} | {} | {} | {} |",
            f.name,
            f.at_s,
            f.detected,
            f.recovered_s.map_or("—".into(), |r| format!("{r:.2}")),
            f.detail
        );
    }
    let _ = writeln!(
        s,
        "\nThe receiver's reported σ against its error: {}.",
        super::coverage_line("main flight", &m.coverage)
    );
    if let Some(c) = &m.fault_runs_coverage {
        let _ = writeln!(
            s,
            "Over the separate fault runs (every antenna blocked beyond the coast limit, a faulty gyro; fast path from the start): {}.",
            super::coverage_line("fault runs", c)
        );
    }
    let _ = writeln!(s, "\n## Plots\n");
    let _ = writeln!(s, "* [Attitude error with ±3σ and ±3× bound](microsat_attitude_error.png)\n\n  ![](microsat_attitude_error.png)\n");
    let _ = writeln!(
        s,
        "* [Satellites and C/N0](microsat_satellites.png)\n\n  ![](microsat_satellites.png)\n"
    );
    let _ = writeln!(
        s,
        "* [Sky of the antennas](microsat_sky.png)\n\n  ![](microsat_sky.png)\n"
    );
    let _ = writeln!(s, "## Data\n");
    for f in [
        "microsat_attitude.csv",
        "microsat_snapshot.csv",
        "microsat_rigid_body.csv",
        "microsat_sky.csv",
        "microsat_events.csv",
    ] {
        let _ = writeln!(s, "* [{f}]({f})");
    }
    let _ = writeln!(s, "\n## Summary\n\n```text");
    for l in summary {
        let _ = writeln!(s, "{l}");
    }
    let _ = writeln!(s, "```");
    let _ = writeln!(s, "\n{} receiver events recorded.", record.events.len());
    s
}
