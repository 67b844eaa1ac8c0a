//! Output of the scenarios: the human summary, progress bars, CSV time series, PNG plots, and
//! the Markdown of `docs/RESULTS.md` ([`markdown`]).

mod csv_out;
pub mod markdown;
mod plot;

use indicatif::{ProgressBar, ProgressStyle};
use serde_json::Value;

use crate::outcome::Outcome;

pub use csv_out::write_csv;
pub use plot::{palette, plot_lines, plot_panels, Dash, Panel, Series};

/// A progress bar on stderr for `len` steps. indicatif hides it when stderr is not a terminal,
/// so it never pollutes `--json` output or CI logs.
pub fn progress(len: u64, message: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    bar.set_style(
        ProgressStyle::with_template(
            "{msg:>14} [{bar:40}] {pos}/{len} {elapsed_precise} eta {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    bar.set_message(message.to_string());
    bar
}

/// Prints the human summary of a run on stdout: the scenario's own lines, then the metrics and
/// the paper's figures as indented JSON values.
pub fn print_human(document: &Value, outcome: &Outcome) {
    println!(
        "scenario {} / variant {} / seed {}",
        document["scenario"].as_str().unwrap_or("?"),
        document["variant"].as_str().unwrap_or("?"),
        document["seed"]
    );
    for line in &outcome.summary {
        println!("  {line}");
    }
    println!("metrics:");
    for (k, v) in &outcome.metrics {
        println!("  {k:<28} {}", format_value(v));
    }
    if !outcome.paper.is_null() {
        println!("paper:");
        match &outcome.paper {
            Value::Object(map) => {
                for (k, v) in map {
                    println!("  {k:<28} {}", format_value(v));
                }
            }
            other => println!("  {}", format_value(other)),
        }
    }
    if !outcome.files.is_empty() {
        println!("files:");
        for f in &outcome.files {
            println!("  {}", f.display());
        }
    }
}

fn format_value(v: &Value) -> String {
    match v {
        Value::Number(n) => match n.as_f64() {
            Some(x) if n.is_f64() => format_number(x),
            _ => n.to_string(),
        },
        Value::Array(items) => {
            let parts: Vec<String> = items.iter().map(format_value).collect();
            format!("[{}]", parts.join(", "))
        }
        other => other.to_string(),
    }
}

fn format_number(x: f64) -> String {
    if x == 0.0 || (1e-3..1e5).contains(&x.abs()) {
        format!("{x:.4}")
    } else {
        format!("{x:.4e}")
    }
}
