//! `host-sim acquisition-stats`: the acquisition's detection probability and false alarms
//! measured on every background the receiver may meet, through the same path as
//! `host-sim acquire` (a synthesized recording written to a file, opened, searched for all
//! 32 PRNs), and the phantom lock time of `host-sim track` on a noise-free recording. Writes
//! the figures as a markdown table (`docs/ACQUISITION.md`) with the date and commit.
//!
//! Backgrounds:
//! * thermal noise with 8 satellites at 40–45 dB-Hz (the detection probability and the
//!   false-alarm rate per PRN search, over `--searches` recordings with fresh noise and sky);
//! * noise-free recordings (signals only, quantized: what signal simulators write), static and
//!   LEO, 8–12 satellites at equal and unequal power, CS8 and CS16;
//! * strong signals in thermal noise (55 and 60 dB-Hz);
//! * degenerate inputs: every sample saturated (+127), all zero, a constant DC offset, a DC
//!   offset on a noisy recording, a continuous-wave tone alone and on a noisy recording.
//!
//! A present satellite counts as found when it is reported with its Doppler within ±250 Hz; a
//! PRN reported that is not in the recording is a false detection.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use serde::Serialize;

use super::acquire::{acquire, AcquireOptions, AcquireReport};
use super::synthesize::{
    open_synthesized, write_recording, Dynamics, Overlay, RecordingTruth, SynthSpec,
};
use super::track::{track, TrackOptions};
use super::FileFormat;

/// Doppler error within which a present satellite counts as found, Hz.
pub const FOUND_DOPPLER_HZ: f64 = 250.0;

/// What to measure.
#[derive(Clone, Debug)]
pub struct StatsOptions {
    /// Recordings of the thermal-noise background (detection probability, false alarms).
    pub thermal_searches: usize,
    /// Recordings of each other background with random content (sky, noise).
    pub seeds: usize,
    /// Seconds of the noise-free recording `track` runs on (phantom lock time).
    pub track_seconds: f64,
    /// Directory for the recordings (removed afterwards).
    pub work_dir: PathBuf,
}

/// The figures of one background.
#[derive(Clone, Debug, Serialize)]
pub struct CaseFigures {
    /// Background.
    pub name: String,
    /// Recordings searched (each for all 32 PRNs).
    pub searches: usize,
    /// PRN searches for PRNs not in the recording.
    pub absent_searches: usize,
    /// Satellites in the recordings.
    pub present: usize,
    /// Present satellites found with the Doppler within ±250 Hz.
    pub found: usize,
    /// Largest Doppler error of a found satellite, Hz.
    pub doppler_err_hz_max: f64,
    /// PRNs reported that are not in the recording.
    pub false_detections: usize,
    /// Peaks rejected as cross-correlations.
    pub rejected_cross_correlations: usize,
    /// Detection probability (`found / present`; NaN without satellites).
    pub detection_probability: f64,
    /// False detections per absent PRN search.
    pub false_alarm_rate: f64,
    /// Wall time, s.
    pub wall_s: f64,
}

/// Phantom lock of `track` on a noise-free recording.
#[derive(Clone, Debug, Serialize)]
pub struct PhantomLock {
    /// The recording.
    pub name: String,
    /// Seconds tracked.
    pub tracked_s: f64,
    /// Satellites in the recording.
    pub present: usize,
    /// Of them held locked to the end.
    pub present_held: usize,
    /// Absent PRNs `track` handed over (its detections).
    pub phantoms_tracked: usize,
    /// Total lock time of absent PRNs, s.
    pub phantom_lock_s: f64,
    /// Longest lock of an absent PRN, s.
    pub phantom_longest_s: f64,
    /// Absent PRNs handed over on purpose at their search peaks (the lock detectors' test).
    pub forced: usize,
    /// Total lock time of those, s.
    pub forced_lock_s: f64,
    /// Of those, released as cross-correlations.
    pub forced_released: usize,
    /// Latest first release of those after the start, s.
    pub forced_release_s_max: f64,
    /// Every present satellite reports a finite C/N0.
    pub cn0_finite: bool,
}

