//! GPS constellation geometry from a real almanac (f64): YUMA parsing, IS-GPS-200 almanac
//! propagation to ECEF position and velocity, WGS-84 receiver positions, and the elevation,
//! azimuth and line of sight of each satellite in the receiver's local NED frame.
//!
//! The bundled almanac ([`Almanac::bundled`], `host-sim/data/gps_almanac.yuma`) is a real YUMA
//! almanac of GPS week 2195 (147 mod 1024), time of applicability 233 472 s; see
//! `host-sim/data/README.md` for its source.
//!
//! ```
//! use host_sim::truth::gps::{Almanac, Geodetic};
//! let almanac = Almanac::bundled();
//! let kyiv = Geodetic::from_degrees(50.45, 30.52, 180.0);
//! let t = almanac.reference_time_s();
//! let views = almanac.visible(&kyiv, t, 10f64.to_radians());
//! assert!(views.len() >= 5);
//! ```

use anyhow::{anyhow, bail, Context};
use nalgebra::{Matrix3, Vector3};

/// WGS-84 value of the Earth's gravitational constant used by GPS, m³/s².
pub const MU: f64 = 3.986_005e14;
/// WGS-84 Earth rotation rate, rad/s.
pub const OMEGA_EARTH: f64 = 7.292_115_146_7e-5;
/// WGS-84 semi-major axis, m.
pub const WGS84_A: f64 = 6_378_137.0;
/// WGS-84 flattening.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// Seconds in a GPS week.
pub const WEEK_S: f64 = 604_800.0;
/// Bound on the Kepler-equation iterations (converges to 1e-15 in < 10 for GPS eccentricities).
pub const KEPLER_MAX_ITERATIONS: usize = 30;

/// One satellite's almanac (YUMA record). Angles in radians, times in seconds of the GPS week.
#[derive(Clone, Debug, PartialEq)]
pub struct AlmanacEntry {
    /// PRN.
    pub prn: u8,
    /// Health word (0 = healthy).
    pub health: u32,
    /// Eccentricity.
    pub eccentricity: f64,
    /// Time of applicability, s of the week.
    pub toa_s: f64,
    /// Inclination, rad.
    pub inclination: f64,
    /// Rate of right ascension, rad/s.
    pub omega_dot: f64,
    /// Square root of the semi-major axis, √m.
    pub sqrt_a: f64,
    /// Longitude of the ascending node at the weekly epoch, rad.
    pub omega0: f64,
    /// Argument of perigee, rad.
    pub argument_of_perigee: f64,
    /// Mean anomaly at the time of applicability, rad.
    pub mean_anomaly: f64,
    /// Clock bias, s.
    pub af0: f64,
    /// Clock drift, s/s.
    pub af1: f64,
    /// GPS week (modulo 1024, as in the file).
    pub week: u32,
}

/// A parsed almanac.
#[derive(Clone, Debug, PartialEq)]
pub struct Almanac {
    /// The satellites, in file order.
    pub entries: Vec<AlmanacEntry>,
}

/// A receiver position on the WGS-84 ellipsoid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geodetic {
    /// Geodetic latitude, rad.
    pub lat: f64,
    /// Longitude, rad.
    pub lon: f64,
    /// Height above the ellipsoid, m.
    pub height: f64,
}

/// One satellite as seen from a receiver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SatelliteView {
    /// PRN.
    pub prn: u8,
    /// Elevation above the local horizon, rad.
    pub elevation: f64,
    /// Azimuth from north towards east, rad, `[0, 2π)`.
    pub azimuth: f64,
    /// Unit line of sight receiver → satellite in the local NED frame (z down).
    pub los_ned: Vector3<f64>,
    /// Range, m.
    pub range: f64,
}

impl Geodetic {
    /// A position from degrees and metres.
    pub fn from_degrees(lat_deg: f64, lon_deg: f64, height_m: f64) -> Self {
        Self {
            lat: lat_deg.to_radians(),
            lon: lon_deg.to_radians(),
            height: height_m,
        }
    }

    /// ECEF coordinates, m.
    pub fn to_ecef(&self) -> Vector3<f64> {
        let e2 = WGS84_F * (2.0 - WGS84_F);
        let (sl, cl) = self.lat.sin_cos();
        let (so, co) = self.lon.sin_cos();
        let n = WGS84_A / (1.0 - e2 * sl * sl).sqrt();
        Vector3::new(
            (n + self.height) * cl * co,
            (n + self.height) * cl * so,
            (n * (1.0 - e2) + self.height) * sl,
        )
    }

