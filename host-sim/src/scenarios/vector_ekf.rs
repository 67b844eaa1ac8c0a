//! `vector-ekf`: the core's EKF toolkit tracking a tumbling rigid body from two noisy vector
//! measurements, over a Monte Carlo of runs.
//!
//! Truth (f64): attitude `q_rb` integrated exactly over 10 sub-steps per filter step, body rate
//! a random walk. Measurements every `DT`: two known reference directions `r₁, r₂` seen in body
//! axes, `b_i = C_rbᵀ r_i + v`, `v ~ N(0, σ² I₃)` (3 components each, not renormalized, so the
//! model is exactly linear-Gaussian in the measurement).
//!
//! Filter: a multiplicative (error-state) EKF on `[δθ; δω]` (6 states): the nominal attitude and
//! rate are propagated outside the toolkit, `δθ` is the body-frame attitude error
//! (`q_true = q̂ ⊗ exp(δθ)`), `H = [[b̂]× 0]`, and after each update the error is folded into
//! the nominal state and reset. It runs in f32 (as on the target) and, on the same data, in f64.
//!
//! Metrics: `rotvec_rms_rad` (attitude error, second half of the runs), `nees_mean` (average
//! NEES over runs and epochs; 6 for a consistent filter), `runs`, and the consistency figures
//! around them.

