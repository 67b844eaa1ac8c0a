//! `track`'s navigation: each channel's 1 ms prompts go through the core's LNAV decoder
//! ([`ChannelDecoder`]) into one [`NavigationStore`]; every [`FIX_INTERVAL_S`] (a common
//! receiver sample instant) the channels' code counts and code phases give times of
//! transmission and pseudoranges, and the core's single-point solver ([`solve`], ground
//! configuration: 5° mask, broadcast ionosphere when known, troposphere, residual check) a
//! position, clock and velocity. The lines of sight of the attitude windows (NED) come from
//! the latest fix and the ephemerides.
//!
//! # Receiver clock
//!
//! The sample count is the receiver clock. Its time of week is set once, at the first
//! measurement instant with a decoded time: the latest time of transmission among the
//! channels plus 75 ms (a nominal flight); the solver estimates the clock bias that remains
//! (a few ms, within the pseudorange's accepted flight range). The GPS time of a fix is the
//! receiver time minus that bias.
//!
//! # Ephemerides
//!
//! Decoded (subframes 1–3 of one issue, from any frames); with `--nav FILE` a RINEX file
//! fills the satellites not decoded yet (and gives the week and the ionosphere before
//! subframe 1 and page 18 arrive, so the first fix needs only one decoded subframe per
//! satellite: its HOW gives the time).

use anyhow::Result;
use gnss_attitude::nav::decoder::DecodeError;
use gnss_attitude::nav::geodesy::Geodetic;
use gnss_attitude::nav::message::KlobucharParameters;
use gnss_attitude::nav::subframe::SubframeError;
use gnss_attitude::nav::{
    line_of_sight, solve, BitSyncConfig, ChannelDecoder, Ephemeris, Fix, GpsTime, NavState,
    NavigationStore, Observation, ReferenceFrame, SolverConfig, Subframe, TransmitTime,
};
use gnss_attitude::signal::{CA_CHIP_RATE_HZ, GPS_L1_HZ};
use gnss_attitude::tracking::{ChannelState, TrackingEpoch};
use nalgebra::Vector3;
use serde::Serialize;

use super::rinex::{EphemerisRecord, NavFile};

/// Interval of the navigation fixes, s.
pub const FIX_INTERVAL_S: f64 = 1.0;

/// Nominal signal flight used to set the receiver clock, s.
pub const NOMINAL_FLIGHT_S: f64 = 0.075;

/// Pseudorange standard deviation at 45 dB-Hz, m (scaled by `10^((45 − C/N0)/20)`).
pub const PSEUDORANGE_SIGMA_45_M: f64 = 1.5;

/// Chips per code period.
const CODE_CHIPS: f64 = 1023.0;

/// One channel's measurement at a fix instant.
#[derive(Clone, Copy, Debug)]
struct Measurement {
    instant: u64,
    transmit: TransmitTime,
    doppler_hz: f32,
    cn0_dbhz: f32,
}

/// The navigation state of one tracking channel.
pub struct NavChannel {
    decoder: ChannelDecoder,
    last_index: Option<u32>,
    subframes: Vec<Subframe>,
    refused: Vec<SubframeError>,
    measurements: Vec<Measurement>,
    fs: f64,
    next_instant: u64,
}

/// Receiver sample of fix instant `m`.
fn instant_sample(m: u64, fs: f64) -> u64 {
    (m as f64 * FIX_INTERVAL_S * fs).round() as u64
}

impl NavChannel {
    /// The decoder of satellite `prn` at sample rate `fs` (Hz).
    pub fn new(prn: u8, fs: f64) -> Self {
        Self {
            decoder: ChannelDecoder::new(prn, BitSyncConfig::default()),
            last_index: None,
            subframes: Vec::new(),
            refused: Vec::new(),
            measurements: Vec::new(),
            fs,
            next_instant: 0,
        }
    }

    /// The satellite.
    pub fn prn(&self) -> u8 {
        self.decoder.prn()
    }

    /// Whether the decoder holds subframe sync (it knows the time of transmission).
    pub fn subframe_synchronized(&self) -> bool {
        self.decoder.subframe_synchronized()
    }

    /// The subframes decoded and the ones refused (parity, preamble) since the last call, for
    /// a caller with a store of its own (the microsat flight's navigation).
    pub fn take_decoded(&mut self) -> (Vec<Subframe>, Vec<SubframeError>) {
        (
            std::mem::take(&mut self.subframes),
            std::mem::take(&mut self.refused),
        )
    }

    /// Gives the decoder the GPS week (a subframe 1's, or the flight computer's), so that its
    /// subframe anchor yields times of transmission.
    pub fn set_week(&mut self, week: u16) {
        if self.decoder.anchor().is_some_and(|a| a.week.is_none()) {
            self.decoder.set_week(week);
        }
    }

