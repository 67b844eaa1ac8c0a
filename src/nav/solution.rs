//! Single-point position, velocity and clock from pseudoranges and Dopplers: iterated
//! weighted least squares (bounded), Earth rotation during the signal flight, the broadcast
//! ionosphere and a troposphere for ground users, DOP, and a residual check that finds and
//! excludes one bad satellite (RAIM-style fault detection and exclusion).
//!
//! # Model
//!
//! `ρ_i = |R_z(−ω⊕ τ_i) r_i − r| + b − c Δt_sv,i + I_i + T_i + ε_i`, with `r_i` the satellite
//! at its time of transmission (ECEF of that instant), `τ_i` the flight time (the rotation
//! `R_z(−ω⊕ τ_i)` carries the satellite into the ECEF frame of the reception: the Sagnac
//! correction), `b` the receiver clock bias in metres. Range rates
//! `−λ f_D,i = u_iᵀ (v_i − v) + ḃ − c Δṫ_sv,i` give the velocity and the clock drift with the
//! same geometry rows `[−u_iᵀ, 1]`.
//!
//! # Precision
//!
//! The state (position, clock bias) and every range are `f64`; residuals, the design matrix,
//! the 4×4 normal equations and their Cholesky factor are `f32` (residuals after the first
//! iteration are metres; unit vectors and DOP need no more than f32). Velocity is `f32`.
//!
//! # Residual check
//!
//! With `n > 4` satellites the weighted sum of squared residuals is χ² with `n − 4` degrees of
//! freedom. Above the configured quantile, each satellite in turn is left out and the solution
//! repeated (at most [`MAX_SATELLITES`] extra solutions, each bounded); the subset with the
//! smallest sum that passes its own test is kept and the excluded PRN reported. With five
//! satellites a fault is detected but cannot be isolated ([`FixError::ResidualCheck`]).

use heapless::Vec;
use nalgebra::{Cholesky, Matrix4, Vector3, Vector4};

use super::atmosphere::{klobuchar_delay_m, troposphere_delay_m};
use super::ephemeris::{Ephemeris, OrbitError};
use super::geodesy::{elevation_azimuth, Geodetic};
use super::message::KlobucharParameters;
use super::pseudorange::{pseudorange_m, TransmitTime, TransmitTimeError};
use super::store::NavigationStore;
use super::time::{GpsTime, TimeError};
use super::{L1_WAVELENGTH_M, OMEGA_EARTH, SPEED_OF_LIGHT};
use crate::ekf::{chi_square_quantile, GateConfidence};

/// Most satellites a fix uses.
pub const MAX_SATELLITES: usize = 12;

/// Where the solver finds ephemerides.
pub trait EphemerisSource {
    /// The ephemeris of `prn`, if known.
    fn ephemeris(&self, prn: u8) -> Option<&Ephemeris>;
}

impl EphemerisSource for NavigationStore {
    fn ephemeris(&self, prn: u8) -> Option<&Ephemeris> {
        Self::ephemeris(self, prn)
    }
}

impl EphemerisSource for [Ephemeris] {
    fn ephemeris(&self, prn: u8) -> Option<&Ephemeris> {
        self.iter().find(|e| e.prn == prn)
    }
}

/// One satellite's measurements at the common receive time.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Observation {
    /// Satellite PRN.
    pub prn: u8,
    /// Time of transmission on the satellite's clock.
    pub transmit: GpsTime,
    /// Pseudorange `c (t_rx − t_sv)`, m.
    pub pseudorange_m: f64,
    /// Measured L1 Doppler (positive when approaching; the receiver clock drift included),
    /// Hz; `None` leaves the satellite out of the velocity solution.
    pub doppler_hz: Option<f32>,
    /// Pseudorange standard deviation, m (weights `1/σ²`).
    pub sigma_m: f32,
}

