//! Truth models, in f64.
//!
//! The truth is always computed in f64 and with its own code paths, so that what the f32
//! estimators of the core are compared against is not limited by f32 or shares their
//! approximations.

pub mod gyro;
pub mod kinematics;
pub mod tumble;
