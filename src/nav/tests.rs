//! Numerical tests of the navigation core against independent f64 references written here:
//! satellite positions, the single-point fix on synthesized pseudoranges and Dopplers, the
//! residual check, the LEO filter through an outage, lines of sight and the store.

use heapless::Vec;

/// Room for the test constellation's satellites and their observations.
const SATS: usize = 32;
/// Room for the LEO truth's 0.1 s steps (the longest run is 420 s).
const TRUTH_STEPS: usize = 4400;

use nalgebra::{Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use super::ephemeris::{Ephemeris, EphemerisError, OrbitError};
use super::filter::{NavState, OrbitFilter, OrbitFilterConfig};
use super::geodesy::Geodetic;
use super::los::{line_of_sight, ReferenceFrame};
use super::message::KlobucharParameters;
use super::solution::{solve, Fix, FixError, Observation, SolverConfig};
use super::store::{NavigationStore, StoreError, StoreUpdate};
use super::subframe::{Subframe, PREAMBLE};
use super::time::GpsTime;

// ---- an independent f64 reference of the IS-GPS-200 user algorithm ----------------------

const REF_MU: f64 = 3.986_005e14;
const REF_OMEGA_E: f64 = 7.292_115_146_7e-5;
const REF_C: f64 = 299_792_458.0;

/// Satellite position (ECEF at `t`) by the user algorithm written another way: eccentric
/// anomaly by fixed-point iteration, true anomaly by the half-angle formula, the orbit plane
/// rotated by nalgebra rotations.
fn reference_position(e: &Ephemeris, t: &GpsTime) -> Vector3<f64> {
    let mut tk = (f64::from(t.week) - f64::from(e.week)) * 604_800.0 + t.tow_s - e.toe_s;
    if tk > 302_400.0 {
        tk -= 604_800.0;
    }
    if tk < -302_400.0 {
        tk += 604_800.0;
    }
    let a = e.sqrt_a.powi(2);
    let n = (REF_MU / a.powi(3)).sqrt() + e.delta_n;
    let m = e.m0 + n * tk;
    let mut ea = m;
    for _ in 0..200 {
        ea = m + e.e * ea.sin();
    }
    let nu = 2.0 * (((1.0 + e.e) / (1.0 - e.e)).sqrt() * (ea / 2.0).tan()).atan();
    let u0 = nu + e.omega;
    let u = u0 + e.cus * (2.0 * u0).sin() + e.cuc * (2.0 * u0).cos();
    let r = a * (1.0 - e.e * ea.cos()) + e.crs * (2.0 * u0).sin() + e.crc * (2.0 * u0).cos();
    let i = e.i0 + e.idot * tk + e.cis * (2.0 * u0).sin() + e.cic * (2.0 * u0).cos();
    let node = e.omega0 + (e.omega_dot - REF_OMEGA_E) * tk - REF_OMEGA_E * e.toe_s;
    let in_plane = Vector3::new(r * u.cos(), r * u.sin(), 0.0);
    Rotation3::from_axis_angle(&Vector3::z_axis(), node)
        * Rotation3::from_axis_angle(&Vector3::x_axis(), i)
        * in_plane
}

/// Reference relativistic clock term `−2 √μ / c² · e √A sin E`.
fn reference_relativistic(e: &Ephemeris, t: &GpsTime) -> f64 {
    let tk = t.tow_s - e.toe_s;
    let a = e.sqrt_a.powi(2);
    let m = e.m0 + ((REF_MU / a.powi(3)).sqrt() + e.delta_n) * tk;
    let mut ea = m;
    for _ in 0..200 {
        ea = m + e.e * ea.sin();
    }
    -2.0 * REF_MU.sqrt() / (REF_C * REF_C) * e.e * e.sqrt_a * ea.sin()
}

/// A constellation of 24 plausible satellites (six planes) with harmonic terms and clocks.
fn constellation(seed: u64, week: u16, toe_s: f64) -> Vec<Ephemeris, SATS> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..24u8)
        .map(|k| {
            let plane = f64::from(k % 6);
            Ephemeris {
                prn: k + 1,
                week,
                toe_s,
                toc_s: toe_s,
                iode: 10 + k,
                iodc: 10 + u16::from(k),
                health: 0,
                ura_index: 0,
                fit_interval: false,
                sqrt_a: 5153.6 + rng.random_range(-0.5..0.5),
                e: rng.random_range(0.001..0.02),
                i0: (55.0f64 + rng.random_range(-1.5..1.5)).to_radians(),
                omega0: (plane * 60.0 + rng.random_range(-2.0..2.0)).to_radians(),
                omega: rng.random_range(-3.1..3.1),
                m0: (f64::from(k / 6) * 90.0 + plane * 15.0).to_radians() - 3.0,
                delta_n: rng.random_range(3e-9..5e-9),
                idot: rng.random_range(-5e-10..5e-10),
                omega_dot: rng.random_range(-8.5e-9..-7.5e-9),
                cuc: rng.random_range(-5e-6..5e-6),
                cus: rng.random_range(-1e-5..1e-5),
                crc: rng.random_range(-300.0..300.0),
                crs: rng.random_range(-120.0..120.0),
                cic: rng.random_range(-1e-7..1e-7),
                cis: rng.random_range(-1e-7..1e-7),
                af0: rng.random_range(-5e-4..5e-4),
                af1: rng.random_range(-1e-11..1e-11),
                af2: 0.0,
                tgd: rng.random_range(-1e-8..1e-8),
            }
        })
        .collect()
}

