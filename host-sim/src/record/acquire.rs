//! `host-sim acquire`: the core's acquisition ([`gnss_attitude::tracking::Acquisition`]) over
//! the first milliseconds of a recording, every PRN searched in parallel.
//!
//! The detection test is the core's: a threshold from the search's own background (the
//! false-alarm probability holds on thermal noise, noise-free simulator output, strong
//! signals, saturated, DC and tone-jammed inputs), a verification dwell on the next
//! milliseconds, then the cross-correlation test of each verified detection, strongest first,
//! against the stronger ones accepted before it
//! ([`gnss_attitude::tracking::Acquisition::cross_check`]): a detection whose power is within
//! [`AcquireOptions::cross_correlation_margin_db`] of the cross-correlation the stronger
//! satellites put at its code lag and Doppler offset is reported as
//! `rejected_cross_correlations` instead of as a detection. Then the second look: each PRN
//! not accepted whose search's background held the stronger satellites' cross-correlation
//! (fewer effective milliseconds than summed) or whose detection was rejected is searched
//! again with the accepted satellites cancelled from the samples
//! ([`gnss_attitude::tracking::Acquisition::search_report_cancelling`]), and a detection
//! there that keeps its power with them cancelled is a satellite (`second_looks`).

use std::time::Instant;

use anyhow::{ensure, Context, Result};
use gnss_attitude::tracking::acquisition::{detection_threshold, MAX_DOPPLER_BINS};
use gnss_attitude::tracking::{AcquisitionConfig, KnownSignal, SearchResult, Verification};
use serde::Serialize;

use super::reader::Recording;
use crate::chain::{detect_prns, Detections, SecondLook};

/// Acquisition settings of the file commands.
#[derive(Clone, Debug)]
pub struct AcquireOptions {
    /// Doppler search half-range, Hz.
    pub doppler_max_hz: f64,
    /// Doppler bin spacing, Hz.
    pub doppler_step_hz: f64,
    /// Milliseconds summed non-coherently (from the file's start).
    pub ms: u16,
    /// PRNs searched.
    pub prns: Vec<u8>,
    /// False-alarm probability per PRN search (noise only).
    pub false_alarm_probability: f64,
    /// Antenna searched (0 = the reference antenna).
    pub antenna: usize,
    /// Margin of the cross-correlation test, dB: a detection at most this much above the
    /// predicted cross-correlation of stronger satellites is rejected (`None`: no test).
    pub cross_correlation_margin_db: Option<f64>,
}

impl Default for AcquireOptions {
    /// ±10 kHz in 500 Hz bins, 20 ms (and 20 more for the verification dwell), PRN 1–32,
    /// P_fa = 10⁻⁵, antenna 0, 3 dB cross-correlation margin (20 ms: at 10 ms a 40 dB-Hz
    /// satellite straddling a code and a Doppler bin sits near the threshold, see the README).
    fn default() -> Self {
        Self {
            doppler_max_hz: 10_000.0,
            doppler_step_hz: 500.0,
            ms: 20,
            prns: (1..=32).collect(),
            false_alarm_probability: 1e-5,
            antenna: 0,
            cross_correlation_margin_db: Some(3.0),
        }
    }
}

/// A detected satellite.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Detection {
    /// PRN.
    pub prn: u8,
    /// Doppler, Hz.
    pub doppler_hz: f64,
    /// Code phase at the file's first sample, chips in `[0, 1023)`.
    pub code_phase_chips: f64,
    /// Peak cell over the mean cell.
    pub metric: f64,
    /// The threshold of this PRN's search (its background's).
    pub threshold: f64,
}

/// A peak over the threshold explained as the cross-correlation of a stronger satellite.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Rejected {
    /// PRN searched.
    pub prn: u8,
    /// Doppler of the peak, Hz.
    pub doppler_hz: f64,
    /// Peak metric.
    pub metric: f64,
    /// The stronger satellite that contributes most.
    pub stronger_prn: u8,
    /// The peak's power over the predicted cross-correlation power, dB.
    pub over_predicted_db: f64,
}

