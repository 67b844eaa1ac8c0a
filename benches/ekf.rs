//! Host cost of one EKF toolkit step (criterion). The target's instruction counts of the same
//! steps come from the firmware under `examples/firmware` (printed by `.ci/run`).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use gnss_attitude::ekf::{Ekf, GateConfidence, NisGate};
use gnss_attitude::selftest::ConstantVelocityModel;
use nalgebra::{Matrix4, SMatrix, SVector, Vector2, Vector4};

fn six_state() -> (
    Ekf<6>,
    SMatrix<f32, 6, 6>,
    SMatrix<f32, 6, 6>,
    SMatrix<f32, 3, 6>,
    SMatrix<f32, 3, 3>,
) {
    let p0 =
        SMatrix::<f32, 6, 6>::from_diagonal(&SVector::from([1e-2, 1e-2, 1e-2, 1e-4, 1e-4, 1e-4]));
    let ekf = Ekf::new(SVector::zeros(), p0).unwrap_or_else(|e| panic!("{e}"));
    let mut f = SMatrix::<f32, 6, 6>::identity();
    f.fixed_view_mut::<3, 3>(0, 3).fill_with_identity();
    let q = SMatrix::<f32, 6, 6>::identity() * 1e-8;
    let h = SMatrix::<f32, 3, 6>::from_fn(|i, j| {
        if j < 3 {
            ((i + 2 * j) as f32).sin()
        } else {
            0.0
        }
    });
    let r = SMatrix::<f32, 3, 3>::identity() * 1e-4;
    (ekf, f, q, h, r)
}

fn bench(c: &mut Criterion) {
    let model = ConstantVelocityModel::new(0.1, 0.2, 0.5);
    let mut cv =
        Ekf::new(Vector4::zeros(), Matrix4::identity() * 10.0).unwrap_or_else(|e| panic!("{e}"));
    c.bench_function("ekf4_cv_predict_update2", |b| {
        b.iter(|| {
            let r = model.step(black_box(&mut cv), black_box(&Vector2::new(0.3, -0.2)));
            black_box(r).ok();
        });
    });

    let (mut ekf, f, q, h, r) = six_state();
    let gate = Some(NisGate::chi_square(3, GateConfidence::P999));
    let y = SVector::<f32, 3>::new(1e-3, -2e-3, 5e-4);
    c.bench_function("ekf6_predict_update3_joseph", |b| {
        b.iter(|| {
            ekf.predict(black_box(&f), black_box(&q)).ok();
            black_box(ekf.update(black_box(&y), &h, &r, gate)).ok();
        });
    });

    let (mut ekf, f, q, h, r) = six_state();
    let r_diag = r.diagonal();
    c.bench_function("ekf6_predict_sequential3", |b| {
        b.iter(|| {
            ekf.predict(black_box(&f), black_box(&q)).ok();
            black_box(ekf.update_sequential(black_box(&y), &h, &r_diag, None)).ok();
        });
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