impl Observation {
    /// An observation from a channel's time of transmission and the receiver-clock time of
    /// the same instant.
    ///
    /// # Errors
    /// As [`pseudorange_m`] and [`TransmitTime::gps_time`].
    pub fn from_transmit_time(
        transmit: &TransmitTime,
        receive: &GpsTime,
        doppler_hz: Option<f32>,
        sigma_m: f32,
    ) -> Result<Self, TransmitTimeError> {
        Ok(Self {
            prn: transmit.prn,
            transmit: transmit.gps_time()?,
            pseudorange_m: pseudorange_m(receive, transmit)?,
            doppler_hz,
            sigma_m,
        })
    }
}

/// Configuration of [`solve`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SolverConfig {
    /// Bound on the Gauss–Newton iterations of one solution.
    pub max_iterations: u8,
    /// The iteration stops when the position and clock step is below this, m.
    pub convergence_m: f32,
    /// Satellites below this elevation are left out (ground users), rad; `None` keeps all
    /// (a receiver in orbit sees satellites below its horizon).
    pub elevation_mask_rad: Option<f32>,
    /// Apply the broadcast ionosphere (when the parameters are given).
    pub ionosphere: bool,
    /// Apply the troposphere.
    pub troposphere: bool,
    /// Residual check and exclusion of one satellite at this confidence; `None` skips it.
    pub raim: Option<GateConfidence>,
    /// Range-rate standard deviation of a Doppler, m/s.
    pub doppler_sigma_m_s: f32,
}

impl SolverConfig {
    /// A receiver on the ground: 5° mask, ionosphere and troposphere, residual check at
    /// 99.9 %.
    pub fn ground() -> Self {
        Self {
            max_iterations: 12,
            convergence_m: 1e-3,
            elevation_mask_rad: Some(5f32.to_radians()),
            ionosphere: true,
            troposphere: true,
            raim: Some(GateConfidence::P999),
            doppler_sigma_m_s: 0.1,
        }
    }

    /// A receiver in low Earth orbit: no mask, no atmosphere (above the troposphere and most
    /// of the ionosphere), residual check at 99.9 %.
    pub fn leo() -> Self {
        Self {
            elevation_mask_rad: None,
            ionosphere: false,
            troposphere: false,
            ..Self::ground()
        }
    }
}

/// Dilutions of precision (dimensionless; `HDOP`/`VDOP` in the local level frame).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Dop {
    /// Geometric.
    pub gdop: f32,
    /// Position.
    pub pdop: f32,
    /// Horizontal.
    pub hdop: f32,
    /// Vertical.
    pub vdop: f32,
    /// Time.
    pub tdop: f32,
}

/// A navigation fix.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Fix {
    /// GPS time of the reception: the receiver-clock time minus the clock bias.
    pub time: GpsTime,
    /// Receiver position, WGS-84 ECEF at [`Fix::time`], m.
    pub position_m: [f64; 3],
    /// Receiver clock bias `b = c δt_r`, m.
    pub clock_bias_m: f64,
    /// Receiver velocity, ECEF, m/s (when at least four used satellites had a Doppler).
    pub velocity_m_s: Option<[f32; 3]>,
    /// Receiver clock drift `c δṫ_r`, m/s.
    pub clock_drift_m_s: Option<f32>,
    /// Position covariance `(Hᵀ W H)⁻¹`, ECEF, m².
    pub position_covariance_m2: [[f32; 3]; 3],
    /// Velocity variance per axis (diagonal of its covariance), m²/s².
    pub velocity_variance_m2_s2: [f32; 3],
    /// Dilutions of precision.
    pub dop: Dop,
    /// Satellites used.
    pub satellites: u8,
    /// The satellite the residual check excluded.
    pub excluded_prn: Option<u8>,
    /// Observations left out: no ephemeris, below the mask, or beyond [`MAX_SATELLITES`].
    pub skipped: u8,
    /// Weighted sum of squared residuals (χ² with `satellites − 4` degrees of freedom).
    pub chi_square: f32,
    /// RMS of the pseudorange residuals, m.
    pub residual_rms_m: f32,
    /// Gauss–Newton iterations of the final solution.
    pub iterations: u8,
}

