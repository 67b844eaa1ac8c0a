//! Sample files: one raw stream per antenna (`<stem>.ant<k>.<ext>`), or one interleaved
//! multi-channel stream. CS8 (`.cs8`, interleaved signed bytes I, Q) and CS16 (`.cs16`,
//! interleaved little-endian i16 I, Q) are what common software receivers read (GNSS-SDR
//! `ibyte` / `ishort`, Pocket SDR `-fmt INT8X2`, GNU Radio `ishort`).

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use gnss_attitude::signal::SampleFormat;

/// The usual file extension of a format.
pub fn extension(format: SampleFormat) -> &'static str {
    match format {
        SampleFormat::Cs8 => "cs8",
        SampleFormat::Cs16 { .. } => "cs16",
        SampleFormat::Int8 => "int8",
        SampleFormat::SignMagnitude2 { .. } => "sm2",
        SampleFormat::Sign1 | SampleFormat::Sign1Iq => "bit1",
        SampleFormat::MultiChannel2 { .. } => "mc2",
    }
}

/// The files holding `streams` (one per antenna, or one for a multi-channel format).
pub fn paths(dir: &Path, stem: &str, format: SampleFormat, streams: usize) -> Vec<PathBuf> {
    let ext = extension(format);
    if streams == 1 {
        vec![dir.join(format!("{stem}.{ext}"))]
    } else {
        (0..streams)
            .map(|a| dir.join(format!("{stem}.ant{a}.{ext}")))
            .collect()
    }
}

/// Writes the streams; returns the paths written.
pub fn write_streams(
    dir: &Path,
    stem: &str,
    format: SampleFormat,
    streams: &[Vec<u8>],
) -> Result<Vec<PathBuf>> {
    let paths = paths(dir, stem, format, streams.len());
    for (p, s) in paths.iter().zip(streams) {
        fs::write(p, s).with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(paths)
}

/// Reads the streams back.
pub fn read_streams(paths: &[PathBuf]) -> Result<Vec<Vec<u8>>> {
    paths
        .iter()
        .map(|p| fs::read(p).with_context(|| format!("reading {}", p.display())))
        .collect()
}
