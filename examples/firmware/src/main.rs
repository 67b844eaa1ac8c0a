//! Self-check and budget firmware of gnss-attitude for the Cortex-M4F (`thumbv7em-none-eabihf`).
//!
//! Runs under `qemu-system-arm -machine netduinoplus2` (an STM32F405) and on real STM32F4-class
//! parts. It
//!
//! 1. runs the core's deterministic self-test and compares it with the report `build.rs`
//!    computed on the host; prints `selfcheck ekf: PASS|FAIL ...`;
//! 2. judges outcomes ([`outcome`]): the snapshot solver and the ambiguity resolver on their
//!    embedded example epoch, the receiver on the example flight (fine attitude within
//!    [`outcome::RECEIVER_LIMIT_DEG`] of the truth); prints `selfcheck <name>: PASS|FAIL ...`;
//! 3. measures budgets: each `budget::measure` region is bracketed by the marker instructions
//!    that QEMU's `insnmark` plugin counts (`mov r8, r8` … `mov r9, r9`), and its stack use is
//!    measured by painting the free stack before the call;
//! 4. exits through semihosting with success only if every self-check passed.
//!
//! Semihosting needs a debugger (or QEMU): on a board without one, the `hprintln!` calls halt.
#![no_std]
#![no_main]

mod budget;
mod cmdline;
mod outcome;

use cortex_m_rt::{entry, exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hprintln};
use gnss_attitude::selftest::{run_ekf_self_test, SelfTestReport};

include!(concat!(env!("OUT_DIR"), "/expected.rs"));

/// Largest relative difference accepted between the target's and the host's self-test
/// (both are IEEE-754 f32 with the same libm; differences come only from instruction
/// selection, e.g. fused multiply-add).
const TOLERANCE: f32 = 1e-4;

#[entry]
fn main() -> ! {
    cmdline::read();
    let mut all_passed = true;
    let expected = expected_report();

    match run_ekf_self_test() {
        Ok(report) => {
            let diff = report.max_relative_difference(&expected);
            let pass = diff <= TOLERANCE;
            all_passed &= pass;
            hprintln!(
                "selfcheck ekf: {} max relative difference to host {:e} (tolerance {:e}); state [{}, {}, {}, {}] host [{}, {}, {}, {}]; mean NIS {} NEES {}",
                if pass { "PASS" } else { "FAIL" },
                diff,
                TOLERANCE,
                report.state[0],
                report.state[1],
                report.state[2],
                report.state[3],
                expected.state[0],
                expected.state[1],
                expected.state[2],
                expected.state[3],
                report.mean_nis,
                report.mean_nees
            );
        }
        Err(e) => {
            all_passed = false;
            hprintln!("selfcheck ekf: FAIL self-test returned {:?}", e);
        }
    }

    all_passed &= signal_self_check();
    all_passed &= bitwise_self_check();

    all_passed &= outcome::snapshot();
    all_passed &= outcome::ambiguity();
    let receiver = budget::run_all();
    all_passed &= outcome::receiver(receiver.as_ref());

    if all_passed {
        hprintln!("selfcheck: all PASS");
        debug::exit(debug::EXIT_SUCCESS);
    } else {
        hprintln!("selfcheck: FAILED");
        debug::exit(debug::EXIT_FAILURE);
    }
    loop {
        cortex_m::asm::nop();
    }
}

/// The host's self-test report as the gate sees it: with `wrong-expected` on the command line
/// ([`cmdline`]) its first state off by 0.5, so the gate must fail.
fn expected_report() -> SelfTestReport {
    let mut expected = EXPECTED;
    if cmdline::wrong_expected() {
        expected.state[0] += 0.5;
    }
    expected
}

/// One antenna's host taps (E I/Q, P I/Q, L I/Q, N I/Q) as the gate sees them: with
/// `wrong-expected` on the command line the prompt I off by one, so the gate must fail.
fn expected_taps(host: &[i32; 8]) -> [i32; 8] {
    let mut expected = *host;
    expected[2] += i32::from(cmdline::wrong_expected());
    expected
}

/// The correlator on the target against the host's integers (must be equal).
fn signal_self_check() -> bool {
    use gnss_attitude::signal::selftest::run_correlator_self_test;
    let s = &budget::SIGNAL_SAMPLES;
    match run_correlator_self_test([&s[0], &s[1], &s[2]], [&s[3], &s[4], &s[5]]) {
        Ok(Some(e)) => {
            let mut equal = e.samples == EXPECTED_SAMPLES;
            for (t, x) in e.taps.iter().zip(EXPECTED_TAPS.iter()) {
                let row = [t.early.i, t.early.q, t.prompt.i, t.prompt.q, t.late.i, t.late.q, t.noise.i, t.noise.q];
                equal &= row == expected_taps(x);
            }
            hprintln!(
                "selfcheck correlator: {} ({} samples, 3 antennas x 4 taps bit-exact vs host; prompt I/Q of antenna 0: {} {})",
                if equal { "PASS" } else { "FAIL" },
                e.samples,
                e.taps[0].prompt.i,
                e.taps[0].prompt.q
            );
            equal
        }
        other => {
            hprintln!("selfcheck correlator: FAIL {:?}", other.map(|o| o.is_some()));
            false
        }
    }
}

/// The bit-parallel correlator on the target against the host's integers (must be equal).
fn bitwise_self_check() -> bool {
    use gnss_attitude::signal::bitwise::selftest::{pack_self_test, run_bit_correlator_self_test};
    use gnss_attitude::signal::bitwise::{CarrierLevels, PlaneFormat, Resolution};
    let s = &budget::SIGNAL_SAMPLES;
    let format = PlaneFormat { resolution: Resolution::TwoBit, complex: true };
    let (Ok(p0), Ok(p1), Ok(p2)) = (
        pack_self_test(format, &s[0], &s[3]),
        pack_self_test(format, &s[1], &s[4]),
        pack_self_test(format, &s[2], &s[5]),
    ) else {
        hprintln!("selfcheck bit-parallel correlator: FAIL packing");
        return false;
    };
    match run_bit_correlator_self_test(&budget::CODE_TABLE_2M6, [p0.planes(), p1.planes(), p2.planes()], CarrierLevels::Three) {
        Ok(Some(e)) => {
            let mut equal = e.samples == EXPECTED_SAMPLES;
            for (t, x) in e.taps.iter().zip(EXPECTED_BIT_TAPS.iter()) {
                let row = [t.early.i, t.early.q, t.prompt.i, t.prompt.q, t.late.i, t.late.q, t.noise.i, t.noise.q];
                equal &= row == expected_taps(x);
            }
            hprintln!(
                "selfcheck bit-parallel correlator: {} ({} samples, 2-bit complex, 3-level carrier, taps bit-exact vs host; prompt I/Q of antenna 0: {} {})",
                if equal { "PASS" } else { "FAIL" },
                e.samples,
                e.taps[0].prompt.i,
                e.taps[0].prompt.q
            );
            equal
        }
        other => {
            hprintln!("selfcheck bit-parallel correlator: FAIL {:?}", other.map(|o| o.is_some()));
            false
        }
    }
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    hprintln!("HardFault at pc {:#010x}", frame.pc());
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::nop();
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("panic: {}", info);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::nop();
    }
}
