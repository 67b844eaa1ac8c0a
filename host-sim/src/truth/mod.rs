//! Truth models, in f64.
//!
//! The truth is always computed in f64 and with its own code paths, so that what the f32
//! estimators of the core are compared against is not limited by f32 or shares their
//! approximations.
//!
//! * [`kinematics`]: attitude kinematics of a rigid body.
//! * [`orbit`]: LEO orbit (Kepler + secular J2), ECI/ECEF, the local orbital frame.
//! * [`attitude`]: attitude histories (nadir pointing with tumble, detumbling body).
//! * [`gyro`]: paper 001's gyro error model and §6 experiment; a MEMS gyro triad with
//!   quantized output on any attitude history.
//! * [`tumble`]: a torque-free tumbling body with a MEMS gyro and a noisy attitude reference
//!   (paper 001's `gnss-ref` variant).
//! * [`gps`]: the GPS constellation from a YUMA almanac; elevation, azimuth, line of sight.
//! * [`tle`]: an orbit from a two-line element set (SGP4, TEME → ECEF → the simulation frame).

pub mod attitude;
pub mod gps;
pub mod gyro;
pub mod kinematics;
pub mod orbit;
pub mod sky;
pub mod tle;
pub mod tumble;
