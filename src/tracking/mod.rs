//! Acquisition and tracking of GPS L1 C/A signals on the reference antenna, with the other
//! antennas' correlators slaved to the reference NCOs.
//!
//! * [`acquisition`]: FFT code-phase × Doppler search, a detection threshold from the
//!   search's own background, a verification dwell and the cross-correlation test.
//! * [`loops`]: Costas / FLL / DLL discriminators and the FLL-assisted PLL filter.
//! * [`cn0`]: C/N0 and phase-lock indicator from the prompt and noise taps.
//! * [`lock`]: lock detectors with hysteresis, bit synchronization.
//! * [`channel`]: the per-satellite channel (hand-over → pull-in → tracking), one
//!   [`TrackingEpoch`] per code period, on either correlator
//!   ([`Correlate`](crate::signal::Correlate): `i8` samples or 1- and 2-bit planes).
//! * [`fft`]: the fixed-size f32 FFT acquisition uses.
//! * [`xcorr`]: the C/A codes' cross-correlation and the test of whether a detection or a
//!   channel is another satellite's cross-correlation.

pub mod acquisition;
pub mod channel;
pub mod cn0;
mod config;
pub mod fft;
pub mod lock;
pub mod loops;
mod refine;
pub mod xcorr;

pub use acquisition::{
    Acquisition, AcquisitionConfig, AcquisitionError, CancellationCheck, CrossCheck, KnownSignal,
    SearchReport, SearchResult, SearchSamples, Verification,
};
pub use channel::{Channel, ChannelConfig, ChannelState, LockFlags, TrackingEpoch, TrackingError};
