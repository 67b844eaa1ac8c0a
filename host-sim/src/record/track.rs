//! `host-sim track`: acquisition, then the core's tracking channels over the whole recording
//! (or `--seconds`), streamed block by block, with re-acquisition of lost satellites.
//!
//! Memory is bounded by the block size plus per-satellite summaries: the epochs themselves
//! are folded into 100 ms rows as they arrive ([`super::satellite`]) (a 1 GB recording at 2.6 Msps, 190 s, keeps
//! about 2000 rows per satellite), so files of any size can be tracked.
//!
//! The channels use [`ChannelConfig::leo`]: the refinement stage also estimates the Doppler
//! rate (harmless for a ground receiver, needed for LEO dynamics; see the README).
//!
//! Re-acquisition: a satellite without code and phase lock for [`REACQUIRE_AFTER_S`] (after
//! its pull-in allowance; phase lock too, because a 100 ms code-lock window passes the C/N0
//! threshold on noise alone a few times in a thousand) is searched again on the next
//! milliseconds of the stream (same settings as the first acquisition) and, when found, handed
//! over again; otherwise searched again [`RETRY_EVERY_S`] later. The re-acquisition tests its
//! detections against the cross-correlation of the satellites still tracked as well.
//!
//! Cross-correlation: after each block every channel is checked against the others
//! ([`gnss_attitude::tracking::Channel::check_cross_correlation`]); a channel that sits on a
//! stronger satellite's cross-correlation releases itself and is searched again later (the
//! re-acquisition then rejects it while the stronger satellite is tracked).

use std::time::Instant;

use anyhow::{ensure, Result};
use gnss_attitude::signal::SampleBlock;
use gnss_attitude::tracking::xcorr::SignalProbe;
use gnss_attitude::tracking::{AcquisitionConfig, Channel, ChannelConfig, KnownSignal};
use serde::Serialize;

use super::acquire::{acquire_with_searches, detect, AcquireOptions, AcquireReport};
use super::attitude::{AttitudeReport, AttitudeSetup, AttitudeSolver};
use super::navigation::{NavChannel, NavigationReport, Navigator};
use super::reader::{Block, Recording};
use super::rinex::NavFile;
pub use super::satellite::{mai_corrected_cn0, Row, SatTrack, SatelliteReport};
use crate::chain::track_block;

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
    /// PRNs handed over at their search peak even when not detected (a test of the lock
    /// detectors on phantoms; empty for normal use).
    pub force_hand_over: Vec<u8>,
    /// Decode the navigation message and fix the position ([`super::navigation`]).
    pub navigation: bool,
    /// A RINEX navigation file (`--nav`) as a further ephemeris source.
    pub nav_file: Option<NavFile>,
}

impl Default for TrackOptions {
    fn default() -> Self {
        Self {
            acquire: AcquireOptions::default(),
            seconds: None,
            block: 1 << 16,
            reacquire: true,
            attitude: None,
            force_hand_over: Vec::new(),
            navigation: true,
            nav_file: None,
        }
    }
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
    /// Attitude (three-antenna recordings with `--baselines`; lines of sight from `--sky`
    /// or the navigation fixes).
    pub attitude: Option<AttitudeReport>,
    /// Navigation: decoded ephemerides, time, position fixes (see [`NavigationReport`]).
    pub navigation: Option<NavigationReport>,
    /// Wall times.
    pub wall: WallTimes,
    /// Files written by `--out`.
    pub files_written: Vec<String>,
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
    /// The navigation (fixes, decoded ephemerides) for the files.
    pub navigator: Option<Navigator>,
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
    let (acq_report, mut found, searches) = acquire_with_searches(rec, &opts.acquire)?;
    for s in &searches {
        let forced = opts.force_hand_over.contains(&s.prn.number());
        if forced && !found.iter().any(|f| f.prn == s.prn) {
            found.push(*s);
        }
    }
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
        let mut track = SatTrack::new(*r, fs, phases);
        if opts.navigation {
            track.nav = Some(NavChannel::new(r.prn.number(), fs));
        }
        channels.push((ch, track));
    }
    let total = match opts.seconds {
        Some(s) => {
            let asked = (s * fs).round();
            if asked > rec.instants as f64 {
                eprintln!(
                    "track: the recording holds {:.3} s, --seconds asks {s}: tracking the whole recording",
                    rec.seconds()
                );
            }
            (asked as u64).min(rec.instants)
        }
        None => rec.instants,
    };
    let mut reader = rec.reader()?;
    let mut wall = WallTimes::default();
    let mut collection: Option<Collection> = None;
    let acq_config = opts.acquire.config(rec, acq_report.noncoherent_ms)?;
    let mut attitude = solver.map(|s| (s, Vec::new()));
    let mut navigator = opts
        .navigation
        .then(|| Navigator::new(fs, opts.nav_file.clone()));
    let mut next_window = 0usize;
    let mut progress = Progress::new(total, opts.block, fs);
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
        let now = (block.first + block.len() as u64) as f64 / fs;
        release_cross_correlations(&mut channels, now);
        wall.tracking_s += t0.elapsed().as_secs_f64();
        progress.advance(now, channels.iter().filter(|(_, s)| s.active).count());
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
        if let Some(nav) = navigator.as_mut() {
            let end = block.first + block.len() as u64;
            nav.after_block(channels.iter_mut().filter_map(|(_, s)| s.nav.as_mut()), end)?;
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
                navigation_los(solver, navigator.as_ref(), &mut channels, next_window);
                out.push(solver.solve_window(next_window, channels.iter_mut().map(|(_, s)| s))?);
                next_window += 1;
            }
            wall.attitude_s += t0.elapsed().as_secs_f64();
        }
    }
    progress.finish();
    let end_t = total as f64 / fs;
    let attitude = match attitude {
        Some((solver, mut out)) => {
            // The windows the stream completed (the last epoch ends within a sample or so of
            // the stream's end).
            while solver.window_end(next_window) <= end_t + 1e-3 {
                navigation_los(&solver, navigator.as_ref(), &mut channels, next_window);
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
            navigation: navigator.as_ref().map(Navigator::report),
            wall,
            files_written: Vec::new(),
        },
        tracks,
        navigator,
    })
}

