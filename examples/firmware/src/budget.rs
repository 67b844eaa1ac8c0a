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
use gnss_attitude::geometry::Quaternion;
use gnss_attitude::gyro::{
    default_rank_tolerance, CalibratorConfig, EpochOutcome, LeastSquaresAccumulator,
    NormalEquations, PaperCalibrator, SqrtInformation,
};
use nalgebra::{Matrix4, SMatrix, SVector, Vector2, Vector3, Vector4};

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
    gyro_budgets();
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

/// Paper 001 §6 on the target: 30 s of the paper's rates with its gyro errors against a perfect
/// reference (131 epochs, 393 rows), then one of each step on the filled accumulators.
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
