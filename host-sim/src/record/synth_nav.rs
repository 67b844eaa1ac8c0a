//! The sky of a synthesized recording that carries the LNAV message (`synth --lnav`): a
//! static ground receiver at a WGS-84 position, the bundled almanac's satellites above 10° at
//! a GPS time, each with the range, Doppler, lines of sight and data bits the truth geometry
//! gives, so that a receiver decoding the message finds time, ephemerides and position.
//!
//! Per satellite and receiver time `t` (s from the first sample; the receiver's sample clock
//! is GPS time: the first sample is at `--gps-start`, no clock bias or drift):
//!
//! ```text
//! τ          signal flight: |R_z(−ω⊕ τ) r_sat(t_rx − τ) − r_rx| / c, iterated (Sagnac)
//! Δt_sv      the satellite clock of the signal (LnavEncoder::signal_clock_offset_s)
//! I, T       broadcast Klobuchar ionosphere (the encoder's page-18 parameters) and the core's
//!            troposphere model, both as group delays
//! ρ_eff(t) = c (τ − Δt_sv) + I + T        the pseudorange a perfect receiver measures
//! t_sv(t)  = t_rx − ρ_eff(t)/c            the signal time received: code phase and data bit
//! ```
//!
//! `ρ_eff` goes into the scene's [`SatelliteTrack`] (cubic Hermite at [`TRACK_STEP_S`]), the
//! code count starts at the subframe start before `t_sv(0)` so that code epoch `k` carries
//! the LNAV bit `⌊k/20⌋` of that subframe on. The antennas' offsets `μ·C_rb r_P` use the line
//! of sight of each table point (NED). Idealizations: the ionosphere delays the carrier as it
//! delays the code (the same `ρ_eff`; a real carrier is advanced), and the receiver clock is
//! perfect.

use std::sync::Arc;

use anyhow::{ensure, Context, Result};
use gnss_attitude::nav::atmosphere::{klobuchar_delay_m, troposphere_delay_m};
use gnss_attitude::nav::message::KlobucharParameters;
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use super::rinex::EphemerisRecord;
use crate::synth::lnav::{LnavBitStream, LnavEncoder, BIT_S, SUBFRAME_S};
use crate::synth::scene::{CHIP_RATE, L1_WAVELENGTH, SPEED_OF_LIGHT};
use crate::synth::{Satellite, SatelliteTrack};
use crate::truth::gps::{AlmanacEntry, Geodetic, OMEGA_EARTH, WEEK_S};

/// Table step of the satellites' range and geometry, s.
pub const TRACK_STEP_S: f64 = 0.05;

/// Elevation mask of the satellites put into the recording, degrees.
pub const ELEVATION_MASK_DEG: f64 = 10.0;

/// Where and when the LNAV recording is made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LnavSpec {
    /// GPS week of the first sample.
    pub week: u16,
    /// GPS time of week of the first sample, s.
    pub tow_s: f64,
    /// Receiver position: latitude, longitude (degrees), height above the ellipsoid (m).
    pub position_llh: [f64; 3],
}

impl Default for LnavSpec {
    /// Week 2195 (the bundled almanac's), TOW 237 003.3 s (an hour after the almanac's
    /// reference time, 3.3 s into a subframe), Munich at 520 m.
    fn default() -> Self {
        Self {
            week: crate::synth::lnav::BUNDLED_ALMANAC_WEEK,
            tow_s: 237_003.3,
            position_llh: [48.1374, 11.5755, 520.0],
        }
    }
}

/// The navigation part of the truth file.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct NavigationTruth {
    /// GPS week of the first sample.
    pub gps_week: u16,
    /// GPS time of week of the first sample, s.
    pub tow_s: f64,
    /// Receiver position (antenna 0), WGS-84 ECEF, m.
    pub position_ecef_m: [f64; 3],
    /// Receiver position: latitude, longitude (degrees), height (m).
    pub position_llh: [f64; 3],
    /// The ephemerides the satellites broadcast at the first sample, RINEX 3 names and units.
    pub ephemerides: Vec<EphemerisRecord>,
}

/// One satellite of the LNAV sky: the scene's satellite and its truth at the first sample.
pub struct NavSatellite {
    /// The scene's satellite (with its track and data bits).
    pub satellite: Satellite,
    /// Azimuth at the first sample, degrees.
    pub azimuth_deg: f64,
    /// Elevation at the first sample, degrees.
    pub elevation_deg: f64,
}

/// The Klobuchar parameters the encoder broadcasts on page 18.
pub fn broadcast_klobuchar(encoder: &LnavEncoder) -> KlobucharParameters {
    KlobucharParameters {
        alpha: encoder.iono_utc.alpha.map(|a| a as f32),
        beta: encoder.iono_utc.beta.map(|b| b as f32),
    }
}

