//! An orbit from a two-line element set (TLE): SGP4 (the `sgp4` crate) in TEME, rotated to
//! ECEF and into the simulation's ECI frame, f64.
//!
//! * **Time**: the flight keeps its GPS start (the almanac's time of applicability plus the
//!   scenario's offset), so the constellation's geometry is the bundled almanac's; the TLE is
//!   propagated from its own epoch to that instant and on through the flight. GPS time → UTC
//!   with the leap seconds of the almanac's date ([`GPS_MINUS_UTC_S`]); UT1 = UTC (|UT1 − UTC|
//!   < 0.9 s: a rotation of the whole ECEF orbit by < 66 µrad about the pole).
//! * **TEME → ECEF**: `r_e = R_z(−θ) r_teme`, `v_e = R_z(−θ) v_teme − ω⊕ × r_e` with `θ` the
//!   Greenwich mean sidereal time (IAU 1982, the `sgp4` crate's; GMST, not the apparent
//!   time, as TEME's mean equinox requires) and **polar motion is ignored** (about 0.3″ =
//!   1.5 µrad: some 10 m at the orbit's radius, the same for the GPS satellites' frame).
//! * **ECEF → the simulation's ECI** ([`super::sky`]: the ECEF frame frozen at `t = 0`):
//!   `r_i = R_z(ω⊕ t) r_e`, `v_i = R_z(ω⊕ t)(v_e + ω⊕ × r_e)`, the rotation the GPS
//!   satellites get in [`super::sky::SkyModel::satellite`].

use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Vector3};

use super::orbit::{eci_to_ecef, StateVector, OMEGA_EARTH};

/// GPS − UTC in 2017–2026 (leap seconds since 1980), s.
pub const GPS_MINUS_UTC_S: f64 = 18.0;
/// Julian date of the GPS epoch, 1980-01-06 00:00 UTC, days.
const GPS_EPOCH_JD: f64 = 2_444_244.5;
/// Julian date of J2000.0, days.
const J2000_JD: f64 = 2_451_545.0;
/// Seconds in a day.
const DAY_S: f64 = 86_400.0;
/// Step of the propagation check over a flight, s.
const CHECK_STEP_S: f64 = 10.0;
/// Margin propagated beyond each end of the flight by the check, s.
const CHECK_MARGIN_S: f64 = 60.0;

/// Why a TLE cannot fly.
#[derive(Debug)]
pub enum TleError {
    /// The file could not be read.
    Read {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The text does not hold a line starting `1 ` followed by one starting `2 `.
    MissingLines,
    /// The two lines do not parse (format or checksum; the crate's error).
    Parse(sgp4::TleError),
    /// The elements cannot be propagated (e.g. eccentricity out of range).
    Elements(sgp4::ElementsError),
    /// SGP4 failed at a time of the flight (decay, eccentricity out of range).
    Propagation {
        /// Minutes after the TLE's epoch.
        minutes: f64,
        /// The cause.
        source: sgp4::Error,
    },
}

impl std::fmt::Display for TleError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Read { path, source } => write!(f, "reading {}: {source}", path.display()),
            Self::MissingLines => {
                write!(
                    f,
                    "no two-line element set (a line '1 …' then a line '2 …')"
                )
            }
            Self::Parse(e) => write!(f, "TLE: {e}"),
            Self::Elements(e) => write!(f, "TLE elements: {e}"),
            Self::Propagation { minutes, source } => {
                write!(f, "SGP4 at {minutes:.1} min from the TLE epoch: {source}")
            }
        }
    }
}

impl std::error::Error for TleError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Read { source, .. } => Some(source),
            Self::Parse(e) => Some(e),
            Self::Elements(e) => Some(e),
            Self::Propagation { source, .. } => Some(source),
            Self::MissingLines => None,
        }
    }
}

/// A parsed two-line element set with its SGP4 constants.
#[derive(Clone, Debug, PartialEq)]
pub struct Tle {
    /// The name line of a three-line set (`None` for two lines).
    pub name: Option<String>,
    /// The elements (epoch UTC, mean motion in rev/day, angles in degrees).
    pub elements: sgp4::Elements,
    constants: sgp4::Constants,
}

