//! From a flight's records to the numbers: per stage time to first fix, error RMS and maximum
//! per body axis, availability, satellites; the bound; and each injected fault's detection and
//! recovery.

use gnss_attitude::receiver::{AttitudeSource, ReceiverEvent};
use nalgebra::Vector3;

use super::run::{FlightRecord, Sample, StageSample};

/// Time after the fine filter's first lock from which errors count as converged, s.
pub const SETTLE_S: f64 = 10.0;

/// Statistics of one stage.
#[derive(Clone, Debug, Default)]
pub struct StageStats {
    /// Stage name.
    pub name: &'static str,
    /// Time of its first output, s.
    pub first_s: Option<f64>,
    /// RMS error per body axis, rad.
    pub rms: Vector3<f64>,
    /// Largest |error| per body axis, rad.
    pub max: Vector3<f64>,
    /// RMS of its own 1σ per axis, rad.
    pub sigma_rms: Vector3<f64>,
    /// Fraction of the flight with an output of this stage.
    pub availability: f64,
    /// Samples in the statistics.
    pub count: usize,
    /// Mean number of satellites the stage used.
    pub satellites: f64,
}

crate::metrics! {
    /// One injected (or natural) fault's outcome.
    pub struct FaultOutcome {
        /// The fault.
        #[metric(unit = "")] pub name: String,
        /// Whether the receiver reported it.
        #[metric(unit = "")] pub detected: bool,
        /// From the fault's end until the receiver had recovered (null: never).
        #[metric(unit = "s")] pub recovered_s: Option<f64>,
        /// When it happened.
        #[metric(unit = "s")] pub at_s: f64,
        /// What was detected and done.
        #[metric(unit = "")] pub detail: String,
    }
}

/// Everything the scenario reports.
#[derive(Clone, Debug)]
pub struct FlightMetrics {
    /// Time to first fix (first attitude of any source), s.
    pub ttff_s: f64,
    /// Time the fine filter first locked, s.
    pub fine_lock_s: f64,
    /// Start of the converged stretch, s.
    pub converged_from_s: f64,
    /// The receiver's attitude after convergence.
    pub receiver: StageStats,
    /// Per stage.
    pub stages: Vec<StageStats>,
    /// RMS of the 1 Hz loop's noise over the converged stretch, per body axis, rad.
    pub loop_noise: Vector3<f64>,
    /// RMS of the physical limit over the converged stretch, per body axis, rad.
    pub limit: Vector3<f64>,
    /// The receiver's reported σ against its error after convergence.
    pub consistency: Consistency,
    /// The line biases' estimation.
    pub line_bias: LineBiasStats,
    /// Fraction of the flight with an attitude (any source).
    pub availability: f64,
    /// Satellites tracked: mean, min, max (after the first fix).
    pub tracked: (f64, usize, usize),
    /// Faults.
    pub faults: Vec<FaultOutcome>,
    /// Gyro bias estimate minus truth at the end, °/h.
    pub gyro_bias_error: Vector3<f64>,
    /// True gyro bias at the end, °/h.
    pub gyro_bias_truth: Vector3<f64>,
    /// The converged receiver attitude split by input path: while the sample-level chain fed
    /// the receiver, and on the fast path after it.
    pub by_path: [PathStats; 2],
    /// How often the reported σ covers the error, over every record with an attitude.
    pub coverage: SigmaCoverage,
    /// The same over the separate fault runs (`None`: none flown).
    pub fault_runs_coverage: Option<SigmaCoverage>,
}

/// How often the receiver's reported σ covers its error: the records with an attitude whose
/// error is within 3σ on every body axis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SigmaCoverage {
    /// Records with an attitude.
    pub records: usize,
    /// Of them, error within 3σ on every axis.
    pub within_3sigma: usize,
    /// Largest `|e_a| / σ_a` over the records and axes.
    pub worst_ratio: f64,
}

impl SigmaCoverage {
    /// The records of `samples` with an attitude.
    pub fn of(samples: &[Sample]) -> Self {
        let mut c = Self::default();
        for s in samples.iter().filter(|s| has_attitude(s)) {
            let ratio = (0..3)
                .map(|a| s.error[a].abs() / s.sigma[a].max(1e-12))
                .fold(0.0, f64::max);
            c.records += 1;
            c.within_3sigma += usize::from(ratio <= 3.0);
            c.worst_ratio = c
                .worst_ratio
                .max(if ratio.is_nan() { f64::INFINITY } else { ratio });
        }
        c
    }

    /// Both sets of records together.
    pub fn merge(self, other: Self) -> Self {
        Self {
            records: self.records + other.records,
            within_3sigma: self.within_3sigma + other.within_3sigma,
            worst_ratio: self.worst_ratio.max(other.worst_ratio),
        }
    }

    /// The fraction within 3σ (NaN without records).
    pub fn fraction(&self) -> f64 {
        if self.records == 0 {
            f64::NAN
        } else {
            self.within_3sigma as f64 / self.records as f64
        }
    }
}

