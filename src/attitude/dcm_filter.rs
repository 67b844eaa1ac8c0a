//! The six-state direction-cosine filter of paper 000: the continuous (Kalman–Bucy) EKF of
//! eq. (10), integrated by classical RK4 over each measurement step.
//!
//! ```text
//! dŶ/dt = Φ⁻¹(Ŷ) V̂ + K (Z − H(Ŷ)),        K = R Φᵀ(Ŷ) D_Q⁻¹                     (10)
//! dR/dt = F_Y R + R F_Yᵀ + Φ⁻¹ D_γ Φ⁻ᵀ − K D_Q Kᵀ,   F_Y = −Φ⁻¹ [(∂Φ/∂Y_j) Φ⁻¹V̂]_j
//! ```
//!
//! with `D_Q = σ_p² Δt I₆` and `D_γ = σ_v² Δt I₆`, the spectral densities that correspond to
//! per-sample standard deviations `σ_p` (baselines, m) and `σ_v` (velocity differences, m/s)
//! at the step `Δt` (the spec's discretization).
//!
//! **Timing within the step.** The velocity difference of an epoch is the mean over the step
//! ([`BaselineEpoch`]), so `Ẏ = Φ⁻¹V̂` held over the step carries `H(Ŷ)` exactly along the
//! chord from `z(t_{k−1})` to `z(t_k)`. The baseline sample belongs to the end of the step;
//! at the RK4 stage time `t_{k−1} + cΔt` the filter compares `H(Ŷ)` with the sample carried
//! back along the same chord, `Z − (1 − c) Δt V̂`. Holding `Z` over the step instead would bias
//! the innovation by `ż Δt / 2` (1.5 mm in the paper's experiment, 60 % of the steady-state
//! `σ_z` of the "intensity" noise reading).
//!
//! **Covariance hygiene in f32.** After each step `R` is symmetrized, its diagonal is held at or
//! above a floor of `(16 ε)²` (the state's resolution), and it is checked by Cholesky: a step
//! that loses positive definiteness is rejected with [`DcmError::NotPositiveDefinite`] and the
//! filter is left unchanged.

use nalgebra::{Cholesky, Matrix3, SMatrix, SVector};

use crate::ekf::{chi_square_quantile, GateConfidence};

use crate::geometry::nearest_rotation;
use crate::{real, Real};

use super::array::{AntennaArray, BaselinePair};
use super::baseline_epoch::BaselineEpoch;
use super::direction_cosine::{givens_inverse, ColumnChoice, DirectionCosineModel};
use super::filter_estimate::{FilterEstimate, FilterHealth};
use crate::attitude::array::ArrayError;
use crate::ekf::FilterError;
use crate::error::{Error, ErrorKind};
use crate::geometry::GeometryError;

/// Below this QR pivot ratio of `Φ(Ŷ)` the estimate is flagged [`FilterHealth::WeakGeometry`]
/// (errors amplified by more than about a thousand along one direction). The paper's geometry
/// has about 0.02.
pub const WEAK_GEOMETRY_PIVOT_RATIO: f64 = 1e-3;

/// Configuration of a [`DirectionCosineFilter`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DcmFilterConfig<T = f32> {
    /// The two baselines the filter uses (the paper: `[P12, P23]`).
    pub pairs: [BaselinePair; 2],
    /// Which column of `M` the state leaves out.
    pub columns: ColumnChoice,
    /// Measurement step `Δt`, seconds (the paper: 0.01 s).
    pub dt: T,
    /// Standard deviation of each baseline component per sample, metres (`D_Q = σ_p² Δt I`).
    pub sigma_baseline: T,
    /// Standard deviation of each velocity-difference component per sample, m/s
    /// (`D_γ = σ_v² Δt I`).
    pub sigma_velocity: T,
}

impl<T: Real> DcmFilterConfig<T> {
    /// The paper's filter: baselines 12 and 23, column 1 eliminated.
    pub fn paper(dt: T, sigma_baseline: T, sigma_velocity: T) -> Self {
        Self {
            pairs: [BaselinePair::P12, BaselinePair::P23],
            columns: ColumnChoice::Paper,
            dt,
            sigma_baseline,
            sigma_velocity,
        }
    }

