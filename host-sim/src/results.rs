//! `host-sim report`: runs the scenarios (in-process, seed 1) and writes `docs/RESULTS.md`,
//! so that no figure of the documentation is copied by hand.
//!
//! The file has a header (date, commit, the command), then the [`QUICK`] runs between
//! [`QUICK_BEGIN`] and [`QUICK_END`] (what CI regenerates and compares, `.ci/results.sh`),
//! then the [`FULL`] runs (without `--quick`), then the wall-clock times of every run, which
//! change from run to run and are never compared.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};

use crate::report::markdown::{render, Rendered};
use crate::scenarios::{self, RunContext};

/// The seed of every run of the report.
pub const SEED: u64 = 1;

/// The runs CI can afford (about a minute on two cores): `(scenario, variant)`.
pub const QUICK: &[(&str, &str)] = &[
    ("vector-ekf", "nominal"),
    ("vector-ekf", "fast-tumble"),
    ("snapshot", "paper"),
    ("snapshot", "ambiguity"),
    ("snapshot", "four-antenna"),
    ("dcm", "paper"),
    ("dcm", "intensity"),
    ("dcm", "wide"),
    ("dcm", "leo"),
    ("gyro-cal", "exact"),
    ("gyro-cal", "quantized"),
    ("gyro-cal", "centered-5.5"),
    ("gyro-cal", "centered-5.6"),
    ("gyro-cal", "gnss-ref"),
    ("one-stage", "8sat-2hz-iq"),
    ("one-stage", "8sat-0.5hz-iq"),
    ("one-stage", "2sat-2hz-iq"),
    ("one-stage", "8sat-2hz-init5deg-iq"),
    ("one-stage", "dynamic-iq"),
    ("one-stage", "linebias-iq"),
    ("microsat", "short"),
];

/// The runs from synthesized samples (minutes): the main job, the signal chain, paper 003
/// from samples.
pub const FULL: &[(&str, &str)] = &[
    ("microsat", "nadir"),
    ("microsat", "detumbling"),
    ("signal", "35dbhz"),
    ("signal", "40dbhz"),
    ("signal", "45dbhz"),
    ("one-stage", "8sat-2hz"),
    ("one-stage", "8sat-0.5hz"),
    ("one-stage", "2sat-2hz"),
    ("one-stage", "8sat-2hz-init5deg"),
    ("one-stage", "dynamic"),
    ("one-stage", "linebias"),
];

/// Marks the start of the part CI compares.
pub const QUICK_BEGIN: &str = "<!-- quick results: begin (checked by .ci/results.sh) -->";
/// Marks its end.
pub const QUICK_END: &str = "<!-- quick results: end -->";

/// One run in the report.
struct Section {
    scenario: &'static str,
    variant: &'static str,
    about: &'static str,
    rendered: Rendered,
}

/// Runs `(scenario, variant)` with [`SEED`] and renders it.
fn run_one(scenario: &str, variant: &str) -> Result<Section> {
    let sc = scenarios::find(scenario)?;
    let variant = sc.variant(Some(variant))?;
    let about = sc
        .variants
        .names()
        .into_iter()
        .find(|v| v.0 == variant)
        .map_or("", |v| v.1);
    eprintln!("report: {} / {variant}", sc.name);
    let outcome = sc
        .run(&RunContext {
            variant: variant.to_string(),
            seed: SEED,
            out_dir: None,
        })
        .with_context(|| format!("running {} / {variant}", sc.name))?;
    Ok(Section {
        scenario: sc.name,
        variant,
        about,
        rendered: render(&outcome).with_context(|| format!("{} / {variant}", sc.name))?,
    })
}

fn write_sections(s: &mut String, sections: &[Section]) {
    let mut last = "";
    for sec in sections {
        if sec.scenario != last {
            let about = scenarios::find(sec.scenario).map_or("", |sc| sc.about);
            let _ = writeln!(s, "## `{}`\n\n{about}\n", sec.scenario);
            last = sec.scenario;
        }
        let _ = writeln!(
            s,
            "### `{}` / `{}`\n\n{}\n\n`host-sim run {} --variant {} --seed {SEED} --json`\n",
            sec.scenario, sec.variant, sec.about, sec.scenario, sec.variant
        );
        let _ = writeln!(s, "{}", sec.rendered.results);
    }
}

fn write_wall_times(s: &mut String, sections: &[&Section]) {
    let _ = writeln!(
        s,
        "## Wall-clock times\n\nOf this generation, on the machine that ran it; they change from run to run and \
         are not compared.\n\n| run | metric | value | unit |\n|---|---|---|---|"
    );
    for sec in sections {
        for (name, value, unit) in &sec.rendered.wall_times {
            let _ = writeln!(
                s,
                "| `{}` / `{}` | `{name}` | {value} | {unit} |",
                sec.scenario, sec.variant
            );
        }
    }
}

/// The short commit of the working tree, or "unknown".
fn commit() -> String {
    std::process::Command::new("git")
        .args(["rev-parse", "--short", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "unknown".into())
}

/// Today's date (UTC) as `YYYY-MM-DD`.
fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (y, m, d) = civil_from_days((secs / 86_400) as i64);
    format!("{y:04}-{m:02}-{d:02}")
}

/// The proleptic Gregorian date of day `z` since 1970-01-01 (H. Hinnant's algorithm).
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

/// Runs the report's scenarios ([`QUICK`], and [`FULL`] unless `quick`) and writes the
/// Markdown to `out`.
///
/// # Errors
/// A run that fails, a metric without a description, I/O.
pub fn write_report(quick: bool, out: &Path) -> Result<()> {
    let command = format!(
        "host-sim report{} --out {}",
        if quick { " --quick" } else { "" },
        out.display()
    );
    let quick_runs = QUICK
        .iter()
        .map(|(s, v)| run_one(s, v))
        .collect::<Result<Vec<_>>>()?;
    let full_runs = if quick {
        Vec::new()
    } else {
        FULL.iter()
            .map(|(s, v)| run_one(s, v))
            .collect::<Result<Vec<_>>>()?
    };
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Results\n\nGenerated by `host-sim report`, not written by hand: every figure below is a metric of a \
         scenario run (seed {SEED}), with its unit, its meaning and, where the source paper has one, the paper's \
         figure for the same case.\n\n* date: {}\n* commit: {}\n* command: `{command}` (from the repository \
         root; `cargo run --release -p host-sim -- report`)\n* runs: {} quick (checked by CI: `.ci/results.sh` \
         regenerates them and fails if a number differs){}\n",
        today(),
        commit(),
        quick_runs.len(),
        if quick {
            String::from("; the runs from samples are left out (`--quick`)")
        } else {
            format!(", {} from synthesized samples", full_runs.len())
        }
    );
    let _ = writeln!(s, "{QUICK_BEGIN}\n");
    write_sections(&mut s, &quick_runs);
    let _ = writeln!(s, "{QUICK_END}\n");
    if !quick {
        let _ = writeln!(s, "# From synthesized samples (not run by CI)\n");
        write_sections(&mut s, &full_runs);
    }
    let all: Vec<&Section> = quick_runs.iter().chain(&full_runs).collect();
    write_wall_times(&mut s, &all);
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    std::fs::write(out, s).with_context(|| format!("writing {}", out.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_from_days() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(civil_from_days(20_423), (2025, 12, 1));
    }

    #[test]
    fn every_listed_run_exists() {
        for (s, v) in QUICK.iter().chain(FULL) {
            let sc = scenarios::find(s).unwrap();
            assert_eq!(sc.variant(Some(v)).unwrap(), *v);
        }
    }
}
