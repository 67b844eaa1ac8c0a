//! `host-sim track`: acquisition, then the core's tracking channels over the whole recording
//! (or `--seconds`), streamed block by block, with re-acquisition of lost satellites.
//!
//! Memory is bounded by the block size plus per-satellite summaries: the epochs themselves
//! are folded into 100 ms rows as they arrive (a 1 GB recording at 2.6 Msps, 190 s, keeps
//! about 2000 rows per satellite), so files of any size can be tracked.
//!
//! The channels use [`ChannelConfig::leo`]: the refinement stage also estimates the Doppler
//! rate (harmless for a ground receiver, needed for LEO dynamics; see the README).
//!
//! Re-acquisition: a satellite without code and phase lock for [`REACQUIRE_AFTER_S`] (after its
//! pull-in allowance; phase lock too, because a 100 ms code-lock window passes the C/N0
//! threshold on noise alone a few times in a thousand) is searched again on the next milliseconds of the stream (same settings as the
//! first acquisition) and, when found, handed over again; otherwise searched again
//! [`RETRY_EVERY_S`] later.

use std::time::Instant;

use anyhow::{ensure, Result};
use gnss_attitude::signal::SampleBlock;
use gnss_attitude::tracking::{
    AcquisitionConfig, Channel, ChannelConfig, ChannelState, SearchResult, TrackingEpoch,
};
use serde::Serialize;

use super::acquire::{acquire, split_cross_correlations, AcquireOptions, AcquireReport};
use super::attitude::{AttitudeReport, AttitudeSetup, AttitudeSolver, PhaseAccumulator};
use super::reader::{Block, Recording};
use crate::chain::{search_prns, track_block};

/// Seconds without code and phase lock after which a satellite is re-acquired.
pub const REACQUIRE_AFTER_S: f64 = 1.0;

/// Interval of the re-acquisition attempts of a satellite not found, s.
pub const RETRY_EVERY_S: f64 = 0.5;

/// Pull-in allowance after a hand-over before the re-acquisition clock runs, s (refinement
/// 0.256 s, pull-in 0.3 s, a lock window 0.1 s, margin).
pub const PULL_IN_ALLOWANCE_S: f64 = 1.0;

/// Interval of the rows (CSV, plots), s.
pub const ROW_INTERVAL_S: f64 = 0.1;

/// Settings of the tracking run.
#[derive(Clone, Debug)]
pub struct TrackOptions {
    /// Acquisition settings (initial and re-acquisition).
    pub acquire: AcquireOptions,
    /// Seconds to track (`None`: the whole recording).
    pub seconds: Option<f64>,
    /// Sample instants per streamed block.
    pub block: usize,
    /// Re-acquire lost satellites.
    pub reacquire: bool,
    /// Attitude from a three-antenna recording (`None`: no attitude).
    pub attitude: Option<AttitudeSetup>,
}

impl Default for TrackOptions {
    fn default() -> Self {
        Self {
            acquire: AcquireOptions::default(),
            seconds: None,
            block: 1 << 16,
            reacquire: true,
            attitude: None,
        }
    }
}

/// One 100 ms row of a satellite.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Row {
    /// End of the interval, s from the first sample.
    pub t_s: f64,
    /// Mean replica Doppler over the interval, Hz.
    pub doppler_hz: f64,
    /// Latest C/N0 report, dB-Hz.
    pub cn0_dbhz: f64,
    /// Fraction of the interval's epochs with code and phase lock.
    pub locked: f64,
}

