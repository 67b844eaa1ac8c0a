//! A position/velocity filter for a receiver in low Earth orbit: two-body + J2 gravity in the
//! rotating ECEF frame (Coriolis and centrifugal terms), fourth-order Runge–Kutta in bounded
//! steps, and an error-state Kalman filter ([`crate::ekf::Ekf`], six states, Joseph form,
//! gated) that takes the single-point fixes as measurements (loosely coupled). Between fixes
//! and through outages it predicts, so the lines of sight keep coming.
//!
//! Precision: the nominal position and velocity are `f64` (7·10⁶ m to a millimetre); the error
//! state, its covariance and the transition matrix are `f32`.
//!
//! Dynamics left out: drag, the higher harmonics, Sun and Moon (together 10⁻⁵–10⁻⁴ m/s² at
//! 550 km); [`OrbitFilterConfig::acceleration_sigma_m_s2`] covers them as white noise.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use super::solution::Fix;
use super::time::{GpsTime, TimeError};
use super::{MU_GPS, OMEGA_EARTH};
use crate::ekf::FilterError;
use crate::ekf::{Ekf, GateConfidence, NisGate};

/// Earth's second zonal harmonic (WGS-84 / EGM96 `J2`).
pub const J2: f64 = 1.082_626_68e-3;
/// Equatorial radius of the J2 term, m.
pub const R_EARTH_M: f64 = 6_378_137.0;

/// Configuration of [`OrbitFilter`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OrbitFilterConfig {
    /// White acceleration noise of the unmodelled forces, m/s² (per axis, √(PSD·s)).
    pub acceleration_sigma_m_s2: f32,
    /// Largest integration step, s.
    pub max_step_s: f64,
    /// Largest prediction interval of one call, s (bounds the steps of a call:
    /// `max_predict_s / max_step_s`).
    pub max_predict_s: f64,
    /// Gate on a fix (NIS of its position and velocity); `None` accepts every fix.
    pub gate: Option<GateConfidence>,
    /// After this many gated fixes in a row the filter restarts from the next fix.
    pub max_rejections: u32,
}

impl Default for OrbitFilterConfig {
    fn default() -> Self {
        Self {
            acceleration_sigma_m_s2: 2e-4,
            max_step_s: 10.0,
            max_predict_s: 600.0,
            gate: Some(GateConfidence::P999),
            max_rejections: 5,
        }
    }
}

/// Error returned by the [`OrbitFilter`] operations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum OrbitFilterError {
    /// The first fix has no velocity (an orbit cannot be propagated from a position).
    #[error("fix without velocity")]
    NoVelocity,
    /// A prediction interval longer than [`OrbitFilterConfig::max_predict_s`].
    #[error("prediction interval too long")]
    TooLong,
    /// The position is inside the Earth or not finite.
    #[error("state not an orbit")]
    NotAnOrbit,
    /// The Kalman filter refused.
    #[error("filter step")]
    Filter(#[from] FilterError),
    /// A time out of range.
    #[error("time out of range")]
    Time(#[from] TimeError),
}

impl crate::error::Error for OrbitFilterError {
    fn kind(&self) -> crate::error::ErrorKind {
        use crate::error::ErrorKind;
        match self {
            Self::NoVelocity | Self::TooLong => ErrorKind::InvalidInput,
            Self::NotAnOrbit => ErrorKind::Numerical,
            Self::Filter(e) => crate::error::Error::kind(e),
            Self::Time(e) => crate::error::Error::kind(e),
        }
    }
}

/// The receiver's navigation state.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NavState {
    /// GPS time the state holds at.
    pub time: GpsTime,
    /// Position, ECEF, m.
    pub position_m: [f64; 3],
    /// Velocity, ECEF, m/s.
    pub velocity_m_s: [f64; 3],
    /// Standard deviation of the position (root of the covariance trace), m.
    pub position_sigma_m: f32,
    /// Standard deviation of the velocity (root of the covariance trace), m/s.
    pub velocity_sigma_m_s: f32,
}

