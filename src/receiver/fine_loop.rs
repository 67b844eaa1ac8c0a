//! The fine attitude without a gyro (or with the gyro excluded): paper 003's one-stage loop on
//! the per-epoch prompts, three angles with their rates and the two line biases.
//!
//! The filter estimates `U(α)` (eq. (2)) from prompts whose lines of sight are given in the
//! frame `F = C_rK₀` (the *anchor*, chosen when the filter starts so that `F = Ĉ_rb`): `U = C_Fb`
//! starts at the identity, far from the gimbal lock of the paper's angles, and the loop follows
//! the motion; when its angles exceed [`ReceiverConfig::reanchor_angle_rad`] the frame is
//! re-anchored on the estimate (a re-initialization around zero with the same covariance,
//! rates and line biases). The attitude is `C_rb = F U(α̂)`.
//!
//! Covariance: `δθ_F = E δα` with `E`'s columns `vee(∂U/∂α_j Uᵀ)` (the reference-frame rotation
//! per angle), so the body-frame rotation-vector covariance is `Uᵀ E P_α Eᵀ U`.

use nalgebra::{Matrix3, Vector3};

use crate::attitude::array::AntennaArray;
use crate::attitude::one_stage::{
    paper003_partials, EpochReport, LockStatus, OneStageError, OneStageFilter, Prior,
    SatelliteObservation,
};
use crate::geometry::{vee, Paper003Angles, Quaternion};

use super::config::ReceiverConfig;
use super::LineBias;

/// State dimension of the loop: three angles, their rates, two line biases.
pub const LOOP_STATES: usize = 8;

/// The loop and its frame.
#[derive(Clone, Debug)]
pub(crate) struct LoopFine {
    filter: OneStageFilter<f32, LOOP_STATES>,
    /// `C_rK₀`, the frame's anchor.
    anchor: Quaternion<f32>,
    /// Last epoch with observations.
    pub last_update: u64,
}

impl LoopFine {
    /// A loop started at `c_rb` with the body-frame rotation-vector covariance `covariance`,
    /// the line biases `line_bias` and body rates `rates` (rad/s), at `epoch`.
    pub fn start(
        config: &ReceiverConfig,
        c_rb: &Quaternion<f32>,
        covariance: &Matrix3<f32>,
        line_bias: &LineBias,
        rates: Vector3<f32>,
        epoch: u64,
    ) -> Result<Self, OneStageError> {
        let array = AntennaArray::new(config.antenna_positions())?;
        let prior = prior_at_identity(covariance, config.prior_rate_sigma, rates, line_bias)?;
        let filter = OneStageFilter::new(config.fine, array, &prior)?;
        Ok(Self {
            filter,
            anchor: c_rb.normalize()?,
            last_update: epoch,
        })
    }

    /// One epoch: the observations (noise units, lines of sight in the reference frame)
    /// rotated into the frame.
    pub fn step(
        &mut self,
        observations: &[SatelliteObservation<f32>],
        epoch: u64,
    ) -> Result<EpochReport<f32>, OneStageError> {
        let c_fr = self.anchor.to_dcm().transpose();
        let mut rotated =
            heapless::Vec::<SatelliteObservation<f32>, { super::MAX_SATELLITES }>::new();
        for obs in observations {
            let los = c_fr * Vector3::from(obs.los);
            let mut o = *obs;
            o.los = [los.x, los.y, los.z];
            // (the receiver never holds more observations than slots)
            rotated
                .push(o)
                .map_err(|_| OneStageError::TooManySatellites)?;
        }
        let report = self.filter.step(&rotated)?;
        if !rotated.is_empty() {
            self.last_update = epoch;
        }
        Ok(report)
    }

    /// The loop's lock verdict.
    pub fn lock(&self) -> LockStatus {
        self.filter.lock_status()
    }

    /// The attitude `C_rb = F U(α̂)`.
    pub fn attitude(&self) -> Quaternion<f32> {
        let u = Quaternion::from_dcm(&self.filter.attitude()).unwrap_or_default();
        let q = self.anchor * u;
        q.normalize().unwrap_or(q)
    }

    /// Body-frame rotation-vector covariance, rad².
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub fn covariance(&self) -> Matrix3<f32> {
        let angles = self.filter.angles();
        let p = self
            .filter
            .angle_covariance()
            .unwrap_or_else(Matrix3::zeros);
        body_covariance(&angles, &p)
    }

    /// The estimated rates (α̇, β̇, γ̇) of `U`, rad/s (≈ the body rates in the frame).
    pub fn rates(&self) -> Vector3<f32> {
        self.filter.rates()
    }

    /// The line biases and their standard deviations, rad.
    pub fn line_bias(&self) -> LineBias {
        let b = self.filter.line_bias();
        let p = self.filter.estimate().covariance();
        let layout = self.filter.layout();
        let sigma = |k: usize| {
            layout.parameter[3 + k]
                .and_then(|i| p.get((i, i)).copied())
                .map_or(0.0, crate::sqrtf)
        };
        LineBias {
            rad: b,
            sigma_rad: [sigma(0), sigma(1)],
            known: true,
        }
    }

    /// The largest of `|α|, |β|, |γ|`, rad.
    pub fn largest_angle(&self) -> f32 {
        let a = self.filter.angles();
        a.alpha.abs().max(a.beta.abs()).max(a.gamma.abs())
    }

    /// Re-anchors the frame on the current estimate and restarts the loop around zero with
    /// the same covariance, rates and line biases.
    pub fn reanchor(&mut self, config: &ReceiverConfig) -> Result<(), OneStageError> {
        let c_rb = self.attitude();
        let cov = self.covariance();
        let line_bias = self.line_bias();
        let prior = prior_at_identity(&cov, config.prior_rate_sigma, self.rates(), &line_bias)?;
        let mut filter = self.filter.clone();
        filter.reinitialize(&prior)?;
        self.anchor = c_rb.normalize()?;
        self.filter = filter;
        Ok(())
    }
}

/// A prior at `U = I` from a body-frame rotation-vector covariance.
#[cfg_attr(feature = "optimize-cold", optimize(size))]
fn prior_at_identity(
    covariance: &Matrix3<f32>,
    rate_sigma: f32,
    rates: Vector3<f32>,
    line_bias: &LineBias,
) -> Result<Prior<f32>, OneStageError> {
    let mut prior = Prior::from_attitude(&Matrix3::identity(), covariance, rate_sigma)?;
    prior.rates = rates;
    if line_bias.known {
        prior.line_bias = line_bias.rad;
        prior.line_bias_variance = line_bias
            .sigma_rad
            .map(|s| (s * s).max(LINE_BIAS_VARIANCE_FLOOR));
    }
    Ok(prior)
}

/// Smallest prior variance of a line bias handed to the loop, rad² (it must keep following
/// the drift).
const LINE_BIAS_VARIANCE_FLOOR: f32 = 1e-4;

/// `Uᵀ E P Eᵀ U`: the covariance of the angles (rad²) as a body-frame rotation vector.
pub(crate) fn body_covariance(angles: &Paper003Angles<f32>, p: &Matrix3<f32>) -> Matrix3<f32> {
    let u = angles.to_dcm();
    let [da, db, dg] = paper003_partials(angles);
    let e = Matrix3::from_columns(&[
        vee(&(da * u.transpose())),
        vee(&(db * u.transpose())),
        vee(&(dg * u.transpose())),
    ]);
    let m = u.transpose() * e;
    let c = m * p * m.transpose();
    (c + c.transpose()) * 0.5
}
