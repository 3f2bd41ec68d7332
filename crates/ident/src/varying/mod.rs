//! Impedance that varies (issue 38): with time during a repeated movement or
//! task, and with a measured operating point.
//!
//! - [`ensemble`]: time-varying identification from an ensemble of
//!   repetitions (Kearney & MacNeil's ensemble methods; the question of
//!   seed 003 §I, impedance that changes during movement). At each instant
//!   the deviations of the repetitions from their mean are regressed:
//!   `δf(t) = M(t) δx''(t) + B(t) δx'(t) + K(t) δx(t)`.
//! - [`scheduled`]: parameter-varying identification (Sobhani Tehrani &
//!   Kearney's parameter-varying parallel cascade): every parameter a smooth
//!   function of a scheduling variable σ, expanded in Chebyshev polynomials,
//!   all fitted in one least-squares problem over the whole record.
//!
//! Both report on a grid of the schedule, with standard errors, and mark the
//! points the data do not support as not identifiable instead of giving
//! numbers there.

pub mod ensemble;
pub mod gait;
pub mod scheduled;
mod settings;

pub use settings::{ScheduleAngle, VaryingParams, VaryingRequest};

use limpid_core::criteria::{
    matrix_criteria, matrix_verdict_within, tolerance, MatrixKind, MatrixVerdict, VAF_FLOOR_PERCENT,
};
use limpid_core::{Error, Matrix, Recording, Result};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The schedule name that asks for time-varying (ensemble) identification.
pub const TIME: &str = "time";

/// Highest Chebyshev order the cross-validation tries.
pub const MAX_BASIS_ORDER: usize = 6;

/// How the impedance was made to vary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum VaryingMethod {
    /// Ensemble of repetitions, one regression per instant.
    Ensemble,
    /// One regression, parameters expanded in a basis of the schedule.
    ParameterVarying,
    /// Walking: perturbed strides minus the unperturbed ones near them.
    Pulses,
}

/// The schedule the impedance is given against.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ScheduleAxis {
    /// `time since trial start` or the column's name.
    pub name: String,
    /// Its unit (`s`, or the column's FORMAT.md unit when known, else empty).
    pub unit: String,
    /// The grid: one value per point.
    pub values: Vec<f64>,
    /// Parameter-varying: what the schedule was read as to the coordinate's
    /// angle, in words (`--schedule-angle`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle: Option<String>,
}

/// The reflex pathway at one point of the schedule.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PointReflex {
    /// DC gain from half-wave rectified velocity to torque (N m s/rad).
    pub gain: f64,
    /// Its standard error.
    pub gain_se: f64,
    /// Reflex delay (s), shared by every point.
    pub delay_s: f64,
}

/// Impedance at one point of the schedule.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct VaryingPoint {
    /// Time (s) or the schedule's value.
    pub sigma: f64,
    /// The data support numbers here; the matrices are absent when not.
    pub identifiable: bool,
    /// Why not, when not identifiable.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// K (d x d).
    pub stiffness: Option<Matrix>,
    /// Standard error of each element of K.
    pub stiffness_se: Option<Matrix>,
    /// B (d x d).
    pub damping: Option<Matrix>,
    /// Standard error of each element of B.
    pub damping_se: Option<Matrix>,
    /// M or I (d x d).
    pub inertia: Option<Matrix>,
    /// Standard error of each element of M.
    pub inertia_se: Option<Matrix>,
    /// The reflex here (parameter-varying with `reflex`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reflex: Option<PointReflex>,
    /// VAF (%) of the force deviations explained here (the instant's window,
    /// or the samples whose schedule is nearest this point).
    pub vaf: Option<f64>,
    /// Ensemble: repetitions; parameter-varying: seconds of data near the point.
    pub support: f64,
    /// Ensemble: condition number of the scaled regressors in this window.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub condition_number: Option<f64>,
    /// Verdicts of K, B and M here, by the rules of every limpid matrix
    /// (the point's VAF, identified, passive, 2 SE within the tolerance).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verdicts: Option<PointVerdicts>,
}

impl VaryingPoint {
    /// A point the data give no number at, and why.
    pub(crate) fn unidentified(sigma: f64, reason: String, support: f64) -> Self {
        VaryingPoint {
            sigma,
            identifiable: false,
            reason: Some(reason),
            stiffness: None,
            stiffness_se: None,
            damping: None,
            damping_se: None,
            inertia: None,
            inertia_se: None,
            reflex: None,
            vaf: None,
            support,
            condition_number: None,
            verdicts: None,
        }
    }
}