/// Without a sky file: the lines of sight of window `k` (at its middle) from the navigation.
fn navigation_los<const A: usize>(
    solver: &AttitudeSolver,
    navigator: Option<&Navigator>,
    channels: &mut [(Channel<A>, SatTrack)],
    k: usize,
) {
    let Some(nav) = navigator.filter(|_| solver.uses_navigation()) else {
        return;
    };
    let mid = solver.window_end(k) - 0.5 * solver.window_s();
    for (_, s) in channels.iter_mut() {
        let los = nav.los_ned(s.prn, mid);
        if let Some(p) = s.phases.as_mut() {
            p.set_los(los);
        }
    }
}

/// Recordings longer than this show their progress on stderr, s.
pub const PROGRESS_AFTER_S: f64 = 5.0;

/// Lines of plain progress (stderr not a terminal) over a recording.
const PROGRESS_LINES: u32 = 10;

/// The progress of `track` on stderr for recordings longer than [`PROGRESS_AFTER_S`]: a bar
/// on a terminal, else a line every tenth of the recording (logs, CI). Stdout is untouched.
struct Progress {
    bar: Option<indicatif::ProgressBar>,
    total_s: f64,
    next_line: u32,
}

impl Progress {
    fn new(total: u64, block: usize, fs: f64) -> Self {
        let total_s = total as f64 / fs;
        let bar = (total_s > PROGRESS_AFTER_S)
            .then(|| crate::report::progress(total.div_ceil(block as u64), "tracking"));
        Self {
            bar,
            total_s,
            next_line: 1,
        }
    }

    /// After a block ending at `now` (s), with `active` satellites tracked.
    fn advance(&mut self, now: f64, active: usize) {
        let Some(bar) = &self.bar else {
            return;
        };
        bar.inc(1);
        if !bar.is_hidden() {
            return;
        }
        let due = f64::from(self.next_line) / f64::from(PROGRESS_LINES) * self.total_s;
        if now >= due && self.next_line <= PROGRESS_LINES {
            eprintln!(
                "track: {now:.1} of {:.1} s ({:.0} %), {active} satellite(s) tracked",
                self.total_s,
                100.0 * now / self.total_s
            );
            self.next_line += 1;
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// Runs every active channel's cross-correlation check against the others (their probes on
/// the same samples: all channels stand at the block's end) and stops the channels that
/// released themselves; they are searched again after [`RETRY_EVERY_S`].
fn release_cross_correlations<const A: usize>(channels: &mut [(Channel<A>, SatTrack)], now: f64) {
    let probes: Vec<SignalProbe> = channels
        .iter()
        .filter(|(_, s)| s.active)
        .filter_map(|(ch, _)| ch.probe())
        .collect();
    for (ch, s) in channels.iter_mut().filter(|(_, s)| s.active) {
        s.note_cn0(ch.cn0_estimate());
        if ch.check_cross_correlation(&probes).is_some() {
            s.release_as_cross_correlation(now, now + RETRY_EVERY_S);
        }
    }
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
    // The satellites still tracked, as known signals on the collected samples.
    let tracked: Vec<KnownSignal> = channels
        .iter()
        .filter(|(_, s)| s.active)
        .filter_map(|(ch, _)| ch.known_signal_at(c.first))
        .collect();
    let found = detect(&c.i, q, c.first, &prns, config, opts, &tracked)?;
    for r in found.reports.iter().map(|r| r.result) {
        let Some((ch, s)) = channels.iter_mut().find(|(_, s)| s.prn == r.prn.number()) else {
            continue;
        };
        if found.accepted.iter().any(|f| f.prn == r.prn) {
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
