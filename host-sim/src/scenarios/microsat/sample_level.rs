//! The sample-level stretch of a flight: the world's sky, orbit Doppler and attitude
//! synthesized as three-antenna complex samples ([`crate::synth`], a [`SatelliteTrack`] per
//! satellite), quantized to CS8 (or the `--front-end`'s 2- or 1-bit levels), then the core's acquisition (±50 kHz, the satellites the
//! almanac and the orbit predict above the reference antenna's mask, searched again every
//! whole second for new ones), its fixed-point correlators and LEO tracking channels
//! ([`ChannelConfig::leo`](gnss_attitude::tracking::ChannelConfig::leo)), the adapter and the epoch clock, all inside the core's
//! [`SampleReceiver`] in front of the flight's `AttitudeReceiver`: what the receiver gets is
//! what the crate's own signal chain produces. The fast path
//! ([`super::fast_path`]) continues from the channels this stretch hands over.
//!
//! Scene: every healthy satellite the reference antenna or another antenna receives during
//! the stretch, its range, range rate, `μ·r_P(t)` and per-antenna C/N0 tabulated every
//! [`TRACK_STEP_S`] from the world (so the signal switches off where an antenna stops
//! receiving it), the world's line biases; 2.6 Msps complex CS8 (noise σ = 16 LSB). Receiver
//! epoch `k` is centred on sample `(k + ½)·2600`.
//!
//! Navigation message: each satellite's signal carries the encoder's LNAV bits
//! ([`crate::synth::lnav`]) at the time they left the satellite, as the fast path's modelled
//! decoding has them ([`Navigation::signal`]: light time with the Sagnac rotation, the
//! satellite clock `Δt_sv`): the track's range is `ρ_eff = c (τ − Δt_sv)` and the code count
//! starts at the subframe start before the signal time of the first sample
//! ([`LnavModulation`], shared with `synth --lnav`), so the code phase at every sample is the
//! time of transmission. The channels' prompts ([`SampleReceiver::push_samples_observed`])
//! go through the core's bit and subframe synchronization ([`NavChannel`], as `track`'s), and
//! the flight's navigation takes the subframes ([`SampleLevel::take_decoded`]).

use std::collections::BTreeMap;
use std::sync::Arc;

use anyhow::{anyhow, Result};
use gnss_attitude::geometry::Quaternion;
use gnss_attitude::nav::subframe::SubframeError;
use gnss_attitude::nav::{Subframe, TransmitTime};
use gnss_attitude::receiver::{
    AttitudeSource, SampleFrontConfig, SampleReceiver, SampleReport, MAX_SATELLITES,
};
use gnss_attitude::signal::{Prn, SampleBlock, SampleFormat};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::fast_path::EPOCH_S;
use super::navigation::Navigation;
use super::world::{World, MASK_RAD};
use crate::chain::{samples, ChainParams, ANTENNAS};
use crate::record::navigation::NavChannel;
use crate::record::synth_nav::LnavModulation;
use crate::synth::lnav::LnavEncoder;
use crate::synth::quantize::Planar;
use crate::synth::quantize::Quantizer;
use crate::synth::scene::{L1_WAVELENGTH, SPEED_OF_LIGHT};
use crate::synth::{AttitudeMotion, CarrierStep, FrontEnd, Satellite, SatelliteTrack, Scene};

/// Sample rate, Hz.
pub const SAMPLE_RATE_HZ: f64 = 2.6e6;
/// Samples per receiver epoch (1 ms).
pub const SAMPLES_PER_EPOCH: u32 = 2600;
/// Samples per streamed block (0.1 s: searches start on whole seconds).
pub const BLOCK: usize = 260_000;
/// Step of the satellite tracks, s.
pub const TRACK_STEP_S: f64 = 0.01;
/// How far below an antenna's mask a satellite predicted with the receiver's own attitude is
/// still searched, rad (5°: the attitude is known to better than a degree once it exists).
pub const SEARCH_MARGIN_RAD: f64 = 5.0 * std::f64::consts::PI / 180.0;
/// A PRN whose search failed is searched again after this long, s.
pub const RETRY_AFTER_S: f64 = 5.0;
/// A channel without lock for this long is closed (its slot searched again), s.
pub const DROP_AFTER_S: f64 = 2.0;

