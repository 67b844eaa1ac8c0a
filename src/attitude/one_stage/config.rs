//! Configuration of the one-stage filter.

use crate::{real, Real};

use super::lock::LockConfig;

/// GPS L1 carrier wavelength, m (`c / 1575.42 MHz`).
pub const GPS_L1_WAVELENGTH_M: f64 = 299_792_458.0 / 1_575.42e6;

/// How the filter turns the discriminators into a state update. The default is the Gaussian
/// approximation (see the module documentation for why).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FilterMode {
    /// The Gaussian-approximation filter of eqs. (9)–(12): covariance propagated (11), the
    /// information update `D⁻¹ = D̃⁻¹ − ∂²F/∂X∂Xᵀ` (12, corrected) with the observed curvature
    /// floored per satellite, and the state moved by `D cᵀ u` (9). Its process noise is set
    /// every epoch from the loop bandwidth (see [`OneStageConfig::process_noise`]).
    #[default]
    GaussianApproximation,
    /// The paper's simulated tracker: the discriminator normalized by its expected slope
    /// `J_T`, then a second-order loop with constant gains `K1 = √2 ω_n T`, `K2 = ω_n² T`,
    /// `ω_n = Δf/0.53` (spec section (a)).
    ConstantGain,
}

/// Which of the paper's angles the filter estimates; the others are held at their prior
/// values (with zero rate).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EstimatedAngles {
    /// Estimate α (the third factor of eq. (2), about `X_c`).
    pub alpha: bool,
    /// Estimate β (about `Y_c`).
    pub beta: bool,
    /// Estimate γ (about the reference `Z`).
    pub gamma: bool,
}

impl EstimatedAngles {
    /// All three angles.
    pub const ALL: Self = Self {
        alpha: true,
        beta: true,
        gamma: true,
    };
    /// β only: the paper's simulation (rotation about `Y_c`).
    pub const BETA_ONLY: Self = Self {
        alpha: false,
        beta: true,
        gamma: false,
    };

    /// The flags in the order α, β, γ.
    pub fn as_array(&self) -> [bool; 3] {
        [self.alpha, self.beta, self.gamma]
    }
}

/// Process noise of the Gaussian-approximation filter: the `D_ξ` of eq. (7), a random walk in
/// the angular rates, and a random walk in the line biases.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ProcessNoise<T = f32> {
    /// Scheduled every epoch so that the filter's steady state is the second-order loop of
    /// bandwidth `loop_bandwidth_hz` (angles) and the first-order loop of `bias_bandwidth_hz`
    /// (biases): `q_j = ω_n⁴ / J_j` with `ω_n = Δf/0.53` and `J_j = 1/(J⁻¹)_jj` the marginal
    /// expected information rate of angle `j` among the angles (biases taken as known,
    /// 1/rad²/s), and `q_b = (4 Δf_b)² / J_b` with `J_b` the marginal information of the bias
    /// among all parameters — the slopes the constant-gain loop normalizes by. (The steady-state
    /// Kalman filter of a double integrator with white acceleration of density `q` and
    /// measurement information rate `J` has `ω_n = (qJ)^{1/4}` and `ζ = 1/√2`, so
    /// `B_L = 0.53 ω_n = Δf`.) The bandwidth then stays at `Δf` as satellites come and go,
    /// like the constant-gain loop's.
    Bandwidth,
    /// Fixed densities: angular acceleration `accel_psd` (rad²/s³, per angle α, β, γ), so that
    /// `D_ξ = q T` per epoch, and line-bias drift `bias_psd` (rad²/s).
    Fixed {
        /// White angular acceleration density per angle, rad²/s³.
        accel_psd: [T; 3],
        /// Line-bias random-walk density, rad²/s.
        bias_psd: T,
    },
}