/// How much wider than a single estimate's a point's standard error is taken
/// for its verdict (see [`PointVerdicts`]): 2 x 1.5 = 3 SE within the tolerance.
pub const POINT_SE_FACTOR: f64 = 1.5;

/// The verdicts of one point's matrices.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PointVerdicts {
    /// Of K.
    pub stiffness: MatrixVerdict,
    /// Of B.
    pub damping: MatrixVerdict,
    /// Of M.
    pub inertia: MatrixVerdict,
}

impl PointVerdicts {
    /// The verdicts of a point's matrices and their standard errors. A grid
    /// judges a hundred points where a single estimate judges one: at 2 SE
    /// about one trusted point in a few hundred came out beyond its tolerance
    /// by chance (`limpid calibrate`), so a point is judged at
    /// [`POINT_SE_FACTOR`] x 2 SE.
    pub(crate) fn of(matrices: [&Matrix; 6], vaf: Option<f64>) -> Self {
        Self::within(matrices, vaf, BENCH_TOLERANCES)
    }

    /// [`PointVerdicts::of`] against tolerances of their own (K, B, M;
    /// relative): walking's are [`gait::WALKING_TOLERANCES`].
    pub(crate) fn within(
        [k, ks, b, bs, m, ms]: [&Matrix; 6],
        vaf: Option<f64>,
        tolerances: [f64; 3],
    ) -> Self {
        let one = |tol, v: &Matrix, se: &Matrix| {
            let se = &Matrix(se.0.map(|x| x * POINT_SE_FACTOR));
            let d = v.nrows();
            let identified = (0..d).all(|i| v[(i, i)].abs() >= 2.0 * se[(i, i)]);
            let passive = matrix_criteria(v).positive_definite;
            let fit_ok = vaf.is_some_and(|x| x >= VAF_FLOOR_PERCENT);
            matrix_verdict_within(tol, v, se, fit_ok, identified, passive)
        };
        PointVerdicts {
            stiffness: one(tolerances[0], k, ks),
            damping: one(tolerances[1], b, bs),
            inertia: one(tolerances[2], m, ms),
        }
    }
}

/// Every limpid matrix's tolerances (K, B, M): what "trusted" promises.
pub const BENCH_TOLERANCES: [f64; 3] = [
    tolerance(MatrixKind::Stiffness),
    tolerance(MatrixKind::Damping),
    tolerance(MatrixKind::Inertia),
];

/// Fit quality over the whole record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct VaryingFit {
    /// VAF (%) of the force deviations.
    pub vaf: f64,
    /// VAF (%) predicting data left out (ensemble: each repetition from the
    /// others; parameter-varying: 10 contiguous blocks of the record).
    pub cross_validated_vaf: f64,
}

/// The reflex pathway of a parameter-varying fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct VaryingReflex {
    /// Delay (s), chosen by the least residual.
    pub delay_s: f64,
    /// Natural frequency of the unit-DC low-pass (Hz), chosen with the delay.
    pub natural_hz: f64,
    /// Its damping ratio (0.5 to 1, chosen with the natural frequency).
    pub damping_ratio: f64,
    /// `positive`: the reflex answers positive velocity; `negative`: negative.
    pub polarity: String,
    /// The data show a reflex: the gain differs from zero (Wald test on
    /// block-robust standard errors, p < 1e-4) and it raises the
    /// cross-validated VAF by at least [`REFLEX_MIN_GAIN_PERCENT`] points.
    pub detected: bool,
    /// Cross-validated VAF gained by the reflex pathway (percentage points).
    pub cross_validated_gain: f64,
    /// Wald statistic of "no reflex" and its degrees of freedom.
    pub wald: f64,
    /// Degrees of freedom of the Wald statistic.
    pub wald_dof: usize,
}

/// Least gain of cross-validated VAF (points) for a reflex to count as detected.
pub const REFLEX_MIN_GAIN_PERCENT: f64 = 0.5;