/// What a fix did to the filter.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FixOutcome {
    /// Whether it was used.
    pub accepted: bool,
    /// Its normalized innovation squared.
    pub nis: f32,
    /// Whether the filter restarted from it.
    pub restarted: bool,
}

/// The LEO position/velocity filter.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OrbitFilter {
    config: OrbitFilterConfig,
    time: GpsTime,
    r: [f64; 3],
    v: [f64; 3],
    ekf: Ekf<6, f32>,
    rejections: u32,
}

type State6 = SVector<f32, 6>;
type Matrix6 = SMatrix<f32, 6, 6>;

impl OrbitFilter {
    /// A filter started from a fix with a velocity.
    ///
    /// # Errors
    /// [`OrbitFilterError::NoVelocity`], [`OrbitFilterError::NotAnOrbit`],
    /// [`OrbitFilterError::Filter`] for a covariance that is not positive definite.
    pub fn from_fix(fix: &Fix, config: OrbitFilterConfig) -> Result<Self, OrbitFilterError> {
        let v = fix.velocity_m_s.ok_or(OrbitFilterError::NoVelocity)?;
        let r = fix.position_m;
        check_orbit(&r)?;
        let ekf = Ekf::new(State6::zeros(), fix_covariance(fix))?;
        Ok(Self {
            config,
            time: fix.time,
            r,
            v: v.map(f64::from),
            ekf,
            rejections: 0,
        })
    }

    /// The current state.
    pub fn state(&self) -> NavState {
        let p = self.ekf.covariance();
        let pos_var = p[(0, 0)] + p[(1, 1)] + p[(2, 2)];
        let vel_var = p[(3, 3)] + p[(4, 4)] + p[(5, 5)];
        NavState {
            time: self.time,
            position_m: self.r,
            velocity_m_s: self.v,
            position_sigma_m: crate::sqrtf(pos_var.max(0.0)),
            velocity_sigma_m_s: crate::sqrtf(vel_var.max(0.0)),
        }
    }

    /// The covariance of the error state (position m, velocity m/s; ECEF).
    pub fn covariance(&self) -> &SMatrix<f32, 6, 6> {
        self.ekf.covariance()
    }

    /// Predicts the state to `t` (forward or backward) in steps of at most
    /// [`OrbitFilterConfig::max_step_s`].
    ///
    /// # Errors
    /// [`OrbitFilterError::TooLong`] beyond [`OrbitFilterConfig::max_predict_s`] (call
    /// repeatedly for longer outages); [`OrbitFilterError::NotAnOrbit`];
    /// [`OrbitFilterError::Filter`]. The filter is unchanged on error.
    pub fn predict_to(&mut self, t: &GpsTime) -> Result<(), OrbitFilterError> {
        let dt = t.seconds_since(&self.time);
        if !(libm::fabs(dt) <= self.config.max_predict_s) {
            return Err(OrbitFilterError::TooLong);
        }
        let max_step = self.config.max_step_s.max(1e-3);
        let steps = libm::ceil(libm::fabs(dt) / max_step).max(1.0) as u32;
        let h = dt / f64::from(steps);
        let mut next = self.clone();
        for _ in 0..steps {
            next.step(h)?;
        }
        next.time = *t;
        *self = next;
        Ok(())
    }

    /// One integration step of `h` seconds: nominal state by RK4, covariance by the
    /// second-order transition matrix.
    fn step(&mut self, h: f64) -> Result<(), OrbitFilterError> {
        let phi = transition(&self.r, h as f32);
        let q = process_noise(self.config.acceleration_sigma_m_s2, libm::fabs(h) as f32);
        let (r, v) = rk4(&self.r, &self.v, h);
        check_orbit(&r)?;
        // the error state is zero between updates: x⁻ = Φ·0
        self.ekf.predict_to(&State6::zeros(), &phi, &q)?;
        self.r = r;
        self.v = v;
        Ok(())
    }

