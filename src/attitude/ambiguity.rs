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
//!    times the best; otherwise the resolver refuses ([`AmbiguityError`]). The search prunes
//!    everything beyond `ratio_threshold × best`, so a fix without a rival inside that bound
//!    knows only a lower bound of its ratio ([`AmbiguityFix::ratio_is_lower_bound`]); with
//!    [`AmbiguityConfig::ratio_nodes`] a second search, whose bound shrinks only to the
//!    second-best cost, finds the true ratio.
//! 5. The fixed phases give range differences, solved by the snapshot solver for the attitude
//!    and its covariance.
//!
//! [`SearchMode::Unconstrained`] drops `G` (plain LAMBDA integer least squares with the same
//! ratio test), for comparison.
//!
//! The search visits at most [`AmbiguityConfig::max_nodes`] tree nodes and keeps two
//! candidates (a `heapless::Vec`); on the target it uses a few kilobytes of stack for
//! `N = 12`.

use nalgebra::{Matrix3, Matrix4, SMatrix, Vector3, Vector4};

use crate::attitude::snapshot::SnapshotError;
use crate::ekf::{chi_square_quantile, GateConfidence};
use crate::{real, Real};

use super::integer_search::{IntegerSearch, SearchFailure, SearchOutcome};
use super::lambda::{decorrelate, Decorrelation};
pub use super::range_model::{PhaseObservations, PhaseSatellite};
use super::range_model::{RangeDifferences, SatelliteRanges};
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
    /// Node budget of a second search that finds the true ratio when the first pruned every
    /// rival beyond the ratio threshold (0: no second search; the ratio is then reported as a
    /// lower bound, [`AmbiguityFix::ratio_is_lower_bound`]).
    pub ratio_nodes: u32,
    /// Constrained (flight) or unconstrained (comparison) search.
    pub mode: SearchMode,
}

