//! Confidence criteria of an impedance matrix (seed 003 §III-C), the one
//! implementation every estimator and the report use.
//!
//! - positive definiteness of the symmetric part `Z_s = (Z + Z^T) / 2`
//!   (smallest eigenvalue > 0: a passive stiffness or damping);
//! - the symmetry ratio `||Z_a||_F / ||Z_s||_F` with `Z_a = (Z - Z^T) / 2`
//!   (seed 000 eq. (10)-(11)); "quasi-symmetric" below [`QUASI_SYMMETRIC`];
//! - the condition number of the regressor, "well-conditioned" below
//!   [`MAX_CONDITION`] (seed 003 eq. (19)).
//!
//! Every test is written so that a NaN fails it: a NaN never reads as trusted.

use nalgebra::DMatrix;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Symmetry ratio below which a matrix counts as quasi-symmetric (seed 003
/// gives no number; 0.1 is our choice, documented in the README).
pub const QUASI_SYMMETRIC: f64 = 0.1;

/// Scaled condition number below which a regressor counts as well-conditioned.
pub const MAX_CONDITION: f64 = 1000.0;

/// Ratio reported for a matrix whose symmetric part is zero but whose
/// antisymmetric part is not (the ratio is unbounded; JSON has no infinity).
pub const UNBOUNDED_RATIO: f64 = f64::MAX;

/// Confidence criteria of one matrix.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct MatrixCriteria {
    /// Smallest eigenvalue of the symmetric part.
    pub min_eigenvalue: f64,
    /// Symmetric part positive definite (smallest eigenvalue > 0).
    pub positive_definite: bool,
    /// ||Z_a||_F / ||Z_s||_F (0 for a symmetric matrix; [`UNBOUNDED_RATIO`]
    /// when Z_s = 0 and Z_a is not).
    pub symmetry_ratio: f64,
}

impl MatrixCriteria {
    /// Symmetry ratio below [`QUASI_SYMMETRIC`].
    pub fn quasi_symmetric(&self) -> bool {
        self.symmetry_ratio < QUASI_SYMMETRIC
    }
}

/// Eigenvalues of the symmetric part, largest first; NaN when they cannot
/// be computed (non-finite entries).
pub fn symmetric_part_eigenvalues(m: &DMatrix<f64>) -> Vec<f64> {
    let s = (m + m.transpose()) * 0.5;
    match crate::linalg::symmetric_eigenvalues(s) {
        Some(e) => {
            let mut v: Vec<f64> = e.iter().copied().collect();
            v.sort_by(|a, b| b.total_cmp(a));
            v
        }
        None => vec![f64::NAN; m.nrows()],
    }
}

/// ||Z_a||_F / ||Z_s||_F.
pub fn symmetry_ratio(m: &DMatrix<f64>) -> f64 {
    let s = ((m + m.transpose()) * 0.5).norm();
    let a = ((m - m.transpose()) * 0.5).norm();
    if s > 0.0 {
        a / s
    } else if a == 0.0 {
        0.0
    } else if a.is_nan() || s.is_nan() {
        f64::NAN
    } else {
        UNBOUNDED_RATIO
    }
}

/// Criteria of one square matrix.
pub fn matrix_criteria(m: &DMatrix<f64>) -> MatrixCriteria {
    let min_eigenvalue = symmetric_part_eigenvalues(m)
        .last()
        .copied()
        .unwrap_or(f64::NAN);
    MatrixCriteria {
        min_eigenvalue,
        positive_definite: min_eigenvalue > 0.0,
        symmetry_ratio: symmetry_ratio(m),
    }
}

/// Scaled condition number below [`MAX_CONDITION`] (NaN fails).
pub fn well_conditioned(condition_number_scaled: f64) -> bool {
    condition_number_scaled < MAX_CONDITION
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ratio_and_definiteness_of_a_known_matrix() {
        let m = DMatrix::from_row_slice(2, 2, &[10.0, 3.0, 1.0, 5.0]);
        let c = matrix_criteria(&m);
        assert!(c.positive_definite);
        let expected = 2f64.sqrt() / (100.0f64 + 8.0 + 25.0).sqrt();
        assert!((c.symmetry_ratio - expected).abs() < 1e-12);
        let e = symmetric_part_eigenvalues(&m);
        assert!(e[0] > e[1]);
        assert!((e[0] + e[1] - 15.0).abs() < 1e-12);
    }

    #[test]
    fn nan_and_degenerate_matrices_are_never_trusted() {
        let nan = DMatrix::from_row_slice(2, 2, &[f64::NAN, 0.0, 0.0, 1.0]);
        let c = matrix_criteria(&nan);
        assert!(!c.positive_definite && !c.quasi_symmetric());
        let skew = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -1.0, 0.0]);
        let c = matrix_criteria(&skew);
        assert_eq!(c.symmetry_ratio, UNBOUNDED_RATIO);
        assert!(!c.positive_definite && !c.quasi_symmetric());
        assert!(!well_conditioned(f64::NAN));
    }
}
