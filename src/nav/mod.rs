//! The receiver's own navigation: the GPS LNAV message, ephemerides, time, pseudoranges, a
//! position/velocity/clock fix, a LEO orbit filter, and the lines of sight the attitude
//! stages need.
//!
//! # Data path
//!
//! ```text
//!  1 ms prompt I ──► bits (bit sync: histogram of sign changes over 20 phases) ──► subframes
//!  (per channel)      (sum over 20 ms)                 (preamble, parity D29*/D30*, HOW/TOW)
//!                                                              │            │
//!                       ChannelDecoder::anchor (TOW at a code period) ◄─────┘
//!                                │                             ▼
//!  code phase, code-period count ┴──► TransmitTime ──► pseudorange   NavigationStore
//!                                                         │        (ephemeris per PRN,
//!                                                         ▼         almanac, iono, UTC)
//!                     solution::solve (LS, Sagnac, iono/tropo, DOP, RAIM) ◄──┘
//!                                │
//!                                ▼
//!                     filter::OrbitFilter (2-body + J2, EKF)  ──► los::line_of_sight
//!                                                                 (ECEF, inertial, NED)
//! ```
//!
//! | Module | What it does |
//! |---|---|
//! | [`bits`] | Bit synchronization from 1 ms prompts, bits from summed prompts |
//! | [`parity`] | IS-GPS-200 word parity (Table 20-XIV), both polarities |
//! | [`subframe`] | Preamble search, ten-word parity, HOW (TOW, subframe id) |
//! | [`message`] | Subframes 1–3 (clock, ephemeris), 4/5 almanac pages, page 18 (Klobuchar, UTC) |
//! | [`store`] | Newest consistent, plausible ephemeris per PRN; counters |
//! | [`decoder`] | One channel's decoder and its time anchor |
//! | [`ephemeris`] | The user algorithm: satellite position, velocity, clock |
//! | [`pseudorange`] | Time of transmission from a channel's counts, pseudorange |
//! | [`solution`] | Single-point position, velocity, clock; DOP; residual check |
//! | [`atmosphere`] | Klobuchar ionosphere, a simple troposphere (ground users) |
//! | [`filter`] | LEO position/velocity filter between and through fixes |
//! | [`los`] | Lines of sight and their rates in the attitude's reference frame |
//! | [`geodesy`] | WGS-84 ECEF ↔ geodetic, NED, elevation and azimuth |
//! | [`time`] | GPS week and time of week |
//! | [`example`] | A deterministic constellation, its subframes and observations (budgets, tests) |
//!
//! # Precision (f32 where it holds, f64 where it cannot)
//!
//! | Quantity | Type | Why |
//! |---|---|---|
//! | Times of week, times of transmission | f64 | 6·10⁵ s to 10⁻¹⁰ s |
//! | Satellite and receiver positions, ranges, pseudoranges, clock bias | f64 | 2.6·10⁷ m to 1 cm |
//! | Ephemeris fields, Kepler's equation, the user algorithm | f64 | 32-bit fields at 2⁻³¹ semicircles |
//! | Residuals, design matrix, normal equations, DOP | f32 | metres and unit vectors |
//! | Velocity, clock drift, Doppler | f32 | km/s to mm/s |
//! | Ionosphere, troposphere | f32 | metres to cm |
//! | LEO filter: nominal state / error state, covariance | f64 / f32 | |
//! | Lines of sight and rates | f32 | 10⁻⁷ rad |
//!
//! # Not done here
//!
//! `AttitudeReceiver` does not run this itself: its caller does, and hands the lines of sight
//! to `set_aiding` (host-sim's `track` from a recording's channels, the microsat scenario in
//! flight). No carrier-smoothed pseudoranges, no RINEX output (host-sim's job), no L2/L5 or
//! CNAV, no GPS–UTC conversion beyond decoding the parameters,
//! no almanac-based orbit computation (the almanac is decoded and stored only).

pub mod atmosphere;
pub mod bits;
pub mod decoder;
pub mod ephemeris;
pub mod example;
pub mod filter;
pub mod geodesy;
pub mod los;
pub mod message;
pub mod parity;
pub mod pseudorange;
pub mod solution;
pub mod store;
pub mod subframe;
pub mod time;

#[cfg(test)]
mod tests;

pub use bits::{BitDecoder, BitSyncConfig, DataBit};
pub use decoder::{ChannelDecoder, TimeAnchor};
pub use ephemeris::{Ephemeris, PlausibilityLimits, SatelliteState};
pub use filter::{NavState, OrbitFilter, OrbitFilterConfig};
pub use los::{line_of_sight, LineOfSight, ReferenceFrame};
pub use pseudorange::{pseudorange_m, TransmitTime};
pub use solution::{solve, Fix, Observation, SolverConfig};
pub use store::{NavigationStore, StoreConfig};
pub use subframe::{Subframe, SubframeSync};
pub use time::GpsTime;

/// IS-GPS-200's value of π for the conversion of semicircles (20.3.3.3.3.1).
// Deliberately not `core::f64::consts::PI`: the interface specification fixes this value.
#[allow(clippy::approx_constant)]
pub const GPS_PI: f64 = 3.141_592_653_589_8;
/// WGS-84 gravitational constant of IS-GPS-200, m³/s².
pub const MU_GPS: f64 = 3.986_005e14;
/// WGS-84 Earth rotation rate, rad/s.
pub const OMEGA_EARTH: f64 = 7.292_115_146_7e-5;
/// Speed of light, m/s.
pub const SPEED_OF_LIGHT: f64 = 299_792_458.0;
/// Relativistic constant `F = −2√μ/c²`, s/√m (IS-GPS-200 20.3.3.3.3.1).
pub const F_RELATIVISTIC: f64 = -4.442_807_633e-10;
/// Seconds per GPS week.
pub const WEEK_S: f64 = 604_800.0;
/// Half a week, s.
pub const HALF_WEEK_S: f64 = 302_400.0;
/// Seconds per LNAV subframe.
pub const SUBFRAME_S: f64 = 6.0;
/// GPS L1 wavelength, m.
pub const L1_WAVELENGTH_M: f64 = SPEED_OF_LIGHT / crate::signal::ca_code::GPS_L1_HZ;
