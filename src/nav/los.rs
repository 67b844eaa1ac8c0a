//! Lines of sight from the receiver's navigation state to the satellites, with their rates, in
//! the frame the attitude is expressed in.
//!
//! The direction is the one the signal arrives from: the satellite at its time of
//! transmission `t − τ` (the orbit computed once at `t − 75 ms`, the light time iterated
//! [`LIGHT_TIME_ITERATIONS`] times along the satellite's velocity: 3 mm at most for the
//! ±70 ms a LEO's flight times differ from the guess), carried into the
//! ECEF frame of the reception by the Earth's rotation during `τ` (Sagnac). host-sim's truth
//! uses instantaneous geometry instead; the two differ by `v_sat τ / ρ ≈ 1.3·10⁻⁵ rad`, which a
//! 0.5 m baseline turns into 7 µm of single difference.
//!
//! # Frames ([`ReferenceFrame`])
//!
//! * `Ecef`: WGS-84 ECEF.
//! * `Inertial { epoch }`: the ECEF frame frozen at the GPS time `epoch`, i.e.
//!   `u_i = R_z(ω⊕ (t − epoch)) u_e` and `u̇_i = R_z(…) (u̇_e + ω⊕ × u_e)`. This is host-sim's
//!   ECI (`truth::sky`: "the simulation's ECI frame is the ECEF frame frozen at t = 0", GPS
//!   time of week `gps_time_of_week_s` at t = 0), the frame of the microsat scenario's
//!   `SatelliteAiding` lines of sight and of its attitude `C_ib`.
//! * `LocalNed`: north-east-down at the receiver's position (the frame of `host-sim track`'s
//!   sky file and its 3-2-1 angles); the rate is the ECEF rate in those axes (the NED frame
//!   of a moving receiver also turns, by `v/R ≈ 10⁻³ rad/s` in orbit, which this leaves out).
//!
//! Precision: positions f64, unit vectors and rates f32.

use nalgebra::{Matrix3, Vector3};

use super::ephemeris::{Ephemeris, OrbitError};
use super::filter::NavState;
use super::geodesy::{elevation_azimuth, Geodetic};
use super::solution::small_rotation;
use super::time::GpsTime;
use super::{OMEGA_EARTH, SPEED_OF_LIGHT};
use crate::receiver::SatelliteAiding;

/// Light-time iterations (each reduces the error by `v/c ≈ 10⁻⁵`; two reach 10⁻¹⁰ s).
pub const LIGHT_TIME_ITERATIONS: u32 = 3;
/// First guess of the signal flight, s.
const FLIGHT_GUESS_S: f64 = 0.075;

/// The frame lines of sight are expressed in.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ReferenceFrame {
    /// WGS-84 ECEF.
    Ecef,
    /// ECEF frozen at `epoch` (host-sim's ECI).
    Inertial {
        /// GPS time at which the inertial frame coincides with ECEF.
        epoch: GpsTime,
    },
    /// North-east-down at the receiver.
    LocalNed,
}

/// Error returned by [`line_of_sight`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum LosError {
    /// The satellite's position could not be computed.
    #[error("satellite orbit")]
    Orbit(#[from] OrbitError),
    /// Receiver and satellite coincide, or the receiver state is not finite.
    #[error("degenerate geometry")]
    Degenerate,
}

impl crate::error::Error for LosError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::Orbit(e) => crate::error::Error::kind(e),
            Self::Degenerate => crate::error::ErrorKind::InvalidInput,
        }
    }
}

/// One satellite's line of sight.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LineOfSight {
    /// Satellite PRN.
    pub prn: u8,
    /// GPS time of the reception it holds at.
    pub time: GpsTime,
    /// Unit vector receiver → satellite, reference frame.
    pub los: [f32; 3],
    /// Its time derivative, reference frame, 1/s.
    pub los_rate: [f32; 3],
    /// Elevation above the receiver's local horizontal (negative below it), rad.
    pub elevation_rad: f32,
    /// Geometric range, m.
    pub range_m: f64,
    /// Range rate, m/s.
    pub range_rate_m_s: f32,
}

