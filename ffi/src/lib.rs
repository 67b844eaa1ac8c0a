//! C ABI of `gnss-attitude`: the receiver for flight software written in C.
//!
//! * **No allocator.** Every object lives in storage the caller provides: [`GaReceiver`]
//!   (the attitude receiver, from observations) and [`GaSampleReceiver`] (the same from raw
//!   samples) are opaque arrays of `uint64_t` of a documented size, so C can put them in a
//!   static or a linker section. Their sizes and alignments are checked against the Rust
//!   types at compile time.
//! * **Status codes.** Every function returns a [`GaStatus`]; outputs go through pointers.
//!   The cause of an object's last failure stays in its storage ([`ga_receiver_last_error`]).
//! * **No unwinding.** The core is panic-free (the firmware's panic-never proof links it);
//!   the staticlib profiles abort on panic, every function is `extern "C"` (a panic cannot
//!   cross it: Rust aborts), and on bare-metal targets the panic handler is a permanently
//!   undefined instruction (a HardFault the flight software's fault handler sees).
//! * **Mirrors.** `#[repr(C)]` copies of the configuration, observation, aiding, attitude,
//!   health and event types ([`types`]), each with its conversion next to it: a field added
//!   to the core is one field and one line here, and `cbindgen` regenerates the header
//!   (`include/gnss_attitude.h`).
//!
//! Objects are not shared between threads by the library: calls on one object must not run
//! concurrently (an interrupt that pushes samples and a task that reads the attitude need a
//! lock or a queue around them); different objects are independent. No global state.
//!
//! `no_std` everywhere. On hosted targets (Linux, for the tests and the host C example) the
//! crate links `std` only to get its panic runtime into the staticlib; it uses nothing of it.
#![no_std]
#![deny(missing_docs)]
#![deny(clippy::undocumented_unsafe_blocks)]
#![warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used))]

#[cfg(not(target_os = "none"))]
extern crate std;

pub mod example;
pub mod formats;
mod ptr;
pub mod receiver;
pub mod samples;
pub mod status;
pub mod types;

pub use example::*;
pub use formats::*;
pub use receiver::*;
pub use samples::*;
pub use status::*;
pub use types::*;

/// Version of this C ABI: bumped when a mirror or a signature changes incompatibly (a field
/// added to a mirror is such a change: C code must be rebuilt against the new header). 2: the
/// receiver storage grew to 10 KiB (`GA_RECEIVER_WORDS` 1280) for the deferred stages.
pub const GA_ABI_VERSION: u32 = 2;

/// The ABI version the library was built with (compare with [`GA_ABI_VERSION`] of the header
/// the C code was compiled against).
#[no_mangle]
pub extern "C" fn ga_abi_version() -> u32 {
    GA_ABI_VERSION
}

// Bare metal: the staticlib needs a panic handler. The core cannot panic (proved by the
// firmware's panic-never link); should one ever be reached, stop with a fault.
#[cfg(all(
    target_os = "none",
    not(feature = "external-panic-handler"),
    not(feature = "panic-never")
))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    loop {
        #[cfg(target_arch = "arm")]
        // SAFETY: `udf` only raises the UsageFault/HardFault exception; it touches no memory
        // and the loop never returns either way.
        unsafe {
            core::arch::asm!("udf #0xfe", options(nomem, nostack));
        }
        core::hint::spin_loop();
    }
}

#[cfg(all(target_os = "none", feature = "panic-never"))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    extern "C" {
        /// Deliberately undefined: a surviving panic path fails the link.
        fn gnss_attitude_ffi_panic_path_survived() -> !;
    }
    // SAFETY: never executes in a linked binary: the symbol does not exist, so the link
    // fails whenever this call is reachable.
    unsafe { gnss_attitude_ffi_panic_path_survived() }
}

#[cfg(test)]
mod size_report {
    #[test]
    fn sizes() {
        std::println!(
            "receiver {} sample {} flight {}",
            crate::ga_receiver_used_size(),
            crate::ga_sample_receiver_used_size(),
            core::mem::size_of::<gnss_attitude::receiver::example::ExampleFlight>()
        );
    }
}
