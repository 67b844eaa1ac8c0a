//! The sample-level input path: the scenario's sky and attitude synthesized as three-antenna
//! complex samples ([`crate::synth`]), quantized to CS8, then the core's acquisition,
//! fixed-point correlators and tracking channels ([`crate::chain::Tracker`]) and the core's
//! adapter ([`ObservationAdapter`], [`EpochClock`]): samples → correlators → filter.
//!
//! Scene: the satellites of G1 with random Dopplers (±4.5 kHz), Doppler rates (±0.8 Hz/s),
//! code and carrier phases and 50 bit/s data, all at the run's C/N0 (thermal noise; the
//! other satellites' cross-correlation adds `(n−1)·(C/N0)T/1023` of interference, 0.29 dB for
//! 8 satellites at 40 dB-Hz); the paper's triangle; the run's line biases; 2.6 Msps complex CS8
//! (noise σ = 16 LSB). The receiver acquires the scene's PRNs on the first 40 ms and tracks
//! from sample 0; the filter starts after [`WARM_UP_S`] (frequency refinement, pull-in and the
//! first lock windows), so scene time `WARM_UP_S + t` is the filter's time `t` and filter
//! epoch `k` is centred on sample `(WARM_UP_S + k·T)·f_s`.

use std::collections::BTreeMap;
use std::sync::Arc;

use anyhow::{anyhow, bail, Result};
use gnss_attitude::attitude::one_stage::SatelliteObservation;
use gnss_attitude::receiver::{AdapterConfig, EpochClock, ObservationAdapter};
use gnss_attitude::signal::SampleFormat;
use gnss_attitude::tracking::{AcquisitionConfig, ChannelConfig};
use nalgebra::Matrix3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::sim::RunConfig;
use super::source::{EpochSource, EPOCH_S};
use super::truth::{antennas, rotation_about_y, sky_g1, Motion};
use crate::chain::{ChainParams, Tracker};
use crate::synth::quantize::Quantizer;
use crate::synth::{AttitudeMotion, FrontEnd, Satellite, Scene};

/// Sample rate, Hz (the `signal` scenario's).
pub const SAMPLE_RATE_HZ: f64 = 2.6e6;
/// Samples per filter epoch (1 ms).
pub const SAMPLES_PER_EPOCH: u32 = 2600;
/// Tracking before the filter starts, s.
pub const WARM_UP_S: f64 = 1.0;
/// Samples per streamed block.
pub const BLOCK: usize = 32_768;

/// Motion A delayed by the warm-up (the scene's clock starts [`WARM_UP_S`] before the filter's).
fn motion_a_scene(t: f64) -> Matrix3<f64> {
    rotation_about_y(Motion::MotionA.beta(t - WARM_UP_S))
}

/// The chain set-up of a run: scene from the run's sky, C/N0, motion and line biases; CS8
/// front end.
pub fn chain_params(cfg: &RunConfig, seed: u64) -> ChainParams {
    chain_params_with(cfg, seed, Quantizer::I8)
}

/// [`chain_params`] with the front end `quantizer` (the same synthesized signals).
pub fn chain_params_with(cfg: &RunConfig, seed: u64, quantizer: Quantizer) -> ChainParams {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5a3d_1e5e_7a11);
    let sky = sky_g1(cfg.satellites);
    let satellites = sky
        .iter()
        .enumerate()
        .map(|(k, s)| Satellite {
            prn: s.prn,
            cn0_dbhz: cfg.cn0_dbhz,
            doppler_hz: rng.random_range(-4500.0..4500.0),
            doppler_rate_hz_s: rng.random_range(-0.8..0.8),
            code_phase_chips: rng.random_range(0.0..1023.0),
            carrier_phase_cycles: rng.random_range(0.0..1.0),
            los_ref: s.los(),
            data_seed: Some(seed.wrapping_mul(31).wrapping_add(k as u64)),
            track: None,
        })
        .collect();
    let attitude = match cfg.motion {
        Motion::Static => AttitudeMotion::Constant(rotation_about_y(Motion::Static.beta(0.0))),
        Motion::MotionA => AttitudeMotion::Function(motion_a_scene),
    };
    let scene = Scene {
        satellites,
        antennas_b: antennas().to_vec(),
        line_bias_cycles: cfg
            .line_bias
            .iter()
            .map(|b| b / std::f64::consts::TAU)
            .collect(),
        attitude,
        front_end: FrontEnd {
            sample_rate_hz: SAMPLE_RATE_HZ,
            intermediate_frequency_hz: 0.0,
            complex: true,
        },
        noise_seed: Some(seed ^ 0x0005_ca1e_0f03),
    };
    ChainParams {
        scene,
        format: SampleFormat::Cs8,
        quantizer,
        acquisition: AcquisitionConfig {
            sample_rate_hz: SAMPLE_RATE_HZ,
            intermediate_frequency_hz: 0.0,
            doppler_max_hz: 10_000.0,
            doppler_step_hz: 500.0,
            noncoherent_ms: 40,
            false_alarm_probability: 1e-5,
        },
        search_prns: sky.iter().map(|s| s.prn).collect(),
        channel: ChannelConfig::new(SAMPLE_RATE_HZ, 0.0),
        duration_s: WARM_UP_S + cfg.duration_s + 0.01,
        block: BLOCK,
    }
}

