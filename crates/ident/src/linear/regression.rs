//! Seed 000 eq. (9)-(12) as one least-squares problem: the rows of [L | F] read window by window, reduced to triangles in blocks (QR), scaled, and solved; the errors-in-variables noise model of the regressors.

use super::standard_errors::autocorrelation_inflation;
use super::{column_names, FitQuality, FitTraces, Solved, CHUNK, MIN_CORRECTABLE, TRACE_POINTS};
use crate::lsq::{householder_in_place, merge};
use crate::prepare::{Plan, Prepared};
use limpid_core::{Error, Result};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
/// Solve the least-squares problem held in the augmented triangle `[R z; 0 s]`.
///
/// With a non-zero `noise` (per-sample noise covariance of the scaled
/// regressors), the bias-compensated estimate (R^T R - rows N)^-1 R^T z
/// removes the attenuation that position noise causes; the Gram matrix is
/// formed only here, on the well-conditioned scaled triangle.
pub(crate) fn solve_triangle(
    r_aug: &DMatrix<f64>,
    p: usize,
    n: usize,
    scales: &[f64],
    noise: &DMatrix<f64>,
    rows: f64,
) -> std::result::Result<Solved, String> {
    let r = r_aug.view((0, 0), (p, p)).into_owned();
    let z = r_aug.view((0, p), (p, n)).into_owned();
    let s_block = r_aug.view((p, p), (n, n)).into_owned();
    let Some(svd) = limpid_core::linalg::svd(r, true, true) else {
        return Err("the least-squares triangle is not finite or its SVD did not converge: the data overflow double precision".into());
    };
    let sv = &svd.singular_values;
    let (smax, smin) = (sv.max(), sv.min());
    // NaN-safe: a NaN singular value also counts as rank-deficient
    if smin.partial_cmp(&(smax * 1e-13)) != Some(std::cmp::Ordering::Greater) {
        return Err(format!(
            "the regressor is rank-deficient (condition number above 1e13): the motion does not excite all {p} parameters independently"
        ));
    }
    let (Some(u), Some(v_t)) = (svd.u.as_ref(), svd.v_t.as_ref()) else {
        return Err("SVD failed".into());
    };
    let inv_s = DMatrix::from_diagonal(&sv.map(|s| 1.0 / s));
    let r_pinv = v_t.transpose() * &inv_s * u.transpose();
    let mut theta_scaled = &r_pinv * &z;
    let mut cov_unit = &r_pinv * r_pinv.transpose();
    let partial_variance = (0..p).map(|j| 1.0 / (rows * cov_unit[(j, j)])).collect();
    if noise.iter().any(|v| *v != 0.0) {
        let r_owned = r_aug.view((0, 0), (p, p)).into_owned();
        let gram = r_owned.transpose() * &r_owned - noise * rows;
        if let Some(chol) = gram.cholesky() {
            theta_scaled = chol.solve(&(r_owned.transpose() * &z));
            cov_unit = chol.inverse();
        }
    }
    let mut theta = DMatrix::<f64>::zeros(p, n);
    for a in 0..n {
        for j in 0..p {
            theta[(j, a)] = theta_scaled[(j, a)] * scales[p + a] / scales[j];
        }
    }
    let rss = (0..n)
        .map(|a| s_block.column(a).norm_squared() * scales[p + a] * scales[p + a])
        .collect();
    Ok(Solved {
        theta,
        rss,
        cov_unit,
        partial_variance,
        condition_number: smax / smin,
    })
}

/// Where a fit reads its prepared rows: the concatenated columns of a
/// [`Prepared`], or a [`Plan`]'s windows computed as the QR reaches them (the
/// prepared signals of a long recording are then never held whole).
#[derive(Clone, Copy)]
pub(crate) enum Rows<'a> {
    Columns(&'a Prepared),
    Windows(&'a Plan<'a>),
}

