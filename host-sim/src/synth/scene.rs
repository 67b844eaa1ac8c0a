//! The coherent three-antenna signal model and its sample generator (f64 truth, f32 samples).
//!
//! Satellite `i` seen at antenna `P` (one sample clock for all antennas):
//!
//! ```text
//! code phase   C_P(t) = C₀ + f_c t + (f_c/f_L1)(f_D t + ½ ḟ_D t²) + f_c (μ·r_P(t))/c      chips
//! carrier      Φ_P(t) = φ₀ + f_D t + ½ ḟ_D t² + (μ·r_P(t))/λ + b_P                         cycles
//! complex      x_P(t) = A d(t) c(C_P(t)) e^{j2π(Φ_P(t) + f_IF t)} + n,   n ~ CN(0, 2)
//! real IF      x_P(t) = √2 A d(t) c(C_P(t)) cos 2π(Φ_P(t) + f_IF t) + n,   n ~ N(0, 1)
//! ```
//! with `r_P(t) = C_rb(t) r_P,b` (antenna position, reference frame), `μ` the unit vector to
//! the satellite (reference frame), `b_P` the antenna's line bias, `d(t)` the 50 bit/s data
//! (edges at every 20th code epoch) and `A = √(2 (C/N0) / f_s)`, so that a 1 ms coherent sum
//! has `SNR = (C/N0)·T`. `(μ·r_P)/λ` is paper 003's `ψ_P/2π`, eq. (4)/(24).
//!
//! A satellite with a [`SatelliteTrack`] (a LEO receiver: the line of sight, the range and the
//! body all move) takes its range, geometric term `μ·r_P(t)` and per-antenna C/N0 from the
//! track instead: `f_D t + ½ ḟ_D t²` becomes `−(ρ(t) − ρ(0))/λ` (cubic Hermite between the
//! track's range and range-rate points, so the Doppler is continuous), `μ·r_P(t)` is
//! interpolated linearly (its curvature over a 10 ms step is below a micrometre) and the
//! amplitude follows the antenna's C/N0 (zero where the antenna does not receive).
//!
//! Within a sub-block of [`SUB_BLOCK`] samples the code rate, carrier frequency and geometric
//! phase are those at the sub-block's middle and its start phases are exact (closed form), so
//! the phase error is below `ḟ_D (B/f_s)²/8` (10⁻⁵ cycle at 100 Hz/s). The noise of each
//! sub-block and antenna has its own seed: the output does not depend on how a run is cut
//! into calls, nor on the number of threads.

use std::sync::Arc;

