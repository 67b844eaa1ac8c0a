//! `--nmea FILE`: the receiver's attitude as NMEA `$GPHDT` + `$GPTHS` sentences, one pair per
//! attitude handed to [`record`], written with the core's formatter
//! ([`gnss_attitude::formats::nmea`]).
//!
//! A process-wide sink so that the scenario loops need one call each and no new parameter:
//! `main` installs it for `run microsat --nmea` and `track --nmea`, the loops call
//! [`record`] with each attitude (a no-op when no sink is installed), `main` calls
//! [`finish`].

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::sync::Mutex;

use anyhow::{Context, Result};
use gnss_attitude::formats::nmea::{write_hdt, write_ths, Heading, HeadingFrame, MAX_SENTENCE};
use gnss_attitude::receiver::ReceiverAttitude;
use nalgebra::{Matrix3, Vector3};

static SINK: Mutex<Option<Sink>> = Mutex::new(None);

struct Sink {
    out: BufWriter<File>,
    sentences: u64,
    error: Option<std::io::Error>,
}

/// Opens `path` (creating its directory) as the sink.
///
/// # Errors
/// When the file cannot be created.
pub fn install(path: &Path) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let file = File::create(path).with_context(|| format!("creating {}", path.display()))?;
    *SINK.lock().unwrap_or_else(|e| e.into_inner()) = Some(Sink {
        out: BufWriter::new(file),
        sentences: 0,
        error: None,
    });
    Ok(())
}

/// Writes `$GPHDT` and `$GPTHS` for `attitude`, its heading measured in `frame` (`None`: no
/// local-level frame is known, the sentences say "not valid"); nothing without a sink. A
/// write error is kept for [`finish`].
pub fn record(attitude: &ReceiverAttitude, frame: Option<&HeadingFrame>) {
    let mut guard = SINK.lock().unwrap_or_else(|e| e.into_inner());
    let Some(sink) = guard.as_mut() else {
        return;
    };
    if sink.error.is_some() {
        return;
    }
    let heading = match frame {
        Some(f) => Heading::from_attitude(attitude, f).unwrap_or_default(),
        None => Heading::default(),
    };
    let mut buf = [0u8; MAX_SENTENCE];
    for write in [write_hdt, write_ths] {
        if let Ok(n) = write(&heading, &mut buf) {
            if let Err(e) = sink.out.write_all(&buf[..n]) {
                sink.error = Some(e);
                return;
            }
            sink.sentences += 1;
        }
    }
}

/// Flushes and closes the sink; returns the number of sentences written (0 without one).
///
/// # Errors
/// The first write error, or the flush's.
pub fn finish() -> Result<u64> {
    let Some(mut sink) = SINK.lock().unwrap_or_else(|e| e.into_inner()).take() else {
        return Ok(0);
    };
    if let Some(e) = sink.error.take() {
        return Err(e).context("writing the NMEA file");
    }
    sink.out.flush().context("writing the NMEA file")?;
    Ok(sink.sentences)
}

/// The local north-east-down frame at a spacecraft at ECI position `r` (m): `C_nr` from ECI,
/// down to the Earth's centre, north toward the ECI pole (`z`). Identity at the poles.
pub fn ned_from_eci(r: &Vector3<f64>) -> HeadingFrame {
    let down = -r.normalize();
    let pole = Vector3::z();
    let north = pole - down * down.dot(&pole);
    let Some(north) = north.try_normalize(1e-9) else {
        return HeadingFrame::NED_X_FORWARD;
    };
    let east = down.cross(&north);
    let c: Matrix3<f64> =
        Matrix3::from_rows(&[north.transpose(), east.transpose(), down.transpose()]);
    HeadingFrame {
        c_nr: std::array::from_fn(|i| std::array::from_fn(|j| c[(i, j)] as f32)),
        forward_body: [1.0, 0.0, 0.0],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gnss_attitude::formats::nmea::verify;
    use gnss_attitude::receiver::example::ExampleFlight;
    use gnss_attitude::receiver::AttitudeReceiver;

    #[test]
    fn writes_valid_sentences() {
        let dir = std::env::temp_dir().join(format!("host-sim-nmea-{}", std::process::id()));
        let path = dir.join("sub/heading.nmea");
        install(&path).unwrap();
        let mut flight = ExampleFlight::new(7);
        let mut rx = AttitudeReceiver::new(ExampleFlight::config(true)).unwrap();
        for k in 0..6 {
            flight.fly(&mut rx, k * 100, (k + 1) * 100).unwrap();
            record(&rx.attitude(), Some(&HeadingFrame::NED_X_FORWARD));
        }
        assert_eq!(finish().unwrap(), 12);
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().count(), 12);
        for line in text.split_inclusive("\r\n") {
            verify(line.as_bytes()).unwrap_or_else(|e| panic!("{line:?}: {e}"));
        }
        assert!(text.contains(",A*"), "{text}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn ned_frame_is_a_rotation() {
        let f = ned_from_eci(&Vector3::new(7e6, 1e6, 2e6));
        let c = Matrix3::from_fn(|i, j| f64::from(f.c_nr[i][j]));
        assert!((c * c.transpose() - Matrix3::identity()).amax() < 1e-6);
        // down row points to the Earth's centre
        assert!((c.row(2).transpose() + Vector3::new(7e6, 1e6, 2e6).normalize()).norm() < 1e-6);
    }
}
