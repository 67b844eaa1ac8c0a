//! The error models of paper 001, eq. (1.2), and the quadratures `Θ(t)` and `Ψ(t, t₀)`.
//!
//! * Gyro: `Δω_E = D(ω_E) c` with `c` of `CM = 3m` constant unknowns ([`GyroErrorModel`]).
//! * Reference: the reference frame `L` drifts from the inertial frame by the small rotation
//!   `v(t) = ½ Ψ(t, t₀) d` (eq. (2.2)) with `d` of `DN = 3n` constant unknowns
//!   ([`ReferenceDriftModel`]).
//! * Eq. (2.4): the attitude error of the gyro-integrated quaternion grows as
//!   `w(t) = w₀ − ½ Θ(t) c`, `Θ(t) = ∫_{t₀}^t Bᵀ D(ω*) dt`, accumulated by
//!   [`ErrorQuadratures`] with the trapezoid rule at the propagation step `H`.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::Real;

/// A gyro error model `Δω = D(ω) c` (paper eq. (1.2)): `D` is `3 × CM`, `c` has `CM = 3m`
/// constant elements.
pub trait GyroErrorModel<T: Real, const CM: usize> {
    /// `D(ω)` for the angular rate `ω` in gyro axes (rad/s): the rate error per unit of each
    /// element of `c`.
    fn rate_error_matrix(&self, omega: &Vector3<T>) -> SMatrix<T, 3, CM>;

    /// `D(θ/Δt) Δt`: the angle error (rad, gyro axes) over an interval `Δt > 0` (s) during
    /// which the gyro turned by the increment `θ` (rad, gyro axes), per unit of `c`. Models
    /// linear in `ω` override it to avoid the division.
    fn increment_error_matrix(&self, theta: &Vector3<T>, dt: T) -> SMatrix<T, 3, CM> {
        self.rate_error_matrix(&(theta / dt)) * dt
    }
}

/// The paper's §6 model, `m = 3`: `D = [D_I D_II E₃]` (`3 × 9`) with
/// `D_I = diag(ω₁, ω₂, ω₃)` (scale factors `c₁…c₃`, dimensionless),
/// `D_II = [[ω₂, 0, ω₃], [ω₁, ω₃, 0], [0, ω₂, ω₁]]` (symmetric misalignments `c₄…c₆`, rad)
/// and `E₃` (biases `c₇…c₉`, rad/s).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScaleMisalignmentBias;

impl ScaleMisalignmentBias {
    /// `[D_I(v) D_II(v) s E₃]` for a vector `v` and a bias weight `s`.
    fn matrix<T: Real>(v: &Vector3<T>, s: T) -> SMatrix<T, 3, 9> {
        let z = T::zero();
        #[rustfmt::skip]
        let m = SMatrix::<T, 3, 9>::from_row_slice(&[
            v.x, z, z,    v.y, z, v.z,    s, z, z,
            z, v.y, z,    v.x, v.z, z,    z, s, z,
            z, z, v.z,    z, v.y, v.x,    z, z, s,
        ]);
        m
    }
}

impl<T: Real> GyroErrorModel<T, 9> for ScaleMisalignmentBias {
    fn rate_error_matrix(&self, omega: &Vector3<T>) -> SMatrix<T, 3, 9> {
        Self::matrix(omega, T::one())
    }

    fn increment_error_matrix(&self, theta: &Vector3<T>, dt: T) -> SMatrix<T, 3, 9> {
        Self::matrix(theta, dt)
    }
}

/// The simplest model, `m = 1`: `D = E₃`, `c` are the three biases (rad/s).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BiasOnly;

impl<T: Real> GyroErrorModel<T, 3> for BiasOnly {
    fn rate_error_matrix(&self, _omega: &Vector3<T>) -> SMatrix<T, 3, 3> {
        Matrix3::identity()
    }

    fn increment_error_matrix(&self, _theta: &Vector3<T>, dt: T) -> SMatrix<T, 3, 3> {
        Matrix3::identity() * dt
    }
}

/// A model of the reference frame's deviation `v(t) = ½ Ψ(t, t₀) d` from the inertial frame
/// (paper eq. (2.2)), `d` of `DN = 3n` constants, with
/// `Ψ(t, t₀) = Ψ_anchor + ∫_{t₀}^t G dt`.
///
/// The paper has `Ψ_anchor = 0` (`v(t₀) = 0`, the reference frame coincides with the inertial
/// one at `t₀ = t*`). A non-zero `Ψ_anchor` describes a reference whose anchor sample at `t₀`
/// is itself in error: then the frame of the reference after `t₀` deviates by
/// `½ Ψ_anchor d` from the frame of the anchor, and the corrected attitude is referred back to
/// the reference frame (see [`crate::gyro::GyroCalibrator::corrected_attitude`]).
pub trait ReferenceDriftModel<T: Real, const DN: usize> {
    /// `G` at `elapsed = t − t₀` seconds (`3 × DN`): `v̇ = ½ G d`.
    fn g(&self, elapsed: T) -> SMatrix<T, 3, DN>;

    /// `Ψ_anchor` (`3 × DN`): the deviation just after the anchor, `v(t₀⁺) = ½ Ψ_anchor d`.
    fn psi_anchor(&self) -> SMatrix<T, 3, DN> {
        SMatrix::zeros()
    }
}