/// Error returned by [`solve`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FixError {
    /// Fewer than four usable satellites.
    #[error("{available} usable satellites, 4 needed")]
    TooFewSatellites {
        /// Satellites with an ephemeris above the mask.
        available: u8,
    },
    /// A pseudorange, Doppler, σ or time was not finite, or a σ not positive.
    #[error("non-finite or invalid observation")]
    InvalidObservation,
    /// A satellite position could not be computed.
    #[error("satellite orbit")]
    Orbit(#[from] OrbitError),
    /// The geometry is singular (normal equations not positive definite).
    #[error("singular geometry")]
    Singular,
    /// The iteration did not converge within [`SolverConfig::max_iterations`].
    #[error("least squares did not converge")]
    NotConverged,
    /// The residual check failed and no single exclusion passes it.
    #[error("residual check failed")]
    ResidualCheck {
        /// The weighted sum of squared residuals of the full set.
        chi_square_milli: u32,
    },
    /// The corrected time of reception is out of range.
    #[error("time out of range")]
    Time(#[from] TimeError),
}

impl crate::error::Error for FixError {
    fn kind(&self) -> crate::error::ErrorKind {
        use crate::error::ErrorKind;
        match self {
            Self::TooFewSatellites { .. } | Self::Singular | Self::ResidualCheck { .. } => {
                ErrorKind::Unobservable
            }
            Self::InvalidObservation => ErrorKind::InvalidInput,
            Self::Orbit(e) => crate::error::Error::kind(e),
            Self::NotConverged => ErrorKind::NotConverged,
            Self::Time(e) => crate::error::Error::kind(e),
        }
    }
}

/// One satellite prepared for the solution.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Prepared {
    prn: u8,
    position: [f64; 3],
    velocity: [f64; 3],
    clock_m: f64,
    clock_rate_m_s: f64,
    pseudorange_m: f64,
    range_rate_m_s: Option<f32>,
    weight: f32,
    used: bool,
}

/// Per-satellite geometry at the current estimate.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
struct Row {
    /// Unit line of sight receiver → satellite, ECEF of the reception.
    u: Vector3<f32>,
    /// Pseudorange residual, m.
    residual: f32,
    /// The satellite's velocity rotated into the reception frame, m/s.
    velocity: Vector3<f64>,
    elevation: f32,
}

/// Result of one least-squares solution on the used satellites.
#[derive(Clone, Copy, Debug)]
struct LsSolution {
    x: [f64; 4],
    normal_inverse: Matrix4<f32>,
    chi_square: f32,
    used: u8,
    iterations: u8,
}

/// Single-point position, velocity and clock at the receiver-clock time `receive` from
/// `observations` (at most [`MAX_SATELLITES`] are used) with the ephemerides of `source` and
/// the broadcast ionosphere `iono` (used when [`SolverConfig::ionosphere`]), started from
/// `initial` (ECEF, m; the Earth's centre when `None`).
///
/// # Errors
/// See [`FixError`].
pub fn solve<S: EphemerisSource + ?Sized>(
    observations: &[Observation],
    source: &S,
    iono: Option<&KlobucharParameters>,
    receive: &GpsTime,
    initial: Option<&[f64; 3]>,
    config: &SolverConfig,
) -> Result<Fix, FixError> {
    let (mut sats, mut skipped) = prepare(observations, source)?;
    let atmosphere = Atmosphere {
        iono: iono.filter(|_| config.ionosphere),
        troposphere: config.troposphere,
        tow_s: receive.tow_s,
    };
    let start = initial.map_or([0.0; 4], |p| [p[0], p[1], p[2], 0.0]);
    let mut ls = least_squares(&mut sats, start, config, &atmosphere)?;
    if let Some(mask) = config.elevation_mask_rad {
        let removed = apply_mask(&mut sats, &ls.x, mask, &atmosphere);
        if removed > 0 {
            skipped = skipped.saturating_add(removed);
            ls = least_squares(&mut sats, ls.x, config, &atmosphere)?;
        }
    }
    let mut excluded_prn = None;
    if let Some(confidence) = config.raim {
        if let Some((prn, better)) =
            residual_check(&mut sats, &ls, config, &atmosphere, confidence)?
        {
            excluded_prn = Some(prn);
            ls = better;
        }
    }
    finish(
        &sats,
        &ls,
        receive,
        excluded_prn,
        skipped,
        config,
        &atmosphere,
    )
}

