//! The contract between the engine and its callers outside Rust: the JavaScript API (the wasm
//! binding, `src/wasm.rs`, and the npm package) and the CLI's JSON (`arps register --json`).
//!
//! # One set of types
//! The options are [`Options`], the result is [`Registration`]; their nested types are
//! [`Evidence`], [`Alternative`], [`FreeMotion`] (with [`FreeMotionKind`]), [`Timings`], [`Start`], [`Search`], [`IcpKind`], [`IcpLoss`], [`NonFinite`],
//! [`Outliers`], [`Support`], [`Stage`] (the progress stages), [`WarningCode`] (what a warning is
//! about) and [`ModelConfig`]; the readers take [`ReadOptions`]. They
//! are serde types: the wasm binding converts them
//! with serde-wasm-bindgen and the CLI with serde_json, so JS and JSON see the same objects, field
//! for field. The TypeScript declarations of the package (`js/arps-contract.d.ts`, part of
//! `pkg/arps.d.ts`) are generated from the same types (`typescript`, cargo feature `ts`;
//! `scripts/gen-types.sh` writes the file, `tests/contract.rs` fails when it is stale).
//!
//! # Naming and layout (JS and JSON alike)
//! * Fields are camelCase (`inlierRmse`, `icpIterations`, `maxCorrespondenceDistance`), and so
//!   are enum values (`"plane"`, `"turnedInitial"`, `"adaptive"`).
//! * Transforms keep their frames in their names: `T_target_source` maps source points into the
//!   target frame, `T_target_source_network` is the estimate before ICP.
//! * A 4x4 is 16 numbers in **column-major** order (element (row r, col c) at index `c * 4 + r`),
//!   what three.js `Matrix4.fromArray` reads and `Matrix4.elements` holds ([`column_major`]).
//!   `initialTransform` also accepts four row-major rows ([`initial_transform`]).
//! * [`ModelConfig`] is stored in the weights file with snake_case keys (the format the PyTorch
//!   trainer shares); across this boundary its keys are camelCase too ([`model_config_json`]).
//!   Its `reference` values (`"top_h"`, `"soft"`) are the file's.
//!
//! [`Options`]: crate::Options
//! [`Registration`]: crate::Registration
//! [`Alternative`]: crate::Alternative
//! [`FreeMotion`]: crate::FreeMotion
//! [`FreeMotionKind`]: crate::FreeMotionKind
//! [`ReadOptions`]: crate::io::ReadOptions
//! [`Evidence`]: crate::confidence::Evidence
//! [`Timings`]: crate::Timings
//! [`Start`]: crate::Start
//! [`Search`]: crate::Search
//! [`IcpKind`]: crate::IcpKind
//! [`IcpLoss`]: crate::IcpLoss
//! [`NonFinite`]: crate::NonFinite
//! [`Outliers`]: crate::Outliers
//! [`Support`]: crate::Support
//! [`Stage`]: crate::Stage
//! [`WarningCode`]: crate::WarningCode
//! [`ModelConfig`]: crate::ModelConfig

use crate::ModelConfig;

/// Serde for a [`nalgebra::Matrix4<f64>`] as 16 numbers in column-major order (use with
/// `#[serde(with = "crate::contract::column_major")]`).
pub mod column_major {
    use nalgebra::Matrix4;
    use serde::{de, Deserialize, Deserializer, Serialize, Serializer};

    /// Writes the 16 entries, column by column.
    pub fn serialize<S: Serializer>(m: &Matrix4<f64>, serializer: S) -> Result<S::Ok, S::Error> {
        let mut a = [0.0; 16];
        a.copy_from_slice(m.as_slice());
        a.serialize(serializer)
    }

    /// Reads 16 numbers, column by column; any other length is an error.
    pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Matrix4<f64>, D::Error> {
        let v = Vec::<f64>::deserialize(deserializer)?;
        if v.len() != 16 {
            return Err(de::Error::custom(format!("expected 16 numbers (column-major), got {}", v.len())));
        }
        Ok(Matrix4::from_column_slice(&v))
    }
}

