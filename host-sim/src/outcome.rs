//! What a scenario run is given and what it hands back: the types [`crate::scenarios`] fill and
//! [`crate::report`] prints, in a module of their own so that neither imports the other.
//!
//! A scenario's metrics are a struct declared with [`metrics!`](crate::metrics): serialized
//! with serde into the `metrics` object of the `--json` document, and described field by field
//! (JSON name, unit, meaning from the doc comment) in [`Describe::FIELDS`], which
//! `host-sim report` prints next to the numbers. The description is generated from the same
//! declaration as the field, so the two cannot drift apart.

use std::path::PathBuf;

use anyhow::Context;
use serde::Serialize;
use serde_json::{json, Map, Value};

use crate::synth::quantize::Quantizer;

/// What a scenario run is asked to do.
#[derive(Clone, Debug)]
pub struct RunContext {
    /// The variant's name (already validated).
    pub variant: String,
    /// Seed of every random stream of the run.
    pub seed: u64,
    /// Where to write CSV and PNG files; `None` writes nothing.
    pub out_dir: Option<PathBuf>,
    /// The front end's quantizer of the sample-level paths (`--front-end`; only the scenarios
    /// in [`FRONT_END_SCENARIOS`](crate::scenarios::FRONT_END_SCENARIOS) take another than
    /// `i8`).
    pub front_end: Quantizer,
    /// A TLE to fly instead of the scenario's built-in orbit (`--tle`; only the scenarios in
    /// [`TLE_SCENARIOS`](crate::scenarios::TLE_SCENARIOS)).
    pub tle: Option<crate::truth::tle::Tle>,
}

/// What a scenario run produced.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The metrics struct, serialized (field order kept).
    pub metrics: Map<String, Value>,
    /// What each metric is: from the metrics struct's declaration.
    pub fields: &'static [Field],
    /// The source paper's figures for the same case (`null` when the paper has none).
    pub paper: Value,
    /// Lines for the human summary (stdout without `--json`).
    pub summary: Vec<String>,
    /// Files written into the output directory.
    pub files: Vec<PathBuf>,
}

