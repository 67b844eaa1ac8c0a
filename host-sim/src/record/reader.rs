//! Opening a recording (validation with clear errors) and reading it block by block into the
//! core's planar `i8` samples, with memory bounded by the block size whatever the file size.

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::PathBuf;

use anyhow::{bail, ensure, Context, Result};
use gnss_attitude::signal::{SampleBlock, CA_CHIP_RATE_HZ};

use super::format::{deinterleave, FileFormat};

/// Largest sample rate the core's correlator accepts, Hz.
pub const MAX_SAMPLE_RATE_HZ: f64 = gnss_attitude::signal::correlator::MAX_SAMPLE_RATE_HZ;

/// What the command line says about a recording.
#[derive(Clone, Debug)]
pub struct RecordingSpec {
    /// One file per antenna (antenna order), or one file of a multi-channel layout.
    pub paths: Vec<PathBuf>,
    /// The layout.
    pub format: FileFormat,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Intermediate frequency, Hz (`None`: 0 for complex formats; required for real ones).
    pub intermediate_frequency_hz: Option<f64>,
    /// Channels of a multi-channel file used as antennas 0, 1, … (`None`: all, in order).
    pub channels: Option<Vec<usize>>,
}

/// An opened, validated recording.
#[derive(Clone, Debug)]
pub struct Recording {
    /// The files.
    pub paths: Vec<PathBuf>,
    /// The layout (CS16 shift resolved).
    pub format: FileFormat,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Intermediate frequency, Hz.
    pub intermediate_frequency_hz: f64,
    /// For each antenna: (file index, channel within the file).
    pub antennas: Vec<(usize, usize)>,
    /// Sample instants in the recording.
    pub instants: u64,
}

impl Recording {
    /// Opens and validates a recording: the sample rate can hold the C/A code (complex:
    /// `f_s ≥ 2.046 MHz`; real: the main lobe `f_IF ± 1.023 MHz` inside `(0, f_s/2)`), the
    /// files exist, are not empty, hold whole sample instants, have equal lengths, and at
    /// least one code period (1 ms). A `cs16` layout without a shift gets one from the data.
    ///
    /// # Errors
    /// Each of the above, with the file and the reason.
    pub fn open(spec: &RecordingSpec) -> Result<Self> {
        let fs = spec.sample_rate_hz;
        let format = spec.format;
        ensure!(!spec.paths.is_empty(), "no --file given");
        ensure!(
            fs.is_finite() && fs > 0.0,
            "sample rate {fs} Hz is not a positive number"
        );
        ensure!(
            fs <= MAX_SAMPLE_RATE_HZ,
            "sample rate {:.3} MHz is above the {:.0} MHz the correlator accepts",
            fs / 1e6,
            MAX_SAMPLE_RATE_HZ / 1e6
        );
        let fif = match (spec.intermediate_frequency_hz, format.is_complex()) {
            (Some(f), _) => f,
            (None, true) => 0.0,
            (None, false) => bail!(
                "format {} carries real samples: give the intermediate frequency with --if",
                format.name()
            ),
        };
        ensure!(
            fif.is_finite(),
            "intermediate frequency {fif} Hz is not finite"
        );
        let lobe = CA_CHIP_RATE_HZ;
        if format.is_complex() {
            ensure!(
                fs >= 2.0 * lobe,
                "sample rate {:.4} MHz cannot hold the C/A code: complex sampling needs at least {:.3} MHz (the code's main lobe, ±1.023 MHz)",
                fs / 1e6,
                2.0 * lobe / 1e6
            );
            ensure!(
                fif.abs() + lobe <= fs / 2.0,
                "intermediate frequency {:.4} MHz puts the C/A main lobe (±1.023 MHz) outside ±f_s/2 = ±{:.4} MHz",
                fif / 1e6,
                fs / 2e6
            );
        } else {
            ensure!(
                fs >= 4.0 * lobe,
                "sample rate {:.4} MHz cannot hold the C/A code on a real IF: real sampling needs at least {:.3} MHz (main lobe ±1.023 MHz between 0 and f_s/2)",
                fs / 1e6,
                4.0 * lobe / 1e6
            );
            ensure!(
                fif.abs() >= lobe && fif.abs() + lobe <= fs / 2.0,
                "intermediate frequency {:.4} MHz puts the C/A main lobe (±1.023 MHz) outside (0, f_s/2 = {:.4} MHz): give the (aliased) IF of the recording",
                fif / 1e6,
                fs / 2e6
            );
        }
        // Antennas: one per file, or channels of one multi-channel file.
        let antennas: Vec<(usize, usize)> = if format.channels > 1 {
            ensure!(
                spec.paths.len() == 1,
                "format {} holds {} channels in one file: give one --file (got {})",
                format.name(),
                format.channels,
                spec.paths.len()
            );
            let chosen = spec
                .channels
                .clone()
                .unwrap_or_else(|| (0..format.channels).collect());
            ensure!(!chosen.is_empty(), "--channels lists no channel");
            for &c in &chosen {
                ensure!(
                    c < format.channels,
                    "channel {c} does not exist in format {} (channels 0-{})",
                    format.name(),
                    format.channels - 1
                );
            }
            chosen.into_iter().map(|c| (0, c)).collect()
        } else {
            ensure!(
                spec.channels.is_none(),
                "--channels needs a multi-channel format (mc2xN, cs8xN, ...)"
            );
            (0..spec.paths.len()).map(|f| (f, 0)).collect()
        };
        let mut instants = None;
        for p in &spec.paths {
            let meta =
                std::fs::metadata(p).with_context(|| format!("cannot open {}", p.display()))?;
            ensure!(meta.is_file(), "{} is not a file", p.display());
            let bytes = meta.len();
            ensure!(bytes > 0, "{} is empty", p.display());
            let n = format
                .instants_in(bytes)
                .with_context(|| format!("{}", p.display()))?;
            match instants {
                None => instants = Some(n),
                Some(m) => ensure!(
                    m == n,
                    "the antenna files differ in length ({} holds {n} sample instants, the first file {m})",
                    p.display()
                ),
            }
        }
        let instants = instants.unwrap_or(0);
        let period = (fs * 1e-3).ceil() as u64;
        ensure!(
            instants >= period,
            "the recording holds {instants} samples ({:.3} ms), shorter than one C/A code period (1 ms = {period} samples at {:.4} MHz)",
            instants as f64 / fs * 1e3,
            fs / 1e6
        );
        let mut rec = Self {
            paths: spec.paths.clone(),
            format,
            sample_rate_hz: fs,
            intermediate_frequency_hz: fif,
            antennas,
            instants,
        };
        if format.auto_shift {
            let shift = rec.choose_cs16_shift()?;
            rec.format = format.with_cs16_shift(shift);
        }
        Ok(rec)
    }

