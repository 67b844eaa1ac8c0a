//! The one-stage filter on `X = [α; α̇]` (plus optional line biases): prediction (7)/(10) and
//! the per-epoch discriminators; the two update forms are in `update.rs`.

use nalgebra::{Matrix3, SMatrix, SVector, Vector2, Vector3};

use crate::ekf::Ekf;
use crate::geometry::Paper003Angles;
use crate::Real;

use super::config::{FilterMode, OneStageConfig};
use super::information::{epoch_information, EpochInformation, PARAMETERS};
use super::input::{CheckedObservation, SatelliteObservation, MAX_SATELLITES};
use super::layout::StateLayout;
use super::lock::{LockDetector, LockStatus};
use super::phase::PhaseModel;
use super::prior::Prior;
use crate::attitude::array::AntennaArray;
use crate::attitude::array::ArrayError;
use crate::ekf::FilterError;
use crate::error::{Error, ErrorKind};
use crate::geometry::wrap_angle as wrap;
use crate::geometry::GeometryError;
use crate::linalg::regularized_solve;

/// What one epoch did.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EpochReport<T = f32> {
    /// Satellites used.
    pub satellites: u8,
    /// The lock detector's verdict after this epoch. Use the attitude only when `Locked`.
    pub status: LockStatus,
    /// Smoothed alignment `η̄` (1 at the true peak, see [`super::lock`]).
    pub alignment: T,
    /// The lock detector's settle statistic `s` (χ² scale, see [`super::lock`]).
    pub settle_statistic: T,
    /// The angle discriminator `u_α` of eq. (32) at the predicted state, 1/rad (α, β, γ;
    /// zero for angles not estimated).
    pub angle_discriminator: [T; 3],
    /// The correction the update applied to the angles, rad.
    pub angle_step: [T; 3],
    /// Satellites whose observed curvature needed the floor.
    pub curvature_floored: u8,
}

/// The one-stage coherent–noncoherent attitude filter of paper 003.
///
/// Every epoch it takes the prompt I/Q of the three antennas for each tracked satellite
/// ([`SatelliteObservation`]) and moves the attitude angles (eq. (2)), their rates and the
/// optional line biases so as to climb the likelihood `Σ_i ln I₀(a X_i)` of eq. (15), in which
/// the common carrier phase and the data bit are averaged out. No per-satellite state is
/// kept: satellites may appear and disappear from one epoch to the next.
///
/// `N` is the state dimension, `2 × (estimated angles) + 2 × (line biases on)`: 2 for the
/// paper's β-only filter `[β, β̇]`, 4 with line biases, 6 for three angles, 8 for everything
/// (`[α, β, γ, α̇, β̇, γ̇, b_B, b_C]`, the default); see [`StateLayout`]. Angles not estimated
/// are held at their prior values. Angles are wrapped to `(−π, π]`.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OneStageFilter<T = f32, const N: usize = 8> {
    pub(super) config: OneStageConfig<T>,
    pub(super) array: AntennaArray<T>,
    pub(super) layout: StateLayout<T, N>,
    /// Values of the angles that are not estimated, rad.
    pub(super) held: [T; 3],
    pub(super) ekf: Ekf<N, T>,
    pub(super) lock: LockDetector<T>,
    /// Last scheduled process-noise densities per parameter (Gaussian mode), kept for epochs
    /// without information.
    pub(super) scheduled_psd: [T; PARAMETERS],
}

impl<T: Real, const N: usize> OneStageFilter<T, N> {
    /// A filter for `array` started from `prior`.
    ///
    /// # Errors
    /// [`OneStageError::InvalidConfig`] when [`OneStageConfig::is_valid`] fails or `N` is not
    /// the dimension the configuration needs ([`OneStageConfig::state_dimension`]);
    /// [`OneStageError::DegenerateArray`] when the antennas span no plane
    /// ([`AntennaArray::check_spans_plane`]); the errors of the prior
    /// ([`OneStageError::NonFiniteInput`], [`OneStageError::InvalidCovariance`]).
    pub fn new(
        config: OneStageConfig<T>,
        array: AntennaArray<T>,
        prior: &Prior<T>,
    ) -> Result<Self, OneStageError> {
        let layout = match StateLayout::of(&config) {
            Some(layout) if config.is_valid() => layout,
            _ => return Err(OneStageError::InvalidConfig),
        };
        array.check_spans_plane()?;
        let (ekf, held) = Self::initial_state(&layout, prior, config.line_bias_states)?;
        Ok(Self {
            lock: LockDetector::new(&config.lock, config.epoch_s),
            config,
            array,
            layout,
            held,
            ekf,
            scheduled_psd: [T::zero(); PARAMETERS],
        })
    }