impl Tle {
    /// Parses a two- or three-line element set: the first line starting `1 ` and the line
    /// after it (which must start `2 `); a non-empty line just before line 1 is the name.
    ///
    /// # Errors
    /// [`TleError::MissingLines`], [`TleError::Parse`], [`TleError::Elements`].
    pub fn parse(text: &str) -> Result<Self, TleError> {
        let lines: Vec<&str> = text.lines().map(str::trim_end).collect();
        let i = lines
            .iter()
            .position(|l| l.starts_with("1 "))
            .ok_or(TleError::MissingLines)?;
        let line2 = lines
            .get(i + 1)
            .filter(|l| l.starts_with("2 "))
            .ok_or(TleError::MissingLines)?;
        let name = i
            .checked_sub(1)
            .map(|j| lines[j].trim())
            .filter(|n| !n.is_empty() && !n.starts_with('#'))
            .map(|n| n.trim_start_matches("0 ").to_string());
        let elements =
            sgp4::Elements::from_tle(name.clone(), lines[i].as_bytes(), line2.as_bytes())
                .map_err(TleError::Parse)?;
        let constants = sgp4::Constants::from_elements(&elements).map_err(TleError::Elements)?;
        Ok(Self {
            name,
            elements,
            constants,
        })
    }

    /// Reads and parses `path` ([`Self::parse`]).
    ///
    /// # Errors
    /// [`TleError::Read`] and those of [`Self::parse`].
    pub fn read(path: &Path) -> Result<Self, TleError> {
        let text = std::fs::read_to_string(path).map_err(|source| TleError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text)
    }

    /// The epoch as UTC seconds since the GPS epoch (1980-01-06 00:00 UTC), s.
    pub fn epoch_utc_s(&self) -> f64 {
        let gps_epoch = sgp4::chrono::NaiveDate::from_ymd_opt(1980, 1, 6)
            .and_then(|d| d.and_hms_opt(0, 0, 0))
            .unwrap_or_default();
        let d = self.elements.datetime - gps_epoch;
        d.num_microseconds().map_or(f64::NAN, |us| us as f64 / 1e6)
    }

    /// Position and velocity in TEME at `minutes` after the epoch, m and m/s.
    ///
    /// # Errors
    /// [`TleError::Propagation`].
    pub fn teme(&self, minutes: f64) -> Result<StateVector, TleError> {
        let p = self
            .constants
            .propagate(sgp4::MinutesSinceEpoch(minutes))
            .map_err(|source| TleError::Propagation { minutes, source })?;
        Ok(StateVector {
            r: Vector3::from(p.position) * 1e3,
            v: Vector3::from(p.velocity) * 1e3,
        })
    }

    /// Position and velocity in ECEF (polar motion ignored) at `utc_s` UTC seconds since the
    /// GPS epoch, m and m/s.
    ///
    /// # Errors
    /// [`TleError::Propagation`].
    pub fn ecef(&self, utc_s: f64) -> Result<StateVector, TleError> {
        let teme = self.teme((utc_s - self.epoch_utc_s()) / 60.0)?;
        Ok(teme_to_ecef(&teme, gmst(utc_s)))
    }

    /// The mean motion of the elements, rad/s.
    pub fn mean_motion(&self) -> f64 {
        self.elements.mean_motion * std::f64::consts::TAU / DAY_S
    }

    /// What to call it: its name, or its NORAD number.
    pub fn label(&self) -> String {
        self.name
            .clone()
            .unwrap_or_else(|| format!("NORAD {}", self.elements.norad_id))
    }
}

/// Greenwich mean sidereal time (IAU 1982, UT1 = UTC) at `utc_s` UTC seconds since the GPS
/// epoch, rad in `[0, 2π)`.
pub fn gmst(utc_s: f64) -> f64 {
    gmst_of_j2000_days(days_from_j2000(utc_s))
}

/// Days from J2000.0 (UTC) at `utc_s` UTC seconds since the GPS epoch. Kept small: a Julian
/// date of 2.46e6 days holds only 40 µs, which would make the orbit jitter by centimetres.
fn days_from_j2000(utc_s: f64) -> f64 {
    (GPS_EPOCH_JD - J2000_JD) + utc_s / DAY_S
}

/// [`gmst`] at `days` from J2000.0, rad.
fn gmst_of_j2000_days(days: f64) -> f64 {
    sgp4::iau_epoch_to_sidereal_time(days / 365.25)
}

