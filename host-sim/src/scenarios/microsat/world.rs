//! The microsatellite's world (f64 truth): a 550 km sun-synchronous orbit, the GPS
//! constellation of the bundled almanac, the attitude history, the three-antenna array on the
//! zenith face, each antenna's view of the sky, the C/N0 and the faults that act on the signal.

use gnss_attitude::geometry::Quaternion;
use nalgebra::{Matrix3, Vector3};

use crate::synth::lnav::BUNDLED_ALMANAC_WEEK;
use crate::synth::quantize::Quantizer;
use crate::truth::attitude::{AttitudeTruth, DetumblingBody, NadirTumble};
use crate::truth::gps::{Almanac, WEEK_S};
use crate::truth::orbit::{Orbit, Trajectory};
use crate::truth::sky::{GpsView, SkyModel, L1_WAVELENGTH_M};
use crate::truth::tle::{Tle, TleError, TleOrbit};

/// Side of the antenna triangle, m.
pub const TRIANGLE_SIDE_M: f64 = 0.5;
/// Elevation mask above each antenna's horizon, rad.
pub const MASK_RAD: f64 = 10.0 * std::f64::consts::PI / 180.0;
/// Altitude of the orbit, m.
pub const ALTITUDE_M: f64 = 550e3;

/// The attitude history of the run.
pub enum Motion {
    /// Nadir pointing with a slow spin about the boresight and a wobble (the default).
    Nadir(NadirTumble),
    /// A body after separation, its rates damped by a magnetorquer-like torque.
    Detumbling(DetumblingBody),
}

impl AttitudeTruth for Motion {
    fn q_ib(&self, t: f64) -> Quaternion<f64> {
        match self {
            Self::Nadir(m) => m.q_ib(t),
            Self::Detumbling(m) => m.q_ib(t),
        }
    }

    fn omega_b(&self, t: f64) -> Vector3<f64> {
        match self {
            Self::Nadir(m) => m.omega_b(t),
            Self::Detumbling(m) => m.omega_b(t),
        }
    }
}

/// An antenna: phase centre and boresight in body axes.
#[derive(Clone, Copy, Debug)]
pub struct Antenna {
    /// Phase centre, body axes, m.
    pub position: Vector3<f64>,
    /// Boresight (unit), body axes.
    pub boresight: Vector3<f64>,
}

/// One satellite as the truth sees it at one instant.
#[derive(Clone, Copy, Debug)]
pub struct SatTruth {
    /// The geometry (ECI).
    pub view: GpsView,
    /// Elevation above each antenna's horizon, rad.
    pub elevation: [f64; 3],
    /// Azimuth in the antenna plane of antenna A (from body +x towards +y), rad.
    pub azimuth: f64,
    /// Whether each antenna receives the satellite (above its mask, not occulted, not blocked).
    pub visible: [bool; 3],
    /// C/N0 at each antenna (of the satellite, before blockage), dB-Hz.
    pub cn0_dbhz: [f64; 3],
}

impl SatTruth {
    /// The satellite as the correlators behind `front_end` see it: C/N0 lowered by the
    /// quantizer's loss ([`Quantizer::theory_loss_db`]).
    pub fn after_front_end(&self, front_end: Quantizer) -> Self {
        Self {
            cn0_dbhz: self.cn0_dbhz.map(|c| c - front_end.theory_loss_db()),
            ..*self
        }
    }
}

/// A time interval during which one antenna receives nothing.
#[derive(Clone, Copy, Debug)]
pub struct Blockage {
    /// Antenna (0 = A, 1 = B, 2 = C).
    pub antenna: usize,
    /// Start, s.
    pub start: f64,
    /// End, s.
    pub end: f64,
}

