//! The whole receiver in real time? `SampleReceiver` (acquisition, 8 tracking channels over
//! 3 antennas, adapter, `AttitudeReceiver` with a gyro) on samples synthesized on the target,
//! for a 1-bit and a 2-bit front end, counted by QEMU's `insnmark` plugin (issue 18, item 4).
//!
//! Per front end ([`frontend::FrontEnd`]):
//!
//! 1. the samples of 3 antennas × 8 satellites (2.6 Msps complex, 45 dB-Hz, the example
//!    flight's attitude, lines of sight and line biases as the embedded truth) are synthesized
//!    in 1 ms blocks as the front end's `bit1iq` or `sm2iq` bytes ([`synth`], [`frontend`]), outside the
//!    counted region;
//! 2. acquisition before the counted region: every PRN searched (`SampleReceiver::search`, ±2.5
//!    kHz, 6 ms non-coherent + the 6 ms dwell) on the reference antenna's first 12 ms; the
//!    receiver gets the lines of sight as its aiding (every 100 ms) and the gyro's increments;
//! 3. the receiver runs the bit-parallel correlators (`SampleReceiver<8, 1024,
//!    BitCorrelator<3, COMPLEX_TWO_LEVEL_KERNELS>>`: only this front end's kernels linked, 1- or
//!    2-bit planes, [`run::CARRIER`]; E, P, L and N on the reference
//!    antenna, the prompt on the other two) with its block and window stages and its
//!    channels' cross-correlation checks deferred (`set_deferred_stages`,
//!    `set_deferred_checks`); warm-up until the attitude comes from the fine
//!    filter, [`run::SETTLE_MS`] more, then [`run::COUNT_MS`] of blocks, each as three counted
//!    regions: the bytes packed into the antennas' bit planes (`PlaneBuffer::pack_bytes`),
//!    `push_samples` with the gyro increments that end in the block (the 1 ms path), and
//!    `SampleReceiver::run_deferred` (the main loop's work); the firmware prints which
//!    regions are that front end's, `.ci/run` sums the plugin's counts into instructions per
//!    1 ms, per stage;
//! 4. the verdict: fine attitude within [`run::LIMIT_DEG`] of the truth, or exit failure.
//!
//! Then flash, static RAM and the worst stack (painted at reset by cortex-m-rt's
//! `paint-stack`, repainted after the construction and after the acquisition to measure each
//! phase). Linked for QEMU's `mps2-an386` (feature `qemu-mps2`, 4 MiB RAM): the receiver's
//! construction (`SampleReceiver::with_settings`, by value: its frame is 53 KB, the receiver
//! 78 KB) and the acquisition (62 KB of `i8` samples beside the receiver) do not fit an
//! STM32F405's 128 KiB; the firmware prints what each phase needs against that target.
//!
//! Its reports go through [`say!`] ([`say`]), not `core::fmt` (15 KiB of flash), and the code
//! outside the counted regions (the synthesizer, the reports, the sky search) is built for
//! size, `#[optimize(size)]`: the firmware fits the 256 KiB flash target (`.ci/run` prints it).
#![no_std]
// (nightly, as build-std already needs: `#[optimize(size)]` on the code outside the counts)
#![feature(optimize_attribute)]
#![no_main]

mod cmdline;
// (first: its `say!` is in scope in the modules below)
#[macro_use]
#[path = "realtime/say.rs"]
mod say;
#[path = "realtime/frontend.rs"]
mod frontend;
#[path = "realtime/memory.rs"]
mod memory;
#[path = "realtime/fixed.rs"]
mod fixed;
#[path = "realtime/run.rs"]
mod run;
#[path = "realtime/synth.rs"]
mod synth;

use cortex_m_rt::{entry, exception, ExceptionFrame};
use cortex_m_semihosting::debug;

use frontend::FrontEnd;

#[entry]
fn main() -> ! {
    cmdline::read();
    say!(
        "realtime: SampleReceiver<",
        run::CHANNELS,
        ", 1024, BitCorrelator<3, COMPLEX_TWO_LEVEL_KERNELS>> ",
        core::mem::size_of::<run::Front>(),
        " B (",
        run::CARRIER,
        " carrier), 3 antennas x 8 satellites, 2.6 Msps complex from bit1iq / sm2iq bytes, ",
        run::BLOCK_MS,
        " ms blocks, ",
        run::COUNT_MS,
        " ms counted per front end"
    );
    say!(
        "realtime sizes: Acquisition<1024> ",
        core::mem::size_of::<gnss_attitude::tracking::Acquisition<1024>>(),
        " B, Channel<3, BitCorrelator<3, ..>> ",
        core::mem::size_of::<gnss_attitude::tracking::Channel<3, run::Correlator>>(),
        " B (x 8), AttitudeReceiver ",
        core::mem::size_of::<gnss_attitude::receiver::AttitudeReceiver>(),
        " B, ObservationAdapter ",
        core::mem::size_of::<gnss_attitude::receiver::ObservationAdapter>(),
        " B"
    );
    let mut all = true;
    let mut stacks = [0usize; 3];
    for front_end in FrontEnd::ALL {
        // (each front end's stack measured alone: the previous run's marks painted over)
        memory::paint_below();
        let o = run::run(front_end);
        say!(
            "realtime ",
            front_end.name(),
            ": regions ",
            o.regions.0,
            "..=",
            o.regions.1,
            " count ",
            o.counted_ms,
            " ms, 3 regions per ms (pack the bytes into planes; push_samples + gyro increments; run_deferred); fine from epoch ",
            o.fine_at,
            "; final attitude ",
            o.source,
            ", error ",
            fixed::fixed(o.error_deg, 4),
            " deg (limit ",
            fixed::fixed(run::LIMIT_DEG, 2),
            " deg): ",
            if o.pass { "PASS" } else { "FAIL" }
        );
        all &= o.pass;
        for (s, o) in stacks.iter_mut().zip([o.construction_stack, o.acquisition_stack, o.stream_stack]) {
            *s = (*s).max(o);
        }
    }
    let (flash, ram) = memory::flash_and_static();
    let worst = stacks[0].max(stacks[1]).max(stacks[2]);
    say!(
        "realtime memory: flash ",
        flash,
        " B, static RAM ",
        ram,
        " B, worst stack ",
        worst,
        " B (construction, SampleReceiver::with_settings: ",
        stacks[0],
        " B; acquisition: ",
        stacks[1],
        " B; tracking, the receiver's ",
        core::mem::size_of::<run::Front>(),
        " B + the 1 ms block's bytes and planes + synthesis + push_samples + run_deferred: ",
        stacks[2],
        " B), RAM (static + worst stack) ",
        ram + worst,
        " B"
    );
    if all {
        say!("realtime: all PASS");
        debug::exit(debug::EXIT_SUCCESS);
    } else {
        say!("realtime: FAILED");
        debug::exit(debug::EXIT_FAILURE);
    }
    loop {
        cortex_m::asm::nop();
    }
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    say!("HardFault at pc ", say::Hex(frame.pc()));
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::nop();
    }
}

/// The panic's place (its message would need `core::fmt`, [`say`]).
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    match info.location() {
        Some(at) => say!("panic at ", at.file(), ":", at.line(), ":", at.column()),
        None => say!("panic"),
    }
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::nop();
    }
}
