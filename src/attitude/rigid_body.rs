//! A rigid-body attitude filter on paper 000's measurements: a multiplicative (error-state,
//! three-parameter) EKF on the shared [`Ekf`] toolkit, propagated with the body rate that the
//! velocity differences give by least squares, and updated with every baseline vector.
//!
//! None of the papers has it. The six-state filter estimates six numbers where a rotation has
//! three, so it never uses the rigid-body constraint; this filter does, in the propagation
//! and in the update.
//!
//! **Rate.** For a rigid body `V_i − V_j = C_rb (ω × b_ij)`. With `u_ij = Ĉᵀ ΔV_ij` (body
//! axes), least squares over the pairs gives
//! `ω̂ = J⁻¹ Σ b_ij × u_ij`, `J = Σ [b_ij]×ᵀ [b_ij]× = Σ (|b|² I − b bᵀ)`, with noise
//! covariance `σ_v² J⁻¹` per sample. The velocity differences are means over the step, so `Ĉ`
//! is taken at the middle of the step (one predictor pass), which removes the `O(ω² Δt)` rate
//! bias of using the attitude at the start.
//!
//! **Error state.** `C_true = Ĉ exp([δθ]×)`, `δθ` in body axes. Because `ω̂` is computed with
//! `Ĉ`, an attitude error feeds into the rate: `ω̂ − ω = −J⁻¹ Σ [b]×[ω×b]× δθ + noise =
//! −J⁻¹ [ω]× S δθ + noise` with `S = Σ b bᵀ`. Hence
//! `δθ̇ = F δθ − n`, `F = −[ω̂]× + J⁻¹ [ω̂]× S`, `Q = σ_v² Δt² J⁻¹` per step. (With this `F` the
//! steady-state covariance is exactly `σ_p σ_v Δt J⁻¹`: the body rotation does not spread the
//! weak axis' error over the well-observed ones, unlike for a rate that is independent of the
//! attitude.)
//!
//! **Update.** Each baseline `Z_ij = C b_ij + q`, rotated into body axes: `Ĉᵀ Z_ij − b_ij =
//! −[b_ij]× δθ + Ĉᵀ q`, so `H = −[b_ij]×`, `R = σ_p² I₃`, one 3-D Joseph update per baseline,
//! each gated at 99.9 % (χ²₃); after three epochs in a row with a rejection the next epoch is
//! applied ungated. The error is then folded into `Ĉ` and reset.

use nalgebra::{Cholesky, Matrix3, Vector3};

use crate::attitude::dcm_filter::DcmError;
use crate::ekf::{Ekf, GateConfidence, NisGate};
use crate::geometry::{skew, Quaternion};
use crate::{real, Real};

use super::array::{AntennaArray, BaselinePair};
use super::baseline_epoch::BaselineEpoch;
use super::dcm_filter::symmetrize;
use super::filter_estimate::{FilterEstimate, FilterHealth};

/// After this many epochs in a row with a gated-out baseline, the next epoch is applied
/// without the gate (a gate that keeps rejecting means the estimate, not the data, is off).
pub const GATE_RECOVERY_EPOCHS: u32 = 3;

/// Below this ratio of the smallest to the largest Cholesky pivot of `J` (squared), the rate
/// geometry is refused as singular (parallel baselines). The paper's array has about 4e-4.
pub const MIN_RATE_GEOMETRY_RATIO: f64 = 1e-6;

/// Configuration of a [`RigidBodyFilter`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RigidBodyConfig<T = f32> {
    /// Measurement step `Δt`, seconds.
    pub dt: T,
    /// Standard deviation of each baseline component per sample, metres.
    pub sigma_baseline: T,
    /// Standard deviation of each velocity-difference component per sample, m/s.
    pub sigma_velocity: T,
    /// Innovation gate per baseline (χ²₃); `None` applies every baseline.
    pub gate: Option<GateConfidence>,
}