    /// The times of transmission measured at the fix instants since the last call: receiver
    /// sample of the instant (a multiple of `FIX_INTERVAL_S · fs`) and the time.
    pub fn take_transmit_times(&mut self) -> Vec<(u64, TransmitTime)> {
        self.measurements
            .drain(..)
            .map(|m| (m.instant, m.transmit))
            .collect()
    }

    /// Takes one tracking epoch (`locked`: code and phase lock).
    pub fn epoch<const A: usize>(&mut self, e: &TrackingEpoch<A>, locked: bool) {
        // a new hand-over restarts the epoch count: the decoder starts over
        if self
            .last_index
            .is_some_and(|l| e.index != l.wrapping_add(1))
        {
            self.decoder.reset();
        }
        self.last_index = Some(e.index);
        let c = &e.correlations;
        let epoch = u64::from(e.index);
        if locked && e.state != ChannelState::Refining {
            match self.decoder.push_prompt(epoch, c.taps[0].prompt.i as f32) {
                Ok(Some(sf)) => self.subframes.push(sf),
                Err(DecodeError::Subframe(err)) => self.refused.push(err),
                _ => {}
            }
        }
        let end = c.first_sample + u64::from(c.samples);
        while instant_sample(self.next_instant, self.fs) < c.first_sample {
            self.next_instant += 1;
        }
        let sample = instant_sample(self.next_instant, self.fs);
        if sample >= end {
            return;
        }
        self.next_instant += 1;
        if !locked {
            return;
        }
        // the replica's code phase at the instant, its code period counted from this epoch
        let rate = CA_CHIP_RATE_HZ * (1.0 + f64::from(e.doppler_hz) / GPS_L1_HZ);
        let mut chips = c.code_phase_at_first as f64 / 4_294_967_296.0;
        if chips > CODE_CHIPS / 2.0 {
            chips -= CODE_CHIPS;
        }
        chips += (sample - c.first_sample) as f64 * rate / self.fs;
        let periods = (chips / CODE_CHIPS).floor();
        let chips = (chips - periods * CODE_CHIPS).clamp(0.0, CODE_CHIPS - 1e-6);
        let Some(period) = epoch.checked_add_signed(periods as i64) else {
            return;
        };
        if let Ok(transmit) = self.decoder.transmit_time(period, chips as f32) {
            self.measurements.push(Measurement {
                instant: sample,
                transmit,
                doppler_hz: e.doppler_hz,
                cn0_dbhz: e.cn0_dbhz,
            });
        }
    }
}

/// One navigation fix as `track` reports it.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FixRow {
    /// Receiver time of the fix, s from the first sample.
    pub t_s: f64,
    /// GPS week of the fix.
    pub gps_week: u16,
    /// GPS time of week of the fix (receiver clock corrected), s.
    pub tow_s: f64,
    /// Position, WGS-84 ECEF, m.
    pub position_ecef_m: [f64; 3],
    /// Latitude, longitude (degrees), height (m).
    pub position_llh: [f64; 3],
    /// Receiver clock bias, m.
    pub clock_bias_m: f64,
    /// Position dilution of precision.
    pub pdop: f64,
    /// Satellites used.
    pub satellites: u8,
    /// RMS of the pseudorange residuals, m.
    pub residual_rms_m: f64,
}

/// The `navigation` object of `track --json`.
#[derive(Clone, Debug, Serialize)]
pub struct NavigationReport {
    /// Where the fixes' ephemerides came from: `decoded`, or `decoded+rinex` with `--nav`.
    pub ephemeris_source: String,
    /// The ephemerides decoded from the signals, one per PRN (RINEX 3 names and units).
    pub ephemerides: Vec<EphemerisRecord>,
    /// GPS week at the first fix.
    pub gps_week: Option<u16>,
    /// GPS time of week at the first fix, s.
    pub tow_s: Option<f64>,
    /// Mean position of the fixes, WGS-84 ECEF, m.
    pub position_ecef_m: Option<[f64; 3]>,
    /// That position as latitude, longitude (degrees), height (m).
    pub position_llh: Option<[f64; 3]>,
    /// Fixes computed.
    pub fixes: usize,
    /// Median PDOP of the fixes.
    pub pdop: Option<f64>,
    /// Subframes refused by their parity (all channels).
    pub parity_failures: u32,
    /// Subframes decoded (all channels).
    pub subframes: u32,
    /// Time to first fix: receiver time of the first fix, s from the first sample.
    pub ttff_s: Option<f64>,
    /// Fix attempts refused by the solver, by reason.
    pub refused_fixes: Vec<(String, usize)>,
    /// Every fix.
    pub per_fix: Vec<FixRow>,
}

