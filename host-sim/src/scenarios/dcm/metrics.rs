//! Pooled error statistics of the `dcm` scenario's filters.

use nalgebra::Matrix3;
use serde_json::{json, Map, Value};

use super::bounds::{self, Noise};
use super::runs::Track;

fn sqrt3(v: [f64; 3]) -> [f64; 3] {
    v.map(f64::sqrt)
}

/// Pooled statistics of one filter against its bound covariance.
pub fn filter_metrics(tracks: &[&Track], bound: &Matrix3<f64>) -> Map<String, Value> {
    let n: usize = tracks.iter().map(|t| t.count).sum::<usize>().max(1);
    let per_axis = |f: &dyn Fn(&Track, usize) -> f64| {
        [0, 1, 2].map(|i| tracks.iter().map(|t| f(t, i)).sum::<f64>())
    };
    let rms = sqrt3(per_axis(&|t, i| t.sum_sq[i]).map(|s| s / n as f64));
    let max = [0, 1, 2].map(|i| tracks.iter().fold(0.0f64, |m, t| m.max(t.max_abs[i])));
    let fin = [0, 1, 2].map(|i| {
        tracks
            .iter()
            .fold(0.0f64, |m, t| m.max(t.final_err[i].abs()))
    });
    let fin_euler = [0, 1, 2].map(|i| {
        tracks
            .iter()
            .fold(0.0f64, |m, t| m.max(t.final_euler_err[i].abs()))
    });
    let rotvec = (tracks.iter().map(|t| t.sum_sq_rotvec).sum::<f64>() / n as f64).sqrt();
    let sigma = sqrt3(per_axis(&|t, i| t.sum_var[i]).map(|s| s / n as f64));
    let b = bounds::axis_sigma(bound);
    let total: usize = tracks.iter().map(|t| t.count).sum();
    let mut m = Map::new();
    m.insert("rms_err_rad".into(), json!(rms));
    m.insert("max_err_rad".into(), json!(max));
    m.insert("final_err_rad".into(), json!(fin));
    m.insert("rotvec_rms_rad".into(), json!(rotvec));
    m.insert("bound_rad".into(), json!(b));
    m.insert("bound_rotvec_rad".into(), json!(bound.trace().sqrt()));
    m.insert(
        "rms_over_bound".into(),
        json!([0, 1, 2].map(|i| rms[i] / b[i])),
    );
    m.insert("filter_sigma_rad".into(), json!(sigma));
    m.insert("final_euler_err_rad".into(), json!(fin_euler));
    m.insert(
        "nis_mean".into(),
        json!(tracks.iter().map(|t| t.sum_nis).sum::<f64>() / n as f64),
    );
    m.insert(
        "nis_dof".into(),
        json!(tracks.first().map_or(0, |t| t.nis_dof)),
    );
    m.insert(
        "not_nominal_fraction".into(),
        json!(
            tracks.iter().map(|t| t.not_nominal).sum::<usize>() as f64 / (2 * total.max(1)) as f64
        ),
    );
    m.insert(
        "step_failures".into(),
        json!(tracks.iter().map(|t| t.failures).sum::<usize>()),
    );
    m
}

/// Relative standard deviation of a pooled RMS figure: the errors are correlated over the
/// filters' memory `τ = σ_p/σ_v`, so the second halves of the runs hold about
/// `N = runs · (T/2) / (2τ)` independent samples, and `σ(RMS)/RMS ≈ 1/√(2N)`.
pub fn rms_uncertainty(noise: Noise, runs: usize, duration: f64) -> f64 {
    let tau = noise.sigma_baseline / noise.sigma_velocity;
    let n = runs as f64 * (duration / 2.0) / (2.0 * tau);
    1.0 / (2.0 * n).sqrt()
}

pub fn get(m: &Map<String, Value>, key: &str) -> f64 {
    m.get(key).and_then(Value::as_f64).unwrap_or(f64::NAN)
}

pub fn max_ratio(m: &Map<String, Value>) -> f64 {
    m.get("rms_over_bound")
        .and_then(Value::as_array)
        .map_or(f64::NAN, |a| {
            a.iter().filter_map(Value::as_f64).fold(0.0, f64::max)
        })
}