/// The rigid-body error-state filter.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RigidBodyFilter<T: Real = f32> {
    /// Body-axes baselines `b₁₂, b₂₃, b₁₃`, metres.
    baselines: [Vector3<T>; 3],
    config: RigidBodyConfig<T>,
    /// Nominal attitude `q_rb`.
    q_rb: Quaternion<T>,
    /// The error state `δθ` (zero between steps) and its covariance, rad².
    ekf: Ekf<3, T>,
    /// The last least-squares body rate, rad/s, body axes.
    rate: Vector3<T>,
    rejected_in_a_row: u32,
}

/// `J = Σ (|b|² I − b bᵀ)` and `S = Σ b bᵀ` over the given baselines.
fn rate_geometry<T: Real>(baselines: &[Option<Vector3<T>>; 3]) -> (Matrix3<T>, Matrix3<T>) {
    let mut s = Matrix3::zeros();
    for b in baselines.iter().flatten() {
        s += b * b.transpose();
    }
    (Matrix3::identity() * s.trace() - s, s)
}

impl<T: Real> RigidBodyFilter<T> {
    /// A filter for the antenna array `array` starting at the attitude `q_rb0` (body to
    /// reference) with the attitude-error covariance `p0` (body axes, rad²).
    ///
    /// # Errors
    /// [`DcmError::InvalidConfig`] for a non-positive step or noise, or a `p0` that is not
    /// positive definite; [`DcmError::NonFinite`]; [`DcmError::NotARotation`] for a quaternion
    /// of zero length.
    pub fn new(
        array: &AntennaArray<T>,
        config: RigidBodyConfig<T>,
        q_rb0: &Quaternion<T>,
        p0: &Matrix3<T>,
    ) -> Result<Self, DcmError> {
        let ok = |v: T| v.is_finite() && v > T::zero();
        if !ok(config.dt) || !ok(config.sigma_baseline) || !ok(config.sigma_velocity) {
            return Err(DcmError::InvalidConfig);
        }
        if !q_rb0.is_finite() || !p0.iter().all(|v| v.is_finite()) {
            return Err(DcmError::NonFinite);
        }
        let q_rb = q_rb0.normalize()?;
        let ekf = Ekf::new(Vector3::zeros(), *p0).map_err(|e| match e {
            crate::ekf::FilterError::InvalidCovariance => DcmError::InvalidConfig,
            other => DcmError::Filter(other),
        })?;
        Ok(Self {
            baselines: BaselinePair::ALL.map(|p| array.baseline(p)),
            config,
            q_rb,
            ekf,
            rate: Vector3::zeros(),
            rejected_in_a_row: 0,
        })
    }

    /// The attitude `q_rb`, body to reference.
    pub fn attitude(&self) -> &Quaternion<T> {
        &self.q_rb
    }

    /// The attitude-error covariance, body axes, rad².
    pub fn covariance(&self) -> &Matrix3<T> {
        self.ekf.covariance()
    }

    /// The body rate of the last step from the velocity differences, body axes, rad/s.
    pub fn rate(&self) -> &Vector3<T> {
        &self.rate
    }

    /// One step of `Δt`: propagation with the least-squares rate from the epoch's velocity
    /// differences (at least two, from non-parallel baselines), then one gated update per
    /// available baseline (at least one).
    ///
    /// # Errors
    /// [`DcmError::MissingBaseline`] when fewer than two velocity differences or no baseline
    /// are available; [`DcmError::NonFinite`], [`DcmError::ZeroLengthBaseline`] for bad
    /// input; [`DcmError::SingularGeometry`] when the available baselines are parallel;
    /// [`DcmError::Filter`] from the toolkit. The filter is unchanged on error.
    pub fn step(&mut self, epoch: &BaselineEpoch<T>) -> Result<FilterEstimate<T>, DcmError> {
        let mut next = self.clone();
        let estimate = next.step_in_place(epoch)?;
        *self = next;
        Ok(estimate)
    }

