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

/// Errors of the one-stage attitude filter ([`crate::attitude::one_stage`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum OneStageError {
    /// An observation, prior, configuration or antenna position held NaN or infinity.
    NonFiniteInput,
    /// A configuration value is outside its domain: a non-positive wavelength, epoch or
    /// bandwidth, a negative process noise, a lock threshold outside `(0, 1]`, no estimated
    /// angle.
    InvalidConfig,
    /// The antenna array is degenerate: two antennas coincide or all three are collinear.
    DegenerateArray,
    /// An observation is unusable: a line of sight that is not a unit vector (length off by more
    /// than 1e-3), a noise variance that is not positive, or a C/N0 outside 0..=90 dB-Hz.
    InvalidObservation,
    /// More satellites in one epoch than [`MAX_SATELLITES`](crate::attitude::one_stage::MAX_SATELLITES).
    TooManySatellites,
    /// A prior covariance is not symmetric positive definite.
    InvalidCovariance,
    /// The prior attitude is at the gimbal lock of the paper's angles (`cos β` below 1e-3),
    /// where a rotation-vector covariance cannot be mapped onto α, β, γ.
    GimbalLock,
    /// The filter step produced non-finite numbers or lost definiteness from finite input; the
    /// filter is unchanged.
    Numerical,
}

impl Error for OneStageError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFiniteInput => ErrorKind::NonFinite,
            Self::InvalidConfig
            | Self::DegenerateArray
            | Self::InvalidObservation
            | Self::TooManySatellites => ErrorKind::InvalidInput,
            Self::InvalidCovariance => ErrorKind::NotPositiveDefinite,
            Self::GimbalLock => ErrorKind::Unobservable,
            Self::Numerical => ErrorKind::Numerical,
        }
    }
}

impl fmt::Display for OneStageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NonFiniteInput => "non-finite one-stage filter input",
            Self::InvalidConfig => "invalid one-stage filter configuration",
            Self::DegenerateArray => "antenna array is degenerate (coincident or collinear)",
            Self::InvalidObservation => "unusable satellite observation",
            Self::TooManySatellites => "too many satellites in one epoch",
            Self::InvalidCovariance => "prior covariance is not positive definite",
            Self::GimbalLock => "prior attitude at the gimbal lock of the paper's angles",
            Self::Numerical => "one-stage filter step failed numerically",
        })
    }
}

impl core::error::Error for OneStageError {}
