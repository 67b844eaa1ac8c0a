//! The receiver from raw samples (acquisition, tracking channels, adapter, attitude
//! receiver) in caller-provided storage: [`GaSampleReceiver`].
//!
//! The receiver-level calls (`ga_receiver_set_aiding`, `…_push_gyro_*`, `…_attitude`,
//! `…_pop_event`, `…_last_error`) take the pointer [`ga_sample_receiver_as_receiver`]
//! returns; the calls here are the ones only the sample path has.

use core::mem::{align_of, size_of};

use gnss_attitude::receiver::AdapterConfig;
use gnss_attitude::receiver::{ReceiverError, SampleFrontConfig, SampleReceiver};
use gnss_attitude::signal::{Prn, SampleBlock};
use gnss_attitude::tracking::{AcquisitionConfig, ChannelConfig, SearchSamples};

use crate::ptr;
use crate::receiver::{
    emplace, header, mark_failed, GaReceiver, Header, Object, GA_STORAGE_ALIGN, MAGIC_SAMPLES,
};
use crate::status::{Failure, GaCall, GaStatus};
use crate::types::GaConfig;

/// Tracking channels of a [`GaSampleReceiver`].
pub const GA_SAMPLE_CHANNELS: usize = 4;
/// FFT size of its acquisition engine (bins per millisecond: at least the samples of 1 ms).
pub const GA_SAMPLE_FFT: usize = 2048;

/// The Rust type behind a [`GaSampleReceiver`].
pub type FfiSampleReceiver = SampleReceiver<GA_SAMPLE_CHANNELS, GA_SAMPLE_FFT>;

/// 64-bit words of a [`GaSampleReceiver`]'s storage.
pub const GA_SAMPLE_RECEIVER_WORDS: usize = 12800;
/// Bytes of a [`GaSampleReceiver`] (`GA_SAMPLE_RECEIVER_WORDS × 8`).
pub const GA_SAMPLE_RECEIVER_SIZE: usize = GA_SAMPLE_RECEIVER_WORDS * 8;

/// Storage of one sample receiver (private content; see [`GaReceiver`]).
#[repr(C)]
pub struct GaSampleReceiver {
    /// Private.
    pub opaque: [u64; GA_SAMPLE_RECEIVER_WORDS],
}

const _: () = assert!(size_of::<Object<FfiSampleReceiver>>() <= GA_SAMPLE_RECEIVER_SIZE);
const _: () = assert!(align_of::<Object<FfiSampleReceiver>>() <= GA_STORAGE_ALIGN);
const _: () = assert!(align_of::<GaSampleReceiver>() == GA_STORAGE_ALIGN);

/// Bytes the sample receiver object really uses on this target.
#[no_mangle]
pub extern "C" fn ga_sample_receiver_used_size() -> usize {
    size_of::<Object<FfiSampleReceiver>>()
}

/// Mirror of [`SampleFrontConfig`] (channel and adapter settings: their defaults,
/// [`ChannelConfig::leo`] and [`AdapterConfig::default`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaSampleFrontConfig {
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Intermediate frequency, Hz (0 for complex baseband).
    pub intermediate_frequency_hz: f64,
    /// Receiver sample at the centre of receiver epoch 0.
    pub epoch_origin_sample: u64,
    /// A channel without a locked epoch for this many samples is closed.
    pub release_after_samples: u64,
    /// Samples per receiver epoch.
    pub samples_per_epoch: u32,
    /// Doppler search span ±, Hz.
    pub doppler_max_hz: f32,
    /// Doppler bin spacing, Hz.
    pub doppler_step_hz: f32,
    /// False-alarm probability per PRN search.
    pub false_alarm_probability: f32,
    /// Milliseconds summed non-coherently.
    pub noncoherent_ms: u16,
}

impl From<&SampleFrontConfig> for GaSampleFrontConfig {
    fn from(c: &SampleFrontConfig) -> Self {
        let a = &c.acquisition;
        Self {
            sample_rate_hz: a.sample_rate_hz,
            intermediate_frequency_hz: a.intermediate_frequency_hz,
            epoch_origin_sample: c.epoch_origin_sample,
            release_after_samples: c.release_after_samples,
            samples_per_epoch: c.samples_per_epoch,
            doppler_max_hz: a.doppler_max_hz,
            doppler_step_hz: a.doppler_step_hz,
            false_alarm_probability: a.false_alarm_probability,
            noncoherent_ms: a.noncoherent_ms,
        }
    }
}

