//! Integer ambiguity resolution from raw single-difference carrier phase and code, constrained
//! by the known antenna geometry, validated, and refusing rather than guessing.
//!
//! # Model
//!
//! One receiver clock drives every antenna, so between antenna 0 and antenna `i` the single
//! differences (SD) of satellite `j` are free of clock terms (calibrated line biases removed):
//!
//! ```text
//! λ φ_ij = s_jᵀ a_i + λ z_ij + ε_ij       (phase, cycles → metres; z_ij integer)
//!   p_ij = s_jᵀ a_i + e_ij                (code, metres)
//! Cov(ε_·j) = σ_φ² c_j Σ_B,   Cov(e_·j) = σ_p² c_j Σ_B
//! ```
//!
//! with `a_i = C_rb b_i` the reference-frame baseline, `c_j` a per-satellite cofactor and
//! `Σ_B` the baseline correlation (0.5 off the diagonal when the SDs share antenna 0).
//!
//! # Method
//!
//! 1. **Float solution** per baseline (identical design on every baseline, so per-baseline LS
//!    is the GLS): `â_i = N⁻¹ S W p_i`, `ẑ_i = φ_i − Sᵀ â_i / λ`, `N = S W Sᵀ`,
//!    `W = diag(1/c_j)`; `Cov(ẑ) = Σ_B ⊗ Q₁`, `Q₁ = (σ_φ² W⁻¹ + σ_p² Sᵀ N⁻¹ S) / λ²`.
//! 2. **LAMBDA decorrelation** of `Q₁` ([`super::lambda`]).
//! 3. **Constrained multivariate integer search** (a bounded depth-first Schnorr–Euchner search) of
//!    `min_Z F(Z) + G(Z)`, the MC-LAMBDA objective (Teunissen; Giorgi): `F` is the float
//!    distance `‖ẑ − z‖²` in the metric of `Cov(ẑ)`, and
//!    `G(Z) = min_{C ∈ SO(3)} Σ_ik (Σ_B⁻¹)_ik (ǎ_i − C b_i)ᵀ κN (ǎ_k − C b_k)` the misfit of
//!    the best rotation to the conditional baselines `ǎ_i(z_i)` (phase + code with `z_i` fixed,
//!    `κ = 1/σ_φ² + 1/σ_p²`): the known baseline lengths *and* the angles between baselines
//!    enter through `G`, computed with [`super::snapshot::SnapshotSolver`]'s Wahba + Gauss–Newton
//!    fit. `F + G` is the full-model weighted residual up to a constant. A baseline's length
//!    alone bounds `G` from below, `G ≥ (|ǎ_i| − |b_i|)² / (Σ_B,ii tr(N⁻¹)/κ)`, which prunes
//!    the tree at the end of each baseline.
//! 4. **Validation**: the best cost must pass the χ² test (99.9 %) with `M n + 3(M − 1)`
//!    degrees of freedom, and the second-best candidate must cost at least `ratio_threshold`
//!    times the best; otherwise the resolver refuses ([`AmbiguityError`]).
//! 5. The fixed phases give range differences, solved by the snapshot solver for the attitude
//!    and its covariance.
//!
//! [`SearchMode::Unconstrained`] drops `G` (plain LAMBDA integer least squares with the same
//! ratio test), for comparison.
//!
//! The search visits at most [`AmbiguityConfig::max_nodes`] tree nodes and keeps two
//! candidates (a `heapless::Vec`); on the target it uses a few kilobytes of stack for
//! `N = 12`.

use nalgebra::{SMatrix, Vector3};

use crate::attitude::snapshot::SnapshotError;
use crate::ekf::{chi_square_quantile, GateConfidence};
use crate::{real, Real};

use super::integer_search::{IntegerSearch, SearchFailure};
use super::lambda::decorrelate;
use super::range_model::{los_normal_matrix, RangeDifferences, SatelliteRanges};
pub use super::range_model::{PhaseObservations, PhaseSatellite};
use super::snapshot::{SnapshotSolution, SnapshotSolver};
use crate::error::{Error, ErrorKind};

/// GPS L1 carrier wavelength, metres (c / 1575.42 MHz).
pub const GPS_L1_WAVELENGTH_M: f64 = 0.190_293_672_798_365;

/// Which integer search to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SearchMode {
    /// Baseline lengths and angles constrain the search (MC-LAMBDA objective). The default.
    Constrained,
    /// Plain integer least squares of the float ambiguities (LAMBDA), for comparison.
    Unconstrained,
}