impl<T: Real> AmbiguityConfig<T> {
    /// GPS L1 with the given SD noise levels (metres), ratio 3, 20 000 nodes, constrained, no
    /// second search for the true ratio.
    pub fn gps_l1(phase_sigma_m: T, code_sigma_m: T) -> Self {
        Self {
            wavelength_m: real(GPS_L1_WAVELENGTH_M),
            phase_sigma_m,
            code_sigma_m,
            ratio_threshold: real(3.0),
            max_nodes: 20_000,
            ratio_nodes: 0,
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
    /// True when the search found no rival inside its bound: `second_cost` is then the
    /// bound, and `ratio` only a lower bound of the true ratio (the bound is pruned to
    /// `ratio_threshold` times the best cost, so such a ratio equals the threshold). With
    /// [`AmbiguityConfig::ratio_nodes`] the second search clears it unless its budget runs out
    /// or no rival lies inside the χ² bound.
    pub ratio_is_lower_bound: bool,
    /// Search tree nodes visited (both searches).
    pub nodes: u32,
    /// Full candidates evaluated (each a Wahba + Gauss–Newton fit when constrained; both
    /// searches).
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

    /// Resolves the ambiguities of one epoch and solves the attitude (line biases removed
    /// by the caller).
    ///
    /// # Errors
    /// [`AmbiguityError::Input`] for too few satellites or coplanar lines of sight;
    /// the refusals [`AmbiguityError::NoCandidate`], [`AmbiguityError::Ambiguous`],
    /// [`AmbiguityError::ModelRejected`], [`AmbiguityError::SearchBudgetExhausted`].
    pub fn resolve<const N: usize>(
        &self,
        obs: &PhaseObservations<M, N, T>,
    ) -> Result<AmbiguityFix<M, N, T>, AmbiguityError> {
        let model = FloatModel::single_differences(obs)?;
        let (fixed, search) = self.fix_integers(&model)?;
        let n = obs.satellites().len().min(N);
        let ranges = self.fixed_ranges(
            obs.satellites().get(..n).unwrap_or(&[]),
            &fixed,
            &[T::zero(); M],
        )?;
        Ok(search.fix(fixed, self.solver.solve(&ranges)?))
    }

    /// Resolves the ambiguities of one epoch whose single differences carry an unknown line
    /// bias per baseline (the phase each slave antenna's RF chain adds), and solves the
    /// attitude and the biases.
    ///
    /// The biases cancel in the double differences against a reference satellite (the one
    /// with the smallest cofactor): the search runs on those, with their full covariance
    /// `C_jl = c_j δ_jl + c_r` (the reference's noise is in every one of them). A bias is
    /// defined only modulo a cycle together with the integers; the convention is that the
    /// reference satellite's integers are zero, so the fix's integers `z_ij` and biases `b_i`
    /// give `φ_ij − b_i − z_ij = s_jᵀ a_i / λ`. The biases come from the joint least squares
    /// of `(a_i, b_i)` on the fixed phases, their σ from its covariance.
    ///
    /// # Errors
    /// As [`Self::resolve`]; at least four satellites are needed (three double differences).
    pub fn resolve_with_line_biases<const N: usize>(
        &self,
        obs: &PhaseObservations<M, N, T>,
    ) -> Result<BiasedFix<M, N, T>, AmbiguityError> {
        let n = obs.satellites().len().min(N);
        let sats = obs.satellites().get(..n).unwrap_or(&[]);
        let reference = best_satellite(sats).ok_or(SnapshotError::TooFewSatellites)?;
        let model = FloatModel::<M, N, T>::double_differences(sats, reference)?;
        let (dd, search) = self.fix_integers(&model)?;
        // single-difference integers: zero for the reference, the DD integers for the others
        let mut fixed = [[0i32; N]; M];
        for (i, row) in (0..M).zip(fixed.iter_mut()) {
            let mut next = 0usize;
            for (j, z) in (0..n).zip(row.iter_mut()) {
                if j != reference {
                    *z = dd[i].get(next).copied().unwrap_or(0);
                    // (at most j: never saturates)
                    next = next.saturating_add(1);
                }
            }
        }
        // the biases from the phases alone, the attitude, then the biases again at the
        // attitude (the baseline lengths and angle now constrain them) and the attitude again
        let (bias, joint_sigma) = self.line_biases(sats, &fixed)?;
        let first = self
            .solver
            .solve(&self.fixed_ranges(sats, &fixed, &bias)?)?;
        let (bias, at_sigma) = self.line_biases_at(sats, &fixed, &first);
        // the attitude's covariance treats the biases as known, which leaves their σ too small
        // by 1.7 (measured by tests/snapshot.rs); the joint least squares' σ (without the
        // baselines' constraint) bounds it from above
        let bias_sigma: [T; M] = core::array::from_fn(|i| {
            (at_sigma[i] * real(BIAS_SIGMA_FACTOR)).max(joint_sigma[i] * real(0.5))
        });
        let mut solution = self
            .solver
            .solve(&self.fixed_ranges(sats, &fixed, &bias)?)?;
        solution.covariance +=
            self.bias_sensitivity(sats, &fixed, &bias, &bias_sigma, &solution)?;
        Ok(BiasedFix {
            fix: search.fix(fixed, solution),
            line_bias_cycles: bias,
            line_bias_sigma_cycles: bias_sigma,
            reference: sats.get(reference).map_or(0, |s| s.id),
        })
    }

    /// Steps 1–4 of the method on a float model: float solution, decorrelation, search,
    /// validation. Returns the fixed integers (model order) and the search's figures.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    fn fix_integers<const N: usize>(
        &self,
        model: &FloatModel<M, N, T>,
    ) -> Result<([[i32; N]; M], SearchFigures<T>), AmbiguityError> {
        let cfg = &self.config;
        let float = model.float_solution(cfg);
        let q1 = model.float_covariance(cfg);
        let dec = decorrelate(&q1, model.n)?;
        let zhat = transformed_floats(&dec, &float.zfloat);
        let t_a = model.baseline_sensitivity(cfg, &dec);
        let first = SearchLimits {
            ratio: cfg.ratio_threshold,
            max_nodes: cfg.max_nodes,
        };
        let outcome = self.search(model, &float, &dec, zhat, &t_a, first)?;
        let verdict = self.validate(model, &outcome)?;
        let fixed = fixed_integers(model.n, &float.shift, &dec, &verdict.z);
        let mut figures = SearchFigures {
            cost: verdict.cost,
            second_cost: verdict.second_cost,
            ratio: verdict.ratio,
            ratio_is_lower_bound: verdict.ratio_is_lower_bound,
            nodes: outcome.nodes,
            candidates: outcome.evaluated,
        };
        if figures.ratio_is_lower_bound && cfg.ratio_nodes > 0 {
            self.true_ratio(model, &float, &dec, zhat, &t_a, &mut figures);
        }
        Ok((fixed, figures))
    }

    /// The true ratio of a validated fix whose search pruned every rival beyond the ratio
    /// threshold: the search again with the bound shrinking only to the second-best cost
    /// (within [`AmbiguityConfig::ratio_nodes`] nodes). Keeps the lower bound when the budget
    /// runs out or no second candidate lies inside the initial (χ²) bound.
    fn true_ratio<const N: usize>(
        &self,
        model: &FloatModel<M, N, T>,
        float: &FloatSolution<M, N, T>,
        dec: &Decorrelation<N, T>,
        zhat: [[T; N]; M],
        t_a: &[Vector3<T>; N],
        figures: &mut SearchFigures<T>,
    ) {
        let wide = SearchLimits {
            ratio: real(UNPRUNED_RATIO),
            max_nodes: self.config.ratio_nodes,
        };
        let Ok(outcome) = self.search(model, float, dec, zhat, t_a, wide) else {
            return;
        };
        figures.nodes = figures.nodes.saturating_add(outcome.nodes);
        figures.candidates = figures.candidates.saturating_add(outcome.evaluated);
        let (Some(best), Some(second)) = (outcome.best.first(), outcome.best.get(1)) else {
            return;
        };
        let tiny = T::default_epsilon();
        figures.second_cost = second.cost;
        figures.ratio = second.cost / if best.cost > tiny { best.cost } else { tiny };
        figures.ratio_is_lower_bound = false;
    }

    /// Step 3: the bounded depth-first integer search, constrained by the baseline lengths
    /// and angles ([`SearchMode::Constrained`]) or not.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    fn search<const N: usize>(
        &self,
        model: &FloatModel<M, N, T>,
        float: &FloatSolution<M, N, T>,
        dec: &Decorrelation<N, T>,
        zhat: [[T; N]; M],
        t_a: &[Vector3<T>; N],
        limits: SearchLimits<T>,
    ) -> Result<SearchOutcome<M, N, T>, AmbiguityError> {
        let cfg = &self.config;
        let n = model.n;
        let kappa = cfg.kappa();
        let conditional = |i: usize, z: &[T; N]| -> Vector3<T> {
            let mut a = float.a_shift.get(i).copied().unwrap_or_else(Vector3::zeros);
            for (t, &zc) in t_a.iter().zip(z.iter()).take(n) {
                a -= t * zc;
            }
            a
        };
        // Σ_B = L_B D_B L_Bᵀ (forward LDLᵀ)
        let sigma_b = self.solver.correlation().matrix();
        let (l_b, d_b) = ldlt_small(sigma_b).ok_or(SnapshotError::InvalidCorrelation)?;
        let constrained = cfg.mode == SearchMode::Constrained;
        let search = IntegerSearch {
            dec,
            zhat,
            l_b,
            d_b,
            initial_bound: self.gate(n) * cfg.ratio_threshold,
            ratio: limits.ratio,
            max_nodes: limits.max_nodes,
        };
        let lengths = self.solver.baselines().as_array().map(|b| b.norm());
        let length_var = model.info_inv.trace() / kappa;
        let fit_info = model.info * kappa;
        search
            .run(
                |i, z| {
                    let (Some(&length), Some(&var_i), true) = (
                        lengths.get(i),
                        i.checked_mul(M + 1).and_then(|d| sigma_b.as_slice().get(d)),
                        constrained,
                    ) else {
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
                    for (i, (ai, zi)) in (0..M).zip(a.iter_mut().zip(z.iter())) {
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
            })
    }

    /// The χ² gate (99.9 %) of the best candidate's cost: `M n + 3(M − 1)` degrees of freedom
    /// constrained, `M n` unconstrained.
    fn gate(&self, n: usize) -> T {
        let constrained = self.config.mode == SearchMode::Constrained;
        let dof = M
            .saturating_mul(n)
            .saturating_add(if constrained { 3 * (M - 1) } else { 0 });
        real(chi_square_quantile(dof, GateConfidence::P999).unwrap_or(UNBOUNDED_GATE))
    }

    /// Step 4: the best candidate must pass the χ² gate and beat every rival by the ratio.
    fn validate<const N: usize>(
        &self,
        model: &FloatModel<M, N, T>,
        outcome: &SearchOutcome<M, N, T>,
    ) -> Result<Verdict<M, N, T>, AmbiguityError> {
        let best = outcome.best.first().ok_or(AmbiguityError::NoCandidate)?;
        let rival = outcome.best.get(1);
        // without a rival inside the search bound, the bound (≥ threshold × best) is all the
        // search proved: the ratio is a lower bound
        let second_cost = rival.map_or(outcome.bound, |c| c.cost);
        let tiny = T::default_epsilon();
        let ratio = second_cost / if best.cost > tiny { best.cost } else { tiny };
        if !(best.cost <= self.gate(model.n)) {
            return Err(AmbiguityError::ModelRejected);
        }
        let ambiguous = rival.is_some_and(|c| c.cost < best.cost * self.config.ratio_threshold);
        if ambiguous || !ratio.is_finite() {
            return Err(AmbiguityError::Ambiguous);
        }
        Ok(Verdict {
            z: best.z,
            cost: best.cost,
            second_cost,
            ratio,
            ratio_is_lower_bound: rival.is_none(),
        })
    }

    /// Step 5: range differences of the fixed phases, biases `bias` (cycles) removed,
    /// combined with the code.
    fn fixed_ranges<const N: usize>(
        &self,
        sats: &[PhaseSatellite<M, T>],
        fixed: &[[i32; N]; M],
        bias: &[T; M],
    ) -> Result<RangeDifferences<M, N, T>, AmbiguityError> {
        let cfg = &self.config;
        let (k_phi, k_code, kappa) = (cfg.k_phi(), cfg.k_code(), cfg.kappa());
        let mut ranges = RangeDifferences::<M, N, T>::new();
        for (j, s) in (0..N).zip(sats.iter()) {
            let mut range_diff = [T::zero(); M];
            for i in 0..M {
                let zij: T = real(f64::from(fixed[i][j]));
                range_diff[i] = (k_phi * cfg.wavelength_m * (s.phase_cycles[i] - bias[i] - zij)
                    + k_code * s.code_m[i])
                    / kappa;
            }
            ranges.push(SatelliteRanges {
                id: s.id,
                los: s.los,
                range_diff,
                sigma: (s.cofactor / kappa).sqrt(),
            })?;
        }
        Ok(ranges)
    }

    /// The line biases (cycles) and their σ from the fixed phases: per baseline the joint
    /// weighted least squares of `(a_i, b_i)` with rows `[s_jᵀ/λ, 1]`.
    fn line_biases<const N: usize>(
        &self,
        sats: &[PhaseSatellite<M, T>],
        fixed: &[[i32; N]; M],
    ) -> Result<([T; M], [T; M]), AmbiguityError> {
        let lambda = self.config.wavelength_m;
        let var_phi = self.config.phase_sigma_m * self.config.phase_sigma_m / (lambda * lambda);
        let mut normal = Matrix4::<T>::zeros();
        for s in sats {
            let row = Vector4::new(
                s.los.x / lambda,
                s.los.y / lambda,
                s.los.z / lambda,
                T::one(),
            );
            normal += row * row.transpose() / s.cofactor;
        }
        let chol = normal
            .cholesky()
            .ok_or(SnapshotError::CoplanarLineOfSight)?;
        let cov = chol.inverse();
        let mut bias = [T::zero(); M];
        let mut sigma = [T::zero(); M];
        for i in 0..M {
            let mut rhs = Vector4::zeros();
            for (j, s) in (0..N).zip(sats.iter()) {
                let row = Vector4::new(
                    s.los.x / lambda,
                    s.los.y / lambda,
                    s.los.z / lambda,
                    T::one(),
                );
                let zij: T = real(f64::from(fixed[i][j]));
                rhs += row * ((s.phase_cycles[i] - zij) / s.cofactor);
            }
            let x = chol.solve(&rhs);
            bias[i] = x[3];
            sigma[i] = (cov[(3, 3)] * var_phi).sqrt();
        }
        Ok((bias, sigma))
    }
}

impl<const M: usize, T: Real> AmbiguityResolver<M, T> {
    /// The attitude covariance the biases' uncertainty adds (the snapshot's own treats them
    /// as known): `Σ_i Δθ_i Δθ_iᵀ`, with `Δθ_i` the attitude's change when bias `i` moves by
    /// its σ (one more solve per baseline).
    fn bias_sensitivity<const N: usize>(
        &self,
        sats: &[PhaseSatellite<M, T>],
        fixed: &[[i32; N]; M],
        bias: &[T; M],
        sigma: &[T; M],
        solution: &SnapshotSolution<T>,
    ) -> Result<Matrix3<T>, AmbiguityError> {
        let mut extra = Matrix3::zeros();
        for i in 0..M {
            let mut moved = *bias;
            moved[i] += sigma[i];
            let s = self
                .solver
                .solve(&self.fixed_ranges(sats, fixed, &moved)?)?;
            let d = (solution.q_rb.conjugate() * s.q_rb).to_rotation_vector();
            extra += d * d.transpose();
        }
        Ok(extra)
    }

    /// The line biases (cycles) at a solved attitude: per baseline the weighted mean of
    /// `φ_ij − z_ij − s_jᵀ C b_i / λ`, and their σ from the phase noise of that mean and the
    /// attitude's covariance along the mean line of sight.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    fn line_biases_at<const N: usize>(
        &self,
        sats: &[PhaseSatellite<M, T>],
        fixed: &[[i32; N]; M],
        solution: &SnapshotSolution<T>,
    ) -> ([T; M], [T; M]) {
        let lambda = self.config.wavelength_m;
        let var_phi = self.config.phase_sigma_m * self.config.phase_sigma_m / (lambda * lambda);
        let baselines = self.solver.baselines().as_array();
        let mut bias = [T::zero(); M];
        let mut sigma = [T::zero(); M];
        let weight: T = sats
            .iter()
            .fold(T::zero(), |w, s| w + T::one() / s.cofactor);
        let mean_los = sats
            .iter()
            .fold(Vector3::zeros(), |m, s| m + s.los / s.cofactor)
            / weight;
        for i in 0..M {
            let a = solution.c_rb * baselines[i];
            let mut sum = T::zero();
            for (j, s) in (0..N).zip(sats.iter()) {
                let zij: T = real(f64::from(fixed[i][j]));
                sum += (s.phase_cycles[i] - zij - s.los.dot(&a) / lambda) / s.cofactor;
            }
            bias[i] = sum / weight;
            // δ(sᵀ C b) = sᵀ C (δθ × b) = δθ · (b × Cᵀ s)
            let g = baselines[i].cross(&(solution.c_rb.transpose() * mean_los)) / lambda;
            let attitude_var = (g.transpose() * solution.covariance * g).x;
            sigma[i] = (var_phi / weight + attitude_var).sqrt();
        }
        (bias, sigma)
    }
}

/// A fix whose single differences carried unknown line biases
/// ([`AmbiguityResolver::resolve_with_line_biases`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BiasedFix<const M: usize, const N: usize, T = f32> {
    /// The integers (zero for the reference satellite) and the attitude.
    pub fix: AmbiguityFix<M, N, T>,
    /// The line bias of each baseline, cycles (`φ − b − z = sᵀa/λ`).
    pub line_bias_cycles: [T; M],
    /// Their standard deviations, cycles.
    pub line_bias_sigma_cycles: [T; M],
    /// Id of the reference satellite (whose integers are zero).
    pub reference: u8,
}

