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
use gnss_attitude::attitude::array::{AntennaArray, BaselinePair};
use gnss_attitude::attitude::baseline_epoch::BaselineEpoch;
use gnss_attitude::attitude::dcm_filter::{DcmFilterConfig, DirectionCosineFilter};
use gnss_attitude::attitude::multi_structure::MultiStructureFilter;
use gnss_attitude::attitude::rigid_body::{RigidBodyConfig, RigidBodyFilter};
use gnss_attitude::geometry::{rot_x, rot_y, rot_z, Quaternion};
use gnss_attitude::gyro::{
    default_rank_tolerance, CalibratorConfig, EpochOutcome, LeastSquaresAccumulator,
    NormalEquations, PaperCalibrator, SqrtInformation,
};
use gnss_attitude::attitude::one_stage::{EstimatedAngles, FilterMode, OneStageConfig, OneStageFilter, PhaseModel, Prior, PromptIq, SatelliteObservation, MAX_SATELLITES};
use gnss_attitude::receiver::{AdapterConfig, EpochClock, ObservationAdapter};
use gnss_attitude::geometry::Paper003Angles;
use gnss_attitude::signal::selftest::{
    run_correlator_self_test, signal_self_test_samples, SIGNAL_SELF_TEST_LEN, SIGNAL_SELF_TEST_RATE_HZ,
};
use gnss_attitude::signal::{Correlator, CorrelatorConfig, EpochCorrelations, Iq, Prn, SampleBlock, SampleFormat, Taps};
use gnss_attitude::signal::bitwise::selftest::{pack_self_test, self_test_correlator, BIT_SELF_TEST_WORDS};
use gnss_attitude::signal::bitwise::{BitBlock, BitScratch, CarrierLevels, CodeTable, PlaneBuffer, PlaneFormat, Resolution};
use gnss_attitude::tracking::{
    Acquisition, AcquisitionConfig, Channel, ChannelConfig, ChannelState, LockFlags, SearchResult, TrackingEpoch,
};
use nalgebra::{ComplexField, Matrix3, Matrix4, SMatrix, SVector, Vector2, Vector3, Vector4};

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

/// The bit-parallel correlator's code expansion table for 2.6 Msps (8 KiB), built at compile
/// time into flash: the nominal code step `round(1.023e6 / 2.6e6 · 2³²)`.
pub static CODE_TABLE_2M6: CodeTable = CodeTable::from_step((1.023e6 / 2.6e6 * 4_294_967_296.0 + 0.5) as u64);

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

/// Calls `f` in a frame of its own, below the caller's stack pointer, so that everything `f`
/// (and whatever the optimizer inlines into it) puts on the stack is below the measuring
/// point.
#[inline(never)]
fn call<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// Runs `f` once between the instruction-count markers and reports its stack use (including
/// the few bytes of the `call` trampoline frame): [`measure_named`] with a plain name.
#[inline(never)]
pub fn measure<R>(name: &str, f: impl FnOnce() -> R) -> R {
    measure_named(format_args!("{}", name), f)
}

/// Runs `f` once between the instruction-count markers (only `f` is counted: the name is
/// formatted after the stop marker) and reports its stack use.
#[inline(never)]
pub fn measure_named<R>(name: core::fmt::Arguments<'_>, f: impl FnOnce() -> R) -> R {
    let n = REGION.fetch_add(1, Ordering::Relaxed);
    paint_free_stack();
    let sp = cortex_m::register::msp::read() as usize;
    // SAFETY: the markers are register-to-self moves with no effect on program state.
    unsafe { core::arch::asm!("mov r8, r8") };
    let out = call(f);
    // The stop marker right after the return (QEMU 7.2's plugin missed a stop marker that
    // followed the result's store in one layout, shifting every later region by one).
    // SAFETY: as the start marker.
    unsafe { core::arch::asm!("mov r9, r9") };
    let out = black_box(out);
    let used = stack_used_below(sp);
    hprintln!("budget region {}: {}, stack {} B", n, name, used);
    out
}

/// Every budget of the firmware, in region order.
pub fn run_all() -> Option<ReceiverOutcome> {
    ekf_budgets();
    correlator_budgets();
    bitwise_budgets();
    packing_budgets();
    tracking_budgets();
    acquisition_budget();
    shared_acquisition_budget();
    fft_budget();
    snapshot_budgets();
    dcm_budgets();
    gyro_budgets();
    one_stage_budgets();
    let receiver = receiver_budgets();
    gyro_aided_budgets();
    nav_budgets();
    receiver
}

// (not inlined: each group's locals get a frame of their own, so the stack is the largest
// group's, not the sum of all)
#[inline(never)]
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

/// Paper 002: one snapshot solve (8 satellites, ambiguities known) and one solve from raw
/// single differences with the constrained integer ambiguity search (8 satellites).
// (not inlined: each group's locals get a frame of their own, so the stack is the largest
// group's, not the sum of all)
#[inline(never)]
fn snapshot_budgets() {
    use gnss_attitude::attitude::example;
    let (Ok(solver), Ok(resolver)) = (example::solver(), example::resolver()) else {
        hprintln!("budget snapshot: example setup failed");
        return;
    };
    let (Ok(ranges), Ok(phases)) = (example::ranges(8, 1), example::phases(8, 1)) else {
        hprintln!("budget snapshot: example data failed");
        return;
    };
    // The calls go through `#[inline(never)]` wrappers so that their frames lie below the
    // painted stack and are counted.
    let ok = measure("snapshot solve, 2 baselines x 8 satellites (Wahba + Gauss-Newton)", || {
        solve_once(black_box(&solver), black_box(&ranges))
    });
    let fix = measure("ambiguity resolve + snapshot, 2 baselines x 8 satellites (LAMBDA + constrained search)", || {
        resolve_once(black_box(&resolver), black_box(&phases))
    });
    match fix {
        Ok(f) => hprintln!(
            "budget snapshot: solve ok {}, fix nodes {} candidates {} ratio {} z00 {} (truth {})",
            ok,
            f.nodes,
            f.candidates,
            f.ratio,
            f.ambiguities[0][0],
            example::ambiguity(0, 0)
        ),
        Err(e) => hprintln!("budget snapshot: resolve refused: {:?}", e),
    }
}

#[inline(never)]
fn solve_once(
    solver: &gnss_attitude::attitude::snapshot::SnapshotSolver<2>,
    ranges: &gnss_attitude::attitude::range_model::RangeDifferences<2, 12>,
) -> bool {
    solver.solve(ranges).is_ok()
}