/// The converged receiver attitude on one input path.
#[derive(Clone, Copy, Debug)]
pub struct PathStats {
    /// RMS error per body axis, rad.
    pub rms: Vector3<f64>,
    /// RMS of the loop noise, rad.
    pub loop_noise: Vector3<f64>,
    /// RMS of the physical limit, rad.
    pub limit: Vector3<f64>,
    /// Records.
    pub count: usize,
}

/// Whether the receiver's σ tells its error: the normalized estimation error squared
/// `NEES = Σ_a (e_a/σ_a)²` (3 degrees of freedom, per-axis σ) over the converged records.
#[derive(Clone, Copy, Debug, Default)]
pub struct Consistency {
    /// Mean NEES (3 for a consistent σ).
    pub nees_mean: f64,
    /// Fraction of records inside the two-sided 95 % band of χ²₃.
    pub nees_in_band: f64,
}

/// The line biases (B − A, C − A) against the truth.
#[derive(Clone, Copy, Debug, Default)]
pub struct LineBiasStats {
    /// RMS error after convergence, rad.
    pub rms_rad: [f64; 2],
    /// Error at the end, rad.
    pub final_rad: [f64; 2],
    /// First time from which both errors stay within [`LINE_BIAS_CONVERGED_RAD`] for
    /// [`LINE_BIAS_HOLD_S`], s (`None`: never).
    pub converged_s: Option<f64>,
}

/// The two-sided 95 % band of χ² with 3 degrees of freedom.
const CHI2_3_BAND: (f64, f64) = (0.2158, 9.348);
/// A line-bias error below this counts as converged, rad (its attitude effect on the 0.5 m
/// triangle is ~λ/(2π·0.5 m) ≈ 0.06 of it: 3e-3 rad of attitude).
pub const LINE_BIAS_CONVERGED_RAD: f64 = 0.05;
/// How long the line-bias error must stay converged, s.
pub const LINE_BIAS_HOLD_S: f64 = 10.0;

fn rms_max<'a>(
    errors: impl Iterator<Item = &'a Vector3<f64>>,
) -> (Vector3<f64>, Vector3<f64>, usize) {
    let (mut s, mut m, mut n) = (Vector3::zeros(), Vector3::zeros(), 0usize);
    for e in errors.filter(|e| e.iter().all(|v| v.is_finite())) {
        s += e.component_mul(e);
        m = m.zip_map(e, |a: f64, b: f64| a.max(b.abs()));
        n += 1;
    }
    if n == 0 {
        return (Vector3::repeat(f64::NAN), Vector3::repeat(f64::NAN), 0);
    }
    ((s / n as f64).map(f64::sqrt), m, n)
}

fn stage_stats(
    name: &'static str,
    samples: &[StageSample],
    from: f64,
    duration: f64,
    interval: f64,
) -> StageStats {
    let kept: Vec<&StageSample> = samples.iter().filter(|s| s.t >= from).collect();
    let (rms, max, count) = rms_max(kept.iter().map(|s| &s.error));
    let (sigma_rms, _, _) = rms_max(kept.iter().map(|s| &s.sigma));
    StageStats {
        name,
        first_s: samples.first().map(|s| s.t),
        rms,
        max,
        sigma_rms,
        availability: (samples.len() as f64 * interval / duration).min(1.0),
        count,
        satellites: f64::NAN,
    }
}

/// Record interval of the receiver's attitude and the stages at 10 Hz, s.
const RECORD_INTERVAL_S: f64 = 0.1;
/// Interval of the snapshot solutions (cold start, 1 Hz), s.
const SNAPSHOT_INTERVAL_S: f64 = 1.0;
/// The rigid-body filter's errors count from this long after its first estimate, s.
const RIGID_SETTLE_S: f64 = 30.0;
/// rad/s to °/h.
const DEG_PER_H: f64 = 180.0 / std::f64::consts::PI * 3600.0;

fn has_attitude(s: &Sample) -> bool {
    s.source != AttitudeSource::None
}

/// The receiver's attitude after `from`, and its availability over the flight.
fn receiver_stats(samples: &[Sample], ttff: f64, from: f64) -> StageStats {
    let converged = samples.iter().filter(|s| s.t >= from && has_attitude(s));
    let (rms, max, count) = rms_max(converged.clone().map(|s| &s.error));
    let (sigma_rms, _, _) = rms_max(converged.map(|s| &s.sigma));
    let n = samples.len().max(1) as f64;
    StageStats {
        name: "receiver",
        first_s: Some(ttff),
        rms,
        max,
        sigma_rms,
        availability: samples.iter().filter(|s| has_attitude(s)).count() as f64 / n,
        count,
        satellites: f64::NAN,
    }
}

/// The receiver's records where `keep` holds, as a stage's samples.
fn stage_samples(samples: &[Sample], keep: fn(&Sample) -> bool, fine: bool) -> Vec<StageSample> {
    samples
        .iter()
        .filter(|s| keep(s))
        .map(|s| StageSample {
            t: s.t,
            error: if fine { s.fine_error } else { s.error },
            sigma: s.sigma,
        })
        .collect()
}

