//! Output of `track`: the human table, CSV files and PNG plots.

use std::path::Path;

use anyhow::Result;

use super::track::TrackRun;
use crate::report::{plot_panels, write_csv, Panel, Series};

/// Prints the human summary of a tracking run on stdout.
pub fn print_track(run: &TrackRun) {
    let r = &run.report;
    let a = &r.acquisition;
    println!(
        "track: {} ({}, {:.4} Msps, IF {:.1} kHz, {} antenna(s)), {:.3} s tracked; wall time: read {:.2} s, tracking {:.2} s, re-acquisition {:.2} s",
        a.files.join(" + "),
        a.format,
        a.sample_rate_hz / 1e6,
        a.intermediate_frequency_hz / 1e3,
        a.antennas,
        r.tracked_s,
        r.wall.read_s,
        r.wall.tracking_s,
        r.wall.reacquisition_s
    );
    println!("  PRN  acq Doppler (Hz)  first lock (s)  locked (s)  held to end  losses  reacq  C/N0 measured / thermal (dB-Hz)  Doppler rate (Hz/s)");
    for s in &r.satellites {
        println!(
            "  {:3}  {:16.1}  {:>14}  {:10.2}  {:>11}  {:6}  {:5}  {:>31}  {:19.2}",
            s.prn,
            s.acquired_doppler_hz,
            s.first_lock_s
                .map_or_else(|| "never".to_string(), |t| format!("{t:.2}")),
            s.lock_time_s,
            if s.held_to_end { "yes" } else { "no" },
            s.losses,
            s.reacquisitions,
            format!("{:.2} / {:.2}", s.cn0_dbhz_mean, s.cn0_dbhz_thermal),
            s.doppler_rate_hz_s
        );
    }
    if let Some(att) = &r.attitude {
        println!(
            "  attitude: {} of {} windows of {} s fixed",
            att.fixed, att.windows, att.window_s
        );
        if let (Some(m), Some(s), Some(f)) =
            (att.ypr_mean_deg, att.ypr_std_deg, att.ypr_sigma_mean_deg)
        {
            println!(
                "  yaw / pitch / roll mean {:.3} / {:.3} / {:.3} deg, spread {:.4} / {:.4} / {:.4} deg, formal sigma {:.4} / {:.4} / {:.4} deg",
                m[0], m[1], m[2], s[0], s[1], s[2], f[0], f[1], f[2]
            );
        }
        for w in att
            .per_window
            .iter()
            .filter(|w| w.refused.is_some())
            .take(5)
        {
            println!(
                "  window {:.1}-{:.1} s refused: {}",
                w.t_start_s,
                w.t_end_s,
                w.refused.as_deref().unwrap_or("")
            );
        }
    }
}

