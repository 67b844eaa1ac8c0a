//! The GPS sky seen from a spacecraft in low Earth orbit, f64: the satellites of a real almanac
//! in the orbit's ECI frame, their lines of sight, ranges, range rates, L1 Doppler and Doppler
//! rate, and whether the Earth hides them.
//!
//! Frames and time: the simulation's ECI frame is the ECEF frame frozen at `t = 0`
//! ([`Orbit`](super::orbit::Orbit)'s `gmst0 = 0`, or a TLE's [`super::tle::TleOrbit`]);
//! simulation time `t` (s) is GPS time of week
//! `gps_time_of_week_s + t` for the almanac. The geometry is instantaneous (no light-time
//! correction): the ~70 ms signal flight shifts ranges by a smooth few tens of metres, which
//! is common to the antennas and irrelevant to attitude.

use nalgebra::{Matrix3, Vector3};

use super::gps::{Almanac, AlmanacEntry};
use super::orbit::{StateVector, Trajectory, OMEGA_EARTH, R_EARTH};

/// GPS L1 wavelength, m.
pub const L1_WAVELENGTH_M: f64 = 299_792_458.0 / 1_575.42e6;

/// Height of the atmosphere a line of sight must clear to count as not occulted, m (the
/// ionosphere and troposphere below it distort and absorb the signal).
pub const OCCULTATION_HEIGHT_M: f64 = 100e3;

/// One GPS satellite as the spacecraft sees it at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpsView {
    /// PRN.
    pub prn: u8,
    /// Satellite position, ECI, m.
    pub position: Vector3<f64>,
    /// Satellite velocity, ECI, m/s.
    pub velocity: Vector3<f64>,
    /// Unit line of sight from the spacecraft to the satellite, ECI.
    pub los: Vector3<f64>,
    /// Range from the spacecraft's centre of mass, m.
    pub range: f64,
    /// Range rate, m/s.
    pub range_rate: f64,
    /// L1 Doppler `−ṙ/λ`, Hz.
    pub doppler_hz: f64,
    /// The line of sight passes below [`OCCULTATION_HEIGHT_M`] above the Earth's surface.
    pub occulted: bool,
}

/// The orbit, the constellation and the time that ties them.
#[derive(Clone, Debug)]
pub struct SkyModel {
    /// The spacecraft's orbit.
    pub orbit: Trajectory,
    /// The GPS almanac (healthy satellites are used).
    pub almanac: Almanac,
    /// GPS time of week at simulation time 0, s.
    pub gps_time_of_week_s: f64,
}

fn rz(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

impl SkyModel {
    /// The spacecraft's position and velocity, ECI.
    pub fn receiver(&self, t: f64) -> StateVector {
        self.orbit.eci(t)
    }

    /// A GPS satellite's position and velocity in ECI: `r_i = R_z(θ) r_e`,
    /// `v_i = R_z(θ)(v_e + ω⊕ × r_e)` with `θ` the Greenwich angle of the orbit's frame.
    pub fn satellite(&self, entry: &AlmanacEntry, t: f64) -> StateVector {
        let (r_e, v_e) = entry.position_velocity(self.gps_time_of_week_s + t);
        let c = rz(self.orbit.gmst(t));
        let w = Vector3::new(0.0, 0.0, OMEGA_EARTH);
        StateVector {
            r: c * r_e,
            v: c * (v_e + w.cross(&r_e)),
        }
    }

    /// The view of one almanac entry from the spacecraft state `rx` at `t`.
    pub fn view_of(&self, entry: &AlmanacEntry, rx: &StateVector, t: f64) -> GpsView {
        let sat = self.satellite(entry, t);
        let d = sat.r - rx.r;
        let range = d.norm();
        let los = d / range;
        let range_rate = los.dot(&(sat.v - rx.v));
        // closest approach of the segment rx → sat to the Earth's centre
        let along = (-rx.r.dot(&los)).clamp(0.0, range);
        let closest = (rx.r + los * along).norm();
        GpsView {
            prn: entry.prn,
            position: sat.r,
            velocity: sat.v,
            los,
            range,
            range_rate,
            doppler_hz: -range_rate / L1_WAVELENGTH_M,
            occulted: closest < R_EARTH + OCCULTATION_HEIGHT_M,
        }
    }

    /// Every healthy satellite at `t` (occulted ones included, flagged).
    pub fn views(&self, t: f64) -> Vec<GpsView> {
        let rx = self.receiver(t);
        self.almanac
            .entries
            .iter()
            .filter(|e| e.health == 0)
            .map(|e| self.view_of(e, &rx, t))
            .collect()
    }

    /// One PRN's view at `t`, `None` when the almanac has no healthy entry for it.
    pub fn view(&self, prn: u8, t: f64) -> Option<GpsView> {
        let e = self
            .almanac
            .entries
            .iter()
            .find(|e| e.prn == prn && e.health == 0)?;
        Some(self.view_of(e, &self.receiver(t), t))
    }

    /// The L1 Doppler rate of one PRN at `t`, Hz/s (central difference over ±0.5 s).
    pub fn doppler_rate_hz_s(&self, prn: u8, t: f64) -> Option<f64> {
        let h = 0.5;
        Some((self.view(prn, t + h)?.doppler_hz - self.view(prn, t - h)?.doppler_hz) / (2.0 * h))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::truth::orbit::Orbit;

    fn sky() -> SkyModel {
        let almanac = Almanac::bundled();
        SkyModel {
            orbit: Orbit::sun_synchronous(550e3, 0.3, 0.0).into(),
            gps_time_of_week_s: almanac.reference_time_s(),
            almanac,
        }
    }

    #[test]
    fn range_rate_is_the_derivative_of_range_and_doppler_stays_within_leo_bounds() {
        let sky = sky();
        let mut max_doppler: f64 = 0.0;
        for t in [0.0, 300.0, 600.0] {
            for v in sky.views(t) {
                let h = 0.01;
                let up = sky.view(v.prn, t + h).unwrap().range;
                let dn = sky.view(v.prn, t - h).unwrap().range;
                assert!(((up - dn) / (2.0 * h) - v.range_rate).abs() < 1e-3);
                assert!((v.los.norm() - 1.0).abs() < 1e-12);
                if !v.occulted {
                    max_doppler = max_doppler.max(v.doppler_hz.abs());
                }
            }
        }
        // LEO at 7.6 km/s: Dopplers of tens of kHz, below 50 kHz
        assert!(max_doppler > 20e3 && max_doppler < 50e3, "{max_doppler}");
    }

    #[test]
    fn satellites_behind_the_earth_are_occulted_and_overhead_ones_are_not() {
        let sky = sky();
        let rx = sky.receiver(0.0);
        let up = rx.r.normalize();
        for v in sky.views(0.0) {
            let elevation = v.los.dot(&up).asin();
            if elevation > 0.0 {
                assert!(!v.occulted, "PRN {} at {elevation}", v.prn);
            }
            if elevation < -0.6 {
                assert!(v.occulted, "PRN {} at {elevation}", v.prn);
            }
        }
    }
}
