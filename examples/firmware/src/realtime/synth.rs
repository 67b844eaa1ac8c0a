//! Three-antenna complex samples of eight satellites, synthesized on the target (outside the
//! counted region), with host-sim's signal model (`host-sim/src/synth/scene.rs`):
//!
//! ```text
//! code phase   C(t)   = C₀ + f_c (1 + f_D / f_L1) t                                  chips
//! carrier      Φ_P(t) = φ₀ + f_D t + (μ·C_rb(t) r_P)/λ + b_P                          cycles
//! complex      x_P(t) = A d(t) c(C(t)) e^{j2π Φ_P(t)} + n,   n ~ CN(0, 2),   A = √(2 (C/N0) / f_s)
//! ```
//!
//! The truth is the core's example flight ([`ExampleFlight`]): the 0.5 m antenna triangle,
//! the eight lines of sight of [`SKY`], the body turning at [`BODY_RATE`] rad/s from `q0`, the
//! line biases of B and C; [`DOPPLER_HZ`] and [`CODE_PHASE_CHIPS`] are this file's. The
//! geometric term is held per block (it moves by 10⁻⁵ cycle in 2 ms). Data bits: 50 bit/s,
//! edges every 20th code period, pseudo-random per satellite. Noise: a xorshift32 generator,
//! the sum of four uniform bytes per component (variance matched to σ = 1; close to Gaussian
//! at the 1σ threshold that matters to the 2-bit quantizer).
//!
//! [`BODY_RATE`]: gnss_attitude::receiver::example::BODY_RATE

use gnss_attitude::attitude::example::SKY;
use gnss_attitude::attitude::one_stage::GPS_L1_WAVELENGTH_M;
use gnss_attitude::receiver::example::{antennas, ExampleFlight, LINE_BIAS_RAD};
use gnss_attitude::signal::Prn;
use nalgebra::{ComplexField, Vector3};

use super::frontend::FrontEnd;

/// Sample rate, Hz (complex).
pub const SAMPLE_RATE_HZ: f64 = 2.6e6;
/// Samples per 1 ms receiver epoch.
pub const SAMPLES_PER_MS: usize = 2600;
/// C/N0 of every satellite at every antenna, dB-Hz (the example flight's).
pub const CN0_DBHZ: f32 = 45.0;
/// Doppler of the eight satellites of [`SKY`] (constant), Hz.
pub const DOPPLER_HZ: [f64; 8] = [1250.0, -730.0, 1840.0, -1620.0, 310.0, -2110.0, 960.0, -180.0];
/// The receiver oscillator's frequency offset as it shows in every Doppler, Hz (0.44 ppm of
/// L1, a TCXO's): in the samples ([`DOPPLER_HZ`] includes it), unknown to the flight computer.
pub const OSCILLATOR_OFFSET_HZ: f64 = 700.0;
/// The flight computer's error in each satellite's predicted geometric Doppler (almanac, time
/// and orbit), Hz.
pub const ORBIT_ERROR_HZ: [f64; 8] = [35.0, -20.0, 55.0, -45.0, 10.0, -60.0, 25.0, -5.0];

/// The warm start's prediction of satellite `s`'s Doppler, Hz: the geometric Doppler the
/// flight computer predicts, without the oscillator's offset and with its orbit error
/// (0 for an index beyond the sky).
pub fn predicted_doppler_hz(s: usize) -> f32 {
    match (DOPPLER_HZ.get(s), ORBIT_ERROR_HZ.get(s)) {
        (Some(d), Some(e)) => (d - OSCILLATOR_OFFSET_HZ + e) as f32,
        _ => 0.0,
    }
}

/// Code phase of the eight satellites at sample 0, chips.
pub const CODE_PHASE_CHIPS: [f64; 8] = [17.3, 905.6, 412.0, 233.9, 688.2, 1001.4, 96.7, 540.5];
/// Carrier phase of the eight satellites at sample 0 (array origin), cycles.
pub const CARRIER_PHASE_CYCLES: [f32; 8] = [0.11, 0.73, 0.42, 0.95, 0.27, 0.58, 0.06, 0.84];

const CHIP_RATE_HZ: f64 = 1.023e6;
const L1_HZ: f64 = 1575.42e6;
const CODE_CHIPS: u64 = 1023;
/// 2³², the fixed-point scale of phases.
const TWO_32: f64 = 4_294_967_296.0;
/// Samples synthesized at a time (scratch of 6 × this many f32 on the stack).
const CHUNK: usize = 260;
/// Entries of the carrier table (one cycle).
const TABLE: usize = 256;

