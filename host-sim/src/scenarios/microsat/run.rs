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
use nalgebra::{Matrix3, Matrix5, Vector3};

use super::bound::bound_rad;
use super::fast_path::{rng, ChannelChange, EmulatedChannel, PhaseTransient, EPOCH_S};
use super::fast_search::{FastPathStats, FastSearch, SearchedSignal};
use super::navigation::{AidingSource, Navigation, NavigationRecord};
use super::sample_level::{
    locked, reported_cn0_dbhz, Front, SampleLevel, SampleSlip, SampleStats, SLIP_CYCLES,
    SLIP_DURATION_S,
};
use super::world::{Blockage, LineBiasTruth, MotionKind, NavigationError, SatTruth, World};
use crate::synth::quantize::Quantizer;
use crate::truth::attitude::AttitudeTruth;
use crate::truth::gyro::{Gyro, GyroErrors};
use crate::truth::sky::GpsView;
use crate::truth::tle::Tle;
use gnss_attitude::receiver::{AdapterConfig, NoiseFloor};
use gnss_attitude::signal::correlator::{EpochCorrelations, Iq, Taps};
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
    /// One-cycle phase turns of a slaved antenna ([`super::sample_level::SLIP_DURATION_S`]):
    /// (time, antenna); each applied to the highest satellite
    /// (in the samples when it falls in the sample-level stretch, else on the fast path).
    pub cycle_slips: Vec<(f64, usize)>,
    /// A data-bit transition at a wrong moment (time); applied to the highest satellite.
    pub bit_flip: Option<f64>,
    /// Gyro faults: what the gyro reports over an interval instead of the truth.
    pub gyro_faults: Vec<GyroFault>,
    /// Outages: every antenna blocked over `(start, end)`, s.
    pub outages: Vec<(f64, f64)>,
}

impl FaultPlan {
    /// Whether the plan injects nothing.
    pub fn is_empty(&self) -> bool {
        self.blockages.is_empty()
            && self.cycle_slips.is_empty()
            && self.bit_flip.is_none()
            && self.gyro_faults.is_empty()
            && self.outages.is_empty()
    }
}

/// A gyro fault over `[start, end)` (the samples whose interval starts inside it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GyroFault {
    /// Start, s.
    pub start: f64,
    /// End, s.
    pub end: f64,
    /// What the gyro reports.
    pub kind: GyroFaultKind,
}

/// What a faulty gyro reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GyroFaultKind {
    /// The true rate plus this rate, body axes, rad/s (e.g. 5 rad/s on x).
    RateOffset([f64; 3]),
    /// Nothing: every increment zero (a stuck gyro).
    Stuck,
}