#[inline(never)]
fn resolve_once(
    resolver: &gnss_attitude::attitude::ambiguity::AmbiguityResolver<2>,
    phases: &gnss_attitude::attitude::ambiguity::PhaseObservations<2, 12>,
) -> Result<gnss_attitude::attitude::ambiguity::AmbiguityFix<2, 12>, gnss_attitude::attitude::ambiguity::AmbiguityError> {
    resolver.resolve(phases)
}

/// One step of each paper-000 filter on the paper's array (noise-free epoch near t = 1 s).
// (not inlined: each group's locals get a frame of their own, so the stack is the largest
// group's, not the sum of all)
#[inline(never)]
fn dcm_budgets() {
    let Ok(array) = AntennaArray::from_baselines(
        &black_box(Vector3::new(1.5f32, 1.8, 1.9)),
        &black_box(Vector3::new(1.7f32, 1.7, 2.0)),
    ) else {
        return;
    };
    let c0 = rot_z(black_box(0.1f32)) * rot_y(0.02) * rot_x(0.03);
    let c1 = rot_z(black_box(0.1011f32)) * rot_y(0.0202) * rot_x(0.0301);
    let mut epoch = BaselineEpoch::default();
    for pair in BaselinePair::ALL {
        let b = array.baseline(pair);
        epoch.baselines[pair.index()] = Some(c1 * b);
        epoch.velocity_differences[pair.index()] = Some((c1 - c0) * b / 0.01);
    }
    let config = DcmFilterConfig::paper(0.01f32, 0.6, 0.1);
    let r0 = SMatrix::<f32, 6, 6>::identity() * 1e-4;
    if let Ok(mut six) = DirectionCosineFilter::new(&array, config, &c0, &r0) {
        let _ = measure("dcm six-state step (RK4 of eq. 10, Givens QR inverse x4, estimate)", || {
            black_box(&mut six).step(black_box(&epoch)).is_ok()
        });
    }
    if let Ok(mut multi) = MultiStructureFilter::new(&array, config, &c0, &r0) {
        let _ = measure("dcm multi-structure step (3 six-state filters + combination)", || {
            black_box(&mut multi).step(black_box(&epoch)).is_ok()
        });
    }
    let rigid_config = RigidBodyConfig {
        dt: 0.01f32,
        sigma_baseline: 0.6,
        sigma_velocity: 0.1,
        gate: Some(GateConfidence::P999),
    };
    let q0 = Quaternion::from_dcm(&c0).unwrap_or_default();
    if let Ok(mut rigid) = RigidBodyFilter::new(&array, rigid_config, &q0, &(Matrix3::identity() * 1e-4)) {
        let _ = measure("dcm rigid-body step (LS rate, ekf3 predict, 3 gated 3-D updates)", || {
            black_box(&mut rigid).step(black_box(&epoch)).is_ok()
        });
    }
}

/// Paper 001 §6 on the target: 30 s of the paper's rates with its gyro errors against a perfect
/// reference (131 epochs, 393 rows), then one of each step on the filled accumulators.
// (not inlined: each group's locals get a frame of their own, so the stack is the largest
// group's, not the sum of all)
#[inline(never)]
fn gyro_budgets() {
    const RATES: [[f32; 3]; 6] = [
        [0.01, 0.02, -0.01],
        [0.02, 0.32, -0.015],
        [0.01, 0.01, -0.02],
        [0.16, 0.015, -0.03],
        [0.03, 0.017, -0.16],
        [0.02, 0.02, -0.02],
    ];
    let h = 0.02f32;
    let bias = Vector3::new(1e-5f32, -1e-5, -1e-5);
    let scale = 3e-4f32;
    let w0 = Quaternion::from_rotation_vector(&Vector3::new(2e-3f32, 2e-3, 2e-3));
    let lambda0 = Quaternion::new(0.64f32, 0.48, 0.36, -0.48);
    let mut cal = match PaperCalibrator::<SqrtInformation<15>>::paper(
        CalibratorConfig::new(h),
        SqrtInformation::new(),
        w0.conjugate() * lambda0,
        lambda0,
    ) {
        Ok(c) => c,
        Err(_) => return,
    };
    let mut normal = NormalEquations::<15>::new();
    let mut truth = lambda0;
    let mut row = (SVector::<f32, 15>::zeros(), 0.0f32);
    for k in 1..=1500usize {
        let w = Vector3::from(RATES[((k - 1) / 250).min(5)]);
        truth = truth * Quaternion::from_rotation_vector(&(w * h));
        if cal
            .push_increment(&((w * (1.0 + scale) + bias) * h))
            .is_err()
        {
            return;
        }
        if k >= 200 && k % 10 == 0 {
            if let Ok(EpochOutcome::Used(eq)) = cal.add_reference(&truth) {
                for r in 0..3 {
                    row = (eq.rows.row(r).transpose(), eq.rhs[r]);
                    let _ = normal.add_row(&row.0, row.1);
                }
            }
        }
    }
    let tol = default_rank_tolerance::<f32>();
    let theta = Vector3::new(4e-4f32, 6.4e-3, -3e-4);
    let mut prop = cal.clone();
    let _ = measure(
        "gyro propagation step H (two increments, coning, quadratures)",
        || {
            let a = black_box(&mut prop)
                .push_increment(black_box(&theta))
                .is_ok();
            a && prop.push_increment(black_box(&theta)).is_ok()
        },
    );
    let mut epoch = cal.clone();
    let _ = measure(
        "gyro calibrator epoch (eq. 2.7 rows + 3 Givens rows, 15 unknowns)",
        || {
            black_box(&mut epoch)
                .add_reference(black_box(&truth))
                .is_ok()
        },
    );
    let mut givens = *cal.accumulator();
    let _ = measure("gyro Givens accumulation of one row (15 unknowns)", || {
        black_box(&mut givens)
            .add_row(black_box(&row.0), black_box(row.1))
            .is_ok()
    });
    let mut ne = normal;
    let _ = measure(
        "gyro normal-equation accumulation of one row, eq. (5.8)",
        || {
            black_box(&mut ne)
                .add_row(black_box(&row.0), black_box(row.1))
                .is_ok()
        },
    );
    let givens = *cal.accumulator();
    let solved = measure(
        "gyro Givens solve + observability (2 Jacobi SVDs, 15 unknowns)",
        || {
            black_box(&givens)
                .solve(black_box(tol))
                .map(|s| s.observability.rank)
        },
    );
    let _ = measure(
        "gyro normal-equation solve + observability (Cholesky)",
        || {
            black_box(&normal)
                .solve(black_box(tol))
                .map(|s| s.observability.rank)
        },
    );
    hprintln!("gyro budgets: Givens solve rank {:?}", solved);
}

