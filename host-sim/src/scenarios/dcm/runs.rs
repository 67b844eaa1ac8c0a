//! One Monte Carlo run of the `dcm` scenario: truth, measurements, every filter, error
//! statistics against the truth.

use anyhow::anyhow;
use gnss_attitude::attitude::array::AntennaArray;
use gnss_attitude::attitude::baseline_epoch::BaselineEpoch;
use gnss_attitude::attitude::dcm_filter::{DcmFilterConfig, DirectionCosineFilter};
use gnss_attitude::attitude::direction_cosine::ColumnChoice;
use gnss_attitude::attitude::filter_estimate::{FilterEstimate, FilterHealth};
use gnss_attitude::attitude::multi_structure::MultiStructureFilter;
use gnss_attitude::attitude::rigid_body::{RigidBodyConfig, RigidBodyFilter};
use gnss_attitude::ekf::GateConfidence;
use gnss_attitude::geometry::Quaternion;
use gnss_attitude::Real;
use nalgebra::{Matrix3, Rotation3, SMatrix, UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::bounds::Noise;
use super::truth::{self, Motion};

/// Initial attitude error of every filter, rad per axis (the spec's "small error"), and the
/// matching initial covariances: `1e-4 I` for `Ŷ` and for `δθ`.
pub const SIGMA_INITIAL: f64 = 0.01;
/// Time-series decimation for CSV and plots, steps.
pub const DECIMATE: usize = 100;

/// One variant's set-up.
#[derive(Clone, Copy, Debug)]
pub struct Setup {
    /// Truth motion.
    pub motion: Motion,
    /// Antenna array, body axes.
    pub array: AntennaArray<f64>,
    /// Noise and step.
    pub noise: Noise,
    /// Run length, s.
    pub duration: f64,
    /// Column choice of the six-state filters.
    pub columns: ColumnChoice,
    /// Also run the Doppler-free comparison and the literal-noise pair (LEO).
    pub doppler_study: Option<Noise>,
}

/// Error statistics of one filter over one run (second half unless named otherwise).
#[derive(Clone, Debug, Default)]
pub struct Track {
    /// Σ e_i² per body axis.
    pub sum_sq: [f64; 3],
    /// Epochs in the second half.
    pub count: usize,
    /// max |e_i| per axis.
    pub max_abs: [f64; 3],
    /// Σ |e|².
    pub sum_sq_rotvec: f64,
    /// Error at the last epoch, per axis.
    pub final_err: [f64; 3],
    /// 3-2-1 angle errors (α, β, γ) at the last epoch.
    pub final_euler_err: [f64; 3],
    /// Σ P_ii (the filter's own variance) per axis.
    pub sum_var: [f64; 3],
    /// Σ NIS and its degrees of freedom.
    pub sum_nis: f64,
    /// NIS degrees of freedom of the last estimate.
    pub nis_dof: u8,
    /// Epochs (whole run) whose health was not nominal.
    pub not_nominal: usize,
    /// Steps that returned an error (whole run).
    pub failures: usize,
    /// Decimated series `(t, error, σ)` (whole run), kept for run 0 only.
    pub series: Vec<(f64, [f64; 3], [f64; 3])>,
}

fn to_f64<T: Real>(m: &Matrix3<T>) -> Matrix3<f64> {
    m.map(|v| nalgebra::try_convert(v).unwrap_or(f64::NAN))
}

/// The 3-2-1 angles (α, β, γ) of a DCM, host formulas.
fn euler(m: &Matrix3<f64>) -> [f64; 3] {
    [
        m[(1, 0)].atan2(m[(0, 0)]),
        -m[(2, 0)].clamp(-1.0, 1.0).asin(),
        m[(2, 1)].atan2(m[(2, 2)]),
    ]
}

fn wrap(a: f64) -> f64 {
    (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
}

/// The attitude error `log(M_trueᵀ Ĉ)`, body axes, rad (the spec's definition).
pub fn attitude_error(truth: &Matrix3<f64>, estimate: &Matrix3<f64>) -> Vector3<f64> {
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(
        truth.transpose() * estimate,
    ))
    .scaled_axis()
}

/// Where in the run an estimate belongs.
#[derive(Clone, Copy)]
struct At<'a> {
    step: usize,
    t: f64,
    second_half: bool,
    last: bool,
    keep_series: bool,
    truth: &'a Matrix3<f64>,
}

