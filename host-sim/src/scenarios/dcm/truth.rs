//! Truth attitude and measurements of the `dcm` scenario, f64, own code paths.
//!
//! * Paper 000's "Example": `Ȧ = −[ω]× A`, `A(0) = I`, so `Aᵀ(t) = exp([ω]× t)` exactly, and
//!   `M(t) = G(Ωt) Aᵀ(t)` with `G` as printed (a rotation about the 2nd axis; erratum 7 says
//!   Earth turns about the 3rd, kept as printed for reproduction).
//! * LEO: a nadir-pointing satellite in a circular orbit seen from ECEF:
//!   `M(t) = R_z(Ω_E t)ᵀ C_io(t) C_ob`, with the local-level frame `o` (z to nadir, y against
//!   the orbit normal) turning at the mean motion and a small fixed mounting offset `C_ob`.
//!
//! Measurements at `t_k = k Δt`: `Z_ij = M(t_k) b_ij + N(0, σ_p² I)` for the three pairs
//! (independent noise per pair, the spec's per-baseline reading), and
//! `V_ij = (M(t_k) − M(t_{k−1})) b_ij / Δt + N(0, σ_v² I)`: the central difference of the
//! noise-free baseline for the middle of the step.

use gnss_attitude::attitude::array::{AntennaArray, BaselinePair};
use gnss_attitude::attitude::baseline_epoch::BaselineEpoch;
use nalgebra::{Matrix3, Rotation3, Vector3};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Earth rotation rate, rad/s (the paper's Ω).
pub const EARTH_RATE: f64 = 7.29e-5;

/// How the body moves relative to ECEF.
#[derive(Clone, Copy, Debug)]
pub enum Motion {
    /// The paper's constant body rate `ω` (rad/s) times the printed `G(Ωt)`.
    Paper {
        /// Body rate, body axes, rad/s.
        omega: [f64; 3],
    },
    /// Nadir pointing in a circular orbit.
    Leo {
        /// Mean motion, rad/s.
        mean_motion: f64,
        /// Inclination, rad.
        inclination: f64,
        /// Fixed mounting offset of the body from the local-level frame, rotation vector, rad.
        offset: [f64; 3],
    },
}

/// `exp([θ]×)` by Rodrigues' formula (nalgebra's, not the core's).
fn exp_so3(theta: &Vector3<f64>) -> Matrix3<f64> {
    Rotation3::new(*theta).into_inner()
}

impl Motion {
    /// The true attitude `M(t)`, body to ECEF.
    pub fn attitude(&self, t: f64) -> Matrix3<f64> {
        match *self {
            Self::Paper { omega } => {
                let (s, c) = (EARTH_RATE * t).sin_cos();
                // G(Ωt) exactly as printed in the paper
                let g = Matrix3::new(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c);
                g * exp_so3(&(Vector3::from(omega) * t))
            }
            Self::Leo {
                mean_motion,
                inclination,
                offset,
            } => {
                let (s, c) = (mean_motion * t).sin_cos();
                let p = Vector3::new(1.0, 0.0, 0.0);
                let q = Vector3::new(0.0, inclination.cos(), inclination.sin());
                let u = p * c + q * s; // radial unit vector, inertial
                let h = p.cross(&q); // orbit normal
                let z_o = -u;
                let y_o = -h;
                let x_o = y_o.cross(&z_o);
                let c_io = Matrix3::from_columns(&[x_o, y_o, z_o]);
                let c_ei = exp_so3(&(Vector3::z() * (-EARTH_RATE * t)));
                c_ei * c_io * exp_so3(&Vector3::from(offset))
            }
        }
    }

    /// Body rate relative to ECEF at `t`, body axes, rad/s (`vee(Mᵀ Ṁ)` by central difference).
    pub fn body_rate(&self, t: f64) -> Vector3<f64> {
        let h = 1e-3;
        let d = (self.attitude(t + h) - self.attitude(t - h)) / (2.0 * h);
        let w = self.attitude(t).transpose() * d;
        Vector3::new(
            w[(2, 1)] - w[(1, 2)],
            w[(0, 2)] - w[(2, 0)],
            w[(1, 0)] - w[(0, 1)],
        ) * 0.5
    }
}

fn gaussian3(rng: &mut ChaCha8Rng, sigma: f64) -> Vector3<f64> {
    Vector3::from_fn(|_, _| {
        sigma * <StandardNormal as Distribution<f64>>::sample(&StandardNormal, rng)
    })
}

/// The measurement epoch for the step `[t_{k−1}, t_k]` given the true attitudes at both ends.
pub fn epoch(
    array: &AntennaArray<f64>,
    m_prev: &Matrix3<f64>,
    m_now: &Matrix3<f64>,
    dt: f64,
    sigma_baseline: f64,
    sigma_velocity: f64,
    rng: &mut ChaCha8Rng,
) -> BaselineEpoch<f64> {
    let mut e = BaselineEpoch::default();
    for pair in BaselinePair::ALL {
        let b = array.baseline(pair);
        e.baselines[pair.index()] = Some(m_now * b + gaussian3(rng, sigma_baseline));
        e.velocity_differences[pair.index()] =
            Some((m_now - m_prev) * b / dt + gaussian3(rng, sigma_velocity));
    }
    e
}

/// A random rotation vector with independent N(0, σ²) components, rad.
pub fn small_rotation(rng: &mut ChaCha8Rng, sigma: f64) -> Matrix3<f64> {
    exp_so3(&gaussian3(rng, sigma))
}

/// Converts an epoch to f32 (the flight filters' input).
pub fn epoch_f32(e: &BaselineEpoch<f64>) -> BaselineEpoch<f32> {
    BaselineEpoch {
        baselines: e.baselines.map(|b| b.map(|v| v.cast::<f32>())),
        velocity_differences: e.velocity_differences.map(|v| v.map(|x| x.cast::<f32>())),
    }
}

/// The epoch without pair 13 (for the rigid-body filter on the paper's two baselines).
pub fn without_13<T: Copy>(e: &BaselineEpoch<T>) -> BaselineEpoch<T> {
    let mut out = *e;
    out.baselines[BaselinePair::P13.index()] = None;
    out.velocity_differences[BaselinePair::P13.index()] = None;
    out
}

/// The epoch with zero velocity differences (a filter that ignores the Doppler).
pub fn without_doppler(e: &BaselineEpoch<f32>) -> BaselineEpoch<f32> {
    let mut out = *e;
    for v in out.velocity_differences.iter_mut() {
        *v = v.map(|_| Vector3::zeros());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_truth_turns_at_the_body_rate() {
        let m = Motion::Paper {
            omega: [0.1047, 0.0174, 0.026],
        };
        assert!((m.attitude(0.0) - Matrix3::identity()).norm() < 1e-15);
        let w = m.body_rate(100.0);
        // body rate = ω plus the printed Earth rotation, at most Ω
        assert!((w - Vector3::new(0.1047, 0.0174, 0.026)).norm() <= EARTH_RATE * 1.0001);
        let r = m.attitude(437.0);
        assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-13);
    }

    #[test]
    fn leo_truth_points_at_nadir_and_turns_at_orbital_rate() {
        let m = Motion::Leo {
            mean_motion: 1.1e-3,
            inclination: 51.6f64.to_radians(),
            offset: [0.0; 3],
        };
        let w = m.body_rate(300.0);
        assert!((w.norm() - 1.1e-3).abs() < 1e-4, "{w:?}");
        // mostly about the body y axis (the orbit normal)
        assert!(w.y.abs() > 0.9 * w.norm());
    }
}
