//! Steady-state bounds of the `dcm` scenario's filters (spec, paper 000 §(d)), f64, derived
//! here independently of the core's code.
//!
//! * **Six-state, linear-equivalent.** In `z = H(Y)` coordinates the six-state filter is six
//!   independent scalar filters (random walk driven by the velocity noise, white measurement
//!   noise), each with steady-state σ_z = (σ_p σ_v Δt)^{1/2}. The attitude error is a linear
//!   function of the six z errors: with `E = Mᵀ δM = [θ]× + S` (body axes), the state's six
//!   degrees of freedom are `θ` and the three of the symmetric `S` that the cross-product
//!   relation of the eliminated column allows (`S` in the relabelled axes
//!   `[[a+b,0,0],[0,a,c],[0,c,b]]`); `δz_i = E b_i`. Solving for `θ` gives `θ = L δz` and the
//!   bound `σ_z² L Lᵀ`, independent of the attitude.
//! * **Multi-structure.** The three structures' z errors share baselines (a baseline's scalar
//!   filters are identical in the two structures that use it); the combination rule of the core
//!   (information weights) applied to `L₁, L₂, L₃` gives the bound of the fused estimate.
//! * **Rigid body with the least-squares rate.** `σ_p σ_v Δt J⁻¹`, `J = Σ [b]×ᵀ[b]×`: the static
//!   bound of the spec, which is also the exact steady state with the body rotating, because
//!   the least-squares rate's dependence on the attitude error cancels the rotation's mixing
//!   (see `gnss_attitude::attitude::rigid_body`). Principal values: `(σ_p σ_v Δt / λ_i)^{1/2}`.
//! * **Rigid body with an attitude-independent rate** (the spec's "Riccati in body axes"):
//!   `Ṗ = A P + P Aᵀ + σ_v² Δt J⁻¹ − P J P / (σ_p² Δt)`, `A = −[ω]×`, integrated to steady
//!   state. What a filter with a rate source independent of its attitude (a gyro) could reach
//!   with the same baselines; reported for comparison, it is not the bound of a Doppler-driven
//!   filter.

use gnss_attitude::attitude::array::{AntennaArray, BaselinePair};
use nalgebra::{Matrix3, SMatrix, Vector3};

