//! `host-sim`: run the scenarios of gnss-attitude on the desktop.
//!
//! ```text
//! host-sim                                   # the default scenario, files into out/
//! host-sim list                              # scenarios and their variants
//! host-sim run <scenario> [--variant V] [--seed N] [--json] [--out DIR] [--front-end i8|sm2|bit1]
//! host-sim acquire --file F --format FMT --fs HZ [--if HZ] [--doppler-max HZ] [--json]
//! host-sim track --file F [--file F2 --file F3] --format FMT --fs HZ [--seconds S]
//!                [--baselines ... [--sky CSV]] [--nav RINEX] [--json] [--out DIR]
//! host-sim synth --out DIR --format FMT --fs HZ --seconds S [--antennas 3] [--leo]
//!                [--no-noise] [--cn0 C1,C2,...] [--cw HZ,DB] [--dc I,Q] [--constant I,Q]
//!                [--lnav] [--gps-start WEEK:TOW] [--position LAT,LON,H]
//! host-sim acquisition-stats [--searches 200] [--markdown docs/ACQUISITION.md]
//! host-sim report [--quick] [--out docs/RESULTS.md]
//! ```
//! With `--json`, stdout carries exactly one JSON object; progress and logs go to stderr.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::{Args, Parser, Subcommand};

use host_sim::record::{
    self, limits, AcquireOptions, Dynamics, FileFormat, Recording, RecordingSpec,
};
use host_sim::report::print_human;
use host_sim::scenarios::{self, RunContext};
use host_sim::synth::quantize::Quantizer;

#[derive(Parser)]
#[command(
    name = "host-sim",
    version,
    about = "Desktop simulator for the gnss-attitude crate"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// List the scenarios and their variants.
    List,
    /// Run one scenario.
    Run {
        /// Scenario name (see `host-sim list`).
        scenario: String,
        /// Variant of the scenario (default: its first variant).
        #[arg(long)]
        variant: Option<String>,
        /// Seed of the random streams (runs are reproducible for a given seed).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Print one JSON object on stdout instead of the human summary.
        #[arg(long)]
        json: bool,
        /// Directory for CSV time series and PNG plots (nothing is written without it).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Front end of the sample-level paths (scenarios signal, one-stage): `i8` (CS8, the
        /// default), `sm2` (2-bit sign/magnitude) or `bit1` (1-bit); the others report their
        /// C/N0 loss against `i8` on the same samples.
        #[arg(long, default_value = "i8", value_parser = parse_front_end)]
        front_end: Quantizer,
        /// Write the receiver's heading as NMEA $GPHDT/$GPTHS sentences to this file
        /// (scenario microsat).
        #[arg(long)]
        nmea: Option<PathBuf>,
        /// Fly this two-line (or three-line, with the name) element set through SGP4 instead
        /// of the built-in orbit, from the scenario's GPS start (scenario microsat).
        #[arg(long)]
        tle: Option<PathBuf>,
    },
    /// Acquisition on the first milliseconds of a recorded sample file.
    Acquire {
        #[command(flatten)]
        file: FileArgs,
        #[command(flatten)]
        search: SearchArgs,
        /// Print one JSON object on stdout instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Acquisition, then tracking of a recorded sample file for its length: per satellite C/N0,
    /// lock time and Doppler over time; with three antennas, `--baselines` and `--sky`, the
    /// attitude.
    Track(TrackArgs),
    /// Run the scenarios (seed 1) and write their figures, units and meanings as Markdown.
    Report {
        /// Only the runs CI can afford (the runs from synthesized samples are left out).
        #[arg(long)]
        quick: bool,
        /// The Markdown file.
        #[arg(long, default_value = "docs/RESULTS.md")]
        out: PathBuf,
    },
    /// Measure the acquisition's detection probability and false alarms on every background
    /// (thermal noise, noise-free, strong signals, saturated, zero, DC, CW) and the phantom
    /// lock of `track` on a noise-free recording; optionally write them as markdown.
    AcquisitionStats {
        /// Thermal-noise recordings (detection probability and false-alarm rate).
        #[arg(long, default_value_t = 200)]
        searches: usize,
        /// Recordings of each other random background.
        #[arg(long, default_value_t = 10)]
        seeds: usize,
        /// Seconds of the noise-free recording tracked.
        #[arg(long, default_value_t = 10.0)]
        track_seconds: f64,
        /// Write the figures into this markdown file (e.g. docs/ACQUISITION.md).
        #[arg(long)]
        markdown: Option<PathBuf>,
        /// Print one JSON object on stdout instead of the markdown.
        #[arg(long)]
        json: bool,
    },
    /// Synthesize a recording (sample files, truth JSON, sky CSV) in any supported layout.
    Synth(SynthArgs),
}

