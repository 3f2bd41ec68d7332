//! Seed 003 eq. (13)-(25): the least-squares fit of ξ, D and K over the observation windows, its standard errors, criteria (eq. (19), (20), (22)) and verdicts.

use super::noise::{compensated_solve, RegressorNoise};
use super::prepare::PlanarData;
use super::{regressor, PlanarTrial};
use crate::linear::{fit_stats, solve_triangle};
use crate::lsq::{merge, triangle};
use limpid_core::arm::{coriolis, mass_matrix};
use limpid_core::criteria::{
    judge_matrix, tolerance, MatrixKind, MatrixVerdict, Verdicts, MAX_CONDITION, QUASI_SYMMETRIC,
    VAF_FLOOR_PERCENT,
};
use limpid_core::{Error, Matrix, Result};
use nalgebra::{DMatrix, DVector, Matrix2, Vector2};
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
/// Confidence criteria of seed 003 §III-C.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct PlanarCriteria {
    /// cond(W) of eq. (19), W as is.
    pub condition_number: f64,
    /// cond(W) with unit-RMS columns.
    pub condition_number_scaled: f64,
    /// Eigenvalues of the symmetric part of K, largest first (N m/rad).
    pub stiffness_eigenvalues: [f64; 2],
    /// Eigenvalues of the symmetric part of D, largest first (N m s/rad).
    pub damping_eigenvalues: [f64; 2],
    /// K_s positive definite.
    pub stiffness_positive_definite: bool,
    /// D_s positive definite.
    pub damping_positive_definite: bool,
    /// ||K_a|| / ||K_s||.
    pub stiffness_symmetry_ratio: f64,
    /// ||D_a|| / ||D_s||.
    pub damping_symmetry_ratio: f64,
    /// Every criterion met: a fit explaining the torques, well-conditioned, K and D identified, precise, positive definite and quasi-symmetric, physical inertial parameters.
    pub trusted: bool,
    /// Why not trusted, one sentence per failed criterion.
    pub reasons: Vec<String>,
    /// The verdict on K and D (the rules every estimator shares).
    pub verdicts: Verdicts,
}

/// A planar estimate.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct PlanarEstimate {
    /// ξ1..ξ3 (kg m²); the given values when fixed.
    pub inertial_parameters: [f64; 3],
    /// True when the inertial parameters were given (reduced model, eq. (23)-(25)).
    pub inertial_parameters_fixed: bool,
    /// Joint stiffness (N m/rad) and damping (N m s/rad).
    pub stiffness: Matrix,
    /// Joint damping D (N m s/rad).
    pub damping: Matrix,
    /// End-point stiffness J^-T K J^-1 at the mean q0 (N/m), without the
    /// geometric term of the baseline force.
    pub endpoint_stiffness: Matrix,
    /// Jackknife (delete-one-trial) standard errors, same layout.
    pub standard_errors: PlanarErrors,
    /// VAF (%) and r of Δτ per joint.
    pub fit: PlanarFit,
    /// Confidence criteria of seed 003 §III-C.
    pub criteria: PlanarCriteria,
    /// Observation window after each onset (ms).
    pub observation_window_ms: f64,
    /// Trials used.
    pub trials: usize,
    /// Samples per joint used.
    pub samples: usize,
    /// Leave-one-trial-out VAF (%) per joint (seed 003 Fig. 6), when computed
    /// ([`estimate_planar`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub leave_one_out_vaf: Option<[f64; 2]>,
    /// Measured and predicted Δτ per joint (N m) along the concatenated
    /// windows, every k-th sample (at most
    /// [`TRACE_POINTS`](crate::linear::TRACE_POINTS) per joint); with known
    /// inertial parameters both have the known inertial torque removed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub traces: Option<crate::linear::FitTraces>,
}