    /// Restarts from a new prior (a snapshot solution, or the caller's after a false lock),
    /// keeping the configuration; the lock detector returns to pull-in.
    ///
    /// # Errors
    /// As [`Self::new`] for the prior; the filter is then unchanged.
    pub fn reinitialize(&mut self, prior: &Prior<T>) -> Result<(), OneStageError> {
        let (ekf, held) = Self::initial_state(&self.layout, prior, self.config.line_bias_states)?;
        self.ekf = ekf;
        self.held = held;
        self.lock.restart();
        Ok(())
    }

    /// Forgets what the filter knows about the line biases (after the front end re-locked and
    /// the inter-channel phases jumped), keeping the attitude and its rates: the bias states'
    /// covariance rows and columns are cleared and their variances set to `variance` (rad²).
    /// The constant-gain loop has no covariance; its bias loop re-converges by itself. A
    /// filter without bias states is left as it is.
    ///
    /// # Errors
    /// [`OneStageError::NonFiniteInput`], [`OneStageError::InvalidCovariance`] for a variance
    /// that is not positive; the filter is then unchanged.
    pub fn reopen_line_biases(&mut self, variance: T) -> Result<(), OneStageError> {
        if !variance.is_finite() {
            return Err(OneStageError::NonFiniteInput);
        }
        if !(variance > T::zero()) {
            return Err(OneStageError::InvalidCovariance);
        }
        // P ← K P K + v S_bᵀS_b with K = I − S_bᵀS_b: the bias rows and columns cleared
        let sb = self.layout.biases.transpose() * self.layout.biases;
        let keep = SMatrix::<T, N, N>::identity() - sb;
        let p = keep * self.ekf.covariance() * keep + sb * variance;
        self.ekf.set_covariance(p).map_err(OneStageError::from)
    }

    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    fn initial_state(
        layout: &StateLayout<T, N>,
        prior: &Prior<T>,
        with_bias: bool,
    ) -> Result<(Ekf<N, T>, [T; 3]), OneStageError> {
        prior.check(with_bias)?;
        let a = [prior.angles.alpha, prior.angles.beta, prior.angles.gamma].map(wrap);
        let (sa, sr, sb) = (&layout.angles, &layout.rates, &layout.biases);
        let x = sa.transpose() * Vector3::from(a)
            + sr.transpose() * prior.rates
            + sb.transpose() * Vector2::from(prior.line_bias);
        let p = sa.transpose() * prior.angle_covariance * sa
            + sr.transpose() * prior.rate_covariance * sr
            + StateLayout::spread(sb, &Vector2::from(prior.line_bias_variance));
        let ekf = Ekf::new(x, p).map_err(|e| match e {
            // the prior was checked finite above: what the toolkit refuses is its covariance
            FilterError::InvalidCovariance => OneStageError::InvalidCovariance,
            e => OneStageError::Filter(e),
        })?;
        Ok((ekf, a))
    }

    /// The angles (α, β, γ) of a state vector: estimated ones from it, held ones as held.
    pub(super) fn angles_of(&self, x: &SVector<T, N>) -> [T; 3] {
        let estimated = self.layout.angles * x;
        let mut a = self.held;
        let active = self.layout.active();
        for ((ai, &on), &v) in a.iter_mut().zip(active.iter()).zip(estimated.iter()) {
            if on {
                *ai = v;
            }
        }
        a
    }

    /// The line biases (`b_B`, `b_C`) of a state vector (zero when not estimated).
    fn biases_of(&self, x: &SVector<T, N>) -> [T; 2] {
        let b = self.layout.biases * x;
        [b.x, b.y]
    }

    /// Transition `F` of eq. (8): `angle ← angle + T · rate` for the estimated angles,
    /// `F = I + T S_αᵀ S_ω`.
    pub(super) fn transition(&self) -> SMatrix<T, N, N> {
        SMatrix::<T, N, N>::identity()
            + self.layout.angles.transpose() * self.layout.rates * self.config.epoch_s
    }

