//! The numbers of a protocol file, checked before anything uses them
//! (issue 13): every float finite, limits, rates, durations, lengths and
//! counts positive, and the size of what they ask for capped, so that
//! `max_force_n = nan` cannot switch a safety check off and `count = 1e9`
//! cannot exhaust memory. Errors name the file, line and key.

use std::path::Path;

use limpid_core::{Error, Result};

/// Most samples one protocol may ask to simulate or export (all trials).
pub const MAX_SAMPLES: f64 = 5e7;
/// Highest sample rate accepted (Hz).
pub const MAX_RATE_HZ: f64 = 1e6;
/// Longest duration accepted for any one phase or experiment (s).
pub const MAX_DURATION_S: f64 = 1e5;
/// Most trials or trials per set.
pub const MAX_COUNT: i64 = 100_000;
/// Most target directions (spreading them evenly costs n^2 per relaxation step).
pub const MAX_TARGETS: i64 = 256;

/// What a key's value must be.
#[derive(Clone, Copy, PartialEq)]
enum Rule {
    Positive,
    NonNegative,
    Any,
}

fn rule(parent: &str, key: &str) -> Rule {
    match key {
        "sample_rate_hz"
        | "cutoff_hz"
        | "duration_s"
        | "centre_out_s"
        | "interpolation_s"
        | "link_lengths_m"
        | "count"
        | "trials"
        | "peak"
        | "max_input_coherence" => Rule::Positive,
        "radius_m" if parent == "targets" => Rule::Positive,
        "radius_m" | "trials_per_set" | "seed" => Rule::NonNegative,
        "workspace_min_m" | "workspace_max_m" => Rule::Any,
        _ if key.starts_with("max_") || key.starts_with("nominal_") => Rule::Positive,
        _ if key.ends_with("_s") => Rule::NonNegative,
        _ => Rule::Any,
    }
}

/// Check every number of the TOML `text` (already known to parse).
pub fn check_numbers(text: &str, path: &Path) -> Result<()> {
    // what the generic parser refuses (e.g. an integer beyond i64) is refused,
    // even where a typed field would have read it as a float
    let table: toml::Table =
        toml::from_str(text).map_err(|e| Error::settings(path, text, e.span(), e.message()))?;
    walk(&table, "", text, path)
}

fn walk(table: &toml::Table, parent: &str, text: &str, path: &Path) -> Result<()> {
    for (key, value) in table {
        let full = if parent.is_empty() {
            key.clone()
        } else {
            format!("{parent}.{key}")
        };
        match value {
            toml::Value::Table(t) => walk(t, &full, text, path)?,
            _ => check_value(value, parent, key, &full, text, path)?,
        }
    }
    Ok(())
}

fn check_value(
    value: &toml::Value,
    parent: &str,
    key: &str,
    full: &str,
    text: &str,
    path: &Path,
) -> Result<()> {
    let fail = |expected: &str, found: String| {
        Err(Error::Format {
            path: path.to_path_buf(),
            message: format!(
                "{}key {full}: expected {expected}, found {found}",
                line_of(text, parent, key).map_or(String::new(), |l| format!("line {l}, "))
            ),
        })
    };
    let number = |v: &toml::Value| match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    };
    let values: Vec<f64> = match value {
        toml::Value::Array(items) => items
            .iter()
            .flat_map(|v| match v {
                toml::Value::Array(inner) => inner.iter().filter_map(number).collect(),
                other => number(other).into_iter().collect::<Vec<_>>(),
            })
            .collect(),
        other => number(other).into_iter().collect(),
    };
    let rule = rule(parent, key);
    for v in values {
        if !v.is_finite() {
            return fail("a finite number", v.to_string());
        }
        match rule {
            Rule::Positive if v <= 0.0 => return fail("a positive number", v.to_string()),
            Rule::NonNegative if v < 0.0 => return fail("a number >= 0", v.to_string()),
            _ => {}
        }
        let cap = if key.ends_with("_hz") {
            MAX_RATE_HZ
        } else if key.ends_with("_s") {
            MAX_DURATION_S
        } else if key == "count" {
            MAX_TARGETS as f64
        } else if matches!(key, "trials" | "trials_per_set") {
            MAX_COUNT as f64
        } else if key.ends_with("_m") && !key.ends_with("_per_m") {
            1e3
        } else {
            f64::INFINITY
        };
        if v.abs() > cap {
            return fail(&format!("at most {cap}"), v.to_string());
        }
        if key == "max_input_coherence" && v > 1.0 {
            return fail("a coherence in (0, 1]", v.to_string());
        }
    }
    Ok(())
}

