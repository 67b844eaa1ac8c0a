//! The EKF toolkit against an independent f64 Kalman filter, its Monte Carlo consistency, and
//! its behaviour on bad input.

use gnss_attitude::ekf::FilterError;
use gnss_attitude::ekf::{Ekf, GateConfidence, NisGate};
use nalgebra::{Matrix2, Matrix2x4, Matrix4, SMatrix, SVector, Vector2, Vector4};
use proptest::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Constant velocity in the plane, position measured: the textbook linear problem.
struct Problem {
    dt: f64,
    sigma_acc: f64,
    f: Matrix4<f64>,
    q: Matrix4<f64>,
    h: Matrix2x4<f64>,
    r: Matrix2<f64>,
}

fn problem(dt: f64, sigma_acc: f64, sigma_pos: f64) -> Problem {
    let mut f = Matrix4::identity();
    f[(0, 2)] = dt;
    f[(1, 3)] = dt;
    let qa = sigma_acc * sigma_acc;
    let mut q = Matrix4::zeros();
    for i in 0..2 {
        q[(i, i)] = qa * dt.powi(4) / 4.0;
        q[(i, i + 2)] = qa * dt.powi(3) / 2.0;
        q[(i + 2, i)] = qa * dt.powi(3) / 2.0;
        q[(i + 2, i + 2)] = qa * dt * dt;
    }
    let h = Matrix2x4::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0);
    Problem {
        dt,
        sigma_acc,
        f,
        q,
        h,
        r: Matrix2::identity() * sigma_pos * sigma_pos,
    }
}

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

/// Draws truth and measurements: a white acceleration held over each step, whose covariance
/// is exactly the model's (rank-deficient) `Q`.
fn simulate(
    p: &Problem,
    x0: Vector4<f64>,
    steps: usize,
    rng: &mut ChaCha8Rng,
) -> (Vec<Vector4<f64>>, Vec<Vector2<f64>>) {
    let lr = p.r.map(f64::sqrt);
    let mut x = x0;
    let (mut xs, mut zs) = (Vec::new(), Vec::new());
    for _ in 0..steps {
        let (ax, ay) = (p.sigma_acc * normal(rng), p.sigma_acc * normal(rng));
        let g = p.dt * p.dt / 2.0;
        x = p.f * x + Vector4::new(g * ax, g * ay, p.dt * ax, p.dt * ay);
        xs.push(x);
        zs.push(p.h * x + lr * Vector2::from_fn(|_, _| normal(rng)));
    }
    (xs, zs)
}

/// The independent reference: the plain textbook filter in f64 with an explicit inverse and
/// the short-form covariance update `P ← (I − KH) P` (fine in f64 for this problem).
fn reference_filter(
    p: &Problem,
    x0: Vector4<f64>,
    p0: Matrix4<f64>,
    zs: &[Vector2<f64>],
) -> Vec<(Vector4<f64>, Matrix4<f64>)> {
    let (mut x, mut cov) = (x0, p0);
    zs.iter()
        .map(|z| {
            x = p.f * x;
            cov = p.f * cov * p.f.transpose() + p.q;
            let s = p.h * cov * p.h.transpose() + p.r;
            let k = cov * p.h.transpose() * s.try_inverse().expect("S is PD");
            x += k * (z - p.h * x);
            cov = (Matrix4::identity() - k * p.h) * cov;
            (x, cov)
        })
        .collect()
}

#[test]
fn f32_toolkit_matches_an_independent_f64_filter_to_a_small_fraction_of_sigma() {
    let p = problem(0.1, 0.5, 2.0);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let x0 = Vector4::new(100.0, -50.0, 3.0, 1.0);
    let p0 = Matrix4::from_diagonal(&Vector4::new(400.0, 400.0, 25.0, 25.0));
    let (_, zs) = simulate(&p, x0, 5000, &mut rng);
    let reference = reference_filter(&p, x0, p0, &zs);

    let mut kf = Ekf::<4, f32>::new(x0.cast(), p0.cast()).unwrap();
    let (f, q, h, r) = (
        p.f.cast::<f32>(),
        p.q.cast::<f32>(),
        p.h.cast::<f32>(),
        p.r.cast::<f32>(),
    );
    let mut worst_state = 0.0f64; // |x32 − x64| / σ, worst element and epoch
    let mut worst_cov = 0.0f64; // |P32 − P64|_ij / √(P_ii P_jj)
    for (z, (x_ref, p_ref)) in zs.iter().zip(&reference) {
        kf.predict(&f, &q).unwrap();
        let y = z.cast::<f32>() - h * kf.state();
        assert!(kf.update(&y, &h, &r, None).unwrap().accepted);
        let x = kf.state().cast::<f64>();
        let cov = kf.covariance().cast::<f64>();
        for i in 0..4 {
            worst_state = worst_state.max((x[i] - x_ref[i]).abs() / p_ref[(i, i)].sqrt());
            for j in 0..4 {
                worst_cov = worst_cov.max(
                    (cov[(i, j)] - p_ref[(i, j)]).abs() / (p_ref[(i, i)] * p_ref[(j, j)]).sqrt(),
                );
            }
        }
    }
    // f32 carries ~7 digits; positions of ~1e3 m against σ ≈ 0.5 m lose ~3 of them.
    assert!(worst_state < 0.01, "state deviation {worst_state} σ");
    assert!(worst_cov < 1e-4, "covariance deviation {worst_cov}");
}

