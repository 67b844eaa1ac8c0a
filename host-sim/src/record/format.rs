//! File layouts of recorded samples: the `--format` names, their byte layouts, and the
//! interleaving of several channels (antennas) in one file.
//!
//! A layout is the core's [`SampleFormat`] of one channel plus how channels share the file:
//!
//! | `--format` | Samples | Bytes per instant | Layout |
//! |---|---|---|---|
//! | `cs8` | complex | 2 | `I Q` signed bytes (HackRF, rtl-sdr after offset removal, GNSS-SDR `ibyte`, Pocket SDR `INT8X2`) |
//! | `cs16[:S]` | complex | 4 | `I Q` little-endian `i16` (USRP `sc16`, GNSS-SDR `ishort`); reduced to 8 bits by `round(v/2^S)` with saturation; without `:S` the shift is chosen from the first 10 ms (noise RMS near 16 LSB) |
//! | `int8` | real (`--if`) | 1 | signed byte |
//! | `sm2` | real (`--if`) | ¼ | four 2-bit sign/magnitude fields per byte, first sample in the two most significant bits; field `s m`: `00 → +1, 01 → +3, 10 → −1, 11 → −3` (MAX2769 / NT1065 `SIGN`, `MAG`) |
//! | `sm2iq` | complex | ½ | as `sm2`, fields alternating I, Q (two complex samples per byte) |
//! | `bit1` | real (`--if`) | ⅛ | eight sign bits per byte, first sample in the most significant bit; `0 → +1, 1 → −1` |
//! | `mc2xN` (N = 1–4) | real (`--if`) | 1 | **one byte per sample instant holding N channels**: channel `c` in bits `2c+1` (sign) and `2c` (magnitude), same field coding as `sm2` (the parallel 2-bit outputs of a four-channel front end such as the NT1065, captured a byte per clock) |
//! | `cs8xN`, `cs16xN[:S]`, `int8xN` | as above | N × above | N channels interleaved **per sample instant**: `I₀ Q₀ I₁ Q₁ … I_{N−1} Q_{N−1}` then the next instant (multi-channel SDR boards that write one interleaved stream) |
//!
//! Three antennas are three files of a single-channel layout (`--file` three times, antenna
//! order) or one file of a multi-channel layout (`--channels` picks the channels, antenna
//! order; default: channels 0, 1, … in order).

use anyhow::{bail, Context, Result};
use gnss_attitude::signal::SampleFormat;

/// Largest number of channels in one file.
pub const MAX_CHANNELS: usize = 4;

/// A file layout: one channel's core format, and the channels in the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FileFormat {
    /// The core format of one channel's samples (for `cs16` without a shift, shift 0 until
    /// [`FileFormat::with_cs16_shift`] sets it).
    pub sample: SampleFormat,
    /// Channels in the file, 1–4.
    pub channels: usize,
    /// `cs16` without an explicit shift: choose it from the data.
    pub auto_shift: bool,
}

/// The format names `--format` accepts, for messages.
pub const FORMAT_NAMES: &str =
    "cs8, cs16[:S], int8, sm2, sm2iq, bit1, bit1iq, mc2xN, cs8xN, cs16xN[:S], int8xN (N = 1-4, S = 0-8)";

