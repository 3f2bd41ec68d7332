//! The one matrix type at the boundaries of limpid's crates.
//!
//! Inside, every estimator computes with nalgebra; a result hands its
//! matrices out as [`Matrix`], which derefs to `DMatrix<f64>` and serialises
//! row-major, `[[m11, m12, ...], [m21, ...], ...]` (the workspace convention,
//! see the crate docs). Deserialising checks that the rows are rectangular
//! and the numbers finite-or-refused by the caller.

use std::borrow::Cow;
use std::ops::{Deref, DerefMut};

use nalgebra::{DMatrix, Matrix2, Matrix3};
use schemars::{JsonSchema, Schema, SchemaGenerator};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A real matrix, row-major in JSON.
#[derive(Debug, Clone, PartialEq)]
pub struct Matrix(pub DMatrix<f64>);

impl Matrix {
    /// `rows x cols` zeros.
    pub fn zeros(rows: usize, cols: usize) -> Self {
        Matrix(DMatrix::zeros(rows, cols))
    }

    /// From rows; `None` when they are not all the same length.
    pub fn from_rows(rows: &[Vec<f64>]) -> Option<Self> {
        let cols = rows.first().map_or(0, Vec::len);
        if rows.iter().any(|r| r.len() != cols) {
            return None;
        }
        Some(Matrix(DMatrix::from_fn(rows.len(), cols, |i, j| {
            rows[i][j]
        })))
    }

    /// The rows, each a vector.
    pub fn rows(&self) -> Vec<Vec<f64>> {
        (0..self.nrows())
            .map(|i| (0..self.ncols()).map(|j| self[(i, j)]).collect())
            .collect()
    }

    /// The symmetric part (Z + Z^T) / 2 (seed 000 eq. (10)).
    pub fn symmetric_part(&self) -> Matrix {
        Matrix((&self.0 + self.0.transpose()) * 0.5)
    }

    /// The antisymmetric part (Z - Z^T) / 2 (seed 000 eq. (11)).
    pub fn antisymmetric_part(&self) -> Matrix {
        Matrix((&self.0 - self.0.transpose()) * 0.5)
    }

    /// The matrix as a 3 x 3, when it is one.
    pub fn to_matrix3(&self) -> Option<Matrix3<f64>> {
        (self.shape() == (3, 3)).then(|| Matrix3::from_fn(|i, j| self[(i, j)]))
    }

    /// The matrix as a 2 x 2, when it is one.
    pub fn to_matrix2(&self) -> Option<Matrix2<f64>> {
        (self.shape() == (2, 2)).then(|| Matrix2::from_fn(|i, j| self[(i, j)]))
    }
}

impl Deref for Matrix {
    type Target = DMatrix<f64>;
    fn deref(&self) -> &DMatrix<f64> {
        &self.0
    }
}

impl DerefMut for Matrix {
    fn deref_mut(&mut self) -> &mut DMatrix<f64> {
        &mut self.0
    }
}

impl From<DMatrix<f64>> for Matrix {
    fn from(m: DMatrix<f64>) -> Self {
        Matrix(m)
    }
}

impl From<Matrix3<f64>> for Matrix {
    fn from(m: Matrix3<f64>) -> Self {
        Matrix(DMatrix::from_fn(3, 3, |i, j| m[(i, j)]))
    }
}

impl From<Matrix2<f64>> for Matrix {
    fn from(m: Matrix2<f64>) -> Self {
        Matrix(DMatrix::from_fn(2, 2, |i, j| m[(i, j)]))
    }
}

impl From<[[f64; 2]; 2]> for Matrix {
    fn from(m: [[f64; 2]; 2]) -> Self {
        Matrix(DMatrix::from_fn(2, 2, |i, j| m[i][j]))
    }
}

impl Serialize for Matrix {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.rows().serialize(s)
    }
}

impl<'de> Deserialize<'de> for Matrix {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let rows = Vec::<Vec<f64>>::deserialize(d)?;
        Matrix::from_rows(&rows)
            .ok_or_else(|| serde::de::Error::custom("matrix rows differ in length"))
    }
}

impl JsonSchema for Matrix {
    fn schema_name() -> Cow<'static, str> {
        "Matrix".into()
    }

    fn json_schema(generator: &mut SchemaGenerator) -> Schema {
        let mut schema = <Vec<Vec<f64>>>::json_schema(generator);
        schema.insert(
            "description".into(),
            "A real matrix, row by row (SI units).".into(),
        );
        schema
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn row_major_round_trip() {
        let m = Matrix::from_rows(&[vec![1.0, 2.0, 3.0], vec![4.0, 5.0, 6.0]]).unwrap();
        assert_eq!(m[(0, 2)], 3.0);
        assert_eq!(m[(1, 0)], 4.0);
        let text = serde_json::to_string(&m).unwrap();
        assert_eq!(text, "[[1.0,2.0,3.0],[4.0,5.0,6.0]]");
        let back: Matrix = serde_json::from_str(&text).unwrap();
        assert_eq!(back, m);
    }

    #[test]
    fn ragged_rows_are_refused() {
        assert!(Matrix::from_rows(&[vec![1.0], vec![1.0, 2.0]]).is_none());
        assert!(serde_json::from_str::<Matrix>("[[1.0],[1.0,2.0]]").is_err());
    }

    #[test]
    fn symmetric_and_antisymmetric_parts_add_up() {
        let m = Matrix::from_rows(&[vec![1.0, 2.0], vec![4.0, 3.0]]).unwrap();
        let (s, a) = (m.symmetric_part(), m.antisymmetric_part());
        assert_eq!(s[(0, 1)], 3.0);
        assert_eq!(a[(0, 1)], -1.0);
        assert_eq!(&s.0 + &a.0, m.0);
    }
}