    /// Number of antennas.
    pub fn antenna_count(&self) -> usize {
        self.antennas.len()
    }

    /// Duration, s.
    pub fn seconds(&self) -> f64 {
        self.instants as f64 / self.sample_rate_hz
    }

    /// A reader from the first sample.
    pub fn reader(&self) -> Result<BlockReader> {
        let files = self
            .paths
            .iter()
            .map(|p| {
                File::open(p)
                    .map(|f| BufReader::with_capacity(1 << 20, f))
                    .with_context(|| format!("cannot open {}", p.display()))
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(BlockReader {
            files,
            format: self.format,
            antennas: self.antennas.clone(),
            remaining: self.instants,
            position: 0,
            raw: vec![Vec::new(); self.paths.len()],
            channel: Vec::new(),
            i: vec![Vec::new(); self.antennas.len()],
            q: vec![Vec::new(); self.antennas.len()],
        })
    }

    /// The CS16 shift that brings the first 10 ms of antenna 0 to an RMS near 16 LSB (the
    /// synthesizer's CS8 level: 2-3 bits of headroom, quantization loss negligible).
    fn choose_cs16_shift(&self) -> Result<u8> {
        let n = ((self.sample_rate_hz * 1e-2) as u64).min(self.instants) as usize;
        let (file, channel) = self.antennas[0];
        let unit = self.format.unit().1;
        let mut raw = vec![0u8; n * unit];
        let mut f = File::open(&self.paths[file])
            .with_context(|| format!("cannot open {}", self.paths[file].display()))?;
        f.read_exact(&mut raw)
            .with_context(|| format!("reading {}", self.paths[file].display()))?;
        let mut sum2 = 0.0f64;
        for instant in raw.chunks_exact(unit) {
            let s = &instant[4 * channel..4 * channel + 4];
            let (i, q) = (
                f64::from(i16::from_le_bytes([s[0], s[1]])),
                f64::from(i16::from_le_bytes([s[2], s[3]])),
            );
            sum2 += 0.5 * (i * i + q * q);
        }
        let rms = (sum2 / n.max(1) as f64).sqrt();
        ensure!(
            rms > 0.0,
            "{}: the first 10 ms are all zero",
            self.paths[file].display()
        );
        Ok((rms / 16.0).log2().round().clamp(0.0, 8.0) as u8)
    }
}

/// Streams a recording in blocks of decoded planar samples (memory: one block per antenna).
pub struct BlockReader {
    files: Vec<BufReader<File>>,
    format: FileFormat,
    antennas: Vec<(usize, usize)>,
    remaining: u64,
    position: u64,
    raw: Vec<Vec<u8>>,
    channel: Vec<u8>,
    i: Vec<Vec<i8>>,
    q: Vec<Vec<i8>>,
}

/// One decoded block: planar samples of every antenna from sample `first`.
pub struct Block<'a> {
    /// Receiver sample index of the first instant.
    pub first: u64,
    /// In-phase (or real) samples per antenna.
    pub i: &'a [Vec<i8>],
    /// Quadrature samples per antenna (empty for real formats).
    pub q: &'a [Vec<i8>],
    /// Whether the samples are complex.
    pub complex: bool,
}

impl Block<'_> {
    /// Sample instants in the block.
    pub fn len(&self) -> usize {
        self.i.first().map_or(0, Vec::len)
    }

