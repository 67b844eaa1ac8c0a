//! The bounds of the file commands (`acquire`, `track`, `synth`): the ranges of their numeric
//! options as clap value parsers (defined once, shared by every command that takes the
//! option; a refusal names the option and its range and exits non-zero), the largest
//! recording `synth` writes, and text input files read with a size cap.
//!
//! | option | range |
//! |---|---|
//! | `--fs` | `(0, 64 MHz]` ([`MAX_SAMPLE_RATE_HZ`], the correlator's limit) |
//! | `--if` | finite, within ±32 MHz ([`MAX_IF_HZ`]) |
//! | `synth --seconds` | `(0, 3600]` s ([`MAX_SYNTH_SECONDS`]), and at most [`MAX_SYNTH_OUTPUT_BYTES`] written |
//! | `track --seconds` | finite, `> 0` (longer than the recording: a warning, the whole recording tracked) |
//! | `--cn0`, `--cn0-min`, `--cn0-max` | `[0, 60]` dB-Hz ([`MAX_SYNTH_CN0_DBHZ`]) |
//! | `--xcorr-margin-db` | `[0, 20]` dB ([`MAX_XCORR_MARGIN_DB`]; 0 switches the test off) |
//! | `--doppler-max` | `[0, 100 kHz]` ([`MAX_DOPPLER_HZ`]) |
//! | `--doppler-step` | `[10 Hz, 100 kHz]` |
//! | `--pfa` | `(0, 0.5)` |
//! | `--ms` | `1..=100` |
//! | `--attitude-window` | `(0, 60]` s ([`MAX_ATTITUDE_WINDOW_S`]) |
//! | `--cw`, `--dc`, `--constant`, `--line-bias` | finite values |
//! | `--sky` file | at most [`MAX_SKY_FILE_BYTES`], lines of at most [`MAX_SKY_LINE_CHARS`] |
//! | `--nav` file | at most [`MAX_NAV_FILE_BYTES`], lines of at most [`MAX_NAV_LINE_CHARS`] |

use std::io::Read;
use std::path::Path;

use anyhow::{ensure, Context, Result};

pub use super::reader::MAX_SAMPLE_RATE_HZ;
pub use super::synthesize::MAX_SYNTH_CN0_DBHZ;

/// Largest |intermediate frequency|, Hz (half the largest sample rate: a larger IF cannot be
/// sampled by any accepted rate).
pub const MAX_IF_HZ: f64 = MAX_SAMPLE_RATE_HZ / 2.0;

/// Longest recording `synth` writes, s (an hour).
pub const MAX_SYNTH_SECONDS: f64 = 3600.0;

/// Most bytes `synth` writes (all files together): 16 GiB, e.g. an hour of one CS8 antenna
/// at 2.3 Msps, or 18 minutes of three at 2.6 Msps.
pub const MAX_SYNTH_OUTPUT_BYTES: u64 = 16 << 30;

/// Largest cross-correlation margin, dB (C/A cross-correlation peaks sit about 24 dB under
/// the signal that makes them: a larger margin would refuse satellites nearly as strong as
/// the stronger one).
pub const MAX_XCORR_MARGIN_DB: f64 = 20.0;

/// Largest Doppler search half-range, Hz (LEO Dopplers stay within ±45 kHz).
pub const MAX_DOPPLER_HZ: f64 = 100e3;

/// Longest attitude window of `track`, s.
pub const MAX_ATTITUDE_WINDOW_S: f64 = 60.0;

/// Largest sky file, bytes (32 PRNs of `prn,azimuth,elevation` fit in 1 KB; comments leave
/// room).
pub const MAX_SKY_FILE_BYTES: u64 = 64 * 1024;

/// Longest line of a sky file, characters.
pub const MAX_SKY_LINE_CHARS: usize = 256;

/// Largest `--nav` RINEX navigation file read, bytes (a day of a full constellation's
/// broadcast ephemerides is about 1 MB).
pub const MAX_NAV_FILE_BYTES: u64 = 32 * 1024 * 1024;

/// Longest line of a `--nav` file, characters (RINEX lines are 80).
pub const MAX_NAV_LINE_CHARS: usize = 256;

