//! The multi-structure filter of paper 000 (its conclusion): three six-state filters on the
//! baseline pairs {12, 23}, {12, 13}, {23, 13}, and a robust combination of their outputs.
//!
//! **Combination rule** ([`fuse`]). Each structure `k` reports an attitude `C_k` and an
//! attitude-error covariance `P_k` (body axes). With the first structure as reference,
//! `θ_k = log(C₁ᵀ C_k)`.
//! 1. Two structures agree when `(θ_k − θ_l)ᵀ (P_k + P_l)⁻¹ (θ_k − θ_l)` is inside the 99.9 %
//!    χ²₃ gate.
//! 2. A structure that agrees with at least one other is an inlier. If no two agree, the
//!    component-wise median of the `θ_k` is used, with the largest of the `P_k`.
//! 3. The inliers are combined with information weights,
//!    `θ = (Σ P_k⁻¹)⁻¹ Σ P_k⁻¹ θ_k`, and the reported covariance is that of **covariance
//!    intersection** with equal weights, `n · (Σ P_k⁻¹)⁻¹` for `n` inliers: the structures
//!    share baselines (each baseline feeds two of them), so their errors are correlated by an
//!    amount the filter does not know, and `(Σ P_k⁻¹)⁻¹` alone would be optimistic.
//! 4. `C = C₁ · exp([θ]×)`. Health is [`FilterHealth::StructuresDisagree`] when a structure was
//!    left out or the median was used, otherwise the worst health of the inliers.

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
    /// The robust combination (its `nis` is the mean NIS of the inlier structures, 6 degrees
    /// of freedom).
    pub fused: FilterEstimate<T>,
    /// The estimates of the structures on [`STRUCTURE_PAIRS`], in order.
    pub structures: [FilterEstimate<T>; 3],
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

    /// Steps the three filters (all or none: the epoch must carry the three baselines and
    /// velocity differences) and combines them.
    ///
    /// # Errors
    /// The first error of a structure's [`DirectionCosineFilter::step`], or of [`fuse`]. The
    /// filter is unchanged on error.
    pub fn step(
        &mut self,
        epoch: &BaselineEpoch<T>,
    ) -> Result<MultiStructureEstimate<T>, DcmError> {
        let mut next = self.filters.clone();
        let [f0, f1, f2] = &mut next;
        let structures = [f0.step(epoch)?, f1.step(epoch)?, f2.step(epoch)?];
        let (fused, inliers) = fuse(&structures)?;
        self.filters = next;
        Ok(MultiStructureEstimate {
            fused,
            structures,
            inliers,
        })
    }
}

