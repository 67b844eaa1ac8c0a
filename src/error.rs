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
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FilterError {
    /// A state, covariance, transition, measurement, Jacobian or noise value was NaN or infinite.
    #[error("non-finite filter input")]
    NonFiniteInput,
    /// A covariance given to the filter (initial covariance, process noise) is not symmetric
    /// positive semi-definite with a positive diagonal.
    #[error("covariance is not symmetric positive semi-definite")]
    InvalidCovariance,
    /// A measurement noise variance is zero or negative.
    #[error("measurement noise variance is not positive")]
    NonPositiveNoise,
    /// The innovation covariance `S = H P Hᵀ + R` is not positive definite, so the update cannot
    /// be weighed. Happens when `R` is not PD or `P` has lost definiteness.
    #[error("innovation covariance is not positive definite")]
    InnovationNotPositiveDefinite,
    /// The step produced non-finite numbers from finite input (overflow). The state is
    /// unchanged.
    #[error("filter step overflowed")]
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

/// Errors of the snapshot attitude solvers ([`crate::attitude`]): input validation, the
/// paper's formula and the bounded numerical routines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SnapshotError {
    /// A baseline, line of sight, range difference, phase, code or noise value was NaN or
    /// infinite.
    NonFinite,
    /// Fewer than 3 satellites: the reference-frame baselines `a_i = (SSᵀ)⁻¹ S r_i` need three
    /// independent lines of sight.
    TooFewSatellites,
    /// More satellites than the compile-time capacity `N` of the observation set.
    TooManySatellites,
    /// The same satellite id was given twice in one epoch.
    DuplicateSatellite,
    /// A line-of-sight vector is not a unit vector (its norm is off 1 by more than 1e-3).
    InvalidLineOfSight,
    /// The lines of sight are (nearly) coplanar or collinear: `N = S W Sᵀ` is singular, so the
    /// three components of a baseline cannot be separated.
    CoplanarLineOfSight,
    /// A noise standard deviation, cofactor or wavelength is zero or negative.
    InvalidNoise,
    /// A body baseline is shorter than 1 mm.
    ZeroBaseline,
    /// The first two body baselines are (nearly) parallel: the attitude about their common
    /// direction is not observable.
    CollinearBaselines,
    /// The paper's formula (16) needs `G = BBᵀ` invertible: at least three non-coplanar
    /// baselines (four non-coplanar antennas).
    CoplanarBaselines,
    /// Fewer baselines than the method needs (two for the snapshot solver, three for the
    /// paper's formula).
    TooFewBaselines,
    /// The baseline noise correlation matrix is not symmetric positive definite.
    InvalidCorrelation,
    /// The paper's formula (16) would return a reflection (`det Q < 0`), not a rotation.
    Reflection,
    /// A bounded iteration (Jacobi eigen-decomposition) reached its bound without converging.
    NotConverged,
    /// A computation produced a non-finite or degenerate result from finite input.
    Numerical,
}

impl Error for SnapshotError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::TooFewSatellites
            | Self::TooManySatellites
            | Self::DuplicateSatellite
            | Self::InvalidLineOfSight
            | Self::InvalidNoise
            | Self::ZeroBaseline
            | Self::CollinearBaselines
            | Self::TooFewBaselines
            | Self::InvalidCorrelation => ErrorKind::InvalidInput,
            Self::CoplanarLineOfSight | Self::CoplanarBaselines | Self::Reflection => {
                ErrorKind::Unobservable
            }
            Self::NotConverged => ErrorKind::NotConverged,
            Self::Numerical => ErrorKind::Numerical,
        }
    }
}

impl fmt::Display for SnapshotError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NonFinite => "non-finite snapshot input",
            Self::TooFewSatellites => "fewer than 3 satellites",
            Self::TooManySatellites => "more satellites than the capacity",
            Self::DuplicateSatellite => "satellite listed twice",
            Self::InvalidLineOfSight => "line of sight is not a unit vector",
            Self::CoplanarLineOfSight => "lines of sight are coplanar or collinear",
            Self::InvalidNoise => "noise, cofactor or wavelength is not positive",
            Self::ZeroBaseline => "baseline of zero length",
            Self::CollinearBaselines => "baselines are collinear",
            Self::CoplanarBaselines => {
                "baselines are coplanar (paper formula needs 3 non-coplanar)"
            }
            Self::TooFewBaselines => "too few baselines",
            Self::InvalidCorrelation => "baseline correlation is not positive definite",
            Self::Reflection => "paper formula (16) gives a reflection (det Q < 0)",
            Self::NotConverged => "eigen-decomposition did not converge",
            Self::Numerical => "snapshot computation failed numerically",
        })
    }
}

impl core::error::Error for SnapshotError {}

