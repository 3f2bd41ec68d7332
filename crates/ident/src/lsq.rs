//! Tall-skinny least squares pieces shared by the estimators: Householder QR
//! triangles of row blocks, merged pairwise (numerically a QR of the stacked
//! rows, never normal equations), so that delete-one-block jackknife
//! replicates cost one small merge each.

use nalgebra::DMatrix;

/// Upper triangle (q x q) of the Householder QR of `a`.
pub fn triangle(a: DMatrix<f64>, q: usize) -> DMatrix<f64> {
    let rows = a.nrows();
    if rows < q {
        let mut padded = DMatrix::<f64>::zeros(q, q);
        padded.rows_mut(0, rows).copy_from(&a);
        return triangle(padded, q);
    }
    a.qr().r()
}

/// Merge q x q triangles into the triangle of their stacked rows.
pub fn merge<'a>(tris: impl Iterator<Item = &'a DMatrix<f64>>, q: usize) -> DMatrix<f64> {
    let tris: Vec<&DMatrix<f64>> = tris.collect();
    let mut stacked = DMatrix::<f64>::zeros(tris.len().max(1) * q, q);
    for (k, t) in tris.iter().enumerate() {
        stacked.rows_mut(k * q, q).copy_from(t);
    }
    triangle(stacked, q)
}
