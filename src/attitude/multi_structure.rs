//! The multi-structure filter of paper 000 (its conclusion): three six-state filters on the
//! baseline pairs {12, 23}, {12, 13}, {23, 13}, and a robust combination of their outputs.
//!
//! **Combination rule** ([`fuse`]). Each structure `k` whose direction cosines can be
//! orthonormalized reports an attitude `C_k` and an attitude-error covariance `P_k` (body
//! axes); one whose kept columns have collapsed (this happens to the two structures with `b₁₃`
//! under the literal noise reading, whose baselines are only 2° apart) reports nothing.
//! 1. The structures are ranked by the precision their geometry allows: the trace of the
//!    steady-state covariance [`steady_state_attitude_covariance`](super::direction_cosine::DirectionCosineModel::steady_state_attitude_covariance)
//!    (fixed, attitude independent). The anchor is the best-ranked reporting structure whose
//!    innovation passed its gate (health not [`FilterHealth::InnovationOutlier`]); if none
//!    passed, the best-ranked reporting one. `θ_k = log(C_anchorᵀ C_k)`. (Ranking by the
//!    filters' own covariances fails when a state has left SO(3): its covariance is then
//!    meaningless, typically too small.)
//! 2. Another structure enters when it is *sound* — its innovation inside its gate and its
//!    direction cosines within their covariance of the rotation constraints (health neither
//!    [`FilterHealth::InnovationOutlier`] nor [`FilterHealth::ConstraintViolated`]) — and
//!    agrees with the anchor:
//!    `(θ_k − θ_a)ᵀ (P_k + P_a)⁻¹ (θ_k − θ_a)` inside the 99.9 % χ²₃ gate. The anchor
//!    always enters. (No majority vote: the structures share baselines — each baseline feeds
//!    two of them — so two structures that agree with each other may share one bad baseline;
//!    a bad baseline shows in the NIS of the two structures that use it.)
//! 3. The entrants are combined with information weights,
//!    `θ = (Σ P_k⁻¹)⁻¹ Σ P_k⁻¹ θ_k`, and the reported covariance is that of **covariance
//!    intersection** with equal weights, `n · (Σ P_k⁻¹)⁻¹` for `n` entrants: the structures'
//!    errors are correlated through the shared baselines by an amount the filter does not
//!    know, and `(Σ P_k⁻¹)⁻¹` alone would be optimistic.
//! 4. `C = C_anchor · exp([θ]×)`. Health is [`FilterHealth::StructuresDisagree`] when fewer
//!    than three structures entered, otherwise the worst health of the three.

use nalgebra::{Cholesky, Matrix3, SMatrix, Vector3};

use crate::attitude::dcm_filter::DcmError;
use crate::ekf::{chi_square_quantile, GateConfidence};
use crate::geometry::{log_so3, Quaternion};
use crate::{real, Real};

use super::array::{AntennaArray, BaselinePair};
use super::baseline_epoch::BaselineEpoch;
use super::dcm_filter::{symmetrize, DcmFilterConfig, DirectionCosineFilter};
use super::direction_cosine::ColumnChoice;
use super::filter_estimate::{FilterEstimate, FilterHealth};

/// The baseline pairs of the three structures, in order.
pub const STRUCTURE_PAIRS: [[BaselinePair; 2]; 3] = [
    [BaselinePair::P12, BaselinePair::P23],
    [BaselinePair::P12, BaselinePair::P13],
    [BaselinePair::P23, BaselinePair::P13],
];

/// The combined estimate and what each structure reported.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MultiStructureEstimate<T = f32> {
    /// The robust combination (its `nis` is the mean NIS of the structures that entered it,
    /// 6 degrees of freedom).
    pub fused: FilterEstimate<T>,
    /// The estimates of the structures on [`STRUCTURE_PAIRS`], in order; `None` for a
    /// structure whose direction cosines could not be orthonormalized this epoch.
    pub structures: [Option<FilterEstimate<T>>; 3],
    /// Which structures entered the combination.
    pub inliers: [bool; 3],
}