/// The LNAV message on a synthesized satellite's signal: the scene's code count starts at
/// the subframe start before the signal time received at the first sample, so that code
/// period `k` carries the LNAV bit `⌊k/20⌋` of that subframe on, and the code phase at any
/// sample is the signal's time of transmission (`code count = CHIP_RATE·(t_sv − reference)`).
#[derive(Clone, Debug, PartialEq)]
pub struct LnavModulation {
    /// The scene satellite's code phase at the first sample (its code count), chips:
    /// `CHIP_RATE·(t_sv0 − reference)`.
    pub code_phase_chips: f64,
    /// The data bits from the subframe start on (a [`SatelliteTrack::data_bits`] table).
    pub data_bits: Vec<bool>,
    /// The subframe start before `t_sv0`, s of the week (satellite clock).
    pub reference_s: f64,
}

impl LnavModulation {
    /// The modulation of `prn` (`week`) whose signal received at the first sample left the
    /// satellite at `t_sv0` (s of `week`, satellite clock: light time and `Δt_sv` included),
    /// covering `seconds` of samples (and a second more). Bits of a PRN the encoder lacks
    /// are 0.
    pub fn new(encoder: &LnavEncoder, prn: u8, week: u16, t_sv0: f64, seconds: f64) -> Self {
        let reference = (t_sv0 / SUBFRAME_S).floor() * SUBFRAME_S;
        let bits = ((t_sv0 - reference + seconds.max(0.0) + 1.0) / BIT_S).ceil() as usize;
        let mut stream = LnavBitStream::default();
        let data_bits = (0..bits)
            .map(|b| {
                stream
                    .bit(encoder, prn, week, reference + (b as f64 + 0.5) * BIT_S)
                    .unwrap_or(false)
            })
            .collect();
        Self {
            code_phase_chips: CHIP_RATE * (t_sv0 - reference),
            data_bits,
            reference_s: reference,
        }
    }
}

/// The geometry of one satellite seen by the receiver.
struct Geometry<'a> {
    encoder: &'a LnavEncoder,
    entry: &'a AlmanacEntry,
    site: Geodetic,
    rx: Vector3<f64>,
    c_ne: Matrix3<f64>,
    iono: KlobucharParameters,
    week: u16,
    tow0: f64,
}

impl Geometry<'_> {
    /// `(ρ_eff, unit line of sight NED)` at receiver time `t` (s from the first sample).
    fn at(&self, t: f64) -> (f64, Vector3<f64>) {
        let t_rx = self.tow0 + t;
        let week_offset = (f64::from(self.week) - f64::from(self.encoder.almanac_week)) * WEEK_S;
        let mut tau = 0.075;
        let mut p = Vector3::zeros();
        for _ in 0..4 {
            let (r, _) = self.entry.position_velocity(week_offset + t_rx - tau);
            let (s, c) = (OMEGA_EARTH * tau).sin_cos();
            p = Vector3::new(c * r.x + s * r.y, -s * r.x + c * r.y, r.z);
            tau = (p - self.rx).norm() / SPEED_OF_LIGHT;
        }
        let d = p - self.rx;
        let los = self.c_ne * (d / d.norm());
        let clock = self
            .encoder
            .signal_clock_offset_s(self.entry.prn, self.week, t_rx - tau)
            .unwrap_or(0.0);
        let el = (-los.z).asin();
        let az = los.y.atan2(los.x);
        let iono = klobuchar_delay_m(
            &self.iono,
            self.site.lat as f32,
            self.site.lon as f32,
            el as f32,
            az as f32,
            t_rx,
        );
        let tropo = troposphere_delay_m(self.site.height as f32, el as f32);
        let rho = SPEED_OF_LIGHT * (tau - clock) + f64::from(iono) + f64::from(tropo);
        (rho, los)
    }
}

