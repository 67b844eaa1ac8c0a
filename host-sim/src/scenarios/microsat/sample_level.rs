//! The sample-level stretch of a flight: the world's sky, orbit Doppler and attitude
//! synthesized as three-antenna complex samples ([`crate::synth`], a [`SatelliteTrack`] per
//! satellite), quantized to CS8, then the core's acquisition (±50 kHz, the satellites the
//! almanac and the orbit predict above the reference antenna's mask, searched again every
//! whole second for new ones), its fixed-point correlators and LEO tracking channels
//! ([`ChannelConfig::leo`]) and the core's [`ObservationAdapter`] / [`EpochClock`]: what the
//! receiver gets is what the crate's own signal chain produces. The fast path
//! ([`super::fast_path`]) continues from the channels this stretch hands over.
//!
//! Scene: every healthy satellite the reference antenna or another antenna receives during
//! the stretch, its range, range rate, `μ·r_P(t)` and per-antenna C/N0 tabulated every
//! [`TRACK_STEP_S`] from the world (so the signal switches off where an antenna stops
//! receiving it), 50 bit/s data, the world's line biases; 2.6 Msps complex CS8 (noise σ = 16
//! LSB). Receiver epoch `k` is centred on sample `(k + ½)·2600`.

use std::collections::BTreeMap;
use std::sync::Arc;

use anyhow::{anyhow, Result};
use gnss_attitude::attitude::one_stage::{
    AdapterConfig, EpochClock, ObservationAdapter, SatelliteObservation,
};
use gnss_attitude::signal::{SampleBlock, SampleFormat};
use gnss_attitude::tracking::{
    AcquisitionConfig, Channel, ChannelConfig, ChannelState, TrackingEpoch,
};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::fast_path::EPOCH_S;
use super::world::World;
use crate::chain::{samples, search_prns, track_block, ChainParams, ANTENNAS};
use crate::synth::scene::{mix, L1_WAVELENGTH};
use crate::synth::{AttitudeMotion, FrontEnd, Satellite, SatelliteTrack, Scene};

/// Sample rate, Hz.
pub const SAMPLE_RATE_HZ: f64 = 2.6e6;
/// Samples per receiver epoch (1 ms).
pub const SAMPLES_PER_EPOCH: u32 = 2600;
/// Samples per streamed block (0.1 s: searches start on whole seconds).
pub const BLOCK: usize = 260_000;
/// Step of the satellite tracks, s.
pub const TRACK_STEP_S: f64 = 0.01;
/// A channel without lock for this long is closed (its slot searched again), s.
pub const DROP_AFTER_S: f64 = 2.0;

/// What the stretch saw.
#[derive(Clone, Debug, Default)]
pub struct SampleStats {
    /// Satellites in the scene.
    pub satellites: usize,
    /// PRN searches run (each ±50 kHz on 20 ms of the reference antenna).
    pub searches: usize,
    /// Searches that found their satellite.
    pub detections: usize,
    /// Channels started.
    pub channels_started: usize,
    /// Observations handed to the receiver.
    pub observations: usize,
    /// Tracking epochs that arrived after their receiver epoch was handed out (should be 0).
    pub late: usize,
    /// Largest |Doppler| of the scene's satellites, Hz.
    pub max_doppler_hz: f64,
    /// Largest |Doppler rate| of the scene's satellites, Hz/s.
    pub max_doppler_rate_hz_s: f64,
    /// Wall time of sample synthesis (signal, noise, CS8), s.
    pub synthesis_s: f64,
    /// Wall time of acquisition, s.
    pub acquisition_s: f64,
    /// Wall time of the tracking channels, s.
    pub tracking_s: f64,
}

/// A running channel and what the stretch knows about it.
#[derive(Clone, Debug)]
struct Live {
    prn: u8,
    /// Epochs of the current block.
    epochs: Vec<TrackingEpoch<ANTENNAS>>,
    /// Last reported C/N0, dB-Hz, and whether the last epoch had code and phase lock.
    cn0_dbhz: f64,
    locked: bool,
    /// Time of the last locked epoch (or of the start), s.
    last_lock_s: f64,
}

