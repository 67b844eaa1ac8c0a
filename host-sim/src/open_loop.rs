//! The open-loop correlator experiment: what a 2- or 1-bit front end costs, and what the
//! bit-parallel correlator's quantized carrier costs on top, with the replica held at the
//! truth (no loops).
//!
//! One satellite (PRN 7, 1234.5 Hz Doppler, no Doppler rate, code phase 211.3 chips, carrier
//! phase 0.17 cycle, **no data bits**) on the `signal` scenario's three antennas and its line
//! biases, a constant attitude, complex samples at 2.6 Msps with thermal noise (σ = 1). Every
//! correlator's NCOs are set to the truth at sample 0, so each antenna's prompt is a constant
//! phasor `m` plus noise over the epochs. Four correlations of the same samples:
//!
//! | path | samples | correlator |
//! |---|---|---|
//! | `cs8` | CS8 (16 LSB per σ) | `i8` [`Correlator`] (256-entry carrier table) |
//! | `quantized` | the front end's (2- or 1-bit, as `i8` values) | `i8` [`Correlator`] |
//! | `bits_2level` | the same samples as bit planes | [`BitCorrelator`], 2-level carrier |
//! | `bits_3level` | the same | [`BitCorrelator`], 3-level carrier |
//!
//! The post-correlation SNR of a path is `Σ_a |m̂_a|² / Σ_a v̂_a` over the antennas `a`, with
//! `m̂_a` the mean prompt and `v̂_a = mean |P − m̂_a|²` its variance over the complete epochs
//! (the prompt's phase and amplitude are whatever the correlator's replica makes of them: a
//! constant rotation or gain does not matter). Losses are ratios of these SNRs in dB:
//! the sample quantization `cs8 / quantized`, the carrier quantization `quantized /
//! bits_Nlevel`. The estimator's spread over `N` epochs and three antennas is about
//! `4.3/√(3N)` dB per SNR (0.06 dB at 2000 epochs); the paths share the noise, so their
//! differences scatter less.

use anyhow::{anyhow, bail, Result};
use gnss_attitude::signal::bitwise::{
    BitBlock, BitCorrelator, BitCorrelatorConfig, BitScratch, CarrierLevels, CodeTable,
    PlaneBuffer, PlaneFormat, Resolution,
};
use gnss_attitude::signal::{
    Correlator, CorrelatorConfig, EpochCorrelations, Iq, Prn, SampleBlock, SampleFormat, SlaveTaps,
    CA_CHIP_RATE_HZ, GPS_L1_HZ,
};
use nalgebra::{Matrix3, Vector3};

use crate::arrays::triangle;
use crate::synth::quantize::{Planar, Quantizer, SM2_LSB_PER_LEVEL};
use crate::synth::{AttitudeMotion, FrontEnd, Satellite, Scene};

/// Complete epochs of the experiment the `signal` scenario runs (2 s).
pub const OPEN_LOOP_EPOCHS: usize = 2000;
/// Sample rate, Hz.
const SAMPLE_RATE_HZ: f64 = 2.6e6;
/// Samples per streamed block (10 ms).
const BLOCK: usize = 26_000;
/// Plane words per buffer (32 768 samples ≥ [`BLOCK`]).
const PLANE_WORDS: usize = 1024;
/// PRN of the satellite.
const PRN: u8 = 7;
/// Antennas.
const ANTENNAS: usize = 3;

crate::metrics! {
    /// The open-loop experiment's losses (module [`crate::open_loop`]).
    pub struct OpenLoopLosses {
        /// Sample quantization: SNR of the `i8` correlator on CS8 samples over its SNR on the
        /// front end's samples (same analog samples).
        #[metric(unit = "dB")] pub open_loop_sample_loss_db: f64,
        /// Carrier quantization: SNR of the `i8` correlator on the front end's samples over
        /// the bit-parallel correlator's (2-level carrier) on the same samples.
        #[metric(unit = "dB")] pub open_loop_carrier_loss_db_2level: f64,
        /// The same with the 3-level carrier.
        #[metric(unit = "dB")] pub open_loop_carrier_loss_db_3level: f64,
        /// Complete 1 ms epochs per path.
        #[metric(unit = "")] pub open_loop_epochs: usize,
    }
}

