//! The front ends the real-time firmware feeds the receiver: 1-bit and 2-bit sign/magnitude
//! complex samples, as the NT1065 / MAX2769 class of RF front ends deliver them.
//!
//! Today the receiver's correlator takes `i8` samples, so each quantized level is handed over
//! as the `i8` value host-sim uses for the same front end (`host-sim/src/synth/quantize.rs`):
//! 1-bit `±16`, 2-bit `±8, ±24` (threshold 1σ).
//!
//! Swapping in the bit-parallel correlator (branch `h-bitrx`, `SampleReceiver` generic over the
//! correlator): `run::Front` names the receiver type; `run::stream` builds each 1 ms block from
//! the buffer the synthesizer fills. For the bit path, the synthesizer's output goes through
//! the core's packing (the sign and magnitude bit planes of each antenna, from these same `i8`
//! levels or from the front end's byte layout) into the block type the bit correlator takes,
//! and `Front` gets its correlator parameter; the acquisition keeps the `i8` samples.

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
/// `i8` value of a 1-bit sample's unit level (host-sim's `BIT1_LSB_PER_LEVEL`).
pub const BIT1_LSB_PER_LEVEL: i8 = 16;
/// `i8` value of a 2-bit sample's unit level (host-sim's `SM2_LSB_PER_LEVEL`: `±1, ±3` become
/// `±8, ±24`).
pub const SM2_LSB_PER_LEVEL: i8 = 8;

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

    /// The sample value the (i8) correlator receives for the analog component `x` (noise σ = 1).
    #[inline(always)]
    pub fn quantize(self, x: f32) -> i8 {
        match self {
            FrontEnd::OneBit => {
                if x < 0.0 {
                    -BIT1_LSB_PER_LEVEL
                } else {
                    BIT1_LSB_PER_LEVEL
                }
            }
            FrontEnd::TwoBit => {
                let level = if x.abs() > TWO_BIT_THRESHOLD { 3 * SM2_LSB_PER_LEVEL } else { SM2_LSB_PER_LEVEL };
                if x < 0.0 {
                    -level
                } else {
                    level
                }
            }
        }
    }
}