impl GaSampleFrontConfig {
    /// The core configuration.
    pub fn to_core(&self) -> SampleFrontConfig {
        SampleFrontConfig {
            acquisition: AcquisitionConfig {
                sample_rate_hz: self.sample_rate_hz,
                intermediate_frequency_hz: self.intermediate_frequency_hz,
                doppler_max_hz: self.doppler_max_hz,
                doppler_step_hz: self.doppler_step_hz,
                noncoherent_ms: self.noncoherent_ms,
                false_alarm_probability: self.false_alarm_probability,
            },
            channel: ChannelConfig::leo(self.sample_rate_hz, self.intermediate_frequency_hz),
            adapter: AdapterConfig::default(),
            epoch_origin_sample: self.epoch_origin_sample,
            samples_per_epoch: self.samples_per_epoch,
            release_after_samples: self.release_after_samples,
        }
    }
}

/// A block of samples of the three antennas (one `int8_t` per sample and antenna, the
/// values the core's sample decoders produce): `q` all null for real (IF) samples.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct GaSampleBlock {
    /// Receiver sample index of the block's first sample.
    pub first_sample: u64,
    /// Samples per antenna.
    pub len: usize,
    /// In-phase (or real) samples of antennas A, B, C.
    pub i: [*const i8; 3],
    /// Quadrature samples of A, B, C (all null for real samples).
    pub q: [*const i8; 3],
}

/// Mirror of [`gnss_attitude::receiver::SampleReport`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct GaSampleReport {
    /// Complete tracking epochs.
    pub epochs: u32,
    /// Observations the receiver accepted.
    pub observations: u32,
    /// Observations refused for want of aiding.
    pub without_aiding: u32,
    /// Observations refused as late.
    pub late: u32,
    /// Channels closed for lack of lock.
    pub released: u8,
}

/// Fills `out` with [`SampleFrontConfig::leo_complex`] at `sample_rate_hz`.
///
/// # Safety
/// `out` is writable.
#[no_mangle]
pub unsafe extern "C" fn ga_sample_front_config_leo_complex(
    sample_rate_hz: f64,
    out: *mut GaSampleFrontConfig,
) -> GaStatus {
    let c = SampleFrontConfig::leo_complex(sample_rate_hz);
    // SAFETY: the caller's contract.
    match unsafe { ptr::write(out, GaSampleFrontConfig::from(&c)) } {
        Ok(()) => GaStatus::Ok,
        Err(s) => s,
    }
}

