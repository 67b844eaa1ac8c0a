//! The crate's errors.
//!
//! Each module that can fail has one small `#[non_exhaustive]` enum here, whose variants name a
//! cause and document when it happens. Generic code (a supervisor that only wants to know whether
//! to retry, re-initialize or give up) matches on [`ErrorKind`] through [`Error::kind`] instead of
//! on every variant, in the style of `embedded-hal`.
//!
//! A call that returns an error leaves the object it was called on unchanged.

use core::fmt;

/// What kind of failure an error is, for code that handles all of the crate's errors alike.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ErrorKind {
    /// An input was NaN or infinite. Fix the caller; retrying with the same data fails again.
    NonFinite,
    /// An input was finite but outside the domain the call accepts (a zero-length vector, a
    /// negative variance, too few items). Fix the caller.
    InvalidInput,
    /// A matrix that must be positive definite was not (a covariance lost definiteness, or a
    /// noise matrix was not PD). Usually means the filter must be re-initialized.
    NotPositiveDefinite,
    /// The geometry or the data carry too little information for the requested estimate (a
    /// singular system, an unobservable direction). Retry with more or better data.
    Unobservable,
    /// An iterative routine reached its iteration bound without meeting its tolerance.
    NotConverged,
    /// A computation overflowed or produced a non-finite result from finite input.
    Numerical,
}

/// Common interface of the crate's error enums.
pub trait Error: fmt::Debug + fmt::Display {
    /// The kind of failure, for generic handling.
    fn kind(&self) -> ErrorKind;
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NonFinite => "non-finite input",
            Self::InvalidInput => "invalid input",
            Self::NotPositiveDefinite => "matrix not positive definite",
            Self::Unobservable => "not observable",
            Self::NotConverged => "iteration bound reached",
            Self::Numerical => "numerical failure",
        })
    }
}

/// Errors of the Kalman filter toolkit ([`crate::ekf`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FilterError {
    /// A state, covariance, transition, measurement, Jacobian or noise value was NaN or infinite.
    NonFiniteInput,
    /// A covariance given to the filter (initial covariance, process noise) is not symmetric
    /// positive semi-definite with a positive diagonal.
    InvalidCovariance,
    /// A measurement noise variance is zero or negative.
    NonPositiveNoise,
    /// The innovation covariance `S = H P Hᵀ + R` is not positive definite, so the update cannot
    /// be weighed. Happens when `R` is not PD or `P` has lost definiteness.
    InnovationNotPositiveDefinite,
    /// The step produced non-finite numbers from finite input (overflow). The state is
    /// unchanged.
    Numerical,
}

impl Error for FilterError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFiniteInput => ErrorKind::NonFinite,
            Self::InvalidCovariance | Self::NonPositiveNoise => ErrorKind::InvalidInput,
            Self::InnovationNotPositiveDefinite => ErrorKind::NotPositiveDefinite,
            Self::Numerical => ErrorKind::Numerical,
        }
    }
}

impl fmt::Display for FilterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NonFiniteInput => "non-finite filter input",
            Self::InvalidCovariance => "covariance is not symmetric positive semi-definite",
            Self::NonPositiveNoise => "measurement noise variance is not positive",
            Self::InnovationNotPositiveDefinite => "innovation covariance is not positive definite",
            Self::Numerical => "filter step overflowed",
        })
    }
}

impl core::error::Error for FilterError {}

/// Errors of the geometry routines ([`crate::geometry`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum GeometryError {
    /// An angle, vector, quaternion or matrix element was NaN or infinite.
    NonFinite,
    /// A vector or quaternion that must be normalized has (near) zero length.
    ZeroLength,
    /// A matrix is too far from a rotation to be repaired: its determinant is not positive, or
    /// it is (near) singular.
    NotARotation,
    /// The bounded orthonormalization did not converge within its iteration bound.
    NotConverged,
}

impl Error for GeometryError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::ZeroLength | Self::NotARotation => ErrorKind::InvalidInput,
            Self::NotConverged => ErrorKind::NotConverged,
        }
    }
}

impl fmt::Display for GeometryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NonFinite => "non-finite geometry input",
            Self::ZeroLength => "vector or quaternion of zero length",
            Self::NotARotation => "matrix is not close to a proper rotation",
            Self::NotConverged => "orthonormalization did not converge",
        })
    }
}

impl core::error::Error for GeometryError {}

/// Errors of the gyro propagation and calibration ([`crate::gyro`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum CalibrationError {
    /// A gyro increment, pulse weight, reference attitude, measurement row or right-hand side
    /// was NaN or infinite.
    NonFiniteInput,
    /// A finite input is outside the accepted range: a measurement row or right-hand side
    /// element larger than [`crate::gyro::MAX_ROW_ENTRY`] in magnitude (so that the accumulators
    /// can never overflow), a pulse count whose angle exceeds one radian per sample, or a
    /// reference quaternion far from unit norm.
    InputOutOfRange,
    /// A configuration value is invalid: a non-positive sample interval or pulse weight, a
    /// negative threshold, or a rank tolerance outside `(0, 1)`.
    InvalidConfig,
    /// A reference attitude arrived between the two samples of a propagation step `H = 2h`: the
    /// computed attitude exists only at step boundaries. Deliver references at even sample
    /// counts.
    MidStep,
    /// Fewer rows were accumulated than there are unknowns (`rows`): no estimate and no
    /// formal standard deviation can be formed.
    TooFewRows {
        /// Rows accumulated so far.
        rows: u32,
    },
    /// The accumulated system is rank deficient: the window does not determine every unknown
    /// (for example a constant angular rate, which cannot separate scale factors,
    /// misalignments and biases). `rank` is the numerical rank found; retry with a window of
    /// richer motion.
    Unobservable {
        /// Numerical rank of the accumulated system (less than the number of unknowns).
        rank: u16,
    },
    /// The one-sided Jacobi singular-value iteration did not converge within
    /// [`crate::gyro::JACOBI_MAX_SWEEPS`] sweeps.
    NotConverged,
    /// The normal matrix passed the rank test but has no Cholesky factor: rounding destroyed
    /// its definiteness (normal equations square the condition number).
    NotPositiveDefinite,
}

impl Error for CalibrationError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFiniteInput => ErrorKind::NonFinite,
            Self::InputOutOfRange | Self::InvalidConfig | Self::MidStep => ErrorKind::InvalidInput,
            Self::TooFewRows { .. } | Self::Unobservable { .. } => ErrorKind::Unobservable,
            Self::NotConverged => ErrorKind::NotConverged,
            Self::NotPositiveDefinite => ErrorKind::NotPositiveDefinite,
        }
    }
}

impl fmt::Display for CalibrationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NonFiniteInput => f.write_str("non-finite calibration input"),
            Self::InputOutOfRange => f.write_str("calibration input out of range"),
            Self::InvalidConfig => f.write_str("invalid calibration configuration"),
            Self::MidStep => f.write_str("reference epoch between the two samples of a step"),
            Self::TooFewRows { rows } => write!(f, "only {rows} rows accumulated"),
            Self::Unobservable { rank } => {
                write!(
                    f,
                    "calibration window not observable (numerical rank {rank})"
                )
            }
            Self::NotConverged => f.write_str("Jacobi singular values did not converge"),
            Self::NotPositiveDefinite => f.write_str("normal matrix lost positive definiteness"),
        }
    }
}

impl core::error::Error for CalibrationError {}
