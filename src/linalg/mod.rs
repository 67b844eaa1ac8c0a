//! Bounded linear algebra on small fixed-size matrices, for the estimators that need more
//! than nalgebra's closed forms and Cholesky factorizations.
//!
//! nalgebra's iterative decompositions (`SVD::new`, `SymmetricEigen::new`) iterate without a
//! bound and its pivoting LU can panic; these routines stop after a stated number of sweeps
//! and report failure instead:
//!
//! | Routine | What it is | Used by |
//! |---|---|---|
//! | [`symmetric_eigen`] | cyclic Jacobi eigen-decomposition, at most [`EIGEN_MAX_SWEEPS`] sweeps | Wahba / Davenport q-method, paper 002's formula |
//! | [`singular_values`] | one-sided (Hestenes) Jacobi SVD, at most [`SVD_MAX_SWEEPS`] sweeps | gyro calibration's observability report |
//! | `givens_inverse` | inverse by Givens QR with its pivot ratio | paper 000's `Φ⁻¹` |
//! | `psd_factor`, `regularized_solve`, `marginal_information` | `LDLᵀ` of a semi-definite matrix, a regularized solve | the one-stage filter's information form |

mod eigen;
mod givens;
mod psd;
mod svd;

pub use eigen::{symmetric_eigen, EIGEN_MAX_SWEEPS};
pub(crate) use givens::givens_inverse;
pub(crate) use psd::{marginal_information, psd_factor, regularized_solve};
pub use svd::{singular_values, SVD_MAX_SWEEPS};

use crate::error::{Error, ErrorKind};

/// Error returned by [`singular_values`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum LinalgError {
    /// An element of the input was NaN or infinite.
    #[error("non-finite matrix element")]
    NonFinite,
    /// The sweep bound was reached before the tolerance was met.
    #[error("sweep bound reached")]
    NotConverged,
}

impl Error for LinalgError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::NonFinite => ErrorKind::NonFinite,
            Self::NotConverged => ErrorKind::NotConverged,
        }
    }
}