    /// Predicts to the fix's time and updates with its position and, when it has one, its
    /// velocity.
    ///
    /// # Errors
    /// As [`Self::predict_to`]; the filter is unchanged on error.
    pub fn update(&mut self, fix: &Fix) -> Result<FixOutcome, OrbitFilterError> {
        let mut next = self.clone();
        next.predict_to(&fix.time)?;
        let y = innovation(&next, fix);
        let r = fix_covariance(fix);
        let report = match fix.velocity_m_s {
            Some(_) => {
                let gate = self.config.gate.map(|g| NisGate::chi_square(6, g));
                let h = Matrix6::identity();
                let rep = next.ekf.update(&y, &h, &r, gate)?;
                (rep.accepted, rep.nis)
            }
            None => {
                let gate = self.config.gate.map(|g| NisGate::chi_square(3, g));
                let h = SMatrix::<f32, 3, 6>::identity();
                let y3 = y.fixed_rows::<3>(0).into_owned();
                let r3 = r.fixed_view::<3, 3>(0, 0).into_owned();
                let rep = next.ekf.update(&y3, &h, &r3, gate)?;
                (rep.accepted, rep.nis)
            }
        };
        let (accepted, nis) = report;
        if !accepted {
            return self.rejected(fix, nis);
        }
        let dx = *next.ekf.state();
        for k in 0..3 {
            next.r[k] += f64::from(dx[k]);
            next.v[k] += f64::from(dx[k + 3]);
        }
        next.ekf.set_state(State6::zeros())?;
        next.rejections = 0;
        *self = next;
        Ok(FixOutcome {
            accepted: true,
            nis,
            restarted: false,
        })
    }

    /// Counts a gated fix; restarts from it after [`OrbitFilterConfig::max_rejections`].
    fn rejected(&mut self, fix: &Fix, nis: f32) -> Result<FixOutcome, OrbitFilterError> {
        self.rejections = self.rejections.saturating_add(1);
        let restart = self.rejections >= self.config.max_rejections && fix.velocity_m_s.is_some();
        if restart {
            *self = Self::from_fix(fix, self.config)?;
        }
        Ok(FixOutcome {
            accepted: restart,
            nis,
            restarted: restart,
        })
    }
}

/// The fix's covariance `R`: position from the fix's covariance, velocity from its
/// variances (zero rows when it has none; only the position block is used then).
fn fix_covariance(fix: &Fix) -> Matrix6 {
    let mut r = Matrix6::zeros();
    for i in 0..3 {
        for j in 0..3 {
            r[(i, j)] = fix.position_covariance_m2[i][j];
        }
        r[(i + 3, i + 3)] = fix.velocity_variance_m2_s2[i].max(VELOCITY_VARIANCE_FLOOR);
    }
    r
}

/// Smallest velocity variance of a fix, m²/s² (a perfect Doppler fix would freeze the
/// filter).
const VELOCITY_VARIANCE_FLOOR: f32 = 1e-6;

/// `z − x̂` in f64, then f32 (zero velocity rows for a fix without velocity).
fn innovation(filter: &OrbitFilter, fix: &Fix) -> State6 {
    let mut y = State6::zeros();
    for k in 0..3 {
        y[k] = (fix.position_m[k] - filter.r[k]) as f32;
        if let Some(v) = fix.velocity_m_s {
            y[k + 3] = (f64::from(v[k]) - filter.v[k]) as f32;
        }
    }
    y
}

fn check_orbit(r: &[f64; 3]) -> Result<(), OrbitFilterError> {
    let n = libm::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    if n.is_finite() && n > R_EARTH_M * 0.9 {
        Ok(())
    } else {
        Err(OrbitFilterError::NotAnOrbit)
    }
}

