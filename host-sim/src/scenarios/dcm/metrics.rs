//! Pooled error statistics of the `dcm` scenario's filters, and the scenario's metrics.

use nalgebra::Matrix3;

use super::bounds::{self, Noise};
use super::runs::Track;

fn sqrt3(v: [f64; 3]) -> [f64; 3] {
    v.map(f64::sqrt)
}

crate::metrics! {
    /// Pooled statistics of one filter against its bound (second halves of the runs; per-axis
    /// triples are body x, y, z of the rotation-vector error).
    pub struct FilterMetrics {
        /// RMS error per body axis.
        #[metric(unit = "rad")] pub rms_err_rad: [f64; 3],
        /// Largest |error| per axis over the runs.
        #[metric(unit = "rad")] pub max_err_rad: [f64; 3],
        /// Largest |error| at the last epoch over the runs.
        #[metric(unit = "rad")] pub final_err_rad: [f64; 3],
        /// RMS of the rotation-vector error.
        #[metric(unit = "rad")] pub rotvec_rms_rad: f64,
        /// Steady-state bound per axis.
        #[metric(unit = "rad")] pub bound_rad: [f64; 3],
        /// Steady-state bound of the rotation vector (√trace).
        #[metric(unit = "rad")] pub bound_rotvec_rad: f64,
        /// RMS over the bound per axis.
        #[metric(unit = "")] pub rms_over_bound: [f64; 3],
        /// RMS of the filter's own σ per axis.
        #[metric(unit = "rad")] pub filter_sigma_rad: [f64; 3],
        /// Largest |3-2-1 angle error| (α, β, γ) at the last epoch.
        #[metric(unit = "rad")] pub final_euler_err_rad: [f64; 3],
        /// Mean NIS.
        #[metric(unit = "")] pub nis_mean: f64,
        /// NIS degrees of freedom.
        #[metric(unit = "")] pub nis_dof: u8,
        /// Fraction of epochs whose health was not nominal.
        #[metric(unit = "")] pub not_nominal_fraction: f64,
        /// Steps that returned an error.
        #[metric(unit = "")] pub step_failures: usize,
    }
}

impl FilterMetrics {
    /// The largest per-axis RMS over the bound (finite values only).
    pub fn max_ratio(&self) -> f64 {
        self.rms_over_bound
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0, |a, &b| f64::max(a, b))
    }
}

/// Pooled statistics of one filter against its bound covariance.
pub fn filter_metrics(tracks: &[&Track], bound: &Matrix3<f64>) -> FilterMetrics {
    let n: usize = tracks.iter().map(|t| t.count).sum::<usize>().max(1);
    let per_axis = |f: &dyn Fn(&Track, usize) -> f64| {
        [0, 1, 2].map(|i| tracks.iter().map(|t| f(t, i)).sum::<f64>())
    };
    let largest = |f: &dyn Fn(&Track, usize) -> f64| {
        [0, 1, 2].map(|i| tracks.iter().fold(0.0f64, |m, t| m.max(f(t, i))))
    };
    let rms = sqrt3(per_axis(&|t, i| t.sum_sq[i]).map(|s| s / n as f64));
    let b = bounds::axis_sigma(bound);
    let total: usize = tracks.iter().map(|t| t.count).sum();
    FilterMetrics {
        rms_err_rad: rms,
        max_err_rad: largest(&|t, i| t.max_abs[i]),
        final_err_rad: largest(&|t, i| t.final_err[i].abs()),
        rotvec_rms_rad: (tracks.iter().map(|t| t.sum_sq_rotvec).sum::<f64>() / n as f64).sqrt(),
        bound_rad: b,
        bound_rotvec_rad: bound.trace().sqrt(),
        rms_over_bound: [0, 1, 2].map(|i| rms[i] / b[i]),
        filter_sigma_rad: sqrt3(per_axis(&|t, i| t.sum_var[i]).map(|s| s / n as f64)),
        final_euler_err_rad: largest(&|t, i| t.final_euler_err[i].abs()),
        nis_mean: tracks.iter().map(|t| t.sum_nis).sum::<f64>() / n as f64,
        nis_dof: tracks.first().map_or(0, |t| t.nis_dof),
        not_nominal_fraction: tracks.iter().map(|t| t.not_nominal).sum::<usize>() as f64
            / (2 * total.max(1)) as f64,
        step_failures: tracks.iter().map(|t| t.failures).sum::<usize>(),
    }
}

