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
        #[metric(unit = "")]
        pub name: String,
        /// Whether the receiver reported it.
        #[metric(unit = "")]
        pub detected: bool,
        /// From the fault's end until the receiver had recovered (null: never).
        #[metric(unit = "s")]
        pub recovered_s: Option<f64>,
        /// When it happened.
        #[metric(unit = "s")]
        pub at_s: f64,
        /// What was detected and done.
        #[metric(unit = "")]
        pub detail: String,
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
    /// RMS of the bound over the converged stretch, per body axis, rad.
    pub bound: Vector3<f64>,
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
    /// The converged receiver attitude split by input path: (RMS error, RMS bound, samples)
    /// while the sample-level chain fed the receiver, and on the fast path after it.
    pub by_path: [(Vector3<f64>, Vector3<f64>, usize); 2],
}

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

/// The metrics of one flight of `duration` seconds.
pub fn evaluate(record: &FlightRecord, duration: f64) -> FlightMetrics {
    let samples = &record.samples;
    let event_time = |pred: &dyn Fn(&ReceiverEvent) -> bool| {
        record.events.iter().find(|(_, e)| pred(e)).map(|(t, _)| *t)
    };
    let ttff = samples
        .iter()
        .find(|s| s.source != AttitudeSource::None)
        .map_or(f64::NAN, |s| s.t);
    let fine_lock =
        event_time(&|e| matches!(e, ReceiverEvent::FineLocked { .. })).unwrap_or(f64::NAN);
    let from = fine_lock + SETTLE_S;
    let converged: Vec<&Sample> = samples.iter().filter(|s| s.t >= from).collect();
    let has = |s: &Sample| s.source != AttitudeSource::None;
    let (rms, max, count) = rms_max(converged.iter().filter(|s| has(s)).map(|s| &s.error));
    let (sigma_rms, _, _) = rms_max(converged.iter().filter(|s| has(s)).map(|s| &s.sigma));
    let (bound, _, _) = rms_max(converged.iter().map(|s| &s.bound));
    let n = samples.len().max(1) as f64;
    let availability = samples.iter().filter(|s| has(s)).count() as f64 / n;
    let receiver = StageStats {
        name: "receiver",
        first_s: Some(ttff),
        rms,
        max,
        sigma_rms,
        availability,
        count,
        satellites: f64::NAN,
    };
    // the fine filter: locked samples after convergence
    let fine_samples: Vec<StageSample> = samples
        .iter()
        .filter(|s| s.fine_locked && s.source == AttitudeSource::OneStage)
        .map(|s| StageSample {
            t: s.t,
            error: s.fine_error,
            sigma: s.sigma,
        })
        .collect();
    let mut fine = stage_stats("one-stage (fine)", &fine_samples, from, duration, 0.1);
    fine.first_s = Some(fine_lock);
    let coast: Vec<StageSample> = samples
        .iter()
        .filter(|s| s.source == AttitudeSource::GyroCoast)
        .map(|s| StageSample {
            t: s.t,
            error: s.error,
            sigma: s.sigma,
        })
        .collect();
    let stages = vec![
        stage_stats(
            "snapshot (cold start, 1 Hz)",
            &record.snapshots,
            ttff,
            duration,
            1.0,
        ),
        fine,
        stage_stats(
            "rigid-body (baselines + Doppler)",
            &record.rigid,
            record.rigid.first().map_or(f64::NAN, |s| s.t + 30.0),
            duration,
            0.1,
        ),
        stage_stats("gyro coast", &coast, 0.0, duration, 0.1),
    ];
    let after_fix: Vec<&Sample> = samples.iter().filter(|s| s.t >= ttff).collect();
    let mean = |f: &dyn Fn(&Sample) -> Option<f64>| {
        let v: Vec<f64> = after_fix.iter().filter_map(|s| f(s)).collect();
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let mut stages = stages;
    let fixed = mean(&|s| Some(s.fixed as f64));
    if let Some(st) = stages.get_mut(0) {
        st.satellites = fixed;
    }
    if let Some(st) = stages.get_mut(1) {
        st.satellites = mean(&|s| (s.fine_locked && s.used > 0).then_some(s.used as f64));
    }
    if let Some(st) = stages.get_mut(2) {
        st.satellites = fixed;
    }
    let mut receiver = receiver;
    receiver.satellites = mean(&|s| Some(s.tracked as f64));
    let tracked = if after_fix.is_empty() {
        (0.0, 0, 0)
    } else {
        (
            after_fix.iter().map(|s| s.tracked as f64).sum::<f64>() / after_fix.len() as f64,
            after_fix.iter().map(|s| s.tracked).min().unwrap_or(0),
            after_fix.iter().map(|s| s.tracked).max().unwrap_or(0),
        )
    };
    let split = |on_samples: bool| {
        let part: Vec<&&Sample> = converged
            .iter()
            .filter(|s| has(s) && (s.t < record.sample_level_s) == on_samples)
            .collect();
        let (rms, _, n) = rms_max(part.iter().map(|s| &s.error));
        let (b, _, _) = rms_max(part.iter().map(|s| &s.bound));
        (rms, b, n)
    };
    FlightMetrics {
        by_path: [split(true), split(false)],
        ttff_s: ttff,
        fine_lock_s: fine_lock,
        converged_from_s: from,
        receiver,
        stages,
        bound,
        availability,
        tracked,
        faults: Vec::new(),
        gyro_bias_error: (record.gyro_bias.1 - record.gyro_bias.0)
            * (180.0 / std::f64::consts::PI * 3600.0),
        gyro_bias_truth: record.gyro_bias.0 * (180.0 / std::f64::consts::PI * 3600.0),
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
        s.source == AttitudeSource::OneStage
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

/// The outcome of every injected or natural fault of the flight.
pub fn evaluate_faults(
    record: &FlightRecord,
    plan: &super::run::FaultPlan,
    after_s: f64,
) -> Vec<FaultOutcome> {
    let mut out = Vec::new();
    let samples = &record.samples;
    let find = |from: f64, to: f64, pred: &dyn Fn(&ReceiverEvent) -> bool| {
        record
            .events
            .iter()
            .find(|(t, e)| *t >= from && *t <= to && pred(e))
            .map(|(t, _)| *t)
    };
    // a satellite setting and one rising (natural, the first after `after_s`)
    if let Some(&(ts, prn, _)) = record
        .horizon
        .iter()
        .find(|(t, _, rises)| *t > after_s && !rises)
    {
        let lost = find(
            ts - 0.2,
            ts + 3.0,
            &|e| matches!(e, ReceiverEvent::SatelliteLost { prn: p, .. } if *p == prn),
        );
        let att = attitude_recovery(samples, ts, 1.0);
        out.push(FaultOutcome {
            name: "satellite setting".into(),
            detected: lost.is_some(),
            recovered_s: lost.zip(att).map(|(l, a)| (l - ts).max(a)),
            at_s: ts,
            detail: format!(
                "PRN {prn} set below the 10° mask at {ts:.1} s; channel lost and slot released {} s later; fine attitude within 3σ after {} s",
                lost.map_or("never".into(), |l| format!("{:.2}", l - ts)),
                att.map_or("never".into(), |a| format!("{a:.1}"))
            ),
        });
    }
    if let Some(&(tr, prn, _)) = record
        .horizon
        .iter()
        .find(|(t, _, rises)| *t > after_s && *rises)
    {
        let acquired = find(
            tr,
            tr + 10.0,
            &|e| matches!(e, ReceiverEvent::SatelliteAcquired { prn: p, .. } if *p == prn),
        );
        let fixed = find(
            tr,
            tr + 20.0,
            &|e| matches!(e, ReceiverEvent::AmbiguityFixed { prn: p, .. } if *p == prn),
        );
        out.push(FaultOutcome {
            name: "satellite rising".into(),
            detected: acquired.is_some(),
            recovered_s: fixed.map(|f| f - tr),
            at_s: tr,
            detail: format!(
                "PRN {prn} rose above the mask at {tr:.1} s; first observation {} s later, ambiguities fixed from the fine attitude (satellite in every stage) {} s later",
                acquired.map_or("never".into(), |a| format!("{:.2}", a - tr)),
                fixed.map_or("never".into(), |f| format!("{:.2}", f - tr))
            ),
        });
    }
    for b in &plan.blockages {
        let antenna = b.antenna as u8;
        let blocked = find(
            b.start,
            b.start + 1.0,
            &|e| matches!(e, ReceiverEvent::AntennaBlocked { antenna: a, .. } if *a == antenna),
        );
        let restored = find(
            b.end,
            b.end + 5.0,
            &|e| matches!(e, ReceiverEvent::AntennaRestored { antenna: a, .. } if *a == antenna),
        );
        let att = attitude_recovery(samples, b.end, 1.0);
        let coast: Vec<&Sample> = samples
            .iter()
            .filter(|s| s.t >= b.start && s.t < b.end)
            .collect();
        let worst = coast
            .iter()
            .map(|s| s.error.amax())
            .fold(0.0f64, f64::max)
            .to_degrees();
        out.push(FaultOutcome {
            name: format!("antenna {} blocked for {:.0} s", ["A", "B", "C"][b.antenna.min(2)], b.end - b.start),
            detected: blocked.is_some(),
            recovered_s: restored.zip(att).map(|(r, a)| (r - b.end).max(a)),
            at_s: b.start,
            detail: format!(
                "detected {} ms after the start (signal power); gyro coast, largest error {worst:.4}°; restored {} s after the end; fine attitude within 3σ after {} s",
                blocked.map_or("never".into(), |t| format!("{:.0}", (t - b.start) * 1e3)),
                restored.map_or("never".into(), |t| format!("{:.2}", t - b.end)),
                att.map_or("never".into(), |a| format!("{a:.1}"))
            ),
        });
    }
    for slip in &record.slips {
        let (ts, antenna, prn) = (slip.start_s, slip.antenna, slip.prn);
        let found = record
            .events
            .iter()
            .find(|(t, e)| {
                *t >= ts
                    && *t <= ts + 3.0
                    && matches!(e, ReceiverEvent::CycleSlip { prn: p, antenna: a, .. } if *p == prn && usize::from(*a) == antenna)
            })
            .copied();
        let att = attitude_recovery(samples, ts, 1.0);
        let path = if ts < record.sample_level_s {
            "in the samples"
        } else {
            "on the fast path"
        };
        out.push(FaultOutcome {
            name: format!("cycle slip ({path})"),
            detected: found.is_some(),
            recovered_s: found.map(|(t, _)| t - ts).zip(att).map(|(s, a)| s.max(a)),
            at_s: ts,
            detail: format!(
                "PRN {prn}, antenna {}: carrier turned by one cycle in 4 ms; {}",
                ["A", "B", "C"][antenna.min(2)],
                match found {
                    Some((t, ReceiverEvent::CycleSlip { cycles, .. })) => format!(
                        "slip of {cycles} cycle(s) found against the fine attitude and repaired {:.2} s later",
                        t - ts
                    ),
                    _ => "not detected".into(),
                }
            ),
        });
    }
    if let (Some(tf), Some(prn)) = (record.bit_flip_s.or(plan.bit_flip), record.bit_flip_prn) {
        let seen = find(
            tf,
            tf + 0.1,
            &|e| matches!(e, ReceiverEvent::BitAnomaly { prn: p, .. } if *p == prn),
        );
        let att = attitude_recovery(samples, tf, 1.0);
        out.push(FaultOutcome {
            name: "data-bit flip at the wrong moment".into(),
            detected: seen.is_some(),
            recovered_s: att,
            at_s: tf,
            detail: format!(
                "PRN {prn}: bit transition half a bit after an edge, {:.1} ms into a code period; {}; the fine filter averages the bit out of every epoch",
                (tf * 1e3) % 1.0,
                seen.map_or("not flagged".into(), |t| format!("flagged {:.0} ms later", (t - tf) * 1e3))
            ),
        });
    }
    out
}