use nalgebra::{Matrix3, Rotation3, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

use super::codes::ca_code;

/// Speed of light, m/s.
pub const SPEED_OF_LIGHT: f64 = 299_792_458.0;
/// GPS L1, Hz.
pub const L1_HZ: f64 = 1_575.42e6;
/// L1 wavelength, m.
pub const L1_WAVELENGTH: f64 = SPEED_OF_LIGHT / L1_HZ;
/// C/A chip rate, Hz.
pub const CHIP_RATE: f64 = 1.023e6;
/// Samples generated with one set of rates and one noise seed.
pub const SUB_BLOCK: usize = 4096;

/// One satellite's signal.
#[derive(Clone, Debug)]
pub struct Satellite {
    /// PRN, 1–32.
    pub prn: u8,
    /// Carrier-to-noise density, dB-Hz (before quantization).
    pub cn0_dbhz: f64,
    /// Doppler at t = 0, Hz.
    pub doppler_hz: f64,
    /// Doppler rate, Hz/s.
    pub doppler_rate_hz_s: f64,
    /// Code phase at the array origin at t = 0, chips.
    pub code_phase_chips: f64,
    /// Carrier phase at the array origin at t = 0, cycles.
    pub carrier_phase_cycles: f64,
    /// Unit vector from the receiver to the satellite, reference frame.
    pub los_ref: Vector3<f64>,
    /// Seed of the navigation data bits; `None`: no data modulation.
    pub data_seed: Option<u64>,
    /// Tabulated motion (range, geometry, C/N0 per antenna); `None`: the constant line of
    /// sight, polynomial Doppler and constant C/N0 above.
    pub track: Option<Arc<SatelliteTrack>>,
}

/// A satellite's range, per-antenna geometry and per-antenna C/N0 tabulated from `t = 0` at a
/// uniform step (the truth of a moving receiver and body, computed once by the scenario).
#[derive(Clone, Debug, Default)]
pub struct SatelliteTrack {
    /// Table step, s.
    pub step_s: f64,
    /// Range from the array origin to the satellite at `t = k·step`, m.
    pub range_m: Vec<f64>,
    /// Range rate at `t = k·step`, m/s.
    pub range_rate_m_s: Vec<f64>,
    /// `μ·r_P` per point and antenna (`[k][P]`), m: antenna P's phase-centre offset projected
    /// on the line of sight (paper 003's `ψ_P λ/2π`).
    pub geometry_m: Vec<Vec<f64>>,
    /// C/N0 per point and antenna (`[k][P]`), dB-Hz; `f64::NEG_INFINITY` where the antenna
    /// does not receive the satellite (below its mask, blocked).
    pub cn0_dbhz: Vec<Vec<f64>>,
    /// Carrier-only phase steps (cycle slips of one antenna's RF chain; the code is unchanged).
    pub carrier_steps: Vec<CarrierStep>,
    /// Navigation data bits (`true` = 1, sent as −1) by bit index: bit `k` covers code epochs
    /// `[20k, 20k + 20)` of the code count `⌊code_chips_total / 1023⌋`; empty: the
    /// satellite's `data_seed` decides. Epochs outside the table carry +1.
    pub data_bits: Vec<bool>,
}

/// A carrier phase step of one antenna: `cycles` added linearly over `duration_s` from
/// `start_s` (a cycle slip as the antenna's carrier sees it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CarrierStep {
    /// Antenna (0 = A).
    pub antenna: usize,
    /// Start, s.
    pub start_s: f64,
    /// Duration of the ramp, s (> 0).
    pub duration_s: f64,
    /// Cycles added.
    pub cycles: f64,
}

impl SatelliteTrack {
    /// Index and fraction of `t` in the table (clamped to its ends).
    fn locate(&self, t: f64) -> (usize, f64) {
        let last = self.range_m.len().saturating_sub(2);
        let x = (t / self.step_s).max(0.0);
        let k = (x.floor() as usize).min(last);
        (k, (x - k as f64).min(1.0))
    }

    /// Range at `t`, m (cubic Hermite on range and range rate).
    pub fn range(&self, t: f64) -> f64 {
        if self.range_m.len() < 2 {
            return self.range_m.first().copied().unwrap_or(0.0);
        }
        let (k, u) = self.locate(t);
        let h = self.step_s;
        let (p0, p1) = (self.range_m[k], self.range_m[k + 1]);
        let (m0, m1) = (self.range_rate_m_s[k] * h, self.range_rate_m_s[k + 1] * h);
        let (u2, u3) = (u * u, u * u * u);
        (2.0 * u3 - 3.0 * u2 + 1.0) * p0
            + (u3 - 2.0 * u2 + u) * m0
            + (-2.0 * u3 + 3.0 * u2) * p1
            + (u3 - u2) * m1
    }

    /// Range rate at `t`, m/s (the derivative of [`SatelliteTrack::range`]).
    pub fn range_rate(&self, t: f64) -> f64 {
        if self.range_m.len() < 2 {
            return self.range_rate_m_s.first().copied().unwrap_or(0.0);
        }
        let (k, u) = self.locate(t);
        let h = self.step_s;
        let (p0, p1) = (self.range_m[k], self.range_m[k + 1]);
        let (m0, m1) = (self.range_rate_m_s[k] * h, self.range_rate_m_s[k + 1] * h);
        let u2 = u * u;
        ((6.0 * u2 - 6.0 * u) * p0
            + (3.0 * u2 - 4.0 * u + 1.0) * m0
            + (-6.0 * u2 + 6.0 * u) * p1
            + (3.0 * u2 - 2.0 * u) * m1)
            / h
    }

