//! One flight: the truth, the signal (sample-level chain for the first stretch, then the I/Q
//! fast path), the gyro, the navigation aiding, the receiver, and the records the metrics and
//! plots are made from.

use std::collections::BTreeMap;

use anyhow::Result;
use gnss_attitude::geometry::Quaternion;
use gnss_attitude::receiver::{
    AttitudeReceiver, AttitudeSource, GyroConfig, ReceiverConfig, ReceiverEvent, SatelliteAiding,
    StageEstimate, MAX_SATELLITES,
};
use nalgebra::{Matrix3, Vector3};

use super::bound::bound_rad;
use super::fast_path::{rng, ChannelState, EmulatedChannel, PhaseTransient, EPOCH_S};
use super::sample_level::{locked, reported_cn0_dbhz, Front, SampleLevel, SampleSlip, SampleStats};
use super::world::{Blockage, MotionKind, SatTruth, World};
use crate::truth::attitude::AttitudeTruth;
use crate::truth::gyro::{Gyro, GyroErrors};
use crate::truth::sky::GpsView;
use gnss_attitude::signal::Prn;

/// Gyro sample interval, s.
pub const GYRO_H: f64 = 0.01;
/// Interval of the records, s.
pub const RECORD_S: f64 = 0.1;
/// Aiding update interval, s (and the receiver's window).
pub const AIDING_S: f64 = 0.1;

/// The faults of a run.
#[derive(Clone, Debug, Default)]
pub struct FaultPlan {
    /// Antenna blockages.
    pub blockages: Vec<Blockage>,
    /// One-cycle phase transients: (time, antenna); each applied to the highest satellite
    /// (in the samples when it falls in the sample-level stretch, else on the fast path).
    pub cycle_slips: Vec<(f64, usize)>,
    /// A data-bit transition at a wrong moment (time); applied to the highest satellite.
    pub bit_flip: Option<f64>,
}

/// What a run does.
#[derive(Clone, Debug)]
pub struct FlightConfig {
    /// Simulated flight, s.
    pub duration_s: f64,
    /// Attitude history.
    pub motion: MotionKind,
    /// Argument of latitude at t = 0, rad.
    pub u0: f64,
    /// GPS time offset from the almanac's time of applicability, s.
    pub gps_offset_s: f64,
    /// Initial body rates of the detumbling body, rad/s.
    pub detumble_rates: [f64; 3],
    /// Faults.
    pub faults: FaultPlan,
    /// Seed.
    pub seed: u64,
    /// Fine loop bandwidth, Hz.
    pub loop_bandwidth_hz: f32,
    /// The first stretch run through the sample-level chain ([`super::sample_level`]), s
    /// (0: the fast path from the start).
    pub sample_level_s: f64,
}

/// One record (every [`RECORD_S`]).
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// Time of the receiver's attitude epoch (its centre), s.
    pub t: f64,
    /// Source of the receiver's attitude.
    pub source: AttitudeSource,
    /// Receiver attitude error, body rotation vector `log(Ĉᵀ C)`, rad (NaN without attitude).
    pub error: Vector3<f64>,
    /// Receiver's 1σ per body axis, rad.
    pub sigma: Vector3<f64>,
    /// Fine filter error (NaN when not running), rad.
    pub fine_error: Vector3<f64>,
    /// Whether the fine filter is locked.
    pub fine_locked: bool,
    /// The bound per body axis, rad (NaN when fewer than 3 satellites).
    pub bound: Vector3<f64>,
    /// Satellites delivering observations.
    pub tracked: usize,
    /// Satellites used by the fine filter.
    pub used: usize,
    /// Satellites with fixed ambiguities.
    pub fixed: usize,
    /// Satellites above the reference antenna's mask.
    pub visible: usize,
    /// Antennas blocked (receiver's view).
    pub blocked: [bool; 3],
    /// Gyro bias estimate minus truth, rad/s.
    pub bias_error: Vector3<f64>,
}

/// A stage estimate's error at its own epoch.
#[derive(Clone, Copy, Debug)]
pub struct StageSample {
    /// Time, s.
    pub t: f64,
    /// Error, body rotation vector, rad.
    pub error: Vector3<f64>,
    /// 1σ per body axis, rad.
    pub sigma: Vector3<f64>,
}

