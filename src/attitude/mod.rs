//! Attitude estimators: from measurements of the three antennas to `C_rb` with a covariance.
//!
//! Paper 000 (baselines and Doppler velocity differences in ECEF):
//! [`direction_cosine`] is the corrected six-state model, [`dcm_filter`] its continuous EKF,
//! [`multi_structure`] three of them on the three baseline pairs with a robust combination,
//! and [`rigid_body`] the three-parameter error-state filter on the same data that the paper
//! does not have. [`baseline_epoch`] holds their inputs and [`filter_estimate`] their output.
pub mod baseline_epoch;
pub mod dcm_filter;
pub mod direction_cosine;
pub mod filter_estimate;
mod givens;
pub mod multi_structure;
pub mod rigid_body;
