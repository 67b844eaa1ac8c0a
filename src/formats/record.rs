//! A compact binary attitude record for telemetry: quaternion, its uncertainty, health and
//! epoch in 50 bytes, little-endian, versioned, with a CRC.
//!
//! # Layout (version 1)
//! | Offset | Size | Type | Field |
//! |---:|---:|---|---|
//! | 0 | 2 | `u8 u8` | sync `0x47 0x41` (`"GA"`) |
//! | 2 | 1 | `u8` | version, [`RECORD_VERSION`] = 1 |
//! | 3 | 1 | `u8` | record length in bytes including sync and CRC, [`RECORD_LEN`] = 50 |
//! | 4 | 8 | `u64` | epoch (receiver epochs, 1 ms for GPS L1 C/A) |
//! | 12 | 16 | `4 × f32` | attitude `q_rb` (body to reference), `w, x, y, z` |
//! | 28 | 12 | `3 × f32` | σ of the body-frame rotation-vector error about x, y, z, rad (√ of the covariance's diagonal) |
//! | 40 | 1 | `u8` | source: 0 none, 1 snapshot, 2 one-stage, 3 gyro coast, 4 rigid body |
//! | 41 | 1 | `u8` | satellites tracked |
//! | 42 | 1 | `u8` | satellites used by the fine filter |
//! | 43 | 1 | `u8` | satellites with fixed ambiguities |
//! | 44 | 1 | `u8` | flags: bit 0 ambiguities fixed, bit 1 gyro running, bit 2 gyro calibrated, bits 3–5 antenna A, B, C blocked |
//! | 45 | 1 | `u8` | fine lock: 0 none, 1 pull-in, 2 locked, 3 false lock |
//! | 46 | 2 | `u16` | time since the fine filter's last update, ms, saturating at 65 535 |
//! | 48 | 2 | `u16` | CRC-16/CCITT-FALSE (polynomial 0x1021, initial 0xFFFF, no reflection, no final XOR) of bytes 0–47 |
//!
//! A reader checks sync, version, length and CRC ([`AttitudeRecord::decode`]); a later
//! version only appends fields before the CRC and raises the length byte.

use crate::attitude::one_stage::LockStatus;
use crate::receiver::{AttitudeSource, ReceiverAttitude};

use super::FormatError;

/// The sync bytes `"GA"`.
pub const RECORD_SYNC: [u8; 2] = [0x47, 0x41];
/// The layout version this module writes.
pub const RECORD_VERSION: u8 = 1;
/// Bytes of a version-1 record.
pub const RECORD_LEN: usize = 50;

/// Milliseconds per second (coasting time field).
const MS_PER_S: f32 = 1000.0;

/// One attitude in the record's terms (what [`AttitudeRecord::encode`] writes and
/// [`AttitudeRecord::decode`] reads back).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AttitudeRecord {
    /// Receiver epoch.
    pub epoch: u64,
    /// `q_rb`, body to reference, `[w, x, y, z]`.
    pub q_rb: [f32; 4],
    /// σ of the body-frame rotation-vector error per axis, rad.
    pub sigma_rad: [f32; 3],
    /// Source code (see the layout table).
    pub source: u8,
    /// Satellites tracked.
    pub satellites_tracked: u8,
    /// Satellites in the fine filter's last epoch.
    pub satellites_used: u8,
    /// Satellites with fixed ambiguities.
    pub satellites_fixed: u8,
    /// Flag bits (see the layout table).
    pub flags: u8,
    /// Fine lock code (see the layout table).
    pub fine_lock: u8,
    /// Time since the fine filter's last update, ms (saturating).
    pub coasting_ms: u16,
}

/// Error returned by [`AttitudeRecord::decode`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum RecordError {
    /// Fewer bytes than the record's length.
    #[error("record truncated")]
    Truncated,
    /// The sync bytes are wrong.
    #[error("record sync not found")]
    Sync,
    /// A version this reader does not know (0), or a length below version 1's.
    #[error("unsupported record version")]
    Version,
    /// The CRC does not match.
    #[error("record crc mismatch")]
    Crc,
}

impl crate::error::Error for RecordError {
    fn kind(&self) -> crate::error::ErrorKind {
        crate::error::ErrorKind::InvalidInput
    }
}

/// The source's code in the record.
pub fn source_code(source: AttitudeSource) -> u8 {
    match source {
        AttitudeSource::None => 0,
        AttitudeSource::Snapshot => 1,
        AttitudeSource::Fine => 2,
        AttitudeSource::GyroCoast => 3,
    }
}