/// Per stage: snapshot, the fine filter (locked, after convergence), rigid body, gyro coast.
fn stages(
    record: &FlightRecord,
    ttff: f64,
    fine_lock: f64,
    from: f64,
    duration: f64,
) -> Vec<StageStats> {
    let samples = &record.samples;
    let fine_samples = stage_samples(
        samples,
        |s| s.fine_locked && s.source == AttitudeSource::Fine,
        true,
    );
    let mut fine = stage_stats(
        "one-stage (fine)",
        &fine_samples,
        from,
        duration,
        RECORD_INTERVAL_S,
    );
    fine.first_s = Some(fine_lock);
    let coast = stage_samples(samples, |s| s.source == AttitudeSource::GyroCoast, false);
    let mut stages = vec![
        stage_stats(
            "snapshot (cold start, 1 Hz)",
            &record.snapshots,
            ttff,
            duration,
            SNAPSHOT_INTERVAL_S,
        ),
        fine,
        stage_stats(
            "rigid-body (baselines + Doppler)",
            &record.rigid,
            record
                .rigid
                .first()
                .map_or(f64::NAN, |s| s.t + RIGID_SETTLE_S),
            duration,
            RECORD_INTERVAL_S,
        ),
        stage_stats("gyro coast", &coast, 0.0, duration, RECORD_INTERVAL_S),
    ];
    // the satellites each stage used, averaged after the first fix
    let after_fix: Vec<&Sample> = samples.iter().filter(|s| s.t >= ttff).collect();
    let fixed = mean_over(&after_fix, &|s| Some(s.fixed as f64));
    stages[0].satellites = fixed;
    stages[1].satellites = mean_over(&after_fix, &|s| {
        (s.fine_locked && s.used > 0).then_some(s.used as f64)
    });
    stages[2].satellites = fixed;
    stages
}

