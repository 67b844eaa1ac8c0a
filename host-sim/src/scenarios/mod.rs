//! The scenarios: one module per experiment, each a [`Scenario`] in [`SCENARIOS`].
//!
//! A scenario takes a [`RunContext`] (variant, seed, output directory) and returns an
//! [`Outcome`]: metrics named as its issue specifies, the paper's figures for the same case,
//! human summary lines, and the files it wrote. It reports progress on stderr only.
//!
//! To add a scenario: write `scenarios/<name>.rs` with a `pub const SCENARIO: Scenario`, declare
//! the module below and append it to [`SCENARIOS`].

use std::path::PathBuf;

use anyhow::{anyhow, bail};
use serde_json::{json, Map, Value};

pub mod dcm;
pub mod gyro_cal;
pub mod gyro_cal_gnss;
pub mod microsat;
pub mod one_stage;
pub mod signal;
pub mod snapshot;
pub mod vector_ekf;

/// Every scenario host-sim can run, in the order `host-sim list` shows them.
pub const SCENARIOS: &[Scenario] = &[
    vector_ekf::SCENARIO,
    snapshot::SCENARIO,
    dcm::SCENARIO,
    gyro_cal::SCENARIO,
    signal::SCENARIO,
    one_stage::SCENARIO,
    microsat::SCENARIO,
];

/// What `host-sim` runs when called without arguments.
pub const DEFAULT_SCENARIO: &str = "microsat";

/// One experiment.
pub struct Scenario {
    /// Name on the command line (`host-sim run <name>`).
    pub name: &'static str,
    /// One line for `host-sim list`.
    pub about: &'static str,
    /// The variants; the first is the default.
    pub variants: &'static [Variant],
    /// Runs it.
    pub run: fn(&RunContext) -> anyhow::Result<Outcome>,
}

/// A variant of a scenario.
pub struct Variant {
    /// Name on the command line (`--variant <name>`).
    pub name: &'static str,
    /// One line for `host-sim list`.
    pub about: &'static str,
}

/// What a scenario run is asked to do.
#[derive(Clone, Debug)]
pub struct RunContext {
    /// The variant's name (already validated).
    pub variant: String,
    /// Seed of every random stream of the run.
    pub seed: u64,
    /// Where to write CSV and PNG files; `None` writes nothing.
    pub out_dir: Option<PathBuf>,
}

/// What a scenario run produced.
#[derive(Clone, Debug, Default)]
pub struct Outcome {
    /// Metrics, named as the scenario's issue specifies (numbers, arrays of numbers, booleans).
    pub metrics: Map<String, Value>,
    /// The source paper's figures for the same case (`null` when the paper has none).
    pub paper: Value,
    /// Lines for the human summary (stdout without `--json`).
    pub summary: Vec<String>,
    /// Files written into the output directory.
    pub files: Vec<PathBuf>,
}

impl Outcome {
    /// Adds a metric.
    pub fn metric(&mut self, name: &str, value: impl Into<Value>) -> &mut Self {
        self.metrics.insert(name.to_string(), value.into());
        self
    }

    /// The JSON document printed by `--json`:
    /// `{scenario, variant, seed, metrics, paper, files}`.
    pub fn to_json(&self, scenario: &str, variant: &str, seed: u64) -> Value {
        json!({
            "scenario": scenario,
            "variant": variant,
            "seed": seed,
            "metrics": Value::Object(self.metrics.clone()),
            "paper": self.paper.clone(),
            "files": self.files.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        })
    }
}

impl Scenario {
    /// The variant called `name`, or the default (first) one for `None`.
    pub fn variant(&self, name: Option<&str>) -> anyhow::Result<&'static str> {
        match name {
            None => self
                .variants
                .first()
                .map(|v| v.name)
                .ok_or_else(|| anyhow!("scenario {} has no variants", self.name)),
            Some(n) => match self.variants.iter().find(|v| v.name == n) {
                Some(v) => Ok(v.name),
                None => bail!(
                    "scenario {} has no variant {n:?}; variants: {}",
                    self.name,
                    self.variants
                        .iter()
                        .map(|v| v.name)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            },
        }
    }
}

/// The scenario called `name`.
pub fn find(name: &str) -> anyhow::Result<&'static Scenario> {
    SCENARIOS.iter().find(|s| s.name == name).ok_or_else(|| {
        anyhow!(
            "no scenario {name:?}; scenarios: {}",
            SCENARIOS
                .iter()
                .map(|s| s.name)
                .collect::<Vec<_>>()
                .join(", ")
        )
    })
}

/// Runs scenario `name` (variant `variant` or the default) without writing files: the entry
/// point for tests.
pub fn run_by_name(name: &str, variant: Option<&str>, seed: u64) -> anyhow::Result<Outcome> {
    let scenario = find(name)?;
    let variant = scenario.variant(variant)?;
    (scenario.run)(&RunContext {
        variant: variant.to_string(),
        seed,
        out_dir: None,
    })
}

/// The text of `host-sim list`.
pub fn listing() -> String {
    let mut s = String::new();
    for sc in SCENARIOS {
        let default = if sc.name == DEFAULT_SCENARIO {
            " (default)"
        } else {
            ""
        };
        s.push_str(&format!("{}{default}: {}\n", sc.name, sc.about));
        for v in sc.variants {
            s.push_str(&format!("    --variant {:<18} {}\n", v.name, v.about));
        }
    }
    s
}
