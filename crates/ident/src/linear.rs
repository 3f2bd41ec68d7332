//! Linear impedance least squares: `M x'' + B x' + K (x - x_eq) = f` in n
//! coordinates (seed 000 eq. (2)-(8); seed 001 eq. (2)-(10)).
//!
//! Seed 000 stacks the 27 parameters of `[M B K]` into one vector and a
//! block-diagonal regressor `Y_a` (3m x 27); seed 001 writes the same problem
//! as `P = F Y^+` with the 3 x 9 matrix `P = [M B K]`. Both are the same
//! least-squares problem: each row of `P` is fitted to one force component with
//! the shared regressor `L = [x''; x'; x - x_ref]` (eq. (7)). We solve it in
//! that form — one regressor with n right-hand sides — which needs 1/n of the
//! memory and flops of the block-diagonal form. With `equilibrium` a constant
//! column is added; its coefficient `c = -K (x_eq - x_ref)` gives
//! `x_eq = x_ref - K^{-1} c`.
//!
//! Numerics: the augmented matrix `[L | F]` is reduced by a tall-skinny
//! Householder QR (blocks reduced in parallel, never normal equations; from
//! a [`Plan`] window by window, without holding the prepared signals), its
//! triangle's columns are scaled to unit RMS (a QR keeps column norms), and
//! the small triangular factor is solved by SVD, which also gives the
//! condition number of the scaled regressor. Standard errors come from the residual variance of each force
//! component times `(L^T L)^{-1}`, inflated by the residuals' autocorrelation
//! over the low-pass correlation length (Bartlett-weighted sum), because
//! filtered residuals are not white. This inflation is exact when the
//! regressors change slowly over that length, and conservative otherwise.

use std::fmt::Write as _;

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::lsq::{householder_in_place, merge};
use crate::prepare::{Plan, Prepared};
use limpid_core::criteria::MatrixKind;
use limpid_core::{Error, Result, Warning, WarningCode};

/// Settings of the linear estimator.
///
/// | Name | Default | Purpose | Range |
/// |---|---|---|---|
/// | `equilibrium` | true | fit a constant, report `x_eq` (seed 000); false: 9-column form of seed 001 | |
/// | `identifiable_ratio` | 2 | a diagonal element counts as identified when `|value| >= ratio * SE` | > 0 |
#[derive(Debug, Clone)]
pub struct LinearParams {
    /// Fit a constant and report the equilibrium x_eq (seed 000); false: the 9-column form of seed 001.
    pub equilibrium: bool,
    /// A diagonal element counts as identified when |value| >= ratio x SE.
    pub identifiable_ratio: f64,
}

impl Default for LinearParams {
    fn default() -> Self {
        LinearParams {
            equilibrium: true,
            identifiable_ratio: 2.0,
        }
    }
}

pub use limpid_core::Matrix;

/// Goodness of fit per force component.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct FitQuality {
    /// Correlation coefficient of measured and predicted force.
    pub r: Vec<f64>,
    /// Variance accounted for, percent: 100 (1 - var(f - f̂) / var(f)).
    pub vaf: Vec<f64>,
    /// Root-mean-square residual (N or N m).
    pub rmse: Vec<f64>,
    /// Measured and predicted force over the first windows, for plots.
    pub traces: FitTraces,
}

/// Measured against predicted force (after preparation: offsets removed,
/// filtered) over the first windows, at most [`TRACE_POINTS`] points per
/// coordinate (every k-th sample).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct FitTraces {
    /// Time (s) along the concatenated windows.
    pub time: Vec<f64>,
    /// `[coordinate][point]`.
    pub measured: Vec<Vec<f64>>,
    /// Predicted force, `[coordinate][point]`.
    pub predicted: Vec<Vec<f64>>,
}

/// Points kept per coordinate in [`FitTraces`].
pub const TRACE_POINTS: usize = 1500;

/// Whether each matrix is identified from the data (every diagonal element >= ratio x SE).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Identifiable {
    /// Every diagonal element of M at least `identifiable_ratio` SE from zero.
    pub inertia: bool,
    /// The same for B.
    pub damping: bool,
    /// The same for K.
    pub stiffness: bool,
}

