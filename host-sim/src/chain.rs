//! Runs the core's signal chain on a synthesized scene: samples → front-end format → decode →
//! acquisition (reference antenna, every PRN) → tracking channels over all antennas, streamed
//! in blocks so that long runs need little memory.
//!
//! The synthesizer is the truth; every per-epoch record carries what the metrics compare with
//! it. Parallel: sample synthesis over sub-blocks, acquisition over PRNs, tracking over
//! satellites (each channel is independent; the shared sample block is read-only).
//!
//! With a 2- or 1-bit front end ([`Quantizer::Sm2`], [`Quantizer::Bit1`]) the channels run
//! the core's bit-parallel correlator ([`ChainChannel::Bits`]) on bit planes packed from the
//! quantized samples, as a receiver on such a front end would; the search stays on the `i8`
//! values of the same samples.

use anyhow::{Context, Result};
use gnss_attitude::signal::bitwise::{BitBlock, BitCorrelator, BitScratch, CodeTable, PlaneBuffer};
use gnss_attitude::signal::{Prn, SampleBlock, SampleFormat};
use gnss_attitude::tracking::acquisition::{CANCELLATION_KEEP_FRACTION, CROSS_CORRELATION_MARGIN};
use gnss_attitude::tracking::{
    Acquisition, AcquisitionConfig, CancellationCheck, Channel, ChannelConfig, CrossCheck,
    KnownSignal, SearchReport, SearchResult, SearchSamples, TrackingEpoch,
};
use rayon::prelude::*;

use crate::synth::quantize::{Planar, Quantizer};
use crate::synth::Scene;

/// Antennas of the chain (the three-antenna array).
pub const ANTENNAS: usize = 3;

/// What to run.
#[derive(Clone, Debug)]
pub struct ChainParams {
    /// The scene (satellites, array, attitude, front end, noise).
    pub scene: Scene,
    /// Front-end format the samples go through (with [`Quantizer::I8`]).
    pub format: SampleFormat,
    /// The front end's quantizer: `format` for `i8`, else 2- or 1-bit samples, searched as
    /// `i8` values and tracked as bit planes by the bit-parallel correlator.
    pub quantizer: Quantizer,
    /// Acquisition set-up.
    pub acquisition: AcquisitionConfig,
    /// PRNs searched.
    pub search_prns: Vec<u8>,
    /// Tracking set-up.
    pub channel: ChannelConfig,
    /// Seconds of tracking (from sample 0).
    pub duration_s: f64,
    /// Samples per streamed block.
    pub block: usize,
}

/// One tracked epoch as the metrics need it.
#[derive(Clone, Copy, Debug)]
pub struct EpochRecord {
    /// Time of the epoch's middle, s.
    pub t: f64,
    /// Prompt of each antenna.
    pub prompt: [(f64, f64); ANTENNAS],
    /// Reported C/N0, dB-Hz.
    pub cn0_dbhz: f64,
    /// Replica Doppler, Hz.
    pub doppler_hz: f64,
    /// Code lock and phase lock.
    pub locked: bool,
    /// Data-bit edges known.
    pub bit_sync: bool,
    /// A data bit decoded at this epoch.
    pub data_bit: Option<i8>,
    /// Replica code phase at the epoch's first sample, chips.
    pub code_phase_chips: f64,
    /// Receiver sample index of the epoch's first sample.
    pub first_sample: u64,
}

/// A tracked satellite.
#[derive(Clone, Debug)]
pub struct TrackedSatellite {
    /// Index of the satellite in the scene.
    pub scene_index: usize,
    /// The acquisition that started it.
    pub acquisition: SearchResult,
    /// Every complete epoch.
    pub epochs: Vec<EpochRecord>,
}

/// The chain's output.
#[derive(Clone, Debug)]
pub struct ChainOutput {
    /// Every PRN's search.
    pub searches: Vec<SearchResult>,
    /// The satellites tracked (detected PRNs that are in the scene).
    pub tracked: Vec<TrackedSatellite>,
    /// Detected PRNs that are not in the scene.
    pub false_detections: Vec<u8>,
    /// Wall time of acquisition (with its synthesis), s.
    pub acquisition_seconds: f64,
    /// Wall time of the tracking run's sample synthesis (signal, noise, quantization,
    /// decoding), s.
    pub synthesis_seconds: f64,
    /// Wall time of the tracking channels (correlators and loops), s.
    pub tracking_seconds: f64,
}

