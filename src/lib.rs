//! Attitude of a microsatellite from GNSS signals received on three antennas.
//!
//! `gnss-attitude` is the onboard half of a GNSS attitude receiver: it turns what three
//! phase-coherent antennas receive into the attitude of the spacecraft, with a covariance and
//! health flags that flight software can act on. Its desktop twin, `host-sim`, synthesizes the
//! truth, the signals and the measurements, and runs every estimator against them.
//!
//! # Design contract
//!
//! Flight software links this crate into an interrupt-driven loop on a Cortex-M4F/M7. The crate
//! therefore promises:
//!
//! * **No allocation.** `#![no_std]` without `alloc`. Every size is a compile-time constant
//!   (const generics on [`nalgebra::SMatrix`], [`heapless`] containers). What a type holds is what
//!   it costs; nothing grows.
//! * **No panics.** No `unwrap`, no indexing that can fail, no unbounded iteration. Every fallible
//!   call returns a `Result` whose error is a small `#[non_exhaustive]` enum with documented
//!   causes (see [`error`]). Non-finite input is rejected at the boundary, never propagated into a
//!   filter state. A call that fails leaves the object it was called on unchanged.
//! * **Bounded time.** Every iterative routine has a fixed iteration bound, stated in its
//!   documentation. The nalgebra decompositions that iterate without bound (`SVD::new`,
//!   `SymmetricEigen::new`, `Rotation3::from_matrix`) are not used; the crate uses closed forms,
//!   Cholesky factorizations and bounded iterations instead.
//! * **f32 that survives long runs.** Estimators run in `f32` (the Cortex-M4F FPU is single
//!   precision) and are written so that `f32` is enough: Joseph-form covariance updates,
//!   enforced symmetry, variance floors, innovation gating. The numerical code is generic over
//!   [`Real`] so that tests run the very same code in `f64` and compare.
//! * **Features only add.** The `defmt` feature derives `defmt::Format` on the public data types
//!   and routes the crate's log macros to defmt; without it the log macros compile to nothing.
//!   No feature changes a numerical result.
//!
//! # Layout: the data path, top to bottom
//!
//! | Module | What it is |
//! |---|---|
//! | [`signal`] | GPS L1 C/A codes, front-end sample formats, NCOs, the fixed-point three-antenna correlator |
//! | [`tracking`] | Acquisition, tracking loops, C/N0, lock detectors, the per-satellite channel |
//! | [`frontend`] | SPI driver of the NT1065 four-channel front end (embedded-hal 1.0) |
//! | [`geometry`] | Frames, rotation matrices, Hamilton quaternions, Euler angles of the papers |
//! | [`ekf`] | The fixed-size Kalman filter toolkit every estimator shares |
//! | [`attitude`] | Attitude estimators: snapshot from carrier phase with ambiguity resolution (paper 002); one-stage filter from three-antenna I/Q (paper 003); direction-cosine, multi-structure and rigid-body filters from baselines and Doppler (paper 000) |
//! | [`gyro`] | Gyro propagation and in-flight calibration against a reference attitude (paper 001) |
//! | [`noise`] | Seeded test-signal and noise generators over any [`rand_core::RngCore`] |
//! | [`selftest`] | A deterministic computation that firmware runs and compares with the host |
//! | [`linalg`] | Bounded eigen-decomposition, SVD, Givens QR and semi-definite factorization of small matrices |
//! | [`formats`] | The attitude as NMEA `$GPHDT`/`$GPTHS` sentences and a binary telemetry record |
//! | [`error`] | What every error has in common: the [`error::Error`] trait and its [`error::ErrorKind`] (each error lives next to its operation) |
//!
//! # Frames and units
//!
//! SI units throughout (metres, seconds, radians) unless a name says otherwise
//! (`_deg`, `_hz`, `_chips`). Frame conventions are stated once, in [`geometry`], and every
//! public item names the frame of each vector it takes or returns.
//!
//! # Features
//!
//! * `defmt`: `defmt::Format` for the public data types; log output through defmt.
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![warn(
    clippy::use_self,
    clippy::doc_markdown,
    clippy::semicolon_if_nothing_returned,
    clippy::cast_lossless,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]
// `!(x > y)` is used on purpose: unlike `x <= y` it is true for NaN, so a NaN fails the check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// MSRV 1.87 makes clippy suggest `is_multiple_of`; `% n == 0` stays until the owners switch.
#![allow(clippy::manual_is_multiple_of)]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used))]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![cfg_attr(feature = "optimize-cold", feature(optimize_attribute))]
#![cfg_attr(feature = "fpu-sqrt", feature(core_float_math))]

#[macro_use]
mod log;

pub mod attitude;
pub mod ekf;
pub mod error;
pub mod formats;
pub mod frontend;
pub mod geometry;
pub mod gyro;
pub mod linalg;
pub mod nav;
pub mod noise;
pub mod receiver;
pub mod selftest;
pub mod signal;
pub mod tracking;

/// The real scalar type the numerical code is generic over: `f32` on the target, `f64` in the
/// reference runs of the tests.
///
/// Implemented for every [`nalgebra::RealField`] that is `Copy` (in practice `f32` and `f64`).
pub trait Real: nalgebra::RealField + Copy {}

impl<T: nalgebra::RealField + Copy> Real for T {}

/// The number of items of `items`, as [`Iterator::count`] but saturating: `count`'s sum keeps an
/// overflow check the optimizer cannot discharge (it cannot bound a slice's length), and a
/// count of items in memory never reaches `usize::MAX`.
#[inline]
pub(crate) fn count<I: Iterator>(items: I) -> usize {
    items.fold(0, |n, _| n.saturating_add(1))
}

/// The square root of `x`, correctly rounded (IEEE 754), as `libm::sqrtf`; NaN for `x < 0`.
///
/// With the nightly feature `fpu-sqrt` it is `core::f32::math::sqrt`, which LLVM lowers to the
/// FPU's instruction (`VSQRT.F32` on a Cortex-M4F, 14 cycles) where libm 0.2 runs a software
/// routine of about a hundred instructions. Both are correctly rounded: the same result bit for
/// bit.
#[inline]
pub(crate) fn sqrtf(x: f32) -> f32 {
    #[cfg(feature = "fpu-sqrt")]
    {
        core::f32::math::sqrt(x)
    }
    #[cfg(not(feature = "fpu-sqrt"))]
    {
        libm::sqrtf(x)
    }
}

/// Converts an `f64` constant into the scalar type `T` (exact for `f64`, rounded for `f32`).
#[inline]
pub(crate) fn real<T: Real>(value: f64) -> T {
    nalgebra::convert(value)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sqrtf_is_the_correctly_rounded_root() {
        // f64 holds the root of every f32 to 53 bits, so rounding it to f32 gives the correctly
        // rounded f32 root (53 ≥ 2·24 + 2: no double-rounding error). With or without the
        // feature `fpu-sqrt`, `sqrtf` must equal it bit for bit: the FPU's root and libm's.
        let reference = |x: f32| libm::sqrt(f64::from(x)) as f32;
        let sweep = (0..0x7f80_0000_u32).step_by(4099).map(f32::from_bits);
        let edges = [
            0.0,
            -0.0,
            f32::MIN_POSITIVE,
            1e-45,
            1.0,
            2.0,
            f32::MAX,
            f32::INFINITY,
        ];
        for x in sweep.chain(edges) {
            assert_eq!(sqrtf(x).to_bits(), reference(x).to_bits(), "sqrt({x:e})");
        }
        for x in [-1e-45, -1.0, f32::NEG_INFINITY, f32::NAN] {
            assert!(sqrtf(x).is_nan(), "sqrt({x}) must be NaN");
        }
    }
}
