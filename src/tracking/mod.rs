//! Acquisition and tracking of GPS L1 C/A signals on the reference antenna, with the other
//! antennas' correlators slaved to the reference NCOs.
//!
//! * [`acquisition`]: FFT code-phase × Doppler search with a false-alarm threshold.
//! * [`loops`]: Costas / FLL / DLL discriminators and the FLL-assisted PLL filter.
//! * [`cn0`]: C/N0 and phase-lock indicator from the prompt and noise taps.
//! * [`lock`]: lock detectors with hysteresis, bit synchronization.
//! * [`channel`]: the per-satellite channel (hand-over → pull-in → tracking), one
//!   [`TrackingEpoch`] per code period.
//! * [`fft`]: the fixed-size f32 FFT acquisition uses.

pub mod acquisition;
pub mod channel;
pub mod cn0;
mod config;
pub mod fft;
pub mod lock;
pub mod loops;
mod refine;

pub use acquisition::{Acquisition, AcquisitionConfig, AcquisitionError, SearchResult};
pub use channel::{Channel, ChannelConfig, ChannelState, LockFlags, TrackingEpoch, TrackingError};