impl FileFormat {
    /// Parses a `--format` name (see the module documentation).
    ///
    /// # Errors
    /// An unknown name, a channel count outside 1–4, a shift outside 0–8, or a shift or
    /// channel count on a format that takes none.
    pub fn parse(name: &str) -> Result<Self> {
        let lower = name.trim().to_ascii_lowercase();
        let (body, shift) = match lower.split_once(':') {
            Some((b, s)) => {
                let v: u8 = s
                    .parse()
                    .ok()
                    .filter(|v| *v <= 8)
                    .with_context(|| format!("format {name:?}: the CS16 shift must be 0-8"))?;
                (b.to_string(), Some(v))
            }
            None => (lower.clone(), None),
        };
        let (base, channels) = match body.split_once('x') {
            Some((b, n)) if !b.is_empty() => {
                let n: usize = n
                    .parse()
                    .ok()
                    .filter(|n| (1..=MAX_CHANNELS).contains(n))
                    .with_context(|| {
                        format!("format {name:?}: the channel count must be 1-{MAX_CHANNELS}")
                    })?;
                (b.to_string(), Some(n))
            }
            _ => (body.clone(), None),
        };
        if shift.is_some() && base != "cs16" {
            bail!("format {name:?}: only cs16 takes a shift (known formats: {FORMAT_NAMES})");
        }
        let sample = match base.as_str() {
            "cs8" => SampleFormat::Cs8,
            "cs16" => SampleFormat::Cs16 {
                shift: shift.unwrap_or(0),
            },
            "int8" => SampleFormat::Int8,
            "sm2" => SampleFormat::SignMagnitude2 { complex: false },
            "sm2iq" => SampleFormat::SignMagnitude2 { complex: true },
            "bit1" => SampleFormat::Sign1,
            "bit1iq" => SampleFormat::Sign1Iq,
            "mc2" => {
                let n = channels.with_context(|| {
                    format!("format {name:?}: mc2 needs its channel count, e.g. mc2x3")
                })?;
                SampleFormat::MultiChannel2 { channels: n as u8 }
            }
            _ => bail!("unknown sample format {name:?} (known formats: {FORMAT_NAMES})"),
        };
        let packed = matches!(
            sample,
            SampleFormat::SignMagnitude2 { .. } | SampleFormat::Sign1 | SampleFormat::Sign1Iq
        );
        if packed && channels.is_some() {
            bail!("format {name:?}: packed formats hold one channel (use mc2xN for several)");
        }
        Ok(Self {
            sample,
            channels: channels.unwrap_or(1),
            auto_shift: base == "cs16" && shift.is_none(),
        })
    }

    /// The canonical name of the layout (what [`FileFormat::parse`] reads back).
    pub fn name(&self) -> String {
        let base = match self.sample {
            SampleFormat::Cs8 => "cs8",
            SampleFormat::Cs16 { .. } => "cs16",
            SampleFormat::Int8 => "int8",
            SampleFormat::SignMagnitude2 { complex: false } => "sm2",
            SampleFormat::SignMagnitude2 { complex: true } => "sm2iq",
            SampleFormat::Sign1 => "bit1",
            SampleFormat::Sign1Iq => "bit1iq",
            SampleFormat::MultiChannel2 { .. } => "mc2",
        };
        let mut s = base.to_string();
        if self.channels > 1 || matches!(self.sample, SampleFormat::MultiChannel2 { .. }) {
            s.push_str(&format!("x{}", self.channels));
        }
        if let SampleFormat::Cs16 { shift } = self.sample {
            if !self.auto_shift {
                s.push_str(&format!(":{shift}"));
            }
        }
        s
    }

    /// The layout with the CS16 shift set (no-op for other formats).
    pub fn with_cs16_shift(self, shift: u8) -> Self {
        match self.sample {
            SampleFormat::Cs16 { .. } => Self {
                sample: SampleFormat::Cs16 { shift },
                auto_shift: false,
                ..self
            },
            _ => self,
        }
    }

    /// Whether the samples are complex (I/Q).
    pub fn is_complex(&self) -> bool {
        self.sample.is_complex()
    }

    /// Channels the core decodes from one byte (the 2-bit multi-channel byte), as opposed to
    /// channels interleaved instant by instant that the reader separates first.
    pub fn packed_channels(&self) -> bool {
        matches!(self.sample, SampleFormat::MultiChannel2 { .. })
    }

    /// Sample instants a whole number of bytes holds: `(instants, bytes)` of the smallest unit
    /// (e.g. `(4, 1)` for `sm2`, `(1, 6)` for `cs8x3`).
    pub fn unit(&self) -> (usize, usize) {
        match self.sample {
            SampleFormat::Cs8 => (1, 2 * self.channels),
            SampleFormat::Cs16 { .. } => (1, 4 * self.channels),
            SampleFormat::Int8 => (1, self.channels),
            SampleFormat::MultiChannel2 { .. } => (1, 1),
            SampleFormat::SignMagnitude2 { complex: false } => (4, 1),
            SampleFormat::SignMagnitude2 { complex: true } => (2, 1),
            SampleFormat::Sign1 => (8, 1),
            SampleFormat::Sign1Iq => (4, 1),
        }
    }