    fn validate(&self) -> Result<(), DcmError> {
        let ok = |v: T| v.is_finite() && v > T::zero();
        if !ok(self.dt) || !ok(self.sigma_baseline) || !ok(self.sigma_velocity) {
            return Err(DcmError::InvalidConfig);
        }
        if self.pairs[0] == self.pairs[1] {
            return Err(DcmError::InvalidConfig);
        }
        Ok(())
    }
}

/// The six-state direction-cosine EKF (paper 000, eq. (10), corrected model).
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DirectionCosineFilter<T: Real = f32> {
    model: DirectionCosineModel<T>,
    config: DcmFilterConfig<T>,
    /// `Ŷ`, the two kept columns of `M`.
    y: SVector<T, 6>,
    /// `R`, the covariance of `Ŷ`.
    r: SMatrix<T, 6, 6>,
    /// NIS of the last step's baselines (6 degrees of freedom); 0 before the first step.
    nis: T,
    /// Smallest QR pivot ratio of `Φ` over the last step's RK4 stages; 1 before the first.
    pivot_ratio: T,
}

/// Right-hand side of eq. (10) at one RK4 stage.
struct Derivative<T: Real> {
    y: SVector<T, 6>,
    r: SMatrix<T, 6, 6>,
    pivot_ratio: T,
}

impl<T: Real> DirectionCosineFilter<T> {
    /// A filter for the antenna array `array` (body axes), starting at the attitude `c_rb0`
    /// (body to reference) with the covariance `r0` of `Ŷ₀` (direction cosines squared; the
    /// spec recommends `1e-4 I`).
    ///
    /// # Errors
    /// [`DcmError::InvalidConfig`] for a bad configuration or an `r0` that is not symmetric
    /// positive definite; [`DcmError::NonFinite`]; the geometry errors of
    /// [`DirectionCosineModel::new`]; [`DcmError::SingularJacobian`] when `Φ(Ŷ₀)` is singular.
    pub fn new(
        array: &AntennaArray<T>,
        config: DcmFilterConfig<T>,
        c_rb0: &Matrix3<T>,
        r0: &SMatrix<T, 6, 6>,
    ) -> Result<Self, DcmError> {
        config.validate()?;
        if !c_rb0.iter().chain(r0.iter()).all(|v| v.is_finite()) {
            return Err(DcmError::NonFinite);
        }
        let [p1, p2] = config.pairs;
        let model =
            DirectionCosineModel::new(&array.baseline(p1), &array.baseline(p2), config.columns)?;
        let r = symmetrize(r0);
        if Cholesky::new(r).is_none() {
            return Err(DcmError::InvalidConfig);
        }
        let y = model.state_from_dcm(c_rb0);
        givens_inverse(&model.jacobian(&y)).ok_or(DcmError::SingularJacobian)?;
        Ok(Self {
            model,
            config,
            y,
            r,
            nis: T::zero(),
            pivot_ratio: T::one(),
        })
    }

    /// The state `Ŷ` (two columns of `M`, interleaved by row; see [`DirectionCosineModel`]).
    pub fn state(&self) -> &SVector<T, 6> {
        &self.y
    }

    /// The covariance `R` of `Ŷ`.
    pub fn covariance(&self) -> &SMatrix<T, 6, 6> {
        &self.r
    }

    /// The model (geometry, eliminated column).
    pub fn model(&self) -> &DirectionCosineModel<T> {
        &self.model
    }

    /// The configuration.
    pub fn config(&self) -> &DcmFilterConfig<T> {
        &self.config
    }

    /// `M(Ŷ)`, the raw (not orthonormalized) direction cosines, body to reference.
    pub fn direction_cosines(&self) -> Matrix3<T> {
        self.model.dcm(&self.y)
    }

    /// One step of `Δt` ([`Self::propagate`]) and the estimate at its end ([`Self::estimate`]).
    ///
    /// # Errors
    /// Those of both; the filter is unchanged on error.
    pub fn step(&mut self, epoch: &BaselineEpoch<T>) -> Result<FilterEstimate<T>, DcmError> {
        let mut next = self.clone();
        next.propagate(epoch)?;
        let estimate = next.estimate()?;
        *self = next;
        Ok(estimate)
    }