/// Writes `track_rows.csv` (100 ms rows), `track_satellites.csv`, `track.png` and, with an
/// attitude, `track_attitude.csv` and `track_attitude.png` into `dir`; returns the paths.
///
/// # Errors
/// I/O and plotting errors.
pub fn write_track_files(dir: &Path, run: &TrackRun) -> Result<Vec<String>> {
    std::fs::create_dir_all(dir)?;
    let mut files = Vec::new();
    let rows = dir.join("track_rows.csv");
    write_csv(
        &rows,
        &["t_s", "prn", "doppler_hz", "cn0_dbhz", "locked_fraction"],
        run.tracks.iter().flat_map(|t| {
            let prn = f64::from(t.prn());
            t.rows()
                .iter()
                .map(move |r| [r.t_s, prn, r.doppler_hz, r.cn0_dbhz, r.locked])
        }),
    )?;
    files.push(rows);
    let sats = dir.join("track_satellites.csv");
    write_csv(
        &sats,
        &[
            "prn",
            "acquired_doppler_hz",
            "acquired_code_phase_chips",
            "first_lock_s",
            "lock_time_s",
            "longest_lock_s",
            "held_to_end",
            "losses",
            "reacquisitions",
            "cn0_dbhz_mean",
            "cn0_dbhz_thermal",
            "doppler_rate_hz_s",
        ],
        run.report.satellites.iter().map(|s| {
            [
                f64::from(s.prn),
                s.acquired_doppler_hz,
                s.acquired_code_phase_chips,
                s.first_lock_s.unwrap_or(f64::NAN),
                s.lock_time_s,
                s.longest_lock_s,
                f64::from(u8::from(s.held_to_end)),
                f64::from(s.losses),
                f64::from(s.reacquisitions),
                s.cn0_dbhz_mean,
                s.cn0_dbhz_thermal,
                s.doppler_rate_hz_s,
            ]
        }),
    )?;
    files.push(sats);
    let series = |f: &dyn Fn(&super::satellite::Row) -> f64| -> Vec<Series> {
        run.tracks
            .iter()
            .enumerate()
            .map(|(c, t)| {
                Series::line(
                    format!("PRN {}", t.prn()),
                    t.rows()
                        .iter()
                        .map(|r| (r.t_s, f(r)))
                        .filter(|p| p.1.is_finite())
                        .collect(),
                    c,
                )
            })
            .collect()
    };
    let png = dir.join("track.png");
    plot_panels(
        &png,
        &format!(
            "track: {} ({}), {} satellites",
            run.report.acquisition.files.join(" + "),
            run.report.acquisition.format,
            run.tracks.len()
        ),
        "time (s)",
        &[
            Panel {
                y_label: "C/N0 (dB-Hz)".into(),
                series: series(&|r| r.cn0_dbhz),
            },
            Panel {
                y_label: "Doppler (kHz)".into(),
                series: series(&|r| r.doppler_hz / 1e3),
            },
            Panel {
                y_label: "locked fraction per 100 ms".into(),
                series: series(&|r| r.locked),
            },
        ],
    )?;
    files.push(png);
    if let Some(att) = &run.report.attitude {
        let csv = dir.join("track_attitude.csv");
        write_csv(
            &csv,
            &[
                "t_end_s",
                "satellites",
                "fixed",
                "ratio",
                "yaw_deg",
                "pitch_deg",
                "roll_deg",
                "yaw_sigma_deg",
                "pitch_sigma_deg",
                "roll_sigma_deg",
            ],
            att.per_window.iter().map(|w| {
                let y = w.ypr_deg.unwrap_or([f64::NAN; 3]);
                let s = w.ypr_sigma_deg.unwrap_or([f64::NAN; 3]);
                [
                    w.t_end_s,
                    w.satellites.len() as f64,
                    f64::from(u8::from(w.ypr_deg.is_some())),
                    w.ratio.unwrap_or(f64::NAN),
                    y[0],
                    y[1],
                    y[2],
                    s[0],
                    s[1],
                    s[2],
                ]
            }),
        )?;
        files.push(csv);
        let png = dir.join("track_attitude.png");
        let angle = |j: usize, name: &str| Panel {
            y_label: format!("{name} (deg)"),
            series: vec![Series::line(
                name,
                att.per_window
                    .iter()
                    .filter_map(|w| w.ypr_deg.map(|y| (w.t_end_s, y[j])))
                    .collect(),
                j,
            )],
        };
        plot_panels(
            &png,
            &format!(
                "attitude per {} s window ({} of {} fixed)",
                att.window_s, att.fixed, att.windows
            ),
            "time (s)",
            &[angle(0, "yaw"), angle(1, "pitch"), angle(2, "roll")],
        )?;
        files.push(png);
    }
    if let Some(nav) = &run.navigator {
        let csv = dir.join("track_position.csv");
        write_csv(
            &csv,
            &[
                "t_s",
                "gps_week",
                "tow_s",
                "x_m",
                "y_m",
                "z_m",
                "lat_deg",
                "lon_deg",
                "height_m",
                "clock_bias_m",
                "pdop",
                "satellites",
                "residual_rms_m",
            ],
            nav.fixes().iter().map(|f| {
                let [x, y, z] = f.position_ecef_m;
                let [lat, lon, h] = f.position_llh;
                [
                    f.t_s,
                    f64::from(f.gps_week),
                    f.tow_s,
                    x,
                    y,
                    z,
                    lat,
                    lon,
                    h,
                    f.clock_bias_m,
                    f.pdop,
                    f64::from(f.satellites),
                    f.residual_rms_m,
                ]
            }),
        )?;
        files.push(csv);
        let rnx = dir.join("track_nav.rnx");
        let (ephemerides, iono) = nav.decoded();
        std::fs::write(
            &rnx,
            super::rinex::write_rinex3(&ephemerides, iono.as_ref()),
        )?;
        files.push(rnx);
    }
    Ok(files.iter().map(|p| p.display().to_string()).collect())
}
