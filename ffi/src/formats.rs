//! The core's attitude formats for C: NMEA `$GPHDT` / `$GPTHS` and the binary record
//! (see [`gnss_attitude::formats`] for the layouts).

use gnss_attitude::formats::nmea::{write_hdt, write_ths, Heading, HeadingFrame};
use gnss_attitude::formats::record::{AttitudeRecord, RECORD_LEN};

use crate::ptr;
use crate::status::GaStatus;
use crate::types::GaAttitude;

/// Bytes of a binary attitude record.
pub const GA_RECORD_LEN: usize = 50;
/// Longest NMEA sentence with `<CR><LF>`, bytes.
pub const GA_NMEA_MAX: usize = 82;

const _: () = assert!(GA_RECORD_LEN == RECORD_LEN);
const _: () = assert!(GA_NMEA_MAX == gnss_attitude::formats::nmea::MAX_SENTENCE);

/// Mirror of [`HeadingFrame`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaHeadingFrame {
    /// `C_nr`: reference frame to north-east-down, row-major.
    pub c_nr: [[f32; 3]; 3],
    /// The forward axis, body axes.
    pub forward_body: [f32; 3],
}

impl GaHeadingFrame {
    fn to_core(self) -> HeadingFrame {
        HeadingFrame {
            c_nr: self.c_nr,
            forward_body: self.forward_body,
        }
    }
}

/// Which sentence [`ga_format_nmea`] writes.
#[repr(u8)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GaSentence {
    /// `$GPHDT`.
    Hdt = 0,
    /// `$GPTHS`.
    Ths = 1,
}

/// Writes `sentence` (0 HDT, 1 THS) for `attitude` into `buf[..capacity]` (not
/// NUL-terminated; [`GA_NMEA_MAX`] is always enough), its length into `*written`. `frame`
/// null: the reference frame is north-east-down and the forward axis body +x.
///
/// # Safety
/// `attitude` points to a [`GaAttitude`]; `frame` null or a [`GaHeadingFrame`]; `buf`
/// `capacity` writable bytes; `written` writable.
#[no_mangle]
pub unsafe extern "C" fn ga_format_nmea(
    sentence: u8,
    attitude: *const GaAttitude,
    frame: *const GaHeadingFrame,
    buf: *mut u8,
    capacity: usize,
    written: *mut usize,
) -> GaStatus {
    // SAFETY: the caller's contract.
    let inputs = unsafe { (ptr::read(attitude), ptr::bytes_mut(buf, capacity)) };
    let frame = if frame.is_null() {
        Ok(HeadingFrame::NED_X_FORWARD)
    } else {
        // SAFETY: non-null: the caller's contract.
        unsafe { ptr::read(frame) }.map(GaHeadingFrame::to_core)
    };
    let result = (|| {
        let (a, out) = inputs;
        let a = a?.to_core()?;
        let heading = Heading::from_attitude(&a, &frame?)?;
        let n = match sentence {
            0 => write_hdt(&heading, out?)?,
            1 => write_ths(&heading, out?)?,
            _ => return Err(GaStatus::InvalidInput),
        };
        Ok(n)
    })();
    // SAFETY: the caller's contract.
    unsafe { finish(result, written) }
}

/// Writes the binary record of `attitude` ([`GA_RECORD_LEN`] bytes) into `buf`.
///
/// # Safety
/// `attitude` points to a [`GaAttitude`]; `buf` `capacity` writable bytes; `written`
/// writable.
#[no_mangle]
pub unsafe extern "C" fn ga_format_record(
    attitude: *const GaAttitude,
    buf: *mut u8,
    capacity: usize,
    written: *mut usize,
) -> GaStatus {
    // SAFETY: the caller's contract.
    let inputs = unsafe { (ptr::read(attitude), ptr::bytes_mut(buf, capacity)) };
    let result = (|| {
        let (a, out) = inputs;
        let record = AttitudeRecord::from_attitude(&a?.to_core()?)?;
        Ok(record.encode(out?)?)
    })();
    // SAFETY: the caller's contract.
    unsafe { finish(result, written) }
}

/// Stores the length of a successful write.
///
/// # Safety
/// `written` is null or writable.
unsafe fn finish(result: Result<usize, GaStatus>, written: *mut usize) -> GaStatus {
    match result {
        // SAFETY: `written` is null (checked inside) or writable by the caller's contract.
        Ok(n) => match unsafe { ptr::write(written, n) } {
            Ok(()) => GaStatus::Ok,
            Err(s) => s,
        },
        Err(s) => s,
    }
}