    /// Bytes of one channel's sample instant in the core format (before interleaving), for
    /// byte-aligned formats.
    pub fn channel_bytes(&self) -> usize {
        match self.sample {
            SampleFormat::Cs8 => 2,
            SampleFormat::Cs16 { .. } => 4,
            _ => 1,
        }
    }

    /// Sample instants in a file of `bytes` bytes.
    ///
    /// # Errors
    /// When the length is not a whole number of sample instants (a CS8 file of odd length, a
    /// CS16 file not a multiple of 4 bytes, an interleaved file cut inside an instant).
    pub fn instants_in(&self, bytes: u64) -> Result<u64> {
        let (instants, unit) = self.unit();
        if bytes % unit as u64 != 0 {
            bail!(
                "length {bytes} B is not a whole number of {} sample instants ({unit} B each): truncated file or wrong --format",
                self.name()
            );
        }
        Ok(bytes / unit as u64 * instants as u64)
    }
}

/// Separates channel `channel` of `bytes` (byte-aligned channels interleaved per instant,
/// `channel_bytes` bytes each, `channels` per instant) into `out` (cleared first).
pub fn deinterleave(
    bytes: &[u8],
    channels: usize,
    channel_bytes: usize,
    channel: usize,
    out: &mut Vec<u8>,
) {
    out.clear();
    let stride = channels * channel_bytes;
    let start = channel * channel_bytes;
    for instant in bytes.chunks_exact(stride) {
        out.extend_from_slice(&instant[start..start + channel_bytes]);
    }
}

/// Interleaves per-channel byte streams (byte-aligned, `channel_bytes` per instant) instant by
/// instant: the inverse of [`deinterleave`].
pub fn interleave(streams: &[Vec<u8>], channel_bytes: usize) -> Vec<u8> {
    let n = streams.first().map_or(0, |s| s.len() / channel_bytes);
    let mut out = Vec::with_capacity(n * channel_bytes * streams.len());
    for k in 0..n {
        for s in streams {
            out.extend_from_slice(&s[k * channel_bytes..(k + 1) * channel_bytes]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_and_print_back() {
        for name in [
            "cs8", "cs16", "cs16:6", "int8", "sm2", "sm2iq", "bit1", "bit1iq", "mc2x3", "mc2x4",
            "cs8x3", "cs16x2:5", "int8x3",
        ] {
            let f = FileFormat::parse(name).unwrap();
            assert_eq!(f.name(), name);
        }
        assert_eq!(FileFormat::parse("CS8").unwrap().sample, SampleFormat::Cs8);
        for bad in [
            "cs7", "", "mc2", "mc2x5", "cs8x0", "sm2x2", "cs8:3", "cs16:9", "cs16:x", "x3",
        ] {
            assert!(FileFormat::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn lengths_must_hold_whole_instants() {
        let cs8 = FileFormat::parse("cs8").unwrap();
        assert_eq!(cs8.instants_in(10).unwrap(), 5);
        assert!(cs8.instants_in(11).is_err());
        assert!(FileFormat::parse("cs16").unwrap().instants_in(6).is_err());
        assert!(FileFormat::parse("cs8x3").unwrap().instants_in(8).is_err());
        assert_eq!(
            FileFormat::parse("sm2").unwrap().instants_in(3).unwrap(),
            12
        );
        assert_eq!(
            FileFormat::parse("bit1").unwrap().instants_in(3).unwrap(),
            24
        );
        assert_eq!(
            FileFormat::parse("bit1iq").unwrap().instants_in(3).unwrap(),
            12
        );
        assert_eq!(
            FileFormat::parse("mc2x3").unwrap().instants_in(7).unwrap(),
            7
        );
    }

    #[test]
    fn interleave_and_deinterleave_are_inverse() {
        let streams = vec![vec![1u8, 2, 3, 4], vec![5, 6, 7, 8], vec![9, 10, 11, 12]];
        let x = interleave(&streams, 2);
        assert_eq!(x, [1, 2, 5, 6, 9, 10, 3, 4, 7, 8, 11, 12]);
        let mut out = Vec::new();
        for (c, s) in streams.iter().enumerate() {
            deinterleave(&x, 3, 2, c, &mut out);
            assert_eq!(&out, s);
        }
    }
}
