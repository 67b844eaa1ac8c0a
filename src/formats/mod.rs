//! The receiver's attitude in the formats other equipment reads: NMEA 0183 heading sentences
//! ([`nmea`]: `$GPHDT`, `$GPTHS`) and a compact, versioned binary telemetry record with a
//! CRC ([`record`]).
//!
//! Everything writes into a buffer the caller owns (`&mut [u8]`, or a [`heapless`] string
//! for the NMEA sentences), in bounded time, without floating-point formatting from
//! `core::fmt` (numbers are written as fixed-point decimals), and fails with a typed error
//! when the buffer is too short or an input is not finite.
//!
//! ```
//! use gnss_attitude::formats::nmea::{Heading, HeadingFrame, write_ths};
//! use gnss_attitude::receiver::{example::ExampleFlight, AttitudeReceiver};
//! let mut flight = ExampleFlight::new(7);
//! let mut receiver = AttitudeReceiver::new(ExampleFlight::config(true))?;
//! flight.fly(&mut receiver, 0, 600)?;
//! // the example's reference frame is local level with z down, x north: heading of body x
//! let heading = Heading::from_attitude(&receiver.attitude(), &HeadingFrame::NED_X_FORWARD)?;
//! let mut buf = [0u8; 82];
//! let n = write_ths(&heading, &mut buf)?;
//! let sentence = core::str::from_utf8(&buf[..n])?;
//! assert!(sentence.starts_with("$GPTHS,") && sentence.contains(",A*")); // A: autonomous
//! gnss_attitude::formats::nmea::verify(&buf[..n])?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod nmea;
pub mod record;

/// Error returned by the writers of [`nmea`] and [`record`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FormatError {
    /// The output buffer is shorter than the sentence or record; nothing usable was written.
    #[error("output buffer too short")]
    BufferTooShort,
    /// A quaternion, covariance or frame value was NaN or infinite.
    #[error("non-finite value to format")]
    NonFinite,
    /// A frame is not usable: a forward axis of zero length, a rotation that is not one.
    #[error("invalid heading frame")]
    InvalidFrame,
}

impl crate::error::Error for FormatError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            Self::NonFinite => crate::error::ErrorKind::NonFinite,
            Self::BufferTooShort | Self::InvalidFrame => crate::error::ErrorKind::InvalidInput,
        }
    }
}

/// A bounded writer over a caller's buffer: every byte is checked against its end.
pub(crate) struct Cursor<'a> {
    buf: &'a mut [u8],
    len: usize,
}

impl<'a> Cursor<'a> {
    pub(crate) fn new(buf: &'a mut [u8]) -> Self {
        Self { buf, len: 0 }
    }

    /// Bytes written so far.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// The bytes written so far.
    pub(crate) fn written(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }

    pub(crate) fn byte(&mut self, b: u8) -> Result<(), FormatError> {
        let slot = self
            .buf
            .get_mut(self.len)
            .ok_or(FormatError::BufferTooShort)?;
        *slot = b;
        self.len += 1;
        Ok(())
    }

    pub(crate) fn bytes(&mut self, bytes: &[u8]) -> Result<(), FormatError> {
        let end = self
            .len
            .checked_add(bytes.len())
            .ok_or(FormatError::BufferTooShort)?;
        let slot = self
            .buf
            .get_mut(self.len..end)
            .ok_or(FormatError::BufferTooShort)?;
        slot.copy_from_slice(bytes);
        self.len = end;
        Ok(())
    }

    /// An unsigned decimal without leading zeros, at least `min_digits` digits.
    pub(crate) fn decimal(&mut self, mut value: u32, min_digits: usize) -> Result<(), FormatError> {
        // u32 has at most 10 decimal digits
        let mut digits = [0u8; 10];
        let mut n = 0usize;
        for d in digits.iter_mut() {
            *d = b'0' + (value % 10) as u8;
            value /= 10;
            n += 1;
            if value == 0 && n >= min_digits {
                break;
            }
        }
        for d in digits.iter().take(n).rev() {
            self.byte(*d)?;
        }
        Ok(())
    }
}