/// Factor on the line biases' σ at the solved attitude (which treats the biases as known).
const BIAS_SIGMA_FACTOR: f64 = 1.7;

/// The gate used when the χ² table has no entry (never in practice).
const UNBOUNDED_GATE: f64 = 1e9;

/// The ratio of the second search ([`AmbiguityConfig::ratio_nodes`]): large enough that the
/// bound shrinks only to the second-best cost.
const UNPRUNED_RATIO: f64 = 1e30;

/// The pruning ratio and node budget of one search.
#[derive(Clone, Copy)]
struct SearchLimits<T> {
    ratio: T,
    max_nodes: u32,
}

/// What the search found, before the attitude is solved.
struct SearchFigures<T> {
    cost: T,
    second_cost: T,
    ratio: T,
    ratio_is_lower_bound: bool,
    nodes: u32,
    candidates: u32,
}

impl<T: Real> SearchFigures<T> {
    fn fix<const M: usize, const N: usize>(
        &self,
        ambiguities: [[i32; N]; M],
        solution: SnapshotSolution<T>,
    ) -> AmbiguityFix<M, N, T> {
        AmbiguityFix {
            ambiguities,
            solution,
            cost: self.cost,
            second_cost: self.second_cost,
            ratio: self.ratio,
            ratio_is_lower_bound: self.ratio_is_lower_bound,
            nodes: self.nodes,
            candidates: self.candidates,
        }
    }
}

