//! Attitude estimators.
//!
//! * [`range_model`]: paper 002's model `R = Bᵀ A S` (range differences between antennas), the
//!   validated input types and the body baselines.
//! * [`eigen`]: a bounded cyclic Jacobi eigen-decomposition of small symmetric matrices.
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
//! Frames: `C_rb` is the attitude (body to reference); paper 002's `A` is `C_br = C_rbᵀ`.
//! Lines of sight `s_j` are unit vectors from the antennas to satellite `j` in the reference
//! frame; baselines `b_i` are from the base antenna (antenna 0) to antenna `i` in body axes,
//! metres. A range difference is `Δr_ij = ρ_0j − ρ_ij = b_iᵀ A s_j`.

pub mod ambiguity;
pub mod eigen;
pub mod example;
mod integer_search;
pub mod lambda;
pub mod paper002;
pub mod range_model;
pub mod snapshot;
pub mod wahba;