impl GyroFault {
    /// The pulses the faulty gyro reports for an interval starting at `t` with true pulses
    /// `pulses` (pulse weight `weight`, rad; `h` the interval, s); `pulses` outside the fault.
    pub fn apply(&self, t: f64, h: f64, pulses: [i32; 3], weight: f64) -> [i32; 3] {
        if t < self.start || t >= self.end {
            return pulses;
        }
        match self.kind {
            GyroFaultKind::Stuck => [0; 3],
            GyroFaultKind::RateOffset(w) => [0, 1, 2].map(|a| {
                let extra = (w[a] * h / weight).round();
                (f64::from(pulses[a]) + extra).clamp(f64::from(i32::MIN), f64::from(i32::MAX))
                    as i32
            }),
        }
    }
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
    /// The attitude goes to the `--nmea` sink (the main flight; not the fault runs).
    pub nmea: bool,
    /// Where the receiver's lines of sight come from.
    pub aiding: AidingSource,
    /// The front end (`--front-end`): the sample-level stretch's quantizer, the fast path's
    /// searches' too, and its emulated correlators' C/N0 lowered by
    /// [`Quantizer::theory_loss_db`].
    pub front_end: Quantizer,
    /// A TLE flown instead of the built-in orbit (`--tle`; [`World::fly_tle`]).
    pub tle: Option<Tle>,
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
    /// The 1 Hz loop's noise `√(2Δf (J⁻¹)_aa)` per body axis ([`super::bound`]), rad (NaN
    /// when fewer than 3 satellites).
    pub loop_noise: Vector3<f64>,
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
    /// Line-bias estimate minus truth (B − A, C − A), wrapped to `(−π, π]`, rad.
    pub line_bias_error: [f64; 2],
    /// The receiver's 1σ of its line biases, rad.
    pub line_bias_sigma: [f64; 2],
    /// Carrier-phase information rate of the usable satellites on the attitude (body axes)
    /// and the two line biases, 1/(rad² s) ([`super::limit::information_rate`]).
    pub information: Matrix5<f64>,
    /// The physical limit per body axis at this record ([`super::limit`]), rad.
    pub limit: Vector3<f64>,
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
    /// What the fast path's searches and channels did.
    pub fast_path: FastPathStats,
    /// What the receiver's own navigation did.
    pub navigation: NavigationRecord,
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

/// Two estimates closer than this are of the same epoch, s.
const SAME_EPOCH_S: f64 = 1e-9;
/// Gyro increments per call (two-sample propagation).
const GYRO_SUBSAMPLES: usize = 2;
/// Epochs between two fast-path searches (whole seconds, as the sample-level stretch).
const SEARCH_EVERY_EPOCHS: u64 = 1000;
/// Epochs between two navigation fixes (1 s).
const NAVIGATION_EVERY_EPOCHS: u64 = 1000;
/// Epochs between two sky-plot points (1 s).
const SKY_EVERY_EPOCHS: u64 = 1000;
/// Extra seconds of samples synthesized beyond the sample-level stretch.
const SAMPLE_MARGIN_S: f64 = 0.5;
/// Seed salt of the gyro's noise.
const GYRO_SEED_SALT: u64 = 0x6779;
/// Seed salt of the RF chains' power-up line biases.
const LINE_BIAS_SEED_SALT: u64 = 0x6c62;
/// Seed salt of the navigation's orbit and ephemeris errors.
const NAVIGATION_SEED_SALT: u64 = 0x6e76;
/// Seed salt of the receiver's own navigation (its clock, code and Doppler noise).
const OWN_NAVIGATION_SEED_SALT: u64 = 0x6f6e;

/// Runs one flight: the sample-level chain for the first [`FlightConfig::sample_level_s`],
/// then the fast path from the channels it hands over.
pub fn fly(
    config: &FlightConfig,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<FlightRecord> {
    let mut flight = Flight::new(config)?;
    let epochs = (config.duration_s / EPOCH_S).round() as u64;
    for k in 0..epochs {
        flight.epoch(k)?;
        if (k + 1) % flight.per_block == 0 {
            if let Some(p) = progress {
                p.set_position(((k + 1) as f64 * EPOCH_S) as u64);
            }
        }
    }
    Ok(flight.finish())
}

/// The state of a flight between epochs: the world, the receiver and its inputs, the
/// emulated channels of the fast path, the sample-level chain while it runs, the records.
struct Flight<'a> {
    config: &'a FlightConfig,
    world: World,
    rx: Box<Front>,
    gyro: Gyro,
    rng: rand_chacha::ChaCha8Rng,
    channels: BTreeMap<u8, EmulatedChannel>,
    record: FlightRecord,
    /// The sample-level chain, until the hand-over.
    sample_level: Option<SampleLevel>,
    /// Epochs of the sample-level stretch.
    sample_epochs: u64,
    /// Epochs per aiding update (and record).
    per_block: u64,
    /// The satellites' views at the start and the end of the current aiding block (the
    /// world's truth, which the signals are synthesized from).
    views: (Vec<GpsView>, Vec<GpsView>),
    /// The same views as the flight computer's navigation predicts them (what the receiver is
    /// aided with).
    navigation_views: (Vec<GpsView>, Vec<GpsView>),
    /// Whether each satellite was above the reference antenna's mask.
    was_visible: BTreeMap<u8, bool>,
    /// The fast path's noise floor: the core's, from the emulated channels' noise taps.
    noise: NoiseFloor,
    /// The fast path's searches.
    search: FastSearch,
    /// The receiver's own navigation.
    navigation: Navigation,
    started: std::time::Instant,
}

/// One epoch's truth: its start and centre, the body attitude, the satellites in view.
struct EpochTruth {
    k: u64,
    t0: f64,
    tc: f64,
    c_ib: Matrix3<f64>,
    truths: Vec<SatTruth>,
    in_samples: bool,
}

impl<'a> Flight<'a> {
    fn new(config: &'a FlightConfig) -> Result<Self> {
        let mut world = World::new(
            config.motion,
            config.u0,
            config.gps_offset_s,
            config.detumble_rates,
        );
        world.blockages = config.faults.blockages.clone();
        for &(start, end) in &config.faults.outages {
            world.blockages.extend((0..3).map(|antenna| Blockage {
                antenna,
                start,
                end,
            }));
        }
        world.line_bias = LineBiasTruth::power_up(config.seed ^ LINE_BIAS_SEED_SALT);
        world.navigation = NavigationError::draw(config.seed ^ NAVIGATION_SEED_SALT);
        if let Some(tle) = &config.tle {
            world.fly_tle(tle, config.duration_s)?;
        }
        let navigation = Navigation::new(&world, config.seed ^ OWN_NAVIGATION_SEED_SALT)?;
        let rcfg = receiver_config(&world, config.loop_bandwidth_hz);
        let rx = Box::new(
            Front::new(rcfg, SampleLevel::front_config())
                .map_err(|e| anyhow::anyhow!("receiver: {e}"))?,
        );
        let gyro = Gyro::new(GyroErrors::mems(), config.seed ^ GYRO_SEED_SALT);
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
        record.slips = sample_slips(config, &world);
        let sample_level = (sample_epochs > 0).then(|| {
            SampleLevel::new(
                &world,
                &navigation,
                config.sample_level_s + SAMPLE_MARGIN_S,
                config.seed,
                &record.slips,
                config.front_end,
            )
        });
        Ok(Self {
            config,
            world,
            rx,
            gyro,
            rng,
            channels,
            record,
            sample_level,
            sample_epochs,
            per_block: (AIDING_S / EPOCH_S).round() as u64,
            views: (Vec::new(), Vec::new()),
            navigation_views: (Vec::new(), Vec::new()),
            was_visible: BTreeMap::new(),
            noise: NoiseFloor::new(AdapterConfig::default().noise_time_constant),
            search: FastSearch::new(config.seed, BTreeMap::new(), config.front_end)?,
            navigation,
            started: std::time::Instant::now(),
        })
    }