/// The per-satellite report.
#[derive(Clone, Debug, Serialize)]
pub struct SatelliteReport {
    /// PRN.
    pub prn: u8,
    /// Doppler of the first acquisition, Hz.
    pub acquired_doppler_hz: f64,
    /// Code phase of the first acquisition (at the first sample), chips.
    pub acquired_code_phase_chips: f64,
    /// First epoch with code and phase lock, s (`None`: never locked).
    pub first_lock_s: Option<f64>,
    /// Total time with code and phase lock, s.
    pub lock_time_s: f64,
    /// Longest uninterrupted lock, s.
    pub longest_lock_s: f64,
    /// Locked without a break from the first lock to the end of the run.
    pub held_to_end: bool,
    /// Lock losses after the first lock.
    pub losses: u32,
    /// Re-acquisitions (successful hand-overs after a loss).
    pub reacquisitions: u32,
    /// Mean of the 1 s C/N0 reports from 2 s on (all reports if fewer), dB-Hz.
    pub cn0_dbhz_mean: f64,
    /// Smallest and largest of those reports, dB-Hz.
    pub cn0_dbhz_range: [f64; 2],
    /// `cn0_dbhz_mean` with the modelled cross-correlation of the other tracked satellites
    /// removed (see [`mai_corrected_cn0`]): the thermal C/N0, dB-Hz.
    pub cn0_dbhz_thermal: f64,
    /// Doppler rate by least squares over the locked epochs, Hz/s.
    pub doppler_rate_hz_s: f64,
    /// Doppler over time: one value per second (mean of the locked epochs), Hz; `null` for
    /// seconds without lock.
    pub doppler_hz_per_s: Vec<Option<f64>>,
    /// C/N0 reports over time (one per second after the first), dB-Hz.
    pub cn0_dbhz_per_s: Vec<f64>,
}

/// Wall times of the run, s.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct WallTimes {
    /// Reading and decoding the blocks.
    pub read_s: f64,
    /// Tracking (all channels, parallel over satellites).
    pub tracking_s: f64,
    /// Re-acquisition searches.
    pub reacquisition_s: f64,
    /// Attitude solutions.
    pub attitude_s: f64,
}

/// What `track` reports (`--json` prints it as one object).
#[derive(Clone, Debug, Serialize)]
pub struct TrackReport {
    /// The initial acquisition.
    pub acquisition: AcquireReport,
    /// Seconds of the recording tracked.
    pub tracked_s: f64,
    /// Satellites, by PRN.
    pub satellites: Vec<SatelliteReport>,
    /// Attitude (three-antenna recordings with `--baselines` and `--sky`).
    pub attitude: Option<AttitudeReport>,
    /// Wall times.
    pub wall: WallTimes,
    /// Files written by `--out`.
    pub files_written: Vec<String>,
}

/// The running state of one satellite (the companion of its channel).
pub struct SatTrack {
    prn: u8,
    first: SearchResult,
    fs: f64,
    active: bool,
    started_t: f64,
    last_lock_t: f64,
    last_t: f64,
    reacquisitions: u32,
    retry_at: f64,
    // lock bookkeeping
    first_lock: Option<f64>,
    run_start: Option<f64>,
    longest: f64,
    locked_epochs: u64,
    losses: u32,
    // rows
    rows: Vec<Row>,
    row_end: f64,
    row_sum: (f64, u32, u32, u32), // Σ Doppler (locked), locked count, epochs, Σ-count of Doppler
    cn0_last: f64,
    cn0_reports: Vec<(f64, f64)>,
    // Doppler-rate least squares over locked epochs: Σ1, Σt, Σt², Σf, Σtf
    fit: [f64; 5],
    /// Phase and code sums of the attitude windows.
    pub phases: Option<PhaseAccumulator>,
}

impl SatTrack {
    fn new(first: SearchResult, fs: f64, phases: Option<PhaseAccumulator>) -> Self {
        Self {
            prn: first.prn.number(),
            first,
            fs,
            active: true,
            started_t: 0.0,
            last_lock_t: 0.0,
            last_t: 0.0,
            reacquisitions: 0,
            retry_at: 0.0,
            first_lock: None,
            run_start: None,
            longest: 0.0,
            locked_epochs: 0,
            losses: 0,
            rows: Vec::new(),
            row_end: ROW_INTERVAL_S,
            row_sum: (0.0, 0, 0, 0),
            cn0_last: f64::NAN,
            cn0_reports: Vec::new(),
            fit: [0.0; 5],
            phases,
        }
    }

    /// PRN.
    pub fn prn(&self) -> u8 {
        self.prn
    }

