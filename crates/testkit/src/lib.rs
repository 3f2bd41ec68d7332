//! limpid-testkit: the helpers every test crate of the workspace shares,
//! written once: where the shared material is, JSON files and matrices,
//! and the relative Frobenius error the tests compare against truth with.

use std::path::{Path, PathBuf};

use limpid_core::Matrix;
use nalgebra::DMatrix;
use serde_json::Value;

/// `../shared` beside the checkout (CI clones the repository next to it).
pub fn shared() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared")
}

/// `../shared/examples/<family>` as a string path.
pub fn examples(family: &str) -> String {
    shared().join("examples").join(family).display().to_string()
}

/// A JSON file, parsed.
pub fn read_json<P: AsRef<Path> + ?Sized>(path: &P) -> Value {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A row-major matrix from JSON.
pub fn mat(v: &Value) -> Matrix {
    let rows: Vec<Vec<f64>> = v
        .as_array()
        .unwrap_or_else(|| panic!("not a matrix: {v}"))
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap_or_else(|| panic!("not a matrix row: {r}"))
                .iter()
                .map(|x| x.as_f64().unwrap_or_else(|| panic!("not a number: {x}")))
                .collect()
        })
        .collect();
    Matrix::from_rows(&rows).unwrap_or_else(|| panic!("ragged matrix: {v}"))
}

/// Relative Frobenius error ||est - truth|| / ||truth||.
pub fn rel_err(est: &DMatrix<f64>, truth: &DMatrix<f64>) -> f64 {
    assert_eq!(
        est.shape(),
        truth.shape(),
        "estimate and truth differ in shape"
    );
    (est - truth).norm() / truth.norm()
}