/// Parses a finite `f64` in `[lo, hi]` (`lo` excluded when `lo_open`), naming the range.
fn f64_in(s: &str, lo: f64, hi: f64, lo_open: bool, unit: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|e| format!("{s:?} is not a number ({e})"))?;
    let above = if lo_open { v > lo } else { v >= lo };
    if v.is_finite() && above && v <= hi {
        return Ok(v);
    }
    let open = if lo_open { '(' } else { '[' };
    let what = if v.is_finite() {
        "is outside"
    } else {
        "is not finite: finite values only, in"
    };
    let lo = if lo == f64::MIN {
        "(-inf".to_string()
    } else {
        format!("{open}{lo}")
    };
    let hi = if hi == f64::MAX {
        "inf)".to_string()
    } else {
        format!("{hi}]")
    };
    Err(format!("{v} {what} the allowed range {lo}, {hi}{unit}"))
}

/// `--fs`: a sample rate in `(0, MAX_SAMPLE_RATE_HZ]`, Hz.
///
/// # Errors
/// Not a number, not finite, zero or negative, above 64 MHz.
pub fn sample_rate_hz(s: &str) -> Result<f64, String> {
    f64_in(s, 0.0, MAX_SAMPLE_RATE_HZ, true, " Hz")
}

/// `--if`: an intermediate frequency with `|f| ≤ MAX_IF_HZ`, Hz.
///
/// # Errors
/// Not a number, not finite, beyond ±32 MHz.
pub fn intermediate_frequency_hz(s: &str) -> Result<f64, String> {
    f64_in(s, -MAX_IF_HZ, MAX_IF_HZ, false, " Hz")
}

/// `synth --seconds`: a duration in `(0, MAX_SYNTH_SECONDS]`, s.
///
/// # Errors
/// Not a number, not finite, zero or negative, above an hour.
pub fn synth_seconds(s: &str) -> Result<f64, String> {
    f64_in(s, 0.0, MAX_SYNTH_SECONDS, true, " s")
}

/// `track --seconds`: a positive finite duration, s.
///
/// # Errors
/// Not a number, not finite, zero or negative.
pub fn track_seconds(s: &str) -> Result<f64, String> {
    f64_in(s, 0.0, f64::MAX, true, " s")
}

/// `--cn0`, `--cn0-min`, `--cn0-max`: a C/N0 in `[0, MAX_SYNTH_CN0_DBHZ]`, dB-Hz.
///
/// # Errors
/// Not a number, not finite, negative, above 60 dB-Hz.
pub fn cn0_dbhz(s: &str) -> Result<f64, String> {
    f64_in(s, 0.0, MAX_SYNTH_CN0_DBHZ, false, " dB-Hz")
}

/// `--xcorr-margin-db`: a margin in `[0, MAX_XCORR_MARGIN_DB]`, dB.
///
/// # Errors
/// Not a number, not finite, negative, above 20 dB.
pub fn xcorr_margin_db(s: &str) -> Result<f64, String> {
    f64_in(s, 0.0, MAX_XCORR_MARGIN_DB, false, " dB")
}

/// `--doppler-max`: a half-range in `[0, MAX_DOPPLER_HZ]`, Hz.
///
/// # Errors
/// Not a number, not finite, negative, above 100 kHz.
pub fn doppler_max_hz(s: &str) -> Result<f64, String> {
    f64_in(s, 0.0, MAX_DOPPLER_HZ, false, " Hz")
}

/// `--doppler-step`: a bin spacing in `[10, MAX_DOPPLER_HZ]`, Hz.
///
/// # Errors
/// Not a number, not finite, below 10 Hz, above 100 kHz.
pub fn doppler_step_hz(s: &str) -> Result<f64, String> {
    f64_in(s, 10.0, MAX_DOPPLER_HZ, false, " Hz")
}

/// `--pfa`: a false-alarm probability in `(0, 0.5)`.
///
/// # Errors
/// Not a number, outside `(0, 0.5)`.
pub fn false_alarm_probability(s: &str) -> Result<f64, String> {
    let v = f64_in(s, 0.0, 0.5, true, "")?;
    if v < 0.5 {
        Ok(v)
    } else {
        Err(format!("{v} is outside the allowed range (0, 0.5)"))
    }
}

/// `--attitude-window`: a window in `(0, MAX_ATTITUDE_WINDOW_S]`, s.
///
/// # Errors
/// Not a number, not finite, zero or negative, above 60 s.
pub fn attitude_window_s(s: &str) -> Result<f64, String> {
    f64_in(s, 0.0, MAX_ATTITUDE_WINDOW_S, true, " s")
}