    /// Epoch `k`: hand-over, gyro, truth, faults, channels, aiding, observations, records.
    fn epoch(&mut self, k: u64) -> Result<()> {
        let t0 = k as f64 * EPOCH_S;
        if k == self.sample_epochs {
            self.hand_over(t0);
        }
        self.push_gyro(k, t0)?;
        let block_start = k % self.per_block == 0;
        if block_start {
            self.views = (
                self.world.sky.views(t0),
                self.world.sky.views(t0 + AIDING_S),
            );
            let predict = |views: &[GpsView], t: f64| -> Vec<GpsView> {
                views
                    .iter()
                    .map(|v| self.world.navigation.predicted(v, t))
                    .collect()
            };
            self.navigation_views = (
                predict(&self.views.0, t0),
                predict(&self.views.1, t0 + AIDING_S),
            );
        }
        let e = self.truth(k, t0);
        if block_start {
            self.inject_faults(&e);
        }
        self.advance_channels(&e);
        if !e.in_samples && k % SEARCH_EVERY_EPOCHS == 0 {
            self.search_fast_path(&e)?;
        }
        if k % NAVIGATION_EVERY_EPOCHS == 0 {
            let tracked = self.tracked_for_navigation(&e);
            let samples = self.sample_level.as_mut().filter(|_| e.in_samples);
            if let Some(sl) = samples {
                self.navigation.add_decoded(sl.take_decoded());
                let week = self.navigation.week();
                for &(prn, _) in &tracked {
                    for (t, transmit) in sl.take_transmit_times(prn, week) {
                        self.navigation
                            .check_transmit_time(&self.world, prn, t, &transmit);
                    }
                }
                let sl = &*sl;
                self.navigation.second(&self.world, e.t0, &tracked, |prn| {
                    Some(sl.subframe_synchronized(prn).unwrap_or(false))
                });
            } else {
                self.navigation
                    .second(&self.world, e.t0, &tracked, |_| None);
            }
        }
        if block_start {
            self.set_aiding(&e)?;
        }
        let tracked = self.observe(&e)?;
        // an epoch without any observation on the fast path (every antenna blocked, nothing
        // tracked) is closed by the flight computer's clock: the receiver coasts on the gyro
        // and its limits apply
        if tracked == 0 && !e.in_samples {
            self.rx.receiver_mut().close_through(k);
        }
        if (k + 1) % self.per_block == 0 {
            self.record_block(&e, tracked);
        }
        Ok(())
    }