/// Sky-plot point of one satellite.
#[derive(Clone, Copy, Debug)]
pub struct SkyPoint {
    /// Time, s.
    pub t: f64,
    /// PRN.
    pub prn: u8,
    /// Azimuth in the antenna plane, rad.
    pub azimuth: f64,
    /// Elevation above the antenna plane, rad.
    pub elevation: f64,
    /// C/N0 the channel reports (0 when not tracked), dB-Hz.
    pub cn0_dbhz: f64,
    /// Tracked (delivering observations).
    pub tracked: bool,
}

/// Everything a run records.
#[derive(Clone, Debug, Default)]
pub struct FlightRecord {
    /// Records every [`RECORD_S`].
    pub samples: Vec<Sample>,
    /// Snapshot solutions.
    pub snapshots: Vec<StageSample>,
    /// Rigid-body filter estimates.
    pub rigid: Vec<StageSample>,
    /// Receiver events, with the time of their epoch.
    pub events: Vec<(f64, ReceiverEvent)>,
    /// Sky points every second.
    pub sky: Vec<SkyPoint>,
    /// Truth: (time, PRN, rises) when a satellite crosses the reference antenna's mask.
    pub horizon: Vec<(f64, u8, bool)>,
    /// When the data-bit flip was injected (mid-bit of its satellite), s.
    pub bit_flip_s: Option<f64>,
    /// The cycle slips injected: time, antenna, PRN.
    pub slips: Vec<SampleSlip>,
    /// The PRN the bit flip was injected on.
    pub bit_flip_prn: Option<u8>,
    /// The true gyro biases at the end, rad/s, and the estimate.
    pub gyro_bias: (Vector3<f64>, Vector3<f64>),
    /// The receiver's gyro calibration report at the end.
    pub calibration: Option<gnss_attitude::receiver::CalibrationReport>,
    /// Wall time of the sample-level part and of the fast path, s.
    pub wall_s: (f64, f64),
    /// What the sample-level stretch saw (`None` without one).
    pub sample_stats: Option<SampleStats>,
    /// Length of the sample-level stretch, s.
    pub sample_level_s: f64,
}

/// `log(Ĉᵀ C)`: the body-frame rotation vector from the estimate to the truth, rad.
pub fn attitude_error(estimate: &Quaternion<f32>, truth: &Quaternion<f64>) -> Vector3<f64> {
    let e = Quaternion::new(
        f64::from(estimate.w),
        f64::from(estimate.x),
        f64::from(estimate.y),
        f64::from(estimate.z),
    );
    (e.conjugate() * *truth).to_rotation_vector()
}

fn sigma_of(cov: &Matrix3<f32>) -> Vector3<f64> {
    Vector3::new(
        f64::from(cov.m11.max(0.0)).sqrt(),
        f64::from(cov.m22.max(0.0)).sqrt(),
        f64::from(cov.m33.max(0.0)).sqrt(),
    )
}

fn nan3() -> Vector3<f64> {
    Vector3::repeat(f64::NAN)
}

/// The receiver configuration for the world's array and gyro.
pub fn receiver_config(world: &World, loop_bandwidth_hz: f32) -> ReceiverConfig {
    let antennas = world.antennas.map(|a| {
        [
            a.position.x as f32,
            a.position.y as f32,
            a.position.z as f32,
        ]
    });
    let gyro = GyroConfig::mems(
        GYRO_H as f32,
        GyroErrors::mems().pulse_weight.map(|p| p as f32),
    );
    // the line biases are unknown to the receiver: it resolves and estimates them
    let mut c = ReceiverConfig::gps_l1(antennas, Some(gyro));
    c.fine.loop_bandwidth_hz = loop_bandwidth_hz;
    c
}

/// Linear interpolation of the line of sight between two views (renormalized).
fn interpolate(a: &GpsView, b: &GpsView, f: f64) -> GpsView {
    let mut v = *a;
    let los = (a.los * (1.0 - f) + b.los * f).normalize();
    v.los = los;
    v.range = a.range * (1.0 - f) + b.range * f;
    v.range_rate = a.range_rate * (1.0 - f) + b.range_rate * f;
    v.doppler_hz = a.doppler_hz * (1.0 - f) + b.doppler_hz * f;
    v
}

