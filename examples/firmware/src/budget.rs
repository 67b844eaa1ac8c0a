//! Budgets: instructions (counted by QEMU's `insnmark` plugin between marker instructions) and
//! stack (by painting) of single calls into the core.
//!
//! Each measured region prints `budget region <n>: <name>, stack <bytes> B`; the plugin prints
//! `insnmark: region <n>: <count> instructions` for the same `<n>`. `.ci/run` joins the two.
//! To add a budget, write a function below and call it from [`run_all`].

use core::hint::black_box;
use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m_semihosting::hprintln;
use gnss_attitude::ekf::{Ekf, GateConfidence, NisGate};
use gnss_attitude::selftest::ConstantVelocityModel;
use gnss_attitude::signal::selftest::{
    run_correlator_self_test, signal_self_test_samples, SIGNAL_SELF_TEST_LEN, SIGNAL_SELF_TEST_RATE_HZ,
};
use gnss_attitude::signal::{Correlator, CorrelatorConfig, Prn, SampleBlock};
use gnss_attitude::tracking::{Acquisition, AcquisitionConfig, Channel, ChannelConfig, SearchResult};
use nalgebra::{Matrix4, SMatrix, SVector, Vector2, Vector4};

/// Six sample streams (I and Q of three antennas), one code period at 2.6 Msps, built at
/// compile time into flash.
pub static SIGNAL_SAMPLES: [[i8; SIGNAL_SELF_TEST_LEN]; 6] = [
    signal_self_test_samples(1),
    signal_self_test_samples(2),
    signal_self_test_samples(3),
    signal_self_test_samples(4),
    signal_self_test_samples(5),
    signal_self_test_samples(6),
];

static REGION: AtomicU32 = AtomicU32::new(0);

const PAINT: u32 = 0xCCCC_CCCC;

extern "C" {
    static mut _stack_end: u32;
}

/// Paints the free stack, from its bottom to 32 bytes below the current stack pointer (inlined
/// into the caller, so that the painted region ends just under the caller's frame).
#[inline(always)]
fn paint_free_stack() {
    let sp = cortex_m::register::msp::read() as usize;
    // SAFETY: the words between the stack's bottom and SP − 32 are not live (the stack grows
    // down and nothing below SP is in use on a single-threaded system without interrupts).
    unsafe {
        let mut p = core::ptr::addr_of_mut!(_stack_end);
        while (p as usize) < sp - 32 {
            core::ptr::write_volatile(p, PAINT);
            p = p.add(1);
        }
    }
}

/// Bytes of stack used below `sp` since [`paint_free_stack`].
fn stack_used_below(sp: usize) -> usize {
    // SAFETY: reads words of the stack region below SP; volatile, no aliasing with live data.
    unsafe {
        let mut p = core::ptr::addr_of!(_stack_end);
        while (p as usize) < sp && core::ptr::read_volatile(p) == PAINT {
            p = p.add(1);
        }
        sp.saturating_sub(p as usize)
    }
}

/// Runs `f` once between the instruction-count markers and reports its stack use.
#[inline(never)]
pub fn measure<R>(name: &str, f: impl FnOnce() -> R) -> R {
    let n = REGION.fetch_add(1, Ordering::Relaxed);
    paint_free_stack();
    let sp = cortex_m::register::msp::read() as usize;
    // SAFETY: the markers are register-to-self moves with no effect on program state.
    unsafe { core::arch::asm!("mov r8, r8") };
    let out = black_box(f());
    unsafe { core::arch::asm!("mov r9, r9") };
    let used = stack_used_below(sp);
    hprintln!("budget region {}: {}, stack {} B", n, name, used);
    out
}

/// Every budget of the firmware, in region order.
pub fn run_all() {
    ekf_budgets();
    signal_budgets();
}

