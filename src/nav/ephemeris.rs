//! The broadcast ephemeris of one satellite (subframes 1–3 of one issue), its plausibility
//! checks, and the IS-GPS-200 user algorithm for the satellite's position, velocity and clock
//! (20.3.3.3.3 and Table 20-IV, 20.3.3.3.3.1 for the clock, relativistic term and `T_GD`).
//!
//! Precision: all `f64`. A satellite position of 2.6·10⁷ m to 1 cm needs 4·10⁻¹⁰ relative
//! precision; f32 has 6·10⁻⁸.

use super::message::{ClockData, OrbitData2, OrbitData3};
use super::time::{wrap_half_week, GpsTime, TimeError};
use super::{F_RELATIVISTIC, MU_GPS, OMEGA_EARTH};

/// Bound on the Newton iterations of Kepler's equation (converges to 10⁻¹⁴ rad in four for
/// GPS eccentricities below 0.03).
pub const KEPLER_MAX_ITERATIONS: u32 = 10;
/// Kepler's equation is solved when a Newton step is below this, rad.
const KEPLER_TOLERANCE: f64 = 1e-14;

/// A complete, consistent broadcast ephemeris. Field names and units are RINEX 3's: radians,
/// seconds, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ephemeris {
    /// Satellite PRN, 1–32.
    pub prn: u8,
    /// Full GPS week of subframe 1's transmission.
    pub week: u16,
    /// Ephemeris reference time `t_oe`, s of the week.
    pub toe_s: f64,
    /// Clock reference time `t_oc`, s of the week.
    pub toc_s: f64,
    /// Issue of data, ephemeris.
    pub iode: u8,
    /// Issue of data, clock.
    pub iodc: u16,
    /// Six-bit SV health.
    pub health: u8,
    /// URA index.
    pub ura_index: u8,
    /// Fit interval flag.
    pub fit_interval: bool,
    /// `√A`, √m.
    pub sqrt_a: f64,
    /// Eccentricity.
    pub e: f64,
    /// Inclination at `t_oe`, rad.
    pub i0: f64,
    /// Longitude of the ascending node at the weekly epoch, rad.
    pub omega0: f64,
    /// Argument of perigee, rad.
    pub omega: f64,
    /// Mean anomaly at `t_oe`, rad.
    pub m0: f64,
    /// Mean motion difference, rad/s.
    pub delta_n: f64,
    /// Rate of inclination, rad/s.
    pub idot: f64,
    /// Rate of right ascension, rad/s.
    pub omega_dot: f64,
    /// Harmonic corrections to the argument of latitude, rad.
    pub cuc: f64,
    /// Sine correction to the argument of latitude, rad.
    pub cus: f64,
    /// Cosine correction to the radius, m.
    pub crc: f64,
    /// Sine correction to the radius, m.
    pub crs: f64,
    /// Cosine correction to the inclination, rad.
    pub cic: f64,
    /// Sine correction to the inclination, rad.
    pub cis: f64,
    /// Clock bias, s.
    pub af0: f64,
    /// Clock drift, s/s.
    pub af1: f64,
    /// Clock drift rate, s/s².
    pub af2: f64,
    /// Group delay `T_GD`, s.
    pub tgd: f64,
}

/// Limits of a plausible GPS ephemeris.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlausibilityLimits {
    /// Smallest `√A`, √m (GPS: 5153.6 √m, a = 26 560 km).
    pub min_sqrt_a: f64,
    /// Largest `√A`, √m.
    pub max_sqrt_a: f64,
    /// Eccentricities at or above this are refused.
    pub max_eccentricity: f64,
    /// Inclination range, rad (GPS: 55° ± a few).
    pub inclination_rad: (f64, f64),
    /// Largest `|a_f0|`, s (GPS clocks are steered within 1 ms).
    pub max_abs_af0_s: f64,
    /// Refuse an ephemeris whose subframe-1 health is not zero.
    pub require_healthy: bool,
}

impl Default for PlausibilityLimits {
    fn default() -> Self {
        Self {
            min_sqrt_a: 5050.0,
            max_sqrt_a: 5250.0,
            max_eccentricity: 0.03,
            inclination_rad: (45f64.to_radians(), 65f64.to_radians()),
            max_abs_af0_s: 1e-3,
            require_healthy: true,
        }
    }
}