/// The mean of `f` over `samples` where it is defined (NaN when nowhere).
fn mean_over(samples: &[&Sample], f: &dyn Fn(&Sample) -> Option<f64>) -> f64 {
    let v: Vec<f64> = samples.iter().filter_map(|s| f(s)).collect();
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// Satellites tracked after the first fix: mean, min, max.
fn tracked_counts(after_fix: &[&Sample]) -> (f64, usize, usize) {
    if after_fix.is_empty() {
        return (0.0, 0, 0);
    }
    (
        after_fix.iter().map(|s| s.tracked as f64).sum::<f64>() / after_fix.len() as f64,
        after_fix.iter().map(|s| s.tracked).min().unwrap_or(0),
        after_fix.iter().map(|s| s.tracked).max().unwrap_or(0),
    )
}

/// The converged receiver attitude on one input path.
fn by_path(converged: &[&Sample], sample_level_s: f64, on_samples: bool) -> PathStats {
    let part: Vec<&&Sample> = converged
        .iter()
        .filter(|s| has_attitude(s) && (s.t < sample_level_s) == on_samples)
        .collect();
    let (rms, _, count) = rms_max(part.iter().map(|s| &s.error));
    PathStats {
        rms,
        loop_noise: rms_max(part.iter().map(|s| &s.loop_noise)).0,
        limit: rms_max(part.iter().map(|s| &s.limit)).0,
        count,
    }
}

/// NEES statistics of the converged records with an attitude.
fn consistency(converged: &[&Sample]) -> Consistency {
    let nees: Vec<f64> = converged
        .iter()
        .filter(|s| has_attitude(s))
        .map(|s| {
            (0..3)
                .map(|a| (s.error[a] / s.sigma[a]).powi(2))
                .sum::<f64>()
        })
        .filter(|v| v.is_finite())
        .collect();
    let n = nees.len().max(1) as f64;
    Consistency {
        nees_mean: nees.iter().sum::<f64>() / n,
        nees_in_band: nees
            .iter()
            .filter(|v| (CHI2_3_BAND.0..=CHI2_3_BAND.1).contains(*v))
            .count() as f64
            / n,
    }
}

/// The line biases' errors: RMS after `from`, at the end, and when they converged.
fn line_bias_stats(samples: &[Sample], from: f64) -> LineBiasStats {
    let within = |s: &Sample| {
        s.line_bias_error
            .iter()
            .all(|e| e.abs() <= LINE_BIAS_CONVERGED_RAD)
    };
    let mut start: Option<f64> = None;
    let mut converged_s = None;
    for s in samples {
        match (within(s), start) {
            (true, None) => start = Some(s.t),
            (false, _) => start = None,
            (true, Some(t0)) if s.t - t0 >= LINE_BIAS_HOLD_S => {
                converged_s = Some(t0);
                break;
            }
            _ => {}
        }
    }
    let after: Vec<&Sample> = samples.iter().filter(|s| s.t >= from).collect();
    let rms = [0, 1].map(|p| {
        let v: Vec<f64> = after.iter().map(|s| s.line_bias_error[p]).collect();
        (v.iter().map(|e| e * e).sum::<f64>() / v.len().max(1) as f64).sqrt()
    });
    LineBiasStats {
        rms_rad: rms,
        final_rad: samples.last().map_or([f64::NAN; 2], |s| s.line_bias_error),
        converged_s,
    }
}

/// The metrics of one flight of `duration` seconds.
pub fn evaluate(record: &FlightRecord, duration: f64) -> FlightMetrics {
    let samples = &record.samples;
    let ttff = samples
        .iter()
        .find(|s| has_attitude(s))
        .map_or(f64::NAN, |s| s.t);
    let fine_lock = record
        .events
        .iter()
        .find(|(_, e)| matches!(e, ReceiverEvent::FineLocked { .. }))
        .map_or(f64::NAN, |(t, _)| *t);
    let from = fine_lock + SETTLE_S;
    let converged: Vec<&Sample> = samples.iter().filter(|s| s.t >= from).collect();
    let with_attitude: Vec<&Sample> = converged
        .iter()
        .copied()
        .filter(|s| has_attitude(s))
        .collect();
    let (loop_noise, _, _) = rms_max(with_attitude.iter().map(|s| &s.loop_noise));
    let (limit, _, _) = rms_max(with_attitude.iter().map(|s| &s.limit));
    let after_fix: Vec<&Sample> = samples.iter().filter(|s| s.t >= ttff).collect();
    let mut receiver = receiver_stats(samples, ttff, from);
    receiver.satellites = mean_over(&after_fix, &|s| Some(s.tracked as f64));
    FlightMetrics {
        by_path: [
            by_path(&converged, record.sample_level_s, true),
            by_path(&converged, record.sample_level_s, false),
        ],
        ttff_s: ttff,
        fine_lock_s: fine_lock,
        converged_from_s: from,
        availability: receiver.availability,
        receiver,
        stages: stages(record, ttff, fine_lock, from, duration),
        loop_noise,
        limit,
        consistency: consistency(&converged),
        line_bias: line_bias_stats(samples, from),
        tracked: tracked_counts(&after_fix),
        faults: Vec::new(),
        coverage: SigmaCoverage::of(samples),
        fault_runs_coverage: None,
        gyro_bias_error: (record.gyro_bias.1 - record.gyro_bias.0) * DEG_PER_H,
        gyro_bias_truth: record.gyro_bias.0 * DEG_PER_H,
    }
}

/// Degrees.
pub fn deg(v: &Vector3<f64>) -> [f64; 3] {
    [v.x.to_degrees(), v.y.to_degrees(), v.z.to_degrees()]
}

/// First time `≥ from` after which the receiver's attitude comes from the fine filter with its
/// error inside 3σ on every axis for at least `hold` seconds; seconds after `from`.
pub fn attitude_recovery(samples: &[Sample], from: f64, hold: f64) -> Option<f64> {
    let ok = |s: &Sample| {
        s.source == AttitudeSource::Fine
            && (0..3).all(|a| s.error[a].abs() <= 3.0 * s.sigma[a].max(1e-9))
    };
    let mut start: Option<f64> = None;
    for s in samples.iter().filter(|s| s.t >= from) {
        if ok(s) {
            let t0 = *start.get_or_insert(s.t);
            if s.t - t0 >= hold {
                return Some(t0 - from);
            }
        } else {
            start = None;
        }
    }
    None
}

/// How long the attitude must stay within 3σ to count as recovered, s.
const RECOVERY_HOLD_S: f64 = 1.0;
/// Windows in which the receiver's reaction to a fault is looked for, s after the fault.
struct Windows {
    /// A setting satellite lost: from this long before it sets...
    lost_before: f64,
    /// ... to this long after.
    lost: f64,
    /// A rising satellite's first observation.
    acquired: f64,
    /// A rising satellite's ambiguities fixed.
    fixed: f64,
    /// An antenna blockage detected.
    blocked: f64,
    /// A blocked antenna restored (after the blockage's end).
    restored: f64,
    /// A cycle slip found.
    slip_found: f64,
    /// A bit flip flagged.
    bit_flagged: f64,
}

const WINDOW: Windows = Windows {
    lost_before: 0.2,
    lost: 3.0,
    acquired: 10.0,
    fixed: 20.0,
    blocked: 1.0,
    restored: 5.0,
    slip_found: 3.0,
    bit_flagged: 0.1,
};

/// Antenna names.
const ANTENNA: [&str; 3] = ["A", "B", "C"];

fn never_or(v: Option<f64>, f: impl Fn(f64) -> String) -> String {
    v.map_or("never".into(), f)
}

/// The record's events, searched by time window.
struct Events<'a> {
    record: &'a FlightRecord,
}