fn t(week: u16, tow: f64) -> GpsTime {
    GpsTime::new(week, tow).unwrap()
}

#[test]
fn satellite_positions_match_the_independent_reference_to_a_centimetre() {
    let ephs = constellation(1, 2195, 237_600.0);
    let mut worst = 0.0f64;
    let mut worst_clock = 0.0f64;
    for e in &ephs {
        for k in -28..=28 {
            let at = t(2195, 237_600.0 + 500.0 * f64::from(k) + 0.123);
            let s = e.satellite_state(&at).unwrap();
            let d = (Vector3::from(s.position_m) - reference_position(e, &at)).norm();
            worst = worst.max(d);
            worst_clock =
                worst_clock.max((s.relativistic_s - reference_relativistic(e, &at)).abs());
            // the velocity is the derivative of the position
            let h = 0.01;
            let p1 = e
                .satellite_state(&at.add_seconds(h).unwrap())
                .unwrap()
                .position_m;
            let p0 = e
                .satellite_state(&at.add_seconds(-h).unwrap())
                .unwrap()
                .position_m;
            let fd = (Vector3::from(p1) - Vector3::from(p0)) / (2.0 * h);
            let dv = (fd - Vector3::from(s.velocity_m_s)).norm();
            assert!(dv < 1e-4, "prn {} velocity {dv} m/s", e.prn);
            let rate_fd = (e
                .satellite_state(&at.add_seconds(1.0).unwrap())
                .unwrap()
                .clock_s
                - e.satellite_state(&at.add_seconds(-1.0).unwrap())
                    .unwrap()
                    .clock_s)
                / 2.0;
            assert!((rate_fd - s.clock_rate).abs() < 1e-15);
        }
    }
    assert!(worst < 0.01, "{worst} m");
    assert!(worst_clock < 1e-13);
}

#[test]
fn the_week_crossover_and_stale_ephemerides() {
    // t_oe at the start of week 2196, transmitted (week field) in week 2195
    let mut e = constellation(2, 2195, 0.0)[3];
    e.toe_s = 0.0;
    e.toc_s = 0.0;
    let late = t(2195, 604_000.0); // 800 s before t_oe
    let s = e.satellite_state(&late).unwrap();
    // the same instant written from the next week with a reference that wraps t − t_oe
    let r = reference_position(&e, &late);
    assert!((Vector3::from(s.position_m) - r).norm() < 0.01);
    assert_eq!(
        e.satellite_state(&t(2195, 500_000.0)),
        Err(OrbitError::Stale)
    );
    assert_eq!(
        e.satellite_state(&GpsTime {
            week: 2195,
            tow_s: f64::NAN
        }),
        Err(OrbitError::NonFinite)
    );
    // clock: a_f0 + a_f1 (t − t_oc) + Δt_r − T_GD across the crossover
    let c = s.clock_s - s.relativistic_s + e.tgd;
    assert!((c - (e.af0 + e.af1 * -800.0)).abs() < 1e-15);
}

// ---- synthesized measurements -------------------------------------------------------------

/// The receiver's truth.
struct Receiver {
    position: Vector3<f64>,
    velocity: Vector3<f64>,
    clock_bias_m: f64,
    clock_drift_m_s: f64,
}

/// Pseudorange and Doppler of `e` for a receiver at GPS time `rx_time` (true), by the
/// reference orbit with the light time solved, Sagnac, the satellite clock, and the given
/// atmosphere delay (m).
fn synthesize(
    e: &Ephemeris,
    rx: &Receiver,
    rx_time: &GpsTime,
    delay_m: f64,
    noise_m: f64,
    rng: &mut ChaCha8Rng,
) -> (Observation, f64) {
    let mut tau = 0.07;
    let mut p = Vector3::zeros();
    let mut tx = *rx_time;
    for _ in 0..10 {
        tx = rx_time.add_seconds(-tau).unwrap();
        let rot = Rotation3::from_axis_angle(&Vector3::z_axis(), -REF_OMEGA_E * tau);
        p = rot * reference_position(e, &tx);
        tau = (p - rx.position).norm() / REF_C;
    }
    let range = (p - rx.position).norm();
    let state = e.satellite_state(&tx).unwrap();
    let dt_sv = state.clock_s;
    let t_sv = tx.add_seconds(dt_sv).unwrap();
    let n: f64 = StandardNormal.sample(rng);
    let pr = range + rx.clock_bias_m - REF_C * dt_sv + delay_m + noise_m * n;
    // Doppler from the range rate by central differences of the reference geometry
    let h = 0.05;
    let range_at = |dt: f64| {
        let rxp = rx.position + rx.velocity * dt;
        let t_rx = rx_time.add_seconds(dt).unwrap();
        let mut tau = range / REF_C;
        let mut q = Vector3::zeros();
        for _ in 0..10 {
            let rot = Rotation3::from_axis_angle(&Vector3::z_axis(), -REF_OMEGA_E * tau);
            q = rot * reference_position(e, &t_rx.add_seconds(-tau).unwrap());
            tau = (q - rxp).norm() / REF_C;
        }
        (q - rxp).norm()
    };
    let rate =
        (range_at(h) - range_at(-h)) / (2.0 * h) + rx.clock_drift_m_s - REF_C * state.clock_rate;
    let nd: f64 = StandardNormal.sample(rng);
    let lambda = REF_C / 1_575.42e6;
    let doppler = -(rate + 0.02 * nd) / lambda;
    (
        Observation {
            prn: e.prn,
            transmit: t_sv,
            pseudorange_m: pr,
            doppler_hz: Some(doppler as f32),
            sigma_m: noise_m.max(0.5) as f32,
        },
        range,
    )
}