    fn step_in_place(&mut self, epoch: &BaselineEpoch<T>) -> Result<FilterEstimate<T>, DcmError> {
        let measured = PairMeasurements::of(epoch)?;
        let (q_pred, omega) = self.predict(&measured)?;
        let (nis, offered, rejected) = self.update_baselines(&q_pred, &measured.baselines)?;
        self.rejected_in_a_row = if rejected > 0 {
            self.rejected_in_a_row.saturating_add(1)
        } else {
            0
        };
        // fold the error into the nominal attitude and reset it
        let dtheta = *self.ekf.state();
        self.q_rb = (q_pred * Quaternion::from_rotation_vector(&dtheta)).normalize()?;
        self.ekf.set_state(Vector3::zeros())?;
        self.rate = omega;
        let health = if rejected > 0 {
            FilterHealth::InnovationOutlier
        } else {
            FilterHealth::Nominal
        };
        FilterEstimate::from_rotation(
            self.q_rb.to_dcm(),
            *self.ekf.covariance(),
            nis,
            offered.saturating_mul(3),
            health,
        )
    }

    /// The rate from the velocity differences (midpoint predictor–corrector), the nominal
    /// attitude propagated by it, and the error state's covariance propagated over the step.
    /// Returns the predicted attitude and the body rate, rad/s.
    fn predict(
        &mut self,
        measured: &PairMeasurements<T>,
    ) -> Result<(Quaternion<T>, Vector3<T>), DcmError> {
        let rate = RateSolver::new(&self.baselines, &measured.velocity_differences)?;
        let dt = self.config.dt;
        let half: T = real(0.5);
        let c0 = self.q_rb.to_dcm();
        let omega0 = rate.body_rate(&c0);
        let c_mid =
            (self.q_rb * Quaternion::from_rotation_vector(&(omega0 * (dt * half)))).to_dcm();
        let omega = rate.body_rate(&c_mid);
        // nominal attitude: q ← q ⊗ exp(ω̂ Δt)
        let q_pred = (self.q_rb * Quaternion::from_rotation_vector(&(omega * dt))).normalize()?;
        // error state: F = −[ω̂]× + J⁻¹ [ω̂]× S;  Φ = I + F Δt + (F Δt)²/2;  Q = σ_v² Δt² J⁻¹
        let j_inv = rate.chol.inverse();
        let f = (-skew(&omega) + j_inv * skew(&omega) * rate.s) * dt;
        let transition = Matrix3::identity() + f + f * f * half;
        let sv = self.config.sigma_velocity;
        let q = symmetrize(&(j_inv * (sv * sv * dt * dt)));
        self.ekf.predict_to(&Vector3::zeros(), &transition, &q)?;
        Ok((q_pred, omega))
    }

    /// One gated update per measured baseline: `Ĉᵀ Z − b = −[b]× δθ + noise`. Returns the
    /// summed NIS and the counts of baselines offered and rejected.
    fn update_baselines(
        &mut self,
        q_pred: &Quaternion<T>,
        measured: &[Option<Vector3<T>>; 3],
    ) -> Result<(T, u8, u8), DcmError> {
        let c_pred = q_pred.to_dcm();
        let sp = self.config.sigma_baseline;
        let r = Matrix3::identity() * (sp * sp);
        let gate = match self.config.gate {
            Some(g) if self.rejected_in_a_row < GATE_RECOVERY_EPOCHS => {
                Some(NisGate::chi_square(3, g))
            }
            _ => None,
        };
        let mut nis = T::zero();
        let (mut offered, mut rejected) = (0u8, 0u8);
        for (b, zk) in self.baselines.iter().zip(measured.iter()) {
            if let Some(zk) = zk {
                let h = -skew(b);
                let y = c_pred.transpose() * zk - b - h * self.ekf.state();
                let report = self.ekf.update(&y, &h, &r, gate)?;
                nis += report.nis;
                offered = offered.saturating_add(1); // (at most one per baseline)
                if !report.accepted {
                    rejected = rejected.saturating_add(1);
                }
            }
        }
        Ok((nis, offered, rejected))
    }
}

