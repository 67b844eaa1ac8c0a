//! The physical limit of the fine attitude, computed by host-sim (f64, no core code): the
//! posterior Cramér–Rao bound of a gyro-aided carrier-phase attitude estimator over the run.
//!
//! # Model
//!
//! The error state (16) is the body-frame attitude error `e` (3, rad), the two slave RF
//! chains' line biases `β` (B − A, C − A, rad) and their drift rates `β̇` (rad/s), and the
//! gyro's error parameters `c` of paper 001 (three scale factors, three symmetric
//! misalignments, three biases: [`paper_d`]):
//!
//! ```text
//! ė = −[ω]× e + D(ω) c + n_ARW        E[n nᵀ] = q_ARW I δ(t)
//! β̇ = r,  ṙ = 0                        (the truth's drift is linear)
//! ċ_{1..6} = 0,  ċ_{7..9} = n_b       E[n_b n_bᵀ] = q_b I δ(t)
//! ```
//!
//! with `ω(t)` the true body rate. Scale factors and misalignments are unknown parameters
//! with a prior, as are the biases at switch-on; an estimator that calibrates them (paper 001)
//! can reach the bound, one that does not is above it. The gyro's pulse quantization carries
//! its residual (the integrated angle's error stays within one pulse, 1e-5 rad) and is left
//! out.
//!
//! Each satellite `i` that two or three antennas receive adds, per second, the information
//! `2 (C/N0)_i H_iᵀ Π H_i` on `(e, β)` with `H_i = [G_i  E]`: `G_i` the phase gradient of
//! [`super::bound`] (rows `k (r_P × s_i)ᵀ`), `E` the selection of the slave chains' biases
//! (rows 0, 1, 0 / 0, 0, 1 for A, B, C) and `Π = I − 11ᵀ/n` over the `n` receiving antennas,
//! the projection that removes the unknown common phase and data bit. The bound follows the
//! information along the run: a Kalman covariance recursion in steps of at most
//! `MAX_STEP_S`, the information entering as unit-variance measurements through its square
//! root (numerically the stable form).
//!
//! `limit_deg` is the RMS of `√P_ee` per body axis over the converged stretch.

use nalgebra::{Matrix3, Matrix5, SMatrix, SVector, Vector3};

use crate::truth::gyro::{paper_d, GyroErrors};
use crate::truth::sky::L1_WAVELENGTH_M;

/// Size of the error state.
const N: usize = 16;
type StateMatrix = SMatrix<f64, N, N>;

/// Index of the attitude error, the line biases, their drifts and the gyro's parameters.
const E: usize = 0;
const BETA: usize = 3;
const DRIFT: usize = 5;
const GYRO: usize = 7;
const GYRO_BIAS: usize = GYRO + 6;

/// Longest step of the recursion, s: well below the gyro-aided loop's time constant
/// `1/(2√(q J))` (≈ 1 s on the default run), so that lumping the information of a step at
/// its end costs under a per cent.
const MAX_STEP_S: f64 = 0.02;

/// The prior the bound starts from (1σ).
#[derive(Clone, Copy, Debug)]
pub struct Prior {
    /// Attitude, rad (nothing known).
    pub attitude_rad: f64,
    /// Line biases, rad (nothing known: π).
    pub line_bias_rad: f64,
    /// Line-bias drift rates, rad/s.
    pub line_bias_drift_rad_s: f64,
    /// Scale factors and misalignments, dimensionless / rad.
    pub scale_misalignment: f64,
    /// Gyro biases at switch-on, rad/s.
    pub gyro_bias_rad_s: f64,
}

/// One satellite as the limit sees it.
#[derive(Clone, Copy, Debug)]
pub struct Satellite {
    /// Line of sight, body axes (unit).
    pub los_body: Vector3<f64>,
    /// C/N0, dB-Hz.
    pub cn0_dbhz: f64,
    /// Which antennas (A, B, C) receive it.
    pub visible: [bool; 3],
}

/// `J = Σ 2 (C/N0)_i H_iᵀ Π H_i` on `(e, β)`, 1/(rad² s), for antennas at `positions` (body,
/// m): over each satellite's receiving antennas (at least two), `Π = I − 11ᵀ/n` on them.
pub fn information_rate(positions: &[Vector3<f64>; 3], satellites: &[Satellite]) -> Matrix5<f64> {
    let k = std::f64::consts::TAU / L1_WAVELENGTH_M;
    let mut j = Matrix5::zeros();
    for sat in satellites {
        let n = sat.visible.iter().filter(|v| **v).count();
        if n < 2 {
            continue;
        }
        let cn0 = 10f64.powf(sat.cn0_dbhz / 10.0);
        let mut h = SMatrix::<f64, 3, 5>::zeros();
        for (p, r) in positions.iter().enumerate() {
            h.fixed_view_mut::<1, 3>(p, 0)
                .copy_from(&(r.cross(&sat.los_body) * k).transpose());
        }
        h[(1, 3)] = 1.0;
        h[(2, 4)] = 1.0;
        // Π over the receiving antennas, zero rows and columns for the others
        let on = Vector3::from(sat.visible.map(|v| if v { 1.0 } else { 0.0 }));
        let pi = Matrix3::from_diagonal(&on) - on * on.transpose() / n as f64;
        j += h.transpose() * pi * h * (2.0 * cn0);
    }
    j
}