/// Standard errors of a planar estimate (delete-one-trial jackknife).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct PlanarErrors {
    /// Of ξ1..ξ3 (kg m²); zeros when given.
    pub inertial_parameters: [f64; 3],
    /// Of K (N m/rad).
    pub stiffness: Matrix,
    /// Of D (N m s/rad).
    pub damping: Matrix,
}

/// Fit of Δτ per joint.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct PlanarFit {
    /// Variance accounted for (%).
    pub vaf: [f64; 2],
    /// Correlation of measured and predicted Δτ.
    pub r: [f64; 2],
}

/// Rows (W | y) of one trial's first `n` samples, unscaled.
pub(crate) fn trial_rows(t: &PlanarTrial, n: usize, xi: Option<[f64; 3]>) -> DMatrix<f64> {
    let p = if xi.is_some() { 8 } else { 11 };
    let n = n.min(t.dq[0].len());
    let mut a = DMatrix::<f64>::zeros(2 * n, p + 1);
    for i in 0..n {
        let qd = [t.qd[0][i], t.qd[1][i]];
        let qdd = [t.qdd[0][i], t.qdd[1][i]];
        let x = regressor(t.q[1][i], qd, qdd, [t.dq[0][i], t.dq[1][i]]);
        let known = xi.map(|xi| {
            mass_matrix(t.q[1][i], xi) * Vector2::new(qdd[0], qdd[1]) + coriolis(t.q[1][i], qd, xi)
        });
        for r in 0..2 {
            let row = 2 * i + r;
            let first = if xi.is_some() { 3 } else { 0 };
            for (c, j) in (first..11).enumerate() {
                a[(row, c)] = x[r][j];
            }
            a[(row, p)] = t.dtau[r][i] - known.map_or(0.0, |k| k[r]);
        }
    }
    a
}

/// Shortest and longest arm segment limpid accepts (m).
pub const MIN_LINK_M: f64 = 0.01;

/// See [`MIN_LINK_M`].
pub const MAX_LINK_M: f64 = 2.0;

/// Largest base inertial parameter limpid accepts (kg m²): a human arm's
/// are below 1.
pub const MAX_INERTIAL_PARAMETER: f64 = 100.0;

/// Known base inertial parameters must be finite, positive (each is a mass
/// times lengths or a moment of inertia) and of an arm's size: NaN, inf and
/// 1e308 gave null estimates with exit 0 (issue 36).
pub fn check_inertial_parameters(xi: &[f64; 3]) -> Result<()> {
    if xi.iter().all(|v| *v > 0.0 && *v <= MAX_INERTIAL_PARAMETER) {
        Ok(())
    } else {
        Err(Error::invalid(
            "inertial_parameters",
            format!(
                "expected three positive values up to {MAX_INERTIAL_PARAMETER} kg m², found {}, {}, {}",
                xi[0], xi[1], xi[2]
            ),
        ))
    }
}