/// One epoch's measurements by baseline pair (`None` where the pair is missing).
struct PairMeasurements<T: Real> {
    /// Velocity differences, reference frame, m/s.
    velocity_differences: [Option<Vector3<T>>; 3],
    /// Baselines, reference frame, m.
    baselines: [Option<Vector3<T>>; 3],
}

impl<T: Real> PairMeasurements<T> {
    /// Sorts the epoch's measurements by pair; at least two velocity differences and one
    /// baseline are required.
    fn of(epoch: &BaselineEpoch<T>) -> Result<Self, DcmError> {
        let present = |r: Result<Vector3<T>, DcmError>| match r {
            Ok(v) => Ok(Some(v)),
            Err(DcmError::MissingBaseline) => Ok(None),
            Err(e) => Err(e),
        };
        let mut m = Self {
            velocity_differences: [None; 3],
            baselines: [None; 3],
        };
        for ((pair, dv), z) in BaselinePair::ALL
            .into_iter()
            .zip(m.velocity_differences.iter_mut())
            .zip(m.baselines.iter_mut())
        {
            *dv = present(epoch.velocity_difference(pair))?;
            *z = present(epoch.baseline(pair))?;
        }
        if crate::count(m.velocity_differences.iter().flatten()) < 2
            || crate::count(m.baselines.iter().flatten()) == 0
        {
            return Err(DcmError::MissingBaseline);
        }
        Ok(m)
    }
}

/// The least-squares body rate from velocity differences:
/// `ω̂ = J⁻¹ Σ b × (Ĉᵀ ΔV)` over the baselines that have a velocity difference.
struct RateSolver<'a, T: Real> {
    chol: Cholesky<T, nalgebra::U3>,
    /// `S` of the rate geometry (see `rate_geometry`).
    s: Matrix3<T>,
    rate_baselines: [Option<Vector3<T>>; 3],
    velocity_differences: &'a [Option<Vector3<T>>; 3],
}

impl<'a, T: Real> RateSolver<'a, T> {
    /// Factors the rate geometry; [`DcmError::SingularGeometry`] when the baselines with a
    /// velocity difference are (nearly) parallel.
    fn new(
        baselines: &[Vector3<T>; 3],
        velocity_differences: &'a [Option<Vector3<T>>; 3],
    ) -> Result<Self, DcmError> {
        let rate_baselines =
            [0, 1, 2].map(|k| match (velocity_differences.get(k), baselines.get(k)) {
                (Some(Some(_)), Some(b)) => Some(*b),
                _ => None,
            });
        let (j, s) = rate_geometry(&rate_baselines);
        let chol = Cholesky::new(j).ok_or(DcmError::SingularGeometry)?;
        let l_diag = chol.l_dirty().diagonal();
        let (lmin, lmax) = (l_diag.min(), l_diag.max());
        if !(lmin * lmin >= lmax * lmax * real(MIN_RATE_GEOMETRY_RATIO)) {
            return Err(DcmError::SingularGeometry);
        }
        Ok(Self {
            chol,
            s,
            rate_baselines,
            velocity_differences,
        })
    }

