//! NMEA 0183 heading sentences: `$GPHDT` (heading, true) and `$GPTHS` (true heading and
//! status).
//!
//! ```text
//! $GPHDT,x.xx,T*hh<CR><LF>     heading of the body's forward axis, degrees true, 0 ≤ x < 360
//! $GPTHS,x.xx,a*hh<CR><LF>     the same with the mode indicator a (NMEA 0183 v3.01+):
//!                              A autonomous, E estimated (dead reckoning), M manual input,
//!                              S simulator, V data not valid
//! ```
//!
//! `hh` is the XOR of every byte between `$` and `*` as two upper-case hexadecimal digits.
//! When the heading is not valid (mode V) `$GPHDT` leaves the heading field empty (HDT has no
//! status field of its own) and `$GPTHS` writes the last heading field empty too. Headings
//! are rounded to 0.01°.
//!
//! # Heading
//! The heading is the direction of a body axis (the *forward* axis, body `+x` by default)
//! projected on the local horizontal plane, clockwise from north: `atan2(f_E, f_N)` of
//! `f_n = C_nr C_rb f_b`, where `C_rb` is the receiver's attitude (body to its reference
//! frame) and `C_nr` the rotation from that reference frame to the local north-east-down
//! frame ([`HeadingFrame`]). Flight software provides `C_nr` from its navigation solution
//! (identity when the aiding's lines of sight are already given in NED). A forward axis within
//! [`MIN_HORIZONTAL`] of the vertical has no heading: mode V.
//!
//! # Mode from the receiver
//! [`HeadingMode::from_receiver`]: the GNSS stages (one-stage filter, snapshot, rigid-body) →
//! A; the gyro carrying the last fine attitude → E; no attitude, or a non-finite one → V.
//! M and S are for callers that output a manual or a simulated heading.

use nalgebra::{Matrix3, Vector3};

use super::{Cursor, FormatError};
use crate::receiver::{AttitudeSource, Integrity, ReceiverAttitude, ReceiverHealth};

/// Longest NMEA 0183 sentence, `$` to `<LF>` inclusive, bytes.
pub const MAX_SENTENCE: usize = 82;

/// A sentence in a [`heapless`] string.
pub type Sentence = heapless::String<MAX_SENTENCE>;

/// Smallest horizontal component (of a unit forward axis) that still defines a heading
/// (1e-3: the axis at least 0.057° away from the vertical).
pub const MIN_HORIZONTAL: f32 = 1e-3;

/// Headings are written in hundredths of a degree.
const CENTIDEGREES: f32 = 100.0;
/// A full turn in hundredths of a degree.
const FULL_TURN_CENTIDEGREES: u32 = 36_000;
/// Largest deviation of `C_nr` from orthonormality (any entry of `C Cᵀ − I`).
const ROTATION_TOLERANCE: f32 = 1e-3;

/// The mode indicator of `$GPTHS` (NMEA 0183 v3.01 and later).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HeadingMode {
    /// `A`: autonomous, from the receiver's own GNSS measurements.
    Autonomous,
    /// `E`: estimated (dead reckoning): the gyro carrying the last GNSS attitude.
    Estimated,
    /// `M`: manual input.
    Manual,
    /// `S`: simulator mode.
    Simulator,
    /// `V`: data not valid.
    #[default]
    Invalid,
}

impl HeadingMode {
    /// The indicator character.
    pub fn indicator(self) -> u8 {
        match self {
            Self::Autonomous => b'A',
            Self::Estimated => b'E',
            Self::Manual => b'M',
            Self::Simulator => b'S',
            Self::Invalid => b'V',
        }
    }

    /// The mode of the receiver's attitude from its source and health: A for the GNSS stages
    /// (with fixed ambiguities and no integrity alarm), E while the gyro coasts, V otherwise.
    pub fn from_receiver(source: AttitudeSource, health: &ReceiverHealth) -> Self {
        if health.integrity == Integrity::Alarm {
            return Self::Invalid;
        }
        match source {
            AttitudeSource::Fine | AttitudeSource::Snapshot if health.ambiguities_fixed => {
                Self::Autonomous
            }
            AttitudeSource::GyroCoast => Self::Estimated,
            _ => Self::Invalid,
        }
    }
}