    /// The hand-over: the chain's locked satellites continue on the fast path, the core's
    /// channels close.
    fn hand_over(&mut self, t0: f64) {
        let Some(mut sl) = self.sample_level.take() else {
            return;
        };
        self.navigation.add_decoded(sl.take_decoded());
        self.navigation
            .hand_over(|prn| sl.subframe_synchronized(prn).unwrap_or(false));
        for prn in locked(&self.rx) {
            let cn0 = reported_cn0_dbhz(&self.rx, prn).unwrap_or(0.0);
            if let Some(ch) = self.channels.get_mut(&prn) {
                ch.continue_tracking(t0, cn0);
                if let Some(edge) = sl.next_bit_edge_epoch(prn, t0) {
                    ch.align_bit_edges(edge);
                }
            }
        }
        let prns: Vec<u8> = self.rx.channels().map(|c| c.prn.number()).collect();
        for p in prns.into_iter().filter_map(Prn::new) {
            self.rx.release(p);
        }
        self.record.sample_stats = Some(sl.stats().clone());
        if let Ok(search) = FastSearch::new(
            self.config.seed,
            sl.failed_at().clone(),
            self.config.front_end,
        ) {
            self.search = search;
        }
        self.record.wall_s.0 = self.started.elapsed().as_secs_f64();
    }

    /// The gyro increment over `[t0 − h, t0]` before the epoch starting at `t0`.
    fn push_gyro(&mut self, k: u64, t0: f64) -> Result<()> {
        let gyro_every = (GYRO_H / EPOCH_S).round() as u64;
        if k > 0 && k % gyro_every == 0 {
            let inc = self
                .gyro
                .increment(&self.world.motion, t0 - GYRO_H, GYRO_H, GYRO_SUBSAMPLES);
            if let Some(mut p) = inc.pulses {
                let weight = GyroErrors::mems().pulse_weight.unwrap_or(1.0);
                for f in &self.config.faults.gyro_faults {
                    p = f.apply(t0 - GYRO_H, GYRO_H, p, weight);
                }
                self.rx
                    .receiver_mut()
                    .push_gyro_pulses(p)
                    .map_err(|e| anyhow::anyhow!("gyro: {e}"))?;
            }
        }
        Ok(())
    }

    /// The satellites not occulted at the epoch's centre, interpolated within the block.
    fn truth(&self, k: u64, t0: f64) -> EpochTruth {
        let tc = t0 + 0.5 * EPOCH_S;
        let f = (tc - (k - k % self.per_block) as f64 * EPOCH_S) / AIDING_S;
        let c_ib = self.world.c_ib(tc);
        let truths = self
            .views
            .0
            .iter()
            .zip(self.views.1.iter())
            .filter(|(a, b)| !(a.occulted && b.occulted))
            .map(|(a, b)| self.world.antenna_view(&interpolate(a, b, f), &c_ib, tc))
            .collect();
        EpochTruth {
            k,
            t0,
            tc,
            c_ib,
            truths,
            in_samples: k < self.sample_epochs,
        }
    }

    /// Cycle slips (after the sample-level stretch) and the bit flip go to the highest
    /// satellite at their time.
    fn inject_faults(&mut self, e: &EpochTruth) {
        let (t0, faults) = (e.t0, &self.config.faults);
        for &(ts, antenna) in &faults.cycle_slips {
            if ts < self.config.sample_level_s || t0 + AIDING_S <= ts || t0 > ts {
                continue;
            }
            let Some(best) = highest(&e.truths) else {
                continue;
            };
            if let Some(ch) = self.channels.get_mut(&best) {
                ch.transients.push(PhaseTransient {
                    antenna,
                    start_s: ts,
                    duration_s: SLIP_DURATION_S,
                    cycles: SLIP_CYCLES,
                });
            }
            self.record.slips.push(SampleSlip {
                start_s: ts,
                antenna,
                prn: best,
            });
        }
        if let Some(tf) = faults.bit_flip {
            if self.record.bit_flip_prn.is_none() && t0 + AIDING_S >= tf && t0 <= tf {
                if let Some(best) = highest(&e.truths) {
                    if let Some(ch) = self.channels.get_mut(&best) {
                        self.record.bit_flip_s = Some(ch.schedule_bit_flip(tf));
                    }
                    self.record.bit_flip_prn = Some(best);
                }
            }
        }
    }