/// The best candidate and what validated it.
struct Verdict<const M: usize, const N: usize, T> {
    z: [[T; N]; M],
    cost: T,
    second_cost: T,
    ratio: T,
    ratio_is_lower_bound: bool,
}

/// Float solution shifted by the nearest integers: `shift`, the remainder `ẑ − shift`, and
/// the conditional baselines at `z = shift`.
struct FloatSolution<const M: usize, const N: usize, T> {
    shift: [[T; N]; M],
    zfloat: [[T; N]; M],
    a_shift: [Vector3<T>; M],
}

/// The float model of one epoch: per integer `j` its design vector `d_j` (a line of sight for
/// single differences, `s_j − s_r` for double differences), the cofactor matrix `C` and its
/// inverse `W`, the phases (cycles) and codes (m) per baseline, and `N = S W Sᵀ`.
struct FloatModel<const M: usize, const N: usize, T> {
    n: usize,
    design: [Vector3<T>; N],
    cofactor: SMatrix<T, N, N>,
    weight: SMatrix<T, N, N>,
    phase: [[T; N]; M],
    code: [[T; N]; M],
    info: Matrix3<T>,
    info_inv: Matrix3<T>,
}

impl<T: Real> AmbiguityConfig<T> {
    fn k_phi(&self) -> T {
        T::one() / (self.phase_sigma_m * self.phase_sigma_m)
    }
    fn k_code(&self) -> T {
        T::one() / (self.code_sigma_m * self.code_sigma_m)
    }
    fn kappa(&self) -> T {
        self.k_phi() + self.k_code()
    }
}