/// Estimate from the first `window` samples after onset of the given trials.
pub fn fit_planar(
    data: &PlanarData,
    window: usize,
    xi: Option<[f64; 3]>,
    use_trials: &[usize],
) -> Result<PlanarEstimate> {
    if let Some(xi) = &xi {
        check_inertial_parameters(xi)?;
    }
    let p = if xi.is_some() { 8 } else { 11 };
    let blocks: Vec<DMatrix<f64>> = use_trials
        .iter()
        .map(|&k| trial_rows(&data.trials[k], window, xi))
        .collect();
    let rows: usize = blocks.iter().map(|b| b.nrows()).sum();
    if rows < 2 * p {
        return Err(Error::TooFewSamples {
            path: data.path.clone(),
            what: format!("a {p}-parameter planar fit"),
            needed: 2 * p,
            found: rows,
        });
    }
    let numerical = |m: String| Error::Numerical {
        path: data.path.clone(),
        message: m,
    };
    let model = RegressorNoise::new(&data.angle_noise, xi);
    let noise: Vec<Option<DMatrix<f64>>> = use_trials
        .iter()
        .map(|&k| model.over(&data.trials[k], 0..window))
        .collect();
    let BlockSolution {
        theta,
        condition_number_scaled: cond_scaled,
        replicates: reps,
        ..
    } = solve_blocks(&blocks, &noise).map_err(numerical)?;
    // the jackknife's effective degrees of freedom (as the linear method's)
    let widen = crate::lsq::small_sample_factors(&blocks, p);
    let se = jackknife_se(&reps, p).component_mul(&DVector::from_vec(widen));
    let condition_number = unscaled_condition_number(&blocks, p);
    let off = if xi.is_some() { 0 } else { 3 };
    let (xi_hat, xi_se) = match xi {
        Some(x) => (x, [0.0; 3]),
        None => ([theta[0], theta[1], theta[2]], [se[0], se[1], se[2]]),
    };
    let m2 =
        |v: &DVector<f64>, s: usize| Matrix::from(Matrix2::new(v[s], v[s + 1], v[s + 2], v[s + 3]));
    let damping = m2(&theta, off);
    let stiffness = m2(&theta, off + 4);
    let (fit, traces) = fit_and_traces(&blocks, &theta, rows, data.fs);
    let (stiffness_se, damping_se) = (m2(&se, off + 4), m2(&se, off));
    let fit_ok = fit.vaf.iter().all(|v| *v >= VAF_FLOOR_PERCENT);
    let mut criteria = criteria(
        &stiffness,
        &damping,
        (&stiffness_se, &damping_se),
        fit_ok,
        condition_number,
        cond_scaled,
    );
    // base inertial parameters of a real arm are positive (seed 003 eq. (5))
    if xi.is_none() && !xi_hat.iter().all(|v| *v > 0.0) {
        criteria.trusted = false;
        criteria.reasons.push(format!(
            "inertial parameters not physical (xi = {:.4}, {:.4}, {:.4} kg m²; all must be positive)",
            xi_hat[0], xi_hat[1], xi_hat[2]
        ));
    }
    let kx = endpoint_stiffness(data, &stiffness).map_err(numerical)?;
    Ok(PlanarEstimate {
        inertial_parameters: xi_hat,
        inertial_parameters_fixed: xi.is_some(),
        stiffness,
        damping,
        endpoint_stiffness: kx,
        standard_errors: PlanarErrors {
            inertial_parameters: xi_se,
            stiffness: stiffness_se,
            damping: damping_se,
        },
        fit,
        criteria,
        observation_window_ms: (1e4
            * window.min(data.trials.iter().map(|t| t.dq[0].len()).min().unwrap_or(0)) as f64
            / data.fs)
            .round()
            / 10.0,
        trials: use_trials.len(),
        samples: rows / 2,
        leave_one_out_vaf: None,
        traces: Some(traces),
    })
}

/// Delete-a-trial jackknife standard errors from the replicates.
fn jackknife_se(reps: &[DVector<f64>], p: usize) -> DVector<f64> {
    let gn = reps.len() as f64;
    let mean = reps.iter().fold(DVector::zeros(p), |a, t| a + t) / gn.max(1.0);
    (reps
        .iter()
        .fold(DVector::zeros(p), |a, t| a + (t - &mean).map(|v| v * v))
        * ((gn - 1.0) / gn.max(1.0)))
    .map(f64::sqrt)
}

/// The unscaled condition number of W (seed 003 eq. (19)).
fn unscaled_condition_number(blocks: &[DMatrix<f64>], p: usize) -> f64 {
    let raw_tris: Vec<DMatrix<f64>> = blocks
        .iter()
        .map(|b| triangle(b.columns(0, p).into_owned(), p))
        .collect();
    let raw = limpid_core::linalg::singular_values(merge(raw_tris.iter(), p))
        .unwrap_or_else(|| DVector::from_element(p, f64::NAN));
    raw.max() / raw.min()
}

