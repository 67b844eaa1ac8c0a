//! Front-end quantization: analog samples (noise σ = 1 per component) into the byte layouts of
//! [`SampleFormat`] (documented in the core's `signal::samples`).
//!
//! * CS8 / Int8: `round(g₈ x)` saturated to `−128..=127`, `g₈` = [`CS8_GAIN`] LSB per σ.
//! * CS16: `round(g₁₆ x)` saturated to `i16`, `g₁₆` = [`CS16_GAIN`] LSB per σ (decode with
//!   `shift = 6` to bring σ to 15.6 LSB).
//! * 2-bit sign/magnitude: sign, and magnitude bit set when `|x| > T`, `T` =
//!   [`TWO_BIT_THRESHOLD`] σ (near the optimum for the `±1, ±3` levels: 0.55 dB loss).
//! * 1-bit: sign (1.96 dB loss).
//!
//! [`Quantizer`] is the front end of the sample-level scenarios (`host-sim run --front-end`):
//! the CS8 layout above, or the 2-bit / 1-bit quantizers as `i8` values
//! ([`Quantizer::quantize`]): the search takes them as they are, and the `signal` and
//! `one-stage` channels ([`crate::chain`]) pack them into bit planes for the core's
//! bit-parallel correlator ([`Quantizer::bit_settings`]); the `microsat` sample-level stretch
//! still hands them to the `i8` correlator.

use anyhow::{bail, Result};
use gnss_attitude::signal::bitwise::{CarrierLevels, PlaneFormat, Resolution};
use gnss_attitude::signal::samples::sign_magnitude;
use gnss_attitude::signal::{BitSettings, SampleFormat};

use super::scene::AnalogSamples;

/// CS8 / Int8 gain, LSB per noise σ.
pub const CS8_GAIN: f32 = 16.0;
/// CS16 gain, LSB per noise σ.
pub const CS16_GAIN: f32 = 1000.0;
/// 2-bit magnitude threshold, in noise σ.
pub const TWO_BIT_THRESHOLD: f32 = 1.0;
/// CS16 decode shift that matches [`CS16_GAIN`] to the correlator's 8-bit input.
pub const CS16_SHIFT: u8 = 6;

fn sat8(x: f32, gain: f32) -> u8 {
    (x * gain).round().clamp(-128.0, 127.0) as i8 as u8
}

fn two_bit(x: f32) -> u8 {
    let sign = u8::from(x < 0.0);
    let mag = u8::from(x.abs() > TWO_BIT_THRESHOLD);
    (sign << 1) | mag
}

/// The C/N0 loss of the bit-parallel correlator's 3-level carrier replica in theory, dB.
pub const CARRIER_3LEVEL_LOSS_DB: f64 = 0.35;

/// Level of a 2-bit sample handed to the `i8` correlator, LSB per unit level (`±1, ±3` become
/// `±8, ±24`: RMS 15.0 LSB at the 1σ threshold, next to CS8's 16 LSB per σ).
pub const SM2_LSB_PER_LEVEL: i8 = 8;
/// Level of a 1-bit sample handed to the `i8` correlator, LSB (`±1` becomes `±16`: RMS 16 LSB,
/// CS8's σ).
pub const BIT1_LSB_PER_LEVEL: i8 = 16;

/// The front end's quantizer on the sample-level paths (`--front-end`): what the receiver's
/// ADC delivers from the same analog samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Quantizer {
    /// Complex 8-bit (CS8, [`CS8_GAIN`] LSB per σ): the default, today's figures.
    #[default]
    I8,
    /// Complex 2-bit sign/magnitude (levels `±1, ±3`, threshold [`TWO_BIT_THRESHOLD`] σ), as a
    /// MAX2769 / NT1065 delivers; as `i8` values `±8, ±24`.
    Sm2,
    /// Complex 1-bit (sign, `±1`); as `i8` values `±16`.
    Bit1,
}

impl Quantizer {
    /// Every quantizer, the reference (`i8`) first.
    pub const ALL: [Self; 3] = [Self::I8, Self::Sm2, Self::Bit1];

