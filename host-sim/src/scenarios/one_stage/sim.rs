//! One run of the one-stage filter against the truth: the loop that feeds an [`EpochSource`]
//! into the core filter and measures the error.

use anyhow::anyhow;
use gnss_attitude::attitude::array::AntennaArray;
use gnss_attitude::attitude::one_stage::{
    EstimatedAngles, FilterMode, LockStatus, OneStageConfig, OneStageFilter, Prior,
    SatelliteObservation,
};
use gnss_attitude::geometry::Paper003Angles;
use nalgebra::Matrix3;

use super::bound::{information_rate, information_rate_three_angles, loop_bound_arcmin};
use super::samples::SampleLevel;
use super::source::{EpochSource, IqFastPath, EPOCH_S};
use super::truth::{rotation_about_y, sky_g1, Motion, SIDE_M, WAVELENGTH_M};
use crate::synth::quantize::Quantizer;

/// Prior standard deviation of the rates, rad/s (the paper's β is static; a snapshot solver
/// reports no rate).
pub const PRIOR_RATE_SIGMA: f64 = 0.005;

/// Which input path feeds the filter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputPath {
    /// Correlator outputs synthesized directly ([`IqFastPath`]).
    IqFastPath,
    /// Three-antenna samples through the core's correlators, tracking and adapter
    /// ([`SampleLevel`]).
    SampleLevel,
}

/// Everything one run needs.
#[derive(Clone, Copy, Debug)]
pub struct RunConfig {
    /// Satellites of G1 (the first `n`).
    pub satellites: usize,
    /// C/N0 of every satellite, dB-Hz.
    pub cn0_dbhz: f64,
    /// Loop bandwidth Δf, Hz.
    pub loop_bandwidth_hz: f64,
    /// Filter form.
    pub mode: FilterMode,
    /// Angles the filter estimates (β only in the paper's simulation).
    pub estimate: EstimatedAngles,
    /// Initial error of β̂, rad.
    pub initial_error_rad: f64,
    /// Prior standard deviation of the angles, rad.
    pub prior_sigma_rad: f64,
    /// Angular motion.
    pub motion: Motion,
    /// True line biases of antennas A, B, C, rad.
    pub line_bias: [f64; 3],
    /// Whether the filter estimates line biases.
    pub line_bias_states: bool,
    /// Run length, s.
    pub duration_s: f64,
    /// Fraction of the run discarded before the RMS.
    pub discard: f64,
    /// Input path.
    pub input: InputPath,
}

impl RunConfig {
    /// The paper's case: 8 satellites of G1, 40 dB-Hz, Δf = 2 Hz, β only, static, no biases,
    /// 60 s with the first 25 % discarded, I/Q fast path.
    pub fn paper(mode: FilterMode) -> Self {
        Self {
            satellites: 8,
            cn0_dbhz: 40.0,
            loop_bandwidth_hz: 2.0,
            mode,
            estimate: EstimatedAngles::BETA_ONLY,
            initial_error_rad: 0.0,
            prior_sigma_rad: 0.5f64.to_radians(),
            motion: Motion::Static,
            line_bias: [0.0; 3],
            line_bias_states: false,
            duration_s: 60.0,
            discard: 0.25,
            input: InputPath::IqFastPath,
        }
    }

    /// The loop-limited bound for this run's geometry, arc-minutes: `√(2Δf/J_β)` at `β = 0`
    /// (for a moving attitude, the RMS of the instantaneous bound over the retained part).
    pub fn bound_arcmin(&self) -> f64 {
        let sky = sky_g1(self.satellites);
        let all = self.estimate == EstimatedAngles::ALL;
        match self.motion {
            Motion::Static if all => loop_bound_arcmin(
                self.loop_bandwidth_hz,
                information_rate_three_angles(0.0, &sky, self.cn0_dbhz),
            ),
            Motion::Static => loop_bound_arcmin(
                self.loop_bandwidth_hz,
                information_rate(0.0, &sky, self.cn0_dbhz),
            ),
            Motion::MotionA => {
                let t0 = self.discard * self.duration_s;
                let n = 200;
                let ms = (0..n)
                    .map(|k| {
                        let t = t0 + (self.duration_s - t0) * (k as f64 + 0.5) / n as f64;
                        let j = information_rate(self.motion.beta(t), &sky, self.cn0_dbhz);
                        loop_bound_arcmin(self.loop_bandwidth_hz, j).powi(2)
                    })
                    .sum::<f64>()
                    / n as f64;
                ms.sqrt()
            }
        }
    }
}

