//! The corrected six-state direction-cosine model of paper 000.
//!
//! The state is two columns of the body-to-ECEF DCM `M`; the third is their cross product
//! (corrected eq. (2)). With the paper's choice the state is
//! `Y = (m₁₂, m₁₃, m₂₂, m₂₃, m₃₂, m₃₃)` — columns `c₂`, `c₃` interleaved by row — and
//! `c₁ = c₂ × c₃`. The paper's printed cofactor `m₂₁ = m₁₂m₃₃ − m₁₃m₃₂` has the wrong sign
//! (erratum 1): with it `M(Y)` is not a rotation.
//!
//! * Observation (8)/(9): `H(Y) = [M(Y) b₁ ; M(Y) b₂]` for the filter's two baselines.
//! * Jacobian (corrected (5)): `Φ(Y) = ∂H/∂Y`. In block form, for a baseline `(x, y, z)` and
//!   the state split into `(c₂, c₃)`, the three rows are `[y I − x[c₃]× , z I + x[c₂]×]`,
//!   which is the spec's corrected table.
//! * Dynamics (6): `Ẏ = Φ⁻¹(Y) V̂`; its Jacobian `F_Y = −Φ⁻¹ [(∂Φ/∂Y₁)Ẏ … (∂Φ/∂Y₆)Ẏ]`, where
//!   `Φ` is linear in `Y`, so that `[(∂Φ/∂Y_j) a]_j` has the closed form
//!   `x [−[a₃]× , [a₂]×]` per baseline ([`DirectionCosineModel::jacobian_product`]).
//!
//! **Singular geometry.** With `n = b₁ × b₂` (body axes), `|det Φ| = |n₁| · |n|²` on SO(3) for
//! the paper's choice: `Φ` is singular at every attitude when the body x axis lies in the
//! antenna plane. [`ColumnChoice::LargestNormal`] applies the spec's fix: it eliminates the
//! column `k` whose body axis has the largest `|n_k|`, relabelling the body axes cyclically
//! (`k, k+1, k+2`), which keeps the cross-product relation `c_k = c_{k+1} × c_{k+2}`.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::attitude::dcm_filter::DcmError;
use crate::geometry::{skew, vee};
use crate::{real, Real};

pub(crate) use crate::linalg::givens_inverse;

/// Which column of `M` the state leaves out (and recovers as the cross product of the other
/// two).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ColumnChoice {
    /// The paper's choice: `c₁ = c₂ × c₃`, state `(m₁₂, m₁₃, m₂₂, m₂₃, m₃₂, m₃₃)`. Singular
    /// when `n_x = 0` (e.g. an array in the body xy- or xz-plane).
    Paper,
    /// The spec's fix: leave out column `k = argmax |n_k|` (cyclic relabelling of the body
    /// axes), which maximizes `|det Φ| = |n_k| · |n|²`.
    LargestNormal,
}

/// Smallest accepted `|n_k| / (|b₁| |b₂|)` (the sine of the baselines' angle times the
/// direction cosine of the eliminated axis with the array normal). Below it `Φ` is singular to
/// working precision at every attitude and the model is refused with
/// [`DcmError::SingularGeometry`]. The paper's geometry has 0.039 (pair 12/23) and 0.020
/// (pairs with b₁₃).
pub const MIN_NORMAL_RATIO: f64 = 5e-3;

/// The six-state model for one pair of baselines.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DirectionCosineModel<T = f32> {
    /// Eliminated column `k` (0-based body axis).
    eliminated: usize,
    /// The two baselines in the relabelled body axes `(k, k+1, k+2)`, metres.
    baselines: [Vector3<T>; 2],
    /// `|n_k| / (|b₁| |b₂|)` for the eliminated axis.
    normal_ratio: T,
}

/// Relabels body-axis components cyclically so that axis `k` comes first.
fn to_model_axes<T: Real>(v: &Vector3<T>, k: usize) -> Vector3<T> {
    Vector3::from_fn(|j, _| v[(k % 3 + j) % 3])
}