/// Synthesizes `[first, first + n)` of every antenna and passes it through the front end
/// (the quantizer; the format for `i8`).
pub fn samples(params: &ChainParams, first: u64, n: usize) -> Result<Planar> {
    let analog = params.scene.synthesize(first, n);
    params.quantizer.quantize(params.format, &analog, n)
}

/// The core's tracking channel on the correlator the front end calls for.
#[derive(Clone, Debug)]
pub enum ChainChannel {
    /// The `i8` correlator (CS8 and the other 8- and 16-bit formats).
    I8(Box<Channel<ANTENNAS>>),
    /// The bit-parallel correlator (2- and 1-bit front ends).
    Bits(Box<Channel<ANTENNAS, BitCorrelator<ANTENNAS>>>),
}

/// Plane words per antenna of one packed sub-block (131 072 samples, 64 KiB of planes).
const PLANE_WORDS: usize = 4096;

/// A tracking channel started from an acquisition of a scene satellite.
#[derive(Clone, Debug)]
pub struct TrackedChannel {
    /// The core's channel.
    pub channel: ChainChannel,
    /// Index of the satellite in the scene.
    pub scene_index: usize,
    /// The acquisition that started it.
    pub acquisition: SearchResult,
}

/// Acquisition, then streamed tracking of the detected scene satellites: the chain a receiver
/// runs, block by block.
#[derive(Clone, Debug)]
pub struct Tracker {
    /// Every PRN's search.
    pub searches: Vec<SearchResult>,
    /// Detected PRNs that are not in the scene.
    pub false_detections: Vec<u8>,
    /// The channels, in the order of the searches.
    pub channels: Vec<TrackedChannel>,
    /// Wall time of acquisition (with its synthesis), s.
    pub acquisition_seconds: f64,
    /// Wall time of the tracking run's sample synthesis so far, s.
    pub synthesis_seconds: f64,
    /// Wall time of the tracking channels so far, s.
    pub tracking_seconds: f64,
    /// The bit-parallel correlators' code table (2- and 1-bit front ends).
    code_table: Option<Box<CodeTable>>,
}

impl Tracker {
    /// Runs acquisition on the first samples and starts a channel for every detected scene
    /// satellite; tracking starts at sample 0 (the acquisition's first sample).
    pub fn acquire(params: &ChainParams) -> Result<Self> {
        let started = std::time::Instant::now();
        let n_acq = params.acquisition.samples_needed();
        let acq_samples = samples(params, 0, n_acq)?;
        let complex = params.format.is_complex();
        let q = complex.then_some(&acq_samples.q[0][..]);
        let found = detect_prns(
            &acq_samples.i[0],
            q,
            0,
            &params.search_prns,
            &params.acquisition,
            &[],
            Some(CROSS_CORRELATION_MARGIN),
        )?;
        let searches: Vec<SearchResult> = found.reports.iter().map(|r| r.result).collect();
        let acquisition_seconds = started.elapsed().as_secs_f64();
        let mut false_detections = Vec::new();
        let mut channels = Vec::new();
        let accepted = |s: &&SearchResult| found.accepted.iter().any(|a| a.prn == s.prn);
        for s in searches.iter().filter(accepted) {
            match params
                .scene
                .satellites
                .iter()
                .position(|sat| sat.prn == s.prn.number())
            {
                Some(k) => {
                    let channel = match params.quantizer.bit_settings(complex) {
                        None => {
                            let mut c = Channel::<ANTENNAS>::new(s.prn, &params.channel)?;
                            c.start(s)?;
                            ChainChannel::I8(Box::new(c))
                        }
                        Some(settings) => {
                            let mut c = Channel::with_settings(s.prn, &params.channel, &settings)?;
                            c.start(s)?;
                            ChainChannel::Bits(Box::new(c))
                        }
                    };
                    channels.push(TrackedChannel {
                        channel,
                        scene_index: k,
                        acquisition: *s,
                    });
                }
                None => false_detections.push(s.prn.number()),
            }
        }
        Ok(Self {
            searches,
            false_detections,
            channels,
            acquisition_seconds,
            synthesis_seconds: 0.0,
            tracking_seconds: 0.0,
            code_table: match params.quantizer.bit_settings(complex) {
                Some(_) => Some(Box::new(CodeTable::new(
                    params.scene.front_end.sample_rate_hz,
                )?)),
                None => None,
            },
        })
    }