/// A PRN searched again with the detected satellites cancelled from the samples (its first
/// search's background held their cross-correlation, or its detection was rejected as one).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SecondLookReport {
    /// PRN.
    pub prn: u8,
    /// Peak over the background mean, with the known satellites cancelled.
    pub metric: f64,
    /// Threshold on that background.
    pub threshold: f64,
    /// Milliseconds that background behaves as independent.
    pub effective_ms: u16,
    /// Detected and verified with them cancelled.
    pub verified: bool,
    /// The detection's power with them cancelled over its power without, dB (`null`: not
    /// detected).
    pub power_kept_db: Option<f64>,
    /// The threshold of the PRN's first search (the metric must pass it too).
    pub first_threshold: f64,
    /// Reported as a satellite (verified, over the first threshold, and it keeps its power).
    pub accepted: bool,
}

/// One PRN's search as the core reports it.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct PrnSearch {
    /// PRN.
    pub prn: u8,
    /// Peak over the background mean.
    pub metric: f64,
    /// Threshold on this background.
    pub threshold: f64,
    /// Milliseconds the background behaves as independent (the configured number on thermal
    /// noise).
    pub effective_ms: u16,
    /// The peak exceeded the threshold.
    pub candidate: bool,
    /// `not_tested`, `no_samples`, `passed` or `failed`.
    pub verification: &'static str,
    /// Verified (the core's `detected`).
    pub verified: bool,
}

/// What `acquire` reports (`--json` prints it as one object).
#[derive(Clone, Debug, Serialize)]
pub struct AcquireReport {
    /// The files.
    pub files: Vec<String>,
    /// Layout.
    pub format: String,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Intermediate frequency, Hz.
    pub intermediate_frequency_hz: f64,
    /// Antennas in the recording.
    pub antennas: usize,
    /// Duration of the recording, s.
    pub recording_s: f64,
    /// Antenna searched.
    pub antenna: usize,
    /// Milliseconds summed non-coherently.
    pub noncoherent_ms: u16,
    /// Doppler search half-range, Hz.
    pub doppler_max_hz: f64,
    /// Doppler bin spacing, Hz.
    pub doppler_step_hz: f64,
    /// False-alarm probability per PRN search.
    pub false_alarm_probability: f64,
    /// Detection threshold on the metric on thermal noise (each PRN's search has its own,
    /// higher on other backgrounds: `searches`).
    pub threshold: f64,
    /// PRNs searched.
    pub searched_prns: Vec<u8>,
    /// Detected satellites, by PRN.
    pub detections: Vec<Detection>,
    /// Peaks rejected as cross-correlations of stronger satellites.
    pub rejected_cross_correlations: Vec<Rejected>,
    /// Wall time of the search (reading and decoding excluded), s.
    pub search_s: f64,
    /// Every PRN's search, in the order searched.
    pub searches: Vec<PrnSearch>,
    /// The PRNs searched again with the detected satellites cancelled.
    pub second_looks: Vec<SecondLookReport>,
}

impl AcquireOptions {
    /// The core's configuration for `rec`, with `ms` milliseconds.
    ///
    /// # Errors
    /// A Doppler range or step the core's engine does not take.
    pub fn config(&self, rec: &Recording, ms: u16) -> Result<AcquisitionConfig> {
        let (max, step) = (self.doppler_max_hz, self.doppler_step_hz);
        ensure!(
            max.is_finite() && max >= 0.0,
            "--doppler-max {max} Hz must be ≥ 0"
        );
        ensure!(
            step.is_finite() && step >= 10.0,
            "--doppler-step {step} Hz must be ≥ 10 Hz"
        );
        let bins = 2 * (max / step).floor() as usize + 1;
        ensure!(
            bins <= MAX_DOPPLER_BINS,
            "--doppler-max {max} Hz in {step} Hz steps is {bins} bins; the engine takes at most {MAX_DOPPLER_BINS} (e.g. ±100 kHz in 500 Hz steps)"
        );
        ensure!(
            (1..=100).contains(&ms),
            "--ms {ms}: the acquisition sums 1-100 ms"
        );
        ensure!(
            self.false_alarm_probability > 0.0 && self.false_alarm_probability < 0.5,
            "false-alarm probability {} must be in (0, 0.5)",
            self.false_alarm_probability
        );
        Ok(AcquisitionConfig {
            sample_rate_hz: rec.sample_rate_hz,
            intermediate_frequency_hz: rec.intermediate_frequency_hz,
            doppler_max_hz: max as f32,
            doppler_step_hz: step as f32,
            noncoherent_ms: ms,
            false_alarm_probability: self.false_alarm_probability as f32,
        })
    }
}

