//! The front ends the real-time firmware feeds the receiver: 1-bit and 2-bit sign/magnitude
//! complex samples, as the NT1065 / MAX2769 class of RF front ends deliver them.
//!
//! The 2-bit front end delivers bytes in the core's `SampleFormat::SignMagnitude2 { complex:
//! true }` layout (`sm2iq`: one byte per two complex samples, fields `I0 Q0 I1 Q1` from the
//! most significant bits, each field `sign·2 + magnitude`); the 1-bit front end in
//! `SampleFormat::Sign1Iq` (`bit1iq`: one byte per four complex samples, sign bits `I0 Q0 I1
//! Q1 I2 Q2 I3 Q3` from the most significant bit). The firmware packs those bytes into the
//! antennas' bit planes with the core's packing (`PlaneBuffer::pack_bytes`), as it would from
//! a DMA buffer; the acquisition searches the
//! reference antenna's planes of its first milliseconds, collected with
//! `PlaneBuffer::append`.

use gnss_attitude::signal::bitwise::{PlaneFormat, Resolution};
use gnss_attitude::signal::SampleFormat;

use super::run::BLOCK;

/// A front end: how many bits per component the ADC delivers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrontEnd {
    /// 1-bit complex samples (the sign of I and of Q).
    OneBit,
    /// 2-bit sign/magnitude complex samples, magnitude threshold [`TWO_BIT_THRESHOLD`] σ.
    TwoBit,
}

/// 2-bit magnitude threshold, in noise σ (host-sim's `TWO_BIT_THRESHOLD`).
pub const TWO_BIT_THRESHOLD: f32 = 1.0;

impl FrontEnd {
    /// Both front ends, in the order the firmware runs them.
    pub const ALL: [FrontEnd; 2] = [FrontEnd::OneBit, FrontEnd::TwoBit];

    /// Name in the firmware's output (`1-bit`, `2-bit`).
    pub fn name(self) -> &'static str {
        match self {
            FrontEnd::OneBit => "1-bit",
            FrontEnd::TwoBit => "2-bit",
        }
    }

    /// The bit planes the receiver's correlators read for this front end: 1- or 2-bit,
    /// complex.
    pub fn plane_format(self) -> PlaneFormat {
        let resolution = match self {
            FrontEnd::OneBit => Resolution::OneBit,
            FrontEnd::TwoBit => Resolution::TwoBit,
        };
        PlaneFormat { resolution, complex: true }
    }

    /// The byte layout this front end delivers: `bit1iq` or `sm2iq`.
    pub const fn sample_format(self) -> SampleFormat {
        match self {
            FrontEnd::OneBit => SampleFormat::Sign1Iq,
            FrontEnd::TwoBit => SampleFormat::SignMagnitude2 { complex: true },
        }
    }

    /// Complex samples per byte of [`sample_format`](Self::sample_format): 4 or 2.
    pub const fn samples_per_byte(self) -> usize {
        self.sample_format().samples_in(1)
    }

    /// Bytes of one block ([`BLOCK`] samples) of one antenna.
    pub const fn block_bytes(self) -> usize {
        BLOCK / self.samples_per_byte()
    }

    /// The byte the ADC outputs for the complex samples `(i[k], q[k])` (analog, noise σ = 1;
    /// [`samples_per_byte`](Self::samples_per_byte) of them), first sample in the most
    /// significant bits.
    #[inline(always)]
    pub fn byte(self, i: &[f32], q: &[f32]) -> u8 {
        let bits = 8 / (2 * self.samples_per_byte()) as u32;
        let mut byte = 0u8;
        for (&x, &y) in i.iter().zip(q) {
            byte = (byte << (2 * bits)) | (self.field(x) << bits) | self.field(y);
        }
        byte
    }

    /// The field the ADC outputs for the analog component `x` (noise σ = 1): the sign
    /// (1 = negative), and for 2 bits the magnitude (1 = large) below it.
    #[inline(always)]
    fn field(self, x: f32) -> u8 {
        let sign = u8::from(x < 0.0);
        match self {
            FrontEnd::OneBit => sign,
            FrontEnd::TwoBit => (sign << 1) | u8::from(x.abs() > TWO_BIT_THRESHOLD),
        }
    }
}