    /// Synthesizes samples `[first, first + n)` and runs every channel over them (in parallel
    /// over channels); returns each channel's complete epochs, in channel order. Blocks must
    /// follow each other without gaps.
    pub fn track(
        &mut self,
        params: &ChainParams,
        first: u64,
        n: usize,
    ) -> Result<Vec<Vec<TrackingEpoch<ANTENNAS>>>> {
        let t0 = std::time::Instant::now();
        let planar = samples(params, first, n)?;
        self.synthesis_seconds += t0.elapsed().as_secs_f64();
        let t0 = std::time::Instant::now();
        if let (Some(settings), Some(table)) = (
            params.quantizer.bit_settings(params.format.is_complex()),
            self.code_table.as_deref(),
        ) {
            let out = track_planes(&mut self.channels, &planar, first, settings, table)?;
            self.tracking_seconds += t0.elapsed().as_secs_f64();
            return Ok(out);
        }
        let iv: [&[i8]; ANTENNAS] = [&planar.i[0], &planar.i[1], &planar.i[2]];
        let sb = if params.format.is_complex() {
            SampleBlock::complex(first, iv, [&planar.q[0], &planar.q[1], &planar.q[2]])?
        } else {
            SampleBlock::real(first, iv)?
        };
        let out = self
            .channels
            .par_iter_mut()
            .map(|ch| -> Result<Vec<TrackingEpoch<ANTENNAS>>> {
                let mut epochs = Vec::new();
                let mut cursor = 0;
                let ChainChannel::I8(channel) = &mut ch.channel else {
                    anyhow::bail!("a bit-plane channel given i8 samples");
                };
                while cursor < sb.len() {
                    if let Some(e) = channel.process(&sb, &mut cursor)? {
                        epochs.push(e);
                    }
                }
                Ok(epochs)
            })
            .collect::<Result<Vec<_>>>()?;
        self.tracking_seconds += t0.elapsed().as_secs_f64();
        Ok(out)
    }
}

/// Runs the bit-plane channels over the quantized samples `planar` (first sample `first`):
/// packs each antenna's planes ([`PLANE_WORDS`] words at a time, once for every channel) from
/// the quantizer's `i8` levels, exactly the planes the front end's bytes give.
fn track_planes(
    channels: &mut [TrackedChannel],
    planar: &Planar,
    first: u64,
    settings: gnss_attitude::signal::BitSettings,
    table: &CodeTable,
) -> Result<Vec<Vec<TrackingEpoch<ANTENNAS>>>> {
    let n = planar.i.first().map_or(0, Vec::len);
    let mut out = vec![Vec::new(); channels.len()];
    let mut planes: Vec<Box<PlaneBuffer<PLANE_WORDS>>> = (0..ANTENNAS)
        .map(|_| Box::new(PlaneBuffer::new(settings.format)))
        .collect();
    let step = PLANE_WORDS * 32;
    let mut start = 0;
    while start < n {
        let end = (start + step).min(n);
        for (a, p) in planes.iter_mut().enumerate() {
            let q = planar
                .q
                .get(a)
                .map_or(&[][..], |q| q.get(start..end).unwrap_or(&[]));
            p.pack_i8(&planar.i[a][start..end], q, Quantizer::PLANE_THRESHOLD)?;
        }
        let block = BitBlock::new(
            first + start as u64,
            table,
            [planes[0].planes(), planes[1].planes(), planes[2].planes()],
        )?;
        let epochs = channels
            .par_iter_mut()
            .map(|ch| -> Result<Vec<TrackingEpoch<ANTENNAS>>> {
                let ChainChannel::Bits(channel) = &mut ch.channel else {
                    anyhow::bail!("an i8 channel given bit planes");
                };
                let mut epochs = Vec::new();
                let mut cursor = 0;
                let mut scratch = BitScratch::new();
                while cursor < block.len() {
                    if let Some(e) = channel.process_in(&block, &mut cursor, &mut scratch)? {
                        epochs.push(e);
                    }
                }
                Ok(epochs)
            })
            .collect::<Result<Vec<_>>>()?;
        for (o, e) in out.iter_mut().zip(epochs) {
            o.extend(e);
        }
        start = end;
    }
    Ok(out)
}