/// Satellite states at their times of transmission.
fn prepare<S: EphemerisSource + ?Sized>(
    observations: &[Observation],
    source: &S,
) -> Result<(Vec<Prepared, MAX_SATELLITES>, u8), FixError> {
    let mut sats: Vec<Prepared, MAX_SATELLITES> = Vec::new();
    let mut skipped = 0u8;
    for o in observations {
        let valid = o.pseudorange_m.is_finite()
            && o.sigma_m > 0.0
            && o.sigma_m.is_finite()
            && o.doppler_hz.is_none_or(f32::is_finite);
        if !valid {
            return Err(FixError::InvalidObservation);
        }
        let Some(eph) = source.ephemeris(o.prn) else {
            skipped = skipped.saturating_add(1);
            continue;
        };
        let (_, state) = eph.state_at_transmission(&o.transmit)?;
        let p = Prepared {
            prn: o.prn,
            position: state.position_m,
            velocity: state.velocity_m_s,
            clock_m: state.clock_s * SPEED_OF_LIGHT,
            clock_rate_m_s: state.clock_rate * SPEED_OF_LIGHT,
            pseudorange_m: o.pseudorange_m,
            range_rate_m_s: o.doppler_hz.map(|d| -d * L1_WAVELENGTH_M as f32),
            weight: 1.0 / (o.sigma_m * o.sigma_m),
            used: true,
        };
        if sats.push(p).is_err() {
            skipped = skipped.saturating_add(1);
        }
    }
    Ok((sats, skipped))
}

/// What the atmosphere adds to the ranges.
struct Atmosphere<'a> {
    iono: Option<&'a KlobucharParameters>,
    troposphere: bool,
    tow_s: f64,
}

impl Atmosphere<'_> {
    fn active(&self) -> bool {
        self.iono.is_some() || self.troposphere
    }

    /// Delay of one satellite, m.
    fn delay_m(&self, at: &Option<Geodetic>, u_ned: &Vector3<f32>) -> f32 {
        let Some(g) = at else { return 0.0 };
        let (el, az) = elevation_azimuth(u_ned);
        let mut d = 0.0;
        if let Some(p) = self.iono {
            d += klobuchar_delay_m(
                p,
                g.lat_rad as f32,
                g.lon_rad as f32,
                el.max(0.0),
                az,
                self.tow_s,
            );
        }
        if self.troposphere {
            d += troposphere_delay_m(g.height_m as f32, el.max(0.0));
        }
        d
    }
}

/// Below this distance from the Earth's centre the estimate is not yet a position
/// (the iteration starts at the centre): no elevation, no atmosphere.
const MIN_POSITION_RADIUS_M: f64 = 6.0e6;

