//! `microsat`: the main job. A microsatellite flies ten minutes of a 550 km sun-synchronous
//! orbit through the GPS constellation of a real almanac; its three antennas' signals go
//! through the core's receiver ([`gnss_attitude::receiver::AttitudeReceiver`]) from raw
//! samples (the first minute: synthesized samples → the core's correlators and tracking
//! channels) and then from the I/Q fast path with the same statistics; faults a real flight
//! meets are injected; the run reports each stage's errors against the truth and against the
//! bound host-sim computes for the same geometry and C/N0 ([`bound`]).

pub mod bound;
pub mod fast_path;
pub mod files;
pub mod metrics;
pub mod nmea;
pub mod run;
pub mod sample_level;
pub mod world;

use anyhow::Result;
use serde_json::json;

use super::{Outcome, RunContext, Scenario, Variant};
use metrics::{deg, evaluate, faults_json, FlightMetrics};
use run::{fly, FaultPlan, FlightConfig};
use world::{Blockage, MotionKind};

/// The scenario.
pub const SCENARIO: Scenario = Scenario {
    name: "microsat",
    about: "the main job: a microsatellite in LEO, raw samples to attitude, every stage, faults",
    variants: &[
        Variant {
            name: "nadir",
            about: "10 min, nadir pointing with a slow spin and wobble, faults (the default run)",
        },
        Variant {
            name: "detumbling",
            about: "10 min, a detumbling body (about 3°/s at the start), faults",
        },
        Variant {
            name: "short",
            about: "30 s without faults (the integration test)",
        },
    ],
    run,
};

/// The flight of a variant.
pub fn flight(variant: &str, seed: u64) -> FlightConfig {
    let faults = FaultPlan {
        // a short one inside the sample-level stretch (the core's correlators see it), the
        // 20 s one later, when the gyro is calibrated
        blockages: vec![
            Blockage {
                antenna: 2,
                start: 40.0,
                end: 42.0,
            },
            Blockage {
                antenna: 1,
                start: 200.0,
                end: 220.0,
            },
        ],
        // one in the samples (the core's correlators see it), one on the fast path
        cycle_slips: vec![(50.0004, 1), (300.0004, 2)],
        bit_flip: Some(400.0107),
    };
    let base = FlightConfig {
        duration_s: 600.0,
        motion: MotionKind::Nadir,
        u0: 0.4,
        gps_offset_s: 3600.0,
        detumble_rates: [0.0; 3],
        faults,
        seed,
        loop_bandwidth_hz: 1.0,
        sample_level_s: 60.0,
    };
    match variant {
        "detumbling" => FlightConfig {
            motion: MotionKind::Detumbling { duration_s: 600.0 },
            detumble_rates: [0.04, -0.03, 0.02],
            ..base
        },
        "short" => FlightConfig {
            duration_s: 30.0,
            sample_level_s: 5.0,
            faults: FaultPlan::default(),
            ..base
        },
        _ => base,
    }
}

fn run(ctx: &RunContext) -> Result<Outcome> {
    let started = std::time::Instant::now();
    let config = flight(&ctx.variant, ctx.seed);
    let bar = crate::report::progress(config.duration_s as u64, "flight (s)");
    let record = fly(&config, Some(&bar))?;
    bar.finish_and_clear();
    let mut m = evaluate(&record, config.duration_s);
    m.faults = metrics::evaluate_faults(&record, &config.faults, 60.0);
    let mut o = outcome(&m, started.elapsed().as_secs_f64());
    sample_level_summary(&mut o, &record, &m);
    if let Some(dir) = &ctx.out_dir {
        let title = format!("microsat / {} / seed {}", ctx.variant, ctx.seed);
        o.files = files::write_all(dir, &record, &m, &title, &o.summary)?;
    }
    Ok(o)
}

