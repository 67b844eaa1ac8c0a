//! The multi-structure filter of paper 000 (its conclusion): three six-state filters on the
//! baseline pairs {12, 23}, {12, 13}, {23, 13}, and a robust combination of their outputs.
//!
//! **Combination rule** ([`fuse`]). Each structure `k` whose direction cosines can be
//! orthonormalized reports an attitude `C_k` and an attitude-error covariance `P_k` (body
//! axes); one whose kept columns have collapsed (this happens to the two structures with `b₁₃`
//! under the literal noise reading, whose baselines are only 2° apart) reports nothing.
//! 1. The reference is the reporting structure with the smallest `tr P_k`;
//!    `θ_k = log(C_refᵀ C_k)`.
//! 2. Two structures agree when `(θ_k − θ_l)ᵀ (P_k + P_l)⁻¹ (θ_k − θ_l)` is inside the 99.9 %
//!    χ²₃ gate. A structure that agrees with at least one other is an inlier.
//! 3. The inliers are combined with information weights,
//!    `θ = (Σ P_k⁻¹)⁻¹ Σ P_k⁻¹ θ_k`, and the reported covariance is that of **covariance
//!    intersection** with equal weights, `n · (Σ P_k⁻¹)⁻¹` for `n` inliers: the structures
//!    share baselines (each baseline feeds two of them), so their errors are correlated by an
//!    amount the filter does not know, and `(Σ P_k⁻¹)⁻¹` alone would be optimistic.
//! 4. If no two agree, the reporting structure with the smallest sum of distances to the
//!    others (the medoid; ties and a lone reporter: the smallest `tr P_k`) is used alone.
//! 5. `C = C_ref · exp([θ]×)`. Health is [`FilterHealth::StructuresDisagree`] when fewer than
//!    three structures entered the combination, otherwise the worst health of the three.

use nalgebra::{Cholesky, Matrix3, SMatrix, Vector3};

use crate::ekf::{chi_square_quantile, GateConfidence};
use crate::error::DcmError;
use crate::geometry::{log_so3, Quaternion};
use crate::{real, Real};

