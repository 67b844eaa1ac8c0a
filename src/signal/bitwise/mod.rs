//! Bit-parallel correlation of 1- and 2-bit samples (docs below are expanded later).

pub mod block;
pub mod carrier;
pub mod code;
pub mod correlator;
mod kernel;
pub mod planes;
pub mod reference;
pub mod selftest;

pub use block::BitBlock;
pub use carrier::CarrierLevels;
pub use code::CodeTable;
pub use correlator::{BitCorrelator, BitCorrelatorConfig, BitCorrelatorError};
pub use planes::{AntennaPlanes, PlaneBuffer, PlaneError, PlaneFormat, Resolution};
pub use reference::ScalarReference;
