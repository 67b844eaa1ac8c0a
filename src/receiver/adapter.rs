//! From the signal chain to the filter: [`TrackingEpoch`]s of the three-antenna tracking
//! channels → [`SatelliteObservation`]s, and the epoch grid the filter steps on.
//!
//! # Conventions (verified on synthesized samples by `tests/one_stage_samples.rs`)
//!
//! * **Antennas.** Correlator input `k` of a [`TrackingEpoch<3>`] is the `k`-th antenna of the
//!   [`SampleBlock`](crate::signal::SampleBlock); [`AntennaMapping::inputs`] says which input
//!   is A, B and C of the [`AntennaArray`](crate::attitude::array::AntennaArray) (default: 0, 1, 2, with A the
//!   reference antenna whose loops drive the replica).
//! * **Sign of Q.** The crate's correlator computes `Σ x_k e^{−jφ_k}` with the replica phase
//!   `φ_k`; a front end without spectral inversion delivers `x ∝ e^{+jΦ_P}` with the carrier
//!   phase `Φ_P` of antenna P, which leads by `ψ_P = k μᵀ U r_P` when P is nearer the
//!   satellite. Its prompts are therefore `Z_P ∝ e^{+j(ψ_P + φ)}`, the filter's convention
//!   ([`QuadratureSign::Receiver`]). A spectrally inverted front end (tracked with a negative
//!   IF) gives the conjugate: [`QuadratureSign::Conjugate`] negates Q.
//! * **Scale.** The filter's likelihood assumes the three antennas have the same SNR, so each
//!   antenna's prompt is divided by its own noise standard deviation, taken from the noise taps
//!   of every channel (a running mean pooled over the satellites, [`NoiseFloor`]); the
//!   observation is then in noise units (`noise_var = 1`). Antennas without a noise tap
//!   ([`SlaveTaps::Prompt`](crate::signal::SlaveTaps::Prompt)) borrow the reference antenna's.
//! * **C/N0 and lock.** The channel's C/N0 estimate is passed on; epochs of channels that are
//!   not [`ChannelState::Tracking`] with code and phase lock, or below
//!   [`AdapterConfig::min_cn0_dbhz`], give no observation (the filter assumes the Doppler is
//!   tracked).
//!
//! # The epoch grid
//!
//! Each channel's code periods start at its own sample, so the receiver groups them:
//! [`EpochClock::epoch_of`] puts a tracking epoch into filter epoch `k` when its middle sample
//! lies within half an epoch of `origin + k·samples_per_epoch`. The receiver steps the filter
//! once per filter epoch, with whatever observations that epoch collected; a filter epoch with
//! none (a gap in the samples, every channel unlocked) is stepped with an empty slice, which
//! only predicts. A channel whose code period drifts (Doppler) occasionally puts two epochs
//! into one filter epoch or none: both are fine (independent observations, or a missing one).
//!
//! # Front-end re-lock
//!
//! A front end whose synthesizer re-locks changes the antennas' line biases (and possibly their
//! gains): call [`OneStageFilter::reopen_line_biases`](crate::attitude::one_stage::OneStageFilter::reopen_line_biases)
//! and [`ObservationAdapter::reset_noise`].

use crate::attitude::one_stage::OneStageError;
use crate::signal::correlator::Iq;
use crate::signal::EpochCorrelations;
use crate::tracking::{ChannelState, TrackingEpoch};

use crate::attitude::one_stage::PromptIq;
use crate::attitude::one_stage::SatelliteObservation;

/// Sign of the chain's quadrature component relative to the filter's `Z ∝ e^{+jφ}`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum QuadratureSign {
    /// The crate's correlator on a front end without spectral inversion: Q as is.
    #[default]
    Receiver,
    /// A spectrally inverted front end (or a correlator computing `x e^{+jφ}`): Q negated.
    Conjugate,
}

/// Which correlator input is which antenna, and the sign of Q.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AntennaMapping {
    /// Correlator input (antenna index of [`TrackingEpoch::correlations`]) of antennas A, B, C.
    /// A permutation of 0, 1, 2.
    pub inputs: [usize; 3],
    /// Sign of Q.
    pub quadrature: QuadratureSign,
}

