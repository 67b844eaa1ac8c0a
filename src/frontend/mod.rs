//! Drivers that configure the multi-channel RF front end over SPI (embedded-hal 1.0).
//!
//! * [`nt1065`]: `NTLab` NT1065, four phase-coherent channels from one synthesizer.

pub mod nt1065;

pub use nt1065::{FrontEndError, Nt1065, Nt1065Config};