/// Three six-state filters and their combination.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MultiStructureFilter<T: Real = f32> {
    filters: [DirectionCosineFilter<T>; 3],
    /// Trace of each structure's steady-state attitude covariance for unit `σ_z²` (rad²/m²):
    /// the geometric ranking of step 1.
    geometric_trace: [T; 3],
}

impl<T: Real> MultiStructureFilter<T> {
    /// Three filters on [`STRUCTURE_PAIRS`], each configured like `template` except for its
    /// pair, all starting at `c_rb0` with covariance `r0`.
    ///
    /// # Errors
    /// As [`DirectionCosineFilter::new`] for any of the three.
    pub fn new(
        array: &AntennaArray<T>,
        template: DcmFilterConfig<T>,
        c_rb0: &Matrix3<T>,
        r0: &SMatrix<T, 6, 6>,
    ) -> Result<Self, DcmError> {
        let make = |pairs: [BaselinePair; 2]| {
            DirectionCosineFilter::new(array, DcmFilterConfig { pairs, ..template }, c_rb0, r0)
        };
        let [a, b, c] = STRUCTURE_PAIRS;
        let filters = [make(a)?, make(b)?, make(c)?];
        let mut geometric_trace = [T::zero(); 3];
        for (t, f) in geometric_trace.iter_mut().zip(&filters) {
            *t = f
                .model()
                .steady_state_attitude_covariance(T::one())
                .ok_or(DcmError::SingularJacobian)?
                .trace();
        }
        Ok(Self {
            filters,
            geometric_trace,
        })
    }

    /// A filter for the paper's experiment: the column choice of `columns` on all three pairs.
    ///
    /// # Errors
    /// As [`Self::new`].
    pub fn with_columns(
        array: &AntennaArray<T>,
        columns: ColumnChoice,
        dt: T,
        sigma_baseline: T,
        sigma_velocity: T,
        c_rb0: &Matrix3<T>,
        r0: &SMatrix<T, 6, 6>,
    ) -> Result<Self, DcmError> {
        let template = DcmFilterConfig {
            columns,
            ..DcmFilterConfig::paper(dt, sigma_baseline, sigma_velocity)
        };
        Self::new(array, template, c_rb0, r0)
    }

    /// The three structure filters, in the order of [`STRUCTURE_PAIRS`].
    pub fn structures(&self) -> &[DirectionCosineFilter<T>; 3] {
        &self.filters
    }

    /// Propagates the three filters (all or none: the epoch must carry the three baselines
    /// and velocity differences), forms their estimates and combines them.
    ///
    /// # Errors
    /// The first error of a structure's [`DirectionCosineFilter::propagate`], or of [`fuse`]
    /// (no structure could be orthonormalized). The filter is unchanged on error.
    pub fn step(
        &mut self,
        epoch: &BaselineEpoch<T>,
    ) -> Result<MultiStructureEstimate<T>, DcmError> {
        let mut next = self.filters.clone();
        for f in next.iter_mut() {
            f.propagate(epoch)?;
        }
        let structures = next.each_ref().map(|f| f.estimate().ok());
        let (fused, inliers) = fuse(&structures, &self.geometric_trace)?;
        self.filters = next;
        Ok(MultiStructureEstimate {
            fused,
            structures,
            inliers,
        })
    }
}