/// The bound's recursion: the posterior covariance of the error state.
pub struct Limit {
    p: StateMatrix,
    arw: f64,
    bias_rw: f64,
}

impl Limit {
    /// Starts from `prior` for a gyro with `errors`' noise densities.
    pub fn new(prior: &Prior, errors: &GyroErrors) -> Self {
        let mut d = SVector::<f64, N>::zeros();
        let mut set = |from: usize, len: usize, sigma: f64| {
            for i in from..from + len {
                d[i] = sigma * sigma;
            }
        };
        set(E, 3, prior.attitude_rad);
        set(BETA, 2, prior.line_bias_rad);
        set(DRIFT, 2, prior.line_bias_drift_rad_s);
        set(GYRO, 6, prior.scale_misalignment);
        set(GYRO_BIAS, 3, prior.gyro_bias_rad_s);
        Self {
            p: StateMatrix::from_diagonal(&d),
            arw: errors.arw,
            bias_rw: errors.bias_rw,
        }
    }

    /// Propagates over `dt` seconds at body rate `omega` (rad/s).
    pub fn propagate(&mut self, omega: &Vector3<f64>, dt: f64) {
        let mut f = StateMatrix::zeros();
        f.fixed_view_mut::<3, 3>(E, E)
            .copy_from(&-omega.cross_matrix());
        f.fixed_view_mut::<3, 9>(E, GYRO).copy_from(&paper_d(omega));
        f.fixed_view_mut::<2, 2>(BETA, DRIFT)
            .copy_from(&nalgebra::Matrix2::identity());
        let fdt = f * dt;
        let phi = StateMatrix::identity() + fdt + fdt * fdt / 2.0 + fdt * fdt * fdt / 6.0;
        let mut qc = StateMatrix::zeros();
        for i in 0..3 {
            qc[(E + i, E + i)] = self.arw * self.arw;
            qc[(GYRO_BIAS + i, GYRO_BIAS + i)] = self.bias_rw * self.bias_rw;
        }
        let q = qc * dt + (f * qc + qc * f.transpose()) * (dt * dt / 2.0);
        self.p = phi * self.p * phi.transpose() + q;
        self.symmetrize();
    }

    /// Adds `information` (on `(e, β)`, 1/(rad² s)) gathered over `dt` seconds.
    pub fn inform(&mut self, information: &Matrix5<f64>, dt: f64) {
        let eig = (information * dt).symmetric_eigen();
        for (lambda, v) in eig.eigenvalues.iter().zip(eig.eigenvectors.column_iter()) {
            if !(*lambda > 0.0 && lambda.is_finite()) {
                continue;
            }
            // one unit-variance scalar measurement y = √λ vᵀ x_(e,β)
            let mut h = SVector::<f64, N>::zeros();
            h.fixed_rows_mut::<5>(E).copy_from(&(v * lambda.sqrt()));
            let ph = self.p * h;
            let s = 1.0 + h.dot(&ph);
            self.p -= ph * ph.transpose() / s;
        }
        self.symmetrize();
    }

    /// `√P_ee` per body axis, rad.
    pub fn attitude_sigma(&self) -> Vector3<f64> {
        Vector3::new(self.p[(0, 0)], self.p[(1, 1)], self.p[(2, 2)]).map(|v| v.max(0.0).sqrt())
    }

    /// `√P_ββ` per slave chain, rad.
    pub fn line_bias_sigma(&self) -> [f64; 2] {
        [BETA, BETA + 1].map(|i| self.p[(i, i)].max(0.0).sqrt())
    }

    fn symmetrize(&mut self) {
        self.p = (self.p + self.p.transpose()) * 0.5;
    }
}

