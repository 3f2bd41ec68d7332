//! Requests from a front-end's flat options (Python's keyword arguments,
//! JSON values), with errors that name the option.

use limpid_core::{Error, Result};
use schemars::JsonSchema;
use serde::Deserialize;

use super::{deserialize_request, Request};

/// The names of a request type's fields (its JSON Schema's properties).
pub fn field_names<T: JsonSchema>() -> Vec<String> {
    let schema = schemars::schema_for!(T);
    schema
        .get("properties")
        .and_then(|p| p.as_object())
        .map(|p| p.keys().cloned().collect())
        .unwrap_or_default()
}

/// The names of a request type's yes/no fields.
pub fn boolean_names<T: JsonSchema>() -> Vec<String> {
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
    Ok(super::method_options(method)?.1)
}

/// Where a method's flat options nest: `prepare` (linear, co-contraction)
/// or `arm` (planar, window sweep) and that part's field names; `None` for
/// methods whose options are all at the top level.
pub fn nesting(method: &str) -> Result<Option<(&'static str, Vec<String>)>> {
    Ok(super::method_options(method)?.0)
}

/// One method's request type from a deserializer, errors naming the option.
pub(super) fn typed<'de, T: Deserialize<'de>, D: serde::Deserializer<'de>>(d: D) -> Result<T> {
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