use super::baseline_epoch::{AntennaArray, BaselineEpoch, BaselinePair};
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
pub struct MultiStructureFilter<T: Real = f32> {
    filters: [DirectionCosineFilter<T>; 3],
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
        Ok(Self {
            filters: [make(a)?, make(b)?, make(c)?],
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
        let (fused, inliers) = fuse(&structures)?;
        self.filters = next;
        Ok(MultiStructureEstimate {
            fused,
            structures,
            inliers,
        })
    }
}

/// A structure's rotation vector relative to the reference and its covariance.
type Tangent<T> = Option<(Vector3<T>, Matrix3<T>)>;

/// Mahalanobis distance `(θ_k − θ_l)ᵀ (P_k + P_l)⁻¹ (θ_k − θ_l)` of two reporting structures.
fn distance<T: Real>(a: &Tangent<T>, b: &Tangent<T>) -> Result<Option<T>, DcmError> {
    match (a, b) {
        (Some((ta, pa)), Some((tb, pb))) => {
            let d = ta - tb;
            let ch = Cholesky::new(symmetrize(&(pa + pb))).ok_or(DcmError::NotPositiveDefinite)?;
            Ok(Some(d.dot(&ch.solve(&d))))
        }
        _ => Ok(None),
    }
}

/// The combination rule of the module documentation. Returns the combined estimate and which
/// structures entered it.
///
/// # Errors
/// [`DcmError::NotARotation`] when no structure reports; [`DcmError::NotPositiveDefinite`]
/// when a covariance has no Cholesky factor.
pub fn fuse<T: Real>(
    estimates: &[Option<FilterEstimate<T>>; 3],
) -> Result<(FilterEstimate<T>, [bool; 3]), DcmError> {
    // 1. reference: the reporting structure with the smallest covariance trace
    let reference = estimates
        .iter()
        .flatten()
        .fold(None::<&FilterEstimate<T>>, |best, e| match best {
            Some(b) if !(e.covariance.trace() < b.covariance.trace()) => Some(b),
            _ => Some(e),
        })
        .ok_or(DcmError::NotARotation)?;
    let mut tangents: [Tangent<T>; 3] = [None; 3];
    for (slot, e) in tangents.iter_mut().zip(estimates) {
        if let Some(e) = e {
            *slot = Some((
                log_so3(&(reference.c_rb.transpose() * e.c_rb))?,
                e.covariance,
            ));
        }
    }
    // 2. pairwise agreement
    let gate: T = real(chi_square_quantile(3, GateConfidence::P999).unwrap_or(16.27));
    let [t0, t1, t2] = tangents;
    let (d01, d02, d12) = (
        distance(&t0, &t1)?,
        distance(&t0, &t2)?,
        distance(&t1, &t2)?,
    );
    let ok = |d: Option<T>| d.is_some_and(|d| d <= gate);
    let mut inliers = [ok(d01) || ok(d02), ok(d01) || ok(d12), ok(d02) || ok(d12)];
    let count = inliers.iter().filter(|&&i| i).count();
    let zero_if_none = |d: Option<T>| d.unwrap_or_else(T::zero);
    let sums = [
        zero_if_none(d01) + zero_if_none(d02),
        zero_if_none(d01) + zero_if_none(d12),
        zero_if_none(d02) + zero_if_none(d12),
    ];
    let (theta, covariance) = if count == 0 {
        // 4. no two agree: the medoid alone
        let mut best: Option<(usize, T, T)> = None;
        for (k, (t, sum)) in tangents.iter().zip(sums).enumerate() {
            if let Some((_, p)) = t {
                let better = match best {
                    None => true,
                    Some((_, s, tr)) => sum < s || (!(sum > s) && p.trace() < tr),
                };
                if better {
                    best = Some((k, sum, p.trace()));
                }
            }
        }
        let k = best.map_or(0, |b| b.0);
        if let Some(flag) = inliers.get_mut(k) {
            *flag = true;
        }
        tangents
            .get(k)
            .copied()
            .flatten()
            .ok_or(DcmError::NotARotation)?
    } else {
        // 3. information-weighted mean, covariance intersection with equal weights
        let mut info = Matrix3::<T>::zeros();
        let mut info_theta = Vector3::<T>::zeros();
        for ((tk, pk), _) in tangents
            .iter()
            .zip(inliers)
            .filter_map(|(t, i)| t.map(|t| (t, i)))
            .filter(|(_, i)| *i)
        {
            let ch = Cholesky::new(symmetrize(&pk)).ok_or(DcmError::NotPositiveDefinite)?;
            let pk_inv = ch.inverse();
            info += pk_inv;
            info_theta += pk_inv * tk;
        }
        let ch = Cholesky::new(symmetrize(&info)).ok_or(DcmError::NotPositiveDefinite)?;
        (
            ch.solve(&info_theta),
            ch.inverse() * real::<T>(count as f64),
        )
    };
    // 5. health, NIS, attitude
    let used = inliers.iter().filter(|&&i| i).count();
    let mut health = if used < 3 {
        FilterHealth::StructuresDisagree
    } else {
        FilterHealth::Nominal
    };
    if health == FilterHealth::Nominal {
        for e in estimates.iter().flatten() {
            if e.health != FilterHealth::Nominal {
                health = e.health;
            }
        }
    }
    let (sum, n) = estimates
        .iter()
        .zip(inliers)
        .filter_map(|(e, i)| e.filter(|_| i))
        .fold((T::zero(), 0u32), |(s, n), e| (s + e.nis, n + 1));
    let nis = sum / real::<T>(f64::from(n.max(1)));
    let q = (reference.q_rb * Quaternion::from_rotation_vector(&theta)).normalize()?;
    let fused = FilterEstimate::from_rotation(q.to_dcm(), symmetrize(&covariance), nis, 6, health)?;
    Ok((fused, inliers))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::rot_z;

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
        let (fused, inliers) = fuse(&[
            Some(estimate(0.0, 0.01)),
            Some(estimate(0.01, 0.01)),
            Some(estimate(0.005, 0.02)),
        ])
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
        let (fused, inliers) = fuse(&[
            Some(estimate(0.0, 0.01)),
            Some(estimate(0.5, 0.01)),
            Some(estimate(0.01, 0.01)),
        ])
        .unwrap();
        assert_eq!(inliers, [true, false, true]);
        assert!((fused.euler.yaw - 0.005).abs() < 1e-9);
        assert_eq!(fused.health, FilterHealth::StructuresDisagree);
        // no two agree: the medoid (the middle one) alone
        let (medoid, inliers) = fuse(&[
            Some(estimate(0.0, 0.001)),
            Some(estimate(0.5, 0.001)),
            Some(estimate(0.2, 0.001)),
        ])
        .unwrap();
        assert_eq!(inliers, [false, false, true]);
        assert!((medoid.euler.yaw - 0.2).abs() < 1e-9);
        // a structure that does not report is left out; none reporting is an error
        let (two, inliers) =
            fuse(&[None, Some(estimate(0.1, 0.01)), Some(estimate(0.11, 0.01))]).unwrap();
        assert_eq!(inliers, [false, true, true]);
        assert!((two.euler.yaw - 0.105).abs() < 1e-9);
        assert_eq!(
            fuse::<f64>(&[None, None, None]),
            Err(DcmError::NotARotation)
        );
    }
}