/// One decimated sample of a run (every 10 ms).
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// Time, s.
    pub t: f64,
    /// `β̂ − β`, arc-minutes.
    pub error_arcmin: f64,
    /// Filter-reported standard deviation of β̂ (Gaussian mode), arc-minutes; NaN otherwise.
    pub sigma_arcmin: f64,
    /// Smoothed alignment `η̄`.
    pub alignment: f64,
    /// Lock status code: 0 pull-in, 1 locked, 2 false lock.
    pub status: u8,
}

/// What a run measured.
#[derive(Clone, Debug)]
pub struct RunResult {
    /// RMS of `β̂ − β` over the retained part, arc-minutes.
    pub rms_arcmin: f64,
    /// Time after which `|β̂ − β|` stays within `5 × bound` for the rest of the run, s; `None`
    /// if the error is outside at the end.
    pub pull_in_s: Option<f64>,
    /// First time the detector declared lock, s.
    pub locked_at_s: Option<f64>,
    /// First time the detector flagged a false lock, s.
    pub flagged_at_s: Option<f64>,
    /// Detector status at the end.
    pub final_status: LockStatus,
    /// `|β̂ − β|` at the end, degrees.
    pub final_error_deg: f64,
    /// Final line-bias estimates minus the truth (B−A, C−A), rad.
    pub line_bias_error_rad: [f64; 2],
    /// Decimated time series.
    pub samples: Vec<Sample>,
}

impl RunResult {
    /// Status at time `t` (the sample at or before `t`).
    pub fn status_at(&self, t: f64) -> Option<u8> {
        self.samples
            .iter()
            .take_while(|s| s.t <= t + 1e-9)
            .last()
            .map(|s| s.status)
    }

    /// `|β̂ − β|` at time `t`, arc-minutes (the sample at or before `t`).
    pub fn error_at_arcmin(&self, t: f64) -> Option<f64> {
        self.samples
            .iter()
            .take_while(|s| s.t <= t + 1e-9)
            .last()
            .map(|s| s.error_arcmin.abs())
    }
}

fn status_code(s: LockStatus) -> u8 {
    match s {
        LockStatus::PullIn => 0,
        LockStatus::Locked => 1,
        LockStatus::FalseLock => 2,
    }
}

