//! The `leo` variant's extra figures: how much the Doppler tells about a slow rotation.

use gnss_attitude::attitude::array::BaselinePair;
use gnss_attitude::attitude::direction_cosine::{ColumnChoice, DirectionCosineModel};
use nalgebra::Matrix3;

use super::bounds::{self, Noise};
use super::metrics::{filter_metrics, DopplerReading, LeoMetrics};
use super::runs::{RunResult, Setup, Track};
use super::{INTENSITY, LITERAL};

/// LEO: how much the Doppler tells about the rotation, and the Doppler-free comparison
/// (`rigid_rms_rad`: the rigid-body filter's RMS with the Doppler, for the summary).
pub fn leo_metrics(
    s: &Setup,
    results: &[RunResult],
    b_rigid: &Matrix3<f64>,
    rigid_rms_rad: f64,
    summary: &mut Vec<String>,
) -> LeoMetrics {
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
    let readings = [("intensity", INTENSITY), ("literal", LITERAL)].map(|(name, n)| {
        let (sr, mem, snr, snrm, cross) = reading(n);
        summary.push(format!(
            "leo, {name} noise: |ω| = {omega:.2e} rad/s; LS rate σ {sr:.2e} rad/s per sample (SNR {snr:.3}); over the filter memory {mem:.0} s SNR {snrm:.2}; Doppler observes the rotation only above {cross:.1e} rad/s"
        ));
        DopplerReading {
            rate_sigma_per_sample_rad_s: sr,
            filter_memory_s: mem,
            doppler_rate_snr_per_sample: snr,
            doppler_rate_snr_over_memory: snrm,
            crossover_rate_rad_s: cross,
        }
    });
    summary.push(format!(
        "leo, intensity: rigid-body with Doppler {:.2e} rad vs Doppler-free {:.2e} rad; literal: with Doppler {:.2e} rad vs Doppler-free {:.2e} rad (rotvec RMS)",
        rigid_rms_rad,
        free.rotvec_rms_rad,
        lit.rotvec_rms_rad,
        lit_free.rotvec_rms_rad,
    ));
    summary.push(format!(
        "leo: six-state filter with the paper's column choice: {paper_columns}"
    ));
    let [intensity, literal] = readings;
    LeoMetrics {
        intensity,
        literal,
        body_rate_rad_s: omega,
        rigid_body_doppler_free: free,
        literal_rigid_body: lit,
        literal_rigid_body_doppler_free: lit_free,
        six_state_with_paper_columns: paper_columns,
    }
}