/// The fine lock's code in the record.
pub fn lock_code(lock: Option<LockStatus>) -> u8 {
    match lock {
        None => 0,
        Some(LockStatus::PullIn) => 1,
        Some(LockStatus::Locked) => 2,
        Some(LockStatus::FalseLock) => 3,
    }
}

impl AttitudeRecord {
    /// The record of a receiver attitude.
    ///
    /// # Errors
    /// [`FormatError::NonFinite`] for a non-finite quaternion or covariance diagonal.
    pub fn from_attitude(attitude: &ReceiverAttitude) -> Result<Self, FormatError> {
        let q = attitude.q_rb;
        let d = attitude.covariance.diagonal();
        if !q.is_finite() || !d.iter().all(|v| v.is_finite()) {
            return Err(FormatError::NonFinite);
        }
        let h = &attitude.health;
        let mut flags = u8::from(h.ambiguities_fixed)
            | u8::from(h.gyro_running) << 1
            | u8::from(h.gyro_calibrated) << 2;
        for (bit, blocked) in h.antenna_blocked.iter().enumerate() {
            flags |= u8::from(*blocked) << (3 + bit);
        }
        // f32 → u16 saturates (and maps a NaN to 0)
        let coasting_ms = libm::roundf(h.coasting_s * MS_PER_S) as u16;
        Ok(Self {
            epoch: attitude.epoch,
            q_rb: [q.w, q.x, q.y, q.z],
            sigma_rad: [d.x, d.y, d.z].map(|v| crate::sqrtf(v.max(0.0))),
            source: source_code(attitude.source),
            satellites_tracked: h.satellites_tracked,
            satellites_used: h.satellites_used,
            satellites_fixed: h.satellites_fixed,
            flags,
            fine_lock: lock_code(h.fine_lock),
            coasting_ms,
        })
    }

    /// Writes the record into `out`; returns [`RECORD_LEN`].
    ///
    /// # Errors
    /// [`FormatError::BufferTooShort`] when `out` has fewer than [`RECORD_LEN`] bytes.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, FormatError> {
        let mut r = [0u8; RECORD_LEN];
        let mut w = super::Cursor::new(&mut r);
        w.bytes(&RECORD_SYNC)?;
        w.byte(RECORD_VERSION)?;
        w.byte(RECORD_LEN as u8)?;
        w.bytes(&self.epoch.to_le_bytes())?;
        for v in self.q_rb.iter().chain(self.sigma_rad.iter()) {
            w.bytes(&v.to_le_bytes())?;
        }
        w.bytes(&[
            self.source,
            self.satellites_tracked,
            self.satellites_used,
            self.satellites_fixed,
            self.flags,
            self.fine_lock,
        ])?;
        w.bytes(&self.coasting_ms.to_le_bytes())?;
        let crc = crc16_ccitt_false(w.written());
        w.bytes(&crc.to_le_bytes())?;
        let dst = out
            .get_mut(..RECORD_LEN)
            .ok_or(FormatError::BufferTooShort)?;
        dst.copy_from_slice(&r);
        Ok(RECORD_LEN)
    }

    /// Reads a record (version 1, or a later version's first fields) from the start of
    /// `bytes`.
    ///
    /// # Errors
    /// [`RecordError::Truncated`], [`RecordError::Sync`], [`RecordError::Version`],
    /// [`RecordError::Crc`].
    pub fn decode(bytes: &[u8]) -> Result<Self, RecordError> {
        let head = bytes.get(..4).ok_or(RecordError::Truncated)?;
        if head.get(..2) != Some(&RECORD_SYNC[..]) {
            return Err(RecordError::Sync);
        }
        let (version, len) = match *head {
            [_, _, v, l] => (v, usize::from(l)),
            _ => return Err(RecordError::Truncated),
        };
        if version == 0 || len < RECORD_LEN {
            return Err(RecordError::Version);
        }
        let record = bytes.get(..len).ok_or(RecordError::Truncated)?;
        let (body, crc) = record.split_at(len - 2);
        if crc16_ccitt_false(body).to_le_bytes() != crc {
            return Err(RecordError::Crc);
        }
        let mut r = Reader { bytes: body, at: 4 };
        let epoch = u64::from_le_bytes(r.array()?);
        let mut f = [0f32; 7];
        for v in f.iter_mut() {
            *v = f32::from_le_bytes(r.array()?);
        }
        let [qw, qx, qy, qz, sx, sy, sz] = f;
        let [source, tracked, used, fixed, flags, fine_lock] = r.array()?;
        Ok(Self {
            epoch,
            q_rb: [qw, qx, qy, qz],
            sigma_rad: [sx, sy, sz],
            source,
            satellites_tracked: tracked,
            satellites_used: used,
            satellites_fixed: fixed,
            flags,
            fine_lock,
            coasting_ms: u16::from_le_bytes(r.array()?),
        })
    }
}