/// Where the heading is measured: the rotation from the receiver's reference frame to the
/// local north-east-down frame, and the body axis whose heading is reported.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadingFrame {
    /// `C_nr`: reference frame to north-east-down, rows N, E, D.
    pub c_nr: [[f32; 3]; 3],
    /// The forward axis in body axes (any length above zero).
    pub forward_body: [f32; 3],
}

impl HeadingFrame {
    /// The reference frame is north-east-down; the forward axis is body `+x`.
    pub const NED_X_FORWARD: Self = Self {
        c_nr: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        forward_body: [1.0, 0.0, 0.0],
    };

    /// Checks the frame: finite, `C_nr` a rotation to [`ROTATION_TOLERANCE`], a forward axis
    /// of non-zero length.
    fn validate(&self) -> Result<(Matrix3<f32>, Vector3<f32>), FormatError> {
        let finite = self
            .c_nr
            .iter()
            .flatten()
            .chain(self.forward_body.iter())
            .all(|v| v.is_finite());
        if !finite {
            return Err(FormatError::NonFinite);
        }
        let c = Matrix3::from_fn(|i, j| {
            self.c_nr
                .get(i)
                .and_then(|row| row.get(j))
                .copied()
                .unwrap_or(0.0)
        });
        let orthonormal = (c * c.transpose() - Matrix3::identity()).amax() <= ROTATION_TOLERANCE
            && c.determinant() > 0.0;
        let forward = Vector3::from(self.forward_body);
        let length = forward.norm();
        if !orthonormal || !(length > 0.0) {
            return Err(FormatError::InvalidFrame);
        }
        Ok((c, forward / length))
    }
}

/// A heading with its mode, ready to be written.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Heading {
    /// Heading, degrees clockwise from true north, in `[0, 360)` (meaningless in mode V).
    pub degrees: f32,
    /// The mode indicator.
    pub mode: HeadingMode,
}

impl Heading {
    /// The heading of `frame.forward_body` for the receiver's attitude, with the mode from its
    /// source and health ([`HeadingMode::from_receiver`]); mode V for a non-finite attitude
    /// or a forward axis within [`MIN_HORIZONTAL`] of the vertical.
    ///
    /// # Errors
    /// [`FormatError::NonFinite`] / [`FormatError::InvalidFrame`] for an unusable frame.
    pub fn from_attitude(
        attitude: &ReceiverAttitude,
        frame: &HeadingFrame,
    ) -> Result<Self, FormatError> {
        let (c_nr, forward) = frame.validate()?;
        let mode = HeadingMode::from_receiver(attitude.source, &attitude.health);
        let q = attitude.q_rb;
        if mode == HeadingMode::Invalid || !q.is_finite() {
            return Ok(Self::default());
        }
        // f_n = C_nr C_rb f_b
        let f_n = c_nr * q.rotate(&forward);
        let horizontal = libm::hypotf(f_n.x, f_n.y);
        if !(horizontal >= MIN_HORIZONTAL) {
            return Ok(Self::default());
        }
        let degrees = libm::atan2f(f_n.y, f_n.x).to_degrees();
        Ok(Self {
            degrees: if degrees < 0.0 {
                degrees + 360.0
            } else {
                degrees
            },
            mode,
        })
    }

    /// The heading in hundredths of a degree, `0..36000`, or `None` in mode V or for a
    /// non-finite heading.
    fn centidegrees(&self) -> Option<u32> {
        if self.mode == HeadingMode::Invalid || !self.degrees.is_finite() {
            return None;
        }
        // into [0, 360) without fmodf (whose libm code keeps panic paths)
        let turns = self.degrees - 360.0 * libm::floorf(self.degrees / 360.0);
        // rounding may reach a full turn: that is north
        let centi = libm::roundf(turns * CENTIDEGREES) as u32;
        Some(if centi >= FULL_TURN_CENTIDEGREES {
            0
        } else {
            centi
        })
    }
}