    /// One step of `Δt` of the state alone: eq. (10) integrated by RK4 from `t_{k−1}` to `t_k`
    /// with the epoch's velocity differences (mean over the step) and baselines (at `t_k`) of
    /// the filter's two pairs. Keeps the NIS of the baselines for [`Self::estimate`].
    ///
    /// The six direction cosines need not stay near a rotation (nothing in eq. (10) holds them
    /// there), so this can succeed where [`Self::estimate`] then fails.
    ///
    /// # Errors
    /// [`DcmError::MissingBaseline`], [`DcmError::NonFinite`], [`DcmError::ZeroLengthBaseline`]
    /// for bad input; [`DcmError::SingularJacobian`] when `Φ` is singular at a stage;
    /// [`DcmError::NotPositiveDefinite`] when `R` loses definiteness; [`DcmError::Numerical`].
    /// The filter is unchanged on error.
    pub fn propagate(&mut self, epoch: &BaselineEpoch<T>) -> Result<(), DcmError> {
        let [p1, p2] = self.config.pairs;
        let (z1, z2) = (epoch.baseline(p1)?, epoch.baseline(p2)?);
        let (v1, v2) = (
            epoch.velocity_difference(p1)?,
            epoch.velocity_difference(p2)?,
        );
        let z = SVector::<T, 6>::new(z1.x, z1.y, z1.z, z2.x, z2.y, z2.z);
        let v = SVector::<T, 6>::new(v1.x, v1.y, v1.z, v2.x, v2.y, v2.z);
        let h = self.config.dt;
        let half: T = real(0.5);
        let sixth = h / real(6.0);
        // Classical RK4 on (Ŷ, R); stage c uses the sample carried back to t_{k−1} + c h.
        let k1 = self.derivative(&self.y, &self.r, &(z - v * h), &v)?;
        let k2 = self.derivative(
            &(self.y + k1.y * (h * half)),
            &(self.r + k1.r * (h * half)),
            &(z - v * (h * half)),
            &v,
        )?;
        let k3 = self.derivative(
            &(self.y + k2.y * (h * half)),
            &(self.r + k2.r * (h * half)),
            &(z - v * (h * half)),
            &v,
        )?;
        let k4 = self.derivative(&(self.y + k3.y * h), &(self.r + k3.r * h), &z, &v)?;
        let two: T = real(2.0);
        let y = self.y + (k1.y + k2.y * two + k3.y * two + k4.y) * sixth;
        let mut r = symmetrize(&(self.r + (k1.r + k2.r * two + k3.r * two + k4.r) * sixth));
        let floor = (T::default_epsilon() * real(16.0)).powi(2);
        for i in 0..6 {
            if let Some(d) = r.get_mut((i, i)) {
                *d = d.max(floor);
            }
        }
        if !y.iter().chain(r.iter()).all(|x| x.is_finite()) {
            return Err(DcmError::Numerical);
        }
        if Cholesky::new(r).is_none() {
            return Err(DcmError::NotPositiveDefinite);
        }
        let pivot_ratio = k1
            .pivot_ratio
            .min(k2.pivot_ratio)
            .min(k3.pivot_ratio)
            .min(k4.pivot_ratio);
        // NIS of the sample against the new state: S_ν = Φ R Φᵀ + σ_p² I
        let phi = self.model.jacobian(&y);
        let sigma2 = self.config.sigma_baseline * self.config.sigma_baseline;
        let s_nu =
            symmetrize(&(phi * r * phi.transpose())) + SMatrix::<T, 6, 6>::identity() * sigma2;
        let nu = z - self.model.observation(&y);
        let nis = Cholesky::new(s_nu)
            .map(|ch| nu.dot(&ch.solve(&nu)))
            .ok_or(DcmError::NotPositiveDefinite)?;
        if !nis.is_finite() {
            return Err(DcmError::Numerical);
        }
        self.y = y;
        self.r = r;
        self.nis = nis;
        self.pivot_ratio = pivot_ratio;
        Ok(())
    }