/// The world.
pub struct World {
    /// Orbit and constellation.
    pub sky: SkyModel,
    /// Attitude history.
    pub motion: Motion,
    /// The antennas A, B, C.
    pub antennas: [Antenna; 3],
    /// Line biases of A, B, C (carrier phase added by each RF chain): new at each power-up,
    /// drifting with temperature.
    pub line_bias: LineBiasTruth,
    /// Blockages.
    pub blockages: Vec<Blockage>,
    /// The error of the flight computer's navigation (orbit and ephemerides), applied to every
    /// view the receiver is aided with.
    pub navigation: NavigationError,
}

/// σ per axis of the onboard orbit's position error, m (a single-frequency single-point fix
/// filtered onboard).
pub const NAV_POSITION_SIGMA_M: f64 = 10.0;
/// σ per axis of the onboard orbit's velocity error, m/s.
pub const NAV_VELOCITY_SIGMA_M_S: f64 = 0.05;
/// σ per axis of a GPS satellite's position from the broadcast ephemeris, m.
pub const EPHEMERIS_POSITION_SIGMA_M: f64 = 2.0;
/// Period of the onboard orbit error's slow oscillation (once per orbit), s.
pub const NAV_ERROR_PERIOD_S: f64 = 5_700.0;
/// Along-track error of the flight computer's copy of a TLE (`--tle`), m: its orbit is the
/// truth's TLE this far ahead (a fresh TLE's typical error is of order 1 km, mostly along
/// the track).
pub const TLE_ALONG_TRACK_ERROR_M: f64 = 1_000.0;

/// The flight computer's own orbit when it propagates a TLE: the truth's trajectory
/// `ahead_s` later (an along-track error of [`TLE_ALONG_TRACK_ERROR_M`]).
#[derive(Clone, Debug, PartialEq)]
pub struct OnboardOrbit {
    /// The trajectory it propagates.
    pub orbit: Trajectory,
    /// How far ahead along it the onboard copy is, s.
    pub ahead_s: f64,
}

/// What the flight computer's navigation gets wrong: its own orbit (a position error that
/// oscillates once per orbit, and a velocity error) and each GPS satellite's ephemeris position
/// (fixed over the flight). Drawn once per run from its seed; zero for [`Self::none`].
#[derive(Clone, Debug, PartialEq)]
pub struct NavigationError {
    /// Amplitude of the orbit position error per ECI axis, m.
    pub position_m: [f64; 3],
    /// Phase of the orbit error's oscillation per axis, rad.
    pub phase_rad: [f64; 3],
    /// Orbit velocity error per ECI axis, m/s.
    pub velocity_m_s: [f64; 3],
    /// Ephemeris position error per PRN (index PRN − 1), ECI, m.
    pub ephemeris_m: Vec<[f64; 3]>,
    /// The onboard TLE (`--tle`): when present, its error replaces the drawn orbit error
    /// (`position_m`, `phase_rad`, `velocity_m_s`); the ephemeris errors stay.
    pub onboard: Option<OnboardOrbit>,
}

impl NavigationError {
    /// No error (the examples and the tests of the geometry).
    pub fn none() -> Self {
        Self {
            position_m: [0.0; 3],
            phase_rad: [0.0; 3],
            velocity_m_s: [0.0; 3],
            ephemeris_m: vec![[0.0; 3]; 32],
            onboard: None,
        }
    }

    /// A navigation error drawn with the σ above from `seed`.
    pub fn draw(seed: u64) -> Self {
        use rand::{Rng, SeedableRng};
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut normal = |sigma: f64| -> f64 {
            let x: f64 = StandardNormal.sample(&mut rng);
            sigma * x
        };
        // the amplitude of a sinusoid whose RMS is σ: √2 σ
        let position_m = [(); 3].map(|_| normal(NAV_POSITION_SIGMA_M * std::f64::consts::SQRT_2));
        let velocity_m_s = [(); 3].map(|_| normal(NAV_VELOCITY_SIGMA_M_S));
        let ephemeris_m = (0..32)
            .map(|_| [(); 3].map(|_| normal(EPHEMERIS_POSITION_SIGMA_M)))
            .collect();
        let phase_rad = [(); 3].map(|_| rng.random_range(0.0..std::f64::consts::TAU));
        Self {
            position_m,
            phase_rad,
            velocity_m_s,
            ephemeris_m,
            onboard: None,
        }
    }

