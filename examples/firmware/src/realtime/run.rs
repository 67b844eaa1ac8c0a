//! One front end through the whole receiver: acquisition, warm-up to fine attitude, then the
//! counted stretch of `push_samples`, then the verdict against the embedded truth.

use core::hint::black_box;
use core::sync::atomic::{AtomicU32, Ordering};

use gnss_attitude::attitude::example::SKY;
use gnss_attitude::receiver::example::ExampleFlight;
use gnss_attitude::receiver::{AttitudeSource, ReceiverConfig, ReceiverError, SampleFrontConfig, SampleReceiver, SampleReport};
use gnss_attitude::signal::bitwise::{BitBlock, BitCorrelator, CarrierLevels, CodeTable, PlaneBuffer, PlaneError, COMPLEX_TWO_LEVEL_KERNELS};
use gnss_attitude::signal::nco::CodeNco;
use gnss_attitude::signal::{BitSettings, Prn, SlaveTaps, CA_CHIP_RATE_HZ};
use gnss_attitude::tracking::{SearchResult, SearchSamples};

use super::fixed::fixed;
use crate::say::{Line, Refusal, Say};
use super::frontend::FrontEnd;
use super::memory;
use super::synth::{predicted_doppler_hz, Synth, CODE_PHASE_CHIPS, DOPPLER_HZ, SAMPLES_PER_MS, SAMPLE_RATE_HZ};

/// Channels (one per satellite; each tracks the three antennas).
pub const CHANNELS: usize = 8;
/// The bit-parallel correlator: three antennas, and only the kernels of this front end (complex
/// 1- and 2-bit samples, the 2-level carrier [`CARRIER`]): the other six are not linked.
pub type Correlator = BitCorrelator<3, COMPLEX_TWO_LEVEL_KERNELS>;
/// The receiver: 8 channels, 1024-point acquisition, bit-parallel correlators over the three
/// antennas' bit planes.
pub type Front = SampleReceiver<CHANNELS, 1024, Correlator>;
/// The carrier replica's levels: the 2-level replica (the M4F's cheaper kernel; 0.91 dB of
/// carrier quantization against 0.35 dB for the 3-level one, docs/METHODS.md).
pub const CARRIER: CarrierLevels = CarrierLevels::Two;
/// Receiver epochs per synthesized block.
pub const BLOCK_MS: usize = 1;
/// Samples per antenna and component in a block.
pub const BLOCK: usize = SAMPLES_PER_MS * BLOCK_MS;
/// Milliseconds the acquisition sums non-coherently (the warm start's 6 ms of `.ci/run`'s
/// acquisition figures).
pub const ACQUISITION_MS: u16 = 6;
/// Samples per component the acquisition searches and verifies on (`2 K` ms + 1).
pub const ACQUISITION_SAMPLES: usize = 2 * ACQUISITION_MS as usize * SAMPLES_PER_MS + 1;
/// Plane words that hold them.
pub const ACQUISITION_WORDS: usize = ACQUISITION_SAMPLES.div_ceil(32);
/// The room for a front end's bytes of one antenna and block: the larger layout's (`sm2iq`:
/// two complex samples per byte; `bit1iq` fills the first half, [`FrontEnd::block_bytes`]).
pub const BLOCK_BYTES: usize = BLOCK / 2;
/// Plane words per antenna and block (32 samples per word).
pub const WORDS: usize = BLOCK.div_ceil(32);
/// The code step of the front end's sample rate, 2⁻³² chip per sample (`CodeNco::step_for`,
/// checked against it at run time).
const CODE_STEP: u64 = (CA_CHIP_RATE_HZ / SAMPLE_RATE_HZ * 4_294_967_296.0 + 0.5) as u64;
/// The chip-to-sample expansion table of the front end's rate, built at compile time (8 KiB of
/// flash, shared by every channel).
static CODE_TABLE: CodeTable = CodeTable::from_step(CODE_STEP);
/// Longest warm-up to fine attitude, receiver epochs (ms).
pub const WARM_UP_MAX_MS: u64 = 3000;
/// Epochs run in fine attitude before the counted stretch starts.
pub const SETTLE_MS: u64 = 1000;
/// Counted epochs (ms) per front end.
pub const COUNT_MS: u64 = 200;
/// Largest attitude error accepted at the end, degrees.
pub const LIMIT_DEG: f32 = 0.1;

