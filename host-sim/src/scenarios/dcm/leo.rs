//! The `leo` variant's extra figures: how much the Doppler tells about a slow rotation.

use gnss_attitude::attitude::array::BaselinePair;
use gnss_attitude::attitude::direction_cosine::{ColumnChoice, DirectionCosineModel};
use nalgebra::Matrix3;
use serde_json::{json, Map, Value};

use super::bounds::{self, Noise};
use super::metrics::{filter_metrics, get};
use super::runs::{RunResult, Setup, Track};
use super::{INTENSITY, LITERAL};
use crate::scenarios::Outcome;

/// LEO: how much the Doppler tells about the rotation, and the Doppler-free comparison.
pub fn leo_metrics(
    s: &Setup,
    results: &[RunResult],
    b_rigid: &Matrix3<f64>,
    outcome: &mut Outcome,
    summary: &mut Vec<String>,
) {
    let omega = s.motion.body_rate(s.duration / 2.0).norm();
    let j = bounds::rate_information(&s.array, &BaselinePair::ALL);
    let tr_j_inv = j.try_inverse().map_or(f64::NAN, |m| m.trace());
    let reading = |n: Noise| {
        // per-sample σ of the least-squares rate, the filter memory σ_p/σ_v, and the rate at
        // which the Doppler resolves the rotation within that memory (SNR 1)
        let sigma_rate = n.sigma_velocity * tr_j_inv.sqrt();
        let memory = n.sigma_baseline / n.sigma_velocity;
        let snr = omega / sigma_rate;
        let snr_memory = snr * (memory / n.dt).sqrt();
        let crossover = omega / snr_memory;
        (sigma_rate, memory, snr, snr_memory, crossover)
    };
    let pick = |f: fn(&RunResult) -> &Track| results.iter().map(f).collect::<Vec<_>>();
    let b_lit =
        bounds::rigid_body(&s.array, &BaselinePair::ALL, LITERAL).unwrap_or_else(Matrix3::zeros);
    let free = filter_metrics(&pick(|r| &r.doppler_free), b_rigid);
    let lit = filter_metrics(&pick(|r| &r.literal_rigid_body), &b_lit);
    let lit_free = filter_metrics(&pick(|r| &r.literal_doppler_free), &b_lit);
    let paper_columns = match DirectionCosineModel::new(
        &s.array.baseline(BaselinePair::P12),
        &s.array.baseline(BaselinePair::P23),
        ColumnChoice::Paper,
    ) {
        Ok(_) => "accepted".to_string(),
        Err(e) => format!("refused: {e}"),
    };
    let mut leo = Map::new();
    for (name, n) in [("intensity", INTENSITY), ("literal", LITERAL)] {
        let (sr, mem, snr, snrm, cross) = reading(n);
        leo.insert(
            name.into(),
            json!({
                "rate_sigma_per_sample_rad_s": sr,
                "filter_memory_s": mem,
                "doppler_rate_snr_per_sample": snr,
                "doppler_rate_snr_over_memory": snrm,
                "crossover_rate_rad_s": cross,
            }),
        );
        summary.push(format!(
            "leo, {name} noise: |ω| = {omega:.2e} rad/s; LS rate σ {sr:.2e} rad/s per sample (SNR {snr:.3}); over the filter memory {mem:.0} s SNR {snrm:.2}; Doppler observes the rotation only above {cross:.1e} rad/s"
        ));
    }
    leo.insert("body_rate_rad_s".into(), json!(omega));
    leo.insert(
        "rigid_body_doppler_free".into(),
        Value::Object(free.clone()),
    );
    leo.insert("literal_rigid_body".into(), Value::Object(lit.clone()));
    leo.insert(
        "literal_rigid_body_doppler_free".into(),
        Value::Object(lit_free.clone()),
    );
    leo.insert("six_state_with_paper_columns".into(), json!(paper_columns));
    summary.push(format!(
        "leo, intensity: rigid-body with Doppler {:.2e} rad vs Doppler-free {:.2e} rad; literal: with Doppler {:.2e} rad vs Doppler-free {:.2e} rad (rotvec RMS)",
        outcome
            .metrics
            .get("rigid_body")
            .and_then(|v| v.get("rotvec_rms_rad"))
            .and_then(Value::as_f64)
            .unwrap_or(f64::NAN),
        get(&free, "rotvec_rms_rad"),
        get(&lit, "rotvec_rms_rad"),
        get(&lit_free, "rotvec_rms_rad"),
    ));
    summary.push(format!(
        "leo: six-state filter with the paper's column choice: {paper_columns}"
    ));
    outcome.metric("leo", Value::Object(leo));
}
