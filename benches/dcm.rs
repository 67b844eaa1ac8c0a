//! Host cost of one step of each paper-000 filter (criterion), f32 as on the target: the
//! six-state direction-cosine EKF (RK4 of eq. (10)), the multi-structure filter (three of them
//! and the combination), and the rigid-body error-state filter. The target's instruction
//! counts of the same steps come from the firmware (`examples/firmware`, printed by `.ci/run`).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use gnss_attitude::attitude::array::{AntennaArray, BaselinePair};
use gnss_attitude::attitude::baseline_epoch::BaselineEpoch;
use gnss_attitude::attitude::dcm_filter::{DcmFilterConfig, DirectionCosineFilter};
use gnss_attitude::attitude::multi_structure::MultiStructureFilter;
use gnss_attitude::attitude::rigid_body::{RigidBodyConfig, RigidBodyFilter};
use gnss_attitude::ekf::GateConfidence;
use gnss_attitude::geometry::{rot_x, rot_y, rot_z, Quaternion};
use nalgebra::{Matrix3, SMatrix, Vector3};

/// The paper's array and one noise-free epoch of its motion near t = 1 s.
fn setup() -> (AntennaArray<f32>, Matrix3<f32>, BaselineEpoch<f32>) {
    let array =
        AntennaArray::from_baselines(&Vector3::new(1.5, 1.8, 1.9), &Vector3::new(1.7, 1.7, 2.0))
            .unwrap_or_else(|e| panic!("{e}"));
    let c0 = rot_z(0.1f32) * rot_y(0.02) * rot_x(0.03);
    let c1 = rot_z(0.1011f32) * rot_y(0.0202) * rot_x(0.0301);
    let mut epoch = BaselineEpoch::default();
    for pair in BaselinePair::ALL {
        let b = array.baseline(pair);
        epoch.baselines[pair.index()] = Some(c1 * b);
        epoch.velocity_differences[pair.index()] = Some((c1 - c0) * b / 0.01);
    }
    (array, c0, epoch)
}

fn bench(c: &mut Criterion) {
    let (array, c0, epoch) = setup();
    let config = DcmFilterConfig::paper(0.01f32, 0.6, 0.1);
    let r0 = SMatrix::<f32, 6, 6>::identity() * 1e-4;
    let six =
        DirectionCosineFilter::new(&array, config, &c0, &r0).unwrap_or_else(|e| panic!("{e}"));
    c.bench_function("dcm_six_state_step", |b| {
        b.iter_batched(
            || six.clone(),
            |mut f| black_box(f.step(black_box(&epoch))).ok(),
            BatchSize::SmallInput,
        );
    });
    let multi =
        MultiStructureFilter::new(&array, config, &c0, &r0).unwrap_or_else(|e| panic!("{e}"));
    c.bench_function("dcm_multi_structure_step", |b| {
        b.iter_batched(
            || multi.clone(),
            |mut f| black_box(f.step(black_box(&epoch))).ok(),
            BatchSize::SmallInput,
        );
    });
    let q0 = Quaternion::from_dcm(&c0).unwrap_or_else(|e| panic!("{e}"));
    let rigid_config = RigidBodyConfig {
        dt: 0.01f32,
        sigma_baseline: 0.6,
        sigma_velocity: 0.1,
        gate: Some(GateConfidence::P999),
    };
    let rigid = RigidBodyFilter::new(&array, rigid_config, &q0, &(Matrix3::identity() * 1e-4))
        .unwrap_or_else(|e| panic!("{e}"));
    c.bench_function("dcm_rigid_body_step", |b| {
        b.iter_batched(
            || rigid.clone(),
            |mut f| black_box(f.step(black_box(&epoch))).ok(),
            BatchSize::SmallInput,
        );
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