impl<'a> Rows<'a> {
    pub(crate) fn meta(&self) -> &'a Prepared {
        match *self {
            Rows::Columns(data) => data,
            Rows::Windows(plan) => &plan.meta,
        }
    }

    pub(crate) fn len(&self) -> usize {
        match *self {
            Rows::Columns(data) => data.len(),
            Rows::Windows(plan) => plan.len(),
        }
    }

    /// Indices of the windows lying inside the sample range.
    pub(crate) fn windows_in(&self, range: &std::ops::Range<usize>) -> std::ops::Range<usize> {
        let w = &self.meta().windows;
        let first = w.partition_point(|w| w.samples.start < range.start);
        let end = w.partition_point(|w| w.samples.end <= range.end);
        first..end.max(first)
    }

    /// Row ranges of a block reduced one after the other: `CHUNK` rows, or
    /// whole windows up to about `CHUNK` rows (at least one window).
    pub(crate) fn chunks(&self, block: std::ops::Range<usize>) -> Vec<std::ops::Range<usize>> {
        let mut out = Vec::new();
        let mut lo = block.start;
        match *self {
            Rows::Columns(_) => {
                while lo < block.end {
                    let hi = (lo + CHUNK).min(block.end);
                    out.push(lo..hi);
                    lo = hi;
                }
            }
            Rows::Windows(plan) => {
                for w in &plan.meta.windows[self.windows_in(&block)] {
                    if w.samples.end - lo > CHUNK && w.samples.start > lo {
                        out.push(lo..w.samples.start);
                        lo = w.samples.start;
                    }
                }
                if lo < block.end {
                    out.push(lo..block.end);
                }
            }
        }
        out
    }

    /// Rows `range` of the unscaled `[L | 1 | F]` (columns acc, vel, disp per
    /// coordinate, the constant when `p > 3n`, forces) into the column-major
    /// `a` of leading dimension `ld`, from row `r0`. For `Windows`, `range`
    /// holds whole windows.
    pub(crate) fn fill(
        &self,
        range: std::ops::Range<usize>,
        a: &mut [f64],
        (ld, r0): (usize, usize),
        (n, p): (usize, usize),
    ) -> Result<()> {
        if p > 3 * n {
            a[3 * n * ld + r0..3 * n * ld + r0 + range.len()].fill(1.0);
        }
        // the kind-major order of Prepared: disp, vel, acc, force
        let order: Vec<usize> = (0..n)
            .map(|k| 2 * n + k)
            .chain((0..n).map(|k| n + k))
            .chain(0..n)
            .chain((0..n).map(|k| p + k))
            .collect();
        match *self {
            Rows::Columns(data) => {
                let sources = data.disp.iter().chain(&data.vel).chain(&data.acc);
                for (dest, src) in column_slices(a, ld, r0, range.len(), &order)
                    .into_iter()
                    .zip(sources.chain(&data.force))
                {
                    dest.copy_from_slice(&src[range.clone()]);
                }
            }
            Rows::Windows(plan) => {
                for i in self.windows_in(&range) {
                    let s = &plan.meta.windows[i].samples;
                    let mut dest =
                        column_slices(a, ld, r0 + s.start - range.start, s.len(), &order);
                    plan.fill_window(i, &mut dest)?;
                }
            }
        }
        Ok(())
    }
}

/// Rows `at..at + len` of the columns of the column-major `a` (leading
/// dimension `ld`), in the order `order`.
pub(crate) fn column_slices<'b>(
    a: &'b mut [f64],
    ld: usize,
    at: usize,
    len: usize,
    order: &[usize],
) -> Vec<&'b mut [f64]> {
    let mut columns: Vec<Option<&mut [f64]>> = a
        .chunks_mut(ld)
        .map(|c| Some(&mut c[at..at + len]))
        .collect();
    order
        .iter()
        .map(|&j| columns[j].take().unwrap_or_default())
        .collect()
}

/// One jackknife block reduced: its unscaled triangle, column sums, and
/// each force's smallest and largest value.
pub(crate) struct BlockSummary {
    pub(crate) triangle: DMatrix<f64>,
    pub(crate) sums: Vec<f64>,
    pub(crate) force_range: Vec<(f64, f64)>,
}

