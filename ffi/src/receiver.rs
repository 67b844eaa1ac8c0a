//! The attitude receiver in caller-provided storage, and the calls of the flight loop.
//!
//! ```c
//! static GaReceiver rx;                       /* zero-initialized, GA_RECEIVER_SIZE bytes */
//! GaConfig cfg;
//! ga_config_gps_l1(antennas, &gyro, &cfg);    /* defaults; change fields as needed */
//! if (ga_receiver_init(&rx, &cfg) != GA_OK) { ... }
//! ga_receiver_set_aiding(&rx, aiding, n);     /* lines of sight, from navigation */
//! ga_receiver_push_gyro_increment(&rx, theta);/* every gyro sample */
//! ga_receiver_push_observation(&rx, k, &obs); /* every satellite, every 1 ms epoch */
//! ga_receiver_attitude(&rx, &att);            /* whenever needed */
//! while (ga_receiver_pop_event(&rx, &ev) == GA_OK) { log(ev); }
//! ```

use core::mem::{align_of, size_of};

use gnss_attitude::receiver::{AttitudeReceiver, SatelliteAiding, MAX_SATELLITES};

use crate::ptr;
use crate::status::{Failure, GaCall, GaError, GaStatus};
use crate::types::{GaAiding, GaAttitude, GaConfig, GaEvent, GaEventKind, GaObservation};

/// 64-bit words of a [`GaReceiver`]'s storage.
pub const GA_RECEIVER_WORDS: usize = 1280;
/// Bytes of a [`GaReceiver`] (`GA_RECEIVER_WORDS × 8`): the receiver takes 7.2 KiB on a
/// 32-bit target and 8.3 KiB on a 64-bit host; the rest is room for fields to come.
pub const GA_RECEIVER_SIZE: usize = GA_RECEIVER_WORDS * 8;
/// Alignment of a [`GaReceiver`], bytes.
pub const GA_STORAGE_ALIGN: usize = 8;

/// Storage of one attitude receiver: place it anywhere (a static, a linker section, the
/// stack of a task with room), zero it or leave it to `ga_receiver_init`, and pass its
/// address to every call. Its content is private.
#[repr(C)]
pub struct GaReceiver {
    /// Private.
    pub opaque: [u64; GA_RECEIVER_WORDS],
}

/// Marks storage holding an initialized [`AttitudeReceiver`].
pub(crate) const MAGIC_ATTITUDE: u32 = 0x4741_5452; // "GATR"
/// Marks storage holding an initialized sample receiver.
pub(crate) const MAGIC_SAMPLES: u32 = 0x4741_5341; // "GASA"
/// Marks storage whose init failed (the header's error is valid, the object is not).
pub(crate) const MAGIC_FAILED: u32 = 0x4741_4641; // "GAFA"

/// What every object's storage starts with.
#[repr(C)]
#[derive(Clone, Copy)]
pub(crate) struct Header {
    pub(crate) magic: u32,
    pub(crate) last_error: GaError,
}

/// An object in its storage: the header, then the Rust value.
#[repr(C)]
pub(crate) struct Object<T> {
    pub(crate) header: Header,
    pub(crate) value: T,
}

// The storage holds the object on every target (checked at compile time: a core type that
// grows past the reserve stops the build here, and the lead raises GA_RECEIVER_WORDS).
const _: () = assert!(size_of::<Object<AttitudeReceiver>>() <= GA_RECEIVER_SIZE);
const _: () = assert!(align_of::<Object<AttitudeReceiver>>() <= GA_STORAGE_ALIGN);
const _: () = assert!(size_of::<GaReceiver>() == GA_RECEIVER_SIZE);
const _: () = assert!(align_of::<GaReceiver>() == GA_STORAGE_ALIGN);

/// Bytes the receiver object really uses on this target (at most [`GA_RECEIVER_SIZE`]).
#[no_mangle]
pub extern "C" fn ga_receiver_used_size() -> usize {
    size_of::<Object<AttitudeReceiver>>()
}

/// Writes an initialized object into storage at `p`.
///
/// # Safety
/// `p` is valid for writes of `Object<T>`, aligned, and not referenced elsewhere.
pub(crate) unsafe fn emplace<T>(p: *mut Object<T>, magic: u32, value: T) {
    // SAFETY: by the caller's contract (valid, aligned, exclusive); whatever the storage
    // held before has no drop glue that matters (the core types own no resources).
    unsafe {
        p.write(Object {
            header: Header {
                magic,
                last_error: GaError::NONE,
            },
            value,
        });
    }
}

