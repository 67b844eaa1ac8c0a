//! The filter's per-epoch input: what the signal chain hands over for each tracked satellite.

use nalgebra::{Complex, Vector3};

use crate::attitude::one_stage::OneStageError;
use crate::{real, Real};

use super::discriminator::PromptIq;

/// Most satellites one epoch may carry (the receiver's channel count).
pub const MAX_SATELLITES: usize = 12;

/// One tracked satellite in one epoch (one coherent integration of `T` seconds, 1 ms for GPS
/// C/A): its line of sight and the prompt correlator outputs of the three antennas, all from
/// one replica and one clock, so that the three outputs share one time scale as eq. (19)
/// requires.
///
/// # Adapter from a signal chain
///
/// Per tracked channel: `id` ← PRN; `los` ← the unit vector from the receiver to the satellite
/// in the filter's reference frame (from the ephemeris and the receiver position, rotated into
/// that frame); `prompt.i/q` ← the three antennas' prompt I and Q, in any common unit;
/// `noise_var` ← the noise variance of one component in the same unit (from the chain's noise
/// tap, or `|Z|²`-statistics); `cn0_dbhz` ← the chain's C/N0 estimate. Negate `q` if the chain's
/// quadrature has the paper's sign (`Z ∝ e^{−jφ}`, see [`super::discriminator`]). Channels
/// without carrier lock (the filter assumes the Doppler is tracked) should be left out.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SatelliteObservation<T = f32> {
    /// Satellite identifier (PRN), carried into the reports only.
    pub id: u8,
    /// Unit line of sight from the array to the satellite, reference frame (`μ_i` of the
    /// paper, the frame `OXYZ` in which `U(α)` expresses the attitude). Its length must be
    /// within 1e-3 of 1; it is renormalized.
    pub los: [T; 3],
    /// Prompt correlator outputs of antennas A, B, C.
    pub prompt: PromptIq<T>,
    /// Noise variance of each of `I` and `Q` (same unit as the outputs, squared); positive.
    pub noise_var: T,
    /// Carrier-to-noise density, dB-Hz, in `0..=90`.
    pub cn0_dbhz: T,
}

impl SatelliteObservation<f32> {
    /// The same observation in `f64` (exact widening), for the f64 reference filter.
    pub fn to_f64(&self) -> SatelliteObservation<f64> {
        SatelliteObservation {
            id: self.id,
            los: self.los.map(f64::from),
            prompt: PromptIq {
                i: self.prompt.i.map(f64::from),
                q: self.prompt.q.map(f64::from),
            },
            noise_var: f64::from(self.noise_var),
            cn0_dbhz: f64::from(self.cn0_dbhz),
        }
    }
}

/// An observation after checking: unit line of sight, outputs in noise units, `q_T`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CheckedObservation<T> {
    pub los: Vector3<T>,
    pub z: [Complex<T>; 3],
    /// Post-correlation SNR `q_T = (C/N0)·T`, linear.
    pub q_t: T,
}

impl<T: Real> SatelliteObservation<T> {
    /// Checks the observation and converts it to noise units for an epoch of `epoch_s` seconds.
    pub(crate) fn check(&self, epoch_s: T) -> Result<CheckedObservation<T>, OneStageError> {
        let finite = self
            .los
            .iter()
            .chain(self.prompt.i.iter())
            .chain(self.prompt.q.iter())
            .all(|v| v.is_finite())
            && self.noise_var.is_finite()
            && self.cn0_dbhz.is_finite();
        if !finite {
            return Err(OneStageError::NonFiniteInput);
        }
        let los = Vector3::from(self.los);
        let n = los.norm();
        let usable = (n - T::one()).abs() <= real(1e-3)
            && self.noise_var > T::zero()
            && self.cn0_dbhz >= T::zero()
            && self.cn0_dbhz <= real(90.0);
        if !usable {
            return Err(OneStageError::InvalidObservation);
        }
        let sigma = self.noise_var.sqrt();
        let z = self.prompt.normalized(sigma);
        if !z.iter().all(|c| c.re.is_finite() && c.im.is_finite()) {
            return Err(OneStageError::InvalidObservation);
        }
        // q_T = 10^(C/N0 / 10) · T
        let q_t = (self.cn0_dbhz * real(core::f64::consts::LN_10 / 10.0)).exp() * epoch_s;
        Ok(CheckedObservation {
            los: los / n,
            z,
            q_t,
        })
    }
}