/// Tall-skinny QR of the unscaled `[L | 1 | F]`: each block reduced to its
/// q x q triangle chunk by chunk (the triangle so far stacked on the next
/// chunk's rows), blocks in parallel, one buffer per block.
pub(crate) fn reduce_blocks(
    rows: Rows<'_>,
    blocks: &[std::ops::Range<usize>],
    (n, p, q): (usize, usize, usize),
) -> Result<Vec<BlockSummary>> {
    blocks
        .par_iter()
        .map(|block| {
            let chunks = rows.chunks(block.clone());
            let longest = chunks.iter().map(|c| c.len()).max().unwrap_or(0);
            let mut buffer = vec![0.0; (longest + q) * q];
            let mut triangle: Option<DMatrix<f64>> = None;
            let mut sums = vec![0.0; q];
            let mut force_range = vec![(f64::INFINITY, f64::NEG_INFINITY); n];
            for chunk in chunks {
                let r0 = triangle.as_ref().map_or(0, |_| q);
                let ld = chunk.len() + r0;
                let a = &mut buffer[..ld * q];
                rows.fill(chunk, a, (ld, r0), (n, p))?;
                column_sums_and_ranges(a, (ld, r0), p, &mut sums, &mut force_range);
                if let Some(t) = &triangle {
                    for (j, column) in a.chunks_mut(ld).enumerate() {
                        for i in 0..q {
                            column[i] = t[(i, j)];
                        }
                    }
                }
                if ld < q {
                    // fewer rows than columns: pad with zero rows
                    let mut padded = DMatrix::<f64>::zeros(q, q);
                    for (j, column) in a.chunks(ld).enumerate() {
                        padded.view_mut((0, j), (ld, 1)).copy_from_slice(column);
                    }
                    triangle = Some(crate::lsq::triangle(padded, q));
                    continue;
                }
                householder_in_place(a, ld, q);
                triangle = Some(DMatrix::from_fn(q, q, |i, j| {
                    if i <= j {
                        a[j * ld + i]
                    } else {
                        0.0
                    }
                }));
            }
            Ok(BlockSummary {
                triangle: triangle.unwrap_or_else(|| DMatrix::zeros(q, q)),
                sums,
                force_range,
            })
        })
        .collect()
}

/// Add each column's sum over rows `r0..ld` of the column-major `a` to
/// `sums`, and widen the ranges of the columns from `p` on (the forces).
/// Four columns at a time, in registers: each column's sum is the same left
/// fold from -0.0 as `iter().sum()` and each range the same `min`/`max`
/// sequence (bit-identical), but four chains of dependent additions run side
/// by side (one column's chain waited 4 cycles an addition: about 7 % of the
/// 60-minute estimate's time, issue 82).
fn column_sums_and_ranges(
    a: &[f64],
    (ld, r0): (usize, usize),
    p: usize,
    sums: &mut [f64],
    force_range: &mut [(f64, f64)],
) {
    let columns: Vec<&[f64]> = a.chunks(ld).map(|c| &c[r0..ld]).collect();
    for (group, totals) in columns.chunks(4).zip(sums.chunks_mut(4)) {
        let found = match group {
            [a, b, c, d] => fold_columns([a, b, c, d], -0.0, |s, v| s + v).to_vec(),
            [a, b, c] => fold_columns([a, b, c], -0.0, |s, v| s + v).to_vec(),
            [a, b] => fold_columns([a, b], -0.0, |s, v| s + v).to_vec(),
            _ => group.iter().map(|c| c.iter().sum::<f64>()).collect(),
        };
        for (total, s) in totals.iter_mut().zip(found) {
            *total += s;
        }
    }
    for (column, range) in columns[p..].iter().zip(force_range.iter_mut()) {
        let [lo] = fold_columns([column], range.0, f64::min);
        let [hi] = fold_columns([column], range.1, f64::max);
        *range = (lo, hi);
    }
}

