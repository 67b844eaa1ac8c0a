//! Front-end quantization: analog samples (noise σ = 1 per component) into the byte layouts of
//! [`SampleFormat`] (documented in the core's `signal::samples`).
//!
//! * CS8 / Int8: `round(g₈ x)` saturated to `−128..=127`, `g₈` = [`CS8_GAIN`] LSB per σ.
//! * CS16: `round(g₁₆ x)` saturated to `i16`, `g₁₆` = [`CS16_GAIN`] LSB per σ (decode with
//!   `shift = 6` to bring σ to 15.6 LSB).
//! * 2-bit sign/magnitude: sign, and magnitude bit set when `|x| > T`, `T` =
//!   [`TWO_BIT_THRESHOLD`] σ (near the optimum for the `±1, ±3` levels: 0.55 dB loss).
//! * 1-bit: sign (1.96 dB loss).

use anyhow::{bail, Result};
use gnss_attitude::signal::SampleFormat;

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