fn elevation(e: &Ephemeris, rx: &Vector3<f64>, at: &GpsTime) -> f64 {
    let d = reference_position(e, at) - rx;
    (d.normalize().dot(&rx.normalize())).asin()
}

fn kyiv() -> Receiver {
    let g = Geodetic {
        lat_rad: 50.45f64.to_radians(),
        lon_rad: 30.52f64.to_radians(),
        height_m: 180.0,
    };
    Receiver {
        position: Vector3::from(g.to_ecef()),
        velocity: Vector3::zeros(),
        clock_bias_m: 31_234.5,
        clock_drift_m_s: 12.5,
    }
}

fn klobuchar() -> KlobucharParameters {
    KlobucharParameters {
        alpha: [1.118e-8, 7.451e-9, -5.961e-8, -5.961e-8],
        beta: [90_112.0, 16_384.0, -196_608.0, -131_072.0],
    }
}

/// The atmosphere the solver models, for the synthesized ranges (what the solver removes
/// is what is added; the test checks the solution, not the model).
fn ground_delay(rx: &Receiver, e: &Ephemeris, at: &GpsTime, params: &KlobucharParameters) -> f64 {
    let g = Geodetic::from_ecef(&[rx.position.x, rx.position.y, rx.position.z]).unwrap();
    let d = (reference_position(e, at) - rx.position).normalize();
    let ned = g.ecef_to_ned() * Vector3::new(d.x as f32, d.y as f32, d.z as f32);
    let (el, az) = super::geodesy::elevation_azimuth(&ned);
    f64::from(
        super::atmosphere::klobuchar_delay_m(
            params,
            g.lat_rad as f32,
            g.lon_rad as f32,
            el,
            az,
            at.tow_s,
        ) + super::atmosphere::troposphere_delay_m(g.height_m as f32, el),
    )
}

