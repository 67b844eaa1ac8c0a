//! The bound the fine attitude is held to, computed by host-sim for the run's own geometry and
//! C/N0 (f64, no core code).
//!
//! # Derivation
//!
//! Write the attitude error as the body-frame rotation vector `e`, `C_true = Ĉ exp([e]×)`.
//! Antenna `P` (body position `r_P`) sees satellite `i` (body line of sight `s_i = Ĉᵀ μ_i`) with
//! the carrier phase `ψ_{P,i} = k μ_iᵀ C_true r_P = k s_iᵀ (r_P + e × r_P) + O(e²)`,
//! `k = 2π/λ`, so `∂ψ_{P,i}/∂e = k (r_P × s_i)ᵀ`: the rows of the 3×3 matrix `G_i`.
//!
//! Per 1 ms epoch each antenna's prompt phase is measured with variance `1/(2 q_T)`
//! (`q_T = (C/N0)_i T`, high-SNR limit of paper 003's Bessel likelihood, which the I₁/I₀
//! weighting approaches above ~35 dB-Hz), and the common carrier phase and the data bit are
//! unknown: only the projection `Π = I − 11ᵀ/3` of the three phases (their differences)
//! carries attitude. The Fisher information rate of `e` is therefore
//!
//! ```text
//! J = Σ_i 2 (C/N0)_i G_iᵀ Π G_i        (1/(rad² s))
//! ```
//!
//! over the satellites all three antennas see. A second-order loop of noise bandwidth `Δf` on
//! a parameter of information rate `j` has the steady-state variance `2Δf / j` (paper 003's
//! loop-limited bound `√(2Δf/J_β)`, spec (d)); the fine filter schedules its process noise so
//! that each angle's loop has bandwidth `Δf` with its marginal information `1/(J⁻¹)_aa`
//! (`ProcessNoise::Bandwidth`). The bound per body axis is hence
//!
//! ```text
//! σ_a = √(2 Δf (J⁻¹)_aa)
//! ```
//!
//! evaluated every record with the satellites and C/N0 of that moment (the fine filter's
//! angles `α, β, γ` of `U = C_Fb ≈ I` are the body rotation vector `(−e_x, e_y, e_z)` to first
//! order, so its axes are the body axes).

use nalgebra::{Matrix3, Vector3};

use crate::truth::sky::L1_WAVELENGTH_M;

/// The bound per body axis, rad: `√(2Δf (J⁻¹)_aa)` for antennas at `positions` (body, m),
/// satellites `(s_body, C/N0 dB-Hz)` and loop bandwidth `bandwidth_hz`. `None` when `J` is
/// singular (fewer than two satellites, or degenerate geometry).
pub fn bound_rad(
    positions: &[Vector3<f64>; 3],
    satellites: &[(Vector3<f64>, f64)],
    bandwidth_hz: f64,
) -> Option<Vector3<f64>> {
    let j = information_rate(positions, satellites);
    let chol = j.cholesky()?;
    let l = chol.l_dirty().diagonal();
    if l.min() <= 1e-6 * l.max() || !l.min().is_finite() {
        return None;
    }
    let inv = chol.inverse();
    let d = inv.diagonal();
    if d.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        return None;
    }
    Some(d.map(|v| (2.0 * bandwidth_hz * v).sqrt()))
}

/// `J = Σ 2 (C/N0)_i G_iᵀ Π G_i`, 1/(rad² s).
pub fn information_rate(
    positions: &[Vector3<f64>; 3],
    satellites: &[(Vector3<f64>, f64)],
) -> Matrix3<f64> {
    let k = std::f64::consts::TAU / L1_WAVELENGTH_M;
    let pi = Matrix3::identity() - Matrix3::repeat(1.0 / 3.0);
    let mut j = Matrix3::zeros();
    for (s, cn0_dbhz) in satellites {
        let cn0 = 10f64.powf(cn0_dbhz / 10.0);
        let g = Matrix3::from_rows(&[
            (positions[0].cross(s) * k).transpose(),
            (positions[1].cross(s) * k).transpose(),
            (positions[2].cross(s) * k).transpose(),
        ]);
        j += g.transpose() * pi * g * (2.0 * cn0);
    }
    j
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gradient_is_the_derivative_of_the_phase() {
        let r = [
            Vector3::new(0.29, 0.0, -0.05),
            Vector3::new(-0.14, 0.25, -0.05),
            Vector3::new(-0.14, -0.25, -0.05),
        ];
        let s = Vector3::new(0.3, -0.2, -0.9).normalize();
        let k = std::f64::consts::TAU / L1_WAVELENGTH_M;
        let phase = |e: &Vector3<f64>, p: usize| {
            let c = nalgebra::Rotation3::from_scaled_axis(*e).into_inner();
            k * s.dot(&(c * r[p]))
        };
        let h = 1e-7;
        for (p, rp) in r.iter().enumerate() {
            for a in 0..3 {
                let mut e = Vector3::zeros();
                e[a] = h;
                let fd = (phase(&e, p) - phase(&-e, p)) / (2.0 * h);
                let analytic = (rp.cross(&s) * k)[a];
                assert!((fd - analytic).abs() < 1e-6, "{fd} {analytic}");
            }
        }
        // one satellite leaves the rotation about its own line of sight unobservable
        assert!(bound_rad(&r, &[(s, 45.0)], 1.0).is_none());
        let two = [(s, 45.0), (Vector3::new(-0.5, 0.4, -0.7).normalize(), 45.0)];
        assert!(bound_rad(&r, &two, 1.0).is_some());
    }
}
