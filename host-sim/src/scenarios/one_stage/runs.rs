//! The runs behind the scenario's figures: a Monte Carlo of the I/Q fast path, and one
//! sample-level recording replayed through every filter configuration; their summaries.

use std::sync::Arc;

use gnss_attitude::attitude::one_stage::LockStatus;
use rayon::prelude::*;

use super::samples::{record, Recording, Replay};
use super::sim::{simulate, simulate_with, InputPath, RunConfig, RunResult};
use crate::report::progress;
use crate::synth::quantize::Quantizer;

/// Monte Carlo runs per filter form on the I/Q fast path.
pub const RUNS: usize = 8;

/// Summary of the runs of one configuration.
#[derive(Clone, Copy, Debug)]
pub struct Summary {
    /// RMS of `β̂ − β` pooled over the runs, arc-minutes.
    pub sigma_arcmin: f64,
    /// Worst pull-in time, s (`None` if a run never pulled in).
    pub pull_in_s: Option<f64>,
    /// Worst time of the lock declaration, s.
    pub locked_s: Option<f64>,
    /// A run that did not pull in, or ended not locked.
    pub false_lock: bool,
    /// Runs in which the detector flagged a false lock at some time.
    pub flagged_runs: usize,
    /// RMS of the final line-bias errors, rad (NaN without bias states).
    pub bias_error_rms_rad: f64,
}

/// Summarizes the runs of one configuration.
pub fn summarize(results: &[RunResult]) -> Summary {
    let n = results.len().max(1) as f64;
    let ms = results.iter().map(|r| r.rms_arcmin.powi(2)).sum::<f64>() / n;
    let worst = |f: fn(&RunResult) -> Option<f64>| {
        results
            .iter()
            .map(f)
            .try_fold(0.0f64, |m, v| v.map(|v| m.max(v)))
    };
    let bias_sq: Vec<f64> = results
        .iter()
        .flat_map(|r| r.line_bias_error_rad)
        .filter(|v| v.is_finite())
        .map(|v| v * v)
        .collect();
    Summary {
        sigma_arcmin: ms.sqrt(),
        pull_in_s: worst(|r| r.pull_in_s),
        locked_s: worst(|r| r.locked_at_s),
        false_lock: results
            .iter()
            .any(|r| r.pull_in_s.is_none() || r.final_status != LockStatus::Locked),
        flagged_runs: results.iter().filter(|r| r.flagged_at_s.is_some()).count(),
        bias_error_rms_rad: if bias_sq.is_empty() {
            f64::NAN
        } else {
            (bias_sq.iter().sum::<f64>() / bias_sq.len() as f64).sqrt()
        },
    }
}

/// Runs [`RUNS`] runs of each configuration on the I/Q fast path, in parallel (the same seeds
/// for every configuration, so the comparison is paired).
pub fn monte_carlo(
    configs: &[RunConfig],
    seed: u64,
    label: &str,
) -> anyhow::Result<Vec<Vec<RunResult>>> {
    let jobs: Vec<(usize, usize)> = (0..configs.len())
        .flat_map(|c| (0..RUNS).map(move |r| (c, r)))
        .collect();
    let bar = progress(jobs.len() as u64, label);
    let results: Vec<((usize, usize), RunResult)> = jobs
        .par_iter()
        .map(|&(c, r)| {
            let cfg = RunConfig {
                input: InputPath::IqFastPath,
                ..configs[c]
            };
            let out = simulate(&cfg, seed.wrapping_mul(1_000_003).wrapping_add(r as u64));
            bar.inc(1);
            out.map(|o| ((c, r), o))
        })
        .collect::<anyhow::Result<_>>()?;
    bar.finish_and_clear();
    let mut by_config: Vec<Vec<RunResult>> = vec![Vec::new(); configs.len()];
    for ((c, _), res) in results {
        by_config[c].push(res);
    }
    Ok(by_config)
}

/// One sample-level recording with `seed` through the front end `quantizer` (the truth of
/// `configs[0]`; every configuration must share its sky, C/N0, motion and line biases),
/// replayed through every configuration's filter in parallel.
pub fn sample_level(
    configs: &[RunConfig],
    seed: u64,
    quantizer: Quantizer,
) -> anyhow::Result<(Arc<Recording>, Vec<RunResult>)> {
    let base = configs
        .first()
        .ok_or_else(|| anyhow::anyhow!("no configuration"))?;
    let bar = progress(1, "one-stage: samples → correlators → filter");
    let recording = Arc::new(record(base, seed, quantizer)?);
    bar.finish_and_clear();
    let results = configs
        .par_iter()
        .map(|c| simulate_with(c, Box::new(Replay::new(recording.clone()))))
        .collect::<anyhow::Result<Vec<_>>>()?;
    Ok((recording, results))
}