/// Runs acquisition on the first samples, then tracks every detected scene satellite.
pub fn run(params: &ChainParams, progress: Option<&indicatif::ProgressBar>) -> Result<ChainOutput> {
    let fs = params.scene.front_end.sample_rate_hz;
    let mut tracker = Tracker::acquire(params)?;
    let mut tracked: Vec<TrackedSatellite> = tracker
        .channels
        .iter()
        .map(|c| TrackedSatellite {
            scene_index: c.scene_index,
            acquisition: c.acquisition,
            epochs: Vec::new(),
        })
        .collect();
    // Stream the run in blocks; the tracking starts at sample 0 (the acquisition's first sample).
    let total = (params.duration_s * fs).round() as u64;
    let block = params.block.max(1);
    let mut first = 0u64;
    while first < total {
        let n = block.min((total - first) as usize);
        let epochs = tracker.track(params, first, n)?;
        for (rec, es) in tracked.iter_mut().zip(epochs) {
            rec.epochs.extend(es.iter().map(|e| record(e, fs)));
        }
        first += n as u64;
        if let Some(p) = progress {
            p.set_position((first as f64 / total as f64 * 1000.0) as u64);
        }
    }
    Ok(ChainOutput {
        searches: tracker.searches,
        tracked,
        false_detections: tracker.false_detections,
        acquisition_seconds: tracker.acquisition_seconds,
        synthesis_seconds: tracker.synthesis_seconds,
        tracking_seconds: tracker.tracking_seconds,
    })
}

fn record(e: &TrackingEpoch<ANTENNAS>, fs: f64) -> EpochRecord {
    let c = &e.correlations;
    let mut prompt = [(0.0, 0.0); ANTENNAS];
    for (p, t) in prompt.iter_mut().zip(c.taps.iter()) {
        *p = (f64::from(t.prompt.i), f64::from(t.prompt.q));
    }
    EpochRecord {
        t: (c.first_sample as f64 + 0.5 * f64::from(c.samples)) / fs,
        prompt,
        cn0_dbhz: f64::from(e.cn0_dbhz),
        doppler_hz: f64::from(e.doppler_hz),
        locked: e.lock.code && e.lock.phase,
        bit_sync: e.lock.bit_sync,
        data_bit: e.data_bit,
        code_phase_chips: c.code_phase_at_first as f64 / 4_294_967_296.0,
        first_sample: c.first_sample,
    }
}

/// Searches `prns` in one antenna's samples (`q = None` for real samples; `first_sample` is
/// the receiver index of `i[0]`), in parallel over PRNs with one `Acquisition<2048>` per
/// worker. Results in the order of `prns`.
///
/// # Errors
/// A PRN outside 1–32, or the core's refusal of the configuration or the samples.
pub fn search_prns(
    i: &[i8],
    q: Option<&[i8]>,
    first_sample: u64,
    prns: &[u8],
    config: &AcquisitionConfig,
) -> Result<Vec<SearchResult>> {
    Ok(search_reports(i, q, first_sample, prns, config)?
        .into_iter()
        .map(|r| r.result)
        .collect())
}