/// Inverse of [`to_model_axes`].
fn from_model_axes<T: Real>(v: &Vector3<T>, k: usize) -> Vector3<T> {
    Vector3::from_fn(|i, _| v[(i + 3 - k % 3) % 3])
}

/// Index in `Y` of row `i` of column `c₂` (`second = false`) or `c₃` (`second = true`).
fn y_index(i: usize, second: bool) -> usize {
    2 * i + usize::from(second)
}

impl<T: Real> DirectionCosineModel<T> {
    /// The model for baselines `b₁`, `b₂` (body axes, metres; the paper's `b₁₂`, `b₂₃`).
    ///
    /// # Errors
    /// [`DcmError::NonFinite`]; [`DcmError::ZeroLengthBaseline`] for a baseline shorter than
    /// [`super::array::MIN_BASELINE_LENGTH`]; [`DcmError::SingularGeometry`] when
    /// `|n_k| / (|b₁||b₂|) <` [`MIN_NORMAL_RATIO`] for the chosen column.
    pub fn new(b1: &Vector3<T>, b2: &Vector3<T>, choice: ColumnChoice) -> Result<Self, DcmError> {
        if !b1.iter().chain(b2.iter()).all(|v| v.is_finite()) {
            return Err(DcmError::NonFinite);
        }
        let min_len: T = real(super::array::MIN_BASELINE_LENGTH);
        if !(b1.norm() >= min_len) || !(b2.norm() >= min_len) {
            return Err(DcmError::ZeroLengthBaseline);
        }
        let n = b1.cross(b2);
        let eliminated = match choice {
            ColumnChoice::Paper => 0,
            ColumnChoice::LargestNormal => n.iamax(),
        };
        let n_k = n.get(eliminated).copied().unwrap_or_else(T::zero);
        let normal_ratio = n_k.abs() / (b1.norm() * b2.norm());
        if !(normal_ratio >= real(MIN_NORMAL_RATIO)) {
            return Err(DcmError::SingularGeometry);
        }
        Ok(Self {
            eliminated,
            baselines: [to_model_axes(b1, eliminated), to_model_axes(b2, eliminated)],
            normal_ratio,
        })
    }

    /// The eliminated column (0-based body axis): 0 for [`ColumnChoice::Paper`].
    pub fn eliminated_column(&self) -> usize {
        self.eliminated
    }

    /// `|n_k| / (|b₁||b₂|)` of the eliminated axis: how far the geometry is from singular.
    pub fn normal_ratio(&self) -> T {
        self.normal_ratio
    }

    /// The state `Y` of a body-to-reference DCM (its two kept columns, interleaved by row).
    pub fn state_from_dcm(&self, c_rb: &Matrix3<T>) -> SVector<T, 6> {
        let k = self.eliminated % 3; // (0–2 by construction; the bound made visible)
        let c2 = c_rb.column((k + 1) % 3);
        let c3 = c_rb.column((k + 2) % 3);
        SVector::<T, 6>::new(c2[0], c3[0], c2[1], c3[1], c2[2], c3[2])
    }

    /// The kept columns `(c₂, c₃)` of the state, in the model's (relabelled) body axes.
    fn columns(y: &SVector<T, 6>) -> (Vector3<T>, Vector3<T>) {
        (
            Vector3::new(y[0], y[2], y[4]),
            Vector3::new(y[1], y[3], y[5]),
        )
    }

    /// `M(Y)` in the model's relabelled axes: `[c₂ × c₃, c₂, c₃]` (corrected eq. (2)).
    fn dcm_model_axes(y: &SVector<T, 6>) -> Matrix3<T> {
        let (c2, c3) = Self::columns(y);
        Matrix3::from_columns(&[c2.cross(&c3), c2, c3])
    }

    /// `M(Y)`, body to reference, in the original body axes (corrected eq. (2)). It is a
    /// rotation only when the two kept columns are orthonormal.
    pub fn dcm(&self, y: &SVector<T, 6>) -> Matrix3<T> {
        let m = Self::dcm_model_axes(y);
        let k = self.eliminated % 3; // (0–2 by construction; the bound made visible)
                                     // column (k + j) mod 3 of M is column j of the relabelled matrix
        Matrix3::from_fn(|r, c| m[(r, (c + 3 - k) % 3)])
    }

