//! Synthesized recordings: a sky (static ground receiver or LEO dynamics), written in any
//! layout of [`super::format`] by the synthesizer ([`crate::synth`]), streamed block by
//! block, with a truth file (`<name>.truth.json`) and a sky file (`<name>.sky.csv`) beside it.
//!
//! Sky: `n` satellites with distinct random PRNs, C/N0 spread evenly over
//! `[cn0_min, cn0_max]` (in random order) or given per satellite (up to
//! [`MAX_SYNTH_CN0_DBHZ`]), azimuths 45° apart, elevations 12°–78°; lines of
//! sight in the local NED frame (the attitude's reference frame). Static: Dopplers within
//! ±4.5 kHz and rates within ±0.8 Hz/s (a ground receiver); LEO: Dopplers within ±40 kHz (the
//! first two at +38…40 and −38…−40 kHz) and rates within ±60 Hz/s. 50 bit/s data.
//! Array (three antennas): paper 003's equilateral triangle of 1.5 m, line biases 0, 0.13,
//! −0.27 cycle, static attitude yaw 30°, pitch 4°, roll −6° (3-2-1, body to NED).
//! Thermal noise (σ = 1 per component before the front-end gain of [`crate::synth::quantize`])
//! or none (`noise: false`, `synth --no-noise`): the signals alone, quantized with the same
//! gain, as signal simulators without a noise model write them.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{ensure, Context, Result};
use nalgebra::{Rotation3, Vector3};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::format::{interleave, FileFormat};
use super::reader::{Recording, RecordingSpec};
use super::synth_nav::{lnav_satellites, LnavSpec, NavigationTruth};
use crate::arrays::triangle;
use crate::synth::file::extension;
use crate::synth::quantize::encode;
use crate::synth::scene::SUB_BLOCK;
use crate::synth::{AnalogSamples, AttitudeMotion, FrontEnd, Satellite, Scene};

/// Receiver dynamics of a synthesized recording.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dynamics {
    /// Ground receiver: Dopplers within ±4.5 kHz, rates within ±0.8 Hz/s.
    Static,
    /// Low Earth orbit: Dopplers within ±40 kHz, rates within ±60 Hz/s.
    Leo,
}

/// What to synthesize.
#[derive(Clone, Debug)]
pub struct SynthSpec {
    /// Layout of the files.
    pub format: FileFormat,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Intermediate frequency, Hz (`None`: 0 for complex layouts, `f_s/4` for real ones).
    pub intermediate_frequency_hz: Option<f64>,
    /// Duration, s.
    pub seconds: f64,
    /// Antennas: 1, or 3 (the triangle).
    pub antennas: usize,
    /// Receiver dynamics.
    pub dynamics: Dynamics,
    /// Number of satellites (1–12).
    pub satellites: usize,
    /// Lowest C/N0, dB-Hz.
    pub cn0_min_dbhz: f64,
    /// Highest C/N0, dB-Hz.
    pub cn0_max_dbhz: f64,
    /// Seed of the sky, data and noise.
    pub seed: u64,
    /// Thermal noise added (`false`: the satellites' signals only, quantized with the same
    /// gain, as signal simulators without a noise model write them).
    pub noise: bool,
    /// C/N0 of each satellite, dB-Hz (`satellites` values, in PRN order); empty: spread evenly
    /// over `[cn0_min_dbhz, cn0_max_dbhz]`.
    pub cn0_dbhz: Vec<f64>,
    /// Interference and degenerate inputs applied to every antenna before quantization, in
    /// order.
    pub overlays: Vec<Overlay>,
    /// The LNAV message and the geometry of a receiver at a place and time (`synth --lnav`,
    /// static only): the almanac's satellites in view instead of the random sky.
    pub lnav: Option<LnavSpec>,
}

