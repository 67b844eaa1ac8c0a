//! In-flight gyro calibration by sequential least squares against a reference attitude
//! (paper 001, Tkachenko; corrected equations in the project's seed specification).
//!
//! A strapdown gyro's increments are integrated into a computed attitude `M`; a reference
//! (the paper's gyrostabilizer, here typically the GNSS attitude) gives the attitude `N` of a
//! body-fixed frame. Comparing the *changes* of both since `t₀`,
//! `P* = M(t) ∘ M̄(t₀)` and `P = N(t) ∘ N̄(t₀)`, gives three linear equations per epoch
//! (eq. (2.7)) in the initial attitude error `w₀`, the gyro errors `c` and the reference drift
//! `d`. They are accumulated without being stored and solved by least squares.
//!
//! # Frames (paper 001 §1–2)
//!
//! | Frame | Meaning |
//! |---|---|
//! | `I` | inertial; the reference frame at `t₀` |
//! | `E` | gyro triad (body); increments and `c` are in `E` |
//! | `J` | body-fixed frame whose attitude the reference measures (mounting unknown, cancels in `P`) |
//! | `L` | the reference's frame, drifting from `I` by `v(t) = ½ Ψ(t, t₀) d` |
//! | `K` | the frame implied by the computed quaternion `M`; `Λ ≈ (1 + w) ∘ M`, `w = w₀ − ½ Θ c` |
//!
//! `Λ` (true, `q_IE`), `M` (computed, `q_KE`) and `N` (`q_LJ`) are Hamilton quaternions, scalar
//! first, body to frame as everywhere in the crate; `Bᵀ` is the DCM of `M`; small quaternions
//! `1 + w` carry **half** rotation vectors.
//!
//! # Modules
//!
//! | Item | Paper |
//! |---|---|
//! | [`AttitudePropagator`], [`PulseDecoder`], [`ResidualCentering`] | eq. (1.1), two-sample update `O(H⁵)`; pulses eq. (5.1); centering eqs. (5.5), (5.6) |
//! | [`GyroErrorModel`], [`ReferenceDriftModel`], [`ErrorQuadratures`] | eqs. (1.2), (2.2), (2.4) |
//! | [`GyroCalibrator`] | eqs. (2.7), (5.4), (5.7) |
//! | [`NormalEquations`], [`SqrtInformation`] | eq. (5.8), and its square-root (Givens) form |
//!
//! # Example: the calibration of the paper's §6, abridged
//!
//! ```
//! use gnss_attitude::geometry::Quaternion;
//! use gnss_attitude::gyro::{CalibratorConfig, PaperCalibrator, SqrtInformation};
//! use nalgebra::Vector3;
//!
//! # fn main() -> Result<(), gnss_attitude::gyro::CalibrationError> {
//! let h = 0.02; // gyro sample interval, s
//! let mut cal = PaperCalibrator::<SqrtInformation<15>>::paper(
//!     CalibratorConfig::new(h),
//!     SqrtInformation::new(),
//!     Quaternion::identity(), // M(t₀)
//!     Quaternion::identity(), // N(t₀)
//! )?;
//! let bias = Vector3::new(1e-5, -1e-5, 2e-5); // rad/s, unknown to the calibrator
//! // the paper's rates (rad/s), 5 s each: a constant rate would not be observable
//! let rates = [[0.01, 0.02, -0.01], [0.02, 0.32, -0.015], [0.01, 0.01, -0.02],
//!              [0.16, 0.015, -0.03], [0.03, 0.017, -0.16], [0.02, 0.02, -0.02]];
//! let mut truth = Quaternion::<f32>::identity();
//! for k in 1..=1500 {
//!     let w = Vector3::from(rates[(k - 1) / 250]);
//!     truth = truth * Quaternion::from_rotation_vector(&(w * h));
//!     cal.push_increment(&((w + bias) * h))?;
//!     if k % 10 == 0 {
//!         cal.add_reference(&truth)?; // a perfect reference, every 0.2 s
//!     }
//! }
//! let est = cal.solve()?;
//! assert!(est.solution.observability.full_rank());
//! assert!((est.c.fixed_rows::<3>(6) - bias).amax() < 1e-6);
//! # Ok(()) }
//! ```

mod calibration;
mod calibration_types;
mod error_model;
pub mod lsq;
mod propagation;

pub use calibration::{CalibrationError, GyroCalibrator};
pub use calibration_types::{
    CalibrationEstimate, CalibratorConfig, EpochCounters, EpochEquations, EpochOutcome, SkipReason,
};
pub use error_model::{
    AnchorErrorAndDrift, BiasOnly, ConstantDrift, ErrorQuadratures, GyroErrorModel,
    ReferenceDriftModel, ScaleMisalignmentBias,
};
pub use lsq::{
    default_rank_tolerance, LeastSquaresAccumulator, LsqSolution, NormalEquations,
    ObservabilityReport, SqrtInformation, MAX_ROW_ENTRY,
};
pub use propagation::{
    two_sample_rotation_vector, AttitudePropagator, PropagationStep, PulseDecoder,
    ResidualCentering, FOLD_ANGLE,
};

use crate::geometry::Quaternion;
use crate::Real;

/// The paper's §6 calibrator: `m = 3` (`D = [D_I D_II E₃]`, 9 gyro parameters), `n = 1`
/// (`G = E₃`, constant drift), 15 unknowns, accumulator `A`.
pub type PaperCalibrator<A, T = f32> =
    GyroCalibrator<ScaleMisalignmentBias, ConstantDrift, A, 9, 3, 15, T>;

impl<A: LeastSquaresAccumulator<T, 15>, T: Real> PaperCalibrator<A, T> {
    /// The paper's calibrator with the given configuration, accumulator, initial computed
    /// attitude `M(t₀)` and initial reference attitude `N(t₀)`.
    ///
    /// # Errors
    /// Those of [`GyroCalibrator::new`].
    pub fn paper(
        config: CalibratorConfig<T>,
        accumulator: A,
        m0: Quaternion<T>,
        reference0: Quaternion<T>,
    ) -> Result<Self, CalibrationError> {
        Self::new(
            config,
            ScaleMisalignmentBias,
            ConstantDrift,
            accumulator,
            m0,
            reference0,
        )
    }
}