/// The live sample-level source.
pub struct SampleLevel {
    params: ChainParams,
    /// PRN of each scene satellite.
    prns: Vec<u8>,
    channels: Vec<(Channel<ANTENNAS>, Live)>,
    adapter: ObservationAdapter,
    clock: EpochClock,
    /// First sample not yet tracked.
    frontier: u64,
    /// Observations waiting for their receiver epoch.
    pending: BTreeMap<u64, Vec<SatelliteObservation<f32>>>,
    next_epoch: u64,
    stats: SampleStats,
}

/// One satellite at one track point: PRN, range (m), range rate (m/s), `μ·r_P` (m) and C/N0
/// (dB-Hz, `NEG_INFINITY` where not received) per antenna.
type TrackPoint = (u8, f64, f64, [f64; 3], [f64; 3]);

/// The satellite tracks of `world` over `[0, duration_s]`: every healthy satellite some
/// antenna receives at some point.
fn tracks(world: &World, duration_s: f64) -> Vec<(u8, SatelliteTrack)> {
    let n = (duration_s / TRACK_STEP_S).ceil() as usize + 2;
    let points: Vec<Vec<TrackPoint>> = (0..n)
        .into_par_iter()
        .map(|k| {
            let t = k as f64 * TRACK_STEP_S;
            let c_ib = world.c_ib(t);
            world
                .sky
                .views(t)
                .iter()
                .map(|v| {
                    let s = world.antenna_view(v, &c_ib, t);
                    let geometry =
                        [0, 1, 2].map(|p| v.los.dot(&(c_ib * world.antennas[p].position)));
                    let cn0 = [0, 1, 2].map(|p| {
                        if s.visible[p] {
                            s.cn0_dbhz[p]
                        } else {
                            f64::NEG_INFINITY
                        }
                    });
                    (v.prn, v.range, v.range_rate, geometry, cn0)
                })
                .collect()
        })
        .collect();
    let mut by_prn: BTreeMap<u8, SatelliteTrack> = BTreeMap::new();
    for point in &points {
        for &(prn, range, rate, geometry, cn0) in point {
            let t = by_prn.entry(prn).or_insert_with(|| SatelliteTrack {
                step_s: TRACK_STEP_S,
                ..SatelliteTrack::default()
            });
            t.range_m.push(range);
            t.range_rate_m_s.push(rate);
            t.geometry_m.push(geometry.to_vec());
            t.cn0_dbhz.push(cn0.to_vec());
        }
    }
    by_prn
        .into_iter()
        .filter(|(_, t)| t.range_m.len() == n && t.cn0_dbhz.iter().flatten().any(|c| c.is_finite()))
        .collect()
}

/// The chain set-up of the stretch: scene from the world's first `duration_s`.
pub fn chain_params(world: &World, duration_s: f64, seed: u64) -> ChainParams {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x6d73_616d_706c_6573);
    let satellites = tracks(world, duration_s)
        .into_iter()
        .map(|(prn, track)| Satellite {
            prn,
            cn0_dbhz: track
                .cn0_dbhz
                .iter()
                .flatten()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max),
            doppler_hz: -track.range_rate_m_s[0] / L1_WAVELENGTH,
            doppler_rate_hz_s: 0.0,
            code_phase_chips: rng.random_range(0.0..1023.0),
            carrier_phase_cycles: rng.random_range(0.0..1.0),
            los_ref: Vector3::z(),
            data_seed: Some(mix(seed, 0xda7a, u64::from(prn))),
            track: Some(Arc::new(track)),
        })
        .collect();
    let scene = Scene {
        satellites,
        antennas_b: world.antennas.iter().map(|a| a.position).collect(),
        line_bias_cycles: world
            .line_bias_rad
            .iter()
            .map(|b| b / std::f64::consts::TAU)
            .collect(),
        attitude: AttitudeMotion::Constant(nalgebra::Matrix3::identity()),
        front_end: FrontEnd {
            sample_rate_hz: SAMPLE_RATE_HZ,
            intermediate_frequency_hz: 0.0,
            complex: true,
        },
        noise_seed: Some(seed ^ 0x6d69_6372_6f00),
    };
    ChainParams {
        scene,
        format: SampleFormat::Cs8,
        acquisition: AcquisitionConfig {
            sample_rate_hz: SAMPLE_RATE_HZ,
            intermediate_frequency_hz: 0.0,
            doppler_max_hz: 50_000.0,
            doppler_step_hz: 500.0,
            noncoherent_ms: 20,
            false_alarm_probability: 1e-5,
        },
        search_prns: Vec::new(),
        channel: ChannelConfig::leo(SAMPLE_RATE_HZ, 0.0),
        duration_s,
        block: BLOCK,
    }
}