    /// `H(Y) = [M(Y) b₁ ; M(Y) b₂]`, reference frame, metres (eqs. (8), (9)).
    pub fn observation(&self, y: &SVector<T, 6>) -> SVector<T, 6> {
        let m = Self::dcm_model_axes(y);
        let [b1, b2] = self.baselines;
        let (z1, z2) = (m * b1, m * b2);
        SVector::<T, 6>::new(z1.x, z1.y, z1.z, z2.x, z2.y, z2.z)
    }

    /// `Φ(Y) = ∂H/∂Y` (corrected eq. (5)): per baseline `(x, y, z)` the rows
    /// `[y I − x[c₃]× , z I + x[c₂]×]` acting on `(δc₂, δc₃)`.
    pub fn jacobian(&self, y: &SVector<T, 6>) -> SMatrix<T, 6, 6> {
        let (c2, c3) = Self::columns(y);
        let mut phi = SMatrix::<T, 6, 6>::zeros();
        for (p, b) in self.baselines.iter().enumerate() {
            let a = Matrix3::identity() * b.y - skew(&c3) * b.x; // ∂(M b)/∂c₂
            let d = Matrix3::identity() * b.z + skew(&c2) * b.x; // ∂(M b)/∂c₃
            fill_blocks(&mut phi, 3 * p, &a, &d);
        }
        phi
    }

    /// `[(∂Φ/∂Y₁) a, …, (∂Φ/∂Y₆) a]` for a state-space vector `a`: the derivative of `Φ(Y) a`
    /// with respect to `Y` (constant in `Y`, since `Φ` is linear in `Y`). Per baseline
    /// `x [−[a₃]× , [a₂]×]` with `a = (a₂, a₃)` split like the state. With `a = Ẏ` it gives
    /// `F_Y = −Φ⁻¹ · jacobian_product(Ẏ)` of eq. (10).
    pub fn jacobian_product(&self, a: &SVector<T, 6>) -> SMatrix<T, 6, 6> {
        let (a2, a3) = Self::columns(a);
        let mut g = SMatrix::<T, 6, 6>::zeros();
        for (p, b) in self.baselines.iter().enumerate() {
            let d2 = -skew(&a3) * b.x; // ∂(x c₂ × a₃)/∂c₂
            let d3 = skew(&a2) * b.x; // ∂(x a₂ × c₃)/∂c₃
            fill_blocks(&mut g, 3 * p, &d2, &d3);
        }
        g
    }

    /// The steady-state attitude-error covariance of the six-state filter on this geometry
    /// (body axes, rad²), to first order: `σ_z² L Lᵀ` with `L = (∂θ/∂Y) Φ⁻¹`, evaluated at any
    /// rotation (it does not depend on the attitude), `σ_z² = σ_p σ_v Δt` the steady-state
    /// variance of each baseline component (m²). `None` if `Φ` is singular.
    pub fn steady_state_attitude_covariance(&self, sigma_z2: T) -> Option<Matrix3<T>> {
        let y = self.state_from_dcm(&Matrix3::identity());
        let (phi_inv, _) = givens_inverse(&self.jacobian(&y))?;
        let l = self.attitude_jacobian(&Matrix3::identity(), &y) * phi_inv;
        Some(l * l.transpose() * sigma_z2)
    }

    /// The rotation constraints of the state, `g(Y) = (|c₂|² − 1, |c₃|² − 1, c₂·c₃)`: zero for
    /// every state of a rotation, whatever the attitude.
    pub fn constraint_residual(y: &SVector<T, 6>) -> Vector3<T> {
        let (c2, c3) = Self::columns(y);
        Vector3::new(
            c2.norm_squared() - T::one(),
            c3.norm_squared() - T::one(),
            c2.dot(&c3),
        )
    }