    /// The onboard orbit's position error at `t`, ECI, m.
    pub fn position_error(&self, t: f64) -> Vector3<f64> {
        if let Some(o) = &self.onboard {
            return o.orbit.eci(t + o.ahead_s).r - o.orbit.eci(t).r;
        }
        let w = std::f64::consts::TAU / NAV_ERROR_PERIOD_S;
        Vector3::from([0, 1, 2].map(|i| self.position_m[i] * (w * t + self.phase_rad[i]).sin()))
    }

    /// The onboard orbit's velocity error at `t`, ECI, m/s.
    pub fn velocity_error(&self, t: f64) -> Vector3<f64> {
        match &self.onboard {
            Some(o) => o.orbit.eci(t + o.ahead_s).v - o.orbit.eci(t).v,
            None => Vector3::from(self.velocity_m_s),
        }
    }

    /// `view` as the flight computer predicts it at `t`: line of sight, range and Doppler
    /// from its own orbit and the broadcast ephemeris instead of the truth's.
    pub fn predicted(&self, view: &GpsView, t: f64) -> GpsView {
        let ephemeris = self
            .ephemeris_m
            .get(usize::from(view.prn).wrapping_sub(1))
            .map_or(Vector3::zeros(), |e| Vector3::from(*e));
        let relative = view.los * view.range + ephemeris - self.position_error(t);
        let range = relative.norm();
        let los = relative / range;
        let range_rate = view.range_rate - los.dot(&self.velocity_error(t));
        GpsView {
            position: view.position + ephemeris,
            los,
            range,
            range_rate,
            doppler_hz: view.doppler_hz - (range_rate - view.range_rate) / L1_WAVELENGTH_M,
            ..*view
        }
    }
}

/// Largest line-bias drift rate of one RF chain, rad/s (a few degrees per hour: 5°/h).
pub const LINE_BIAS_DRIFT_MAX_RAD_S: f64 = 5.0 * std::f64::consts::PI / 180.0 / 3600.0;

/// The carrier phase each RF chain adds (rad): unknown at switch-on, then drifting
/// linearly like a slow temperature change, `β_p(t) = β_p(0) + β̇_p t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineBiasTruth {
    /// Bias of A, B, C at power-up, rad.
    pub at_power_up_rad: [f64; 3],
    /// Drift of A, B, C, rad/s.
    pub drift_rad_s: [f64; 3],
}

impl Default for LineBiasTruth {
    /// The fixed biases of the examples (no drift).
    fn default() -> Self {
        Self {
            at_power_up_rad: [0.0, 0.7, -1.2],
            drift_rad_s: [0.0; 3],
        }
    }
}

impl LineBiasTruth {
    /// A power-up of the RF chains: each bias uniform in `[−π, π)` and each drift uniform in
    /// `±`[`LINE_BIAS_DRIFT_MAX_RAD_S`], drawn from `seed`.
    pub fn power_up(seed: u64) -> Self {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let pi = std::f64::consts::PI;
        Self {
            at_power_up_rad: [(); 3].map(|_| rng.random_range(-pi..pi)),
            drift_rad_s: [(); 3]
                .map(|_| rng.random_range(-LINE_BIAS_DRIFT_MAX_RAD_S..LINE_BIAS_DRIFT_MAX_RAD_S)),
        }
    }

    /// The biases of A, B, C at `t`, rad.
    pub fn at(&self, t: f64) -> [f64; 3] {
        [0, 1, 2].map(|p| self.at_power_up_rad[p] + self.drift_rad_s[p] * t)
    }

    /// What the receiver estimates: the slave chains' biases minus the reference's (B − A,
    /// C − A) at `t`, rad.
    pub fn differences(&self, t: f64) -> [f64; 2] {
        let b = self.at(t);
        [b[1] - b[0], b[2] - b[0]]
    }
}