/// TEME → ECEF (pseudo-Earth-fixed: polar motion ignored) at sidereal angle `gmst` (rad):
/// `r_e = R_z(−θ) r`, `v_e = R_z(−θ)(v − ω⊕ × r)`.
pub fn teme_to_ecef(s: &StateVector, gmst: f64) -> StateVector {
    eci_to_ecef(s, gmst)
}

/// A TLE flown from a GPS instant: simulation time `t` (s) is UTC
/// `start_utc_s + t` (seconds since the GPS epoch), and the simulation's ECI frame is the ECEF
/// frame frozen at `t = 0`.
#[derive(Clone, Debug, PartialEq)]
pub struct TleOrbit {
    /// The elements.
    pub tle: Tle,
    /// UTC at `t = 0`, s since the GPS epoch.
    pub start_utc_s: f64,
    /// `t = 0` from the TLE's epoch, s (held apart so that `t` keeps its sub-µs resolution).
    start_from_epoch_s: f64,
    /// `t = 0` from J2000.0, days.
    start_days: f64,
}

impl TleOrbit {
    /// `tle` flown from GPS time `gps_start_s` (s since the GPS epoch) for `duration_s`:
    /// SGP4 is checked every 10 s over the flight and a minute beyond either end.
    ///
    /// # Errors
    /// [`TleError::Propagation`] where SGP4 fails.
    pub fn new(tle: Tle, gps_start_s: f64, duration_s: f64) -> Result<Self, TleError> {
        let start_utc_s = gps_start_s - GPS_MINUS_UTC_S;
        let orbit = Self {
            start_from_epoch_s: start_utc_s - tle.epoch_utc_s(),
            start_days: days_from_j2000(start_utc_s),
            tle,
            start_utc_s,
        };
        let steps = ((duration_s.max(0.0) + 2.0 * CHECK_MARGIN_S) / CHECK_STEP_S).ceil() as usize;
        for k in 0..=steps {
            orbit.try_ecef(k as f64 * CHECK_STEP_S - CHECK_MARGIN_S)?;
        }
        Ok(orbit)
    }

    fn try_ecef(&self, t: f64) -> Result<StateVector, TleError> {
        let teme = self.tle.teme((self.start_from_epoch_s + t) / 60.0)?;
        Ok(teme_to_ecef(
            &teme,
            gmst_of_j2000_days(self.start_days + t / DAY_S),
        ))
    }

    /// Minutes from the TLE's epoch to `t = 0`.
    pub fn minutes_from_epoch(&self) -> f64 {
        self.start_from_epoch_s / 60.0
    }

    /// Position and velocity in ECEF at `t`, m and m/s.
    ///
    /// # Panics
    /// Where SGP4 fails: [`Self::new`] checked the flight and a minute beyond it, so only far
    /// outside it.
    pub fn ecef(&self, t: f64) -> StateVector {
        match self.try_ecef(t) {
            Ok(s) => s,
            Err(e) => panic!("TLE orbit at t = {t} s (checked at construction): {e}"),
        }
    }

    /// Position and velocity in the simulation's ECI frame at `t`, m and m/s.
    pub fn eci(&self, t: f64) -> StateVector {
        let e = self.ecef(t);
        let c = rz(OMEGA_EARTH * t);
        let w = Vector3::new(0.0, 0.0, OMEGA_EARTH);
        StateVector {
            r: c * e.r,
            v: c * (e.v + w.cross(&e.r)),
        }
    }
}

