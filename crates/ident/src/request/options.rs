//! Requests from a front-end's flat options (Python's keyword arguments,
//! JSON values), with errors that name the option.

use limpid_core::{Error, Result};
use schemars::JsonSchema;
use serde::Deserialize;

use super::methods::{
    ArmRequest, LinearRequest, PrepareRequest, SpectraRequest, StochasticRequest,
};
use super::Request;
use crate::reflex::ReflexRequest;
use crate::varying::VaryingRequest;

/// The names of a request type's fields (its JSON Schema's properties).
pub fn field_names<T: JsonSchema>() -> Vec<String> {
    let schema = schemars::schema_for!(T);
    schema
        .get("properties")
        .and_then(|p| p.as_object())
        .map(|p| p.keys().cloned().collect())
        .unwrap_or_default()
}

fn boolean_names<T: JsonSchema>() -> Vec<String> {
    let schema = schemars::schema_for!(T);
    schema
        .get("properties")
        .and_then(|p| p.as_object())
        .map(|p| {
            p.iter()
                .filter(|(_, v)| v.get("type").and_then(|t| t.as_str()) == Some("boolean"))
                .map(|(k, _)| k.clone())
                .collect()
        })
        .unwrap_or_default()
}

/// The yes/no options of a method (top level and nested), so a front-end
/// whose numbers and truth values mix (Python: `True == 1`) can keep them apart.
pub fn boolean_options(method: &str) -> Result<Vec<String>> {
    nesting(method)?;
    Ok(match method {
        "linear" => [
            boolean_names::<LinearRequest>(),
            boolean_names::<PrepareRequest>(),
        ]
        .concat(),
        "cocontraction" => boolean_names::<PrepareRequest>(),
        "planar" | "window_sweep" => boolean_names::<ArmRequest>(),
        "stochastic" => boolean_names::<StochasticRequest>(),
        "varying" => boolean_names::<VaryingRequest>(),
        "spectra" => boolean_names::<SpectraRequest>(),
        _ => boolean_names::<ReflexRequest>(),
    })
}

/// Where a method's flat options nest: `prepare` (linear, co-contraction)
/// or `arm` (planar, window sweep) and that part's field names; `None` for
/// methods whose options are all at the top level.
pub fn nesting(method: &str) -> Result<Option<(&'static str, Vec<String>)>> {
    Ok(match method {
        "linear" | "cocontraction" => Some(("prepare", field_names::<PrepareRequest>())),
        "planar" | "window_sweep" => Some(("arm", field_names::<ArmRequest>())),
        "stochastic" | "reflex" | "varying" | "spectra" => None,
        other => {
            return Err(Error::invalid(
                "method",
                format!(
                    "{other:?} is not a method: linear, cocontraction, planar, window_sweep, stochastic, reflex, varying or spectra"
                ),
            ))
        }
    })
}

/// A method's request from any serde deserializer of its (nested) options:
/// each method's own type (not the tagged enum, which would buffer the value
/// and lose the path of an error); an error names the option (`band_hz`, `order`, ...).
pub fn deserialize_request<'de, D: serde::Deserializer<'de>>(
    method: &str,
    options: D,
) -> Result<Request> {
    fn typed<'de, T: Deserialize<'de>, D: serde::Deserializer<'de>>(d: D) -> Result<T> {
        serde_path_to_error::deserialize(d).map_err(|e| {
            let path = e.path().to_string();
            let message = e.into_inner().to_string();
            let path = path
                .trim_start_matches("prepare.")
                .trim_start_matches("arm.");
            let name = match path {
                "." | "prepare" | "arm" => "options",
                p => p,
            };
            Error::invalid(name, message)
        })
    }
    nesting(method)?;
    Ok(match method {
        "linear" => Request::Linear(typed(options)?),
        "cocontraction" => Request::Cocontraction(typed(options)?),
        "planar" => Request::Planar(typed(options)?),
        "window_sweep" => Request::WindowSweep(typed(options)?),
        "stochastic" => Request::Stochastic(typed(options)?),
        "varying" => Request::Varying(typed(options)?),
        "spectra" => Request::Spectra(typed(options)?),
        _ => Request::Reflex(typed(options)?),
    })
}

/// A request from flat options (a front-end's keyword arguments, as JSON
/// values): the fields of the nested `prepare` and `arm` parts may be given
/// at the top level; a null option keeps its default. Errors name the option.
pub fn from_options(
    method: &str,
    options: serde_json::Map<String, serde_json::Value>,
) -> Result<Request> {
    let nested = nesting(method)?;
    let mut top = serde_json::Map::new();
    let mut inner = serde_json::Map::new();
    for (key, value) in options {
        if value.is_null() {
            continue;
        }
        match &nested {
            Some((_, names)) if names.contains(&key) => {
                inner.insert(key, value);
            }
            _ => {
                top.insert(key, value);
            }
        }
    }
    if let Some((name, _)) = nested {
        top.insert(name.into(), inner.into());
    }
    deserialize_request(method, serde_json::Value::Object(top))
}