impl Track {
    fn record<T: Real>(
        &mut self,
        at: &At<'_>,
        result: Result<FilterEstimate<T>, gnss_attitude::attitude::dcm_filter::DcmError>,
    ) {
        let At {
            step,
            t,
            second_half,
            last,
            keep_series,
            truth,
        } = *at;
        let est = match result {
            Ok(e) => e,
            Err(_) => {
                self.failures += 1;
                return;
            }
        };
        let c = to_f64(&est.c_rb);
        let e = attitude_error(truth, &c);
        let p = to_f64(&est.covariance);
        if est.health != FilterHealth::Nominal {
            self.not_nominal += 1;
        }
        if second_half {
            self.count += 1;
            for i in 0..3 {
                self.sum_sq[i] += e[i] * e[i];
                self.max_abs[i] = self.max_abs[i].max(e[i].abs());
                self.sum_var[i] += p[(i, i)];
            }
            self.sum_sq_rotvec += e.norm_squared();
            self.sum_nis += nalgebra::try_convert::<T, f64>(est.nis).unwrap_or(f64::NAN);
            self.nis_dof = est.nis_dof;
        }
        if last {
            self.final_err = [e.x, e.y, e.z];
            let (a, b) = (euler(truth), euler(&c));
            self.final_euler_err = [wrap(b[0] - a[0]), b[1] - a[1], wrap(b[2] - a[2])];
        }
        if keep_series && step % DECIMATE == 0 {
            self.series.push((
                t,
                [e.x, e.y, e.z],
                [p[(0, 0)].sqrt(), p[(1, 1)].sqrt(), p[(2, 2)].sqrt()],
            ));
        }
    }
}

/// What one run produced.
#[derive(Clone, Debug, Default)]
pub struct RunResult {
    /// The paper's filter on baselines 12/23 (structure 1 of the multi-structure filter).
    pub six_state: Track,
    /// The robust combination of the three structures.
    pub multi_structure: Track,
    /// Structures 2 and 3 of the multi-structure filter (pairs 12/13 and 23/13) on their own.
    pub structures_b13: [Track; 2],
    /// Epochs at which each structure entered the combination.
    pub inlier_counts: [usize; 3],
    /// The rigid-body filter on the three baselines.
    pub rigid_body: Track,
    /// The rigid-body filter on baselines 12/23 only (the six-state filter's data).
    pub rigid_body_pair: Track,
    /// LEO: the rigid-body filter fed zero velocity differences.
    pub doppler_free: Track,
    /// LEO: rigid-body filter under the literal noise reading.
    pub literal_rigid_body: Track,
    /// LEO: its Doppler-free twin under the literal noise reading.
    pub literal_doppler_free: Track,
    /// Run 0: largest angle between the f32 and f64 six-state (and rigid-body) estimates, rad.
    pub f32_vs_f64: Option<(f64, f64)>,
}

fn rigid<T: Real>(
    array: &AntennaArray<f64>,
    noise: Noise,
    c0: &Matrix3<f64>,
) -> anyhow::Result<RigidBodyFilter<T>> {
    let cv = |v: f64| -> T { nalgebra::convert(v) };
    let q0 = Quaternion::from_dcm(&c0.map(cv)).map_err(|e| anyhow!("{e}"))?;
    let array_t =
        AntennaArray::new(array.positions().map(|p| p.map(cv))).map_err(|e| anyhow!("{e}"))?;
    RigidBodyFilter::new(
        &array_t,
        RigidBodyConfig {
            dt: cv(noise.dt),
            sigma_baseline: cv(noise.sigma_baseline),
            sigma_velocity: cv(noise.sigma_velocity),
            gate: Some(GateConfidence::P999),
        },
        &q0,
        &(Matrix3::identity() * cv(SIGMA_INITIAL * SIGMA_INITIAL)),
    )
    .map_err(|e| anyhow!("rigid-body filter: {e}"))
}

fn six_state_config<T: Real>(setup: &Setup) -> DcmFilterConfig<T> {
    let cv = |v: f64| -> T { nalgebra::convert(v) };
    DcmFilterConfig {
        columns: setup.columns,
        ..DcmFilterConfig::paper(
            cv(setup.noise.dt),
            cv(setup.noise.sigma_baseline),
            cv(setup.noise.sigma_velocity),
        )
    }
}

/// Every filter of one run.
struct Filters {
    multi: MultiStructureFilter<f32>,
    rigid_all: RigidBodyFilter<f32>,
    rigid_pair: RigidBodyFilter<f32>,
    doppler_free: RigidBodyFilter<f32>,
    literal_rigid: RigidBodyFilter<f32>,
    literal_free: RigidBodyFilter<f32>,
    six64: DirectionCosineFilter<f64>,
    rigid64: RigidBodyFilter<f64>,
}

impl Filters {
    /// All filters started from `c0` (the literal-noise pair with `literal`).
    fn new(setup: &Setup, c0: &Matrix3<f64>, literal: Noise) -> anyhow::Result<Self> {
        let noise = setup.noise;
        let array32 = AntennaArray::new(setup.array.positions().map(|p| p.cast::<f32>()))
            .map_err(|e| anyhow!("{e}"))?;
        let r0 = SMatrix::<f32, 6, 6>::identity() * (SIGMA_INITIAL * SIGMA_INITIAL) as f32;
        Ok(Self {
            multi: MultiStructureFilter::new(
                &array32,
                six_state_config(setup),
                &c0.cast::<f32>(),
                &r0,
            )
            .map_err(|e| anyhow!("multi-structure filter: {e}"))?,
            rigid_all: rigid::<f32>(&setup.array, noise, c0)?,
            rigid_pair: rigid::<f32>(&setup.array, noise, c0)?,
            doppler_free: rigid::<f32>(&setup.array, noise, c0)?,
            literal_rigid: rigid::<f32>(&setup.array, literal, c0)?,
            literal_free: rigid::<f32>(&setup.array, literal, c0)?,
            six64: DirectionCosineFilter::<f64>::new(
                &setup.array,
                six_state_config(setup),
                c0,
                &(SMatrix::<f64, 6, 6>::identity() * SIGMA_INITIAL * SIGMA_INITIAL),
            )
            .map_err(|e| anyhow!("six-state filter (f64): {e}"))?,
            rigid64: rigid::<f64>(&setup.array, noise, c0)?,
        })
    }
}