/// The satellites of an LNAV recording of `seconds` s: the healthy almanac satellites above
/// [`ELEVATION_MASK_DEG`] at the first sample, highest first, at most `count`, with C/N0
/// `cn0_dbhz[k]` (by elevation rank), the array `antennas_b` at the constant attitude `c_rb`
/// (body to NED), carrier phases from `carrier_phase`.
///
/// # Errors
/// A position or time out of range, fewer than four satellites in view.
pub fn lnav_satellites(
    lnav: &LnavSpec,
    seconds: f64,
    count: usize,
    cn0_dbhz: &[f64],
    antennas_b: &[Vector3<f64>],
    c_rb: &Matrix3<f64>,
    mut carrier_phase: impl FnMut() -> f64,
) -> Result<(Vec<NavSatellite>, NavigationTruth)> {
    let [lat, lon, h] = lnav.position_llh;
    ensure!(
        (-90.0..=90.0).contains(&lat)
            && (-180.0..=360.0).contains(&lon)
            && (-500.0..=20_000.0).contains(&h),
        "--position {lat},{lon},{h}: latitude ±90°, longitude -180..360°, height -500..20000 m"
    );
    ensure!(
        lnav.tow_s.is_finite() && (0.0..WEEK_S).contains(&lnav.tow_s),
        "--gps-start time of week {} outside 0..604800 s",
        lnav.tow_s
    );
    let encoder = LnavEncoder::bundled();
    let site = Geodetic::from_degrees(lat, lon, h);
    let rx = site.to_ecef();
    let week_offset = (f64::from(lnav.week) - f64::from(encoder.almanac_week)) * WEEK_S;
    let mut views = encoder.almanac.visible(
        &site,
        week_offset + lnav.tow_s,
        ELEVATION_MASK_DEG.to_radians(),
    );
    views.sort_by(|a, b| b.elevation.total_cmp(&a.elevation));
    views.truncate(count);
    ensure!(
        views.len() >= 4,
        "{} satellites above {ELEVATION_MASK_DEG}° at week {} TOW {} from {lat},{lon}: 4 needed",
        views.len(),
        lnav.week,
        lnav.tow_s
    );
    let points = (seconds / TRACK_STEP_S).ceil() as usize + 3;
    let mut out = Vec::with_capacity(views.len());
    let mut ephemerides = Vec::new();
    for (k, view) in views.iter().enumerate() {
        let entry = encoder
            .almanac
            .entries
            .iter()
            .find(|e| e.prn == view.prn)
            .context("almanac entry of a visible satellite")?;
        let geometry = Geometry {
            encoder: &encoder,
            entry,
            site,
            rx,
            c_ne: site.ecef_to_ned(),
            iono: broadcast_klobuchar(&encoder),
            week: lnav.week,
            tow0: lnav.tow_s,
        };
        let cn0 = cn0_dbhz.get(k).copied().unwrap_or(45.0);
        let mut track = SatelliteTrack {
            step_s: TRACK_STEP_S,
            ..SatelliteTrack::default()
        };
        let delta = 1e-3;
        for p in 0..points {
            let t = p as f64 * TRACK_STEP_S;
            let (rho, los) = geometry.at(t);
            let rate = (geometry.at(t + delta).0 - geometry.at(t - delta).0) / (2.0 * delta);
            track.range_m.push(rho);
            track.range_rate_m_s.push(rate);
            track
                .geometry_m
                .push(antennas_b.iter().map(|r| los.dot(&(c_rb * r))).collect());
            track.cn0_dbhz.push(vec![cn0; antennas_b.len()]);
        }
        let (rho0, los0) = geometry.at(0.0);
        // the signal time received at the first sample
        let t_sv0 = lnav.tow_s - rho0 / SPEED_OF_LIGHT;
        let modulation = LnavModulation::new(&encoder, view.prn, lnav.week, t_sv0, seconds);
        track.data_bits = modulation.data_bits;
        let rate0 = track.range_rate_m_s.first().copied().unwrap_or(0.0);
        let rate1 = track.range_rate_m_s.get(1).copied().unwrap_or(rate0);
        let frame_start = lnav.tow_s - lnav.tow_s.rem_euclid(30.0);
        if let Some(e) = encoder.ephemeris(view.prn, lnav.week, frame_start) {
            ephemerides.push(EphemerisRecord::from(&e.to_core()));
        }
        out.push(NavSatellite {
            satellite: Satellite {
                prn: view.prn,
                cn0_dbhz: cn0,
                doppler_hz: -rate0 / L1_WAVELENGTH,
                doppler_rate_hz_s: -(rate1 - rate0) / TRACK_STEP_S / L1_WAVELENGTH,
                code_phase_chips: modulation.code_phase_chips,
                carrier_phase_cycles: carrier_phase(),
                los_ref: los0,
                data_seed: None,
                track: Some(Arc::new(track)),
            },
            azimuth_deg: los0.y.atan2(los0.x).to_degrees().rem_euclid(360.0),
            elevation_deg: (-los0.z).asin().to_degrees(),
        });
    }
    let truth = NavigationTruth {
        gps_week: lnav.week,
        tow_s: lnav.tow_s,
        position_ecef_m: [rx.x, rx.y, rx.z],
        position_llh: lnav.position_llh,
        ephemerides,
    };
    Ok((out, truth))
}