/// The linear estimate with its quality.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct LinearEstimate {
    /// Coordinate names, in the order of the matrices' rows and columns.
    pub coordinates: Vec<String>,
    /// M (kg, or kg m^2 for angles), row = force component, column = coordinate.
    pub inertia: Matrix,
    /// B (N s/m, N m s/rad).
    pub damping: Matrix,
    /// K (N/m, N m/rad).
    pub stiffness: Matrix,
    /// Equilibrium position (absolute coordinates), when fitted and K is invertible.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub equilibrium: Option<Vec<f64>>,
    /// Standard errors, same layout as the estimates.
    pub standard_errors: StandardErrors,
    /// Goodness of fit per force component.
    pub fit: FitQuality,
    /// Condition number of the column-scaled regressor.
    pub condition_number: f64,
    /// Which matrices the data identify.
    pub identifiable: Identifiable,
    /// Samples used.
    pub samples: usize,
    /// Parameters fitted (n x columns of the regressor).
    pub parameters: usize,
    /// Autocorrelation inflation of the residual variance, per force
    /// component, where the analytic standard errors were used (else null).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub variance_inflation: Option<Vec<f64>>,
    /// Share of each regressor's variance that is signal, not propagated
    /// position noise (`[acceleration, velocity, displacement]` per
    /// coordinate). Below [`MIN_RELIABILITY`] the matching parameters are
    /// attenuated towards zero (errors in variables) and are reported as not
    /// identifiable.
    pub regressor_reliability: Vec<[f64; 3]>,
    /// How the standard errors were obtained.
    pub standard_error_method: String,
    /// What the reader should know about this estimate.
    pub warnings: Vec<Warning>,
}

/// Standard errors of the estimate.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct StandardErrors {
    /// Of M.
    pub inertia: Matrix,
    /// Of B.
    pub damping: Matrix,
    /// Of K.
    pub stiffness: Matrix,
    /// Of the constant term (N), when fitted.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub constant: Option<Vec<f64>>,
}

const CHUNK: usize = 1024;
/// Smallest regressor reliability at which a parameter counts as identifiable.
pub const MIN_RELIABILITY: f64 = 0.8;
/// Smallest regressor reliability at which its noise bias is compensated;
/// below it the compensation would amplify noise more than it removes bias.
pub const MIN_CORRECTABLE: f64 = 0.5;
/// Least standard error of each damping and inertia element, as a share of
/// its magnitude: the zero-phase low-pass and the finite differences bias B
/// and M by a shared amount that no resampling of the trials can see
/// (noise-free seed 001 protocol at the 30 Hz default: B -0.75 %, M -0.4 %;
/// 1.8 % for B at 20 Hz). `limpid calibrate` measured the coverage with it.
pub const DERIVATIVE_ERROR_FLOOR: f64 = 0.01;
/// Prior standard deviation of an end-point inertia the data cannot identify
/// (kg, diagonal elements; off-diagonal elements get a fifth of it). The human
/// arm's end-point inertia lies between about 0.1 and 2 kg along its principal
/// axes (seed 000 Table I: 0.14-0.75 kg; seed 001's subjects 1.4-2 kg).
pub const UNIDENTIFIED_INERTIA_SD_KG: f64 = 0.5;
/// The same for joint coordinates (kg m^2; upper arm and forearm about a joint: 0.02-0.3).
pub const UNIDENTIFIED_INERTIA_SD_KG_M2: f64 = 0.05;
/// Prior mean of a diagonal end-point inertia the data cannot identify (kg):
/// the middle of the 0.1-2 kg range above, so that ±2 prior s.d. span it.
pub const UNIDENTIFIED_INERTIA_MEAN_KG: f64 = 1.0;
/// The same for joint coordinates (kg m^2).
pub const UNIDENTIFIED_INERTIA_MEAN_KG_M2: f64 = 0.1;
/// Share of the diagonal prior given to off-diagonal inertia elements.
const OFF_DIAGONAL_INERTIA_SHARE: f64 = 0.2;
/// Fewest blocks for a jackknife standard error.
const MIN_JACKKNIFE_BLOCKS: usize = 8;
/// Most jackknife groups; more trials are grouped into consecutive runs.
const MAX_JACKKNIFE_GROUPS: usize = 64;
/// Contiguous pieces used as jackknife blocks when the trials are too few.
const CONTIGUOUS_BLOCKS: usize = 20;