/// Everything measured.
#[derive(Clone, Debug, Serialize)]
pub struct StatsReport {
    /// Per background.
    pub cases: Vec<CaseFigures>,
    /// Phantom lock.
    pub phantom_lock: PhantomLock,
    /// Acquisition settings.
    pub settings: String,
}

/// One background: the recording's synthesis, the search span, how many recordings.
struct Case {
    name: String,
    spec: SynthSpec,
    doppler_max_hz: f64,
    recordings: usize,
}

fn base(format: &str, satellites: usize, noise: bool) -> SynthSpec {
    SynthSpec {
        format: FileFormat::parse(format).unwrap_or_else(|_| unreachable!("a layout")),
        seconds: 0.05,
        satellites,
        noise,
        ..SynthSpec::default()
    }
}

fn equal(spec: SynthSpec, cn0: f64) -> SynthSpec {
    SynthSpec {
        cn0_min_dbhz: cn0,
        cn0_max_dbhz: cn0,
        ..spec
    }
}

fn spread(spec: SynthSpec, lo: f64, hi: f64) -> SynthSpec {
    SynthSpec {
        cn0_min_dbhz: lo,
        cn0_max_dbhz: hi,
        ..spec
    }
}

fn with(spec: SynthSpec, overlay: Overlay) -> SynthSpec {
    SynthSpec {
        overlays: vec![overlay],
        ..spec
    }
}

/// A tone 3.7 kHz from the band centre, `jn_db` over the noise level.
fn tone(jn_db: f64) -> Overlay {
    Overlay::Cw {
        offset_hz: 3_700.0,
        jn_db,
    }
}

fn leo(spec: SynthSpec) -> SynthSpec {
    SynthSpec {
        dynamics: Dynamics::Leo,
        ..spec
    }
}

/// The backgrounds (see the module documentation).
fn cases(opts: &StatsOptions) -> Vec<Case> {
    let n = opts.seeds;
    let case = |name: &str, spec: SynthSpec, recordings: usize| Case {
        name: name.into(),
        doppler_max_hz: if spec.dynamics == Dynamics::Leo {
            50_000.0
        } else {
            10_000.0
        },
        spec,
        recordings,
    };
    let saturated = Overlay::Constant { i: 1e9, q: 1e9 };
    let silent = Overlay::Constant { i: 0.0, q: 0.0 };
    vec![
        case(
            "thermal noise, 8 satellites at 40-45 dB-Hz, CS8",
            spread(base("cs8", 8, true), 40.0, 45.0),
            opts.thermal_searches,
        ),
        case(
            "noise-free static, 11 satellites at 45 dB-Hz, CS8",
            equal(base("cs8", 11, false), 45.0),
            n,
        ),
        case(
            "noise-free static, 12 satellites at 40-55 dB-Hz, CS8",
            spread(base("cs8", 12, false), 40.0, 55.0),
            n,
        ),
        case(
            "noise-free static, 8 satellites at 50 dB-Hz, CS16",
            equal(base("cs16", 8, false), 50.0),
            n,
        ),
        case(
            "noise-free static, 12 satellites at 40-50 dB-Hz, CS16",
            spread(base("cs16", 12, false), 40.0, 50.0),
            n,
        ),
        case(
            "noise-free LEO, 10 satellites at 45 dB-Hz, CS8",
            leo(equal(base("cs8", 10, false), 45.0)),
            n.div_ceil(2),
        ),
        case(
            "noise-free LEO, 12 satellites at 40-55 dB-Hz, CS16",
            leo(spread(base("cs16", 12, false), 40.0, 55.0)),
            n.div_ceil(2),
        ),
        case(
            "thermal noise, 8 satellites at 55 dB-Hz, CS8",
            equal(base("cs8", 8, true), 55.0),
            n,
        ),
        case(
            "thermal noise, 8 satellites at 60 dB-Hz, CS8",
            equal(base("cs8", 8, true), 60.0),
            n,
        ),
        case(
            "thermal noise, 12 satellites at 45-60 dB-Hz, CS8",
            spread(base("cs8", 12, true), 45.0, 60.0),
            n,
        ),
        case(
            "every sample saturated (+127), CS8",
            with(base("cs8", 1, false), saturated),
            1,
        ),
        case(
            "all samples zero, CS8",
            with(base("cs8", 1, false), silent),
            1,
        ),
        case(
            "constant DC offset (+20, -13 LSB), CS8",
            with(
                base("cs8", 1, false),
                Overlay::Constant {
                    i: 1.25,
                    q: -0.8125,
                },
            ),
            1,
        ),
        case(
            "DC offset (+1.25, -0.8 sigma) on thermal noise, 8 satellites at 40-50 dB-Hz",
            with(
                spread(base("cs8", 8, true), 40.0, 50.0),
                Overlay::Dc { i: 1.25, q: -0.8 },
            ),
            n,
        ),
        case(
            "continuous-wave tone alone (+3.7 kHz, 20 dB over the noise level, clipped by CS8)",
            SynthSpec {
                overlays: vec![silent, tone(20.0)],
                ..base("cs8", 1, false)
            },
            1,
        ),
        case(
            "continuous-wave tone alone (+3.7 kHz, 30 dB over the noise level, hard-limited)",
            SynthSpec {
                overlays: vec![silent, tone(30.0)],
                ..base("cs8", 1, false)
            },
            1,
        ),
        case(
            "continuous-wave tone (+3.7 kHz, J/N 10 dB) on thermal noise, 8 satellites at 40-50 dB-Hz",
            with(spread(base("cs8", 8, true), 40.0, 50.0), tone(10.0)),
            n,
        ),
    ]
}