/// Acceleration in the rotating ECEF frame: two-body + J2, Coriolis, centrifugal, m/s².
pub fn acceleration(r: &[f64; 3], v: &[f64; 3]) -> [f64; 3] {
    let [x, y, z] = *r;
    let r2 = x * x + y * y + z * z;
    let rn = libm::sqrt(r2);
    let mu_r3 = MU_GPS / (r2 * rn);
    // a_J2 = −(3/2) J2 μ R² / r⁵ · [x(1 − 5z²/r²), y(1 − 5z²/r²), z(3 − 5z²/r²)]
    let k = 1.5 * J2 * MU_GPS * R_EARTH_M * R_EARTH_M / (r2 * r2 * rn);
    let zz = 5.0 * z * z / r2;
    let w = OMEGA_EARTH;
    [
        -mu_r3 * x - k * x * (1.0 - zz) + 2.0 * w * v[1] + w * w * x,
        -mu_r3 * y - k * y * (1.0 - zz) - 2.0 * w * v[0] + w * w * y,
        -mu_r3 * z - k * z * (3.0 - zz),
    ]
}

/// One RK4 step of `h` seconds.
fn rk4(r: &[f64; 3], v: &[f64; 3], h: f64) -> ([f64; 3], [f64; 3]) {
    let add =
        |a: &[f64; 3], b: &[f64; 3], s: f64| [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]];
    let k1v = acceleration(r, v);
    let k1r = *v;
    let r2 = add(r, &k1r, h / 2.0);
    let v2 = add(v, &k1v, h / 2.0);
    let k2v = acceleration(&r2, &v2);
    let r3 = add(r, &v2, h / 2.0);
    let v3 = add(v, &k2v, h / 2.0);
    let k3v = acceleration(&r3, &v3);
    let r4 = add(r, &v3, h);
    let v4 = add(v, &k3v, h);
    let k4v = acceleration(&r4, &v4);
    let mut rn = *r;
    let mut vn = *v;
    for i in 0..3 {
        rn[i] += h / 6.0 * (k1r[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]);
        vn[i] += h / 6.0 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i]);
    }
    (rn, vn)
}

/// `Φ = I + A h + (A h)²/2` with `A = [[0, I], [G, −2[ω×]]]`, `G` the two-body gravity
/// gradient plus the centrifugal term (J2's gradient is three orders smaller).
fn transition(r: &[f64; 3], h: f32) -> Matrix6 {
    let rv = Vector3::new(r[0] as f32, r[1] as f32, r[2] as f32);
    let rn = rv.norm();
    let u = rv / rn;
    let rn64 = f64::from(rn);
    let mu_r3 = (MU_GPS / (rn64 * rn64 * rn64)) as f32;
    let w = OMEGA_EARTH as f32;
    // G = μ/r³ (3 û ûᵀ − I) + diag(ω², ω², 0)
    let g = (u * u.transpose() * 3.0 - Matrix3::identity()) * mu_r3
        + Matrix3::from_diagonal(&Vector3::new(w * w, w * w, 0.0));
    let coriolis = Matrix3::new(0.0, 2.0 * w, 0.0, -2.0 * w, 0.0, 0.0, 0.0, 0.0, 0.0);
    let mut a = Matrix6::zeros();
    a.fixed_view_mut::<3, 3>(0, 3).fill_with_identity();
    a.fixed_view_mut::<3, 3>(3, 0).copy_from(&g);
    a.fixed_view_mut::<3, 3>(3, 3).copy_from(&coriolis);
    let ah = a * h;
    Matrix6::identity() + ah + ah * ah * 0.5
}

/// White-acceleration process noise over `h` seconds:
/// `q [[h³/3 I, h²/2 I], [h²/2 I, h I]]`, `q = σ_a²`.
fn process_noise(sigma: f32, h: f32) -> Matrix6 {
    let q = sigma * sigma;
    let mut m = Matrix6::zeros();
    for i in 0..3 {
        m[(i, i)] = q * h * h * h / 3.0;
        m[(i, i + 3)] = q * h * h / 2.0;
        m[(i + 3, i)] = q * h * h / 2.0;
        m[(i + 3, i + 3)] = q * h;
    }
    m
}