impl SampleLevel {
    /// The stretch of `world`'s first `duration_s` drawn with `seed`.
    pub fn new(world: &World, duration_s: f64, seed: u64) -> Result<Self> {
        let params = chain_params(world, duration_s, seed);
        let prns = params.scene.satellites.iter().map(|s| s.prn).collect();
        let mut stats = SampleStats {
            satellites: params.scene.satellites.len(),
            ..SampleStats::default()
        };
        for (k, s) in params.scene.satellites.iter().enumerate() {
            let f = |t: f64| params.scene.truth(k, 0, t).doppler_hz;
            let mut t = 0.0;
            while t < duration_s {
                stats.max_doppler_hz = stats.max_doppler_hz.max(f(t).abs());
                stats.max_doppler_rate_hz_s = stats
                    .max_doppler_rate_hz_s
                    .max(((f(t + 1.0) - f(t)) / 1.0).abs());
                t += 1.0;
            }
            let _ = s;
        }
        Ok(Self {
            adapter: ObservationAdapter::new(AdapterConfig::default())
                .map_err(|e| anyhow!("{e}"))?,
            clock: EpochClock::new(u64::from(SAMPLES_PER_EPOCH / 2), SAMPLES_PER_EPOCH)
                .map_err(|e| anyhow!("{e}"))?,
            params,
            prns,
            channels: Vec::new(),
            frontier: 0,
            pending: BTreeMap::new(),
            next_epoch: 0,
            stats,
        })
    }

    /// What the stretch saw so far.
    pub fn stats(&self) -> &SampleStats {
        &self.stats
    }

    /// The PRNs with a channel that delivers locked epochs now.
    pub fn locked(&self) -> Vec<u8> {
        self.channels
            .iter()
            .filter(|(_, l)| l.locked)
            .map(|(_, l)| l.prn)
            .collect()
    }

    /// Whether `prn` has a channel.
    pub fn has_channel(&self, prn: u8) -> bool {
        self.channels.iter().any(|(_, l)| l.prn == prn)
    }

    /// The C/N0 `prn`'s channel reports (`None` without a locked channel), dB-Hz.
    pub fn reported_cn0_dbhz(&self, prn: u8) -> Option<f64> {
        self.channels
            .iter()
            .find(|(_, l)| l.prn == prn && l.locked)
            .map(|(_, l)| l.cn0_dbhz)
    }

    /// The first receiver epoch edge of `prn`'s data bits at or after `t` (s), from the
    /// scene's truth at the reference antenna: the receiver epoch whose tracking epoch starts
    /// with a new bit.
    pub fn next_bit_edge_epoch(&self, prn: u8, t: f64) -> Option<u64> {
        let k = self.prns.iter().position(|&p| p == prn)?;
        let chips = |t: f64| self.params.scene.truth(k, 0, t).code_chips_total;
        let bit = 20.0 * 1023.0;
        let target = (chips(t) / bit).ceil() * bit;
        // code rate ≈ 1.023 Mchip/s: two Newton steps
        let mut te = t + (target - chips(t)) / 1.023e6;
        for _ in 0..2 {
            te += (target - chips(te)) / 1.023e6;
        }
        Some((te / EPOCH_S).round() as u64)
    }

