//! Where the filter's per-epoch input comes from.
//!
//! [`EpochSource`] is the seam between the truth and the core filter: given the true attitude
//! of one epoch, it returns the [`SatelliteObservation`]s the receiver would hand over. Two
//! sources implement it:
//!
//! * [`IqFastPath`] (here) synthesizes the prompt correlator outputs directly with the
//!   statistics of an ideal correlator: cheap, for Monte Carlo.
//! * [`SampleLevel`](super::samples::SampleLevel) synthesizes the three antennas' samples and
//!   runs the core's acquisition, fixed-point correlators and tracking channels, then the
//!   core's adapter ([`gnss_attitude::receiver::ObservationAdapter`],
//!   [`gnss_attitude::receiver::EpochClock`]): samples → correlators → filter.
//!   [`Replay`](super::samples::Replay) plays a recorded sample-level run back, so that
//!   several filters see the same observations.

use gnss_attitude::attitude::one_stage::{PromptIq, SatelliteObservation};
use nalgebra::Matrix3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use super::truth::{phases, Satellite};

/// Produces one epoch's observations from the truth.
pub trait EpochSource {
    /// The observations of filter epoch `t` seconds (`t = k·T`) with true attitude `c_rb`
    /// (body to reference), written into `out` (cleared first).
    ///
    /// # Errors
    /// A failure of the signal chain (sample-level sources).
    fn epoch(
        &mut self,
        t: f64,
        c_rb: &Matrix3<f64>,
        out: &mut Vec<SatelliteObservation<f32>>,
    ) -> anyhow::Result<()>;
}

/// Noise standard deviation of each correlator component, in "counts": an arbitrary scale,
/// not 1, so that the filter's normalization by the noise is exercised.
pub const NOISE_SIGMA: f64 = 40.0;
/// Coherent integration time, s.
pub const EPOCH_S: f64 = 1e-3;
/// Navigation data bit length, s.
const BIT_S: f64 = 0.02;
/// Random-walk step of each satellite's common carrier phase per epoch, rad (residual
/// tracking error and clock phase; averaged out by the filter).
const COMMON_PHASE_STEP: f64 = 0.05;

/// Per-satellite state of the synthesizer.
struct Channel {
    sat: Satellite,
    /// Common carrier phase `φ`, rad.
    phase: f64,
    /// Current data bit, ±1.
    bit: f64,
    /// Time of the next bit edge, s.
    next_edge: f64,
}

/// Correlator outputs synthesized directly: for satellite `i` and antenna `P`,
/// `Z_P = A d e^{j(φ_i + ψ_{P,i} + b_P)} + n`, `n` complex Gaussian with variance `σ²` per
/// component, `A = √(2 (C/N0) T) σ` (so that `A²/(2σ²) = (C/N0)·T`), `d` a ±1 data bit that
/// changes every 20 ms at a random phase per satellite, `φ_i` a random walk, `b_P` the
/// antennas' line biases. This is what an ideal correlator over one code period returns when
/// code and Doppler are tracked exactly, which the filter assumes.
pub struct IqFastPath {
    rng: ChaCha8Rng,
    channels: Vec<Channel>,
    amplitude: f64,
    line_bias: [f64; 3],
    cn0_dbhz: f64,
}

impl IqFastPath {
    /// A synthesizer for `sky` at `cn0_dbhz`, with line biases `line_bias` (rad, antennas A,
    /// B, C), seeded.
    pub fn new(sky: &[Satellite], cn0_dbhz: f64, line_bias: [f64; 3], seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let channels = sky
            .iter()
            .map(|&sat| Channel {
                sat,
                phase: rng.random_range(0.0..std::f64::consts::TAU),
                bit: if rng.random_bool(0.5) { 1.0 } else { -1.0 },
                next_edge: rng.random_range(0.0..BIT_S),
            })
            .collect();
        let cn0 = 10f64.powf(cn0_dbhz / 10.0);
        Self {
            rng,
            channels,
            amplitude: (2.0 * cn0 * EPOCH_S).sqrt() * NOISE_SIGMA,
            line_bias,
            cn0_dbhz,
        }
    }
}

impl EpochSource for IqFastPath {
    fn epoch(
        &mut self,
        t: f64,
        c_rb: &Matrix3<f64>,
        out: &mut Vec<SatelliteObservation<f32>>,
    ) -> anyhow::Result<()> {
        out.clear();
        for ch in &mut self.channels {
            if t >= ch.next_edge {
                ch.bit = if self.rng.random_bool(0.5) { 1.0 } else { -1.0 };
                ch.next_edge += BIT_S;
            }
            let n: f64 = StandardNormal.sample(&mut self.rng);
            ch.phase += COMMON_PHASE_STEP * n;
            let los = ch.sat.los();
            let psi = phases(c_rb, &los);
            let mut prompt = PromptIq::default();
            let outputs = prompt.i.iter_mut().zip(prompt.q.iter_mut());
            for ((i, q), (&psi_p, &b_p)) in outputs.zip(psi.iter().zip(&self.line_bias)) {
                let theta = ch.phase + psi_p + b_p;
                let ni: f64 = StandardNormal.sample(&mut self.rng);
                let nq: f64 = StandardNormal.sample(&mut self.rng);
                *i = (self.amplitude * ch.bit * theta.cos() + NOISE_SIGMA * ni) as f32;
                *q = (self.amplitude * ch.bit * theta.sin() + NOISE_SIGMA * nq) as f32;
            }
            out.push(SatelliteObservation {
                id: ch.sat.prn,
                los: [los.x as f32, los.y as f32, los.z as f32],
                prompt,
                noise_var: (NOISE_SIGMA * NOISE_SIGMA) as f32,
                cn0_dbhz: self.cn0_dbhz as f32,
            });
        }
        Ok(())
    }
}