/// `host-sim track`.
#[derive(Args)]
struct TrackArgs {
    #[command(flatten)]
    file: FileArgs,
    #[command(flatten)]
    search: SearchArgs,
    /// Seconds to track (default: the whole recording; longer than the recording: a warning,
    /// the whole recording is tracked).
    #[arg(long, value_parser = limits::track_seconds)]
    seconds: Option<f64>,
    /// Do not re-acquire satellites that lost lock.
    #[arg(long)]
    no_reacquire: bool,
    /// Baselines of antennas 1 and 2 from antenna 0, body frame, m: 'x1,y1,z1;x2,y2,z2'.
    #[arg(long)]
    baselines: Option<String>,
    /// Sky file (lines 'prn,azimuth_deg,elevation_deg'; NED reference frame); without it the
    /// lines of sight come from the decoded navigation message and the position fixes.
    #[arg(long)]
    sky: Option<PathBuf>,
    /// Line biases of antennas 1 and 2 relative to antenna 0, cycles: 'b1,b2' (a bench
    /// calibration; without it they are estimated with the integers in each window).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true, value_parser = limits::finite)]
    line_bias: Option<Vec<f64>>,
    /// Attitude window, s (up to 60).
    #[arg(long, default_value_t = 1.0, value_parser = limits::attitude_window_s)]
    attitude_window: f64,
    /// Print one JSON object on stdout instead of the table.
    #[arg(long)]
    json: bool,
    /// Directory for CSV rows and PNG plots (and the navigation's `track_position.csv` and
    /// `track_nav.rnx`).
    #[arg(long)]
    out: Option<PathBuf>,
    /// A RINEX 2/3 GPS navigation file: ephemerides (and ionosphere) for the satellites not
    /// decoded yet.
    #[arg(long)]
    nav: Option<PathBuf>,
}

/// `host-sim synth`.
#[derive(Args)]
struct SynthArgs {
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
    /// Base name of the files.
    #[arg(long, default_value = "recording")]
    name: String,
    /// Layout (see `acquire --help`).
    #[arg(long)]
    format: String,
    /// Sample rate, Hz (up to 64 MHz).
    #[arg(long, value_parser = limits::sample_rate_hz)]
    fs: f64,
    /// Intermediate frequency, Hz (default 0 for complex layouts, fs/4 for real ones).
    #[arg(long = "if", allow_negative_numbers = true, value_parser = limits::intermediate_frequency_hz)]
    if_hz: Option<f64>,
    /// Duration, s (up to 3600, and at most 16 GiB written).
    #[arg(long, value_parser = limits::synth_seconds)]
    seconds: f64,
    /// Antennas: 1, or 3 (paper 003's 1.5 m triangle).
    #[arg(long, default_value_t = 1)]
    antennas: usize,
    /// LEO dynamics (Dopplers within ±40 kHz, rates within ±60 Hz/s) instead of a static
    /// ground receiver.
    #[arg(long)]
    leo: bool,
    /// Number of satellites, 1-12 (default 8, or as many as `--cn0` values).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=12))]
    satellites: Option<u8>,
    /// C/N0 of each satellite, dB-Hz, up to 60 (comma-separated; instead of the
    /// `--cn0-min`..`--cn0-max` spread).
    #[arg(long, value_delimiter = ',', value_parser = limits::cn0_dbhz)]
    cn0: Option<Vec<f64>>,
    /// Signals only, no thermal noise (quantized with the same gain).
    #[arg(long)]
    no_noise: bool,
    /// A continuous-wave interferer: 'offset_hz,jn_db' (offset from the band centre, power
    /// over the noise power).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true, value_parser = limits::finite)]
    cw: Option<Vec<f64>>,
    /// A constant offset added: 'i,q' in noise σ (16 LSB in CS8).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true, value_parser = limits::finite)]
    dc: Option<Vec<f64>>,
    /// Every sample replaced by 'i,q' in noise σ (e.g. '100,100' saturates: CS8 +127).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true, value_parser = limits::finite)]
    constant: Option<Vec<f64>>,
    /// Lowest C/N0, dB-Hz (0-60).
    #[arg(long, default_value_t = 40.0, value_parser = limits::cn0_dbhz)]
    cn0_min: f64,
    /// Highest C/N0, dB-Hz (0-60).
    #[arg(long, default_value_t = 50.0, value_parser = limits::cn0_dbhz)]
    cn0_max: f64,
    /// Seed of the sky, data and noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Carry the LNAV navigation message and the true geometry of a static receiver (the
    /// bundled almanac's satellites in view) instead of the random sky and data.
    #[arg(long)]
    lnav: bool,
    /// GPS time of the first sample, 'WEEK:TOW' (implies --lnav; default 2195:237003.3).
    #[arg(long)]
    gps_start: Option<String>,
    /// Receiver position 'LAT,LON,H' (degrees, degrees, metres; implies --lnav; default
    /// 48.1374,11.5755,520).
    #[arg(long, allow_negative_numbers = true)]
    position: Option<String>,
}

