//! Gyro truth models, f64, own code paths: the rate-error matrix of paper 001 §6, the
//! integrate-and-dump pulse register, and the §6 experiment (piecewise-constant rates,
//! gyrostabilizer reference with drift), and a MEMS gyro triad ([`Gyro`]) with angle and bias
//! random walks on any [`AttitudeTruth`].

use gnss_attitude::geometry::{Euler321, Quaternion};
use nalgebra::{SMatrix, SVector, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use super::attitude::AttitudeTruth;

/// `D(ω) = [D_I D_II E₃]` of paper 001 §6 (`3 × 9`), written out independently of the core.
pub fn paper_d(w: &Vector3<f64>) -> SMatrix<f64, 3, 9> {
    let mut d = SMatrix::<f64, 3, 9>::zeros();
    // D_I = diag(ω)
    d[(0, 0)] = w.x;
    d[(1, 1)] = w.y;
    d[(2, 2)] = w.z;
    // D_II = [[ω₂, 0, ω₃], [ω₁, ω₃, 0], [0, ω₂, ω₁]]
    d[(0, 3)] = w.y;
    d[(0, 5)] = w.z;
    d[(1, 3)] = w.x;
    d[(1, 4)] = w.z;
    d[(2, 4)] = w.y;
    d[(2, 5)] = w.x;
    // E₃
    d[(0, 6)] = 1.0;
    d[(1, 7)] = 1.0;
    d[(2, 8)] = 1.0;
    d
}

/// A pulse-output gyro channel triple: per axis, a register integrates the rate; each time its
/// magnitude reaches `σ` a pulse of that sign is emitted and `σ` is taken off. Sampling counts
/// the pulses of the interval ("integrate and dump"); the register keeps the residual
/// `Δθ_k ∈ (−σ, σ)` (paper eq. (5.1)), starting at `Δθ_0 = 0`.
#[derive(Clone, Debug)]
pub struct IntegrateAndDump {
    sigma: f64,
    register: Vector3<f64>,
}

impl IntegrateAndDump {
    /// Empty registers, pulse weight `sigma` (rad).
    pub fn new(sigma: f64) -> Self {
        Self {
            sigma,
            register: Vector3::zeros(),
        }
    }

    /// Integrates the true increment `theta` (rad) of one sample interval and returns the pulse
    /// counts emitted during it.
    pub fn sample(&mut self, theta: &Vector3<f64>) -> [i32; 3] {
        let mut counts = [0i32; 3];
        for i in 0..3 {
            self.register[i] += theta[i];
            let n = (self.register[i] / self.sigma).trunc();
            self.register[i] -= n * self.sigma;
            counts[i] = n as i32;
        }
        counts
    }

    /// The residual `Δθ` left in the registers (rad).
    pub fn residual(&self) -> Vector3<f64> {
        self.register
    }
}

/// The set-up of paper 001 §6 (seed specification, paper 001 (c)).
pub mod section6 {
    use super::*;

    /// Duration (s).
    pub const T_F: f64 = 30.0;
    /// Gyro sample interval `h` (s); the propagation step is `H = 2h`.
    pub const H_SAMPLE: f64 = 0.02;
    /// Pulse weight of the quantized variants (rad).
    pub const SIGMA: f64 = 2e-5;
    /// First epoch with equations (s) and the spacing of the epochs (s).
    pub const FIRST_EPOCH: f64 = 4.0;
    /// Spacing of the equation epochs (s).
    pub const EPOCH_SPACING: f64 = 0.2;

    /// `ω_E` (rad/s), piecewise constant over six 5 s intervals (ω₂ = 0.32 in (5, 10] kept).
    pub const RATES: [[f64; 3]; 6] = [
        [0.01, 0.02, -0.01],
        [0.02, 0.32, -0.015],
        [0.01, 0.01, -0.02],
        [0.16, 0.015, -0.03],
        [0.03, 0.017, -0.16],
        [0.02, 0.02, -0.02],
    ];

    /// `Λ(0)`.
    pub fn lambda0() -> Quaternion<f64> {
        Quaternion::new(0.64, 0.48, 0.36, -0.48)
    }

    /// `w₀` (half-angle vector).
    pub fn w0() -> Vector3<f64> {
        Vector3::new(1e-3, 1e-3, 1e-3)
    }

    /// `c`: scale factors, symmetric misalignments, biases (s⁻¹).
    pub fn c() -> SVector<f64, 9> {
        SVector::<f64, 9>::from([3e-4, 3e-4, 3e-4, 5e-4, 5e-4, -5e-4, 1e-5, -1e-5, -1e-5])
    }

    /// `d` (rad/s).
    pub fn d() -> Vector3<f64> {
        Vector3::new(1e-6, 1e-6, 1e-6)
    }

    /// The gyrostabilizer's initial angles φ₀ (yaw, pitch, roll), rad.
    pub fn phi0() -> Euler321<f64> {
        Euler321::new(-0.5, 0.17, -0.6)
    }

    /// `ω_E` over the sample interval ending at sample `k` (1-based).
    pub fn rate(k: usize) -> Vector3<f64> {
        let t_mid = (k as f64 - 0.5) * H_SAMPLE;
        let i = ((t_mid / 5.0) as usize).min(RATES.len() - 1);
        Vector3::from(RATES[i])
    }

    /// One gyro sample of the truth.
    #[derive(Clone, Debug)]
    pub struct Sample {
        /// `t_k` (s).
        pub t: f64,
        /// True attitude `Λ(t_k)` (gyro axes to inertial).
        pub lambda: Quaternion<f64>,
        /// Exact gyro increment `∫ω* dt` over the sample (rad).
        pub theta: Vector3<f64>,
        /// Pulse counts of weight [`SIGMA`] over the sample.
        pub counts: [i32; 3],
        /// The gyrostabilizer's quaternion `N_J(φ(t_k))` (J to the drifting frame L).
        pub reference: Quaternion<f64>,
    }

    /// The whole 30 s of truth.
    #[derive(Clone, Debug)]
    pub struct Truth {
        /// `M(0) = (1 + w₀)⁻¹ ∘ Λ(0)`.
        pub m0: Quaternion<f64>,
        /// `N_J(φ₀)`.
        pub reference0: Quaternion<f64>,
        /// Samples 1..=1500.
        pub samples: Vec<Sample>,
    }

    /// Generates the truth: exact attitude for piecewise-constant rates, exact and quantized
    /// increments of `ω* = ω + D(ω) c`, the reference `N_J = L̄ ∘ N°_J` with
    /// `N°_J(t) = Λ(t) ∘ Λ̄(0) ∘ N°_J(0)` and `L(t) = exp(½ d t)`.
    pub fn generate() -> Truth {
        let lambda0 = lambda0();
        let w0 = w0();
        let one_plus_w0 = Quaternion::from_parts((1.0 - w0.norm_squared()).sqrt(), w0);
        let m0 = one_plus_w0.conjugate() * lambda0;
        let n0 = phi0().to_quaternion();
        let steps = (T_F / H_SAMPLE).round() as usize;
        let (c, d) = (c(), d());
        let mut lambda = lambda0;
        let mut dump = IntegrateAndDump::new(SIGMA);
        let mut samples = Vec::with_capacity(steps);
        for k in 1..=steps {
            let t = k as f64 * H_SAMPLE;
            let w = rate(k);
            lambda = lambda * Quaternion::from_rotation_vector(&(w * H_SAMPLE));
            let theta = (w + paper_d(&w) * c) * H_SAMPLE;
            let counts = dump.sample(&theta);
            let n_true = lambda * lambda0.conjugate() * n0;
            let drift = Quaternion::from_rotation_vector(&(d * t));
            samples.push(Sample {
                t,
                lambda,
                theta,
                counts,
                reference: drift.conjugate() * n_true,
            });
        }
        Truth {
            m0,
            reference0: n0,
            samples,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// A MEMS gyro on an arbitrary attitude truth (the microsatellite scenarios).
//
// Measured rate `ω* = ω + D(ω) c + n` with the same `D(ω)`; angle random walk, bias random walk,
// and an optional integrate-and-dump pulse output.

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
    pub pulses: Option<[i32; 3]>,
}

/// Generates gyro increments from an attitude truth.
pub struct Gyro {
    errors: GyroErrors,
    bias_drift: Vector3<f64>,
    register: Option<IntegrateAndDump>,
    rng: ChaCha8Rng,
}

impl Gyro {
    /// A gyro with the given errors; `seed` drives its noise.
    pub fn new(errors: GyroErrors, seed: u64) -> Self {
        Self {
            errors,
            bias_drift: Vector3::zeros(),
            register: errors.pulse_weight.map(IntegrateAndDump::new),
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
            w + paper_d(&w) * c
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
        let pulses = self.register.as_mut().map(|r| r.sample(&theta));
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
            orbit: Orbit::sun_synchronous(550e3, 0.0, 0.0).into(),
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
            sum_pulses += Vector3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2])) * 1e-5;
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