/// Impedance as a function of time or of an operating point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct VaryingEstimate {
    /// Ensemble or parameter-varying.
    pub method: VaryingMethod,
    /// The schedule and its grid.
    pub schedule: ScheduleAxis,
    /// Coordinates (positions), in order.
    pub coordinates: Vec<String>,
    /// Their forces or torques.
    pub forces: Vec<String>,
    /// Sample rate of the recording (Hz).
    pub sample_rate_hz: f64,
    /// Low-pass cut-off before differentiation (Hz).
    pub cutoff_hz: f64,
    /// Resolution along the schedule: ensemble, the window width (s); parameter-varying, range / (order + 1).
    pub resolution: f64,
    /// What the resolution means, in words.
    pub resolution_note: String,
    /// Ensemble: repetitions (strides) used; pulses: perturbations fitted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repetitions: Option<usize>,
    /// Parameter-varying: Chebyshev order of every parameter.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub basis_order: Option<usize>,
    /// Parameter-varying: cross-validated VAF (%) of each order tried (0, 1, ...).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub order_cv_vaf: Vec<f64>,
    /// The estimate at each grid point.
    pub points: Vec<VaryingPoint>,
    /// Overall fit.
    pub fit: VaryingFit,
    /// The reflex pathway (parameter-varying with `reflex`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reflex: Option<VaryingReflex>,
    /// Walking: the strides, the flawed events and the baseline.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gait: Option<gait::GaitSummary>,
    /// What a reader should know.
    pub warnings: Vec<String>,
}

/// Impedance that varies: `params.schedule == "time"` runs the ensemble
/// method on the recording's repetitions (`trial`), any other value the
/// parameter-varying method on that column.
///
/// # Example
///
/// A joint whose stiffness doubles for 150 ms in the middle of each of 100
/// repetitions, in the virtual lab without noise (the ensemble method):
///
/// ```
/// use limpid_ident::varying::{estimate_varying, VaryingParams};
/// use limpid_lab::varying::{simulate_ensemble, EnsembleExperiment, EnsembleSubject};
///
/// let joint = EnsembleSubject::joint();
/// let experiment = EnsembleExperiment { torque_noise_nm: 0.0, ..EnsembleExperiment::default() };
/// let rec = simulate_ensemble(&joint, &experiment, 1)?;
/// let est = estimate_varying(&rec, &VaryingParams::default())?;
/// let middle = est.points.iter().find(|p| p.identifiable && p.sigma >= 0.6).unwrap();
/// let k_true = joint.truth_at(middle.sigma)[2][0][0];
/// let k = middle.stiffness.as_ref().unwrap()[(0, 0)];
/// assert!((k - k_true).abs() < 0.03 * k_true, "{k} vs {k_true}");
/// # Ok::<(), limpid_core::Error>(())
/// ```
pub fn estimate_varying(rec: &Recording, params: &VaryingParams) -> Result<VaryingEstimate> {
    let (coords, forces) = crate::prepare::choose_coordinates(rec)?;
    // the force fitted cannot schedule itself: its perturbation response
    // moves the schedule with it (issue 56: K(tau1) came out "trusted")
    if forces.contains(&params.schedule) {
        return Err(Error::invalid(
            "schedule",
            format!(
                "{} is the force or torque being fitted; it cannot be its own schedule (its response to the perturbation moves the schedule too): schedule on an operating point recorded apart, e.g. a slowly varying angle or a background-torque column",
                params.schedule
            ),
        ));
    }
    if coords.len() > 3 {
        return Err(Error::invalid(
            "coordinates",
            format!("at most 3 coordinates, found {}", coords.len()),
        ));
    }
    // positions logged faster than they were measured: their measured samples (issue 58)
    let (rec, measured_rate) =
        crate::prepare::at_measured_rate(std::borrow::Cow::Borrowed(rec), &coords)?;
    // a closed-loop rig: the motion the commanded references drive (issue 79)
    let (rec, closed_loop) =
        crate::closed_loop::instrumented(rec, &coords, (params.open_loop, None))?;
    let rec = rec.as_ref();
    let cutoff = params
        .cutoff_hz
        .unwrap_or_else(|| crate::prepare::default_cutoff(rec.sample_rate()));
    if cutoff >= 0.5 * rec.sample_rate() {
        return Err(Error::invalid(
            "cutoff_hz",
            format!(
                "{} Hz is not below half the sample rate ({} Hz, the Nyquist frequency)",
                limpid_core::error::Num(cutoff),
                limpid_core::error::Num(0.5 * rec.sample_rate())
            ),
        ));
    }
    let mut estimate = if params.event.is_some() {
        gait::estimate(rec, params, coords, forces, cutoff)
    } else if params.schedule == TIME {
        ensemble::estimate(rec, params, coords, forces, cutoff)
    } else {
        scheduled::estimate(rec, params, coords, forces, cutoff)
    }?;
    estimate
        .warnings
        .extend(measured_rate.map(|m| m.warning().message));
    if let Some(closed) = closed_loop {
        estimate
            .warnings
            .extend(closed.warnings().into_iter().map(|w| w.message));
        if params.reflex {
            estimate.warnings.push(
                "closed loop: the reflex pathway was fitted on the predicted motion, which a nonlinear pathway makes only approximate (on the virtual ankle on servos of 10, 1.5 and 0.5 x its K a plug-in parallel cascade gave 90, 55 and 21 % of the reflex gain); estimate reflex fits it by instrumental variables".to_string(),
            );
        }
    }
    Ok(estimate)
}