/// The satellite with the smallest cofactor (the double differences' reference).
fn best_satellite<const M: usize, T: Real>(sats: &[PhaseSatellite<M, T>]) -> Option<usize> {
    let mut best: Option<(usize, T)> = None;
    // (indices from a range, not `enumerate`: its counter keeps an overflow check)
    for (j, s) in (0..sats.len()).zip(sats.iter()) {
        if best.is_none_or(|(_, c)| s.cofactor < c) {
            best = Some((j, s.cofactor));
        }
    }
    best.map(|(j, _)| j)
}

// index loops mirror the equations of the method
#[allow(clippy::needless_range_loop)]
impl<const M: usize, const N: usize, T: Real> FloatModel<M, N, T> {
    /// Single differences: `d_j = s_j`, `C = diag(c_j)`.
    fn single_differences(obs: &PhaseObservations<M, N, T>) -> Result<Self, SnapshotError> {
        let n = obs.satellites().len().min(N);
        let sats = obs.satellites().get(..n).unwrap_or(&[]);
        let mut model = Self::empty(n);
        for (j, s) in (0..N).zip(sats.iter()) {
            model.design[j] = s.los;
            model.cofactor[(j, j)] = s.cofactor;
            model.weight[(j, j)] = T::one() / s.cofactor;
            for i in 0..M {
                model.phase[i][j] = s.phase_cycles[i];
                model.code[i][j] = s.code_m[i];
            }
        }
        model.normal()
    }