/// [`search_prns`] with the core's full reports (background, verification).
///
/// # Errors
/// As [`search_prns`].
pub fn search_reports(
    i: &[i8],
    q: Option<&[i8]>,
    first_sample: u64,
    prns: &[u8],
    config: &AcquisitionConfig,
) -> Result<Vec<SearchReport>> {
    prns.par_iter()
        .map_init(
            || Acquisition::<2048>::new().map(Box::new),
            |engine, &p| -> Result<SearchReport> {
                let engine = engine.as_mut().map_err(|e| anyhow::anyhow!("{e}"))?;
                let prn = Prn::new(p).with_context(|| format!("PRN {p} out of range 1-32"))?;
                Ok(engine.search_report(
                    prn,
                    SearchSamples::decoded(i, q)?,
                    first_sample,
                    config,
                )?)
            },
        )
        .collect()
}

/// A detection rejected as the cross-correlation of a stronger satellite.
#[derive(Clone, Copy, Debug)]
pub struct CrossCorrelationRejection {
    /// The detection.
    pub result: SearchResult,
    /// The core's test.
    pub check: CrossCheck,
}

/// The detections of one search round.
#[derive(Clone, Debug)]
pub struct Detections {
    /// Every PRN's search, in the order searched.
    pub reports: Vec<SearchReport>,
    /// Detected, verified and not explained as a cross-correlation; by PRN.
    pub accepted: Vec<SearchResult>,
    /// Detected and verified, but the cross-correlation of stronger satellites.
    pub rejected: Vec<CrossCorrelationRejection>,
    /// The second looks ([`second_look`]), in the order of the PRNs searched.
    pub second_looks: Vec<SecondLook>,
}

/// A PRN searched again with the known signals cancelled ([`second_look`]).
#[derive(Clone, Copy, Debug)]
pub struct SecondLook {
    /// The search with the known signals cancelled.
    pub report: SearchReport,
    /// The threshold of the PRN's first search: the second look's metric must pass it too
    /// (the cancellation lowers the background's spread, not a tone's or a jammer's tail).
    pub first_threshold: f32,
    /// Its detection's power with and without them (`None`: nothing detected).
    pub check: Option<CancellationCheck>,
}

impl SecondLook {
    /// Detected with the known signals cancelled, and a satellite of its own.
    pub fn accepted(&self) -> bool {
        self.report.result.detected
            && self.report.result.metric > self.first_threshold
            && self.check.is_some_and(|c| c.kept)
    }
}

/// The second look at the PRNs stronger satellites may have masked: those of `reports` not
/// `accepted` whose background was not thermal (fewer effective milliseconds than summed:
/// cross-correlation in it; not when interference was found, which makes a background of its
/// own) or whose detection was `rejected` as a cross-correlation, each
/// searched again with the `known` signals cancelled from the samples
/// ([`Acquisition::search_report_cancelling`]); a detection there is a satellite when its
/// metric passes the first search's threshold too and it keeps its power with them
/// cancelled ([`Acquisition::cancellation_check`]). In parallel,
/// one engine per worker; nothing to do without known signals.
///
/// # Errors
/// The core's refusal of the configuration or the samples.
#[allow(clippy::too_many_arguments)]
pub fn second_look(
    i: &[i8],
    q: Option<&[i8]>,
    first_sample: u64,
    config: &AcquisitionConfig,
    reports: &[SearchReport],
    accepted: &[SearchResult],
    rejected: &[CrossCorrelationRejection],
    known: &[KnownSignal],
) -> Result<Vec<SecondLook>> {
    if known.is_empty() {
        return Ok(Vec::new());
    }
    let masked = |r: &&SearchReport| {
        let prn = r.result.prn;
        !accepted.iter().any(|a| a.prn == prn)
            && !r.interference
            && (r.effective_ms < config.noncoherent_ms
                || rejected.iter().any(|x| x.result.prn == prn))
    };
    let again: Vec<(Prn, f32)> = reports
        .iter()
        .filter(masked)
        .map(|r| (r.result.prn, r.result.threshold))
        .collect();
    again
        .par_iter()
        .map_init(
            || Acquisition::<2048>::new().map(Box::new),
            |engine, &(prn, first_threshold)| -> Result<SecondLook> {
                let engine = engine.as_mut().map_err(|e| anyhow::anyhow!("{e}"))?;
                let samples = SearchSamples::decoded(i, q)?;
                let report =
                    engine.search_report_cancelling(prn, samples, first_sample, config, known)?;
                let check = if report.result.detected {
                    Some(engine.cancellation_check(
                        &report.result,
                        known,
                        samples,
                        config,
                        CANCELLATION_KEEP_FRACTION,
                    )?)
                } else {
                    None
                };
                Ok(SecondLook {
                    report,
                    first_threshold,
                    check,
                })
            },
        )
        .collect()
}

