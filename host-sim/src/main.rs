//! `host-sim`: run the scenarios of gnss-attitude on the desktop.
//!
//! ```text
//! host-sim                                   # the default scenario, files into out/
//! host-sim list                              # scenarios and their variants
//! host-sim run <scenario> [--variant V] [--seed N] [--json] [--out DIR]
//! ```
//! With `--json`, stdout carries exactly one JSON object; progress and logs go to stderr.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use host_sim::report::print_human;
use host_sim::scenarios::{self, RunContext};

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
    },
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
        }) => run(&scenario, variant.as_deref(), seed, json, out),
        None => run(
            scenarios::DEFAULT_SCENARIO,
            None,
            1,
            false,
            Some(PathBuf::from("out")),
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

fn run(
    name: &str,
    variant: Option<&str>,
    seed: u64,
    json: bool,
    out: Option<PathBuf>,
) -> anyhow::Result<()> {
    let scenario = scenarios::find(name)?;
    let variant = scenario.variant(variant)?;
    if let Some(dir) = &out {
        std::fs::create_dir_all(dir)?;
    }
    let ctx = RunContext {
        variant: variant.to_string(),
        seed,
        out_dir: out,
    };
    let outcome = (scenario.run)(&ctx)?;
    let document = outcome.to_json(scenario.name, variant, seed);
    if json {
        println!("{}", serde_json::to_string(&document)?);
    } else {
        print_human(&document, &outcome);
    }
    Ok(())
}
