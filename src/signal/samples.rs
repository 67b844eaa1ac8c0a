//! Sample formats of real front ends, decoded into small signed integers without allocation.
//!
//! Every format decodes to `i8` values (planar: one slice for I, one for Q), the type the
//! correlators take. The byte layouts:
//!
//! | Format | Kind | Layout |
//! |---|---|---|
//! | [`SampleFormat::Cs8`] | complex | interleaved `I0 Q0 I1 Q1 …`, each a signed byte (`HackRF`, rtl-sdr after offset removal, GNSS-SDR `ibyte`, Pocket SDR `INT8X2`) |
//! | [`SampleFormat::Cs16`] | complex | interleaved `I0 Q0 …`, each a little-endian signed 16-bit word (USRP `sc16`, GNSS-SDR `ishort`); decoded as `round(v / 2^shift)` saturated to `−128..=127` (the shift is the receiver's gain setting) |
//! | [`SampleFormat::Int8`] | real | one signed byte per sample (real IF) |
//! | [`SampleFormat::SignMagnitude2`] | real or complex | four 2-bit fields per byte, **first sample in the two most significant bits**; in each field the high bit is the sign (1 = negative) and the low bit the magnitude (1 = large): `00 → +1, 01 → +3, 10 → −1, 11 → −3` (MAX2769 / NT1065 two-bit ADC outputs `SIGN`, `MAG`). Complex: fields alternate I, Q |
//! | [`SampleFormat::Sign1`] | real | eight 1-bit samples per byte, first sample in the most significant bit; `0 → +1, 1 → −1` |
//! | [`SampleFormat::Sign1Iq`] | complex | four 1-bit I/Q pairs per byte, `I0 Q0 I1 Q1 I2 Q2 I3 Q3` from the most significant bit; `0 → +1, 1 → −1` (the `SIGN` outputs of a 1-bit I/Q front end, captured two bits a clock) |
//! | [`SampleFormat::MultiChannel2`] | real, up to 4 channels | one byte per sample instant; channel `c` (0–3) in bits `2c+1` (sign) and `2c` (magnitude), same field coding as above (the four-channel 2-bit parallel output of NT1065-class front ends, captured a byte per clock) |
//!
//! The field coding of the 2-bit formats is this crate's convention; a board that packs the
//! bits otherwise needs a byte-wise remapping table before decoding (a 256-entry lookup).

use crate::error::{Error, ErrorKind};

/// The format of raw sample bytes. See the module documentation for the layouts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SampleFormat {
    /// Interleaved signed 8-bit I/Q.
    Cs8,
    /// Interleaved little-endian signed 16-bit I/Q, reduced to 8 bits by `round(v / 2^shift)`
    /// with saturation; `shift` is 0–8.
    Cs16 {
        /// Right shift applied before saturation to `i8`, 0–8.
        shift: u8,
    },
    /// Real signed 8-bit samples.
    Int8,
    /// Packed 2-bit sign/magnitude, four fields per byte, most significant field first.
    SignMagnitude2 {
        /// `true`: fields alternate I, Q (complex); `false`: real samples.
        complex: bool,
    },
    /// Packed 1-bit sign, eight per byte, most significant bit first.
    Sign1,
    /// Packed 1-bit complex sign, four I/Q pairs per byte (`I0 Q0 I1 Q1 …`), most
    /// significant bit first.
    Sign1Iq,
    /// One byte per sample instant holding 2-bit sign/magnitude fields of up to four channels.
    MultiChannel2 {
        /// Channels present in each byte, 1–4.
        channels: u8,
    },
}

impl SampleFormat {
    /// Whether the format carries complex (I/Q) samples.
    pub const fn is_complex(self) -> bool {
        match self {
            Self::Cs8 | Self::Cs16 { .. } | Self::Sign1Iq => true,
            Self::SignMagnitude2 { complex } => complex,
            Self::Int8 | Self::Sign1 | Self::MultiChannel2 { .. } => false,
        }
    }

    /// Number of channels (antennas) interleaved in the stream.
    pub const fn channels(self) -> usize {
        match self {
            Self::MultiChannel2 { channels } => channels as usize,
            _ => 1,
        }
    }