    /// Double differences against satellite `r`: `d = s_j − s_r`, `C_jl = c_j δ_jl + c_r`.
    fn double_differences(sats: &[PhaseSatellite<M, T>], r: usize) -> Result<Self, SnapshotError> {
        let reference = sats.get(r).ok_or(SnapshotError::TooFewSatellites)?;
        let n = sats.len().saturating_sub(1).min(N);
        let mut model = Self::empty(n);
        let others = (0..sats.len())
            .zip(sats.iter())
            .filter(|(j, _)| *j != r)
            .map(|(_, s)| s);
        for (j, s) in (0..n).zip(others) {
            // (j < n ≤ N; the check lets the compiler see it through the filter)
            if j >= N {
                break;
            }
            model.design[j] = s.los - reference.los;
            for i in 0..M {
                model.phase[i][j] = s.phase_cycles[i] - reference.phase_cycles[i];
                model.code[i][j] = s.code_m[i] - reference.code_m[i];
            }
            for l in 0..n {
                model.cofactor[(j, l)] = reference.cofactor;
            }
            model.cofactor[(j, j)] += s.cofactor;
        }
        // W = C⁻¹ on the block in use (identity beyond it)
        let mut c = SMatrix::<T, N, N>::identity();
        for j in 0..n {
            for l in 0..n {
                c[(j, l)] = model.cofactor[(j, l)];
            }
        }
        model.weight = c
            .cholesky()
            .map(|f| f.inverse())
            .ok_or(SnapshotError::InvalidNoise)?;
        for j in n..N {
            model.weight[(j, j)] = T::zero();
        }
        model.normal()
    }

    fn empty(n: usize) -> Self {
        Self {
            n,
            design: [Vector3::zeros(); N],
            cofactor: SMatrix::zeros(),
            weight: SMatrix::zeros(),
            phase: [[T::zero(); N]; M],
            code: [[T::zero(); N]; M],
            info: Matrix3::zeros(),
            info_inv: Matrix3::zeros(),
        }
    }

    /// The integers in use (`n ≤ N` by construction; the clamp lets the compiler see it).
    fn dim(&self) -> usize {
        self.n.min(N)
    }