/// A recording on the command line.
#[derive(Args)]
struct FileArgs {
    /// Sample file; give it once per antenna (antenna order) for single-channel layouts.
    #[arg(long = "file", required = true)]
    files: Vec<PathBuf>,
    /// Layout: cs8, cs16[:S], int8, sm2, sm2iq, bit1, bit1iq, mc2xN, cs8xN, cs16xN[:S], int8xN (README
    /// "Recorded sample files" documents the byte layouts).
    #[arg(long)]
    format: String,
    /// Sample rate, Hz (up to 64 MHz).
    #[arg(long, value_parser = limits::sample_rate_hz)]
    fs: f64,
    /// Intermediate frequency, Hz (required for real layouts; default 0 for complex ones).
    #[arg(long = "if", allow_negative_numbers = true, value_parser = limits::intermediate_frequency_hz)]
    if_hz: Option<f64>,
    /// Channels of a multi-channel file used as antennas 0, 1, ... (comma-separated).
    #[arg(long, value_delimiter = ',')]
    channels: Option<Vec<usize>>,
}

impl FileArgs {
    fn open(&self) -> anyhow::Result<Recording> {
        let format = FileFormat::parse(&self.format)?;
        Recording::open(&RecordingSpec {
            paths: self.files.clone(),
            format,
            sample_rate_hz: self.fs,
            intermediate_frequency_hz: self.if_hz,
            channels: self.channels.clone(),
        })
    }
}

/// Acquisition settings on the command line.
#[derive(Args)]
struct SearchArgs {
    /// Doppler search half-range, Hz (50000 for LEO recordings).
    #[arg(long, default_value_t = 10_000.0, value_parser = limits::doppler_max_hz)]
    doppler_max: f64,
    /// Doppler bin spacing, Hz (10 Hz to 100 kHz).
    #[arg(long, default_value_t = 500.0, value_parser = limits::doppler_step_hz)]
    doppler_step: f64,
    /// Milliseconds summed non-coherently from the file's start (1-100; fewer when the
    /// recording holds less than twice as many, with a warning).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u16).range(1..=100))]
    ms: u16,
    /// PRNs to search (comma-separated; default 1-32).
    #[arg(long, value_delimiter = ',')]
    prns: Option<Vec<u8>>,
    /// False-alarm probability per PRN search, in (0, 0.5).
    #[arg(long, default_value_t = 1e-5, value_parser = limits::false_alarm_probability)]
    pfa: f64,
    /// Antenna searched.
    #[arg(long, default_value_t = 0)]
    antenna: usize,
    /// Margin of the cross-correlation test, dB: a detection at most this much above the
    /// cross-correlation the stronger satellites predict at it is rejected (0 switches the
    /// test off; up to 20).
    #[arg(long, default_value_t = 3.0, value_parser = limits::xcorr_margin_db)]
    xcorr_margin_db: f64,
}

