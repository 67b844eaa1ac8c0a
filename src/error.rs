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

/// Errors of sample decoding ([`crate::signal::samples`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SampleError {
    /// The format's parameters are out of range (a CS16 shift above 8, a multi-channel format
    /// with 0 or more than 4 channels).
    InvalidFormat,
    /// The requested channel is not in the stream (channel ≥ the format's channel count).
    NoSuchChannel,
    /// The byte slice ends inside a sample (odd CS8 length, CS16 length not a multiple of 4).
    PartialSample,
}

impl Error for SampleError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::InvalidInput
    }
}

impl fmt::Display for SampleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::InvalidFormat => "sample format parameters out of range",
            Self::NoSuchChannel => "channel not present in the sample stream",
            Self::PartialSample => "byte stream ends inside a sample",
        })
    }
}

impl core::error::Error for SampleError {}

/// Errors of the correlators and NCOs ([`crate::signal`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SignalError {
    /// A frequency, rate or phase was NaN or infinite.
    NonFinite,
    /// A configuration value is out of range: sample rate outside 1.023–64 MHz, IF beyond the
    /// sample rate, early/late offset outside (0, 1] chip, a carrier frequency beyond ±`f_s`/2,
    /// a code rate more than 1 % off nominal, or no antennas.
    InvalidConfig,
    /// The antennas' sample slices of a block differ in length.
    BlockLengthMismatch,
    /// The cursor passed to the correlator lies beyond the end of the block.
    CursorOutOfRange,
}

impl Error for SignalError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::InvalidConfig | Self::BlockLengthMismatch | Self::CursorOutOfRange => {
                ErrorKind::InvalidInput
            }
        }
    }
}

impl fmt::Display for SignalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NonFinite => "non-finite NCO input",
            Self::InvalidConfig => "correlator configuration out of range",
            Self::BlockLengthMismatch => "antenna sample slices differ in length",
            Self::CursorOutOfRange => "cursor beyond the end of the sample block",
        })
    }
}

impl core::error::Error for SignalError {}

/// Errors of acquisition ([`crate::tracking::acquisition`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AcquisitionError {
    /// A configuration value was NaN or infinite.
    NonFinite,
    /// The configuration is out of range (sample rate outside 1.023–64 MHz, IF beyond the
    /// sample rate, Doppler step below 10 Hz, more Doppler bins than the engine holds, zero or
    /// too many milliseconds, a false-alarm probability outside (0, 0.5)), or the engine's
    /// FFT size is not a power of two in 1024–8192.
    InvalidConfig,
    /// Fewer samples than the configured number of milliseconds needs.
    NotEnoughSamples,
    /// The quadrature samples are fewer than the in-phase samples.
    LengthMismatch,
}

impl Error for AcquisitionError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            _ => ErrorKind::InvalidInput,
        }
    }
}

impl fmt::Display for AcquisitionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NonFinite => "non-finite acquisition configuration",
            Self::InvalidConfig => "acquisition configuration out of range",
            Self::NotEnoughSamples => "fewer samples than the search needs",
            Self::LengthMismatch => "quadrature samples shorter than in-phase samples",
        })
    }
}

impl core::error::Error for AcquisitionError {}

/// Errors of the tracking channel ([`crate::tracking::channel`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum TrackingError {
    /// A loop parameter or a hand-over value was NaN or infinite.
    NonFinite,
    /// A loop parameter is out of range (a bandwidth outside 0–100 Hz, an empty window).
    InvalidConfig,
    /// The channel was asked to process samples before an acquisition was handed over.
    NotStarted,
    /// The acquisition handed over is for another PRN.
    WrongPrn,
    /// The correlator refused a configuration, NCO setting or block.
    Signal(SignalError),
}

impl From<SignalError> for TrackingError {
    fn from(e: SignalError) -> Self {
        Self::Signal(e)
    }
}

impl Error for TrackingError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::InvalidConfig | Self::NotStarted | Self::WrongPrn => ErrorKind::InvalidInput,
            Self::Signal(e) => e.kind(),
        }
    }
}

impl fmt::Display for TrackingError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NonFinite => f.write_str("non-finite tracking input"),
            Self::InvalidConfig => f.write_str("tracking configuration out of range"),
            Self::NotStarted => f.write_str("channel not started"),
            Self::WrongPrn => f.write_str("acquisition result is for another PRN"),
            Self::Signal(e) => write!(f, "correlator: {e}"),
        }
    }
}

impl core::error::Error for TrackingError {}

/// Errors of the front-end drivers ([`crate::frontend`]); `E` is the SPI bus error.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FrontEndError<E> {
    /// The SPI transfer failed.
    Spi(E),
    /// A configuration value is out of range (PLL dividers, clock divider, register address).
    InvalidConfig,
    /// The chip ID read back is not the expected part's; nothing was written.
    WrongChip,
    /// The part did not report ready (PLL lock, AOK) within the polling bound.
    NotReady,
}

impl<E: fmt::Debug> Error for FrontEndError<E> {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::InvalidConfig | Self::WrongChip => ErrorKind::InvalidInput,
            Self::Spi(_) | Self::NotReady => ErrorKind::NotConverged,
        }
    }
}

impl<E: fmt::Debug> fmt::Display for FrontEndError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Spi(e) => write!(f, "SPI error: {e:?}"),
            Self::InvalidConfig => f.write_str("front-end configuration out of range"),
            Self::WrongChip => f.write_str("unexpected chip ID"),
            Self::NotReady => f.write_str("front end not ready within the polling bound"),
        }
    }
}

impl<E: fmt::Debug> core::error::Error for FrontEndError<E> {}
