//! The gyro-aided fine filter on a simulated spinning body: a MEMS gyro (bias, angle random
//! walk), six satellites, carrier-phase single differences every 20 ms with unknown line
//! biases. The filter must converge, estimate the gyro bias and the line biases, keep its
//! reported σ honest, and give the same answer in f32 as in f64.

use gnss_attitude::attitude::gyro_aided::{
    GyroAidedConfig, GyroAidedFilter, GyroAidedPrior, PhaseDifferenceBlock,
};
use gnss_attitude::ekf::GateConfidence;
use gnss_attitude::geometry::Quaternion;
use gnss_attitude::Real;
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

const LAMBDA: f64 = 0.190_293_672_798_365;
const BLOCK_S: f64 = 0.02;
const ARW: f64 = 8.7e-5; // 0.3 °/√h
const BIAS_RW: f64 = 2e-6;

struct Run {
    /// Attitude error (rad, body rotation vector) and 1σ per axis, per block.
    errors: Vec<(Vector3<f64>, Vector3<f64>)>,
    bias_error: Vector3<f64>,
    line_bias_error: Vector2<f64>,
    /// Attitudes as estimated, for the f32/f64 comparison.
    attitudes: Vec<Quaternion<f64>>,
}

/// The scalar types the filter runs in, back to f64.
trait Scalar: Real {
    fn f64(self) -> f64;
}
impl Scalar for f32 {
    fn f64(self) -> f64 {
        f64::from(self)
    }
}
impl Scalar for f64 {
    fn f64(self) -> f64 {
        self
    }
}

fn back<T: Scalar>(v: T) -> f64 {
    v.f64()
}

fn n(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

fn sky() -> Vec<Vector3<f64>> {
    [
        (0.3, 1.2),
        (1.5, 0.8),
        (2.7, 0.5),
        (3.9, 1.0),
        (5.0, 0.35),
        (0.9, 0.25),
    ]
    .iter()
    .map(|&(az, el): &(f64, f64)| Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin()))
    .collect()
}