    fn epoch<const A: usize>(&mut self, e: &TrackingEpoch<A>) {
        let c = &e.correlations;
        let t = (c.first_sample as f64 + 0.5 * f64::from(c.samples)) / self.fs;
        let dt = f64::from(c.samples) / self.fs;
        while t > self.row_end {
            self.close_row();
        }
        // The lock detector also runs during the refinement stage, whose carrier loop is open:
        // lock counts from the pull-in on.
        let locked = e.lock.code && e.lock.phase && e.state != ChannelState::Refining;
        if locked {
            self.last_lock_t = t;
        }
        let doppler = f64::from(e.doppler_hz);
        self.row_sum.2 += 1;
        if locked {
            self.row_sum.0 += doppler;
            self.row_sum.1 += 1;
            self.locked_epochs += 1;
            for (s, v) in self
                .fit
                .iter_mut()
                .zip([1.0, t, t * t, doppler, t * doppler])
            {
                *s += v;
            }
            if self.first_lock.is_none() {
                self.first_lock = Some(t - 0.5 * dt);
            }
            if self.run_start.is_none() {
                self.run_start = Some(t - 0.5 * dt);
            }
        } else if let Some(s) = self.run_start.take() {
            self.longest = self.longest.max(t - 0.5 * dt - s);
            self.losses += 1;
        }
        // 0 until the channel's first lock window completes: no estimate yet.
        self.cn0_last = if e.cn0_dbhz > 0.0 {
            f64::from(e.cn0_dbhz)
        } else {
            f64::NAN
        };
        // A fresh 1 s C/N0 report completes with every 1000th epoch since the hand-over.
        if (e.index + 1) % 1000 == 0 {
            self.cn0_reports.push((t, self.cn0_last));
        }
        if let Some(p) = self.phases.as_mut() {
            p.add(e, t, locked);
        }
        self.last_t = t + 0.5 * dt;
    }

    fn close_row(&mut self) {
        let (sum, locked, n, _) = self.row_sum;
        self.rows.push(Row {
            t_s: self.row_end,
            doppler_hz: if locked > 0 {
                sum / f64::from(locked)
            } else {
                f64::NAN
            },
            cn0_dbhz: self.cn0_last,
            locked: if n > 0 {
                f64::from(locked) / f64::from(n)
            } else {
                0.0
            },
        });
        self.row_sum = (0.0, 0, 0, 0);
        self.row_end += ROW_INTERVAL_S;
    }

    fn needs_reacquisition(&self, now: f64) -> bool {
        let since = self.last_lock_t.max(self.started_t + PULL_IN_ALLOWANCE_S);
        self.active && now - since > REACQUIRE_AFTER_S
    }

    fn report(&mut self, end_t: f64) -> SatelliteReport {
        while self.row_end <= end_t + 1e-9 {
            self.close_row();
        }
        if self.row_sum.2 > 0 {
            self.close_row();
        }
        let held = self.run_start.is_some() && self.losses == 0;
        if let Some(s) = self.run_start {
            self.longest = self.longest.max(self.last_t - s);
        }
        let late: Vec<f64> = self
            .cn0_reports
            .iter()
            .filter(|(t, _)| *t >= 2.0)
            .map(|r| r.1)
            .collect();
        let reports: Vec<f64> = if late.is_empty() {
            self.cn0_reports.iter().map(|r| r.1).collect()
        } else {
            late
        };
        let mean = reports.iter().sum::<f64>() / reports.len().max(1) as f64;
        let range = reports
            .iter()
            .fold([f64::INFINITY, f64::NEG_INFINITY], |r, &c| {
                [r[0].min(c), r[1].max(c)]
            });
        let [n, st, stt, sf, stf] = self.fit;
        let det = n * stt - st * st;
        let rate = if n > 10.0 && det > 1e-12 {
            (n * stf - st * sf) / det
        } else {
            f64::NAN
        };
        let per_s = |rows: &[Row]| -> Vec<Option<f64>> {
            rows.chunks(10)
                .map(|c| {
                    let v: Vec<f64> = c
                        .iter()
                        .map(|r| r.doppler_hz)
                        .filter(|d| d.is_finite())
                        .collect();
                    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
                })
                .collect()
        };
        SatelliteReport {
            prn: self.prn,
            acquired_doppler_hz: f64::from(self.first.doppler_hz),
            acquired_code_phase_chips: f64::from(self.first.code_phase_chips),
            first_lock_s: self.first_lock,
            lock_time_s: self.locked_epochs as f64 * 1e-3,
            longest_lock_s: self.longest,
            held_to_end: held,
            losses: self.losses,
            reacquisitions: self.reacquisitions,
            cn0_dbhz_mean: if reports.is_empty() { f64::NAN } else { mean },
            cn0_dbhz_range: if reports.is_empty() {
                [f64::NAN; 2]
            } else {
                range
            },
            cn0_dbhz_thermal: f64::NAN,
            doppler_rate_hz_s: rate,
            doppler_hz_per_s: per_s(&self.rows),
            cn0_dbhz_per_s: self.cn0_reports.iter().map(|r| r.1).collect(),
        }
    }