    /// Satellites the almanac and orbit predict above the reference antenna's mask at `t`
    /// without a channel.
    fn to_search(&self, t: f64) -> Vec<u8> {
        self.params
            .scene
            .satellites
            .iter()
            .filter(|s| {
                s.track.as_ref().is_some_and(|tr| tr.cn0(0, t).is_finite())
                    && !self.has_channel(s.prn)
            })
            .map(|s| s.prn)
            .collect()
    }

    /// Tracks the next block (searching first on whole seconds) and files its usable epochs
    /// under their receiver epochs.
    fn advance(&mut self) -> Result<()> {
        let n = BLOCK;
        let first = self.frontier;
        let t_first = first as f64 / SAMPLE_RATE_HZ;
        let started = std::time::Instant::now();
        let planar = samples(&self.params, first, n)?;
        self.stats.synthesis_s += started.elapsed().as_secs_f64();
        // searches on whole seconds
        if (t_first - t_first.round()).abs() < 1e-9 {
            let prns = self.to_search(t_first);
            if !prns.is_empty() {
                let started = std::time::Instant::now();
                let needed = self.params.acquisition.samples_needed();
                let results = search_prns(
                    &planar.i[0][..needed],
                    Some(&planar.q[0][..needed]),
                    first,
                    &prns,
                    &self.params.acquisition,
                )?;
                self.stats.acquisition_s += started.elapsed().as_secs_f64();
                self.stats.searches += results.len();
                for r in results.iter().filter(|r| r.detected) {
                    self.stats.detections += 1;
                    let mut ch = Channel::<ANTENNAS>::new(r.prn, &self.params.channel)?;
                    ch.start(r)?;
                    self.stats.channels_started += 1;
                    self.channels.push((
                        ch,
                        Live {
                            prn: r.prn.number(),
                            epochs: Vec::new(),
                            cn0_dbhz: 0.0,
                            locked: false,
                            last_lock_s: t_first,
                        },
                    ));
                }
            }
        }
        let started = std::time::Instant::now();
        let iv: [&[i8]; ANTENNAS] = [&planar.i[0], &planar.i[1], &planar.i[2]];
        let qv: [&[i8]; ANTENNAS] = [&planar.q[0], &planar.q[1], &planar.q[2]];
        let block = SampleBlock::complex(first, iv, qv)?;
        track_block(
            &mut self.channels,
            &block,
            |_| true,
            |live, e| live.epochs.push(*e),
        )?;
        self.stats.tracking_s += started.elapsed().as_secs_f64();
        self.frontier += n as u64;
        let t_end = self.frontier as f64 / SAMPLE_RATE_HZ;
        for (_, live) in self.channels.iter_mut() {
            for e in live.epochs.drain(..) {
                live.cn0_dbhz = f64::from(e.cn0_dbhz);
                live.locked = e.lock.code && e.lock.phase && e.state == ChannelState::Tracking;
                if live.locked {
                    live.last_lock_s = e.correlations.first_sample as f64 / SAMPLE_RATE_HZ;
                }
                let obs = self
                    .adapter
                    .observe(&e, [0.0, 0.0, 1.0])
                    .map_err(|e| anyhow!("{e}"))?;
                let Some(obs) = obs else { continue };
                match self.clock.epoch_of(&e.correlations) {
                    Some(k) if k >= self.next_epoch => {
                        self.pending.entry(k).or_default().push(obs);
                    }
                    Some(_) => self.stats.late += 1,
                    None => {}
                }
            }
        }
        // close channels that lost their satellite (set, or never locked)
        self.channels
            .retain(|(_, live)| t_end - live.last_lock_s < DROP_AFTER_S);
        Ok(())
    }

    /// The observations of receiver epoch `k` (every satellite whose channel delivered a
    /// usable epoch centred there).
    pub fn observations(&mut self, k: u64, out: &mut Vec<SatelliteObservation<f32>>) -> Result<()> {
        let needed = self.clock.sample_of(k) + 2 * u64::from(SAMPLES_PER_EPOCH);
        while self.frontier < needed {
            self.advance()?;
        }
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
        self.stats.observations += out.len();
        Ok(())
    }
}