/// Wraps an angle difference to `(−π, π]`.
fn wrap(a: f64) -> f64 {
    let w = (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    if w <= -std::f64::consts::PI {
        w + std::f64::consts::TAU
    } else {
        w
    }
}

/// Runs the filter of `cfg` for `cfg.duration_s` on data drawn with `seed` by `cfg.input`.
pub fn simulate(cfg: &RunConfig, seed: u64) -> anyhow::Result<RunResult> {
    let sky = sky_g1(cfg.satellites);
    let source: Box<dyn EpochSource> = match cfg.input {
        InputPath::IqFastPath => Box::new(IqFastPath::new(&sky, cfg.cn0_dbhz, cfg.line_bias, seed)),
        InputPath::SampleLevel => Box::new(SampleLevel::new(cfg, seed, Quantizer::I8)?),
    };
    simulate_with(cfg, source)
}

/// Runs the filter of `cfg` for `cfg.duration_s` on the observations of `source` (whose truth
/// must be `cfg`'s; `cfg.input` is not used).
pub fn simulate_with(cfg: &RunConfig, source: Box<dyn EpochSource>) -> anyhow::Result<RunResult> {
    let mut config = OneStageConfig::<f32>::gps_l1(cfg.mode, cfg.loop_bandwidth_hz as f32);
    config.wavelength_m = WAVELENGTH_M as f32;
    config.epoch_s = EPOCH_S as f32;
    config.estimate = cfg.estimate;
    config.line_bias_states = cfg.line_bias_states;
    let array = AntennaArray::paper_triangle(SIDE_M as f32).map_err(|e| anyhow!("{e}"))?;
    let beta0 = cfg.motion.beta(0.0) + cfg.initial_error_rad;
    let mut prior = Prior::new(
        Paper003Angles::new(0.0, beta0 as f32, 0.0),
        cfg.prior_sigma_rad as f32,
        PRIOR_RATE_SIGMA as f32,
    );
    prior.line_bias_variance = [0.25; 2];
    match config.state_dimension() {
        2 => run::<2>(cfg, source, config, array, &prior),
        4 => run::<4>(cfg, source, config, array, &prior),
        6 => run::<6>(cfg, source, config, array, &prior),
        8 => run::<8>(cfg, source, config, array, &prior),
        n => Err(anyhow!("no filter instance with {n} states")),
    }
}

/// The epoch loop for a filter with `N` states.
fn run<const N: usize>(
    cfg: &RunConfig,
    mut source: Box<dyn EpochSource>,
    config: OneStageConfig<f32>,
    array: AntennaArray<f32>,
    prior: &Prior<f32>,
) -> anyhow::Result<RunResult> {
    let mut filter =
        OneStageFilter::<f32, N>::new(config, array, prior).map_err(|e| anyhow!("{e}"))?;
    let bound = cfg.bound_arcmin();
    let steps = (cfg.duration_s / EPOCH_S).round() as usize;
    let first_kept = (cfg.discard * steps as f64).round() as usize;
    let mut obs: Vec<SatelliteObservation<f32>> = Vec::with_capacity(cfg.satellites);
    let mut sum_sq = 0.0;
    let mut kept = 0usize;
    let mut last_outside: Option<f64> = Some(0.0);
    let mut locked_at = None;
    let mut flagged_at = None;
    let mut samples = Vec::with_capacity(steps / 10 + 1);
    let mut err_arcmin = 0.0;
    for k in 0..steps {
        let t = k as f64 * EPOCH_S;
        let beta = cfg.motion.beta(t);
        let c_rb: Matrix3<f64> = rotation_about_y(beta);
        source.epoch(t, &c_rb, &mut obs)?;
        let report = filter.step(&obs).map_err(|e| anyhow!("epoch {k}: {e}"))?;
        let t_end = t + EPOCH_S;
        err_arcmin = wrap(f64::from(filter.angles().beta) - beta).to_degrees() * 60.0;
        if err_arcmin.abs() > 5.0 * bound {
            last_outside = Some(t_end);
        }
        if k >= first_kept {
            sum_sq += err_arcmin * err_arcmin;
            kept += 1;
        }
        match report.status {
            LockStatus::Locked if locked_at.is_none() => locked_at = Some(t_end),
            LockStatus::FalseLock if flagged_at.is_none() => flagged_at = Some(t_end),
            _ => {}
        }
        if (k + 1) % 10 == 0 {
            let sigma = filter
                .angle_covariance()
                .map_or(f64::NAN, |c| f64::from(c.m22).sqrt().to_degrees() * 60.0);
            samples.push(Sample {
                t: t_end,
                error_arcmin: err_arcmin,
                sigma_arcmin: sigma,
                alignment: f64::from(report.alignment),
                status: status_code(report.status),
            });
        }
    }
    let [ba, bb, bc] = cfg.line_bias;
    let [eb, ec] = filter.line_bias().map(f64::from);
    let bias_err = if cfg.line_bias_states {
        [wrap(eb - (bb - ba)), wrap(ec - (bc - ba))]
    } else {
        [f64::NAN; 2]
    };
    Ok(RunResult {
        rms_arcmin: (sum_sq / kept.max(1) as f64).sqrt(),
        pull_in_s: if err_arcmin.abs() > 5.0 * bound {
            None
        } else {
            last_outside
        },
        locked_at_s: locked_at,
        flagged_at_s: flagged_at,
        final_status: filter.lock_status(),
        final_error_deg: err_arcmin.abs() / 60.0,
        line_bias_error_rad: bias_err,
        samples,
    })
}