/// The multi-structure filter's step into the six-state, per-structure and fused tracks;
/// returns the six-state estimate (f64) for the f32-vs-f64 comparison.
fn record_multi(
    out: &mut RunResult,
    at: &At<'_>,
    multi_result: Result<
        gnss_attitude::attitude::multi_structure::MultiStructureEstimate<f32>,
        gnss_attitude::attitude::dcm_filter::DcmError,
    >,
) -> Option<Matrix3<f64>> {
    use gnss_attitude::attitude::dcm_filter::DcmError;
    let six32 = multi_result
        .as_ref()
        .ok()
        .and_then(|m| m.structures[0])
        .map(|e| to_f64(&e.c_rb));
    match multi_result {
        Ok(m) => {
            out.six_state
                .record(at, m.structures[0].ok_or(DcmError::NotARotation));
            for (track, e) in out.structures_b13.iter_mut().zip(&m.structures[1..]) {
                let quiet = At {
                    keep_series: false,
                    ..*at
                };
                track.record(&quiet, e.ok_or(DcmError::NotARotation));
            }
            for (c, i) in out.inlier_counts.iter_mut().zip(m.inliers) {
                *c += usize::from(i);
            }
            out.multi_structure.record(at, Ok(m.fused));
        }
        Err(e) => {
            out.six_state.record::<f32>(at, Err(e));
            out.multi_structure.record::<f32>(at, Err(e));
        }
    }
    six32
}

/// Runs every filter over one realization.
pub fn one_run(setup: &Setup, seed: u64, run: usize) -> anyhow::Result<RunResult> {
    let mut rng =
        ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0x9E37_79B9).wrapping_add(run as u64));
    let mut rng_literal = ChaCha8Rng::seed_from_u64(
        seed.wrapping_mul(0x85EB_CA6B)
            .wrapping_add(run as u64 + 1000),
    );
    let noise = setup.noise;
    let m0 = setup.motion.attitude(0.0);
    let c0 = m0 * truth::small_rotation(&mut rng, SIGMA_INITIAL);
    let literal = setup.doppler_study.unwrap_or(noise);
    let mut f = Filters::new(setup, &c0, literal)?;
    let reference = run == 0;
    let steps = (setup.duration / noise.dt).round() as usize;
    let mut out = RunResult::default();
    let mut diff = (0.0f64, 0.0f64);
    let mut m_prev = m0;
    for k in 1..=steps {
        let t = k as f64 * noise.dt;
        let m_now = setup.motion.attitude(t);
        let e64: BaselineEpoch<f64> = truth::epoch(
            &setup.array,
            &m_prev,
            &m_now,
            noise.dt,
            noise.sigma_baseline,
            noise.sigma_velocity,
            &mut rng,
        );
        let e32 = truth::epoch_f32(&e64);
        let at = At {
            step: k,
            t,
            second_half: t > setup.duration / 2.0,
            last: k == steps,
            keep_series: reference,
            truth: &m_now,
        };
        let six32 = record_multi(&mut out, &at, f.multi.step(&e32));
        let r = f.rigid_all.step(&e32);
        out.rigid_body.record(&at, r);
        let rp = f.rigid_pair.step(&truth::without_13(&e32));
        out.rigid_body_pair.record(&at, rp);
        if reference {
            let s64 = f.six64.step(&e64);
            let r64 = f.rigid64.step(&e64);
            if let (Ok(s64), Some(c32)) = (s64, six32) {
                diff.0 = diff.0.max(attitude_error(&s64.c_rb, &c32).norm());
            }
            if let (Ok(r64), Ok(r32)) = (r64, r) {
                diff.1 = diff
                    .1
                    .max(attitude_error(&r64.c_rb, &to_f64(&r32.c_rb)).norm());
            }
        }
        if setup.doppler_study.is_some() {
            let df = f.doppler_free.step(&truth::without_doppler(&e32));
            out.doppler_free.record(&at, df);
            let el = truth::epoch_f32(&truth::epoch(
                &setup.array,
                &m_prev,
                &m_now,
                literal.dt,
                literal.sigma_baseline,
                literal.sigma_velocity,
                &mut rng_literal,
            ));
            let lr = f.literal_rigid.step(&el);
            out.literal_rigid_body.record(&at, lr);
            let lf = f.literal_free.step(&truth::without_doppler(&el));
            out.literal_doppler_free.record(&at, lf);
        }
        m_prev = m_now;
    }
    if reference {
        out.f32_vs_f64 = Some(diff);
    }
    Ok(out)
}