/// Runs the acquisition on the first milliseconds of `rec`. Returns the report and the core's
/// search results of the accepted detections (for the tracking hand-over).
///
/// # Errors
/// Bad options, a recording shorter than one code period (plus one sample), I/O errors.
pub fn acquire(
    rec: &Recording,
    opts: &AcquireOptions,
) -> Result<(AcquireReport, Vec<SearchResult>)> {
    acquire_with_searches(rec, opts).map(|(report, accepted, _)| (report, accepted))
}

/// [`acquire`], also returning every PRN's search (in the order of [`AcquireOptions::prns`]).
///
/// # Errors
/// As [`acquire`].
pub fn acquire_with_searches(
    rec: &Recording,
    opts: &AcquireOptions,
) -> Result<(AcquireReport, Vec<SearchResult>, Vec<SearchResult>)> {
    ensure!(
        opts.antenna < rec.antenna_count(),
        "--antenna {} does not exist (the recording has {})",
        opts.antenna,
        rec.antenna_count()
    );
    let period = rec.sample_rate_hz * 1e-3;
    // Whole milliseconds the file holds with the one extra sample the search reads.
    let available = ((rec.instants.saturating_sub(1)) as f64 / period).floor() as u64;
    ensure!(
        available >= 1,
        "the recording ({} samples) is shorter than one code period plus one sample",
        rec.instants
    );
    // The search's milliseconds and as many again for the verification dwell.
    let ms = u64::from(opts.ms).min(available / 2).max(1) as u16;
    if ms < opts.ms {
        eprintln!(
            "acquire: the recording holds {available} ms, --ms asks {} (and as many again for the verification dwell): summing {ms} ms and verifying on the next {ms} ms",
            opts.ms
        );
    }
    let config = opts.config(rec, ms)?;
    // Shorter than the search and its dwell: searched, but nothing can be verified.
    let needed = config
        .samples_needed()
        .min(usize::try_from(rec.instants).unwrap_or(usize::MAX))
        .max(config.search_samples());
    if needed < config.samples_needed() {
        eprintln!("acquire: the recording is too short for the verification dwell: nothing can be detected");
    }
    let unit = rec.format.unit().0;
    let request = needed.div_ceil(unit) * unit;
    let mut reader = rec.reader()?;
    let block = reader
        .read(request)?
        .context("the recording holds no samples")?;
    ensure!(
        block.len() >= needed,
        "read {} samples, the search needs {needed}",
        block.len()
    );
    let i = &block.i[opts.antenna];
    let q = block.complex.then(|| &block.q[opts.antenna][..]);
    let started = Instant::now();
    let found = detect(i, q, 0, &opts.prns, &config, opts, &[])?;
    let search_s = started.elapsed().as_secs_f64();
    let threshold = f64::from(detection_threshold(
        ms,
        (2048 * config.doppler_bins()) as f64,
        opts.false_alarm_probability,
    ));
    let detections = found
        .accepted
        .iter()
        .map(|r| Detection {
            prn: r.prn.number(),
            doppler_hz: f64::from(r.doppler_hz),
            code_phase_chips: f64::from(r.code_phase_chips),
            metric: f64::from(r.metric),
            threshold: f64::from(r.threshold),
        })
        .collect();
    let report = AcquireReport {
        files: rec.paths.iter().map(|p| p.display().to_string()).collect(),
        format: rec.format.name(),
        sample_rate_hz: rec.sample_rate_hz,
        intermediate_frequency_hz: rec.intermediate_frequency_hz,
        antennas: rec.antenna_count(),
        recording_s: rec.seconds(),
        antenna: opts.antenna,
        noncoherent_ms: ms,
        doppler_max_hz: opts.doppler_max_hz,
        doppler_step_hz: opts.doppler_step_hz,
        false_alarm_probability: opts.false_alarm_probability,
        threshold,
        searched_prns: opts.prns.clone(),
        detections,
        rejected_cross_correlations: rejections(&found),
        search_s,
        searches: found.reports.iter().map(prn_search).collect(),
        second_looks: found.second_looks.iter().map(second_look).collect(),
    };
    let results = found.reports.iter().map(|r| r.result).collect();
    Ok((report, found.accepted, results))
}