/// The geometry row of satellite `s` at the estimate `x` (position, clock bias).
fn row(s: &Prepared, x: &[f64; 4], at: &Option<Geodetic>, atm: &Atmosphere) -> Row {
    let d0 = [
        s.position[0] - x[0],
        s.position[1] - x[1],
        s.position[2] - x[2],
    ];
    let range0 = libm::sqrt(d0[0] * d0[0] + d0[1] * d0[1] + d0[2] * d0[2]);
    // Earth rotation during the flight τ: the satellite in the frame of the reception
    let (st, ct) = small_rotation(OMEGA_EARTH * range0 / SPEED_OF_LIGHT);
    let p = [
        ct * s.position[0] + st * s.position[1],
        -st * s.position[0] + ct * s.position[1],
        s.position[2],
    ];
    let v = Vector3::new(
        ct * s.velocity[0] + st * s.velocity[1],
        -st * s.velocity[0] + ct * s.velocity[1],
        s.velocity[2],
    );
    let d = [p[0] - x[0], p[1] - x[1], p[2] - x[2]];
    let range = libm::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    let u = Vector3::new(
        (d[0] / range) as f32,
        (d[1] / range) as f32,
        (d[2] / range) as f32,
    );
    let (u_ned, elevation) = match at {
        Some(g) => {
            let n = g.ecef_to_ned() * u;
            (n, elevation_azimuth(&n).0)
        }
        None => (Vector3::zeros(), core::f32::consts::FRAC_PI_2),
    };
    let delay = atm.delay_m(at, &u_ned);
    let predicted = range + x[3] - s.clock_m + f64::from(delay);
    Row {
        u,
        residual: (s.pseudorange_m - predicted) as f32,
        velocity: v,
        elevation,
    }
}

/// `(sin θ, cos θ)` of the Earth's rotation during a signal flight, `θ = ω⊕ τ ≤ 2.5·10⁻⁵ rad`
/// (τ ≤ 0.3 s): `θ` and `1 − θ²/2` are exact to 10⁻¹⁵ there and spare two f64 soft-float
/// trigonometric calls per satellite and iteration on the target.
pub(crate) fn small_rotation(theta: f64) -> (f64, f64) {
    (theta, 1.0 - 0.5 * theta * theta)
}

fn position_of(x: &[f64; 4]) -> Option<Geodetic> {
    let r = libm::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    (r > MIN_POSITION_RADIUS_M)
        .then(|| Geodetic::from_ecef(&[x[0], x[1], x[2]]))
        .flatten()
}

/// Gauss–Newton on the used satellites from `x0`, bounded by `max_iterations`.
fn least_squares(
    sats: &mut [Prepared],
    x0: [f64; 4],
    config: &SolverConfig,
    atm: &Atmosphere,
) -> Result<LsSolution, FixError> {
    let used = crate::count(sats.iter().filter(|s| s.used));
    if used < 4 {
        return Err(FixError::TooFewSatellites {
            available: used as u8,
        });
    }
    let mut x = x0;
    for iteration in 1..=config.max_iterations {
        let at = if atm.active() { position_of(&x) } else { None };
        let (normal, gradient, _) = normal_equations(sats, &x, &at, atm);
        let chol = Cholesky::new(normal).ok_or(FixError::Singular)?;
        let dx = chol.solve(&gradient);
        for (xi, di) in x.iter_mut().zip(dx.iter()) {
            *xi += f64::from(*di);
        }
        if !x.iter().all(|v| v.is_finite()) {
            return Err(FixError::Singular);
        }
        if dx.norm() < config.convergence_m {
            let at = if atm.active() { position_of(&x) } else { None };
            let (normal, _, chi_square) = normal_equations(sats, &x, &at, atm);
            let chol = Cholesky::new(normal).ok_or(FixError::Singular)?;
            return Ok(LsSolution {
                x,
                normal_inverse: chol.inverse(),
                chi_square,
                used: used as u8,
                iterations: iteration,
            });
        }
    }
    Err(FixError::NotConverged)
}

/// `Hᵀ W H`, `Hᵀ W y` and `yᵀ W y` over the used satellites.
fn normal_equations(
    sats: &[Prepared],
    x: &[f64; 4],
    at: &Option<Geodetic>,
    atm: &Atmosphere,
) -> (Matrix4<f32>, Vector4<f32>, f32) {
    let mut normal = Matrix4::zeros();
    let mut gradient = Vector4::zeros();
    let mut chi_square = 0.0f32;
    for s in sats.iter().filter(|s| s.used) {
        let r = row(s, x, at, atm);
        let h = Vector4::new(-r.u.x, -r.u.y, -r.u.z, 1.0);
        // N += w h hᵀ ; g += w h y
        normal += h * h.transpose() * s.weight;
        gradient += h * (s.weight * r.residual);
        chi_square += s.weight * r.residual * r.residual;
    }
    (normal, gradient, chi_square)
}