/// The combination rule of the module documentation, with the structures ranked by
/// `geometric_trace` (smaller is better). Returns the combined estimate and which structures
/// entered it.
///
/// # Errors
/// [`DcmError::NotARotation`] when no structure reports; [`DcmError::NotPositiveDefinite`]
/// when a covariance has no Cholesky factor.
pub fn fuse<T: Real>(
    estimates: &[Option<FilterEstimate<T>>; 3],
    geometric_trace: &[T; 3],
) -> Result<(FilterEstimate<T>, [bool; 3]), DcmError> {
    // 1. anchor: the best-ranked reporting structure whose innovation passed its gate
    let (anchor_index, anchor) = most_precise(estimates, geometric_trace, true)
        .or_else(|| most_precise(estimates, geometric_trace, false))
        .ok_or(DcmError::NotARotation)?;
    let gate: T = real(chi_square_quantile(3, GateConfidence::P999).unwrap_or(16.27));
    // 2. the structures that agree with the anchor, 3. information-weighted
    let mut inliers = [false; 3];
    let mut info = Matrix3::<T>::zeros();
    let mut info_theta = Vector3::<T>::zeros();
    // (indices from `0..3`, not `enumerate`: its counter keeps an overflow check)
    for (k, (e, inlier)) in (0..3).zip(estimates.iter().zip(inliers.iter_mut())) {
        let Some(e) = e else { continue };
        let theta = log_so3(&(anchor.c_rb.transpose() * e.c_rb))?;
        let sound = !matches!(
            e.health,
            FilterHealth::InnovationOutlier | FilterHealth::ConstraintViolated
        );
        let enters = if k == anchor_index {
            true
        } else if !sound {
            false
        } else {
            let ch = Cholesky::new(symmetrize(&(e.covariance + anchor.covariance)))
                .ok_or(DcmError::NotPositiveDefinite)?;
            theta.dot(&ch.solve(&theta)) <= gate
        };
        if enters {
            let ch =
                Cholesky::new(symmetrize(&e.covariance)).ok_or(DcmError::NotPositiveDefinite)?;
            let p_inv = ch.inverse();
            info += p_inv;
            info_theta += p_inv * theta;
            *inlier = true;
        }
    }
    let count = crate::count(inliers.iter().filter(|&&i| i));
    let ch = Cholesky::new(symmetrize(&info)).ok_or(DcmError::NotPositiveDefinite)?;
    let theta = ch.solve(&info_theta);
    let covariance = ch.inverse() * real::<T>(count as f64);
    // 4. health, NIS, attitude
    let health = fused_health(estimates, count);
    let (sum, n) = estimates
        .iter()
        .zip(inliers)
        .filter_map(|(e, i)| e.filter(|_| i))
        .fold((T::zero(), 0u32), |(s, n), e| {
            (s + e.nis, n.saturating_add(1))
        }); // (at most 3)
    let nis = sum / real::<T>(f64::from(n.max(1)));
    let q = (anchor.q_rb * Quaternion::from_rotation_vector(&theta)).normalize()?;
    let fused = FilterEstimate::from_rotation(q.to_dcm(), symmetrize(&covariance), nis, 6, health)?;
    Ok((fused, inliers))
}

/// The reporting structure with the smallest `geometric_trace`; with `gated_only`, among
/// those whose innovation passed its gate. Returns its index and estimate.
fn most_precise<'a, T: Real>(
    estimates: &'a [Option<FilterEstimate<T>>; 3],
    geometric_trace: &[T; 3],
    gated_only: bool,
) -> Option<(usize, &'a FilterEstimate<T>)> {
    (0..3)
        .zip(estimates.iter().zip(geometric_trace))
        .filter_map(|(k, (e, t))| e.as_ref().map(|e| (k, e, *t)))
        .filter(|(_, e, _)| !gated_only || e.health != FilterHealth::InnovationOutlier)
        .fold(
            None::<(usize, &FilterEstimate<T>, T)>,
            |best, (k, e, t)| match best {
                Some((_, _, bt)) if !(t < bt) => best,
                _ => Some((k, e, t)),
            },
        )
        .map(|(k, e, _)| (k, e))
}