/// Errors (refusals) of the integer ambiguity resolution ([`crate::attitude::ambiguity`]).
///
/// Every variant except [`AmbiguityError::Input`] is a *refusal*: the data were valid, but no
/// integer solution could be validated, and the resolver returns no attitude rather than a
/// possibly wrong one. Retry with the next epoch.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AmbiguityError {
    /// The observations or the configuration were invalid (see the inner error).
    Input(SnapshotError),
    /// The integer search visited its node budget before it could prove its answer.
    SearchBudgetExhausted,
    /// No integer candidate lies inside the search bound: the data are inconsistent with the
    /// model (a cycle slip, a wrong baseline, a multipath outlier).
    NoCandidate,
    /// The ratio test failed: the second-best candidate fits almost as well as the best.
    Ambiguous,
    /// The best candidate fails the χ² test of the whole model (99.9 %).
    ModelRejected,
}

impl From<SnapshotError> for AmbiguityError {
    fn from(e: SnapshotError) -> Self {
        Self::Input(e)
    }
}

impl Error for AmbiguityError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::Input(e) => e.kind(),
            Self::SearchBudgetExhausted => ErrorKind::NotConverged,
            Self::NoCandidate | Self::Ambiguous | Self::ModelRejected => ErrorKind::Unobservable,
        }
    }
}

impl fmt::Display for AmbiguityError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Input(e) => write!(f, "ambiguity input: {e}"),
            Self::SearchBudgetExhausted => f.write_str("integer search budget exhausted"),
            Self::NoCandidate => f.write_str("no integer candidate inside the search bound"),
            Self::Ambiguous => f.write_str("ratio test failed: ambiguities not validated"),
            Self::ModelRejected => f.write_str("best integer candidate fails the model test"),
        }
    }
}

impl core::error::Error for AmbiguityError {}
/// Errors of the baseline and Doppler attitude filters of paper 000 ([`crate::attitude`]:
/// the direction-cosine filter, the multi-structure filter and the rigid-body filter).
///
/// A step that returns one of these leaves its filter exactly as it was before the call.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DcmError {
    /// A measurement, an antenna position, an initial attitude or a covariance was NaN or
    /// infinite.
    NonFinite,
    /// A baseline vector or a velocity difference that the filter needs is absent (one of its
    /// two antennas has no solution in this epoch).
    MissingBaseline,
    /// A baseline — an antenna-position difference in body axes, or a measured baseline in the
    /// reference frame — is shorter than [`crate::attitude::baseline_epoch::MIN_BASELINE_LENGTH`].
    ZeroLengthBaseline,
    /// A configuration value is out of its domain: a non-positive step or noise level, a pair
    /// of identical baselines, a covariance that is not symmetric positive definite.
    InvalidConfig,
    /// The antenna geometry makes the model singular at every attitude: the two baselines are
    /// (nearly) parallel, or the eliminated column's body axis lies (nearly) in the antenna
    /// plane (`n_k → 0` with `n = b₁ × b₂`, the paper's `n_x = 0` case).
    SingularGeometry,
    /// `Φ(Ŷ)` is singular in working precision at the current estimate. Since
    /// `|det Φ(Y)| ≥ |n_k|³` for every state, this happens only for geometry close to the
    /// limit of [`DcmError::SingularGeometry`], or after an overflow. Re-initialize the filter.
    SingularJacobian,
    /// The covariance lost positive definiteness during the step (the step is rejected).
    NotPositiveDefinite,
    /// The estimate could not be turned into a rotation (its direction cosines are too far
    /// from orthonormal, or the orthonormalization did not converge).
    NotARotation,
    /// The shared Kalman filter toolkit rejected the step.
    Filter(FilterError),
    /// The step overflowed or produced a non-finite number from finite input.
    Numerical,
}

impl Error for DcmError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::MissingBaseline | Self::ZeroLengthBaseline | Self::InvalidConfig => {
                ErrorKind::InvalidInput
            }
            Self::SingularGeometry | Self::SingularJacobian => ErrorKind::Unobservable,
            Self::NotPositiveDefinite => ErrorKind::NotPositiveDefinite,
            Self::NotARotation | Self::Numerical => ErrorKind::Numerical,
            Self::Filter(e) => e.kind(),
        }
    }
}

impl fmt::Display for DcmError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NonFinite => f.write_str("non-finite baseline filter input"),
            Self::MissingBaseline => {
                f.write_str("a needed baseline or velocity difference is missing")
            }
            Self::ZeroLengthBaseline => f.write_str("baseline of (near) zero length"),
            Self::InvalidConfig => f.write_str("invalid baseline filter configuration"),
            Self::SingularGeometry => {
                f.write_str("antenna geometry makes the direction-cosine model singular")
            }
            Self::SingularJacobian => f.write_str("observation Jacobian is numerically singular"),
            Self::NotPositiveDefinite => f.write_str("covariance lost positive definiteness"),
            Self::NotARotation => f.write_str("estimate is too far from a rotation"),
            Self::Filter(e) => write!(f, "filter toolkit: {e}"),
            Self::Numerical => f.write_str("baseline filter step overflowed"),
        }
    }
}

impl core::error::Error for DcmError {}

impl From<FilterError> for DcmError {
    fn from(e: FilterError) -> Self {
        Self::Filter(e)
    }
}