/// Something added to, or put instead of, the synthesized signals before quantization (noise
/// σ units: the thermal noise has σ = 1 per component, see [`crate::synth::quantize`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Overlay {
    /// Every sample replaced by a constant, σ units (satellites and noise gone): a huge value
    /// saturates every layout (CS8 +127), 0 is silence.
    Constant {
        /// In-phase value (the real sample of real layouts).
        i: f64,
        /// Quadrature value.
        q: f64,
    },
    /// A constant offset added, σ units.
    Dc {
        /// In-phase offset.
        i: f64,
        /// Quadrature offset.
        q: f64,
    },
    /// A continuous-wave tone `offset_hz` from the band centre (the IF of real layouts), its
    /// power `jn_db` above the thermal noise power (2σ² complex, σ² real).
    Cw {
        /// Offset from the band centre, Hz.
        offset_hz: f64,
        /// Tone power over the noise power, dB.
        jn_db: f64,
    },
}

impl Overlay {
    /// Whether the overlay removes the satellites (a constant input).
    pub fn replaces_signals(&self) -> bool {
        matches!(self, Self::Constant { .. })
    }

    /// Applies the overlay to samples `[first, first + n)` of every antenna.
    fn apply(&self, analog: &mut [AnalogSamples], first: u64, fe: &FrontEnd) {
        for a in analog.iter_mut() {
            let complex = !a.q.is_empty();
            match *self {
                Self::Constant { i, q } => {
                    a.i.fill(i as f32);
                    a.q.fill(q as f32);
                }
                Self::Dc { i, q } => {
                    a.i.iter_mut().for_each(|x| *x += i as f32);
                    a.q.iter_mut().for_each(|x| *x += q as f32);
                }
                Self::Cw { offset_hz, jn_db } => {
                    // Complex: |a|² = 2σ² · J/N; real: a²/2 = σ² · J/N.
                    let amplitude = (2.0 * 10f64.powf(jn_db / 10.0)).sqrt();
                    let f = fe.intermediate_frequency_hz + offset_hz;
                    for k in 0..a.i.len() {
                        let t = (first + k as u64) as f64 / fe.sample_rate_hz;
                        let phase = std::f64::consts::TAU * (f * t).rem_euclid(1.0);
                        a.i[k] += (amplitude * phase.cos()) as f32;
                        if complex {
                            a.q[k] += (amplitude * phase.sin()) as f32;
                        }
                    }
                }
            }
        }
    }
}

impl Default for SynthSpec {
    /// CS8 at 2.6 Msps, 1 s, one antenna, static, 8 satellites at 40–50 dB-Hz with thermal
    /// noise, seed 1.
    fn default() -> Self {
        Self {
            format: FileFormat::parse("cs8").unwrap_or_else(|_| unreachable!("cs8 is a layout")),
            sample_rate_hz: 2.6e6,
            intermediate_frequency_hz: None,
            seconds: 1.0,
            antennas: 1,
            dynamics: Dynamics::Static,
            satellites: 8,
            cn0_min_dbhz: 40.0,
            cn0_max_dbhz: 50.0,
            seed: 1,
            noise: true,
            cn0_dbhz: Vec::new(),
            overlays: Vec::new(),
            lnav: None,
        }
    }
}

/// Highest C/N0 a synthesized satellite may have, dB-Hz (CS8 holds twelve satellites at this
/// level with noise without clipping more than a few samples in a thousand).
pub const MAX_SYNTH_CN0_DBHZ: f64 = 60.0;

/// One synthesized satellite, as the receiver should find it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SatelliteTruth {
    /// PRN.
    pub prn: u8,
    /// C/N0, dB-Hz.
    pub cn0_dbhz: f64,
    /// Doppler at the first sample, Hz.
    pub doppler_hz: f64,
    /// Doppler rate, Hz/s.
    pub doppler_rate_hz_s: f64,
    /// Code phase at antenna 0 at the first sample, chips in `[0, 1023)`.
    pub code_phase_chips: f64,
    /// Azimuth, degrees from north towards east.
    pub azimuth_deg: f64,
    /// Elevation, degrees.
    pub elevation_deg: f64,
}