    /// The rows (100 ms) so far.
    pub fn rows(&self) -> &[Row] {
        &self.rows
    }
}

/// Spectral separation coefficient of two GPS C/A (BPSK-R(1)) signals with rectangular chips
/// and no band limit, 1/Hz: `κ = ∫ G(f)² df = 2/(3 f_c)` (−61.9 dB/Hz). A 1 ms prompt sees
/// another satellite's code at a random fractional chip offset `u`; its cross-correlation power
/// is `((1 − u)² + u²)/1023` on average over the code, i.e. `(2/3)/1023` over `u`.
pub const CA_SPECTRAL_SEPARATION_PER_HZ: f64 = 2.0 / (3.0 * gnss_attitude::signal::CA_CHIP_RATE_HZ);

/// Thermal C/N0 from the measured ones (dB-Hz; NaN entries are skipped): the noise tap and the
/// prompt both see the other satellites' cross-correlation, so the core's estimator measures
/// `C_i/(N0 + I0_i)` with `I0_i = κ Σ_{j≠i} C_j` (the effective C/N0 of Betz's spectral
/// separation coefficient, `κ` = [`CA_SPECTRAL_SEPARATION_PER_HZ`]). Solved for the thermal
/// values by a fixed-point iteration (10 steps; it contracts by `κ Σ C/N0 ≪ 1`). Satellites
/// that are not tracked are not in the sum; a band-limited front end has a somewhat smaller
/// `κ`.
pub fn mai_corrected_cn0(measured_dbhz: &[f64]) -> Vec<f64> {
    let kappa = CA_SPECTRAL_SEPARATION_PER_HZ;
    let x: Vec<f64> = measured_dbhz
        .iter()
        .map(|c| {
            if c.is_finite() {
                10f64.powf(c / 10.0)
            } else {
                0.0
            }
        })
        .collect();
    let mut thermal = x.clone();
    for _ in 0..10 {
        let sum: f64 = thermal.iter().map(|c| c * kappa).sum();
        thermal = x
            .iter()
            .zip(&thermal)
            .map(|(&xi, &ti)| xi * (1.0 + sum - ti * kappa))
            .collect();
    }
    measured_dbhz
        .iter()
        .zip(thermal)
        .map(|(m, t)| {
            if m.is_finite() {
                10.0 * t.log10()
            } else {
                f64::NAN
            }
        })
        .collect()
}

/// Samples of the reference antenna collected for a re-acquisition.
struct Collection {
    first: u64,
    i: Vec<i8>,
    q: Vec<i8>,
}

/// The result of a run: the report and the per-satellite state (rows for the files).
pub struct TrackRun {
    /// The report.
    pub report: TrackReport,
    /// Per-satellite state, in the report's order.
    pub tracks: Vec<SatTrack>,
}