fn measure_case(case: &Case, dir: &Path) -> Result<CaseFigures> {
    let started = Instant::now();
    let mut f = CaseFigures {
        name: case.name.clone(),
        searches: 0,
        absent_searches: 0,
        present: 0,
        found: 0,
        doppler_err_hz_max: 0.0,
        false_detections: 0,
        rejected_cross_correlations: 0,
        detection_probability: f64::NAN,
        false_alarm_rate: f64::NAN,
        wall_s: 0.0,
    };
    for k in 0..case.recordings {
        let spec = SynthSpec {
            seed: 1000 + k as u64,
            ..case.spec.clone()
        };
        let (truth, _) = write_recording(dir, "stats", &spec)?;
        let rec = open_synthesized(dir, &truth)?;
        let opts = AcquireOptions {
            doppler_max_hz: case.doppler_max_hz,
            ..AcquireOptions::default()
        };
        let (report, _) = acquire(&rec, &opts)?;
        f.searches += 1;
        f.present += truth.satellites.len();
        f.absent_searches += 32 - truth.satellites.len();
        f.rejected_cross_correlations += report.rejected_cross_correlations.len();
        for d in &report.detections {
            match truth.satellites.iter().find(|s| s.prn == d.prn) {
                Some(s) => {
                    let err = (d.doppler_hz - s.doppler_hz).abs();
                    if err <= FOUND_DOPPLER_HZ {
                        f.found += 1;
                        f.doppler_err_hz_max = f.doppler_err_hz_max.max(err);
                    }
                }
                None => f.false_detections += 1,
            }
        }
        report_misses(&case.name, spec.seed, &truth, &report);
    }
    if f.present > 0 {
        f.detection_probability = f.found as f64 / f.present as f64;
    }
    f.false_alarm_rate = f.false_detections as f64 / f.absent_searches.max(1) as f64;
    f.wall_s = started.elapsed().as_secs_f64();
    Ok(f)
}

/// Prints (stderr) every present satellite not found and every absent PRN reported, with
/// what the search and the cross-correlation test said about it.
fn report_misses(case: &str, seed: u64, truth: &RecordingTruth, report: &AcquireReport) {
    for s in &truth.satellites {
        let found = report
            .detections
            .iter()
            .any(|d| d.prn == s.prn && (d.doppler_hz - s.doppler_hz).abs() <= FOUND_DOPPLER_HZ);
        if found {
            continue;
        }
        let search = report.searches.iter().find(|x| x.prn == s.prn);
        let detection = report.detections.iter().find(|d| d.prn == s.prn);
        let rejected = report
            .rejected_cross_correlations
            .iter()
            .find(|x| x.prn == s.prn);
        eprintln!(
            "acquisition-stats: {case}, seed {seed}: PRN {} ({:.1} dB-Hz, {:.0} Hz, {:.2} chips) missed: search {search:?}, detection {detection:?}, rejected {rejected:?}",
            s.prn, s.cn0_dbhz, s.doppler_hz, s.code_phase_chips
        );
    }
    for d in &report.detections {
        if !truth.satellites.iter().any(|s| s.prn == d.prn) {
            eprintln!(
                "acquisition-stats: {case}, seed {seed}: absent PRN {} reported: {d:?}",
                d.prn
            );
        }
    }
}