    /// `∂g/∂Y` (3×6) of [`Self::constraint_residual`]: rows `(2c₂ᵀ, 0)`, `(0, 2c₃ᵀ)`,
    /// `(c₃ᵀ, c₂ᵀ)` in the `(c₂, c₃)` split, interleaved like the state.
    pub fn constraint_jacobian(y: &SVector<T, 6>) -> SMatrix<T, 3, 6> {
        let (c2, c3) = Self::columns(y);
        let two: T = real(2.0);
        let mut g = SMatrix::<T, 3, 6>::zeros();
        for i in 0..3 {
            let (a, b) = (c2[i], c3[i]);
            for (row, (d2, d3)) in [(a * two, T::zero()), (T::zero(), b * two), (b, a)]
                .into_iter()
                .enumerate()
            {
                if let Some(v) = g.get_mut((row, y_index(i, false))) {
                    *v = d2;
                }
                if let Some(v) = g.get_mut((row, y_index(i, true))) {
                    *v = d3;
                }
            }
        }
        g
    }

    /// `∂θ/∂Y` (3×6): the body-axes rotation vector `θ = vee(skew(Ĉᵀ δM))` of a state
    /// perturbation `δY` about the attitude `c_hat` (a proper rotation close to `M(Y)`). Maps
    /// the state covariance to the attitude-error covariance `S R Sᵀ`.
    pub fn attitude_jacobian(&self, c_hat: &Matrix3<T>, y: &SVector<T, 6>) -> SMatrix<T, 3, 6> {
        let k = self.eliminated % 3; // (0–2 by construction; the bound made visible)
        let c_model = Matrix3::from_fn(|r, c| c_hat[(r, (c + k) % 3)]);
        let (c2, c3) = Self::columns(y);
        let half: T = real(0.5);
        let mut s = SMatrix::<T, 3, 6>::zeros();
        for i in 0..3 {
            let e = Vector3::from_fn(|r, _| if r == i { T::one() } else { T::zero() });
            for second in [false, true] {
                // δM for δc₂ = e (or δc₃ = e): columns (e × c₃, e, 0) or (c₂ × e, 0, e)
                let dm = if second {
                    Matrix3::from_columns(&[c2.cross(&e), Vector3::zeros(), e])
                } else {
                    Matrix3::from_columns(&[e.cross(&c3), e, Vector3::zeros()])
                };
                let ed = c_model.transpose() * dm;
                let theta = from_model_axes(&vee(&((ed - ed.transpose()) * half)), k);
                s.set_column(y_index(i, second), &theta);
            }
        }
        s
    }
}