impl SearchArgs {
    fn options(&self) -> AcquireOptions {
        AcquireOptions {
            doppler_max_hz: self.doppler_max,
            doppler_step_hz: self.doppler_step,
            ms: self.ms,
            prns: self.prns.clone().unwrap_or_else(|| (1..=32).collect()),
            false_alarm_probability: self.pfa,
            antenna: self.antenna,
            cross_correlation_margin_db: (self.xcorr_margin_db > 0.0)
                .then_some(self.xcorr_margin_db),
        }
    }
}

/// Runs `f` with the NMEA sink of `--nmea` installed (when given), then closes it.
fn with_nmea(
    path: Option<&std::path::Path>,
    f: impl FnOnce() -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    if let Some(p) = path {
        host_sim::nmea_out::install(p)?;
    }
    let result = f();
    let sentences = host_sim::nmea_out::finish()?;
    if let Some(p) = path {
        eprintln!("host-sim: {sentences} NMEA sentences in {}", p.display());
    }
    result
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::List) => {
            print!("{}", scenarios::listing());
            Ok(())
        }
        Some(Command::Run {
            scenario,
            variant,
            seed,
            json,
            out,
            front_end,
            nmea,
            tle,
        }) => with_nmea(nmea.as_deref(), || {
            let options = RunOptions {
                json,
                out,
                front_end,
                tle,
            };
            run(&scenario, variant.as_deref(), seed, options)
        }),
        Some(Command::Acquire { file, search, json }) => acquire(&file, &search, json),
        Some(Command::Track(args)) => track_command(args),
        Some(Command::Synth(args)) => synth_command(args),
        Some(Command::Report { quick, out }) => host_sim::results::write_report(quick, &out),
        Some(Command::AcquisitionStats {
            searches,
            seeds,
            track_seconds,
            markdown,
            json,
        }) => acquisition_stats(searches, seeds, track_seconds, markdown, json),
        None => run(
            scenarios::DEFAULT_SCENARIO,
            None,
            1,
            RunOptions {
                json: false,
                out: Some(PathBuf::from("out")),
                front_end: Quantizer::I8,
                tle: None,
            },
        ),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("host-sim: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// `host-sim track`.
fn track_command(args: TrackArgs) -> anyhow::Result<()> {
    let TrackArgs {
        file,
        search,
        seconds,
        no_reacquire,
        baselines,
        sky,
        line_bias,
        attitude_window,
        json,
        out,
        nav,
    } = args;
    let nav_file = nav
        .map(|p| {
            let text = limits::read_text_capped(
                &p,
                limits::MAX_NAV_FILE_BYTES,
                limits::MAX_NAV_LINE_CHARS,
                "navigation file",
            )?;
            record::rinex::parse_rinex_nav(&text)
                .with_context(|| format!("navigation file {}", p.display()))
        })
        .transpose()?;
    let attitude = attitude_setup(
        baselines.as_deref(),
        sky.as_deref(),
        line_bias,
        attitude_window,
    )?;
    let opts = record::TrackOptions {
        acquire: search.options(),
        seconds,
        reacquire: !no_reacquire,
        attitude,
        nav_file,
        ..record::TrackOptions::default()
    };
    track(&file, &opts, json, out.as_deref())
}

/// `host-sim synth`.
fn synth_command(args: SynthArgs) -> anyhow::Result<()> {
    let SynthArgs {
        out,
        name,
        format,
        fs,
        if_hz,
        seconds,
        antennas,
        leo,
        satellites,
        cn0,
        no_noise,
        cw,
        dc,
        constant,
        cn0_min,
        cn0_max,
        seed,
        lnav,
        gps_start,
        position,
    } = args;
    let lnav = lnav_spec(lnav, gps_start.as_deref(), position.as_deref())?;
    let overlays = overlays(cw, dc, constant)?;
    let cn0 = cn0.unwrap_or_default();
    let satellites = satellites.map_or(if cn0.is_empty() { 8 } else { cn0.len() }, usize::from);
    let spec = record::SynthSpec {
        format: FileFormat::parse(&format)?,
        sample_rate_hz: fs,
        intermediate_frequency_hz: if_hz,
        seconds,
        antennas,
        dynamics: if leo { Dynamics::Leo } else { Dynamics::Static },
        satellites,
        cn0_min_dbhz: cn0_min,
        cn0_max_dbhz: cn0_max,
        seed,
        noise: !no_noise,
        cn0_dbhz: cn0,
        overlays,
        lnav,
    };
    synth(&out, &name, &spec)
}

/// `--lnav`, `--gps-start WEEK:TOW`, `--position LAT,LON,H`.
fn lnav_spec(
    lnav: bool,
    gps_start: Option<&str>,
    position: Option<&str>,
) -> anyhow::Result<Option<record::synth_nav::LnavSpec>> {
    if !lnav && gps_start.is_none() && position.is_none() {
        return Ok(None);
    }
    let mut spec = record::synth_nav::LnavSpec::default();
    if let Some(text) = gps_start {
        let parsed = text.split_once(':').and_then(|(w, t)| {
            Some((w.trim().parse::<u16>().ok()?, t.trim().parse::<f64>().ok()?))
        });
        let (week, tow) = parsed.with_context(|| {
            format!("--gps-start {text:?}: expected WEEK:TOW, e.g. 2195:237003.3")
        })?;
        spec.week = week;
        spec.tow_s = tow;
    }
    if let Some(text) = position {
        let v: Vec<f64> = text
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .with_context(|| format!("--position {text:?}: expected LAT,LON,H"))?;
        anyhow::ensure!(
            v.len() == 3 && v.iter().all(|x| x.is_finite()),
            "--position {text:?}: three finite numbers LAT,LON,H (degrees, degrees, metres)"
        );
        spec.position_llh = [v[0], v[1], v[2]];
    }
    Ok(Some(spec))
}

fn parse_front_end(s: &str) -> Result<Quantizer, String> {
    Quantizer::parse(s).map_err(|e| e.to_string())
}

/// `host-sim run`'s options beside the scenario, variant and seed.
struct RunOptions {
    json: bool,
    out: Option<PathBuf>,
    front_end: Quantizer,
    tle: Option<PathBuf>,
}

fn run(name: &str, variant: Option<&str>, seed: u64, options: RunOptions) -> anyhow::Result<()> {
    let RunOptions {
        json,
        out,
        front_end,
        tle,
    } = options;
    let scenario = scenarios::find(name)?;
    let variant = scenario.variant(variant)?;
    let tle = tle
        .map(|p| host_sim::truth::tle::Tle::read(&p))
        .transpose()?;
    if let Some(dir) = &out {
        std::fs::create_dir_all(dir)?;
    }
    let ctx = RunContext {
        variant: variant.to_string(),
        seed,
        out_dir: out,
        front_end,
        tle,
    };
    let outcome = scenario.run(&ctx)?;
    let document = outcome.to_json(scenario.name, variant, seed);
    if json {
        println!("{}", serde_json::to_string(&document)?);
    } else {
        print_human(&document, &outcome);
    }
    Ok(())
}

fn acquire(file: &FileArgs, search: &SearchArgs, json: bool) -> anyhow::Result<()> {
    let rec = file.open()?;
    let (report, _) = record::acquire(&rec, &search.options())?;
    if json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        record::acquire::print_report(&report);
    }
    Ok(())
}