    /// One epoch: prediction (eq. (10)), the discriminators at the predicted state, the update
    /// of the configured [`FilterMode`], the lock detector. An empty slice only predicts.
    ///
    /// # Errors
    /// [`OneStageError::TooManySatellites`] for more than [`MAX_SATELLITES`];
    /// [`OneStageError::NonFiniteInput`] or [`OneStageError::InvalidObservation`] when any
    /// observation is unusable (drop that channel and call again);
    /// [`OneStageError::Numerical`] when the step fails numerically. On error the filter is
    /// unchanged.
    #[cfg_attr(feature = "optimize-cold", optimize(size))]
    pub fn step(
        &mut self,
        observations: &[SatelliteObservation<T>],
    ) -> Result<EpochReport<T>, OneStageError> {
        // eq. (10): X̃ = F X̂
        let f = self.transition();
        let x_pred = f * self.ekf.state();
        let info = self.information_at(&x_pred, observations)?;
        // the normalized angle discriminator v = J_αα⁻¹ u_α (conditional on the biases)
        let j_aa = info.expected_angles();
        let u_a = info.angle_gradient();
        let normalized = regularized_solve(&j_aa, &u_a);

        let mut next = self.clone();
        match self.config.mode {
            FilterMode::GaussianApproximation => next.gaussian_update(&f, &x_pred, &info)?,
            FilterMode::ConstantGain => next.constant_gain_update(&x_pred, &info, &normalized)?,
        }
        let x = *next.ekf.state();
        let angles = self.layout.angles * x;
        let x = x + self.layout.angles.transpose() * (angles.map(wrap) - angles);
        next.ekf.set_state(x)?;
        next.lock.update(
            info.coherent_power,
            info.aligned_power,
            info.satellites,
            &normalized,
            &j_aa,
        );
        let (before, after) = (self.angles_of(&x_pred), self.angles_of(&x));
        let mut angle_step = [T::zero(); 3];
        for ((step, a), b) in angle_step.iter_mut().zip(after).zip(before) {
            *step = wrap(a - b);
        }
        let report = EpochReport {
            satellites: info.satellites,
            status: next.lock.status(),
            alignment: next.lock.alignment(),
            settle_statistic: next.lock.settle_statistic(),
            angle_discriminator: [info.gradient[0], info.gradient[1], info.gradient[2]],
            angle_step,
            curvature_floored: info.floored,
        };
        *self = next;
        Ok(report)
    }

    /// The epoch's discriminators and information (zero for parameters not estimated) at the
    /// state `x`.
    fn information_at(
        &self,
        x: &SVector<T, N>,
        observations: &[SatelliteObservation<T>],
    ) -> Result<EpochInformation<T>, OneStageError> {
        if observations.len() > MAX_SATELLITES {
            return Err(OneStageError::TooManySatellites);
        }
        let mut checked = heapless::Vec::<CheckedObservation<T>, MAX_SATELLITES>::new();
        for obs in observations {
            let c = obs.check(self.config.epoch_s)?;
            checked
                .push(c)
                // (the item handed back is dropped: the epoch is refused as a whole)
                .map_err(|_| OneStageError::TooManySatellites)?;
        }
        let [a, b, g] = self.angles_of(x);
        let model = PhaseModel::new(
            &self.array,
            self.config.wavelength_m,
            &Paper003Angles::new(a, b, g),
        );
        let mut info = epoch_information(
            &model,
            self.biases_of(x),
            &checked,
            self.config.curvature_floor,
            self.config.mode == FilterMode::GaussianApproximation,
        );
        mask(&mut info, &self.layout.active());
        Ok(info)
    }

    /// The discriminators and information of `observations` at the current estimate, without
    /// changing the filter (diagnostics; [`Self::step`] evaluates them at the predicted state).
    ///
    /// # Errors
    /// As [`Self::step`] for the observations.
    pub fn information(
        &self,
        observations: &[SatelliteObservation<T>],
    ) -> Result<EpochInformation<T>, OneStageError> {
        self.information_at(self.ekf.state(), observations)
    }

    /// The configuration.
    pub fn config(&self) -> &OneStageConfig<T> {
        &self.config
    }

    /// The antenna array.
    pub fn array(&self) -> &AntennaArray<T> {
        &self.array
    }

    /// Where each quantity sits in [`Self::estimate`]'s state vector.
    pub fn layout(&self) -> &StateLayout<T, N> {
        &self.layout
    }

    /// The estimated angles α, β, γ of eq. (2), rad (held angles at their prior values).
    pub fn angles(&self) -> Paper003Angles<T> {
        let [a, b, g] = self.angles_of(self.ekf.state());
        Paper003Angles::new(a, b, g)
    }