    /// Eq. (6) and (10): `(dŶ/dt, dR/dt)` at `(y, r)` against the baseline sample `z`.
    fn derivative(
        &self,
        y: &SVector<T, 6>,
        r: &SMatrix<T, 6, 6>,
        z: &SVector<T, 6>,
        v: &SVector<T, 6>,
    ) -> Result<Derivative<T>, DcmError> {
        let (d_q, d_gamma) = self.intensities();
        let phi = self.model.jacobian(y);
        let (phi_inv, pivot_ratio) = givens_inverse(&phi).ok_or(DcmError::SingularJacobian)?;
        // Ẏ = Φ⁻¹ V̂                                                   (6)
        let y_dot_kin = phi_inv * v;
        // K = R Φᵀ D_Q⁻¹                                               (10)
        let phi_r = phi * r; // Φ R (= (R Φᵀ)ᵀ, R symmetric)
        let k = phi_r.transpose() / d_q;
        // dŶ/dt = Φ⁻¹ V̂ + K (Z − H(Ŷ))                                (10)
        let y_dot = y_dot_kin + k * (z - self.model.observation(y));
        // F_Y = −Φ⁻¹ [(∂Φ/∂Y_j) Ẏ]_j, Ẏ = Φ⁻¹ V̂
        let f = -(phi_inv * self.model.jacobian_product(&y_dot_kin));
        // dR/dt = F R + R Fᵀ + Φ⁻¹ D_γ Φ⁻ᵀ − K D_Q Kᵀ, with K D_Q Kᵀ = K (Φ R)    (10)
        let fr = f * r;
        let r_dot = fr + fr.transpose() + phi_inv * phi_inv.transpose() * d_gamma - k * phi_r;
        Ok(Derivative {
            y: y_dot,
            r: r_dot,
            pivot_ratio,
        })
    }

    /// `(D_Q, D_γ)` per component: `σ_p² Δt`, `σ_v² Δt`.
    fn intensities(&self) -> (T, T) {
        let c = &self.config;
        (
            c.sigma_baseline * c.sigma_baseline * c.dt,
            c.sigma_velocity * c.sigma_velocity * c.dt,
        )
    }

    /// The attitude estimate of the current state: `M(Ŷ)` orthonormalized by
    /// [`nearest_rotation`], the attitude covariance `S R Sᵀ` with `S = ∂θ/∂Y`, the NIS of the
    /// last step, and the health: [`FilterHealth::WeakGeometry`] from the conditioning of `Φ`,
    /// then [`FilterHealth::ConstraintViolated`] when the rotation constraints `g(Ŷ)` fail
    /// `gᵀ (G R Gᵀ)⁻¹ g ≤ χ²₃(99.9 %)` with `G = ∂g/∂Y`, then
    /// [`FilterHealth::InnovationOutlier`] from the NIS.
    ///
    /// # Errors
    /// [`DcmError::NotARotation`] when `M(Ŷ)` is too far from a rotation to be orthonormalized
    /// (its kept columns have become (nearly) parallel); [`DcmError::Numerical`].
    pub fn estimate(&self) -> Result<FilterEstimate<T>, DcmError> {
        let c = nearest_rotation(&self.model.dcm(&self.y))?;
        let s = self.model.attitude_jacobian(&c, &self.y);
        let covariance = symmetrize(&(s * self.r * s.transpose()));
        let gate: T = real(chi_square_quantile(6, GateConfidence::P999).unwrap_or(22.46));
        // the truth satisfies g(Y) = 0: test the state's constraint residual against R
        let g = DirectionCosineModel::constraint_residual(&self.y);
        let g_jac = DirectionCosineModel::constraint_jacobian(&self.y);
        let constraint_nis = Cholesky::new(symmetrize(&(g_jac * self.r * g_jac.transpose())))
            .map(|ch| g.dot(&ch.solve(&g)));
        let constraint_gate: T =
            real(chi_square_quantile(3, GateConfidence::P999).unwrap_or(16.27));
        let health = if !(self.pivot_ratio >= real(WEAK_GEOMETRY_PIVOT_RATIO)) {
            FilterHealth::WeakGeometry
        } else if !constraint_nis.is_some_and(|c| c <= constraint_gate) {
            FilterHealth::ConstraintViolated
        } else if !(self.nis <= gate) {
            FilterHealth::InnovationOutlier
        } else {
            FilterHealth::Nominal
        };
        FilterEstimate::from_rotation(c, covariance, self.nis, 6, health)
    }
}