/// What the sample-level stretch did, and the receiver's error on each input path.
fn sample_level_summary(o: &mut Outcome, record: &run::FlightRecord, m: &FlightMetrics) {
    let [(rs, bs, ns), (rf, bf, nf)] = m.by_path;
    o.metric("rms_err_samples_deg", deg(&rs).to_vec())
        .metric("bound_samples_deg", deg(&bs).to_vec())
        .metric("rms_err_fast_path_deg", deg(&rf).to_vec())
        .metric("bound_fast_path_deg", deg(&bf).to_vec());
    let Some(st) = &record.sample_stats else {
        return;
    };
    o.metric("sample_level_s", record.sample_level_s)
        .metric("sample_level_searches", st.searches)
        .metric("sample_level_found", st.detections)
        .metric("sample_level_late", st.late)
        .metric("sample_level_observations", st.observations)
        .metric("sample_level_wall_s", record.wall_s.0)
        .metric("fast_path_wall_s", record.wall_s.1);
    let line = |name: &str, r: &nalgebra::Vector3<f64>, b: &nalgebra::Vector3<f64>, n: usize| {
        let (r, b) = (deg(r), deg(b));
        format!(
            "  {name:<28} RMS {:.4}/{:.4}/{:.4} deg vs bound {:.4}/{:.4}/{:.4} ({n} samples)",
            r[0], r[1], r[2], b[0], b[1], b[2]
        )
    };
    let mut lines = vec![
        format!(
            "sample-level chain for the first {:.0} s: {} satellites in the scene (|Doppler| ≤ {:.1} kHz, |rate| ≤ {:.0} Hz/s), {} searches ±50 kHz, {} found (a channel each); {} observations, {} late; wall {:.1} s (synthesis {:.1}, acquisition {:.1}, tracking {:.1}), fast path {:.1} s",
            record.sample_level_s,
            st.satellites,
            st.max_doppler_hz / 1e3,
            st.max_doppler_rate_hz_s,
            st.searches,
            st.detections,
            st.observations,
            st.late,
            record.wall_s.0,
            st.synthesis_s,
            st.acquisition_s,
            st.tracking_s,
            record.wall_s.1
        ),
        line("converged, from samples", &rs, &bs, ns),
        line("converged, fast path", &rf, &bf, nf),
    ];
    // after the bound line
    let pos = o
        .summary
        .iter()
        .position(|l| l.starts_with("bound"))
        .map_or(o.summary.len(), |p| p + 1);
    for (i, l) in lines.drain(..).enumerate() {
        o.summary.insert(pos + i, l);
    }
}

fn outcome(m: &FlightMetrics, wall_s: f64) -> Outcome {
    let mut o = Outcome::default();
    o.metric("ttff_s", m.ttff_s)
        .metric("rms_err_deg", deg(&m.receiver.rms).to_vec())
        .metric("max_err_deg", deg(&m.receiver.max).to_vec())
        .metric("availability", m.availability)
        .metric("bound_deg", deg(&m.bound).to_vec())
        .metric("faults", faults_json(&m.faults))
        .metric("fine_lock_s", m.fine_lock_s)
        .metric("wall_time_s", wall_s);
    o.paper = json!({
        "case": "none: no paper flies this case; each paper's own case is its scenario (snapshot: 002, dcm: 000, gyro-cal: 001, one-stage: 003)",
    });
    o.summary.push(format!(
        "{:<34} {:>8} {:>26} {:>26} {:>7} {:>5}",
        "stage", "first s", "RMS error x/y/z (deg)", "max error x/y/z (deg)", "avail", "sats"
    ));
    let row = |s: &metrics::StageStats| {
        let d = deg(&s.rms);
        let x = deg(&s.max);
        format!(
            "{:<34} {:>8.2} {:>8.4}/{:>8.4}/{:>8.4} {:>8.4}/{:>8.4}/{:>8.4} {:>7.3} {:>5.1}",
            s.name,
            s.first_s.unwrap_or(f64::NAN),
            d[0],
            d[1],
            d[2],
            x[0],
            x[1],
            x[2],
            s.availability,
            s.satellites
        )
    };
    for s in &m.stages {
        o.summary.push(row(s));
    }
    o.summary.push(row(&m.receiver));
    let b = deg(&m.bound);
    o.summary.push(format!(
        "bound (√(2Δf (J⁻¹)_aa), same geometry and C/N0): {:.4}/{:.4}/{:.4} deg; RMS/bound {:.2}/{:.2}/{:.2}",
        b[0],
        b[1],
        b[2],
        m.receiver.rms.x / m.bound.x,
        m.receiver.rms.y / m.bound.y,
        m.receiver.rms.z / m.bound.z
    ));
    o.summary.push(format!(
        "satellites tracked: mean {:.1}, min {}, max {}",
        m.tracked.0, m.tracked.1, m.tracked.2
    ));
    for f in &m.faults {
        o.summary.push(format!(
            "fault {:<36} detected {:<5} recovered {:>7} s  {}",
            f.name,
            f.detected,
            f.recovered_s.map_or("never".into(), |r| format!("{r:.2}")),
            f.detail
        ));
    }
    o.summary.push(format!(
        "gyro bias estimate − truth at the end: {:.1}/{:.1}/{:.1} °/h (truth {:.1}/{:.1}/{:.1} °/h)",
        m.gyro_bias_error.x, m.gyro_bias_error.y, m.gyro_bias_error.z,
        m.gyro_bias_truth.x, m.gyro_bias_truth.y, m.gyro_bias_truth.z
    ));
    o.summary.push(format!("wall time {wall_s:.1} s"));
    o
}
