//! limpid-analysis: what an impedance matrix says.
//!
//! - symmetric / antisymmetric split Z = Z_s + Z_a (seed 000 eq. (10)-(11),
//!   seed 001 eq. (11)-(12)) and the Table II quantities of seed 000;
//! - the ellipsoid of a symmetric matrix (seed 000 eq. (13)-(17)): principal
//!   axes sorted by decreasing eigenvalue, made a right-handed rotation
//!   (det +1) by flipping the third axis if needed, yaw/pitch/roll with
//!   R = Rz(yaw) Ry(pitch) Rx(roll) per eq. (17), and two radius conventions:
//!   `radii_inverse_sqrt` = 1/sqrt(λ) (seed 000, the quadric x^T A x = 1) and
//!   `radii_proportional` = λ (seed 001 Fig. 5, length proportional to stiffness);
//! - criteria (seed 003 §III-C): positive definiteness of the symmetric part
//!   (smallest eigenvalue > 0) and the symmetry ratio ||Z_a||_F / ||Z_s||_F.

#![warn(missing_docs)]

pub mod cocontraction;
pub mod emg;
pub mod linear;
pub mod markers;
pub mod result;
pub mod shapes;
pub mod shoulder;

use nalgebra::{DMatrix, Matrix3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

pub use limpid_core::criteria::{matrix_criteria as criteria, MatrixCriteria};
pub use limpid_core::Matrix;

/// Symmetric part (Z + Z^T) / 2.
pub fn symmetric(m: &Matrix) -> Matrix {
    m.symmetric_part()
}

/// Antisymmetric part (Z - Z^T) / 2.
pub fn antisymmetric(m: &Matrix) -> Matrix {
    m.antisymmetric_part()
}

/// Seed 000 Table II quantities of one matrix.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct TableII {
    /// Largest absolute element of the symmetric part.
    pub max_symmetric: f64,
    /// Smallest absolute element of the symmetric part.
    pub min_symmetric: f64,
    /// Largest absolute off-diagonal element of the antisymmetric part.
    pub max_antisymmetric: f64,
}

/// Table II quantities (seed 000).
pub fn table_ii(m: &Matrix) -> TableII {
    let s = symmetric(m);
    let a = antisymmetric(m);
    let abs_s = s.iter().map(|v| v.abs());
    TableII {
        max_symmetric: abs_s.clone().fold(0.0, f64::max),
        min_symmetric: abs_s.fold(f64::INFINITY, f64::min),
        max_antisymmetric: a.iter().map(|v| v.abs()).fold(0.0, f64::max),
    }
}

/// The ellipsoid (or ellipse, for 2 x 2) of a symmetric matrix.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Ellipsoid {
    /// Eigenvalues, largest first.
    pub eigenvalues: Vec<f64>,
    /// Principal axes as the columns of a rotation matrix (det +1), row-major.
    pub axes: Matrix,
    /// Yaw, pitch, roll in degrees (seed 000 eq. (17)); for 2 x 2, one angle of
    /// the major axis from the first coordinate axis.
    pub angles_deg: Vec<f64>,
    /// 1/sqrt(λ) per axis (seed 000); absent when some λ <= 0 (the quadric
    /// x^T A x = 1 is then no ellipsoid), with the reason in `note`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radii_inverse_sqrt: Option<Vec<f64>>,
    /// Why a radius convention is absent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// λ per axis: length proportional to stiffness (seed 001).
    pub radii_proportional: Vec<f64>,
}

/// Ellipsoid of the symmetric part of `m` (n = 2 or 3); `None` for other sizes.
pub fn ellipsoid(m: &Matrix) -> Option<Ellipsoid> {
    let n = m.nrows();
    if !(2..=3).contains(&n) || m.ncols() != n {
        return None;
    }
    let s = symmetric(m).0;
    let eig = limpid_core::linalg::symmetric_eigen(s)?;
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let values: Vec<f64> = order.iter().map(|&i| eig.eigenvalues[i]).collect();
    let mut axes = DMatrix::from_fn(n, n, |r, c| eig.eigenvectors[(r, order[c])]);
    if axes.determinant() < 0.0 {
        for r in 0..n {
            axes[(r, n - 1)] = -axes[(r, n - 1)];
        }
    }
    let angles_deg = if n == 3 {
        let r = Matrix3::from_fn(|i, j| axes[(i, j)]);
        let (yaw, pitch, roll) = yaw_pitch_roll(&r);
        vec![yaw.to_degrees(), pitch.to_degrees(), roll.to_degrees()]
    } else {
        vec![axes[(1, 0)].atan2(axes[(0, 0)]).to_degrees()]
    };
    Some(Ellipsoid {
        radii_inverse_sqrt: values
            .iter()
            .all(|l| *l > 0.0)
            .then(|| values.iter().map(|l| 1.0 / l.sqrt()).collect()),
        note: values.iter().any(|l| *l <= 0.0).then(|| {
            format!(
                "radii_inverse_sqrt omitted: the smallest eigenvalue is {:.4e} <= 0, so the matrix is not positive definite and x^T A x = 1 is no ellipsoid",
                values[n - 1]
            )
        }),
        radii_proportional: values.clone(),
        eigenvalues: values,
        axes: Matrix(axes),
        angles_deg,
    })
}