/// Parse a settings file into `T`: errors at their line and key, and an
/// array longer than its field refused ([`refuse_extra_elements`]).
pub fn parse_settings<T: serde::de::DeserializeOwned>(text: &str, path: &Path) -> Result<T> {
    let typed: T =
        toml::from_str(text).map_err(|e| Error::settings(path, text, e.span(), e.message()))?;
    refuse_extra_elements::<T>(text, path)?;
    Ok(typed)
}

/// The TOML parser fills a fixed-size field (`[[f64; 2]; 2]`, `[f64; 2]`)
/// from the first elements of a longer array and drops the rest in silence
/// (`stiffness = [[37.95, 9.31, 99, 99, 99], [9.31, 10.14]]` read as 2 x 2;
/// issue 76). Its generic value counts what is left: a second reading
/// through it names the array with elements to spare, by key and line.
pub fn refuse_extra_elements<T: serde::de::DeserializeOwned>(
    text: &str,
    path: &Path,
) -> Result<()> {
    let Ok(table) = toml::from_str::<toml::Table>(text) else {
        return Ok(()); // the typed reading has said what is wrong
    };
    let Err(e) = serde_path_to_error::deserialize::<_, T>(toml::Value::Table(table)) else {
        return Ok(());
    };
    if !e.inner().to_string().contains("fewer elements in array") {
        return Ok(()); // the typed reading accepted it; only lengths are ours
    }
    let key = e.path().to_string();
    // `a.b[1]` -> table `a`, key `b` for the line
    let bare = key.split('[').next().unwrap_or(&key);
    let (parent, name) = bare.rsplit_once('.').unwrap_or(("", bare));
    Err(Error::Format {
        path: path.to_path_buf(),
        message: format!(
            "{}key {key}: more elements than it takes (the extra ones would be dropped); give exactly the elements it takes",
            line_of(text, parent, name).map_or(String::new(), |l| format!("line {l}, "))
        ),
    })
}

/// The line of `key = ...` inside the table `parent` of `text`, if found.
fn line_of(text: &str, parent: &str, key: &str) -> Option<usize> {
    let mut table = String::new();
    let mut fallback = None;
    for (i, line) in text.lines().enumerate() {
        let l = line.trim();
        if let Some(h) = l.strip_prefix('[') {
            table = h
                .trim_start_matches('[')
                .split(']')
                .next()
                .unwrap_or("")
                .trim()
                .to_string();
            continue;
        }
        let dotted = format!("{parent}.{key}");
        let assigns = |k: &str| {
            l.strip_prefix(k)
                .is_some_and(|rest| rest.trim_start().starts_with('='))
        };
        if table == parent && assigns(key) {
            return Some(i + 1);
        }
        if (table.is_empty() && assigns(&dotted)) || (fallback.is_none() && assigns(key)) {
            fallback = Some(i + 1);
        }
        if fallback.is_none() && l.contains(&format!("{key} =")) {
            fallback = Some(i + 1);
        }
    }
    fallback
}

/// The first `(field, value, least, most)` outside its range, named with
/// its range: one rule per field (a negative `actuator_hz` listed every
/// rule and named none; issue 76). NaN is outside every range.
pub fn field_out_of_range(fields: &[(&str, f64, f64, f64)]) -> Option<String> {
    let num = limpid_core::error::Num;
    fields
        .iter()
        .find(|(_, v, least, most)| !(*least..=*most).contains(v))
        .map(|&(name, v, least, most)| {
            format!(
                "{name} = {}: expected {} to {}",
                num(v),
                num(least),
                num(most)
            )
        })
}

/// [`field_out_of_range`] as the error of the settings `what`.
pub fn fields_within(what: &str, fields: &[(&str, f64, f64, f64)]) -> Result<()> {
    match field_out_of_range(fields) {
        Some(message) => Err(Error::invalid(what, message)),
        None => Ok(()),
    }
}

/// Refuse a protocol that asks for more than [`MAX_SAMPLES`] samples.
pub fn check_size(samples: f64, what: &str) -> Result<()> {
    let within = samples <= MAX_SAMPLES; // false for NaN too
    if !within {
        return Err(Error::invalid(
            "protocol",
            format!(
                "it asks for {samples:.3e} samples ({what}); limpid simulates and exports at most {MAX_SAMPLES:e} per protocol"
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_and_non_positive_limits_name_line_and_key() {
        let text = "name = \"p\"\n[limits]\nmax_force_n = nan\n";
        let e = check_numbers(text, Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "p.toml: line 3, key limits.max_force_n: expected a finite number, found NaN"
        );
        let text = "link_lengths_m = [0.3, 0.0]\n";
        let e = check_numbers(text, Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "p.toml: line 1, key link_lengths_m: expected a positive number, found 0"
        );
        let text = "[targets]\ncount = 9223372036854775807\n";
        let e = check_numbers(text, Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 2, key targets.count: expected at most 256"),
            "{e}"
        );
    }
}
