//! A deterministic bit-parallel correlation that firmware runs on the target and compares bit
//! for bit with the host (integer only, so the outputs must be equal), and that the budgets
//! measure: PRN 5, 2.6 Msps, one code period, three antennas, prompt-only slaves.

use super::block::BitBlock;
use super::carrier::CarrierLevels;
use super::code::CodeTable;
use super::correlator::{BitCorrelator, BitCorrelatorConfig, BitCorrelatorError};
use super::planes::{AntennaPlanes, PlaneBuffer, PlaneError, PlaneFormat};
use crate::signal::correlator::{CorrelatorConfig, EpochCorrelations, SlaveTaps};
use crate::signal::Prn;

/// Sample rate of the self-test, Hz.
pub const BIT_SELF_TEST_RATE_HZ: f64 = 2.6e6;

/// Magnitude threshold used to pack the `i8` self-test samples (`−32..=31`, near their
/// standard deviation) into 2-bit planes.
pub const BIT_SELF_TEST_THRESHOLD: u8 = 18;

/// Plane words of the self-test buffers (2 624 samples: one code period and margin).
pub const BIT_SELF_TEST_WORDS: usize = 82;

/// Carrier frequency of the self-test's complex case (Doppler), Hz.
pub const BIT_SELF_TEST_DOPPLER_HZ: f64 = 2345.0;

/// Intermediate frequency of the self-test's real case, Hz (a quarter of the sample rate less
/// 1 kHz, as host-sim's real front ends).
pub const BIT_SELF_TEST_IF_HZ: f64 = 649_000.0;

/// Error returned by [`run_bit_correlator_self_test`] and [`pack_self_test`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum BitSelfTestError {
    /// Packing or the block refused the inputs.
    #[error("planes refused")]
    Planes(#[from] PlaneError),
    /// The correlator refused its configuration or the block.
    #[error("correlator refused")]
    Correlator(#[from] BitCorrelatorError),
}

impl crate::error::Error for BitSelfTestError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::Planes(e) => crate::error::Error::kind(e),
            Self::Correlator(e) => crate::error::Error::kind(e),
        }
    }
}

/// The self-test's planes of one antenna: `i` (and `q` for complex formats) packed with
/// [`BIT_SELF_TEST_THRESHOLD`].
///
/// # Errors
/// [`BitSelfTestError::Planes`] from [`PlaneBuffer::pack_i8`].
pub fn pack_self_test(
    format: PlaneFormat,
    i: &[i8],
    q: &[i8],
) -> Result<PlaneBuffer<BIT_SELF_TEST_WORDS>, BitSelfTestError> {
    let mut buf = PlaneBuffer::new(format);
    buf.pack_i8(i, q, BIT_SELF_TEST_THRESHOLD)?;
    Ok(buf)
}

/// The self-test's correlator configuration for planes of `format`.
pub fn self_test_config(format: PlaneFormat, carrier: CarrierLevels) -> BitCorrelatorConfig {
    BitCorrelatorConfig {
        correlator: CorrelatorConfig {
            sample_rate_hz: BIT_SELF_TEST_RATE_HZ,
            intermediate_frequency_hz: 0.0,
            early_late_offset_chips: 0.5,
            slave_taps: SlaveTaps::Prompt,
        },
        format,
        carrier,
    }
}

/// A correlator of the self-test, NCOs set: PRN 5, code phase 0, carrier at
/// [`BIT_SELF_TEST_DOPPLER_HZ`] (complex) or [`BIT_SELF_TEST_IF_HZ`] plus it (real).
///
/// # Errors
/// [`BitSelfTestError::Correlator`] (not for the self-test's own configuration).
pub fn self_test_correlator(
    format: PlaneFormat,
    carrier: CarrierLevels,
) -> Result<BitCorrelator<3>, BitSelfTestError> {
    let prn = Prn::new(5).ok_or(BitCorrelatorError::InvalidConfig)?;
    let mut c = BitCorrelator::<3>::new(prn, &self_test_config(format, carrier))?;
    let f = if format.complex {
        BIT_SELF_TEST_DOPPLER_HZ
    } else {
        BIT_SELF_TEST_IF_HZ + BIT_SELF_TEST_DOPPLER_HZ
    };
    c.set_carrier_frequency(f)?;
    c.set_code_phase(0.0)?;
    Ok(c)
}

/// One code period of the self-test over the given planes.
///
/// # Errors
/// [`BitSelfTestError`] from the block or the correlator.
pub fn run_bit_correlator_self_test(
    table: &CodeTable,
    planes: [AntennaPlanes<'_>; 3],
    carrier: CarrierLevels,
) -> Result<Option<EpochCorrelations<3>>, BitSelfTestError> {
    let format = planes[0].format();
    let block = BitBlock::new(0, table, planes)?;
    let mut c = self_test_correlator(format, carrier)?;
    let mut cursor = 0;
    Ok(c.run(&block, &mut cursor)?)
}
