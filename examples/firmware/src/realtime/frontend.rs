//! The front ends the real-time firmware feeds the receiver: 1-bit and 2-bit sign/magnitude
//! complex samples, as the NT1065 / MAX2769 class of RF front ends deliver them.
//!
//! The front end delivers bytes in the core's `SampleFormat::SignMagnitude2 { complex: true }`
//! layout (`sm2iq`: one byte per two complex samples, fields `I0 Q0 I1 Q1` from the most
//! significant bits, each field `sign·2 + magnitude`); the 1-bit front end delivers the same
//! layout with every magnitude bit 0 (its ADC has no magnitude output). The firmware packs
//! those bytes into the antennas' bit planes with the core's packing
//! (`PlaneBuffer::pack_bytes`), as it would from a DMA buffer; the acquisition searches the
//! reference antenna's planes of its first milliseconds, collected with
//! `PlaneBuffer::append`.

use gnss_attitude::signal::bitwise::{PlaneFormat, Resolution};
use gnss_attitude::signal::SampleFormat;

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
/// The byte layout the front ends deliver (`sm2iq`).
pub const SM2IQ: SampleFormat = SampleFormat::SignMagnitude2 { complex: true };

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

    /// The 2-bit `sm2iq` field the ADC outputs for the analog component `x` (noise σ = 1):
    /// sign (1 = negative) in bit 1, magnitude (1 = large; always 0 for 1-bit) in bit 0.
    #[inline(always)]
    pub fn field(self, x: f32) -> u8 {
        let sign = u8::from(x < 0.0) << 1;
        match self {
            FrontEnd::OneBit => sign,
            FrontEnd::TwoBit => sign | u8::from(x.abs() > TWO_BIT_THRESHOLD),
        }
    }
}
