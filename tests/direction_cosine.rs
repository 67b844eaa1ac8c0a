//! Paper 000's experiment, shortened, and what the issue asks of its filters: the corrected
//! six-state filter and the rigid-body filter reach their steady-state bounds, the paper's
//! quoted accuracy is out of reach, f32 runs 100 000 steps with a positive definite covariance
//! and agrees with f64, singular geometry and bad input are typed errors that change nothing.

use gnss_attitude::attitude::array::{AntennaArray, BaselinePair};
use gnss_attitude::attitude::baseline_epoch::BaselineEpoch;
use gnss_attitude::attitude::dcm_filter::DcmError;
use gnss_attitude::attitude::dcm_filter::{DcmFilterConfig, DirectionCosineFilter};
use gnss_attitude::attitude::direction_cosine::ColumnChoice;
use gnss_attitude::attitude::direction_cosine::DirectionCosineModel;
use gnss_attitude::attitude::multi_structure::MultiStructureFilter;
use gnss_attitude::attitude::multi_structure::STRUCTURE_PAIRS;
use gnss_attitude::attitude::rigid_body::{RigidBodyConfig, RigidBodyFilter};
use gnss_attitude::ekf::GateConfidence;
use gnss_attitude::error::Error;
use gnss_attitude::error::ErrorKind;
use gnss_attitude::geometry::Quaternion;
use host_sim::scenarios::dcm::bounds::{self, Noise};
use host_sim::scenarios::dcm::run_plan;
use host_sim::scenarios::dcm::truth::{self, Motion};
use host_sim::scenarios::RunContext;
use nalgebra::{Matrix3, SMatrix, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde_json::Value;

const OMEGA: [f64; 3] = [0.1047, 0.0174, 0.026];
const DT: f64 = 0.01;

fn paper_array() -> AntennaArray<f64> {
    AntennaArray::from_baselines(&Vector3::new(1.5, 1.8, 1.9), &Vector3::new(1.7, 1.7, 2.0))
        .unwrap()
}

fn scenario(variant: &str, runs: usize, duration: f64) -> Value {
    let ctx = RunContext {
        variant: variant.to_string(),
        seed: 7,
        out_dir: None,
        front_end: host_sim::synth::quantize::Quantizer::I8,
        tle: None,
    };
    let outcome = run_plan(&ctx, runs, duration).unwrap();
    Value::Object(outcome.metrics)
}

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// Per-axis RMS over the bound must be within [1/1.5, 1.5]: above, the filter misses its
/// bound; below, the bound would be wrong.
fn assert_near_bound(m: &Value, filter: &str) {
    for r in numbers(&m[filter]["rms_over_bound"]) {
        assert!(
            (0.67..1.5).contains(&r),
            "{filter}: RMS/bound {r} ({})",
            m[filter]
        );
    }
}

#[test]
fn paper_experiment_intensity_reading_reaches_the_bounds_and_rigid_body_wins() {
    // 2 runs x 400 s (statistics of the second halves: about ±9 % on an RMS)
    let m = scenario("intensity", 2, 400.0);
    assert_near_bound(&m, "six_state");
    assert_near_bound(&m, "rigid_body");
    let six = m["six_state"]["rotvec_rms_rad"].as_f64().unwrap();
    let rigid = m["rigid_body"]["rotvec_rms_rad"].as_f64().unwrap();
    // bounds: 2.19e-2 and 1.59e-2 rad
    assert!(rigid < six / 1.2, "rigid {rigid} six {six}");
    assert!(
        m["f32_vs_f64"]["six_state_fraction_of_rms"]
            .as_f64()
            .unwrap()
            < 0.01
    );
    assert!(
        m["f32_vs_f64"]["rigid_body_fraction_of_rms"]
            .as_f64()
            .unwrap()
            < 0.01
    );
    assert_eq!(m["six_state"]["step_failures"], 0);
}

#[test]
fn paper_experiment_literal_reading_cannot_reach_the_quoted_errors() {
    let m = scenario("paper", 2, 400.0);
    assert_near_bound(&m, "six_state");
    assert_near_bound(&m, "rigid_body");
    assert_eq!(m["paper_quoted_reachable_by_any_filter"], false);
    // the paper quotes (7.5, 5, 8.4)e-4 rad; every filter is two orders above
    for filter in ["six_state", "multi_structure", "rigid_body"] {
        for r in numbers(&m[filter]["rms_err_rad"]) {
            assert!(r > 50.0 * 8.4e-4, "{filter}: {r}");
        }
    }
}

#[test]
fn wide_geometry_gains_an_order_of_magnitude() {
    let narrow = scenario("intensity", 1, 200.0);
    let wide = scenario("wide", 1, 200.0);
    for filter in ["six_state", "rigid_body"] {
        let a = narrow[filter]["rotvec_rms_rad"].as_f64().unwrap();
        let b = wide[filter]["rotvec_rms_rad"].as_f64().unwrap();
        assert!(a > 5.0 * b, "{filter}: narrow {a} wide {b}");
    }
    assert_near_bound(&wide, "rigid_body");
}

#[test]
fn core_steady_state_covariance_matches_the_host_bound_derived_independently() {
    // core: σ_z² (∂θ/∂Y Φ⁻¹)(…)ᵀ from the model's Jacobians; host-sim: θ solved from
    // δz = ([θ]× + S) b with S restricted by the eliminated column's cross-product relation
    let array = paper_array();
    let noise = Noise {
        sigma_baseline: 0.6,
        sigma_velocity: 0.1,
        dt: DT,
    };
    for columns in [ColumnChoice::Paper, ColumnChoice::LargestNormal] {
        for pairs in STRUCTURE_PAIRS {
            let model = DirectionCosineModel::new(
                &array.baseline(pairs[0]),
                &array.baseline(pairs[1]),
                columns,
            )
            .unwrap();
            let core = model
                .steady_state_attitude_covariance(noise.sigma_z2())
                .unwrap();
            let host = bounds::six_state(&array, pairs, model.eliminated_column(), noise).unwrap();
            assert!(
                (core - host).norm() < 1e-9 * host.norm(),
                "{pairs:?} {columns:?}\n{core}\n{host}"
            );
        }
    }
}

/// Paper truth and literal-noise measurements, f64.
struct Experiment {
    motion: Motion,
    array: AntennaArray<f64>,
    rng: ChaCha8Rng,
    m_prev: Matrix3<f64>,
    t: f64,
}

impl Experiment {
    fn new(seed: u64) -> Self {
        let motion = Motion::Paper { omega: OMEGA };
        Self {
            m_prev: motion.attitude(0.0),
            motion,
            array: paper_array(),
            rng: ChaCha8Rng::seed_from_u64(seed),
            t: 0.0,
        }
    }

    fn next(
        &mut self,
        sigma_baseline: f64,
        sigma_velocity: f64,
    ) -> (Matrix3<f64>, BaselineEpoch<f64>) {
        self.t += DT;
        let m = self.motion.attitude(self.t);
        let e = truth::epoch(
            &self.array,
            &self.m_prev,
            &m,
            DT,
            sigma_baseline,
            sigma_velocity,
            &mut self.rng,
        );
        self.m_prev = m;
        (m, e)
    }
}

fn angle(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    let q = Quaternion::from_dcm(&(a.transpose() * b)).unwrap();
    q.to_rotation_vector().norm()
}

#[test]
fn f32_runs_100000_steps_with_a_positive_definite_covariance_and_agrees_with_f64() {
    // The whole 1000 s of the paper's experiment under the literal noise reading (the hardest:
    // errors of 0.1-0.3 rad), six-state and rigid-body filters in f32 and f64 on the same data.
    let mut x = Experiment::new(11);
    let a32 = AntennaArray::new(x.array.positions().map(|p| p.cast::<f32>())).unwrap();
    let six_config = DcmFilterConfig::paper(DT, 0.6, 0.1);
    let c0 = Matrix3::identity();
    let r0 = SMatrix::<f64, 6, 6>::identity() * 1e-4;
    let mut six64 = DirectionCosineFilter::new(&x.array, six_config, &c0, &r0).unwrap();
    let mut six32 = DirectionCosineFilter::new(
        &a32,
        DcmFilterConfig::paper(0.01f32, 0.6, 0.1),
        &c0.cast(),
        &r0.cast(),
    )
    .unwrap();
    let rigid_config = RigidBodyConfig {
        dt: DT,
        sigma_baseline: 0.6,
        sigma_velocity: 0.1,
        gate: Some(GateConfidence::P999),
    };
    let p0 = Matrix3::identity() * 1e-4;
    let mut rigid64 =
        RigidBodyFilter::new(&x.array, rigid_config, &Quaternion::identity(), &p0).unwrap();
    let mut rigid32 = RigidBodyFilter::new(
        &a32,
        RigidBodyConfig {
            dt: 0.01f32,
            sigma_baseline: 0.6,
            sigma_velocity: 0.1,
            gate: Some(GateConfidence::P999),
        },
        &Quaternion::identity(),
        &p0.cast(),
    )
    .unwrap();
    let (mut max_diff_six, mut max_diff_rigid) = (0.0f64, 0.0f64);
    let (mut sq_six, mut sq_rigid, mut n) = (0.0, 0.0, 0usize);
    for _ in 0..100_000 {
        let (m, e) = x.next(0.6, 0.1);
        let e32 = truth::epoch_f32(&e);
        // the step rejects (and reports) a covariance that is not positive definite
        let s32 = six32.step(&e32).expect("six-state f32 step");
        let s64 = six64.step(&e).expect("six-state f64 step");
        let r32 = rigid32.step(&e32).expect("rigid-body f32 step");
        let r64 = rigid64.step(&e).expect("rigid-body f64 step");
        max_diff_six = max_diff_six.max(angle(&s64.c_rb, &s32.c_rb.cast()));
        max_diff_rigid = max_diff_rigid.max(angle(&r64.c_rb, &r32.c_rb.cast()));
        sq_six += angle(&m, &s64.c_rb).powi(2);
        sq_rigid += angle(&m, &r64.c_rb).powi(2);
        n += 1;
    }
    let (rms_six, rms_rigid) = ((sq_six / n as f64).sqrt(), (sq_rigid / n as f64).sqrt());
    assert!(
        max_diff_six < 0.01 * rms_six,
        "six-state: f32 vs f64 {max_diff_six:e}, RMS {rms_six:e}"
    );
    assert!(
        max_diff_rigid < 0.01 * rms_rigid,
        "rigid: f32 vs f64 {max_diff_rigid:e}, RMS {rms_rigid:e}"
    );
    // the final f32 covariance: symmetric, positive definite, and the f64 one to 1e-3
    let r32 = six32.covariance().cast::<f64>();
    let r64 = *six64.covariance();
    assert_eq!(r32, r32.transpose());
    let eig = r32.symmetric_eigenvalues();
    assert!(eig.min() > 0.0, "{eig:?}");
    assert!((r32 - r64).norm() < 1e-3 * r64.norm(), "{r32} vs {r64}");
}

#[test]
fn singular_geometry_is_a_typed_error_and_column_reselection_tracks() {
    // an array in the body xy-plane: n = b12 × b23 along z, so n_x = 0 at every attitude
    let s = 3f64.sqrt() / 2.0;
    let array = AntennaArray::new([
        Vector3::zeros(),
        Vector3::new(-1.0, 0.0, 0.0),
        Vector3::new(-0.5, -s, 0.0),
    ])
    .unwrap();
    let config = DcmFilterConfig::paper(DT, 0.06, 0.01);
    let r0 = SMatrix::<f64, 6, 6>::identity() * 1e-4;
    let err = DirectionCosineFilter::new(&array, config, &Matrix3::identity(), &r0).unwrap_err();
    assert_eq!(err, DcmError::SingularGeometry);
    assert_eq!(err.kind(), ErrorKind::Unobservable);
    let reselected = DcmFilterConfig {
        columns: ColumnChoice::LargestNormal,
        ..config
    };
    let mut f = DirectionCosineFilter::new(&array, reselected, &Matrix3::identity(), &r0).unwrap();
    assert_eq!(f.model().eliminated_column(), 2);
    // noise-free data: the filter follows the truth
    let motion = Motion::Paper { omega: OMEGA };
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut prev = motion.attitude(0.0);
    for k in 1..=2000 {
        let m = motion.attitude(k as f64 * DT);
        let est = f
            .step(&truth::epoch(&array, &prev, &m, DT, 0.0, 0.0, &mut rng))
            .unwrap();
        assert!(angle(&m, &est.c_rb) < 1e-6, "step {k}");
        prev = m;
    }
    // |det Φ(Y)| = |n_x| (n_x² + |n_z c₂ − n_y c₃|²) ≥ |n_x|³ for every Y, rotation or not:
    // even a state whose kept columns vanish keeps Φ regular, but it is no attitude
    let mut collapsed = Matrix3::identity();
    collapsed.set_column(1, &Vector3::zeros());
    collapsed.set_column(2, &Vector3::zeros());
    let f = DirectionCosineFilter::new(&paper_array(), config, &collapsed, &r0).unwrap();
    let n = Vector3::new(1.5f64, 1.8, 1.9).cross(&Vector3::new(1.7, 1.7, 2.0));
    let det = f.model().jacobian(f.state()).determinant().abs();
    assert!((det - n.x.abs().powi(3)).abs() < 1e-12);
    assert_eq!(f.estimate().unwrap_err(), DcmError::NotARotation);
}

#[test]
fn bad_input_is_a_typed_error_and_leaves_every_filter_unchanged() {
    let array = paper_array();
    let mut x = Experiment::new(3);
    let r0 = SMatrix::<f64, 6, 6>::identity() * 1e-4;
    let six_config = DcmFilterConfig::paper(DT, 0.06, 0.01);
    let mut six =
        DirectionCosineFilter::new(&array, six_config, &Matrix3::identity(), &r0).unwrap();
    let mut multi =
        MultiStructureFilter::new(&array, six_config, &Matrix3::identity(), &r0).unwrap();
    let rigid_config = RigidBodyConfig {
        dt: DT,
        sigma_baseline: 0.06,
        sigma_velocity: 0.01,
        gate: Some(GateConfidence::P999),
    };
    let mut rigid = RigidBodyFilter::new(
        &array,
        rigid_config,
        &Quaternion::identity(),
        &(Matrix3::identity() * 1e-4),
    )
    .unwrap();
    for _ in 0..200 {
        let (_, e) = x.next(0.06, 0.01);
        six.step(&e).unwrap();
        multi.step(&e).unwrap();
        rigid.step(&e).unwrap();
    }
    let (_, good) = x.next(0.06, 0.01);
    let mut nan_baseline = good;
    nan_baseline.baselines[0] = Some(Vector3::new(f64::NAN, 1.0, 2.0));
    let mut inf_velocity = good;
    inf_velocity.velocity_differences[1] = Some(Vector3::new(0.0, f64::INFINITY, 0.0));
    let mut zero_baseline = good;
    zero_baseline.baselines[1] = Some(Vector3::zeros());
    // antenna 2 has no solution: pairs 12 and 23 are missing
    let positions = [
        Some(Vector3::new(1.0, 2.0, 3.0)),
        None,
        Some(Vector3::new(0.0, 1.0, 0.5)),
    ];
    let missing_antenna = BaselineEpoch::from_antennas(&positions, &positions);
    assert!(missing_antenna.baselines[BaselinePair::P13.index()].is_some());
    let cases = [
        (nan_baseline, DcmError::NonFinite),
        (inf_velocity, DcmError::NonFinite),
        (zero_baseline, DcmError::ZeroLengthBaseline),
        (missing_antenna, DcmError::MissingBaseline),
    ];
    for (epoch, expected) in cases {
        let (s0, m0, r0) = (six.clone(), multi.clone(), rigid.clone());
        assert_eq!(six.step(&epoch).unwrap_err(), expected);
        assert_eq!(multi.step(&epoch).unwrap_err(), expected);
        assert_eq!(rigid.step(&epoch).unwrap_err(), expected);
        assert_eq!(six, s0);
        assert_eq!(multi, m0);
        assert_eq!(rigid, r0);
    }
    // and the filters carry on with good data
    assert!(six.step(&good).is_ok() && multi.step(&good).is_ok() && rigid.step(&good).is_ok());
}