/// Records a failed init in the header of storage at `p` (its value stays unusable).
///
/// # Safety
/// `p` is valid for writes of a [`Header`], aligned, and not referenced elsewhere.
pub(crate) unsafe fn mark_failed(p: *mut Header, record: GaError) {
    // SAFETY: by the caller's contract.
    unsafe {
        p.write(Header {
            magic: MAGIC_FAILED,
            last_error: record,
        });
    }
}

/// The header of storage at `p`, checked for null and alignment.
///
/// # Safety
/// `p` is null or points to storage of at least a [`Header`] that was zeroed or written by
/// an init, and that no Rust reference aliases during the call.
pub(crate) unsafe fn header<'a>(p: *mut Header) -> Result<&'a mut Header, GaStatus> {
    if p.is_null() {
        return Err(GaStatus::NullPointer);
    }
    if !p.cast::<u64>().is_aligned() {
        return Err(GaStatus::Misaligned);
    }
    // SAFETY: non-null, 8-aligned (≥ the header's alignment), initialized (zeroed or
    // written by an init) and exclusive by the caller's contract.
    Ok(unsafe { &mut *p })
}

/// The receiver inside storage at `p`, whichever object holds it (attitude or sample
/// receiver), with its header.
///
/// # Safety
/// As [`header`]; storage whose magic says it holds an object was written by that object's
/// init and still holds it.
unsafe fn receiver<'a>(
    p: *mut GaReceiver,
) -> Result<(&'a mut Header, &'a mut AttitudeReceiver), GaStatus> {
    // SAFETY: the caller's contract.
    let magic = unsafe { header(p.cast::<Header>()) }?.magic;
    match magic {
        MAGIC_ATTITUDE => {
            // SAFETY: the magic is written only by `ga_receiver_init` together with a valid
            // `Object<AttitudeReceiver>` at this address (alignment checked by `header`).
            let o = unsafe { &mut *p.cast::<Object<AttitudeReceiver>>() };
            Ok((&mut o.header, &mut o.value))
        }
        MAGIC_SAMPLES => {
            // SAFETY: the magic is written only by `ga_sample_receiver_init` together with
            // a valid sample-receiver object at this address.
            let o = unsafe { &mut *p.cast::<Object<crate::samples::FfiSampleReceiver>>() };
            Ok((&mut o.header, o.value.receiver_mut()))
        }
        _ => Err(GaStatus::NotInitialized),
    }
}

/// Runs `f` on the receiver at `p`, records a failure in its header, returns the status.
///
/// # Safety
/// As [`receiver`].
unsafe fn with_receiver(
    p: *mut GaReceiver,
    f: impl FnOnce(&mut AttitudeReceiver) -> Result<GaStatus, Failure>,
) -> GaStatus {
    // SAFETY: the caller's contract.
    match unsafe { receiver(p) } {
        Err(status) => status,
        Ok((header, rx)) => match f(rx) {
            Ok(status) => status,
            Err(failure) => {
                header.last_error = failure.record;
                failure.status
            }
        },
    }
}

fn abi(call: GaCall) -> impl Fn(GaStatus) -> Failure {
    move |status| Failure::abi(status, call)
}

/// Fills `out` with the defaults of [`gnss_attitude::receiver::ReceiverConfig::gps_l1`] for
/// the antennas (`[antenna][axis]`, body axes, m) and the gyro (`gyro` null: no gyro).
///
/// # Safety
/// `antennas` points to 3 rows of 3 floats; `gyro` is null or points to a [`crate::GaGyroConfig`];
/// `out` is writable.
#[no_mangle]
pub unsafe extern "C" fn ga_config_gps_l1(
    antennas: *const [f32; 3],
    gyro: *const crate::GaGyroConfig,
    out: *mut GaConfig,
) -> GaStatus {
    // SAFETY: the caller's contract (null checked inside).
    let antennas = match unsafe { ptr::array::<[f32; 3], 3>(antennas) } {
        Ok(a) => a,
        Err(s) => return s,
    };
    let gyro = if gyro.is_null() {
        None
    } else {
        // SAFETY: non-null: points to a gyro configuration by the caller's contract.
        match unsafe { ptr::read(gyro) } {
            Ok(g) => Some(g.to_core()),
            Err(s) => return s,
        }
    };
    let c = gnss_attitude::receiver::ReceiverConfig::gps_l1(antennas, gyro);
    // SAFETY: the caller's contract.
    match unsafe { ptr::write(out, GaConfig::from(&c)) } {
        Ok(()) => GaStatus::Ok,
        Err(s) => s,
    }
}