/// Observations of the `count` highest satellites for the receiver at `rx_time`.
fn ground_observations(
    ephs: &[Ephemeris],
    rx: &Receiver,
    rx_time: &GpsTime,
    noise_m: f64,
    count: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<Observation, SATS> {
    let mut sky: Vec<(f64, &Ephemeris), SATS> = ephs
        .iter()
        .map(|e| (elevation(e, &rx.position, rx_time), e))
        .filter(|(el, _)| *el > 10f64.to_radians())
        .collect();
    sky.sort_by(|a, b| b.0.total_cmp(&a.0));
    let params = klobuchar();
    sky.iter()
        .take(count)
        .map(|(_, e)| {
            let delay = ground_delay(rx, e, rx_time, &params);
            synthesize(e, rx, rx_time, delay, noise_m, rng).0
        })
        .collect()
}

fn receiver_clock_time(rx: &Receiver, at: &GpsTime) -> GpsTime {
    at.add_seconds(rx.clock_bias_m / REF_C).unwrap()
}

fn position_error(fix: &Fix, rx: &Receiver) -> Vector3<f64> {
    Vector3::from(fix.position_m) - rx.position
}

#[test]
fn a_noise_free_fix_is_exact_and_a_noisy_one_is_within_its_covariance() {
    let ephs = constellation(3, 2195, 237_600.0);
    let rx = kyiv();
    let at = t(2195, 238_000.0);
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let obs = ground_observations(&ephs, &rx, &at, 0.0, 8, &mut rng);
    assert_eq!(obs.len(), 8, "satellites above 10°");
    let iono = klobuchar();
    let rx_clock = receiver_clock_time(&rx, &at);
    let fix = solve(
        &obs,
        &ephs[..],
        Some(&iono),
        &rx_clock,
        None,
        &SolverConfig::ground(),
    )
    .unwrap();
    let err = position_error(&fix, &rx).norm();
    assert!(err < 0.02, "{err}");
    assert!((fix.clock_bias_m - rx.clock_bias_m).abs() < 0.02);
    assert!((fix.time.seconds_since(&at)).abs() < 1e-10);
    let v = fix.velocity_m_s.unwrap();
    assert!(Vector3::new(v[0], v[1], v[2]).norm() < 0.1, "{v:?}");
    assert!((fix.clock_drift_m_s.unwrap() - 12.5).abs() < 0.1);
    assert!(fix.dop.pdop > 1.0 && fix.dop.pdop < 4.0 && fix.dop.hdop < fix.dop.pdop);
    // with 3 m noise: NEES against the fix's own covariance over many epochs
    let (mut nees_sum, mut rms, mut pdop2, n) = (0.0, 0.0, 0.0, 60);
    for k in 0..n {
        let at = t(2195, 238_000.0 + 30.0 * f64::from(k));
        let obs = ground_observations(&ephs, &rx, &at, 3.0, 8, &mut rng);
        let rx_clock = receiver_clock_time(&rx, &at);
        let fix = solve(
            &obs,
            &ephs[..],
            Some(&iono),
            &rx_clock,
            None,
            &SolverConfig::ground(),
        )
        .unwrap();
        let e = position_error(&fix, &rx);
        let p = nalgebra::Matrix3::from_fn(|i, j| f64::from(fix.position_covariance_m2[i][j]));
        nees_sum += e.dot(&(p.try_inverse().unwrap() * e));
        rms += e.norm_squared();
        pdop2 += f64::from(fix.dop.pdop).powi(2);
    }
    let nees = nees_sum / f64::from(n);
    let rms = (rms / f64::from(n)).sqrt();
    let pdop_rms = (pdop2 / f64::from(n)).sqrt();
    assert!(nees > 2.0 && nees < 4.2, "{nees}");
    assert!(rms < 1.3 * 3.0 * pdop_rms, "{rms} vs {pdop_rms}");
}

#[test]
fn the_residual_check_excludes_a_biased_satellite() {
    let ephs = constellation(4, 2195, 237_600.0);
    let rx = kyiv();
    let at = t(2195, 240_000.0);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut obs = ground_observations(&ephs, &rx, &at, 1.0, 8, &mut rng);
    let biased = obs[3].prn;
    obs[3].pseudorange_m += 80.0;
    let rx_clock = receiver_clock_time(&rx, &at);
    let iono = klobuchar();
    let fix = solve(
        &obs,
        &ephs[..],
        Some(&iono),
        &rx_clock,
        None,
        &SolverConfig::ground(),
    )
    .unwrap();
    assert!(obs.len() >= 7);
    assert_eq!(fix.excluded_prn, Some(biased));
    assert_eq!(usize::from(fix.satellites), obs.len() - 1);
    let err = position_error(&fix, &rx).norm();
    assert!(err < 8.0, "{err}");
    // without the check the bias pulls the fix
    let blind = SolverConfig {
        raim: None,
        ..SolverConfig::ground()
    };
    let pulled = solve(&obs, &ephs[..], Some(&iono), &rx_clock, None, &blind).unwrap();
    assert!(position_error(&pulled, &rx).norm() > err);
    // five satellites: detected, not isolated
    let five: Vec<Observation, SATS> = obs.iter().take(5).copied().collect();
    let five = if five.iter().any(|o| o.prn == biased) {
        five
    } else {
        let mut f = five;
        f[0] = obs[3];
        f
    };
    let r = solve(
        &five,
        &ephs[..],
        Some(&iono),
        &rx_clock,
        None,
        &SolverConfig::ground(),
    );
    assert!(matches!(r, Err(FixError::ResidualCheck { .. })), "{r:?}");
    // four satellites: no check possible, a fix; three: refused
    assert!(solve(
        &obs[..4],
        &ephs[..],
        Some(&iono),
        &rx_clock,
        None,
        &SolverConfig::ground()
    )
    .is_ok());
    assert_eq!(
        solve(
            &obs[..3],
            &ephs[..],
            Some(&iono),
            &rx_clock,
            None,
            &SolverConfig::ground()
        ),
        Err(FixError::TooFewSatellites { available: 3 })
    );
    let mut bad = obs.clone();
    bad[0].pseudorange_m = f64::NAN;
    assert_eq!(
        solve(
            &bad,
            &ephs[..],
            Some(&iono),
            &rx_clock,
            None,
            &SolverConfig::ground()
        ),
        Err(FixError::InvalidObservation)
    );
}

// ---- a receiver in low Earth orbit --------------------------------------------------------

const LEO_MU: f64 = 3.986_004_418e14;
const LEO_J2: f64 = 1.082_626_68e-3;
const LEO_J3: f64 = -2.532_66e-6;
const LEO_R: f64 = 6_378_137.0;

/// Inertial acceleration: two-body, J2, J3 and a drag-like deceleration (m/s²): a model
/// richer than the filter's.
fn truth_acceleration(r: &Vector3<f64>, v: &Vector3<f64>) -> Vector3<f64> {
    let rn = r.norm();
    let (x, y, z) = (r.x, r.y, r.z);
    let zr = z / rn;
    let k2 = -1.5 * LEO_J2 * LEO_MU * LEO_R.powi(2) / rn.powi(5);
    let j2 = Vector3::new(
        k2 * x * (1.0 - 5.0 * zr * zr),
        k2 * y * (1.0 - 5.0 * zr * zr),
        k2 * z * (3.0 - 5.0 * zr * zr),
    );
    let k3 = -2.5 * LEO_J3 * LEO_MU * LEO_R.powi(3) / rn.powi(7);
    let j3 = Vector3::new(
        k3 * x * (3.0 * z - 7.0 * z.powi(3) / (rn * rn)),
        k3 * y * (3.0 * z - 7.0 * z.powi(3) / (rn * rn)),
        k3 * (6.0 * z * z - 7.0 * z.powi(4) / (rn * rn) - 0.6 * rn * rn),
    );
    let drag = -v.normalize() * 2e-6;
    -r * LEO_MU / rn.powi(3) + j2 + j3 + drag
}

/// Inertial truth at 0.1 s steps (RK4), in the ECEF frame at `gps0` + `t`: ECEF = `R_z(−ω t)`
/// ECI (the frames coincide at `t = 0`).
struct LeoTruth {
    eci: Vec<(Vector3<f64>, Vector3<f64>), TRUTH_STEPS>,
    step: f64,
}

impl LeoTruth {
    fn new(seconds: f64) -> Self {
        let a: f64 = LEO_R + 550e3;
        let speed = (LEO_MU / a).sqrt();
        let inc = 97.6f64.to_radians();
        // at the ascending node, moving at the inclination
        let mut r = Vector3::new(a * 0.6, a * 0.8, 0.0);
        let mut v = Vector3::new(-0.8 * inc.cos(), 0.6 * inc.cos(), inc.sin()) * speed;
        let step = 0.1;
        let mut eci = Vec::new();
        let steps = (seconds / step).round() as usize;
        for _ in 0..=steps {
            eci.push((r, v)).expect("room for every step");
            let f = |r: &Vector3<f64>, v: &Vector3<f64>| (*v, truth_acceleration(r, v));
            let (k1r, k1v) = f(&r, &v);
            let (k2r, k2v) = f(&(r + k1r * step / 2.0), &(v + k1v * step / 2.0));
            let (k3r, k3v) = f(&(r + k2r * step / 2.0), &(v + k2v * step / 2.0));
            let (k4r, k4v) = f(&(r + k3r * step), &(v + k3v * step));
            r += (k1r + 2.0 * k2r + 2.0 * k3r + k4r) * step / 6.0;
            v += (k1v + 2.0 * k2v + 2.0 * k3v + k4v) * step / 6.0;
        }
        Self { eci, step }
    }

    /// ECEF position and velocity at `t` (a multiple of the step).
    fn ecef(&self, t: f64) -> (Vector3<f64>, Vector3<f64>) {
        let (r, v) = self.eci[(t / self.step).round() as usize];
        let c = Rotation3::from_axis_angle(&Vector3::z_axis(), -REF_OMEGA_E * t);
        let w = Vector3::new(0.0, 0.0, REF_OMEGA_E);
        (c * r, c * (v - w.cross(&r)))
    }
}

fn fake_fix(
    time: GpsTime,
    p: Vector3<f64>,
    v: Vector3<f64>,
    sp: f64,
    sv: f64,
    rng: &mut ChaCha8Rng,
) -> Fix {
    let mut n = || -> f64 { StandardNormal.sample(&mut *rng) };
    let pos = [p.x + sp * n(), p.y + sp * n(), p.z + sp * n()];
    let vel = [
        (v.x + sv * n()) as f32,
        (v.y + sv * n()) as f32,
        (v.z + sv * n()) as f32,
    ];
    let vp = (sp * sp) as f32;
    Fix {
        time,
        position_m: pos,
        clock_bias_m: 0.0,
        velocity_m_s: Some(vel),
        clock_drift_m_s: Some(0.0),
        position_covariance_m2: [[vp, 0.0, 0.0], [0.0, vp, 0.0], [0.0, 0.0, vp]],
        velocity_variance_m2_s2: [(sv * sv) as f32; 3],
        dop: Default::default(),
        satellites: 8,
        excluded_prn: None,
        skipped: 0,
        chi_square: 0.0,
        residual_rms_m: 0.0,
        iterations: 3,
    }
}

#[test]
fn the_leo_filter_coasts_through_a_60_s_outage() {
    let truth = LeoTruth::new(420.0);
    let gps0 = t(2195, 233_472.0);
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let at = |s: f64| gps0.add_seconds(s).unwrap();
    let (p, v) = truth.ecef(0.0);
    let mut f = OrbitFilter::from_fix(
        &fake_fix(at(0.0), p, v, 5.0, 0.1, &mut rng),
        OrbitFilterConfig::default(),
    )
    .unwrap();
    let mut accepted = 0;
    for k in 1..=300 {
        let s = f64::from(k);
        let (p, v) = truth.ecef(s);
        if f.update(&fake_fix(at(s), p, v, 5.0, 0.1, &mut rng))
            .unwrap()
            .accepted
        {
            accepted += 1;
        }
    }
    assert!(accepted >= 295, "{accepted}");
    let (p, v) = truth.ecef(300.0);
    let before = (Vector3::from(f.state().position_m) - p).norm();
    let before_v = (Vector3::from(f.state().velocity_m_s) - v).norm();
    assert!(
        before < 10.0 && before_v < 0.1,
        "{before} m, {before_v} m/s"
    );
    // outage: predictions only, every second (aiding continues)
    let mut worst = 0.0f64;
    for k in 301..=360 {
        let s = f64::from(k);
        f.predict_to(&at(s)).unwrap();
        let (p, _) = truth.ecef(s);
        worst = worst.max((Vector3::from(f.state().position_m) - p).norm());
    }
    let state = f.state();
    let (p, v) = truth.ecef(360.0);
    let after = (Vector3::from(state.position_m) - p).norm();
    let after_v = (Vector3::from(state.velocity_m_s) - v).norm();
    assert!(after < 10.0 && after_v < 0.5, "{after} m, {after_v} m/s");
    assert!(after < 3.0 * f64::from(state.position_sigma_m) + 1.0);
    // the fixes come back and are accepted
    let (p, v) = truth.ecef(361.0);
    assert!(
        f.update(&fake_fix(at(361.0), p, v, 5.0, 0.1, &mut rng))
            .unwrap()
            .accepted
    );
    // a predict beyond the bound is refused and changes nothing
    let copy = f.clone();
    assert!(f.predict_to(&at(2000.0)).is_err());
    assert_eq!(f, copy);
}

#[test]
fn a_leo_receiver_fixes_without_atmosphere_and_its_filter_follows() {
    let ephs = constellation(6, 2195, 237_600.0);
    let truth = LeoTruth::new(20.0);
    let gps0 = t(2195, 238_200.0);
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let (p, v) = truth.ecef(0.0);
    let rx = Receiver {
        position: p,
        velocity: v,
        clock_bias_m: -1234.0,
        clock_drift_m_s: -3.0,
    };
    // every satellite whose line of sight clears the Earth by 100 km
    let clear = |e: &Ephemeris| {
        let s = reference_position(e, &gps0);
        let d = (s - p).normalize();
        let along = (-p.dot(&d)).max(0.0);
        (p + d * along).norm() > LEO_R + 100e3
    };
    let obs: Vec<Observation, SATS> = ephs
        .iter()
        .filter(|e| clear(e))
        .take(10)
        .map(|e| synthesize(e, &rx, &gps0, 0.0, 2.0, &mut rng).0)
        .collect();
    assert!(obs.len() >= 8, "{}", obs.len());
    let fix = solve(
        &obs,
        &ephs[..],
        None,
        &receiver_clock_time(&rx, &gps0),
        None,
        &SolverConfig::leo(),
    )
    .unwrap();
    let err = position_error(&fix, &rx).norm();
    let v = fix.velocity_m_s.unwrap();
    let verr =
        (Vector3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2])) - rx.velocity).norm();
    assert!(err < 6.0 * f64::from(fix.dop.pdop), "{err}");
    assert!(verr < 0.1, "{verr}");
    assert!(OrbitFilter::from_fix(&fix, OrbitFilterConfig::default()).is_ok());
}