/// The truth file of a synthesized recording.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RecordingTruth {
    /// `--format` name of the files.
    pub format: String,
    /// The files (antenna order), beside the truth file.
    pub files: Vec<String>,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Intermediate frequency, Hz.
    pub intermediate_frequency_hz: f64,
    /// Sample instants written.
    pub instants: u64,
    /// Duration, s.
    pub seconds: f64,
    /// `static` or `leo`.
    pub dynamics: String,
    /// Antennas.
    pub antennas: usize,
    /// Baselines of antennas 1, 2, … from antenna 0, body frame, m (`--baselines`).
    pub baselines_body_m: Vec<[f64; 3]>,
    /// Line bias of antennas 1, 2, … relative to antenna 0, cycles (`--line-bias`).
    pub line_bias_cycles: Vec<f64>,
    /// Attitude (body to NED) as 3-2-1 yaw, pitch, roll, degrees.
    pub attitude_ypr_deg: [f64; 3],
    /// The satellites.
    pub satellites: Vec<SatelliteTruth>,
    /// Seed.
    pub seed: u64,
    /// Thermal noise was added (`false`: signals only).
    #[serde(default = "noise_default")]
    pub noise: bool,
    /// Interference and degenerate inputs applied (a constant input leaves no satellites).
    #[serde(default)]
    pub overlays: Vec<Overlay>,
    /// GPS time of the first sample, receiver position and the broadcast ephemerides
    /// (recordings with `--lnav`): `gps_week`, `tow_s`, `position_ecef_m`, `position_llh`,
    /// `ephemerides`.
    #[serde(flatten, default, skip_serializing_if = "Option::is_none")]
    pub navigation: Option<NavigationTruth>,
}

fn noise_default() -> bool {
    true
}

/// Attitude of the synthesized array, 3-2-1 yaw, pitch, roll, degrees.
pub const ATTITUDE_YPR_DEG: [f64; 3] = [30.0, 4.0, -6.0];

/// Line biases of the three antennas, cycles.
pub const LINE_BIAS_CYCLES: [f64; 3] = [0.0, 0.13, -0.27];

/// The scene of a synthesized recording and the truth the receiver should recover.
///
/// # Errors
/// An antenna count other than 1 or 3, a satellite count outside 1–12, a C/N0 range that is
/// not finite or reversed.
pub fn scene(spec: &SynthSpec) -> Result<(Scene, Vec<SatelliteTruth>)> {
    scene_with_navigation(spec).map(|(scene, truth, _)| (scene, truth))
}

