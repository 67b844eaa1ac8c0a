//! The file commands are bounded (issue 15): `synth` refuses zero, non-finite and excessive
//! rates, durations and sizes; `acquire`/`track` refuse non-finite options; `track --sky`
//! reads at most its cap; a `--seconds` or `--ms` beyond the recording is said plainly. Every
//! refusal exits non-zero and names the option and its range.

use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn host_sim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .unwrap()
}

/// A fresh directory in the system's temporary directory, removed with its files when the
/// test ends, passed or failed (a run writes about 26 MB).
fn temp_dir(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("host-sim-bounds-{name}-"))
        .tempdir()
        .unwrap()
}

/// Asserts a non-zero exit whose stderr contains every one of `words`.
fn refused(out: &Output, words: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "accepted: {err}");
    for w in words {
        assert!(err.contains(w), "stderr lacks {w:?}: {err}");
    }
}

fn synth_args<'a>(dir: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec!["synth", "--out", dir, "--format", "cs8"];
    v.extend_from_slice(extra);
    v
}

#[test]
fn synth_fs_0_is_refused_instead_of_writing_nan() {
    let tmp = temp_dir("fs0");
    let dir = tmp.path();
    let d = dir.to_str().unwrap();
    let out = host_sim(&synth_args(d, &["--fs", "0", "--seconds", "0.01"]));
    refused(&out, &["--fs", "(0, 64000000]"]);
    assert!(!dir.join("recording.cs8").exists());
}

#[test]
fn synth_if_nan_and_cn0_nan_are_refused() {
    let tmp = temp_dir("nan");
    let dir = tmp.path();
    let d = dir.to_str().unwrap();
    let out = host_sim(&synth_args(
        d,
        &["--fs", "2.6e6", "--if", "nan", "--seconds", "0.01"],
    ));
    refused(&out, &["--if", "finite"]);
    let out = host_sim(&synth_args(
        d,
        &["--fs", "2.6e6", "--cn0-min", "nan", "--seconds", "0.01"],
    ));
    refused(&out, &["--cn0-min", "[0, 60]"]);
    let out = host_sim(&synth_args(
        d,
        &["--fs", "2.6e6", "--cn0", "45,inf", "--seconds", "0.01"],
    ));
    refused(&out, &["--cn0", "[0, 60]"]);
}

#[test]
fn synth_seconds_1e9_and_fs_1e12_are_refused_before_writing() {
    let tmp = temp_dir("huge");
    let dir = tmp.path();
    let d = dir.to_str().unwrap();
    let started = Instant::now();
    let out = host_sim(&synth_args(d, &["--fs", "2.6e6", "--seconds", "1e9"]));
    refused(&out, &["--seconds", "3600"]);
    let out = host_sim(&synth_args(d, &["--fs", "1e12", "--seconds", "1"]));
    refused(&out, &["--fs", "64000000"]);
    // within the duration and rate maxima, but beyond the output cap: refused before any file
    let out = host_sim(&[
        "synth",
        "--out",
        d,
        "--format",
        "cs16",
        "--fs",
        "64e6",
        "--seconds",
        "3600",
        "--antennas",
        "3",
    ]);
    refused(&out, &["GiB", "16 GiB", "--seconds"]);
    assert!(!dir.join("recording.ant0.cs16").exists());
    assert!(started.elapsed() < Duration::from_secs(20));
}

#[test]
fn acquire_and_track_refuse_xcorr_margin_nan() {
    for cmd in ["acquire", "track"] {
        let out = host_sim(&[
            cmd,
            "--file",
            "none.cs8",
            "--format",
            "cs8",
            "--fs",
            "2.6e6",
            "--xcorr-margin-db",
            "nan",
        ]);
        refused(&out, &["--xcorr-margin-db", "[0, 20]"]);
    }
    let out = host_sim(&[
        "acquire", "--file", "none.cs8", "--format", "cs8", "--fs", "2.6e6", "--ms", "1000",
    ]);
    refused(&out, &["--ms", "1..=100"]);
}