/// What the sample-level path saw.
#[derive(Clone, Debug, Default)]
pub struct SampleStats {
    /// Satellites in the scene.
    pub satellites: usize,
    /// Satellites acquired and tracked.
    pub tracked: usize,
    /// Observations handed to the filter.
    pub observations: usize,
    /// Filter epochs with no observation (before lock, or gaps).
    pub empty_epochs: usize,
    /// Tracking epochs that arrived after their filter epoch had been stepped (should be 0).
    pub late: usize,
    /// Mean C/N0 the channels reported for the observations, dB-Hz.
    pub mean_cn0_dbhz: f64,
    /// Wall time of sample synthesis (signal, noise, CS8), s.
    pub synthesis_s: f64,
    /// Wall time of acquisition (with its synthesis), s.
    pub acquisition_s: f64,
    /// Wall time of the tracking channels, s.
    pub tracking_s: f64,
}

/// The live sample-level source.
pub struct SampleLevel {
    params: ChainParams,
    tracker: Tracker,
    adapter: ObservationAdapter,
    clock: EpochClock,
    /// Line of sight (reference frame) per channel.
    los: Vec<[f32; 3]>,
    /// First sample not yet tracked.
    frontier: u64,
    /// Observations waiting for their filter epoch.
    pending: BTreeMap<u64, Vec<SatelliteObservation<f32>>>,
    /// Next filter epoch to hand out.
    next_epoch: u64,
    stats: SampleStats,
    cn0_sum: f64,
}

impl SampleLevel {
    /// Acquires the scene of `cfg` drawn with `seed` through the front end `quantizer` and
    /// starts its channels.
    pub fn new(cfg: &RunConfig, seed: u64, quantizer: Quantizer) -> Result<Self> {
        let params = chain_params_with(cfg, seed, quantizer);
        let tracker = Tracker::acquire(&params)?;
        let los = tracker
            .channels
            .iter()
            .map(|c| {
                let l = params.scene.satellites[c.scene_index].los_ref;
                [l.x as f32, l.y as f32, l.z as f32]
            })
            .collect();
        let origin = (WARM_UP_S * SAMPLE_RATE_HZ).round() as u64;
        let stats = SampleStats {
            satellites: params.scene.satellites.len(),
            tracked: tracker.channels.len(),
            acquisition_s: tracker.acquisition_seconds,
            ..SampleStats::default()
        };
        Ok(Self {
            adapter: ObservationAdapter::new(AdapterConfig::default())
                .map_err(|e| anyhow!("{e}"))?,
            clock: EpochClock::new(origin, SAMPLES_PER_EPOCH).map_err(|e| anyhow!("{e}"))?,
            params,
            tracker,
            los,
            frontier: 0,
            pending: BTreeMap::new(),
            next_epoch: 0,
            stats,
            cn0_sum: 0.0,
        })
    }

    /// What the path saw so far.
    pub fn stats(&self) -> SampleStats {
        let mut s = self.stats.clone();
        s.mean_cn0_dbhz = self.cn0_sum / s.observations.max(1) as f64;
        s.synthesis_s = self.tracker.synthesis_seconds;
        s.tracking_s = self.tracker.tracking_seconds;
        s
    }

    /// Tracks the next block and files its usable epochs under their filter epochs.
    fn advance(&mut self) -> Result<()> {
        let n = BLOCK;
        let per_channel = self.tracker.track(&self.params, self.frontier, n)?;
        self.frontier += n as u64;
        for (epochs, los) in per_channel.iter().zip(&self.los) {
            for e in epochs {
                let Some(obs) = self.adapter.observe(e, *los).map_err(|e| anyhow!("{e}"))? else {
                    continue;
                };
                match self.clock.epoch_of(&e.correlations) {
                    Some(k) if k >= self.next_epoch => {
                        self.pending.entry(k).or_default().push(obs);
                    }
                    Some(_) => self.stats.late += 1,
                    None => {}
                }
            }
        }
        Ok(())
    }
}