/// The equilateral triangle of side [`TRIANGLE_SIDE_M`] on the zenith face (`z = −0.05 m`,
/// boresight body −z: the body's +z points to nadir), centred on the body z axis.
pub fn zenith_triangle() -> [Antenna; 3] {
    let r = TRIANGLE_SIDE_M / 3f64.sqrt();
    let at = |angle_deg: f64| {
        let a = angle_deg.to_radians();
        Antenna {
            position: Vector3::new(r * a.cos(), r * a.sin(), -0.05),
            boresight: -Vector3::z(),
        }
    };
    [at(0.0), at(120.0), at(240.0)]
}

/// C/N0 of a satellite at elevation `el` above an antenna's horizon: 38 + 9 sin(el) dB-Hz
/// (a patch antenna: 47 dB-Hz at the boresight, 39.6 dB-Hz at the 10° mask).
pub fn cn0_model(el: f64) -> f64 {
    38.0 + 9.0 * el.max(0.0).sin()
}

impl World {
    /// The default world: sun-synchronous orbit (RAAN 0.3 rad, argument of latitude `u0`),
    /// the bundled almanac, GPS time at `t = 0` = the almanac's time of applicability plus
    /// `gps_offset_s`.
    pub fn new(motion_kind: MotionKind, u0: f64, gps_offset_s: f64, seed_rates: [f64; 3]) -> Self {
        let almanac = Almanac::bundled();
        let orbit = Orbit::sun_synchronous(ALTITUDE_M, 0.3, u0);
        let motion = match motion_kind {
            MotionKind::Nadir => Motion::Nadir(NadirTumble {
                orbit: orbit.into(),
                spin_rate: 0.6f64.to_radians(),
                wobble: 4f64.to_radians(),
                wobble_period: 150.0,
            }),
            MotionKind::Detumbling { duration_s } => {
                let inertia = Matrix3::from_diagonal(&Vector3::new(0.9, 1.1, 0.7));
                let q0 = Quaternion::from_rotation_vector(&Vector3::new(0.3, -2.6, 0.4));
                let w0 = Vector3::from(seed_rates);
                Motion::Detumbling(DetumblingBody::simulate(
                    inertia,
                    4e-4,
                    q0,
                    w0,
                    duration_s + 5.0,
                    0.01,
                ))
            }
        };
        Self {
            sky: SkyModel {
                orbit: orbit.into(),
                gps_time_of_week_s: almanac.reference_time_s() + gps_offset_s,
                almanac,
            },
            motion,
            antennas: zenith_triangle(),
            line_bias: LineBiasTruth::default(),
            blockages: Vec::new(),
            navigation: NavigationError::none(),
        }
    }

    /// Flies `tle` instead of the built-in orbit: the truth's orbit (the sky's geometry, the
    /// nadir frame, the pseudoranges) is SGP4 of the TLE from the flight's GPS start (kept:
    /// the almanac's time of applicability plus the offset, so the constellation is the
    /// almanac's; the TLE is propagated from its epoch to it) over `duration_s`; the flight
    /// computer's orbit is the same TLE [`TLE_ALONG_TRACK_ERROR_M`] ahead ([`OnboardOrbit`]).
    /// Call after drawing [`Self::navigation`].
    ///
    /// # Errors
    /// SGP4 fails somewhere in the flight.
    pub fn fly_tle(&mut self, tle: &Tle, duration_s: f64) -> Result<(), TleError> {
        let gps_start_s = gps_week_start_s() + self.sky.gps_time_of_week_s;
        let flown = TleOrbit::new(tle.clone(), gps_start_s, duration_s)?;
        let speed = flown.eci(0.0).v.norm();
        let orbit = Trajectory::Tle(Box::new(flown));
        if let Motion::Nadir(m) = &mut self.motion {
            m.orbit = orbit.clone();
        }
        self.sky.orbit = orbit.clone();
        self.navigation.onboard = Some(OnboardOrbit {
            orbit,
            ahead_s: TLE_ALONG_TRACK_ERROR_M / speed,
        });
        Ok(())
    }

