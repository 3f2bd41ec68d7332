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

use nalgebra::{DMatrix, DVector};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::prepare::{Plan, Prepared};
use limpid_core::criteria::MatrixKind;
use limpid_core::{Error, Result, Warning, WarningCode};

mod regression;
mod standard_errors;
mod verdict;

pub(crate) use regression::{reduce_blocks, solve_triangle, Regression, Rows};
pub(crate) use standard_errors::{
    block_jackknife, condition_on_prior_inertia, few_trials_warning, inertia_sensitivity,
    jackknife_blocks, widen_for_what_the_regression_cannot_see,
};
pub(crate) use verdict::{fit_stats, identified, quality_warnings};

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
    /// How a closed-loop recording (with commanded reference columns) was
    /// estimated; absent in open loop.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub closed_loop: Option<crate::closed_loop::ClosedLoop>,
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
///
/// # Example
///
/// Artemiadis et al. (2010)'s centre-out protocol on their subject 1 in the
/// virtual lab, without sensor noise:
///
/// ```
/// use limpid_ident::{fit_linear_plan, plan, LinearParams, PrepareParams};
/// use limpid_lab::{seed000_subject1, simulate_centre_out, CentreOut, NoiseModel, Profile};
///
/// let posture = seed000_subject1()[1].clone();
/// let protocol = CentreOut::seed000(Profile::Cubic);
/// let rec = simulate_centre_out(&posture, &protocol, &NoiseModel::none(), 1)?;
/// let windows = plan(&rec, &PrepareParams::default())?;
/// let est = fit_linear_plan(&windows, &LinearParams::default())?;
/// let truth = posture.stiffness[(0, 0)];
/// assert!((est.stiffness[(0, 0)] - truth).abs() < 1e-3 * truth);
/// # Ok::<(), limpid_core::Error>(())
/// ```
pub fn fit_linear_plan(plan: &Plan<'_>, params: &LinearParams) -> Result<LinearEstimate> {
    if plan.meta.windows.len() < MIN_JACKKNIFE_BLOCKS {
        return fit_linear(&plan.materialise()?, params);
    }
    fit_rows(Rows::Windows(plan), params)
}

/// The columns of the regression.
struct ModelSize {
    /// A constant term: the equilibrium (seed 000), or the unknown offset of
    /// continuous data; demeaned windows already had their per-trial constants removed.
    with_const: bool,
    /// Constants absorbed by demeaning (one per window), for the degrees of freedom.
    absorbed: usize,
    /// Parameters per force coordinate.
    p: usize,
}

/// The regression's size, refusing data with fewer than two samples per parameter.
fn model_size(data: &Prepared, params: &LinearParams, m: usize) -> Result<ModelSize> {
    let with_const = !data.demeaned && (params.equilibrium || data.continuous);
    let absorbed = if data.demeaned { data.windows.len() } else { 0 };
    let p = 3 * data.dims() + usize::from(with_const);
    if m < 2 * (p + absorbed) {
        return Err(Error::TooFewSamples {
            path: data.path.clone(),
            what: format!("a {p}-parameter linear fit"),
            needed: 2 * (p + absorbed),
            found: m,
        });
    }
    Ok(ModelSize {
        with_const,
        absorbed,
        p,
    })
}

/// The least-squares solution with its fit and sampling errors.
struct Sampled {
    reg: Regression,
    solved: Solved,
    fit: FitQuality,
    inflation: Vec<f64>,
    se: DMatrix<f64>,
    se_method: String,
}