/// Noise levels and validation settings of the resolver.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AmbiguityConfig<T = f32> {
    /// Carrier wavelength, metres.
    pub wavelength_m: T,
    /// Standard deviation of one SD phase at cofactor 1, metres.
    pub phase_sigma_m: T,
    /// Standard deviation of one SD code at cofactor 1, metres.
    pub code_sigma_m: T,
    /// Accept only if the second-best candidate costs at least this times the best (`> 1`).
    pub ratio_threshold: T,
    /// Node budget of the integer search; exhausted → [`AmbiguityError::SearchBudgetExhausted`].
    pub max_nodes: u32,
    /// Constrained (flight) or unconstrained (comparison) search.
    pub mode: SearchMode,
}

impl<T: Real> AmbiguityConfig<T> {
    /// GPS L1 with the given SD noise levels (metres), ratio 3, 20 000 nodes, constrained.
    pub fn gps_l1(phase_sigma_m: T, code_sigma_m: T) -> Self {
        Self {
            wavelength_m: real(GPS_L1_WAVELENGTH_M),
            phase_sigma_m,
            code_sigma_m,
            ratio_threshold: real(3.0),
            max_nodes: 20_000,
            mode: SearchMode::Constrained,
        }
    }
}

/// A validated integer fix and the attitude it gives.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AmbiguityFix<const M: usize, const N: usize, T = f32> {
    /// Integer ambiguities `z_ij` (cycles) per baseline `i` and satellite `j` in input order
    /// (entries past the number of satellites are 0).
    pub ambiguities: [[i32; N]; M],
    /// The attitude from the fixed phases.
    pub solution: SnapshotSolution<T>,
    /// Cost `F + G` of the fix (χ² with `M n + 3(M−1)` dof, `M n` unconstrained).
    pub cost: T,
    /// Cost of the second-best candidate, or the final search bound when none was inside it.
    pub second_cost: T,
    /// `second_cost / cost`.
    pub ratio: T,
    /// Search tree nodes visited.
    pub nodes: u32,
    /// Full candidates evaluated (each a Wahba + Gauss–Newton fit when constrained).
    pub candidates: u32,
}

/// Integer ambiguity resolution plus snapshot attitude, for `M` baselines.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AmbiguityResolver<const M: usize, T = f32> {
    solver: SnapshotSolver<M, T>,
    config: AmbiguityConfig<T>,
}

impl<const M: usize, T: Real> AmbiguityResolver<M, T> {
    /// A resolver for the solver's array and the given configuration.
    ///
    /// # Errors
    /// [`SnapshotError::NonFinite`] or [`SnapshotError::InvalidNoise`] for a non-positive
    /// wavelength, noise level, or a ratio threshold `< 1`.
    pub fn new(
        solver: SnapshotSolver<M, T>,
        config: AmbiguityConfig<T>,
    ) -> Result<Self, SnapshotError> {
        let c = &config;
        let values = [
            c.wavelength_m,
            c.phase_sigma_m,
            c.code_sigma_m,
            c.ratio_threshold,
        ];
        if !values.iter().all(|v| v.is_finite()) {
            return Err(SnapshotError::NonFinite);
        }
        if !(c.wavelength_m > T::zero()
            && c.phase_sigma_m > T::zero()
            && c.code_sigma_m > T::zero()
            && c.ratio_threshold >= T::one())
        {
            return Err(SnapshotError::InvalidNoise);
        }
        Ok(Self { solver, config })
    }

    /// The configuration.
    pub fn config(&self) -> &AmbiguityConfig<T> {
        &self.config
    }