    /// The name on the command line and in the JSON (`i8`, `sm2`, `bit1`).
    pub const fn name(self) -> &'static str {
        match self {
            Self::I8 => "i8",
            Self::Sm2 => "sm2",
            Self::Bit1 => "bit1",
        }
    }

    /// The C/N0 loss of this quantizer on white Gaussian noise, in theory, dB: 0 for `i8`
    /// (16 LSB per σ), 0.55 for 2-bit sign/magnitude at the [`TWO_BIT_THRESHOLD`], 1.96
    /// (`10·log₁₀(π/2)`) for 1-bit. The microsat fast path lowers the correlator outputs it
    /// emulates by this much; the sample-level paths get the loss from the quantizer itself.
    pub fn theory_loss_db(self) -> f64 {
        match self {
            Self::I8 => 0.0,
            Self::Sm2 => 0.55,
            Self::Bit1 => 10.0 * std::f64::consts::FRAC_PI_2.log10(),
        }
    }

    /// The C/N0 loss of the bit-parallel path ([`Quantizer::bit_settings`]) in theory, dB:
    /// the samples' ([`Quantizer::theory_loss_db`]) plus the 3-level carrier's 0.35 dB (0 for
    /// `i8`). The `signal` and `one-stage` scenarios' channels run this path.
    pub fn bit_path_theory_loss_db(self) -> f64 {
        match self {
            Self::I8 => 0.0,
            _ => self.theory_loss_db() + CARRIER_3LEVEL_LOSS_DB,
        }
    }

    /// The quantizer called `name`.
    ///
    /// # Errors
    /// An unknown name.
    pub fn parse(name: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|q| q.name() == name)
            .ok_or_else(|| anyhow::anyhow!("no front end {name:?}; front ends: i8, sm2, bit1"))
    }

    /// The sample value the correlator receives for analog `x` (noise σ = 1) from a 2- or
    /// 1-bit quantizer (`None` for [`Quantizer::I8`], which goes through the CS8 layout).
    pub fn level(self, x: f32) -> Option<i8> {
        match self {
            Self::I8 => None,
            Self::Sm2 => Some(sign_magnitude(two_bit(x)) * SM2_LSB_PER_LEVEL),
            Self::Bit1 => Some(if x < 0.0 {
                -BIT1_LSB_PER_LEVEL
            } else {
                BIT1_LSB_PER_LEVEL
            }),
        }
    }

    /// The antennas' analog samples as the receiver's correlators take them: through `format`
    /// (encoded and decoded by the core) for [`Quantizer::I8`], else quantized sample by
    /// sample ([`Quantizer::level`]; complex samples need complex analog samples).
    ///
    /// # Errors
    /// As [`encode`] and [`decode`] for `i8`.
    pub fn quantize(
        self,
        format: SampleFormat,
        analog: &[AnalogSamples],
        n: usize,
    ) -> Result<Planar> {
        if self == Self::I8 {
            let streams = encode(format, analog)?;
            return decode(format, &streams, analog.len(), n);
        }
        let map = |v: &[f32]| -> Vec<i8> {
            v.iter()
                .take(n)
                .map(|&x| self.level(x).unwrap_or(0))
                .collect()
        };
        Ok(Planar {
            i: analog.iter().map(|a| map(&a.i)).collect(),
            q: analog.iter().map(|a| map(&a.q)).collect(),
        })
    }
}

impl Quantizer {
    /// The bit-parallel correlator's settings the sample-level chain ([`crate::chain`]) runs
    /// for this front end's samples (`None` for [`Quantizer::I8`], which runs the `i8`
    /// correlator): 2- or 1-bit planes and the 3-level carrier (0.35 dB of carrier
    /// quantization against 0.91 dB for the 2-level one, which keeps both front ends within
    /// issue 18's loss targets; the M4F's cheaper 2-level kernel is the firmware's choice).
    pub fn bit_settings(self, complex: bool) -> Option<BitSettings> {
        let resolution = match self {
            Self::I8 => return None,
            Self::Sm2 => Resolution::TwoBit,
            Self::Bit1 => Resolution::OneBit,
        };
        let carrier = CarrierLevels::Three;
        Some(BitSettings {
            format: PlaneFormat {
                resolution,
                complex,
            },
            carrier,
        })
    }

    /// The magnitude threshold that packs this quantizer's `i8` values
    /// ([`Quantizer::level`]) into bit planes exactly (`PlaneBuffer::pack_i8`): between the
    /// 2-bit levels `±8` and `±24`.
    pub const PLANE_THRESHOLD: u8 = 2 * SM2_LSB_PER_LEVEL as u8;
}