/// The fused estimate's health: structures disagree when fewer than three entered, else the
/// last non-nominal health of any structure, else nominal.
fn fused_health<T: Real>(
    estimates: &[Option<FilterEstimate<T>>; 3],
    inliers: usize,
) -> FilterHealth {
    if inliers < 3 {
        return FilterHealth::StructuresDisagree;
    }
    estimates
        .iter()
        .flatten()
        .map(|e| e.health)
        .filter(|h| *h != FilterHealth::Nominal)
        .last()
        .unwrap_or(FilterHealth::Nominal)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::rot_z;

    /// The paper geometry's ranking: the {12, 23} structure first.
    const RANK: [f64; 3] = [1.0, 2.0, 2.1];

    fn estimate(angle: f64, sigma: f64) -> FilterEstimate<f64> {
        FilterEstimate::from_rotation(
            rot_z(angle),
            Matrix3::identity() * sigma * sigma,
            6.0,
            6,
            FilterHealth::Nominal,
        )
        .unwrap()
    }

    #[test]
    fn agreeing_structures_are_averaged_by_information() {
        let (fused, inliers) = fuse(
            &[
                Some(estimate(0.0, 0.01)),
                Some(estimate(0.01, 0.01)),
                Some(estimate(0.005, 0.02)),
            ],
            &RANK,
        )
        .unwrap();
        assert_eq!(inliers, [true; 3]);
        let yaw = fused.euler.yaw;
        // weights 4 : 4 : 1 → (0 + 0.04 + 0.005) / 9
        assert!((yaw - 0.045 / 9.0).abs() < 1e-9, "{yaw}");
        // covariance intersection: 3 · (Σ P⁻¹)⁻¹ = 3 / (1e4 + 1e4 + 2.5e3)
        assert!((fused.covariance[(2, 2)] - 3.0 / 22_500.0).abs() < 1e-12);
        assert_eq!(fused.health, FilterHealth::Nominal);
    }

    #[test]
    fn an_outlier_structure_is_left_out() {
        let (fused, inliers) = fuse(
            &[
                Some(estimate(0.0, 0.01)),
                Some(estimate(0.5, 0.01)),
                Some(estimate(0.01, 0.01)),
            ],
            &RANK,
        )
        .unwrap();
        assert_eq!(inliers, [true, false, true]);
        assert!((fused.euler.yaw - 0.005).abs() < 1e-9);
        assert_eq!(fused.health, FilterHealth::StructuresDisagree);
        // two that agree with each other do not outvote the more precise anchor
        let (anchored, inliers) = fuse(
            &[
                Some(estimate(0.0, 0.001)),
                Some(estimate(0.5, 0.002)),
                Some(estimate(0.5, 0.002)),
            ],
            &RANK,
        )
        .unwrap();
        assert_eq!(inliers, [true, false, false]);
        assert!(anchored.euler.yaw.abs() < 1e-9);
        // an anchor whose own innovation failed its gate gives way to the next most precise
        let mut suspect = estimate(0.0, 0.001);
        suspect.health = FilterHealth::InnovationOutlier;
        let (_, inliers) = fuse(
            &[
                Some(suspect),
                Some(estimate(0.5, 0.002)),
                Some(estimate(0.5, 0.002)),
            ],
            &RANK,
        )
        .unwrap();
        assert_eq!(inliers, [false, true, true]);
        // the anchor is chosen by geometry: a structure claiming a tiny covariance does not
        // take over (its state may have left SO(3))
        let (ranked, inliers) = fuse(
            &[
                Some(estimate(0.0, 0.01)),
                Some(estimate(0.5, 1e-4)),
                Some(estimate(0.5, 1e-4)),
            ],
            &RANK,
        )
        .unwrap();
        assert_eq!(inliers, [true, false, false]);
        assert!(ranked.euler.yaw.abs() < 1e-9);
        // a structure that does not report is left out; none reporting is an error
        let (two, inliers) = fuse(
            &[None, Some(estimate(0.1, 0.01)), Some(estimate(0.11, 0.01))],
            &RANK,
        )
        .unwrap();
        assert_eq!(inliers, [false, true, true]);
        assert!((two.euler.yaw - 0.105).abs() < 1e-9);
        assert_eq!(
            fuse::<f64>(&[None, None, None], &RANK),
            Err(DcmError::NotARotation)
        );
    }
}