    /// The largest magnitude a decoded value can have (128 for the 8-bit formats, whose range
    /// is `−128..=127`; 3 and 1 for the 2- and 1-bit formats). The correlator's overflow
    /// analysis uses it.
    pub const fn max_abs(self) -> i32 {
        match self {
            Self::Cs8 | Self::Cs16 { .. } | Self::Int8 => 128,
            Self::SignMagnitude2 { .. } | Self::MultiChannel2 { .. } => 3,
            Self::Sign1 | Self::Sign1Iq => 1,
        }
    }

    /// Checks the format's parameters.
    pub fn validate(self) -> Result<Self, SampleError> {
        match self {
            Self::Cs16 { shift } if shift > 8 => Err(SampleError::InvalidFormat),
            Self::MultiChannel2 { channels } if channels == 0 || channels > 4 => {
                Err(SampleError::InvalidFormat)
            }
            other => Ok(other),
        }
    }

    /// Bytes holding `samples` sample instants (complex or real, all channels); `None` when
    /// the count does not fill whole bytes (a packed format needs multiples of 4 or 8 fields).
    pub const fn bytes_for(self, samples: usize) -> Option<usize> {
        match self {
            Self::Cs8 => samples.checked_mul(2),
            Self::Cs16 { .. } => samples.checked_mul(4),
            Self::Int8 | Self::MultiChannel2 { .. } => Some(samples),
            Self::SignMagnitude2 { complex } => {
                let fields = if complex { samples * 2 } else { samples };
                if fields % 4 == 0 {
                    Some(fields / 4)
                } else {
                    None
                }
            }
            Self::Sign1 => {
                if samples % 8 == 0 {
                    Some(samples / 8)
                } else {
                    None
                }
            }
            Self::Sign1Iq => {
                if samples % 4 == 0 {
                    Some(samples / 4)
                } else {
                    None
                }
            }
        }
    }

    /// Sample instants held by `bytes` bytes (whole instants only).
    pub const fn samples_in(self, bytes: usize) -> usize {
        match self {
            Self::Cs8 => bytes / 2,
            Self::Cs16 { .. } => bytes / 4,
            Self::Int8 | Self::MultiChannel2 { .. } => bytes,
            Self::SignMagnitude2 { complex } => {
                if complex {
                    bytes * 2
                } else {
                    bytes * 4
                }
            }
            Self::Sign1 => bytes * 8,
            Self::Sign1Iq => bytes * 4,
        }
    }