/// Leaves out the satellites below `mask`; returns how many.
fn apply_mask(sats: &mut [Prepared], x: &[f64; 4], mask: f32, atm: &Atmosphere) -> u8 {
    let Some(at) = position_of(x) else { return 0 };
    let mut removed = 0u8;
    for s in sats.iter_mut().filter(|s| s.used) {
        if row(s, x, &Some(at), atm).elevation < mask {
            s.used = false;
            removed = removed.saturating_add(1);
        }
    }
    removed
}

fn chi_square_threshold(used: u8, confidence: GateConfidence) -> Option<f32> {
    let dof = usize::from(used).checked_sub(4).filter(|&d| d > 0)?;
    chi_square_quantile(dof, confidence).map(|q| q as f32)
}

/// The residual test; on failure, the best single exclusion that passes.
fn residual_check(
    sats: &mut [Prepared],
    ls: &LsSolution,
    config: &SolverConfig,
    atm: &Atmosphere,
    confidence: GateConfidence,
) -> Result<Option<(u8, LsSolution)>, FixError> {
    let Some(threshold) = chi_square_threshold(ls.used, confidence) else {
        return Ok(None);
    };
    if ls.chi_square <= threshold {
        return Ok(None);
    }
    let fault = FixError::ResidualCheck {
        chi_square_milli: (ls.chi_square * 1000.0).min(u32::MAX as f32) as u32,
    };
    let mut best: Option<(usize, LsSolution)> = None;
    for k in 0..sats.len() {
        if !sats.get(k).is_some_and(|s| s.used) {
            continue;
        }
        set_used(sats, k, false);
        let candidate = least_squares(sats, ls.x, config, atm);
        set_used(sats, k, true);
        let Ok(c) = candidate else { continue };
        let passes = chi_square_threshold(c.used, confidence).is_some_and(|t| c.chi_square <= t);
        if passes
            && best
                .as_ref()
                .is_none_or(|(_, b)| c.chi_square < b.chi_square)
        {
            best = Some((k, c));
        }
    }
    let (k, solution) = best.ok_or(fault)?;
    set_used(sats, k, false);
    let prn = sats.get(k).map_or(0, |s| s.prn);
    warn!("residual check excluded prn {}", prn);
    Ok(Some((prn, solution)))
}

fn set_used(sats: &mut [Prepared], k: usize, used: bool) {
    if let Some(s) = sats.get_mut(k) {
        s.used = used;
    }
}

/// Velocity, DOP and the fix.
fn finish(
    sats: &[Prepared],
    ls: &LsSolution,
    receive: &GpsTime,
    excluded_prn: Option<u8>,
    skipped: u8,
    config: &SolverConfig,
    atm: &Atmosphere,
) -> Result<Fix, FixError> {
    let at = position_of(&ls.x);
    let dop = dop(sats, &ls.x, &at, atm);
    let velocity = velocity(sats, &ls.x, &at, atm, config.doppler_sigma_m_s);
    let q = ls.normal_inverse;
    let mut cov = [[0.0f32; 3]; 3];
    for (i, row) in cov.iter_mut().enumerate() {
        for (j, c) in row.iter_mut().enumerate() {
            *c = q[(i, j)];
        }
    }
    let n = f32::from(ls.used.max(1));
    let weight_mean = sats
        .iter()
        .filter(|s| s.used)
        .map(|s| s.weight)
        .sum::<f32>()
        / n;
    let residual_rms_m = crate::sqrtf(ls.chi_square / n / weight_mean.max(f32::MIN_POSITIVE));
    Ok(Fix {
        time: receive.add_seconds(-ls.x[3] / SPEED_OF_LIGHT)?,
        position_m: [ls.x[0], ls.x[1], ls.x[2]],
        clock_bias_m: ls.x[3],
        velocity_m_s: velocity.map(|v| [v.0[0], v.0[1], v.0[2]]),
        clock_drift_m_s: velocity.map(|v| v.0[3]),
        position_covariance_m2: cov,
        velocity_variance_m2_s2: velocity.map_or([0.0; 3], |v| v.1),
        dop,
        satellites: ls.used,
        excluded_prn,
        skipped,
        chi_square: ls.chi_square,
        residual_rms_m,
        iterations: ls.iterations,
    })
}

