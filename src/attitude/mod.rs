//! Attitude estimators: from the three antennas' signals to the attitude `C_rb`.
//!
//! Each estimator is one submodule; they share the conventions of [`crate::geometry`] (the
//! attitude is `C_rb`, body to reference) and the filter toolkit [`crate::ekf`].
//!
//! | Module | Paper | What it estimates, from what |
//! |---|---|---|
//! | [`one_stage`] | 003 (Perov) | Attitude angles and rates straight from per-antenna prompt I/Q, common carrier phase and data bit averaged out |

pub mod one_stage;