    fn linear(&self, table: &[Vec<f64>], antenna: usize, t: f64) -> f64 {
        let at = |k: usize| table.get(k).and_then(|r| r.get(antenna)).copied();
        if table.len() < 2 {
            return at(0).unwrap_or(0.0);
        }
        let (k, u) = self.locate(t);
        let (a, b) = (at(k).unwrap_or(0.0), at(k + 1).unwrap_or(0.0));
        a + (b - a) * u
    }

    /// Carrier phase added by the steps of antenna `antenna` until `t`, cycles.
    pub fn carrier_offset(&self, antenna: usize, t: f64) -> f64 {
        self.carrier_steps
            .iter()
            .filter(|c| c.antenna == antenna && t > c.start_s)
            .map(|c| c.cycles * ((t - c.start_s) / c.duration_s.max(1e-12)).min(1.0))
            .sum()
    }

    /// The data bit (±1) of code epoch `epoch` from [`SatelliteTrack::data_bits`] (a data
    /// bit 1 is sent as −1, IS-GPS-200's `d = 1` ↔ a phase inversion).
    pub fn data_bit(&self, epoch: i64) -> f32 {
        let bit = usize::try_from(epoch.div_euclid(20))
            .ok()
            .and_then(|k| self.data_bits.get(k));
        match bit {
            Some(true) => -1.0,
            _ => 1.0,
        }
    }

    /// `μ·r_P` of antenna `antenna` at `t`, m.
    pub fn geometry(&self, antenna: usize, t: f64) -> f64 {
        self.linear(&self.geometry_m, antenna, t)
    }

    /// C/N0 of antenna `antenna` at `t`, dB-Hz (`NEG_INFINITY` when either neighbouring point
    /// is not received: the signal switches off and on at table points).
    pub fn cn0(&self, antenna: usize, t: f64) -> f64 {
        let (k, u) = self.locate(t);
        let at = |k: usize| {
            self.cn0_dbhz
                .get(k)
                .and_then(|r| r.get(antenna))
                .copied()
                .unwrap_or(f64::NEG_INFINITY)
        };
        let (a, b) = (at(k), at(k + 1));
        if a.is_finite() && b.is_finite() {
            a + (b - a) * u
        } else if u < 0.5 {
            a
        } else {
            b
        }
    }
}

/// Attitude of the body (`C_rb`) over time.
#[derive(Clone, Copy, Debug)]
pub enum AttitudeMotion {
    /// Fixed attitude.
    Constant(Matrix3<f64>),
    /// `C_rb(t) = C_rb(0) · exp([ω t]×)`, `ω` constant in body axes (rad/s).
    ConstantRate {
        /// Attitude at t = 0.
        c_rb0: Matrix3<f64>,
        /// Body rate, body axes, rad/s.
        omega_b: Vector3<f64>,
    },
    /// `C_rb(t)` given by a function of time (s), e.g. a scenario's own motion law.
    Function(fn(f64) -> Matrix3<f64>),
}

impl AttitudeMotion {
    /// `C_rb(t)`.
    pub fn c_rb(&self, t: f64) -> Matrix3<f64> {
        match *self {
            Self::Constant(c) => c,
            Self::ConstantRate { c_rb0, omega_b } => {
                c_rb0 * Rotation3::from_scaled_axis(omega_b * t).into_inner()
            }
            Self::Function(f) => f(t),
        }
    }
}

/// Front end: sampling.
#[derive(Clone, Copy, Debug)]
pub struct FrontEnd {
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Intermediate frequency, Hz (0 for complex baseband).
    pub intermediate_frequency_hz: f64,
    /// Complex (I/Q) or real samples.
    pub complex: bool,
}

/// The whole scene: satellites, antenna array, attitude, front end, noise seed.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Satellites.
    pub satellites: Vec<Satellite>,
    /// Antenna positions, body frame, m (antenna 0 is the reference).
    pub antennas_b: Vec<Vector3<f64>>,
    /// Per-antenna line biases (carrier phase added by the antenna's cable and RF chain),
    /// cycles.
    pub line_bias_cycles: Vec<f64>,
    /// Attitude over time.
    pub attitude: AttitudeMotion,
    /// Front end.
    pub front_end: FrontEnd,
    /// Noise seed; `None` for noise-free samples.
    pub noise_seed: Option<u64>,
}