    /// Horizon crossings (truth, for the metrics).
    fn advance_channels(&mut self, e: &EpochTruth) {
        for s in &e.truths {
            let sees = s.elevation[0] >= super::world::MASK_RAD && !s.view.occulted;
            let before = self.was_visible.insert(s.view.prn, sees).unwrap_or(sees);
            if before != sees && e.k > 0 {
                self.record.horizon.push((e.tc, s.view.prn, sees));
            }
        }
    }

    /// The fast path's searches at a whole second: the PRNs of the receiver's own search list
    /// without a channel and due, while channels are free; the world synthesizes each search
    /// block from its truth, the core's acquisition decides ([`super::fast_search`]).
    fn search_fast_path(&mut self, e: &EpochTruth) -> Result<()> {
        let t = e.t0;
        let mut running = self.channels.values().filter(|c| c.active()).count();
        for prn in SampleLevel::to_search(t, &self.rx, &self.world) {
            if running >= MAX_SATELLITES {
                break;
            }
            let Some(ch) = self.channels.get_mut(&prn) else {
                continue;
            };
            if ch.active() || !self.search.due(prn, t) {
                continue;
            }
            let rate = doppler_rate(&self.views, prn);
            let signal = e
                .truths
                .iter()
                .find(|s| s.view.prn == prn && s.visible[0])
                .map(|s| SearchedSignal {
                    // the analog signal: the search quantizes it with the front end
                    cn0_dbhz: s.cn0_dbhz[0],
                    doppler_hz: s.view.doppler_hz,
                    doppler_rate_hz_s: rate,
                });
            if self.search.search(prn, t, e.k, signal)? {
                ch.start(t);
                running += 1;
            }
        }
        Ok(())
    }

    /// Aiding for the channels that run (the receiver's channels), highest first.
    fn set_aiding(&mut self, e: &EpochTruth) -> Result<()> {
        let samples = self.sample_level.is_some() && e.in_samples;
        let elevation = |prn: u8| {
            e.truths
                .iter()
                .find(|s| s.view.prn == prn)
                .map_or(f64::NEG_INFINITY, |s| s.elevation[0])
        };
        let mut wanted: Vec<(u8, f64)> = if samples {
            e.truths
                .iter()
                .filter(|s| Prn::new(s.view.prn).is_some_and(|p| self.rx.tracks(p)))
                .map(|s| (s.view.prn, s.elevation[0]))
                .collect()
        } else {
            self.channels
                .values()
                .filter(|c| c.active())
                .map(|c| (c.prn, elevation(c.prn)))
                .collect()
        };
        wanted.sort_by(|a, b| b.1.total_cmp(&a.1));
        wanted.truncate(MAX_SATELLITES);
        let prns: Vec<u8> = wanted.iter().map(|&(prn, _)| prn).collect();
        let from_views = |views: &(Vec<GpsView>, Vec<GpsView>)| -> Vec<SatelliteAiding> {
            prns.iter()
                .filter_map(|&prn| aiding_for(prn, views, e.k))
                .collect()
        };
        let aiding = match self.config.aiding {
            AidingSource::Truth => from_views(&self.views),
            AidingSource::Own => {
                let predicted = from_views(&self.navigation_views);
                match self.navigation.aiding(&self.world, e.t0, e.k, &prns) {
                    Some(own) => own_first(&prns, own, predicted),
                    None => predicted,
                }
            }
        };
        self.rx
            .receiver_mut()
            .set_aiding(&aiding)
            .map_err(|e| anyhow::anyhow!("aiding: {e}"))
    }