/// Builds a sample receiver (no channels yet) in `storage`.
///
/// Stack: the object is built on the stack before it is moved: about
/// `ga_sample_receiver_used_size()` bytes plus the receiver's own.
///
/// # Safety
/// `storage` points to a [`GaSampleReceiver`] no other call uses meanwhile; `config` and
/// `front` point to their structs.
#[no_mangle]
pub unsafe extern "C" fn ga_sample_receiver_init(
    storage: *mut GaSampleReceiver,
    config: *const GaConfig,
    front: *const GaSampleFrontConfig,
) -> GaStatus {
    if storage.is_null() {
        return GaStatus::NullPointer;
    }
    if !storage.is_aligned() {
        return GaStatus::Misaligned;
    }
    let abi = |s| Failure::abi(s, GaCall::Init);
    // SAFETY: the caller's contract (null checked inside).
    let inputs = unsafe { (ptr::read(config), ptr::read(front)) };
    let built = match inputs {
        (Ok(c), Ok(f)) => c.to_core().map_err(abi).and_then(|c| {
            FfiSampleReceiver::new(c, f.to_core())
                .map_err(|e| Failure::receiver(e, GaCall::Init, 0))
        }),
        (Err(s), _) | (_, Err(s)) => Err(abi(s)),
    };
    match built {
        Ok(rx) => {
            // SAFETY: non-null, aligned, large enough (compile-time assert), exclusive.
            unsafe {
                emplace(
                    storage.cast::<Object<FfiSampleReceiver>>(),
                    MAGIC_SAMPLES,
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

/// The same storage as a [`GaReceiver`] handle, for the receiver-level calls.
#[no_mangle]
pub extern "C" fn ga_sample_receiver_as_receiver(
    storage: *mut GaSampleReceiver,
) -> *mut GaReceiver {
    storage.cast::<GaReceiver>()
}

/// The sample receiver at `p`.
///
/// # Safety
/// As [`crate::receiver`]'s header access; storage with the sample magic holds the object.
unsafe fn with_samples(
    p: *mut GaSampleReceiver,
    f: impl FnOnce(&mut FfiSampleReceiver) -> Result<GaStatus, Failure>,
) -> GaStatus {
    // SAFETY: the caller's contract.
    let magic = match unsafe { header(p.cast::<Header>()) } {
        Ok(h) => h.magic,
        Err(s) => return s,
    };
    if magic != MAGIC_SAMPLES {
        return GaStatus::NotInitialized;
    }
    // SAFETY: the magic is written only by `ga_sample_receiver_init` together with a valid
    // object at this (checked, aligned) address; exclusive by the caller's contract.
    let o = unsafe { &mut *p.cast::<Object<FfiSampleReceiver>>() };
    match f(&mut o.value) {
        Ok(s) => s,
        Err(failure) => {
            o.header.last_error = failure.record;
            failure.status
        }
    }
}

/// Searches `prn` in `len` samples of the reference antenna (`q` null for real samples)
/// starting at receiver sample `first_sample`, over the configured Doppler span about zero;
/// a detection starts a channel. `*detected` is set to 1 on a detection, else 0.
///
/// # Safety
/// `storage` as for [`ga_sample_receiver_init`]; `i` (and `q` unless null) point to `len`
/// samples; `detected` is writable.
#[no_mangle]
pub unsafe extern "C" fn ga_sample_receiver_search(
    storage: *mut GaSampleReceiver,
    prn: u8,
    i: *const i8,
    q: *const i8,
    len: usize,
    first_sample: u64,
    detected: *mut u8,
) -> GaStatus {
    let samples = GaSearchSamples {
        i,
        q,
        len,
        first_sample,
    };
    // SAFETY: the caller's contract, the same as `ga_sample_receiver_search_near`'s.
    unsafe { ga_sample_receiver_search_near(storage, prn, samples, 0.0, detected) }
}

/// The samples a search reads: `len` samples of the reference antenna at `i` (and `q`; null
/// for real samples), the first one receiver sample `first_sample`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct GaSearchSamples {
    /// In-phase (or real) samples.
    pub i: *const i8,
    /// Quadrature samples; null for real samples.
    pub q: *const i8,
    /// Samples at `i` (and at `q`).
    pub len: usize,
    /// Receiver sample index of `i[0]`.
    pub first_sample: u64,
}

/// [`ga_sample_receiver_search`] over the configured Doppler span about
/// `predicted_doppler_hz` (a warm start: the Doppler predicted from the almanac, time and
/// orbit, Hz; a non-finite one or one beyond ±60 kHz gives `GA_STATUS_ACQUISITION`, the
/// error record's kind saying which).
///
/// # Safety
/// `storage` as for [`ga_sample_receiver_init`]; `samples.i` (and `samples.q` unless null)
/// point to `samples.len` samples; `detected` is writable.
#[no_mangle]
pub unsafe extern "C" fn ga_sample_receiver_search_near(
    storage: *mut GaSampleReceiver,
    prn: u8,
    samples: GaSearchSamples,
    predicted_doppler_hz: f32,
    detected: *mut u8,
) -> GaStatus {
    let call = GaCall::Search;
    let abi = |s| Failure::abi(s, call);
    let GaSearchSamples {
        i,
        q,
        len,
        first_sample,
    } = samples;
    // SAFETY: the caller's contract.
    let i = unsafe { ptr::slice(i, len) };
    // SAFETY: the caller's contract (q may be null: real samples).
    let q = (!q.is_null()).then(|| unsafe { ptr::slice(q, len) });
    // SAFETY: the caller's contract.
    unsafe {
        with_samples(storage, |rx| {
            let i = i.map_err(abi)?;
            let q = q.transpose().map_err(abi)?;
            let prn = Prn::new(prn).ok_or(abi(GaStatus::InvalidInput))?;
            let r = SearchSamples::decoded(i, q)
                .map_err(ReceiverError::from)
                .and_then(|s| rx.search_samples_near(prn, s, first_sample, predicted_doppler_hz))
                .map_err(|e| Failure::receiver(e, call, 0))?;
            // (inside the caller's unsafe block) the caller's contract: `detected` is
            // writable and not part of the storage
            ptr::write(detected, u8::from(r.detected)).map_err(abi)?;
            Ok(GaStatus::Ok)
        })
    }
}

/// Runs every channel over the block and feeds the receiver; `report` (nullable) gets what
/// the call did.
///
/// # Safety
/// `storage` as for [`ga_sample_receiver_init`]; `block` points to a [`GaSampleBlock`]
/// whose pointers each point to `len` samples (the `q` ones all null for real samples);
/// `report` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn ga_sample_receiver_push_samples(
    storage: *mut GaSampleReceiver,
    block: *const GaSampleBlock,
    report: *mut GaSampleReport,
) -> GaStatus {
    let call = GaCall::PushSamples;
    let abi = |s| Failure::abi(s, call);
    // SAFETY: the caller's contract.
    let b = match unsafe { ptr::read(block) } {
        Ok(b) => b,
        Err(s) => return s,
    };
    let len = b.len;
    let [i0, i1, i2] = b.i;
    // SAFETY: the caller's contract: each pointer to `len` samples.
    let i = unsafe {
        [
            ptr::slice(i0, len),
            ptr::slice(i1, len),
            ptr::slice(i2, len),
        ]
    };
    let complex = b.q.iter().any(|p| !p.is_null());
    let [q0, q1, q2] = b.q;
    // SAFETY: the caller's contract: each pointer to `len` samples when complex.
    let q = complex.then(|| unsafe {
        [
            ptr::slice(q0, len),
            ptr::slice(q1, len),
            ptr::slice(q2, len),
        ]
    });
    // SAFETY: the caller's contract.
    unsafe {
        with_samples(storage, |rx| {
            let [a, b2, c] = i;
            let i = [a.map_err(abi)?, b2.map_err(abi)?, c.map_err(abi)?];
            let block = match q {
                None => SampleBlock::real(b.first_sample, i),
                Some([a, b2, c]) => {
                    let q = [a.map_err(abi)?, b2.map_err(abi)?, c.map_err(abi)?];
                    SampleBlock::complex(b.first_sample, i, q)
                }
            }
            .map_err(|_| abi(GaStatus::InvalidInput))?;
            let r = rx
                .push_samples(&block)
                .map_err(|e| Failure::receiver(e, call, 0))?;
            if !report.is_null() {
                let out = GaSampleReport {
                    epochs: r.epochs,
                    observations: r.observations,
                    without_aiding: r.without_aiding,
                    late: r.late,
                    released: r.released,
                };
                // (inside the caller's unsafe block) non-null, writable by the caller's
                // contract
                ptr::write(report, out).map_err(abi)?;
            }
            Ok(GaStatus::Ok)
        })
    }
}

/// Closes `prn`'s channel (`GA_EMPTY` when it had none).
///
/// # Safety
/// `storage` as for [`ga_sample_receiver_init`].
#[no_mangle]
pub unsafe extern "C" fn ga_sample_receiver_release(
    storage: *mut GaSampleReceiver,
    prn: u8,
) -> GaStatus {
    let call = GaCall::Search;
    // SAFETY: the caller's contract.
    unsafe {
        with_samples(storage, |rx| {
            let prn = Prn::new(prn).ok_or(Failure::abi(GaStatus::InvalidInput, call))?;
            Ok(if rx.release(prn) {
                GaStatus::Ok
            } else {
                GaStatus::Empty
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ga_example_config, ga_receiver_last_error, GaError, GA_KIND_NON_FINITE};
    use gnss_attitude::signal::CA_CHIP_RATE_HZ;
    use std::boxed::Box;
    use std::vec::Vec;

    const FS: f64 = 2.6e6;

    /// Complex samples of PRN 7 at `doppler_hz`, code phase 300 chips, in noise (σ 8 LSB,
    /// amplitude 3 LSB: about 46 dB-Hz), for `n` samples.
    fn satellite(doppler_hz: f64, n: usize) -> (Vec<i8>, Vec<i8>) {
        let prn = Prn::new(7).unwrap();
        let mut state = 0x9E37_79B9_7F4A_7C15_u64;
        let mut gaussian = || {
            // a sum of four uniforms, scaled to σ = 1
            let mut s = 0.0;
            for _ in 0..4 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                s += (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            }
            s * 3f64.sqrt()
        };
        (0..n)
            .map(|k| {
                let t = k as f64 / FS;
                let chip = (300.0 + t * CA_CHIP_RATE_HZ) as usize % 1023;
                let c = f64::from(prn.chip(chip));
                let ph = core::f64::consts::TAU * doppler_hz * t;
                let x = 3.0 * c * ph.cos() + 8.0 * gaussian();
                let y = 3.0 * c * ph.sin() + 8.0 * gaussian();
                (x.round() as i8, y.round() as i8)
            })
            .unzip()
    }

    /// Through the C ABI, a warm search: a satellite at +3.32 kHz is outside the ±1 kHz span
    /// about zero (`ga_sample_receiver_search`: not detected) and inside it about a predicted
    /// +3 kHz (`ga_sample_receiver_search_near`: detected); a NaN prediction is refused as an
    /// acquisition failure whose record says non-finite.
    #[test]
    fn a_warm_search_through_the_c_abi_finds_the_satellite_about_its_prediction() {
        let mut config = core::mem::MaybeUninit::<crate::GaConfig>::uninit();
        let mut front = core::mem::MaybeUninit::<GaSampleFrontConfig>::uninit();
        // SAFETY: both outputs are writable.
        let (config, mut front) = unsafe {
            assert_eq!(ga_example_config(0, config.as_mut_ptr()), GaStatus::Ok);
            let s = ga_sample_front_config_leo_complex(FS, front.as_mut_ptr());
            assert_eq!(s, GaStatus::Ok);
            (config.assume_init(), front.assume_init())
        };
        front.doppler_max_hz = 1000.0;
        let mut rx = Box::new(GaSampleReceiver {
            opaque: [0; GA_SAMPLE_RECEIVER_WORDS],
        });
        let rx: *mut GaSampleReceiver = &mut *rx;
        // SAFETY: `rx` is this test's storage; the configurations are the structs above.
        let status = unsafe { ga_sample_receiver_init(rx, &config, &front) };
        assert_eq!(status, GaStatus::Ok);
        let n = front.to_core().acquisition.samples_needed();
        let (i, q) = satellite(3320.0, n);
        let samples = GaSearchSamples {
            i: i.as_ptr(),
            q: q.as_ptr(),
            len: n,
            first_sample: 0,
        };
        let mut detected = 9u8;
        // SAFETY: the samples point to `n` samples each; `detected` is writable.
        let status =
            unsafe { ga_sample_receiver_search(rx, 7, samples.i, samples.q, n, 0, &mut detected) };
        assert_eq!((status, detected), (GaStatus::Ok, 0));
        // SAFETY: as above.
        let status =
            unsafe { ga_sample_receiver_search_near(rx, 7, samples, 3000.0, &mut detected) };
        assert_eq!((status, detected), (GaStatus::Ok, 1));
        // SAFETY: as above.
        let status =
            unsafe { ga_sample_receiver_search_near(rx, 9, samples, f32::NAN, &mut detected) };
        assert_eq!(status, GaStatus::Acquisition);
        let mut error = core::mem::MaybeUninit::<GaError>::uninit();
        // SAFETY: a sample receiver's storage is a receiver's (`ga_sample_receiver_as_receiver`
        // documents it); `error` is writable.
        let error = unsafe {
            let as_receiver = ga_sample_receiver_as_receiver(rx);
            assert_eq!(
                ga_receiver_last_error(as_receiver, error.as_mut_ptr()),
                GaStatus::Ok
            );
            error.assume_init()
        };
        assert_eq!(error.source_kind, GA_KIND_NON_FINITE, "{error:?}");
    }
}
