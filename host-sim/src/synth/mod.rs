//! The coherent three-antenna GPS L1 C/A sample synthesizer.
//!
//! * [`scene`]: the signal model (satellites with code delay, Doppler and Doppler rate, data
//!   bits; per-antenna carrier phase from the baseline geometry and the true attitude; line
//!   biases; thermal noise at a given C/N0) and the parallel sample generator.
//! * [`quantize`]: front-end quantization into the core's sample formats, and decoding back
//!   with the core's decoder.
//! * [`file`](mod@file): CS8/CS16 (and the other formats') files, written and read back.
//! * [`codes`]: the synthesizer's own C/A code generator.
//! * [`lnav`]: the LNAV navigation message (ephemerides from the almanac's orbits, subframes
//!   1–5 with parity, the data bit of any satellite at any time).

pub mod codes;
pub mod file;
pub mod lnav;
pub mod quantize;
pub mod scene;

pub use scene::{
    AnalogSamples, AttitudeMotion, CarrierStep, FrontEnd, Satellite, SatelliteTrack, Scene,
    SignalTruth,
};
