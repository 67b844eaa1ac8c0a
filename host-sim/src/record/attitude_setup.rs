//! The attitude inputs of `track`: the body baselines (`--baselines`), the sky file
//! (`--sky`: the lines of sight) and the line biases (`--line-bias`), parsed with clear errors.

use anyhow::{bail, ensure, Result};

/// What the command line gives for the attitude.
#[derive(Clone, Debug)]
pub struct AttitudeSetup {
    /// Baselines of antennas 1 and 2 from antenna 0, body frame, m.
    pub baselines_body_m: [[f64; 3]; 2],
    /// Line biases of antennas 1 and 2 relative to antenna 0, cycles (`None`: unknown, the
    /// resolver estimates them with the integers from double differences).
    pub line_bias_cycles: Option<[f64; 2]>,
    /// Sky: (PRN, azimuth from north towards east, elevation), degrees; empty: the lines of
    /// sight come from `track`'s navigation fixes (time-varying).
    pub sky: Vec<(u8, f64, f64)>,
    /// Window, s.
    pub window_s: f64,
}

/// Parses `x,y,z;x,y,z` (two baselines, m).
///
/// # Errors
/// Anything but two triples of finite numbers.
pub fn parse_baselines(text: &str) -> Result<[[f64; 3]; 2]> {
    let rows: Vec<&str> = text.split(';').map(str::trim).collect();
    ensure!(
        rows.len() == 2,
        "--baselines needs two baselines 'x1,y1,z1;x2,y2,z2' (antennas 1 and 2 from antenna 0, body frame, m), got {text:?}"
    );
    let mut out = [[0.0; 3]; 2];
    for (o, r) in out.iter_mut().zip(&rows) {
        let v: Vec<f64> = r
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|e| anyhow::anyhow!("--baselines {text:?}: {e}"))?;
        ensure!(
            v.len() == 3 && v.iter().all(|x| x.is_finite()),
            "--baselines {text:?}: each baseline is three finite numbers"
        );
        o.copy_from_slice(&v);
    }
    Ok(out)
}

/// Parses a sky file: lines `prn,azimuth_deg,elevation_deg` (a header line and `#` comments
/// are skipped).
///
/// # Errors
/// A malformed line, a PRN outside 1–32, an elevation outside ±90°.
pub fn parse_sky(text: &str) -> Result<Vec<(u8, f64, f64)>> {
    let mut sky = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') || line.starts_with("prn") {
            continue;
        }
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let parsed = (f.len() == 3)
            .then(|| {
                Some((
                    f[0].parse::<u8>().ok()?,
                    f[1].parse::<f64>().ok()?,
                    f[2].parse::<f64>().ok()?,
                ))
            })
            .flatten();
        let Some((prn, az, el)) = parsed else {
            bail!(
                "sky line {}: expected 'prn,azimuth_deg,elevation_deg', got {line:?}",
                n + 1
            );
        };
        ensure!(
            (1..=32).contains(&prn) && az.is_finite() && (-90.0..=90.0).contains(&el),
            "sky line {}: PRN 1-32, finite azimuth, elevation within ±90°: {line:?}",
            n + 1
        );
        sky.push((prn, az, el));
    }
    ensure!(!sky.is_empty(), "the sky file lists no satellite");
    Ok(sky)
}