/// Error returned by [`Ephemeris::check`] (and the store when it refuses a set).
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EphemerisError {
    /// The satellite reports itself unhealthy (subframe 1 health ≠ 0).
    #[error("satellite unhealthy (health {health})")]
    Unhealthy {
        /// The six-bit health.
        health: u8,
    },
    /// `√A` outside [`PlausibilityLimits`] (not a GPS orbit).
    #[error("semi-major axis outside GPS orbits")]
    SemiMajorAxis,
    /// Eccentricity at or above the limit.
    #[error("eccentricity too large")]
    Eccentricity,
    /// Inclination outside the limits.
    #[error("inclination outside GPS orbits")]
    Inclination,
    /// `|a_f0|` above the limit.
    #[error("clock bias implausible")]
    ClockBias,
    /// A field is not finite.
    #[error("non-finite ephemeris field")]
    NonFinite,
}

impl crate::error::Error for EphemerisError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::NonFinite => crate::error::ErrorKind::NonFinite,
            _ => crate::error::ErrorKind::InvalidInput,
        }
    }
}

/// Error returned by [`Ephemeris::satellite_state`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum OrbitError {
    /// The time was not finite.
    #[error("non-finite time")]
    NonFinite,
    /// `|t − t_oe|` exceeds [`MAX_EPHEMERIS_AGE_S`]: the ephemeris does not describe the
    /// orbit at that time.
    #[error("ephemeris too old or too new for the time")]
    Stale,
    /// Kepler's equation did not converge in [`KEPLER_MAX_ITERATIONS`].
    #[error("kepler iteration did not converge")]
    NotConverged,
    /// The corrected time of transmission is outside the representable weeks.
    #[error("time of transmission out of range")]
    Time(#[from] TimeError),
}

impl crate::error::Error for OrbitError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::NonFinite => crate::error::ErrorKind::NonFinite,
            Self::Stale => crate::error::ErrorKind::InvalidInput,
            Self::NotConverged => crate::error::ErrorKind::NotConverged,
            Self::Time(e) => crate::error::Error::kind(e),
        }
    }
}

/// Largest `|t − t_oe|` an ephemeris is used for, s (the 4 h fit interval is `t_oe ± 2 h`;
/// 4 h on either side leaves room for a receiver that has not seen the next issue yet).
pub const MAX_EPHEMERIS_AGE_S: f64 = 4.0 * 3600.0;

/// A satellite's position, velocity and clock at one GPS time (ECEF of that instant).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SatelliteState {
    /// Position, WGS-84 ECEF at the time it holds for, m.
    pub position_m: [f64; 3],
    /// Velocity, ECEF (rotating frame), m/s.
    pub velocity_m_s: [f64; 3],
    /// Satellite clock offset for an L1 C/A user `Δt_sv = a_f0 + a_f1 (t − t_oc) +
    /// a_f2 (t − t_oc)² + Δt_r − T_GD`, s (subtract from the satellite's time to get GPS
    /// time).
    pub clock_s: f64,
    /// Its rate, s/s.
    pub clock_rate: f64,
    /// The relativistic term `Δt_r = F e √A sin E_k` inside `clock_s`, s.
    pub relativistic_s: f64,
}

impl Ephemeris {
    /// Assembles subframes 1–3 of one issue: `None` unless the IODE of subframes 2 and 3 and
    /// the low eight bits of the IODC agree.
    pub fn from_subframes(
        prn: u8,
        week: u16,
        clock: &ClockData,
        orbit2: &OrbitData2,
        orbit3: &OrbitData3,
    ) -> Option<Self> {
        let consistent = orbit2.iode == orbit3.iode && (clock.iodc & 0xFF) as u8 == orbit2.iode;
        consistent.then_some(Self {
            prn,
            week,
            toe_s: orbit2.toe_s,
            toc_s: clock.toc_s,
            iode: orbit2.iode,
            iodc: clock.iodc,
            health: clock.health,
            ura_index: clock.ura_index,
            fit_interval: orbit2.fit_interval,
            sqrt_a: orbit2.sqrt_a,
            e: orbit2.e,
            i0: orbit3.i0,
            omega0: orbit3.omega0,
            omega: orbit3.omega,
            m0: orbit2.m0,
            delta_n: orbit2.delta_n,
            idot: orbit3.idot,
            omega_dot: orbit3.omega_dot,
            cuc: orbit2.cuc,
            cus: orbit2.cus,
            crc: orbit3.crc,
            crs: orbit2.crs,
            cic: orbit3.cic,
            cis: orbit3.cis,
            af0: clock.af0,
            af1: clock.af1,
            af2: clock.af2,
            tgd: clock.tgd_s,
        })
    }