/// Reads fixed-size fields in order.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn array<const N: usize>(&mut self) -> Result<[u8; N], RecordError> {
        let end = self.at.checked_add(N).ok_or(RecordError::Truncated)?;
        let s = self.bytes.get(self.at..end).ok_or(RecordError::Truncated)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        self.at = end;
        Ok(a)
    }
}

/// CRC-16/CCITT-FALSE: polynomial 0x1021, initial value 0xFFFF, MSB first, no final XOR
/// (check value of `"123456789"`: 0x29B1). Bitwise: 8 steps per byte, no table.
pub fn crc16_ccitt_false(bytes: &[u8]) -> u16 {
    const POLY: u16 = 0x1021;
    let mut crc: u16 = 0xFFFF;
    for &b in bytes {
        crc ^= u16::from(b) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ POLY
            } else {
                crc << 1
            };
        }
    }
    crc
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Euler321, Quaternion};
    use crate::receiver::ReceiverHealth;
    use nalgebra::{Matrix3, Vector3};

    fn sample() -> ReceiverAttitude {
        let q = Quaternion::from_rotation_vector(&Vector3::new(0.1, -0.2, 0.3));
        ReceiverAttitude {
            epoch: 0x0102_0304_0506_0708,
            q_rb: q,
            c_rb: q.to_dcm(),
            euler: Euler321::from_quaternion(&q).unwrap(),
            covariance: Matrix3::from_diagonal(&Vector3::new(1e-6, 4e-6, 9e-6)),
            source: AttitudeSource::GyroCoast,
            health: ReceiverHealth {
                satellites_tracked: 8,
                satellites_used: 7,
                satellites_fixed: 6,
                ambiguities_fixed: true,
                fine_lock: Some(LockStatus::Locked),
                antenna_blocked: [false, false, true],
                gyro_running: true,
                gyro_calibrated: false,
                coasting_s: 1.2345,
                ..ReceiverHealth::default()
            },
        }
    }

    #[test]
    fn crc_check_value() {
        assert_eq!(crc16_ccitt_false(b"123456789"), 0x29B1);
    }

    #[test]
    fn layout_and_round_trip() {
        let rec = AttitudeRecord::from_attitude(&sample()).unwrap();
        let mut buf = [0u8; 64];
        assert_eq!(rec.encode(&mut buf).unwrap(), RECORD_LEN);
        assert_eq!(&buf[..4], &[0x47, 0x41, 1, 50]);
        assert_eq!(&buf[4..12], &[8, 7, 6, 5, 4, 3, 2, 1]);
        let q = sample().q_rb;
        assert_eq!(&buf[12..16], &q.w.to_le_bytes());
        assert_eq!(&buf[28..32], &1e-3f32.to_le_bytes());
        assert_eq!(buf[40], 3); // gyro coast
        assert_eq!(&buf[41..44], &[8, 7, 6]);
        assert_eq!(buf[44], 0b0010_0011);
        assert_eq!(buf[45], 2);
        assert_eq!(u16::from_le_bytes([buf[46], buf[47]]), 1235);
        assert_eq!(
            u16::from_le_bytes([buf[48], buf[49]]),
            crc16_ccitt_false(&buf[..48])
        );
        assert_eq!(AttitudeRecord::decode(&buf).unwrap(), rec);
    }

    #[test]
    fn decode_errors_and_every_bit_flip_caught() {
        let rec = AttitudeRecord::from_attitude(&sample()).unwrap();
        let mut buf = [0u8; RECORD_LEN];
        rec.encode(&mut buf).unwrap();
        assert_eq!(
            AttitudeRecord::decode(&buf[..49]),
            Err(RecordError::Truncated)
        );
        assert_eq!(
            rec.encode(&mut [0u8; RECORD_LEN - 1]),
            Err(FormatError::BufferTooShort)
        );
        for byte in 4..RECORD_LEN {
            for bit in 0..8 {
                let mut b = buf;
                b[byte] ^= 1 << bit;
                assert_eq!(AttitudeRecord::decode(&b), Err(RecordError::Crc));
            }
        }
        let mut b = buf;
        b[0] = 0;
        assert_eq!(AttitudeRecord::decode(&b), Err(RecordError::Sync));
        let mut b = buf;
        b[2] = 0;
        assert_eq!(AttitudeRecord::decode(&b), Err(RecordError::Version));
        let mut nan = sample();
        nan.covariance[(1, 1)] = f32::NAN;
        assert_eq!(
            AttitudeRecord::from_attitude(&nan),
            Err(FormatError::NonFinite)
        );
    }
}