impl Default for AntennaMapping {
    fn default() -> Self {
        Self {
            inputs: [0, 1, 2],
            quadrature: QuadratureSign::Receiver,
        }
    }
}

impl AntennaMapping {
    fn is_valid(&self) -> bool {
        let [a, b, c] = self.inputs;
        a < 3 && b < 3 && c < 3 && a != b && b != c && a != c
    }
}

/// One tracked epoch as a filter observation: the prompts of A, B, C (by `mapping`) divided by
/// the noise standard deviation of their correlator input (`noise_variance`, counts², per
/// input, one component), Q's sign fixed, `noise_var = 1`, the channel's C/N0, `id` = PRN, and
/// the line of sight `los` (unit vector from the array to the satellite, reference frame).
/// Does not look at the lock flags (see [`ObservationAdapter::observe`]).
///
/// # Errors
/// [`OneStageError::InvalidConfig`] for a mapping that is not a permutation of 0, 1, 2;
/// [`OneStageError::NonFiniteInput`] for a non-finite `los`, noise variance or C/N0;
/// [`OneStageError::InvalidObservation`] for a noise variance that is not positive, a C/N0
/// outside `0..=90` dB-Hz or a line of sight whose length is off 1 by more than 1e-3.
pub fn observation_from_epoch(
    epoch: &TrackingEpoch<3>,
    los: [f32; 3],
    noise_variance: [f32; 3],
    mapping: &AntennaMapping,
) -> Result<SatelliteObservation<f32>, OneStageError> {
    if !mapping.is_valid() {
        return Err(OneStageError::InvalidConfig);
    }
    let finite = los
        .iter()
        .chain(noise_variance.iter())
        .chain(core::iter::once(&epoch.cn0_dbhz))
        .all(|v| v.is_finite());
    if !finite {
        return Err(OneStageError::NonFiniteInput);
    }
    let [x, y, z] = los;
    let norm2 = x * x + y * y + z * z;
    let usable = noise_variance.iter().all(|&v| v > 0.0)
        && (0.0..=90.0).contains(&epoch.cn0_dbhz)
        && (norm2 - 1.0).abs() <= 2e-3;
    if !usable {
        return Err(OneStageError::InvalidObservation);
    }
    let q_sign = match mapping.quadrature {
        QuadratureSign::Receiver => 1.0,
        QuadratureSign::Conjugate => -1.0,
    };
    let mut prompt = PromptIq::<f32>::default();
    for (p, &input) in (0..mapping.inputs.len()).zip(mapping.inputs.iter()) {
        let (Some(taps), Some(&var)) = (
            epoch.correlations.taps.get(input),
            noise_variance.get(input),
        ) else {
            return Err(OneStageError::InvalidConfig);
        };
        // z_P = Z_P / σ_P: equal noise on every antenna (module docs, "Scale")
        let inv_sigma = 1.0 / crate::sqrtf(var);
        if let (Some(i), Some(q)) = (prompt.i.get_mut(p), prompt.q.get_mut(p)) {
            *i = taps.prompt.i as f32 * inv_sigma;
            *q = q_sign * taps.prompt.q as f32 * inv_sigma;
        }
    }
    Ok(SatelliteObservation {
        id: epoch.prn.number(),
        los,
        prompt,
        noise_var: 1.0,
        cn0_dbhz: epoch.cn0_dbhz,
    })
}

/// Running noise variance of one component of each correlator input, from the noise taps
/// (`(I_N² + Q_N²)/2`) of every channel: a mean over the first `time_constant` taps, then an
/// exponential average with that time constant (in taps). A tap reading exactly zero (a slaved
/// antenna without a noise tap) is skipped.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NoiseFloor {
    mean: [f32; 3],
    taps: [u32; 3],
    time_constant: u32,
}

