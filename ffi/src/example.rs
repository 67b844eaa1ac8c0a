//! The deterministic example flight of [`gnss_attitude::receiver::example`] for C: the same
//! observations, aiding and gyro increments, so that a C program runs the very scenario the
//! Rust documentation, tests and firmware budgets run, and checks its attitude against the
//! truth.

use core::mem::{align_of, size_of};

use gnss_attitude::receiver::example::{ExampleFlight, EPOCH_S, GYRO_H};

use crate::ptr;
use crate::receiver::GA_STORAGE_ALIGN;
use crate::status::GaStatus;
use crate::types::{GaAiding, GaConfig, GaObservation};

/// 64-bit words of a [`GaExampleFlight`].
pub const GA_EXAMPLE_FLIGHT_WORDS: usize = 32;

/// Storage of one example flight (private content).
#[repr(C)]
pub struct GaExampleFlight {
    /// Private.
    pub opaque: [u64; GA_EXAMPLE_FLIGHT_WORDS],
}

#[repr(C)]
struct Flight {
    magic: u32,
    flight: ExampleFlight,
}

const MAGIC_FLIGHT: u32 = 0x4741_4558; // "GAEX"

const _: () = assert!(size_of::<Flight>() <= size_of::<GaExampleFlight>());
const _: () = assert!(align_of::<Flight>() <= GA_STORAGE_ALIGN);

/// Epochs between two gyro increments of the example flight (10: 100 Hz gyro, 1 ms epochs).
pub const GA_EXAMPLE_EPOCHS_PER_GYRO: u32 = 10;
/// Epochs between two aiding updates of the example flight.
pub const GA_EXAMPLE_EPOCHS_PER_AIDING: u32 = 100;

const _: () = assert!((GYRO_H / EPOCH_S + 0.5) as u32 == GA_EXAMPLE_EPOCHS_PER_GYRO);

/// The flight in storage at `p`.
///
/// # Safety
/// `p` is null or points to a zeroed or initialized [`GaExampleFlight`] nothing else uses
/// during the call.
unsafe fn flight<'a>(p: *mut GaExampleFlight) -> Result<&'a mut ExampleFlight, GaStatus> {
    if p.is_null() {
        return Err(GaStatus::NullPointer);
    }
    if !p.is_aligned() {
        return Err(GaStatus::Misaligned);
    }
    let f = p.cast::<Flight>();
    // SAFETY: non-null, aligned, initialized memory (zeroed or written by the init) by the
    // caller's contract; the magic is a plain u32.
    let magic = unsafe { (*f).magic };
    if magic != MAGIC_FLIGHT {
        return Err(GaStatus::NotInitialized);
    }
    // SAFETY: the magic is written only by `ga_example_flight_init` with a valid flight.
    Ok(unsafe { &mut (*f).flight })
}

/// Starts the example flight with the noise seed `seed` (the Rust examples use 7).
///
/// # Safety
/// `storage` points to a [`GaExampleFlight`] no other call uses meanwhile.
#[no_mangle]
pub unsafe extern "C" fn ga_example_flight_init(
    storage: *mut GaExampleFlight,
    seed: u64,
) -> GaStatus {
    if storage.is_null() {
        return GaStatus::NullPointer;
    }
    if !storage.is_aligned() {
        return GaStatus::Misaligned;
    }
    let value = Flight {
        magic: MAGIC_FLIGHT,
        flight: ExampleFlight::new(seed),
    };
    // SAFETY: non-null, aligned, large enough (compile-time assert), exclusive.
    unsafe { storage.cast::<Flight>().write(value) };
    GaStatus::Ok
}

/// The example's receiver configuration (`with_gyro` non-zero: with its 100 Hz gyro).
///
/// # Safety
/// `out` is writable.
#[no_mangle]
pub unsafe extern "C" fn ga_example_config(with_gyro: u8, out: *mut GaConfig) -> GaStatus {
    let c = ExampleFlight::config(with_gyro != 0);
    // SAFETY: the caller's contract.
    match unsafe { ptr::write(out, GaConfig::from(&c)) } {
        Ok(()) => GaStatus::Ok,
        Err(s) => s,
    }
}

/// The aiding valid from `epoch` into `out` (room for `capacity`), its count in `*count`.
///
/// # Safety
/// `storage` initialized by [`ga_example_flight_init`]; `out` points to `capacity` writable
/// [`GaAiding`]; `count` writable.
#[no_mangle]
pub unsafe extern "C" fn ga_example_aiding(
    storage: *mut GaExampleFlight,
    epoch: u64,
    out: *mut GaAiding,
    capacity: usize,
    count: *mut usize,
) -> GaStatus {
    // SAFETY: the caller's contract.
    let f = match unsafe { flight(storage) } {
        Ok(f) => f,
        Err(s) => return s,
    };
    let list = f.aiding(epoch);
    // SAFETY: the caller's contract.
    unsafe {
        write_list(
            list.iter().map(GaAiding::from),
            list.len(),
            out,
            capacity,
            count,
        )
    }
}