/// Relative standard deviation of a pooled RMS figure: the errors are correlated over the
/// filters' memory `τ = σ_p/σ_v`, so the second halves of the runs hold about
/// `N = runs · (T/2) / (2τ)` independent samples, and `σ(RMS)/RMS ≈ 1/√(2N)`.
pub fn rms_uncertainty(noise: Noise, runs: usize, duration: f64) -> f64 {
    let tau = noise.sigma_baseline / noise.sigma_velocity;
    let n = runs as f64 * (duration / 2.0) / (2.0 * tau);
    1.0 / (2.0 * n).sqrt()
}

crate::metrics! {
    /// One structure (baseline pair) of the multi-structure filter on its own.
    pub struct StructureMetrics {
        /// The two baselines of the structure.
        #[metric(unit = "")] pub pairs: String,
        /// RMS of the rotation-vector error.
        #[metric(unit = "rad")] pub rotvec_rms_rad: f64,
        /// Steady-state bound of the structure.
        #[metric(unit = "rad")] pub bound_rotvec_rad: f64,
        /// RMS over the bound per axis.
        #[metric(unit = "")] pub rms_over_bound: [f64; 3],
        /// Epochs without an estimate.
        #[metric(unit = "")] pub no_estimate_epochs: usize,
        /// Fraction of epochs at which it entered the combination.
        #[metric(unit = "")] pub inlier_fraction: f64,
    }
}

crate::metrics! {
    /// The multi-structure filter: the robust combination and each structure.
    pub struct MultiStructureMetrics {
        /// The combination.
        #[metric(flatten)] #[serde(flatten)] pub fused: FilterMetrics,
        /// Each structure on its own.
        #[metric(nested)] pub structures: Vec<StructureMetrics>,
    }
}

crate::metrics! {
    /// The rigid-body filter on the three baselines.
    pub struct RigidBodyMetrics {
        /// Its statistics.
        #[metric(flatten)] #[serde(flatten)] pub filter: FilterMetrics,
        /// The bound along the principal axes of the information.
        #[metric(unit = "rad")] pub bound_principal_rad: Vec<f64>,
        /// The bound if the rate were estimated independently of the attitude, per axis.
        #[metric(unit = "rad")] pub bound_independent_rate_rad: [f64; 3],
    }
}

crate::metrics! {
    /// The f32 filters against f64 twins on run 0.
    pub struct F32VsF64 {
        /// Largest angle between the f32 and f64 six-state estimates.
        #[metric(unit = "rad")] pub six_state_max_rad: f64,
        /// Largest angle between the f32 and f64 rigid-body estimates.
        #[metric(unit = "rad")] pub rigid_body_max_rad: f64,
        /// The six-state difference over its RMS error.
        #[metric(unit = "")] pub six_state_fraction_of_rms: f64,
        /// The rigid-body difference over its RMS error.
        #[metric(unit = "")] pub rigid_body_fraction_of_rms: f64,
    }
}

crate::metrics! {
    /// The measurement noise of the variant.
    pub struct NoiseMetrics {
        /// Per-sample σ of a baseline component.
        #[metric(unit = "m")] pub sigma_baseline_m: f64,
        /// Per-sample σ of a velocity-difference component.
        #[metric(unit = "m/s")] pub sigma_velocity_m_s: f64,
        /// Step.
        #[metric(unit = "s")] pub dt_s: f64,
    }
}