    /// Decodes channel `channel` of `bytes` into `i` (and `q` for complex formats; `q` is not
    /// touched for real ones and may be empty). Decodes `min(samples in bytes, i.len())` sample
    /// instants (and no more than `q.len()` for complex formats) and returns that count.
    ///
    /// # Errors
    /// [`SampleError::InvalidFormat`] for bad format parameters, [`SampleError::NoSuchChannel`]
    /// for a channel the format does not carry, [`SampleError::PartialSample`] when `bytes`
    /// ends inside a sample instant (a CS8 stream of odd length, a CS16 stream not a multiple
    /// of 4 bytes).
    pub fn decode(
        self,
        bytes: &[u8],
        channel: usize,
        i: &mut [i8],
        q: &mut [i8],
    ) -> Result<usize, SampleError> {
        let format = self.validate()?;
        if channel >= format.channels() {
            return Err(SampleError::NoSuchChannel);
        }
        let whole = match format {
            Self::Cs8 => bytes.len() % 2 == 0,
            Self::Cs16 { .. } => bytes.len() % 4 == 0,
            _ => true,
        };
        if !whole {
            return Err(SampleError::PartialSample);
        }
        let mut n = format.samples_in(bytes.len()).min(i.len());
        if format.is_complex() {
            n = n.min(q.len());
        }
        let (i, q) = (&mut i[..n], q);
        match format {
            Self::Cs8 => {
                for ((pair, vi), vq) in bytes.chunks_exact(2).zip(i.iter_mut()).zip(q.iter_mut()) {
                    *vi = pair[0] as i8;
                    *vq = pair[1] as i8;
                }
            }
            Self::Cs16 { shift } => {
                for ((quad, vi), vq) in bytes.chunks_exact(4).zip(i.iter_mut()).zip(q.iter_mut()) {
                    *vi = reduce16(i16::from_le_bytes([quad[0], quad[1]]), shift);
                    *vq = reduce16(i16::from_le_bytes([quad[2], quad[3]]), shift);
                }
            }
            Self::Int8 => {
                for (b, v) in bytes.iter().zip(i.iter_mut()) {
                    *v = *b as i8;
                }
            }
            Self::SignMagnitude2 { complex: false } => {
                // (indices from a range, not `enumerate`: its counter keeps an overflow check)
                for (k, v) in (0..i.len()).zip(i.iter_mut()) {
                    let byte = bytes.get(k >> 2).copied().unwrap_or(0);
                    *v = sign_magnitude(byte >> (6 - 2 * (k & 3)));
                }
            }
            Self::SignMagnitude2 { complex: true } => {
                for (k, (vi, vq)) in (0..i.len()).zip(i.iter_mut().zip(q.iter_mut())) {
                    // Sample k's I field is field 2k, its Q field 2k + 1; two samples a byte.
                    let byte = bytes.get(k >> 1).copied().unwrap_or(0);
                    let shift = if k & 1 == 0 { 4 } else { 0 };
                    *vi = sign_magnitude(byte >> (shift + 2));
                    *vq = sign_magnitude(byte >> shift);
                }
            }
            Self::Sign1 => {
                for (k, v) in (0..i.len()).zip(i.iter_mut()) {
                    let byte = bytes.get(k >> 3).copied().unwrap_or(0);
                    *v = 1 - 2 * ((byte >> (7 - (k & 7))) & 1) as i8;
                }
            }
            Self::Sign1Iq => {
                for (k, (vi, vq)) in (0..i.len()).zip(i.iter_mut().zip(q.iter_mut())) {
                    // Sample k's I bit is bit 2k of the stream, its Q bit 2k + 1.
                    let byte = bytes.get(k >> 2).copied().unwrap_or(0);
                    let shift = 6 - 2 * (k & 3);
                    *vi = 1 - 2 * ((byte >> (shift + 1)) & 1) as i8;
                    *vq = 1 - 2 * ((byte >> shift) & 1) as i8;
                }
            }
            Self::MultiChannel2 { .. } => {
                let shift = 2 * (channel as u32 & 3);
                for (b, v) in bytes.iter().zip(i.iter_mut()) {
                    *v = sign_magnitude(b >> shift);
                }
            }
        }
        Ok(n)
    }
}

/// The value of a 2-bit sign/magnitude field held in the two low bits of `field`.
#[inline(always)]
pub const fn sign_magnitude(field: u8) -> i8 {
    let magnitude = 1 + 2 * (field & 1) as i8;
    if field & 2 != 0 {
        -magnitude
    } else {
        magnitude
    }
}

/// `round(v / 2^shift)` saturated to `i8` (`shift` ≤ 8; ties round up).
#[inline(always)]
fn reduce16(v: i16, shift: u8) -> i8 {
    let v = i32::from(v);
    let shift = shift.min(8); // (as documented; the bound made visible)
    let r = if shift == 0 {
        v
    } else {
        (v + (1 << (shift - 1))) >> shift
    };
    r.clamp(-128, 127) as i8
}

/// Errors of sample decoding ([`crate::signal::samples`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SampleError {
    /// The format's parameters are out of range (a CS16 shift above 8, a multi-channel format
    /// with 0 or more than 4 channels).
    #[error("sample format parameters out of range")]
    InvalidFormat,
    /// The requested channel is not in the stream (channel ≥ the format's channel count).
    #[error("channel not present in the sample stream")]
    NoSuchChannel,
    /// The byte slice ends inside a sample (odd CS8 length, CS16 length not a multiple of 4).
    #[error("byte stream ends inside a sample")]
    PartialSample,
}

impl Error for SampleError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::InvalidInput
    }
}
