//! One scenario run as Markdown for `docs/RESULTS.md`: a table of its metrics with their
//! units, meanings and the paper's figure where the paper has one, sub-tables for lists of
//! records (faults, structures), the paper's figures, and its wall-clock times apart (they
//! change from run to run and are never compared).

use std::fmt::Write as _;

use anyhow::{bail, Result};
use serde_json::{Map, Value};

use crate::outcome::{find_field_in, Field, Nesting, Outcome};

/// A run rendered: the Markdown of its results, and its wall-clock times.
#[derive(Clone, Debug, Default)]
pub struct Rendered {
    /// The tables (deterministic for a given commit and seed).
    pub results: String,
    /// `(metric, value, unit)` of each wall-clock time.
    pub wall_times: Vec<(String, String, String)>,
}

/// A metric row.
struct Row {
    name: String,
    value: String,
    unit: &'static str,
    paper: String,
    about: String,
}

/// A list of records (an array of objects) shown as its own table.
struct Records<'a> {
    name: String,
    about: String,
    fields: &'static [Field],
    items: &'a [Value],
}

/// What the walk over the metrics collects.
#[derive(Default)]
struct Collected<'a> {
    rows: Vec<Row>,
    records: Vec<Records<'a>>,
    wall: Vec<(String, String, String)>,
}

/// Significant digits of the numbers in the tables.
const SIGNIFICANT: i32 = 4;
/// Magnitudes shown in fixed notation; others in scientific notation.
const FIXED_RANGE: std::ops::Range<f64> = 1e-3..1e5;

/// A number to four significant digits (fixed notation from 0.001 to 100 000).
pub fn number(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    if !x.is_finite() {
        return x.to_string();
    }
    if FIXED_RANGE.contains(&x.abs()) {
        let decimals = (SIGNIFICANT - 1 - x.abs().log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.prec$e}", prec = (SIGNIFICANT - 1) as usize)
    }
}

/// A JSON value as table text: numbers to four digits, arrays joined by " / ", null as "—".
pub fn value_text(v: &Value) -> String {
    match v {
        Value::Null => "—".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => match (n.as_u64(), n.as_i64(), n.as_f64()) {
            (Some(u), _, _) => u.to_string(),
            (_, Some(i), _) => i.to_string(),
            (_, _, Some(x)) => number(x),
            _ => n.to_string(),
        },
        Value::String(s) => cell(s),
        Value::Array(items) => items.iter().map(value_text).collect::<Vec<_>>().join(" / "),
        Value::Object(_) => cell(&v.to_string()),
    }
}

/// Text safe in a table cell.
fn cell(s: &str) -> String {
    s.trim().replace('|', "\\|").replace('\n', " ")
}

/// A figure quoted from a paper, as printed (no digits added): numbers in their shortest
/// form, arrays joined by " / ".
pub fn quoted_text(v: &Value) -> String {
    match v {
        Value::Number(n) => n.to_string(),
        Value::Array(items) => items
            .iter()
            .map(quoted_text)
            .collect::<Vec<_>>()
            .join(" / "),
        other => value_text(other),
    }
}

/// The paper's figure for top-level metric `name`: `paper[name]`, or `paper.paper[name]`.
fn paper_figure(paper: &Value, name: &str) -> String {
    paper
        .get(name)
        .or_else(|| paper.get("paper").and_then(|p| p.get(name)))
        .map_or_else(String::new, quoted_text)
}

fn collect<'a>(
    fields: &'static [Field],
    map: &'a Map<String, Value>,
    prefix: &str,
    paper: &Value,
    out: &mut Collected<'a>,
) -> Result<()> {
    for (key, value) in map {
        let Some((field, group)) = find_field_in(fields, key) else {
            bail!("metric {prefix}{key} has no description in its metrics struct");
        };
        // a suffixed group's doc says what its suffix means
        let about = match group {
            Some(g) => format!("{} ({})", cell(field.about), cell(g.about)),
            None => cell(field.about),
        };
        let name = format!("{prefix}{key}");
        match (field.nesting, value) {
            (Nesting::Object(inner), Value::Object(m)) => {
                collect(inner, m, &format!("{name}."), paper, out)?;
            }
            (Nesting::Object(inner), Value::Array(items)) => out.records.push(Records {
                name,
                about,
                fields: inner,
                items,
            }),
            _ if field.wall_time => {
                out.wall
                    .push((name, value_text(value), field.unit.to_string()));
            }
            _ => out.rows.push(Row {
                paper: if prefix.is_empty() {
                    paper_figure(paper, key)
                } else {
                    String::new()
                },
                name,
                value: value_text(value),
                unit: field.unit,
                about,
            }),
        }
    }
    Ok(())
}

/// The metrics table (with a paper column when the paper has a figure for one of them).
fn write_rows(s: &mut String, rows: &[Row]) {
    let with_paper = rows.iter().any(|r| !r.paper.is_empty());
    if with_paper {
        let _ = writeln!(s, "| metric | value | unit | paper | meaning |");
        let _ = writeln!(s, "|---|---|---|---|---|");
    } else {
        let _ = writeln!(s, "| metric | value | unit | meaning |");
        let _ = writeln!(s, "|---|---|---|---|");
    }
    for r in rows {
        let paper = if with_paper {
            format!(" {} |", r.paper)
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            "| `{}` | {} | {} |{paper} {} |",
            r.name, r.value, r.unit, r.about
        );
    }
}