/// Reduce the rows block by block, solve, and measure the fit and the
/// sampling errors (jackknife over the blocks when there are enough, else
/// analytic with the residuals' autocorrelation).
fn regress(
    rows: Rows<'_>,
    data: &Prepared,
    (n, p, absorbed): (usize, usize, usize),
    with_const: bool,
    numerical: impl Fn(String) -> Error + Copy,
) -> Result<Sampled> {
    let m = rows.len();
    let q = p + n;
    let blocks = jackknife_blocks(&data.windows, m, q);
    let summaries = reduce_blocks(rows, &blocks, (n, p, q))?;
    let (reg, triangles) = Regression::new(data, m, with_const, &summaries, numerical)?;
    drop(summaries);
    let solved = reg.solve(triangles.iter(), m).map_err(numerical)?;
    let theta = &solved.theta;
    let g = blocks.len();
    let use_jackknife = g >= MIN_JACKKNIFE_BLOCKS;
    let (fit, inflation) = reg.fit_quality(rows, theta, !use_jackknife)?;
    let (se, se_method) = if use_jackknife {
        block_jackknife(&reg, &triangles, &blocks, data.windows.len())
    } else {
        (
            reg.analytic_se(&solved, (m - p - absorbed) as f64, &inflation),
            "analytic, residual variance inflated by its autocorrelation".to_string(),
        )
    };
    Ok(Sampled {
        reg,
        solved,
        fit,
        inflation,
        se,
        se_method,
    })
}

fn fit_rows(rows: Rows<'_>, params: &LinearParams) -> Result<LinearEstimate> {
    let data = rows.meta();
    let n = data.dims();
    let m = rows.len();
    let ModelSize {
        with_const,
        absorbed,
        p,
    } = model_size(data, params, m)?;
    let numerical = |message: String| Error::Numerical {
        path: data.path.clone(),
        message,
    };
    let Sampled {
        reg,
        solved,
        fit,
        inflation,
        mut se,
        mut se_method,
    } = regress(rows, data, (n, p, absorbed), with_const, numerical)?;
    let condition_number = solved.condition_number;
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
    let mut warnings: Vec<Warning> = few_trials_warning(data.windows.len(), &se_method)
        .into_iter()
        .collect();
    if data.demeaned && params.equilibrium {
        warnings.push(Warning::new(WarningCode::EquilibriumAbsorbed, "equilibrium not estimated: each trial's force offset was fitted, which absorbs it; use rest offsets (Artemiadis et al. 2010) to estimate it"));
    }
    let equilibrium = (with_const && params.equilibrium)
        .then(|| {
            let constant = DVector::from_fn(n, |i, _| theta[(3 * n, i)]);
            equilibrium_position(&stiffness, constant, &data.reference, &mut warnings)
        })
        .flatten();
    // inertia first: when it is not identified, B and K carry its uncertainty too
    let inertia_se = block(&se, 0);
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
    let inertia_identified = judge(MatrixKind::Inertia, &inertia, &inertia_se, &mut warnings);
    widen_for_what_the_regression_cannot_see(
        (&mut se, &mut se_method),
        theta,
        data,
        &reg,
        &solved,
        sensitivity.as_ref(),
        &prior_inertia,
    );
    let se_out = StandardErrors {
        inertia: inertia_se,
        damping: block(&se, 1),
        stiffness: block(&se, 2),
        constant: with_const.then(|| (0..n).map(|a| se[(3 * n, a)]).collect()),
    };
    let finite = |m: &Matrix| m.iter().all(|v| v.is_finite());
    let estimates = [&inertia, &damping, &stiffness];
    let errors = [&se_out.inertia, &se_out.damping, &se_out.stiffness];
    if !(estimates.into_iter().chain(errors).all(finite) && condition_number.is_finite()) {
        return Err(numerical(
            "the estimate or its standard errors are not finite numbers: the data overflow double precision or do not determine the model".into(),
        ));
    }
    let mut identifiable = Identifiable {
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
    // positions cut back to their measured samples first (issue 58)
    warnings.extend(data.measured_rate.as_ref().map(|m| m.warning()));
    warnings.extend(data.closed_loop.iter().flat_map(|c| c.warnings()));
    distrust_derivatives_the_reference_does_not_drive(data, &mut identifiable, &mut warnings);
    distrust_derivatives_of_resampled_positions(data, &mut identifiable, &mut warnings);
    for (k, c) in data.coordinates.iter().enumerate() {
        if let Some(kind) = crate::units::Coordinate::of_name(c) {
            warnings.extend(crate::units::implausible_motion(
                c,
                kind,
                data.position_range[k],
            ));
        }
    }
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
        closed_loop: data.closed_loop.clone(),
        warnings,
    })
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
        ("kg m²", "N m s/rad", "N m/rad")
    } else {
        ("SI", "SI", "SI")
    }
}