use gnss_attitude::ekf::{Ekf, GateConfidence, NisGate};
use gnss_attitude::geometry::{skew, Quaternion};
use gnss_attitude::Real;
use nalgebra::{SMatrix, SVector, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

use super::{Outcome, RunContext, Scenario, Variant, Variants};
use crate::report::{plot_lines, plot_panels, progress, write_csv, Panel, Series};
use crate::stats;
use crate::truth::kinematics::step_constant_rate;

/// The scenario.
pub const SCENARIO: Scenario = Scenario {
    name: "vector-ekf",
    about:
        "EKF toolkit: multiplicative attitude EKF from two vector measurements, Monte Carlo NEES",
    variants: &Variants {
        list: &[
            Variant::new(
                "nominal",
                "0.06 rad/s tumble, σ = 0.01, 200 runs of 120 s",
                Config {
                    omega_mean: [0.03, -0.02, 0.045],
                },
            ),
            Variant::new(
                "fast-tumble",
                "0.6 rad/s tumble: linearization over 0.06 rad steps",
                Config {
                    omega_mean: [0.3, -0.2, 0.45],
                },
            ),
        ],
        run,
    },
};

/// Filter step, s.
const DT: f64 = 0.1;
/// Truth sub-steps per filter step.
const SUBSTEPS: usize = 10;
/// Duration of a run, s.
const DURATION: f64 = 120.0;
/// Monte Carlo runs.
const RUNS: usize = 200;
/// Measurement noise per component (unit vectors, dimensionless).
const SIGMA_V: f64 = 0.01;
/// Rate random-walk spectral density, rad/s/√s.
const SIGMA_RW: f64 = 2e-4;
/// Initial attitude error, rad per axis; initial rate error, rad/s per axis.
const SIGMA_THETA0: f64 = 0.1;
const SIGMA_OMEGA0: f64 = 0.01;

/// What a variant changes: the mean body rate of the tumble.
#[derive(Clone, Copy)]
pub struct Config {
    /// Mean body rate, rad/s.
    omega_mean: [f64; 3],
}

/// Degrees of freedom of the NEES (the six error states).
const NEES_DOF: usize = 6;
/// Probability outside the NEES interval.
const NEES_ALPHA: f64 = 0.05;

/// One epoch of one run.
#[derive(Clone, Copy, Default)]
struct Epoch {
    t: f64,
    err: [f64; 3],
    sigma: [f64; 3],
    nees: f64,
    accepted: bool,
}

/// One run, with the f32 and the f64 filter on the same data.
struct RunResult {
    f32_epochs: Vec<Epoch>,
    f64_epochs: Vec<Epoch>,
    /// Largest angle between the f32 and f64 estimates over the run, rad.
    f32_vs_f64_max: f64,
}

/// The error-state filter, generic over the scalar so that f32 and f64 run the same code.
struct VectorAttitudeEkf<T: Real> {
    q_rb: Quaternion<T>,
    omega_b: Vector3<T>,
    ekf: Ekf<6, T>,
    /// Consecutive measurements rejected by the gate.
    rejected_in_a_row: u32,
}

/// After this many consecutive rejections the next measurement is applied ungated: a gate that
/// keeps rejecting means the estimate, not the data, has gone astray (or has not converged yet:
/// with a 0.1 rad prior the first innovations carry second-order terms of ~2σ).
const GATE_RECOVERY: u32 = 3;

fn c<T: Real>(v: f64) -> T {
    nalgebra::convert(v)
}

impl<T: Real> VectorAttitudeEkf<T> {
    fn new(q_rb: Quaternion<f64>, omega_b: Vector3<f64>) -> anyhow::Result<Self> {
        let mut p0 = SMatrix::<T, 6, 6>::zeros();
        for i in 0..3 {
            p0[(i, i)] = c(SIGMA_THETA0 * SIGMA_THETA0);
            p0[(i + 3, i + 3)] = c(SIGMA_OMEGA0 * SIGMA_OMEGA0);
        }
        let ekf = Ekf::new(SVector::zeros(), p0).map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(Self {
            q_rb: Quaternion::new(c(q_rb.w), c(q_rb.x), c(q_rb.y), c(q_rb.z)),
            omega_b: omega_b.map(c),
            ekf,
            rejected_in_a_row: GATE_RECOVERY,
        })
    }

    fn predict(&mut self, dt: T) -> anyhow::Result<()> {
        // nominal: q ← q ⊗ exp(ω̂ dt); error: δθ' = exp(−[ω̂ dt]×) δθ + δω dt, δω' = δω + w
        let step = Quaternion::from_rotation_vector(&(self.omega_b * dt));
        self.q_rb = (self.q_rb * step)
            .normalize()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let mut f = SMatrix::<T, 6, 6>::identity();
        f.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&step.conjugate().to_dcm());
        f.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&(nalgebra::Matrix3::identity() * dt));
        let q = c::<T>(SIGMA_RW * SIGMA_RW);
        let mut qm = SMatrix::<T, 6, 6>::zeros();
        for i in 0..3 {
            qm[(i, i)] = q * dt * dt * dt / c(3.0);
            qm[(i, i + 3)] = q * dt * dt / c(2.0);
            qm[(i + 3, i)] = q * dt * dt / c(2.0);
            qm[(i + 3, i + 3)] = q * dt;
        }
        self.ekf
            .predict_to(&SVector::zeros(), &f, &qm)
            .map_err(|e| anyhow::anyhow!("{e}"))
    }

    fn update(
        &mut self,
        refs: &[Vector3<f64>; 2],
        meas: &[Vector3<f64>; 2],
    ) -> anyhow::Result<bool> {
        let c_br = self.q_rb.conjugate().to_dcm();
        let mut y = SVector::<T, 6>::zeros();
        let mut h = SMatrix::<T, 6, 6>::zeros();
        for i in 0..2 {
            let b_hat = c_br * refs[i].map(c::<T>);
            y.fixed_rows_mut::<3>(3 * i)
                .copy_from(&(meas[i].map(c::<T>) - b_hat));
            h.fixed_view_mut::<3, 3>(3 * i, 0).copy_from(&skew(&b_hat)); // ∂b/∂δθ = [b̂]×
        }
        let r = SMatrix::<T, 6, 6>::identity() * c::<T>(SIGMA_V * SIGMA_V);
        let gate = (self.rejected_in_a_row < GATE_RECOVERY)
            .then(|| NisGate::chi_square(6, GateConfidence::P999));
        let report = self
            .ekf
            .update(&y, &h, &r, gate)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        self.rejected_in_a_row = if report.accepted {
            0
        } else {
            self.rejected_in_a_row + 1
        };
        // fold the error into the nominal state and reset it
        let x = *self.ekf.state();
        let dtheta = Vector3::new(x[0], x[1], x[2]);
        self.q_rb = (self.q_rb * Quaternion::from_rotation_vector(&dtheta))
            .normalize()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        self.omega_b += Vector3::new(x[3], x[4], x[5]);
        self.ekf
            .set_state(SVector::zeros())
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(report.accepted)
    }

    fn attitude_f64(&self) -> Quaternion<f64> {
        let q = self.q_rb;
        Quaternion::new(
            nalgebra::try_convert(q.w).unwrap_or(f64::NAN),
            nalgebra::try_convert(q.x).unwrap_or(f64::NAN),
            nalgebra::try_convert(q.y).unwrap_or(f64::NAN),
            nalgebra::try_convert(q.z).unwrap_or(f64::NAN),
        )
    }

    /// Error against the truth: `[δθ; δω]` with `q_true = q̂ ⊗ exp(δθ)`, f64.
    fn epoch(
        &self,
        t: f64,
        q_true: &Quaternion<f64>,
        omega_true: &Vector3<f64>,
        accepted: bool,
    ) -> anyhow::Result<Epoch> {
        let dtheta = (self.attitude_f64().conjugate() * *q_true).to_rotation_vector();
        let omega_hat = self
            .omega_b
            .map(|v| nalgebra::try_convert(v).unwrap_or(f64::NAN));
        let domega = omega_true - omega_hat;
        let e = SVector::<f64, 6>::new(dtheta.x, dtheta.y, dtheta.z, domega.x, domega.y, domega.z);
        let p = self
            .ekf
            .covariance()
            .map(|v| nalgebra::try_convert(v).unwrap_or(f64::NAN));
        let nees = p
            .cholesky()
            .map(|ch| e.dot(&ch.solve(&e)))
            .ok_or_else(|| anyhow::anyhow!("covariance lost definiteness"))?;
        Ok(Epoch {
            t,
            err: [dtheta.x, dtheta.y, dtheta.z],
            sigma: [p[(0, 0)].sqrt(), p[(1, 1)].sqrt(), p[(2, 2)].sqrt()],
            nees,
            accepted,
        })
    }
}