crate::metrics! {
    /// What the issue asks of the filters.
    pub struct Acceptance {
        /// The six-state filter's largest RMS/bound.
        #[metric(unit = "")] pub six_state_rms_over_bound_max: f64,
        /// The rigid-body filter's largest RMS/bound.
        #[metric(unit = "")] pub rigid_body_rms_over_bound_max: f64,
        /// The rigid-body filter's rotation-vector RMS is below the six-state filter's.
        #[metric(unit = "")] pub rigid_body_beats_six_state: bool,
        /// Six-state RMS over rigid-body RMS.
        #[metric(unit = "")] pub rigid_body_gain_over_six_state: f64,
    }
}

crate::metrics! {
    /// How much the Doppler tells about the rotation under one noise reading.
    pub struct DopplerReading {
        /// Per-sample σ of the least-squares rate.
        #[metric(unit = "rad/s")] pub rate_sigma_per_sample_rad_s: f64,
        /// The filters' memory σ_p/σ_v.
        #[metric(unit = "s")] pub filter_memory_s: f64,
        /// |ω| over the per-sample rate σ.
        #[metric(unit = "")] pub doppler_rate_snr_per_sample: f64,
        /// The same over the filter memory.
        #[metric(unit = "")] pub doppler_rate_snr_over_memory: f64,
        /// Rate above which the Doppler observes the rotation within the memory (SNR 1).
        #[metric(unit = "rad/s")] pub crossover_rate_rad_s: f64,
    }
}

crate::metrics! {
    /// The `leo` variant: where the Doppler stops helping.
    pub struct LeoMetrics {
        /// Under the intensity noise reading.
        #[metric(nested)] pub intensity: DopplerReading,
        /// Under the literal noise reading.
        #[metric(nested)] pub literal: DopplerReading,
        /// Body rate at mid-run.
        #[metric(unit = "rad/s")] pub body_rate_rad_s: f64,
        /// The rigid-body filter fed zero velocity differences.
        #[metric(nested)] pub rigid_body_doppler_free: FilterMetrics,
        /// The rigid-body filter under the literal noise.
        #[metric(nested)] pub literal_rigid_body: FilterMetrics,
        /// Its Doppler-free twin under the literal noise.
        #[metric(nested)] pub literal_rigid_body_doppler_free: FilterMetrics,
        /// Whether the six-state filter accepts the paper's column choice here.
        #[metric(unit = "")] pub six_state_with_paper_columns: String,
    }
}

crate::metrics! {
    /// Metrics of `dcm`.
    pub struct Metrics {
        /// The paper's six-state filter (baselines 12/23).
        #[metric(nested)] pub six_state: FilterMetrics,
        /// The multi-structure filter.
        #[metric(nested)] pub multi_structure: MultiStructureMetrics,
        /// The rigid-body filter on the three baselines.
        #[metric(nested)] pub rigid_body: RigidBodyMetrics,
        /// The rigid-body filter on baselines 12/23 only (the six-state filter's data).
        #[metric(nested)] pub rigid_body_pair_12_23: FilterMetrics,
        /// f32 against f64.
        #[metric(nested)] pub f32_vs_f64: F32VsF64,
        /// The noise.
        #[metric(nested)] pub noise: NoiseMetrics,
        /// Monte Carlo runs.
        #[metric(unit = "")] pub runs: usize,
        /// Relative statistical uncertainty of the pooled RMS figures.
        #[metric(unit = "")] pub rms_relative_uncertainty: f64,
        /// Run length.
        #[metric(unit = "s")] pub duration_s: f64,
        /// Column of the DCM the six-state filter eliminates (1-based).
        #[metric(unit = "")] pub six_state_eliminated_column: usize,
        /// The acceptance figures.
        #[metric(nested)] pub acceptance: Acceptance,
        /// Whether the paper's quoted errors are within the six-state filter's bound.
        #[metric(unit = "")] pub paper_quoted_reachable_by_six_state: bool,
        /// Whether they are within the best filter's bound.
        #[metric(unit = "")] pub paper_quoted_reachable_by_any_filter: bool,
        /// The `leo` variant's Doppler study.
        #[metric(nested)] #[serde(skip_serializing_if = "Option::is_none")] pub leo: Option<LeoMetrics>,
    }
}