/// Everything the filter needs besides the antenna array and the prior.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OneStageConfig<T = f32> {
    /// Gaussian approximation or constant gains.
    pub mode: FilterMode,
    /// Carrier wavelength, m.
    pub wavelength_m: T,
    /// Coherent integration time per epoch `T`, s (1 ms for GPS C/A).
    pub epoch_s: T,
    /// Which angles are estimated.
    pub estimate: EstimatedAngles,
    /// Estimate the line biases `b_B`, `b_C` (carrier phase of antennas B and C relative to A
    /// from cables and RF channels, rad), assumed constant or slowly drifting.
    pub line_bias_states: bool,
    /// Loop bandwidth `Δf` (one-sided noise bandwidth `B_L`) of the angle tracking, Hz.
    pub loop_bandwidth_hz: T,
    /// Bandwidth of the first-order line-bias loop, Hz.
    pub bias_bandwidth_hz: T,
    /// Process noise of the Gaussian-approximation filter.
    pub process_noise: ProcessNoise<T>,
    /// `κ`: each satellite's observed curvature (eq. (12)) is floored at `κ · 2q_T` in the
    /// phase-difference plane, a fraction of its expected value. `κ > 0` keeps `D_X⁻¹` positive
    /// definite and bounds the step away from the peak, where the curvature is small or
    /// negative, to at most `1/κ` times the normalized discriminator. In `[0, 1]`.
    pub curvature_floor: T,
    /// The pull-in / false-lock detector.
    pub lock: LockConfig<T>,
}

impl<T: Real> OneStageConfig<T> {
    /// The state dimension `N` of a [`OneStageFilter`](super::OneStageFilter) for this
    /// configuration: twice the estimated angles, plus two with line biases.
    pub fn state_dimension(&self) -> usize {
        super::layout::dimension_of(self)
    }

    /// GPS L1 C/A (λ = 0.1903 m, T = 1 ms), all three angles, no bias states, bandwidth
    /// `loop_bandwidth_hz`, bias loop 0.05 Hz, `κ = 0.5`, default lock detector.
    pub fn gps_l1(mode: FilterMode, loop_bandwidth_hz: T) -> Self {
        Self {
            mode,
            wavelength_m: real(GPS_L1_WAVELENGTH_M),
            epoch_s: real(1e-3),
            estimate: EstimatedAngles::ALL,
            line_bias_states: false,
            loop_bandwidth_hz,
            bias_bandwidth_hz: real(0.05),
            process_noise: ProcessNoise::Bandwidth,
            curvature_floor: real(0.5),
            lock: LockConfig::default(),
        }
    }

    /// True when every value is finite and in its domain.
    pub fn is_valid(&self) -> bool {
        let positive = |v: T| v.is_finite() && v > T::zero();
        let noise_ok = match self.process_noise {
            ProcessNoise::Bandwidth => true,
            ProcessNoise::Fixed {
                accel_psd,
                bias_psd,
            } => accel_psd
                .iter()
                .chain(core::iter::once(&bias_psd))
                .all(|v| v.is_finite() && *v >= T::zero()),
        };
        positive(self.wavelength_m)
            && positive(self.epoch_s)
            && positive(self.loop_bandwidth_hz)
            && positive(self.bias_bandwidth_hz)
            && self.curvature_floor.is_finite()
            && self.curvature_floor >= T::zero()
            && self.curvature_floor <= T::one()
            && self.estimate.as_array().iter().any(|&b| b)
            && noise_ok
            && self.lock.is_valid()
    }

    /// Natural frequency `ω_n = Δf/0.53` of the angle loop, rad/s.
    pub fn natural_frequency(&self) -> T {
        self.loop_bandwidth_hz / real(0.53)
    }

    /// The constant gains `(K1, K2)` of the angle loop: `K2н = (Δf/0.53)²`, `K1н = √(2 K2н)`,
    /// `K1 = K1н T` (dimensionless), `K2 = K2н T` (1/s).
    pub fn loop_gains(&self) -> (T, T) {
        let k2n = self.natural_frequency() * self.natural_frequency();
        let k1n = (k2n * real(2.0)).sqrt();
        (k1n * self.epoch_s, k2n * self.epoch_s)
    }

    /// The constant gain of the first-order bias loop, `K_b = 4 Δf_b T` (`B_L = K/4`).
    pub fn bias_gain(&self) -> T {
        self.bias_bandwidth_hz * real(4.0) * self.epoch_s
    }
}
