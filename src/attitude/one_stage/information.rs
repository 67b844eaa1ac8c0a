//! One epoch's information about the parameters `θ = [α, β, γ, b_B, b_C]` (attitude angles of
//! eq. (2) and the line biases of antennas B and C relative to A), summed over the satellites:
//! the gradient of `F = Σ_i ln I₀(a X_i)` (eq. (32), extended to the biases), its observed
//! curvature `−∂²F/∂θ∂θᵀ` (eq. (12)) and its expected value (the Fisher information `J_T`).

use nalgebra::{Matrix2x5, Matrix3, SMatrix, SVector, Vector3};

use crate::{real, Real};

use super::discriminator::{difference_basis, floored_plane_curvature, satellite_terms};
use super::input::CheckedObservation;
use super::phase::PhaseModel;

/// Number of parameters the discriminators act on: α, β, γ, `b_B`, `b_C`.
pub const PARAMETERS: usize = 5;

/// The epoch's sums over satellites, in the parameter order α, β, γ, `b_B`, `b_C` (radians).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EpochInformation<T = f32> {
    /// `∂F/∂θ`: for the angles the discriminator `u_α = (∂Ψ/∂α)ᵀ u_ψ` of eq. (32) (the `2π/λ`
    /// included), for the biases `Σ_i ∂F_i/∂ψ_{B,i}` and `Σ_i ∂F_i/∂ψ_{C,i}`. 1/rad.
    pub gradient: SVector<T, PARAMETERS>,
    /// The observed information `−∂²F/∂θ∂θᵀ` with each satellite's curvature floored in the
    /// phase-difference plane (the definiteness guard of eq. (12)); positive semi-definite.
    /// 1/rad². Zero in the constant-gain mode, which does not use it.
    pub observed: SMatrix<T, PARAMETERS, PARAMETERS>,
    /// The expected information (discriminator slope) `J_T = Σ_i 2q_{T,i} G_iᵀ Π G_i`,
    /// `Π = I − 11ᵀ/3`, `G_i = ∂ψ_i/∂θ` (spec (a)). 1/rad².
    pub expected: SMatrix<T, PARAMETERS, PARAMETERS>,
    /// `Σ_i (X_i² − 6)`: the coherent power above its noise-only mean, noise units.
    pub coherent_power: T,
    /// `Σ_i 3(Σ_P |z_P|² − 6)`: what the coherent power would be with every satellite's
    /// antennas perfectly phase-aligned, noise units.
    pub aligned_power: T,
    /// Satellites summed.
    pub satellites: u8,
    /// Satellites whose curvature needed the floor.
    pub floored: u8,
}

impl<T: Real> EpochInformation<T> {
    /// The angle block `J_αα` of [`Self::expected`], 1/rad².
    pub fn expected_angles(&self) -> Matrix3<T> {
        self.expected.fixed_view::<3, 3>(0, 0).into_owned()
    }

    /// The angle part `u_α` of [`Self::gradient`] (eq. (32)), 1/rad.
    pub fn angle_gradient(&self) -> Vector3<T> {
        self.gradient.fixed_rows::<3>(0).into_owned()
    }
}

/// Sums the satellites' contributions at the model's attitude and the line biases
/// `line_bias = [b_B, b_C]` (radians). `curvature_floor` is the fraction `κ` of each
/// satellite's expected information `2q_T` below which an eigenvalue of its observed curvature
/// is raised. The observed curvature is only formed when `observed` is true (the constant-gain
/// loop does not use it); otherwise [`EpochInformation::observed`] is zero.
pub(crate) fn epoch_information<T: Real>(
    model: &PhaseModel<T>,
    line_bias: [T; 2],
    observations: &[CheckedObservation<T>],
    curvature_floor: T,
    observed: bool,
) -> EpochInformation<T> {
    let e = difference_basis::<T>();
    let two = real::<T>(2.0);
    let six = real::<T>(6.0);
    let [b_b, b_c] = line_bias;
    let mut info = EpochInformation {
        gradient: SVector::zeros(),
        observed: SMatrix::zeros(),
        expected: SMatrix::zeros(),
        coherent_power: T::zero(),
        aligned_power: T::zero(),
        satellites: 0,
        floored: 0,
    };
    for obs in observations {
        // eq. (24) plus the line biases (b_A ≡ 0: a common bias is part of the common phase)
        let psi = model.phases(&obs.los) + Vector3::new(T::zero(), b_b, b_c);
        let terms = satellite_terms(&obs.z, &psi, obs.q_t);
        // G_i = ∂ψ_i/∂θ (3×5): eqs. (26)–(28) for the angles, unit columns for b_B, b_C
        let jac: Matrix3<T> = model.jacobian(&obs.los);
        let o = T::zero();
        let l = T::one();
        #[rustfmt::skip]
        let g = SMatrix::<T, 3, PARAMETERS>::new(
            jac.m11, jac.m12, jac.m13, o, o,
            jac.m21, jac.m22, jac.m23, l, o,
            jac.m31, jac.m32, jac.m33, o, l,
        );
        // eq. (32): u_θ = G_iᵀ ∂F_i/∂ψ
        info.gradient += g.transpose() * terms.gradient;
        // the curvature lives in the difference plane: M_i = Eᵀ G_i (2×5), Π = E Eᵀ
        let m: Matrix2x5<T> = e.transpose() * g;
        if observed {
            let (h, floored) =
                floored_plane_curvature(&terms.curvature, curvature_floor * two * obs.q_t);
            info.observed += m.transpose() * h * m;
            if floored {
                info.floored = info.floored.saturating_add(1);
            }
        }
        info.expected += m.transpose() * m * (two * obs.q_t);
        info.coherent_power += terms.x_squared - six;
        info.aligned_power += (terms.antenna_power - six) * real(3.0);
        info.satellites = info.satellites.saturating_add(1);
    }
    info
}
