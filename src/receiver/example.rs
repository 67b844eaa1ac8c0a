//! A deterministic flight for documentation, tests, benchmarks and the firmware budgets: the
//! 0.5 m triangle on the zenith face (boresight body −z), the eight satellites of
//! [`crate::attitude::example::SKY`] at 45 dB-Hz, a body turning at a constant rate, an ideal
//! gyro, data bits, and seeded noise ([`crate::noise`]). Everything is `f32` and allocation
//! free, so the firmware can run it on the target.
//!
//! ```
//! use gnss_attitude::receiver::{example::ExampleFlight, AttitudeReceiver, AttitudeSource};
//! let mut flight = ExampleFlight::new(7);
//! let mut receiver = AttitudeReceiver::new(ExampleFlight::config(true))?;
//! flight.fly(&mut receiver, 0, 600)?; // 0.6 s: cold start, then the fine filter
//! let att = receiver.attitude();
//! assert_eq!(att.source, AttitudeSource::Fine);
//! let truth = flight.attitude(att.epoch);
//! assert!(att.q_rb.angle_to(&truth) < 0.2f32.to_radians());
//! # Ok::<(), gnss_attitude::receiver::ReceiverError>(())
//! ```

use nalgebra::Vector3;

use crate::attitude::example::SKY;
use crate::attitude::one_stage::{PromptIq, SatelliteObservation, GPS_L1_WAVELENGTH_M};
use crate::geometry::Quaternion;
use crate::noise::{SplitMix64, StandardNormal};
use crate::receiver::ReceiverError;

use super::{AttitudeReceiver, GyroConfig, ReceiverConfig, SatelliteAiding, MAX_SATELLITES};

/// C/N0 of every satellite, dB-Hz.
pub const CN0_DBHZ: f32 = 45.0;
/// Noise standard deviation of each correlator component, counts.
pub const NOISE_SIGMA: f32 = 40.0;
/// Epoch, s.
pub const EPOCH_S: f32 = 1e-3;
/// Gyro sample interval, s.
pub const GYRO_H: f32 = 0.01;
/// The line biases of B and C the flight's front end adds, rad.
pub const LINE_BIAS_RAD: [f32; 2] = [0.7, -1.2];
/// The body rate, body axes, rad/s.
pub const BODY_RATE: [f32; 3] = [0.004, -0.003, 0.0105];

/// The antennas: a 0.5 m equilateral triangle at `z = −0.05 m`, body axes, m.
pub fn antennas() -> [[f32; 3]; 3] {
    let r = 0.5 / crate::sqrtf(3.0);
    let at = |deg: f32| {
        let a = deg.to_radians();
        [r * libm::cosf(a), r * libm::sinf(a), -0.05]
    };
    [at(0.0), at(120.0), at(240.0)]
}

/// A flight: the truth and the generator of its observations.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ExampleFlight {
    rng: SplitMix64,
    normal: StandardNormal,
    /// Attitude at epoch 0 (body to reference).
    pub q0: Quaternion<f32>,
    /// Per satellite and antenna an extra phase (rad) added to the prompts (fault injection).
    pub phase_offset: [[f32; 3]; 8],
    /// Per antenna a gain on the signal (0 blocks the antenna).
    pub antenna_gain: [f32; 3],
    /// Data-sign inversion of one satellite from an epoch on: `(satellite index, epoch)`.
    pub bit_flip: Option<(usize, u64)>,
    /// Line biases of B and C (the phase their RF chains add), rad: unknown to the receiver.
    pub line_bias: [f32; 2],
}

impl ExampleFlight {
    /// A flight with the given noise seed.
    pub fn new(seed: u64) -> Self {
        Self {
            rng: SplitMix64::new(seed),
            normal: StandardNormal::default(),
            q0: Quaternion::from_rotation_vector(&Vector3::new(0.3, -0.2, 1.1)),
            phase_offset: [[0.0; 3]; 8],
            antenna_gain: [1.0; 3],
            bit_flip: None,
            line_bias: LINE_BIAS_RAD,
        }
    }

    /// The receiver configuration for this flight, with or without the gyro.
    pub fn config(with_gyro: bool) -> ReceiverConfig {
        let gyro = with_gyro.then(|| GyroConfig::mems(GYRO_H, None));
        ReceiverConfig::gps_l1(antennas(), gyro)
    }

    /// The true attitude at the centre of `epoch`.
    pub fn attitude(&self, epoch: u64) -> Quaternion<f32> {
        let t = (epoch as f32 + 0.5) * EPOCH_S;
        self.q0 * Quaternion::from_rotation_vector(&(Vector3::from(BODY_RATE) * t))
    }

    /// The line of sight of satellite `i` (reference frame: a local level frame, z to nadir),
    /// constant over the flight.
    pub fn los(i: usize) -> Vector3<f32> {
        let (_, el, az) = SKY.get(i).copied().unwrap_or((0, 90.0, 0.0));
        let (el, az) = (el.to_radians(), az.to_radians());
        Vector3::new(
            libm::cosf(el) * libm::cosf(az),
            libm::cosf(el) * libm::sinf(az),
            -libm::sinf(el),
        )
    }