/// Fills `out` with the defaults of a MEMS gyro sampled every `sample_interval_s`
/// ([`gnss_attitude::receiver::GyroConfig::mems`]); `pulse_weight_rad > 0` for a pulse-count
/// gyro, 0 for float increments.
///
/// # Safety
/// `out` is writable.
#[no_mangle]
pub unsafe extern "C" fn ga_gyro_config_mems(
    sample_interval_s: f32,
    pulse_weight_rad: f32,
    out: *mut crate::GaGyroConfig,
) -> GaStatus {
    let weight = (pulse_weight_rad > 0.0).then_some(pulse_weight_rad);
    let g = gnss_attitude::receiver::GyroConfig::mems(sample_interval_s, weight);
    // SAFETY: the caller's contract.
    match unsafe { ptr::write(out, crate::GaGyroConfig::from(&g)) } {
        Ok(()) => GaStatus::Ok,
        Err(s) => s,
    }
}

/// Builds a receiver from `config` in `storage` (any previous content is overwritten). On
/// failure the storage is marked failed: every call but [`ga_receiver_last_error`] then
/// returns `GA_STATUS_NOT_INITIALIZED`.
///
/// Stack: about 7.3 KiB on a Cortex-M4F beyond the caller's frame (the receiver is built on
/// the stack, then moved).
///
/// # Safety
/// `storage` points to a [`GaReceiver`] that no other call uses meanwhile; `config` points
/// to a [`GaConfig`].
#[no_mangle]
pub unsafe extern "C" fn ga_receiver_init(
    storage: *mut GaReceiver,
    config: *const GaConfig,
) -> GaStatus {
    if storage.is_null() {
        return GaStatus::NullPointer;
    }
    if !storage.is_aligned() {
        return GaStatus::Misaligned;
    }
    // SAFETY: the caller's contract (null checked inside).
    let built = unsafe { ptr::read(config) }
        .and_then(|c| c.to_core())
        .map_err(abi(GaCall::Init))
        .and_then(|c| AttitudeReceiver::new(c).map_err(|e| Failure::receiver(e, GaCall::Init, 0)));
    match built {
        Ok(rx) => {
            // SAFETY: non-null, aligned (checked above), GA_RECEIVER_SIZE bytes ≥ the object
            // (compile-time assert), exclusive by the caller's contract.
            unsafe {
                emplace(
                    storage.cast::<Object<AttitudeReceiver>>(),
                    MAGIC_ATTITUDE,
                    rx,
                )
            };
            GaStatus::Ok
        }
        Err(f) => {
            // SAFETY: as above, for the header only.
            unsafe { mark_failed(storage.cast::<Header>(), f.record) };
            f.status
        }
    }
}

/// Replaces the navigation aiding with `count` satellites (at most 12).
///
/// # Safety
/// `storage` as for [`ga_receiver_init`]; `aiding` points to `count` [`GaAiding`] (may be
/// null for `count = 0`).
#[no_mangle]
pub unsafe extern "C" fn ga_receiver_set_aiding(
    storage: *mut GaReceiver,
    aiding: *const GaAiding,
    count: usize,
) -> GaStatus {
    let call = GaCall::SetAiding;
    // SAFETY: the caller's contract.
    let list = unsafe { ptr::slice(aiding, count) };
    // SAFETY: the caller's contract.
    unsafe {
        with_receiver(storage, |rx| {
            let list = list.map_err(abi(call))?;
            let mut core = heapless::Vec::<SatelliteAiding, MAX_SATELLITES>::new();
            for a in list {
                core.push(a.to_core())
                    .map_err(|_| Failure::abi(GaStatus::TooManySatellites, call))?;
            }
            rx.set_aiding(&core)
                .map_err(|e| Failure::receiver(e, call, 0))?;
            Ok(GaStatus::Ok)
        })
    }
}

