//! From a flight's records to the numbers: per stage time to first fix, error RMS and maximum
//! per body axis, availability, satellites; the bound; and each injected fault's detection and
//! recovery.

use gnss_attitude::receiver::{AttitudeSource, ReceiverEvent};
use nalgebra::Vector3;
use serde_json::{json, Value};

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
}

/// One injected fault's outcome.
#[derive(Clone, Debug)]
pub struct FaultOutcome {
    /// Name.
    pub name: String,
    /// Whether the receiver reported it.
    pub detected: bool,
    /// Seconds from the fault's end until the receiver had recovered (see each fault).
    pub recovered_s: Option<f64>,
    /// When it happened, s.
    pub at_s: f64,
    /// What was detected and done.
    pub detail: String,
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
    let tracked = if after_fix.is_empty() {
        (0.0, 0, 0)
    } else {
        (
            after_fix.iter().map(|s| s.tracked as f64).sum::<f64>() / after_fix.len() as f64,
            after_fix.iter().map(|s| s.tracked).min().unwrap_or(0),
            after_fix.iter().map(|s| s.tracked).max().unwrap_or(0),
        )
    };
    FlightMetrics {
        ttff_s: ttff,
        fine_lock_s: fine_lock,
        converged_from_s: from,
        receiver,
        stages,
        bound,
        availability,
        tracked,
        faults: Vec::new(),
    }
}

/// Degrees.
pub fn deg(v: &Vector3<f64>) -> [f64; 3] {
    [v.x.to_degrees(), v.y.to_degrees(), v.z.to_degrees()]
}

/// The faults as JSON.
pub fn faults_json(faults: &[FaultOutcome]) -> Value {
    Value::Array(
        faults
            .iter()
            .map(|f| {
                json!({
                    "name": f.name,
                    "detected": f.detected,
                    "recovered_s": f.recovered_s,
                    "at_s": f.at_s,
                    "detail": f.detail,
                })
            })
            .collect(),
    )
}