/// Runs acquisition and tracking on `rec` (1 to 4 antennas).
///
/// # Errors
/// Bad options, no satellite found, read or decode errors, attitude set-up errors (which need
/// three antennas).
pub fn track(rec: &Recording, opts: &TrackOptions) -> Result<TrackRun> {
    match rec.antenna_count() {
        1 => track_n::<1>(rec, opts),
        2 => track_n::<2>(rec, opts),
        3 => track_n::<3>(rec, opts),
        4 => track_n::<4>(rec, opts),
        n => anyhow::bail!("{n} antennas: the tracker takes 1-4"),
    }
}

fn track_n<const A: usize>(rec: &Recording, opts: &TrackOptions) -> Result<TrackRun> {
    let fs = rec.sample_rate_hz;
    ensure!(
        opts.block >= 1024,
        "block of {} samples is too small",
        opts.block
    );
    if opts.attitude.is_some() {
        ensure!(
            A == 3,
            "the attitude needs three antennas (the recording has {A})"
        );
    }
    if let Some(s) = opts.seconds {
        ensure!(s.is_finite() && s > 0.0, "--seconds {s} must be positive");
    }
    let (acq_report, found) = acquire(rec, &opts.acquire)?;
    ensure!(
        !found.is_empty(),
        "no satellite found in the first {} ms (threshold {:.2}): check --fs, --if, --format and the Doppler range",
        acq_report.noncoherent_ms,
        acq_report.threshold
    );
    let config = ChannelConfig::leo(fs, rec.intermediate_frequency_hz);
    let solver = match &opts.attitude {
        Some(setup) => Some(AttitudeSolver::new(setup, fs, &config)?),
        None => None,
    };
    let mut channels: Vec<(Channel<A>, SatTrack)> = Vec::new();
    for r in &found {
        let mut ch = Channel::<A>::new(r.prn, &config)?;
        ch.start(r)?;
        let phases = solver.as_ref().map(|s| s.accumulator(r.prn.number()));
        channels.push((ch, SatTrack::new(*r, fs, phases)));
    }
    let total = match opts.seconds {
        Some(s) => ((s * fs).round() as u64).min(rec.instants),
        None => rec.instants,
    };
    let mut reader = rec.reader()?;
    let mut wall = WallTimes::default();
    let mut collection: Option<Collection> = None;
    let acq_config = opts.acquire.config(rec, acq_report.noncoherent_ms)?;
    let mut attitude = solver.map(|s| (s, Vec::new()));
    let mut next_window = 0usize;
    let bar = crate::report::progress(total.div_ceil(opts.block as u64), "tracking");
    loop {
        let left = total.saturating_sub(reader.position());
        if left == 0 {
            break;
        }
        let t0 = Instant::now();
        let Some(block) = reader.read((opts.block as u64).min(left) as usize)? else {
            break;
        };
        wall.read_s += t0.elapsed().as_secs_f64();
        let t0 = Instant::now();
        let sb: SampleBlock<'_, A> = block.samples()?;
        track_block(&mut channels, &sb, |s| s.active, |s, e| s.epoch(e))?;
        wall.tracking_s += t0.elapsed().as_secs_f64();
        let now = (block.first + block.len() as u64) as f64 / fs;
        bar.inc(1);
        if opts.reacquire {
            let t0 = Instant::now();
            reacquire(
                &mut channels,
                &block,
                &mut collection,
                &acq_config,
                now,
                &opts.acquire,
            )?;
            wall.reacquisition_s += t0.elapsed().as_secs_f64();
        }
        if let Some((solver, out)) = attitude.as_mut() {
            let t0 = Instant::now();
            // Windows every active satellite has completed.
            let done = channels
                .iter()
                .filter(|(_, s)| s.active)
                .map(|(_, s)| s.last_t)
                .fold(now, f64::min);
            while solver.window_end(next_window) <= done {
                out.push(solver.solve_window(next_window, channels.iter_mut().map(|(_, s)| s))?);
                next_window += 1;
            }
            wall.attitude_s += t0.elapsed().as_secs_f64();
        }
    }
    bar.finish_and_clear();
    let end_t = total as f64 / fs;
    let attitude = match attitude {
        Some((solver, mut out)) => {
            // The windows the stream completed (the last epoch ends within a sample or so of
            // the stream's end).
            while solver.window_end(next_window) <= end_t + 1e-3 {
                out.push(solver.solve_window(next_window, channels.iter_mut().map(|(_, s)| s))?);
                next_window += 1;
            }
            Some(solver.report(out))
        }
        None => None,
    };
    let mut tracks: Vec<SatTrack> = channels.into_iter().map(|(_, s)| s).collect();
    let mut satellites: Vec<SatelliteReport> = tracks.iter_mut().map(|s| s.report(end_t)).collect();
    let measured: Vec<f64> = satellites.iter().map(|s| s.cn0_dbhz_mean).collect();
    for (s, c) in satellites.iter_mut().zip(mai_corrected_cn0(&measured)) {
        s.cn0_dbhz_thermal = c;
    }
    Ok(TrackRun {
        report: TrackReport {
            acquisition: acq_report,
            tracked_s: end_t,
            satellites,
            attitude,
            wall,
            files_written: Vec::new(),
        },
        tracks,
    })
}