/// Duration of an injected cycle slip: the slaved antenna's carrier turns by [`SLIP_CYCLES`]
/// over it, s.
///
/// Why 100 ms and not the 4 ms of a PLL's slip: the receiver keeps the whole cycles of each
/// single difference in a counter advanced once per 20 ms block
/// ([`ReceiverConfig::block_epochs`](gnss_attitude::receiver::ReceiverConfig)) from the
/// block's phase `arg Σ z_P z_A*`. A whole cycle turned inside one block (4 ms) leaves that
/// phase where it was (the turning epochs' products sum to about zero) and the counter, the
/// integers, the fine filter's block phases and the attitude all unchanged: the count stays
/// consistent with the geometry, there is nothing to detect and nothing to repair (a run with
/// it reports the attitude inside 3σ throughout). The slip that harms this receiver is one its
/// counter *does* count while the geometry does not move: a turn spread over several blocks
/// (here 0.2 cycle per block, well inside the counter's ±½ cycle). Its whole-cycle count is
/// then one off the fixed integer, exactly what a PLL slip does to a per-antenna receiver's
/// count; the ambiguity upkeep must find it against the fine attitude
/// ([`ReceiverEvent::CycleSlip`](gnss_attitude::receiver::ReceiverEvent)) and repair the
/// integer, or the snapshot monitor, the rigid-body filter and the integrity check take a
/// one-cycle error.
pub const SLIP_DURATION_S: f64 = 0.1;
/// Size of an injected cycle slip, cycles.
pub const SLIP_CYCLES: f64 = 1.0;