    /// The body rate with the attitude `c` (body to reference), rad/s.
    fn body_rate(&self, c: &Matrix3<T>) -> Vector3<T> {
        let mut rhs = Vector3::zeros();
        for (b, v) in self
            .rate_baselines
            .iter()
            .zip(self.velocity_differences.iter())
        {
            if let (Some(b), Some(v)) = (b, v) {
                rhs += b.cross(&(c.transpose() * v));
            }
        }
        self.chol.solve(&rhs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{log_so3, rot_x, rot_y, rot_z};

    fn array() -> AntennaArray<f64> {
        AntennaArray::from_baselines(&Vector3::new(1.5, 1.8, 1.9), &Vector3::new(1.7, 1.7, 2.0))
            .unwrap()
    }

    fn exp(theta: &Vector3<f64>) -> Matrix3<f64> {
        Quaternion::from_rotation_vector(theta).to_dcm()
    }

    /// Noise-free epoch for the step from `c0` to `c1` (velocity differences = chord / Δt).
    fn epoch(
        a: &AntennaArray<f64>,
        c0: &Matrix3<f64>,
        c1: &Matrix3<f64>,
        dt: f64,
    ) -> BaselineEpoch<f64> {
        let mut e = BaselineEpoch::default();
        for p in BaselinePair::ALL {
            let b = a.baseline(p);
            e.baselines[p.index()] = Some(c1 * b);
            e.velocity_differences[p.index()] = Some((c1 - c0) * b / dt);
        }
        e
    }

    #[test]
    fn error_transition_matches_the_nonlinear_propagation() {
        // δθ⁺(δθ₀) − δθ⁺(0) ≈ Φ δθ₀ for the nominal propagation with noise-free data.
        let a = array();
        let dt = 0.5; // large, so that F Δt is well above the rounding level
        let omega = Vector3::new(0.1047, 0.0174, 0.026) * 2.0;
        let c0 = rot_z(0.3) * rot_y(-0.2) * rot_x(1.0);
        let c1 = c0 * exp(&(omega * dt));
        let e = epoch(&a, &c0, &c1, dt);
        let config = RigidBodyConfig {
            dt,
            sigma_baseline: 1e3,
            sigma_velocity: 1e-3,
            gate: None,
        };
        let propagate = |d0: &Vector3<f64>| {
            // estimate Ĉ = C exp(−δθ₀), so that C = Ĉ exp(δθ₀)
            let q0 = Quaternion::from_dcm(&(c0 * exp(&-d0))).unwrap();
            let mut f =
                RigidBodyFilter::new(&a, config, &q0, &(Matrix3::identity() * 1e-12)).unwrap();
            f.step(&e).unwrap();
            log_so3(&(f.attitude().to_dcm().transpose() * c1)).unwrap()
        };
        let base = propagate(&Vector3::zeros());
        // the transition the filter used, rebuilt from its formulas with the true rate
        let (j, s) = rate_geometry(&BaselinePair::ALL.map(|p| Some(a.baseline(p))));
        let j_inv = j.try_inverse().unwrap();
        let f = (-skew(&omega) + j_inv * skew(&omega) * s) * dt;
        let transition = Matrix3::identity() + f + f * f * 0.5;
        for d0 in [Vector3::new(1e-5, 0.0, 0.0), Vector3::new(0.0, -1e-5, 2e-5)] {
            let moved = propagate(&d0) - base;
            let predicted = transition * d0;
            assert!(
                (moved - predicted).norm() < 0.02 * d0.norm(),
                "moved {moved:?} predicted {predicted:?}"
            );
            // and it is not the identity: the rate coupling matters at this step
            assert!((moved - d0).norm() > 0.05 * d0.norm());
        }
    }

    #[test]
    fn noise_free_tracking_error_is_second_order_in_the_step() {
        let a = array();
        let dt = 0.01;
        let omega = Vector3::new(0.1047, 0.0174, 0.026);
        let mut c = rot_x(0.4);
        let config = RigidBodyConfig {
            dt,
            sigma_baseline: 0.06,
            sigma_velocity: 0.01,
            gate: Some(GateConfidence::P999),
        };
        let q0 = Quaternion::from_dcm(&c).unwrap();
        let mut f = RigidBodyFilter::new(&a, config, &q0, &(Matrix3::identity() * 1e-8)).unwrap();
        for _ in 0..1000 {
            let c1 = c * exp(&(omega * dt));
            f.step(&epoch(&a, &c, &c1, dt)).unwrap();
            c = c1;
        }
        // midpoint rule: rate error (Δt²/24)·|ω|³-sized (5e-9 rad/s here), attitude lag below
        // 1e-7 rad — four orders below the noise-driven errors of the scenarios
        let err = log_so3(&(f.attitude().to_dcm().transpose() * c))
            .unwrap()
            .norm();
        assert!(err < 1e-7, "{err:e}");
        assert!((f.rate() - omega).norm() < 1e-8);
    }
}
