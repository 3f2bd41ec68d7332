//! Helpers shared by limpid-ident's integration tests.
#![allow(dead_code)]

use serde_json::Value;

/// `../shared/examples/<family>` from this crate.
pub fn examples(family: &str) -> String {
    format!(
        "{}/../../../shared/examples/{family}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// A JSON file.
pub fn truth(path: &str) -> Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    serde_json::from_str(&text).unwrap()
}

/// A row-major matrix from JSON.
pub fn mat(v: &Value) -> Vec<Vec<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

/// Relative Frobenius error ||est - truth|| / ||truth||.
pub fn rel_err(est: &[Vec<f64>], truth: &[Vec<f64>]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (a, b) in est.iter().flatten().zip(truth.iter().flatten()) {
        num += (a - b) * (a - b);
        den += b * b;
    }
    (num / den).sqrt()
}