    /// The satellites whose reference-antenna channel tracks (PRN, C/N0 in dB-Hz): the core's
    /// locked channels in the samples, the emulated channels that deliver on the fast path.
    fn tracked_for_navigation(&self, e: &EpochTruth) -> Vec<(u8, f64)> {
        let cn0 = |prn: u8| {
            e.truths
                .iter()
                .find(|s| s.view.prn == prn)
                .map(|s| (prn, s.cn0_dbhz[0] - self.config.front_end.theory_loss_db()))
        };
        if self.sample_level.is_some() && e.in_samples {
            locked(&self.rx).into_iter().filter_map(cn0).collect()
        } else {
            self.channels
                .values()
                .filter(|c| c.delivering())
                .filter_map(|c| cn0(c.prn))
                .collect()
        }
    }

    /// The epoch's observations (from the samples or the fast path); returns how many the
    /// receiver took.
    fn observe(&mut self, e: &EpochTruth) -> Result<usize> {
        let mut tracked = 0;
        if let (Some(sl), true) = (self.sample_level.as_mut(), e.in_samples) {
            tracked += sl.epoch(e.k, &mut self.rx, &self.world)?.observations as usize;
        }
        if e.in_samples {
            return Ok(tracked);
        }
        let line_bias = self.world.line_bias.at(e.tc);
        for ch in self.channels.values_mut().filter(|c| c.active()) {
            let sat = e
                .truths
                .iter()
                .find(|s| s.view.prn == ch.prn)
                .map(|s| s.after_front_end(self.config.front_end));
            let sat = sat.as_ref();
            let psi = sat.map_or([0.0; 3], |s| {
                [0, 1, 2].map(|p| self.world.geometric_phase(p, &s.view.los, &e.c_ib))
            });
            let (obs, noise, change) = ch.observe(e.k, e.tc, sat, psi, line_bias, &mut self.rng);
            if let ChannelChange::Lost { gone_s } = change {
                let st = &mut self.search.stats;
                st.losses += 1;
                st.loss_delays_s.extend(gone_s);
            }
            self.noise.add(&noise_taps(noise));
            // the noise variance the receiver measures, as its adapter does from samples
            let (Some(mut obs), Some(var)) = (
                obs,
                self.noise.variance(AdapterConfig::default().noise_min_taps),
            ) else {
                continue;
            };
            obs.noise_var = var[0];
            match self.rx.receiver_mut().push_observation(e.k, &obs) {
                Ok(()) => tracked += 1,
                Err(gnss_attitude::receiver::ReceiverError::NoAiding) => {}
                Err(err) => anyhow::bail!("observation: {err}"),
            }
        }
        Ok(tracked)
    }

    /// The records at the end of an aiding block: the sample, the events, the sky points.
    fn record_block(&mut self, e: &EpochTruth, tracked: usize) {
        record_sample(
            &mut self.record,
            self.rx.receiver(),
            &self.world,
            &self.gyro,
            &e.truths,
            tracked,
            self.config.nmea,
        );
        while let Some(ev) = self.rx.receiver_mut().pop_event() {
            self.record
                .events
                .push(((ev.epoch() as f64 + 0.5) * EPOCH_S, ev));
        }
        if (e.k + 1) % SKY_EVERY_EPOCHS == 0 {
            self.record_sky(e);
        }
    }

    /// One sky-plot point per satellite above the reference antenna's horizon.
    fn record_sky(&mut self, e: &EpochTruth) {
        let samples = self.sample_level.is_some() && e.in_samples;
        for s in &e.truths {
            let ch = self.channels.get(&s.view.prn);
            let (delivering, reported) = if samples {
                let r = reported_cn0_dbhz(&self.rx, s.view.prn);
                (r.is_some(), r.unwrap_or(0.0))
            } else {
                (
                    ch.is_some_and(|c| c.delivering()),
                    ch.map_or(0.0, |c| c.reported_cn0_dbhz()),
                )
            };
            if s.elevation[0] > 0.0 {
                self.record.sky.push(SkyPoint {
                    t: e.tc,
                    prn: s.view.prn,
                    azimuth: s.azimuth,
                    elevation: s.elevation[0],
                    cn0_dbhz: if delivering { reported } else { 0.0 },
                    tracked: delivering,
                });
            }
        }
    }

