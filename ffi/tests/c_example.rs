//! Builds `examples/c/scenario.c` with the host C compiler against this crate's static
//! library, runs it, and compares its attitude with the Rust run of the same example flight.
//! Its NMEA sentences and binary record are checked with the core's readers.

use std::path::{Path, PathBuf};
use std::process::Command;

use gnss_attitude::formats::nmea;
use gnss_attitude::formats::record::AttitudeRecord;
use gnss_attitude::receiver::example::ExampleFlight;
use gnss_attitude::receiver::{AttitudeReceiver, AttitudeSource};

/// The static library of the build that made this test: `cargo test` builds the library's
/// `staticlib` crate type beside its rlib in `deps/` (with the build's hash in the name) but
/// does not copy it up to `target/<profile>/`. This build's is the newest one not newer than
/// the test executable (linked after it; another feature resolution's, built later by another
/// command, is newer); `None` when there is none.
fn staticlib_in_deps() -> Option<PathBuf> {
    let exe = std::env::current_exe().expect("test executable path");
    let linked = std::fs::metadata(&exe).ok()?.modified().ok()?;
    let deps = exe.parent().expect("target/<profile>/deps/<test>");
    std::fs::read_dir(deps)
        .ok()?
        .filter_map(Result::ok)
        .filter(|e| {
            let name = e.file_name();
            let name = name.to_string_lossy();
            name.starts_with("libgnss_attitude_ffi-") && name.ends_with(".a")
        })
        .filter_map(|e| Some((e.metadata().ok()?.modified().ok()?, e.path())))
        .filter(|(built, _)| *built <= linked)
        .max()
        .map(|(_, path)| path)
}

/// Builds the staticlib with `cargo build` (only when the test's own build left none: it
/// resolves features on its own, so it compiles the core again).
fn build_staticlib(root: &Path) -> PathBuf {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut build = Command::new(cargo);
    build
        .current_dir(root)
        .args(["build", "-q", "-p", "gnss-attitude-ffi", "--lib"]);
    if !cfg!(debug_assertions) {
        build.arg("--release");
    }
    let status = build.status().expect("run cargo build for the staticlib");
    assert!(status.success(), "cargo build of the staticlib failed");
    // `cargo build` puts it in `target/<profile>/`, beside the test's `deps/`.
    let exe = std::env::current_exe().expect("test executable path");
    let profile_dir = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile>/deps/<test>");
    profile_dir.join("libgnss_attitude_ffi.a")
}

fn build_and_run() -> (std::process::ExitStatus, String) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let lib = staticlib_in_deps().unwrap_or_else(|| build_staticlib(&root));
    assert!(lib.exists(), "static library not built: {}", lib.display());
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("c-scenario");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let status = Command::new(&cc)
        .args(["-O2", "-std=c11", "-Wall", "-Wextra", "-Werror", "-I"])
        .arg(root.join("ffi/include"))
        .arg(root.join("examples/c/scenario.c"))
        .arg(&lib)
        // what `--print native-static-libs` lists for the std-linked host staticlib
        .args([
            "-lgcc_s",
            "-lutil",
            "-lrt",
            "-lpthread",
            "-lm",
            "-ldl",
            "-lc",
            "-o",
        ])
        .arg(&out)
        .status()
        .expect("run the C compiler");
    assert!(status.success(), "{cc} failed");
    let run = Command::new(&out).output().expect("run the C example");
    (
        run.status,
        String::from_utf8_lossy(&run.stdout).into_owned(),
    )
}

#[test]
fn c_example_matches_the_rust_flight() {
    let (status, stdout) = build_and_run();
    print!("{stdout}");
    assert!(status.success(), "the C example failed: {status}");

    // the same flight in Rust
    let mut flight = ExampleFlight::new(7);
    let mut receiver = AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
    flight.fly(&mut receiver, 0, 600).unwrap();
    let rust = receiver.attitude();
    assert_eq!(rust.source, AttitudeSource::Fine);

    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix("attitude: "))
        .expect("attitude line");
    let words: Vec<&str> = line.split_whitespace().collect();
    let epoch: u64 = words[1].parse().unwrap();
    let q: Vec<f32> = words[3..7].iter().map(|w| w.parse().unwrap()).collect();
    assert_eq!(epoch, rust.epoch);
    let r = [rust.q_rb.w, rust.q_rb.x, rust.q_rb.y, rust.q_rb.z];
    for (c, r) in q.iter().zip(r.iter()) {
        // same library code, same machine: the same floats (printed with 9 digits)
        assert!((c - r).abs() <= 1e-7, "C {q:?} vs Rust {r:?}");
    }

    for sentence in stdout.lines().filter_map(|l| l.strip_prefix("nmea: ")) {
        nmea::verify(sentence.as_bytes()).unwrap_or_else(|e| panic!("{sentence}: {e}"));
    }
    let hex = stdout
        .lines()
        .find_map(|l| l.strip_prefix("record (50 B): "))
        .expect("record line");
    let bytes: Vec<u8> = hex
        .split_whitespace()
        .map(|h| u8::from_str_radix(h, 16).unwrap())
        .collect();
    let rec = AttitudeRecord::decode(&bytes).unwrap();
    assert_eq!(rec.epoch, rust.epoch);
    assert_eq!(rec.q_rb, r);
}
