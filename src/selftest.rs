//! A deterministic computation that firmware runs on the target and compares with the host.
//!
//! [`run_ekf_self_test`] tracks a simulated object with the [`crate::ekf`] toolkit on data it
//! draws itself from a [`SplitMix64`] seed, so it needs no input and gives the same answer on
//! every IEEE-754 machine up to rounding differences of the math library. The firmware under
//! `examples/firmware` runs it under QEMU and exits with failure unless its report matches the
//! report computed on the host at build time.

use nalgebra::{Matrix2, Matrix2x4, Matrix4, Vector2, Vector4};

use crate::ekf::FilterError;
use crate::ekf::{Ekf, GateConfidence, NisGate, UpdateReport};
use crate::noise::{SplitMix64, StandardNormal};

/// Seed of the self-test's random stream.
pub const SELF_TEST_SEED: u64 = 0x5EED_A771_7D0E_0001;
/// Number of predict+update steps of the self-test.
pub const SELF_TEST_STEPS: usize = 200;
/// Step of the self-test model, seconds.
pub const SELF_TEST_DT: f32 = 0.1;
/// Standard deviation of the self-test's position measurements, metres.
pub const SELF_TEST_SIGMA_POS: f32 = 0.5;
/// Standard deviation of the self-test's white acceleration, m/s².
pub const SELF_TEST_SIGMA_ACC: f32 = 0.2;

/// The self-test model: a point moving in a plane with constant velocity plus white
/// acceleration; state `(p_x, p_y, v_x, v_y)` in metres and m/s, position measured.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ConstantVelocityModel {
    /// Transition matrix for one step.
    pub f: Matrix4<f32>,
    /// Process noise covariance for one step (discrete white-acceleration model).
    pub q: Matrix4<f32>,
    /// Measurement matrix (position).
    pub h: Matrix2x4<f32>,
    /// Measurement noise covariance, m².
    pub r: Matrix2<f32>,
}

impl ConstantVelocityModel {
    /// The model with time step `dt` (s), acceleration noise `sigma_acc` (m/s²) and
    /// measurement noise `sigma_pos` (m).
    pub fn new(dt: f32, sigma_acc: f32, sigma_pos: f32) -> Self {
        let mut f = Matrix4::identity();
        f.m13 = dt;
        f.m24 = dt;
        // Q = σa² [[dt⁴/4, dt³/2], [dt³/2, dt²]] per axis
        let qa = sigma_acc * sigma_acc;
        let (q11, q13, q33) = (
            qa * dt * dt * dt * dt / 4.0,
            qa * dt * dt * dt / 2.0,
            qa * dt * dt,
        );
        let q = Matrix4::new(
            q11, 0.0, q13, 0.0, //
            0.0, q11, 0.0, q13, //
            q13, 0.0, q33, 0.0, //
            0.0, q13, 0.0, q33,
        );
        let h = Matrix2x4::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0);
        let r = Matrix2::identity() * (sigma_pos * sigma_pos);
        Self { f, q, h, r }
    }

    /// One predict+update step of `ekf` with the measured position `z` (m), gated at 99.9 %.
    /// This is the step whose instruction count the CI budget reports.
    ///
    /// # Errors
    /// As [`Ekf::predict`] and [`Ekf::update`].
    pub fn step(&self, ekf: &mut Ekf<4>, z: &Vector2<f32>) -> Result<UpdateReport<2>, FilterError> {
        ekf.predict(&self.f, &self.q)?;
        let y = z - self.h * ekf.state();
        ekf.update(
            &y,
            &self.h,
            &self.r,
            Some(NisGate::chi_square(2, GateConfidence::P999)),
        )
    }
}

/// What the self-test computed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SelfTestReport {
    /// Final state estimate `(p_x, p_y, v_x, v_y)`, m and m/s.
    pub state: [f32; 4],
    /// Final true state, m and m/s.
    pub truth: [f32; 4],
    /// Trace of the final covariance.
    pub covariance_trace: f32,
    /// Mean NIS over all steps (≈ 2 for a consistent filter).
    pub mean_nis: f32,
    /// Mean NEES over the second half (≈ 4 for a consistent filter).
    pub mean_nees: f32,
    /// Number of measurements the gate accepted.
    pub accepted: u32,
}

