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
use gnss_attitude::attitude::one_stage::{
    AntennaArray, EstimatedAngles, FilterMode, OneStageConfig, OneStageFilter, PhaseModel, Prior,
    PromptIq, SatelliteObservation, MAX_SATELLITES,
};
use gnss_attitude::geometry::Paper003Angles;
use nalgebra::{ComplexField, Matrix4, SMatrix, SVector, Vector2, Vector3, Vector4};

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
    one_stage_budgets();
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

fn one_stage_budgets() {
    let Ok(array) = AntennaArray::paper_triangle(1.5f32) else { return };
    let obs = one_stage_observations(&array);
    one_stage_budget::<8>(&array, &obs, "one-stage step, 12 sats, Gaussian approx., 3 angles + 2 biases (N = 8)", FilterMode::GaussianApproximation, EstimatedAngles::ALL, true, MAX_SATELLITES);
    one_stage_budget::<8>(&array, &obs, "one-stage step, 12 sats, constant gain, 3 angles + 2 biases (N = 8)", FilterMode::ConstantGain, EstimatedAngles::ALL, true, MAX_SATELLITES);
    one_stage_budget::<2>(&array, &obs, "one-stage step, 12 sats, Gaussian approx., beta only (N = 2)", FilterMode::GaussianApproximation, EstimatedAngles::BETA_ONLY, false, MAX_SATELLITES);
    one_stage_budget::<2>(&array, &obs, "one-stage step, 8 sats, Gaussian approx., beta only (paper, N = 2)", FilterMode::GaussianApproximation, EstimatedAngles::BETA_ONLY, false, 8);
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