/// Standard errors with `share` of each value's magnitude added in quadrature.
pub(crate) fn floored(value: &Matrix, se: Matrix, share: f64) -> Matrix {
    if share == 0.0 {
        return se;
    }
    matrix(value.nrows(), |i, j| {
        se[(i, j)].hypot(share * value[(i, j)].abs())
    })
}

/// A d x d matrix from a column-of-outputs layout: `at(j, k)` is row j, column k.
pub(crate) fn matrix(d: usize, at: impl Fn(usize, usize) -> f64) -> Matrix {
    Matrix(nalgebra::DMatrix::from_fn(d, d, at))
}

/// Solve the symmetric positive (semi)definite system `g θ = h` (h: q x d)
/// after Jacobi scaling; `None` when it is singular.
pub(crate) fn solve_scaled(
    g: &nalgebra::DMatrix<f64>,
    h: &nalgebra::DMatrix<f64>,
) -> Option<nalgebra::DMatrix<f64>> {
    let q = g.nrows();
    let s: Vec<f64> = (0..q)
        .map(|i| {
            let v = g[(i, i)];
            if v > 0.0 && v.is_finite() {
                1.0 / v.sqrt()
            } else {
                0.0
            }
        })
        .collect();
    if s.contains(&0.0) {
        return None;
    }
    let gs = nalgebra::DMatrix::from_fn(q, q, |i, j| g[(i, j)] * s[i] * s[j]);
    let hs = nalgebra::DMatrix::from_fn(q, h.ncols(), |i, j| h[(i, j)] * s[i]);
    let chol = nalgebra::Cholesky::new(gs)?;
    let y = chol.solve(&hs);
    let out = nalgebra::DMatrix::from_fn(q, h.ncols(), |i, j| y[(i, j)] * s[i]);
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// Inverse of a symmetric positive definite matrix after Jacobi scaling.
pub(crate) fn inverse_scaled(g: &nalgebra::DMatrix<f64>) -> Option<nalgebra::DMatrix<f64>> {
    solve_scaled(g, &nalgebra::DMatrix::identity(g.nrows(), g.nrows()))
}

/// Condition number of the Jacobi-scaled Gram matrix's square root (the
/// scaled regressors' condition number, seed 003 eq. (19)).
pub(crate) fn scaled_condition(g: &nalgebra::DMatrix<f64>) -> f64 {
    let q = g.nrows();
    let s: Vec<f64> = (0..q)
        .map(|i| 1.0 / g[(i, i)].max(f64::MIN_POSITIVE).sqrt())
        .collect();
    let gs = nalgebra::DMatrix::from_fn(q, q, |i, j| g[(i, j)] * s[i] * s[j]);
    match limpid_core::linalg::symmetric_eigenvalues(gs) {
        Some(ev) => {
            let max = ev.max();
            let min = ev.min();
            if min > 0.0 {
                (max / min).sqrt()
            } else {
                f64::INFINITY
            }
        }
        None => f64::INFINITY,
    }
}

/// A duration in ms for people: whole ms from 10 ms on, else one decimal.
pub(crate) fn round_ms(s: f64) -> String {
    let ms = s * 1e3;
    if ms >= 10.0 {
        format!("{ms:.0}")
    } else {
        format!("{ms:.1}")
    }
}

/// Velocity and acceleration by five-point central differences (error
/// O(dt⁴)): over records this long the standard errors are small enough
/// that the three-point stencils' O(dt²) loss at the perturbation's upper
/// frequencies shows as a bias of the damping. The two samples at each end
/// fall back to three-point differences.
pub(crate) fn derivatives(x: &[f64], dt: f64) -> (Vec<f64>, Vec<f64>) {
    let n = x.len();
    let mut v = limpid_dsp::central_first(x, dt);
    let mut a = limpid_dsp::central_second(x, dt);
    for t in 2..n.saturating_sub(2) {
        let (m2, m1, c, p1, p2) = (x[t - 2], x[t - 1], x[t], x[t + 1], x[t + 2]);
        v[t] = (m2 - 8.0 * m1 + 8.0 * p1 - p2) / (12.0 * dt);
        a[t] = (-m2 + 16.0 * m1 - 30.0 * c + 16.0 * p1 - p2) / (12.0 * dt * dt);
    }
    (v, a)
}