/// Skew matrix `[v]×` (host-side copy).
fn cross_matrix(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Noise levels and step.
#[derive(Clone, Copy, Debug)]
pub struct Noise {
    /// Baseline component σ per sample, m.
    pub sigma_baseline: f64,
    /// Velocity-difference component σ per sample, m/s.
    pub sigma_velocity: f64,
    /// Step, s.
    pub dt: f64,
}

impl Noise {
    /// `σ_p σ_v Δt`, m²: the steady-state z variance of one scalar filter.
    pub fn sigma_z2(&self) -> f64 {
        self.sigma_baseline * self.sigma_velocity * self.dt
    }
}

/// `θ = L δz` for the six-state filter on baselines `b1`, `b2` with column `k` eliminated.
pub fn six_state_map(b1: &Vector3<f64>, b2: &Vector3<f64>, k: usize) -> Option<SMatrix<f64, 3, 6>> {
    // Body axis (k + j) mod 3 is model axis j.
    let perm = Matrix3::from_fn(|r, c| if r == (c + k) % 3 { 1.0 } else { 0.0 });
    let e_of = |p: &[f64; 6]| {
        let s_model = Matrix3::new(p[3] + p[4], 0.0, 0.0, 0.0, p[3], p[5], 0.0, p[5], p[4]);
        cross_matrix(&Vector3::new(p[0], p[1], p[2])) + perm * s_model * perm.transpose()
    };
    let mut a = SMatrix::<f64, 6, 6>::zeros();
    for j in 0..6 {
        let mut p = [0.0; 6];
        p[j] = 1.0;
        let e = e_of(&p);
        a.fixed_view_mut::<3, 1>(0, j).copy_from(&(e * b1));
        a.fixed_view_mut::<3, 1>(3, j).copy_from(&(e * b2));
    }
    let inv = a.try_inverse()?;
    Some(inv.fixed_rows::<3>(0).into_owned())
}

/// Attitude-error covariance bound of the six-state filter on a pair of baselines, rad².
pub fn six_state(
    array: &AntennaArray<f64>,
    pairs: [BaselinePair; 2],
    k: usize,
    noise: Noise,
) -> Option<Matrix3<f64>> {
    let l = six_state_map(&array.baseline(pairs[0]), &array.baseline(pairs[1]), k)?;
    Some(l * l.transpose() * noise.sigma_z2())
}

/// Bound of the multi-structure combination (all three structures inliers), rad².
pub fn multi_structure(
    array: &AntennaArray<f64>,
    structures: &[[BaselinePair; 2]; 3],
    k: usize,
    noise: Noise,
) -> Option<Matrix3<f64>> {
    let maps: Vec<SMatrix<f64, 3, 6>> = structures
        .iter()
        .map(|p| six_state_map(&array.baseline(p[0]), &array.baseline(p[1]), k))
        .collect::<Option<_>>()?;
    let infos: Vec<Matrix3<f64>> = maps
        .iter()
        .map(|l| (l * l.transpose()).try_inverse())
        .collect::<Option<_>>()?;
    let total = infos.iter().sum::<Matrix3<f64>>().try_inverse()?;
    // θ_f = Σ_k W_k L_k δz_k, W_k = (Σ I)⁻¹ I_k; collect the gain of each pair's z error
    let mut cov = Matrix3::zeros();
    for pair in BaselinePair::ALL {
        let mut g = Matrix3::zeros();
        for ((l, info), pairs) in maps.iter().zip(&infos).zip(structures) {
            for (slot, p) in pairs.iter().enumerate() {
                if *p == pair {
                    g += total * info * l.fixed_view::<3, 3>(0, 3 * slot);
                }
            }
        }
        cov += g * g.transpose();
    }
    Some(cov * noise.sigma_z2())
}

/// `J = Σ [b]×ᵀ[b]×` over the given pairs, m².
pub fn rate_information(array: &AntennaArray<f64>, pairs: &[BaselinePair]) -> Matrix3<f64> {
    pairs
        .iter()
        .map(|&p| {
            let b = cross_matrix(&array.baseline(p));
            b.transpose() * b
        })
        .sum()
}

/// Rigid-body bound with the least-squares rate: `σ_p σ_v Δt J⁻¹`, rad².
pub fn rigid_body(
    array: &AntennaArray<f64>,
    pairs: &[BaselinePair],
    noise: Noise,
) -> Option<Matrix3<f64>> {
    Some(rate_information(array, pairs).try_inverse()? * noise.sigma_z2())
}

/// Principal standard deviations `(σ_p σ_v Δt / λ_i)^{1/2}`, ascending eigenvalue order, rad.
pub fn rigid_body_principal(
    array: &AntennaArray<f64>,
    pairs: &[BaselinePair],
    noise: Noise,
) -> Vector3<f64> {
    let mut eig: Vec<f64> = rate_information(array, pairs)
        .symmetric_eigenvalues()
        .iter()
        .copied()
        .collect();
    eig.sort_by(f64::total_cmp);
    Vector3::from_fn(|i, _| (noise.sigma_z2() / eig[i]).sqrt())
}

/// The spec's "Riccati in body axes" with an attitude-independent rate `ω` (body axes), rad².
pub fn rigid_body_independent_rate(
    array: &AntennaArray<f64>,
    pairs: &[BaselinePair],
    omega: &Vector3<f64>,
    noise: Noise,
) -> Option<Matrix3<f64>> {
    let j = rate_information(array, pairs);
    let q = j.try_inverse()? * (noise.sigma_velocity.powi(2) * noise.dt);
    let info = j / (noise.sigma_baseline.powi(2) * noise.dt);
    let a = -cross_matrix(omega);
    let f = |p: &Matrix3<f64>| a * p + p * a.transpose() + q - p * info * p;
    let mut p = q * 1e3;
    let h = 0.01;
    // RK4 to steady state; at most 2·10⁶ steps (the slowest time constant is σ_p/σ_v ≈ 6 s)
    for _ in 0..2_000_000 {
        let k1 = f(&p);
        let k2 = f(&(p + k1 * (h / 2.0)));
        let k3 = f(&(p + k2 * (h / 2.0)));
        let k4 = f(&(p + k3 * h));
        let next = p + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
        let next = (next + next.transpose()) * 0.5;
        let change = (next - p).norm() / next.norm();
        p = next;
        if change < 1e-13 {
            return Some(p);
        }
    }
    None
}

/// Per-axis standard deviations of a covariance, rad.
pub fn axis_sigma(p: &Matrix3<f64>) -> [f64; 3] {
    [p[(0, 0)].sqrt(), p[(1, 1)].sqrt(), p[(2, 2)].sqrt()]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper() -> (AntennaArray<f64>, Noise) {
        let a = AntennaArray::from_baselines(
            &Vector3::new(1.5, 1.8, 1.9),
            &Vector3::new(1.7, 1.7, 2.0),
        )
        .unwrap();
        (
            a,
            Noise {
                sigma_baseline: 0.6,
                sigma_velocity: 0.1,
                dt: 0.01,
            },
        )
    }

    #[test]
    fn rigid_body_bounds_reproduce_the_spec() {
        let (a, n) = paper();
        let two = [BaselinePair::P12, BaselinePair::P23];
        let s = rigid_body_principal(&a, &two, n);
        // spec: 0.159 rad about the near-baseline axis, 5.6e-3 rad about the two others
        assert!(
            (s[0] - 0.159).abs() < 1e-3
                && (s[1] - 5.6e-3).abs() < 1e-4
                && (s[2] - 5.6e-3).abs() < 1e-4
        );
        // spec's "with ω": per body axis (0.052, 0.062, 0.057) rad
        let p =
            rigid_body_independent_rate(&a, &two, &Vector3::new(0.1047, 0.0174, 0.026), n).unwrap();
        let ax = axis_sigma(&p);
        for (got, want) in ax.iter().zip([0.052, 0.062, 0.057]) {
            assert!((got - want).abs() < 1e-3, "{ax:?}");
        }
    }

    #[test]
    fn six_state_map_inverts_the_observation_and_the_choice_matters() {
        let (a, n) = paper();
        let p = six_state(&a, [BaselinePair::P12, BaselinePair::P23], 0, n).unwrap();
        // σ_z = 0.0245 m spread by the near-collinear geometry: ≈ 0.1 rad per axis
        let ax = axis_sigma(&p);
        assert!(ax.iter().all(|s| (0.08..0.2).contains(s)), "{ax:?}");
        let p2 = six_state(&a, [BaselinePair::P12, BaselinePair::P23], 2, n).unwrap();
        assert!((p - p2).norm() > 1e-6);
    }
}