fn synth(out: &std::path::Path, name: &str, spec: &record::SynthSpec) -> anyhow::Result<()> {
    let (truth, paths) = record::write_recording(out, name, spec)
        .with_context(|| format!("synthesizing into {}", out.display()))?;
    let files: Vec<String> = paths
        .iter()
        .map(|p| format!("--file {}", p.display()))
        .collect();
    eprintln!(
        "synth: {} satellites, {:.3} s, {} ({}); truth in {}",
        truth.satellites.len(),
        truth.seconds,
        truth.format,
        truth.dynamics,
        out.join(format!("{name}.truth.json")).display()
    );
    println!(
        "{} --format {} --fs {} --if {}",
        files.join(" "),
        truth.format,
        truth.sample_rate_hz,
        truth.intermediate_frequency_hz
    );
    Ok(())
}

fn acquisition_stats(
    searches: usize,
    seeds: usize,
    track_seconds: f64,
    markdown: Option<PathBuf>,
    json: bool,
) -> anyhow::Result<()> {
    use record::acquisition_stats as stats;
    anyhow::ensure!(
        track_seconds.is_finite() && track_seconds >= 1.0,
        "--track-seconds {track_seconds} must be at least 1"
    );
    let report = stats::measure(&stats::StatsOptions {
        thermal_searches: searches,
        seeds,
        track_seconds,
        work_dir: std::env::temp_dir().join(format!("host-sim-acq-stats-{}", std::process::id())),
    })?;
    let text = stats::markdown(&report, &stats::today(), &stats::commit());
    if let Some(path) = markdown {
        std::fs::write(&path, &text).with_context(|| format!("writing {}", path.display()))?;
    }
    if json {
        println!("{}", serde_json::to_string(&report)?);
    } else {
        print!("{text}");
    }
    Ok(())
}

