//! Host cost of the gyro calibration's steps (criterion), on the equations of paper 001's §6
//! experiment: one row into each accumulator, one solve of each (with the observability
//! report), one epoch of the calibrator (equations + three Givens rows), one propagation step.
//! The target's instruction counts of the same steps come from `examples/firmware`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use gnss_attitude::geometry::Quaternion;
use gnss_attitude::gyro::{
    default_rank_tolerance, CalibratorConfig, EpochOutcome, LeastSquaresAccumulator,
    NormalEquations, PaperCalibrator, SqrtInformation,
};
use host_sim::truth::gyro::section6;
use nalgebra::{SVector, Vector3};

type Cal = PaperCalibrator<SqrtInformation<15>>;

fn quat(q: &Quaternion<f64>) -> Quaternion<f32> {
    Quaternion::new(q.w as f32, q.x as f32, q.y as f32, q.z as f32)
}

/// The calibrator after the §6 run (131 epochs), the normal equations of the same rows, and one
/// row.
fn section6_state() -> (
    Cal,
    NormalEquations<15>,
    SVector<f32, 15>,
    f32,
    Quaternion<f32>,
) {
    let truth = section6::generate();
    let mut cal = Cal::paper(
        CalibratorConfig::new(section6::H_SAMPLE as f32),
        SqrtInformation::new(),
        quat(&truth.m0),
        quat(&truth.reference0),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut normal = NormalEquations::<15>::new();
    let mut last = (SVector::zeros(), 0.0);
    for (i, s) in truth.samples.iter().enumerate() {
        cal.push_increment(&s.theta.map(|v| v as f32))
            .unwrap_or_else(|e| panic!("{e}"));
        if i + 1 >= 200 && (i + 1) % 10 == 0 {
            if let Ok(EpochOutcome::Used(eq)) = cal.add_reference(&quat(&s.reference)) {
                for r in 0..3 {
                    last = (eq.rows.row(r).transpose(), eq.rhs[r]);
                    normal
                        .add_row(&last.0, last.1)
                        .unwrap_or_else(|e| panic!("{e}"));
                }
            }
        }
    }
    let reference = quat(&truth.samples[truth.samples.len() - 1].reference);
    (cal, normal, last.0, last.1, reference)
}

fn bench(c: &mut Criterion) {
    let (cal, normal, u, z, reference) = section6_state();
    let tol = default_rank_tolerance::<f32>();

    let mut givens = *cal.accumulator();
    c.bench_function("gyro_givens_add_row_15", |b| {
        b.iter(|| black_box(givens.add_row(black_box(&u), black_box(z))).ok());
    });
    let mut ne = normal;
    c.bench_function("gyro_normal_add_row_15", |b| {
        b.iter(|| black_box(ne.add_row(black_box(&u), black_box(z))).ok());
    });
    let givens = *cal.accumulator();
    c.bench_function("gyro_givens_solve_15", |b| {
        b.iter(|| black_box(black_box(&givens).solve(tol)).ok());
    });
    c.bench_function("gyro_normal_solve_15", |b| {
        b.iter(|| black_box(black_box(&normal).solve(tol)).ok());
    });
    c.bench_function("gyro_calibrator_epoch_15", |b| {
        b.iter_batched_ref(
            || cal.clone(),
            |cal| black_box(cal.add_reference(black_box(&reference))).ok(),
            BatchSize::SmallInput,
        );
    });
    let mut prop = cal.clone();
    let theta = Vector3::new(4e-4f32, 6.4e-3, -3e-4);
    c.bench_function("gyro_propagate_step_h", |b| {
        b.iter(|| {
            prop.push_increment(black_box(&theta)).ok();
            black_box(prop.push_increment(black_box(&theta))).ok();
        });
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