fn signal_budgets() {
    let s = &SIGNAL_SAMPLES;
    let i = [&s[0][..], &s[1][..], &s[2][..]];
    let q = [&s[3][..], &s[4][..], &s[5][..]];
    // One 1 ms code period (2600 samples) of the 3-antenna correlator, E/P/L + noise taps.
    let _ = measure("correlator 3 ant x 1 sat, 1 ms @ 2.6 Msps complex i8, E/P/L+N (2600 samples)", || {
        run_correlator_self_test(black_box(i), black_box(q)).is_ok()
    });
    // Prompt-only slaves (what paper 003's filter needs): E/P/L+N on the reference antenna,
    // P on the other two.
    let cfg_p = CorrelatorConfig {
        sample_rate_hz: SIGNAL_SELF_TEST_RATE_HZ,
        intermediate_frequency_hz: 0.0,
        early_late_offset_chips: 0.5,
        slave_taps: gnss_attitude::signal::SlaveTaps::Prompt,
    };
    if let (Some(prn), Ok(block)) = (Prn::new(5), SampleBlock::complex(0, i, q)) {
        if let Ok(mut corr) = Correlator::<3>::new(prn, &cfg_p) {
            let _ = corr.set_carrier_frequency(2345.0);
            let _ = corr.set_code_phase(0.0);
            let _ = measure("correlator 3 ant x 1 sat, 1 ms @ 2.6 Msps complex, E/P/L+N ref + P slaves", || {
                let mut cursor = 0;
                black_box(&mut corr).run(black_box(&block), &mut cursor).is_ok()
            });
        }
    }
    // The same on real IF samples (2-bit-style front ends).
    let cfg = CorrelatorConfig {
        sample_rate_hz: SIGNAL_SELF_TEST_RATE_HZ,
        intermediate_frequency_hz: 650_000.0,
        early_late_offset_chips: 0.5,
        slave_taps: gnss_attitude::signal::SlaveTaps::All,
    };
    if let (Some(prn), Ok(block)) = (Prn::new(5), SampleBlock::real(0, i)) {
        if let Ok(mut corr) = Correlator::<3>::new(prn, &cfg) {
            let _ = corr.set_code_phase(0.0);
            let _ = measure("correlator 3 ant x 1 sat, 1 ms @ 2.6 Msps real IF, E/P/L+N (2600 samples)", || {
                let mut cursor = 0;
                black_box(&mut corr).run(black_box(&block), &mut cursor).is_ok()
            });
        }
    }
    // One tracking epoch: correlator + discriminators + loop filters + lock/C/N0 windows.
    let ch_cfg = ChannelConfig::new(SIGNAL_SELF_TEST_RATE_HZ, 0.0);
    if let (Some(prn), Ok(block)) = (Prn::new(5), SampleBlock::complex(0, i, q)) {
        if let Ok(mut ch) = Channel::<3>::new(prn, &ch_cfg) {
            let acq = SearchResult {
                prn,
                detected: true,
                metric: 10.0,
                threshold: 2.0,
                doppler_hz: 2345.0,
                code_phase_chips: 1022.9,
                first_sample: 0,
            };
            let mut cursor = 0;
            if ch.start(&acq).is_ok() {
                // The hand-over's partial period (a sample or so), then one full period.
                let _ = ch.process(&block, &mut cursor);
                let _ = measure("tracking channel: 1 epoch (correlator + loops), 3 antennas, 2.6 Msps", || {
                    black_box(&mut ch).process(black_box(&block), &mut cursor).is_ok()
                });
            }
        }
    }
    // Acquisition: one Doppler bin x one millisecond, N = 1024 (the target's size).
    if let (Ok(mut acq), Some(prn)) = (Acquisition::<1024>::new(), Prn::new(5)) {
        let cfg = AcquisitionConfig {
            sample_rate_hz: SIGNAL_SELF_TEST_RATE_HZ,
            intermediate_frequency_hz: 0.0,
            doppler_max_hz: 0.0,
            doppler_step_hz: 500.0,
            noncoherent_ms: 1,
            false_alarm_probability: 1e-3,
        };
        let _ = measure("acquisition N=1024: 1 PRN x 1 Doppler bin x 1 ms (mix, 2 FFTs, threshold)", || {
            black_box(&mut acq).search(prn, black_box(&s[0][..]), Some(black_box(&s[3][..])), 0, &cfg).is_ok()
        });
    }
}

fn ekf_budgets() {
    let model = ConstantVelocityModel::new(0.1, 0.2, 0.5);
    let mut cv = match Ekf::new(Vector4::new(1.0, 2.0, 0.5, -0.5), Matrix4::identity() * 4.0) {
        Ok(k) => k,
        Err(_) => return,
    };
    let z = Vector2::new(1.1, 1.9);
    let _ = measure("ekf4 predict+update2 (constant velocity, Joseph, gated)", || {
        model.step(black_box(&mut cv), black_box(&z)).is_ok()
    });

    let p0 = SMatrix::<f32, 6, 6>::from_diagonal(&SVector::from([1e-2, 1e-2, 1e-2, 1e-4, 1e-4, 1e-4]));
    let mut six = match Ekf::<6>::new(SVector::zeros(), p0) {
        Ok(k) => k,
        Err(_) => return,
    };
    let mut f = SMatrix::<f32, 6, 6>::identity();
    f.fixed_view_mut::<3, 3>(0, 3).fill_with_identity();
    let q = SMatrix::<f32, 6, 6>::identity() * 1e-8;
    let h = SMatrix::<f32, 3, 6>::from_fn(|i, j| if j < 3 { (i as f32 + 2.0 * j as f32) * 0.1 - 0.2 } else { 0.0 });
    let r = SMatrix::<f32, 3, 3>::identity() * 1e-4;
    let y = SVector::<f32, 3>::new(1e-3, -2e-3, 5e-4);
    let gate = Some(NisGate::chi_square(3, GateConfidence::P999));
    let _ = measure("ekf6 predict+update3 (Joseph, gated)", || {
        let a = black_box(&mut six).predict(black_box(&f), black_box(&q)).is_ok();
        a && six.update(black_box(&y), &h, &r, gate).is_ok()
    });
    let r_diag = r.diagonal();
    let _ = measure("ekf6 predict+sequential3 (scalar Joseph)", || {
        let a = black_box(&mut six).predict(black_box(&f), black_box(&q)).is_ok();
        a && six.update_sequential(black_box(&y), &h, &r_diag, None).is_ok()
    });
}