    /// `N = S W Sᵀ` and its inverse (the lines of sight must span three dimensions).
    fn normal(mut self) -> Result<Self, SnapshotError> {
        if self.n < 3 {
            return Err(SnapshotError::TooFewSatellites);
        }
        let mut info = Matrix3::zeros();
        for j in 0..self.dim() {
            for l in 0..self.dim() {
                info += self.design[j] * self.design[l].transpose() * self.weight[(j, l)];
            }
        }
        let mean = info.trace() / real(3.0);
        if !(mean > T::zero()) || !mean.is_finite() {
            return Err(SnapshotError::Numerical);
        }
        if !(info.determinant() / (mean * mean * mean) >= real(MIN_LOS_SHAPE)) {
            return Err(SnapshotError::CoplanarLineOfSight);
        }
        self.info_inv = info
            .cholesky()
            .map(|c| c.inverse())
            .ok_or(SnapshotError::CoplanarLineOfSight)?;
        self.info = info;
        Ok(self)
    }

    /// `S W v` for a vector `v` over the integers.
    fn s_w(&self, v: &[T; N]) -> Vector3<T> {
        let mut out = Vector3::zeros();
        for j in 0..self.dim() {
            let mut wv = T::zero();
            for l in 0..self.dim() {
                wv += self.weight[(j, l)] * v[l];
            }
            out += self.design[j] * wv;
        }
        out
    }

    /// Step 1: `â_i = N⁻¹ S W p_i`, `ẑ_ij = φ_ij − d_j·â_i/λ` shifted by its nearest integer,
    /// and `ǎ_i` at `z = shift`: `N⁻¹ S W (κ_φ λ(φ − shift) + κ_p p) / κ`.
    fn float_solution(&self, cfg: &AmbiguityConfig<T>) -> FloatSolution<M, N, T> {
        let (lambda, k_phi, k_code, kappa) =
            (cfg.wavelength_m, cfg.k_phi(), cfg.k_code(), cfg.kappa());
        let mut out = FloatSolution {
            shift: [[T::zero(); N]; M],
            zfloat: [[T::zero(); N]; M],
            a_shift: [Vector3::zeros(); M],
        };
        for i in 0..M {
            let a_code = self.info_inv * self.s_w(&self.code[i]);
            let mut r = [T::zero(); N];
            for j in 0..self.dim() {
                let zf = self.phase[i][j] - self.design[j].dot(&a_code) / lambda;
                let sh = zf.round();
                out.shift[i][j] = sh;
                out.zfloat[i][j] = zf - sh;
                r[j] =
                    (k_phi * lambda * (self.phase[i][j] - sh) + k_code * self.code[i][j]) / kappa;
            }
            out.a_shift[i] = self.info_inv * self.s_w(&r);
        }
        out
    }

    /// `Q₁ = (σ_φ² C + σ_p² Sᵀ N⁻¹ S) / λ²` (identity beyond the integers in use).
    fn float_covariance(&self, cfg: &AmbiguityConfig<T>) -> SMatrix<T, N, N> {
        let (var_phi, var_code) = (
            cfg.phase_sigma_m * cfg.phase_sigma_m,
            cfg.code_sigma_m * cfg.code_sigma_m,
        );
        let l2 = cfg.wavelength_m * cfg.wavelength_m;
        let mut q1 = SMatrix::<T, N, N>::identity();
        for j in 0..self.dim() {
            for l in 0..self.dim() {
                let v = var_code * self.design[j].dot(&(self.info_inv * self.design[l]))
                    + var_phi * self.cofactor[(j, l)];
                q1[(j, l)] = v / l2;
            }
        }
        q1
    }

    /// `T_a = (λ κ_φ / κ) N⁻¹ S W Z⁻ᵀ`: `ǎ_i(z') = ǎ_i(shift) − T_a z'_i`.
    fn baseline_sensitivity(
        &self,
        cfg: &AmbiguityConfig<T>,
        dec: &Decorrelation<N, T>,
    ) -> [Vector3<T>; N] {
        let scale = cfg.wavelength_m * cfg.k_phi() / cfg.kappa();
        let mut t_a = [Vector3::zeros(); N];
        for (c, col) in (0..self.dim()).zip(t_a.iter_mut()) {
            let mut column = [T::zero(); N];
            for (j, v) in (0..self.dim()).zip(column.iter_mut()) {
                *v = dec.z_inv_t[(j, c)];
            }
            *col = self.info_inv * self.s_w(&column) * scale;
        }
        t_a
    }
}

