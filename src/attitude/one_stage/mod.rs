//! Paper 003 (Perov): the one-stage coherent–noncoherent filter of the attitude angles,
//! straight from the three antennas' prompt I/Q.
//!
//! There is no phase-tracking loop per antenna pair and no integer-ambiguity search: the
//! filter climbs the likelihood of the attitude given all antennas' correlator outputs,
//! `F = Σ_i ln I₀(a X_i(α))` (eq. (15)), in which the common carrier phase and the data bit of
//! each satellite are averaged out, so that only the phase *differences* between the antennas,
//! `ψ_{P,i}(α) = (2π/λ) μ_iᵀ U(α) r_P`, carry information.
//!
//! # Data path, one epoch (1 ms)
//!
//! | Step | Paper | Here |
//! |---|---|---|
//! | Rotation `U(α) = R_z(γ) R_y(β) R_x'(α)` | (2) | [`crate::geometry::Paper003Angles`], [`paper003_partials`] |
//! | Antenna phases `ψ_{P,i}`, Jacobian `∂Ψ/∂α` | (4), (24)–(28) | [`AntennaArray`](crate::attitude::array::AntennaArray), [`PhaseModel`] |
//! | Coherent sum and `X_i²` | (18), (20) | [`coherent_sum`], [`satellite_terms`] |
//! | Phase discriminators `(I₁/I₀)(aX) a ∂X/∂ψ` | (22), (23) | [`satellite_terms`], [`BesselRatio`] |
//! | Angle discriminator `u_α = (∂Ψ/∂α)ᵀ u_ψ` | (32) | [`EpochInformation::gradient`] |
//! | Prediction `X̃ = F X̂`, `D̃ = F D Fᵀ + G D_ξ Gᵀ` | (7)–(8), (10)–(11) | [`OneStageFilter::step`] |
//! | Update, Gaussian approximation: `D⁻¹ = D̃⁻¹ − ∂²F/∂X∂Xᵀ`, `X̂ = X̃ + D cᵀ u` | (9), (12) corrected | [`FilterMode::GaussianApproximation`] |
//! | Update, constant gains on `u/J_T` | simulation section; spec (a) | [`FilterMode::ConstantGain`] |
//! | Pull-in / false-lock verdict | — (added) | [`LockDetector`], [`LockStatus`] |
//!
//! Input: [`SatelliteObservation`] per tracked satellite (line of sight in the reference frame,
//! prompt I/Q of A, B, C, noise variance, C/N0); at most [`MAX_SATELLITES`] per epoch.
//! Output: the angles α, β, γ (hence `C_rb`), their rates, optional line biases `b_B`, `b_C`,
//! the covariance (Gaussian mode) and an [`EpochReport`] with the lock verdict.
//!
//! # From the signal chain (samples → attitude)
//!
//! The receiver's adapter ([`crate::receiver::ObservationAdapter`]) turns the tracking
//! channels' [`TrackingEpoch`](crate::tracking::TrackingEpoch)s into observations (antenna
//! mapping, sign of Q, per-antenna noise normalization from the noise taps, lock and C/N0
//! gating) and groups them into filter epochs ([`crate::receiver::EpochClock`]). A cold start averages the inter-antenna phases ([`PhaseDifferences`]),
//! solves them with the snapshot solver's ambiguity resolver and starts from
//! [`Prior::from_snapshot`]. Per receiver:
//!
//! ```text
//! let mut adapter = ObservationAdapter::new(AdapterConfig::default())?;
//! let clock = EpochClock::new(first_sample, samples_per_ms)?;
//! // every TrackingEpoch e of every channel, with its satellite's line of sight:
//! if let Some(obs) = adapter.observe(&e, los)? { epochs[clock.epoch_of(&e.correlations)?].push(obs) }
//! // once per filter epoch k, in order (empty when nothing arrived):
//! let report = filter.step(&epochs[k])?;  // use filter.attitude() when report.status == Locked
//! ```
//!
//! # The two update forms
//!
//! * **Gaussian approximation** (eqs. (9)–(12)). The information update uses the observed
//!   curvature `−∂²F`; per satellite it is floored in the phase-difference plane at `κ` times
//!   its expected value `2q_T` ([`OneStageConfig::curvature_floor`]), which keeps `D_X⁻¹`
//!   positive definite and bounds the step far from the peak, where the curvature is small or
//!   negative. Its process noise is scheduled so that its steady state is the loop of
//!   bandwidth `Δf` ([`ProcessNoise::Bandwidth`]), or fixed (`D_ξ` of eq. (7)).
//! * **Constant gains**. The paper's simulated tracker: `u_n = J_T⁻¹ u` with the expected slope
//!   `J_T = Σ_i 2q_T G_iᵀ Π G_i`, then `K1 = √2 ω_n T`, `K2 = ω_n² T`, `ω_n = Δf/0.53`.
//!
//! Both sit at the loop-limited bound `σ = √(2Δf/J_β)` in steady state (the steady-state
//! Kalman filter of this model *is* a second-order loop with `ζ = 1/√2`); host-sim's
//! `one-stage` scenario measures 0.707′ and 0.706′ against 0.694′ for the paper's case.
//! **The Gaussian approximation is the default** ([`FilterMode::default`]) because it is the
//! better filter everywhere except cost: it starts from the prior's covariance, so it pulls in
//! from a 5° error in under 0.1 s where a 2 Hz constant-gain loop needs about 2 s to settle
//! (and is flagged by the lock detector meanwhile); it learns line biases with decreasing gains
//! (`σ_β` +4 % against +134 % for a 0.05 Hz constant-gain bias loop over the same minute); it
//! weighs each satellite by its observed curvature and reports a covariance for whatever
//! fuses the attitude next. It costs about twice the instructions of the constant-gain loop
//! (56 k against 25 k per 1 ms epoch with 12 satellites and every state, Cortex-M4F).
//!
//! # State dimension
//!
//! The state holds only what is estimated ([`StateLayout`]); its dimension `N` is a const
//! generic of [`OneStageFilter`]: 2 for the paper's β-only filter `[β, β̇]`, 4 with line
//! biases, 6 for three angles, 8 for three angles and biases (the default).
//!
//! # Line biases
//!
//! Real RF channels add a constant phase `b_P` per antenna. A common part is absorbed by the
//! common carrier phase; the differences `b_B − b_A`, `b_C − b_A` bias the attitude directly
//! unless they are estimated ([`OneStageConfig::line_bias_states`]). Estimating them costs
//! accuracy: per epoch the biases and β share information (for G1 only 15 % of β's
//! information is independent of the biases), which the filter recovers over time because the
//! biases are constant while the attitude moves.

pub mod bessel;
mod cold_start;
mod config;
pub mod discriminator;
mod filter;
mod information;
mod input;
mod layout;
pub mod lock;
mod phase;
mod prior;
mod trig;
mod update;

#[cfg(test)]
mod tests;

pub use bessel::BesselRatio;
pub use cold_start::PhaseDifferences;
pub use config::{EstimatedAngles, FilterMode, OneStageConfig, ProcessNoise, GPS_L1_WAVELENGTH_M};
pub use discriminator::{
    coherent_sum, difference_basis, floored_plane_curvature, satellite_terms, PromptIq,
    SatelliteTerms,
};
pub use filter::{EpochReport, OneStageError, OneStageFilter};
pub use information::{EpochInformation, PARAMETERS};
pub use input::{SatelliteObservation, MAX_SATELLITES};
pub use layout::StateLayout;
pub use lock::{LockConfig, LockDetector, LockStatus};
pub use phase::{paper003_partials, PhaseModel};
pub use prior::Prior;
