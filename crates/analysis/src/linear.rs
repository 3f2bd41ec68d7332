//! The complete result of `estimate linear`: estimate, analysis and quality,
//! with the keys the CLI's `--json` and the Python package share.

use serde::Serialize;

use crate::{
    antisymmetric, criteria, ellipsoid, symmetric, table_ii, Ellipsoid, Mat, MatrixCriteria,
    TableII,
};
use limpid_ident::linear::{units, FitQuality, Identifiable, LinearEstimate, StandardErrors};
use limpid_ident::Prepared;

/// One value per matrix kind.
#[derive(Debug, Clone, Serialize)]
pub struct PerMatrix<T> {
    pub inertia: T,
    pub damping: T,
    pub stiffness: T,
}

impl<T> PerMatrix<Option<T>> {
    /// True when no matrix has a value.
    pub fn all_none(&self) -> bool {
        self.inertia.is_none() && self.damping.is_none() && self.stiffness.is_none()
    }
}

impl<T> PerMatrix<T> {
    fn from_fn(est: &LinearEstimate, f: impl Fn(&Mat) -> T) -> Self {
        PerMatrix {
            inertia: f(&est.inertia),
            damping: f(&est.damping),
            stiffness: f(&est.stiffness),
        }
    }
}

/// Quality criteria of the whole estimate.
#[derive(Debug, Clone, Serialize)]
pub struct Criteria {
    pub condition_number: f64,
    pub matrices: PerMatrix<MatrixCriteria>,
    pub identifiable: Identifiable,
    /// `[acceleration, velocity, displacement]` signal share per coordinate.
    pub regressor_reliability: Vec<[f64; 3]>,
    pub standard_error_method: String,
    pub samples: usize,
    pub parameters: usize,
}

/// Where the data came from and how it was prepared.
#[derive(Debug, Clone, Serialize)]
pub struct Provenance {
    pub recording: String,
    pub coordinates: Vec<String>,
    pub force_columns: Vec<String>,
    /// Units of inertia, damping, stiffness entries.
    pub units: [String; 3],
    pub sample_rate_hz: f64,
    pub windows: usize,
    pub continuous: bool,
    pub cutoff_hz: f64,
    pub filter_order: usize,
    pub derivative: String,
    pub offsets: String,
    pub edge_trim_samples: usize,
}

/// Everything `estimate linear --json` prints.
#[derive(Debug, Clone, Serialize)]
pub struct LinearResult {
    pub inertia: Mat,
    pub damping: Mat,
    pub stiffness: Mat,
    /// Absolute equilibrium position, or null (see `warnings`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub equilibrium: Option<Vec<f64>>,
    pub standard_errors: StandardErrors,
    pub symmetric: PerMatrix<Mat>,
    pub antisymmetric: PerMatrix<Mat>,
    /// Ellipsoids of the symmetric parts (2 or 3 coordinates; the key is
    /// absent for 1 coordinate, where no ellipsoid exists).
    #[serde(skip_serializing_if = "PerMatrix::all_none")]
    pub ellipsoids: PerMatrix<Option<Ellipsoid>>,
    pub table_ii: PerMatrix<TableII>,
    pub fit: FitQuality,
    pub criteria: Criteria,
    pub warnings: Vec<String>,
    pub provenance: Provenance,
}

/// Analyse a linear estimate.
pub fn linear_result(est: &LinearEstimate, data: &Prepared) -> LinearResult {
    let (mu, bu, ku) = units(&data.coordinates);
    let matrices = PerMatrix::from_fn(est, criteria);
    let mut warnings = est.warnings.clone();
    for (name, c, identified) in [
        ("stiffness", &matrices.stiffness, est.identifiable.stiffness),
        ("damping", &matrices.damping, est.identifiable.damping),
    ] {
        if identified && !c.positive_definite {
            warnings.push(format!(
                "the symmetric part of the {name} matrix is not positive definite (smallest eigenvalue {:.4}): not a passive {name}",
                c.min_eigenvalue
            ));
        }
    }
    LinearResult {
        inertia: est.inertia.clone(),
        damping: est.damping.clone(),
        stiffness: est.stiffness.clone(),
        equilibrium: est.equilibrium.clone(),
        standard_errors: est.standard_errors.clone(),
        symmetric: PerMatrix::from_fn(est, symmetric),
        antisymmetric: PerMatrix::from_fn(est, antisymmetric),
        ellipsoids: PerMatrix::from_fn(est, ellipsoid),
        table_ii: PerMatrix::from_fn(est, table_ii),
        fit: est.fit.clone(),
        criteria: Criteria {
            condition_number: est.condition_number,
            matrices,
            identifiable: est.identifiable.clone(),
            regressor_reliability: est.regressor_reliability.clone(),
            standard_error_method: est.standard_error_method.clone(),
            samples: est.samples,
            parameters: est.parameters,
        },
        warnings,
        provenance: Provenance {
            recording: data.path.display().to_string(),
            coordinates: data.coordinates.clone(),
            force_columns: data.force_columns.clone(),
            units: [mu.into(), bu.into(), ku.into()],
            sample_rate_hz: data.fs,
            windows: data.windows.len(),
            continuous: data.continuous,
            cutoff_hz: data.cutoff_hz,
            filter_order: data.filter_order,
            derivative: format!("{:?}", data.derivative).to_lowercase(),
            offsets: if data.continuous {
                "constant".into()
            } else if data.demeaned {
                "fit".into()
            } else {
                "rest".into()
            },
            edge_trim_samples: data.trim,
        },
    }
}