/// Unweighted DOP from `(HᵀH)⁻¹`, horizontal and vertical in the local level frame.
fn dop(sats: &[Prepared], x: &[f64; 4], at: &Option<Geodetic>, atm: &Atmosphere) -> Dop {
    let mut normal = Matrix4::<f32>::zeros();
    for s in sats.iter().filter(|s| s.used) {
        let r = row(s, x, at, atm);
        let h = Vector4::new(-r.u.x, -r.u.y, -r.u.z, 1.0);
        normal += h * h.transpose();
    }
    let Some(chol) = Cholesky::new(normal) else {
        return Dop::default();
    };
    let q = chol.inverse();
    let qp = q.fixed_view::<3, 3>(0, 0).into_owned();
    let (h2, v2) = match at {
        Some(g) => {
            let c = g.ecef_to_ned();
            let ned = c * qp * c.transpose();
            (ned[(0, 0)] + ned[(1, 1)], ned[(2, 2)])
        }
        None => (qp[(0, 0)] + qp[(1, 1)], qp[(2, 2)]),
    };
    let root = |v: f32| crate::sqrtf(v.max(0.0));
    Dop {
        gdop: root(q.trace()),
        pdop: root(qp.trace()),
        hdop: root(h2),
        vdop: root(v2),
        tdop: root(q[(3, 3)]),
    }
}

/// Velocity and clock drift from the range rates of the used satellites that have one;
/// `None` with fewer than four. Returns `([vx, vy, vz, drift], variances of vx, vy, vz)`.
fn velocity(
    sats: &[Prepared],
    x: &[f64; 4],
    at: &Option<Geodetic>,
    atm: &Atmosphere,
    sigma_m_s: f32,
) -> Option<([f32; 4], [f32; 3])> {
    let mut normal = Matrix4::<f32>::zeros();
    let mut gradient = Vector4::<f32>::zeros();
    let mut count = 0u32;
    for s in sats.iter().filter(|s| s.used) {
        let Some(rate) = s.range_rate_m_s else {
            continue;
        };
        let r = row(s, x, at, atm);
        let vs = Vector3::new(
            r.velocity.x as f32,
            r.velocity.y as f32,
            r.velocity.z as f32,
        );
        // −λ f_D = uᵀ(v_s − v) + ḃ − c Δṫ_sv  ⇒  y = −λ f_D − uᵀ v_s + c Δṫ_sv = [−uᵀ, 1]·[v, ḃ]
        let y = rate - r.u.dot(&vs) + s.clock_rate_m_s as f32;
        let h = Vector4::new(-r.u.x, -r.u.y, -r.u.z, 1.0);
        normal += h * h.transpose();
        gradient += h * y;
        count = count.saturating_add(1);
    }
    if count < 4 {
        return None;
    }
    let chol = Cholesky::new(normal)?;
    let v = chol.solve(&gradient);
    let q = chol.inverse() * (sigma_m_s * sigma_m_s);
    let out = [v[0], v[1], v[2], v[3]];
    out.iter()
        .all(|c| c.is_finite())
        .then_some((out, [q[(0, 0)], q[(1, 1)], q[(2, 2)]]))
}