/// VAF and correlation per torque, and the traces of measured and predicted
/// torque (every k-th sample of the concatenated windows).
fn fit_and_traces(
    blocks: &[DMatrix<f64>],
    theta: &DVector<f64>,
    rows: usize,
    fs: f64,
) -> (PlanarFit, crate::linear::FitTraces) {
    let p = theta.len();
    let mut fit = PlanarFit {
        vaf: [0.0; 2],
        r: [0.0; 2],
    };
    // every k-th sample of the concatenated windows goes to the traces
    let stride = (rows / 2).div_ceil(crate::linear::TRACE_POINTS).max(1);
    let mut traces = crate::linear::FitTraces {
        time: (0..rows / 2)
            .step_by(stride)
            .map(|i| i as f64 / fs)
            .collect(),
        measured: vec![Vec::new(), Vec::new()],
        predicted: vec![Vec::new(), Vec::new()],
    };
    for r in 0..2 {
        let (mut y, mut yh) = (Vec::with_capacity(rows / 2), Vec::with_capacity(rows / 2));
        for b in blocks {
            for i in (r..b.nrows()).step_by(2) {
                let pred: f64 = (0..p).map(|j| b[(i, j)] * theta[j]).sum();
                y.push(b[(i, p)]);
                yh.push(pred);
            }
        }
        let (rr, vaf, _) = fit_stats(&y, &yh);
        fit.vaf[r] = vaf;
        fit.r[r] = rr;
        traces.measured[r] = y.iter().step_by(stride).copied().collect();
        traces.predicted[r] = yh.iter().step_by(stride).copied().collect();
    }
    (fit, traces)
}

/// The end-point stiffness `J^-T K J^-1` at the trials' mean rest posture.
fn endpoint_stiffness(
    data: &PlanarData,
    stiffness: &Matrix,
) -> std::result::Result<Matrix, String> {
    let q0 = {
        let n = data.trials.len() as f64;
        [
            data.trials.iter().map(|t| t.q0[0]).sum::<f64>() / n,
            data.trials.iter().map(|t| t.q0[1]).sum::<f64>() / n,
        ]
    };
    let j = data.arm.jacobian(q0);
    match j.try_inverse() {
        Some(ji) => {
            let k = stiffness.to_matrix2().unwrap_or_else(Matrix2::zeros);
            Ok(Matrix::from(ji.transpose() * k * ji))
        }
        None => Err("the arm is singular (stretched) at q0: no end-point stiffness".into()),
    }
}

/// Fewest samples of each trial in an observation window: the derivatives
/// and the 11 parameters need the motion, not a few points of it.
pub const MIN_WINDOW_SAMPLES: usize = 10;

/// Seed 003's estimate from every trial's first `window` samples, with its
/// leave-one-trial-out validation.
///
/// # Example
///
/// Lakatos et al. (2011)'s arm in the virtual lab, without noise, every
/// sample of every trial (`usize::MAX`):
///
/// ```
/// use limpid_ident::planar::{estimate_planar, prepare_planar, PlanarPrepare};
/// use limpid_lab::planar::{simulate_planar, PlanarProtocol, PlanarSubject};
///
/// let subject = PlanarSubject::seed003(); // K11 = 37.95 N m/rad
/// let rec = simulate_planar(&subject, &PlanarProtocol::seed003(), 0.0, 0.0, 1)?;
/// let data = prepare_planar(&rec, &PlanarPrepare::new(0.32, 0.31))?;
/// let est = estimate_planar(&data, usize::MAX, None)?;
/// assert!((est.stiffness[(0, 0)] - 37.95).abs() < 0.01);
/// assert!(est.criteria.trusted);
/// # Ok::<(), limpid_core::Error>(())
/// ```
pub fn estimate_planar(
    data: &PlanarData,
    window: usize,
    xi: Option<[f64; 3]>,
) -> Result<PlanarEstimate> {
    if window < MIN_WINDOW_SAMPLES {
        // 1 ms gave 30 samples for 11 parameters and K at 120x the truth (issue 36)
        return Err(Error::invalid(
            "window_ms",
            format!(
                "the observation window holds {window} sample(s) of each trial at {} Hz; at least {MIN_WINDOW_SAMPLES} ({} ms) are needed",
                data.fs,
                MIN_WINDOW_SAMPLES as f64 * 1e3 / data.fs
            ),
        ));
    }
    let all: Vec<usize> = (0..data.trials.len()).collect();
    let mut est = fit_planar(data, window, xi, &all)?;
    est.leave_one_out_vaf = Some(leave_one_out_vaf(data, window, xi)?);
    Ok(est)
}

