//! Puts `memory.x` on the linker path and computes, on the host, the self-test report the
//! firmware must reproduce on the target.

use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let root = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR")).join("../..");
    fs::copy(root.join("memory.x"), out.join("memory.x")).expect("copy memory.x");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=../../memory.x");

    let mut r = gnss_attitude::selftest::run_ekf_self_test().expect("host self-test runs");
    if env::var_os("CARGO_FEATURE_WRONG_EXPECTED").is_some() {
        r.state[0] += 0.5; // a deliberately wrong expectation
    }
    let expected = format!(
        "/// The self-test report computed on the host by build.rs.\n\
         const EXPECTED: SelfTestReport = SelfTestReport {{ state: {:?}, truth: {:?}, covariance_trace: {:?}, mean_nis: {:?}, mean_nees: {:?}, accepted: {} }};\n",
        r.state, r.truth, r.covariance_trace, r.mean_nis, r.mean_nees, r.accepted
    );
    fs::write(out.join("expected.rs"), expected).expect("write expected.rs");
}