/// [`scene`] and, with [`SynthSpec::lnav`], the navigation truth.
///
/// # Errors
/// As [`scene`]; with `lnav`, LEO dynamics, a position or time out of range, fewer than
/// four satellites in view.
pub fn scene_with_navigation(
    spec: &SynthSpec,
) -> Result<(Scene, Vec<SatelliteTruth>, Option<NavigationTruth>)> {
    ensure!(
        spec.antennas == 1 || spec.antennas == 3,
        "synthesized recordings have 1 or 3 antennas"
    );
    ensure!(
        (1..=12).contains(&spec.satellites),
        "1-12 satellites, got {}",
        spec.satellites
    );
    ensure!(
        spec.cn0_min_dbhz.is_finite()
            && spec.cn0_max_dbhz.is_finite()
            && spec.cn0_min_dbhz <= spec.cn0_max_dbhz,
        "C/N0 range {}..{} dB-Hz",
        spec.cn0_min_dbhz,
        spec.cn0_max_dbhz
    );
    ensure!(
        spec.cn0_dbhz.is_empty() || spec.cn0_dbhz.len() == spec.satellites,
        "{} C/N0 values for {} satellites",
        spec.cn0_dbhz.len(),
        spec.satellites
    );
    let levels = spec
        .cn0_dbhz
        .iter()
        .chain([&spec.cn0_min_dbhz, &spec.cn0_max_dbhz]);
    for &c in levels {
        ensure!(
            c.is_finite() && c <= MAX_SYNTH_CN0_DBHZ,
            "C/N0 {c} dB-Hz: the synthesizer takes finite values up to {MAX_SYNTH_CN0_DBHZ} dB-Hz"
        );
    }
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let mut prns: Vec<u8> = (1..=32).collect();
    prns.shuffle(&mut rng);
    prns.truncate(spec.satellites);
    prns.sort_unstable();
    let n = spec.satellites;
    let mut cn0: Vec<f64> = (0..n)
        .map(|k| {
            let f = if n > 1 {
                k as f64 / (n - 1) as f64
            } else {
                0.5
            };
            spec.cn0_min_dbhz + f * (spec.cn0_max_dbhz - spec.cn0_min_dbhz)
        })
        .collect();
    cn0.shuffle(&mut rng);
    if !spec.cn0_dbhz.is_empty() {
        cn0.clone_from(&spec.cn0_dbhz);
    }
    let [yaw, pitch, roll] = ATTITUDE_YPR_DEG.map(f64::to_radians);
    let c_rb = Rotation3::from_euler_angles(roll, pitch, yaw).into_inner();
    let (antennas_b, bias) = if spec.antennas == 3 {
        (triangle(1.5), LINE_BIAS_CYCLES.to_vec())
    } else {
        (vec![Vector3::zeros()], vec![0.0])
    };
    if let Some(lnav) = &spec.lnav {
        ensure!(
            spec.dynamics == Dynamics::Static,
            "--lnav recordings are static (a ground receiver)"
        );
        let (sky, nav) = lnav_satellites(lnav, spec.seconds, n, &cn0, &antennas_b, &c_rb, || {
            rng.random_range(0.0..1.0)
        })?;
        let truth = sky
            .iter()
            .map(|s| SatelliteTruth {
                prn: s.satellite.prn,
                cn0_dbhz: s.satellite.cn0_dbhz,
                doppler_hz: s.satellite.doppler_hz,
                doppler_rate_hz_s: s.satellite.doppler_rate_hz_s,
                code_phase_chips: s.satellite.code_phase_chips.rem_euclid(1023.0),
                azimuth_deg: s.azimuth_deg,
                elevation_deg: s.elevation_deg,
            })
            .collect();
        let scene = build_scene(
            spec,
            sky.into_iter().map(|s| s.satellite).collect(),
            antennas_b,
            bias,
            c_rb,
        );
        return Ok((scene, truth, Some(nav)));
    }
    let az0: f64 = rng.random_range(0.0..45.0);
    let mut sats = Vec::with_capacity(n);
    for (k, &prn) in prns.iter().enumerate() {
        let az = (az0 + 45.0 * k as f64 + 7.0 * (k / 8) as f64).rem_euclid(360.0);
        let el = 12.0 + 9.5 * (k % 8) as f64 + 4.0 * (k / 8) as f64;
        let (doppler, rate) = match spec.dynamics {
            Dynamics::Static => (
                rng.random_range(-4500.0..4500.0),
                rng.random_range(-0.8..0.8),
            ),
            Dynamics::Leo => {
                let f = match k {
                    0 => rng.random_range(38_000.0..40_000.0),
                    1 => rng.random_range(-40_000.0..-38_000.0),
                    _ => rng.random_range(-40_000.0..40_000.0),
                };
                (f, rng.random_range(-60.0..60.0))
            }
        };
        let (a, e) = (az.to_radians(), el.to_radians());
        sats.push(Satellite {
            prn,
            cn0_dbhz: cn0[k],
            doppler_hz: doppler,
            doppler_rate_hz_s: rate,
            code_phase_chips: rng.random_range(0.0..1023.0),
            carrier_phase_cycles: rng.random_range(0.0..1.0),
            los_ref: Vector3::new(e.cos() * a.cos(), e.cos() * a.sin(), -e.sin()),
            data_seed: Some(spec.seed.wrapping_mul(977).wrapping_add(k as u64)),
            track: None,
        });
    }
    let scene = build_scene(spec, sats, antennas_b, bias, c_rb);
    let truth = scene
        .satellites
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let t = scene.truth(k, 0, 0.0);
            let los = s.los_ref;
            SatelliteTruth {
                prn: s.prn,
                cn0_dbhz: s.cn0_dbhz,
                doppler_hz: t.doppler_hz,
                doppler_rate_hz_s: s.doppler_rate_hz_s,
                code_phase_chips: t.code_phase_chips,
                azimuth_deg: los.y.atan2(los.x).to_degrees().rem_euclid(360.0),
                elevation_deg: (-los.z).asin().to_degrees(),
            }
        })
        .collect();
    Ok((scene, truth, None))
}

