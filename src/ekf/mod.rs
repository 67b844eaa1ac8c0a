//! The fixed-size Kalman filter toolkit the estimators share.
//!
//! [`Ekf`] holds a Gaussian estimate `(x, P)` of compile-time dimension `N` and implements the
//! steps every filter of the crate needs — prediction, Joseph-form vector update, scalar and
//! sequential updates, NIS gating, symmetry and variance-floor hygiene — with typed errors and
//! transactional semantics (a failed step changes nothing). The models stay with the filters
//! that use the toolkit: they compute predicted states, innovations and Jacobians and pass them
//! in.
//!
//! ```
//! use gnss_attitude::ekf::{Ekf, GateConfidence, NisGate};
//! use nalgebra::{Matrix1, Matrix1x2, Matrix2, Vector1, Vector2};
//!
//! // Constant velocity along a line: x = (position m, velocity m/s), 0.1 s steps.
//! let mut kf = Ekf::<2>::new(Vector2::zeros(), Matrix2::identity() * 10.0)?;
//! let f = Matrix2::new(1.0, 0.1, 0.0, 1.0);
//! let q = Matrix2::new(1e-4, 0.0, 0.0, 1e-3);
//! let h = Matrix1x2::new(1.0, 0.0); // position is measured
//! let r = Matrix1::new(0.25); // (0.5 m)²
//! let gate = Some(NisGate::chi_square(1, GateConfidence::P999));
//! for k in 0..50 {
//!     kf.predict(&f, &q)?;
//!     let z = 0.1 * k as f32 * 2.0; // moving at 2 m/s
//!     let y = Vector1::new(z - (h * kf.state()).x);
//!     kf.update(&y, &h, &r, gate)?;
//! }
//! assert!((kf.state().y - 2.0).abs() < 0.3);
//! # Ok::<(), gnss_attitude::ekf::FilterError>(())
//! ```

mod filter;
mod gate;

pub use filter::{Ekf, FilterError, ScalarUpdateReport, SequentialUpdateReport, UpdateReport};
pub use gate::{chi_square_quantile, GateConfidence, NisGate};
