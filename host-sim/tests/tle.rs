//! `--tle`: the main job flown on SGP4 of the bundled AO-73 element set (a 1U CubeSat at about
//! 635 km instead of the built-in 550 km orbit). A two-minute flight without faults from the
//! scenario's GPS start: the receiver decodes its ephemerides, fixes its position on the TLE's
//! orbit and keeps the attitude at the accuracy of the built-in orbit. Heavy (the first
//! seconds from samples): run it in release with `--ignored`. The refusal for a scenario
//! without an orbit is fast.

use std::path::PathBuf;

use host_sim::scenarios::microsat::metrics::evaluate;
use host_sim::scenarios::microsat::run::{fly, FlightConfig};
use host_sim::scenarios::microsat::short;
use host_sim::scenarios::{self, RunContext, UnsupportedOption};
use host_sim::synth::quantize::Quantizer;
use host_sim::truth::tle::Tle;

fn bundled() -> Tle {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/ao73.tle");
    Tle::read(&path).unwrap()
}

#[test]
#[ignore = "heavy: cargo test --release -p host-sim --test tle -- --ignored"]
fn the_main_job_flies_a_tle_orbit_with_own_fixes_and_the_usual_attitude_accuracy() {
    let config = FlightConfig {
        duration_s: 120.0,
        tle: Some(bundled()),
        ..short(1)
    };
    let record = fly(&config, None).unwrap();
    let m = evaluate(&record, config.duration_s);
    let nav = &record.navigation;

    // navigation: subframes 1–3 of at least four satellites (≤ 30 s plus bit sync), then a
    // fix a second; each within 15 m of the TLE's truth (code noise of about a metre times a
    // PDOP of about 2, no ionosphere), their RMS within 5 m: a fix compared with another
    // orbit than the one the pseudoranges came from would be kilometres off
    let first = nav.first_fix_s.expect("a first fix");
    assert!(first <= 45.0, "first fix at {first} s");
    assert!(
        nav.fix_errors.len() as f64 >= 0.8 * (config.duration_s - first),
        "{} fixes",
        nav.fix_errors.len()
    );
    let worst = nav.fix_errors.iter().map(|e| e.1).fold(0.0, f64::max);
    let rms = (nav.fix_errors.iter().map(|e| e.1 * e.1).sum::<f64>() / nav.fix_errors.len() as f64)
        .sqrt();
    assert!(
        worst < 15.0 && rms < 5.0,
        "fix error RMS {rms} m, worst {worst} m"
    );

    // attitude: on the default orbit the short flight's RMS is 0.007–0.010° per axis; the
    // TLE's orbit must not cost accuracy (each axis within 0.02°, and the receiver never
    // lost for long)
    let rms_deg = m.receiver.rms.map(f64::to_degrees);
    assert!(
        rms_deg.iter().all(|&x| x < 0.02),
        "attitude RMS {rms_deg} deg"
    );
    assert!(m.availability > 0.95, "availability {}", m.availability);
    println!(
        "TLE flight: first fix {first:.1} s, {} fixes, RMS {rms:.2} m (worst {worst:.2} m); attitude RMS {:.4} / {:.4} / {:.4} deg",
        nav.fix_errors.len(),
        rms_deg.x,
        rms_deg.y,
        rms_deg.z
    );
}

#[test]
fn a_scenario_without_an_orbit_refuses_a_tle_with_a_typed_error() {
    let scenario = scenarios::find("vector-ekf").unwrap();
    let err = scenario
        .run(&RunContext {
            variant: scenario.variant(None).unwrap().to_string(),
            seed: 1,
            out_dir: None,
            front_end: Quantizer::I8,
            tle: Some(bundled()),
        })
        .unwrap_err();
    let refused = err
        .downcast_ref::<UnsupportedOption>()
        .unwrap_or_else(|| panic!("{err:#}"));
    assert_eq!(refused.option, "--tle");
    assert_eq!(refused.supported, &["microsat"]);
}