/// Leave-one-trial-out prediction of Δτ (seed 003 Fig. 6): each trial
/// predicted by the estimate from all the others, VAF (%) pooled per joint.
pub fn leave_one_out_vaf(
    data: &PlanarData,
    window: usize,
    xi: Option<[f64; 3]>,
) -> Result<[f64; 2]> {
    let n = data.trials.len();
    // per held-out trial: measured and predicted Δτ of joint 1, then of joint 2
    type Held = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>);
    let preds: Vec<Result<Held>> = (0..n)
        .into_par_iter()
        .map(|k| {
            let others: Vec<usize> = (0..n).filter(|&j| j != k).collect();
            let est = fit_planar(data, window, xi, &others)?;
            let rows = trial_rows(&data.trials[k], window, xi);
            let p = rows.ncols() - 1;
            let mut theta = Vec::with_capacity(p);
            if xi.is_none() {
                theta.extend(est.inertial_parameters);
            }
            // row-major, as the regressor's columns (seed 003 eq. (8))
            theta.extend(est.damping.transpose().iter());
            theta.extend(est.stiffness.transpose().iter());
            let (mut y1, mut h1, mut y2, mut h2) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for i in 0..rows.nrows() {
                let pred: f64 = (0..p).map(|j| rows[(i, j)] * theta[j]).sum();
                if i % 2 == 0 {
                    y1.push(rows[(i, p)]);
                    h1.push(pred);
                } else {
                    y2.push(rows[(i, p)]);
                    h2.push(pred);
                }
            }
            Ok((y1, h1, y2, h2))
        })
        .collect();
    let (mut y1, mut h1, mut y2, mut h2) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for p in preds {
        let (a, b, c, d) = p?;
        y1.extend(a);
        h1.extend(b);
        y2.extend(c);
        h2.extend(d);
    }
    Ok([fit_stats(&y1, &h1).1, fit_stats(&y2, &h2).1])
}

/// Reliability above which a column's noise is still compensated when
/// correcting the less reliable ones too leaves the Gram matrix indefinite.
const COMPENSATE_ONLY_ABOVE: f64 = 0.95;

/// Least squares on per-trial blocks `[W | y]` (columns scaled to unit RMS,
/// tall-skinny QR), with delete-one-trial jackknife replicates.
pub(crate) struct BlockSolution {
    pub(crate) theta: DVector<f64>,
    pub(crate) condition_number_scaled: f64,
    pub(crate) replicates: Vec<DVector<f64>>,
    /// Per parameter, the share of its regressor's mean square that is
    /// signal rather than angle noise (1 without noise).
    pub(crate) reliability: Vec<f64>,
    /// `(Σ_i A_iᵀ A_i)⁻¹` of the regressors (unscaled), from the merged
    /// triangle; None when it is singular.
    pub(crate) gram_inverse: Option<DMatrix<f64>>,
}