/// The paper's §6 model, `n = 1`: `G = E₃`, `Ψ(t, t₀) = (t − t₀) E₃`; `d` is the constant drift
/// rate of the reference frame (rad/s).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ConstantDrift;

impl<T: Real> ReferenceDriftModel<T, 3> for ConstantDrift {
    fn g(&self, _elapsed: T) -> SMatrix<T, 3, 3> {
        Matrix3::identity()
    }
}

/// `n = 2`: a reference whose anchor sample is noisy, plus a constant drift.
/// `d = [e₀; d_drift]`: `e₀` (half-angle vector, rad) is the error of the reference attitude at
/// `t₀` (`Ψ_anchor = [2E₃ 0]`), `d_drift` the drift rate (rad/s, `G = [0 E₃]`). For a GNSS
/// attitude reference, whose samples carry independent noise, the error of the one sample that
/// anchors the relative quaternions `P = N(t) N̄(t₀)` would otherwise bias every equation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AnchorErrorAndDrift;

impl<T: Real> ReferenceDriftModel<T, 6> for AnchorErrorAndDrift {
    fn g(&self, _elapsed: T) -> SMatrix<T, 3, 6> {
        let mut g = SMatrix::<T, 3, 6>::zeros();
        g.fixed_view_mut::<3, 3>(0, 3).fill_with_identity();
        g
    }

    fn psi_anchor(&self) -> SMatrix<T, 3, 6> {
        let mut p = SMatrix::<T, 3, 6>::zeros();
        p.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * crate::real::<T>(2.0)));
        p
    }
}

/// The quadratures of eqs. (2.2) and (2.4), by the trapezoid rule with the propagation step:
/// `Θ(t) = ∫_{t₀}^t Bᵀ D(ω*) dt` (`3 × CM`) and `∫_{t₀}^t G dt` (`3 × DN`).
///
/// Over a step `[t_{k−1}, t_k]` the gyro turned by `θ` (the sum of the step's increments), so
/// `D(ω*) dt = D(θ/H) H` and `Θ_k = Θ_{k−1} + ½ (Bᵀ_{k−1} + Bᵀ_k) D(θ/H) H`: the trapezoid
/// rule on `Bᵀ` with the rate of the step, local error `O(H³)` as the paper specifies. `Bᵀ` is
/// the rotation from gyro axes to the computed frame `K`, the DCM of `M`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ErrorQuadratures<const CM: usize, const DN: usize, T = f32> {
    theta: SMatrix<T, 3, CM>,
    correction_integral: Vector3<T>,
    g_integral: SMatrix<T, 3, DN>,
    bt_prev: Matrix3<T>,
    g_prev: SMatrix<T, 3, DN>,
}

impl<const CM: usize, const DN: usize, T: Real> ErrorQuadratures<CM, DN, T> {
    /// Quadratures starting at `t₀` with `Bᵀ(t₀) = bt0` and `G(t₀) = g0`.
    pub fn new(bt0: Matrix3<T>, g0: SMatrix<T, 3, DN>) -> Self {
        Self {
            theta: SMatrix::zeros(),
            correction_integral: Vector3::zeros(),
            g_integral: SMatrix::zeros(),
            bt_prev: bt0,
            g_prev: g0,
        }
    }

    /// Advances the integrals over one step of `h_step` seconds, at whose end the computed
    /// attitude has DCM `bt` and the drift model `G = g`; `d_dt = D(θ/H) H` of the step and
    /// `correction` the gyro correction applied over it.
    pub fn step(
        &mut self,
        bt: &Matrix3<T>,
        d_dt: &SMatrix<T, 3, CM>,
        g: &SMatrix<T, 3, DN>,
        h_step: T,
        correction: &SVector<T, CM>,
    ) {
        let half: T = crate::real(0.5);
        // eq. (2.4), trapezoid: ΔΘ = ½ (Bᵀ_{k−1} + Bᵀ_k) D(ω*) H
        let d_theta = (self.bt_prev + bt) * d_dt * half;
        self.theta += d_theta;
        // the same quadrature of the applied correction: K += ΔΘ c_applied
        self.correction_integral += d_theta * correction;
        // eq. (2.2), trapezoid: ∫G += ½ (G_{k−1} + G_k) H
        self.g_integral += (self.g_prev + g) * (half * h_step);
        self.bt_prev = *bt;
        self.g_prev = *g;
    }

    /// `Θ(t)` (`3 × CM`): attitude error in the computed frame per unit of `c`, times −2.
    pub fn theta(&self) -> &SMatrix<T, 3, CM> {
        &self.theta
    }

    /// `K(t) = ∫_{t₀}^t Bᵀ D(ω*) c_applied dt` (rad, half-angle × 2, frame `K`): the part of
    /// `Θ c` that the gyro correction applied so far has already removed (`K = Θ c_applied`
    /// while the correction is constant).
    pub fn correction_integral(&self) -> &Vector3<T> {
        &self.correction_integral
    }

    /// `∫_{t₀}^t G dt` (`3 × DN`), without the anchor term.
    pub fn g_integral(&self) -> &SMatrix<T, 3, DN> {
        &self.g_integral
    }
}