/// Searches `prns` ([`search_reports`]), then tests the verified detections, strongest first,
/// against the cross-correlation of the stronger accepted ones and of `tracked` (signals
/// known on these samples, e.g. the channels') with the core's
/// [`Acquisition::cross_check`]; `margin` is its margin (`None`: no test, and no second
/// look). Then the [`second_look`] at the PRNs the stronger satellites may have masked, with
/// the tracked and accepted signals (strongest first) cancelled.
///
/// # Errors
/// As [`search_prns`].
pub fn detect_prns(
    i: &[i8],
    q: Option<&[i8]>,
    first_sample: u64,
    prns: &[u8],
    config: &AcquisitionConfig,
    tracked: &[KnownSignal],
    margin: Option<f32>,
) -> Result<Detections> {
    let reports = search_reports(i, q, first_sample, prns, config)?;
    let mut detected: Vec<SearchResult> = reports
        .iter()
        .map(|r| r.result)
        .filter(|r| r.detected)
        .collect();
    detected.sort_by(|a, b| b.metric.total_cmp(&a.metric));
    let mut engine = Box::new(Acquisition::<2048>::new().map_err(|e| anyhow::anyhow!("{e}"))?);
    let mut accepted: Vec<SearchResult> = Vec::new();
    let mut rejected = Vec::new();
    for r in detected {
        let Some(margin) = margin else {
            accepted.push(r);
            continue;
        };
        let known: Vec<KnownSignal> = tracked
            .iter()
            .copied()
            .chain(accepted.iter().map(KnownSignal::from))
            .collect();
        let check =
            engine.cross_check(&r, &known, SearchSamples::decoded(i, q)?, config, margin)?;
        if check.explained {
            rejected.push(CrossCorrelationRejection { result: r, check });
        } else {
            accepted.push(r);
        }
    }
    // The known signals, strongest first (the cancellation takes the first ones).
    let known: Vec<KnownSignal> = tracked
        .iter()
        .copied()
        .chain(accepted.iter().map(KnownSignal::from))
        .collect();
    let second_looks = match margin {
        Some(_) => second_look(
            i,
            q,
            first_sample,
            config,
            &reports,
            &accepted,
            &rejected,
            &known,
        )?,
        None => Vec::new(),
    };
    for look in second_looks.iter().filter(|l| l.accepted()) {
        let prn = look.report.result.prn;
        rejected.retain(|x| x.result.prn != prn);
        accepted.push(look.report.result);
    }
    accepted.sort_by_key(|r| r.prn.number());
    Ok(Detections {
        reports,
        accepted,
        rejected,
        second_looks,
    })
}

/// Runs every active channel over `block` (in parallel over channels) and hands each complete
/// epoch to `on_epoch` with the channel's companion state `S`.
///
/// # Errors
/// The first channel error (the block must continue the stream the channels have seen).
pub fn track_block<const A: usize, S: Send>(
    channels: &mut [(Channel<A>, S)],
    block: &SampleBlock<'_, A>,
    active: impl Fn(&S) -> bool + Sync,
    on_epoch: impl Fn(&mut S, &TrackingEpoch<A>) + Sync,
) -> Result<()> {
    channels
        .par_iter_mut()
        .filter(|(_, s)| active(s))
        .try_for_each(|(ch, s)| -> Result<()> {
            let mut cursor = 0;
            while cursor < block.len() {
                if let Some(e) = ch.process(block, &mut cursor)? {
                    on_epoch(s, &e);
                }
            }
            Ok(())
        })
}
