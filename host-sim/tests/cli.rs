//! The command-line contract: `list`, `run --json` printing exactly one JSON object with
//! `scenario`, `variant`, `metrics` and `paper`, errors for unknown names.

use std::process::Command;

fn host_sim() -> Command {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
}

#[test]
fn list_names_every_scenario_and_the_default() {
    let out = host_sim().arg("list").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    for s in host_sim::scenarios::SCENARIOS {
        assert!(text.contains(s.name), "{text}");
    }
    assert!(text.contains("(default)"));
}

#[test]
fn run_json_prints_one_object_with_the_contract_fields() {
    let out = host_sim()
        .args([
            "run",
            "vector-ekf",
            "--variant",
            "fast-tumble",
            "--seed",
            "5",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(
        text.trim().lines().count(),
        1,
        "stdout must be one JSON line: {text}"
    );
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["scenario"], "vector-ekf");
    assert_eq!(v["variant"], "fast-tumble");
    assert_eq!(v["seed"], 5);
    for key in ["rotvec_rms_rad", "nees_mean", "runs"] {
        assert!(v["metrics"][key].is_number(), "metric {key} missing: {v}");
    }
    assert!(v.get("paper").is_some());
}

#[test]
fn unknown_scenario_or_variant_fails_with_a_message() {
    let out = host_sim()
        .args(["run", "no-such-scenario"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no scenario"));
    let out = host_sim()
        .args(["run", "vector-ekf", "--variant", "nope"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no variant"));
}

/// `--front-end` takes `i8`, `sm2`, `bit1` only, and only where there are samples: an unknown
/// front end, a scenario without a sample-level path and a `-iq` variant are refused before
/// anything runs.
#[test]
fn front_end_is_refused_where_there_are_no_samples() {
    let refused = |args: &[&str], message: &str| {
        let out = host_sim().args(args).output().unwrap();
        assert!(!out.status.success(), "{args:?} ran");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(message), "{args:?}: {err}");
    };
    refused(&["run", "signal", "--front-end", "cs16"], "no front end");
    refused(
        &["run", "vector-ekf", "--front-end", "sm2"],
        "no sample-level path",
    );
    refused(
        &[
            "run",
            "one-stage",
            "--variant",
            "8sat-2hz-iq",
            "--front-end",
            "bit1",
        ],
        "-iq variants have no samples",
    );
}

#[test]
fn tle_is_refused_without_an_orbit_and_a_bad_file_says_why() {
    let refused = |args: &[&str], message: &str| {
        let out = host_sim().args(args).output().unwrap();
        assert!(!out.status.success(), "{args:?} ran");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(message), "{args:?}: {err}");
    };
    let tle = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ao73.tle");
    refused(
        &["run", "vector-ekf", "--tle", tle],
        "scenario vector-ekf cannot use --tle (only microsat)",
    );
    refused(&["run", "microsat", "--tle", "/nonexistent.tle"], "reading");
    let not_a_tle = concat!(env!("CARGO_MANIFEST_DIR"), "/data/README.md");
    refused(
        &["run", "microsat", "--tle", not_a_tle],
        "no two-line element set",
    );
}
