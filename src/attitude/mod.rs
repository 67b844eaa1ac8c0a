//! Attitude estimators: from measurements of the three antennas to `C_rb` with a covariance.
//!
//! The antenna array (three phase centres in body axes) is one type for every estimator:
//! [`array::AntennaArray`].
//!
//! Frames: `C_rb` is the attitude (body to reference); paper 002's `A` is `C_br = C_rbᵀ`;
//! paper 000's `M` is `C_rb` with ECEF as the reference. Lines of sight `s_j` are unit vectors
//! from the antennas to satellite `j` in the reference frame; baselines `b_i` are from the base
//! antenna (antenna 0) to antenna `i` in body axes, metres. A range difference is
//! `Δr_ij = ρ_0j − ρ_ij = b_iᵀ A s_j`.
//!
//! **Snapshot (paper 002)**, one epoch of carrier phase:
//! * [`range_model`]: paper 002's model `R = Bᵀ A S` (range differences between antennas), the
//!   validated input types and the body baselines.
//! * [`wahba`]: Wahba's problem by Davenport's q-method (never a reflection).
//! * [`paper002`]: the paper's own formula (16), `A = Qᵀ(QQᵀ)^{-1/2}`, kept as the reference
//!   for four non-coplanar antennas, with its reflection reported as an error.
//! * [`snapshot`]: [`snapshot::SnapshotSolver`], the single-epoch maximum-likelihood attitude
//!   from range differences for two or more baselines (the three-antenna case included).
//! * [`lambda`]: LAMBDA decorrelation (integer Gauss transforms and permutations).
//! * [`ambiguity`]: [`ambiguity::AmbiguityResolver`], integer ambiguity resolution from raw
//!   single-difference carrier phase and code, constrained by the known baselines (the
//!   multivariate constrained idea of MC-LAMBDA), validated by a ratio test, refusing rather
//!   than returning a wrong fix.
//! * [`example`]: a deterministic example epoch (docs, benchmarks, firmware budgets).
//!
//! **Filters on baselines and Doppler velocity differences (paper 000)**, in ECEF:
//! * [`direction_cosine`]: the corrected six-state model.
//! * [`dcm_filter`]: its continuous EKF (eq. (10), RK4).
//! * [`multi_structure`]: three of them on the three baseline pairs with a robust combination.
//! * [`rigid_body`]: the three-parameter error-state filter on the same data, which the paper
//!   does not have.
//! * [`baseline_epoch`] holds their inputs and [`filter_estimate`] their output.
//!
//! **One-stage filter (paper 003)**, straight from per-antenna prompt I/Q:
//! * [`one_stage`]: attitude angles and rates with the common carrier phase and the data bit
//!   averaged out (product of I₀ Bessel functions); Gaussian-approximation and constant-gain
//!   forms, lock detector, optional line-bias states.

pub mod ambiguity;
pub mod array;
pub mod baseline_epoch;
pub mod dcm_filter;
pub mod direction_cosine;
pub mod example;
pub mod filter_estimate;
pub mod gyro_aided;
mod integer_search;
pub mod lambda;
pub mod multi_structure;
pub mod one_stage;
pub mod paper002;
pub mod range_model;
pub mod rigid_body;
pub mod snapshot;
pub mod wahba;