    /// `C_ne`: ECEF components to local north-east-down components.
    pub fn ecef_to_ned(&self) -> Matrix3<f64> {
        let (sl, cl) = self.lat.sin_cos();
        let (so, co) = self.lon.sin_cos();
        Matrix3::new(
            -sl * co,
            -sl * so,
            cl,
            -so,
            co,
            0.0,
            -cl * co,
            -cl * so,
            -sl,
        )
    }
}

impl AlmanacEntry {
    /// Position and velocity (ECEF, m and m/s) at `t` seconds of the almanac's GPS week, by the
    /// almanac form of the IS-GPS-200 user algorithm (Table 20-IV without the harmonic
    /// corrections, which the almanac does not carry). `t − toa` is wrapped into ±half a week.
    pub fn position_velocity(&self, t: f64) -> (Vector3<f64>, Vector3<f64>) {
        let a = self.sqrt_a * self.sqrt_a;
        let n0 = (MU / (a * a * a)).sqrt();
        let mut tk = t - self.toa_s;
        if tk > WEEK_S / 2.0 {
            tk -= WEEK_S;
        } else if tk < -WEEK_S / 2.0 {
            tk += WEEK_S;
        }
        let e = self.eccentricity;
        let m = self.mean_anomaly + n0 * tk;
        // Kepler's equation M = E − e sin E by Newton's method (bounded)
        let mut ea = m;
        for _ in 0..KEPLER_MAX_ITERATIONS {
            let step = (ea - e * ea.sin() - m) / (1.0 - e * ea.cos());
            ea -= step;
            if step.abs() < 1e-15 {
                break;
            }
        }
        let (se, ce) = ea.sin_cos();
        let nu = ((1.0 - e * e).sqrt() * se).atan2(ce - e);
        let phi = nu + self.argument_of_perigee;
        let r = a * (1.0 - e * ce);
        let omega_k = self.omega0 + (self.omega_dot - OMEGA_EARTH) * tk - OMEGA_EARTH * self.toa_s;
        let (sp, cp) = phi.sin_cos();
        let (so, co) = omega_k.sin_cos();
        let (si, ci) = self.inclination.sin_cos();
        let (xp, yp) = (r * cp, r * sp);
        let pos = Vector3::new(xp * co - yp * ci * so, xp * so + yp * ci * co, yp * si);
        // time derivatives
        let e_dot = n0 / (1.0 - e * ce);
        let phi_dot = (1.0 - e * e).sqrt() * e_dot / (1.0 - e * ce);
        let r_dot = a * e * se * e_dot;
        let xp_dot = r_dot * cp - r * sp * phi_dot;
        let yp_dot = r_dot * sp + r * cp * phi_dot;
        let omega_k_dot = self.omega_dot - OMEGA_EARTH;
        let vel = Vector3::new(
            xp_dot * co - yp_dot * ci * so - omega_k_dot * pos.y,
            xp_dot * so + yp_dot * ci * co + omega_k_dot * pos.x,
            yp_dot * si,
        );
        (pos, vel)
    }
}

impl Almanac {
    /// The bundled real almanac (`host-sim/data/gps_almanac.yuma`).
    pub fn bundled() -> Self {
        // The file is part of the crate; a parse failure is a build defect caught by the tests.
        Self::parse_yuma(include_str!("../../data/gps_almanac.yuma")).unwrap_or(Self {
            entries: Vec::new(),
        })
    }

    /// Parses a YUMA almanac (records of `Key: value` lines separated by `****` headers).
    ///
    /// # Errors
    /// A record with a missing or unparsable field.
    pub fn parse_yuma(text: &str) -> anyhow::Result<Self> {
        let mut entries = Vec::new();
        let mut fields: Vec<(String, String)> = Vec::new();
        let flush = |fields: &mut Vec<(String, String)>, entries: &mut Vec<AlmanacEntry>| {
            if fields.is_empty() {
                return Ok(());
            }
            let entry = entry_from_fields(fields)?;
            entries.push(entry);
            fields.clear();
            anyhow::Ok(())
        };
        for line in text.lines() {
            let line = line.trim();
            if line.starts_with("****") {
                flush(&mut fields, &mut entries)?;
                continue;
            }
            if let Some((key, value)) = line.split_once(':') {
                fields.push((key.trim().to_ascii_lowercase(), value.trim().to_string()));
            }
        }
        flush(&mut fields, &mut entries)?;
        if entries.is_empty() {
            bail!("no almanac records");
        }
        Ok(Self { entries })
    }

