//! A MEMS rate gyro triad, f64: the error model of paper 001 (scale factors, symmetric
//! misalignments, biases), angle random walk, bias random walk, and quantized pulse output.
//!
//! Measured rate `ω* = ω + D(ω) c + n`, `D(ω) = [D_I D_II E₃]` with
//! `D_I = diag(ω₁, ω₂, ω₃)`, `D_II = [[ω₂, 0, ω₃], [ω₁, ω₃, 0], [0, ω₂, ω₁]]`: `c₁..₃` scale
//! factors, `c₄..₆` symmetric misalignments, `c₇..₉` biases (rad/s). The output over each
//! interval `H` is the increment `θ = ∫ ω* dt` (rad), or, quantized, the number of pulses of
//! weight `σ` emitted by an integrate-and-dump register (the residual below one pulse carries
//! over to the next interval).

use nalgebra::{SMatrix, SVector, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use super::attitude::AttitudeTruth;

/// The 3×9 matrix `D(ω)` of paper 001's error model.
pub fn error_matrix(w: &Vector3<f64>) -> SMatrix<f64, 3, 9> {
    #[rustfmt::skip]
    let d = SMatrix::<f64, 3, 9>::from_row_slice(&[
        w.x, 0.0, 0.0,   w.y, 0.0, w.z,   1.0, 0.0, 0.0,
        0.0, w.y, 0.0,   w.x, w.z, 0.0,   0.0, 1.0, 0.0,
        0.0, 0.0, w.z,   0.0, w.y, w.x,   0.0, 0.0, 1.0,
    ]);
    d
}

/// Error parameters of a gyro triad.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GyroErrors {
    /// `c`: scale factors (3, dimensionless), symmetric misalignments (3, rad), biases (3, rad/s).
    pub c: SVector<f64, 9>,
    /// Angle random walk, rad/√s (white rate noise density).
    pub arw: f64,
    /// Bias random walk, rad/s/√s.
    pub bias_rw: f64,
    /// Pulse weight σ, rad; `None` for unquantized increments.
    pub pulse_weight: Option<f64>,
}

impl GyroErrors {
    /// A representative MEMS gyro of a microsatellite (consumer/industrial grade): scale factor
    /// errors ~1e-3, misalignments ~1e-3 rad, turn-on biases ~50 °/h, ARW 0.3 °/√h, bias
    /// instability modelled as a random walk of 5e-6 rad/s/√s, 16-bit-class quantization.
    pub fn mems() -> Self {
        let deg_h = std::f64::consts::PI / 180.0 / 3600.0;
        Self {
            c: SVector::from([
                1.2e-3,
                -0.8e-3,
                1.5e-3,
                0.9e-3,
                -1.1e-3,
                0.6e-3,
                50.0 * deg_h,
                -35.0 * deg_h,
                42.0 * deg_h,
            ]),
            arw: 0.3 * std::f64::consts::PI / 180.0 / 60.0,
            bias_rw: 5e-6,
            pulse_weight: Some(1e-5),
        }
    }
}

/// One output interval of the gyro.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GyroIncrement {
    /// Start of the interval, s.
    pub t0: f64,
    /// Integrated measured angle over the interval, rad (exact, before quantization).
    pub theta: Vector3<f64>,
    /// Pulse counts per axis when the gyro is quantized.
    pub pulses: Option<[i64; 3]>,
}

/// Generates gyro increments from an attitude truth.
pub struct Gyro {
    errors: GyroErrors,
    bias_drift: Vector3<f64>,
    residual: Vector3<f64>,
    rng: ChaCha8Rng,
}

impl Gyro {
    /// A gyro with the given errors; `seed` drives its noise.
    pub fn new(errors: GyroErrors, seed: u64) -> Self {
        Self {
            errors,
            bias_drift: Vector3::zeros(),
            residual: Vector3::zeros(),
            rng: ChaCha8Rng::seed_from_u64(seed),
        }
    }

    /// The error parameters, including the current bias drift in `c₇..₉`.
    pub fn current_errors(&self) -> SVector<f64, 9> {
        let mut c = self.errors.c;
        for i in 0..3 {
            c[6 + i] += self.bias_drift[i];
        }
        c
    }

    fn normal(&mut self) -> f64 {
        StandardNormal.sample(&mut self.rng)
    }

    /// The increment over `[t0, t0 + h]`: the truth rate is integrated with `substeps`
    /// Simpson panels (exact for the rate models used here to ~1e-12 rad).
    pub fn increment(
        &mut self,
        truth: &dyn AttitudeTruth,
        t0: f64,
        h: f64,
        substeps: usize,
    ) -> GyroIncrement {
        let n = substeps.max(1);
        let dt = h / n as f64;
        let c = self.current_errors();
        let measured = |t: f64| {
            let w = truth.omega_b(t);
            w + error_matrix(&w) * c
        };
        let mut theta = Vector3::zeros();
        for k in 0..n {
            let a = t0 + k as f64 * dt;
            theta += (measured(a) + measured(a + dt / 2.0) * 4.0 + measured(a + dt)) * (dt / 6.0);
        }
        theta += Vector3::new(self.normal(), self.normal(), self.normal())
            * (self.errors.arw * h.sqrt());
        let rw = Vector3::new(self.normal(), self.normal(), self.normal())
            * (self.errors.bias_rw * h.sqrt());
        self.bias_drift += rw;
        let pulses = self.errors.pulse_weight.map(|sigma| {
            let total = self.residual + theta;
            let counts = total.map(|v| (v / sigma).floor());
            self.residual = total - counts * sigma;
            [counts.x as i64, counts.y as i64, counts.z as i64]
        });
        GyroIncrement { t0, theta, pulses }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::truth::attitude::NadirTumble;
    use crate::truth::orbit::Orbit;

    #[test]
    fn noiseless_gyro_integrates_rate_plus_the_error_model_and_pulses_lose_nothing() {
        let truth = NadirTumble {
            orbit: Orbit::sun_synchronous(550e3, 0.0, 0.0),
            spin_rate: 0.02,
            wobble: 0.05,
            wobble_period: 60.0,
        };
        let errors = GyroErrors {
            arw: 0.0,
            bias_rw: 0.0,
            pulse_weight: Some(1e-5),
            ..GyroErrors::mems()
        };
        let mut gyro = Gyro::new(errors, 1);
        let (mut sum_theta, mut sum_pulses) = (Vector3::zeros(), Vector3::zeros());
        for k in 0..500 {
            let inc = gyro.increment(&truth, k as f64 * 0.04, 0.04, 4);
            sum_theta += inc.theta;
            let p = inc.pulses.unwrap();
            sum_pulses += Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64) * 1e-5;
        }
        // the register never holds more than one pulse
        assert!((sum_theta - sum_pulses).amax() < 1e-5 + 1e-12);
        // the bias dominates the error over 20 s: θ − ∫ω ≈ c₇..₉ · 20 s + scale/misalignment terms
        let w = truth.omega_b(10.0);
        let expected_bias = Vector3::new(errors.c[6], errors.c[7], errors.c[8]) * 20.0;
        let ideal = (0..2000)
            .map(|k| truth.omega_b(k as f64 * 0.01 + 0.005) * 0.01)
            .sum::<Vector3<f64>>();
        let err = sum_theta - ideal;
        assert!(
            (err - expected_bias).amax() < 2e-3 * w.amax() * 20.0 + 1e-6,
            "{err} vs {expected_bias}"
        );
    }
}