/// One satellite's observation of `epoch`.
///
/// # Safety
/// `storage` as for [`ga_receiver_init`]; `observation` points to a [`GaObservation`].
#[no_mangle]
pub unsafe extern "C" fn ga_receiver_push_observation(
    storage: *mut GaReceiver,
    epoch: u64,
    observation: *const GaObservation,
) -> GaStatus {
    let call = GaCall::PushObservation;
    // SAFETY: the caller's contract.
    let obs = unsafe { ptr::read(observation) };
    // SAFETY: the caller's contract.
    unsafe {
        with_receiver(storage, |rx| {
            let o = obs.map_err(abi(call))?.to_core();
            rx.push_observation(epoch, &o)
                .map_err(|e| Failure::receiver(e, call, epoch))?;
            Ok(GaStatus::Ok)
        })
    }
}

/// One gyro increment (rad, body axes) over the configured sample interval.
///
/// # Safety
/// `storage` as for [`ga_receiver_init`]; `theta` points to 3 floats.
#[no_mangle]
pub unsafe extern "C" fn ga_receiver_push_gyro_increment(
    storage: *mut GaReceiver,
    theta: *const f32,
) -> GaStatus {
    let call = GaCall::PushGyroIncrement;
    // SAFETY: the caller's contract.
    let theta = unsafe { ptr::array::<f32, 3>(theta) };
    // SAFETY: the caller's contract.
    unsafe {
        with_receiver(storage, |rx| {
            let t = theta.map_err(abi(call))?;
            rx.push_gyro_increment(&t)
                .map_err(|e| Failure::receiver(e, call, 0))?;
            Ok(GaStatus::Ok)
        })
    }
}

/// One gyro sample as signed pulse counts per axis (the gyro configuration's pulse weight).
///
/// # Safety
/// `storage` as for [`ga_receiver_init`]; `counts` points to 3 `int32_t`.
#[no_mangle]
pub unsafe extern "C" fn ga_receiver_push_gyro_pulses(
    storage: *mut GaReceiver,
    counts: *const i32,
) -> GaStatus {
    let call = GaCall::PushGyroPulses;
    // SAFETY: the caller's contract.
    let counts = unsafe { ptr::array::<i32, 3>(counts) };
    // SAFETY: the caller's contract.
    unsafe {
        with_receiver(storage, |rx| {
            let c = counts.map_err(abi(call))?;
            rx.push_gyro_pulses(c)
                .map_err(|e| Failure::receiver(e, call, 0))?;
            Ok(GaStatus::Ok)
        })
    }
}

/// Closes every open epoch up to and including `epoch` (steps the stages); observations two
/// epochs later close them too.
///
/// # Safety
/// `storage` as for [`ga_receiver_init`].
#[no_mangle]
pub unsafe extern "C" fn ga_receiver_close_through(
    storage: *mut GaReceiver,
    epoch: u64,
) -> GaStatus {
    // SAFETY: the caller's contract.
    unsafe {
        with_receiver(storage, |rx| {
            rx.close_through(epoch);
            Ok(GaStatus::Ok)
        })
    }
}

/// Moves the block and window stages out of the epoch path (`deferred` true): the epoch that
/// closes a block or a window only captures its single differences, and
/// [`ga_receiver_run_deferred`] runs the stages (call it from the main loop while the 1 ms
/// interrupt pushes observations). False (the default) runs them inside the epoch, and runs
/// any waiting work at once.
///
/// # Safety
/// `storage` as for [`ga_receiver_init`].
#[no_mangle]
pub unsafe extern "C" fn ga_receiver_set_deferred_stages(
    storage: *mut GaReceiver,
    deferred: bool,
) -> GaStatus {
    // SAFETY: the caller's contract.
    unsafe {
        with_receiver(storage, |rx| {
            rx.set_deferred_stages(deferred);
            Ok(GaStatus::Ok)
        })
    }
}

/// Runs the waiting block and window work (deferred mode); `*ran` tells whether there was
/// any. Call it within 20 ms of every closed block; work still waiting when the next block
/// closes is run by that epoch and counted ([`ga_receiver_deferred_overruns`]).
///
/// # Safety
/// `storage` as for [`ga_receiver_init`]; `ran` is writable.
#[no_mangle]
pub unsafe extern "C" fn ga_receiver_run_deferred(
    storage: *mut GaReceiver,
    ran: *mut bool,
) -> GaStatus {
    let call = GaCall::Output;
    // SAFETY: the caller's contract.
    unsafe {
        with_receiver(storage, |rx| {
            let any = rx.run_deferred();
            // (inside the caller's unsafe block) the caller's contract: `ran` is writable
            ptr::write(ran, any).map_err(abi(call))?;
            Ok(GaStatus::Ok)
        })
    }
}

