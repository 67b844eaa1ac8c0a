//! Filter-level tests of the one-stage module on noise-free data (statistical behaviour is in
//! the crate's `tests/one_stage.rs`, driven by host-sim).

use nalgebra::{SMatrix, Vector3};

use super::*;
use crate::attitude::array::AntennaArray;
use crate::attitude::one_stage::OneStageError;
use crate::geometry::Paper003Angles;

fn los(az_deg: f64, el_deg: f64) -> [f64; 3] {
    let (az, el) = (az_deg.to_radians(), el_deg.to_radians());
    [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()]
}

/// Noise-free observations of G1 at attitude `truth`, with per-satellite common phases.
fn observations(
    truth: &Paper003Angles<f64>,
    n: usize,
) -> heapless::Vec<SatelliteObservation<f64>, MAX_SATELLITES> {
    let array = AntennaArray::paper_triangle(1.5).unwrap();
    let model = PhaseModel::new(&array, GPS_L1_WAVELENGTH_M, truth);
    let amp = (2.0 * 10.0f64).sqrt(); // 40 dB-Hz, T = 1 ms, σ = 1
    let mut out = heapless::Vec::new();
    for i in 0..n {
        let l = los(45.0 * i as f64, 10.0 * (i + 1) as f64);
        let psi = model.phases(&Vector3::from(l));
        let phi = 0.7 * i as f64;
        let mut prompt = PromptIq::default();
        for p in 0..3 {
            prompt.i[p] = amp * (phi + psi[p]).cos();
            prompt.q[p] = amp * (phi + psi[p]).sin();
        }
        let o = SatelliteObservation {
            id: i as u8 + 1,
            los: l,
            prompt,
            noise_var: 1.0,
            cn0_dbhz: 40.0,
        };
        out.push(o).unwrap();
    }
    out
}

#[test]
fn gaussian_update_is_the_information_form_of_eq_12() {
    // one step from a static prior with fixed process noise: D⁻¹ = D̃⁻¹ + cᵀ W c and
    // X̂ = X̃ + D cᵀ u, computed here independently with plain inverses (f64, 8×8)
    let mut config = OneStageConfig::<f64>::gps_l1(FilterMode::GaussianApproximation, 2.0);
    config.process_noise = ProcessNoise::Fixed {
        accel_psd: [1e-4, 2e-4, 3e-4],
        bias_psd: 1e-6,
    };
    config.line_bias_states = true;
    let array = AntennaArray::paper_triangle(1.5).unwrap();
    let prior_angles = Paper003Angles::new(0.01, -0.02, 0.015);
    let mut prior = Prior::new(prior_angles, 0.02, 0.001);
    prior.line_bias_variance = [0.01, 0.02];
    let mut f = OneStageFilter::<f64, 8>::new(config, array, &prior).unwrap();
    let obs = observations(&Paper003Angles::new(0.0, 0.0, 0.0), 8);
    let info = f.information(&obs).unwrap(); // rates are zero: predicted = current
    let d_pred = f.transition() * f.ekf.covariance() * f.transition().transpose() + {
        let mut q = SMatrix::<f64, 8, 8>::zeros();
        for (k, v) in [1e-4, 2e-4, 3e-4, 1e-6, 1e-6].iter().enumerate() {
            q[(k + 3, k + 3)] = v * 1e-3;
        }
        q
    };
    let mut c = SMatrix::<f64, PARAMETERS, 8>::zeros();
    for (k, col) in f.layout.parameter.iter().enumerate() {
        c[(k, col.unwrap())] = 1.0;
    }
    let info_post = d_pred.try_inverse().unwrap() + c.transpose() * info.observed * c;
    let d_post = info_post.try_inverse().unwrap();
    let x_post = f.ekf.state() + d_post * c.transpose() * info.gradient;
    f.step(&obs).unwrap();
    assert!((f.ekf.covariance() - d_post).norm() < 1e-9 * d_post.norm());
    assert!((f.ekf.state() - x_post).norm() < 1e-9);
}

#[test]
fn noise_free_data_pull_all_three_angles_in_with_either_form() {
    let truth = Paper003Angles::new(0.004, -0.006, 0.003);
    let obs = observations(&truth, 8);
    for mode in [FilterMode::GaussianApproximation, FilterMode::ConstantGain] {
        let config = OneStageConfig::<f64>::gps_l1(mode, 2.0);
        let array = AntennaArray::paper_triangle(1.5).unwrap();
        let prior = Prior::new(Paper003Angles::new(0.0, 0.0, 0.0), 0.01, 0.001);
        let mut f = OneStageFilter::<f64, 6>::new(config, array, &prior).unwrap();
        let mut last = None;
        for _ in 0..8000 {
            last = Some(f.step(&obs).unwrap());
        }
        let a = f.angles();
        for (e, t) in [
            (a.alpha, truth.alpha),
            (a.beta, truth.beta),
            (a.gamma, truth.gamma),
        ] {
            assert!((e - t).abs() < 1e-6, "{mode:?}: {e} vs {t}");
        }
        assert_eq!(last.unwrap().status, LockStatus::Locked);
        assert!(f.rates().norm() < 1e-6);
    }
}