/// The navigation of a `track` run.
pub struct Navigator {
    store: NavigationStore,
    file: Option<NavFile>,
    fs: f64,
    receiver_epoch: Option<GpsTime>,
    next_instant: u64,
    last_fix: Option<Fix>,
    fixes: Vec<FixRow>,
    refused: Vec<(String, usize)>,
}

impl Navigator {
    /// A navigator at sample rate `fs` (Hz), with the RINEX file of `--nav` if given.
    pub fn new(fs: f64, file: Option<NavFile>) -> Self {
        Self {
            store: NavigationStore::default(),
            file,
            fs,
            receiver_epoch: None,
            next_instant: 0,
            last_fix: None,
            fixes: Vec::new(),
            refused: Vec::new(),
        }
    }

    /// After a block ending at sample `end` (every channel has reached it): the decoded
    /// subframes into the store, the week to the decoders, the fixes of the instants passed.
    ///
    /// # Errors
    /// None today (solver refusals are counted in the report).
    pub fn after_block<'a>(
        &mut self,
        channels: impl Iterator<Item = &'a mut NavChannel>,
        end: u64,
    ) -> Result<()> {
        let mut channels: Vec<&mut NavChannel> = channels.collect();
        for ch in channels.iter_mut() {
            let prn = ch.decoder.prn();
            for sf in ch.subframes.drain(..) {
                // an implausible set is counted by the store
                let _ = self.store.add_subframe(prn, &sf);
            }
            for err in ch.refused.drain(..) {
                self.store.record_decode_error(&err);
            }
        }
        if let Some(week) = self.week() {
            for ch in channels.iter_mut() {
                if ch.decoder.anchor().is_some_and(|a| a.week.is_none()) {
                    ch.decoder.set_week(week);
                }
            }
        }
        while instant_sample(self.next_instant, self.fs) < end {
            let sample = instant_sample(self.next_instant, self.fs);
            self.next_instant += 1;
            let measured: Vec<Measurement> = channels
                .iter_mut()
                .flat_map(|ch| {
                    let taken: Vec<Measurement> = ch
                        .measurements
                        .iter()
                        .filter(|m| m.instant == sample)
                        .copied()
                        .collect();
                    ch.measurements.retain(|m| m.instant > sample);
                    taken
                })
                .collect();
            self.fix(sample, &measured);
        }
        Ok(())
    }

    /// The GPS week: decoded from a subframe 1, or the RINEX file's first ephemeris.
    fn week(&self) -> Option<u16> {
        self.store.week().or_else(|| {
            self.file
                .as_ref()
                .and_then(|f| f.ephemerides.first().map(|e| e.week))
        })
    }

    /// The ephemerides available: decoded ones, the RINEX file's (nearest `t_oe`) for the
    /// others.
    fn ephemerides(&self, time: &GpsTime) -> Vec<Ephemeris> {
        let mut out: Vec<Ephemeris> = self.store.ephemerides().copied().collect();
        if let Some(file) = &self.file {
            for prn in 1..=32u8 {
                if out.iter().any(|e| e.prn == prn) {
                    continue;
                }
                let nearest = file
                    .ephemerides
                    .iter()
                    .filter(|e| e.prn == prn)
                    .min_by(|a, b| {
                        let da = a.toe().seconds_since(time).abs();
                        let db = b.toe().seconds_since(time).abs();
                        da.total_cmp(&db)
                    });
                if let Some(e) = nearest {
                    out.push(*e);
                }
            }
        }
        out
    }

    fn ionosphere(&self) -> Option<KlobucharParameters> {
        self.store
            .ionosphere()
            .or_else(|| self.file.as_ref().and_then(|f| f.ionosphere))
    }

    fn refuse(&mut self, reason: String) {
        match self.refused.iter_mut().find(|r| r.0 == reason) {
            Some(r) => r.1 += 1,
            None => self.refused.push((reason, 1)),
        }
    }

    /// A fix at receiver sample `sample` from the channels' measurements.
    fn fix(&mut self, sample: u64, measured: &[Measurement]) {
        if measured.len() < 4 {
            return;
        }
        let t_rx = sample as f64 / self.fs;
        if self.receiver_epoch.is_none() {
            let latest = measured
                .iter()
                .filter_map(|m| m.transmit.gps_time().ok())
                .max_by(|a, b| a.seconds_since(b).total_cmp(&0.0));
            self.receiver_epoch = latest.and_then(|t| t.add_seconds(NOMINAL_FLIGHT_S - t_rx).ok());
        }
        let Some(receive) = self.receiver_epoch.and_then(|e| e.add_seconds(t_rx).ok()) else {
            return;
        };
        let observations: Vec<Observation> = measured
            .iter()
            .filter_map(|m| {
                let sigma = PSEUDORANGE_SIGMA_45_M
                    * 10f64.powf((45.0 - f64::from(m.cn0_dbhz).clamp(20.0, 60.0)) / 20.0);
                Observation::from_transmit_time(
                    &m.transmit,
                    &receive,
                    Some(m.doppler_hz),
                    sigma as f32,
                )
                .ok()
            })
            .collect();
        let ephemerides = self.ephemerides(&receive);
        let iono = self.ionosphere();
        let initial = self.last_fix.map(|f| f.position_m);
        let result = solve(
            &observations,
            &ephemerides[..],
            iono.as_ref(),
            &receive,
            initial.as_ref(),
            &SolverConfig::ground(),
        );
        match result {
            Ok(fix) => {
                let g = Geodetic::from_ecef(&fix.position_m);
                self.fixes.push(FixRow {
                    t_s: t_rx,
                    gps_week: fix.time.week,
                    tow_s: fix.time.tow_s,
                    position_ecef_m: fix.position_m,
                    position_llh: g.map_or([f64::NAN; 3], |g| {
                        [g.lat_rad.to_degrees(), g.lon_rad.to_degrees(), g.height_m]
                    }),
                    clock_bias_m: fix.clock_bias_m,
                    pdop: f64::from(fix.dop.pdop),
                    satellites: fix.satellites,
                    residual_rms_m: f64::from(fix.residual_rms_m),
                });
                self.last_fix = Some(fix);
            }
            Err(e) => self.refuse(e.to_string()),
        }
    }

    /// The line of sight to `prn` (unit vector, local NED at the latest fix) at receiver
    /// time `t_s` (s from the first sample); `None` before the first fix or without an
    /// ephemeris.
    pub fn los_ned(&self, prn: u8, t_s: f64) -> Option<Vector3<f64>> {
        let fix = self.last_fix.as_ref()?;
        let row = self.fixes.last()?;
        let time = fix.time.add_seconds(t_s - row.t_s).ok()?;
        let eph = self.ephemerides(&time).into_iter().find(|e| e.prn == prn)?;
        let state = NavState {
            time,
            position_m: fix.position_m,
            velocity_m_s: [0.0; 3],
            position_sigma_m: 0.0,
            velocity_sigma_m_s: 0.0,
        };
        let los = line_of_sight(&state, &eph, &ReferenceFrame::LocalNed).ok()?;
        Some(Vector3::new(
            f64::from(los.los[0]),
            f64::from(los.los[1]),
            f64::from(los.los[2]),
        ))
    }

    /// The decoded ephemerides and the broadcast ionosphere (for `track_nav.rnx`).
    pub fn decoded(&self) -> (Vec<Ephemeris>, Option<KlobucharParameters>) {
        (
            self.store.ephemerides().copied().collect(),
            self.store.ionosphere(),
        )
    }

    /// The report.
    pub fn report(&self) -> NavigationReport {
        let counters = self.store.counters();
        let n = self.fixes.len();
        let mean = (n > 0).then(|| {
            std::array::from_fn(|i| {
                self.fixes.iter().map(|f| f.position_ecef_m[i]).sum::<f64>() / n as f64
            })
        });
        let llh = mean
            .and_then(|p: [f64; 3]| Geodetic::from_ecef(&p))
            .map(|g| [g.lat_rad.to_degrees(), g.lon_rad.to_degrees(), g.height_m]);
        let mut pdops: Vec<f64> = self.fixes.iter().map(|f| f.pdop).collect();
        pdops.sort_by(f64::total_cmp);
        let first = self.fixes.first();
        NavigationReport {
            ephemeris_source: if self.file.is_some() {
                "decoded+rinex"
            } else {
                "decoded"
            }
            .into(),
            ephemerides: self
                .store
                .ephemerides()
                .map(EphemerisRecord::from)
                .collect(),
            gps_week: first.map(|f| f.gps_week),
            tow_s: first.map(|f| f.tow_s),
            position_ecef_m: mean,
            position_llh: llh,
            fixes: n,
            pdop: pdops.get(n / 2).copied(),
            parity_failures: counters.parity_failures,
            subframes: counters.subframes,
            ttff_s: first.map(|f| f.t_s),
            refused_fixes: self.refused.clone(),
            per_fix: self.fixes.clone(),
        }
    }

    /// The fixes.
    pub fn fixes(&self) -> &[FixRow] {
        &self.fixes
    }
}
