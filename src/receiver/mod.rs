//! The attitude receiver: every estimator of the crate tied into the one type flight software
//! would use, [`AttitudeReceiver`].
//!
//! # Data path
//!
//! ```text
//!  tracking epochs ──► per-satellite single differences ──► window (100 ms) ──► cold start ──┐
//!  (prompts A, B, C     (counters, window sums, bit          │                (paper 002 +   │
//!   per satellite,       monitor; antenna power monitor)     │                 ambiguities)  │
//!   1 ms)                                                    ├──► ambiguity upkeep, slips    │
//!        │                                                   ├──► snapshot monitor (1 Hz)    │
//!        │                                                   └──► baselines + velocity       │
//!        │                                                        differences ──► rigid-body │
//!        │                                                        filter (paper 000)         │
//!        └──────────────► fine filter (paper 003, in the gyro frame) ◄── start ──────────────┘
//!  gyro increments ──► propagation (paper 001) ──► frame of the fine filter, coasting
//!                  └─► calibration against the fine attitude (paper 001) ──► bias correction
//! ```
//!
//! * **Inputs.** [`AttitudeReceiver::push_observation`]: per satellite and 1 ms epoch, the
//!   three antennas' prompt I/Q from one replica (a [`SatelliteObservation`] in any unit with
//!   its noise variance and C/N0), from the crate's software correlators and tracking channels
//!   or from a hardware correlator (on a Cortex-M4F the software correlators cannot keep up
//!   with one satellite in real time, see the README's signal budgets).
//!   [`AttitudeReceiver::push_gyro_increment`] / [`AttitudeReceiver::push_gyro_pulses`]: the
//!   gyro, in time order with the epochs. [`AttitudeReceiver::set_aiding`]: the lines of sight
//!   of the satellites, in the frame the attitude is wanted in, from the onboard navigation
//!   solution (receiver position and ephemeris; host-sim computes them from its truth orbit
//!   and the almanac). A line-of-sight error `δμ` enters the single differences as `bᵀδμ`:
//!   1e-4 rad on a 0.5 m baseline is 0.05 mm, far below the carrier-phase noise.
//! * **Output.** [`AttitudeReceiver::attitude`]: quaternion, DCM, 3-2-1 angles, the
//!   body-frame rotation-vector covariance, the [`AttitudeSource`] and [`ReceiverHealth`];
//!   per-stage estimates ([`AttitudeReceiver::fine_estimate`],
//!   [`AttitudeReceiver::snapshot_estimate`], [`AttitudeReceiver::rigid_body_estimate`]);
//!   [`ReceiverEvent`]s ([`AttitudeReceiver::pop_event`]) for what was detected and done.
//!
//! From raw samples, [`SampleReceiver`] owns the acquisition engine, the tracking channels
//! and the adapter in front of an `AttitudeReceiver` (see [`samples`]).
//!
//! # Stages
//!
//! 1. **Single differences** ([`satellite`]): `z_P z_A*` per epoch, a counter per baseline
//!    that keeps whole cycles, window sums (the window's SD and its rate).
//! 2. **Cold start**: when at least [`ReceiverConfig::min_cold_start_satellites`] satellites
//!    have clean windows, paper 002's snapshot solver with the constrained integer ambiguity
//!    resolution ([`crate::attitude::ambiguity`]) fixes the integers and gives the first
//!    attitude, or refuses (ratio or χ² test) and the next window tries again.
//! 3. **Fine attitude** ([`fine`]): paper 003's one-stage filter, started from the fix, in the
//!    frame the gyro propagates; locked, it is the receiver's attitude.
//! 4. **Ambiguity upkeep**: every window, each fixed single difference is compared with the
//!    fine attitude's prediction: a jump by whole cycles is a cycle slip and is repaired; a
//!    new satellite (rising, re-acquired) or an antenna back from a blockage gets its integers
//!    from the prediction.
//! 5. **Snapshot monitor**: every [`ReceiverConfig::snapshot_windows`] windows, the snapshot
//!    solver on the fixed single differences: an independent attitude, and the restart point
//!    of a fine filter that reports false lock.
//! 6. **Rigid-body filter** (paper 000): baselines `a_B`, `a_C` by least squares from the
//!    fixed window SDs, velocity differences from their rates (least squares over the
//!    satellites of the SD rates, i.e. inter-antenna Doppler differences), every window.
//! 7. **Gyro** ([`gyro_frame`]): propagation (paper 001 eq. (1.1)), the fine filter's frame,
//!    coasting while the fine filter has no usable input, and bias calibration by paper 001's
//!    sequential least squares against the locked fine attitude, one window of
//!    [`GyroConfig::calibration_window_s`] after another.
//!
//! # Faults
//!
//! Satellites that set stop delivering epochs and lose their slot; rising ones are fixed from
//! the fine attitude. A blocked antenna is detected from its signal power within
//! tens of milliseconds and left out: the fine filter predicts and the gyro carries the
//! attitude; when the antenna returns its single differences are re-fixed from the attitude.
//! Cycle slips are repaired as above. The data-bit monitor flags a sign change of the
//! reference prompt away from the bit edges; the fine filter averages the data bit out of
//! every epoch (paper 003, eq. (15)), so such a flip costs at most one epoch's information.
//!
//! # Memory and time
//!
//! Fixed size (7 224 B on the Cortex-M4F; twelve satellite slots, two epoch buffers, the
//! stages). Per epoch: the fine filter's step dominates (see the README's budgets); per window: the least squares,
//! the snapshot solver or the ambiguity search at the cold start (bounded by the resolver's
//! node budget).

mod antenna;
mod carrier;
mod config;
pub mod example;
pub mod fine;
pub mod gyro_frame;
mod output;
#[allow(clippy::module_inception)]
mod receiver;
pub mod samples;
pub mod satellite;
mod window;

#[cfg(test)]
mod tests;

pub use config::{ConfigError, GyroConfig, ReceiverConfig};
pub use fine::FINE_STATES;
pub use gyro_frame::{BiasCalibrator, CalibrationReport, NoReferenceDrift};
pub use output::{AttitudeSource, ReceiverAttitude, ReceiverEvent, ReceiverHealth, StageEstimate};
pub use receiver::{AttitudeReceiver, ReceiverError, EVENT_QUEUE};
pub use samples::{ChannelStatus, SampleFrontConfig, SampleReceiver, SampleReport};
pub use satellite::SatelliteAiding;

#[cfg(doc)]
use crate::attitude::one_stage::SatelliteObservation;

/// Satellites the receiver tracks at once (its slots).
pub const MAX_SATELLITES: usize = 12;