impl Outcome {
    /// An outcome with `metrics` serialized, no paper figures, no summary, no files.
    ///
    /// # Errors
    /// A metrics type that does not serialize into a JSON object.
    pub fn new<M: Serialize + Describe>(metrics: &M) -> anyhow::Result<Self> {
        let value = serde_json::to_value(metrics).context("serializing the metrics")?;
        let Value::Object(metrics) = value else {
            anyhow::bail!("the metrics are not a JSON object: {value}");
        };
        Ok(Self {
            metrics,
            fields: M::FIELDS,
            paper: Value::Null,
            summary: Vec::new(),
            files: Vec::new(),
        })
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

/// One metric, as its struct declares it.
#[derive(Clone, Copy, Debug)]
pub struct Field {
    /// Its JSON name.
    pub name: &'static str,
    /// Its unit (`""` for a plain number, a flag, a name or a group).
    pub unit: &'static str,
    /// What it means (the field's doc comment).
    pub about: &'static str,
    /// A wall-clock time: differs from run to run, not a result.
    pub wall_time: bool,
    /// Whether it is a number, a group of metrics under its name, or a group merged into its
    /// parent.
    pub nesting: Nesting,
}

/// How a metric holds its value.
#[derive(Clone, Copy, Debug)]
pub enum Nesting {
    /// A value: a number, an array of numbers, a flag or a string.
    Leaf,
    /// An object (or an array of objects) under the field's name, with these fields.
    Object(&'static [Field]),
    /// These fields, merged into the parent object (`#[serde(flatten)]`).
    Flatten(&'static [Field]),
    /// These fields with this suffix on their names, merged into the parent object
    /// ([`Suffixed`] under `#[serde(flatten)]`).
    Suffixed(&'static str, &'static [Field]),
}

/// A type whose serialized fields are described.
pub trait Describe {
    /// The fields, in serialization order.
    const FIELDS: &'static [Field];
}

impl<T: Describe> Describe for Option<T> {
    const FIELDS: &'static [Field] = T::FIELDS;
}

impl<T: Describe> Describe for Vec<T> {
    const FIELDS: &'static [Field] = T::FIELDS;
}

/// A metrics group whose JSON names carry a suffix: the same group measured twice (with and
/// without something) declared once. Serialize it under `#[serde(flatten)]`.
#[derive(Clone, Debug)]
pub struct Suffixed<T> {
    /// Appended to every field name of `inner`.
    pub suffix: &'static str,
    /// The group.
    pub inner: T,
}

impl<T: Serialize> Serialize for Suffixed<T> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::{Error, SerializeMap};
        let Value::Object(fields) = serde_json::to_value(&self.inner).map_err(S::Error::custom)?
        else {
            return Err(S::Error::custom("a suffixed group must be a struct"));
        };
        let mut map = serializer.serialize_map(Some(fields.len()))?;
        for (k, v) in &fields {
            map.serialize_entry(&format!("{k}{}", self.suffix), v)?;
        }
        map.end()
    }
}

impl<T: Describe> Describe for Suffixed<T> {
    const FIELDS: &'static [Field] = T::FIELDS;
}

/// The description of the field called `name` among `fields`, looking into flattened groups.
pub fn find_field(fields: &'static [Field], name: &str) -> Option<&'static Field> {
    find_field_in(fields, name).map(|(f, _)| f)
}

/// [`find_field`], with the suffixed group the field was found in (whose doc says what the
/// suffix means).
pub fn find_field_in(
    fields: &'static [Field],
    name: &str,
) -> Option<(&'static Field, Option<&'static Field>)> {
    fields.iter().find_map(|f| match f.nesting {
        Nesting::Flatten(inner) => find_field_in(inner, name),
        Nesting::Suffixed(suffix, inner) => name
            .strip_suffix(suffix)
            .and_then(|n| find_field(inner, n))
            .map(|found| (found, Some(f))),
        _ => (f.name == name).then_some((f, None)),
    })
}

/// Declares a metrics struct: `#[derive(Clone, Debug, Serialize)]` plus its [`Describe`]
/// impl, one [`Field`] per field from the field's doc comment and its `#[metric(..)]`
/// attribute (written on the field's line: one line per metric):
///
/// * `#[metric(unit = "rad")]`: a value with its unit (`unit = ""` for none);
/// * `#[metric(unit = "rad", rename = "json name")]`: the same under another JSON name;
/// * `#[metric(wall = "s")]`: a wall-clock time (reported, never compared);
/// * `#[metric(nested)]`: a struct (or `Vec`/`Option` of one) declared with this macro, as an
///   object under the field's name;
/// * `#[metric(flatten)]`: the same merged into this object; write `#[serde(flatten)]` after
///   it;
/// * `#[metric(suffixed = "_suffix")]`: a [`Suffixed`] group merged into this object; write
///   `#[serde(flatten)]` after it.
///
/// Further attributes after `#[metric(..)]` (such as `#[serde(..)]`) are passed through.
///
/// ```
/// host_sim::metrics! {
///     /// Example metrics.
///     pub struct Example {
///         /// Attitude error RMS.
///         #[metric(unit = "rad")] pub rms_rad: f64,
///     }
/// }
/// use host_sim::outcome::Describe;
/// assert_eq!(Example::FIELDS[0].name, "rms_rad");
/// assert_eq!(Example::FIELDS[0].about.trim(), "Attitude error RMS.");
/// ```
#[macro_export]
macro_rules! metrics {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $(
                $(#[doc = $doc:literal])*
                #[metric($kind:ident $(= $unit:literal)? $(, rename = $json:literal)?)]
                $(#[$attr:meta])*
                $fvis:vis $field:ident : $ty:ty
            ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Debug, serde::Serialize)]
        $vis struct $name {
            $(
                $(#[doc = $doc])*
                $(#[serde(rename = $json)])?
                $(#[$attr])*
                $fvis $field: $ty,
            )*
        }

        impl $crate::outcome::Describe for $name {
            const FIELDS: &'static [$crate::outcome::Field] = &[$(
                $crate::outcome::Field {
                    name: $crate::metrics!(@name $field $($json)?),
                    unit: $crate::metrics!(@unit $kind $($unit)?),
                    about: concat!($($doc),*),
                    wall_time: $crate::metrics!(@wall $kind),
                    nesting: $crate::metrics!(@nesting $kind $ty $(, $unit)?),
                }
            ),*];
        }
    };
    (@name $field:ident $json:literal) => { $json };
    (@name $field:ident) => { stringify!($field) };
    (@unit unit $unit:literal) => { $unit };
    (@unit wall $unit:literal) => { $unit };
    (@unit $kind:ident $($unit:literal)?) => { "" };
    (@nesting unit $ty:ty, $unit:literal) => { $crate::outcome::Nesting::Leaf };
    (@nesting wall $ty:ty, $unit:literal) => { $crate::outcome::Nesting::Leaf };
    (@wall wall) => { true };
    (@wall $kind:ident) => { false };
    (@nesting nested $ty:ty) => {
        $crate::outcome::Nesting::Object(<$ty as $crate::outcome::Describe>::FIELDS)
    };
    (@nesting flatten $ty:ty) => {
        $crate::outcome::Nesting::Flatten(<$ty as $crate::outcome::Describe>::FIELDS)
    };
    (@nesting suffixed $ty:ty, $suffix:literal) => {
        $crate::outcome::Nesting::Suffixed(
            $suffix,
            <$ty as $crate::outcome::Describe>::FIELDS,
        )
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    metrics! {
        /// Inner group.
        pub struct Inner {
            /// A count.
            #[metric(unit = "")] pub count: usize,
            /// Time it took.
            #[metric(wall = "s")] pub wall_s: f64,
        }
    }

    metrics! {
        /// Outer metrics.
        pub struct Outer {
            /// An error,
            /// over two lines.
            #[metric(unit = "rad", rename = "error rad")] pub error: f64,
            /// A group.
            #[metric(nested)] pub group: Inner,
            /// A flattened group.
            #[metric(flatten)] #[serde(flatten)] pub extra: Option<Inner>,
            /// The same group again, suffixed.
            #[metric(suffixed = "_again")] #[serde(flatten)] pub again: Suffixed<Inner>,
        }
    }

    #[test]
    fn fields_follow_the_declaration_and_the_json() {
        let m = Outer {
            error: f64::NAN,
            group: Inner {
                count: 2,
                wall_s: 0.5,
            },
            extra: Some(Inner {
                count: 3,
                wall_s: 0.5,
            }),
            again: Suffixed {
                suffix: "_again",
                inner: Inner {
                    count: 4,
                    wall_s: 0.5,
                },
            },
        };
        let o = Outcome::new(&m).unwrap();
        let keys: Vec<&str> = o.metrics.keys().map(String::as_str).collect();
        assert_eq!(
            keys,
            [
                "error rad",
                "group",
                "count",
                "wall_s",
                "count_again",
                "wall_s_again"
            ]
        );
        assert_eq!(o.metrics["count_again"], 4);
        assert!(o.metrics["error rad"].is_null(), "NaN serializes as null");
        assert_eq!(o.fields.len(), 4);
        assert_eq!(find_field(o.fields, "count_again").unwrap().name, "count");
        assert_eq!(find_field(o.fields, "again").map(|f| f.name), None);
        let error = find_field(o.fields, "error rad").unwrap();
        assert_eq!(error.unit, "rad");
        assert_eq!(error.about, " An error, over two lines.");
        assert!(matches!(
            find_field(o.fields, "group").unwrap().nesting,
            Nesting::Object(f) if f[0].name == "count"
        ));
        // the flattened group's field is found at the top level
        assert_eq!(find_field(o.fields, "count").unwrap().about, " A count.");
        assert!(find_field(o.fields, "missing").is_none());
        let none = Outcome::new(&Outer {
            extra: None,
            ..m.clone()
        })
        .unwrap();
        assert_eq!(none.metrics.len(), 4);
        assert!(find_field(o.fields, "wall_s").unwrap().wall_time);
        assert!(!error.wall_time);
    }
}