/// Truth of one satellite at one antenna at one instant.
#[derive(Clone, Copy, Debug)]
pub struct SignalTruth {
    /// Code phase, chips in `[0, 1023)`.
    pub code_phase_chips: f64,
    /// Code phase since t = 0 in chips (not wrapped).
    pub code_chips_total: f64,
    /// Carrier phase (without the IF), cycles.
    pub carrier_phase_cycles: f64,
    /// Doppler, Hz.
    pub doppler_hz: f64,
}

/// Samples of one antenna, noise σ = 1 per component.
#[derive(Clone, Debug, Default)]
pub struct AnalogSamples {
    /// In-phase (or real) samples.
    pub i: Vec<f32>,
    /// Quadrature samples (empty for real sampling).
    pub q: Vec<f32>,
}

impl Scene {
    /// The truth of satellite `sat` at antenna `antenna` at time `t` (s).
    pub fn truth(&self, sat: usize, antenna: usize, t: f64) -> SignalTruth {
        let s = &self.satellites[sat];
        let (geo_m, dopp_cycles, doppler_hz, step_cycles) = match &s.track {
            Some(track) => (
                track.geometry(antenna, t),
                -(track.range(t) - track.range(0.0)) / L1_WAVELENGTH,
                -track.range_rate(t) / L1_WAVELENGTH,
                track.carrier_offset(antenna, t),
            ),
            None => (
                s.los_ref
                    .dot(&(self.attitude.c_rb(t) * self.antennas_b[antenna])),
                s.doppler_hz * t + 0.5 * s.doppler_rate_hz_s * t * t,
                s.doppler_hz + s.doppler_rate_hz_s * t,
                0.0,
            ),
        };
        let code = s.code_phase_chips
            + CHIP_RATE * t
            + CHIP_RATE / L1_HZ * dopp_cycles
            + CHIP_RATE * geo_m / SPEED_OF_LIGHT;
        SignalTruth {
            code_phase_chips: code.rem_euclid(1023.0),
            code_chips_total: code,
            carrier_phase_cycles: s.carrier_phase_cycles
                + dopp_cycles
                + geo_m / L1_WAVELENGTH
                + step_cycles
                + self.line_bias_cycles.get(antenna).copied().unwrap_or(0.0),
            doppler_hz,
        }
    }

    /// Signal amplitude of a satellite (noise σ = 1 per component).
    pub fn amplitude(&self, sat: usize) -> f64 {
        (2.0 * 10f64.powf(self.satellites[sat].cn0_dbhz / 10.0) / self.front_end.sample_rate_hz)
            .sqrt()
    }

    /// Signal amplitude of a satellite at an antenna at `t` (the track's C/N0 when it has
    /// one; zero where that antenna does not receive it).
    pub fn amplitude_at(&self, sat: usize, antenna: usize, t: f64) -> f64 {
        match &self.satellites[sat].track {
            Some(track) => {
                let cn0 = track.cn0(antenna, t);
                if cn0.is_finite() {
                    (2.0 * 10f64.powf(cn0 / 10.0) / self.front_end.sample_rate_hz).sqrt()
                } else {
                    0.0
                }
            }
            None => self.amplitude(sat),
        }
    }

    /// Samples `[first, first + n)` of every antenna (`first` a multiple of [`SUB_BLOCK`] keeps
    /// the noise identical to a run cut elsewhere), in parallel over sub-blocks.
    pub fn synthesize(&self, first: u64, n: usize) -> Vec<AnalogSamples> {
        let codes: Vec<Vec<f32>> = self.satellites.iter().map(|s| ca_code(s.prn)).collect();
        let n_ant = self.antennas_b.len();
        let complex = self.front_end.complex;
        let mut out: Vec<AnalogSamples> = (0..n_ant)
            .map(|_| AnalogSamples {
                i: vec![0.0; n],
                q: if complex { vec![0.0; n] } else { Vec::new() },
            })
            .collect();
        // Work items: (antenna, sub-block); each owns disjoint output slices.
        let mut items: Vec<(usize, u64, &mut [f32], &mut [f32])> = Vec::new();
        for (a, ant) in out.iter_mut().enumerate() {
            let mut qi = ant.q.chunks_mut(SUB_BLOCK);
            for (b, ci) in ant.i.chunks_mut(SUB_BLOCK).enumerate() {
                let cq = qi.next().unwrap_or_default();
                items.push((a, first + (b * SUB_BLOCK) as u64, ci, cq));
            }
        }
        items
            .into_par_iter()
            .for_each(|(a, k0, i, q)| self.fill(a, k0, i, q, &codes));
        out
    }