/// One satellite's generator state.
struct Satellite {
    /// Its C/A code.
    prn: Prn,
    /// Code phase, chips in 32.32 fixed point, in `[0, 1023·2³²)`.
    code_phase: u64,
    /// Code phase step per sample, 32.32 chips.
    code_step: u64,
    /// Code periods since sample 0 (the data bits' clock).
    periods: u32,
    /// Data bit of the current period, ±1.
    bit: f32,
    /// Carrier phase at the array origin, cycles · 2³² (wrapping).
    carrier: u32,
    /// Carrier phase step per sample, cycles · 2³² (wrapping).
    carrier_step: u32,
    /// Per-antenna phase offset (geometry + line bias), cycles · 2³².
    offset: [u32; 3],
    /// Line of sight (reference frame).
    los: Vector3<f32>,
}

/// The sample generator: the stream's state (sample index, every satellite's phases, the
/// noise generator's state).
pub struct Synth {
    sats: [Satellite; 8],
    /// `cos 2π k / TABLE`.
    cos: [f32; TABLE],
    /// Signal amplitude per component, noise σ.
    amplitude: f32,
    rng: u32,
    /// The stream's next sample.
    next_sample: u64,
    flight: ExampleFlight,
}

/// ±1 data bit of satellite `s`'s bit number `b`.
fn data_bit(s: usize, b: u32) -> f32 {
    let h = (b.wrapping_add(0x51ED * s as u32)).wrapping_mul(0x9E37_79B9);
    if (h >> 13) & 1 == 0 {
        1.0
    } else {
        -1.0
    }
}

impl Synth {
    /// The generator at sample 0, noise seed `seed`.
    #[optimize(size)]
    pub fn new(seed: u32) -> Self {
        let flight = ExampleFlight::new(7);
        let sats = core::array::from_fn(|s| {
            let doppler = DOPPLER_HZ[s];
            let prn = Prn::new(SKY[s].0).unwrap_or(Prn::FIRST);
            let code_rate = CHIP_RATE_HZ * (1.0 + doppler / L1_HZ);
            Satellite {
                prn,
                code_phase: (CODE_PHASE_CHIPS[s] * TWO_32) as u64,
                code_step: (code_rate / SAMPLE_RATE_HZ * TWO_32 + 0.5) as u64,
                periods: 0,
                bit: data_bit(s, 0),
                carrier: (CARRIER_PHASE_CYCLES[s] as f64 * TWO_32) as u32,
                carrier_step: (doppler / SAMPLE_RATE_HZ * TWO_32).round() as i64 as u32,
                offset: [0; 3],
                los: ExampleFlight::los(s),
            }
        });
        let cos = core::array::from_fn(|k| ComplexField::cos(core::f32::consts::TAU * k as f32 / TABLE as f32));
        let cn0 = ComplexField::powf(10.0f32, 0.1 * CN0_DBHZ);
        let mut synth = Self {
            sats,
            cos,
            amplitude: ComplexField::sqrt(2.0 * cn0 / SAMPLE_RATE_HZ as f32),
            rng: seed | 1,
            next_sample: 0,
            flight,
        };
        synth.set_geometry(0);
        synth
    }

    /// The stream's next sample.
    pub fn next_sample(&self) -> u64 {
        self.next_sample
    }

    /// The true attitude (body to reference) at the centre of receiver epoch `epoch`, as the
    /// gate sees it: with `wrong-expected` on the semihosting command line rotated by
    /// [`crate::cmdline::WRONG_TRUTH_DEG`] about body x (the gate must then fail; `.ci/run` checks it).
    pub fn truth(&self, epoch: u64) -> gnss_attitude::geometry::Quaternion<f32> {
        crate::cmdline::gate_truth(self.flight.attitude(epoch))
    }

    /// The example flight (its aiding and gyro increments).
    pub fn flight(&self) -> &ExampleFlight {
        &self.flight
    }

    /// Sets every satellite's per-antenna phase offset to the geometry of epoch `epoch`:
    /// `(μ·C_rb r_P)/λ + b_P` (`b_A = 0`).
    #[optimize(size)]
    pub fn set_geometry(&mut self, epoch: u64) {
        let c_rb = self.flight.attitude(epoch).to_dcm();
        let positions = antennas().map(Vector3::from);
        let lambda = GPS_L1_WAVELENGTH_M as f32;
        let bias = [0.0, LINE_BIAS_RAD[0], LINE_BIAS_RAD[1]];
        for sat in self.sats.iter_mut() {
            for (p, off) in sat.offset.iter_mut().enumerate() {
                let cycles = sat.los.dot(&(c_rb * positions[p])) / lambda + bias[p] / core::f32::consts::TAU;
                let frac = cycles - ComplexField::floor(cycles);
                *off = (frac as f64 * TWO_32) as u32;
            }
        }
    }