/// Writes the 3×3 blocks `a` (for `c₂`) and `d` (for `c₃`) into rows `row..row+3` of a 6×6
/// matrix whose columns follow the interleaved state order.
fn fill_blocks<T: Real>(m: &mut SMatrix<T, 6, 6>, row: usize, a: &Matrix3<T>, d: &Matrix3<T>) {
    for r in 0..3 {
        for i in 0..3 {
            if let Some(v) = m.get_mut((row + r, y_index(i, false))) {
                *v = a[(r, i)];
            }
            if let Some(v) = m.get_mut((row + r, y_index(i, true))) {
                *v = d[(r, i)];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{rot_x, rot_y, rot_z};

    fn paper_baselines() -> (Vector3<f64>, Vector3<f64>) {
        (Vector3::new(1.5, 1.8, 1.9), Vector3::new(1.7, 1.7, 2.0))
    }

    fn rotation(a: f64) -> Matrix3<f64> {
        rot_z(0.7 * a) * rot_y(-0.4 + a) * rot_x(2.1 - 0.3 * a)
    }

    #[test]
    fn model_reproduces_the_rotation_and_the_paper_determinant() {
        let (b1, b2) = paper_baselines();
        for choice in [ColumnChoice::Paper, ColumnChoice::LargestNormal] {
            let model = DirectionCosineModel::new(&b1, &b2, choice).unwrap();
            let n = b1.cross(&b2);
            let k = model.eliminated_column();
            for a in [0.0, 0.5, 1.3, -2.0] {
                let c = rotation(a);
                let y = model.state_from_dcm(&c);
                assert!((model.dcm(&y) - c).norm() < 1e-14);
                let h = model.observation(&y);
                assert!((h.fixed_rows::<3>(0) - c * b1).norm() < 1e-14);
                assert!((h.fixed_rows::<3>(3) - c * b2).norm() < 1e-14);
                // |det Φ| = |n_k| |n|² on SO(3), independent of the attitude
                let det = model.jacobian(&y).determinant().abs();
                assert!((det - n[k].abs() * n.norm_squared()).abs() < 1e-12);
            }
        }
        let paper = DirectionCosineModel::new(&b1, &b2, ColumnChoice::Paper).unwrap();
        let y = paper.state_from_dcm(&Matrix3::identity());
        assert!((paper.jacobian(&y).determinant() + 0.16646).abs() < 1e-5);
    }

    #[test]
    fn jacobians_match_finite_differences() {
        let (b1, b2) = paper_baselines();
        let model = DirectionCosineModel::new(&b1, &b2, ColumnChoice::Paper).unwrap();
        // off SO(3) on purpose: the formulas hold for any Y
        let y = model.state_from_dcm(&rotation(0.4))
            + SVector::<f64, 6>::from_fn(|i, _| 0.01 * i as f64);
        let a = SVector::<f64, 6>::from_fn(|i, _| (i as f64 + 1.0).cos());
        let phi = model.jacobian(&y);
        let g = model.jacobian_product(&a);
        let eps = 1e-6;
        for j in 0..6 {
            let mut d = SVector::<f64, 6>::zeros();
            d[j] = eps;
            let dh = (model.observation(&(y + d)) - model.observation(&(y - d))) / (2.0 * eps);
            assert!((dh - phi.column(j)).norm() < 1e-8, "Φ column {j}");
            let dphi_a =
                (model.jacobian(&(y + d)) * a - model.jacobian(&(y - d)) * a) / (2.0 * eps);
            assert!((dphi_a - g.column(j)).norm() < 1e-8, "∂Φ/∂Y column {j}");
            let dg = (DirectionCosineModel::<f64>::constraint_residual(&(y + d))
                - DirectionCosineModel::<f64>::constraint_residual(&(y - d)))
                / (2.0 * eps);
            let cj = DirectionCosineModel::<f64>::constraint_jacobian(&y);
            assert!((dg - cj.column(j)).norm() < 1e-8, "∂g/∂Y column {j}");
        }
        let on = model.state_from_dcm(&rotation(0.9));
        assert!(DirectionCosineModel::<f64>::constraint_residual(&on).norm() < 1e-14);
    }

    #[test]
    fn attitude_jacobian_matches_a_small_rotation() {
        let (b1, b2) = paper_baselines();
        for choice in [ColumnChoice::Paper, ColumnChoice::LargestNormal] {
            let model = DirectionCosineModel::new(&b1, &b2, choice).unwrap();
            let c = rotation(1.1);
            let y = model.state_from_dcm(&c);
            let s = model.attitude_jacobian(&c, &y);
            let theta = Vector3::new(1e-6, -2e-6, 3e-6);
            let y2 = model.state_from_dcm(&(c * (Matrix3::identity() + skew(&theta))));
            assert!((s * (y2 - y) - theta).norm() < 1e-11);
        }
    }

    #[test]
    fn singular_geometry_is_refused_and_column_reselection_fixes_a_planar_array() {
        // array in the body xy-plane: n along z, n_x = 0 for every attitude
        let b1 = Vector3::new(1.0, 0.0, 0.0);
        let b2 = Vector3::new(-0.5, 0.866, 0.0);
        assert_eq!(
            DirectionCosineModel::new(&b1, &b2, ColumnChoice::Paper),
            Err(DcmError::SingularGeometry)
        );
        let model = DirectionCosineModel::new(&b1, &b2, ColumnChoice::LargestNormal).unwrap();
        assert_eq!(model.eliminated_column(), 2);
        let c = rotation(0.2);
        let y = model.state_from_dcm(&c);
        assert!((model.dcm(&y) - c).norm() < 1e-14);
        assert!(givens_inverse(&model.jacobian(&y)).is_some());
        // parallel baselines are singular for every choice
        assert_eq!(
            DirectionCosineModel::new(&b1, &(b1 * 2.0), ColumnChoice::LargestNormal),
            Err(DcmError::SingularGeometry)
        );
    }
}