    fn fill(
        &self,
        antenna: usize,
        k0: u64,
        out_i: &mut [f32],
        out_q: &mut [f32],
        codes: &[Vec<f32>],
    ) {
        let fe = &self.front_end;
        let fs = fe.sample_rate_hz;
        let n = out_i.len();
        let t0 = k0 as f64 / fs;
        let t_mid = (k0 as f64 + 0.5 * n as f64) / fs;
        let dt = 1.0 / fs;
        let mut values = vec![0.0f64; n];
        for (si, s) in self.satellites.iter().enumerate() {
            let amp = self.amplitude_at(si, antenna, t_mid)
                * if fe.complex {
                    1.0
                } else {
                    std::f64::consts::SQRT_2
                };
            if amp == 0.0 {
                continue;
            }
            let tr0 = self.truth(si, antenna, t0);
            let tr_mid = self.truth(si, antenna, t_mid);
            // Rates over the sub-block from the exact phases at its start and middle.
            let half = t_mid - t0;
            let code_rate = (tr_mid.code_chips_total - tr0.code_chips_total) / half; // chips/s
            let carr_rate = (tr_mid.carrier_phase_cycles - tr0.carrier_phase_cycles) / half;
            let phase0 = tr0.carrier_phase_cycles + fe.intermediate_frequency_hz * t0;
            let dphi = (carr_rate + fe.intermediate_frequency_hz) * dt;
            // Four interleaved carrier phasors (samples k ≡ r mod 4), each advanced by w⁴:
            // four independent recurrences instead of one long dependency chain.
            let phasor = |a: f64| {
                let a = std::f64::consts::TAU * a.rem_euclid(1.0);
                (a.cos(), a.sin())
            };
            let mut pr = [0.0f64; 4];
            let mut pi = [0.0f64; 4];
            for r in 0..4 {
                (pr[r], pi[r]) = phasor(phase0 + r as f64 * dphi);
            }
            let (wr, wi) = phasor(4.0 * dphi);
            // Code phase in 32.32 fixed point (own implementation), epoch count for data:
            // first the code × data × amplitude of every sample.
            let total = tr0.code_chips_total;
            let mut epoch = (total / 1023.0).floor() as i64;
            let mut cph = ((total - 1023.0 * epoch as f64) * 4_294_967_296.0) as u64;
            let cstep = (code_rate * dt * 4_294_967_296.0).round() as u64;
            const WRAP: u64 = 1023u64 << 32;
            let code = &codes[si];
            let bit_of = |epoch: i64| match s.track.as_deref() {
                Some(t) if !t.data_bits.is_empty() => t.data_bit(epoch),
                _ => data_bit(s.data_seed, epoch),
            };
            let mut bit = bit_of(epoch);
            for v in values.iter_mut().take(n) {
                let chip = code[((cph >> 32) as usize).min(1022)];
                *v = amp * f64::from(chip * bit);
                cph += cstep;
                if cph >= WRAP {
                    cph -= WRAP;
                    epoch += 1;
                    bit = bit_of(epoch);
                }
            }
            // Then the carrier, four samples at a time.
            for (c, vals) in values[..n].chunks(4).enumerate() {
                for (r, &v) in vals.iter().enumerate() {
                    let k = 4 * c + r;
                    out_i[k] += (v * pr[r]) as f32;
                    if fe.complex {
                        out_q[k] += (v * pi[r]) as f32;
                    }
                }
                for r in 0..4 {
                    let x = pr[r] * wr - pi[r] * wi;
                    pi[r] = pr[r] * wi + pi[r] * wr;
                    pr[r] = x;
                }
            }
        }
        if let Some(seed) = self.noise_seed {
            let mut rng = ChaCha8Rng::seed_from_u64(mix(seed, antenna as u64, k0));
            for v in out_i.iter_mut() {
                let z: f32 = StandardNormal.sample(&mut rng);
                *v += z;
            }
            for v in out_q.iter_mut() {
                let z: f32 = StandardNormal.sample(&mut rng);
                *v += z;
            }
        }
    }
}

