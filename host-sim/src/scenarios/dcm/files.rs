//! CSV and PNG output of the `dcm` scenario (run 0).

use nalgebra::Matrix3;

use super::bounds;
use super::runs::{RunResult, Track};
use crate::report::{plot_panels, write_csv, Panel, Series};

pub fn write_files(
    dir: &std::path::Path,
    variant: &str,
    duration: f64,
    results: &[RunResult],
    bounds_six_rigid: [&Matrix3<f64>; 2],
) -> anyhow::Result<Vec<std::path::PathBuf>> {
    let Some(r0) = results.first() else {
        return Ok(Vec::new());
    };
    let tracks = [&r0.six_state, &r0.multi_structure, &r0.rigid_body];
    let n = tracks.iter().map(|t| t.series.len()).min().unwrap_or(0);
    let csv = dir.join(format!("dcm_{variant}_run0.csv"));
    let mut header = vec!["t_s".to_string()];
    for name in ["six", "multi", "rigid"] {
        for col in ["err_x", "err_y", "err_z", "sigma_x", "sigma_y", "sigma_z"] {
            header.push(format!("{name}_{col}_rad"));
        }
    }
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    write_csv(
        &csv,
        &header,
        (0..n).map(|i| {
            let mut row = vec![tracks[0].series[i].0];
            for t in &tracks {
                let (_, e, s) = t.series[i];
                row.extend_from_slice(&e);
                row.extend_from_slice(&s);
            }
            row
        }),
    )?;
    let [bs, br] = bounds_six_rigid.map(bounds::axis_sigma);
    let panels: Vec<Panel> = ["x", "y", "z"]
        .iter()
        .enumerate()
        .map(|(i, axis)| {
            let line = |t: &Track| t.series.iter().map(|p| (p.0, p.1[i])).collect::<Vec<_>>();
            let flat = |v: f64| vec![(0.0, v), (duration, v)];
            Panel {
                y_label: format!("error about body {axis} (rad)"),
                series: vec![
                    Series::line("six-state", line(tracks[0]), 0),
                    Series::line("multi-structure", line(tracks[1]), 1),
                    Series::line("rigid-body", line(tracks[2]), 2),
                    Series::bound("+1σ six-state bound", flat(bs[i]), 0),
                    Series::bound("-1σ six-state bound", flat(-bs[i]), 0),
                    Series::bound("+1σ rigid-body bound", flat(br[i]), 2),
                    Series::bound("-1σ rigid-body bound", flat(-br[i]), 2),
                ],
            }
        })
        .collect();
    let png = dir.join(format!("dcm_{variant}_error.png"));
    plot_panels(
        &png,
        &format!("dcm / {variant}: attitude error of run 0 (body axes)"),
        "time (s)",
        &panels,
    )?;
    Ok(vec![csv, png])
}