impl Events<'_> {
    /// The largest |error| (°) of the records in `[from, to]` with an attitude, and whether
    /// every one of them was inside 3σ on every axis.
    fn worst_against_sigma(&self, from: f64, to: f64) -> (f64, bool) {
        let inside = |s: &Sample| (0..3).all(|a| s.error[a].abs() <= 3.0 * s.sigma[a]);
        self.record
            .samples
            .iter()
            .filter(|s| s.t >= from && s.t <= to && has_attitude(s))
            .fold((0.0, true), |(w, ok), s| {
                (w.max(s.error.amax().to_degrees()), ok && inside(s))
            })
    }

    /// The time of the first event in `[from, to]` that satisfies `pred`.
    fn find(&self, from: f64, to: f64, pred: &dyn Fn(&ReceiverEvent) -> bool) -> Option<f64> {
        self.record
            .events
            .iter()
            .find(|(t, e)| *t >= from && *t <= to && pred(e))
            .map(|(t, _)| *t)
    }

    /// Seconds after `from` until the fine attitude is back within 3σ.
    fn recovery(&self, from: f64) -> Option<f64> {
        attitude_recovery(&self.record.samples, from, RECOVERY_HOLD_S)
    }
}

/// The first satellite setting below the mask after `after_s`.
fn satellite_setting(ev: &Events, after_s: f64) -> Option<FaultOutcome> {
    let &(ts, prn, _) = ev
        .record
        .horizon
        .iter()
        .find(|(t, _, rises)| *t > after_s && !rises)?;
    let lost = ev.find(
        ts - WINDOW.lost_before,
        ts + WINDOW.lost,
        &|e| matches!(e, ReceiverEvent::SatelliteLost { prn: p, .. } if *p == prn),
    );
    let att = ev.recovery(ts);
    Some(FaultOutcome {
        name: "satellite setting".into(),
        detected: lost.is_some(),
        recovered_s: lost.zip(att).map(|(l, a)| (l - ts).max(a)),
        at_s: ts,
        detail: format!(
            "PRN {prn} set below the 10° mask at {ts:.1} s; channel lost and slot released {} s later; fine attitude within 3σ after {} s",
            never_or(lost, |l| format!("{:.2}", l - ts)),
            never_or(att, |a| format!("{a:.1}"))
        ),
    })
}

/// The first satellite rising above the mask after `after_s`.
fn satellite_rising(ev: &Events, after_s: f64) -> Option<FaultOutcome> {
    let &(tr, prn, _) = ev
        .record
        .horizon
        .iter()
        .find(|(t, _, rises)| *t > after_s && *rises)?;
    let acquired = ev.find(
        tr,
        tr + WINDOW.acquired,
        &|e| matches!(e, ReceiverEvent::SatelliteAcquired { prn: p, .. } if *p == prn),
    );
    let fixed = ev.find(
        tr,
        tr + WINDOW.fixed,
        &|e| matches!(e, ReceiverEvent::AmbiguityFixed { prn: p, .. } if *p == prn),
    );
    Some(FaultOutcome {
        name: "satellite rising".into(),
        detected: acquired.is_some(),
        recovered_s: fixed.map(|f| f - tr),
        at_s: tr,
        detail: format!(
            "PRN {prn} rose above the mask at {tr:.1} s; first observation {} s later, ambiguities fixed from the fine attitude (satellite in every stage) {} s later",
            never_or(acquired, |a| format!("{:.2}", a - tr)),
            never_or(fixed, |f| format!("{:.2}", f - tr))
        ),
    })
}

/// An antenna blockage: detected, coasted on the gyro, restored.
fn blockage(ev: &Events, b: &super::world::Blockage) -> FaultOutcome {
    let antenna = b.antenna as u8;
    let blocked = ev.find(
        b.start,
        b.start + WINDOW.blocked,
        &|e| matches!(e, ReceiverEvent::AntennaBlocked { antenna: a, .. } if *a == antenna),
    );
    let restored = ev.find(
        b.end,
        b.end + WINDOW.restored,
        &|e| matches!(e, ReceiverEvent::AntennaRestored { antenna: a, .. } if *a == antenna),
    );
    let att = ev.recovery(b.end);
    let worst = ev
        .record
        .samples
        .iter()
        .filter(|s| s.t >= b.start && s.t < b.end)
        .map(|s| s.error.amax())
        .fold(0.0f64, f64::max)
        .to_degrees();
    FaultOutcome {
        name: format!(
            "antenna {} blocked for {:.0} s",
            ANTENNA[b.antenna.min(2)],
            b.end - b.start
        ),
        detected: blocked.is_some(),
        recovered_s: restored.zip(att).map(|(r, a)| (r - b.end).max(a)),
        at_s: b.start,
        detail: format!(
            "detected {} ms after the start (signal power); gyro coast, largest error {worst:.4}°; restored {} s after the end; fine attitude within 3σ after {} s",
            never_or(blocked, |t| format!("{:.0}", (t - b.start) * 1e3)),
            never_or(restored, |t| format!("{:.2}", t - b.end)),
            never_or(att, |a| format!("{a:.1}"))
        ),
    }
}

/// The largest |error| (°) and `|e|/σ` of the records with an attitude in `[from, to)`.
fn worst_in(ev: &Events, from: f64, to: f64) -> (f64, f64) {
    let part: Vec<Sample> = ev
        .record
        .samples
        .iter()
        .filter(|s| s.t >= from && s.t < to)
        .copied()
        .collect();
    let worst = part
        .iter()
        .filter(|s| has_attitude(s))
        .map(|s| s.error.amax())
        .fold(0.0f64, f64::max)
        .to_degrees();
    (worst, SigmaCoverage::of(&part).worst_ratio)
}