#[test]
fn track_sky_dev_zero_is_refused_fast_without_growing() {
    let tmp = temp_dir("sky");
    let dir = tmp.path();
    let big = dir.join("big.sky.csv");
    // a syntactically valid sky file, but 100 kB of it
    std::fs::write(&big, "1,10.0,45.0\n".repeat(9000)).unwrap();
    let long_line = dir.join("line.sky.csv");
    std::fs::write(&long_line, format!("1,10.0,45.0{}\n", " ".repeat(300))).unwrap();
    let zero = if cfg!(unix) { "/dev/zero" } else { "" };
    for (sky, words) in [
        (zero, &["sky file", "longer than 65536 bytes"][..]),
        (
            big.to_str().unwrap(),
            &["sky file", "longer than 65536 bytes"][..],
        ),
        (long_line.to_str().unwrap(), &["line 1", "256"][..]),
    ] {
        if sky.is_empty() {
            continue;
        }
        let started = Instant::now();
        let out = host_sim(&[
            "track",
            "--file",
            "none.cs8",
            "--format",
            "cs8",
            "--fs",
            "2.6e6",
            "--baselines",
            "1,0,0;0,1,0",
            "--sky",
            sky,
        ]);
        refused(&out, words);
        assert!(started.elapsed() < Duration::from_secs(10), "{sky}");
    }
}

#[test]
fn track_seconds_and_ms_beyond_the_recording_say_what_they_do() {
    let tmp = temp_dir("short");
    let dir = tmp.path();
    let d = dir.to_str().unwrap();
    let out = host_sim(&synth_args(
        d,
        &["--fs", "2.6e6", "--seconds", "0.3", "--cn0", "48,46"],
    ));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let truth: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("recording.truth.json")).unwrap()).unwrap();
    let prns = format!(
        "{},{}",
        truth["satellites"][0]["prn"], truth["satellites"][1]["prn"]
    );
    let file = dir.join("recording.cs8");
    let f = file.to_str().unwrap();
    let out = host_sim(&[
        "track",
        "--file",
        f,
        "--format",
        "cs8",
        "--fs",
        "2.6e6",
        "--prns",
        &prns,
        "--seconds",
        "1000",
        "--json",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("holds 0.300 s, --seconds asks 1000"), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!((v["tracked_s"].as_f64().unwrap() - 0.3).abs() < 1e-3, "{v}");
    // the first 30 ms hold 29 whole milliseconds (and the one extra sample a search reads):
    // --ms 20 and as many again for the verification do not fit, 14 do
    let short = dir.join("short.cs8");
    let bytes = std::fs::read(&file).unwrap();
    std::fs::write(&short, &bytes[..2 * 78_000]).unwrap();
    let out = host_sim(&[
        "acquire",
        "--file",
        short.to_str().unwrap(),
        "--format",
        "cs8",
        "--fs",
        "2.6e6",
        "--prns",
        &prns,
        "--ms",
        "20",
        "--json",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("holds 29 ms, --ms asks 20") && err.contains("summing 14 ms"),
        "{err}"
    );
}

#[test]
fn track_on_a_recording_longer_than_5_s_shows_progress_on_stderr_only() {
    let tmp = temp_dir("progress");
    let dir = tmp.path();
    let d = dir.to_str().unwrap();
    let out = host_sim(&synth_args(
        d,
        &["--fs", "2.1e6", "--seconds", "6", "--cn0", "48"],
    ));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let truth: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("recording.truth.json")).unwrap()).unwrap();
    let prn = truth["satellites"][0]["prn"].to_string();
    let file = dir.join("recording.cs8");
    let out = host_sim(&[
        "track",
        "--file",
        file.to_str().unwrap(),
        "--format",
        "cs8",
        "--fs",
        "2.1e6",
        "--prns",
        &prn,
        "--json",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    // stderr is a pipe here, not a terminal: plain lines every tenth of the recording
    let lines = err.lines().filter(|l| l.starts_with("track: ")).count();
    assert!((9..=10).contains(&lines), "{err}");
    assert!(err.contains("of 6.0 s (100 %)"), "{err}");
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(text.trim().lines().count(), 1, "{text}");
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert!((v["tracked_s"].as_f64().unwrap() - 6.0).abs() < 1e-3, "{v}");
}
