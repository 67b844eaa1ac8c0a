//! The scenarios: one module per experiment, each a [`Scenario`] in [`SCENARIOS`].
//!
//! A scenario's variants are one table ([`Variants`]): each variant's name, description and
//! configuration, and the one function that runs a configuration with a [`RunContext`] (variant,
//! seed, output directory). It returns an [`Outcome`]: its metrics struct (declared with
//! [`metrics!`](crate::metrics), named as its issue specifies), the paper's figures for the
//! same case, human summary lines, and the files it wrote. It reports progress on stderr only.
//!
//! To add a scenario: write `scenarios/<name>.rs` with a `pub const SCENARIO: Scenario`, declare
//! the module below and append it to [`SCENARIOS`]. To add a variant: add a row to its table.

use anyhow::{anyhow, bail};

pub use crate::outcome::{Outcome, RunContext};
use crate::synth::quantize::Quantizer;

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

/// The scenarios whose sample-level path takes `--front-end` other than `i8`.
pub const FRONT_END_SCENARIOS: &[&str] = &["signal", "one-stage", "microsat"];

/// The scenarios that fly a TLE (`--tle`) instead of their built-in orbit.
pub const TLE_SCENARIOS: &[&str] = &["microsat"];

/// A run option the scenario cannot use (`--tle` for a scenario without an orbit to replace).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnsupportedOption {
    /// The scenario asked.
    pub scenario: &'static str,
    /// The option, as on the command line.
    pub option: &'static str,
    /// The scenarios that take it.
    pub supported: &'static [&'static str],
}

impl std::fmt::Display for UnsupportedOption {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "scenario {} cannot use {} (only {})",
            self.scenario,
            self.option,
            self.supported.join(", ")
        )
    }
}

impl std::error::Error for UnsupportedOption {}

/// What `host-sim` runs when called without arguments.
pub const DEFAULT_SCENARIO: &str = "microsat";

/// One experiment.
pub struct Scenario {
    /// Name on the command line (`host-sim run <name>`).
    pub name: &'static str,
    /// One line for `host-sim list`.
    pub about: &'static str,
    /// Its variants, each with what it runs; the first is the default.
    pub variants: &'static dyn VariantTable,
}

/// A variant of a scenario: its name, a line for `host-sim list`, and what it runs (`config`,
/// of the scenario's own type: a configuration, a constructor, a function).
pub struct Variant<C: 'static> {
    /// Name on the command line (`--variant <name>`).
    pub name: &'static str,
    /// One line for `host-sim list`.
    pub about: &'static str,
    /// What the variant runs, handed to its scenario's runner.
    pub config: C,
}

/// A scenario's variants and the one function that runs any of them: a variant cannot exist
/// without its configuration, nor run another's.
pub struct Variants<C: 'static> {
    /// The variants; the first is the default.
    pub list: &'static [Variant<C>],
    /// Runs a variant's configuration.
    pub run: fn(&C, &RunContext) -> anyhow::Result<Outcome>,
}

impl<C> Variant<C> {
    /// The variant `name` (`about` for `host-sim list`) running `config`.
    pub const fn new(name: &'static str, about: &'static str, config: C) -> Self {
        Self {
            name,
            about,
            config,
        }
    }
}

impl<C> Variants<C> {
    /// The variant called `name`.
    ///
    /// # Errors
    /// No variant of that name.
    pub fn get(&self, name: &str) -> anyhow::Result<&'static Variant<C>> {
        self.list.iter().find(|v| v.name == name).ok_or_else(|| {
            anyhow!(
                "no variant {name:?}; variants: {}",
                self.list
                    .iter()
                    .map(|v| v.name)
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
    }
}

/// The variants of a scenario, whatever their configuration type.
pub trait VariantTable: Sync {
    /// `(name, about)` of each variant; the first is the default.
    fn names(&self) -> Vec<(&'static str, &'static str)>;
    /// Runs the variant called `ctx.variant`.
    ///
    /// # Errors
    /// No such variant, or the run's own error.
    fn run(&self, ctx: &RunContext) -> anyhow::Result<Outcome>;
}

impl<C: Sync> VariantTable for Variants<C> {
    fn names(&self) -> Vec<(&'static str, &'static str)> {
        self.list.iter().map(|v| (v.name, v.about)).collect()
    }

    fn run(&self, ctx: &RunContext) -> anyhow::Result<Outcome> {
        let variant = self.get(&ctx.variant)?;
        (self.run)(&variant.config, ctx)
    }
}

impl Scenario {
    /// The variant called `name`, or the default (first) one for `None`.
    pub fn variant(&self, name: Option<&str>) -> anyhow::Result<&'static str> {
        let names = self.variants.names();
        match name {
            None => names
                .first()
                .map(|v| v.0)
                .ok_or_else(|| anyhow!("scenario {} has no variants", self.name)),
            Some(n) => match names.iter().find(|v| v.0 == n) {
                Some(v) => Ok(v.0),
                None => bail!(
                    "scenario {} has no variant {n:?}; variants: {}",
                    self.name,
                    names.iter().map(|v| v.0).collect::<Vec<_>>().join(", ")
                ),
            },
        }
    }

    /// Runs the variant `ctx.variant`.
    ///
    /// # Errors
    /// No such variant, an option the scenario cannot use ([`UnsupportedOption`] for
    /// `--tle`), or the run's own error.
    pub fn run(&self, ctx: &RunContext) -> anyhow::Result<Outcome> {
        if ctx.front_end != Quantizer::I8 && !FRONT_END_SCENARIOS.contains(&self.name) {
            bail!(
                "scenario {} has no sample-level path for --front-end {} (only {})",
                self.name,
                ctx.front_end,
                FRONT_END_SCENARIOS.join(", ")
            );
        }
        if ctx.tle.is_some() && !TLE_SCENARIOS.contains(&self.name) {
            return Err(UnsupportedOption {
                scenario: self.name,
                option: "--tle",
                supported: TLE_SCENARIOS,
            }
            .into());
        }
        self.variants.run(ctx)
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
    run_front_end(name, variant, seed, Quantizer::I8)
}

/// [`run_by_name`] with the front end `front_end` (`--front-end`).
pub fn run_front_end(
    name: &str,
    variant: Option<&str>,
    seed: u64,
    front_end: Quantizer,
) -> anyhow::Result<Outcome> {
    let scenario = find(name)?;
    let variant = scenario.variant(variant)?;
    scenario.run(&RunContext {
        variant: variant.to_string(),
        seed,
        out_dir: None,
        front_end,
        tle: None,
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
        for (name, about) in sc.variants.names() {
            s.push_str(&format!("    --variant {name:<18} {about}\n"));
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_scenario_has_variants_with_distinct_names_and_a_default() {
        for sc in SCENARIOS {
            let names: Vec<&str> = sc.variants.names().iter().map(|v| v.0).collect();
            assert!(!names.is_empty(), "{}", sc.name);
            let mut unique = names.clone();
            unique.sort_unstable();
            unique.dedup();
            assert_eq!(unique.len(), names.len(), "{}: {names:?}", sc.name);
            assert_eq!(sc.variant(None).unwrap(), names[0]);
            assert!(sc.variant(Some("no-such-variant")).is_err());
        }
        assert!(find(DEFAULT_SCENARIO).is_ok());
    }
}