/// Serde for [`crate::Options::initial_transform`] (`Option<[[f64; 4]; 4]>`, four row-major
/// rows in Rust): written as 16 column-major numbers like every 4x4 of the contract; read from
/// 16 column-major numbers (e.g. a previous result's `T_target_source`, a three.js
/// `Matrix4.elements`) or from four row-major rows of four numbers; `null` is `None`.
pub mod initial_transform {
    use crate::transform;
    use serde::{de, Deserialize, Deserializer, Serialize, Serializer};

    /// Writes `None` as `null`, a matrix as 16 column-major numbers.
    pub fn serialize<S: Serializer>(rows: &Option<[[f64; 4]; 4]>, serializer: S) -> Result<S::Ok, S::Error> {
        rows.map(|r| {
            let mut a = [0.0; 16];
            a.copy_from_slice(transform::from_rows(&r).as_slice());
            a
        })
        .serialize(serializer)
    }

    /// The value: a list, or anything else (an error naming the expected shapes).
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Layout {
        List(Vec<Element>),
        Other(de::IgnoredAny),
    }

    /// One element of the outer list: a number (flat layout) or a row.
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Element {
        Number(f64),
        Row(Vec<f64>),
        Other(de::IgnoredAny),
    }

    const EXPECTED: &str = "expected 16 numbers (column-major) or 4 rows of 4 numbers (row-major)";

    /// Reads either layout (see the module docs); anything else is an error naming both.
    pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Option<[[f64; 4]; 4]>, D::Error> {
        let elements = match Option::<Layout>::deserialize(deserializer)? {
            None => return Ok(None),
            Some(Layout::List(elements)) => elements,
            Some(Layout::Other(_)) => return Err(de::Error::custom(format!("initialTransform: {EXPECTED}"))),
        };
        let numbers: Vec<f64> =
            elements.iter().filter_map(|e| if let Element::Number(x) = e { Some(*x) } else { None }).collect();
        if numbers.len() == 16 && elements.len() == 16 {
            let mut a = [0.0; 16];
            a.copy_from_slice(&numbers);
            return Ok(Some(transform::to_rows(&transform::from_column_major(&a))));
        }
        let rows: Vec<&Vec<f64>> =
            elements.iter().filter_map(|e| if let Element::Row(r) = e { Some(r) } else { None }).collect();
        if rows.len() == 4 && elements.len() == 4 && rows.iter().all(|r| r.len() == 4) {
            let mut out = [[0.0; 4]; 4];
            for (o, r) in out.iter_mut().zip(&rows) {
                o.copy_from_slice(r);
            }
            return Ok(Some(out));
        }
        Err(de::Error::custom(format!("initialTransform has {} elements; {EXPECTED}", elements.len())))
    }
}

/// Serde for [`crate::Options::up`] (`Option<[f64; 3]>`): three numbers, read strictly. A list
/// of another length is an error in every reader (serde-wasm-bindgen reads a fixed-size array
/// by its first elements and would let a fourth through unseen).
pub mod up {
    use serde::{de, Deserialize, Deserializer, Serialize, Serializer};

    /// Writes `None` as `null`, a direction as its three numbers.
    pub fn serialize<S: Serializer>(up: &Option<[f64; 3]>, serializer: S) -> Result<S::Ok, S::Error> {
        up.serialize(serializer)
    }

    /// Reads `null` as `None`, a list of exactly three numbers as the direction.
    pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Option<[f64; 3]>, D::Error> {
        match Option::<Vec<f64>>::deserialize(deserializer)? {
            None => Ok(None),
            Some(v) if v.len() == 3 => Ok(Some([v[0], v[1], v[2]])),
            Some(v) => Err(de::Error::custom(format!("expected 3 numbers [x, y, z], got {}", v.len()))),
        }
    }
}

/// A [`ModelConfig`] as the contract shows it: its serde JSON (the weights file's snake_case
/// keys) with every key in camelCase (`n_points` -> `nPoints`); values are left alone.
pub fn model_config_json(config: &ModelConfig) -> serde_json::Value {
    camel_case_keys(serde_json::to_value(config).unwrap_or(serde_json::Value::Null))
}

/// Object keys from `snake_case` to `camelCase`, recursively (values are left alone).
fn camel_case_keys(value: serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    match value {
        Value::Object(map) => {
            Value::Object(map.into_iter().map(|(k, v)| (camel_case(&k), camel_case_keys(v))).collect())
        }
        Value::Array(items) => Value::Array(items.into_iter().map(camel_case_keys).collect()),
        other => other,
    }
}