impl SelfTestReport {
    /// Largest difference to another report, relative to `1 + |value|`, over every field.
    pub fn max_relative_difference(&self, other: &Self) -> f32 {
        let pairs = self
            .state
            .iter()
            .zip(other.state.iter())
            .chain(self.truth.iter().zip(other.truth.iter()))
            .chain([
                (&self.covariance_trace, &other.covariance_trace),
                (&self.mean_nis, &other.mean_nis),
                (&self.mean_nees, &other.mean_nees),
            ]);
        let mut worst = (self.accepted as f32 - other.accepted as f32).abs();
        for (a, b) in pairs {
            let d = (a - b).abs() / (1.0 + a.abs());
            worst = if d.is_nan() {
                f32::INFINITY
            } else {
                worst.max(d)
            };
        }
        worst
    }
}

/// Runs the self-test: [`SELF_TEST_STEPS`] steps of a [`ConstantVelocityModel`] on data drawn
/// from [`SELF_TEST_SEED`].
///
/// # Errors
/// Any [`FilterError`] of a step (none is expected: the data are well inside the model).
pub fn run_ekf_self_test() -> Result<SelfTestReport, FilterError> {
    let model = ConstantVelocityModel::new(SELF_TEST_DT, SELF_TEST_SIGMA_ACC, SELF_TEST_SIGMA_POS);
    let mut rng = SplitMix64::new(SELF_TEST_SEED);
    let mut normal = StandardNormal::new();
    let mut truth = Vector4::new(0.0, 0.0, 3.0, -1.0);
    let mut ekf = Ekf::new(
        Vector4::zeros(),
        Matrix4::from_diagonal(&Vector4::new(25.0, 25.0, 16.0, 16.0)),
    )?;
    let (mut nis_sum, mut nees_sum, mut accepted) = (0.0f32, 0.0f32, 0u32);
    let dt = SELF_TEST_DT;
    for k in 0..SELF_TEST_STEPS {
        // truth: constant velocity with a white acceleration held over the step
        let a = normal.vector::<2, _>(&mut rng, SELF_TEST_SIGMA_ACC);
        truth = model.f * truth
            + Vector4::new(0.5 * dt * dt * a.x, 0.5 * dt * dt * a.y, dt * a.x, dt * a.y);
        let z = model.h * truth + normal.vector::<2, _>(&mut rng, SELF_TEST_SIGMA_POS);
        let report = model.step(&mut ekf, &z)?;
        nis_sum += report.nis;
        accepted = accepted.saturating_add(u32::from(report.accepted)); // (one per step)
        if k >= SELF_TEST_STEPS / 2 {
            nees_sum += ekf.nees(&truth)?;
        }
    }
    let x = ekf.state();
    Ok(SelfTestReport {
        state: [x.x, x.y, x.z, x.w],
        truth: [truth.x, truth.y, truth.z, truth.w],
        covariance_trace: ekf.covariance().trace(),
        mean_nis: nis_sum / SELF_TEST_STEPS as f32,
        mean_nees: nees_sum / (SELF_TEST_STEPS - SELF_TEST_STEPS / 2) as f32,
        accepted,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn self_test_tracks_the_truth_consistently() {
        let r = run_ekf_self_test().unwrap();
        // Position error within a few σ of the steady-state position σ (~0.3 m).
        assert!((r.state[0] - r.truth[0]).abs() < 1.5, "{r:?}");
        assert!((r.state[1] - r.truth[1]).abs() < 1.5, "{r:?}");
        // NIS ≈ 2 (two measured components), NEES ≈ 4. The errors are correlated over ~10
        // steps, so 100 NEES samples are ~10 independent ones: std of the mean ≈ 0.9. The
        // Monte Carlo consistency test is in tests/ekf_toolkit.rs; this only catches gross
        // breakage.
        assert!(r.mean_nis > 1.4 && r.mean_nis < 2.8, "{r:?}");
        assert!(r.mean_nees > 1.0 && r.mean_nees < 8.0, "{r:?}");
        assert!(r.accepted >= 198);
        assert_eq!(r.max_relative_difference(&r), 0.0);
    }
}
