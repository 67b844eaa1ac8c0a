//! Attitude truth of a spacecraft, f64: nadir pointing with a slow tumble, and a detumbling
//! rigid body.
//!
//! Both give `q_ib(t)` (body to ECI, Hamilton) and the body rate `ω_b(t)` (rad/s, body axes,
//! relative to inertial space), which is what a gyro measures.

use gnss_attitude::geometry::Quaternion;
use nalgebra::{Matrix3, Vector3};

use super::orbit::{lvlh_to_frame, Trajectory};

/// A truth attitude history.
pub trait AttitudeTruth: Sync {
    /// Body to ECI at `t` seconds.
    fn q_ib(&self, t: f64) -> Quaternion<f64>;

    /// Body rate relative to inertial space, body axes, rad/s; by default the central
    /// difference of [`Self::q_ib`] over ±0.5 ms (error O(h² |ω|³), far below gyro noise).
    fn omega_b(&self, t: f64) -> Vector3<f64> {
        let h = 5e-4;
        let dq = self.q_ib(t - h).conjugate() * self.q_ib(t + h);
        dq.to_rotation_vector() / (2.0 * h)
    }
}

/// Nadir pointing (body frame aligned with LVLH: z to nadir) with a slow tumble relative to it:
/// a constant spin about body z plus a sinusoidal wobble of roll and pitch.
#[derive(Clone, Debug)]
pub struct NadirTumble {
    /// The orbit, which defines LVLH.
    pub orbit: Trajectory,
    /// Spin about the body z axis relative to LVLH, rad/s.
    pub spin_rate: f64,
    /// Amplitude of the roll and pitch wobble, rad.
    pub wobble: f64,
    /// Period of the wobble, s.
    pub wobble_period: f64,
}

impl NadirTumble {
    /// LVLH → body rotation at `t`: yaw = spin·t, roll and pitch wobbling out of phase.
    fn q_lvlh_b(&self, t: f64) -> Quaternion<f64> {
        let phase = 2.0 * std::f64::consts::PI * t / self.wobble_period;
        gnss_attitude::geometry::Euler321::new(
            self.spin_rate * t,
            self.wobble * phase.sin(),
            self.wobble * phase.cos(),
        )
        .to_quaternion()
    }
}

impl AttitudeTruth for NadirTumble {
    fn q_ib(&self, t: f64) -> Quaternion<f64> {
        let c_i_lvlh: Matrix3<f64> = lvlh_to_frame(&self.orbit.eci(t));
        let q_i_lvlh = Quaternion::from_dcm(&c_i_lvlh).unwrap_or_default();
        q_i_lvlh * self.q_lvlh_b(t)
    }
}

/// A rigid body after separation, detumbled by a rate-damping torque `τ = −k ω`:
/// `J ω̇ = −ω × Jω − k ω`, `q̇ = ½ q ⊗ ω`, integrated by RK4 at a fixed step and interpolated.
#[derive(Clone, Debug)]
pub struct DetumblingBody {
    step: f64,
    samples: Vec<(Quaternion<f64>, Vector3<f64>)>,
}