/// Runs one flight: the sample-level chain for the first [`FlightConfig::sample_level_s`],
/// then the fast path from the channels it hands over.
pub fn fly(
    config: &FlightConfig,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<FlightRecord> {
    let mut world = World::new(
        config.motion,
        config.u0,
        config.gps_offset_s,
        config.detumble_rates,
    );
    world.blockages = config.faults.blockages.clone();
    let rcfg = receiver_config(&world, config.loop_bandwidth_hz);
    let mut rx = Box::new(
        Front::new(rcfg, SampleLevel::front_config())
            .map_err(|e| anyhow::anyhow!("receiver: {e}"))?,
    );
    let mut gyro = Gyro::new(GyroErrors::mems(), config.seed ^ 0x6779);
    let mut rng = rng(config.seed);
    let mut channels: BTreeMap<u8, EmulatedChannel> = BTreeMap::new();
    for e in world.sky.almanac.entries.iter().filter(|e| e.health == 0) {
        channels.insert(e.prn, EmulatedChannel::new(e.prn, &mut rng));
    }
    let mut record = FlightRecord {
        sample_level_s: config.sample_level_s,
        ..FlightRecord::default()
    };
    let sample_epochs = (config.sample_level_s / EPOCH_S).round() as u64;
    // the slips inside the sample-level stretch go into the scene, on the highest satellite
    for &(ts, antenna) in &config.faults.cycle_slips {
        if ts < config.sample_level_s {
            if let Some(prn) = highest(&world.satellites(ts)) {
                record.slips.push(SampleSlip {
                    start_s: ts,
                    antenna,
                    prn,
                });
            }
        }
    }
    let mut sample_level = if sample_epochs > 0 {
        Some(SampleLevel::new(
            &world,
            config.sample_level_s + 0.5,
            config.seed,
            &record.slips,
        ))
    } else {
        None
    };
    let epochs = (config.duration_s / EPOCH_S).round() as u64;
    let per_block = (AIDING_S / EPOCH_S).round() as u64;
    let mut views: (Vec<GpsView>, Vec<GpsView>) = (Vec::new(), Vec::new());
    let mut was_visible: BTreeMap<u8, bool> = BTreeMap::new();
    let started = std::time::Instant::now();
    for k in 0..epochs {
        let t0 = k as f64 * EPOCH_S;
        let tc = t0 + 0.5 * EPOCH_S;
        if k == sample_epochs {
            // hand-over: the chain's locked satellites continue on the fast path
            if let Some(sl) = sample_level.take() {
                for prn in locked(&rx) {
                    if let Some(ch) = channels.get_mut(&prn) {
                        ch.continue_tracking();
                        if let Some(edge) = sl.next_bit_edge_epoch(prn, t0) {
                            ch.align_bit_edges(edge);
                        }
                    }
                }
                // the fast path takes over: the core's channels close
                let prns: Vec<u8> = rx.channels().map(|c| c.prn.number()).collect();
                for p in prns.into_iter().filter_map(Prn::new) {
                    rx.release(p);
                }
                record.sample_stats = Some(sl.stats().clone());
                record.wall_s.0 = started.elapsed().as_secs_f64();
            }
        }
        let in_samples = k < sample_epochs;
        // gyro: the increment over [t0 − h, t0] before the epoch starting at t0
        let gyro_every = (GYRO_H / EPOCH_S).round() as u64;
        if k > 0 && k % gyro_every == 0 {
            let inc = gyro.increment(&world.motion, t0 - GYRO_H, GYRO_H, 2);
            if let Some(p) = inc.pulses {
                rx.receiver_mut()
                    .push_gyro_pulses(p)
                    .map_err(|e| anyhow::anyhow!("gyro: {e}"))?;
            }
        }
        if k % per_block == 0 {
            let t1 = t0 + AIDING_S;
            let a: Vec<GpsView> = world.sky.views(t0);
            let b: Vec<GpsView> = world.sky.views(t1);
            views = (a, b);
        }
        let f = (tc - (k - k % per_block) as f64 * EPOCH_S) / AIDING_S;
        let c_ib = world.c_ib(tc);
        let mut truths: Vec<SatTruth> = Vec::new();
        for (a, b) in views.0.iter().zip(views.1.iter()) {
            if a.occulted && b.occulted {
                continue;
            }
            let v = interpolate(a, b, f);
            truths.push(world.antenna_view(&v, &c_ib, tc));
        }
        // faults go to the highest satellite at their time
        if k % per_block == 0 {
            for &(ts, antenna) in &config.faults.cycle_slips {
                if ts >= config.sample_level_s && t0 + AIDING_S > ts && t0 <= ts {
                    if let Some(best) = highest(&truths) {
                        if let Some(ch) = channels.get_mut(&best) {
                            ch.transients.push(PhaseTransient {
                                antenna,
                                start_s: ts,
                                duration_s: 0.004,
                                cycles: 1.0,
                            });
                        }
                        record.slips.push(SampleSlip {
                            start_s: ts,
                            antenna,
                            prn: best,
                        });
                    }
                }
            }
            if let Some(tf) = config.faults.bit_flip {
                if record.bit_flip_prn.is_none() && t0 + AIDING_S >= tf && t0 <= tf {
                    if let Some(best) = highest(&truths) {
                        if let Some(ch) = channels.get_mut(&best) {
                            record.bit_flip_s = Some(ch.schedule_bit_flip(tf));
                        }
                        record.bit_flip_prn = Some(best);
                    }
                }
            }
        }
        // channel lives, horizon crossings
        for s in &truths {
            let sees = s.elevation[0] >= super::world::MASK_RAD && !s.view.occulted;
            let before = was_visible.insert(s.view.prn, sees).unwrap_or(sees);
            if before != sees && k > 0 {
                record.horizon.push((tc, s.view.prn, sees));
            }
            if in_samples {
                continue;
            }
            if let Some(ch) = channels.get_mut(&s.view.prn) {
                ch.advance(tc, s.visible[0]);
            }
        }
        // aiding for the channels that deliver or search, highest first
        if k % per_block == 0 {
            let mut wanted: Vec<&SatTruth> = truths
                .iter()
                .filter(|s| match &sample_level {
                    Some(_) if in_samples => Prn::new(s.view.prn).is_some_and(|p| rx.tracks(p)),
                    _ => channels
                        .get(&s.view.prn)
                        .is_some_and(|c| c.state != ChannelState::Idle),
                })
                .collect();
            wanted.sort_by(|a, b| b.elevation[0].total_cmp(&a.elevation[0]));
            wanted.truncate(MAX_SATELLITES);
            let aiding: Vec<SatelliteAiding> = wanted
                .iter()
                .map(|s| {
                    let prn = s.view.prn;
                    let (a, b) = (
                        views.0.iter().find(|v| v.prn == prn),
                        views.1.iter().find(|v| v.prn == prn),
                    );
                    let rate = match (a, b) {
                        (Some(a), Some(b)) => (b.los - a.los) / AIDING_S,
                        _ => Vector3::zeros(),
                    };
                    let los = a.map_or(s.view.los, |a| a.los);
                    SatelliteAiding {
                        prn,
                        epoch: k,
                        los: [los.x as f32, los.y as f32, los.z as f32],
                        los_rate: [rate.x as f32, rate.y as f32, rate.z as f32],
                    }
                })
                .collect();
            rx.receiver_mut()
                .set_aiding(&aiding)
                .map_err(|e| anyhow::anyhow!("aiding: {e}"))?;
        }
        // observations
        let line_bias = world.line_bias_rad;
        let mut tracked = 0;
        if let (Some(sl), true) = (sample_level.as_mut(), in_samples) {
            tracked += sl.epoch(k, &mut rx)?.observations as usize;
        }
        for s in truths.iter().filter(|_| !in_samples) {
            let Some(ch) = channels.get_mut(&s.view.prn) else {
                continue;
            };
            if !ch.delivering() {
                continue;
            }
            let psi = [0, 1, 2].map(|p| world.geometric_phase(p, &s.view.los, &c_ib));
            let obs = ch.observe(k, tc, s, psi, line_bias, &mut rng);
            match rx.receiver_mut().push_observation(k, &obs) {
                Ok(()) => tracked += 1,
                Err(gnss_attitude::receiver::ReceiverError::NoAiding) => {}
                Err(e) => anyhow::bail!("observation: {e}"),
            }
        }
        // records
        if (k + 1) % per_block == 0 {
            record_sample(&mut record, rx.receiver(), &world, &gyro, &truths, tracked);
            while let Some(e) = rx.receiver_mut().pop_event() {
                record.events.push(((e.epoch() as f64 + 0.5) * EPOCH_S, e));
            }
            if (k + 1) % 1000 == 0 {
                for s in &truths {
                    let ch = channels.get(&s.view.prn);
                    let (delivering, reported) = match &sample_level {
                        Some(_) if in_samples => {
                            let r = reported_cn0_dbhz(&rx, s.view.prn);
                            (r.is_some(), r.unwrap_or(0.0))
                        }
                        _ => (
                            ch.is_some_and(|c| c.delivering()),
                            ch.map_or(0.0, |c| c.reported_cn0_dbhz()),
                        ),
                    };
                    if s.elevation[0] > 0.0 {
                        record.sky.push(SkyPoint {
                            t: tc,
                            prn: s.view.prn,
                            azimuth: s.azimuth,
                            elevation: s.elevation[0],
                            cn0_dbhz: if delivering { reported } else { 0.0 },
                            tracked: delivering,
                        });
                    }
                }
            }
            if let Some(p) = progress {
                p.set_position(((k + 1) as f64 * EPOCH_S) as u64);
            }
        }
    }
    record.wall_s.1 = started.elapsed().as_secs_f64() - record.wall_s.0;
    if let Some(sl) = sample_level {
        record.sample_stats = Some(sl.stats().clone());
    }
    record.calibration = rx.receiver_mut().gyro_calibration();
    let b = gyro.current_errors();
    let est = rx.receiver_mut().gyro_bias();
    record.gyro_bias = (
        Vector3::new(b[6], b[7], b[8]),
        Vector3::new(f64::from(est[0]), f64::from(est[1]), f64::from(est[2])),
    );
    Ok(record)
}

fn highest(truths: &[SatTruth]) -> Option<u8> {
    truths
        .iter()
        .filter(|s| s.visible == [true, true, true])
        .max_by(|a, b| a.elevation[0].total_cmp(&b.elevation[0]))
        .map(|s| s.view.prn)
}

fn stage_error(world: &World, s: &StageEstimate) -> StageSample {
    let t = (s.epoch as f64 + 0.5) * EPOCH_S;
    StageSample {
        t,
        error: attitude_error(&s.q_rb, &world.motion.q_ib(t)),
        sigma: sigma_of(&s.covariance),
    }
}

fn record_sample(
    record: &mut FlightRecord,
    receiver: &AttitudeReceiver,
    world: &World,
    gyro: &Gyro,
    truths: &[SatTruth],
    tracked: usize,
) {
    let att = receiver.attitude();
    let t = (att.epoch as f64 + 0.5) * EPOCH_S;
    super::nmea::record(&att, world, t);
    let truth = world.motion.q_ib(t);
    let has = att.source != AttitudeSource::None;
    let (fine_error, fine_locked) = match receiver.fine_estimate() {
        Some(e) => (
            attitude_error(&e.q_rb, &truth),
            att.source == AttitudeSource::Fine,
        ),
        None => (nan3(), false),
    };
    // the bound over the satellites the receiver can use (tracked on all three antennas)
    let c_ib = world.c_ib(t);
    let usable: Vec<(Vector3<f64>, f64)> = truths
        .iter()
        .filter(|s| s.visible == [true, true, true])
        .map(|s| (c_ib.transpose() * s.view.los, s.cn0_dbhz[0]))
        .collect();
    let positions = world.antennas.map(|a| a.position);
    let bound = bound_rad(
        &positions,
        &usable,
        f64::from(receiver.config().fine.loop_bandwidth_hz),
    )
    .unwrap_or_else(nan3);
    let h = att.health;
    let b = gyro.current_errors();
    let est = receiver.gyro_bias();
    let bias_error = Vector3::new(
        f64::from(est[0]) - b[6],
        f64::from(est[1]) - b[7],
        f64::from(est[2]) - b[8],
    );
    record.samples.push(Sample {
        t,
        source: att.source,
        error: if has {
            attitude_error(&att.q_rb, &truth)
        } else {
            nan3()
        },
        sigma: if has {
            sigma_of(&att.covariance)
        } else {
            nan3()
        },
        fine_error,
        fine_locked,
        bound,
        tracked,
        used: usize::from(h.satellites_used),
        fixed: usize::from(h.satellites_fixed),
        visible: truths
            .iter()
            .filter(|s| s.elevation[0] >= super::world::MASK_RAD)
            .count(),
        blocked: h.antenna_blocked,
        bias_error,
    });
    if let Some(s) = receiver.snapshot_estimate() {
        let t = (s.epoch as f64 + 0.5) * EPOCH_S;
        if record
            .snapshots
            .last()
            .is_none_or(|l| (l.t - t).abs() > 1e-9)
        {
            record.snapshots.push(stage_error(world, &s));
        }
    }
    if let Some(s) = receiver.rigid_body_estimate() {
        let t = (s.epoch as f64 + 0.5) * EPOCH_S;
        if record.rigid.last().is_none_or(|l| (l.t - t).abs() > 1e-9) {
            record.rigid.push(stage_error(world, &s));
        }
    }
}