/// `G` equally long columns folded side by side from `init`, row by row.
fn fold_columns<const G: usize>(
    columns: [&[f64]; G],
    init: f64,
    step: impl Fn(f64, f64) -> f64,
) -> [f64; G] {
    let rows = columns[0].len();
    let columns = columns.map(|c| &c[..rows]);
    let mut acc = [init; G];
    // row i of every column: the G chains advance together
    #[allow(clippy::needless_range_loop)]
    for i in 0..rows {
        for g in 0..G {
            acc[g] = step(acc[g], columns[g][i]);
        }
    }
    acc
}

/// The scaled regression problem of one fit: the RMS scales of the columns
/// of `[L | F]`, and the noise model of the regressors.
pub(crate) struct Regression {
    /// Coordinates.
    pub(crate) n: usize,
    /// Samples.
    pub(crate) m: usize,
    /// Parameters per force component (3n, plus the constant).
    pub(crate) p: usize,
    /// Columns of the augmented matrix `[L | F]`.
    pub(crate) q: usize,
    /// RMS of each column of `[L | F]` (1 for the constant).
    pub(crate) scales: Vec<f64>,
    /// Per coordinate: signal share of its acceleration, velocity and displacement regressors.
    pub(crate) reliability: Vec<[f64; 3]>,
    /// Per-sample noise covariance of the scaled regressors (errors-in-variables).
    pub(crate) noise: DMatrix<f64>,
    /// Triangle of all rows, unscaled (`R^T R = A^T A`).
    pub(crate) total: DMatrix<f64>,
    /// Column sums of the unscaled `[L | 1 | F]`.
    pub(crate) sums: Vec<f64>,
    /// Per force: every sample has the same value.
    pub(crate) constant_force: Vec<bool>,
}