impl DetumblingBody {
    /// Simulates `duration` seconds from attitude `q0` and rate `omega0` (rad/s) for the
    /// inertia `inertia` (kg·m², body axes) and damping gain `k` (N·m·s), at step `step` (s).
    pub fn simulate(
        inertia: Matrix3<f64>,
        k: f64,
        q0: Quaternion<f64>,
        omega0: Vector3<f64>,
        duration: f64,
        step: f64,
    ) -> Self {
        let inv = inertia.try_inverse().unwrap_or_else(Matrix3::identity);
        // state (q, ω); derivative (½ q ⊗ (0, ω), J⁻¹(−ω × Jω − k ω)); classical RK4 on both
        let deriv = |q: &Quaternion<f64>, w: &Vector3<f64>| {
            let dq = *q * Quaternion::from_parts(0.0, *w);
            let dq = Quaternion::new(0.5 * dq.w, 0.5 * dq.x, 0.5 * dq.y, 0.5 * dq.z);
            (dq, inv * (-w.cross(&(inertia * w)) - w * k))
        };
        let add = |q: &Quaternion<f64>, d: &Quaternion<f64>, h: f64| {
            Quaternion::new(q.w + h * d.w, q.x + h * d.x, q.y + h * d.y, q.z + h * d.z)
        };
        let n = (duration / step).ceil() as usize + 2;
        let mut samples = Vec::with_capacity(n);
        let (mut q, mut w) = (q0, omega0);
        samples.push((q, w));
        for _ in 1..n {
            let (q1, w1) = deriv(&q, &w);
            let (q2, w2) = deriv(&add(&q, &q1, step / 2.0), &(w + w1 * (step / 2.0)));
            let (q3, w3) = deriv(&add(&q, &q2, step / 2.0), &(w + w2 * (step / 2.0)));
            let (q4, w4) = deriv(&add(&q, &q3, step), &(w + w3 * step));
            let dq = Quaternion::new(
                q1.w + 2.0 * q2.w + 2.0 * q3.w + q4.w,
                q1.x + 2.0 * q2.x + 2.0 * q3.x + q4.x,
                q1.y + 2.0 * q2.y + 2.0 * q3.y + q4.y,
                q1.z + 2.0 * q2.z + 2.0 * q3.z + q4.z,
            );
            q = add(&q, &dq, step / 6.0).normalize().unwrap_or(q);
            w += (w1 + w2 * 2.0 + w3 * 2.0 + w4) * (step / 6.0);
            samples.push((q, w));
        }
        Self { step, samples }
    }

    fn at(&self, t: f64) -> (usize, f64) {
        let x = (t / self.step).max(0.0);
        let i = (x.floor() as usize).min(self.samples.len().saturating_sub(2));
        (i, (x - i as f64).clamp(0.0, 1.0))
    }
}

impl AttitudeTruth for DetumblingBody {
    fn q_ib(&self, t: f64) -> Quaternion<f64> {
        let (i, f) = self.at(t);
        let (q0, _) = self.samples[i];
        let (q1, _) = self.samples[i + 1];
        q0 * Quaternion::from_rotation_vector(&((q0.conjugate() * q1).to_rotation_vector() * f))
    }

    fn omega_b(&self, t: f64) -> Vector3<f64> {
        let (i, f) = self.at(t);
        self.samples[i].1.lerp(&self.samples[i + 1].1, f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::truth::orbit::Orbit;

    #[test]
    fn nadir_tumble_points_z_to_nadir_up_to_the_wobble() {
        let orbit = Orbit::sun_synchronous(550e3, 0.0, 0.0);
        let truth = NadirTumble {
            orbit: orbit.into(),
            spin_rate: 0.01,
            wobble: 0.0,
            wobble_period: 100.0,
        };
        for t in [0.0, 100.0, 2000.0] {
            let z_body_in_eci = truth.q_ib(t).rotate(&Vector3::z());
            let nadir = -orbit.eci(t).r.normalize();
            assert!((z_body_in_eci - nadir).norm() < 1e-12);
        }
        // rate: spin about z plus the orbital rate about the negative orbit normal (body −y
        // rotated by the spin)
        let w = truth.omega_b(1000.0);
        // (the J2 drift of the node adds ~2e-7 rad/s about the orbit normal and nadir)
        assert!((w.z - 0.01).abs() < 1e-6, "{w}");
        assert!(
            ((w.x * w.x + w.y * w.y).sqrt() - orbit.mean_motion()).abs() < 2e-6,
            "{w}"
        );
    }

    #[test]
    fn detumbling_body_loses_rate_and_conserves_direction_of_momentum_without_damping() {
        let j = Matrix3::from_diagonal(&Vector3::new(0.05, 0.06, 0.04));
        let w0 = Vector3::new(0.1, -0.05, 0.08);
        let free = DetumblingBody::simulate(j, 0.0, Quaternion::identity(), w0, 100.0, 0.01);
        let h0 = free.q_ib(0.0).rotate(&(j * free.omega_b(0.0)));
        let h1 = free.q_ib(100.0).rotate(&(j * free.omega_b(100.0)));
        assert!(
            (h0 - h1).norm() < 1e-6 * h0.norm(),
            "inertial momentum drifts {}",
            (h0 - h1).norm()
        );
        let damped = DetumblingBody::simulate(j, 2e-3, Quaternion::identity(), w0, 300.0, 0.01);
        assert!(damped.omega_b(300.0).norm() < 0.01 * w0.norm());
    }
}