impl std::fmt::Display for Quantizer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Encodes the antennas' samples into `format`: one byte stream per antenna, or a single
/// stream for [`SampleFormat::MultiChannel2`] (which must list as many channels as antennas).
pub fn encode(format: SampleFormat, antennas: &[AnalogSamples]) -> Result<Vec<Vec<u8>>> {
    let complex = format.is_complex();
    if let Some(a) = antennas.first() {
        if complex && a.q.len() != a.i.len() {
            bail!("complex format {format:?} needs complex samples");
        }
    }
    if let SampleFormat::MultiChannel2 { channels } = format {
        if usize::from(channels) != antennas.len() {
            bail!(
                "format has {channels} channels, scene has {} antennas",
                antennas.len()
            );
        }
        let n = antennas.first().map_or(0, |a| a.i.len());
        let mut out = vec![0u8; n];
        for (c, a) in antennas.iter().enumerate() {
            for (o, &x) in out.iter_mut().zip(&a.i) {
                *o |= two_bit(x) << (2 * c);
            }
        }
        return Ok(vec![out]);
    }
    antennas
        .iter()
        .map(|a| {
            let n = a.i.len();
            let bytes = format.bytes_for(n).ok_or_else(|| {
                anyhow::anyhow!("{n} samples do not fill whole bytes of {format:?}")
            })?;
            let mut out = vec![0u8; bytes];
            match format {
                SampleFormat::Cs8 => {
                    for k in 0..n {
                        out[2 * k] = sat8(a.i[k], CS8_GAIN);
                        out[2 * k + 1] = sat8(a.q[k], CS8_GAIN);
                    }
                }
                SampleFormat::Cs16 { .. } => {
                    for k in 0..n {
                        for (j, x) in [a.i[k], a.q[k]].into_iter().enumerate() {
                            let v = (x * CS16_GAIN).round().clamp(-32768.0, 32767.0) as i16;
                            out[4 * k + 2 * j..4 * k + 2 * j + 2].copy_from_slice(&v.to_le_bytes());
                        }
                    }
                }
                SampleFormat::Int8 => {
                    for (o, &x) in out.iter_mut().zip(&a.i) {
                        *o = sat8(x, CS8_GAIN);
                    }
                }
                SampleFormat::SignMagnitude2 { complex: false } => {
                    for k in 0..n {
                        out[k / 4] |= two_bit(a.i[k]) << (6 - 2 * (k % 4));
                    }
                }
                SampleFormat::SignMagnitude2 { complex: true } => {
                    for k in 0..n {
                        let shift = if k % 2 == 0 { 4 } else { 0 };
                        out[k / 2] |= (two_bit(a.i[k]) << (shift + 2)) | (two_bit(a.q[k]) << shift);
                    }
                }
                SampleFormat::Sign1 => {
                    for k in 0..n {
                        out[k / 8] |= u8::from(a.i[k] < 0.0) << (7 - k % 8);
                    }
                }
                SampleFormat::Sign1Iq => {
                    for k in 0..n {
                        let shift = 6 - 2 * (k % 4);
                        out[k / 4] |= (u8::from(a.i[k] < 0.0) << (shift + 1))
                            | (u8::from(a.q[k] < 0.0) << shift);
                    }
                }
                SampleFormat::MultiChannel2 { .. } => unreachable!("handled above"),
            }
            Ok(out)
        })
        .collect()
}

/// Planar decoded samples of every antenna, as the core's correlators take them.
#[derive(Clone, Debug, Default)]
pub struct Planar {
    /// In-phase samples per antenna.
    pub i: Vec<Vec<i8>>,
    /// Quadrature samples per antenna (empty vectors for real formats).
    pub q: Vec<Vec<i8>>,
}

/// Decodes encoded streams (as [`encode`] makes them) with the core's decoder.
pub fn decode(
    format: SampleFormat,
    streams: &[Vec<u8>],
    antennas: usize,
    n: usize,
) -> Result<Planar> {
    let mut p = Planar::default();
    for a in 0..antennas {
        let (stream, channel) = match format {
            SampleFormat::MultiChannel2 { .. } => (&streams[0], a),
            _ => (&streams[a], 0),
        };
        let mut i = vec![0i8; n];
        let mut q = vec![0i8; if format.is_complex() { n } else { 0 }];
        let got = format.decode(stream, channel, &mut i, &mut q)?;
        if got != n {
            bail!("decoded {got} of {n} samples");
        }
        p.i.push(i);
        p.q.push(q);
    }
    Ok(p)
}