// ---- lines of sight -------------------------------------------------------------------

#[test]
fn lines_of_sight_and_their_rates_in_each_frame() {
    let ephs = constellation(7, 2195, 237_600.0);
    let truth = LeoTruth::new(1.0);
    let (p, v) = truth.ecef(0.0);
    let now = t(2195, 238_000.0);
    let state = |dt: f64| NavState {
        time: now.add_seconds(dt).unwrap(),
        position_m: (p + v * dt).into(),
        velocity_m_s: v.into(),
        position_sigma_m: 1.0,
        velocity_sigma_m_s: 0.1,
    };
    let epoch = t(2195, 237_000.0);
    for frame in [
        ReferenceFrame::Ecef,
        ReferenceFrame::Inertial { epoch },
        ReferenceFrame::LocalNed,
    ] {
        for e in ephs.iter().take(6) {
            let l = line_of_sight(&state(0.0), e, &frame).unwrap();
            let u = Vector3::from(l.los);
            assert!((u.norm() - 1.0).abs() < 1e-6);
            // the rate is the derivative (the NED axes held at the receiver's position)
            if frame != ReferenceFrame::LocalNed {
                let h = 0.5;
                let up = Vector3::from(line_of_sight(&state(h), e, &frame).unwrap().los);
                let dn = Vector3::from(line_of_sight(&state(-h), e, &frame).unwrap().los);
                let fd = (up - dn) / (2.0 * h as f32);
                assert!(
                    (fd - Vector3::from(l.los_rate)).norm() < 2e-7,
                    "{frame:?}: {}",
                    (fd - Vector3::from(l.los_rate)).norm()
                );
            }
            // against the reference geometry (ECEF, light time, Sagnac)
            if frame == ReferenceFrame::Ecef {
                let mut tau = 0.07;
                let mut s = Vector3::zeros();
                for _ in 0..5 {
                    let rot = Rotation3::from_axis_angle(&Vector3::z_axis(), -REF_OMEGA_E * tau);
                    s = rot * reference_position(e, &now.add_seconds(-tau).unwrap());
                    tau = (s - p).norm() / REF_C;
                }
                let reference = (s - p).normalize();
                let d = (u.cast::<f64>() - reference).norm();
                assert!(d < 1e-7, "{d}");
            }
            if let ReferenceFrame::Inertial { .. } = frame {
                let ecef = Vector3::from(
                    line_of_sight(&state(0.0), e, &ReferenceFrame::Ecef)
                        .unwrap()
                        .los,
                );
                let c =
                    Rotation3::from_axis_angle(&Vector3::z_axis(), (REF_OMEGA_E * 1000.0) as f32);
                assert!((c * ecef - u).norm() < 1e-6);
                let a = l.to_aiding(42);
                assert_eq!((a.prn, a.epoch, a.los), (e.prn, 42, l.los));
            }
        }
    }
}