pub(crate) struct Solved {
    pub(crate) theta: DMatrix<f64>,
    pub(crate) rss: Vec<f64>,
    pub(crate) cov_unit: DMatrix<f64>,
    /// Per-sample variance of each scaled column's part that the other columns
    /// do not explain (`1 / (rows [(R^T R)^-1]_jj)`): what identifies its parameter.
    pub(crate) partial_variance: Vec<f64>,
    pub(crate) condition_number: f64,
}

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
enum Rows<'a> {
    Columns(&'a Prepared),
    Windows(&'a Plan<'a>),
}

impl<'a> Rows<'a> {
    fn meta(&self) -> &'a Prepared {
        match *self {
            Rows::Columns(data) => data,
            Rows::Windows(plan) => &plan.meta,
        }
    }

    fn len(&self) -> usize {
        match *self {
            Rows::Columns(data) => data.len(),
            Rows::Windows(plan) => plan.len(),
        }
    }

    /// Indices of the windows lying inside the sample range.
    fn windows_in(&self, range: &std::ops::Range<usize>) -> std::ops::Range<usize> {
        let w = &self.meta().windows;
        let first = w.partition_point(|w| w.samples.start < range.start);
        let end = w.partition_point(|w| w.samples.end <= range.end);
        first..end.max(first)
    }

    /// Row ranges of a block reduced one after the other: `CHUNK` rows, or
    /// whole windows up to about `CHUNK` rows (at least one window).
    fn chunks(&self, block: std::ops::Range<usize>) -> Vec<std::ops::Range<usize>> {
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
    fn fill(
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
fn column_slices<'b>(
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
struct BlockSummary {
    triangle: DMatrix<f64>,
    sums: Vec<f64>,
    force_range: Vec<(f64, f64)>,
}

/// Tall-skinny QR of the unscaled `[L | 1 | F]`: each block reduced to its
/// q x q triangle chunk by chunk (the triangle so far stacked on the next
/// chunk's rows), blocks in parallel, one buffer per block.
fn reduce_blocks(
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
                for (j, column) in a.chunks(ld).enumerate() {
                    sums[j] += column[r0..].iter().sum::<f64>();
                    if j >= p {
                        let range = &mut force_range[j - p];
                        for v in &column[r0..] {
                            range.0 = range.0.min(*v);
                            range.1 = range.1.max(*v);
                        }
                    }
                }
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

/// The scaled regression problem of one fit: the RMS scales of the columns
/// of `[L | F]`, and the noise model of the regressors.
struct Regression {
    /// Coordinates.
    n: usize,
    /// Samples.
    m: usize,
    /// Parameters per force component (3n, plus the constant).
    p: usize,
    /// Columns of the augmented matrix `[L | F]`.
    q: usize,
    /// RMS of each column of `[L | F]` (1 for the constant).
    scales: Vec<f64>,
    /// Per coordinate: signal share of its acceleration, velocity and displacement regressors.
    reliability: Vec<[f64; 3]>,
    /// Per-sample noise covariance of the scaled regressors (errors-in-variables).
    noise: DMatrix<f64>,
    /// Triangle of all rows, unscaled (`R^T R = A^T A`).
    total: DMatrix<f64>,
    /// Column sums of the unscaled `[L | 1 | F]`.
    sums: Vec<f64>,
    /// Per force: every sample has the same value.
    constant_force: Vec<bool>,
}

impl Regression {
    /// From the reduced blocks: the scales are the column norms of the
    /// merged triangle (a QR keeps column norms), so no pass over the data
    /// is spent on them. Returns the blocks' triangles scaled to unit RMS columns.
    fn new(
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
    fn solve<'t>(
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
    fn fit_quality(
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
    fn jackknife(&self, triangles: &[DMatrix<f64>], block_rows: &[usize]) -> DMatrix<f64> {
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
        var.map(f64::sqrt)
    }

    /// Analytic standard errors: residual variance, inflated by its
    /// autocorrelation, times the diagonal of `(L^T L)^-1`.
    fn analytic_se(&self, solved: &Solved, dof: f64, inflation: &[f64]) -> DMatrix<f64> {
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

/// Sensitivity of every parameter row to the inertia columns, unscaled:
/// `dθ_j/dM_k = C_jM (C_MM)^-1` with `C` the unit covariance `(L^T L)^-1`
/// (partitioned inverse: minus the regression of the acceleration columns on
/// the others). Rows 0..n (the inertia itself) are left zero. None when the
/// inertia block of `C` is singular.
fn inertia_sensitivity(reg: &Regression, solved: &Solved) -> Option<DMatrix<f64>> {
    let (n, p) = (reg.n, reg.p);
    let c = &solved.cov_unit;
    let c_mm_inv = c.view((0, 0), (n, n)).into_owned().try_inverse()?;
    let mut sens = DMatrix::<f64>::zeros(p, n);
    for j in n..p {
        for k in 0..n {
            let scaled: f64 = (0..n).map(|l| c[(j, l)] * c_mm_inv[(l, k)]).sum();
            sens[(j, k)] = scaled * reg.scales[k] / reg.scales[j];
        }
    }
    Some(sens)
}

/// Prior (mean, s.d.) of an inertia element the data cannot identify, for
/// coordinate `k` (end-point kg or joint kg m^2).
fn inertia_prior(coords: &[String], k: usize) -> (f64, f64) {
    if matches!(coords[k].as_str(), "x" | "y" | "z") {
        (UNIDENTIFIED_INERTIA_MEAN_KG, UNIDENTIFIED_INERTIA_SD_KG)
    } else {
        (
            UNIDENTIFIED_INERTIA_MEAN_KG_M2,
            UNIDENTIFIED_INERTIA_SD_KG_M2,
        )
    }
}

/// B, K and the constant conditional on the prior mean inertia instead of an
/// attenuated estimate, for every acceleration column too noisy to be
/// bias-compensated (reliability below [`MIN_CORRECTABLE`]): such a column's
/// M comes out near zero whatever the truth (`limpid calibrate`: 0.02 kg for a
/// true 1.5 kg on seed 000's cubic ramps), and since the ramps tie
/// acceleration to displacement (`Σ a x = -Σ v²`), K absorbed `-M Σv²/Σx²`:
/// cubic and trapezoid K diagonals were 1.2 SE low on average (coverage 89 %).
/// Returns the shifted columns' names.
fn condition_on_prior_inertia(
    theta: &mut DMatrix<f64>,
    sens: &DMatrix<f64>,
    reliability: &[[f64; 3]],
    coords: &[String],
) -> Vec<String> {
    let n = coords.len();
    let mut shifted = Vec::new();
    for k in 0..n {
        if reliability[k][0] >= MIN_CORRECTABLE {
            continue;
        }
        let (mean, _) = inertia_prior(coords, k);
        for a in 0..n {
            let target = if a == k { mean } else { 0.0 };
            let delta = target - theta[(k, a)];
            for j in n..theta.nrows() {
                theta[(j, a)] += sens[(j, k)] * delta;
            }
        }
        shifted.push(coords[k].clone());
    }
    shifted
}

/// The variance a not-identified inertia adds to the damping and stiffness
/// estimates, per parameter row (p) and force component (n).
///
/// The fit reports B and K conditional on an M (its own, or the prior mean,
/// see [`condition_on_prior_inertia`]); when M is not identified, a wrong M
/// moves them along `sens` ([`inertia_sensitivity`]). (A pure sinusoid makes
/// acceleration proportional to displacement, so K absorbs `-ω² M` exactly;
/// block jackknife standard errors cannot see such a bias, every trial
/// sharing it.) Applied when less than [`MIN_RELIABILITY`] of some
/// acceleration column's own part (what the other columns do not explain) is
/// signal rather than propagated position noise; each M element then gets the
/// prior s.d. of [`UNIDENTIFIED_INERTIA_SD_KG`].
fn inertia_confounding(sens: &DMatrix<f64>, coords: &[String]) -> DMatrix<f64> {
    let (p, n) = (sens.nrows(), sens.ncols());
    let mut out = DMatrix::<f64>::zeros(p, n);
    let sd = |k: usize| inertia_prior(coords, k).1;
    for j in n..p.min(3 * n) {
        for a in 0..n {
            out[(j, a)] = (0..n)
                .map(|k| {
                    let s = (sd(a) * sd(k)).sqrt()
                        * if k == a {
                            1.0
                        } else {
                            OFF_DIAGONAL_INERTIA_SHARE
                        };
                    (sens[(j, k)] * s).powi(2)
                })
                .sum();
        }
    }
    out
}

/// Jackknife groups: the windows (contiguous runs of them when there are
/// more than MAX_JACKKNIFE_GROUPS), else contiguous pieces of the data.
fn jackknife_blocks(
    w: &[crate::prepare::PreparedWindow],
    m: usize,
    q: usize,
) -> Vec<std::ops::Range<usize>> {
    if w.len() >= MIN_JACKKNIFE_BLOCKS {
        let g = w.len().min(MAX_JACKKNIFE_GROUPS);
        (0..g)
            .map(|b| w[b * w.len() / g].samples.start..w[(b + 1) * w.len() / g - 1].samples.end)
            .collect()
    } else {
        let g = CONTIGUOUS_BLOCKS.min(m / (4 * q)).max(1);
        (0..g).map(|b| b * m / g..(b + 1) * m / g).collect()
    }
}

/// `x_eq = x_ref - K^-1 c` (seed 000), or None with a warning when K is singular.
fn equilibrium_position(
    stiffness: &Matrix,
    constant: DVector<f64>,
    reference: &[f64],
    warnings: &mut Vec<Warning>,
) -> Option<Vec<f64>> {
    let k = stiffness.0.clone();
    match k.clone().lu().solve(&constant) {
        Some(kc)
            if limpid_core::linalg::singular_values(k.clone())
                .is_some_and(|s| s.min() > 1e-12 * k.norm()) =>
        {
            Some(
                reference
                    .iter()
                    .zip(kc.iter())
                    .map(|(r, v)| r - v)
                    .collect(),
            )
        }
        _ => {
            warnings.push(Warning::new(
                WarningCode::EquilibriumSingular,
                "equilibrium not reported: the stiffness matrix is singular",
            ));
            None
        }
    }
}

/// Fit the linear model to prepared data.
pub fn fit_linear(data: &Prepared, params: &LinearParams) -> Result<LinearEstimate> {
    fit_rows(Rows::Columns(data), params)
}

/// Fit the linear model window by window from a [`Plan`]: each window's
/// signals are computed, reduced into its jackknife block's QR triangle and
/// dropped, so a long recording's prepared signals are never held whole
/// (issue 16). The same estimate as [`fit_linear`] of the materialised plan
/// (to rounding). With fewer than 8 windows (the fewest jackknife blocks) the
/// blocks are contiguous pieces that cut through windows: the plan is then
/// materialised first.
pub fn fit_linear_plan(plan: &Plan<'_>, params: &LinearParams) -> Result<LinearEstimate> {
    if plan.meta.windows.len() < MIN_JACKKNIFE_BLOCKS {
        return fit_linear(&plan.materialise()?, params);
    }
    fit_rows(Rows::Windows(plan), params)
}

fn fit_rows(rows: Rows<'_>, params: &LinearParams) -> Result<LinearEstimate> {
    let data = rows.meta();
    let n = data.dims();
    let m = rows.len();
    // a constant term: the equilibrium (seed 000), or the unknown offset of continuous data;
    // demeaned windows already had their per-trial constants removed
    let with_const = !data.demeaned && (params.equilibrium || data.continuous);
    let absorbed = if data.demeaned { data.windows.len() } else { 0 };
    let p = 3 * n + usize::from(with_const);
    let q = p + n;
    let numerical = |message: String| Error::Numerical {
        path: data.path.clone(),
        message,
    };
    if m < 2 * (p + absorbed) {
        return Err(Error::TooFewSamples {
            path: data.path.clone(),
            what: format!("a {p}-parameter linear fit"),
            needed: 2 * (p + absorbed),
            found: m,
        });
    }
    let blocks = jackknife_blocks(&data.windows, m, q);
    let summaries = reduce_blocks(rows, &blocks, (n, p, q))?;
    let (reg, triangles) = Regression::new(data, m, with_const, &summaries, numerical)?;
    drop(summaries);
    let solved = reg.solve(triangles.iter(), m).map_err(numerical)?;
    let theta = &solved.theta;
    let condition_number = solved.condition_number;
    let g = blocks.len();
    let use_jackknife = g >= MIN_JACKKNIFE_BLOCKS;
    let (fit, inflation) = reg.fit_quality(rows, theta, !use_jackknife)?;
    let (mut se, mut se_method) = if use_jackknife {
        let block_rows: Vec<usize> = blocks.iter().map(|b| b.len()).collect();
        let unit = if g == data.windows.len() {
            "trials"
        } else if data.windows.len() >= MIN_JACKKNIFE_BLOCKS {
            "groups of consecutive trials"
        } else {
            "contiguous pieces"
        };
        (
            reg.jackknife(&triangles, &block_rows),
            format!("jackknife over {g} blocks ({unit})"),
        )
    } else {
        (
            reg.analytic_se(&solved, (m - p - absorbed) as f64, &inflation),
            "analytic, residual variance inflated by its autocorrelation".to_string(),
        )
    };
    let block = |m_: &DMatrix<f64>, b: usize| {
        Matrix(DMatrix::from_fn(n, n, |row, col| m_[(b * n + col, row)]))
    };
    let sensitivity = inertia_sensitivity(&reg, &solved);
    // the inertia stays the data's (flagged when not identified); B, K and the
    // constant are reported for the prior inertia where the data give none
    let mut theta = solved.theta.clone();
    let prior_inertia = sensitivity.as_ref().map_or_else(Vec::new, |sens| {
        condition_on_prior_inertia(&mut theta, sens, &reg.reliability, &data.coordinates)
    });
    let theta = &theta;
    let inertia = block(&solved.theta, 0);
    let damping = block(theta, 1);
    let stiffness = block(theta, 2);
    let mut warnings = Vec::new();
    if data.demeaned && params.equilibrium {
        warnings.push(Warning::new(WarningCode::EquilibriumAbsorbed, "equilibrium not estimated: each trial's force offset was fitted, which absorbs it; use rest offsets (Artemiadis et al. 2010) to estimate it"));
    }
    let equilibrium = (with_const && params.equilibrium).then(|| {
        let constant = DVector::from_fn(n, |i, _| theta[(3 * n, i)]);
        equilibrium_position(&stiffness, constant, &data.reference, &mut warnings)
    });
    let equilibrium = equilibrium.flatten();
    // inertia first: when it is not identified, B and K carry its uncertainty too
    let inertia_se = block(&se, 0);
    let inertia_identified = identified(
        MatrixKind::Inertia,
        &inertia,
        &inertia_se,
        &data.coordinates,
        &reg.reliability,
        params.identifiable_ratio,
        &mut warnings,
    );
    // the share of each acceleration column's own part (not explained by
    // velocity, displacement and constant) that is signal rather than noise
    let partial_reliability: Vec<f64> = (0..n)
        .map(|k| {
            let nv = data.regressor_noise_var.get(k).map_or(0.0, |v| v[2]);
            let noise = nv / (reg.scales[k] * reg.scales[k]);
            (1.0 - noise / solved.partial_variance[k]).max(0.0)
        })
        .collect();
    let least = partial_reliability.iter().copied().fold(1.0, f64::min);
    if let Some(sens) = sensitivity
        .as_ref()
        .filter(|_| partial_reliability.iter().any(|r| *r < MIN_RELIABILITY))
    {
        let extra = inertia_confounding(sens, &data.coordinates);
        se.zip_apply(&extra, |v, e| *v = (*v * *v + e).sqrt());
        let _ = write!(
            se_method,
            "; B and K include an unknown inertia's effect (prior s.d. {UNIDENTIFIED_INERTIA_SD_KG} kg or {UNIDENTIFIED_INERTIA_SD_KG_M2} kg m^2): only {:.0} % of the acceleration the motion does not tie to displacement and velocity is signal",
            100.0 * least
        );
    }
    if !prior_inertia.is_empty() {
        let _ = write!(
            se_method,
            "; B and K are given for the prior mean inertia ({UNIDENTIFIED_INERTIA_MEAN_KG} kg or {UNIDENTIFIED_INERTIA_MEAN_KG_M2} kg m^2 on the diagonal) along {}: the acceleration there is mostly noise",
            prior_inertia.join(", ")
        );
    }
    for j in 0..2 * n {
        for a in 0..n {
            let floor = DERIVATIVE_ERROR_FLOOR * theta[(j, a)].abs();
            se[(j, a)] = se[(j, a)].hypot(floor);
        }
    }
    let se_out = StandardErrors {
        inertia: inertia_se,
        damping: block(&se, 1),
        stiffness: block(&se, 2),
        constant: with_const.then(|| (0..n).map(|a| se[(3 * n, a)]).collect()),
    };
    let finite = |m: &Matrix| m.iter().all(|v| v.is_finite());
    if ![
        &inertia,
        &damping,
        &stiffness,
        &se_out.inertia,
        &se_out.damping,
        &se_out.stiffness,
    ]
    .into_iter()
    .all(finite)
        || !condition_number.is_finite()
    {
        return Err(numerical(
            "the estimate or its standard errors are not finite numbers: the data overflow double precision or do not determine the model".into(),
        ));
    }
    let judge = |kind: MatrixKind, value: &Matrix, se: &Matrix, warnings: &mut Vec<Warning>| {
        identified(
            kind,
            value,
            se,
            &data.coordinates,
            &reg.reliability,
            params.identifiable_ratio,
            warnings,
        )
    };
    let identifiable = Identifiable {
        inertia: inertia_identified,
        damping: judge(
            MatrixKind::Damping,
            &damping,
            &se_out.damping,
            &mut warnings,
        ),
        stiffness: judge(
            MatrixKind::Stiffness,
            &stiffness,
            &se_out.stiffness,
            &mut warnings,
        ),
    };
    quality_warnings(
        &identifiable,
        condition_number,
        &fit,
        &reg.constant_force,
        &data.coordinates,
        &mut warnings,
    );
    Ok(LinearEstimate {
        coordinates: data.coordinates.clone(),
        inertia,
        damping,
        stiffness,
        equilibrium,
        standard_errors: se_out,
        fit,
        condition_number,
        identifiable,
        samples: m,
        parameters: p * n,
        variance_inflation: (!inflation.is_empty()).then_some(inflation),
        regressor_reliability: reg.reliability,
        standard_error_method: se_method,
        warnings,
    })
}

/// The column of a matrix kind's regressors in the per-coordinate
/// reliabilities `[acceleration, velocity, displacement]`.
fn regressor_column(kind: MatrixKind) -> usize {
    match kind {
        MatrixKind::Inertia => 0,
        MatrixKind::Damping => 1,
        MatrixKind::Stiffness => 2,
    }
}

/// Whether one matrix is identified: every diagonal element at least `ratio` standard errors from
/// zero (NaN-safe; an exact zero, no force at all, identifies nothing) and
/// its regressors carrying signal, not propagated position noise. Says why
/// not in `warnings`.
fn identified(
    matrix: MatrixKind,
    value: &Matrix,
    se: &Matrix,
    coords: &[String],
    reliability: &[[f64; 3]],
    ratio: f64,
    warnings: &mut Vec<Warning>,
) -> bool {
    let n = coords.len();
    let kind = regressor_column(matrix);
    let (label, name) = [("M", "inertia"), ("B", "damping"), ("K", "stiffness")][kind];
    let (mu, bu, ku) = units(coords);
    let unit = [mu, bu, ku][kind];
    let noisy: Vec<String> = (0..n)
        .filter(|&i| reliability[i][kind] < MIN_RELIABILITY)
        .map(|i| format!("{} {:.0} %", coords[i], 100.0 * reliability[i][kind]))
        .collect();
    if !noisy.is_empty() {
        warnings.push(Warning::new(WarningCode::NoisyRegressors, format!(
            "{} regressors are dominated by position noise (signal share {}; needs {:.0} %): the {name} estimate is biased towards zero",
            ["acceleration", "velocity", "displacement"][kind],
            noisy.join(", "),
            100.0 * MIN_RELIABILITY,
        )));
    }
    let bad: Vec<String> = (0..n)
        .filter(|&i| {
            let identified = value[(i, i)].abs() >= ratio * se[(i, i)];
            value[(i, i)] == 0.0 || !identified
        })
        .map(|i| {
            // rounded to the error, as the report rounds (issue 37)
            format!(
                "{label}{} = {} {unit}",
                sub(coords, i, i),
                limpid_core::with_standard_error(value[(i, i)], se[(i, i)])
            )
        })
        .collect();
    if !bad.is_empty() {
        warnings.push(Warning::new(WarningCode::NotIdentifiable, format!(
            "{name} is not identifiable from this data ({}; |value| < {ratio} SE): treat it as unknown",
            bad.join(", ")
        )));
    }
    bad.is_empty() && noisy.is_empty()
}

/// Warnings on the whole fit: inertia below the noise, an ill-conditioned
/// regressor, a force the model explains poorly.
fn quality_warnings(
    identifiable: &Identifiable,
    condition_number: f64,
    fit: &FitQuality,
    constant_force: &[bool],
    coords: &[String],
    warnings: &mut Vec<Warning>,
) {
    if !identifiable.inertia {
        warnings.push(Warning::new(WarningCode::InertiaBelowNoise, "inertial forces are below the noise: perturbations this slow cannot identify inertia (Artemiadis et al. 2010's 3 s motions are such a case)"));
    }
    if condition_number > 1e4 {
        warnings.push(Warning::new(WarningCode::IllConditioned, format!(
            "the scaled regressor is ill-conditioned (condition number {condition_number:.3e}): parameters are strongly correlated"
        )));
    }
    for (a, v) in fit.vaf.iter().enumerate() {
        if constant_force[a] {
            warnings.push(Warning::new(
                WarningCode::PoorFit,
                format!(
                    "the force along {} is the same in every sample: there is nothing to fit (check the force columns)",
                    coords[a]
                ),
            ));
        } else if *v < 50.0 {
            warnings.push(Warning::new(
                WarningCode::PoorFit,
                format!(
                    "the model explains only {v:.1} % of the force variance along {}",
                    coords[a]
                ),
            ));
        }
    }
}

/// Correlation r, VAF (%) and RMS error of measured `f` against predicted `fhat`.
pub(crate) fn fit_stats(f: &[f64], fhat: &[f64]) -> (f64, f64, f64) {
    let m = f.len() as f64;
    // two passes (means, then centred sums), each over row chunks in parallel
    const ROWS: usize = 1 << 15;
    let sum = |x: &[f64]| {
        x.par_chunks(ROWS)
            .map(|c| c.iter().sum::<f64>())
            .sum::<f64>()
    };
    let mf = sum(f) / m;
    let mh = sum(fhat) / m;
    let add = |a: [f64; 5], b: [f64; 5]| std::array::from_fn(|i| a[i] + b[i]);
    let [sff, shh, sfh, see, sum_e] = f
        .par_chunks(ROWS)
        .zip(fhat.par_chunks(ROWS))
        .map(|(fc, hc)| {
            let mut acc = [0.0; 5];
            for (y, yh) in fc.iter().zip(hc) {
                let (dy, dh) = (y - mf, yh - mh);
                acc[0] += dy * dy;
                acc[1] += dh * dh;
                acc[2] += dy * dh;
                let e = y - yh;
                acc[3] += e * e;
                acc[4] += e;
            }
            acc
        })
        .reduce(|| [0.0; 5], add);
    let var_e = see / m - (sum_e / m).powi(2);
    let r = if sff > 0.0 && shh > 0.0 {
        sfh / (sff * shh).sqrt()
    } else {
        0.0
    };
    let vaf = if sff > 0.0 {
        100.0 * (1.0 - var_e / (sff / m))
    } else {
        0.0
    };
    (r, vaf, (see / m).sqrt())
}

/// 1 + 2 Σ_k (1 - k/(L+1)) ρ_k of the residuals, lags not crossing window edges; at least 1.
fn autocorrelation_inflation(
    e: &[f64],
    windows: &[crate::prepare::PreparedWindow],
    lags: usize,
) -> f64 {
    let var: f64 = e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64;
    if var == 0.0 {
        return 1.0;
    }
    let mut tau = 1.0;
    for k in 1..=lags {
        let mut s = 0.0;
        let mut count = 0usize;
        for w in windows {
            let seg = &e[w.samples.clone()];
            if seg.len() > k {
                s += seg[k..].iter().zip(seg).map(|(a, b)| a * b).sum::<f64>();
                count += seg.len() - k;
            }
        }
        if count == 0 {
            break;
        }
        let rho = s / count as f64 / var;
        tau += 2.0 * (1.0 - k as f64 / (lags as f64 + 1.0)) * rho;
    }
    tau.max(1.0)
}

fn column_names(coords: &[String], with_const: bool) -> Vec<String> {
    let mut names = Vec::new();
    for prefix in ["acceleration ", "velocity ", "displacement "] {
        names.extend(coords.iter().map(|c| format!("{prefix}{c}")));
    }
    if with_const {
        names.push("constant".into());
    }
    names
}

/// Subscript of element (i, j), e.g. `xy`, or `11` for joint coordinates.
pub fn sub(coords: &[String], i: usize, j: usize) -> String {
    let short = |c: &str| c.trim_start_matches('q').to_string();
    if coords.iter().all(|c| c.len() == 1) {
        format!("{}{}", coords[i], coords[j])
    } else {
        format!("{},{}", short(&coords[i]), short(&coords[j]))
    }
}

/// Units of M, B, K entries for these coordinates (translational or rotational).
pub fn units(coords: &[String]) -> (&'static str, &'static str, &'static str) {
    if coords.iter().all(|c| matches!(c.as_str(), "x" | "y" | "z")) {
        ("kg", "N s/m", "N/m")
    } else if coords.iter().all(|c| c == "theta" || c.starts_with('q')) {
        ("kg m^2", "N m s/rad", "N m/rad")
    } else {
        ("SI", "SI", "SI")
    }
}