/// Closings that found deferred work still waiting (run then, in the epoch path).
///
/// # Safety
/// `storage` as for [`ga_receiver_init`]; `out` is writable.
#[no_mangle]
pub unsafe extern "C" fn ga_receiver_deferred_overruns(
    storage: *mut GaReceiver,
    out: *mut u32,
) -> GaStatus {
    let call = GaCall::Output;
    // SAFETY: the caller's contract.
    unsafe {
        with_receiver(storage, |rx| {
            let n = rx.deferred_overruns();
            // (inside the caller's unsafe block) the caller's contract: `out` is writable
            ptr::write(out, n).map_err(abi(call))?;
            Ok(GaStatus::Ok)
        })
    }
}

/// The attitude now, with its covariance, source and health.
///
/// # Safety
/// `storage` as for [`ga_receiver_init`]; `out` is writable.
#[no_mangle]
pub unsafe extern "C" fn ga_receiver_attitude(
    storage: *mut GaReceiver,
    out: *mut GaAttitude,
) -> GaStatus {
    let call = GaCall::Output;
    // SAFETY: the caller's contract.
    unsafe {
        with_receiver(storage, |rx| {
            let a = GaAttitude::from(&rx.attitude());
            // (inside the caller's unsafe block) the caller's contract: `out` is writable and
            // not part of the receiver's storage
            ptr::write(out, a).map_err(abi(call))?;
            Ok(GaStatus::Ok)
        })
    }
}

/// The oldest queued event into `out`: `GA_STATUS_OK`, or `GA_STATUS_EMPTY` (and `out->kind` =
/// `GA_EVENT_KIND_NONE`) when none is queued.
///
/// # Safety
/// `storage` as for [`ga_receiver_init`]; `out` is writable.
#[no_mangle]
pub unsafe extern "C" fn ga_receiver_pop_event(
    storage: *mut GaReceiver,
    out: *mut GaEvent,
) -> GaStatus {
    let call = GaCall::Output;
    if out.is_null() {
        return GaStatus::NullPointer;
    }
    // SAFETY: the caller's contract.
    unsafe {
        with_receiver(storage, |rx| {
            let (event, status) = match rx.pop_event() {
                Some(e) => (GaEvent::from(&e), GaStatus::Ok),
                None => (
                    GaEvent {
                        kind: GaEventKind::None,
                        ..GaEvent::default()
                    },
                    GaStatus::Empty,
                ),
            };
            // (inside the caller's unsafe block) the caller's contract: `out` is writable and
            // not part of the receiver's storage
            ptr::write(out, event).map_err(abi(call))?;
            Ok(status)
        })
    }
}

/// Events lost because the queue (32) was full.
///
/// # Safety
/// `storage` as for [`ga_receiver_init`]; `out` is writable.
#[no_mangle]
pub unsafe extern "C" fn ga_receiver_events_dropped(
    storage: *mut GaReceiver,
    out: *mut u32,
) -> GaStatus {
    let call = GaCall::Output;
    // SAFETY: the caller's contract.
    unsafe {
        with_receiver(storage, |rx| {
            let n = rx.events_dropped();
            // (inside the caller's unsafe block) the caller's contract: `out` is writable
            ptr::write(out, n).map_err(abi(call))?;
            Ok(GaStatus::Ok)
        })
    }
}

/// The object's last failure (status `GA_STATUS_OK` when none since init); also readable after a
/// failed init.
///
/// # Safety
/// `storage` points to a [`GaReceiver`] or a [`crate::GaSampleReceiver`] (through
/// [`crate::ga_sample_receiver_as_receiver`]), zeroed or initialized; `out` is writable.
#[no_mangle]
pub unsafe extern "C" fn ga_receiver_last_error(
    storage: *mut GaReceiver,
    out: *mut GaError,
) -> GaStatus {
    // SAFETY: the caller's contract.
    let h = match unsafe { header(storage.cast::<Header>()) } {
        Ok(h) => h,
        Err(s) => return s,
    };
    let record = match h.magic {
        MAGIC_ATTITUDE | MAGIC_SAMPLES | MAGIC_FAILED => h.last_error,
        _ => GaError::abi(GaStatus::NotInitialized, GaCall::None),
    };
    // SAFETY: the caller's contract.
    match unsafe { ptr::write(out, record) } {
        Ok(()) => GaStatus::Ok,
        Err(s) => s,
    }
}