/// Seed 000 eq. (17): yaw α, pitch β, roll γ (rad) of R = Rz(α) Ry(β) Rx(γ).
pub fn yaw_pitch_roll(r: &Matrix3<f64>) -> (f64, f64, f64) {
    let yaw = r[(1, 0)].atan2(r[(0, 0)]);
    let pitch = (-r[(2, 0)]).atan2((r[(2, 1)].powi(2) + r[(2, 2)].powi(2)).sqrt());
    let roll = r[(2, 1)].atan2(r[(2, 2)]);
    (yaw, pitch, roll)
}

/// R = Rz(yaw) Ry(pitch) Rx(roll), angles in rad.
pub fn rotation_from_ypr(yaw: f64, pitch: f64, roll: f64) -> Matrix3<f64> {
    let rz = Matrix3::new(
        yaw.cos(),
        -yaw.sin(),
        0.0,
        yaw.sin(),
        yaw.cos(),
        0.0,
        0.0,
        0.0,
        1.0,
    );
    let ry = Matrix3::new(
        pitch.cos(),
        0.0,
        pitch.sin(),
        0.0,
        1.0,
        0.0,
        -pitch.sin(),
        0.0,
        pitch.cos(),
    );
    let rx = Matrix3::new(
        1.0,
        0.0,
        0.0,
        0.0,
        roll.cos(),
        -roll.sin(),
        0.0,
        roll.sin(),
        roll.cos(),
    );
    rz * ry * rx
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mat(rows: &[&[f64]]) -> Matrix {
        Matrix::from_rows(&rows.iter().map(|r| r.to_vec()).collect::<Vec<_>>()).unwrap()
    }
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn ellipsoid_angles_round_trip(yaw in -3.0f64..3.0, pitch in -1.5f64..1.5, roll in -3.0f64..3.0,
                                       l1 in 500.0f64..1000.0, l2 in 200.0f64..450.0, l3 in 10.0f64..150.0) {
            let r = rotation_from_ypr(yaw, pitch, roll);
            let k = r * Matrix3::from_diagonal(&nalgebra::Vector3::new(l1, l2, l3)) * r.transpose();
            let m = Matrix::from(k);
            let e = ellipsoid(&m).unwrap();
            prop_assert!((e.eigenvalues[0] - l1).abs() < 1e-8 * l1);
            prop_assert!((e.eigenvalues[2] - l3).abs() < 1e-8 * l1);
            let axes = Matrix3::from_fn(|i, j| e.axes[(i, j)]);
            prop_assert!((axes.determinant() - 1.0).abs() < 1e-9, "right-handed");
            // the recovered angles rebuild the principal frame up to axis signs:
            // each rebuilt column is parallel to the true column
            let back = rotation_from_ypr(e.angles_deg[0].to_radians(), e.angles_deg[1].to_radians(), e.angles_deg[2].to_radians());
            prop_assert!((back - axes).norm() < 1e-8);
            for c in 0..3 {
                prop_assert!((back.column(c).dot(&r.column(c)).abs() - 1.0).abs() < 1e-8);
            }
        }
    }

    #[test]
    fn split_and_table_ii() {
        let m = mat(&[&[10.0, 3.0], &[1.0, 5.0]]);
        assert_eq!(symmetric(&m), mat(&[&[10.0, 2.0], &[2.0, 5.0]]));
        assert_eq!(antisymmetric(&m), mat(&[&[0.0, 1.0], &[-1.0, 0.0]]));
        let t = table_ii(&m);
        assert_eq!(
            (t.max_symmetric, t.min_symmetric, t.max_antisymmetric),
            (10.0, 2.0, 1.0)
        );
        let c = criteria(&m);
        assert!(c.positive_definite);
        assert!(
            (c.symmetry_ratio - (2.0f64).sqrt() / (100.0f64 + 8.0 + 25.0).sqrt()).abs() < 1e-12
        );
    }

    #[test]
    fn ellipse_radii_conventions() {
        let m = mat(&[&[400.0, 0.0], &[0.0, 100.0]]);
        let e = ellipsoid(&m).unwrap();
        assert_eq!(e.radii_proportional, vec![400.0, 100.0]);
        assert_eq!(e.radii_inverse_sqrt, Some(vec![0.05, 0.1]));
        assert!(e.angles_deg[0].abs() < 1e-12 || (e.angles_deg[0].abs() - 180.0).abs() < 1e-12);
        assert!(e.note.is_none());
    }

    #[test]
    fn a_matrix_that_is_not_positive_definite_has_no_inverse_radii_and_says_why() {
        let e = ellipsoid(&mat(&[&[400.0, 0.0], &[0.0, -10.0]])).unwrap();
        let json = serde_json::to_value(&e).unwrap();
        assert!(json.get("radii_inverse_sqrt").is_none(), "{json}");
        assert!(json["note"]
            .as_str()
            .unwrap()
            .contains("not positive definite"));
        assert!(!json.to_string().contains("null"), "{json}");
        // a non-finite matrix has no ellipsoid at all, rather than NaN axes
        assert!(ellipsoid(&mat(&[&[f64::NAN, 0.0], &[0.0, 1.0]])).is_none());
    }
}