    /// Resolves the ambiguities of one epoch and solves the attitude.
    #[allow(clippy::needless_range_loop)] // index loops mirror the equations
    ///
    /// # Errors
    /// [`AmbiguityError::Input`] for too few satellites or coplanar lines of sight;
    /// the refusals [`AmbiguityError::NoCandidate`], [`AmbiguityError::Ambiguous`],
    /// [`AmbiguityError::ModelRejected`], [`AmbiguityError::SearchBudgetExhausted`].
    pub fn resolve<const N: usize>(
        &self,
        obs: &PhaseObservations<M, N, T>,
    ) -> Result<AmbiguityFix<M, N, T>, AmbiguityError> {
        // (n ≤ N holds by construction; the clamp lets the compiler see it, so that indexing
        // by satellite cannot panic.)
        let n = obs.satellites().len().min(N);
        let sats = obs.satellites().get(..n).unwrap_or(&[]);
        let cfg = &self.config;
        let lambda = cfg.wavelength_m;
        let (var_phi, var_code) = (
            cfg.phase_sigma_m * cfg.phase_sigma_m,
            cfg.code_sigma_m * cfg.code_sigma_m,
        );
        let (k_phi, k_code) = (T::one() / var_phi, T::one() / var_code);
        let kappa = k_phi + k_code;
        let (info, info_inv) =
            los_normal_matrix(sats.iter().map(|s| (s.los, T::one() / s.cofactor)))?;

        // 1. Float solution: â_i = N⁻¹ S W p_i ; ẑ_ij = φ_ij − s_j·â_i / λ, shifted by round(ẑ)
        let mut shift = [[T::zero(); N]; M];
        let mut zfloat = [[T::zero(); N]; M];
        let mut a_shift = [Vector3::<T>::zeros(); M];
        for i in 0..M {
            let mut rhs = Vector3::zeros();
            for s in sats {
                rhs += s.los * (s.code_m[i] / s.cofactor);
            }
            let a_code = info_inv * rhs;
            let mut rhs_fixed = Vector3::zeros();
            for (j, s) in sats.iter().enumerate() {
                if j >= N {
                    break;
                }
                let zf = s.phase_cycles[i] - s.los.dot(&a_code) / lambda;
                let sh = zf.round();
                shift[i][j] = sh;
                zfloat[i][j] = zf - sh;
                // ǎ_i at z = shift: N⁻¹ S W (κ_φ λ(φ − shift) + κ_p p) / κ
                let r = (k_phi * lambda * (s.phase_cycles[i] - sh) + k_code * s.code_m[i]) / kappa;
                rhs_fixed += s.los * (r / s.cofactor);
            }
            a_shift[i] = info_inv * rhs_fixed;
        }
        // Q₁ = (σ_φ² W⁻¹ + σ_p² Sᵀ N⁻¹ S) / λ²
        let mut q1 = SMatrix::<T, N, N>::identity();
        let l2 = lambda * lambda;
        for (j, sj) in sats.iter().enumerate().take(N) {
            for (l, sl) in sats.iter().enumerate().take(N) {
                let mut v = var_code * sj.los.dot(&(info_inv * sl.los));
                if j == l {
                    v += var_phi * sj.cofactor;
                }
                q1[(j, l)] = v / l2;
            }
        }
        // 2. LAMBDA decorrelation, ẑ' = Zᵀ ẑ
        let dec = decorrelate(&q1, n)?;
        let mut zhat = [[T::zero(); N]; M];
        for i in 0..M {
            for c in 0..n {
                let mut v = T::zero();
                for j in 0..n {
                    v += dec.z[(j, c)] * zfloat[i][j];
                }
                zhat[i][c] = v;
            }
        }
        // ǎ_i(z') = ǎ_i(shift) − T_a z'_i, T_a = (λ κ_φ / κ) N⁻¹ S W Z⁻ᵀ
        let mut t_a = [Vector3::<T>::zeros(); N];
        for (c, col) in t_a.iter_mut().enumerate().take(n) {
            let mut v = Vector3::zeros();
            for (j, s) in sats.iter().enumerate().take(N) {
                v += s.los * (dec.z_inv_t[(j, c)] / s.cofactor);
            }
            *col = info_inv * v * (lambda * k_phi / kappa);
        }
        let conditional = |i: usize, z: &[T; N]| -> Vector3<T> {
            let mut a = a_shift.get(i).copied().unwrap_or_else(Vector3::zeros);
            for (t, &zc) in t_a.iter().zip(z.iter()).take(n) {
                a -= t * zc;
            }
            a
        };
        // Σ_B = L_B D_B L_Bᵀ (forward LDLᵀ)
        let sigma_b = self.solver.correlation().matrix();
        let (l_b, d_b) = ldlt_small(sigma_b).ok_or(SnapshotError::InvalidCorrelation)?;

        // 3. Search
        let constrained = cfg.mode == SearchMode::Constrained;
        let dof = M * n + if constrained { 3 * (M - 1) } else { 0 };
        let gate: T = real(chi_square_quantile(dof, GateConfidence::P999).unwrap_or(1e9));
        let search = IntegerSearch {
            dec: &dec,
            zhat,
            l_b,
            d_b,
            initial_bound: gate * cfg.ratio_threshold,
            ratio: cfg.ratio_threshold,
            max_nodes: cfg.max_nodes,
        };
        let lengths = self.solver.baselines().as_array().map(|b| b.norm());
        let length_var = info_inv.trace() / kappa;
        let fit_info = info * kappa;
        let outcome = search
            .run(
                |i, z| {
                    if !constrained {
                        return T::zero();
                    }
                    let (Some(&length), Some(&var_i)) =
                        (lengths.get(i), sigma_b.as_slice().get(i * (M + 1)))
                    else {
                        return T::zero();
                    };
                    let d = conditional(i, z).norm() - length;
                    d * d / (var_i * length_var)
                },
                |z| {
                    if !constrained {
                        return Some(T::zero());
                    }
                    let mut a = [Vector3::zeros(); M];
                    for (i, (ai, zi)) in a.iter_mut().zip(z.iter()).enumerate() {
                        *ai = conditional(i, zi);
                    }
                    self.solver
                        .fit_reference_baselines(&a, &fit_info)
                        .ok()
                        .map(|f| f.cost)
                },
            )
            .map_err(|f| match f {
                SearchFailure::Budget => AmbiguityError::SearchBudgetExhausted,
                SearchFailure::Input(e) => AmbiguityError::Input(e),
            })?;

        // 4. Validation
        let best = outcome.best.first().ok_or(AmbiguityError::NoCandidate)?;
        let second_cost = outcome.best.get(1).map(|c| c.cost).unwrap_or(outcome.bound);
        let tiny = T::default_epsilon();
        let ratio = second_cost / if best.cost > tiny { best.cost } else { tiny };
        if !(best.cost <= gate) {
            return Err(AmbiguityError::ModelRejected);
        }
        // Ambiguous when a second candidate was found below `threshold × best`. (When none was
        // found, `second_cost` is the search bound, at least `threshold × best` up to rounding.)
        let rival = outcome
            .best
            .get(1)
            .is_some_and(|c| c.cost < best.cost * cfg.ratio_threshold);
        if rival || !ratio.is_finite() {
            return Err(AmbiguityError::Ambiguous);
        }

        // 5. Fixed ambiguities z = shift + Z⁻ᵀ z', range differences, attitude
        let mut ambiguities = [[0i32; N]; M];
        let mut ranges = RangeDifferences::<M, N, T>::new();
        let sigma_fixed = |c: T| (c / kappa).sqrt();
        for (j, s) in sats.iter().enumerate() {
            if j >= N {
                break;
            }
            let mut range_diff = [T::zero(); M];
            for i in 0..M {
                let mut zij = shift[i][j];
                for c in 0..n {
                    zij += dec.z_inv_t[(j, c)] * best.z[i][c];
                }
                ambiguities[i][j] = to_i32(zij);
                range_diff[i] =
                    (k_phi * lambda * (s.phase_cycles[i] - zij) + k_code * s.code_m[i]) / kappa;
            }
            ranges.push(SatelliteRanges {
                id: s.id,
                los: s.los,
                range_diff,
                sigma: sigma_fixed(s.cofactor),
            })?;
        }
        let solution = self.solver.solve(&ranges)?;
        Ok(AmbiguityFix {
            ambiguities,
            solution,
            cost: best.cost,
            second_cost,
            ratio,
            nodes: outcome.nodes,
            candidates: outcome.evaluated,
        })
    }
}