/// The combination rule of the module documentation. Returns the combined estimate and the
/// inlier flags.
///
/// # Errors
/// [`DcmError::NotARotation`] if an attitude cannot be compared; [`DcmError::NotPositiveDefinite`]
/// if a covariance has no Cholesky factor.
pub fn fuse<T: Real>(
    estimates: &[FilterEstimate<T>; 3],
) -> Result<(FilterEstimate<T>, [bool; 3]), DcmError> {
    let [e0, e1, e2] = estimates;
    let reference = e0.c_rb;
    let theta = [
        Vector3::zeros(),
        log_so3(&(reference.transpose() * e1.c_rb))?,
        log_so3(&(reference.transpose() * e2.c_rb))?,
    ];
    let p = [e0.covariance, e1.covariance, e2.covariance];
    let gate: T = real(chi_square_quantile(3, GateConfidence::P999).unwrap_or(16.27));
    // agree[k][l]: step 1
    let [t0, t1, t2] = theta;
    let [p0, p1, p2] = p;
    let agree = |tk: Vector3<T>, pk: Matrix3<T>, tl: Vector3<T>, pl: Matrix3<T>| {
        let d = tk - tl;
        let ch = Cholesky::new(symmetrize(&(pk + pl))).ok_or(DcmError::NotPositiveDefinite)?;
        Ok::<bool, DcmError>(d.dot(&ch.solve(&d)) <= gate)
    };
    let (a01, a02, a12) = (
        agree(t0, p0, t1, p1)?,
        agree(t0, p0, t2, p2)?,
        agree(t1, p1, t2, p2)?,
    );
    let inliers = [a01 || a02, a01 || a12, a02 || a12];
    let count = inliers.iter().filter(|&&i| i).count();
    let (theta_f, covariance, mut health) = if count == 0 {
        // step 2: no two agree — component-wise median, the largest covariance
        let median = Vector3::from_fn(|i, _| {
            let c = |t: &Vector3<T>| t.get(i).copied().unwrap_or_else(T::zero);
            median3(c(&t0), c(&t1), c(&t2))
        });
        let widest = [p1, p2]
            .into_iter()
            .fold(p0, |w, pk| if pk.trace() > w.trace() { pk } else { w });
        (median, widest, FilterHealth::StructuresDisagree)
    } else {
        // step 3: information-weighted mean, covariance intersection with equal weights
        let mut info = Matrix3::<T>::zeros();
        let mut info_theta = Vector3::<T>::zeros();
        for ((tk, pk), _) in theta.iter().zip(p.iter()).zip(inliers).filter(|(_, i)| *i) {
            let ch = Cholesky::new(symmetrize(pk)).ok_or(DcmError::NotPositiveDefinite)?;
            let pk_inv = ch.inverse();
            info += pk_inv;
            info_theta += pk_inv * tk;
        }
        let ch = Cholesky::new(symmetrize(&info)).ok_or(DcmError::NotPositiveDefinite)?;
        let theta_f = ch.solve(&info_theta);
        let covariance = ch.inverse() * real::<T>(count as f64);
        let health = if count < 3 {
            FilterHealth::StructuresDisagree
        } else {
            FilterHealth::Nominal
        };
        (theta_f, covariance, health)
    };
    if health == FilterHealth::Nominal {
        // the worst health of the structures (all are inliers here)
        for e in estimates {
            if e.health != FilterHealth::Nominal {
                health = e.health;
            }
        }
    }
    // mean NIS of the structures that were used (all three for the median)
    let (sum, n) = estimates
        .iter()
        .zip(inliers)
        .filter(|(_, i)| *i || count == 0)
        .fold((T::zero(), 0u32), |(s, n), (e, _)| (s + e.nis, n + 1));
    let nis = sum / real::<T>(f64::from(n.max(1)));
    // step 4: C = C₁ exp([θ]×)
    let q = (e0.q_rb * Quaternion::from_rotation_vector(&theta_f)).normalize()?;
    let fused = FilterEstimate::from_rotation(q.to_dcm(), symmetrize(&covariance), nis, 6, health)?;
    Ok((fused, inliers))
}

/// The median of three numbers.
fn median3<T: Real>(a: T, b: T, c: T) -> T {
    a.max(b).min(a.min(b).max(c))
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
    fn median_of_three() {
        assert_eq!(median3(3.0, 1.0, 2.0), 2.0);
        assert_eq!(median3(1.0, 2.0, 3.0), 2.0);
        assert_eq!(median3(2.0, 3.0, 1.0), 2.0);
    }

    #[test]
    fn agreeing_structures_are_averaged_by_information() {
        let (fused, inliers) = fuse(&[
            estimate(0.0, 0.01),
            estimate(0.01, 0.01),
            estimate(0.005, 0.02),
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
            estimate(0.0, 0.01),
            estimate(0.5, 0.01),
            estimate(0.01, 0.01),
        ])
        .unwrap();
        assert_eq!(inliers, [true, false, true]);
        assert!((fused.euler.yaw - 0.005).abs() < 1e-9);
        assert_eq!(fused.health, FilterHealth::StructuresDisagree);
        let (median, inliers) = fuse(&[
            estimate(0.0, 0.001),
            estimate(0.5, 0.001),
            estimate(0.2, 0.001),
        ])
        .unwrap();
        assert_eq!(inliers, [false; 3]);
        assert!((median.euler.yaw - 0.2).abs() < 1e-9);
    }
}
