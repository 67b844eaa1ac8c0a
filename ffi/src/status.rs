//! Status codes and the record of an object's last failure.

use gnss_attitude::error::{Error as _, ErrorKind};
use gnss_attitude::formats::FormatError;
use gnss_attitude::receiver::ReceiverError;

/// What a call returns. `GA_STATUS_OK` (0) is success, [`GaStatus::Empty`] a success with nothing
/// to report ([`crate::ga_receiver_pop_event`] on an empty queue), negative values failures.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GaStatus {
    /// Success.
    Ok = 0,
    /// Success, nothing to return (no event queued).
    Empty = 1,
    /// A required pointer was null.
    NullPointer = -1,
    /// A pointer was not aligned for its type.
    Misaligned = -2,
    /// The object's storage was not initialized by its `*_init` (or the init failed).
    NotInitialized = -3,
    /// A configuration value is outside its domain.
    InvalidConfig = -4,
    /// An input was NaN or infinite.
    NonFinite = -5,
    /// An input is finite but unusable (out of range, wrong length, unknown code).
    InvalidInput = -6,
    /// An observation for a satellite without aiding.
    NoAiding = -7,
    /// More satellites than the receiver (or the buffer) has room for.
    TooManySatellites = -8,
    /// An observation for an epoch already closed.
    StaleEpoch = -9,
    /// A tracking channel refused a hand-over or a sample block.
    Tracking = -10,
    /// The acquisition engine refused a search.
    Acquisition = -11,
    /// The output buffer is too short.
    BufferTooShort = -12,
    /// A gyro sample for a receiver without a gyro.
    NoGyro = -13,
    /// The gyro stage refused a sample (above one radian, pulses without a pulse weight).
    Gyro = -14,
    /// An epoch number within a few windows of `u64::MAX`.
    EpochOutOfRange = -15,
    /// The observation adapter refused a tracking epoch.
    Adapter = -16,
    /// A failure this version of the ABI has no code for (a newer core error).
    Other = -100,
}

impl From<ReceiverError> for GaStatus {
    fn from(e: ReceiverError) -> Self {
        match e {
            ReceiverError::NonFinite => Self::NonFinite,
            ReceiverError::InvalidConfig(_) => Self::InvalidConfig,
            ReceiverError::NoGyro => Self::NoGyro,
            ReceiverError::Gyro(_) => Self::Gyro,
            ReceiverError::EpochOutOfRange => Self::EpochOutOfRange,
            ReceiverError::Adapter(_) => Self::Adapter,
            ReceiverError::InvalidInput => Self::InvalidInput,
            ReceiverError::NoAiding => Self::NoAiding,
            ReceiverError::TooManySatellites => Self::TooManySatellites,
            ReceiverError::StaleEpoch => Self::StaleEpoch,
            ReceiverError::Tracking(_) => Self::Tracking,
            ReceiverError::Acquisition(_) => Self::Acquisition,
            _ => Self::Other,
        }
    }
}

impl From<FormatError> for GaStatus {
    fn from(e: FormatError) -> Self {
        match e {
            FormatError::BufferTooShort => Self::BufferTooShort,
            FormatError::NonFinite => Self::NonFinite,
            _ => Self::InvalidInput,
        }
    }
}

/// Kind of failure, from the core's [`ErrorKind`] (0 when the failure is the ABI's own:
/// a null pointer, an uninitialized object).
pub const GA_KIND_NONE: u8 = 0;
/// [`ErrorKind::NonFinite`].
pub const GA_KIND_NON_FINITE: u8 = 1;
/// [`ErrorKind::InvalidInput`].
pub const GA_KIND_INVALID_INPUT: u8 = 2;
/// [`ErrorKind::NotPositiveDefinite`].
pub const GA_KIND_NOT_POSITIVE_DEFINITE: u8 = 3;
/// [`ErrorKind::Unobservable`].
pub const GA_KIND_UNOBSERVABLE: u8 = 4;
/// [`ErrorKind::NotConverged`].
pub const GA_KIND_NOT_CONVERGED: u8 = 5;
/// [`ErrorKind::Numerical`].
pub const GA_KIND_NUMERICAL: u8 = 6;
/// A kind this version of the ABI has no code for.
pub const GA_KIND_OTHER: u8 = 255;