/// The `--cw`, `--dc` and `--constant` overlays of `synth`.
fn overlays(
    cw: Option<Vec<f64>>,
    dc: Option<Vec<f64>>,
    constant: Option<Vec<f64>>,
) -> anyhow::Result<Vec<record::synthesize::Overlay>> {
    use record::synthesize::Overlay;
    let pair = |v: &[f64], name: &str| -> anyhow::Result<(f64, f64)> {
        anyhow::ensure!(
            v.len() == 2 && v.iter().all(|x| x.is_finite()),
            "--{name} takes two finite values"
        );
        Ok((v[0], v[1]))
    };
    let mut out = Vec::new();
    if let Some(v) = constant {
        let (i, q) = pair(&v, "constant")?;
        out.push(Overlay::Constant { i, q });
    }
    if let Some(v) = dc {
        let (i, q) = pair(&v, "dc")?;
        out.push(Overlay::Dc { i, q });
    }
    if let Some(v) = cw {
        let (offset_hz, jn_db) = pair(&v, "cw")?;
        out.push(Overlay::Cw { offset_hz, jn_db });
    }
    Ok(out)
}

fn attitude_setup(
    baselines: Option<&str>,
    sky: Option<&std::path::Path>,
    line_bias: Option<Vec<f64>>,
    window_s: f64,
) -> anyhow::Result<Option<record::attitude::AttitudeSetup>> {
    let Some(baselines) = baselines else {
        anyhow::ensure!(
            sky.is_none() && line_bias.is_none(),
            "--sky and --line-bias go with --baselines"
        );
        return Ok(None);
    };
    let sky = sky
        .map(|sky| -> anyhow::Result<_> {
            let text = limits::read_text_capped(
                sky,
                limits::MAX_SKY_FILE_BYTES,
                limits::MAX_SKY_LINE_CHARS,
                "sky file",
            )?;
            record::attitude::parse_sky(&text)
                .with_context(|| format!("sky file {}", sky.display()))
        })
        .transpose()?
        .unwrap_or_default();
    let bias = line_bias
        .map(|b| {
            anyhow::ensure!(
                b.len() == 2 && b.iter().all(|v| v.is_finite()),
                "--line-bias needs two values (antennas 1 and 2, cycles)"
            );
            Ok([b[0], b[1]])
        })
        .transpose()?;
    Ok(Some(record::attitude::AttitudeSetup {
        baselines_body_m: record::attitude::parse_baselines(baselines)?,
        line_bias_cycles: bias,
        sky,
        window_s,
    }))
}

fn track(
    file: &FileArgs,
    opts: &record::TrackOptions,
    json: bool,
    out: Option<&std::path::Path>,
) -> anyhow::Result<()> {
    let rec = file.open()?;
    let mut run = record::track(&rec, opts)?;
    if let Some(dir) = out {
        run.report.files_written = record::report::write_track_files(dir, &run)?;
    }
    if json {
        println!("{}", serde_json::to_string(&run.report)?);
    } else {
        record::report::print_track(&run);
    }
    Ok(())
}