#[test]
fn invalid_configuration_and_prior_are_rejected() {
    let array = AntennaArray::<f32>::paper_triangle(1.5).unwrap();
    let prior = Prior::new(Paper003Angles::new(0.0, 0.0, 0.0), 0.01, 0.001);
    let good = OneStageConfig::<f32>::gps_l1(FilterMode::ConstantGain, 2.0);
    let mut bad = good;
    bad.estimate = EstimatedAngles {
        alpha: false,
        beta: false,
        gamma: false,
    };
    assert_eq!(
        OneStageFilter::<f32, 6>::new(bad, array, &prior).err(),
        Some(OneStageError::InvalidConfig)
    );
    let mut bad = good;
    bad.loop_bandwidth_hz = f32::NAN;
    assert!(OneStageFilter::<f32, 6>::new(bad, array, &prior).is_err());
    // a state dimension that does not fit the configuration
    assert_eq!(
        OneStageFilter::<f32, 8>::new(good, array, &prior).err(),
        Some(OneStageError::InvalidConfig)
    );
    // three collinear antennas are an array (paper 000 takes them) but not a one-stage array
    let line = AntennaArray::new([Vector3::zeros(), Vector3::x(), Vector3::x() * 2.0]).unwrap();
    assert_eq!(
        OneStageFilter::<f32, 6>::new(good, line, &prior).err(),
        Some(OneStageError::DegenerateArray)
    );
    assert_eq!(
        AntennaArray::<f32>::paper_triangle(0.0).map_err(OneStageError::from),
        Err(OneStageError::DegenerateArray)
    );
    let mut bad_prior = prior;
    bad_prior.angle_covariance.m22 = -1.0;
    assert_eq!(
        OneStageFilter::<f32, 6>::new(good, array, &bad_prior).err(),
        Some(OneStageError::InvalidCovariance)
    );
    let mut f = OneStageFilter::<f32, 6>::new(good, array, &prior).unwrap();
    let before = f.clone();
    bad_prior.angles.beta = f32::INFINITY;
    assert_eq!(
        f.reinitialize(&bad_prior),
        Err(OneStageError::NonFiniteInput)
    );
    assert_eq!(f, before);
    // an empty epoch only predicts
    assert_eq!(f.step(&[]).unwrap().satellites, 0);
}

#[test]
fn reopening_the_line_biases_keeps_the_attitude_and_forgets_only_the_biases() {
    let mut config = OneStageConfig::<f64>::gps_l1(FilterMode::GaussianApproximation, 2.0);
    config.line_bias_states = true;
    let array = AntennaArray::paper_triangle(1.5).unwrap();
    let prior = Prior::new(Paper003Angles::new(0.0, 0.0, 0.0), 0.01, 0.001);
    let mut f = OneStageFilter::<f64, 8>::new(config, array, &prior).unwrap();
    let obs = observations(&Paper003Angles::new(0.001, -0.002, 0.001), 8);
    for _ in 0..500 {
        f.step(&obs).unwrap();
    }
    let (bb, bc) = (
        f.layout.parameter[3].unwrap(),
        f.layout.parameter[4].unwrap(),
    );
    let beta = f.layout.parameter[1].unwrap();
    let p0 = *f.ekf.covariance();
    assert!(p0[(bb, bb)] < 0.01 && p0[(bb, beta)].abs() > 0.0);
    let (angles, rates) = (f.angles(), f.rates());
    let before = f.clone();
    assert_eq!(
        f.reopen_line_biases(-1.0),
        Err(OneStageError::InvalidCovariance)
    );
    assert_eq!(
        f.reopen_line_biases(f64::NAN),
        Err(OneStageError::NonFiniteInput)
    );
    assert_eq!(f, before);
    f.reopen_line_biases(0.25).unwrap();
    let p = f.ekf.covariance();
    assert_eq!((p[(bb, bb)], p[(bc, bc)]), (0.25, 0.25));
    assert_eq!((p[(bb, beta)], p[(beta, bc)], p[(bb, bc)]), (0.0, 0.0, 0.0));
    assert_eq!(p[(beta, beta)], p0[(beta, beta)]);
    assert_eq!((f.angles(), f.rates()), (angles, rates));
    // and the filter goes on
    f.step(&obs).unwrap();
}