/// The scene of `satellites` on the array, front end and noise of `spec`.
fn build_scene(
    spec: &SynthSpec,
    satellites: Vec<Satellite>,
    antennas_b: Vec<Vector3<f64>>,
    line_bias_cycles: Vec<f64>,
    c_rb: nalgebra::Matrix3<f64>,
) -> Scene {
    let complex = spec.format.is_complex();
    let fif = spec.intermediate_frequency_hz.unwrap_or(if complex {
        0.0
    } else {
        spec.sample_rate_hz / 4.0
    });
    Scene {
        satellites,
        antennas_b,
        line_bias_cycles,
        attitude: AttitudeMotion::Constant(c_rb),
        front_end: FrontEnd {
            sample_rate_hz: spec.sample_rate_hz,
            intermediate_frequency_hz: fif,
            complex,
        },
        noise_seed: spec.noise.then_some(spec.seed ^ 0x7265_636f_7264),
    }
}

/// The file names of a recording `name` in layout `format` with `antennas` antennas: one
/// file for a multi-channel layout, `<name>.ant<k>.<ext>` per antenna otherwise.
pub fn file_names(name: &str, format: &FileFormat, antennas: usize) -> Vec<String> {
    let ext = extension(format.sample);
    if format.channels > 1 || antennas == 1 {
        vec![format!("{name}.{ext}")]
    } else {
        (0..antennas)
            .map(|a| format!("{name}.ant{a}.{ext}"))
            .collect()
    }
}

/// Opens a recording [`write_recording`] wrote into `dir`, as the command line would.
///
/// # Errors
/// Those of [`Recording::open`].
pub fn open_synthesized(dir: &Path, truth: &RecordingTruth) -> Result<Recording> {
    Recording::open(&RecordingSpec {
        paths: truth.files.iter().map(|f| dir.join(f)).collect(),
        format: FileFormat::parse(&truth.format)?,
        sample_rate_hz: truth.sample_rate_hz,
        intermediate_frequency_hz: Some(truth.intermediate_frequency_hz),
        channels: None,
    })
}

/// The bounds of [`super::limits`]: a duration in `(0, MAX_SYNTH_SECONDS]`, a sample rate in
/// `(0, MAX_SAMPLE_RATE_HZ]`, a finite IF, at most `MAX_SYNTH_OUTPUT_BYTES` written.
fn check_bounds(spec: &SynthSpec) -> Result<()> {
    use super::limits::{
        synth_output_bytes, MAX_SAMPLE_RATE_HZ, MAX_SYNTH_OUTPUT_BYTES, MAX_SYNTH_SECONDS,
    };
    let (fs, seconds) = (spec.sample_rate_hz, spec.seconds);
    ensure!(
        seconds.is_finite() && seconds > 0.0 && seconds <= MAX_SYNTH_SECONDS,
        "--seconds {seconds}: the synthesizer writes (0, {MAX_SYNTH_SECONDS}] s"
    );
    ensure!(
        fs.is_finite() && fs > 0.0 && fs <= MAX_SAMPLE_RATE_HZ,
        "--fs {fs} Hz: the synthesizer takes (0, {MAX_SAMPLE_RATE_HZ}] Hz"
    );
    if let Some(f) = spec.intermediate_frequency_hz {
        ensure!(f.is_finite(), "--if {f} Hz is not finite");
    }
    let bytes = synth_output_bytes(&spec.format, spec.antennas, (seconds * fs).round() as u64);
    ensure!(
        bytes <= MAX_SYNTH_OUTPUT_BYTES,
        "{seconds} s at {:.3} Msps in {} on {} antenna(s) is {:.2} GiB, more than the {} GiB synth writes: shorten --seconds or lower --fs",
        fs / 1e6,
        spec.format.name(),
        spec.antennas,
        bytes as f64 / f64::from(1u32 << 30),
        MAX_SYNTH_OUTPUT_BYTES >> 30
    );
    Ok(())
}