/// The core's detection chain with this command's options: search, verification, and the
/// cross-correlation test against the stronger detections and the `tracked` signals.
///
/// # Errors
/// The core's refusal of the configuration or the samples.
pub fn detect(
    i: &[i8],
    q: Option<&[i8]>,
    first_sample: u64,
    prns: &[u8],
    config: &AcquisitionConfig,
    opts: &AcquireOptions,
    tracked: &[KnownSignal],
) -> Result<Detections> {
    let margin = opts
        .cross_correlation_margin_db
        .map(|db| 10f64.powf(db / 10.0) as f32);
    detect_prns(i, q, first_sample, prns, config, tracked, margin)
}

fn rejections(found: &Detections) -> Vec<Rejected> {
    found
        .rejected
        .iter()
        .map(|x| Rejected {
            prn: x.result.prn.number(),
            doppler_hz: f64::from(x.result.doppler_hz),
            metric: f64::from(x.result.metric),
            stronger_prn: x.check.source.map_or(0, |p| p.number()),
            over_predicted_db: 10.0
                * (f64::from(x.check.power) / f64::from(x.check.predicted_power)).log10(),
        })
        .collect()
}

fn second_look(l: &SecondLook) -> SecondLookReport {
    let r = &l.report;
    SecondLookReport {
        prn: r.result.prn.number(),
        metric: f64::from(r.result.metric),
        threshold: f64::from(r.result.threshold),
        effective_ms: r.effective_ms,
        verified: r.result.detected,
        power_kept_db: l
            .check
            .map(|c| 10.0 * (f64::from(c.cancelled_power) / f64::from(c.power)).log10()),
        first_threshold: f64::from(l.first_threshold),
        accepted: l.accepted(),
    }
}

fn prn_search(r: &gnss_attitude::tracking::SearchReport) -> PrnSearch {
    PrnSearch {
        prn: r.result.prn.number(),
        metric: f64::from(r.result.metric),
        threshold: f64::from(r.result.threshold),
        effective_ms: r.effective_ms,
        candidate: r.candidate,
        verification: match r.verification {
            Verification::NotTested => "not_tested",
            Verification::NoSamples => "no_samples",
            Verification::Passed => "passed",
            _ => "failed",
        },
        verified: r.result.detected,
    }
}

/// The human table of a report.
pub fn print_report(r: &AcquireReport) {
    println!(
        "acquisition: {} ({}, {:.4} Msps, IF {:.1} kHz, {} antenna(s), {:.3} s), antenna {}, {} ms non-coherent, ±{:.0} Hz in {:.0} Hz bins, threshold {:.3} (P_fa {:e} per PRN), {:.2} s",
        r.files.join(" + "),
        r.format,
        r.sample_rate_hz / 1e6,
        r.intermediate_frequency_hz / 1e3,
        r.antennas,
        r.recording_s,
        r.antenna,
        r.noncoherent_ms,
        r.doppler_max_hz,
        r.doppler_step_hz,
        r.threshold,
        r.false_alarm_probability,
        r.search_s
    );
    println!("  PRN   Doppler (Hz)   code phase (chip)   metric   threshold");
    for d in &r.detections {
        println!(
            "  {:3}   {:12.1}   {:17.3}   {:6.2}   {:9.2}",
            d.prn, d.doppler_hz, d.code_phase_chips, d.metric, d.threshold
        );
    }
    if r.detections.is_empty() {
        println!("  (none)");
    }
    for x in &r.rejected_cross_correlations {
        println!(
            "  PRN {} at {:.0} Hz (metric {:.2}) rejected: cross-correlation of PRN {} ({:+.1} dB over the prediction)",
            x.prn, x.doppler_hz, x.metric, x.stronger_prn, x.over_predicted_db
        );
    }
    for x in r.second_looks.iter().filter(|x| x.accepted) {
        println!(
            "  PRN {} found with the stronger satellites cancelled (metric {:.2} over {:.2}, {:+.1} dB of its power kept)",
            x.prn,
            x.metric,
            x.threshold,
            x.power_kept_db.unwrap_or(f64::NAN)
        );
    }
    for x in r.searches.iter().filter(|x| x.candidate && !x.verified) {
        println!(
            "  PRN {} (metric {:.2} over {:.2}) not verified on the next {} ms ({})",
            x.prn, x.metric, x.threshold, r.noncoherent_ms, x.verification
        );
    }
}