impl NoiseFloor {
    /// An empty estimate averaging over `time_constant` taps per input (at least 1).
    pub fn new(time_constant: u32) -> Self {
        Self {
            mean: [0.0; 3],
            taps: [0; 3],
            time_constant: time_constant.max(1),
        }
    }

    /// Adds the noise taps of one epoch.
    pub fn add(&mut self, correlations: &EpochCorrelations<3>) {
        let inputs = self.mean.iter_mut().zip(self.taps.iter_mut());
        for ((mean, taps), tap) in inputs.zip(correlations.taps.iter()) {
            let Iq { i, q } = tap.noise;
            if i == 0 && q == 0 {
                continue;
            }
            let (i, q) = (i as f32, q as f32);
            *taps = taps.saturating_add(1);
            let gain = 1.0 / (*taps).min(self.time_constant) as f32;
            *mean += gain * (0.5 * (i * i + q * q) - *mean);
        }
    }

    /// The variance of one component per correlator input, counts², once every input has
    /// `min_taps` taps (inputs that never had one take input 0's); `None` before.
    pub fn variance(&self, min_taps: u32) -> Option<[f32; 3]> {
        let [m0, m1, m2] = self.mean;
        let [t0, t1, t2] = self.taps;
        if t0 < min_taps.max(1) {
            return None;
        }
        let pick = |m: f32, t: u32| match t {
            0 => Some(m0),
            t if t >= min_taps => Some(m),
            _ => None,
        };
        Some([m0, pick(m1, t1)?, pick(m2, t2)?])
    }
}

/// Settings of [`ObservationAdapter`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AdapterConfig {
    /// Antenna order and Q sign.
    pub mapping: AntennaMapping,
    /// Time constant of the noise-floor average, taps (pooled over channels).
    pub noise_time_constant: u32,
    /// Noise taps per input before the first observation.
    pub noise_min_taps: u32,
    /// Lowest C/N0 passed to the filter, dB-Hz.
    pub min_cn0_dbhz: f32,
}

impl Default for AdapterConfig {
    /// Mapping 0, 1, 2 with Q as is, noise averaged over 2000 taps (0.25 s of 8 channels) after
    /// at least 200, C/N0 from 25 dB-Hz.
    fn default() -> Self {
        Self {
            mapping: AntennaMapping::default(),
            noise_time_constant: 2000,
            noise_min_taps: 200,
            min_cn0_dbhz: 25.0,
        }
    }
}

/// The stateful adapter a receiver runs: feeds every tracking epoch's noise taps into the
/// [`NoiseFloor`] and turns the usable ones into observations.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ObservationAdapter {
    config: AdapterConfig,
    noise: NoiseFloor,
}