    /// Advances the stream by `n` samples without producing them.
    #[optimize(size)]
    pub fn skip(&mut self, n: u64) {
        for (s, sat) in self.sats.iter_mut().enumerate() {
            let total = sat.code_phase as u128 + sat.code_step as u128 * n as u128;
            let period = (CODE_CHIPS as u128) << 32;
            sat.periods = sat.periods.wrapping_add((total / period) as u32);
            sat.code_phase = (total % period) as u64;
            sat.bit = data_bit(s, sat.periods / 20);
            sat.carrier = sat.carrier.wrapping_add(sat.carrier_step.wrapping_mul(n as u32));
        }
        self.next_sample = self.next_sample.wrapping_add(n);
    }

    /// One noise component, σ = 1 (sum of four uniform bytes, centred and scaled).
    #[inline(always)]
    fn noise(&mut self) -> f32 {
        let mut x = self.rng;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.rng = x;
        let sum = (x & 0xFF) + ((x >> 8) & 0xFF) + ((x >> 16) & 0xFF) + (x >> 24);
        // four uniform bytes: mean 510, variance 4 (256² − 1) / 12
        (sum as f32 - 510.0) * (1.0 / 147.800_54)
    }

    /// The stream's next complex samples of the three antennas as the front end delivers
    /// them, `out[0].len()` bytes of each ([`FrontEnd::sample_format`]: `bit1iq` or `sm2iq`,
    /// first sample in the most significant bits), one stream per antenna.
    #[optimize(size)]
    pub fn fill_bytes(&mut self, front_end: FrontEnd, out: [&mut [u8]; 3]) {
        let per_byte = front_end.samples_per_byte();
        let len = per_byte * out[0].len();
        let mut out = out;
        self.generate(3, len, |p, start, re, im| {
            let bytes = &mut out[p][start / per_byte..(start + re.len()) / per_byte];
            for (b, (i, q)) in bytes.iter_mut().zip(re.chunks_exact(per_byte).zip(im.chunks_exact(per_byte))) {
                *b = front_end.byte(i, q);
            }
        });
    }

    /// Generates the next `len` samples of the first `antennas` antennas in chunks of
    /// [`CHUNK`] (even, so that byte outputs stay aligned): `out(antenna, first, re, im)` takes
    /// each chunk's analog components (noise σ = 1).
    #[optimize(size)]
    fn generate(&mut self, antennas: usize, len: usize, mut out: impl FnMut(usize, usize, &[f32], &[f32])) {
        let mut start = 0;
        while start < len {
            let n = CHUNK.min(len - start);
            let mut re = [[0.0f32; CHUNK]; 3];
            let mut im = [[0.0f32; CHUNK]; 3];
            for p in 0..antennas {
                for k in 0..n {
                    re[p][k] = self.noise();
                    im[p][k] = self.noise();
                }
            }
            for (s, sat) in self.sats.iter_mut().enumerate() {
                let a = self.amplitude;
                for k in 0..n {
                    let chip = (sat.code_phase >> 32) as usize;
                    let v = a * sat.bit * f32::from(sat.prn.chip(chip));
                    for p in 0..antennas {
                        let ph = sat.carrier.wrapping_add(sat.offset[p]) >> 24;
                        re[p][k] += v * self.cos[ph as usize];
                        im[p][k] += v * self.cos[(ph.wrapping_sub(64) & 0xFF) as usize];
                    }
                    sat.carrier = sat.carrier.wrapping_add(sat.carrier_step);
                    sat.code_phase += sat.code_step;
                    if sat.code_phase >= CODE_CHIPS << 32 {
                        sat.code_phase -= CODE_CHIPS << 32;
                        sat.periods = sat.periods.wrapping_add(1);
                        sat.bit = data_bit(s, sat.periods / 20);
                    }
                }
            }
            for p in 0..antennas {
                out(p, start, &re[p][..n], &im[p][..n]);
            }
            start += n;
        }
        self.next_sample = self.next_sample.wrapping_add(len as u64);
    }
}