/// Forward `LDLᵀ` of a small SPD matrix: `A = L D Lᵀ`, `L` unit lower triangular.
fn ldlt_small<T: Real, const M: usize>(a: &SMatrix<T, M, M>) -> Option<(SMatrix<T, M, M>, [T; M])> {
    let mut l = SMatrix::<T, M, M>::identity();
    let mut d = [T::zero(); M];
    for j in 0..M {
        let mut dj = a[(j, j)];
        for k in 0..j {
            dj -= l[(j, k)] * l[(j, k)] * d[k];
        }
        if !(dj > T::zero()) {
            return None;
        }
        d[j] = dj;
        for i in (j + 1)..M {
            let mut v = a[(i, j)];
            for k in 0..j {
                v -= l[(i, k)] * l[(j, k)] * d[k];
            }
            l[(i, j)] = v / dj;
        }
    }
    Some((l, d))
}

/// Nearest `i32` of an integer-valued real (saturating; non-finite → 0).
fn to_i32<T: Real>(x: T) -> i32 {
    nalgebra::try_convert::<T, f64>(x.round())
        .filter(|v| v.is_finite())
        .map(|v| v as i32)
        .unwrap_or(0)
}

/// Errors (refusals) of the integer ambiguity resolution ([`crate::attitude::ambiguity`]).
///
/// Every variant except [`AmbiguityError::Input`] is a *refusal*: the data were valid, but no
/// integer solution could be validated, and the resolver returns no attitude rather than a
/// possibly wrong one. Retry with the next epoch.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AmbiguityError {
    /// The observations or the configuration were invalid (see the inner error).
    #[error("ambiguity input refused")]
    Input(#[from] SnapshotError),
    /// The integer search visited its node budget before it could prove its answer.
    #[error("integer search budget exhausted")]
    SearchBudgetExhausted,
    /// No integer candidate lies inside the search bound: the data are inconsistent with the
    /// model (a cycle slip, a wrong baseline, a multipath outlier).
    #[error("no integer candidate inside the search bound")]
    NoCandidate,
    /// The ratio test failed: the second-best candidate fits almost as well as the best.
    #[error("ratio test failed: ambiguities not validated")]
    Ambiguous,
    /// The best candidate fails the χ² test of the whole model (99.9 %).
    #[error("best integer candidate fails the model test")]
    ModelRejected,
}

impl Error for AmbiguityError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::Input(e) => e.kind(),
            Self::SearchBudgetExhausted => ErrorKind::NotConverged,
            Self::NoCandidate | Self::Ambiguous | Self::ModelRejected => ErrorKind::Unobservable,
        }
    }
}
