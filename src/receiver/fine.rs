//! The fine attitude: paper 003's one-stage filter, run in the gyro-propagated frame.
//!
//! The filter estimates `U(α)` (eq. (2)) from prompts whose lines of sight are given in some
//! frame. The receiver gives them in `F(t) = C_rK₀ M(t)`, the body frame as the gyro carries it
//! from the anchor `C_rK₀` (chosen when the filter starts so that `F = Ĉ_rb`): then
//! `U = C_Fb` stays near the identity, far from the gimbal lock of the paper's angles, and its
//! rate is the gyro's error rather than the body's rotation, so a loop of a fraction of a hertz
//! follows any tumble the gyro follows. The attitude is `C_rb = F(t) U(α̂)`. Without a gyro
//! `M = I`, and the loop follows the motion itself; when its angles exceed
//! [`ReceiverConfig::reanchor_angle_rad`] the frame is re-anchored on the estimate (a
//! re-initialization around zero with the same covariance and rates).
//!
//! Covariance: `δθ_F = E δα` with `E`'s columns `vee(∂U/∂α_j Uᵀ)` (the reference-frame rotation
//! per angle), so the body-frame rotation-vector covariance is `Uᵀ E P_α Eᵀ U`.

use nalgebra::{Matrix3, Vector3};

use crate::attitude::array::AntennaArray;
use crate::attitude::one_stage::OneStageError;
use crate::attitude::one_stage::{
    paper003_partials, EpochReport, LockStatus, OneStageFilter, Prior, SatelliteObservation,
};
use crate::geometry::{vee, Paper003Angles, Quaternion};

use super::config::ReceiverConfig;

/// State dimension of the receiver's fine filter: three angles and their rates.
pub const FINE_STATES: usize = 6;

/// The fine stage.
#[derive(Clone, Debug)]
pub(crate) struct FineStage {
    pub filter: OneStageFilter<f32, FINE_STATES>,
    /// `C_rK₀`: the anchor of the filter's frame, as a quaternion.
    pub anchor: Quaternion<f32>,
    /// The last epoch's report.
    pub report: Option<EpochReport<f32>>,
    /// Last epoch with observations.
    pub last_update: u64,
}

impl FineStage {
    /// A fine filter started at `c_rb` (body to reference, at the epoch where the gyro's
    /// attitude is `m`) with the body-frame rotation-vector covariance `covariance`.
    pub fn start(
        config: &ReceiverConfig,
        c_rb: &Quaternion<f32>,
        covariance: &Matrix3<f32>,
        m: &Quaternion<f32>,
        rates: Vector3<f32>,
        epoch: u64,
    ) -> Result<Self, OneStageError> {
        let [a, b, c] = config.antenna_positions();
        let array = AntennaArray::new([a, b, c])?;
        let prior = prior_at_identity(covariance, config.prior_rate_sigma, rates)?;
        let filter = OneStageFilter::new(config.fine, array, &prior)?;
        // F = C_rK₀ M = C_rb at this epoch: C_rK₀ = C_rb Mᵀ
        let anchor = (*c_rb * m.conjugate()).normalize()?;
        Ok(Self {
            filter,
            anchor,
            report: None,
            last_update: epoch,
        })
    }

    /// `F(t) = C_rK₀ M(t)`.
    pub fn frame(&self, m: &Quaternion<f32>) -> Quaternion<f32> {
        self.anchor * *m
    }

    /// One epoch: the observations (lines of sight in the reference frame) rotated into `F`.
    pub fn step(
        &mut self,
        observations: &[SatelliteObservation<f32>],
        m: &Quaternion<f32>,
        epoch: u64,
    ) -> Result<EpochReport<f32>, OneStageError> {
        let c_fr = self.frame(m).to_dcm().transpose();
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
        self.report = Some(report);
        Ok(report)
    }

    /// The filter's lock verdict.
    pub fn lock(&self) -> LockStatus {
        self.filter.lock_status()
    }

    /// `C_Fb = U(α̂)`.
    pub fn relative(&self) -> Quaternion<f32> {
        Quaternion::from_dcm(&self.filter.attitude()).unwrap_or_default()
    }

    /// The attitude `C_rb = F U(α̂)` with `M = m`.
    pub fn attitude(&self, m: &Quaternion<f32>) -> Quaternion<f32> {
        let q = self.frame(m) * self.relative();
        q.normalize().unwrap_or(q)
    }

    /// Body-frame rotation-vector covariance, rad².
    pub fn covariance(&self) -> Matrix3<f32> {
        let angles = self.filter.angles();
        let p = self
            .filter
            .angle_covariance()
            .unwrap_or_else(Matrix3::zeros);
        body_covariance(&angles, &p)
    }

    /// The largest of `|α|, |β|, |γ|`, rad.
    pub fn largest_angle(&self) -> f32 {
        let a = self.filter.angles();
        a.alpha.abs().max(a.beta.abs()).max(a.gamma.abs())
    }

    /// Re-anchors the frame on the current estimate (at gyro attitude `m`) and restarts the
    /// filter around zero with the same covariance and rates.
    pub fn reanchor(
        &mut self,
        config: &ReceiverConfig,
        m: &Quaternion<f32>,
    ) -> Result<(), OneStageError> {
        let c_rb = self.attitude(m);
        let cov = self.covariance();
        let rates = self.filter.rates();
        let mut prior = prior_at_identity(&cov, config.prior_rate_sigma, rates)?;
        // keep the learned rates' covariance
        let p = self.filter.estimate().covariance();
        let layout = *self.filter.layout();
        for i in 0..3 {
            for j in 0..3 {
                if let (Some(Some(ri)), Some(Some(rj))) = (layout.rate.get(i), layout.rate.get(j)) {
                    if let (Some(dst), Some(v)) =
                        (prior.rate_covariance.get_mut((i, j)), p.get((*ri, *rj)))
                    {
                        *dst = *v;
                    }
                }
            }
        }
        let mut filter = self.filter.clone();
        filter.reinitialize(&prior)?;
        let anchor = (c_rb * m.conjugate()).normalize()?;
        self.filter = filter;
        self.anchor = anchor;
        Ok(())
    }
}

/// A prior at `U = I` from a body-frame rotation-vector covariance.
fn prior_at_identity(
    covariance: &Matrix3<f32>,
    rate_sigma: f32,
    rates: Vector3<f32>,
) -> Result<Prior<f32>, OneStageError> {
    let mut prior = Prior::from_attitude(&Matrix3::identity(), covariance, rate_sigma)?;
    prior.rates = rates;
    Ok(prior)
}

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