    /// Whether the block is empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The core's view of the block for `A` antennas.
    ///
    /// # Errors
    /// When the recording has another number of antennas.
    pub fn samples<const A: usize>(&self) -> Result<SampleBlock<'_, A>> {
        ensure!(
            self.i.len() == A,
            "block has {} antennas, {A} expected",
            self.i.len()
        );
        let i: [&[i8]; A] = std::array::from_fn(|a| &self.i[a][..]);
        Ok(if self.complex {
            let q: [&[i8]; A] = std::array::from_fn(|a| &self.q[a][..]);
            SampleBlock::complex(self.first, i, q)?
        } else {
            SampleBlock::real(self.first, i)?
        })
    }
}

impl BlockReader {
    /// Receiver sample index of the next instant to read.
    pub fn position(&self) -> u64 {
        self.position
    }

    /// Reads and decodes up to `n` sample instants (rounded down to the layout's unit, at
    /// least one unit); `None` at the end of the recording.
    ///
    /// # Errors
    /// I/O errors (a file shorter than it was when opened), decoding errors.
    pub fn read(&mut self, n: usize) -> Result<Option<Block<'_>>> {
        let (unit_instants, unit_bytes) = self.format.unit();
        let units = (n / unit_instants)
            .max(1)
            .min((self.remaining / unit_instants as u64) as usize);
        let instants = units * unit_instants;
        if instants == 0 {
            return Ok(None);
        }
        let bytes = units * unit_bytes;
        for (f, raw) in self.files.iter_mut().zip(self.raw.iter_mut()) {
            raw.resize(bytes, 0);
            f.read_exact(raw)
                .context("the recording ended early (was it truncated while being read?)")?;
        }
        let complex = self.format.is_complex();
        let sample = self.format.sample;
        for (a, &(file, channel)) in self.antennas.iter().enumerate() {
            let i = &mut self.i[a];
            let q = &mut self.q[a];
            i.resize(instants, 0);
            q.resize(if complex { instants } else { 0 }, 0);
            let raw = &self.raw[file];
            let got = if self.format.packed_channels() {
                sample.decode(raw, channel, i, q)?
            } else if self.format.channels > 1 {
                deinterleave(
                    raw,
                    self.format.channels,
                    self.format.channel_bytes(),
                    channel,
                    &mut self.channel,
                );
                sample.decode(&self.channel, 0, i, q)?
            } else {
                sample.decode(raw, 0, i, q)?
            };
            ensure!(got == instants, "decoded {got} of {instants} samples");
        }
        let first = self.position;
        self.position += instants as u64;
        self.remaining -= instants as u64;
        Ok(Some(Block {
            first,
            i: &self.i,
            q: &self.q,
            complex,
        }))
    }
}
