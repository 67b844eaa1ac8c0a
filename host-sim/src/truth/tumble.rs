//! A torque-free rigid body (a tumbling microsatellite), f64: Euler's equations and the
//! attitude kinematics integrated together by RK4, with the exact angle increments a rate gyro
//! would integrate.

use gnss_attitude::geometry::Quaternion;
use nalgebra::Vector3;

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