fn kind_code(kind: ErrorKind) -> u8 {
    match kind {
        ErrorKind::NonFinite => GA_KIND_NON_FINITE,
        ErrorKind::InvalidInput => GA_KIND_INVALID_INPUT,
        ErrorKind::NotPositiveDefinite => GA_KIND_NOT_POSITIVE_DEFINITE,
        ErrorKind::Unobservable => GA_KIND_UNOBSERVABLE,
        ErrorKind::NotConverged => GA_KIND_NOT_CONVERGED,
        ErrorKind::Numerical => GA_KIND_NUMERICAL,
        #[allow(unreachable_patterns)]
        _ => GA_KIND_OTHER,
    }
}

/// Which call failed (in [`GaError::call`]).
#[repr(u8)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GaCall {
    /// No failure recorded.
    None = 0,
    /// `*_init`.
    Init = 1,
    /// `ga_receiver_set_aiding`.
    SetAiding = 2,
    /// `ga_receiver_push_observation`.
    PushObservation = 3,
    /// `ga_receiver_push_gyro_increment`.
    PushGyroIncrement = 4,
    /// `ga_receiver_push_gyro_pulses`.
    PushGyroPulses = 5,
    /// `ga_sample_receiver_push_samples`.
    PushSamples = 6,
    /// `ga_sample_receiver_search`.
    Search = 7,
    /// `ga_receiver_attitude`, `ga_receiver_pop_event`, `ga_receiver_close_through`.
    Output = 8,
}

/// An object's last failure.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GaError {
    /// The status the failing call returned (`GA_STATUS_OK` when none failed since init).
    pub status: i32,
    /// `GA_KIND_*`: the core's classification of the cause.
    pub kind: u8,
    /// [`GaCall`] code of the failing call.
    pub call: u8,
    /// The core's inner cause for [`GaStatus::Tracking`] / [`GaStatus::Acquisition`]: the
    /// kind (`GA_KIND_*`) of the stage error that the receiver wrapped, else 0.
    pub source_kind: u8,
    /// Reserved, 0.
    pub reserved: u8,
    /// Epoch of the failing call where it has one (observations), else 0.
    pub epoch: u64,
}

impl GaError {
    /// No failure.
    pub(crate) const NONE: Self = Self {
        status: GaStatus::Ok as i32,
        kind: GA_KIND_NONE,
        call: GaCall::None as u8,
        source_kind: GA_KIND_NONE,
        reserved: 0,
        epoch: 0,
    };

    /// An ABI failure (null pointer, bad code) of `call`.
    pub fn abi(status: GaStatus, call: GaCall) -> Self {
        Self {
            status: status as i32,
            call: call as u8,
            ..Self::NONE
        }
    }

    /// A core receiver failure of `call`.
    pub fn receiver(e: ReceiverError, call: GaCall, epoch: u64) -> Self {
        let source_kind = match e {
            ReceiverError::Tracking(t) => kind_code(t.kind()),
            ReceiverError::Acquisition(a) => kind_code(a.kind()),
            ReceiverError::InvalidConfig(c) => kind_code(c.kind()),
            ReceiverError::Gyro(g) => kind_code(g.kind()),
            ReceiverError::Adapter(a) => kind_code(a.kind()),
            _ => GA_KIND_NONE,
        };
        Self {
            status: GaStatus::from(e) as i32,
            kind: kind_code(e.kind()),
            call: call as u8,
            source_kind,
            reserved: 0,
            epoch,
        }
    }
}

/// A failure on its way out: the status for the caller and the record for the object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Failure {
    pub(crate) status: GaStatus,
    pub(crate) record: GaError,
}

impl Failure {
    pub(crate) fn abi(status: GaStatus, call: GaCall) -> Self {
        Self {
            status,
            record: GaError::abi(status, call),
        }
    }

    pub(crate) fn receiver(e: ReceiverError, call: GaCall, epoch: u64) -> Self {
        Self {
            status: GaStatus::from(e),
            record: GaError::receiver(e, call, epoch),
        }
    }
}

/// A short English text for a status (static, NUL-terminated), for logs.
#[no_mangle]
pub extern "C" fn ga_status_str(status: i32) -> *const core::ffi::c_char {
    let text: &'static core::ffi::CStr = match status {
        0 => c"ok",
        1 => c"nothing to return",
        -1 => c"null pointer",
        -2 => c"misaligned pointer",
        -3 => c"object not initialized",
        -4 => c"invalid configuration",
        -5 => c"non-finite input",
        -6 => c"invalid input",
        -7 => c"no aiding for this satellite",
        -8 => c"too many satellites",
        -9 => c"epoch already closed",
        -10 => c"tracking channel refused",
        -11 => c"acquisition refused",
        -12 => c"output buffer too short",
        _ => c"unknown status",
    };
    text.as_ptr()
}