    /// Checks the ephemeris against `limits`.
    ///
    /// # Errors
    /// The first limit it violates, as an [`EphemerisError`].
    pub fn check(&self, limits: &PlausibilityLimits) -> Result<(), EphemerisError> {
        let fields = [
            self.toe_s,
            self.toc_s,
            self.sqrt_a,
            self.e,
            self.i0,
            self.omega0,
            self.omega,
            self.m0,
            self.delta_n,
            self.idot,
            self.omega_dot,
            self.cuc,
            self.cus,
            self.crc,
            self.crs,
            self.cic,
            self.cis,
            self.af0,
            self.af1,
            self.af2,
            self.tgd,
        ];
        if fields.iter().any(|v| !v.is_finite()) {
            return Err(EphemerisError::NonFinite);
        }
        if limits.require_healthy && self.health != 0 {
            return Err(EphemerisError::Unhealthy {
                health: self.health,
            });
        }
        if !(self.sqrt_a >= limits.min_sqrt_a && self.sqrt_a <= limits.max_sqrt_a) {
            return Err(EphemerisError::SemiMajorAxis);
        }
        if !(self.e < limits.max_eccentricity) {
            return Err(EphemerisError::Eccentricity);
        }
        let (lo, hi) = limits.inclination_rad;
        if !(self.i0 >= lo && self.i0 <= hi) {
            return Err(EphemerisError::Inclination);
        }
        if !(libm::fabs(self.af0) <= limits.max_abs_af0_s) {
            return Err(EphemerisError::ClockBias);
        }
        Ok(())
    }

    /// The reference time `t_oe` as a [`GpsTime`] in the week nearest to the transmission
    /// week (a `t_oe` at the start of the next week is placed there).
    pub fn toe(&self) -> GpsTime {
        GpsTime {
            week: self.week,
            tow_s: self.toe_s,
        }
    }

    /// Satellite clock offset `Δt_sv` (L1 C/A, with the relativistic term and `T_GD`) at the
    /// satellite's own time `t_sv`, s; GPS time of transmission is `t_sv − Δt_sv`.
    ///
    /// # Errors
    /// As [`Self::satellite_state`].
    pub fn clock_offset_s(&self, t_sv: &GpsTime) -> Result<f64, OrbitError> {
        Ok(self.satellite_state(t_sv)?.clock_s)
    }

    /// Position, velocity (ECEF at `t`) and clock of the satellite at GPS time `t`
    /// (IS-GPS-200 Table 20-IV with the velocity terms of its 20.3.3.4.3.1 revision).
    ///
    /// # Errors
    /// [`OrbitError::NonFinite`], [`OrbitError::Stale`] beyond [`MAX_EPHEMERIS_AGE_S`],
    /// [`OrbitError::NotConverged`].
    pub fn satellite_state(&self, t: &GpsTime) -> Result<SatelliteState, OrbitError> {
        if !t.tow_s.is_finite() {
            return Err(OrbitError::NonFinite);
        }
        // t_k = t − t_oe, wrapped across the week crossover
        let tk = wrap_half_week(t.seconds_since(&self.toe()));
        if !(libm::fabs(tk) <= MAX_EPHEMERIS_AGE_S) {
            return Err(OrbitError::Stale);
        }
        let a = self.sqrt_a * self.sqrt_a;
        // n = √(μ/A³) + Δn ; M_k = M0 + n t_k
        let n = libm::sqrt(MU_GPS / (a * a * a)) + self.delta_n;
        let mk = self.m0 + n * tk;
        let ek = solve_kepler(mk, self.e)?;
        let (sin_e, cos_e) = (libm::sin(ek), libm::cos(ek));
        let one_minus = 1.0 - self.e * cos_e;
        let root = libm::sqrt(1.0 - self.e * self.e);
        // true anomaly ν_k and argument of latitude Φ_k = ν_k + ω
        let nu = libm::atan2(root * sin_e, cos_e - self.e);
        let phi = nu + self.omega;
        let (s2, c2) = (libm::sin(2.0 * phi), libm::cos(2.0 * phi));
        // second harmonic perturbations
        let du = self.cus * s2 + self.cuc * c2;
        let dr = self.crs * s2 + self.crc * c2;
        let di = self.cis * s2 + self.cic * c2;
        let u = phi + du;
        let r = a * one_minus + dr;
        let i = self.i0 + di + self.idot * tk;
        let (su, cu) = (libm::sin(u), libm::cos(u));
        let (xp, yp) = (r * cu, r * su);
        // Ω_k = Ω0 + (Ω̇ − Ω̇e) t_k − Ω̇e t_oe
        let omega_k_dot = self.omega_dot - OMEGA_EARTH;
        let om = self.omega0 + omega_k_dot * tk - OMEGA_EARTH * self.toe_s;
        let (so, co) = (libm::sin(om), libm::cos(om));
        let (si, ci) = (libm::sin(i), libm::cos(i));
        let position_m = [xp * co - yp * ci * so, xp * so + yp * ci * co, yp * si];
        // rates: Ė, ν̇, and the harmonic terms' derivatives
        let e_dot = n / one_minus;
        let nu_dot = e_dot * root / one_minus;
        let i_dot = self.idot + 2.0 * nu_dot * (self.cis * c2 - self.cic * s2);
        let u_dot = nu_dot + 2.0 * nu_dot * (self.cus * c2 - self.cuc * s2);
        let r_dot = self.e * a * e_dot * sin_e + 2.0 * nu_dot * (self.crs * c2 - self.crc * s2);
        let xp_dot = r_dot * cu - r * u_dot * su;
        let yp_dot = r_dot * su + r * u_dot * cu;
        let velocity_m_s = [
            -xp * omega_k_dot * so + xp_dot * co
                - yp_dot * so * ci
                - yp * (omega_k_dot * co * ci - i_dot * so * si),
            xp * omega_k_dot * co + xp_dot * so + yp_dot * co * ci
                - yp * (omega_k_dot * so * ci + i_dot * co * si),
            yp_dot * si + yp * i_dot * ci,
        ];
        // clock: Δt_sv = a_f0 + a_f1 Δt + a_f2 Δt² + Δt_r − T_GD, Δt = t − t_oc
        let dt = wrap_half_week(t.tow_s - self.toc_s);
        let relativistic_s = F_RELATIVISTIC * self.e * self.sqrt_a * sin_e;
        let relativistic_rate = F_RELATIVISTIC * self.e * self.sqrt_a * cos_e * e_dot;
        Ok(SatelliteState {
            position_m,
            velocity_m_s,
            clock_s: self.af0 + self.af1 * dt + self.af2 * dt * dt + relativistic_s - self.tgd,
            clock_rate: self.af1 + 2.0 * self.af2 * dt + relativistic_rate,
            relativistic_s,
        })
    }