    /// The wall times, the sample-level statistics, the gyro calibration at the end.
    fn finish(mut self) -> FlightRecord {
        let mut record = std::mem::take(&mut self.record);
        self.attach_limit(&mut record);
        record.wall_s.1 = self.started.elapsed().as_secs_f64() - record.wall_s.0;
        if let Some(sl) = &self.sample_level {
            record.sample_stats = Some(sl.stats().clone());
        }
        record.fast_path = self.search.stats.clone();
        record.navigation = std::mem::take(&mut self.navigation.record);
        record.calibration = self.rx.receiver_mut().gyro_calibration();
        let b = self.gyro.current_errors();
        let est = self.rx.receiver_mut().gyro_bias();
        record.gyro_bias = (
            Vector3::new(b[6], b[7], b[8]),
            Vector3::new(f64::from(est[0]), f64::from(est[1]), f64::from(est[2])),
        );
        record
    }
}

impl Flight<'_> {
    /// The physical limit along the records: the truth's gyro error model and body rates, the
    /// information of the satellites all antennas saw.
    fn attach_limit(&self, record: &mut FlightRecord) {
        let deg_h = std::f64::consts::PI / 180.0 / 3600.0;
        let prior = super::limit::Prior {
            attitude_rad: 1.0,
            line_bias_rad: std::f64::consts::PI,
            line_bias_drift_rad_s: super::world::LINE_BIAS_DRIFT_MAX_RAD_S / 3f64.sqrt(),
            scale_misalignment: 2e-3,
            gyro_bias_rad_s: 50.0 * deg_h,
        };
        let motion = &self.world.motion;
        let records = record
            .samples
            .iter()
            .map(|s| (s.t, motion.omega_b(s.t), s.information));
        let sigma = super::limit::along(records, &prior, &GyroErrors::mems());
        for (s, l) in record.samples.iter_mut().zip(sigma) {
            s.limit = l;
        }
    }
}

/// The slips inside the sample-level stretch: they go into the scene, on the highest
/// satellite at their time.
fn sample_slips(config: &FlightConfig, world: &World) -> Vec<SampleSlip> {
    config
        .faults
        .cycle_slips
        .iter()
        .filter(|&&(ts, _)| ts < config.sample_level_s)
        .filter_map(|&(ts, antenna)| {
            highest(&world.satellites(ts)).map(|prn| SampleSlip {
                start_s: ts,
                antenna,
                prn,
            })
        })
        .collect()
}

/// The aiding of satellite `prn` at epoch `k`: its line of sight at the block's start and the
/// rate over the block (`None` when the views lack it).
/// The aiding of `prns` in their order: the receiver's own (from its fix and the decoded
/// ephemeris) where it has one, else the flight computer's prediction (almanac and onboard
/// orbit), so that a satellite that rose or was re-acquired is aided while its ephemeris is
/// still being decoded (18–36 s after lock).
fn own_first(
    prns: &[u8],
    own: Vec<SatelliteAiding>,
    predicted: Vec<SatelliteAiding>,
) -> Vec<SatelliteAiding> {
    prns.iter()
        .filter_map(|prn| {
            own.iter()
                .chain(&predicted)
                .find(|a| a.prn == *prn)
                .copied()
        })
        .collect()
}

fn aiding_for(prn: u8, views: &(Vec<GpsView>, Vec<GpsView>), k: u64) -> Option<SatelliteAiding> {
    let a = views.0.iter().find(|v| v.prn == prn)?;
    let rate = views
        .1
        .iter()
        .find(|v| v.prn == prn)
        .map_or(Vector3::zeros(), |b| (b.los - a.los) / AIDING_S);
    let los = a.los;
    Some(SatelliteAiding {
        prn,
        epoch: k,
        los: [los.x as f32, los.y as f32, los.z as f32],
        los_rate: [rate.x as f32, rate.y as f32, rate.z as f32],
    })
}