/// The bound along a run: at each `(t, ω, J)` (s, rad/s, 1/(rad² s)) the attitude σ per body
/// axis, rad. The information of a record counts from the previous record's time.
pub fn along(
    records: impl Iterator<Item = (f64, Vector3<f64>, Matrix5<f64>)>,
    prior: &Prior,
    errors: &GyroErrors,
) -> Vec<Vector3<f64>> {
    let mut limit = Limit::new(prior, errors);
    let mut last: Option<f64> = None;
    records
        .map(|(t, omega, j)| {
            if let Some(t0) = last {
                let steps = ((t - t0) / MAX_STEP_S).ceil().max(1.0);
                let dt = (t - t0) / steps;
                for _ in 0..steps as usize {
                    if dt <= 0.0 {
                        break;
                    }
                    limit.propagate(&omega, dt);
                    if j.iter().all(|v| v.is_finite()) {
                        limit.inform(&j, dt);
                    }
                }
            }
            last = Some(t);
            limit.attitude_sigma()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle() -> [Vector3<f64>; 3] {
        [
            Vector3::new(0.29, 0.0, -0.05),
            Vector3::new(-0.14, 0.25, -0.05),
            Vector3::new(-0.14, -0.25, -0.05),
        ]
    }

    fn sky() -> Vec<Satellite> {
        [
            (0.3, -0.2, -0.9),
            (-0.5, 0.4, -0.7),
            (0.6, 0.5, -0.6),
            (-0.2, -0.7, -0.65),
            (0.05, 0.1, -1.0),
        ]
        .iter()
        .map(|&(x, y, z)| Satellite {
            los_body: Vector3::new(x, y, z).normalize(),
            cn0_dbhz: 45.0,
            visible: [true; 3],
        })
        .collect()
    }

    fn quiet_gyro(arw: f64) -> GyroErrors {
        GyroErrors {
            arw,
            bias_rw: 0.0,
            ..GyroErrors::mems()
        }
    }

    fn prior() -> Prior {
        Prior {
            attitude_rad: 1.0,
            line_bias_rad: std::f64::consts::PI,
            line_bias_drift_rad_s: 1e-5,
            scale_misalignment: 2e-3,
            gyro_bias_rad_s: 5e-4,
        }
    }

    /// With known line biases and a perfect gyro at rest, the bound after `T` seconds is the
    /// batch bound `√((J T)⁻¹)` of the attitude block.
    #[test]
    fn without_gyro_noise_the_bound_is_the_batch_bound() {
        let j = information_rate(&triangle(), &sky());
        let mut p = prior();
        p.line_bias_rad = 1e-9;
        p.line_bias_drift_rad_s = 1e-15;
        p.scale_misalignment = 1e-12;
        p.gyro_bias_rad_s = 1e-12;
        let t_end = 10.0;
        let records = (0..=100).map(|k| (k as f64 * 0.1, Vector3::zeros(), j));
        let sigma = *along(records, &p, &quiet_gyro(0.0)).last().unwrap();
        let jee = j.fixed_view::<3, 3>(0, 0).into_owned() * t_end;
        let batch = jee.try_inverse().unwrap().diagonal().map(f64::sqrt);
        for a in 0..3 {
            assert!(
                (sigma[a] / batch[a] - 1.0).abs() < 1e-3,
                "{sigma} vs {batch}"
            );
        }
    }

    /// The gyro-aided steady state of one axis with information rate `j` and angle random
    /// walk `q` solves `q − P² j = 0`: `σ = (q/j)^¼`. Check the scaling law.
    #[test]
    fn the_steady_state_scales_as_the_fourth_root_of_q_over_j() {
        let j = information_rate(&triangle(), &sky());
        let mut known = prior();
        known.line_bias_rad = 1e-9;
        known.line_bias_drift_rad_s = 1e-15;
        known.gyro_bias_rad_s = 1e-12;
        let run = |arw: f64, scale: f64| {
            // steps well below the loop's time constant (≥ 2 s here), 100 s to settle
            let records = (0..=10_000).map(|k| (k as f64 * 0.01, Vector3::zeros(), j * scale));
            *along(records, &known, &quiet_gyro(arw)).last().unwrap()
        };
        let base = run(1e-5, 1.0);
        let more_noise = run(16e-5, 1.0); // q × 256 → σ × 4
        let more_info = run(1e-5, 16.0); // j × 16 → σ / 2
        for a in 0..3 {
            // the record interval's discretization holds it to a few per cent
            assert!(
                (more_noise[a] / base[a] / 4.0 - 1.0).abs() < 0.05,
                "{more_noise} {base}"
            );
            assert!(
                (base[a] / more_info[a] / 2.0 - 1.0).abs() < 0.05,
                "{more_info} {base}"
            );
        }
    }

    /// Unknown line biases cost information: the bound with them is above the bound without.
    #[test]
    fn unknown_line_biases_raise_the_bound() {
        let j = information_rate(&triangle(), &sky());
        let records = || (0..=600).map(|k| (k as f64 * 0.1, Vector3::zeros(), j));
        let unknown = *along(records(), &prior(), &quiet_gyro(1e-4))
            .last()
            .unwrap();
        let mut known = prior();
        known.line_bias_rad = 1e-9;
        known.line_bias_drift_rad_s = 1e-15;
        let known = *along(records(), &known, &quiet_gyro(1e-4)).last().unwrap();
        for a in 0..3 {
            assert!(unknown[a] >= known[a] * (1.0 - 1e-9), "{unknown} {known}");
        }
        assert!((unknown - known).norm() > 1e-3 * known.norm());
    }

    /// A satellite two antennas receive carries their difference; one antenna alone, nothing.
    #[test]
    fn a_blocked_antenna_leaves_the_other_pair() {
        let mut sats = sky();
        let all = information_rate(&triangle(), &sats);
        for s in &mut sats {
            s.visible = [true, false, true];
        }
        let pair = information_rate(&triangle(), &sats);
        assert!(pair.trace() > 0.1 * all.trace() && pair.trace() < all.trace());
        // nothing on B's bias
        assert!(pair.row(3).norm() < 1e-9 * all.norm());
        for s in &mut sats {
            s.visible = [true, false, false];
        }
        assert_eq!(information_rate(&triangle(), &sats), Matrix5::zeros());
    }
}