/// `n ≤ 12` satellites spread over the sky with noise-free-plus-wobble prompt outputs at
/// 40 dB-Hz (the bench's data), on the stack.
fn one_stage_observations(
    array: &AntennaArray<f32>,
) -> [SatelliteObservation<f32>; MAX_SATELLITES] {
    let truth = Paper003Angles::new(0.001, -0.002, 0.0015);
    let model = PhaseModel::new(array, 0.190_293_7, &truth);
    let amp = ComplexField::sqrt(20.0f32) * 40.0;
    let mut out = [SatelliteObservation::default(); MAX_SATELLITES];
    for (i, o) in out.iter_mut().enumerate() {
        let az = i as f32 * 0.52;
        let el = 0.15 + 1.3 * i as f32 / MAX_SATELLITES as f32;
        let los = [
            ComplexField::cos(el) * ComplexField::cos(az),
            ComplexField::cos(el) * ComplexField::sin(az),
            ComplexField::sin(el),
        ];
        let psi = model.phases(&Vector3::from(los));
        let mut prompt = PromptIq::default();
        for (p, (pi, pq)) in prompt.i.iter_mut().zip(prompt.q.iter_mut()).enumerate() {
            let th = 0.3 * i as f32 + psi[p];
            let wobble = 4.0 * ComplexField::sin((i * 3 + p) as f32);
            *pi = amp * ComplexField::cos(th) + wobble;
            *pq = amp * ComplexField::sin(th) - wobble;
        }
        *o = SatelliteObservation { id: i as u8 + 1, los, prompt, noise_var: 1600.0, cn0_dbhz: 40.0 };
    }
    out
}

// (not inlined: each group's locals get a frame of their own, so the stack is the largest
// group's, not the sum of all)
#[inline(never)]
fn one_stage_budgets() {
    let Ok(array) = AntennaArray::paper_triangle(1.5f32) else { return };
    let obs = one_stage_observations(&array);
    one_stage_budget::<8>(&array, &obs, "one-stage step, 12 sats, Gaussian approx., 3 angles + 2 biases (N = 8)", FilterMode::GaussianApproximation, EstimatedAngles::ALL, true, MAX_SATELLITES);
    one_stage_budget::<8>(&array, &obs, "one-stage step, 12 sats, constant gain, 3 angles + 2 biases (N = 8)", FilterMode::ConstantGain, EstimatedAngles::ALL, true, MAX_SATELLITES);
    one_stage_budget::<2>(&array, &obs, "one-stage step, 12 sats, Gaussian approx., beta only (N = 2)", FilterMode::GaussianApproximation, EstimatedAngles::BETA_ONLY, false, MAX_SATELLITES);
    one_stage_budget::<2>(&array, &obs, "one-stage step, 8 sats, Gaussian approx., beta only (paper, N = 2)", FilterMode::GaussianApproximation, EstimatedAngles::BETA_ONLY, false, 8);
    one_stage_adapter_budget();
}

/// The adapter from the tracking channels: one `TrackingEpoch<3>` → observation and its
/// filter epoch (per channel and code period).
// (not inlined: each group's locals get a frame of their own, so the stack is the largest
// group's, not the sum of all)
#[inline(never)]
fn one_stage_adapter_budget() {
    let taps = |p: i32, n: i32| Taps {
        prompt: Iq { i: 40_000 + p, q: -25_000 + 3 * p },
        noise: Iq { i: 9_000 - n, q: 7_000 + n },
        ..Taps::default()
    };
    let Some(prn) = Prn::new(5) else { return };
    let mut epoch = TrackingEpoch {
        prn,
        index: 1000,
        correlations: EpochCorrelations {
            taps: [taps(0, 0), taps(100, 50), taps(-80, -20)],
            samples: 2600,
            first_sample: 2_600_000,
            code_phase_at_first: 0,
            carrier_phase_at_first: 0,
            complete: true,
        },
        doppler_hz: 1200.0,
        cn0_dbhz: 40.0,
        lock: LockFlags { code: true, phase: true, bit_sync: true },
        state: ChannelState::Tracking,
        phase_error_cycles: 0.0,
        code_error_chips: 0.0,
        data_bit: None,
    };
    let (Ok(mut adapter), Ok(clock)) = (ObservationAdapter::new(AdapterConfig::default()), EpochClock::new(2_600_000, 2600)) else {
        return;
    };
    for k in 0..300 {
        epoch.correlations.taps[1].noise.i = 8_000 + 7 * k;
        let _ = adapter.observe(&epoch, [0.0, 0.6, 0.8]);
    }
    let _ = measure("one-stage adapter: TrackingEpoch<3> -> observation + filter epoch", || {
        let o = black_box(&mut adapter).observe(black_box(&epoch), black_box([0.0, 0.6, 0.8]));
        let k = clock.epoch_of(&black_box(epoch).correlations);
        matches!(o, Ok(Some(_))) && k.is_some()
    });
}

#[allow(clippy::too_many_arguments)]
fn one_stage_budget<const N: usize>(
    array: &AntennaArray<f32>,
    obs: &[SatelliteObservation<f32>; MAX_SATELLITES],
    name: &str,
    mode: FilterMode,
    estimate: EstimatedAngles,
    bias: bool,
    n: usize,
) {
    let prior = Prior::new(Paper003Angles::new(0.0, 0.0, 0.0), 0.01, 0.001);
    let mut config = OneStageConfig::gps_l1(mode, 2.0);
    config.estimate = estimate;
    config.line_bias_states = bias;
    let Ok(mut filter) = OneStageFilter::<f32, N>::new(config, *array, &prior) else { return };
    let Some(epoch) = obs.get(..n) else { return };
    // a few epochs first, so that the measured one is a steady-state step
    for _ in 0..20 {
        let _ = filter.step(epoch);
    }
    let _ = measure(name, || black_box(&mut filter).step(black_box(epoch)).is_ok());
}

// (not inlined: each group's locals get a frame of their own, so the stack is the largest
// group's, not the sum of all)
#[inline(never)]
fn correlator_budgets() {
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
}