/// The observations of `epoch` (eight satellites) into `out` (room for `capacity`), their
/// count in `*count`. Advances the flight's noise generator: call once per epoch, in order.
///
/// # Safety
/// As [`ga_example_aiding`], for [`GaObservation`].
#[no_mangle]
pub unsafe extern "C" fn ga_example_observations(
    storage: *mut GaExampleFlight,
    epoch: u64,
    out: *mut GaObservation,
    capacity: usize,
    count: *mut usize,
) -> GaStatus {
    // SAFETY: the caller's contract.
    let f = match unsafe { flight(storage) } {
        Ok(f) => f,
        Err(s) => return s,
    };
    let list = f.observations(epoch);
    // SAFETY: the caller's contract.
    unsafe {
        write_list(
            list.iter().map(GaObservation::from),
            list.len(),
            out,
            capacity,
            count,
        )
    }
}

/// The gyro increment of sample `n` (over `[n h, (n + 1) h]`), rad.
///
/// # Safety
/// `storage` initialized; `out` points to 3 writable floats.
#[no_mangle]
pub unsafe extern "C" fn ga_example_gyro_increment(
    storage: *mut GaExampleFlight,
    n: u64,
    out: *mut f32,
) -> GaStatus {
    // SAFETY: the caller's contract.
    let f = match unsafe { flight(storage) } {
        Ok(f) => f,
        Err(s) => return s,
    };
    // SAFETY: the caller's contract.
    match unsafe { ptr::write_array(out, f.gyro_increment(n)) } {
        Ok(()) => GaStatus::Ok,
        Err(s) => s,
    }
}

/// The true attitude at the centre of `epoch` (`w, x, y, z`) and, when `attitude_q` is not
/// null, the angle between it and `attitude_q`, rad, into `*error_rad` (nullable).
///
/// # Safety
/// `storage` initialized; `q_out` points to 4 writable floats (nullable); `attitude_q` null
/// or 4 floats; `error_rad` null or writable.
#[no_mangle]
pub unsafe extern "C" fn ga_example_truth(
    storage: *mut GaExampleFlight,
    epoch: u64,
    q_out: *mut f32,
    attitude_q: *const f32,
    error_rad: *mut f32,
) -> GaStatus {
    // SAFETY: the caller's contract.
    let f = match unsafe { flight(storage) } {
        Ok(f) => f,
        Err(s) => return s,
    };
    let t = f.attitude(epoch);
    if !q_out.is_null() {
        // SAFETY: non-null, writable by the caller's contract.
        if let Err(s) = unsafe { ptr::write_array(q_out, [t.w, t.x, t.y, t.z]) } {
            return s;
        }
    }
    if !attitude_q.is_null() && !error_rad.is_null() {
        // SAFETY: non-null, readable by the caller's contract.
        let [w, x, y, z] = match unsafe { ptr::array::<f32, 4>(attitude_q) } {
            Ok(q) => q,
            Err(s) => return s,
        };
        let q = gnss_attitude::geometry::Quaternion::new(w, x, y, z);
        // SAFETY: non-null, writable by the caller's contract.
        if let Err(s) = unsafe { ptr::write(error_rad, q.angle_to(&t)) } {
            return s;
        }
    }
    GaStatus::Ok
}

/// Copies `len` items into `out[..capacity]` and the count into `*count`.
///
/// # Safety
/// `out` points to `capacity` writable `T`; `count` writable.
unsafe fn write_list<T>(
    items: impl Iterator<Item = T>,
    len: usize,
    out: *mut T,
    capacity: usize,
    count: *mut usize,
) -> GaStatus {
    if len > capacity {
        return GaStatus::BufferTooShort;
    }
    if out.is_null() && len > 0 {
        return GaStatus::NullPointer;
    }
    if !out.is_aligned() {
        return GaStatus::Misaligned;
    }
    for (k, item) in items.take(capacity).enumerate() {
        // SAFETY: non-null, aligned, `k < len ≤ capacity`, writable by the caller's contract.
        unsafe { out.add(k).write(item) };
    }
    // SAFETY: the caller's contract.
    match unsafe { ptr::write(count, len) } {
        Ok(()) => GaStatus::Ok,
        Err(s) => s,
    }
}