static REGION: AtomicU32 = AtomicU32::new(0);

/// Calls `f` in a frame of its own.
#[inline(never)]
fn call<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// Runs `f` between the instruction-count markers that `.ci/insnmark.c` counts (`mov r8, r8`
/// … `mov r9, r9`, as `budget::measure` in the self-check); returns the region's number.
#[inline(never)]
fn count<R>(f: impl FnOnce() -> R) -> (u32, R) {
    let n = REGION.fetch_add(1, Ordering::Relaxed);
    // SAFETY: the markers are register-to-self moves with no effect on program state.
    unsafe { core::arch::asm!("mov r8, r8") };
    let out = call(f);
    unsafe { core::arch::asm!("mov r9, r9") };
    (n, black_box(out))
}

/// The front half's configuration: complex 2.6 Msps, LEO channels, a warm search (±2 kHz
/// about the flight computer's predicted Doppler, [`predicted_doppler_hz`]: it knows the
/// almanac, time and orbit, not its oscillator's offset; [`ACQUISITION_MS`] non-coherent), false alarms 10⁻³ per PRN search; the slaved antennas prompt only (paper 003's
/// filter needs no more of them; the adapter scales their prompts by the reference antenna's
/// noise, equal to theirs behind a quantizer's AGC).
pub fn front_config() -> SampleFrontConfig {
    let mut c = SampleFrontConfig::leo_complex(SAMPLE_RATE_HZ);
    c.acquisition.doppler_max_hz = 2000.0;
    c.acquisition.noncoherent_ms = ACQUISITION_MS;
    c.acquisition.false_alarm_probability = 1e-3;
    c.channel.slave_taps = SlaveTaps::Prompt;
    c
}

/// Why a block did not reach the receiver, or what the receiver refused.
pub enum BlockError {
    /// The front end's bytes did not pack into a whole block of planes (the packing's error;
    /// `PlaneLength` for a short block).
    Plane(PlaneError),
    /// The receiver refused the block.
    Receiver(ReceiverError),
}

impl Say for BlockError {
    /// Which stage refused and its error's kind: `packing refused (invalid input)`.
    fn say(&self, line: &mut Line) {
        match self {
            BlockError::Plane(e) => {
                line.bytes(b"packing ");
                Refusal(e).say(line);
            }
            BlockError::Receiver(e) => {
                line.bytes(b"receiver ");
                Refusal(e).say(line);
            }
        }
    }
}

/// The antennas' bit planes of one block, packed from the front end's bytes
/// ([`FrontEnd::sample_format`]) with the core's packing, as firmware would from the DMA
/// buffer (counted: the receiver's work).
#[inline(always)]
fn pack_block(front_end: FrontEnd, planes: &mut [PlaneBuffer<WORDS>; 3], bytes: [&[u8]; 3]) -> Result<(), BlockError> {
    for (p, b) in planes.iter_mut().zip(bytes) {
        if p.pack_bytes(front_end.sample_format(), b, 0).map_err(BlockError::Plane)? != BLOCK {
            return Err(BlockError::Plane(PlaneError::PlaneLength));
        }
    }
    Ok(())
}

/// One block of the stream handed to the receiver (counted): the antennas' planes, first
/// sample `first`, with the front end's code table.
#[inline(always)]
fn push_block(rx: &mut Front, first: u64, planes: &[PlaneBuffer<WORDS>; 3]) -> Result<SampleReport, BlockError> {
    let block = BitBlock::new(first, &CODE_TABLE, [planes[0].planes(), planes[1].planes(), planes[2].planes()]).map_err(BlockError::Plane)?;
    rx.push_samples(&block).map_err(BlockError::Receiver)
}

/// What one front end's run gave.
pub struct Outcome {
    /// Receiver epoch at which the attitude first came from the fine filter.
    pub fine_at: Option<u64>,
    /// First and last counted region.
    pub regions: (u32, u32),
    /// Counted epochs.
    pub counted_ms: u64,
    /// Final attitude's source and error against the truth, degrees.
    pub source: AttitudeSource,
    /// Attitude error at the end, degrees.
    pub error_deg: f32,
    /// Worst stack of the receiver's construction (`SampleReceiver::with_settings`), bytes from the
    /// stack's top.
    pub construction_stack: usize,
    /// Worst stack of the acquisition (the receiver in `run`'s frame, the searched samples,
    /// the search), bytes from the stack's top.
    pub acquisition_stack: usize,
    /// Worst stack while tracking (the receiver in `run`'s frame, the block buffer, the
    /// synthesis and the receiver's work), bytes from the stack's top.
    pub stream_stack: usize,
    /// The run passed (fine attitude within [`LIMIT_DEG`], no refusal).
    pub pass: bool,
}