fn unit(v: [f64; 3]) -> Vector3<f64> {
    Vector3::from(v).normalize()
}

fn gaussian3(rng: &mut ChaCha8Rng, sigma: f64) -> Vector3<f64> {
    Vector3::from_fn(|_, _| {
        sigma * <StandardNormal as Distribution<f64>>::sample(&StandardNormal, rng)
    })
}

fn one_run(cfg: Config, seed: u64, run: usize) -> anyhow::Result<RunResult> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(1_000_003).wrapping_add(run as u64));
    let refs = [unit([1.0, 0.2, -0.3]), unit([-0.2, 0.9, 0.4])];
    // truth initial state: random attitude, mean rate plus a random part
    let mut q_true = Quaternion::from_rotation_vector(&gaussian3(&mut rng, 2.0));
    let mut omega_true = Vector3::from(cfg.omega_mean) + gaussian3(&mut rng, SIGMA_OMEGA0);
    // filter initial state: drawn from its own prior around the truth
    let q0 =
        q_true * Quaternion::from_rotation_vector(&gaussian3(&mut rng, SIGMA_THETA0)).conjugate();
    let w0 = omega_true - gaussian3(&mut rng, SIGMA_OMEGA0);
    let mut f32_filter = VectorAttitudeEkf::<f32>::new(q0, w0)?;
    let mut f64_filter = VectorAttitudeEkf::<f64>::new(q0, w0)?;
    let steps = (DURATION / DT).round() as usize;
    let mut result = RunResult {
        f32_epochs: Vec::with_capacity(steps),
        f64_epochs: Vec::with_capacity(steps),
        f32_vs_f64_max: 0.0,
    };
    let h = DT / SUBSTEPS as f64;
    for k in 1..=steps {
        for _ in 0..SUBSTEPS {
            q_true = step_constant_rate(&q_true, &omega_true, h);
            omega_true += gaussian3(&mut rng, SIGMA_RW * h.sqrt());
        }
        let c_br = q_true.conjugate().to_dcm();
        let meas = [
            c_br * refs[0] + gaussian3(&mut rng, SIGMA_V),
            c_br * refs[1] + gaussian3(&mut rng, SIGMA_V),
        ];
        f32_filter.predict(DT as f32)?;
        f64_filter.predict(DT)?;
        let a32 = f32_filter.update(&refs, &meas)?;
        let a64 = f64_filter.update(&refs, &meas)?;
        let t = k as f64 * DT;
        result
            .f32_epochs
            .push(f32_filter.epoch(t, &q_true, &omega_true, a32)?);
        result
            .f64_epochs
            .push(f64_filter.epoch(t, &q_true, &omega_true, a64)?);
        let diff = f32_filter
            .attitude_f64()
            .angle_to(&f64_filter.attitude_f64());
        result.f32_vs_f64_max = result.f32_vs_f64_max.max(diff);
    }
    Ok(result)
}

