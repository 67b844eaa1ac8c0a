//! A torque-free rigid body (a tumbling microsatellite), f64: Euler's equations and the
//! attitude kinematics integrated together by RK4, with the exact angle increments a rate gyro
//! would integrate; a MEMS gyro on it and a noisy attitude reference (GNSS-like).

use gnss_attitude::geometry::{Euler321, Quaternion};
use nalgebra::{SVector, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use super::gyro::paper_d;

/// The state of a tumbling body.
#[derive(Clone, Debug)]
pub struct TumblingBody {
    /// Principal moments of inertia (kg m²), body axes = gyro axes.
    pub inertia: Vector3<f64>,
    /// Attitude `q_IE` (body to inertial, Hamilton).
    pub q: Quaternion<f64>,
    /// Body rate (rad/s, body axes).
    pub omega: Vector3<f64>,
}

/// Euler's equations without torque: `J ω̇ = −ω × J ω`.
fn omega_dot(inertia: &Vector3<f64>, w: &Vector3<f64>) -> Vector3<f64> {
    let h = inertia.component_mul(w);
    (-w.cross(&h)).component_div(inertia)
}

/// `q̇ = ½ q ∘ (0, ω)`.
fn q_dot(q: &Quaternion<f64>, w: &Vector3<f64>) -> [f64; 4] {
    let d = *q * Quaternion::from_parts(0.0, *w);
    [0.5 * d.w, 0.5 * d.x, 0.5 * d.y, 0.5 * d.z]
}

fn add(q: &Quaternion<f64>, d: &[f64; 4], s: f64) -> Quaternion<f64> {
    Quaternion::new(
        q.w + s * d[0],
        q.x + s * d[1],
        q.y + s * d[2],
        q.z + s * d[3],
    )
}

impl TumblingBody {
    /// Advances by `dt` seconds (RK4 on attitude, rate and the integral of the rate) and
    /// returns `∫ω dt` over the step (rad, body axes).
    pub fn step(&mut self, dt: f64) -> Vector3<f64> {
        let j = self.inertia;
        let (q0, w0) = (self.q, self.omega);
        let k1w = omega_dot(&j, &w0);
        let k1q = q_dot(&q0, &w0);
        let w1 = w0 + k1w * (dt / 2.0);
        let k2w = omega_dot(&j, &w1);
        let k2q = q_dot(&add(&q0, &k1q, dt / 2.0), &w1);
        let w2 = w0 + k2w * (dt / 2.0);
        let k3w = omega_dot(&j, &w2);
        let k3q = q_dot(&add(&q0, &k2q, dt / 2.0), &w2);
        let w3 = w0 + k3w * dt;
        let k4w = omega_dot(&j, &w3);
        let k4q = q_dot(&add(&q0, &k3q, dt), &w3);
        // θ̇ = ω: RK4 on the rate's integral uses the same stage rates
        let theta = (w0 + w1 * 2.0 + w2 * 2.0 + w3) * (dt / 6.0);
        self.omega = w0 + (k1w + k2w * 2.0 + k3w * 2.0 + k4w) * (dt / 6.0);
        let q = Quaternion::new(
            q0.w + dt / 6.0 * (k1q[0] + 2.0 * k2q[0] + 2.0 * k3q[0] + k4q[0]),
            q0.x + dt / 6.0 * (k1q[1] + 2.0 * k2q[1] + 2.0 * k3q[1] + k4q[1]),
            q0.y + dt / 6.0 * (k1q[2] + 2.0 * k2q[2] + 2.0 * k3q[2] + k4q[2]),
            q0.z + dt / 6.0 * (k1q[3] + 2.0 * k2q[3] + 2.0 * k3q[3] + k4q[3]),
        );
        self.q = q.normalize().unwrap_or(q);
        theta
    }
}

/// A MEMS gyro: the errors of paper 001's model `D = [D_I D_II E₃]` plus random walks.
#[derive(Clone, Debug)]
pub struct MemsGyro {
    /// Scale factors, symmetric misalignments (rad), initial biases (rad/s).
    pub c: SVector<f64, 9>,
    /// Angle random walk (rad/√s).
    pub arw: f64,
    /// Bias random walk (rad/s/√s).
    pub bias_rw: f64,
}

/// What [`generate_tumble_run`] simulates.
#[derive(Clone, Debug)]
pub struct TumbleSetup {
    /// Gyro sample interval (s).
    pub sample_interval: f64,
    /// RK4 sub-steps of the truth per sample.
    pub substeps: usize,
    /// Samples to generate.
    pub samples: usize,
    /// The first this many samples define the mean gyro error [`TumbleRun::c_mean`].
    pub mean_over: usize,
    /// White noise of the reference attitude (rad per axis, antenna frame).
    pub reference_noise: f64,
    /// The gyro.
    pub gyro: MemsGyro,
}

/// One simulated run; vectors are indexed by sample (index 0 is `t = 0`).
#[derive(Clone, Debug)]
pub struct TumbleRun {
    /// True attitude `q_IE` (gyro axes to inertial).
    pub lambda: Vec<Quaternion<f64>>,
    /// Gyro output increments (rad) over the sample ending at each index (index 0 unused).
    pub gyro: Vec<Vector3<f64>>,
    /// Reference attitude samples `N = Λ ∘ q_EJ ∘ exp(n)` of the antenna frame `J`.
    pub reference: Vec<Quaternion<f64>>,
    /// Initial computed attitude: the first reference sample with a nominal mounting that is
    /// 0.25° off.
    pub m0: Quaternion<f64>,
    /// Mean of the true `c` over the first `mean_over` samples (the bias wanders).
    pub c_mean: SVector<f64, 9>,
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    <StandardNormal as Distribution<f64>>::sample(&StandardNormal, rng)
}

fn gauss3(rng: &mut ChaCha8Rng, s: f64) -> Vector3<f64> {
    Vector3::new(gauss(rng), gauss(rng), gauss(rng)) * s
}

/// A tumbling microsatellite (principal inertia 1.2, 1.6, 2.0 kg m², rate about (3, −4, 5)°/s,
/// random initial attitude) with a MEMS gyro and an antenna-frame attitude reference mounted at
/// an angle unknown to the calibrator. Deterministic for `(seed, run)`.
pub fn generate_tumble_run(seed: u64, run: usize, setup: &TumbleSetup) -> TumbleRun {
    let h = setup.sample_interval;
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(7_919).wrapping_add(run as u64));
    let mut body = TumblingBody {
        inertia: Vector3::new(1.2, 1.6, 2.0),
        q: Quaternion::from_rotation_vector(&gauss3(&mut rng, 2.0)),
        omega: Vector3::new(3.0, -4.0, 5.0).map(f64::to_radians) + gauss3(&mut rng, 0.01),
    };
    let mount = Euler321::new(0.5, -0.2, 0.3).to_quaternion(); // q_EJ
    let mount_nominal =
        mount * Quaternion::from_rotation_vector(&Vector3::new(3.5e-3, -1.7e-3, 2.6e-3));
    let n = setup.samples;
    let mut c = setup.gyro.c;
    let mut c_sum = SVector::<f64, 9>::zeros();
    let (mut lambda, mut gyro, mut reference) = (
        Vec::with_capacity(n + 1),
        Vec::with_capacity(n + 1),
        Vec::with_capacity(n + 1),
    );
    let noise = setup.reference_noise;
    let noisy_ref = |q: &Quaternion<f64>, rng: &mut ChaCha8Rng| {
        *q * mount * Quaternion::from_rotation_vector(&gauss3(rng, noise))
    };
    lambda.push(body.q);
    gyro.push(Vector3::zeros());
    reference.push(noisy_ref(&body.q, &mut rng));
    for k in 1..=n {
        let mut theta = Vector3::zeros();
        for _ in 0..setup.substeps {
            theta += body.step(h / setup.substeps as f64);
        }
        // θ* = θ + [D_I D_II](θ) c₁…₆ + h c₇…₉ + angle random walk; then the bias wanders
        let mut d = paper_d(&theta);
        for i in 0..3 {
            d[(i, 6 + i)] = h;
        }
        gyro.push(theta + d * c + gauss3(&mut rng, setup.gyro.arw * h.sqrt()));
        for i in 6..9 {
            c[i] += setup.gyro.bias_rw * h.sqrt() * gauss(&mut rng);
        }
        if k <= setup.mean_over {
            c_sum += c;
        }
        lambda.push(body.q);
        reference.push(noisy_ref(&body.q, &mut rng));
    }
    let m0 = reference[0] * mount_nominal.conjugate();
    TumbleRun {
        lambda,
        gyro,
        reference,
        m0,
        c_mean: c_sum / setup.mean_over.max(1) as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn energy_and_angular_momentum_are_conserved() {
        let mut b = TumblingBody {
            inertia: Vector3::new(0.06, 0.08, 0.10),
            q: Quaternion::new(0.64, 0.48, 0.36, -0.48),
            omega: Vector3::new(0.05, -0.06, 0.07),
        };
        let energy = |b: &TumblingBody| b.omega.dot(&b.inertia.component_mul(&b.omega));
        let momentum = |b: &TumblingBody| b.q.rotate(&b.inertia.component_mul(&b.omega));
        let (e0, h0) = (energy(&b), momentum(&b));
        for _ in 0..100_000 {
            b.step(0.002);
        }
        assert!((energy(&b) - e0).abs() < 1e-12 * e0.abs().max(1.0));
        assert!((momentum(&b) - h0).norm() < 1e-10);
    }
}