/// `(P + Pᵀ) / 2`.
pub(crate) fn symmetrize<T: Real, const N: usize>(p: &SMatrix<T, N, N>) -> SMatrix<T, N, N> {
    let half: T = real(0.5);
    (p + p.transpose()) * half
}

/// Errors of the baseline and Doppler attitude filters of paper 000 ([`crate::attitude`]:
/// the direction-cosine filter, the multi-structure filter and the rigid-body filter).
///
/// A step that returns one of these leaves its filter exactly as it was before the call.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DcmError {
    /// A measurement, an antenna position, an initial attitude or a covariance was NaN or
    /// infinite.
    #[error("non-finite baseline filter input")]
    NonFinite,
    /// A baseline vector or a velocity difference that the filter needs is absent (one of its
    /// two antennas has no solution in this epoch).
    #[error("a needed baseline or velocity difference is missing")]
    MissingBaseline,
    /// A baseline — an antenna-position difference in body axes, or a measured baseline in the
    /// reference frame — is shorter than [`crate::attitude::array::MIN_BASELINE_LENGTH`].
    #[error("baseline of (near) zero length")]
    ZeroLengthBaseline,
    /// A configuration value is out of its domain: a non-positive step or noise level, a pair
    /// of identical baselines, a covariance that is not symmetric positive definite.
    #[error("invalid baseline filter configuration")]
    InvalidConfig,
    /// The antenna geometry makes the model singular at every attitude: the two baselines are
    /// (nearly) parallel, or the eliminated column's body axis lies (nearly) in the antenna
    /// plane (`n_k → 0` with `n = b₁ × b₂`, the paper's `n_x = 0` case).
    #[error("antenna geometry makes the direction-cosine model singular")]
    SingularGeometry,
    /// `Φ(Ŷ)` is singular in working precision at the current estimate. Since
    /// `|det Φ(Y)| ≥ |n_k|³` for every state, this happens only for geometry close to the
    /// limit of [`DcmError::SingularGeometry`], or after an overflow. Re-initialize the filter.
    #[error("observation Jacobian is numerically singular")]
    SingularJacobian,
    /// The covariance lost positive definiteness during the step (the step is rejected).
    #[error("covariance lost positive definiteness")]
    NotPositiveDefinite,
    /// The estimate could not be turned into a rotation (its direction cosines are too far
    /// from orthonormal, or the orthonormalization did not converge).
    #[error("estimate is too far from a rotation")]
    NotARotation,
    /// The shared Kalman filter toolkit rejected the step.
    #[error("filter toolkit refused the step")]
    Filter(#[from] FilterError),
    /// The step overflowed or produced a non-finite number from finite input.
    #[error("baseline filter step overflowed")]
    Numerical,
}

impl Error for DcmError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::MissingBaseline | Self::ZeroLengthBaseline | Self::InvalidConfig => {
                ErrorKind::InvalidInput
            }
            Self::SingularGeometry | Self::SingularJacobian => ErrorKind::Unobservable,
            Self::NotPositiveDefinite => ErrorKind::NotPositiveDefinite,
            Self::NotARotation | Self::Numerical => ErrorKind::Numerical,
            Self::Filter(e) => e.kind(),
        }
    }
}

impl From<GeometryError> for DcmError {
    fn from(e: GeometryError) -> Self {
        match e {
            GeometryError::NonFinite => Self::NonFinite,
            GeometryError::ZeroLength
            | GeometryError::NotARotation
            | GeometryError::NotConverged => Self::NotARotation,
        }
    }
}

impl From<ArrayError> for DcmError {
    fn from(e: ArrayError) -> Self {
        match e {
            ArrayError::NonFinite => Self::NonFinite,
            ArrayError::CoincidentAntennas => Self::ZeroLengthBaseline,
            ArrayError::CollinearAntennas => Self::SingularGeometry,
        }
    }
}