    /// The satellites' views at `t` as the flight computer predicts them (almanac and
    /// ephemerides with its own orbit, [`NavigationError`]): what the receiver is aided with.
    pub fn navigation_views(&self, t: f64) -> Vec<GpsView> {
        self.sky
            .views(t)
            .iter()
            .map(|v| self.navigation.predicted(v, t))
            .collect()
    }

    /// `C_ib(t)`: body to ECI.
    pub fn c_ib(&self, t: f64) -> Matrix3<f64> {
        self.motion.q_ib(t).to_dcm()
    }

    /// Whether antenna `a` is blocked at `t`.
    pub fn blocked(&self, a: usize, t: f64) -> bool {
        self.blockages
            .iter()
            .any(|b| b.antenna == a && t >= b.start && t < b.end)
    }

    /// The antenna-frame view of a satellite with line of sight `los` (ECI) under `c_ib`.
    pub fn antenna_view(&self, view: &GpsView, c_ib: &Matrix3<f64>, t: f64) -> SatTruth {
        let s_b = c_ib.transpose() * view.los;
        let mut elevation = [0.0; 3];
        let mut visible = [false; 3];
        let mut cn0 = [0.0; 3];
        for (i, a) in self.antennas.iter().enumerate() {
            let el = s_b.dot(&a.boresight).clamp(-1.0, 1.0).asin();
            elevation[i] = el;
            visible[i] = el >= MASK_RAD && !view.occulted && !self.blocked(i, t);
            cn0[i] = cn0_model(el);
        }
        // azimuth in antenna A's plane: x_b, y_b (boresight −z)
        let azimuth = s_b.y.atan2(s_b.x).rem_euclid(std::f64::consts::TAU);
        SatTruth {
            view: *view,
            elevation,
            azimuth,
            visible,
            cn0_dbhz: cn0,
        }
    }

    /// Every healthy satellite above the Earth's limb at `t`, with its antenna-frame view.
    pub fn satellites(&self, t: f64) -> Vec<SatTruth> {
        let c = self.c_ib(t);
        self.sky
            .views(t)
            .iter()
            .filter(|v| !v.occulted)
            .map(|v| self.antenna_view(v, &c, t))
            .collect()
    }

    /// The carrier phase of antenna `a` relative to the array origin for line of sight `los`
    /// (ECI) under `c_ib`: `ψ = 2π μᵀ C_ib r_a / λ` (paper 003, eq. (4)), rad.
    pub fn geometric_phase(&self, a: usize, los: &Vector3<f64>, c_ib: &Matrix3<f64>) -> f64 {
        std::f64::consts::TAU * los.dot(&(c_ib * self.antennas[a].position)) / L1_WAVELENGTH_M
    }
}

/// The start of the bundled almanac's GPS week, s since the GPS epoch.
fn gps_week_start_s() -> f64 {
    f64::from(BUNDLED_ALMANAC_WEEK) * WEEK_S
}

/// A flight's GPS start, s since the GPS epoch (1980-01-06): the bundled almanac's time of
/// applicability plus `gps_offset_s` (what [`World::new`] flies).
pub fn gps_start_s(gps_offset_s: f64) -> f64 {
    gps_week_start_s() + Almanac::bundled().reference_time_s() + gps_offset_s
}