/// Acquisition: every PRN of the sky searched on the reference antenna's first
/// [`ACQUISITION_SAMPLES`], collected as bit planes block by block as the front end delivers
/// them (packed with the stream's `bytes` and `planes`, appended to a buffer of this frame's:
/// 15.6 KB where `i8` samples took 62 KB). The searches are counted as one region (printed
/// with the number detected). Returns the number detected.
#[inline(never)]
#[optimize(size)]
fn acquire(rx: &mut Front, synth: &mut Synth, front_end: FrontEnd, bytes: &mut [[u8; BLOCK_BYTES]; 3], planes: &mut [PlaneBuffer<WORDS>; 3]) -> usize {
    let mut collected = PlaneBuffer::<ACQUISITION_WORDS>::new(front_end.plane_format());
    let first = synth.next_sample();
    while collected.len() < ACQUISITION_SAMPLES {
        let [b0, b1, b2] = bytes;
        let n = front_end.block_bytes();
        synth.fill_bytes(front_end, [&mut b0[..n], &mut b1[..n], &mut b2[..n]]);
        let appended = pack_block(front_end, planes, [&b0[..n], &b1[..n], &b2[..n]]).map_err(|e| say!("realtime ", front_end.name(), ": acquisition block ", e)).and_then(|()| collected.append(&planes[0].planes()).map_err(|e| say!("realtime ", front_end.name(), ": acquisition planes ", Refusal(&e))));
        if appended.is_err() {
            return 0;
        }
    }
    let samples = SearchSamples::Planes(collected.planes());
    let (region, results) = count(|| search_sky(rx, samples, first));
    let mut detected = 0;
    for (s, result) in results.iter().enumerate() {
        match result {
            Some(Ok(r)) => {
                detected += usize::from(r.detected);
                say!(
                    "realtime ",
                    front_end.name(),
                    ": search PRN ",
                    r.prn.number(),
                    ": detected ",
                    r.detected,
                    " Doppler ",
                    fixed(r.doppler_hz, 1),
                    " Hz (truth ",
                    fixed(DOPPLER_HZ[s], 1),
                    ", predicted ",
                    fixed(predicted_doppler_hz(s), 1),
                    "), code phase ",
                    fixed(r.code_phase_chips, 3),
                    " chips (truth ",
                    fixed(CODE_PHASE_CHIPS[s], 3),
                    ")"
                );
            }
            Some(Err(e)) => say!("realtime ", front_end.name(), ": search of sky entry ", s, " ", Refusal(e)),
            None => say!("realtime ", front_end.name(), ": sky entry ", s, " is no PRN"),
        }
    }
    say!(
        "realtime ",
        front_end.name(),
        ": acquisition region ",
        region,
        ": ",
        detected,
        " of ",
        SKY.len(),
        " PRNs detected (+-2 kHz about the predicted Doppler, ",
        ACQUISITION_MS,
        " ms non-coherent, on bit planes)"
    );
    detected
}

/// Every PRN of the sky searched on `samples` (the reference antenna's, from sample `first`)
/// about its predicted Doppler: `None` for a sky entry that is no PRN.
#[inline(never)]
#[optimize(size)]
fn search_sky(rx: &mut Front, samples: SearchSamples<'_>, first: u64) -> [Option<Result<SearchResult, ReceiverError>>; SKY.len()] {
    core::array::from_fn(|s| SKY.get(s).and_then(|&(prn, _, _)| Prn::new(prn).map(|prn| rx.search_samples_near(prn, samples, first, predicted_doppler_hz(s)))))
}

