//! The fixed-point GPS L1 C/A signal chain's front half: codes, sample formats, NCOs and the
//! three-antenna correlator.
//!
//! Data path: raw bytes from the front end → [`samples::SampleFormat::decode`] (planar `i8`
//! per antenna, once per block, shared by every satellite) → [`SampleBlock`] → one
//! [`Correlator`] per satellite, which applies one replica to all antennas and outputs
//! [`EpochCorrelations`] every code period (1 ms). The tracking loops
//! ([`crate::tracking`]) steer its NCOs.
//!
//! Integer arithmetic only in the sample loop; see [`correlator`] for the overflow analysis
//! and the fixed-point error bound.
//!
//! For 1- and 2-bit front ends, [`bitwise`] correlates the samples as bit planes (32 per word,
//! XOR and population counts) with the same interface and output ([`bitwise::BitCorrelator`]).
//! Both implement [`Correlate`] ([`correlate`]): tracking and the receiver are generic over it,
//! with the `i8` correlator as the default.

pub mod bitwise;
pub mod block;
pub mod ca_code;
pub mod correlate;
pub mod correlator;
mod kernels;
pub mod nco;
pub mod samples;
pub mod selftest;

pub use block::SampleBlock;
pub use ca_code::{Prn, CA_CHIP_RATE_HZ, CA_CODE_LENGTH, GPS_L1_HZ};
pub use correlate::{BitSettings, Correlate, CorrelationBlock};
pub use correlator::{
    Correlator, CorrelatorConfig, EpochCorrelations, Iq, SignalError, SlaveTaps, Taps,
};
pub use samples::{SampleError, SampleFormat};