/// Any finite number (`--cw`, `--dc`, `--constant`, `--line-bias` values).
///
/// # Errors
/// Not a number, not finite.
pub fn finite(s: &str) -> Result<f64, String> {
    f64_in(s, f64::MIN, f64::MAX, false, "")
}

/// Bytes `synth` would write for `instants` sample instants of `format` on `antennas`
/// antennas (all files).
pub fn synth_output_bytes(format: &super::FileFormat, antennas: usize, instants: u64) -> u64 {
    let (unit_instants, unit_bytes) = format.unit();
    let files = if format.channels > 1 { 1 } else { antennas };
    (instants / unit_instants as u64)
        .saturating_mul(unit_bytes as u64)
        .saturating_mul(files as u64)
}

/// Reads a text file of at most `max_bytes` bytes and lines of at most `max_line` characters
/// (`what` names it in the errors). Reads at most `max_bytes + 1` bytes whatever the file is
/// (a device such as `/dev/zero`, a pipe, a huge file), so memory stays bounded.
///
/// # Errors
/// Cannot open or read it, longer than `max_bytes`, not UTF-8, a line longer than `max_line`.
pub fn read_text_capped(
    path: &Path,
    max_bytes: u64,
    max_line: usize,
    what: &str,
) -> Result<String> {
    let file = std::fs::File::open(path)
        .with_context(|| format!("cannot open the {what} {}", path.display()))?;
    let mut bytes = Vec::new();
    file.take(max_bytes + 1)
        .read_to_end(&mut bytes)
        .with_context(|| format!("reading the {what} {}", path.display()))?;
    ensure!(
        bytes.len() as u64 <= max_bytes,
        "the {what} {} is longer than {max_bytes} bytes: not a {what}",
        path.display()
    );
    let text = String::from_utf8(bytes)
        .map_err(|e| anyhow::anyhow!("the {what} {} is not UTF-8 text ({e})", path.display()))?;
    if let Some((n, l)) = text
        .lines()
        .enumerate()
        .find(|(_, l)| l.chars().count() > max_line)
    {
        anyhow::bail!(
            "the {what} {}: line {} has {} characters, more than the {max_line} a {what} line may have",
            path.display(),
            n + 1,
            l.chars().count()
        );
    }
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ranges_refuse_zero_nan_infinity_and_excess_and_name_the_range() {
        assert_eq!(sample_rate_hz("2.6e6"), Ok(2.6e6));
        for bad in ["0", "-1", "nan", "inf", "1e12", "x"] {
            assert!(sample_rate_hz(bad).is_err(), "{bad}");
        }
        assert!(sample_rate_hz("0").unwrap_err().contains("(0, 64000000]"));
        assert!(intermediate_frequency_hz("nan").is_err());
        assert_eq!(intermediate_frequency_hz("-4.1e6"), Ok(-4.1e6));
        assert!(synth_seconds("1e9").unwrap_err().contains("3600"));
        assert!(synth_seconds("0").is_err());
        assert_eq!(synth_seconds("3600"), Ok(3600.0));
        assert!(cn0_dbhz("nan").is_err() && cn0_dbhz("61").is_err());
        assert!(xcorr_margin_db("nan").is_err() && xcorr_margin_db("-1").is_err());
        assert_eq!(xcorr_margin_db("0"), Ok(0.0));
        assert!(false_alarm_probability("0.5").is_err() && false_alarm_probability("0").is_err());
        assert!(finite("inf").is_err() && finite("-3.5") == Ok(-3.5));
        assert!(track_seconds("inf").is_err() && track_seconds("1e6").is_ok());
    }

    #[test]
    fn a_text_file_beyond_its_cap_is_refused_after_reading_only_the_cap() {
        let dir = std::env::temp_dir().join(format!("host-sim-limits-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let ok = dir.join("ok.csv");
        std::fs::write(&ok, "prn,az,el\n1,2,3\n").unwrap();
        assert!(read_text_capped(&ok, 100, 20, "sky file").is_ok());
        assert!(read_text_capped(&ok, 10, 20, "sky file")
            .unwrap_err()
            .to_string()
            .contains("longer than 10 bytes"));
        assert!(read_text_capped(&ok, 100, 5, "sky file")
            .unwrap_err()
            .to_string()
            .contains("line 1"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