/// The NMEA checksum: XOR of `body` (the bytes between `$` and `*`).
pub fn checksum(body: &[u8]) -> u8 {
    body.iter().fold(0, |acc, b| acc ^ b)
}

/// Writes `$GPHDT` into `out`; returns the sentence's length (with `<CR><LF>`).
///
/// # Errors
/// [`FormatError::BufferTooShort`] when `out` is shorter than the sentence.
pub fn write_hdt(heading: &Heading, out: &mut [u8]) -> Result<usize, FormatError> {
    let mut w = Cursor::new(out);
    w.bytes(b"$GPHDT,")?;
    write_degrees(&mut w, heading)?;
    w.bytes(b",T")?;
    finish(&mut w)
}

/// Writes `$GPTHS` into `out`; returns the sentence's length (with `<CR><LF>`).
///
/// # Errors
/// [`FormatError::BufferTooShort`] when `out` is shorter than the sentence.
pub fn write_ths(heading: &Heading, out: &mut [u8]) -> Result<usize, FormatError> {
    let mut w = Cursor::new(out);
    w.bytes(b"$GPTHS,")?;
    write_degrees(&mut w, heading)?;
    w.byte(b',')?;
    w.byte(heading.mode.indicator())?;
    finish(&mut w)
}

/// `$GPHDT` as a [`Sentence`].
///
/// # Errors
/// As [`write_hdt`] (cannot happen: [`MAX_SENTENCE`] holds it).
pub fn hdt(heading: &Heading) -> Result<Sentence, FormatError> {
    to_sentence(heading, write_hdt)
}

/// `$GPTHS` as a [`Sentence`].
///
/// # Errors
/// As [`write_ths`] (cannot happen: [`MAX_SENTENCE`] holds it).
pub fn ths(heading: &Heading) -> Result<Sentence, FormatError> {
    to_sentence(heading, write_ths)
}

fn to_sentence(
    heading: &Heading,
    write: fn(&Heading, &mut [u8]) -> Result<usize, FormatError>,
) -> Result<Sentence, FormatError> {
    let mut buf = [0u8; MAX_SENTENCE];
    let n = write(heading, &mut buf)?;
    let ascii = buf.get(..n).ok_or(FormatError::BufferTooShort)?;
    // (`write` emits ASCII only, so a UTF-8 refusal can only be a sentence cut short; and the
    // sentence has MAX_SENTENCE bytes of room: both causes are the one variant names)
    let text = core::str::from_utf8(ascii).map_err(|_| FormatError::BufferTooShort)?;
    let mut s = Sentence::new();
    s.push_str(text).map_err(|_| FormatError::BufferTooShort)?;
    Ok(s)
}

/// The heading field: `ddd.dd` without leading zeros, empty in mode V.
fn write_degrees(w: &mut Cursor<'_>, heading: &Heading) -> Result<(), FormatError> {
    let Some(centi) = heading.centidegrees() else {
        return Ok(());
    };
    w.decimal(centi / 100, 1)?;
    w.byte(b'.')?;
    w.decimal(centi % 100, 2)
}

/// `*hh<CR><LF>` over everything after the `$`.
fn finish(w: &mut Cursor<'_>) -> Result<usize, FormatError> {
    let sum = checksum(w.written().get(1..).unwrap_or(&[]));
    w.byte(b'*')?;
    w.byte(hex_digit(sum >> 4))?;
    w.byte(hex_digit(sum & 0x0f))?;
    w.bytes(b"\r\n")?;
    Ok(w.len())
}

fn hex_digit(nibble: u8) -> u8 {
    match nibble {
        0..=9 => b'0' + nibble,
        _ => b'A' + (nibble - 10),
    }
}

/// Error returned by [`verify`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SentenceError {
    /// Not of the form `$…*hh` (optionally followed by `<CR><LF>`), or longer than
    /// [`MAX_SENTENCE`].
    #[error("not an nmea sentence")]
    Malformed,
    /// The checksum does not match the body.
    #[error("nmea checksum mismatch")]
    Checksum,
}