/// `track` on a noise-free static recording of 11 satellites at 45 dB-Hz (the kind of file
/// the simulator wrote), once as it is and once with the five absent PRNs of highest
/// search metric handed over on purpose.
fn phantom_lock(opts: &StatsOptions) -> Result<PhantomLock> {
    let spec = SynthSpec {
        seconds: opts.track_seconds,
        seed: 11,
        ..equal(base("cs8", 11, false), 45.0)
    };
    let (truth, _) = write_recording(&opts.work_dir, "phantom", &spec)?;
    let rec = open_synthesized(&opts.work_dir, &truth)?;
    let present: Vec<u8> = truth.satellites.iter().map(|s| s.prn).collect();
    let run = track(&rec, &TrackOptions::default())?;
    let absent = |prn: u8| !present.contains(&prn);
    let phantoms: Vec<_> = run
        .report
        .satellites
        .iter()
        .filter(|s| absent(s.prn))
        .collect();
    // The absent PRNs of highest metric, handed over whether detected or not.
    let (_, _, searches) = super::acquire::acquire_with_searches(&rec, &AcquireOptions::default())?;
    let mut candidates: Vec<_> = searches.iter().filter(|s| absent(s.prn.number())).collect();
    candidates.sort_by(|a, b| b.metric.total_cmp(&a.metric));
    let forced: Vec<u8> = candidates.iter().take(5).map(|s| s.prn.number()).collect();
    let forced_run = track(
        &rec,
        &TrackOptions {
            force_hand_over: forced.clone(),
            reacquire: false,
            ..TrackOptions::default()
        },
    )?;
    let forced_sats: Vec<_> = forced_run
        .report
        .satellites
        .iter()
        .filter(|s| forced.contains(&s.prn))
        .collect();
    let forced_lock_s = forced_sats
        .iter()
        .map(|s| s.lock_time_s)
        .fold(0.0, |a, b| a + b);
    let releases: Vec<f64> = forced_sats
        .iter()
        .filter_map(|s| s.first_cross_correlation_release_s)
        .collect();
    let real = run.report.satellites.iter().filter(|s| !absent(s.prn));
    Ok(PhantomLock {
        name: format!(
            "noise-free static, 11 satellites at 45 dB-Hz, CS8, {} s",
            opts.track_seconds
        ),
        tracked_s: run.report.tracked_s,
        present: present.len(),
        present_held: real.clone().filter(|s| s.held_to_end).count(),
        phantoms_tracked: phantoms.len(),
        phantom_lock_s: phantoms
            .iter()
            .map(|s| s.lock_time_s)
            .fold(0.0, |a, b| a + b),
        phantom_longest_s: phantoms
            .iter()
            .map(|s| s.longest_lock_s)
            .fold(0.0, f64::max),
        forced: forced.len(),
        forced_lock_s,
        forced_released: releases.len(),
        forced_release_s_max: releases.iter().copied().fold(0.0, f64::max),
        cn0_finite: real.clone().all(|s| s.cn0_dbhz_mean.is_finite()),
    })
}

/// Measures the thermal-noise background alone (detection probability, false alarms).
///
/// # Errors
/// Synthesis, I/O or acquisition errors.
pub fn measure_thermal(opts: &StatsOptions) -> Result<CaseFigures> {
    std::fs::create_dir_all(&opts.work_dir)?;
    let case = cases(opts).into_iter().next();
    let case = case.ok_or_else(|| anyhow::anyhow!("no thermal case"))?;
    measure_case(&case, &opts.work_dir)
}

