//! What the crate's errors have in common.
//!
//! Each error lives next to the operation that raises it (`SnapshotSolver::solve` returns a
//! [`SnapshotError`](crate::attitude::snapshot::SnapshotError), `AttitudeReceiver::new` a
//! [`ReceiverError`](crate::receiver::ReceiverError) whose `InvalidConfig` names the field or
//! keeps the refusing stage's error as its source). Each is a small `#[non_exhaustive]` enum
//! whose variants name a cause and document when it happens. Generic code (a supervisor that
//! only wants to know whether to retry, re-initialize or give up) matches on [`ErrorKind`]
//! through [`Error::kind`] instead of on every variant, in the style of `embedded-hal`; a
//! wrapping error reports its source's kind.
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

impl ErrorKind {
    /// What the kind means, in a few words (`"invalid input"`): its `Display` text, for
    /// reports that do without `core::fmt` (firmware printing through semihosting or a UART).
    pub const fn as_str(self) -> &'static str {
        match self {
            Self::NonFinite => "non-finite input",
            Self::InvalidInput => "invalid input",
            Self::NotPositiveDefinite => "matrix not positive definite",
            Self::Unobservable => "not observable",
            Self::NotConverged => "iteration bound reached",
            Self::Numerical => "numerical failure",
        }
    }
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::ErrorKind;
    use core::fmt::Write;

    const ALL: [ErrorKind; 6] = [
        ErrorKind::NonFinite,
        ErrorKind::InvalidInput,
        ErrorKind::NotPositiveDefinite,
        ErrorKind::Unobservable,
        ErrorKind::NotConverged,
        ErrorKind::Numerical,
    ];

    #[test]
    fn each_kind_names_itself_apart_and_displays_its_words() {
        for (i, kind) in ALL.into_iter().enumerate() {
            let mut shown = heapless::String::<40>::new();
            write!(shown, "{kind}").expect("fits");
            assert_eq!(shown.as_str(), kind.as_str());
            assert!(!kind.as_str().is_empty());
            assert!(
                ALL[..i].iter().all(|k| k.as_str() != kind.as_str()),
                "{kind:?} repeats a name"
            );
        }
    }
}
