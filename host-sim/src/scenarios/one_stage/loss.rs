//! The information an input path actually delivers about β, measured on its recorded
//! observations with the core's discriminator: the effective Fisher information per epoch
//! `J_eff = (mean slope)² / var(u_β)`, with `u_β` the angle discriminator of eq. (32) at the
//! true attitude and the slope `−∂u_β/∂β` from ±δ displacements (δ = 2′, well inside the
//! linear range). An ideal correlator at the synthesized C/N0 gives `J_eff = J_β T` (the
//! bound's information); the ratio is the path's loss, and the bound it supports is
//! `bound / √ratio`. This is independent of the C/N0 the filter is told (a wrong `q_T` scales
//! the slope and the noise of `u_β` alike) and has far less sampling noise than the RMS error
//! of one 60 s run (tens of thousands of epochs, not a few hundred loop time constants).

use anyhow::{anyhow, Result};
use gnss_attitude::attitude::array::AntennaArray;
use gnss_attitude::attitude::one_stage::{
    EstimatedAngles, FilterMode, OneStageConfig, OneStageFilter, Prior, SatelliteObservation,
};
use gnss_attitude::geometry::Paper003Angles;

use super::bound::information_rate;
use super::sim::RunConfig;
use super::source::EPOCH_S;
use super::truth::{sky_g1, SIDE_M, WAVELENGTH_M};

/// Epochs per block of the low-frequency ratio.
const BLOCK: usize = 50;

/// Displacement used for the slope, rad (2 arc-minutes).
const DELTA: f64 = 2.0 / 60.0 * std::f64::consts::PI / 180.0;

/// The measured information of one recorded run.
#[derive(Clone, Copy, Debug)]
pub struct InformationLoss {
    /// Epochs used.
    pub epochs: usize,
    /// `J_eff / (J_β T)` (1 for an ideal correlator at the synthesized C/N0).
    pub ratio: f64,
    /// `−10 log₁₀ ratio`, dB.
    pub loss_db: f64,
    /// The same ratio from the variance of 50-epoch means of `u_β` (the noise below 10 Hz,
    /// where a loop of a few hertz lives): lower than [`Self::ratio`] when the noise has more
    /// power at low frequencies than white noise, higher when part of it is high-pass (the
    /// other satellites' cross-correlation beats at their Doppler differences). About ±5 %
    /// (1σ) for 45 s.
    pub ratio_low_frequency: f64,
    /// Mean slope over the slope the filter expects from the C/N0 it is told
    /// (`EpochInformation::expected`): the factor by which the loop's gain differs from its
    /// design (1 − 0.5 % for an ideal correlator: the non-coherent `I₁/I₀` factor).
    pub slope_over_expected: f64,
}

impl InformationLoss {
    /// The bound this information supports, given the ideal one.
    pub fn bound_arcmin(&self, ideal_bound_arcmin: f64) -> f64 {
        ideal_bound_arcmin / self.ratio.sqrt()
    }
}

/// Measures the information of `epochs` (filter epoch `k` at `t = k·T`, truth from `cfg`'s
/// motion and line biases), skipping the first `cfg.discard` of the run and empty epochs.
pub fn measure(
    cfg: &RunConfig,
    epochs: &[Vec<SatelliteObservation<f32>>],
) -> Result<InformationLoss> {
    let mut config = OneStageConfig::<f64>::gps_l1(FilterMode::GaussianApproximation, 2.0);
    config.wavelength_m = WAVELENGTH_M;
    config.epoch_s = EPOCH_S;
    config.estimate = EstimatedAngles::BETA_ONLY;
    config.line_bias_states = true;
    let array = AntennaArray::paper_triangle(SIDE_M).map_err(|e| anyhow!("{e}"))?;
    let [ba, bb, bc] = cfg.line_bias;
    let prior_at = |beta: f64| {
        let mut p = Prior::new(Paper003Angles::new(0.0, beta, 0.0), 0.01, 0.005);
        p.line_bias = [bb - ba, bc - ba];
        p
    };
    let mut filter =
        OneStageFilter::<f64, 4>::new(config, array, &prior_at(0.0)).map_err(|e| anyhow!("{e}"))?;
    let first = (cfg.discard * epochs.len() as f64).round() as usize;
    let (mut n, mut sum, mut sum_sq, mut slope_sum) = (0usize, 0.0, 0.0, 0.0);
    let mut blocks: Vec<f64> = Vec::new();
    let (mut block_sum, mut block_n) = (0.0, 0usize);
    let mut expected_sum = 0.0;
    let mut u_at = |beta: f64, obs: &[SatelliteObservation<f64>]| -> Result<(f64, f64)> {
        filter
            .reinitialize(&prior_at(beta))
            .map_err(|e| anyhow!("{e}"))?;
        let info = filter.information(obs).map_err(|e| anyhow!("{e}"))?;
        Ok((info.gradient[1], info.expected[(1, 1)]))
    };
    for (k, obs) in epochs.iter().enumerate().skip(first) {
        if obs.is_empty() {
            continue;
        }
        let obs64: Vec<_> = obs.iter().map(SatelliteObservation::to_f64).collect();
        let beta = cfg.motion.beta(k as f64 * EPOCH_S);
        let (u, expected) = u_at(beta, &obs64)?;
        let slope =
            -(u_at(beta + DELTA, &obs64)?.0 - u_at(beta - DELTA, &obs64)?.0) / (2.0 * DELTA);
        expected_sum += expected;
        n += 1;
        block_sum += u;
        block_n += 1;
        if block_n == BLOCK {
            blocks.push(block_sum / BLOCK as f64);
            (block_sum, block_n) = (0.0, 0);
        }
        sum += u;
        sum_sq += u * u;
        slope_sum += slope;
    }
    let nf = n.max(1) as f64;
    let mean = sum / nf;
    let var = sum_sq / nf - mean * mean;
    let slope = slope_sum / nf;
    // the ideal information per epoch at the truth (static: β = 0; moving: the mean over the run)
    let sky = sky_g1(cfg.satellites);
    let ideal = (first..epochs.len())
        .step_by(100)
        .map(|k| information_rate(cfg.motion.beta(k as f64 * EPOCH_S), &sky, cfg.cn0_dbhz))
        .sum::<f64>()
        / ((epochs.len() - first).div_ceil(100)).max(1) as f64
        * EPOCH_S;
    let ratio = slope * slope / var / ideal;
    let block_mean = blocks.iter().sum::<f64>() / blocks.len().max(1) as f64;
    let block_var = blocks.iter().map(|b| (b - block_mean).powi(2)).sum::<f64>()
        / (blocks.len().max(2) - 1) as f64;
    let ratio_low_frequency = slope * slope / (BLOCK as f64 * block_var) / ideal;
    Ok(InformationLoss {
        epochs: n,
        ratio,
        loss_db: -10.0 * ratio.log10(),
        ratio_low_frequency,
        slope_over_expected: slope / (expected_sum / nf),
    })
}