    /// The estimated attitude `C_rb = U(α)` (body to reference).
    pub fn attitude(&self) -> Matrix3<T> {
        self.angles().to_dcm()
    }

    /// The estimated rates (α̇, β̇, γ̇), rad/s (zero for held angles).
    pub fn rates(&self) -> Vector3<T> {
        self.layout.rates * self.ekf.state()
    }

    /// The estimated line biases `b_B`, `b_C`, rad (zero when not estimated).
    pub fn line_bias(&self) -> [T; 2] {
        self.biases_of(self.ekf.state())
    }

    /// The covariance of the angles (rad², zero rows for held angles) in the
    /// Gaussian-approximation mode; `None` for the constant-gain loop, which has none.
    pub fn angle_covariance(&self) -> Option<Matrix3<T>> {
        if self.config.mode != FilterMode::GaussianApproximation {
            return None;
        }
        let s = &self.layout.angles;
        Some(s * self.ekf.covariance() * s.transpose())
    }

    /// The state (ordered as [`Self::layout`]) and, in the Gaussian mode, its covariance.
    pub fn estimate(&self) -> &Ekf<N, T> {
        &self.ekf
    }

    /// The lock detector's verdict.
    pub fn lock_status(&self) -> LockStatus {
        self.lock.status()
    }
}

/// Zeroes the information of parameters that are not estimated.
fn mask<T: Real>(info: &mut EpochInformation<T>, active: &[bool; PARAMETERS]) {
    // (indices from a range, not `enumerate`: its counter keeps an overflow check)
    for (k, &on) in (0..PARAMETERS).zip(active.iter()) {
        if !on {
            info.gradient[k] = T::zero();
            info.observed.row_mut(k).fill(T::zero());
            info.observed.column_mut(k).fill(T::zero());
            info.expected.row_mut(k).fill(T::zero());
            info.expected.column_mut(k).fill(T::zero());
        }
    }
}

/// Errors of the one-stage attitude filter ([`crate::attitude::one_stage`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum OneStageError {
    /// An observation, prior, configuration or antenna position held NaN or infinity.
    #[error("non-finite one-stage filter input")]
    NonFiniteInput,
    /// A configuration value is outside its domain: a non-positive wavelength, epoch or
    /// bandwidth, a negative process noise, a lock threshold outside `(0, 1]`, no estimated
    /// angle.
    #[error("invalid one-stage filter configuration")]
    InvalidConfig,
    /// The antenna array is degenerate: two antennas coincide or all three are collinear.
    #[error("antenna array is degenerate (coincident or collinear)")]
    DegenerateArray,
    /// An observation is unusable: a line of sight that is not a unit vector (length off by more
    /// than 1e-3), a noise variance that is not positive, or a C/N0 outside 0..=90 dB-Hz.
    #[error("unusable satellite observation")]
    InvalidObservation,
    /// More satellites in one epoch than [`MAX_SATELLITES`](crate::attitude::one_stage::MAX_SATELLITES).
    #[error("too many satellites in one epoch")]
    TooManySatellites,
    /// A prior covariance is not symmetric positive definite.
    #[error("prior covariance is not positive definite")]
    InvalidCovariance,
    /// The prior attitude is at the gimbal lock of the paper's angles (`cos β` below 1e-3),
    /// where a rotation-vector covariance cannot be mapped onto α, β, γ.
    #[error("prior attitude at the gimbal lock of the paper's angles")]
    GimbalLock,
    /// A snapshot solution offered as the prior is not of
    /// [`SnapshotQuality::Good`](crate::attitude::snapshot::SnapshotQuality::Good) (its
    /// residuals failed the χ² test or its iteration did not converge).
    #[error("snapshot solution not good enough for a prior")]
    UnusableSnapshot,
    /// The filter step produced non-finite numbers or lost definiteness from finite input; the
    /// filter is unchanged.
    #[error("one-stage filter step failed numerically")]
    Numerical,
    /// The Kalman filter toolkit refused a step (prediction, update or state) from finite
    /// input: overflow or loss of definiteness.
    #[error("filter step refused")]
    Filter(#[from] FilterError),
    /// A rotation handed to the filter (an anchor, a prior attitude) could not be normalized
    /// or is not a rotation.
    #[error("rotation refused")]
    Geometry(#[from] GeometryError),
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
            Self::Geometry(e) => e.kind(),
            Self::Filter(e) => e.kind(),
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