impl From<GeometryError> for DcmError {
    fn from(e: GeometryError) -> Self {
        match e {
            GeometryError::NonFinite => Self::NonFinite,
            GeometryError::ZeroLength
            | GeometryError::NotARotation
            | GeometryError::NotConverged => Self::NotARotation,
        }
    }
}
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
    /// A snapshot solution offered as the prior is not of
    /// [`SnapshotQuality::Good`](crate::attitude::snapshot::SnapshotQuality::Good) (its
    /// residuals failed the χ² test or its iteration did not converge).
    UnusableSnapshot,
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
            Self::UnusableSnapshot => ErrorKind::InvalidInput,
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
            Self::UnusableSnapshot => "snapshot solution not good enough for a prior",
            Self::Numerical => "one-stage filter step failed numerically",
        })
    }
}

impl core::error::Error for OneStageError {}

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

/// Errors of the attitude receiver ([`crate::receiver`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ReceiverError {
    /// An input (observation, line of sight, gyro increment, configuration value) was NaN or
    /// infinite.
    NonFinite,
    /// A configuration value is outside its domain (a non-positive epoch, window or noise
    /// level, a degenerate antenna array, a window that is not a whole number of gyro steps);
    /// the error of the stage that refused it is logged.
    InvalidConfig,
    /// An input is finite but unusable: a line of sight that is not a unit vector, a noise
    /// variance that is not positive, a C/N0 outside 0..=90 dB-Hz, a gyro increment above one
    /// radian.
    InvalidInput,
    /// An observation arrived for a satellite without navigation aiding (no line of sight):
    /// call [`crate::receiver::AttitudeReceiver::set_aiding`] first.
    NoAiding,
    /// More satellites than the receiver has slots for.
    TooManySatellites,
    /// An observation arrived for an epoch the receiver has already closed.
    StaleEpoch,
    /// A software tracking channel refused a hand-over or a sample block.
    Tracking(TrackingError),
    /// The acquisition engine refused a search (too few samples, bad configuration).
    Acquisition(AcquisitionError),
}

impl From<AcquisitionError> for ReceiverError {
    fn from(e: AcquisitionError) -> Self {
        Self::Acquisition(e)
    }
}

impl From<TrackingError> for ReceiverError {
    fn from(e: TrackingError) -> Self {
        Self::Tracking(e)
    }
}

impl Error for ReceiverError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::InvalidConfig
            | Self::InvalidInput
            | Self::NoAiding
            | Self::TooManySatellites
            | Self::StaleEpoch => ErrorKind::InvalidInput,
            Self::Tracking(e) => e.kind(),
            Self::Acquisition(e) => e.kind(),
        }
    }
}

impl fmt::Display for ReceiverError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NonFinite => f.write_str("non-finite receiver input"),
            Self::InvalidConfig => f.write_str("invalid receiver configuration"),
            Self::InvalidInput => f.write_str("receiver input out of range"),
            Self::NoAiding => f.write_str("no line of sight for this satellite"),
            Self::TooManySatellites => f.write_str("no free satellite slot"),
            Self::StaleEpoch => f.write_str("observation for an epoch already closed"),
            Self::Tracking(e) => write!(f, "tracking channel: {e}"),
            Self::Acquisition(e) => write!(f, "acquisition: {e}"),
        }
    }
}

impl core::error::Error for ReceiverError {}
/// Errors of the antenna array ([`crate::attitude::array::AntennaArray`]), shared by the
/// paper-000 filters and the one-stage filter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ArrayError {
    /// An antenna coordinate or the side of the triangle was NaN or infinite.
    NonFinite,
    /// Two antennas are closer than
    /// [`MIN_BASELINE_LENGTH`](crate::attitude::array::MIN_BASELINE_LENGTH) (or a triangle
    /// side is shorter than that, or negative).
    CoincidentAntennas,
    /// The three antennas are (nearly) collinear: they span no plane, so the rotation about
    /// their line is unobservable (checked by the estimators that need a plane).
    CollinearAntennas,
}

impl Error for ArrayError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::CoincidentAntennas | Self::CollinearAntennas => ErrorKind::InvalidInput,
        }
    }
}

impl fmt::Display for ArrayError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::NonFinite => "non-finite antenna position",
            Self::CoincidentAntennas => "two antennas (nearly) coincide",
            Self::CollinearAntennas => "the three antennas are (nearly) collinear",
        })
    }
}

impl core::error::Error for ArrayError {}

impl From<ArrayError> for DcmError {
    fn from(e: ArrayError) -> Self {
        match e {
            ArrayError::NonFinite => Self::NonFinite,
            ArrayError::CoincidentAntennas => Self::ZeroLengthBaseline,
            ArrayError::CollinearAntennas => Self::SingularGeometry,
        }
    }
}

impl From<ArrayError> for OneStageError {
    fn from(e: ArrayError) -> Self {
        match e {
            ArrayError::NonFinite => Self::NonFiniteInput,
            ArrayError::CoincidentAntennas | ArrayError::CollinearAntennas => Self::DegenerateArray,
        }
    }
}
