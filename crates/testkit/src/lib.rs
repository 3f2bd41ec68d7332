//! limpid-testkit: the helpers every test crate of the workspace shares,
//! written once: the example recordings (made by limpid's lab, [`examples`]),
//! the optional outside data (`LIMPID_EXAMPLES`, `LIMPID_REAL_DATA`), JSON
//! files and matrices, and the relative Frobenius error the tests compare
//! against truth with.

use std::path::{Path, PathBuf};

use limpid_core::truth::{
    CartesianTruth, CocontractionTruth, PlanarTruth, StochasticTruth, Truth, VaryingTruth,
};
use limpid_core::Matrix;
use nalgebra::DMatrix;
use serde_json::Value;

pub mod examples;
pub mod xdf;

pub use examples::limpid_examples;

/// limpid-made examples of `family` (`cartesian_slow`, `cocontraction`,
/// `planar`, `stochastic`) as a folder path.
pub fn examples(family: &str) -> PathBuf {
    limpid_examples(family)
}

/// Every example set a truth test should run on: limpid's own, then the
/// outside generator's when `LIMPID_EXAMPLES` names it (said on stderr when not).
pub fn example_sets(family: &str) -> Vec<(&'static str, PathBuf)> {
    let mut sets = vec![("limpid", limpid_examples(family))];
    if let Some(outside) = outside_examples(family) {
        sets.push(("outside", outside));
    }
    sets
}

/// The outside generator's examples of `family` (`$LIMPID_EXAMPLES/<family>`),
/// or `None`, saying on stderr that those checks were skipped.
pub fn outside_examples(family: &str) -> Option<PathBuf> {
    optional_folder("LIMPID_EXAMPLES", family)
}

/// Real recordings (`$LIMPID_REAL_DATA/<sub>`, e.g. `reklab_ankle`), or
/// `None`, saying on stderr that the test was skipped.
pub fn real_data(sub: &str) -> Option<PathBuf> {
    optional_folder("LIMPID_REAL_DATA", sub)
}

fn optional_folder(variable: &str, sub: &str) -> Option<PathBuf> {
    match std::env::var_os(variable) {
        Some(root) if !root.is_empty() => {
            let dir = PathBuf::from(root).join(sub);
            assert!(
                dir.is_dir(),
                "{variable} is set but {} is not a folder",
                dir.display()
            );
            Some(dir)
        }
        _ => {
            eprintln!("skipped: {variable} is not set ({sub})");
            None
        }
    }
}

/// A JSON file, parsed.
pub fn read_json<P: AsRef<Path> + ?Sized>(path: &P) -> Value {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A truth file (`*.truth.json`), read through its type.
pub fn read_truth<P: AsRef<Path> + ?Sized>(path: &P) -> Truth {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Truth::from_json(&path.display().to_string(), &text).unwrap_or_else(|e| panic!("{e}"))
}

macro_rules! truth_of_kind {
    ($name:ident, $variant:ident, $ty:ty) => {
        #[doc = concat!("A truth file that must be a `", stringify!($variant), "` one.")]
        pub fn $name<P: AsRef<Path> + ?Sized>(path: &P) -> $ty {
            match read_truth(path) {
                Truth::$variant(t) => t,
                other => panic!(
                    "{}: not a {} truth: {other:?}",
                    path.as_ref().display(),
                    stringify!($variant)
                ),
            }
        }
    };
}
truth_of_kind!(cartesian_truth, Cartesian, CartesianTruth);
truth_of_kind!(cocontraction_truth, Cocontraction, CocontractionTruth);
truth_of_kind!(planar_truth, Planar, PlanarTruth);
truth_of_kind!(stochastic_truth, Stochastic, StochasticTruth);
truth_of_kind!(varying_truth, Varying, VaryingTruth);

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
