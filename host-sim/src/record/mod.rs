//! Recorded sample files from real front ends: reading them in every supported layout, and
//! running the core's signal chain on them (`host-sim acquire`, `host-sim track`), plus the
//! synthesized recordings that test it (`host-sim synth`).
//!
//! * [`format`](mod@format): the `--format` names and byte layouts (single- and multi-channel).
//! * [`limits`]: the ranges of the commands' options (clap value parsers), `synth`'s largest
//!   output, text inputs read with a size cap.
//! * [`reader`]: validation with clear errors, and streaming block reads (bounded memory).
//! * [`acquire`](mod@acquire): acquisition over the first milliseconds.
//! * [`acquisition_stats`]: detection and false alarms measured on every background.
//! * [`track`](mod@track): acquisition, tracking with re-acquisition, per-satellite reports.
//! * [`satellite`]: per-satellite state and summaries of `track`, thermal C/N0.
//! * [`report`]: the human table, CSV and PNG files of `track`.
//! * [`attitude`]: three-antenna recordings through the ambiguity resolver and the snapshot
//!   attitude solver.
//! * [`attitude_setup`]: `--baselines`, `--sky`, `--line-bias`.
//! * [`synthesize`]: synthesized recordings with their truth.
//! * [`synth_nav`]: the LNAV sky of a synthesized recording (`synth --lnav`).
//! * [`navigation`]: `track`'s navigation: LNAV decoding, pseudoranges, fixes, lines of sight.
//! * [`rinex`]: RINEX navigation files, written (3.04) and read (2.xx, 3.xx).

pub mod acquire;
pub mod acquisition_stats;
pub mod attitude;
pub mod attitude_setup;
pub mod format;
pub mod limits;
pub mod navigation;
pub mod reader;
pub mod report;
pub mod rinex;
pub mod satellite;
pub mod synth_nav;
pub mod synthesize;
pub mod track;

pub use acquire::{acquire, AcquireOptions, AcquireReport, Detection};
pub use format::FileFormat;
pub use reader::{Recording, RecordingSpec};
pub use synthesize::{write_recording, Dynamics, RecordingTruth, SynthSpec};
pub use track::{track, TrackOptions, TrackReport};