/// A loss reason as words.
fn reason(e: &ReceiverEvent) -> String {
    match e {
        ReceiverEvent::AttitudeLost { reason, .. } => format!("{reason:?}"),
        _ => String::new(),
    }
}

/// Every antenna blocked for longer than the gyro may coast: the attitude is lost (fixes
/// dropped, [`ReceiverEvent::AttitudeLost`]) and the cold start finds it again after the
/// signals return; recovered when the fine attitude is back within 3σ.
fn outage(ev: &Events, start: f64, end: f64) -> FaultOutcome {
    let lost = ev
        .record
        .events
        .iter()
        .find(|(t, e)| {
            *t >= start
                && *t <= end + WINDOW.restored
                && matches!(e, ReceiverEvent::AttitudeLost { .. })
        })
        .copied();
    let first_fix = ev.find(end, f64::INFINITY, &|e| {
        matches!(e, ReceiverEvent::FirstFix { .. })
    });
    let att = ev.recovery(end);
    let (worst, ratio) = worst_in(ev, start, lost.map_or(end, |(t, _)| t));
    FaultOutcome {
        name: format!("every antenna blocked for {:.0} s", end - start),
        detected: lost.is_some(),
        recovered_s: att,
        at_s: start,
        detail: format!(
            "gyro coast, largest error {worst:.4}° ({ratio:.1}σ); attitude lost {} s after the start; cold start: first fix {} s after the signals returned; fine attitude within 3σ after {} s",
            lost.map_or("never".into(), |(t, e)| format!("{:.1} ({})", t - start, reason(&e))),
            never_or(first_fix, |t| format!("{:.2}", t - end)),
            never_or(att, |a| format!("{a:.1}"))
        ),
    }
}