/// What the stretch saw.
#[derive(Clone, Debug, Default)]
pub struct SampleStats {
    /// Satellites in the scene.
    pub satellites: usize,
    /// PRN searches run (each ±50 kHz on 20 ms of the reference antenna).
    pub searches: usize,
    /// Searches that found their satellite (each starts a channel).
    pub detections: usize,
    /// Searches of PRNs no antenna received at the time (predicted up, but below the antennas'
    /// horizon, blocked, or not in the sky).
    pub searches_absent: usize,
    /// Detections of a PRN the reference antenna did not receive: false alarms.
    pub false_alarms: usize,
    /// Searches of a PRN the reference antenna received that found nothing.
    pub missed: usize,
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

/// The live sample-level source: the scene and its current block of samples; the channels,
/// the adapter and the epoch clock are the core's [`SampleReceiver`]'s.
pub struct SampleLevel {
    params: ChainParams,
    /// PRN of each scene satellite.
    prns: Vec<u8>,
    /// The current block: its first sample and its decoded samples.
    block: Option<(u64, Planar)>,
    stats: SampleStats,
    /// When each PRN's last search failed, s: searched again [`RETRY_AFTER_S`] later.
    failed_at: BTreeMap<u8, f64>,
    /// The LNAV decoder of each PRN a channel tracked (bit and subframe sync on its prompts).
    decoders: BTreeMap<u8, NavChannel>,
}

/// What one satellite's channel decoded: its PRN, the subframes, the refused ones.
pub type Decoded = (u8, Vec<Subframe>, Vec<SubframeError>);

/// One satellite at one track point: PRN, pseudorange `ρ_eff` (m), its rate (m/s), `μ·r_P` (m)
/// and C/N0 (dB-Hz, `NEG_INFINITY` where not received) per antenna.
type TrackPoint = (u8, f64, f64, [f64; 3], [f64; 3]);

/// The satellite tracks of `world` over `[0, duration_s]`: every healthy satellite some
/// antenna receives at some point, its range the signal's `ρ_eff = c (τ − Δt_sv)` as `nav`'s
/// truth has it (so the code carries the time of transmission).
fn tracks(world: &World, nav: &Navigation, duration_s: f64) -> Vec<(u8, SatelliteTrack)> {
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
                .filter_map(|v| {
                    let sig = nav.signal(world, v.prn, t)?;
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
                    let rho = sig.range_m - SPEED_OF_LIGHT * sig.clock_s;
                    let rate = sig.range_rate_m_s - SPEED_OF_LIGHT * sig.clock_rate;
                    Some((v.prn, rho, rate, geometry, cn0))
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

/// An injected cycle slip: from `start_s`, antenna `antenna`'s carrier of satellite `prn` turns
/// by [`SLIP_CYCLES`] over [`SLIP_DURATION_S`] (in the samples inside the sample-level
/// stretch, in the fast path's prompts after it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleSlip {
    /// Time, s.
    pub start_s: f64,
    /// Antenna (1 = B, 2 = C).
    pub antenna: usize,
    /// Satellite.
    pub prn: u8,
}

/// The chain set-up of the stretch: scene from the world's first `duration_s`, with `slips`
/// in the carriers, the LNAV message at the signal times `nav`'s truth gives.
pub fn chain_params(
    world: &World,
    nav: &Navigation,
    duration_s: f64,
    seed: u64,
    slips: &[SampleSlip],
) -> ChainParams {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x6d73_616d_706c_6573);
    let encoder = LnavEncoder::bundled();
    let satellites = tracks(world, nav, duration_s)
        .into_iter()
        .map(|(prn, mut track)| {
            track.carrier_steps = slips
                .iter()
                .filter(|s| s.prn == prn)
                .map(|s| CarrierStep {
                    antenna: s.antenna,
                    start_s: s.start_s,
                    duration_s: SLIP_DURATION_S,
                    cycles: SLIP_CYCLES,
                })
                .collect();
            (prn, track)
        })
        .filter_map(|(prn, mut track)| {
            let sig = nav.signal(world, prn, 0.0)?;
            let t_sv0 = sig.transmit_s + sig.clock_s;
            let m = LnavModulation::new(&encoder, prn, encoder.almanac_week, t_sv0, duration_s);
            track.data_bits = m.data_bits;
            // (a code phase was drawn here before the message: the draw keeps the carrier
            // phases of the seeds)
            let _: f64 = rng.random_range(0.0..1023.0);
            Some(Satellite {
                prn,
                cn0_dbhz: track
                    .cn0_dbhz
                    .iter()
                    .flatten()
                    .copied()
                    .fold(f64::NEG_INFINITY, f64::max),
                doppler_hz: -track.range_rate_m_s[0] / L1_WAVELENGTH,
                doppler_rate_hz_s: 0.0,
                code_phase_chips: m.code_phase_chips,
                carrier_phase_cycles: rng.random_range(0.0..1.0),
                los_ref: Vector3::z(),
                data_seed: None,
                track: Some(Arc::new(track)),
            })
        })
        .collect();
    let scene = Scene {
        satellites,
        antennas_b: world.antennas.iter().map(|a| a.position).collect(),
        line_bias_cycles: world
            .line_bias
            .at(0.5 * duration_s)
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
    let front = SampleLevel::front_config();
    ChainParams {
        scene,
        format: SampleFormat::Cs8,
        quantizer: Quantizer::I8,
        acquisition: front.acquisition,
        search_prns: Vec::new(),
        channel: front.channel,
        duration_s,
        block: BLOCK,
    }
}

impl SampleLevel {
    /// The stretch of `world`'s first `duration_s` drawn with `seed`, with `slips`, the
    /// signals' times of transmission from `nav`'s truth. `front_end` quantizes the samples
    /// the receiver gets.
    pub fn new(
        world: &World,
        nav: &Navigation,
        duration_s: f64,
        seed: u64,
        slips: &[SampleSlip],
        front_end: Quantizer,
    ) -> Self {
        let params = ChainParams {
            quantizer: front_end,
            ..chain_params(world, nav, duration_s, seed, slips)
        };
        let prns = params.scene.satellites.iter().map(|s| s.prn).collect();
        let mut stats = SampleStats {
            satellites: params.scene.satellites.len(),
            ..SampleStats::default()
        };
        for k in 0..params.scene.satellites.len() {
            let f = |t: f64| params.scene.truth(k, 0, t).doppler_hz;
            let mut t = 0.0;
            while t < duration_s {
                stats.max_doppler_hz = stats.max_doppler_hz.max(f(t).abs());
                stats.max_doppler_rate_hz_s =
                    stats.max_doppler_rate_hz_s.max((f(t + 1.0) - f(t)).abs());
                t += 1.0;
            }
        }
        Self {
            params,
            prns,
            block: None,
            stats,
            failed_at: BTreeMap::new(),
            decoders: BTreeMap::new(),
        }
    }

    /// What each satellite's channel decoded since the last call (PRN order).
    pub fn take_decoded(&mut self) -> Vec<Decoded> {
        self.decoders
            .values_mut()
            .map(|d| {
                let (subframes, refused) = d.take_decoded();
                (d.prn(), subframes, refused)
            })
            .filter(|(_, s, r)| !s.is_empty() || !r.is_empty())
            .collect()
    }

    /// The times of transmission `prn`'s channel measured from its code phase at the whole
    /// seconds since the last call (flight time s, the time), its decoder given `week` first.
    pub fn take_transmit_times(&mut self, prn: u8, week: u16) -> Vec<(f64, TransmitTime)> {
        let Some(d) = self.decoders.get_mut(&prn) else {
            return Vec::new();
        };
        d.set_week(week);
        d.take_transmit_times()
            .into_iter()
            .map(|(sample, t)| (sample as f64 / SAMPLE_RATE_HZ, t))
            .collect()
    }

    /// Whether `prn`'s decoder holds subframe sync (`None`: no channel has tracked it).
    pub fn subframe_synchronized(&self, prn: u8) -> Option<bool> {
        self.decoders
            .get(&prn)
            .map(NavChannel::subframe_synchronized)
    }

    /// The front-end configuration of the core's receiver for this stretch.
    pub fn front_config() -> SampleFrontConfig {
        SampleFrontConfig {
            release_after_samples: (DROP_AFTER_S * SAMPLE_RATE_HZ) as u64,
            ..SampleFrontConfig::leo_complex(SAMPLE_RATE_HZ)
        }
    }

    /// When each PRN's last failed search was, s (the fast path continues the retries).
    pub fn failed_at(&self) -> &BTreeMap<u8, f64> {
        &self.failed_at
    }

    /// What the stretch saw so far.
    pub fn stats(&self) -> &SampleStats {
        &self.stats
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

    /// What the receiver decides to search at `t`, from what a flight computer has: the
    /// almanac and the orbit (`world.sky`) say which healthy satellites are above the Earth's
    /// limb; with an attitude of its own (`rx`'s receiver), only those predicted above some
    /// antenna's horizon less [`SEARCH_MARGIN_RAD`]; cold, all of them. PRNs with a channel
    /// are not searched again. The fast path searches from the same list
    /// ([`super::fast_search`]).
    pub fn to_search(t: f64, rx: &Front, world: &World) -> Vec<u8> {
        let attitude = rx.receiver().attitude();
        let c_ib = (attitude.source != AttitudeSource::None).then(|| {
            let q = attitude.q_rb;
            Quaternion::new(
                f64::from(q.w),
                f64::from(q.x),
                f64::from(q.y),
                f64::from(q.z),
            )
            .to_dcm()
        });
        world
            .navigation_views(t)
            .into_iter()
            .filter(|v| !v.occulted)
            .filter(|v| {
                c_ib.is_none_or(|c| {
                    let s_b = c.transpose() * v.los;
                    world
                        .antennas
                        .iter()
                        .any(|a| s_b.dot(&a.boresight).asin() >= MASK_RAD - SEARCH_MARGIN_RAD)
                })
            })
            .map(|v| v.prn)
            .filter(|&p| Prn::new(p).is_some_and(|p| !rx.tracks(p)))
            .collect()
    }

    /// Receiver epoch `k` from samples: synthesizes the next block when `k` starts one,
    /// searches the predicted satellites without a channel on whole seconds, and pushes the
    /// epoch's samples through `rx`'s channels into its receiver.
    pub fn epoch(&mut self, k: u64, rx: &mut Front, world: &World) -> Result<SampleReport> {
        let per = u64::from(SAMPLES_PER_EPOCH);
        let first = k * per;
        let stale = match &self.block {
            Some((b0, p)) => first < *b0 || first + per > b0 + p.i[0].len() as u64,
            None => true,
        };
        if stale {
            let started = std::time::Instant::now();
            let planar = samples(&self.params, first, BLOCK)?;
            self.stats.synthesis_s += started.elapsed().as_secs_f64();
            self.block = Some((first, planar));
        }
        let Some((b0, planar)) = &self.block else {
            return Ok(SampleReport::default());
        };
        let off = (first - b0) as usize;
        let t = first as f64 / SAMPLE_RATE_HZ;
        if k % 1000 == 0 {
            let needed = self.params.acquisition.samples_needed();
            let failed = &self.failed_at;
            let prns: Vec<u8> = Self::to_search(t, rx, world)
                .into_iter()
                .filter(|p| failed.get(p).is_none_or(|&f| t - f >= RETRY_AFTER_S - 1e-9))
                .collect();
            let started = std::time::Instant::now();
            for p in prns {
                let prn = Prn::new(p).ok_or_else(|| anyhow!("PRN {p}"))?;
                let (i, q) = (
                    planar.i[0].get(off..off + needed),
                    planar.q[0].get(off..off + needed),
                );
                let (Some(i), Some(q)) = (i, q) else {
                    break;
                };
                let r = rx
                    .search(prn, i, Some(q), first)
                    .map_err(|e| anyhow!("search PRN {p}: {e}"))?;
                count_search(&self.params, &mut self.stats, p, t, r.detected);
                if r.detected {
                    self.failed_at.remove(&p);
                } else {
                    self.failed_at.insert(p, t);
                }
            }
            self.stats.acquisition_s += started.elapsed().as_secs_f64();
        }
        let started = std::time::Instant::now();
        let r = off..off + per as usize;
        let iv: [&[i8]; ANTENNAS] = [
            &planar.i[0][r.clone()],
            &planar.i[1][r.clone()],
            &planar.i[2][r.clone()],
        ];
        let qv: [&[i8]; ANTENNAS] = [
            &planar.q[0][r.clone()],
            &planar.q[1][r.clone()],
            &planar.q[2][r],
        ];
        let block = SampleBlock::complex(first, iv, qv)?;
        let decoders = &mut self.decoders;
        let report = rx
            .push_samples_observed(&block, &mut |prn, epoch, locked| {
                let p = prn.number();
                decoders
                    .entry(p)
                    .or_insert_with(|| NavChannel::new(p, SAMPLE_RATE_HZ))
                    .epoch(epoch, locked);
            })
            .map_err(|e| anyhow!("samples of epoch {k}: {e}"))?;
        self.stats.tracking_s += started.elapsed().as_secs_f64();
        self.stats.observations += report.observations as usize;
        self.stats.late += report.late as usize;
        Ok(report)
    }
}

/// Counts one search's outcome against the truth: whether the reference antenna received
/// `prn` at `t` in the scene of `params`.
fn count_search(params: &ChainParams, stats: &mut SampleStats, prn: u8, t: f64, detected: bool) {
    let received = params
        .scene
        .satellites
        .iter()
        .any(|s| s.prn == prn && s.track.as_ref().is_some_and(|tr| tr.cn0(0, t).is_finite()));
    stats.searches += 1;
    stats.detections += usize::from(detected);
    stats.searches_absent += usize::from(!received);
    stats.false_alarms += usize::from(detected && !received);
    stats.missed += usize::from(!detected && received);
}

/// The core's receiver from samples as host-sim runs it: 12 channels, 2048-point acquisition.
pub type Front = SampleReceiver<MAX_SATELLITES, 2048>;

/// The PRNs with a locked channel in `rx`.
pub fn locked(rx: &Front) -> Vec<u8> {
    rx.channels()
        .filter(|c| c.locked)
        .map(|c| c.prn.number())
        .collect()
}

/// The C/N0 `prn`'s channel in `rx` reports (`None` without a locked channel), dB-Hz.
pub fn reported_cn0_dbhz(rx: &Front, prn: u8) -> Option<f64> {
    rx.channels()
        .find(|c| c.prn.number() == prn && c.locked)
        .map(|c| f64::from(c.cn0_dbhz))
}