/// The data bit (±1) in force during code epoch `epoch` (bit edges every 20 epochs).
pub fn data_bit(seed: Option<u64>, epoch: i64) -> f32 {
    match seed {
        None => 1.0,
        Some(s) => {
            let bit_index = epoch.div_euclid(20) as u64;
            if mix(s, 0x5a5a, bit_index) & 1 == 0 {
                1.0
            } else {
                -1.0
            }
        }
    }
}

/// SplitMix64-style hash of three words (seeds of the noise and data streams).
pub fn mix(a: u64, b: u64, c: u64) -> u64 {
    let mut z = a
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(b.wrapping_mul(0xBF58_476D_1CE4_E5B9))
        .wrapping_add(c.wrapping_mul(0x94D0_49BB_1331_11EB))
        .wrapping_add(0x2545_F491_4F6C_DD1D);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A track sampled from a known LEO-like range history reproduces it between its points,
    /// and its range rate is the derivative of its range (finite differences).
    #[test]
    fn a_satellite_track_interpolates_range_and_its_rate_consistently() {
        // range = ρ0 + v t + ½ a t² + j t³/6 (a LEO-GPS pair: 3 km/s, 11 m/s², 0.05 m/s³)
        let r = |t: f64| 2.2e7 + 3000.0 * t + 5.5 * t * t + 0.05 / 6.0 * t * t * t;
        let v = |t: f64| 3000.0 + 11.0 * t + 0.025 * t * t;
        let step = 0.01;
        let n = 201;
        let track = SatelliteTrack {
            step_s: step,
            range_m: (0..n).map(|k| r(k as f64 * step)).collect(),
            range_rate_m_s: (0..n).map(|k| v(k as f64 * step)).collect(),
            geometry_m: (0..n).map(|k| vec![0.1 * k as f64, -0.2]).collect(),
            cn0_dbhz: (0..n)
                .map(|k| vec![45.0, if k < 100 { 40.0 } else { f64::NEG_INFINITY }])
                .collect(),
            carrier_steps: vec![CarrierStep {
                antenna: 1,
                start_s: 1.0,
                duration_s: 0.004,
                cycles: 1.0,
            }],
            data_bits: Vec::new(),
        };
        for &t in &[0.0021, 0.0037, 0.5, 0.7351, 1.9949] {
            assert!((track.range(t) - r(t)).abs() < 1e-6, "range at {t}");
            let h = 1e-3;
            let fd = (track.range(t + h) - track.range(t - h)) / (2.0 * h);
            assert!((track.range_rate(t) - fd).abs() < 1e-3, "rate at {t}");
            assert!(
                (track.range_rate(t) - v(t)).abs() < 1e-6,
                "rate truth at {t}"
            );
        }
        assert!((track.geometry(0, 0.015) - 0.15).abs() < 1e-12);
        assert!((track.geometry(1, 1.0) + 0.2).abs() < 1e-12);
        assert_eq!(track.cn0(0, 0.5), 45.0);
        assert_eq!(track.cn0(1, 0.5), 40.0);
        assert_eq!(track.cn0(1, 1.5), f64::NEG_INFINITY);
        // clamped past the end
        assert!(track.range(5.0).is_finite());
        // the slip: antenna B only, a ramp of one cycle over 4 ms
        assert_eq!(track.carrier_offset(0, 1.5), 0.0);
        assert_eq!(track.carrier_offset(1, 0.999), 0.0);
        assert!((track.carrier_offset(1, 1.002) - 0.5).abs() < 1e-9);
        assert_eq!(track.carrier_offset(1, 1.5), 1.0);
    }
}
