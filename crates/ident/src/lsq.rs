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

/// The triangle of every delete-one-block set: `out[b]` merges all blocks
/// but `tris[b]`. Built from prefix and suffix merges, 3 g small merges
/// instead of g stacks of g - 1 triangles; the same rows, so the same
/// least-squares solutions.
pub fn leave_one_out(tris: &[DMatrix<f64>], q: usize) -> Vec<DMatrix<f64>> {
    let g = tris.len();
    let pair = |a: &DMatrix<f64>, b: &DMatrix<f64>| merge([a, b].into_iter(), q);
    // prefix[i] merges tris[..i], suffix[i] merges tris[i..]
    let mut prefix: Vec<Option<DMatrix<f64>>> = vec![None; g + 1];
    for i in 0..g {
        prefix[i + 1] = Some(match &prefix[i] {
            Some(p) => pair(p, &tris[i]),
            None => tris[i].clone(),
        });
    }
    let mut suffix: Vec<Option<DMatrix<f64>>> = vec![None; g + 1];
    for i in (0..g).rev() {
        suffix[i] = Some(match &suffix[i + 1] {
            Some(s) => pair(&tris[i], s),
            None => tris[i].clone(),
        });
    }
    (0..g)
        .map(|b| match (&prefix[b], &suffix[b + 1]) {
            (Some(p), Some(s)) => pair(p, s),
            (Some(t), None) | (None, Some(t)) => t.clone(),
            (None, None) => DMatrix::zeros(q, q),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leave_one_out_triangles_solve_like_the_stacked_rows() {
        // 5 blocks of 7 rows, 3 columns; compare R^T R (sign-free) with the stacked Gram matrix
        let blocks: Vec<DMatrix<f64>> = (0..5)
            .map(|b| DMatrix::from_fn(7, 3, |i, j| ((b * 31 + i * 7 + j * 3) as f64).sin()))
            .collect();
        let tris: Vec<DMatrix<f64>> = blocks.iter().map(|b| triangle(b.clone(), 3)).collect();
        for (b, t) in leave_one_out(&tris, 3).iter().enumerate() {
            let mut gram = DMatrix::<f64>::zeros(3, 3);
            for (k, blk) in blocks.iter().enumerate() {
                if k != b {
                    gram += blk.transpose() * blk;
                }
            }
            let got = t.transpose() * t;
            assert!((got - &gram).norm() < 1e-12 * gram.norm(), "block {b}");
        }
    }
}