/// One tracking epoch and the refinement's frequency estimates.
#[inline(never)]
fn tracking_budgets() {
    let s = &SIGNAL_SAMPLES;
    let i = [&s[0][..], &s[1][..], &s[2][..]];
    let q = [&s[3][..], &s[4][..], &s[5][..]];
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
    // The end of the refinement stage (one epoch per hand-over): the residual Doppler from
    // 256 squared prompts, and with the LEO Doppler-rate estimate.
    let mut squares = [[0.0f32; 2]; gnss_attitude::tracking::channel::REFINEMENT_EPOCHS];
    for (k, z) in squares.iter_mut().enumerate() {
        let t = k as f32 * 1e-3;
        let w = core::f32::consts::TAU * (2.0 * 37.0 * t + 60.0 * t * t);
        *z = [nalgebra::ComplexField::cos(w), nalgebra::ComplexField::sin(w)];
    }
    let _ = measure("refinement: residual Doppler from 256 squared prompts", || {
        gnss_attitude::tracking::channel::refine_frequency(black_box(&squares), black_box(1e-3))
    });
    let _ = measure("refinement: residual Doppler + rate (LEO), 256 squared prompts", || {
        gnss_attitude::tracking::channel::refine_frequency_and_rate(
            black_box(&squares),
            black_box(1e-3),
            black_box(150.0),
        )
    });
}

/// Acquisition: one Doppler bin x one millisecond, N = 1024 (the target's size). Its own
/// frame: the engine is the largest object of the self-check (tens of KiB).
#[inline(never)]
fn acquisition_budget() {
    let s = &SIGNAL_SAMPLES;
    // (made blank where it stays and built there: one copy of it on the stack)
    let mut engine = Acquisition::<1024>::blank();
    if engine.build().is_err() {
        hprintln!("budget acquisition: engine refused");
        return;
    }
    let acq = &mut engine;
    let Some(prn) = Prn::new(5) else { return };
    let cfg = AcquisitionConfig {
        sample_rate_hz: SIGNAL_SELF_TEST_RATE_HZ,
        intermediate_frequency_hz: 0.0,
        doppler_max_hz: 0.0,
        doppler_step_hz: 500.0,
        noncoherent_ms: 1,
        false_alarm_probability: 1e-3,
    };
    let _ = measure("acquisition N=1024: 1 PRN x 1 Doppler bin x 1 ms (mix, 2 FFTs, threshold)", || {
        black_box(&mut *acq).search(prn, black_box(&s[0][..]), Some(black_box(&s[3][..])), 0, &cfg).is_ok()
    });
}

/// Lanes of the shared-FFT acquisition measured below (Doppler bins of one sub-bin offset
/// searched from one mix + FFT per millisecond): `.ci/run` derives the warm and cold starts
/// with the same number.
pub const SHARED_LANES: usize = 4;

/// The shared-FFT search (radix-4 FFT, whole-kHz Doppler steps as spectrum shifts,
/// `SHARED_LANES` bins per mix + FFT of the data) on noise, N = 1024, one PRN: 1 bin
/// (1 chunk), ±1 kHz (5 bins, 2 chunks), ±1.5 kHz (7 bins, 2 chunks) over 1 ms, ±1.5 kHz
/// over 2 ms, and the threshold for K = 1, 2, 6 and 8 over a cold grid's cells. `.ci/run`
/// solves these for the per-search, per-chunk·ms, per-bin·ms and per-bin costs. Its own
/// frame: the engine (54 KiB with 4 lanes, made with `blank` and built in place: `new`, by
/// value, left copies of it in this frame) is the largest object of the self-check.
#[inline(never)]
fn shared_acquisition_budget() {
    let s = &SIGNAL_SAMPLES;
    // (made blank where it stays and built there: one copy of the engine on the stack)
    let mut engine = Acquisition::<1024, SHARED_LANES>::blank();
    if engine.build().is_err() {
        hprintln!("budget shared acquisition: engine refused");
        return;
    }
    let acq = &mut engine;
    let Some(prn) = Prn::new(5) else { return };
    // 2 ms of noise: the flash's millisecond twice over.
    let (mut i, mut q) = ([0i8; 2 * SIGNAL_SELF_TEST_LEN], [0i8; 2 * SIGNAL_SELF_TEST_LEN]);
    for (k, (a, b)) in i.iter_mut().zip(q.iter_mut()).enumerate() {
        *a = s[0][k % SIGNAL_SELF_TEST_LEN];
        *b = s[3][(k * 7) % SIGNAL_SELF_TEST_LEN];
    }
    for (max, bins, ms) in [(0.0f32, 1, 1u16), (1000.0, 5, 1), (1500.0, 7, 1), (1500.0, 7, 2)] {
        let cfg = AcquisitionConfig {
            sample_rate_hz: SIGNAL_SELF_TEST_RATE_HZ,
            intermediate_frequency_hz: 0.0,
            doppler_max_hz: max,
            doppler_step_hz: 500.0,
            noncoherent_ms: ms,
            false_alarm_probability: 1e-3,
        };
        let _ = measure_named(format_args!("shared acquisition N=1024 L={}: 1 PRN x {} bins x {} ms", SHARED_LANES, bins, ms), || {
            black_box(&mut *acq).search(prn, black_box(&i[..]), Some(black_box(&q[..])), 0, &cfg).is_ok()
        });
    }
    for k in [1u16, 2, 6, 8] {
        let _ = measure_named(format_args!("acquisition threshold K={}: 201 x 1024 cells", k), || {
            gnss_attitude::tracking::acquisition::detection_threshold(black_box(k), black_box(201.0 * 1024.0), black_box(1e-3))
        });
    }
}

/// One 1024-point forward FFT (the acquisition's), in a frame of its own.
#[inline(never)]
fn fft_budget() {
    let s = &SIGNAL_SAMPLES;
    if let Some(fft) = gnss_attitude::tracking::fft::Fft::<1024>::new() {
        let mut x = [[0.0f32; 2]; 1024];
        for (k, v) in x.iter_mut().enumerate() {
            *v = [f32::from(s[0][k]), f32::from(s[3][k])];
        }
        measure("fft N=1024 forward (radix 4)", || fft.forward(black_box(&mut x)));
    }
}

/// Epochs of the receiver's example flight on the target (3 s: the cold start, the fine
/// filter's pull-in, then steady fine tracking through the third 1 s integrity window).
pub const FLIGHT_EPOCHS: u64 = 3000;

/// The receiver's state at the end of the example flight, for the self-check to judge.
pub struct ReceiverOutcome {
    /// Which stage produced the final attitude.
    pub source: gnss_attitude::receiver::AttitudeSource,
    /// The final attitude `q_rb`.
    pub attitude: Quaternion,
    /// The flight's true attitude at the final attitude's epoch.
    pub truth: Quaternion,
    /// The final attitude's epoch.
    pub epoch: u64,
    /// Refusals of the receiver's calls during the flight (must be 0).
    pub refusals: u32,
}