/// The experiment's scene at `cn0_dbhz` (module documentation).
pub fn scene(cn0_dbhz: f64, seed: u64) -> Scene {
    Scene {
        satellites: vec![Satellite {
            prn: PRN,
            cn0_dbhz,
            doppler_hz: 1234.5,
            doppler_rate_hz_s: 0.0,
            code_phase_chips: 211.3,
            carrier_phase_cycles: 0.17,
            los_ref: Vector3::new(0.3, -0.2, 0.932_737_905).normalize(),
            data_seed: None,
            track: None,
        }],
        antennas_b: triangle(1.5),
        line_bias_cycles: vec![0.0, 0.13, -0.27],
        attitude: AttitudeMotion::Constant(Matrix3::identity()),
        front_end: FrontEnd {
            sample_rate_hz: SAMPLE_RATE_HZ,
            intermediate_frequency_hz: 0.0,
            complex: true,
        },
        noise_seed: Some(seed ^ 0x0b3e_410b),
    }
}

/// The four paths' prompts over the same samples.
#[derive(Default)]
struct Prompts {
    cs8: Vec<[Iq; ANTENNAS]>,
    quantized: Vec<[Iq; ANTENNAS]>,
    bits_2level: Vec<[Iq; ANTENNAS]>,
    bits_3level: Vec<[Iq; ANTENNAS]>,
}

/// The correlators of the four paths, their NCOs at the truth of sample 0.
struct Engines {
    cs8: Correlator<ANTENNAS>,
    quantized: Correlator<ANTENNAS>,
    bits: [BitCorrelator<ANTENNAS>; 2],
    format: PlaneFormat,
}

impl Engines {
    fn new(sc: &Scene, quantizer: Quantizer) -> Result<Self> {
        let resolution = match quantizer {
            Quantizer::Sm2 => Resolution::TwoBit,
            Quantizer::Bit1 => Resolution::OneBit,
            Quantizer::I8 => bail!("the open-loop experiment needs a 2- or 1-bit front end"),
        };
        let truth = sc.truth(0, 0, 0.0);
        let carrier_hz = truth.doppler_hz;
        let code_rate = CA_CHIP_RATE_HZ * (1.0 + truth.doppler_hz / GPS_L1_HZ);
        let cfg = CorrelatorConfig {
            sample_rate_hz: SAMPLE_RATE_HZ,
            intermediate_frequency_hz: 0.0,
            early_late_offset_chips: 0.5,
            slave_taps: SlaveTaps::Prompt,
        };
        let prn = Prn::new(PRN).ok_or_else(|| anyhow!("PRN {PRN}"))?;
        let i8_engine = || -> Result<Correlator<ANTENNAS>> {
            let mut c = Correlator::new(prn, &cfg)?;
            c.set_carrier_frequency(carrier_hz)?;
            c.set_code_rate(code_rate)?;
            c.set_code_phase(truth.code_phase_chips)?;
            Ok(c)
        };
        let format = PlaneFormat {
            resolution,
            complex: true,
        };
        let bit_engine = |carrier: CarrierLevels| -> Result<BitCorrelator<ANTENNAS>> {
            let config = BitCorrelatorConfig {
                correlator: cfg,
                format,
                carrier,
            };
            let mut c = BitCorrelator::new(prn, &config)?;
            c.set_carrier_frequency(carrier_hz)?;
            c.set_code_rate(code_rate)?;
            c.set_code_phase(truth.code_phase_chips)?;
            Ok(c)
        };
        Ok(Self {
            cs8: i8_engine()?,
            quantized: i8_engine()?,
            bits: [
                bit_engine(CarrierLevels::Two)?,
                bit_engine(CarrierLevels::Three)?,
            ],
            format,
        })
    }
}

fn prompts(e: &EpochCorrelations<ANTENNAS>) -> Option<[Iq; ANTENNAS]> {
    e.complete
        .then(|| core::array::from_fn(|a| e.taps[a].prompt))
}

/// Runs an `i8` correlator over a decoded block; complete epochs' prompts into `out`.
fn run_i8(
    c: &mut Correlator<ANTENNAS>,
    first: u64,
    p: &Planar,
    out: &mut Vec<[Iq; ANTENNAS]>,
) -> Result<()> {
    let sb = SampleBlock::complex(
        first,
        [&p.i[0], &p.i[1], &p.i[2]],
        [&p.q[0], &p.q[1], &p.q[2]],
    )?;
    let mut cursor = 0;
    while cursor < sb.len() {
        if let Some(e) = c.run(&sb, &mut cursor)? {
            out.extend(prompts(&e));
        }
    }
    Ok(())
}