/// A faulty gyro: excluded (detected) while it lies, used again after it agrees with the
/// signals; recovered when it is used again and the fine attitude is within 3σ.
fn gyro_fault(ev: &Events, f: &super::run::GyroFault) -> FaultOutcome {
    use super::run::GyroFaultKind;
    let excluded = ev.find(f.start, f.end + WINDOW.blocked, &|e| {
        matches!(e, ReceiverEvent::GyroExcluded { .. })
    });
    let restored = ev.find(f.end, f64::INFINITY, &|e| {
        matches!(e, ReceiverEvent::GyroRestored { .. })
    });
    let alarms = ev
        .record
        .events
        .iter()
        .filter(|(t, e)| {
            *t >= f.start && *t <= f.end && matches!(e, ReceiverEvent::IntegrityAlarm { .. })
        })
        .count();
    let att = ev.recovery(f.end);
    let (worst, ratio) = worst_in(ev, f.start, f.end + WINDOW.restored);
    let what = match f.kind {
        GyroFaultKind::RateOffset(w) => {
            format!(
                "gyro {:.0} rad/s off",
                (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt()
            )
        }
        GyroFaultKind::Stuck => "gyro stuck at zero".into(),
    };
    let recovered = match excluded {
        Some(_) => restored.zip(att).map(|(r, a)| (r - f.end).max(a)),
        None => att,
    };
    FaultOutcome {
        name: format!("{what} for {:.0} s", f.end - f.start),
        detected: excluded.is_some(),
        recovered_s: recovered,
        at_s: f.start,
        detail: format!(
            "gyro excluded {} ms after the start ({alarms} integrity alarms); largest error until {:.0} s after the end {worst:.4}° ({ratio:.1}σ); gyro used again {} s after the end; fine attitude within 3σ after {} s",
            never_or(excluded, |t| format!("{:.0}", (t - f.start) * 1e3)),
            WINDOW.restored,
            never_or(restored, |t| format!("{:.2}", t - f.end)),
            never_or(att, |a| format!("{a:.1}"))
        ),
    }
}

/// The outcome of the faults of a separate fault run (outages and gyro faults).
pub fn evaluate_fault_run(
    record: &FlightRecord,
    plan: &super::run::FaultPlan,
) -> Vec<FaultOutcome> {
    let ev = Events { record };
    let mut out: Vec<FaultOutcome> = plan
        .outages
        .iter()
        .map(|&(a, b)| outage(&ev, a, b))
        .collect();
    out.extend(plan.gyro_faults.iter().map(|f| gyro_fault(&ev, f)));
    out
}

/// A one-cycle slip ([`super::sample_level::SLIP_DURATION_S`]): found against the fine attitude
/// and repaired.
fn cycle_slip(ev: &Events, slip: &super::sample_level::SampleSlip) -> FaultOutcome {
    let (ts, antenna, prn) = (slip.start_s, slip.antenna, slip.prn);
    let found = ev
        .record
        .events
        .iter()
        .find(|(t, e)| {
            *t >= ts
                && *t <= ts + WINDOW.slip_found
                && matches!(e, ReceiverEvent::CycleSlip { prn: p, antenna: a, .. } if *p == prn && usize::from(*a) == antenna)
        })
        .copied();
    let att = ev.recovery(ts);
    let path = if ts < ev.record.sample_level_s {
        "in the samples"
    } else {
        "on the fast path"
    };
    FaultOutcome {
        name: format!("cycle slip ({path})"),
        detected: found.is_some(),
        recovered_s: found.map(|(t, _)| t - ts).zip(att).map(|(s, a)| s.max(a)),
        at_s: ts,
        detail: format!(
            "PRN {prn}, antenna {}: carrier turned by {} cycle in {:.0} ms (the block counter counts it, the geometry does not move); {}",
            ANTENNA[antenna.min(2)],
            super::sample_level::SLIP_CYCLES,
            super::sample_level::SLIP_DURATION_S * 1e3,
            match found {
                Some((t, ReceiverEvent::CycleSlip { cycles, .. })) => format!(
                    "slip of {cycles} cycle(s) found against the fine attitude and repaired {:.2} s later",
                    t - ts
                ),
                _ => {
                    let (worst, inside) = ev.worst_against_sigma(ts, ts + WINDOW.slip_found);
                    format!(
                        "not detected: largest error within {:.0} s {worst:.4}°, {}",
                        WINDOW.slip_found,
                        if inside { "inside 3σ throughout" } else { "outside 3σ at times" }
                    )
                }
            }
        ),
    }
}

/// A data-bit transition at the wrong moment.
fn bit_flip(ev: &Events, plan: &super::run::FaultPlan) -> Option<FaultOutcome> {
    let (tf, prn) = (
        ev.record.bit_flip_s.or(plan.bit_flip)?,
        ev.record.bit_flip_prn?,
    );
    let seen = ev.find(
        tf,
        tf + WINDOW.bit_flagged,
        &|e| matches!(e, ReceiverEvent::BitAnomaly { prn: p, .. } if *p == prn),
    );
    Some(FaultOutcome {
        name: "data-bit flip at the wrong moment".into(),
        detected: seen.is_some(),
        recovered_s: ev.recovery(tf),
        at_s: tf,
        detail: format!(
            "PRN {prn}: bit transition half a bit after an edge, {:.1} ms into a code period; {}; the fine filter averages the bit out of every epoch",
            (tf * 1e3) % 1.0,
            seen.map_or("not flagged".into(), |t| format!("flagged {:.0} ms later", (t - tf) * 1e3))
        ),
    })
}

/// The outcome of every injected or natural fault of the flight.
pub fn evaluate_faults(
    record: &FlightRecord,
    plan: &super::run::FaultPlan,
    after_s: f64,
) -> Vec<FaultOutcome> {
    let ev = Events { record };
    let mut out: Vec<FaultOutcome> = satellite_setting(&ev, after_s)
        .into_iter()
        .chain(satellite_rising(&ev, after_s))
        .collect();
    out.extend(plan.blockages.iter().map(|b| blockage(&ev, b)));
    out.extend(record.slips.iter().map(|s| cycle_slip(&ev, s)));
    out.extend(bit_flip(&ev, plan));
    out
}

#[cfg(test)]
mod tests {
    use gnss_attitude::receiver::LossReason;
    use nalgebra::Matrix5;

    use super::super::run::{FaultPlan, GyroFault, GyroFaultKind};
    use super::*;

    /// A record at `t` with an attitude from `source` (or none), error `e_sigmas` σ on x.
    fn sample(t: f64, source: AttitudeSource, e_sigmas: f64) -> Sample {
        let sigma = Vector3::repeat(1e-3);
        Sample {
            t,
            source,
            error: Vector3::new(e_sigmas * 1e-3, 0.0, 0.0),
            sigma,
            fine_error: Vector3::zeros(),
            fine_locked: source == AttitudeSource::Fine,
            loop_noise: sigma,
            tracked: 8,
            used: 8,
            fixed: 8,
            visible: 8,
            blocked: [false; 3],
            bias_error: Vector3::zeros(),
            line_bias_error: [0.0; 2],
            line_bias_sigma: [0.0; 2],
            information: Matrix5::zeros(),
            limit: sigma,
        }
    }

    /// 10 Hz records over `[from, to)`.
    fn records(from: f64, to: f64, source: AttitudeSource, e_sigmas: f64) -> Vec<Sample> {
        let n = ((to - from) / 0.1).round() as usize;
        (0..n)
            .map(|k| sample(from + 0.1 * k as f64, source, e_sigmas))
            .collect()
    }

    fn at(t: f64) -> u64 {
        (t * 1e3) as u64
    }

    #[test]
    fn a_faulty_gyro_reports_its_fault_only_inside_it() {
        let f = GyroFault {
            start: 60.0,
            end: 70.0,
            kind: GyroFaultKind::RateOffset([5.0, 0.0, -5.0]),
        };
        // 5 rad/s over 10 ms in 1e-5 rad pulses: 5000 more pulses
        assert_eq!(f.apply(65.0, 0.01, [3, 4, 5], 1e-5), [5003, 4, -4995]);
        assert_eq!(f.apply(70.0, 0.01, [3, 4, 5], 1e-5), [3, 4, 5]);
        assert_eq!(f.apply(59.99, 0.01, [3, 4, 5], 1e-5), [3, 4, 5]);
        let stuck = GyroFault {
            kind: GyroFaultKind::Stuck,
            ..f
        };
        assert_eq!(stuck.apply(60.0, 0.01, [3, 4, 5], 1e-5), [0; 3]);
    }

    #[test]
    fn a_long_outage_is_detected_by_the_loss_and_recovered_by_the_cold_start() {
        let (start, end) = (40.0, 190.0);
        let mut samples = records(0.0, 40.0, AttitudeSource::Fine, 1.0);
        samples.extend(records(40.0, 160.0, AttitudeSource::GyroCoast, 2.0));
        samples.extend(records(160.0, 192.0, AttitudeSource::None, 0.0));
        samples.extend(records(192.0, 193.0, AttitudeSource::Snapshot, 1.0));
        samples.extend(records(193.0, 200.0, AttitudeSource::Fine, 1.0));
        let lost = ReceiverEvent::AttitudeLost {
            epoch: at(160.0),
            reason: LossReason::CoastTooLong,
        };
        let fix = ReceiverEvent::FirstFix {
            epoch: at(192.0),
            satellites: 7,
        };
        let record = FlightRecord {
            samples,
            events: vec![(160.0, lost), (192.0, fix)],
            ..FlightRecord::default()
        };
        let plan = FaultPlan {
            outages: vec![(start, end)],
            ..FaultPlan::default()
        };
        let out = evaluate_fault_run(&record, &plan);
        assert_eq!(out.len(), 1);
        assert!(out[0].detected, "{out:?}");
        let r = out[0].recovered_s.unwrap();
        assert!((r - 3.0).abs() < 0.05, "{r}");
        assert!(out[0].detail.contains("CoastTooLong"), "{}", out[0].detail);
        // no loss reported: not detected; never fine again: not recovered
        let record = FlightRecord {
            samples: records(0.0, 200.0, AttitudeSource::GyroCoast, 1.0),
            ..FlightRecord::default()
        };
        let out = evaluate_fault_run(&record, &plan);
        assert!(!out[0].detected && out[0].recovered_s.is_none(), "{out:?}");
    }

    #[test]
    fn a_faulty_gyro_is_detected_by_its_exclusion_and_recovered_when_used_again() {
        let f = GyroFault {
            start: 60.0,
            end: 70.0,
            kind: GyroFaultKind::RateOffset([5.0, 0.0, 0.0]),
        };
        let mut samples = records(0.0, 60.3, AttitudeSource::Fine, 1.0);
        // the error shows before the exclusion: 4σ for three records
        samples.extend(records(60.3, 60.6, AttitudeSource::Fine, 4.0));
        samples.extend(records(60.6, 100.0, AttitudeSource::Fine, 1.0));
        let record = FlightRecord {
            samples: samples.clone(),
            events: vec![
                (60.25, ReceiverEvent::GyroExcluded { epoch: at(60.25) }),
                (75.0, ReceiverEvent::GyroRestored { epoch: at(75.0) }),
            ],
            ..FlightRecord::default()
        };
        let plan = FaultPlan {
            gyro_faults: vec![f],
            ..FaultPlan::default()
        };
        let out = evaluate_fault_run(&record, &plan);
        assert!(out[0].detected, "{out:?}");
        assert!((out[0].recovered_s.unwrap() - 5.0).abs() < 1e-9, "{out:?}");
        assert!(out[0].detail.contains("250 ms"), "{}", out[0].detail);
        assert!(out[0].detail.contains("(4.0σ)"), "{}", out[0].detail);
        // never excluded: not detected, recovered when the attitude is within 3σ again
        let record = FlightRecord {
            samples,
            ..FlightRecord::default()
        };
        let out = evaluate_fault_run(&record, &plan);
        assert!(!out[0].detected, "{out:?}");
        assert!(out[0].recovered_s.is_some_and(|r| r < 0.01), "{out:?}");
    }

    #[test]
    fn the_sigma_coverage_counts_the_records_with_an_attitude() {
        let mut s = records(0.0, 1.0, AttitudeSource::Fine, 1.0);
        s[3].error.y = -3.5e-3;
        s.extend(records(1.0, 2.0, AttitudeSource::None, 9.0));
        let c = SigmaCoverage::of(&s);
        assert_eq!((c.records, c.within_3sigma), (10, 9));
        assert!((c.fraction() - 0.9).abs() < 1e-12);
        assert!((c.worst_ratio - 3.5).abs() < 1e-9);
        let both = c.merge(SigmaCoverage::of(&records(
            0.0,
            1.0,
            AttitudeSource::Fine,
            0.5,
        )));
        assert_eq!((both.records, both.within_3sigma), (20, 19));
        assert!(SigmaCoverage::default().fraction().is_nan());
    }
}