    /// The time of applicability of the first record, s of the week.
    pub fn reference_time_s(&self) -> f64 {
        self.entries.first().map(|e| e.toa_s).unwrap_or(0.0)
    }

    /// The healthy satellites above `mask` elevation (rad) for a receiver at `receiver`, at
    /// `t` seconds of the almanac week.
    pub fn visible(&self, receiver: &Geodetic, t: f64, mask: f64) -> Vec<SatelliteView> {
        let rx = receiver.to_ecef();
        let c_ne = receiver.ecef_to_ned();
        self.entries
            .iter()
            .filter(|e| e.health == 0)
            .filter_map(|e| {
                let (pos, _) = e.position_velocity(t);
                // Earth rotation during the signal flight (Sagnac) is irrelevant for a
                // direction at the 1e-4 rad level and ignored.
                let d = pos - rx;
                let range = d.norm();
                let los = c_ne * (d / range);
                let elevation = (-los.z).asin();
                let azimuth = los.y.atan2(los.x).rem_euclid(std::f64::consts::TAU);
                (elevation >= mask).then_some(SatelliteView {
                    prn: e.prn,
                    elevation,
                    azimuth,
                    los_ned: los,
                    range,
                })
            })
            .collect()
    }
}

fn entry_from_fields(fields: &[(String, String)]) -> anyhow::Result<AlmanacEntry> {
    let get = |prefix: &str| -> anyhow::Result<f64> {
        let (_, v) = fields
            .iter()
            .find(|(k, _)| k.starts_with(prefix))
            .ok_or_else(|| anyhow!("almanac record without {prefix:?}"))?;
        v.parse::<f64>()
            .with_context(|| format!("almanac field {prefix:?}: {v:?}"))
    };
    Ok(AlmanacEntry {
        prn: get("id")? as u8,
        health: get("health")? as u32,
        eccentricity: get("eccentricity")?,
        toa_s: get("time of applicability")?,
        inclination: get("orbital inclination")?,
        omega_dot: get("rate of right ascen")?,
        sqrt_a: get("sqrt(a)")?,
        omega0: get("right ascen at")?,
        argument_of_perigee: get("argument of perigee")?,
        mean_anomaly: get("mean anom")?,
        af0: get("af0")?,
        af1: get("af1")?,
        week: get("week")? as u32,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_bundled_almanac() {
        let alm = Almanac::bundled();
        assert_eq!(alm.entries.len(), 31);
        let first = &alm.entries[0];
        assert_eq!((first.prn, first.week), (1, 147));
        assert!((first.sqrt_a - 5153.621094).abs() < 1e-9);
        assert_eq!(alm.entries.iter().filter(|e| e.health != 0).count(), 1);
        assert!(Almanac::parse_yuma("ID: 1\n").is_err());
    }

    #[test]
    fn orbits_have_gps_radius_and_consistent_velocity() {
        let alm = Almanac::bundled();
        let t = alm.reference_time_s() + 3600.0;
        for e in &alm.entries {
            let (p, v) = e.position_velocity(t);
            let a = e.sqrt_a * e.sqrt_a;
            assert!((a - 26_560e3).abs() < 5e3);
            assert!(
                (p.norm() - a).abs() <= a * e.eccentricity + 1.0,
                "radius {}",
                p.norm()
            );
            let h = 0.5;
            let (p1, _) = e.position_velocity(t + h);
            let (p0, _) = e.position_velocity(t - h);
            let fd = (p1 - p0) / (2.0 * h);
            assert!((fd - v).norm() < 1e-3, "velocity {} vs {}", v, fd);
        }
    }

    #[test]
    fn a_mid_latitude_site_sees_a_normal_sky() {
        let alm = Almanac::bundled();
        let site = Geodetic::from_degrees(50.45, 30.52, 180.0);
        let mut counts = Vec::new();
        for k in 0..48 {
            let t = alm.reference_time_s() + 1800.0 * k as f64;
            let v = site_views(&alm, &site, t);
            for s in &v {
                assert!((s.los_ned.norm() - 1.0).abs() < 1e-12);
                assert!(s.range > 19_000e3 && s.range < 26_000e3);
            }
            counts.push(v.len());
        }
        let min = *counts.iter().min().unwrap();
        let max = *counts.iter().max().unwrap();
        assert!(min >= 5 && max <= 14, "{min}..{max}");
    }

    fn site_views(alm: &Almanac, site: &Geodetic, t: f64) -> Vec<SatelliteView> {
        alm.visible(site, t, 10f64.to_radians())
    }
}