/// Marks satellites that lost lock, collects reference-antenna samples for them, searches
/// when enough are in, and hands the found ones over again.
fn reacquire<const A: usize>(
    channels: &mut [(Channel<A>, SatTrack)],
    block: &Block<'_>,
    collection: &mut Option<Collection>,
    config: &AcquisitionConfig,
    now: f64,
    opts: &AcquireOptions,
) -> Result<()> {
    let needed = config.samples_needed();
    for (_, s) in channels.iter_mut() {
        if s.needs_reacquisition(now) {
            s.active = false;
            s.retry_at = now;
            if let Some(run) = s.run_start.take() {
                s.longest = s.longest.max(s.last_t - run);
                s.losses += 1;
            }
        }
    }
    let waiting = channels.iter().any(|(_, s)| !s.active && s.retry_at <= now);
    if collection.is_none() && waiting {
        *collection = Some(Collection {
            first: block.first + block.len() as u64,
            i: Vec::with_capacity(needed),
            q: Vec::with_capacity(needed),
        });
        return Ok(());
    }
    let Some(c) = collection.as_mut() else {
        return Ok(());
    };
    let take = needed.saturating_sub(c.i.len()).min(block.len());
    c.i.extend_from_slice(&block.i[0][..take]);
    if block.complex {
        c.q.extend_from_slice(&block.q[0][..take]);
    }
    if c.i.len() < needed {
        return Ok(());
    }
    let prns: Vec<u8> = channels
        .iter()
        .filter(|(_, s)| !s.active && s.retry_at <= now)
        .map(|(_, s)| s.prn)
        .collect();
    let q = block.complex.then_some(&c.q[..]);
    let results = search_prns(&c.i, q, c.first, &prns, config)?;

    let (found, _) = split_cross_correlations(&results, opts);
    for r in results {
        let Some((ch, s)) = channels.iter_mut().find(|(_, s)| s.prn == r.prn.number()) else {
            continue;
        };
        if found.iter().any(|f| f.prn == r.prn) {
            ch.start(&r)?;
            s.active = true;
            s.started_t = now;
            s.reacquisitions += 1;
        } else {
            s.retry_at = now + RETRY_EVERY_S;
        }
    }
    *collection = None;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::mai_corrected_cn0;

    /// Two satellites at 50 dB-Hz: each sees I0/N0 = 10⁵ · 2/(3 · 1.023·10⁶) = 0.0652, so the
    /// measured value is 50 − 10 log10(1.0652) = 49.726 dB-Hz; the correction returns 50.
    /// A lone satellite is unchanged; NaN stays NaN and is not counted.
    #[test]
    fn mai_correction_inverts_the_model() {
        let measured = 50.0 - 10.0 * (1.0 + 1e5 * 2.0 / 3.0 / 1.023e6f64).log10();
        let c = mai_corrected_cn0(&[measured, measured, f64::NAN]);
        assert!(
            (c[0] - 50.0).abs() < 1e-3 && (c[1] - 50.0).abs() < 1e-3,
            "{c:?}"
        );
        assert!(c[2].is_nan());
        assert_eq!(mai_corrected_cn0(&[43.0]), vec![43.0]);
    }
}