/// Which attitude history.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MotionKind {
    /// Nadir pointing, slow spin and wobble.
    Nadir,
    /// Detumbling body over `duration_s`.
    Detumbling {
        /// Length of the simulated history, s.
        duration_s: f64,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The navigation's prediction moves the lines of sight by about its position errors over
    /// the range (tens of metres over 20 000 km: microradians), never by zero when it has
    /// errors, and not at all without them.
    #[test]
    fn navigation_errors_move_the_predicted_lines_of_sight_by_microradians() {
        let mut w = World::new(MotionKind::Nadir, 0.0, 0.0, [0.0; 3]);
        let t = 100.0;
        let truth = w.sky.views(t);
        for (a, b) in truth.iter().zip(&w.navigation_views(t)) {
            assert!(
                a.los.cross(&b.los).norm() < 1e-12 && (a.doppler_hz - b.doppler_hz).abs() < 1e-9
            );
        }
        w.navigation = NavigationError::draw(7);
        let predicted = w.navigation_views(t);
        let mut largest = 0.0f64;
        for (a, b) in truth.iter().zip(&predicted) {
            let angle = a.los.cross(&b.los).norm();
            assert!(angle > 1e-9, "PRN {}: unchanged", a.prn);
            largest = largest.max(angle);
            let doppler = (a.doppler_hz - b.doppler_hz).abs();
            assert!(
                doppler < 5.0 * NAV_VELOCITY_SIGMA_M_S / L1_WAVELENGTH_M,
                "{doppler} Hz"
            );
        }
        let expected = (NAV_POSITION_SIGMA_M + EPHEMERIS_POSITION_SIGMA_M) / 2.0e7;
        assert!(
            largest < 10.0 * expected && largest > 0.1 * expected,
            "{largest} rad"
        );
    }

    /// With a TLE the truth's orbit, the nadir frame and the sky are SGP4's (AO-73 at about
    /// 635 km, not the built-in 550 km), and the flight computer's orbit is 1 km ahead along
    /// the track: its lines of sight move by some 1 km / 20 000 km.
    #[test]
    fn a_tle_replaces_the_orbit_everywhere_and_the_onboard_copy_is_1_km_ahead() {
        let tle = Tle::parse(include_str!("../../../data/ao73.tle")).unwrap();
        let mut w = World::new(MotionKind::Nadir, 0.4, 3600.0, [0.0; 3]);
        w.fly_tle(&tle, 600.0).unwrap();
        let flown = TleOrbit::new(tle, gps_start_s(3600.0), 600.0).unwrap();
        for t in [0.0, 300.0, 600.0] {
            let r = w.sky.receiver(t).r;
            assert!((r - flown.eci(t).r).norm() < 1e-6);
            let altitude = r.norm() - crate::truth::orbit::R_EARTH;
            assert!((600e3..680e3).contains(&altitude), "{altitude} m");
            let z_body = w.motion.q_ib(t).rotate(&Vector3::z());
            // nadir up to the 4° wobble
            assert!(z_body.dot(&-r.normalize()) > 4.5f64.to_radians().cos());
            let along = w.navigation.position_error(t);
            let v = w.sky.receiver(t).v;
            assert!(
                (along.norm() - TLE_ALONG_TRACK_ERROR_M).abs() < 5.0,
                "{along}"
            );
            assert!(along.normalize().dot(&v.normalize()) > 0.999);
        }
        let truth = w.sky.views(100.0);
        let predicted = w.navigation_views(100.0);
        for (a, b) in truth.iter().zip(&predicted).filter(|(a, _)| !a.occulted) {
            let angle = a.los.cross(&b.los).norm();
            assert!(
                angle < 2.0 * TLE_ALONG_TRACK_ERROR_M / 1.9e7,
                "PRN {}: {angle}",
                a.prn
            );
        }
    }

    #[test]
    fn the_zenith_antennas_see_a_leo_sky_with_enough_satellites() {
        let w = World::new(MotionKind::Nadir, 0.0, 0.0, [0.0; 3]);
        for t in [0.0, 200.0, 400.0, 600.0] {
            let n = w.satellites(t).iter().filter(|s| s.visible[0]).count();
            assert!((6..=14).contains(&n), "t {t}: {n} visible");
        }
        let a = zenith_triangle();
        assert!(((a[0].position - a[1].position).norm() - TRIANGLE_SIDE_M).abs() < 1e-12);
        assert!(((a[1].position - a[2].position).norm() - TRIANGLE_SIDE_M).abs() < 1e-12);
    }
}