// ---- the store ------------------------------------------------------------------------

/// Packs an ephemeris into the data words of subframes 1, 2, 3 (test-side packer, scale
/// factors of IS-GPS-200 Table 20-III), HOW counts `tow_count`, `+1`, `+2`.
fn pack(e: &Ephemeris, tow_count: u32) -> [Subframe; 3] {
    let sc = |v: f64, p: i32| (v / 2f64.powi(p)).round() as i64;
    let semi = |v: f64, p: i32| (v / super::GPS_PI / 2f64.powi(p)).round() as i64;
    let m = |v: i64, bits: u32| (v as u64 & ((1u64 << bits) - 1)) as u32;
    let tlm = PREAMBLE << 16;
    let how = |k: u32, id: u32| ((tow_count + k) << 7) | (id << 2);
    let mut s1 = [0u32; 10];
    s1[0] = tlm;
    s1[1] = how(0, 1);
    s1[2] = (u32::from(e.week % 1024) << 14)
        | (u32::from(e.ura_index) << 8)
        | (u32::from(e.health) << 2)
        | (u32::from(e.iodc) >> 8);
    s1[6] = m(sc(e.tgd, -31), 8);
    s1[7] = ((u32::from(e.iodc) & 0xFF) << 16) | m(sc(e.toc_s, 4), 16);
    s1[8] = (m(sc(e.af2, -55), 8) << 16) | m(sc(e.af1, -43), 16);
    s1[9] = m(sc(e.af0, -31), 22) << 2;
    let m0 = m(semi(e.m0, -31), 32);
    let ecc = m(sc(e.e, -33), 32);
    let sqa = m(sc(e.sqrt_a, -19), 32);
    let mut s2 = [0u32; 10];
    s2[0] = tlm;
    s2[1] = how(1, 2);
    s2[2] = (u32::from(e.iode) << 16) | m(sc(e.crs, -5), 16);
    s2[3] = (m(semi(e.delta_n, -43), 16) << 8) | (m0 >> 24);
    s2[4] = m0 & 0xFF_FFFF;
    s2[5] = (m(sc(e.cuc, -29), 16) << 8) | (ecc >> 24);
    s2[6] = ecc & 0xFF_FFFF;
    s2[7] = (m(sc(e.cus, -29), 16) << 8) | (sqa >> 24);
    s2[8] = sqa & 0xFF_FFFF;
    s2[9] = m(sc(e.toe_s, 4), 16) << 8;
    let om0 = m(semi(e.omega0, -31), 32);
    let i0 = m(semi(e.i0, -31), 32);
    let w = m(semi(e.omega, -31), 32);
    let mut s3 = [0u32; 10];
    s3[0] = tlm;
    s3[1] = how(2, 3);
    s3[2] = (m(sc(e.cic, -29), 16) << 8) | (om0 >> 24);
    s3[3] = om0 & 0xFF_FFFF;
    s3[4] = (m(sc(e.cis, -29), 16) << 8) | (i0 >> 24);
    s3[5] = i0 & 0xFF_FFFF;
    s3[6] = (m(sc(e.crc, -5), 16) << 8) | (w >> 24);
    s3[7] = w & 0xFF_FFFF;
    s3[8] = m(semi(e.omega_dot, -43), 24);
    s3[9] = (u32::from(e.iode) << 16) | (m(semi(e.idot, -43), 14) << 2);
    let sf = |words| Subframe {
        words,
        start_epoch: 0,
        inverted: false,
    };
    [sf(s1), sf(s2), sf(s3)]
}

