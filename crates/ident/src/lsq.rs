//! Tall-skinny least squares pieces shared by the estimators: Householder QR
//! triangles of row blocks, merged pairwise (numerically a QR of the stacked
//! rows, never normal equations), so that delete-one-block jackknife
//! replicates cost one small merge each.

use nalgebra::DMatrix;

/// Upper triangle (q x q) of the Householder QR of `a` (rows of R may differ
/// in sign from another QR's; R^T R and every least-squares solution do not).
pub fn triangle(mut a: DMatrix<f64>, q: usize) -> DMatrix<f64> {
    let rows = a.nrows();
    if rows < q {
        let mut padded = DMatrix::<f64>::zeros(q, q);
        padded.rows_mut(0, rows).copy_from(&a);
        return triangle(padded, q);
    }
    let cols = q.min(a.ncols());
    householder_in_place(a.as_mut_slice(), rows, cols);
    DMatrix::from_fn(q, q, |i, j| if i <= j { a[(i, j)] } else { 0.0 })
}

/// Householder QR of a column-major `m x q` matrix in place; R is left in
/// the upper triangle (below it: garbage, not the reflectors). Written on
/// contiguous column slices so that the dot products and updates vectorise:
/// this is the hot loop of every tall-skinny fit (issue 16). On x86-64 CPUs
/// with AVX2 the same code runs compiled for 4-wide vectors (the baseline
/// target has 2-wide SSE2); the arithmetic per element is the same, so the
/// results are bit-identical.
pub fn householder_in_place(a: &mut [f64], m: usize, q: usize) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        unsafe { householder_avx2(a, m, q) };
        return;
    }
    householder_body(a, m, q)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn householder_avx2(a: &mut [f64], m: usize, q: usize) {
    householder_body(a, m, q)
}

#[inline(always)]
fn householder_body(a: &mut [f64], m: usize, q: usize) {
    debug_assert!(a.len() >= m * q && m >= q);
    for j in 0..q {
        let (head, tail) = a.split_at_mut((j + 1) * m);
        let v = &mut head[j * m + j..];
        let norm = {
            let w: &[f64] = v;
            dot(w, w)
        }
        .sqrt();
        if norm == 0.0 || !norm.is_finite() {
            continue;
        }
        let x0 = v[0];
        let alpha = if x0 > 0.0 { -norm } else { norm };
        v[0] = x0 - alpha;
        // ||v||^2 = 2 ||x||^2 - 2 x0 alpha
        let tau = 1.0 / (norm * norm - x0 * alpha);
        for k in 0..q - j - 1 {
            let col = &mut tail[k * m + j..(k + 1) * m];
            let s = dot(v, col) * tau;
            for (c, vi) in col.iter_mut().zip(v.iter()) {
                *c -= s * vi;
            }
        }
        v[0] = alpha;
    }
}

/// Dot product with four partial sums (lets the compiler vectorise the reduction).
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (x, y) in ra.iter().zip(rb) {
        s += x * y;
    }
    s
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

/// Per coefficient of a delete-a-block jackknife over `blocks` (each a
/// block's rows, or its triangle: only `X_i'X_i` of the first `p` columns
/// counts): Student's t over the normal quantile (both at 0.975) for
/// the jackknife's effective degrees of freedom, so that ±2 SE is a 95 %
/// interval however few blocks inform the coefficient (issue 58). A
/// delete-a-block jackknife is a sum of one square per block, block i
/// weighing `h_i = a' X_i'X_i a` (a = (X'X)^-1 e_j: the block's share of the
/// design for coefficient j); Welch–Satterthwaite gives `ν = (Σ h)² / Σ h²`
/// blocks, times (g - 1)/g for the mean taken out (Bell & McCaffrey's
/// degrees of freedom for cluster-robust errors). 16 trials in 16 directions
/// inform K_xx through fewer than 16: on signal-dependent force noise ±2 SE
/// covered 90 % of K's diagonal without it.
pub(crate) fn small_sample_factors(blocks: &[DMatrix<f64>], p: usize) -> Vec<f64> {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    let g = blocks.len();
    let grams: Vec<DMatrix<f64>> = blocks
        .iter()
        .map(|t| {
            let x = t.columns(0, p);
            x.transpose() * x
        })
        .collect();
    let total = grams
        .iter()
        .fold(DMatrix::<f64>::zeros(p, p), |acc, gram| acc + gram);
    let Some(inverse) = total.try_inverse() else {
        return vec![1.0; p];
    };
    let normal = 1.959_963_984_540_054;
    (0..p)
        .map(|j| {
            let a = inverse.column(j);
            let shares: Vec<f64> = grams
                .iter()
                .map(|gram| (a.transpose() * gram * a)[(0, 0)])
                .collect();
            let sum: f64 = shares.iter().sum();
            let squares: f64 = shares.iter().map(|h| h * h).sum();
            if g < 2 || !(sum > 0.0 && squares > 0.0) {
                return 1.0;
            }
            let dof = (sum * sum / squares * (g as f64 - 1.0) / g as f64).max(1.0);
            StudentsT::new(0.0, 1.0, dof)
                .map(|t| t.inverse_cdf(0.975) / normal)
                .unwrap_or(1.0)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn householder_triangle_matches_nalgebra_up_to_row_signs() {
        let a = DMatrix::from_fn(203, 7, |i, j| {
            ((i * 13 + j * 5) as f64).cos() + (j as f64) * 1e-3
        });
        let ours = triangle(a.clone(), 7);
        let theirs = a.qr().r();
        for i in 0..7 {
            let sign = (ours[(i, i)] * theirs[(i, i)]).signum();
            for j in 0..7 {
                assert!(
                    (ours[(i, j)] - sign * theirs[(i, j)]).abs() < 1e-12,
                    "({i},{j})"
                );
            }
        }
    }

    #[test]
    fn the_avx2_build_of_the_qr_gives_the_same_bits() {
        let a: Vec<f64> = (0..1037 * 13i32)
            .map(|i| ((i * 7919 % 1013) as f64).sin() * 10f64.powi((i % 5) - 2))
            .collect();
        let (mut dispatched, mut baseline) = (a.clone(), a);
        householder_in_place(&mut dispatched, 1037, 13);
        householder_body(&mut baseline, 1037, 13);
        assert_eq!(dispatched, baseline);
    }

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

    #[test]
    fn equal_blocks_give_students_t_on_g_minus_1_and_one_informative_block_one() {
        // 16 blocks with the same design: t(15) / z = 2.131 / 1.960
        let block = DMatrix::from_row_slice(2, 2, &[2.0, 0.5, 0.0, 1.0]);
        let same = vec![block.clone(); 16];
        let f = small_sample_factors(&same, 2);
        assert!((f[0] - 2.1314 / 1.95996).abs() < 1e-3, "{f:?}");
        // the second coefficient informed by one block only: one degree of freedom
        let mut lone: Vec<DMatrix<f64>> =
            vec![DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 0.0]); 15];
        lone.push(DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 1.0]));
        let f = small_sample_factors(&lone, 2);
        assert!((f[1] - 12.706 / 1.95996).abs() < 1e-2, "{f:?}");
        assert!(f[0] < 1.1, "{f:?}");
    }
}
