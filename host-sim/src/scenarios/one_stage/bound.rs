//! The loop-limited bound `σ_β = √(2Δf/J_β)` for the scenario's geometry, computed by host-sim
//! itself (f64, finite differences of the truth phases; no core code): `J_β = 2(C/N0)
//! Σ_i g_iᵀ Π g_i`, `g_i = ∂ψ_i/∂β`, `Π = I − 11ᵀ/3` (spec (d)).

use nalgebra::{Matrix3, Vector3};

use super::truth::{paper003_u, phases, rotation_about_y, Satellite};

/// `g_i = ∂ψ_i/∂β` at `beta` by central differences, rad/rad.
fn g(beta: f64, sat: &Satellite) -> Vector3<f64> {
    let h = 1e-6;
    let up = phases(&rotation_about_y(beta + h), &sat.los());
    let dn = phases(&rotation_about_y(beta - h), &sat.los());
    Vector3::from_fn(|p, _| (up[p] - dn[p]) / (2.0 * h))
}

fn projector() -> Matrix3<f64> {
    Matrix3::identity() - Matrix3::repeat(1.0 / 3.0)
}

/// Fisher information rate of β, 1/(rad² s): `2 (C/N0) Σ gᵀ Π g`.
pub fn information_rate(beta: f64, sky: &[Satellite], cn0_dbhz: f64) -> f64 {
    let cn0 = 10f64.powf(cn0_dbhz / 10.0);
    let p = projector();
    2.0 * cn0
        * sky
            .iter()
            .map(|s| g(beta, s).dot(&(p * g(beta, s))))
            .sum::<f64>()
}

/// Information rate of β when the line biases `b_B`, `b_C` are unknown in every epoch (the
/// Schur complement), 1/(rad² s): what estimating the biases costs before the filter has
/// learned them.
pub fn information_rate_biases_unknown(beta: f64, sky: &[Satellite], cn0_dbhz: f64) -> f64 {
    let cn0 = 10f64.powf(cn0_dbhz / 10.0);
    let p = projector();
    // parameters (β, b_B, b_C); G_i = [g_i, e_B, e_C]
    let mut j = Matrix3::<f64>::zeros();
    for s in sky {
        let gi = Matrix3::from_columns(&[g(beta, s), Vector3::y(), Vector3::z()]);
        j += gi.transpose() * p * gi * (2.0 * cn0);
    }
    let jbb = j.fixed_view::<2, 2>(1, 1).into_owned();
    let jba = j.fixed_view::<2, 1>(1, 0).into_owned();
    match jbb.try_inverse() {
        Some(inv) => j[(0, 0)] - (jba.transpose() * inv * jba)[(0, 0)],
        None => 0.0,
    }
}

/// Information rate of β when all three angles α, β, γ are estimated: `1/(J⁻¹)_ββ` with `J`
/// the 3×3 information rate of (α, β, γ) at `α = γ = 0`, 1/(rad² s).
pub fn information_rate_three_angles(beta: f64, sky: &[Satellite], cn0_dbhz: f64) -> f64 {
    let cn0 = 10f64.powf(cn0_dbhz / 10.0);
    let p = projector();
    let h = 1e-6;
    let mut j = Matrix3::<f64>::zeros();
    for s in sky {
        let los = s.los();
        let d = |da: f64, db: f64, dg: f64| phases(&paper003_u(da, beta + db, dg), &los);
        let col = |up: [f64; 3], dn: [f64; 3]| Vector3::from_fn(|q, _| (up[q] - dn[q]) / (2.0 * h));
        let gi = Matrix3::from_columns(&[
            col(d(h, 0.0, 0.0), d(-h, 0.0, 0.0)),
            col(d(0.0, h, 0.0), d(0.0, -h, 0.0)),
            col(d(0.0, 0.0, h), d(0.0, 0.0, -h)),
        ]);
        j += gi.transpose() * p * gi * (2.0 * cn0);
    }
    j.try_inverse().map_or(0.0, |inv| 1.0 / inv[(1, 1)])
}

/// `√(2Δf/J)` in arc-minutes.
pub fn loop_bound_arcmin(bandwidth_hz: f64, information_rate: f64) -> f64 {
    (2.0 * bandwidth_hz / information_rate).sqrt().to_degrees() * 60.0
}