fn run<T: Scalar>(seconds: f64, seed: u64) -> Run {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let baselines = [Vector3::new(0.5, 0.0, 0.0), Vector3::new(0.25, 0.433, 0.0)];
    let line_bias = Vector2::new(0.7, -1.2);
    let gyro_bias = Vector3::new(2.4e-4, -1.5e-4, 1.0e-4); // ~50 °/h
    let omega = Vector3::new(0.002, -0.001, 0.0105); // 0.6 °/s spin
    let sigma_sd = 0.05; // rad per SD per block (≈ 45 dB-Hz over 20 ms)
    let mut q_true = Quaternion::from_rotation_vector(&Vector3::new(0.2, -0.3, 1.0));
    let err0 = Vector3::new(0.004, -0.003, 0.005);
    let q0 = q_true * Quaternion::from_rotation_vector(&(-err0));
    let cast = |v: f64| -> T { nalgebra::convert(v) };
    let cv = |v: &Vector3<f64>| v.map(cast);
    let config = GyroAidedConfig {
        wavelength_m: cast(LAMBDA),
        angle_random_walk: cast(ARW),
        bias_random_walk: cast(BIAS_RW),
        line_bias_random_walk: cast(1e-5),
        gate: Some(GateConfidence::P999),
    };
    let prior = GyroAidedPrior {
        q_rb: Quaternion::new(cast(q0.w), cast(q0.x), cast(q0.y), cast(q0.z)),
        attitude_covariance: Matrix3::identity() * cast(3e-5),
        bias_sigma: cast(5e-4),
        // the line biases are known to a fraction of a cycle only
        line_bias: Vector2::new(cast(0.9), cast(-1.0)),
        line_bias_covariance: Matrix2::identity() * cast(0.1),
    };
    let mut filter = GyroAidedFilter::new(
        config,
        [cv(&baselines[0]), cv(&baselines[1])],
        &prior,
        &Quaternion::identity(),
    )
    .expect("filter");
    // the gyro's propagated attitude M (corrected by the bias estimate fed back)
    let mut m = Quaternion::<f64>::identity();
    // M at the last update (the filter's epoch)
    let mut m_filter = m;
    let mut applied_bias = Vector3::<f64>::zeros();
    let mut bias = gyro_bias;
    let los = sky();
    let mut out = Run {
        errors: Vec::new(),
        bias_error: Vector3::zeros(),
        line_bias_error: Vector2::zeros(),
        attitudes: Vec::new(),
    };
    let steps = (seconds / BLOCK_S) as usize;
    for _ in 0..steps {
        // truth over one block, gyro increment with bias and ARW
        let theta_true = omega * BLOCK_S;
        bias += Vector3::new(n(&mut rng), n(&mut rng), n(&mut rng)) * (BIAS_RW * BLOCK_S.sqrt());
        let noise = Vector3::new(n(&mut rng), n(&mut rng), n(&mut rng)) * (ARW * BLOCK_S.sqrt());
        let theta_meas = theta_true + bias * BLOCK_S + noise;
        let q_mid = q_true * Quaternion::from_rotation_vector(&(theta_true * 0.5));
        q_true = q_true * Quaternion::from_rotation_vector(&theta_true);
        let m_mid =
            m * Quaternion::from_rotation_vector(&((theta_meas - applied_bias * BLOCK_S) * 0.5));
        m = m * Quaternion::from_rotation_vector(&(theta_meas - applied_bias * BLOCK_S));
        // the block's single differences at its centre
        let c = q_mid.to_dcm();
        let blocks: Vec<PhaseDifferenceBlock<T>> = los
            .iter()
            .enumerate()
            .map(|(i, mu)| {
                let k = std::f64::consts::TAU / LAMBDA;
                let na = n(&mut rng) * sigma_sd / 2f64.sqrt();
                let mut phase = |p: usize| {
                    let geo = k * mu.dot(&(c * baselines[p]));
                    geo + line_bias[p] + na + n(&mut rng) * sigma_sd / 2f64.sqrt()
                };
                let (pb, pc) = (phase(0), phase(1));
                let wrap = |x: f64| {
                    (x + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                        - std::f64::consts::PI
                };
                let v = sigma_sd * sigma_sd;
                PhaseDifferenceBlock {
                    id: i as u8 + 1,
                    los: cv(mu),
                    phase_rad: Vector2::new(cast(wrap(pb)), cast(wrap(pc))),
                    covariance: Matrix2::new(cast(v), cast(v / 2.0), cast(v / 2.0), cast(v)),
                }
            })
            .collect();
        let to_t =
            |q: &Quaternion<f64>| Quaternion::new(cast(q.w), cast(q.x), cast(q.y), cast(q.z));
        let delta = m_filter.conjugate() * m_mid;
        m_filter = m_mid;
        filter
            .predict(&to_t(&delta), cast(BLOCK_S))
            .expect("predict");
        let report = filter.update(&to_t(&m_mid), &blocks).expect("update");
        applied_bias += report.bias_correction.map(|v| back(v));
        let q_est = filter.attitude(&to_t(&m_mid));
        let q_est = Quaternion::new(back(q_est.w), back(q_est.x), back(q_est.y), back(q_est.z));
        let error = (q_est.conjugate() * q_mid).to_rotation_vector();
        let p = filter.attitude_covariance();
        let sigma = Vector3::new(p[(0, 0)], p[(1, 1)], p[(2, 2)]).map(|v| back(v).sqrt());
        out.errors.push((error, sigma));
        out.attitudes.push(q_est);
    }
    out.bias_error = applied_bias - bias;
    let lb = filter.line_bias();
    out.line_bias_error = Vector2::new(back(lb.x) - line_bias.x, back(lb.y) - line_bias.y);
    out
}

#[test]
fn the_filter_converges_estimates_the_biases_and_its_sigma_is_honest() {
    let r = run::<f32>(120.0, 7);
    let converged = &r.errors[r.errors.len() / 4..];
    // attitude error within 3σ in nearly every block after convergence
    let within = converged
        .iter()
        .filter(|(e, s)| (0..3).all(|i| e[i].abs() <= 3.0 * s[i]))
        .count() as f64
        / converged.len() as f64;
    let last = r.errors.last().unwrap();
    eprintln!(
        "within {within:.4}, last error {:?} sigma {:?}, bias err {:?}, line bias err {:?}",
        last.0, last.1, r.bias_error, r.line_bias_error
    );
    assert!(within > 0.97, "only {within:.3} of blocks within 3σ");
    // the attitude is at the sub-milliradian level
    let rms = (converged.iter().map(|(e, _)| e.norm_squared()).sum::<f64>()
        / converged.len() as f64)
        .sqrt();
    assert!(rms < 1e-3, "rms {rms}");
    // gyro bias to a few °/h, line biases to a few milliradians
    assert!(r.bias_error.amax() < 2e-5, "bias error {:?}", r.bias_error);
    assert!(
        r.line_bias_error.amax() < 0.01,
        "line bias error {:?}",
        r.line_bias_error
    );
}

#[test]
fn f32_follows_the_f64_reference() {
    let a = run::<f32>(30.0, 3);
    let b = run::<f64>(30.0, 3);
    let worst = a
        .attitudes
        .iter()
        .zip(b.attitudes.iter())
        .map(|(x, y)| x.angle_to(y))
        .fold(0.0, f64::max);
    assert!(worst < 2e-5, "f32 departs from f64 by {worst} rad");
}
