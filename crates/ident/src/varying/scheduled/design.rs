//! Least squares over the rows: cross products by folds, the fit and its
//! cross-validated residual, block-jackknife covariances.

use nalgebra::DMatrix;
use rayon::prelude::*;

use super::rows::Rows;
use super::{solve_scaled, FOLDS};

pub(super) struct Design<'a> {
    pub(super) rows: &'a Rows,
    pub(super) order: usize,
    pub(super) reflex: Option<&'a [f64]>,
}

impl Design<'_> {
    /// Columns: M, B, K of each coordinate (degrees 0..=order), the offset
    /// c(σ) (degrees 1..=order + 1: it holds `K(σ) σ_eq(σ)`, one order above
    /// K; its constant detrends to zero), the reflex gain (0..=order).
    pub(super) fn columns(&self) -> usize {
        let p1 = self.order + 1;
        3 * self.rows.d * p1
            + usize::from(self.rows.offset) * p1
            + usize::from(self.reflex.is_some()) * p1
    }

    pub(super) fn row(&self, n: usize, out: &mut [f64]) {
        let (d, p1, top1) = (self.rows.d, self.order + 1, self.rows.top + 1);
        let x = &self.rows.x[n * self.rows.width..(n + 1) * self.rows.width];
        let mut c = 0;
        for g in 0..3 * d {
            out[c..c + p1].copy_from_slice(&x[g * top1..g * top1 + p1]);
            c += p1;
        }
        if self.rows.offset {
            out[c..c + p1].copy_from_slice(&x[3 * d * top1 + 1..3 * d * top1 + p1 + 1]);
            c += p1;
        }
        if let Some(r) = self.reflex {
            out[c..c + p1].copy_from_slice(&r[n * top1..n * top1 + p1]);
        }
    }

    /// The first column of the reflex gains.
    pub(super) fn reflex_start(&self) -> usize {
        (3 * self.rows.d + usize::from(self.rows.offset)) * (self.order + 1)
    }

    /// Over the rows `range`: Gram matrix, regressor-force products, Σ f² per output.
    pub(super) fn cross_products(
        &self,
        range: std::ops::Range<usize>,
    ) -> (DMatrix<f64>, DMatrix<f64>, Vec<f64>) {
        let (q, d) = (self.columns(), self.rows.d);
        let mut g = vec![0.0; q * q];
        let mut h = DMatrix::zeros(q, d);
        let mut yy = vec![0.0; d];
        let mut x = vec![0.0; q];
        for r in range {
            self.row(r, &mut x);
            for i in 0..q {
                let xi = x[i];
                for j in i..q {
                    g[i * q + j] += xi * x[j];
                }
            }
            for j in 0..d {
                let f = self.rows.f[r * d + j];
                yy[j] += f * f;
                for i in 0..q {
                    h[(i, j)] += x[i] * f;
                }
            }
        }
        let g = DMatrix::from_fn(q, q, |i, j| g[i.min(j) * q + i.max(j)]);
        (g, h, yy)
    }

    /// [`Design::cross_products`] of `folds` contiguous parts of the record.
    pub(super) fn folds(&self, folds: usize) -> Vec<(DMatrix<f64>, DMatrix<f64>, Vec<f64>)> {
        let n = self.rows.len();
        (0..folds)
            .into_par_iter()
            .map(|fold| self.cross_products(fold * n / folds..(fold + 1) * n / folds))
            .collect()
    }
}

pub(super) struct Fitted {
    pub(super) theta: DMatrix<f64>,
    pub(super) rss: f64,
    pub(super) press: f64,
    pub(super) gram: DMatrix<f64>,
}

