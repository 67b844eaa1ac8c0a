//! Bit-parallel correlation of 1- and 2-bit samples: 32 samples per `u32` operation, XOR for
//! the sign products, population counts for the sums.
//!
//! The front ends this crate targets (NT1065, MAX2769) deliver 1- and 2-bit sign/magnitude
//! samples. Instead of decoding them to `i8` and multiplying ([`Correlator`]), this module
//! keeps them as bits:
//!
//! ```text
//! front-end bytes ──PlaneBuffer::pack_bytes──▶ bit planes per antenna (once per block,
//!   (sm2, sm2iq, bit1, mc2xN; or i8)            shared by every satellite)
//!                                                    │ BitBlock (+ CodeTable of the rate)
//!                                                    ▼
//!   per satellite: BitCorrelator ── one carrier NCO, one code NCO for all antennas
//!     replica words per 32 samples: carrier signs (and zero masks), prompt code string,
//!     early/late/noise as shifted windows of it ── per antenna: stream words, XOR with the
//!     tap's code words, SWAR population counts ──▶ EpochCorrelations<A> every code period
//! ```
//!
//! [`BitCorrelator`] has the interface and output of the `i8` [`Correlator`]: the same NCO
//! setters, [`BitCorrelator::run`] stops at the end of each code period (1 ms) whatever the
//! block boundaries, and the [`EpochCorrelations`] it returns carry the same stamps (first
//! sample, code and carrier phase at it, sample count, completeness) and the same taps (early,
//! prompt, late, noise; prompt only on the slaved antennas with [`SlaveTaps::Prompt`]). Only
//! the scale of the taps differs (below). Everything is integer and exact: [`ScalarReference`]
//! computes the same sums one sample at a time, and the property tests
//! (`tests/bitwise_props.rs`) check that the two agree bit for bit.
//!
//! Both implement [`Correlate`](super::Correlate): a tracking
//! [`Channel`](crate::tracking::Channel) or a
//! [`SampleReceiver`](crate::receiver::SampleReceiver) runs on either (`with_settings` and a
//! [`BitSettings`](super::BitSettings)), reading [`BitBlock`]s instead of
//! [`SampleBlock`](super::SampleBlock)s; the acquisition searches the reference antenna's
//! planes as they are ([`SearchSamples::Planes`](crate::tracking::SearchSamples::Planes);
//! [`PlaneBuffer::append`] collects the search's milliseconds block by block).
//!
//! # Word layout
//! Sample `32·w + k` of a block is bit `k` of word `w` ([`planes`]). Per antenna there is a
//! sign plane of I (bit set: negative), for 2-bit samples a magnitude plane (bit set: `|x| = 3`,
//! else 1), and for complex samples the same for Q. A 1-bit sample is `±1`, a 2-bit sample
//! `±1, ±3`, the values [`SampleFormat::decode`](super::SampleFormat::decode) gives. The
//! replica words use the same layout: bit `k` of a carrier word is the carrier at sample
//! `32·w + k`, bit `k` of a code word the chip there (set: `−1`).
//!
//! # The replica
//! * **Carrier** ([`carrier`]): the exact 32-bit NCO phase of every sample, quantized to
//!   [`CarrierLevels::Two`] (`c, s ∈ {±1}`: the quadrant's signs, four phases) or
//!   [`CarrierLevels::Three`] (`c, s ∈ {−1, 0, +1}`, a quarter of zeros each: eight phases).
//!   Words are made without a per-sample loop, from the crossings of the quadrant (octant)
//!   boundaries, one division per word.
//! * **Code** ([`code`]): the 32.32 code NCO anchors every byte (8 samples) exactly, rounded to
//!   the middle of a 1/256-chip bin; within the byte the samples advance by the nominal step.
//!   An 8 KiB [`CodeTable`] per sample rate expands five chips into eight samples per lookup.
//!   The replica is within 1/512 chip + 7·|step − nominal step| of the exact per-sample code
//!   phase (1.5·10⁻⁴ chip at a code Doppler of 5·10⁻⁵).
//! * **Taps**: early and late are the prompt string advanced and delayed by
//!   `d = round(early_late_offset_chips · f_s / f_chip)` whole samples (at least one:
//!   [`CorrelatorConfig::early_late_offset_samples`], as for the `i8` correlator: 1 sample =
//!   0.39 chip at 2.6 Msps with the default 0.5 chip); the noise tap is the prompt string
//!   delayed by `D_n = round((q + ½)·f_s/f_chip)` samples, `q` the PRN's quiet offset
//!   ([`quiet_offset_chips`](super::ca_code::quiet_offset_chips)): a delay inside
//!   `[q, q + 1]` chips, where the autocorrelation is −1/1023 (16 samples for PRN 5 at
//!   2.6 Msps). All four are windows of one string, so a word costs four shifts, not four code
//!   generations.
//!
//! # The sums
//! Per tap and antenna the output is `I + jQ = Σ_k x_k · (c_k − j s_k) · T_k` over the code
//! period (`x = x_I + j x_Q` or real `x`, `T = ±1` the tap's chip), as for the `i8` correlator.
//! It is assembled from *streams*: `±1` products whose sum is `n − 2·popcount` over their
//! support (the kernel's documentation in the source has the table of streams). For complex samples and the 2-level
//! carrier the mixing is rotated by 45° (`X = I + Q`, `Y = I − Q`): each sample contributes one
//! of its components to each, so a tap costs two population counts per word instead of four.
//! A 2-bit sample is `2·(−1)^σ − (−1)^{σ⊕m}`, two 1-bit streams. Streams per tap:
//!
//! | samples | 2-level carrier | 3-level carrier |
//! |---|---|---|
//! | 1-bit complex | 2 | 4 |
//! | 2-bit complex | 4 | 8 |
//! | 1-bit real | 2 | 2 (masked) |
//! | 2-bit real | 4 | 4 (masked) |
//!
//! Population counts are SWAR with deferred reduction: 4-bit counts summed over three words,
//! 8-bit counts over a chunk of 30 words, one final fold per chunk (on hosts the vectorizer
//! makes SIMD population counts of the same integers).
//!
//! # Overflow analysis
//! An integration holds at most [`MAX_SAMPLES_PER_EPOCH`](super::correlator::MAX_SAMPLES_PER_EPOCH)
//! `= 65 536` samples (the correlator refuses code rates that make it longer). A stream's
//! population count is at most the samples integrated, `< 2¹⁷`, kept in `u32`; inside a chunk
//! the 8-bit counters reach at most `8 · 30 = 240 < 256` and the 4-bit counters `3 · 4 = 12 <
//! 16`. An output term is at most `|x_I c| + |x_Q s| ≤ 6` per sample (2-bit complex), so
//! `|I|, |Q| ≤ 6 · 65 536 < 2¹⁹`: every `i32` combination is exact. No input can overflow.
//!
//! # Scale of the outputs against the `i8` correlator
//! The `i8` correlator's taps are `127 · Σ x·e^{−jφ}·T` with `x` in `i8` units; these are
//! `Σ x_q·r*·T` with `x_q ∈ {±1}` (1-bit) or `{±1, ±3}` (2-bit) and the quantized replica
//! `r = c + js` of magnitude `√2` (2-level) or `1`/`√2` (3-level). A tap's noise power is
//! `E|N|² = n · E|x_q|² · E|r|²`: for 1-bit complex samples and the 2-level carrier `4n`
//! (`2n` per component), for 2-bit samples with the magnitude threshold at 1σ
//! (`P(|x| > σ) = 0.317`) `E|x_q|² = 2 · 3.54`. Ratios of taps (the discriminators, C/N0 from
//! the prompt and noise taps, the phase-lock indicator, inter-antenna phases) are unaffected;
//! the signal-to-noise ratio is lower by the quantization loss, measured in
//! `tests/bitwise_signal.rs` on synthesized signals against the `i8` path (complex 2.6 Msps,
//! 45 dB-Hz): 1-bit 3.1 dB (2-level carrier) / 2.4 dB (3-level), 2-bit 1.7 / 1.0 dB (theory
//! 2.9 / 2.3 and 1.5 / 0.9 dB).
//!
//! # Memory and cost
//! A [`BitCorrelator`] holds its NCOs, accumulators and the extended code (136 B):
//! `size_of::<BitCorrelator<3>>()` is 0.7 KiB. Its chunk loop's words (replica and stream
//! words of 30 words, 3.3 KiB) live in a [`BitScratch`] passed to [`BitCorrelator::run_in`],
//! one for all the correlators that run in turn (a
//! [`SampleReceiver`](crate::receiver::SampleReceiver) keeps one for its channels). The
//! [`CodeTable`] (8 KiB) is shared by every correlator of a front end through the blocks. Planes cost 4 bytes per 32 samples and
//! plane. Code: each of the eight kernels (complex or real IF × 1- or 2-bit × 2- or
//! 3-level carrier) is 1.1–1.8 KB of Cortex-M4 code; `BitCorrelator<A, KERNELS>` compiles in
//! only the [`kernel_bit`]s of `KERNELS` (default [`ALL_KERNELS`]), e.g.
//! [`COMPLEX_TWO_LEVEL_KERNELS`] for a complex front end (firmware `realtime`: 11.8 KB less
//! flash), and refuses the other formats at construction. Measured costs (Cortex-M4F instruction counts of the firmware's budget regions, host
//! times of `benches/correlator.rs`) are printed by `.ci/run`: on the M4F, 3 antennas ×
//! 1 satellite at 2.6 Msps complex with prompt-only slaves cost 4.16 instructions per
//! sample·channel for 1-bit samples and the 2-level carrier, 6.26 for 2-bit samples (3-level
//! carrier: 6.86 / 10.58; the `i8` correlator: 46.8). Of the 1-bit figure the per-antenna
//! XOR/popcount kernel is 55 %, the code replica (four byte lookups per prompt word, four tap
//! windows) 27 %, the carrier words 11 % (docs/METHODS.md has the profile).
//!
//! [`Correlator`]: super::Correlator
//! [`EpochCorrelations`]: super::EpochCorrelations
//! [`SlaveTaps::Prompt`]: super::SlaveTaps::Prompt
//! [`CorrelatorConfig::early_late_offset_samples`]: super::CorrelatorConfig::early_late_offset_samples

pub mod block;
pub mod carrier;
pub mod code;
pub mod correlator;
mod kernel;
pub mod planes;
pub mod reference;
pub mod selftest;

pub use block::BitBlock;
pub use carrier::CarrierLevels;
pub use code::CodeTable;
pub use correlator::{
    kernel_bit, BitCorrelator, BitCorrelatorConfig, BitCorrelatorError, BitScratch, ALL_KERNELS,
    COMPLEX_TWO_LEVEL_KERNELS,
};
pub use planes::{AntennaPlanes, PlaneBuffer, PlaneError, PlaneFormat, Resolution};
pub use reference::ScalarReference;