/// Measures every background and the phantom lock.
///
/// # Errors
/// Synthesis, I/O, acquisition or tracking errors.
pub fn measure(opts: &StatsOptions) -> Result<StatsReport> {
    std::fs::create_dir_all(&opts.work_dir)?;
    let mut figures = Vec::new();
    for case in cases(opts) {
        let f = measure_case(&case, &opts.work_dir)?;
        eprintln!(
            "acquisition-stats: {}: {} of {} found, {} false in {} absent-PRN searches ({:.1} s)",
            f.name, f.found, f.present, f.false_detections, f.absent_searches, f.wall_s
        );
        figures.push(f);
    }
    let phantom_lock = phantom_lock(opts)?;
    std::fs::remove_dir_all(&opts.work_dir).ok();
    let a = AcquireOptions::default();
    Ok(StatsReport {
        cases: figures,
        phantom_lock,
        settings: format!(
            "host-sim acquire defaults: {} ms non-coherent, +-{:.0} kHz in {:.0} Hz bins (+-50 kHz for LEO), P_fa {:e} per PRN search, all 32 PRNs, CS8/CS16 at 2.6 Msps",
            a.ms,
            a.doppler_max_hz / 1e3,
            a.doppler_step_hz,
            a.false_alarm_probability
        ),
    })
}

/// The short commit id of the working tree (`unknown` outside git), with `+dirty` when it has
/// changes.
pub fn commit() -> String {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let id = git(&["rev-parse", "--short", "HEAD"]).unwrap_or_else(|| "unknown".into());
    let dirty =
        git(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
    if dirty {
        format!("{id}+dirty")
    } else {
        id
    }
}

/// Today's date (UTC), `YYYY-MM-DD`.
pub fn today() -> String {
    let days = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() / 86_400) as i64;
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

fn pct(x: f64) -> String {
    if x.is_nan() {
        "-".into()
    } else {
        format!("{:.2} %", 100.0 * x)
    }
}

/// The markdown document of a report.
pub fn markdown(r: &StatsReport, date: &str, commit: &str) -> String {
    let mut s = String::new();
    s.push_str("# Acquisition: detection and false alarms by background\n\n");
    s.push_str(&format!(
        "Generated by `host-sim acquisition-stats --markdown docs/ACQUISITION.md` on {date} at commit `{commit}` (do not edit by hand).\n\n"
    ));
    s.push_str(&format!("Settings: {}.\n\n", r.settings));
    s.push_str("Each recording is synthesized, written, opened and searched for all 32 PRNs as `host-sim acquire` does. *Found*: reported with the Doppler within ±250 Hz. *False*: a PRN reported that is not in the recording. *Rate*: false detections per search of an absent PRN.\n\n");
    s.push_str("| background | recordings | found / present | Pd | Doppler err. max (Hz) | false / absent-PRN searches | false-alarm rate | cross-corr. rejected |\n");
    s.push_str("|---|---:|---:|---:|---:|---:|---:|---:|\n");
    for c in &r.cases {
        s.push_str(&format!(
            "| {} | {} | {} / {} | {} | {:.0} | {} / {} | {:.1e} | {} |\n",
            c.name,
            c.searches,
            c.found,
            c.present,
            pct(c.detection_probability),
            c.doppler_err_hz_max,
            c.false_detections,
            c.absent_searches,
            c.false_alarm_rate,
            c.rejected_cross_correlations
        ));
    }
    let p = &r.phantom_lock;
    s.push_str(&format!(
        "\n## Phantom lock in `host-sim track`\n\n{}: {} of {} satellites held to the end; {} absent PRNs tracked, {:.1} s of phantom lock in total (longest {:.1} s). With the {} absent PRNs of highest search metric handed over on purpose (no re-acquisition): {:.1} s of lock in total, {} released themselves as cross-correlations, the last after {:.3} s. Finite C/N0 for every present satellite: {}.\n",
        p.name,
        p.present_held,
        p.present,
        p.phantoms_tracked,
        p.phantom_lock_s,
        p.phantom_longest_s,
        p.forced,
        p.forced_lock_s,
        p.forced_released,
        p.forced_release_s_max,
        if p.cn0_finite { "yes" } else { "no" }
    ));
    s
}
