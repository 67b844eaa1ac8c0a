//! Acquisition and tracking of GPS L1 C/A signals on the reference antenna, with the other
//! antennas' correlators slaved to the reference NCOs.
//!
//! * [`acquisition`]: FFT code-phase × Doppler search with a false-alarm threshold.
//! * [`fft`]: the fixed-size f32 FFT acquisition uses.

pub mod acquisition;
pub mod fft;

pub use acquisition::{Acquisition, AcquisitionConfig, SearchResult};