    /// The aiding of the eight satellites, valid from `epoch`.
    pub fn aiding(&self, epoch: u64) -> heapless::Vec<SatelliteAiding, MAX_SATELLITES> {
        let mut v = heapless::Vec::new();
        for (i, (prn, _, _)) in SKY.iter().enumerate() {
            let los = Self::los(i);
            let aiding = SatelliteAiding {
                prn: *prn,
                epoch,
                los: [los.x, los.y, los.z],
                los_rate: [0.0; 3],
            };
            // the sky holds at most MAX_SATELLITES satellites: a full vector ends the list
            if v.push(aiding).is_err() {
                break;
            }
        }
        v
    }

    /// The gyro increment of sample `n` (over `[n h, (n + 1) h]`): the exact constant rate.
    pub fn gyro_increment(&self, _n: u64) -> [f32; 3] {
        BODY_RATE.map(|w| w * GYRO_H)
    }

    /// The observations of `epoch` (line of sight left to the aiding).
    pub fn observations(
        &mut self,
        epoch: u64,
    ) -> heapless::Vec<SatelliteObservation<f32>, MAX_SATELLITES> {
        let c_rb = self.attitude(epoch).to_dcm();
        let k = core::f32::consts::TAU / GPS_L1_WAVELENGTH_M as f32;
        let cn0 = libm::powf(10.0, 0.1 * CN0_DBHZ);
        let amplitude = crate::sqrtf(2.0 * cn0 * EPOCH_S) * NOISE_SIGMA;
        let positions = antennas().map(Vector3::from);
        let mut out = heapless::Vec::new();
        for (i, (prn, _, _)) in SKY.iter().enumerate() {
            let los = Self::los(i);
            // data bit: a new pseudo-random bit every 20 epochs
            // (saturating: the flight is defined for every epoch, up to u64::MAX)
            let bit_index = epoch.saturating_add(7u64.saturating_mul(i as u64)) / 20;
            let mut bit = if (bit_index.wrapping_mul(0x9E37_79B9) >> 7) & 1 == 0 {
                1.0
            } else {
                -1.0
            };
            if let Some((sat, from)) = self.bit_flip {
                if sat == i && epoch >= from {
                    bit = -bit;
                }
            }
            let [pa, _, _] = positions;
            let psi_a = k * los.dot(&(c_rb * pa));
            let mut offsets = self.phase_offset.get(i).copied().unwrap_or([0.0; 3]);
            offsets[1] += self.line_bias[0];
            offsets[2] += self.line_bias[1];
            let mut prompt = PromptIq::default();
            let outputs = prompt.i.iter_mut().zip(prompt.q.iter_mut());
            let antennas = positions
                .iter()
                .zip(self.antenna_gain.iter())
                .zip(offsets.iter());
            for ((pi, pq), ((pos, gain), offset)) in outputs.zip(antennas) {
                let psi = k * los.dot(&(c_rb * pos)) - psi_a + offset;
                let a = amplitude * bit * gain;
                let ni = self.normal.sample(&mut self.rng);
                let nq = self.normal.sample(&mut self.rng);
                *pi = a * libm::cosf(psi) + NOISE_SIGMA * ni;
                *pq = a * libm::sinf(psi) + NOISE_SIGMA * nq;
            }
            let observation = SatelliteObservation {
                id: *prn,
                los: [los.x, los.y, los.z],
                prompt,
                noise_var: NOISE_SIGMA * NOISE_SIGMA,
                cn0_dbhz: CN0_DBHZ,
            };
            // the sky holds at most MAX_SATELLITES satellites: a full vector ends the epoch
            if out.push(observation).is_err() {
                break;
            }
        }
        out
    }

    /// Epochs `from..to` without any signal (an eclipse of every antenna, a blockage): only
    /// the gyro increments (when the receiver has a gyro), then the epochs are closed.
    ///
    /// # Errors
    /// The receiver's.
    pub fn coast(
        &mut self,
        receiver: &mut AttitudeReceiver,
        from: u64,
        to: u64,
    ) -> Result<(), ReceiverError> {
        let per_gyro = libm::roundf(GYRO_H / EPOCH_S) as u64;
        if receiver.config().gyro.is_some() {
            for k in (from..to).filter(|k| *k > 0 && k.checked_rem(per_gyro) == Some(0)) {
                receiver.push_gyro_increment(
                    &self.gyro_increment(k.checked_div(per_gyro).unwrap_or(1).saturating_sub(1)),
                )?;
                receiver.close_through(k.saturating_sub(1));
            }
        }
        receiver.close_through(to.saturating_sub(1));
        Ok(())
    }

    /// Flies epochs `from..to` into `receiver`: aiding every 100 epochs, a gyro increment
    /// every 10 epochs (when the receiver has a gyro), the observations of every epoch; closes
    /// the epochs at the end.
    ///
    /// # Errors
    /// The receiver's.
    pub fn fly(
        &mut self,
        receiver: &mut AttitudeReceiver,
        from: u64,
        to: u64,
    ) -> Result<(), ReceiverError> {
        let per_gyro = libm::roundf(GYRO_H / EPOCH_S) as u64;
        for k in from..to {
            if k % 100 == 0 {
                receiver.set_aiding(&self.aiding(k))?;
            }
            if receiver.config().gyro.is_some() && k > 0 && k.checked_rem(per_gyro) == Some(0) {
                receiver.push_gyro_increment(
                    &self.gyro_increment(k.checked_div(per_gyro).unwrap_or(1).saturating_sub(1)),
                )?;
            }
            for o in self.observations(k).iter() {
                receiver.push_observation(k, o)?;
            }
        }
        receiver.close_through(to.saturating_sub(1));
        Ok(())
    }
}