impl crate::error::Error for SentenceError {
    fn kind(&self) -> crate::error::ErrorKind {
        crate::error::ErrorKind::InvalidInput
    }
}

/// Checks one sentence (`$`, body, `*`, two hexadecimal digits, optional `<CR><LF>`): its
/// form, length and checksum.
///
/// # Errors
/// [`SentenceError::Malformed`], [`SentenceError::Checksum`].
pub fn verify(sentence: &[u8]) -> Result<(), SentenceError> {
    let s = sentence.strip_suffix(b"\r\n").unwrap_or(sentence);
    if s.len() + 2 > MAX_SENTENCE {
        return Err(SentenceError::Malformed);
    }
    let rest = s.strip_prefix(b"$").ok_or(SentenceError::Malformed)?;
    let star = rest
        .iter()
        .rposition(|&b| b == b'*')
        .ok_or(SentenceError::Malformed)?;
    let (body, tail) = rest.split_at(star);
    let [_, hi, lo] = *tail else {
        return Err(SentenceError::Malformed);
    };
    let value = |c: u8| match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'A'..=b'F' => Some(c - b'A' + 10),
        _ => None,
    };
    let (Some(hi), Some(lo)) = (value(hi), value(lo)) else {
        return Err(SentenceError::Malformed);
    };
    if body
        .iter()
        .any(|&b| !(0x20..0x7f).contains(&b) || b == b'$' || b == b'*')
    {
        return Err(SentenceError::Malformed);
    }
    if checksum(body) != (hi << 4 | lo) {
        return Err(SentenceError::Checksum);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Euler321, Quaternion};

    fn attitude(q: Quaternion<f32>, source: AttitudeSource) -> ReceiverAttitude {
        ReceiverAttitude {
            epoch: 5,
            q_rb: q,
            c_rb: q.to_dcm(),
            euler: Euler321::from_quaternion(&q).unwrap_or_default(),
            covariance: Matrix3::identity() * 1e-6,
            source,
            health: ReceiverHealth {
                ambiguities_fixed: true,
                ..ReceiverHealth::default()
            },
        }
    }

    fn yaw(deg: f32) -> Quaternion<f32> {
        Quaternion::from_rotation_vector(&Vector3::new(0.0, 0.0, deg.to_radians()))
    }

    fn text(buf: &[u8], n: usize) -> &str {
        core::str::from_utf8(&buf[..n]).unwrap()
    }

    #[test]
    fn known_sentences() {
        // the checksums by hand: XOR of "GPHDT,274.07,T" and "GPTHS,274.07,A"
        let h = Heading {
            degrees: 274.07,
            mode: HeadingMode::Autonomous,
        };
        let mut buf = [0u8; MAX_SENTENCE];
        let n = write_hdt(&h, &mut buf).unwrap();
        let expect = checksum(b"GPHDT,274.07,T");
        assert_eq!(text(&buf, n), format_args_str("$GPHDT,274.07,T", expect));
        let n = write_ths(&h, &mut buf).unwrap();
        assert_eq!(
            text(&buf, n),
            format_args_str("$GPTHS,274.07,A", checksum(b"GPTHS,274.07,A"))
        );
        // a published example sentence with its checksum
        assert!(verify(b"$GPHDT,274.07,T*03\r\n").is_ok());
        assert_eq!(verify(b"$GPHDT,274.07,T*04"), Err(SentenceError::Checksum));
    }

    fn format_args_str(body: &str, sum: u8) -> heapless::String<90> {
        use core::fmt::Write;
        let mut s = heapless::String::new();
        write!(s, "{body}*{sum:02X}\r\n").unwrap();
        s
    }

    #[test]
    fn heading_from_attitude_and_rounding() {
        let frame = HeadingFrame::NED_X_FORWARD;
        for (deg, field) in [
            (0.0, "0.00"),
            (45.0, "45.00"),
            (-90.0, "270.00"),
            (359.996, "0.00"),
            (123.456, "123.46"),
        ] {
            let h =
                Heading::from_attitude(&attitude(yaw(deg), AttitudeSource::Fine), &frame).unwrap();
            assert_eq!(h.mode, HeadingMode::Autonomous);
            let s = ths(&h).unwrap();
            let got = s.split(',').nth(1).unwrap();
            assert_eq!(got, field, "{deg}");
            verify(s.as_bytes()).unwrap();
            verify(hdt(&h).unwrap().as_bytes()).unwrap();
        }
    }

    #[test]
    fn modes_and_invalid_headings() {
        let frame = HeadingFrame::NED_X_FORWARD;
        let coast = attitude(yaw(10.0), AttitudeSource::GyroCoast);
        let h = Heading::from_attitude(&coast, &frame).unwrap();
        assert_eq!(h.mode, HeadingMode::Estimated);
        assert!(ths(&h).unwrap().contains(",E*"));
        let none = attitude(yaw(10.0), AttitudeSource::None);
        let h = Heading::from_attitude(&none, &frame).unwrap();
        assert_eq!(h.mode, HeadingMode::Invalid);
        assert!(ths(&h).unwrap().starts_with("$GPTHS,,V*"));
        assert!(hdt(&h).unwrap().starts_with("$GPHDT,,T*"));
        // nose straight down: no heading
        let pitch = Quaternion::from_rotation_vector(&Vector3::new(
            0.0,
            -core::f32::consts::FRAC_PI_2,
            0.0,
        ));
        let h = Heading::from_attitude(&attitude(pitch, AttitudeSource::Fine), &frame).unwrap();
        assert_eq!(h.mode, HeadingMode::Invalid);
        // snapshot without fixed ambiguities cannot happen, but is not autonomous
        let mut a = attitude(yaw(10.0), AttitudeSource::Snapshot);
        a.health.ambiguities_fixed = false;
        assert_eq!(
            Heading::from_attitude(&a, &frame).unwrap().mode,
            HeadingMode::Invalid
        );
    }

    #[test]
    fn frame_and_buffer_errors() {
        let a = attitude(yaw(10.0), AttitudeSource::Fine);
        let mut frame = HeadingFrame::NED_X_FORWARD;
        frame.forward_body = [0.0; 3];
        assert_eq!(
            Heading::from_attitude(&a, &frame),
            Err(FormatError::InvalidFrame)
        );
        frame.forward_body = [f32::NAN, 0.0, 0.0];
        assert_eq!(
            Heading::from_attitude(&a, &frame),
            Err(FormatError::NonFinite)
        );
        let mut frame = HeadingFrame::NED_X_FORWARD;
        frame.c_nr[0][0] = 2.0;
        assert_eq!(
            Heading::from_attitude(&a, &frame),
            Err(FormatError::InvalidFrame)
        );
        let h = Heading::from_attitude(&a, &HeadingFrame::NED_X_FORWARD).unwrap();
        let full = ths(&h).unwrap().len();
        for short in 0..full {
            let mut buf = [0u8; MAX_SENTENCE];
            assert_eq!(
                write_ths(&h, &mut buf[..short]),
                Err(FormatError::BufferTooShort)
            );
        }
        // a rotated reference frame: reference = NED turned by 30° about down
        let mut frame = HeadingFrame::NED_X_FORWARD;
        let c = yaw(30.0).to_dcm();
        for i in 0..3 {
            for j in 0..3 {
                frame.c_nr[i][j] = c[(i, j)];
            }
        }
        let h = Heading::from_attitude(&a, &frame).unwrap();
        assert!((h.degrees - 40.0).abs() < 1e-3, "{}", h.degrees);
    }

    #[test]
    fn verify_rejects_malformed() {
        for bad in [
            &b""[..],
            b"GPHDT,1.00,T*00",
            b"$GPHDT,1.00,T",
            b"$GPHDT,1.00,T*0",
            b"$GPHDT,1.00,T*zz",
            b"$GP$HDT,1.00,T*00",
        ] {
            assert_eq!(verify(bad), Err(SentenceError::Malformed), "{bad:?}");
        }
    }
}