/// What is measured in one epoch of the flight.
#[derive(Clone, Copy, PartialEq)]
enum Profile {
    /// Nothing.
    None,
    /// The whole epoch in one region: the observations pushed and the epoch closed.
    Whole(&'static str),
    /// Three regions: the 8 observations pushed, `close_through` of the epoch (the 1 ms
    /// path: the block or window only captured), then `run_deferred` (its stages).
    Split(&'static str, &'static str, &'static str),
}

/// One epoch of the example flight: the aiding every 100 epochs, a gyro increment every 10
/// (not measured), the observations of 8 satellites x 3 antennas pushed, the epoch closed,
/// the deferred stages run (the receiver is in deferred mode); measured as `profile` says.
/// Counts the receiver's refusals.
fn flight_epoch(
    r: &mut gnss_attitude::receiver::AttitudeReceiver,
    flight: &mut gnss_attitude::receiver::example::ExampleFlight,
    k: u64,
    profile: Profile,
    refusals: &mut u32,
) {
    if k % 100 == 0 && r.set_aiding(&flight.aiding(k)).is_err() {
        *refusals += 1;
    }
    if k > 0 && k % 10 == 0 && r.push_gyro_increment(&flight.gyro_increment(k / 10 - 1)).is_err() {
        *refusals += 1;
    }
    let obs = flight.observations(k);
    let push = |r: &mut gnss_attitude::receiver::AttitudeReceiver| {
        let r = black_box(r);
        let mut refused = 0u32;
        for o in black_box(&obs).iter() {
            refused += u32::from(r.push_observation(black_box(k), o).is_err());
        }
        refused
    };
    let refused = match profile {
        Profile::None => {
            let n = push(r);
            r.close_through(k);
            r.run_deferred();
            n
        }
        Profile::Whole(name) => measure(name, || {
            let n = push(&mut *r);
            black_box(&mut *r).close_through(black_box(k));
            black_box(&mut *r).run_deferred();
            n
        }),
        Profile::Split(push_name, close_name, work_name) => {
            let n = measure(push_name, || push(&mut *r));
            measure(close_name, || black_box(&mut *r).close_through(black_box(k)));
            measure(work_name, || black_box(&mut *r).run_deferred());
            n
        }
    };
    *refusals += refused;
}

/// The receiver on the example flight (8 satellites x 3 antennas at 45 dB-Hz, 0.5 m
/// triangle, gyro at 100 Hz), [`FLIGHT_EPOCHS`] epochs: the cold start's window, then in
/// steady fine tracking (after 2 s) the per-stage profile: a plain 1 ms epoch (observations
/// pushed; epoch closed), a 20 ms block epoch, a 100 ms window epoch (snapshot monitor every
/// window) and the 1 s window epoch (with the integrity fix), and one gyro sample. Returns the
/// final attitude against the truth for the self-check.
// (not inlined: see the other groups)
#[inline(never)]
pub fn receiver_budgets() -> Option<ReceiverOutcome> {
    use gnss_attitude::receiver::example::ExampleFlight;
    use gnss_attitude::receiver::AttitudeReceiver;
    let mut flight = ExampleFlight::new(7);
    let mut r = match AttitudeReceiver::new(ExampleFlight::config(true)) {
        Ok(r) => r,
        Err(e) => {
            hprintln!("receiver: new refused: {:?}", e);
            return None;
        }
    };
    hprintln!("receiver: {} B", core::mem::size_of::<AttitudeReceiver>());
    // the stages out of the 1 ms path: each epoch's `run_deferred` right after it gives the
    // inline attitude bit for bit (the self-check compares it with the host's inline run)
    r.set_deferred_stages(true);
    let mut refusals = 0u32;
    // epoch 2050: not a block's end (k + 1 = 2051); 2059: a block's end (2060 = 103 x 20),
    // not a window's; 2099: the 21st window's end (snapshot monitor); 2999: the 30th window's
    // end (snapshot monitor and the integrity fix, every 10 windows)
    for k in 0..FLIGHT_EPOCHS {
        let profile = match k {
            99 => Profile::Whole("receiver epoch closing the cold-start window (8 sats: SDs, ambiguity resolution, fine start)"),
            2050 => Profile::Split(
                "receiver steady epoch: 8 x push_observation (8 sats x 3 antennas)",
                "receiver steady epoch: close_through, plain 1 ms epoch (normalize, antenna + bit monitors, block sums)",
                "receiver steady epoch: run_deferred (nothing waits)",
            ),
            2059 => Profile::Split(
                "receiver steady block epoch: 8 x push_observation",
                "receiver steady block epoch: close_through, 20 ms block (epoch + block SDs captured)",
                "receiver steady block epoch: run_deferred (gyro-aided fine update)",
            ),
            2099 => Profile::Split(
                "receiver steady window epoch: 8 x push_observation",
                "receiver steady window epoch: close_through, 100 ms window (block + window SDs captured)",
                "receiver steady window epoch: run_deferred (fine update, ambiguity upkeep, snapshot monitor, rigid body)",
            ),
            2999 => Profile::Split(
                "receiver steady 1 s window epoch: 8 x push_observation",
                "receiver steady 1 s window epoch: close_through, 1 s window (block + window SDs captured)",
                "receiver steady 1 s window epoch: run_deferred (100 ms window's work + integrity fix)",
            ),
            _ => Profile::None,
        };
        flight_epoch(&mut r, &mut flight, k, profile, &mut refusals);
    }
    let att = r.attitude();
    // the next gyro sample in sequence (the flight pushes sample n at epoch 10 (n + 1))
    let theta = flight.gyro_increment(FLIGHT_EPOCHS / 10 - 1);
    let _ = measure("receiver gyro sample (propagation, calibrator increment)", || {
        black_box(&mut r).push_gyro_increment(black_box(&theta)).is_ok()
    });
    Some(ReceiverOutcome {
        source: att.source,
        attitude: att.q_rb,
        truth: flight.attitude(att.epoch),
        epoch: att.epoch,
        refusals,
    })
}

/// The receiver's block stage alone: the gyro-aided fine filter's prediction over one 20 ms
/// block and its update with 8 satellites' block phase differences (the example flight's
/// sky and antennas, phases consistent with the prior attitude), each in a region.
// (not inlined: see the other groups)
#[inline(never)]
fn gyro_aided_budgets() {
    use gnss_attitude::attitude::gyro_aided::{GyroAidedConfig, GyroAidedFilter, GyroAidedPrior, PhaseDifferenceBlock};
    use gnss_attitude::receiver::example::{antennas, ExampleFlight};
    use nalgebra::Matrix2;
    const WAVELENGTH_M: f32 = 0.190_293_7;
    let config = GyroAidedConfig {
        wavelength_m: WAVELENGTH_M,
        angle_random_walk: 1e-4,
        bias_random_walk: 1e-5,
        line_bias_random_walk: 1e-4,
        gate: Some(GateConfidence::P999),
    };
    let [a, b, c] = antennas().map(Vector3::from);
    let baselines = [b - a, c - a];
    let q = Quaternion::from_rotation_vector(&Vector3::new(0.3f32, -0.2, 1.1));
    let prior = GyroAidedPrior {
        q_rb: q,
        attitude_covariance: Matrix3::identity() * 1e-6,
        bias_sigma: 1e-4,
        line_bias: Vector2::zeros(),
        line_bias_covariance: Matrix2::identity() * 1e-4,
    };
    let m = Quaternion::identity();
    let Ok(mut f) = GyroAidedFilter::new(config, baselines, &prior, &m) else {
        hprintln!("gyro-aided budgets: filter refused");
        return;
    };
    let c_rb = q.to_dcm();
    let k = core::f32::consts::TAU / WAVELENGTH_M;
    let blocks: [PhaseDifferenceBlock<f32>; 8] = core::array::from_fn(|i| {
        let los = ExampleFlight::los(i);
        let s = c_rb.transpose() * los;
        PhaseDifferenceBlock {
            id: i as u8 + 1,
            los,
            phase_rad: Vector2::new(k * s.dot(&baselines[0]), k * s.dot(&baselines[1])),
            covariance: Matrix2::new(2e-3, 1e-3, 1e-3, 2e-3),
        }
    });
    let predicted = measure("receiver sub-stage: gyro-aided fine filter predict over one 20 ms block (8 states)", || {
        black_box(&mut f).predict(black_box(&m), black_box(0.02)).is_ok()
    });
    let report = measure("receiver sub-stage: gyro-aided fine filter update, 8 sats x 2 baselines (8 gated 2-D updates, fold-in)", || {
        black_box(&mut f).update(black_box(&m), black_box(&blocks[..]))
    });
    match report {
        Ok(r) => hprintln!("gyro-aided budgets: predict ok {}, update accepted {} of {}", predicted, r.accepted, r.offered),
        Err(e) => hprintln!("gyro-aided budgets: update refused: {:?}", e),
    }
}

/// The bit-parallel correlator on the i8 correlator's case (3 antennas x 1 satellite, one 1 ms
/// code period at 2.6 Msps, E/P/L+N on the reference antenna, prompt on the slaves), planes
/// packed from the same samples before the region: 1- and 2-bit, complex and real IF, 2- and
/// 3-level carrier.
// (not inlined: each group's locals get a frame of their own, so the stack is the largest
// group's, not the sum of all)
#[inline(never)]
fn bitwise_budgets() {
    let s = &SIGNAL_SAMPLES;
    // The chunk loop's scratch, as a receiver shares it between its channels.
    let mut scratch = BitScratch::new();
    let cases = [
        (Resolution::OneBit, true, CarrierLevels::Two, "bit-parallel correlator 3 ant x 1 sat, 1 ms @ 2.6 Msps complex 1-bit, 2-level carrier, E/P/L+N ref + P slaves"),
        (Resolution::TwoBit, true, CarrierLevels::Two, "bit-parallel correlator 3 ant x 1 sat, 1 ms @ 2.6 Msps complex 2-bit, 2-level carrier, E/P/L+N ref + P slaves"),
        (Resolution::OneBit, true, CarrierLevels::Three, "bit-parallel correlator 3 ant x 1 sat, 1 ms @ 2.6 Msps complex 1-bit, 3-level carrier, E/P/L+N ref + P slaves"),
        (Resolution::TwoBit, true, CarrierLevels::Three, "bit-parallel correlator 3 ant x 1 sat, 1 ms @ 2.6 Msps complex 2-bit, 3-level carrier, E/P/L+N ref + P slaves"),
        (Resolution::OneBit, false, CarrierLevels::Two, "bit-parallel correlator 3 ant x 1 sat, 1 ms @ 2.6 Msps real IF 1-bit, 2-level carrier, E/P/L+N ref + P slaves"),
        (Resolution::TwoBit, false, CarrierLevels::Two, "bit-parallel correlator 3 ant x 1 sat, 1 ms @ 2.6 Msps real IF 2-bit, 2-level carrier, E/P/L+N ref + P slaves"),
        (Resolution::OneBit, false, CarrierLevels::Three, "bit-parallel correlator 3 ant x 1 sat, 1 ms @ 2.6 Msps real IF 1-bit, 3-level carrier, E/P/L+N ref + P slaves"),
        (Resolution::TwoBit, false, CarrierLevels::Three, "bit-parallel correlator 3 ant x 1 sat, 1 ms @ 2.6 Msps real IF 2-bit, 3-level carrier, E/P/L+N ref + P slaves"),
    ];
    for (resolution, complex, levels, name) in cases {
        let format = PlaneFormat { resolution, complex };
        let q = |k: usize| if complex { &s[3 + k][..] } else { &[][..] };
        let (Ok(p0), Ok(p1), Ok(p2)) = (
            pack_self_test(format, &s[0], q(0)),
            pack_self_test(format, &s[1], q(1)),
            pack_self_test(format, &s[2], q(2)),
        ) else {
            hprintln!("budget bitwise: packing failed");
            continue;
        };
        let Ok(block) = BitBlock::new(0, &CODE_TABLE_2M6, [p0.planes(), p1.planes(), p2.planes()]) else {
            hprintln!("budget bitwise: block refused");
            continue;
        };
        let Ok(mut corr) = self_test_correlator(format, levels) else {
            hprintln!("budget bitwise: correlator refused");
            continue;
        };
        let out = measure(name, || {
            let mut cursor = 0;
            black_box(&mut corr).run_in(black_box(&block), &mut cursor, &mut scratch)
        });
        if !matches!(out, Ok(Some(ref e)) if e.samples == 2600) {
            hprintln!("budget bitwise: {} did not complete one code period: {:?}", name, out.map(|o| o.map(|e| e.samples)));
        }
    }
    // LEO Doppler: the carrier words then hold up to two quadrant crossings each.
    let format = PlaneFormat { resolution: Resolution::OneBit, complex: true };
    if let (Ok(p0), Ok(p1), Ok(p2), Ok(mut corr)) = (
        pack_self_test(format, &s[0], &s[3]),
        pack_self_test(format, &s[1], &s[4]),
        pack_self_test(format, &s[2], &s[5]),
        self_test_correlator(format, CarrierLevels::Two),
    ) {
        if let (Ok(block), Ok(())) = (
            BitBlock::new(0, &CODE_TABLE_2M6, [p0.planes(), p1.planes(), p2.planes()]),
            corr.set_carrier_frequency(40_000.0),
        ) {
            let _ = measure("bit-parallel correlator 3 ant x 1 sat, 1 ms @ 2.6 Msps complex 1-bit, 2-level carrier at 40 kHz Doppler, E/P/L+N ref + P slaves", || {
                let mut cursor = 0;
                black_box(&mut corr).run_in(black_box(&block), &mut cursor, &mut scratch).is_ok()
            });
        }
    }
}

/// Packing 1 ms (2600 sample instants) of front-end bytes of 3 antennas into bit planes: the
/// DMA layouts a flight receiver hands over (sm2iq: two complex samples a byte per antenna;
/// bit1iq: four complex 1-bit samples a byte per antenna; mc2x3: one byte per instant holding
/// the three antennas' 2-bit real samples; bit1: eight real samples a byte per antenna).
// (not inlined: each group's locals get a frame of their own, so the stack is the largest
// group's, not the sum of all)
#[inline(never)]
fn packing_budgets() {
    let s = &SIGNAL_SAMPLES;
    let field = |x: i8| (u8::from(x < 0) << 1) | u8::from(x.unsigned_abs() >= 18);
    let mut sm2iq = [[0u8; 1300]; 3];
    for (a, bytes) in sm2iq.iter_mut().enumerate() {
        for (k, b) in bytes.iter_mut().enumerate() {
            let (i0, q0, i1, q1) = (s[a][2 * k], s[a + 3][2 * k], s[a][2 * k + 1], s[a + 3][2 * k + 1]);
            *b = (field(i0) << 6) | (field(q0) << 4) | (field(i1) << 2) | field(q1);
        }
    }
    let mut mc2 = [0u8; 2600];
    for (k, b) in mc2.iter_mut().enumerate() {
        *b = field(s[0][k]) | (field(s[1][k]) << 2) | (field(s[2][k]) << 4);
    }
    let mut bit1iq = [[0u8; 650]; 3];
    for (a, bytes) in bit1iq.iter_mut().enumerate() {
        for (k, b) in bytes.iter_mut().enumerate() {
            for j in 0..4 {
                let (i, q) = (s[a][4 * k + j], s[a + 3][4 * k + j]);
                *b |= (u8::from(i < 0) << (7 - 2 * j)) | (u8::from(q < 0) << (6 - 2 * j));
            }
        }
    }
    let mut bit1 = [[0u8; 325]; 3];
    for (a, bytes) in bit1.iter_mut().enumerate() {
        for (k, b) in bytes.iter_mut().enumerate() {
            for j in 0..8 {
                *b |= u8::from(s[a][8 * k + j] < 0) << (7 - j);
            }
        }
    }
    let two_cx = PlaneFormat { resolution: Resolution::TwoBit, complex: true };
    let one_cx = PlaneFormat { resolution: Resolution::OneBit, complex: true };
    let two_re = PlaneFormat { resolution: Resolution::TwoBit, complex: false };
    let one_re = PlaneFormat { resolution: Resolution::OneBit, complex: false };
    let mut bufs = [PlaneBuffer::<BIT_SELF_TEST_WORDS>::new(two_cx), PlaneBuffer::new(two_cx), PlaneBuffer::new(two_cx)];
    let n = measure("packing 1 ms sm2iq -> 2-bit complex planes, 3 antennas (3 x 2600 samples)", || {
        let mut n = 0;
        for (b, bytes) in black_box(&mut bufs).iter_mut().zip(black_box(&sm2iq)) {
            n += b.pack_bytes(SampleFormat::SignMagnitude2 { complex: true }, bytes, 0).unwrap_or(0);
        }
        n
    });
    let mut bufs = [PlaneBuffer::<BIT_SELF_TEST_WORDS>::new(one_cx), PlaneBuffer::new(one_cx), PlaneBuffer::new(one_cx)];
    let n1 = measure("packing 1 ms sm2iq -> 1-bit complex planes, 3 antennas (3 x 2600 samples)", || {
        let mut n = 0;
        for (b, bytes) in black_box(&mut bufs).iter_mut().zip(black_box(&sm2iq)) {
            n += b.pack_bytes(SampleFormat::SignMagnitude2 { complex: true }, bytes, 0).unwrap_or(0);
        }
        n
    });
    let mut bufs = [PlaneBuffer::<BIT_SELF_TEST_WORDS>::new(one_cx), PlaneBuffer::new(one_cx), PlaneBuffer::new(one_cx)];
    let n1q = measure("packing 1 ms bit1iq -> 1-bit complex planes, 3 antennas (3 x 2600 samples)", || {
        let mut n = 0;
        for (b, bytes) in black_box(&mut bufs).iter_mut().zip(black_box(&bit1iq)) {
            n += b.pack_bytes(SampleFormat::Sign1Iq, bytes, 0).unwrap_or(0);
        }
        n
    });
    let mut bufs = [PlaneBuffer::<BIT_SELF_TEST_WORDS>::new(two_re), PlaneBuffer::new(two_re), PlaneBuffer::new(two_re)];
    let n2 = measure("packing 1 ms mc2x3 -> 2-bit real planes, 3 antennas (3 x 2600 samples)", || {
        let mut n = 0;
        for (c, b) in black_box(&mut bufs).iter_mut().enumerate() {
            n += b.pack_bytes(SampleFormat::MultiChannel2 { channels: 3 }, black_box(&mc2[..]), c).unwrap_or(0);
        }
        n
    });
    let mut bufs = [PlaneBuffer::<BIT_SELF_TEST_WORDS>::new(one_re), PlaneBuffer::new(one_re), PlaneBuffer::new(one_re)];
    let n3 = measure("packing 1 ms bit1 -> 1-bit real planes, 3 antennas (3 x 2600 samples)", || {
        let mut n = 0;
        for (b, bytes) in black_box(&mut bufs).iter_mut().zip(black_box(&bit1)) {
            n += b.pack_bytes(SampleFormat::Sign1, bytes, 0).unwrap_or(0);
        }
        n
    });
    hprintln!("budget packing: samples packed {} {} {} {} {}", n, n1, n1q, n2, n3);
}

/// Navigation (`nav`, f64 soft-float on the M4F for times, ranges and orbits): one subframe
/// decode, one satellite's position, a single-point fix from 8 satellites (LEO and ground
/// configurations), the LEO filter and the lines of sight.
// (not inlined: each group's locals get a frame of their own, so the stack is the largest
// group's, not the sum of all)
#[inline(never)]
fn nav_budgets() {
    use gnss_attitude::nav::bits::DataBit;
    use gnss_attitude::nav::example::{self, EXAMPLE_KLOBUCHAR};
    use gnss_attitude::nav::geodesy::Geodetic;
    use gnss_attitude::nav::{
        line_of_sight, solve, GpsTime, NavigationStore, OrbitFilter, OrbitFilterConfig, ReferenceFrame,
        SolverConfig, SubframeSync,
    };
    let ephs = example::constellation();
    // subframes 1 and 2 of PRN 7 held, subframe 3 decoded bit by bit; the last bit completes it
    let mut sync = SubframeSync::new();
    let mut store = NavigationStore::default();
    let mut epoch = 0u64;
    let mut bit = |value: bool| {
        epoch += 20;
        DataBit { value, start_epoch: epoch, strength: 1.0 }
    };
    let _ = sync.push(&bit(false));
    let _ = sync.push(&bit(false));
    let mut last = None;
    for id in 1..=3u8 {
        let bits = example::subframe_bits(&example::subframe_words(&ephs[6], id, 39_600 + u32::from(id)));
        for (k, &b) in bits.iter().enumerate() {
            let d = bit(b);
            if id == 3 && k == 299 {
                last = Some(d);
            } else if id == 3 && k == 150 {
                let _ = measure("nav subframe sync, one bit inside a subframe (shift, preamble test)", || {
                    black_box(&mut sync).push(black_box(&d)).is_ok()
                });
            } else if let Ok(Some(sf)) = sync.push(&d) {
                let _ = store.add_subframe(7, &sf);
            }
        }
    }
    if let Some(d) = last {
        let stored = measure("nav subframe decode: the bit completing subframe 3 (10-word parity) + store (fields, IODE/IODC, plausibility)", || {
            match black_box(&mut sync).push(black_box(&d)) {
                Ok(Some(sf)) => black_box(&mut store).add_subframe(7, &sf).is_ok(),
                _ => false,
            }
        });
        hprintln!("nav budgets: subframe decoded and ephemeris stored: {}", stored && store.ephemeris(7).is_some());
    }
    let Ok(at) = GpsTime::new(example::EXAMPLE_WEEK, 238_000.0) else { return };
    let _ = measure("nav satellite position, velocity, clock of 1 satellite (f64 Kepler, user algorithm)", || {
        black_box(&ephs[3]).satellite_state(black_box(&at)).is_ok()
    });
    // LEO: 550 km above Kyiv, 7.6 km/s
    let leo = Geodetic { lat_rad: 0.8805, lon_rad: 0.5327, height_m: 550e3 }.to_ecef();
    let v = [-3000.0, 2500.0, 6500.0];
    let clock = 1000.0;
    let Ok(rx_clock) = at.add_seconds(clock / 299_792_458.0) else { return };
    let Ok(obs) = example::observations(&ephs, &leo, &v, clock, &at, 8, None) else { return };
    let fix = measure("nav fix LEO, 8 satellites (orbits, LS f64 state/f32 normal eqs, Sagnac, DOP, velocity, residual check)", || {
        solve(black_box(&obs[..]), black_box(&ephs[..]), None, black_box(&rx_clock), None, &SolverConfig::leo())
    });
    let prior = [leo[0] + 100.0, leo[1] - 60.0, leo[2] + 80.0];
    let _ = measure("nav fix LEO, 8 satellites, started from a prediction 140 m off (the 1 Hz case)", || {
        solve(black_box(&obs[..]), black_box(&ephs[..]), None, black_box(&rx_clock), Some(&prior), &SolverConfig::leo()).is_ok()
    });
    let ground = Geodetic { lat_rad: 0.8805, lon_rad: 0.5327, height_m: 180.0 }.to_ecef();
    let iono = EXAMPLE_KLOBUCHAR;
    if let Ok(gobs) = example::observations(&ephs, &ground, &[0.0; 3], clock, &at, 8, Some(&iono)) {
        let g = measure("nav fix ground, 8 satellites (as LEO + Klobuchar + troposphere + 5 deg mask)", || {
            solve(black_box(&gobs[..]), black_box(&ephs[..]), Some(&iono), black_box(&rx_clock), None, &SolverConfig::ground())
        });
        match g {
            Ok(f) => hprintln!("nav budgets: ground fix {} sats, {} iterations, error {} m", f.satellites, f.iterations,
                ((f.position_m[0] - ground[0]).powi(2) + (f.position_m[1] - ground[1]).powi(2) + (f.position_m[2] - ground[2]).powi(2)).sqrt()),
            Err(e) => hprintln!("nav budgets: ground fix refused: {:?}", e),
        }
    }
    let Ok(fix) = fix else {
        hprintln!("nav budgets: LEO fix refused");
        return;
    };
    hprintln!("nav budgets: LEO fix {} sats, {} iterations, pdop {}, error {} m", fix.satellites, fix.iterations, fix.dop.pdop,
        ((fix.position_m[0] - leo[0]).powi(2) + (fix.position_m[1] - leo[1]).powi(2) + (fix.position_m[2] - leo[2]).powi(2)).sqrt());
    let Ok(mut filter) = OrbitFilter::from_fix(&fix, OrbitFilterConfig::default()) else { return };
    let Ok(next) = fix.time.add_seconds(1.0) else { return };
    let _ = measure("nav LEO filter predict 1 s (RK4 2-body + J2 f64, 6x6 covariance f32)", || {
        black_box(&mut filter).predict_to(black_box(&next)).is_ok()
    });
    let mut later = fix;
    later.time = next;
    let _ = measure("nav LEO filter update with a fix (6-D Joseph update, gate)", || {
        black_box(&mut filter).update(black_box(&later)).is_ok()
    });
    let state = filter.state();
    let frame = ReferenceFrame::Inertial { epoch: at };
    let _ = measure("nav lines of sight + rates, 8 satellites, inertial frame (light time x3)", || {
        let mut n = 0;
        for o in black_box(&obs).iter() {
            if let Some(e) = ephs.iter().find(|e| e.prn == o.prn) {
                n += usize::from(line_of_sight(black_box(&state), e, &frame).is_ok());
            }
        }
        n
    });
}