/// Runs a bit-parallel correlator over a block of planes; complete epochs' prompts into `out`.
fn run_bits(
    c: &mut BitCorrelator<ANTENNAS>,
    block: &BitBlock<'_, ANTENNAS>,
    out: &mut Vec<[Iq; ANTENNAS]>,
) -> Result<()> {
    let mut cursor = 0;
    let mut scratch = BitScratch::new();
    while cursor < block.len() {
        if let Some(e) = c.run_in(block, &mut cursor, &mut scratch)? {
            out.extend(prompts(&e));
        }
    }
    Ok(())
}

/// Correlates `epochs` complete epochs (and a little more) of `sc` on the four paths.
fn correlate(sc: &Scene, quantizer: Quantizer, epochs: usize) -> Result<Prompts> {
    let mut engines = Engines::new(sc, quantizer)?;
    let table = CodeTable::new(SAMPLE_RATE_HZ)?;
    let mut bufs: Vec<Box<PlaneBuffer<PLANE_WORDS>>> = (0..ANTENNAS)
        .map(|_| Box::new(PlaneBuffer::new(engines.format)))
        .collect();
    let threshold = 2 * SM2_LSB_PER_LEVEL.unsigned_abs();
    let mut out = Prompts::default();
    let mut first = 0u64;
    while out.bits_3level.len() < epochs {
        let analog = sc.synthesize(first, BLOCK);
        let cs8 = Quantizer::I8.quantize(SampleFormat::Cs8, &analog, BLOCK)?;
        run_i8(&mut engines.cs8, first, &cs8, &mut out.cs8)?;
        let q = quantizer.quantize(SampleFormat::Cs8, &analog, BLOCK)?;
        run_i8(&mut engines.quantized, first, &q, &mut out.quantized)?;
        for (buf, (i, qq)) in bufs.iter_mut().zip(q.i.iter().zip(&q.q)) {
            if buf.pack_i8(i, qq, threshold)? != BLOCK {
                bail!("a plane buffer holds fewer than {BLOCK} samples");
            }
        }
        let block = BitBlock::new(
            first,
            &table,
            [bufs[0].planes(), bufs[1].planes(), bufs[2].planes()],
        )?;
        let [two, three] = &mut engines.bits;
        run_bits(two, &block, &mut out.bits_2level)?;
        run_bits(three, &block, &mut out.bits_3level)?;
        first += BLOCK as u64;
    }
    Ok(out)
}

/// The post-correlation SNR `Σ_a |m̂_a|² / Σ_a v̂_a` of the first `n` epochs (module
/// documentation).
pub fn post_correlation_snr(prompts: &[[Iq; ANTENNAS]], n: usize) -> f64 {
    let p = &prompts[..n.min(prompts.len())];
    let count = p.len().max(1) as f64;
    let (mut signal, mut noise) = (0.0, 0.0);
    for a in 0..ANTENNAS {
        let z = |e: &[Iq; ANTENNAS]| (f64::from(e[a].i), f64::from(e[a].q));
        let (mi, mq) = p
            .iter()
            .map(z)
            .fold((0.0, 0.0), |s, (i, q)| (s.0 + i, s.1 + q));
        let (mi, mq) = (mi / count, mq / count);
        signal += mi * mi + mq * mq;
        noise += p
            .iter()
            .map(z)
            .map(|(i, q)| (i - mi).powi(2) + (q - mq).powi(2))
            .sum::<f64>()
            / count;
    }
    signal / noise
}

/// Runs the experiment for `quantizer` (`sm2` or `bit1`) at `cn0_dbhz` over `epochs` epochs.
///
/// # Errors
/// `i8` (nothing to compare), or a correlator's refusal.
pub fn open_loop_losses(
    quantizer: Quantizer,
    cn0_dbhz: f64,
    seed: u64,
    epochs: usize,
) -> Result<OpenLoopLosses> {
    let sc = scene(cn0_dbhz, seed);
    let p = correlate(&sc, quantizer, epochs)?;
    let n = [&p.cs8, &p.quantized, &p.bits_2level, &p.bits_3level]
        .iter()
        .map(|v| v.len())
        .min()
        .unwrap_or(0)
        .min(epochs);
    let snr = |v: &[[Iq; ANTENNAS]]| post_correlation_snr(v, n);
    let db = |a: f64, b: f64| 10.0 * (a / b).log10();
    let quantized = snr(&p.quantized);
    Ok(OpenLoopLosses {
        open_loop_sample_loss_db: db(snr(&p.cs8), quantized),
        open_loop_carrier_loss_db_2level: db(quantized, snr(&p.bits_2level)),
        open_loop_carrier_loss_db_3level: db(quantized, snr(&p.bits_3level)),
        open_loop_epochs: n,
    })
}