/// The Doppler rate of `prn` over the aiding block, Hz/s (0 when the views lack it).
fn doppler_rate(views: &(Vec<GpsView>, Vec<GpsView>), prn: u8) -> f64 {
    let find = |v: &[GpsView]| v.iter().find(|v| v.prn == prn).map(|v| v.doppler_hz);
    match (find(&views.0), find(&views.1)) {
        (Some(a), Some(b)) => (b - a) / AIDING_S,
        _ => 0.0,
    }
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
    nmea: bool,
) {
    let att = receiver.attitude();
    let t = (att.epoch as f64 + 0.5) * EPOCH_S;
    if nmea {
        super::nmea::record(&att, world, t);
    }
    let truth = world.motion.q_ib(t);
    let has = att.source != AttitudeSource::None;
    let (fine_error, fine_locked) = match receiver.fine_estimate() {
        Some(e) => (
            attitude_error(&e.q_rb, &truth),
            att.source == AttitudeSource::Fine,
        ),
        None => (nan3(), false),
    };
    let loop_noise = bound_now(
        world,
        truths,
        t,
        f64::from(receiver.config().fine.loop_bandwidth_hz),
    );
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
        loop_noise,
        tracked,
        used: usize::from(h.satellites_used),
        fixed: usize::from(h.satellites_fixed),
        visible: truths
            .iter()
            .filter(|s| s.elevation[0] >= super::world::MASK_RAD)
            .count(),
        blocked: h.antenna_blocked,
        bias_error,
        line_bias_error: line_bias_error(&h.line_bias_rad, &world.line_bias.differences(t)),
        line_bias_sigma: h.line_bias_sigma_rad.map(f64::from),
        information: information_now(world, truths, t),
        limit: nan3(),
    });
    record_stages(record, receiver, world);
}

/// The bound at `t` over the satellites the receiver can use (tracked on all three antennas),
/// rad per body axis (NaN when it is singular).
fn bound_now(world: &World, truths: &[SatTruth], t: f64, bandwidth_hz: f64) -> Vector3<f64> {
    let c_ib = world.c_ib(t);
    let usable: Vec<(Vector3<f64>, f64)> = truths
        .iter()
        .filter(|s| s.visible == [true, true, true])
        .map(|s| (c_ib.transpose() * s.view.los, s.cn0_dbhz[0]))
        .collect();
    let positions = world.antennas.map(|a| a.position);
    bound_rad(&positions, &usable, bandwidth_hz).unwrap_or_else(nan3)
}

/// One epoch's correlations carrying only the noise taps of A, B, C (what the noise floor
/// reads).
fn noise_taps(noise: [Iq; 3]) -> EpochCorrelations<3> {
    EpochCorrelations {
        taps: noise.map(|n| Taps {
            noise: n,
            ..Taps::default()
        }),
        samples: 0,
        first_sample: 0,
        code_phase_at_first: 0,
        carrier_phase_at_first: 0,
        complete: true,
    }
}

/// The carrier-phase information rate at `t` of the satellites at least two antennas receive.
fn information_now(world: &World, truths: &[SatTruth], t: f64) -> Matrix5<f64> {
    let c_ib = world.c_ib(t);
    let usable: Vec<super::limit::Satellite> = truths
        .iter()
        .map(|s| super::limit::Satellite {
            los_body: c_ib.transpose() * s.view.los,
            cn0_dbhz: s.cn0_dbhz[0],
            visible: s.visible,
        })
        .collect();
    let positions = world.antennas.map(|a| a.position);
    super::limit::information_rate(&positions, &usable)
}

/// `estimate − truth` per slave chain, wrapped to `(−π, π]` (a bias is defined modulo a cycle
/// together with the integers), rad.
fn line_bias_error(estimate: &[f32; 2], truth: &[f64; 2]) -> [f64; 2] {
    use std::f64::consts::{PI, TAU};
    [0, 1].map(|p| {
        let e = (f64::from(estimate[p]) - truth[p]).rem_euclid(TAU);
        if e > PI {
            e - TAU
        } else {
            e
        }
    })
}

/// The snapshot and rigid-body estimates, each once per epoch of its own.
fn record_stages(record: &mut FlightRecord, receiver: &AttitudeReceiver, world: &World) {
    if let Some(s) = receiver.snapshot_estimate() {
        let t = (s.epoch as f64 + 0.5) * EPOCH_S;
        if record
            .snapshots
            .last()
            .is_none_or(|l| (l.t - t).abs() > SAME_EPOCH_S)
        {
            record.snapshots.push(stage_error(world, &s));
        }
    }
    if let Some(s) = receiver.rigid_body_estimate() {
        let t = (s.epoch as f64 + 0.5) * EPOCH_S;
        if record
            .rigid
            .last()
            .is_none_or(|l| (l.t - t).abs() > SAME_EPOCH_S)
        {
            record.rigid.push(stage_error(world, &s));
        }
    }
}