pub(crate) fn solve_blocks(
    blocks: &[DMatrix<f64>],
    noise: &[Option<DMatrix<f64>>],
) -> std::result::Result<BlockSolution, String> {
    let q = blocks.first().map_or(1, |b| b.ncols());
    let p = q - 1;
    let rows: usize = blocks.iter().map(|b| b.nrows()).sum();
    let mut sums = vec![0.0; q];
    for b in blocks {
        for (j, s) in sums.iter_mut().enumerate() {
            *s += b.column(j).norm_squared();
        }
    }
    let scales: Vec<f64> = sums
        .iter()
        .map(|s| (s / rows.max(1) as f64).sqrt())
        .map(|s| if s == 0.0 { 1.0 } else { s })
        .collect();
    let tris: Vec<DMatrix<f64>> = blocks
        .par_iter()
        .map(|b| {
            let mut b = b.clone();
            for (j, s) in scales.iter().enumerate() {
                b.column_mut(j).scale_mut(1.0 / s);
            }
            triangle(b, q)
        })
        .collect();
    // the regressors' noise (errors in variables), scaled as the columns
    let scaled_noise: Vec<DMatrix<f64>> = noise
        .iter()
        .flatten()
        .map(|n| DMatrix::from_fn(q, q, |i, j| n[(i, j)] / (scales[i] * scales[j])))
        .collect();
    let per_block = scaled_noise.len() == blocks.len();
    let total_noise = scaled_noise
        .iter()
        .fold(DMatrix::<f64>::zeros(q, q), |a, n| a + n);
    // share of each column's mean square that is signal rather than noise
    let reliability: Vec<f64> = (0..p)
        .map(|j| {
            if per_block {
                (1.0 - total_noise[(j, j)] / (sums[j] / (scales[j] * scales[j]))).max(0.0)
            } else {
                1.0
            }
        })
        .collect();
    // the columns to correct: the reliable enough (as the linear estimator),
    // fewer when that leaves the corrected Gram matrix indefinite (a column
    // barely above the noise, nearly collinear with the others)
    let correctable_at = |least: f64| -> Vec<bool> {
        (0..p)
            .map(|j| per_block && total_noise[(j, j)] > 0.0 && reliability[j] >= least)
            .collect()
    };
    let levels = [
        crate::linear::MIN_CORRECTABLE,
        crate::linear::MIN_RELIABILITY,
        COMPENSATE_ONLY_ABOVE,
    ];
    let no_noise = DMatrix::<f64>::zeros(p, p);
    let unscale = |t: DVector<f64>| DVector::from_fn(p, |j, _| t[j] * scales[p] / scales[j]);
    let merged = merge(tris.iter(), q);
    let correctable = levels
        .iter()
        .map(|l| correctable_at(*l))
        .find(|c| c.iter().any(|v| *v) && compensated_solve(&merged, &total_noise, c).is_some())
        .unwrap_or_else(|| vec![false; p]);
    let compensate = correctable.iter().any(|c| *c);
    let solve = |r_aug: &DMatrix<f64>, noise: Option<DMatrix<f64>>| {
        let plain = solve_triangle(r_aug, p, 1, &scales, &no_noise, rows as f64)
            .map(|s| (s.theta.column(0).into_owned(), s.condition_number))
            .map_err(|_| "the observation matrix W is rank-deficient: the perturbations do not excite every parameter".to_string())?;
        let corrected = noise
            .and_then(|n| compensated_solve(r_aug, &n, &correctable))
            .map(unscale);
        Ok::<_, String>((corrected.unwrap_or(plain.0), plain.1))
    };
    let (theta, condition_number_scaled) = solve(&merged, compensate.then(|| total_noise.clone()))?;
    let replicates: Vec<DVector<f64>> = crate::lsq::leave_one_out(&tris, q)
        .par_iter()
        .enumerate()
        .filter_map(|(b, t)| {
            let noise = compensate.then(|| &total_noise - &scaled_noise[b]);
            solve(t, noise).ok().map(|s| s.0)
        })
        .collect();
    let r = merged.view((0, 0), (p, p));
    let gram_inverse = (r.transpose() * r)
        .cholesky()
        .map(|c| c.inverse())
        .map(|inv| DMatrix::from_fn(p, p, |i, j| inv[(i, j)] / (scales[i] * scales[j])));
    Ok(BlockSolution {
        theta,
        condition_number_scaled,
        replicates,
        reliability,
        gram_inverse,
    })
}

