//! Attitude kinematics of a rigid body, f64.
//!
//! The attitude is `q_rb` (body to reference, Hamilton), the rate `ω` is the body's angular
//! velocity relative to the reference frame in body axes: `q̇_rb = ½ q_rb ⊗ (0, ω)`.

use gnss_attitude::geometry::Quaternion;
use nalgebra::Vector3;

/// Attitude after `dt` seconds of constant body rate `omega_b` (rad/s): exact,
/// `q ⊗ exp(ω dt)`.
pub fn step_constant_rate(
    q_rb: &Quaternion<f64>,
    omega_b: &Vector3<f64>,
    dt: f64,
) -> Quaternion<f64> {
    renormalize(*q_rb * Quaternion::from_rotation_vector(&(omega_b * dt)))
}

/// Attitude after `dt` seconds of a time-varying body rate, by classical RK4 on
/// `q̇ = ½ q ⊗ (0, ω(t))`, renormalized. Local error O(dt⁵).
pub fn step_rk4(
    q_rb: &Quaternion<f64>,
    t: f64,
    dt: f64,
    omega_b: impl Fn(f64) -> Vector3<f64>,
) -> Quaternion<f64> {
    let deriv = |q: Quaternion<f64>, t: f64| {
        let d = q * Quaternion::from_parts(0.0, omega_b(t));
        Quaternion::new(0.5 * d.w, 0.5 * d.x, 0.5 * d.y, 0.5 * d.z)
    };
    let add = |q: Quaternion<f64>, d: Quaternion<f64>, h: f64| {
        Quaternion::new(q.w + h * d.w, q.x + h * d.x, q.y + h * d.y, q.z + h * d.z)
    };
    let k1 = deriv(*q_rb, t);
    let k2 = deriv(add(*q_rb, k1, dt / 2.0), t + dt / 2.0);
    let k3 = deriv(add(*q_rb, k2, dt / 2.0), t + dt / 2.0);
    let k4 = deriv(add(*q_rb, k3, dt), t + dt);
    let q = Quaternion::new(
        q_rb.w + dt / 6.0 * (k1.w + 2.0 * k2.w + 2.0 * k3.w + k4.w),
        q_rb.x + dt / 6.0 * (k1.x + 2.0 * k2.x + 2.0 * k3.x + k4.x),
        q_rb.y + dt / 6.0 * (k1.y + 2.0 * k2.y + 2.0 * k3.y + k4.y),
        q_rb.z + dt / 6.0 * (k1.z + 2.0 * k2.z + 2.0 * k3.z + k4.z),
    );
    renormalize(q)
}

fn renormalize(q: Quaternion<f64>) -> Quaternion<f64> {
    // A unit quaternion times a unit quaternion is unit to rounding; norm 0 cannot occur.
    q.normalize().unwrap_or(q)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rk4_matches_the_exact_step_for_constant_rate() {
        let q0 = Quaternion::new(0.64, 0.48, 0.36, -0.48);
        let w = Vector3::new(0.1047, 0.0174, 0.026);
        let (mut a, mut b) = (q0, q0);
        for k in 0..1000 {
            a = step_constant_rate(&a, &w, 0.01);
            b = step_rk4(&b, k as f64 * 0.01, 0.01, |_| w);
        }
        assert!(a.angle_to(&b) < 1e-12);
        // and the total rotation is |ω| t about ω
        let expected = q0 * Quaternion::from_rotation_vector(&(w * 10.0));
        assert!(a.angle_to(&expected) < 1e-12);
    }
}