impl Regression {
    /// From the reduced blocks: the scales are the column norms of the
    /// merged triangle (a QR keeps column norms), so no pass over the data
    /// is spent on them. Returns the blocks' triangles scaled to unit RMS columns.
    pub(crate) fn new(
        data: &Prepared,
        m: usize,
        with_const: bool,
        blocks: &[BlockSummary],
        numerical: impl Fn(String) -> Error,
    ) -> Result<(Self, Vec<DMatrix<f64>>)> {
        let n = data.dims();
        let p = 3 * n + usize::from(with_const);
        let q = p + n;
        let total = merge(blocks.iter().map(|b| &b.triangle), q);
        let scales: Vec<f64> = (0..q)
            .map(|j| match j {
                j if j < 3 * n || j >= p => total.column(j).norm() / (m as f64).sqrt(),
                _ => 1.0,
            })
            .collect();
        let names = column_names(&data.coordinates, with_const);
        if let Some(j) = (0..p).find(|&j| scales[j] == 0.0) {
            return Err(numerical(format!(
                "regressor column {} is zero in every sample: that coordinate never moves, so its parameters cannot be estimated",
                names[j]
            )));
        }
        let unscale: Vec<f64> = scales
            .iter()
            .map(|s| if *s > 0.0 { 1.0 / s } else { 1.0 })
            .collect();
        let scaled = blocks
            .iter()
            .map(|b| {
                let mut t = b.triangle.clone();
                for (j, mut column) in t.column_iter_mut().enumerate() {
                    column *= unscale[j];
                }
                t
            })
            .collect();
        let sums = (0..q)
            .map(|j| blocks.iter().map(|b| b.sums[j]).sum())
            .collect();
        let constant_force = (0..n)
            .map(|a| {
                let (lo, hi) = blocks
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |r, b| {
                        (r.0.min(b.force_range[a].0), r.1.max(b.force_range[a].1))
                    });
                lo == hi
            })
            .collect();
        let reliability: Vec<[f64; 3]> = (0..n)
            .map(|k| {
                let nv = data.regressor_noise_var.get(k).copied().unwrap_or([0.0; 4]);
                let rel =
                    |col: usize, noise: f64| (1.0 - noise / (scales[col] * scales[col])).max(0.0);
                [rel(k, nv[2]), rel(n + k, nv[1]), rel(2 * n + k, nv[0])]
            })
            .collect();
        // errors-in-variables: only the columns reliable enough to correct (bias-compensated LS)
        let mut noise = DMatrix::<f64>::zeros(p, p);
        let correctable = |k: usize, kind: usize| reliability[k][kind] >= MIN_CORRECTABLE;
        for k in 0..n {
            let nv = data.regressor_noise_var.get(k).copied().unwrap_or([0.0; 4]);
            let (ia, iv, ix) = (k, n + k, 2 * n + k);
            if correctable(k, 0) {
                noise[(ia, ia)] = nv[2] / (scales[ia] * scales[ia]);
            }
            if correctable(k, 1) {
                noise[(iv, iv)] = nv[1] / (scales[iv] * scales[iv]);
            }
            if correctable(k, 2) {
                noise[(ix, ix)] = nv[0] / (scales[ix] * scales[ix]);
            }
            if correctable(k, 0) && correctable(k, 2) {
                let c = nv[3] / (scales[ia] * scales[ix]);
                noise[(ia, ix)] = c;
                noise[(ix, ia)] = c;
            }
        }
        let reg = Self {
            n,
            m,
            p,
            q,
            scales,
            reliability,
            noise,
            total,
            sums,
            constant_force,
        };
        Ok((reg, scaled))
    }

    /// Solve from merged (scaled) triangles holding `rows` samples.
    pub(crate) fn solve<'t>(
        &self,
        triangles: impl Iterator<Item = &'t DMatrix<f64>>,
        rows: usize,
    ) -> std::result::Result<Solved, String> {
        let r_aug = merge(triangles, self.q);
        solve_triangle(
            &r_aug,
            self.p,
            self.n,
            &self.scales,
            &self.noise,
            rows as f64,
        )
    }

    /// r, VAF and RMSE per force component from the unscaled triangle and
    /// column sums (every sum of products of `f` and `f̂ = L θ` is a
    /// quadratic form of `R^T R`; the residual norm is `|R w|`, exact without
    /// cancellation), traces of the first windows, and (when `inflate`) the
    /// autocorrelation inflation of the residuals, which reads every row again.
    pub(crate) fn fit_quality(
        &self,
        rows: Rows<'_>,
        theta: &DMatrix<f64>,
        inflate: bool,
    ) -> Result<(FitQuality, Vec<f64>)> {
        let (n, m, p, q) = (self.n, self.m, self.p, self.q);
        let data = rows.meta();
        let mf = m as f64;
        let mut fit = FitQuality {
            r: Vec::with_capacity(n),
            vaf: Vec::with_capacity(n),
            rmse: Vec::with_capacity(n),
            traces: FitTraces {
                time: Vec::new(),
                measured: Vec::with_capacity(n),
                predicted: Vec::with_capacity(n),
            },
        };
        for a in 0..n {
            let mut w = DVector::<f64>::zeros(q);
            for j in 0..p {
                w[j] = theta[(j, a)];
            }
            let predicted = &self.total * &w;
            let measured = self.total.column(p + a).into_owned();
            let residual = &measured - &predicted;
            let sum_f = self.sums[p + a];
            let sum_h: f64 = (0..p).map(|j| self.sums[j] * w[j]).sum();
            let (ff, hh) = (measured.norm_squared(), predicted.norm_squared());
            // centred sums; a rounding residue of a constant signal counts as zero
            let centred = |s: f64, sum: f64| {
                let c = s - sum * sum / mf;
                if c <= 1e-12 * s {
                    0.0
                } else {
                    c
                }
            };
            let sff = if self.constant_force[a] {
                0.0
            } else {
                centred(ff, sum_f)
            };
            let shh = centred(hh, sum_h);
            let sfh = measured.dot(&predicted) - sum_f * sum_h / mf;
            let see = residual.norm_squared();
            let var_e = (see / mf - ((sum_f - sum_h) / mf).powi(2)).max(0.0);
            fit.r.push(if sff > 0.0 && shh > 0.0 {
                (sfh / (sff * shh).sqrt()).clamp(-1.0, 1.0)
            } else {
                0.0
            });
            fit.vaf.push(if sff > 0.0 {
                100.0 * (1.0 - var_e / (sff / mf))
            } else {
                0.0
            });
            fit.rmse.push((see / mf).sqrt());
        }
        // the first (up to) three windows, decimated to TRACE_POINTS
        let trace_len = data
            .windows
            .get(data.windows.len().min(3).saturating_sub(1))
            .map_or(m, |w| w.samples.end)
            .min(m);
        let read_len = if inflate { m } else { trace_len };
        let mut a = vec![0.0; read_len * q];
        rows.fill(0..read_len, &mut a, (read_len, 0), (n, p))?;
        let predict = |i: usize, f: usize| -> f64 {
            (0..p).map(|j| theta[(j, f)] * a[j * read_len + i]).sum()
        };
        let trace_step = trace_len.div_ceil(TRACE_POINTS).max(1);
        let trace_idx: Vec<usize> = (0..trace_len).step_by(trace_step).collect();
        fit.traces.time = trace_idx.iter().map(|&i| i as f64 / data.fs).collect();
        for f in 0..n {
            let column = &a[(p + f) * read_len..(p + f + 1) * read_len];
            fit.traces
                .measured
                .push(trace_idx.iter().map(|&i| column[i]).collect());
            fit.traces
                .predicted
                .push(trace_idx.iter().map(|&i| predict(i, f)).collect());
        }
        let mut inflation = Vec::new();
        if inflate {
            let lags = data.correlation_lags().min(m / 4).max(1);
            for f in 0..n {
                let column = &a[(p + f) * read_len..(p + f + 1) * read_len];
                let resid: Vec<f64> = (0..m).map(|i| column[i] - predict(i, f)).collect();
                inflation.push(autocorrelation_inflation(&resid, &data.windows, lags));
            }
        }
        Ok((fit, inflation))
    }

    /// Delete-one-block jackknife standard errors from the per-block triangles
    /// (robust to slow force drift, which correlates residuals over whole trials).
    pub(crate) fn jackknife(
        &self,
        triangles: &[DMatrix<f64>],
        block_rows: &[usize],
    ) -> DMatrix<f64> {
        let (p, n) = (self.p, self.n);
        let replicates: Vec<DMatrix<f64>> = crate::lsq::leave_one_out(triangles, self.q)
            .par_iter()
            .zip(block_rows)
            .filter_map(|(t, rows)| {
                self.solve(std::iter::once(t), self.m - rows)
                    .ok()
                    .map(|s| s.theta)
            })
            .collect();
        let g_ok = replicates.len() as f64;
        let mean = replicates
            .iter()
            .fold(DMatrix::<f64>::zeros(p, n), |acc, t| acc + t)
            / g_ok;
        let var = replicates
            .iter()
            .fold(DMatrix::<f64>::zeros(p, n), |acc, t| {
                acc + (t - &mean).map(|v| v * v)
            })
            * ((g_ok - 1.0) / g_ok);
        let widen = crate::lsq::small_sample_factors(triangles, p);
        DMatrix::from_fn(p, n, |j, f| var[(j, f)].sqrt() * widen[j])
    }

    /// Analytic standard errors: residual variance, inflated by its
    /// autocorrelation, times the diagonal of `(L^T L)^-1`.
    pub(crate) fn analytic_se(&self, solved: &Solved, dof: f64, inflation: &[f64]) -> DMatrix<f64> {
        let (p, n) = (self.p, self.n);
        let mut se = DMatrix::<f64>::zeros(p, n);
        for a in 0..n {
            let sigma2 = solved.rss[a] / dof * inflation[a];
            for j in 0..p {
                se[(j, a)] = (sigma2 * solved.cov_unit[(j, j)]).sqrt() / self.scales[j];
            }
        }
        se
    }
}
