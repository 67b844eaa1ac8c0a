//! The run's options, from the semihosting command line.
//!
//! QEMU hands the words of `-semihosting-config enable=on,target=native,arg=<name>,arg=<word>…`
//! (or, without `arg=`, the kernel's path and `-append`) to `SYS_GET_CMDLINE`. One word is
//! understood:
//!
//! * `wrong-expected`: every expected value is perturbed (the self-check's host results and
//!   truths, `realtime`'s truth rotated by 1°), so the run must fail. `.ci/run` proves each
//!   gate can fail by running the same ELF again with it: no second build, and the same code
//!   and instruction counts as the passing run.
//!
//! [`read`] asks the host once, at the start of `main`; the answer is kept in a static, so the
//! gates read a flag, not the host. Without a host (a board without a debugger) the
//! semihosting call halts, as every `hprintln!` of these firmwares does.

use core::sync::atomic::{AtomicBool, Ordering};

use cortex_m_semihosting::{nr, syscall1};
use gnss_attitude::geometry::Quaternion;
use nalgebra::Vector3;

/// The word that perturbs the expected values.
const WRONG_EXPECTED: &[u8] = b"wrong-expected";

/// Bytes of the command line read (a longer line is refused by the host: no option then).
const LINE_CAPACITY: usize = 128;

static WRONG_EXPECTED_REQUESTED: AtomicBool = AtomicBool::new(false);

/// Reads the semihosting command line and keeps what it asks for. Call once, first in `main`.
pub fn read() {
    let mut line = [0u8; LINE_CAPACITY];
    let length = command_line(&mut line);
    let words = line.get(..length).unwrap_or(&[]);
    let requested = words.split(|&b| b == b' ' || b == 0).any(|word| word == WRONG_EXPECTED);
    WRONG_EXPECTED_REQUESTED.store(requested, Ordering::Relaxed);
}

/// Whether this run perturbs every expected value (the word `wrong-expected` was on the
/// command line when [`read`] ran).
pub fn wrong_expected() -> bool {
    WRONG_EXPECTED_REQUESTED.load(Ordering::Relaxed)
}

/// Rotation of every truth attitude with `wrong-expected` on the command line, degrees.
pub const WRONG_TRUTH_DEG: f32 = 1.0;

/// The truth attitude `q` as a gate sees it: unchanged, or with `wrong-expected` on the
/// command line rotated by [`WRONG_TRUTH_DEG`] about body x.
pub fn gate_truth(q: Quaternion<f32>) -> Quaternion<f32> {
    if wrong_expected() {
        q * Quaternion::from_rotation_vector(&Vector3::new(WRONG_TRUTH_DEG.to_radians(), 0.0, 0.0))
    } else {
        q
    }
}

/// Copies the host's command line into `line`; returns its length in bytes (0 if the host has
/// none or refused: it did not fit).
fn command_line(line: &mut [u8; LINE_CAPACITY]) -> usize {
    // The argument block of SYS_GET_CMDLINE: the buffer's address and its size; the host
    // replaces the size with the length it wrote (without the terminating zero).
    let mut block = [line.as_mut_ptr() as usize, LINE_CAPACITY];
    // SAFETY: SYS_GET_CMDLINE (0x15) takes the address of a two-word block {buffer, size}. The
    // host writes at most `size` bytes into `line` (a live, exclusively borrowed array of that
    // size) and one word into `block[1]` (a live local); both outlive the call, which returns
    // before either is read. The `bkpt` asm is not `nomem`, so the compiler assumes the writes.
    let status = unsafe { syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    if status == 0 {
        block[1].min(LINE_CAPACITY)
    } else {
        0
    }
}