/// Smallest `det N / (tr N / 3)³` of the normal matrix: below, the design vectors span less
/// than three dimensions.
const MIN_LOS_SHAPE: f64 = 1e-5;

/// Step 2's transform of the floats: `ẑ' = Zᵀ ẑ` per baseline.
#[allow(clippy::needless_range_loop)] // index loops mirror the equations
fn transformed_floats<const M: usize, const N: usize, T: Real>(
    dec: &Decorrelation<N, T>,
    zfloat: &[[T; N]; M],
) -> [[T; N]; M] {
    let n = dec.n.min(N);
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
    zhat
}

/// The fixed integers `z = shift + Z⁻ᵀ z'`.
#[allow(clippy::needless_range_loop)] // index loops mirror the equations
fn fixed_integers<const M: usize, const N: usize, T: Real>(
    n: usize,
    shift: &[[T; N]; M],
    dec: &Decorrelation<N, T>,
    best: &[[T; N]; M],
) -> [[i32; N]; M] {
    let n = n.min(N);
    let mut out = [[0i32; N]; M];
    for i in 0..M {
        for j in 0..n {
            let mut zij = shift[i][j];
            for c in 0..n {
                zij += dec.z_inv_t[(j, c)] * best[i][c];
            }
            out[i][j] = to_i32(zij);
        }
    }
    out
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
#[cfg(test)]
mod tests {
    use super::*;
    use crate::attitude::example;

    fn resolver_f64(ratio_nodes: u32) -> AmbiguityResolver<2, f64> {
        let b = example::baselines().unwrap();
        let baselines =
            crate::attitude::range_model::Baselines::new(b.as_array().map(|v| v.cast::<f64>()))
                .unwrap();
        let solver = SnapshotSolver::new(
            baselines,
            crate::attitude::range_model::BaselineCorrelation::shared_base_antenna(),
        );
        let config = AmbiguityConfig {
            ratio_nodes,
            ..AmbiguityConfig::gps_l1(
                f64::from(example::PHASE_SIGMA_M),
                f64::from(example::CODE_SIGMA_M),
            )
        };
        AmbiguityResolver::new(solver, config).unwrap()
    }

    fn obs_f64(n: usize, seed: u64) -> PhaseObservations<2, 12, f64> {
        let o = example::phases(n, seed).unwrap();
        let mut out = PhaseObservations::new();
        for s in o.satellites() {
            out.push(PhaseSatellite {
                id: s.id,
                los: s.los.cast(),
                phase_cycles: s.phase_cycles.map(f64::from),
                code_m: s.code_m.map(f64::from),
                cofactor: f64::from(s.cofactor),
            })
            .unwrap();
        }
        out
    }

    /// Without the second search a fix whose search pruned every rival reports the threshold
    /// as a lower bound, flagged; with it, the true ratio (above the bound), agreeing with the
    /// f64 resolver's; the fix itself is the same.
    #[test]
    fn the_ratio_is_the_true_one_or_flagged_as_a_lower_bound() {
        let mut lower_bounds = 0;
        for seed in 1..=6u64 {
            for n in [5usize, 6, 8] {
                let obs = example::phases(n, seed).unwrap();
                let plain = example::resolver().unwrap();
                let Ok(first) = plain.resolve(&obs) else {
                    continue;
                };
                let mut config = *plain.config();
                config.ratio_nodes = 200_000;
                let full = AmbiguityResolver::new(example::solver().unwrap(), config).unwrap();
                let fix = full.resolve(&obs).unwrap();
                assert_eq!(fix.ambiguities, first.ambiguities);
                if first.ratio_is_lower_bound {
                    lower_bounds += 1;
                    assert!((first.ratio - 3.0).abs() < 1e-3, "{}", first.ratio);
                    if !fix.ratio_is_lower_bound {
                        assert!(
                            fix.ratio >= first.ratio * 0.999,
                            "{} < {}",
                            fix.ratio,
                            first.ratio
                        );
                    }
                } else {
                    assert_eq!(fix.ratio, first.ratio);
                }
                let reference = resolver_f64(200_000).resolve(&obs_f64(n, seed)).unwrap();
                assert_eq!(reference.ratio_is_lower_bound, fix.ratio_is_lower_bound);
                let err = (f64::from(fix.ratio) - reference.ratio).abs() / reference.ratio;
                assert!(
                    err < 2e-3,
                    "n {n} seed {seed}: {} vs {}",
                    fix.ratio,
                    reference.ratio
                );
            }
        }
        assert!(
            lower_bounds > 0,
            "no fix pruned every rival: the test tests nothing"
        );
    }
}