/// A list of records as a table, one row per record, its columns explained below it.
fn write_records(s: &mut String, rec: &Records<'_>) {
    let _ = writeln!(s, "\n`{}`: {}\n", rec.name, rec.about);
    if rec.items.is_empty() {
        let _ = writeln!(s, "(none)");
        return;
    }
    let header: Vec<String> = rec
        .fields
        .iter()
        .map(|f| match f.unit {
            "" => f.name.to_string(),
            u => format!("{} ({u})", f.name),
        })
        .collect();
    let _ = writeln!(s, "| {} |", header.join(" | "));
    let _ = writeln!(s, "|{}", "---|".repeat(header.len()));
    for item in rec.items {
        let cells: Vec<String> = rec
            .fields
            .iter()
            .map(|f| item.get(f.name).map_or_else(String::new, value_text))
            .collect();
        let _ = writeln!(s, "| {} |", cells.join(" | "));
    }
    let _ = writeln!(s);
    for f in rec.fields {
        let _ = writeln!(s, "* `{}`: {}", f.name, cell(f.about));
    }
}

/// The paper's (or the acceptance targets') figures, flattened, as a list.
fn write_paper(s: &mut String, paper: &Value) {
    fn walk(s: &mut String, v: &Value, name: &str) {
        match v {
            Value::Object(m) => {
                for (k, x) in m {
                    let n = if name.is_empty() {
                        k.clone()
                    } else {
                        format!("{name}.{k}")
                    };
                    walk(s, x, &n);
                }
            }
            other => {
                let _ = writeln!(s, "* `{name}`: {}", quoted_text(other));
            }
        }
    }
    if paper.is_null() {
        return;
    }
    let _ = writeln!(
        s,
        "\nFigures of the paper (or the targets) for this case:\n"
    );
    walk(s, paper, "");
}

/// Renders one run: its metrics, records and paper figures; its wall-clock times apart.
///
/// # Errors
/// A metric without a description (its metrics struct does not declare it).
pub fn render(outcome: &Outcome) -> Result<Rendered> {
    let mut c = Collected::default();
    collect(outcome.fields, &outcome.metrics, "", &outcome.paper, &mut c)?;
    let mut s = String::new();
    write_rows(&mut s, &c.rows);
    for rec in &c.records {
        write_records(&mut s, rec);
    }
    write_paper(&mut s, &outcome.paper);
    Ok(Rendered {
        results: s,
        wall_times: c.wall,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    crate::metrics! {
        /// A record.
        pub struct Item {
            /// Its name.
            #[metric(unit = "")] pub name: String,
            /// When.
            #[metric(unit = "s")] pub at_s: f64,
        }
    }

    crate::metrics! {
        /// Test metrics.
        pub struct Example {
            /// An error | with a bar.
            #[metric(unit = "rad")] pub err_rad: [f64; 2],
            /// A count.
            #[metric(unit = "")] pub count: usize,
            /// Records.
            #[metric(nested)] pub items: Vec<Item>,
            /// Took.
            #[metric(wall = "s")] pub wall_s: f64,
        }
    }

    #[test]
    fn numbers_keep_four_significant_digits() {
        assert_eq!(number(0.0), "0");
        assert_eq!(number(1.23456), "1.235");
        assert_eq!(number(0.0123456), "0.01235");
        assert_eq!(number(123.456), "123.5");
        assert_eq!(number(12345.6), "12346");
        assert_eq!(number(2.5e-6), "2.500e-6");
        assert_eq!(number(-7.0e7), "-7.000e7");
    }

    #[test]
    fn a_run_renders_rows_records_paper_and_wall_times_apart() {
        let mut o = Outcome::new(&Example {
            err_rad: [1e-4, f64::NAN],
            count: 3,
            items: vec![Item {
                name: "a".into(),
                at_s: 2.0,
            }],
            wall_s: 1.5,
        })
        .unwrap();
        o.paper = serde_json::json!({"count": 4, "note": "n", "x": [0.282, 1.5e-6]});
        let r = render(&o).unwrap();
        assert!(r
            .results
            .contains("| `err_rad` | 1.000e-4 / — | rad |  | An error \\| with a bar. |"));
        assert!(r.results.contains("| `count` | 3 |  | 4 | A count. |"));
        assert!(r
            .results
            .contains("| name | at_s (s) |\n|---|---|\n| a | 2.000 |"));
        assert!(r.results.contains("* `note`: n"));
        assert!(r.results.contains("* `x`: 0.282 / 1.5e-6"), "{}", r.results);
        assert!(!r.results.contains("wall_s"));
        assert_eq!(
            r.wall_times,
            vec![("wall_s".into(), "1.500".into(), "s".into())]
        );
    }

    #[test]
    fn an_undescribed_metric_is_an_error() {
        let mut o = Outcome::new(&Example {
            err_rad: [0.0; 2],
            count: 0,
            items: vec![],
            wall_s: 0.0,
        })
        .unwrap();
        o.metrics.insert("stray".into(), Value::from(1));
        assert!(render(&o).is_err());
    }
}