/// Fit on everything and cross-validate over the folds.
pub(super) fn fit(design: &Design<'_>) -> Option<Fitted> {
    let parts = design.folds(FOLDS);
    let q = design.columns();
    let d = design.rows.d;
    let mut gram = DMatrix::zeros(q, q);
    let mut h = DMatrix::zeros(q, d);
    let mut yy = 0.0;
    for (g, hh, y) in &parts {
        gram += g;
        h += hh;
        yy += y.iter().sum::<f64>();
    }
    let theta = solve_scaled(&gram, &h)?;
    let rss =
        yy - 2.0 * (theta.transpose() * &h).trace() + (theta.transpose() * &gram * &theta).trace();
    let mut press = 0.0;
    for (g, hh, y) in &parts {
        let t = solve_scaled(&(&gram - g), &(&h - hh))?;
        press += y.iter().sum::<f64>() - 2.0 * (t.transpose() * hh).trace()
            + (t.transpose() * g * &t).trace();
    }
    Some(Fitted {
        theta,
        rss,
        press,
        gram,
    })
}

pub(super) fn total_ss(rows: &Rows) -> f64 {
    let d = rows.d;
    let n = rows.len() as f64;
    (0..d)
        .map(|j| {
            let mean = (0..rows.len()).map(|r| rows.f[r * d + j]).sum::<f64>() / n;
            (0..rows.len())
                .map(|r| (rows.f[r * d + j] - mean).powi(2))
                .sum::<f64>()
        })
        .sum()
}

/// Covariance of each output's coefficients by the delete-a-block jackknife
/// over 1 s blocks: robust to a coloured residual, and, unlike the plain
/// sandwich, not too small when the coefficients are many for the blocks.
pub(super) fn robust_covariances(design: &Design<'_>, f: &Fitted) -> Option<Vec<DMatrix<f64>>> {
    let (q, d, n) = (design.columns(), design.rows.d, design.rows.len());
    // the rows of one block are contiguous
    let mut ranges = Vec::new();
    let mut start = 0;
    for r in 1..=n {
        if r == n || design.rows.block[r] != design.rows.block[start] {
            ranges.push(start..r);
            start = r;
        }
    }
    let parts: Vec<(DMatrix<f64>, DMatrix<f64>)> = ranges
        .into_par_iter()
        .map(|range| {
            let (g, h, _) = design.cross_products(range);
            (g, h)
        })
        .collect();
    let blocks = parts.len();
    if blocks < 2 {
        return None;
    }
    let h_all = parts
        .iter()
        .fold(DMatrix::zeros(q, d), |acc, (_, h)| acc + h);
    let thetas: Vec<DMatrix<f64>> = parts
        .par_iter()
        .map(|(g, h)| solve_scaled(&(&f.gram - g), &(&h_all - h)))
        .collect::<Option<Vec<_>>>()?;
    let b = blocks as f64;
    Some(
        (0..d)
            .map(|j| {
                let mean: Vec<f64> = (0..q)
                    .map(|i| thetas.iter().map(|t| t[(i, j)]).sum::<f64>() / b)
                    .collect();
                let mut c = DMatrix::zeros(q, q);
                for t in &thetas {
                    for a in 0..q {
                        let da = t[(a, j)] - mean[a];
                        for e in 0..q {
                            c[(a, e)] += da * (t[(e, j)] - mean[e]);
                        }
                    }
                }
                c * ((b - 1.0) / b)
            })
            .collect(),
    )
}

/// Per grid point: residual and total sums of squares of the rows nearest it.
pub(super) fn region_residuals(
    design: &Design<'_>,
    f: &Fitted,
    region: &[usize],
    points: usize,
) -> Vec<(f64, f64)> {
    let (q, d) = (design.columns(), design.rows.d);
    let mut sums = vec![(0.0, 0.0, 0.0, 0usize); points * d];
    let mut x = vec![0.0; q];
    for (r, &g) in region.iter().enumerate() {
        design.row(r, &mut x);
        for j in 0..d {
            let y = design.rows.f[r * d + j];
            let pred: f64 = (0..q).map(|i| x[i] * f.theta[(i, j)]).sum();
            let s = &mut sums[g * d + j];
            s.0 += (y - pred).powi(2);
            s.1 += y;
            s.2 += y * y;
            s.3 += 1;
        }
    }
    (0..points)
        .map(|g| {
            (0..d).fold((0.0, 0.0), |(rss, tss), j| {
                let (e, s, ss, n) = sums[g * d + j];
                let centred = if n > 0 { ss - s * s / n as f64 } else { 0.0 };
                (rss + e, tss + centred)
            })
        })
        .collect()
}
