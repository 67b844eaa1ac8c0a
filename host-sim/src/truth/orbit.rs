//! Low Earth orbit: Keplerian elements with the secular J2 drift, f64.
//!
//! Good to a few km over hours for a near-circular LEO, which is what the attitude scenarios
//! need: the orbit sets the line-of-sight geometry, the Doppler (±45 kHz at L1) and the
//! direction of nadir. Frames: ECI (true-of-date, simplified: the Earth rotates about its z axis
//! at [`OMEGA_EARTH`] from Greenwich angle `gmst0` at t = 0) and ECEF.

use nalgebra::{Matrix3, Vector3};

/// Earth's gravitational parameter, m³/s² (WGS-84).
pub const MU_EARTH: f64 = 3.986_004_418e14;
/// Earth's equatorial radius, m (WGS-84).
pub const R_EARTH: f64 = 6_378_137.0;
/// Second zonal harmonic (WGS-84).
pub const J2: f64 = 1.082_626_68e-3;
/// Earth's rotation rate, rad/s (WGS-84).
pub const OMEGA_EARTH: f64 = 7.292_115_146_7e-5;
/// Mean solar year, s.
const YEAR: f64 = 365.242_189_7 * 86_400.0;

/// Position and velocity, metres and m/s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StateVector {
    /// Position, m.
    pub r: Vector3<f64>,
    /// Velocity, m/s.
    pub v: Vector3<f64>,
}

/// Keplerian elements at t = 0 with secular J2 rates of the node, perigee and mean anomaly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    /// Semi-major axis, m.
    pub a: f64,
    /// Eccentricity.
    pub e: f64,
    /// Inclination, rad.
    pub i: f64,
    /// Right ascension of the ascending node at t = 0, rad.
    pub raan: f64,
    /// Argument of perigee at t = 0, rad.
    pub argp: f64,
    /// Mean anomaly at t = 0, rad.
    pub m0: f64,
    /// Greenwich sidereal angle at t = 0, rad.
    pub gmst0: f64,
}

impl Orbit {
    /// A circular sun-synchronous orbit at `altitude` metres: the inclination makes the J2 node
    /// drift equal to one turn per year. `raan`, `u0` (argument of latitude at t = 0) in rad.
    pub fn sun_synchronous(altitude: f64, raan: f64, u0: f64) -> Self {
        let a = R_EARTH + altitude;
        let n = (MU_EARTH / (a * a * a)).sqrt();
        // Ω̇ = −(3/2) n J2 (R/a)² cos i  =  2π / year
        let cos_i = -(2.0 * std::f64::consts::PI / YEAR) / (1.5 * n * J2 * (R_EARTH / a).powi(2));
        Self {
            a,
            e: 0.0,
            i: cos_i.acos(),
            raan,
            argp: 0.0,
            m0: u0,
            gmst0: 0.0,
        }
    }

    /// Mean motion, rad/s.
    pub fn mean_motion(&self) -> f64 {
        (MU_EARTH / self.a.powi(3)).sqrt()
    }

    /// Orbital period, s.
    pub fn period(&self) -> f64 {
        2.0 * std::f64::consts::PI / self.mean_motion()
    }

    /// Secular rates (node, perigee, mean anomaly) from J2, rad/s (Vallado, eq. 9-41).
    pub fn j2_rates(&self) -> (f64, f64, f64) {
        let n = self.mean_motion();
        let p = self.a * (1.0 - self.e * self.e);
        let k = 1.5 * n * J2 * (R_EARTH / p).powi(2);
        let (s, c) = self.i.sin_cos();
        let raan_dot = -k * c;
        let argp_dot = k * (2.0 - 2.5 * s * s);
        let m_dot = n + k * (1.0 - 1.5 * s * s) * (1.0 - self.e * self.e).sqrt();
        (raan_dot, argp_dot, m_dot)
    }

    /// Position and velocity in ECI at `t` seconds.
    pub fn eci(&self, t: f64) -> StateVector {
        let (raan_dot, argp_dot, m_dot) = self.j2_rates();
        let raan = self.raan + raan_dot * t;
        let argp = self.argp + argp_dot * t;
        let m = self.m0 + m_dot * t;
        // Kepler's equation, Newton, bounded (converges in < 6 steps for e < 0.1)
        let mut ecc = m;
        for _ in 0..20 {
            let d = (ecc - self.e * ecc.sin() - m) / (1.0 - self.e * ecc.cos());
            ecc -= d;
            if d.abs() < 1e-14 {
                break;
            }
        }
        let (se, ce) = ecc.sin_cos();
        let b = (1.0 - self.e * self.e).sqrt();
        // perifocal position and velocity (the along-track rate includes the drift of M)
        let r_pf = Vector3::new(self.a * (ce - self.e), self.a * b * se, 0.0);
        let edot = m_dot / (1.0 - self.e * ce);
        let v_pf = Vector3::new(-self.a * se * edot, self.a * b * ce * edot, 0.0);
        let rot = rz(raan) * rx(self.i) * rz(argp);
        // the frame itself turns at (Ω̇ about z) and (ω̇ about the orbit normal)
        let omega_frame = Vector3::new(0.0, 0.0, raan_dot) + rot * Vector3::new(0.0, 0.0, argp_dot);
        let r = rot * r_pf;
        StateVector {
            r,
            v: rot * v_pf + omega_frame.cross(&r),
        }
    }