/// The whole run of one front end: the receiver built (on the stack, bound inside its
/// `Result`: one copy of its 78 KB), then [`stream`] in a frame of its own.
#[inline(never)]
#[optimize(size)]
pub fn run(front_end: FrontEnd) -> Outcome {
    // (through an opaque function pointer: `new` keeps a frame of its own instead of
    // inlining its temporaries into this one)
    let new: fn(ReceiverConfig, SampleFrontConfig, BitSettings) -> Result<Front, ReceiverError> = black_box(Front::with_settings);
    let settings = BitSettings { format: front_end.plane_format(), carrier: CARRIER };
    let mut made = new(ExampleFlight::config(true), front_config(), settings);
    match made.as_mut() {
        Ok(rx) => {
            rx.receiver_mut().set_deferred_stages(true);
            rx.set_deferred_checks(true);
            // the construction's high-water mark, then the stream's own
            let sp = memory::sp();
            let built = memory::stack_top() - sp + memory::used_below(sp);
            memory::paint_below();
            let mut out = stream(front_end, rx);
            out.construction_stack = built;
            out.stream_stack = memory::stack_top() - sp + memory::used_below(sp);
            out
        }
        Err(e) => {
            say!("realtime ", front_end.name(), ": receiver configuration ", Refusal(&*e));
            Outcome {
                fine_at: None,
                regions: (0, 0),
                counted_ms: 0,
                source: AttitudeSource::None,
                error_deg: f32::NAN,
                pass: false,
                stream_stack: 0,
                construction_stack: 0,
                acquisition_stack: 0,
            }
        }
    }
}