/// `n_points` -> `nPoints`.
fn camel_case(key: &str) -> String {
    let mut out = String::with_capacity(key.len());
    let mut upper = false;
    for c in key.chars() {
        if c == '_' {
            upper = true;
        } else if upper {
            out.extend(c.to_uppercase());
            upper = false;
        } else {
            out.push(c);
        }
    }
    out
}

/// The TypeScript declarations of the contract's types, as `js/arps-contract.d.ts` holds them:
/// one `export` per type, with its docs, in a fixed order.
#[cfg(feature = "ts")]
pub fn typescript() -> String {
    use crate::confidence::Evidence;
    use crate::model::config::Reference;
    use crate::{
        Alternative, FreeMotion, FreeMotionKind, IcpKind, IcpLoss, NonFinite, Options, Outliers, Registration, Search,
        Stage, Start, Support, Timings,
    };
    use ts_rs::{Config, TS};

    fn decl<T: TS>(cfg: &Config) -> String {
        format!("{}export {}\n", T::docs().unwrap_or_default(), tidy(&T::decl(cfg)))
    }
    let cfg = Config::new();
    let mut out = String::from(
        "// Generated from the Rust types by `scripts/gen-types.sh` (arps::contract::typescript);\n\
         // do not edit: change the Rust types and their docs, then run the script.\n\n",
    );
    for d in [
        decl::<Options>(&cfg),
        decl::<Start>(&cfg),
        decl::<Search>(&cfg),
        decl::<IcpKind>(&cfg),
        decl::<IcpLoss>(&cfg),
        decl::<NonFinite>(&cfg),
        decl::<Outliers>(&cfg),
        decl::<Support>(&cfg),
        decl::<Stage>(&cfg),
        decl::<Registration>(&cfg),
        decl::<crate::WarningCode>(&cfg),
        decl::<Timings>(&cfg),
        decl::<Evidence>(&cfg),
        decl::<Alternative>(&cfg),
        decl::<FreeMotion>(&cfg),
        decl::<FreeMotionKind>(&cfg),
        decl::<crate::io::ReadOptions>(&cfg),
        decl::<crate::io::ScanInfo>(&cfg),
        decl::<ModelConfig>(&cfg),
        decl::<Reference>(&cfg),
    ] {
        out.push_str(&d);
        out.push('\n');
    }
    let out = rustdoc_to_tsdoc(&out);
    out.trim_end().to_string() + "\n"
}

/// ts-rs's one-line-per-field object types, indented two spaces inside the braces, trailing
/// spaces removed, the closing brace on its own line.
#[cfg(feature = "ts")]
fn tidy(decl: &str) -> String {
    let mut out = String::new();
    let mut inside = false;
    for line in decl.lines() {
        let line = line.trim_end();
        let (line, closes) = match line.strip_suffix(" };") {
            Some(field) if inside => (field, true),
            _ => (line, false),
        };
        if inside {
            out.push_str("  ");
        }
        out.push_str(line);
        out.push('\n');
        if !inside && line.ends_with('{') {
            inside = true;
        }
        if closes {
            out.push_str("};");
            inside = false;
        }
    }
    out.trim_end().to_string()
}

/// Rustdoc links (`` [`Start::Turned`] ``) as plain code spans (`` `Start::Turned` ``).
#[cfg(feature = "ts")]
fn rustdoc_to_tsdoc(s: &str) -> String {
    s.replace("[`", "`").replace("`]", "`")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camel_case_converts_snake_keys() {
        assert_eq!(camel_case("n_points"), "nPoints");
        assert_eq!(camel_case("layer_norm_eps"), "layerNormEps");
        assert_eq!(camel_case("top_h"), "topH");
        assert_eq!(camel_case("preset"), "preset");
    }

    #[test]
    fn model_config_keys_are_camel_case_and_values_untouched() {
        let v = model_config_json(&ModelConfig::web());
        let o = v.as_object().unwrap();
        assert_eq!(o["nPoints"], 256);
        assert_eq!(o["reference"], "soft");
        assert!(o.keys().all(|k| !k.contains('_')), "{o:?}");
    }
}