impl LineOfSight {
    /// The receiver's aiding for this satellite at receiver epoch `epoch` (the line of
    /// sight must be in the frame the receiver's attitude is wanted in).
    pub fn to_aiding(&self, epoch: u64) -> SatelliteAiding {
        SatelliteAiding {
            prn: self.prn,
            epoch,
            los: self.los,
            los_rate: self.los_rate,
        }
    }
}

/// The line of sight from `receiver` to the satellite of `ephemeris`, in `frame`.
///
/// # Errors
/// [`LosError::Orbit`]; [`LosError::Degenerate`].
pub fn line_of_sight(
    receiver: &NavState,
    ephemeris: &Ephemeris,
    frame: &ReferenceFrame,
) -> Result<LineOfSight, LosError> {
    let rx = Vector3::from(receiver.position_m);
    let vx = Vector3::from(receiver.velocity_m_s);
    if !(rx.iter().chain(vx.iter()).all(|v| v.is_finite())) {
        return Err(LosError::Degenerate);
    }
    // the satellite once at t − τ0, then the light time iterated along its velocity
    let t0 = receiver
        .time
        .add_seconds(-FLIGHT_GUESS_S)
        .map_err(OrbitError::from)?;
    let s0 = ephemeris.satellite_state(&t0)?;
    let (mut p, mut v) = (Vector3::zeros(), Vector3::zeros());
    let mut tau = FLIGHT_GUESS_S;
    for _ in 0..LIGHT_TIME_ITERATIONS {
        let s = Ephemeris::extrapolate(&s0, FLIGHT_GUESS_S - tau);
        // into the ECEF frame of the reception: R_z(−ω⊕ τ)
        let (st, ct) = small_rotation(-OMEGA_EARTH * tau);
        let c = Matrix3::new(ct, -st, 0.0, st, ct, 0.0, 0.0, 0.0, 1.0);
        p = c * Vector3::from(s.position_m);
        v = c * Vector3::from(s.velocity_m_s);
        tau = (p - rx).norm() / SPEED_OF_LIGHT;
    }
    let d = p - rx;
    let range = d.norm();
    if !(range > 1.0) {
        return Err(LosError::Degenerate);
    }
    let u = d / range;
    let dv = v - vx;
    // u̇ = (Δv − u (uᵀ Δv)) / ρ
    let range_rate = u.dot(&dv);
    let u_dot = (dv - u * range_rate) / range;
    let elevation = libm::asin(u.dot(&rx.normalize()).clamp(-1.0, 1.0)) as f32;
    let (los, los_rate) = to_frame(receiver, &u, &u_dot, frame);
    Ok(LineOfSight {
        prn: ephemeris.prn,
        time: receiver.time,
        los: [los.x as f32, los.y as f32, los.z as f32],
        los_rate: [los_rate.x as f32, los_rate.y as f32, los_rate.z as f32],
        elevation_rad: elevation,
        range_m: range,
        range_rate_m_s: range_rate as f32,
    })
}

/// ECEF unit vector and rate into `frame`.
fn to_frame(
    receiver: &NavState,
    u: &Vector3<f64>,
    u_dot: &Vector3<f64>,
    frame: &ReferenceFrame,
) -> (Vector3<f64>, Vector3<f64>) {
    match frame {
        ReferenceFrame::Ecef => (*u, *u_dot),
        ReferenceFrame::Inertial { epoch } => {
            let c = rz(OMEGA_EARTH * receiver.time.seconds_since(epoch));
            let w = Vector3::new(0.0, 0.0, OMEGA_EARTH);
            (c * u, c * (u_dot + w.cross(u)))
        }
        ReferenceFrame::LocalNed => match Geodetic::from_ecef(&receiver.position_m) {
            Some(g) => {
                let c = g.ecef_to_ned().cast::<f64>();
                (c * u, c * u_dot)
            }
            None => (*u, *u_dot),
        },
    }
}

/// Elevation and azimuth (rad) of a line of sight given in local NED.
pub fn ned_elevation_azimuth(los: &LineOfSight) -> (f32, f32) {
    elevation_azimuth(&Vector3::from(los.los))
}

/// `R_z(a)`.
fn rz(a: f64) -> Matrix3<f64> {
    let (s, c) = (libm::sin(a), libm::cos(a));
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}