/// Synthesizes the recording into `dir`, streamed in blocks (memory independent of the
/// duration): the sample files, `<name>.truth.json` and `<name>.sky.csv`. Returns the truth
/// and the paths of the sample files.
///
/// # Errors
/// A layout whose channel count does not match the antennas, a duration, rate or size beyond
/// the bounds of [`super::limits`], a bad sky (see [`scene`]), I/O errors.
pub fn write_recording(
    dir: &Path,
    name: &str,
    spec: &SynthSpec,
) -> Result<(RecordingTruth, Vec<PathBuf>)> {
    let format = spec.format;
    ensure!(
        format.channels == 1 || format.channels == spec.antennas,
        "format {} has {} channels but the recording has {} antennas",
        format.name(),
        format.channels,
        spec.antennas
    );
    check_bounds(spec)?;
    let (scene, satellites, navigation) = scene_with_navigation(spec)?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let names = file_names(name, &format, spec.antennas);
    let paths: Vec<PathBuf> = names.iter().map(|n| dir.join(n)).collect();
    let mut writers = paths
        .iter()
        .map(|p| {
            File::create(p)
                .map(BufWriter::new)
                .with_context(|| format!("creating {}", p.display()))
        })
        .collect::<Result<Vec<_>>>()?;
    let fs = spec.sample_rate_hz;
    let unit = format.unit().0 as u64;
    let total = ((spec.seconds * fs).round() as u64) / unit * unit;
    let block = (16 * SUB_BLOCK) as u64;
    let mut first = 0u64;
    while first < total {
        let n = block.min(total - first) as usize;
        let mut analog = scene.synthesize(first, n);
        for o in &spec.overlays {
            o.apply(&mut analog, first, &scene.front_end);
        }
        let streams = encode(format.sample, &analog)?;
        if format.channels > 1 && !format.packed_channels() {
            let one = interleave(&streams, format.channel_bytes());
            writers[0].write_all(&one)?;
        } else {
            for (w, s) in writers.iter_mut().zip(&streams) {
                w.write_all(s)?;
            }
        }
        first += n as u64;
    }
    for w in &mut writers {
        w.flush()?;
    }
    let r0 = scene.antennas_b[0];
    let satellites = if spec.overlays.iter().any(Overlay::replaces_signals) {
        Vec::new()
    } else {
        satellites
    };
    let truth = RecordingTruth {
        format: format.name(),
        files: names,
        sample_rate_hz: fs,
        intermediate_frequency_hz: scene.front_end.intermediate_frequency_hz,
        instants: total,
        seconds: total as f64 / fs,
        dynamics: match spec.dynamics {
            Dynamics::Static => "static",
            Dynamics::Leo => "leo",
        }
        .into(),
        antennas: spec.antennas,
        baselines_body_m: scene.antennas_b[1..]
            .iter()
            .map(|r| {
                let b = r - r0;
                [b.x, b.y, b.z]
            })
            .collect(),
        line_bias_cycles: scene.line_bias_cycles[1..]
            .iter()
            .map(|b| b - scene.line_bias_cycles[0])
            .collect(),
        attitude_ypr_deg: ATTITUDE_YPR_DEG,
        satellites,
        seed: spec.seed,
        noise: spec.noise,
        overlays: spec.overlays.clone(),
        navigation,
    };
    let truth_path = dir.join(format!("{name}.truth.json"));
    std::fs::write(&truth_path, serde_json::to_string_pretty(&truth)?)
        .with_context(|| format!("writing {}", truth_path.display()))?;
    let sky_path = dir.join(format!("{name}.sky.csv"));
    let mut sky = String::from("prn,azimuth_deg,elevation_deg\n");
    for s in &truth.satellites {
        sky.push_str(&format!(
            "{},{:.6},{:.6}\n",
            s.prn, s.azimuth_deg, s.elevation_deg
        ));
    }
    std::fs::write(&sky_path, sky).with_context(|| format!("writing {}", sky_path.display()))?;
    Ok((truth, paths))
}