fn norm3(v: &[f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

crate::metrics! {
    /// Metrics of `vector-ekf`.
    pub struct Metrics {
        /// Attitude error RMS (rotation vector), second half of every run, f32 filter.
        #[metric(unit = "rad")] pub rotvec_rms_rad: f64,
        /// NEES averaged over runs and epochs (6 for a consistent filter).
        #[metric(unit = "")] pub nees_mean: f64,
        /// Monte Carlo runs.
        #[metric(unit = "")] pub runs: usize,
        /// Degrees of freedom of the NEES.
        #[metric(unit = "")] pub nees_dof: usize,
        /// 95 % interval of the run-averaged NEES of a consistent filter.
        #[metric(unit = "")] pub nees_interval_95: [f64; 2],
        /// Fraction of epochs whose run-averaged NEES lies inside that interval.
        #[metric(unit = "")] pub nees_epochs_inside_95: f64,
        /// RMS of the filter's own predicted attitude σ (norm over the axes), second half.
        #[metric(unit = "rad")] pub predicted_rms_rad: f64,
        /// Attitude error RMS of the same filter in f64 on the same data.
        #[metric(unit = "rad")] pub rotvec_rms_rad_f64: f64,
        /// Largest angle between the f32 and f64 estimates over all runs.
        #[metric(unit = "rad")] pub f32_vs_f64_max_rad: f64,
        /// Fraction of measurements the NIS gate accepted.
        #[metric(unit = "")] pub accepted_fraction: f64,
    }
}

/// The pooled statistics of the runs.
struct Pooled {
    err32: Vec<f64>,
    err64: Vec<f64>,
    predicted: Vec<f64>,
    nees_all: Vec<f64>,
    nees_by_epoch: Vec<f64>,
    interval: (f64, f64),
    inside: f64,
    accepted: f64,
    f32_vs_f64: f64,
}

/// Errors, predicted σ and NEES over the second half of every run (NEES: all epochs).
fn pool(results: &[RunResult]) -> Pooled {
    let steps = results[0].f32_epochs.len();
    let half = steps / 2;
    let errors = |pick: fn(&RunResult) -> &Vec<Epoch>| -> Vec<f64> {
        results
            .iter()
            .flat_map(|r| pick(r)[half..].iter().map(|e| norm3(&e.err)))
            .collect()
    };
    let predicted: Vec<f64> = results
        .iter()
        .flat_map(|r| r.f32_epochs[half..].iter().map(|e| norm3(&e.sigma)))
        .collect();
    let nees_all: Vec<f64> = results
        .iter()
        .flat_map(|r| r.f32_epochs.iter().map(|e| e.nees))
        .collect();
    let (lo, hi) = stats::average_chi_square_interval(NEES_DOF, RUNS, NEES_ALPHA);
    let nees_by_epoch: Vec<f64> = (0..steps)
        .map(|k| results.iter().map(|r| r.f32_epochs[k].nees).sum::<f64>() / RUNS as f64)
        .collect();
    let inside = nees_by_epoch
        .iter()
        .filter(|&&n| n >= lo && n <= hi)
        .count() as f64
        / steps as f64;
    let accepted = results
        .iter()
        .flat_map(|r| r.f32_epochs.iter())
        .filter(|e| e.accepted)
        .count() as f64
        / (RUNS * steps) as f64;
    Pooled {
        err32: errors(|r| &r.f32_epochs),
        err64: errors(|r| &r.f64_epochs),
        predicted,
        nees_all,
        nees_by_epoch,
        interval: (lo, hi),
        inside,
        accepted,
        f32_vs_f64: results.iter().fold(0.0f64, |m, r| m.max(r.f32_vs_f64_max)),
    }
}

impl Pooled {
    fn metrics(&self) -> Metrics {
        Metrics {
            rotvec_rms_rad: stats::rms(&self.err32),
            nees_mean: stats::mean(&self.nees_all),
            runs: RUNS,
            nees_dof: NEES_DOF,
            nees_interval_95: [self.interval.0, self.interval.1],
            nees_epochs_inside_95: self.inside,
            predicted_rms_rad: stats::rms(&self.predicted),
            rotvec_rms_rad_f64: stats::rms(&self.err64),
            f32_vs_f64_max_rad: self.f32_vs_f64,
            accepted_fraction: self.accepted,
        }
    }

    fn summary(&self) -> Vec<String> {
        let (lo, hi) = self.interval;
        vec![
            format!(
                "{RUNS} runs x {DURATION} s at {} Hz, two vector measurements (σ = {SIGMA_V}), rate random walk {SIGMA_RW} rad/s/√s",
                1.0 / DT
            ),
            format!(
                "attitude error RMS (2nd half): f32 {:.3e} rad, f64 {:.3e} rad, filter-predicted {:.3e} rad",
                stats::rms(&self.err32),
                stats::rms(&self.err64),
                stats::rms(&self.predicted)
            ),
            format!(
                "NEES mean {:.3} (6 if consistent); run-averaged NEES inside its 95 % interval [{lo:.2}, {hi:.2}] at {:.1} % of epochs",
                stats::mean(&self.nees_all),
                100.0 * self.inside
            ),
        ]
    }
}

fn run(cfg: &Config, ctx: &RunContext) -> anyhow::Result<Outcome> {
    let cfg = *cfg;
    let bar = progress(RUNS as u64, "vector-ekf");
    let results: Vec<RunResult> = (0..RUNS)
        .into_par_iter()
        .map(|r| {
            let out = one_run(cfg, ctx.seed, r);
            bar.inc(1);
            out
        })
        .collect::<anyhow::Result<_>>()?;
    bar.finish_and_clear();
    let pooled = pool(&results);
    let mut outcome = Outcome::new(&pooled.metrics())?;
    outcome.summary = pooled.summary();
    if let Some(dir) = &ctx.out_dir {
        outcome.files = write_files(dir, &results[0].f32_epochs, &pooled)?;
    }
    Ok(outcome)
}

/// Run 0's errors as CSV and plot, and the run-averaged NEES with its band.
fn write_files(
    dir: &std::path::Path,
    run0: &[Epoch],
    pooled: &Pooled,
) -> anyhow::Result<Vec<std::path::PathBuf>> {
    let csv = dir.join("vector_ekf_run0.csv");
    write_csv(
        &csv,
        &[
            "t_s",
            "err_x_rad",
            "err_y_rad",
            "err_z_rad",
            "sigma_x_rad",
            "sigma_y_rad",
            "sigma_z_rad",
            "nees",
        ],
        run0.iter().map(|e| {
            [
                e.t, e.err[0], e.err[1], e.err[2], e.sigma[0], e.sigma[1], e.sigma[2], e.nees,
            ]
        }),
    )?;
    let panels: Vec<Panel> = ["x", "y", "z"]
        .iter()
        .enumerate()
        .map(|(i, axis)| Panel {
            y_label: format!("δθ_{axis} (rad)"),
            series: vec![
                Series::line(
                    format!("error {axis}"),
                    run0.iter().map(|e| (e.t, e.err[i])).collect(),
                    0,
                ),
                Series::bound(
                    "+3σ",
                    run0.iter().map(|e| (e.t, 3.0 * e.sigma[i])).collect(),
                    1,
                ),
                Series::bound(
                    "-3σ",
                    run0.iter().map(|e| (e.t, -3.0 * e.sigma[i])).collect(),
                    1,
                ),
            ],
        })
        .collect();
    let png = dir.join("vector_ekf_error.png");
    plot_panels(
        &png,
        "vector-ekf: attitude error of run 0 with ±3σ",
        "time (s)",
        &panels,
    )?;
    let nees_png = dir.join("vector_ekf_nees.png");
    let t: Vec<f64> = run0.iter().map(|e| e.t).collect();
    let (lo, hi) = pooled.interval;
    plot_lines(
        &nees_png,
        &format!("vector-ekf: NEES averaged over {RUNS} runs, 95 % band"),
        "time (s)",
        "average NEES",
        vec![
            Series::line(
                "average NEES",
                t.iter()
                    .zip(&pooled.nees_by_epoch)
                    .map(|(&a, &b)| (a, b))
                    .collect(),
                0,
            ),
            Series::bound("lower 95 %", t.iter().map(|&a| (a, lo)).collect(), 1),
            Series::bound("upper 95 %", t.iter().map(|&a| (a, hi)).collect(), 1),
        ],
    )?;
    Ok(vec![csv, png, nees_png])
}