/// Acquisition, warm-up, the counted stretch and the verdict. The sample buffer is this
/// frame's: it takes the stack the receiver's construction used (its temporaries are gone),
/// so the two never coexist (a static buffer would add to the construction's peak).
/// The stack below this frame is painted again first: the stream's own high-water mark is
/// reported apart from the construction's.
#[inline(never)]
#[optimize(size)]
fn stream(front_end: FrontEnd, rx: &mut Front) -> Outcome {
    let mut bytes = [[0u8; BLOCK_BYTES]; 3];
    let block_bytes = front_end.block_bytes();
    let mut planes = [(); 3].map(|_| PlaneBuffer::<WORDS>::new(front_end.plane_format()));
    let mut out = Outcome {
        fine_at: None,
        regions: (0, 0),
        counted_ms: 0,
        source: AttitudeSource::None,
        error_deg: f32::NAN,
        pass: false,
        stream_stack: 0,
        construction_stack: 0,
        acquisition_stack: 0,
    };
    let seed = match front_end {
        FrontEnd::OneBit => 0x1B17,
        FrontEnd::TwoBit => 0x2B17,
    };
    let mut synth = Synth::new(seed);
    let sp = memory::sp();
    let detected = acquire(rx, &mut synth, front_end, &mut bytes, &mut planes);
    out.acquisition_stack = memory::stack_top() - sp + memory::used_below(sp);
    memory::paint_below();
    // the stream continues on the receiver's 1 ms grid
    let start = synth.next_sample().div_ceil(SAMPLES_PER_MS as u64) * SAMPLES_PER_MS as u64;
    synth.skip(start - synth.next_sample());

    let mut refusals = 0u32;
    if CODE_TABLE.step() != CodeNco::step_for(CA_CHIP_RATE_HZ, SAMPLE_RATE_HZ) {
        say!("realtime ", front_end.name(), ": code table step ", CODE_TABLE.step(), " is not the sample rate's");
        refusals += 1;
    }
    let mut total = SampleReport::default();
    let mut gyro_next = 0u64;
    let mut first_region = None;
    let mut last_region = 0;
    loop {
        let first = synth.next_sample();
        let e0 = first / SAMPLES_PER_MS as u64;
        if e0 % 100 < BLOCK_MS as u64 || first == start {
            refusals += u32::from(rx.receiver_mut().set_aiding(&synth.flight().aiding(e0)).is_err());
        }
        synth.set_geometry(e0);
        {
            let [b0, b1, b2] = &mut bytes;
            synth.fill_bytes(front_end, [&mut b0[..block_bytes], &mut b1[..block_bytes], &mut b2[..block_bytes]]);
        }
        let counting = out.fine_at.is_some_and(|f| e0 >= f + SETTLE_MS);
        let flight = synth.flight();
        let input = [&bytes[0][..block_bytes], &bytes[1][..block_bytes], &bytes[2][..block_bytes]];
        // the receiver's work of one block, in three stages: the front end's bytes packed
        // into planes; the gyro increments that end in the block and its samples (the 1 ms
        // path); the stages deferred out of it
        let pack = |planes: &mut [PlaneBuffer<WORDS>; 3]| pack_block(front_end, planes, black_box(input));
        let work = |rx: &mut Front, gyro_next: &mut u64, planes: &[PlaneBuffer<WORDS>; 3]| {
            let mut refused = 0u32;
            while 10 * (*gyro_next + 1) < e0 + BLOCK_MS as u64 {
                refused += u32::from(rx.receiver_mut().push_gyro_increment(&flight.gyro_increment(*gyro_next)).is_err());
                *gyro_next += 1;
            }
            (refused, push_block(rx, first, planes))
        };
        let deferred = |rx: &mut Front| rx.run_deferred();
        let (packed, (refused, report), main_loop) = if counting {
            let (n, packed) = count(|| pack(&mut planes));
            let (_, r) = count(|| work(&mut *rx, &mut gyro_next, &planes));
            let (m, d) = count(|| deferred(&mut *rx));
            first_region.get_or_insert(n);
            last_region = m;
            out.counted_ms += BLOCK_MS as u64;
            (packed, r, d)
        } else {
            let packed = pack(&mut planes);
            let r = work(&mut *rx, &mut gyro_next, &planes);
            (packed, r, deferred(&mut *rx))
        };
        refusals += refused;
        total.released += main_loop.released;
        let report = packed.and(report);
        match report {
            Ok(r) => {
                total.epochs += r.epochs;
                total.observations += r.observations;
                total.without_aiding += r.without_aiding;
                total.late += r.late;
                total.released += r.released;
            }
            Err(e) => {
                say!("realtime ", front_end.name(), ": push_samples at epoch ", e0, ": ", e);
                refusals += 1;
                break;
            }
        }
        let att = rx.attitude();
        if out.fine_at.is_none() && att.source == AttitudeSource::Fine {
            out.fine_at = Some(e0 + BLOCK_MS as u64);
            say!(
                "realtime ",
                front_end.name(),
                ": fine attitude at epoch ",
                e0 + BLOCK_MS as u64,
                " (",
                total.observations,
                " observations, ",
                rx.channels().filter(|c| c.locked).count(),
                " channels locked)"
            );
        }
        if out.fine_at.is_some() && (e0 + BLOCK_MS as u64) % 100 == 0 {
            let e = att.q_rb.angle_to(&synth.truth(att.epoch)).to_degrees();
            let sigma = nalgebra::ComplexField::sqrt(att.covariance.trace().max(0.0)).to_degrees();
            say!("realtime ", front_end.name(), ": epoch ", att.epoch, " source ", att.source, " error ", fixed(e, 4), " deg (1 sigma ", fixed(sigma, 4), " deg)");
        }
        if out.counted_ms >= COUNT_MS {
            break;
        }
        if out.fine_at.is_none() && e0 >= WARM_UP_MAX_MS {
            say!("realtime ", front_end.name(), ": no fine attitude after ", e0, " ms");
            break;
        }
    }
    let att = rx.attitude();
    out.source = att.source;
    out.error_deg = att.q_rb.angle_to(&synth.truth(att.epoch)).to_degrees();
    out.regions = (first_region.unwrap_or(0), last_region);
    out.pass = detected == SKY.len()
        && out.fine_at.is_some()
        && out.counted_ms >= COUNT_MS
        && att.source == AttitudeSource::Fine
        && out.error_deg.is_finite()
        && out.error_deg <= LIMIT_DEG
        && refusals == 0;
    let cn0 = rx.channels().map(|c| c.cn0_dbhz).fold(0.0f32, |a, c| a + c) / rx.channels().count().max(1) as f32;
    say!(
        "realtime ",
        front_end.name(),
        ": ",
        detected,
        " of ",
        SKY.len(),
        " satellites acquired, ",
        rx.channels().filter(|c| c.locked).count(),
        " channels locked (mean C/N0 ",
        fixed(cn0, 1),
        " dB-Hz), ",
        total.observations,
        " observations, ",
        total.late,
        " late, ",
        total.without_aiding,
        " without aiding, ",
        total.released,
        " channels released, ",
        rx.receiver().deferred_overruns(),
        " deferred overruns (",
        rx.check_overruns(),
        " of the checks), ",
        refusals,
        " calls refused"
    );
    out
}