    /// The satellite at the GPS time of transmission of a signal whose satellite-clock
    /// time of transmission is `t_sv`: `t = t_sv − Δt_sv(t_sv)` (IS-GPS-200 20.3.3.3.3.1; the
    /// clock is evaluated at `t_sv`, whose error is below 10⁻¹² s). The state is computed once,
    /// at `t_sv`, and carried to `t` along the velocity: the error `½ |a| Δt_sv²` is below
    /// 1 µm for `|Δt_sv| ≤ 1 ms`. Returns `(t, state)`.
    ///
    /// # Errors
    /// As [`Self::satellite_state`].
    pub fn state_at_transmission(
        &self,
        t_sv: &GpsTime,
    ) -> Result<(GpsTime, SatelliteState), OrbitError> {
        let mut state = self.satellite_state(t_sv)?;
        let offset = state.clock_s;
        let t = t_sv.add_seconds(-offset)?;
        for (p, v) in state.position_m.iter_mut().zip(state.velocity_m_s.iter()) {
            *p -= v * offset;
        }
        Ok((t, state))
    }

    /// The state at `t + dt` from the state at `t` for a small `dt` (a light-time step),
    /// along the velocity: error `½ |a| dt²` (0.6 m/s² for GPS: 3 mm at `dt` = 0.1 s, µm at
    /// the millisecond corrections of a light-time iteration).
    pub fn extrapolate(state: &SatelliteState, dt: f64) -> SatelliteState {
        let mut out = *state;
        for (p, v) in out.position_m.iter_mut().zip(state.velocity_m_s.iter()) {
            *p += v * dt;
        }
        out.clock_s += state.clock_rate * dt;
        out
    }
}

/// Kepler's equation `M = E − e sin E` by Newton's method from `E = M`, bounded by
/// [`KEPLER_MAX_ITERATIONS`].
///
/// # Errors
/// [`OrbitError::NotConverged`]; [`OrbitError::NonFinite`] for non-finite input.
pub fn solve_kepler(mean_anomaly: f64, e: f64) -> Result<f64, OrbitError> {
    if !mean_anomaly.is_finite() || !e.is_finite() {
        return Err(OrbitError::NonFinite);
    }
    let mut ek = mean_anomaly;
    for _ in 0..KEPLER_MAX_ITERATIONS {
        let step = (ek - e * libm::sin(ek) - mean_anomaly) / (1.0 - e * libm::cos(ek));
        ek -= step;
        if libm::fabs(step) < KEPLER_TOLERANCE {
            return Ok(ek);
        }
    }
    Err(OrbitError::NotConverged)
}