    /// Greenwich sidereal angle at `t`, rad.
    pub fn gmst(&self, t: f64) -> f64 {
        self.gmst0 + OMEGA_EARTH * t
    }

    /// Position and velocity in ECEF at `t` seconds.
    pub fn ecef(&self, t: f64) -> StateVector {
        eci_to_ecef(&self.eci(t), self.gmst(t))
    }
}

/// The spacecraft's orbit: the built-in Keplerian one with secular J2, or SGP4 of a TLE
/// ([`super::tle`]). Both give the simulation's ECI frame (the ECEF frame frozen at `t = 0`:
/// Greenwich angle [`OMEGA_EARTH`]` t` for a TLE, `gmst0 + `[`OMEGA_EARTH`]` t` for [`Orbit`]).
#[derive(Clone, Debug, PartialEq)]
pub enum Trajectory {
    /// Keplerian elements with secular J2 (the scenarios' built-in orbits).
    Kepler(Orbit),
    /// SGP4 of a two-line element set (`--tle`).
    Tle(Box<super::tle::TleOrbit>),
}

impl From<Orbit> for Trajectory {
    fn from(o: Orbit) -> Self {
        Self::Kepler(o)
    }
}

impl Trajectory {
    /// Position and velocity in ECI at `t` seconds, m and m/s.
    pub fn eci(&self, t: f64) -> StateVector {
        match self {
            Self::Kepler(o) => o.eci(t),
            Self::Tle(o) => o.eci(t),
        }
    }

    /// Position and velocity in ECEF at `t` seconds, m and m/s.
    pub fn ecef(&self, t: f64) -> StateVector {
        match self {
            Self::Kepler(o) => o.ecef(t),
            Self::Tle(o) => o.ecef(t),
        }
    }

    /// Greenwich angle of the simulation's ECI frame at `t` (ECI = `R_z(θ)` ECEF), rad.
    pub fn gmst(&self, t: f64) -> f64 {
        match self {
            Self::Kepler(o) => o.gmst(t),
            Self::Tle(_) => OMEGA_EARTH * t,
        }
    }
}

/// ECI → ECEF for Greenwich angle `gmst` (rad): `r_e = R_z(−θ) r_i`,
/// `v_e = R_z(−θ) (v_i − ω⊕ × r_i)`.
pub fn eci_to_ecef(s: &StateVector, gmst: f64) -> StateVector {
    let c = rz(-gmst);
    let w = Vector3::new(0.0, 0.0, OMEGA_EARTH);
    StateVector {
        r: c * s.r,
        v: c * (s.v - w.cross(&s.r)),
    }
}

/// The DCM from the local orbital frame (LVLH: z to nadir, y against the orbit normal, x
/// completing the triad, close to the velocity) to the frame of `r`, `v`: `C_frame_lvlh`.
pub fn lvlh_to_frame(s: &StateVector) -> Matrix3<f64> {
    let z = -s.r.normalize();
    let y = -s.r.cross(&s.v).normalize();
    let x = y.cross(&z);
    Matrix3::from_columns(&[x, y, z])
}

fn rz(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

fn rx(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sun_synchronous_550_km_has_the_textbook_inclination_and_period() {
        let o = Orbit::sun_synchronous(550e3, 0.3, 0.0);
        assert!(
            (o.i.to_degrees() - 97.59).abs() < 0.02,
            "{}",
            o.i.to_degrees()
        );
        assert!((o.period() - 5739.0).abs() < 5.0, "{}", o.period());
        let (raan_dot, _, _) = o.j2_rates();
        assert!((raan_dot * YEAR - 2.0 * std::f64::consts::PI).abs() < 1e-9);
    }

    #[test]
    fn velocity_is_the_derivative_of_position_in_eci_and_ecef() {
        let o = Orbit {
            e: 0.01,
            argp: 0.4,
            ..Orbit::sun_synchronous(550e3, 1.0, 0.2)
        };
        for t in [0.0, 1234.5, 5000.0] {
            let h = 0.01;
            for f in [|o: &Orbit, t| o.eci(t), |o: &Orbit, t| o.ecef(t)] {
                let d = (f(&o, t + h).r - f(&o, t - h).r) / (2.0 * h);
                assert!(
                    (d - f(&o, t).v).norm() < 1e-3,
                    "t {t}: {}",
                    (d - f(&o, t).v).norm()
                );
            }
        }
    }

    #[test]
    fn circular_orbit_keeps_its_radius_and_speed() {
        let o = Orbit::sun_synchronous(550e3, 0.0, 0.0);
        for k in 0..20 {
            let s = o.eci(k as f64 * 300.0);
            assert!((s.r.norm() - o.a).abs() < 1e-3);
            assert!((s.v.norm() - 7585.0).abs() < 15.0, "{}", s.v.norm());
            let c = lvlh_to_frame(&s);
            assert!((c.transpose() * c - Matrix3::identity()).norm() < 1e-12);
            assert!((c.determinant() - 1.0).abs() < 1e-12);
        }
    }
}