/// Below this share (%) of a velocity's or acceleration's variance driven by
/// the commanded reference, a closed-loop fit on the predicted motion cannot
/// pin damping or inertia down. Chosen on the outside end point on a servo
/// (`ex_endpoint_servo`): its acceleration is 5-6 % reference-driven and M
/// came out 10-40 % low at up to 9 SE; its velocity 29-42 %, and B was within
/// 7 % (the predicted motion's error does not bias a linear fit, it only
/// costs precision, until it swamps the derivative).
pub const MIN_REFERENCE_DRIVEN_DERIVATIVE: f64 = 20.0;

/// In closed loop, damping and inertia are judged by how much of the
/// velocity and acceleration the reference drives: the fit on the predicted
/// motion misses the rest, and the jackknife cannot see what it misses.
fn distrust_derivatives_the_reference_does_not_drive(
    data: &Prepared,
    identifiable: &mut Identifiable,
    warnings: &mut Vec<Warning>,
) {
    let Some(shares) = data
        .closed_loop
        .as_ref()
        .and_then(|c| c.derivative_percent.as_ref())
    else {
        return;
    };
    for (k, (what, flag)) in [
        ("velocity", &mut identifiable.damping),
        ("acceleration", &mut identifiable.inertia),
    ]
    .into_iter()
    .enumerate()
    {
        let low: Vec<String> = data
            .coordinates
            .iter()
            .zip(shares)
            .filter(|(_, s)| s[k] < MIN_REFERENCE_DRIVEN_DERIVATIVE)
            .map(|(c, s)| format!("{c} {:.0} %", s[k]))
            .collect();
        if low.is_empty() {
            continue;
        }
        *flag = false;
        let matrix = if k == 0 { "damping" } else { "inertia" };
        warnings.push(Warning::new(
            WarningCode::ClosedLoop,
            format!(
                "closed loop: the reference drives too little of the {what} ({}; below {MIN_REFERENCE_DRIVEN_DERIVATIVE:.0} %), so {matrix} is not identifiable from the motion it predicts: the rest is sensor noise or the subject's own motion",
                low.join(", ")
            ),
        ));
    }
}

/// Positions logged faster than they were measured (held or interpolated
/// samples, issue 56): their velocity and acceleration are steps and spikes
/// of the logging, not the limb's, and B and M came out 13-55 % low at tens
/// of standard errors while "trusted". Damping and inertia are then not
/// identifiable, and a warning says why; the noise was read at the measured rate.
fn distrust_derivatives_of_resampled_positions(
    data: &Prepared,
    identifiable: &mut Identifiable,
    warnings: &mut Vec<Warning>,
) {
    // coordinates resampled alike are named together: "x, y, z (each value held for 4 samples)"
    let mut groups: Vec<(String, Vec<&str>)> = Vec::new();
    for (c, r) in data.coordinates.iter().zip(&data.resampled) {
        let Some(r) = r else { continue };
        let how = r.describe();
        match groups.iter_mut().find(|(h, _)| *h == how) {
            Some((_, names)) => names.push(c),
            None => groups.push((how, vec![c])),
        }
    }
    if groups.is_empty() {
        return;
    }
    let found: Vec<String> = groups
        .iter()
        .map(|(how, names)| format!("{} ({how})", names.join(", ")))
        .collect();
    identifiable.damping = false;
    identifiable.inertia = false;
    warnings.push(Warning::new(
        WarningCode::ResampledSignal,
        format!(
            "positions logged faster than they were measured: {}; their velocity and acceleration are the logging's steps, so damping and inertia are not identifiable (position noise read at the measured rate); record at the sensor's own rate",
            found.join(", ")
        ),
    ));
}