#[test]
fn monte_carlo_nees_is_chi_square_with_n_degrees_of_freedom() {
    // 400 runs x 300 steps. At every epoch the NEES averaged over runs is, for a consistent
    // filter, χ²(4·400)/400: its 99 % interval is [3.65, 4.37]. Allow 3 % of epochs outside
    // (1 % expected), and the grand mean within ±2 % of 4.
    let p = problem(0.1, 0.3, 0.5);
    let (runs, steps) = (400usize, 300usize);
    let mut sum_by_epoch = vec![0.0f64; steps];
    let mut nis_sum = 0.0f64;
    for run in 0..runs {
        let mut rng = ChaCha8Rng::seed_from_u64(1000 + run as u64);
        let p0 = Matrix4::from_diagonal(&Vector4::new(4.0, 4.0, 1.0, 1.0));
        let truth0 = Vector4::new(0.0, 0.0, 1.0, -1.0);
        // initial estimate drawn from the prior around the truth
        let x0 = truth0 + p0.map(f64::sqrt) * Vector4::from_fn(|_, _| normal(&mut rng));
        let (xs, zs) = simulate(&p, truth0, steps, &mut rng);
        let mut kf = Ekf::<4, f32>::new(x0.cast(), p0.cast()).unwrap();
        let (f, q, h, r) = (
            p.f.cast::<f32>(),
            p.q.cast::<f32>(),
            p.h.cast::<f32>(),
            p.r.cast::<f32>(),
        );
        for (k, (x, z)) in xs.iter().zip(&zs).enumerate() {
            kf.predict(&f, &q).unwrap();
            let y = z.cast::<f32>() - h * kf.state();
            nis_sum += f64::from(kf.update(&y, &h, &r, None).unwrap().nis);
            sum_by_epoch[k] += f64::from(kf.nees(&x.cast()).unwrap());
        }
    }
    let (lo, hi) = (3.65, 4.37);
    let outside = sum_by_epoch
        .iter()
        .filter(|&&s| !(lo..=hi).contains(&(s / runs as f64)))
        .count();
    let grand = sum_by_epoch.iter().sum::<f64>() / (runs * steps) as f64;
    let mean_nis = nis_sum / (runs * steps) as f64;
    assert!(
        outside as f64 <= 0.03 * steps as f64,
        "{outside} of {steps} epochs outside the 99 % NEES interval"
    );
    assert!((grand - 4.0).abs() < 0.08, "mean NEES {grand}");
    assert!((mean_nis - 2.0).abs() < 0.04, "mean NIS {mean_nis}");
}

#[test]
fn sequential_scalar_updates_equal_the_batch_update_for_diagonal_noise() {
    let p = problem(0.1, 0.5, 1.0);
    let p0 = Matrix4::from_diagonal(&Vector4::new(9.0, 4.0, 1.0, 2.0)) + Matrix4::from_element(0.1);
    let mut batch = Ekf::<4, f64>::new(Vector4::new(1.0, 2.0, 0.0, 0.0), p0).unwrap();
    let mut seq = batch.clone();
    let y = Vector2::new(0.7, -1.3);
    batch.update(&y, &p.h, &p.r, None).unwrap();
    let report = seq
        .update_sequential(&y, &p.h, &p.r.diagonal(), None)
        .unwrap();
    assert_eq!(report.accepted_count(), 2);
    assert!((batch.state() - seq.state()).norm() < 1e-12);
    assert!((batch.covariance() - seq.covariance()).norm() < 1e-12);
}

