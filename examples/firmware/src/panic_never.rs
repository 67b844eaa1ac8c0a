//! Link-time proof that the core's entry points called here contain no reachable panic.
//!
//! The panic handler calls a function that does not exist. If any panic path survives
//! optimization (release, fat LTO), the link fails with an undefined symbol
//! `gnss_attitude_core_can_panic`. The inputs are opaque (`black_box`), so the optimizer cannot
//! prove a path dead by knowing the data; only the code's own checks can remove it.
//! Build: `cargo build --release --bin panic-never`; it is linked, never run.
#![no_std]
#![no_main]

use core::hint::black_box;

use cortex_m_rt::entry;
use gnss_attitude::ekf::{Ekf, GateConfidence, NisGate};
use gnss_attitude::geometry::{nearest_rotation, Euler321, Paper003Angles, Quaternion};
use gnss_attitude::attitude::one_stage::{
    satellite_terms, AntennaArray, BesselRatio, FilterMode, OneStageConfig, OneStageFilter, Prior,
    SatelliteObservation, MAX_SATELLITES,
};
use gnss_attitude::selftest::run_ekf_self_test;
use nalgebra::{Matrix3, SMatrix, SVector};

extern "C" {
    fn gnss_attitude_core_can_panic() -> !;
}

#[entry]
fn main() -> ! {
    let p0: SMatrix<f32, 6, 6> = black_box(SMatrix::identity());
    if let Ok(mut ekf) = Ekf::<6>::new(black_box(SVector::zeros()), p0) {
        ekf = ekf.with_variance_floor(black_box(1e-9));
        let _ = ekf.predict(&black_box(SMatrix::identity()), &black_box(SMatrix::identity()));
        let _ = ekf.predict_to(&black_box(SVector::zeros()), &black_box(SMatrix::identity()), &black_box(SMatrix::identity()));
        let h: SMatrix<f32, 3, 6> = black_box(SMatrix::zeros());
        let gate = Some(NisGate::chi_square(black_box(3), GateConfidence::P999));
        let _ = ekf.update(&black_box(SVector::<f32, 3>::zeros()), &h, &black_box(SMatrix::identity()), gate);
        let _ = ekf.update_scalar(black_box(0.1), &black_box(SMatrix::<f32, 1, 6>::zeros()), black_box(1.0), gate);
        let _ = ekf.update_sequential(&black_box(SVector::<f32, 3>::zeros()), &h, &black_box(SVector::<f32, 3>::zeros()), gate);
        let _ = ekf.set_covariance(black_box(SMatrix::identity()));
        let _ = ekf.set_state(black_box(SVector::zeros()));
        let _ = black_box(ekf.nees(&black_box(SVector::zeros())));
        let _ = black_box(ekf.std_dev(black_box(7)));
    }
    let m: Matrix3<f32> = black_box(Matrix3::identity());
    let _ = black_box(Quaternion::from_dcm(&m));
    let _ = black_box(Euler321::from_dcm(&m));
    let _ = black_box(Paper003Angles::from_dcm(&m));
    let _ = black_box(nearest_rotation(&m));
    let q = Quaternion::from_rotation_vector(&black_box(nalgebra::Vector3::new(0.1f32, 0.2, 0.3)));
    let _ = black_box(q.to_rotation_vector());
    let _ = black_box(q.normalize());
    let _ = black_box(run_ekf_self_test());
    one_stage();
    loop {
        cortex_m::asm::nop();
    }
}

/// The one-stage filter's entry points on opaque data.
fn one_stage() {
    let v = || black_box(nalgebra::Vector3::new(0.1f32, 0.2, 0.3));
    let _ = black_box(BesselRatio::at(black_box(61.0f32)));
    let z = black_box([nalgebra::Complex::new(1.0f32, 2.0); 3]);
    let _ = black_box(satellite_terms(&z, &v(), black_box(10.0)));
    let Ok(array) = AntennaArray::new(v(), v() * 2.0, v() + nalgebra::Vector3::x()) else {
        return;
    };
    let prior = match Prior::from_attitude(&black_box(Matrix3::identity()), &black_box(Matrix3::identity()), black_box(0.01)) {
        Ok(p) => p,
        Err(_) => black_box(Prior::new(gnss_attitude::geometry::Paper003Angles::new(0.0, 0.0, 0.0), 0.01, 0.001)),
    };
    let mut config = OneStageConfig::gps_l1(black_box(FilterMode::GaussianApproximation), black_box(2.0));
    config.line_bias_states = black_box(true);
    let config = black_box(config);
    let prior = black_box(prior);
    if let Ok(mut f) = OneStageFilter::<f32, 8>::new(config, black_box(array), &prior) {
        let obs: [SatelliteObservation<f32>; MAX_SATELLITES] = black_box([SatelliteObservation::default(); MAX_SATELLITES]);
        let epoch = obs.get(..black_box(12usize)).unwrap_or(&[]);
        let _ = black_box(f.step(epoch));
        let _ = black_box(f.information(epoch));
        let _ = black_box(f.reinitialize(&prior));
        let _ = black_box((f.angles(), f.rates(), f.line_bias(), f.angle_covariance(), f.lock_status()));
    }
    let mut beta = config;
    beta.estimate = black_box(gnss_attitude::attitude::one_stage::EstimatedAngles::BETA_ONLY);
    beta.line_bias_states = black_box(false);
    if let Ok(mut f) = OneStageFilter::<f32, 2>::new(beta, black_box(array), &prior) {
        let obs: [SatelliteObservation<f32>; MAX_SATELLITES] = black_box([SatelliteObservation::default(); MAX_SATELLITES]);
        let epoch = obs.get(..black_box(8usize)).unwrap_or(&[]);
        let _ = black_box(f.step(epoch));
        let _ = black_box(f.angles());
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // SAFETY: never called if the proof holds; the symbol does not exist, so a surviving panic
    // path fails the link.
    unsafe { gnss_attitude_core_can_panic() }
}