impl EpochSource for SampleLevel {
    fn epoch(
        &mut self,
        t: f64,
        c_rb: &Matrix3<f64>,
        out: &mut Vec<SatelliteObservation<f32>>,
    ) -> Result<()> {
        let k = (t / EPOCH_S).round() as u64;
        let truth = self.params.scene.attitude.c_rb(WARM_UP_S + t);
        if (truth - c_rb).norm() > 1e-9 {
            bail!("the sample-level scene's attitude differs from the run's truth at t = {t}");
        }
        // A tracking epoch filed under k has its middle within half an epoch of k's centre, so
        // it ends at most one epoch (plus the code-period drift) after that centre.
        let needed = self.clock.sample_of(k) + 2 * u64::from(SAMPLES_PER_EPOCH);
        while self.frontier < needed {
            self.advance()?;
        }
        // drop what belongs to skipped epochs
        while let Some((&first, _)) = self.pending.first_key_value() {
            if first >= k {
                break;
            }
            self.pending.pop_first();
        }
        out.clear();
        if let Some(obs) = self.pending.remove(&k) {
            out.extend(obs);
        }
        self.next_epoch = k + 1;
        if out.is_empty() {
            self.stats.empty_epochs += 1;
        }
        self.stats.observations += out.len();
        self.cn0_sum += out.iter().map(|o| f64::from(o.cn0_dbhz)).sum::<f64>();
        Ok(())
    }
}

/// A recorded sample-level run: the observations of every filter epoch.
#[derive(Clone, Debug)]
pub struct Recording {
    /// Observations per filter epoch.
    pub epochs: Vec<Vec<SatelliteObservation<f32>>>,
    /// What the path saw.
    pub stats: SampleStats,
    /// Wall time of the whole recording, s.
    pub wall_s: f64,
}

/// Runs the sample-level path of `cfg` for its duration through the front end `quantizer`
/// and records the observations.
pub fn record(cfg: &RunConfig, seed: u64, quantizer: Quantizer) -> Result<Recording> {
    let started = std::time::Instant::now();
    let mut source = SampleLevel::new(cfg, seed, quantizer)?;
    let epochs = record_source(cfg, &mut source)?;
    Ok(Recording {
        epochs,
        stats: source.stats(),
        wall_s: started.elapsed().as_secs_f64(),
    })
}

/// The observations of every filter epoch of `cfg`'s duration from any source (truth from
/// `cfg`'s motion).
pub fn record_source(
    cfg: &RunConfig,
    source: &mut dyn EpochSource,
) -> Result<Vec<Vec<SatelliteObservation<f32>>>> {
    let steps = (cfg.duration_s / EPOCH_S).round() as usize;
    let mut epochs = Vec::with_capacity(steps);
    let mut obs = Vec::new();
    for k in 0..steps {
        let t = k as f64 * EPOCH_S;
        source.epoch(t, &rotation_about_y(cfg.motion.beta(t)), &mut obs)?;
        epochs.push(obs.clone());
    }
    Ok(epochs)
}

impl Recording {
    /// Each satellite's (observation `id`'s) C/N0 averaged over the recorded observations
    /// (the adapter passes locked channels only), dB-Hz.
    pub fn cn0_by_satellite(&self) -> BTreeMap<u8, f64> {
        let mut sums: BTreeMap<u8, (f64, usize)> = BTreeMap::new();
        for o in self.epochs.iter().flatten() {
            let e = sums.entry(o.id).or_default();
            e.0 += f64::from(o.cn0_dbhz);
            e.1 += 1;
        }
        sums.into_iter()
            .map(|(id, (s, n))| (id, s / n as f64))
            .collect()
    }
}

/// Plays a [`Recording`] back (the truth passed in is not used: it was the recording's).
pub struct Replay {
    recording: Arc<Recording>,
}

impl Replay {
    /// A player of `recording`.
    pub fn new(recording: Arc<Recording>) -> Self {
        Self { recording }
    }
}

impl EpochSource for Replay {
    fn epoch(
        &mut self,
        t: f64,
        _c_rb: &Matrix3<f64>,
        out: &mut Vec<SatelliteObservation<f32>>,
    ) -> Result<()> {
        let k = (t / EPOCH_S).round() as usize;
        out.clear();
        match self.recording.epochs.get(k) {
            Some(obs) => out.extend_from_slice(obs),
            None => bail!("epoch {k} is beyond the recording"),
        }
        Ok(())
    }
}
