//! Puts `memory.x` on the linker path and computes, on the host, the self-test report the
//! firmware must reproduce on the target.

use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let root = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR")).join("../..");
    if env::var_os("CARGO_FEATURE_QEMU_MPS2").is_some() {
        // QEMU's mps2-an386 (Cortex-M4 with FPU): flash at 0, 4 MiB of RAM. For the `realtime`
        // bin only, whose receiver's construction needs more than an STM32F405's 128 KiB
        // (it prints the RAM it used against that target).
        fs::write(
            out.join("memory.x"),
            "MEMORY\n{\n  FLASH : ORIGIN = 0x00000000, LENGTH = 4M\n  RAM : ORIGIN = 0x20000000, LENGTH = 4M\n}\n",
        )
        .expect("write memory.x");
    } else {
        fs::copy(root.join("memory.x"), out.join("memory.x")).expect("copy memory.x");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=../../memory.x");

    // (`wrong-expected` on the firmware's semihosting command line perturbs these at run time.)
    let r = gnss_attitude::selftest::run_ekf_self_test().expect("host self-test runs");
    let expected = format!(
        "/// The self-test report computed on the host by build.rs.\n\
         const EXPECTED: SelfTestReport = SelfTestReport {{ state: {:?}, truth: {:?}, covariance_trace: {:?}, mean_nis: {:?}, mean_nees: {:?}, accepted: {} }};\n",
        r.state, r.truth, r.covariance_trace, r.mean_nis, r.mean_nees, r.accepted
    );
    // The correlator is integer-only: the target must reproduce the host's taps exactly.
    use gnss_attitude::signal::selftest::{run_correlator_self_test, signal_self_test_samples};
    let s: Vec<_> = (1..=6u32).map(signal_self_test_samples).collect();
    let e = run_correlator_self_test([&s[0], &s[1], &s[2]], [&s[3], &s[4], &s[5]])
        .expect("host correlator self-test runs")
        .expect("one code period");
    let mut taps = Vec::new();
    for t in e.taps.iter() {
        let row = [t.early.i, t.early.q, t.prompt.i, t.prompt.q, t.late.i, t.late.q, t.noise.i, t.noise.q];
        taps.push(format!("{row:?}"));
    }
    let expected = format!(
        "{expected}/// The correlator self-test's taps per antenna (E I/Q, P I/Q, L I/Q, N I/Q), host.\n\
         const EXPECTED_TAPS: [[i32; 8]; 3] = [{}];\n/// Samples integrated on the host.\nconst EXPECTED_SAMPLES: u32 = {};\n",
        taps.join(", "),
        e.samples
    );
    // The bit-parallel correlator (2-bit complex planes, 3-level carrier: every stream kind).
    use gnss_attitude::signal::bitwise::selftest::{pack_self_test, run_bit_correlator_self_test};
    use gnss_attitude::signal::bitwise::{CarrierLevels, CodeTable, PlaneFormat, Resolution};
    let format = PlaneFormat { resolution: Resolution::TwoBit, complex: true };
    let table = CodeTable::new(2.6e6).expect("code table");
    let p: Vec<_> = (0..3).map(|a| pack_self_test(format, &s[a], &s[a + 3]).expect("pack")).collect();
    let e = run_bit_correlator_self_test(&table, [p[0].planes(), p[1].planes(), p[2].planes()], CarrierLevels::Three)
        .expect("host bit-parallel self-test runs")
        .expect("one code period");
    let mut taps = Vec::new();
    for t in e.taps.iter() {
        let row = [t.early.i, t.early.q, t.prompt.i, t.prompt.q, t.late.i, t.late.q, t.noise.i, t.noise.q];
        taps.push(format!("{row:?}"));
    }
    let expected = format!(
        "{expected}/// The bit-parallel self-test's taps per antenna (2-bit complex, 3-level carrier), host.\n\
         const EXPECTED_BIT_TAPS: [[i32; 8]; 3] = [{}];\n",
        taps.join(", ")
    );
    fs::write(out.join("expected.rs"), expected).expect("write expected.rs");
}