fn rz(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::truth::orbit::{MU_EARTH, R_EARTH};

    /// The bundled TLE (AO-73, a 1U CubeSat in a ~600 km sun-synchronous orbit).
    fn bundled() -> Tle {
        Tle::parse(include_str!("../../data/ao73.tle")).unwrap()
    }

    /// TEME → ECEF keeps the radius, puts the satellite at the altitude its mean motion
    /// implies, and its ECEF velocity is the TEME velocity less the Earth's rotation (the
    /// derivative of the ECEF position, not the inertial speed).
    #[test]
    fn ecef_radius_and_speed_follow_the_mean_motion_and_the_earth_rotation() {
        let tle = bundled();
        let n = tle.mean_motion();
        let a = (MU_EARTH / (n * n)).cbrt();
        let e = tle.elements.eccentricity;
        let epoch = tle.epoch_utc_s();
        for k in 0..12 {
            let utc = epoch + f64::from(k) * 500.0;
            let teme = tle.teme((utc - epoch) / 60.0).unwrap();
            let ecef = tle.ecef(utc).unwrap();
            let r = ecef.r.norm();
            assert!(
                (r - teme.r.norm()).abs() < 1e-6,
                "rotation changed the radius"
            );
            // within the eccentric orbit's radii (plus SGP4's few-km short-period terms)
            assert!(
                r > a * (1.0 - e) - 15e3 && r < a * (1.0 + e) + 15e3,
                "radius {r} vs a {a}, e {e}"
            );
            let altitude = r - R_EARTH;
            assert!((500e3..700e3).contains(&altitude), "{altitude} m");
            // inertial speed: vis-viva within 0.5 %
            let vis_viva = (MU_EARTH * (2.0 / r - 1.0 / a)).sqrt();
            assert!(
                (teme.v.norm() / vis_viva - 1.0).abs() < 5e-3,
                "{} vs {vis_viva}",
                teme.v.norm()
            );
            // ECEF: v − ω⊕ × r, by hand, and the numerical derivative of the ECEF position
            let w = Vector3::new(0.0, 0.0, OMEGA_EARTH);
            let by_hand = (teme.v - w.cross(&teme.r)).norm();
            assert!((ecef.v.norm() - by_hand).abs() < 1e-6);
            assert!(
                (ecef.v.norm() - teme.v.norm()).abs() > 1.0,
                "no Earth rotation"
            );
            let h = 0.5;
            let d = (tle.ecef(utc + h).unwrap().r - tle.ecef(utc - h).unwrap().r) / (2.0 * h);
            assert!((d - ecef.v).norm() < 0.05, "{}", (d - ecef.v).norm());
        }
    }

    /// The sidereal angle turns once a sidereal day and matches a textbook value (Vallado,
    /// example 3-5: 1992-08-20 12:14 UT1 → 152.578 787 886°).
    #[test]
    fn gmst_matches_vallado_and_turns_at_the_earth_rate() {
        // 1992-08-20 12:14:00 = JD 2448855.009722 → seconds since the GPS epoch
        let utc = (2_448_855.009_722 - GPS_EPOCH_JD) * DAY_S;
        assert!((gmst(utc).to_degrees() - 152.578_787_886).abs() < 1e-3);
        let rate = (gmst(utc + 60.0) - gmst(utc)) / 60.0;
        assert!((rate - OMEGA_EARTH).abs() < 1e-10, "{rate}");
    }

    /// In the simulation's ECI frame the velocity is the derivative of the position, and
    /// `t = 0` lies the requested span from the epoch.
    #[test]
    fn the_flown_orbit_is_consistent_in_the_simulation_frame() {
        let tle = bundled();
        let start = tle.epoch_utc_s() + GPS_MINUS_UTC_S + 3600.0;
        let o = TleOrbit::new(tle, start, 600.0).unwrap();
        assert!((o.minutes_from_epoch() - 60.0).abs() < 1e-9);
        for t in [0.0, 123.4, 600.0] {
            // a short step: no time quantization shows (the flight's `t` is kept apart from
            // the 1.3e9 s of UTC, which hold only 0.2 µs: 2 mm of orbit). SGP4's own
            // velocity differs from the derivative of its position by a few cm/s; the frame
            // changes must add nothing to that
            let h = 0.01;
            let d = (o.eci(t + h).r - o.eci(t - h).r) / (2.0 * h);
            let in_eci = (d - o.eci(t).v).norm();
            let m = |dt: f64| (o.start_from_epoch_s + t + dt) / 60.0;
            let teme = |dt: f64| o.tle.teme(m(dt)).unwrap();
            let d_teme = (teme(h).r - teme(-h).r) / (2.0 * h);
            let in_teme = (d_teme - teme(0.0).v).norm();
            assert!(in_teme < 0.1, "SGP4 itself: {in_teme} m/s");
            assert!((in_eci - in_teme).abs() < 1e-3, "{in_eci} vs {in_teme} m/s");
            assert!((o.eci(t).r.norm() - o.ecef(t).r.norm()).abs() < 1e-6);
        }
        assert!((o.eci(0.0).r - o.ecef(0.0).r).norm() < 1e-6);
    }

    #[test]
    fn malformed_sets_are_refused_with_their_cause() {
        assert!(matches!(Tle::parse("nothing"), Err(TleError::MissingLines)));
        let text = include_str!("../../data/ao73.tle").replace("97.6190", "97.6191");
        assert!(matches!(Tle::parse(&text), Err(TleError::Parse(_))));
    }
}
