//! host-sim: the desktop twin of `gnss-attitude`.
//!
//! It synthesizes what the onboard crate consumes — truth motion, satellite geometry,
//! three-antenna signals and measurements — runs the crate's estimators on it, and reports the
//! result against the truth, against the theoretical bound for the same data, and against the
//! figures printed in the source papers.
//!
//! * [`outcome`]: what a scenario run is given and returns (shared by scenarios and report).
//! * [`arrays`]: antenna arrays shared by the synthesized scenes.
//! * [`chain`]: the core's signal chain (acquisition, tracking) run on synthesized samples.
//! * [`scenarios`]: one module per experiment, registered in [`scenarios::SCENARIOS`].
//! * [`truth`]: the f64 truth models (attitude kinematics, ...).
//! * [`report`]: the human summary, CSV time series, PNG plots, progress bars, and
//!   `docs/RESULTS.md` (`host-sim report`).
//! * [`results`]: `host-sim report`, the scenarios' figures into `docs/RESULTS.md`.
//! * [`stats`]: small statistics helpers (RMS, percentiles, χ² intervals).
//! * [`synth`]: the coherent three-antenna GPS L1 C/A sample synthesizer.
//! * [`record`]: recorded sample files: layouts, streaming reader, `acquire` / `track` / `synth`
//!   commands.

pub mod arrays;
pub mod chain;
pub mod nmea_out;
pub mod open_loop;
pub mod outcome;
pub mod record;
pub mod report;
pub mod results;
pub mod scenarios;
pub mod stats;
pub mod synth;
pub mod truth;