impl ObservationAdapter {
    /// An adapter with an empty noise floor.
    ///
    /// # Errors
    /// [`OneStageError::InvalidConfig`] for a mapping that is not a permutation of 0, 1, 2 or a
    /// C/N0 threshold that is not finite.
    pub fn new(config: AdapterConfig) -> Result<Self, OneStageError> {
        if !config.mapping.is_valid() || !config.min_cn0_dbhz.is_finite() {
            return Err(OneStageError::InvalidConfig);
        }
        Ok(Self {
            noise: NoiseFloor::new(config.noise_time_constant),
            config,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &AdapterConfig {
        &self.config
    }

    /// The noise floor.
    pub fn noise(&self) -> &NoiseFloor {
        &self.noise
    }

    /// Forgets the noise floor (after a front-end gain change or re-lock).
    pub fn reset_noise(&mut self) {
        self.noise = NoiseFloor::new(self.config.noise_time_constant);
    }

    /// Takes one tracking epoch (every channel's, locked or not, complete code periods only)
    /// with its satellite's line of sight `los` (unit vector, reference frame): its noise taps
    /// update the noise floor; it yields an observation when the channel tracks with code and
    /// phase lock at or above the C/N0 threshold and the noise floor is ready.
    ///
    /// # Errors
    /// As [`observation_from_epoch`] for a usable epoch; the adapter is then unchanged.
    pub fn observe(
        &mut self,
        epoch: &TrackingEpoch<3>,
        los: [f32; 3],
    ) -> Result<Option<SatelliteObservation<f32>>, OneStageError> {
        if !epoch.correlations.complete {
            return Ok(None);
        }
        let mut noise = self.noise;
        noise.add(&epoch.correlations);
        let usable = epoch.state == ChannelState::Tracking
            && epoch.lock.code
            && epoch.lock.phase
            && epoch.cn0_dbhz >= self.config.min_cn0_dbhz;
        let out = match noise.variance(self.config.noise_min_taps) {
            Some(var) if usable => Some(observation_from_epoch(
                epoch,
                los,
                var,
                &self.config.mapping,
            )?),
            _ => None,
        };
        self.noise = noise;
        Ok(out)
    }
}

/// The filter's epoch grid in receiver samples: filter epoch `k` is centred on sample
/// `origin + k · samples_per_epoch`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EpochClock {
    origin: u64,
    samples_per_epoch: u32,
}

impl EpochClock {
    /// A grid starting at receiver sample `origin` with `samples_per_epoch` samples per filter
    /// epoch (the filter's `T` times the sample rate: 2600 for 1 ms at 2.6 Msps).
    ///
    /// # Errors
    /// [`OneStageError::InvalidConfig`] for zero samples per epoch.
    pub fn new(origin: u64, samples_per_epoch: u32) -> Result<Self, OneStageError> {
        if samples_per_epoch == 0 {
            return Err(OneStageError::InvalidConfig);
        }
        Ok(Self {
            origin,
            samples_per_epoch,
        })
    }

    /// The filter epoch a tracking epoch belongs to: `round((m − origin)/samples_per_epoch)`
    /// with `m` its middle sample; `None` when that is before epoch 0.
    pub fn epoch_of(&self, correlations: &EpochCorrelations<3>) -> Option<u64> {
        // 2m − 2 origin + n, all doubled so that the middle and the rounding stay integers
        let twice_mid =
            u128::from(correlations.first_sample) * 2 + u128::from(correlations.samples);
        let n = u128::from(self.samples_per_epoch);
        let shifted = (twice_mid + n).checked_sub(u128::from(self.origin) * 2)?;
        // n > 0 by construction; checked so that no division-by-zero path is compiled in.
        // (in 32-bit steps when the dividend fits 64 bits, as it does for 2⁶³ samples: the
        // u128 division is a library call of hundreds of instructions on the M4F, the u64 one
        // of about 150, every channel epoch)
        let quotient = match u64::try_from(shifted) {
            Ok(s) => u128::from(div_by_digits(s, u64::try_from(2 * n).ok()?)?),
            Err(_) => shifted.checked_div(2 * n)?,
        };
        u64::try_from(quotient).ok()
    }

    /// The receiver sample at the centre of filter epoch `k` (saturating).
    pub fn sample_of(&self, k: u64) -> u64 {
        self.origin
            .saturating_add(k.saturating_mul(u64::from(self.samples_per_epoch)))
    }
}

/// `⌊x/d⌋` (`None` for `d = 0`): for `d < 2¹⁶` (an epoch of up to 32 767 samples, doubled)
/// a long division in 16-bit digits, four 32-bit divisions that the Cortex-M4 does in
/// hardware; otherwise the 64-bit division.
fn div_by_digits(x: u64, d: u64) -> Option<u64> {
    let Ok(d16) = u16::try_from(d) else {
        return x.checked_div(d);
    };
    let d32 = u32::from(d16);
    let mut quotient = 0u64;
    let mut remainder = 0u32;
    for shift in [48u32, 32, 16, 0] {
        // remainder < d < 2¹⁶: the partial dividend fits 32 bits, its quotient 16
        let partial = (remainder << 16) | ((x >> shift) as u32 & 0xffff);
        let digit = partial.checked_div(d32)?;
        remainder = partial.wrapping_sub(digit.wrapping_mul(d32));
        quotient = (quotient << 16) | u64::from(digit);
    }
    Some(quotient)
}