/// Criteria of seed 003 §III-C on a 2 x 2 K and D (through
/// [`limpid_core::criteria`], shared with every estimator).
///
/// `se` are the standard errors of K and D and `fit_ok` whether the fit
/// explains the torques (every VAF at least [`VAF_FLOOR_PERCENT`]): with them
/// each matrix gets its [`Verdicts`] (the rules every estimator shares), and
/// a matrix that is not identified or not precise is not trusted either.
pub fn criteria(
    k: &Matrix,
    d: &Matrix,
    se: (&Matrix, &Matrix),
    fit_ok: bool,
    cond: f64,
    cond_scaled: f64,
) -> PlanarCriteria {
    use limpid_core::criteria::{symmetric_part_eigenvalues, symmetry_ratio};
    let eig = |m: &Matrix| {
        let e = symmetric_part_eigenvalues(m);
        [e[0], e[1]]
    };
    let (ke, de) = (eig(k), eig(d));
    let (kr, dr) = (symmetry_ratio(k), symmetry_ratio(d));
    let mut reasons = Vec::new();
    // written so that a NaN fails each test (a NaN must never read as trusted)
    let well_conditioned = limpid_core::criteria::well_conditioned(cond_scaled);
    if !well_conditioned {
        reasons.push(format!(
            "ill-conditioned: scaled condition number {cond_scaled:.0} >= {MAX_CONDITION:.0}"
        ));
    }
    let k_pd = ke[1] > 0.0;
    if !k_pd {
        reasons.push(format!(
            "stiffness not positive definite (eigenvalues {:.3}, {:.3})",
            ke[0], ke[1]
        ));
    }
    let d_pd = de[1] > 0.0;
    if !d_pd {
        reasons.push(format!(
            "damping not positive definite (eigenvalues {:.3}, {:.3})",
            de[0], de[1]
        ));
    }
    let k_sym = kr < QUASI_SYMMETRIC;
    if !k_sym {
        reasons.push(format!(
            "stiffness not quasi-symmetric (ratio {kr:.3} >= {QUASI_SYMMETRIC})"
        ));
    }
    let d_sym = dr < QUASI_SYMMETRIC;
    if !d_sym {
        reasons.push(format!(
            "damping not quasi-symmetric (ratio {dr:.3} >= {QUASI_SYMMETRIC})"
        ));
    }
    let verdicts = Verdicts {
        stiffness: judge_matrix(MatrixKind::Stiffness, k, se.0, fit_ok),
        damping: judge_matrix(MatrixKind::Damping, d, se.1, fit_ok),
        inertia: None,
    };
    if !fit_ok {
        reasons.push(format!(
            "poor fit: the model explains less than {VAF_FLOOR_PERCENT:.0} % of a joint torque"
        ));
    }
    for (name, v, tol) in [
        (
            "stiffness",
            verdicts.stiffness,
            tolerance(MatrixKind::Stiffness),
        ),
        ("damping", verdicts.damping, tolerance(MatrixKind::Damping)),
    ] {
        match v {
            MatrixVerdict::NotIdentifiable => reasons.push(format!(
                "{name} not identifiable: a diagonal element within 2 SE of zero"
            )),
            MatrixVerdict::Imprecise => reasons.push(format!(
                "{name} imprecise: 2 SE exceed {:.0} % of it",
                100.0 * tol
            )),
            _ => {}
        }
    }
    PlanarCriteria {
        verdicts,
        condition_number: cond,
        condition_number_scaled: cond_scaled,
        stiffness_eigenvalues: ke,
        damping_eigenvalues: de,
        stiffness_positive_definite: ke[1] > 0.0,
        damping_positive_definite: de[1] > 0.0,
        stiffness_symmetry_ratio: kr,
        damping_symmetry_ratio: dr,
        trusted: reasons.is_empty(),
        reasons,
    }
}