#[test]
fn the_store_keeps_the_newest_consistent_plausible_set_and_counts_refusals() {
    let e = constellation(8, 2195, 237_600.0)[4];
    let mut store = NavigationStore::default();
    let [s1, s2, s3] = pack(&e, 39_600);
    assert_eq!(store.add_subframe(e.prn, &s1), Ok(StoreUpdate::Pending));
    assert_eq!(store.add_subframe(e.prn, &s2), Ok(StoreUpdate::Pending));
    assert_eq!(
        store.add_subframe(e.prn, &s3),
        Ok(StoreUpdate::Ephemeris {
            prn: e.prn,
            iode: e.iode
        })
    );
    let d = *store.ephemeris(e.prn).unwrap();
    assert_eq!(d.week, 2195);
    // every field within half its scale factor
    let close = |a: f64, b: f64, lsb: f64| (a - b).abs() <= 0.5 * lsb * (1.0 + 1e-9);
    // angles beyond ±1 semicircle come back wrapped by 2π (IS-GPS-200's π)
    let close_angle = |a: f64, b: f64, lsb: f64| {
        let d = (a - b) / (2.0 * super::GPS_PI);
        ((d - d.round()) * 2.0 * super::GPS_PI).abs() <= 0.5 * lsb * (1.0 + 1e-6)
    };
    let pi = super::GPS_PI;
    assert!(close(d.sqrt_a, e.sqrt_a, 2f64.powi(-19)));
    assert!(close(d.e, e.e, 2f64.powi(-33)));
    assert!(close_angle(d.m0, e.m0, pi * 2f64.powi(-31)));
    assert!(close_angle(d.omega0, e.omega0, pi * 2f64.powi(-31)));
    assert!(close(d.i0, e.i0, pi * 2f64.powi(-31)));
    assert!(close_angle(d.omega, e.omega, pi * 2f64.powi(-31)));
    assert!(close(d.omega_dot, e.omega_dot, pi * 2f64.powi(-43)));
    assert!(close(d.idot, e.idot, pi * 2f64.powi(-43)));
    assert!(close(d.delta_n, e.delta_n, pi * 2f64.powi(-43)));
    assert!(close(d.crc, e.crc, 2f64.powi(-5)) && close(d.crs, e.crs, 2f64.powi(-5)));
    assert!(close(d.cuc, e.cuc, 2f64.powi(-29)) && close(d.cis, e.cis, 2f64.powi(-29)));
    assert!(close(d.af0, e.af0, 2f64.powi(-31)) && close(d.af1, e.af1, 2f64.powi(-43)));
    assert!(close(d.tgd, e.tgd, 2f64.powi(-31)));
    assert_eq!((d.toe_s, d.toc_s, d.iodc), (e.toe_s, e.toc_s, e.iodc));
    // a subframe 2 of the next issue waits for its subframes 1 and 3
    let mut next = e;
    next.iode = e.iode + 1;
    next.iodc = e.iodc + 1;
    next.toe_s += 7200.0;
    next.toc_s += 7200.0;
    let [n1, n2, n3] = pack(&next, 40_800);
    assert_eq!(store.add_subframe(e.prn, &n2), Ok(StoreUpdate::Pending));
    assert_eq!(store.ephemeris(e.prn).unwrap().iode, e.iode);
    assert_eq!(store.add_subframe(e.prn, &n3), Ok(StoreUpdate::Pending));
    assert!(matches!(
        store.add_subframe(e.prn, &n1),
        Ok(StoreUpdate::Ephemeris { .. })
    ));
    assert_eq!(store.ephemeris(e.prn).unwrap().iode, next.iode);
    // the old issue again is older: ignored
    store.add_subframe(e.prn, &s1).unwrap();
    store.add_subframe(e.prn, &s2).unwrap();
    store.add_subframe(e.prn, &s3).unwrap();
    assert_eq!(store.ephemeris(e.prn).unwrap().iode, next.iode);
    assert!(store.counters().older_ignored >= 1);
    // implausible sets are refused and counted
    let mut bad = next;
    bad.prn = 9;
    bad.e = 0.05;
    let [b1, b2, b3] = pack(&bad, 40_800);
    store.add_subframe(9, &b1).unwrap();
    store.add_subframe(9, &b2).unwrap();
    assert_eq!(
        store.add_subframe(9, &b3),
        Err(StoreError::Implausible {
            prn: 9,
            source: EphemerisError::Eccentricity
        })
    );
    let mut sick = next;
    sick.prn = 10;
    sick.health = 0b10_0000;
    let [h1, h2, h3] = pack(&sick, 40_800);
    store.add_subframe(10, &h1).unwrap();
    store.add_subframe(10, &h2).unwrap();
    assert!(matches!(
        store.add_subframe(10, &h3),
        Err(StoreError::Implausible {
            source: EphemerisError::Unhealthy { .. },
            ..
        })
    ));
    let mut far = next;
    far.prn = 11;
    far.sqrt_a = 4000.0;
    let [f1, f2, f3] = pack(&far, 40_800);
    store.add_subframe(11, &f1).unwrap();
    store.add_subframe(11, &f2).unwrap();
    assert!(store.add_subframe(11, &f3).is_err());
    assert_eq!(store.counters().implausible, 3);
    assert!(store.ephemeris(9).is_none() && store.ephemeris(10).is_none());
    assert_eq!(
        store.add_subframe(33, &s1),
        Err(StoreError::InvalidPrn { prn: 33 })
    );
    store.record_decode_error(&super::subframe::SubframeError::Parity {
        word: 4,
        source: super::parity::ParityError::Mismatch {
            computed: 1,
            received: 2,
        },
    });
    assert_eq!(store.counters().parity_failures, 1);
}