#[test]
fn joseph_form_keeps_f32_covariance_symmetric_positive_definite_over_100k_steps() {
    // A stiff problem: nearly perfect position measurements (σ = 1 mm) of a slowly driven
    // state at large values. The covariance spans ~10 orders of magnitude.
    let p = problem(0.01, 1e-3, 1e-3);
    let (f, q, h, r) = (
        p.f.cast::<f32>(),
        p.q.cast::<f32>(),
        p.h.cast::<f32>(),
        p.r.cast::<f32>(),
    );
    let mut kf = Ekf::<4, f32>::new(
        Vector4::new(1e3, -1e3, 0.0, 0.0),
        Matrix4::identity() * 100.0,
    )
    .unwrap()
    .with_variance_floor(1e-12);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..100_000 {
        kf.predict(&f, &q).unwrap();
        let z = Vector2::new(1e3, -1e3) + Vector2::from_fn(|_, _| 1e-3 * normal(&mut rng) as f32);
        let y = z - h * kf.state();
        kf.update(&y, &h, &r, None).unwrap();
    }
    let cov = kf.covariance();
    assert_eq!(
        cov,
        &cov.transpose(),
        "covariance must be exactly symmetric"
    );
    assert!(
        cov.cholesky().is_some(),
        "covariance must stay positive definite: {cov}"
    );
    assert!(cov.diagonal().iter().all(|&v| v >= 1e-12));
}

#[test]
fn rejected_and_failed_steps_leave_the_filter_unchanged() {
    let h = SMatrix::<f32, 1, 2>::new(1.0, 0.0);
    let mut kf = Ekf::<2, f32>::new(SVector::zeros(), Matrix2::identity()).unwrap();
    let before = kf.clone();

    let nan = SVector::<f32, 1>::new(f32::NAN);
    let r = SMatrix::<f32, 1, 1>::new(1.0);
    assert_eq!(
        kf.update(&nan, &h, &r, None),
        Err(FilterError::NonFiniteInput)
    );
    let bad_r = SMatrix::<f32, 1, 1>::new(-5.0);
    assert_eq!(
        kf.update(&SVector::<f32, 1>::new(0.1), &h, &bad_r, None),
        Err(FilterError::InnovationNotPositiveDefinite)
    );
    assert_eq!(
        kf.update_scalar(0.1, &h, 0.0, None),
        Err(FilterError::NonPositiveNoise)
    );
    let mut f = Matrix2::identity();
    f[(0, 1)] = f32::INFINITY;
    assert_eq!(
        kf.predict(&f, &Matrix2::identity()),
        Err(FilterError::NonFiniteInput)
    );
    let neg_q = Matrix2::new(-1.0, 0.0, 0.0, 1.0);
    assert_eq!(
        kf.predict(&Matrix2::identity(), &neg_q),
        Err(FilterError::InvalidCovariance)
    );
    let huge = Matrix2::identity() * 1e30;
    assert_eq!(
        kf.predict(&huge, &Matrix2::zeros()),
        Err(FilterError::Numerical)
    );
    assert_eq!(kf, before);

    // a 10σ outlier is gated and changes nothing
    let gate = Some(NisGate::chi_square(1, GateConfidence::P999));
    let report = kf.update_scalar(10.0 * 2f32.sqrt(), &h, 1.0, gate).unwrap();
    assert!(!report.accepted && (report.nis - 100.0).abs() < 1e-3);
    assert_eq!(kf, before);

    assert_eq!(
        Ekf::<2, f32>::new(SVector::zeros(), Matrix2::new(1.0, 2.0, 2.0, 1.0)),
        Err(FilterError::InvalidCovariance)
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Whatever numbers arrive (huge, tiny, NaN, infinite, negative variances), a step returns
    /// a result — never a panic — and a filter that reports success holds finite numbers.
    #[test]
    fn no_input_makes_the_toolkit_panic_or_hold_non_finite_numbers(
        x in prop::array::uniform3(prop_oneof![any::<f32>(), -1e3f32..1e3]),
        pdiag in prop::array::uniform3(prop_oneof![any::<f32>(), 1e-6f32..1e6]),
        fvals in prop::array::uniform9(prop_oneof![any::<f32>(), -2f32..2.0]),
        hvals in prop::array::uniform3(prop_oneof![any::<f32>(), -10f32..10.0]),
        y in prop_oneof![any::<f32>(), -1e3f32..1e3],
        r in prop_oneof![any::<f32>(), 1e-6f32..1e3],
    ) {
        let p0 = SMatrix::<f32, 3, 3>::from_diagonal(&SVector::from(pdiag));
        if let Ok(mut kf) = Ekf::<3, f32>::new(SVector::from(x), p0) {
            let f = SMatrix::<f32, 3, 3>::from_row_slice(&fvals);
            let _ = kf.predict(&f, &SMatrix::identity());
            let h = SMatrix::<f32, 1, 3>::from_row_slice(&hvals);
            let _ = kf.update_scalar(y, &h, r, Some(NisGate::new(25.0)));
            let _ = kf.update(&SVector::<f32, 1>::new(y), &h, &SMatrix::<f32, 1, 1>::new(r), None);
            let _ = kf.update_sequential(&SVector::<f32, 1>::new(y), &h, &SVector::<f32, 1>::new(r), None);
            prop_assert!(kf.state().iter().all(|v| v.is_finite()));
            prop_assert!(kf.covariance().iter().all(|v| v.is_finite()));
        }
    }
}