// ---- the deterministic example (the firmware's budgets) ------------------------------------

#[test]
fn the_example_decodes_and_fixes() {
    use super::bits::DataBit;
    use super::example::{constellation, observations, subframe_bits, subframe_words};
    use super::subframe::SubframeSync;
    let ephs = constellation();
    // subframes 1-3 of PRN 7 through the synchronizer and the store
    let mut sync = SubframeSync::new();
    let mut store = NavigationStore::default();
    let mut epoch = 1000u64;
    let push = |sync: &mut SubframeSync, b: bool, epoch: &mut u64| {
        *epoch += 20;
        sync.push(&DataBit {
            value: b,
            start_epoch: *epoch,
            strength: 1.0,
        })
    };
    for b in [false, true, true, false, false, false] {
        assert_eq!(push(&mut sync, b, &mut epoch), Ok(None));
    }
    let mut got: Vec<_, 3> = Vec::new();
    for id in 1..=3u8 {
        let bits = subframe_bits(&subframe_words(&ephs[6], id, 39_600 + u32::from(id)));
        for (i, &b) in bits.iter().enumerate() {
            let r = push(&mut sync, b, &mut epoch);
            assert!(r.is_ok(), "subframe {id} bit {i}: {r:?}");
            if let Some(sf) = r.unwrap() {
                got.push(store.add_subframe(7, &sf).unwrap())
                    .expect("three subframes");
            }
        }
    }
    assert_eq!(got.len(), 3);
    assert!(matches!(got[2], StoreUpdate::Ephemeris { prn: 7, .. }));
    let d = store.ephemeris(7).unwrap();
    let s0 = d.satellite_state(&t(2195, 238_000.0)).unwrap();
    let s1 = ephs[6].satellite_state(&t(2195, 238_000.0)).unwrap();
    assert!((Vector3::from(s0.position_m) - Vector3::from(s1.position_m)).norm() < 0.1);
    // a fix at Kyiv from the example's observations
    let rx = kyiv();
    let at = t(2195, 238_000.0);
    let p = [rx.position.x, rx.position.y, rx.position.z];
    let iono = super::example::EXAMPLE_KLOBUCHAR;
    let obs = observations(&ephs, &p, &[0.0; 3], 1000.0, &at, 8, Some(&iono)).unwrap();
    assert_eq!(obs.len(), 8);
    let rx_clock = at.add_seconds(1000.0 / REF_C).unwrap();
    let fix = solve(
        &obs,
        &ephs[..],
        Some(&iono),
        &rx_clock,
        None,
        &SolverConfig::ground(),
    )
    .unwrap();
    assert!(
        position_error(&fix, &rx).norm() < 0.01,
        "{:?}",
        position_error(&fix, &rx)
    );
}
