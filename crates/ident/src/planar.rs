//! Planar two-link arm in joint space (seed 003).
//!
//! Model, eq. (9): `M(q, ξ) q'' + (C(q, q', ξ) + D) q' + K Δq = Δτ_ext` with
//! `M = [[ξ1 + 2 ξ2 cos q2, ξ3 + ξ2 cos q2], [ξ3 + ξ2 cos q2, ξ3]]`, q1 the
//! shoulder and q2 the relative elbow angle. The regressor rows are eq. (13)
//! (11 parameters: ξ1..ξ3, D11, D12, D21, D22, K11, K12, K21, K22); with known ξ
//! the reduced model eq. (23)-(25) has 8.
//!
//! Data: joint-space recordings (`q1,q2,tau1,tau2`) or end-point recordings
//! (`x,y,fx,fy`), converted by analytical inverse kinematics (elbow branch
//! q2 > 0, i.e. the elbow flexed, unless told otherwise) and `τ = J(q)^T F`
//! (§IV-C). Per trial, `q0` and `τ0` are the means over the pre-onset rest;
//! angles and torques get the same zero-phase low-pass (each window end
//! extended by the reflection that keeps it consistent), derivatives by
//! central differences. The observation window of a trial runs from the
//! perturbation onset for `T_obs` (seed 003 Fig. 3).
//!
//! Criteria (§III-C): condition number of W (eq. (19), reported both for W
//! as is and with unit-RMS columns), positive definiteness of the symmetric
//! parts of K and D (eq. (20)), and the symmetry ratio ||X_a|| / ||X_s|| of K
//! and D (eq. (22)). Verdict "trusted" when the scaled condition number is
//! below 1000, K_s and D_s are positive definite and both ratios are below 0.1
//! ("quasi-symmetric", our threshold).

use limpid_core::criteria::{
    judge_matrix, tolerance, MatrixKind, MatrixVerdict, Verdicts, VAF_FLOOR_PERCENT,
};
use limpid_core::Matrix;
use nalgebra::{DMatrix, DVector, Matrix2, Vector2};
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::linear::{fit_stats, solve_triangle};
use crate::lsq::{merge, triangle};
use crate::prepare::edge_kinds;
pub use limpid_core::arm::{coriolis, mass_matrix, Arm};
use limpid_core::trial::{change_floors, detect_onset, noise_sigma, windows_from_trial_column};
use limpid_core::{Error, Recording, Result};
use limpid_dsp::{central_first, central_second, LowPass};

/// Regressor rows X (2 x 11) of eq. (13) at one sample.
pub fn regressor(q2: f64, qd: [f64; 2], qdd: [f64; 2], dq: [f64; 2]) -> [[f64; 11]; 2] {
    let (s, c) = q2.sin_cos();
    let mut x = [[0.0; 11]; 2];
    x[0][0] = qdd[0];
    x[0][1] = (2.0 * qdd[0] + qdd[1]) * c - (2.0 * qd[0] * qd[1] + qd[1] * qd[1]) * s;
    x[0][2] = qdd[1];
    x[1][1] = qdd[0] * c + qd[0] * qd[0] * s;
    x[1][2] = qdd[0] + qdd[1];
    x[0][3] = qd[0];
    x[0][4] = qd[1];
    x[1][5] = qd[0];
    x[1][6] = qd[1];
    x[0][7] = dq[0];
    x[0][8] = dq[1];
    x[1][9] = dq[0];
    x[1][10] = dq[1];
    x
}

/// One prepared trial: samples from the perturbation onset to the end of the window.
#[derive(Debug, Clone)]
pub struct PlanarTrial {
    /// Trial id (the recording's `trial` column).
    pub id: i64,
    /// Joint angles q1, q2 (rad).
    pub q: [Vec<f64>; 2],
    /// Joint velocities (rad/s).
    pub qd: [Vec<f64>; 2],
    /// Joint accelerations (rad/s^2).
    pub qdd: [Vec<f64>; 2],
    /// Δq = q - q0.
    pub dq: [Vec<f64>; 2],
    /// Δτ = τ - τ0.
    pub dtau: [Vec<f64>; 2],
    /// Posture before the onset: mean over the rest (rad).
    pub q0: [f64; 2],
    /// Joint torques before the onset: mean over the rest (N m).
    pub tau0: [f64; 2],
}

/// Preparation settings of planar data.
///
/// | Name | Default | Purpose | Range |
/// |---|---|---|---|
/// | `arm` | required | link lengths, shoulder | l1, l2 > 0 |
/// | `cutoff_hz` | 30 Hz (at most 0.4 fs) | zero-phase low-pass of angles and torques | (0, fs/2) |
/// | `order` | 4 | Butterworth order | 1..=20 |
/// | `elbow_positive` | true | inverse-kinematics branch for end-point data | |
#[derive(Debug, Clone)]
pub struct PlanarPrepare {
    /// Link lengths and shoulder position.
    pub arm: Arm,
    /// Low-pass cut-off (Hz); `None`: 30 Hz, at most 0.4 fs.
    pub cutoff_hz: Option<f64>,
    /// Butterworth order.
    pub order: usize,
    /// Elbow branch of the inverse kinematics: q2 > 0 (flexed).
    pub elbow_positive: bool,
}

impl PlanarPrepare {
    /// Link lengths (m), shoulder at the origin, the elbow flexed (q2 > 0),
    /// the default low-pass and a 4th-order Butterworth.
    pub fn new(l1: f64, l2: f64) -> Self {
        PlanarPrepare {
            arm: Arm {
                l1,
                l2,
                shoulder: [0.0, 0.0],
            },
            cutoff_hz: None,
            order: 4,
            elbow_positive: true,
        }
    }
}

/// Prepared planar data.
#[derive(Debug, Clone)]
pub struct PlanarData {
    /// The recording's path.
    pub path: std::path::PathBuf,
    /// Sample rate (Hz).
    pub fs: f64,
    /// The arm the data were converted with.
    pub arm: Arm,
    /// Prepared trials.
    pub trials: Vec<PlanarTrial>,
    /// True when the recording held end-point data converted to joint space.
    pub from_endpoint: bool,
    /// Low-pass cut-off used (Hz).
    pub cutoff_hz: f64,
}

impl PlanarData {
    /// Longest observation window available in every trial (s).
    pub fn max_window_s(&self) -> f64 {
        self.trials.iter().map(|t| t.dq[0].len()).min().unwrap_or(0) as f64 / self.fs
    }
}

/// The longest a torque may lead the motion and still mark the onset (s);
/// physically the torque leads by the few ms the quintic needs to move the
/// angles out of their noise band.
pub const ONSET_LEAD_S: f64 = 0.03;

/// Convert, cut into trials, take baselines, filter and differentiate.
pub fn prepare_planar(rec: &Recording, p: &PlanarPrepare) -> Result<PlanarData> {
    let fs = rec.sample_rate();
    let arm = p.arm;
    // a human arm's segments: a 4.9e-324 m forearm made every end-point
    // stiffness null (issue 36)
    if ![arm.l1, arm.l2]
        .iter()
        .all(|l| (MIN_LINK_M..=MAX_LINK_M).contains(l))
    {
        return Err(Error::invalid(
            "link lengths",
            format!(
                "expected two lengths from {MIN_LINK_M} to {MAX_LINK_M} m, found {}, {}",
                arm.l1, arm.l2
            ),
        ));
    }
    // the recordings' own position limit
    let (limit, _) = limpid_core::recording::magnitude_limit("x");
    if !arm
        .shoulder
        .iter()
        .all(|v| v.is_finite() && v.abs() <= limit)
    {
        return Err(Error::invalid(
            "shoulder",
            format!(
                "expected a position within {limit} m, found {}, {}",
                arm.shoulder[0], arm.shoulder[1]
            ),
        ));
    }
    let from_endpoint = !rec.has("q1");
    if from_endpoint {
        if let (Some(x), Some(y), Some(z)) = (rec.column("x"), rec.column("y"), rec.column("z")) {
            let range = |c: &[f64]| {
                let (lo, hi) = c
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                        (l.min(*v), h.max(*v))
                    });
                hi - lo
            };
            let (rz, rxy) = (range(z), range(x).max(range(y)));
            if rz > 0.1 * rxy {
                return Err(Error::Format {
                    path: rec.path().to_path_buf(),
                    message: format!(
                        "the end point moves in z (range {rz:.4} m against {rxy:.4} m in x, y): a planar estimate would ignore that motion; use estimate linear for 3-D data"
                    ),
                });
            }
        }
    }
    let (q, tau): ([Vec<f64>; 2], [Vec<f64>; 2]) = if from_endpoint {
        let x = rec.require("x", "end-point position (or give q1,q2 joint angles)")?;
        let y = rec.require("y", "end-point position")?;
        let fx = rec.require("fx", "end-point force")?;
        let fy = rec.require("fy", "end-point force")?;
        let mut q = [Vec::with_capacity(rec.len()), Vec::with_capacity(rec.len())];
        let mut tau = [Vec::with_capacity(rec.len()), Vec::with_capacity(rec.len())];
        for i in 0..rec.len() {
            let qi = arm.ik([x[i], y[i]], p.elbow_positive).ok_or_else(|| Error::Numerical {
                path: rec.path().to_path_buf(),
                message: format!(
                    "row {}, columns x,y: ({}, {}) is out of reach of links {} + {} m from the shoulder at ({}, {})",
                    rec.row_of(i), x[i], y[i], arm.l1, arm.l2, arm.shoulder[0], arm.shoulder[1]
                ),
            })?;
            let t = arm.jacobian(qi).transpose() * Vector2::new(fx[i], fy[i]);
            for k in 0..2 {
                q[k].push(qi[k]);
                tau[k].push(t[k]);
            }
        }
        (q, tau)
    } else {
        let get = |n: &str, why: &str| rec.require(n, why).map(<[f64]>::to_vec);
        (
            [
                get("q1", "shoulder angle")?,
                get("q2", "relative elbow angle")?,
            ],
            [
                get("tau1", "shoulder torque")?,
                get("tau2", "elbow torque")?,
            ],
        )
    };
    let cutoff = p
        .cutoff_hz
        .unwrap_or_else(|| crate::prepare::default_cutoff(fs));
    let lp = LowPass::butterworth(p.order, cutoff, fs)?;
    let signals: Vec<&[f64]> = vec![&q[0], &q[1], &tau[0], &tau[1]];
    let sigmas: Vec<f64> = signals.iter().map(|c| noise_sigma(c)).collect();
    let floors = change_floors(&signals);
    let windows = windows_from_trial_column(rec, "trial")?;
    let dt = 1.0 / fs;
    let min_rest = ((0.02 * fs).round() as usize).max(3);
    let qs: Vec<&[f64]> = vec![&q[0], &q[1]];
    let trials = windows
        .iter()
        .map(|w| {
            let r = w.range.clone();
            // Onset: the first of the angles and torques to leave rest, as
            // long as the torque leads the motion by at most ONSET_LEAD_S.
            // A torque that leaves earlier is the subject's slow force
            // fluctuation or grip drift, not the perturbation: the angles
            // (the robot's motion) decide then.
            let lead_max = (ONSET_LEAD_S * fs).round() as usize;
            let any = detect_onset(&signals, r.clone(), &sigmas, &floors);
            let motion = detect_onset(&signals[..2], r.clone(), &sigmas[..2], &floors[..2]);
            let onset = match (any, motion) {
                (Some(a), Some(m)) if m - a <= lead_max => a,
                (_, Some(m)) => {
                    // refine with the torques against their level just before
                    // the lead window (the fluctuation moves little in 40 ms)
                    let from = m.saturating_sub(lead_max + 10).max(r.start);
                    match detect_onset(&signals, from..r.end, &sigmas, &floors) {
                        Some(a) if a + lead_max >= m && a >= from + 10 => a,
                        _ => m,
                    }
                }
                (a, None) => a.unwrap_or(r.end),
            };
            if onset - r.start < min_rest {
                return Err(Error::NoRestBeforeOnset {
                    path: rec.path().to_path_buf(),
                    row: rec.row_of(r.start),
                    column: "trial".into(),
                    trial: w.id,
                    rest_samples: onset - r.start,
                    needed: min_rest,
                });
            }
            if r.len() <= lp.padlen() + 1 {
                return Err(Error::TooFewSamples {
                    path: rec.path().to_path_buf(),
                    what: format!("trial {} with zero-phase filtering", w.id),
                    needed: lp.padlen() + 2,
                    found: r.len(),
                });
            }
            let rest_end = onset.saturating_sub(2).max(r.start + 1);
            let span = ((fs / cutoff).round() as usize).max(3);
            let (left, right) = edge_kinds(&qs, r.clone(), span, dt);
            let extra = ((3.0 * fs / cutoff).round() as usize).min(r.len() - 1);
            let mut t = PlanarTrial {
                id: w.id,
                q: Default::default(),
                qd: Default::default(),
                qdd: Default::default(),
                dq: Default::default(),
                dtau: Default::default(),
                q0: [0.0; 2],
                tau0: [0.0; 2],
            };
            let start = onset - r.start;
            for k in 0..2 {
                let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
                t.q0[k] = mean(&q[k][r.start..rest_end]);
                t.tau0[k] = mean(&tau[k][r.start..rest_end]);
                let qf = lp.filtfilt_edges(&q[k][r.clone()], left, right, extra)?;
                let tf = lp.filtfilt_edges(&tau[k][r.clone()], left, right, extra)?;
                let qd = central_first(&qf, dt);
                let qdd = central_second(&qf, dt);
                t.dq[k] = qf[start..].iter().map(|v| v - t.q0[k]).collect();
                t.dtau[k] = tf[start..].iter().map(|v| v - t.tau0[k]).collect();
                t.q[k] = qf[start..].to_vec();
                t.qd[k] = qd[start..].to_vec();
                t.qdd[k] = qdd[start..].to_vec();
            }
            Ok(t)
        })
        .collect::<Result<Vec<_>>>()?;
    if trials.len() < 2 {
        return Err(Error::TooFewSamples {
            path: rec.path().to_path_buf(),
            what: "a planar estimate (trials)".into(),
            needed: 2,
            found: trials.len(),
        });
    }
    Ok(PlanarData {
        path: rec.path().to_path_buf(),
        fs,
        arm,
        trials,
        from_endpoint,
        cutoff_hz: cutoff,
    })
}

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
    /// ξ1..ξ3 (kg m^2); the given values when fixed.
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
    /// Of ξ1..ξ3 (kg m^2); zeros when given.
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
fn trial_rows(t: &PlanarTrial, n: usize, xi: Option<[f64; 3]>) -> DMatrix<f64> {
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

/// Largest base inertial parameter limpid accepts (kg m^2): a human arm's
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
            "inertial parameters",
            format!(
                "expected three positive values up to {MAX_INERTIAL_PARAMETER} kg m^2, found {}, {}, {}",
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
    let BlockSolution {
        theta,
        condition_number_scaled: cond_scaled,
        replicates: reps,
        ..
    } = solve_blocks(&blocks).map_err(numerical)?;
    let gn = reps.len() as f64;
    let mean = reps.iter().fold(DVector::zeros(p), |a, t| a + t) / gn.max(1.0);
    let se = (reps
        .iter()
        .fold(DVector::zeros(p), |a, t| a + (t - &mean).map(|v| v * v))
        * ((gn - 1.0) / gn.max(1.0)))
    .map(f64::sqrt);
    // unscaled condition number of W (eq. (19))
    let raw_tris: Vec<DMatrix<f64>> = blocks
        .iter()
        .map(|b| triangle(b.columns(0, p).into_owned(), p))
        .collect();
    let raw = limpid_core::linalg::singular_values(merge(raw_tris.iter(), p))
        .unwrap_or_else(|| DVector::from_element(p, f64::NAN));
    let condition_number = raw.max() / raw.min();
    let off = if xi.is_some() { 0 } else { 3 };
    let (xi_hat, xi_se) = match xi {
        Some(x) => (x, [0.0; 3]),
        None => ([theta[0], theta[1], theta[2]], [se[0], se[1], se[2]]),
    };
    let m2 =
        |v: &DVector<f64>, s: usize| Matrix::from(Matrix2::new(v[s], v[s + 1], v[s + 2], v[s + 3]));
    let damping = m2(&theta, off);
    let stiffness = m2(&theta, off + 4);
    // fit
    let mut fit = PlanarFit {
        vaf: [0.0; 2],
        r: [0.0; 2],
    };
    // every k-th sample of the concatenated windows goes to the traces
    let stride = (rows / 2).div_ceil(crate::linear::TRACE_POINTS).max(1);
    let mut traces = crate::linear::FitTraces {
        time: (0..rows / 2)
            .step_by(stride)
            .map(|i| i as f64 / data.fs)
            .collect(),
        measured: vec![Vec::new(), Vec::new()],
        predicted: vec![Vec::new(), Vec::new()],
    };
    for r in 0..2 {
        let (mut y, mut yh) = (Vec::with_capacity(rows / 2), Vec::with_capacity(rows / 2));
        for b in &blocks {
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
            "inertial parameters not physical (xi = {:.4}, {:.4}, {:.4} kg m^2; all must be positive)",
            xi_hat[0], xi_hat[1], xi_hat[2]
        ));
    }
    let q0 = {
        let n = data.trials.len() as f64;
        [
            data.trials.iter().map(|t| t.q0[0]).sum::<f64>() / n,
            data.trials.iter().map(|t| t.q0[1]).sum::<f64>() / n,
        ]
    };
    let j = data.arm.jacobian(q0);
    let kx = match j.try_inverse() {
        Some(ji) => {
            let k = stiffness.to_matrix2().unwrap_or_else(Matrix2::zeros);
            Matrix::from(ji.transpose() * k * ji)
        }
        None => {
            return Err(numerical(
                "the arm is singular (stretched) at q0: no end-point stiffness".into(),
            ))
        }
    };
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

/// Fewest samples of each trial in an observation window: the derivatives
/// and the 11 parameters need the motion, not a few points of it.
pub const MIN_WINDOW_SAMPLES: usize = 10;

/// Seed 003's estimate from every trial's first `window` samples, with its
/// leave-one-trial-out validation.
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

/// One observation window of the sweep.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct SweepRow {
    /// T_obs (ms).
    pub observation_window_ms: f64,
    /// The estimate from this window.
    pub estimate: PlanarEstimate,
    /// Whether this window's estimate may be used (see `Sweep::trust_definition`).
    pub trusted: bool,
    /// Why not, one sentence per failed condition (empty when trusted).
    pub reasons: Vec<String>,
}

/// One interpolation interval of seed 003's experiment (§IV): the trials
/// whose perturbation lasted T_k, observed over T_obs = T_k + 70 ms.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct IntervalRow {
    /// T_k (ms), measured from the trials' motion and rounded to 10 ms.
    pub interpolation_ms: f64,
    /// T_obs = T_k + 70 ms (shorter when the trials end sooner).
    pub observation_window_ms: f64,
    /// Trials with this T_k.
    pub trials: usize,
    /// The estimate from these trials and this window.
    pub estimate: PlanarEstimate,
    /// The estimate's criteria met (with precision) and the window ends
    /// before any change of K or D within the trials.
    pub trusted: bool,
    /// Why not, one sentence per failed condition (empty when trusted).
    pub reasons: Vec<String>,
}

/// Observation after the end of the interpolation (seed 003: T_obs = T_k + 70 ms).
pub const OBSERVATION_AFTER_INTERPOLATION_MS: f64 = 70.0;
/// Fewest trials of one T_k for its own estimate.
pub const MIN_TRIALS_PER_INTERVAL: usize = 4;
/// Share of the speed peak that marks the start and end of a trial's motion.
const MOTION_SPEED_SHARE: f64 = 0.05;

/// A trial's interpolation interval T_k (s), from its joint speed: seed
/// 003's quintic `s(τ) = 10τ³ - 15τ⁴ + 6τ⁵` moves faster than 5 % of its
/// peak speed for a share `1 - 2τ₅` of T_k, with `30τ₅²(1-τ₅)² = 0.05 ×
/// 30/16`; T_k is that span divided by the share. None when the motion does
/// not settle within the trial.
pub fn interpolation_interval_s(t: &PlanarTrial, fs: f64) -> Option<f64> {
    let speed: Vec<f64> = (0..t.qd[0].len())
        .map(|i| t.qd[0][i].hypot(t.qd[1][i]))
        .collect();
    let (peak_at, peak) = speed
        .iter()
        .copied()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    if peak.is_nan() || peak <= 0.0 {
        return None;
    }
    let level = MOTION_SPEED_SHARE * peak;
    let start = (0..peak_at)
        .rev()
        .find(|&i| speed[i] < level)
        .map_or(0, |i| i + 1);
    let end = (peak_at..speed.len()).find(|&i| speed[i] < level)?;
    // τ(1-τ) = sqrt(share × 30/16 / 30) at the 5 % crossings
    let tau = (1.0 - (1.0 - 4.0 * (MOTION_SPEED_SHARE / 16.0).sqrt()).sqrt()) / 2.0;
    Some((end - start) as f64 / fs / (1.0 - 2.0 * tau))
}

/// Seed 003's T_k study: the trials grouped by their interpolation interval
/// (rounded to 10 ms), each group fitted over T_obs = T_k + 70 ms. Empty
/// unless the recording holds at least two intervals with
/// [`MIN_TRIALS_PER_INTERVAL`] trials each.
///
/// Each group gets its own search for a change of K or D within its trials
/// ([`impedance_change`] on split times `step` samples apart), since fast
/// and slow perturbations mixed in one fit do not share one model.
pub fn interval_sweep(data: &PlanarData, xi: Option<[f64; 3]>, step: usize) -> Vec<IntervalRow> {
    let mut groups: std::collections::BTreeMap<i64, Vec<usize>> = Default::default();
    for (i, t) in data.trials.iter().enumerate() {
        if let Some(tk) = interpolation_interval_s(t, data.fs) {
            groups
                .entry((tk * 100.0).round() as i64)
                .or_default()
                .push(i);
        }
    }
    groups.retain(|_, v| v.len() >= MIN_TRIALS_PER_INTERVAL);
    if groups.len() < 2 {
        return Vec::new();
    }
    let groups: Vec<(i64, Vec<usize>)> = groups.into_iter().collect();
    groups
        .par_iter()
        .filter_map(|(tk_cs, trials)| {
            let tk_ms = *tk_cs as f64 * 10.0;
            let shortest = trials
                .iter()
                .map(|&i| data.trials[i].dq[0].len())
                .min()
                .unwrap_or(0);
            let n = (((tk_ms + OBSERVATION_AFTER_INTERPOLATION_MS) * data.fs / 1000.0).round()
                as usize)
                .min(shortest);
            let estimate = PlanarEstimate {
                traces: None,
                ..fit_planar(data, n, xi, trials).ok()?
            };
            let window_ms = estimate.observation_window_ms;
            let mut reasons = estimate.criteria.reasons.clone();
            let change = impedance_change(data, trials, shortest, step, xi);
            if let Some(c) = change.filter(|c| window_ms > c.onset_ms) {
                reasons.push(format!(
                    "the window reaches past a change of the impedance at {:.0} ms (a reflex?)",
                    c.onset_ms
                ));
            }
            Some(IntervalRow {
                interpolation_ms: tk_ms,
                observation_window_ms: window_ms,
                trials: trials.len(),
                trusted: estimate.criteria.trusted && reasons.is_empty(),
                reasons,
                estimate,
            })
        })
        .collect()
}

/// A change of the joint impedance within the trials, such as a stretch
/// reflex: K and D fitted separately before and after `onset_ms` differ by
/// more than the tolerance and by more than 3 jackknife standard errors.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct ImpedanceChange {
    /// Time after the perturbation onset at which the change is clearest (ms).
    pub onset_ms: f64,
    /// ||K_after - K_before|| / ||K_before|| (relative Frobenius norm).
    pub stiffness_change: f64,
    /// The same for D.
    pub damping_change: f64,
    /// The clearer of the two changes over its jackknife standard error.
    pub z: f64,
}

/// The observation-window study (seed 003 §IV, Fig. 4-5).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Sweep {
    /// One row per observation window.
    pub rows: Vec<SweepRow>,
    /// Shortest T_obs from which K_s stays positive definite.
    pub min_positive_definite_ms: Option<f64>,
    /// Shortest T_obs from which K and D stay quasi-symmetric.
    pub min_quasi_symmetric_ms: Option<f64>,
    /// Shortest T_obs from which every parameter group stays quasi-constant.
    pub min_quasi_constant_ms: Option<f64>,
    /// How "quasi-constant" is defined.
    pub quasi_constant_definition: String,
    /// Leave-one-trial-out VAF (%) per joint at the longest window.
    pub leave_one_out_vaf: [f64; 2],
    /// Shortest trusted window (ms); none when no window earns trust.
    pub shortest_trusted_ms: Option<f64>,
    /// A change of K or D within the trials (a reflex), when the data show one.
    pub impedance_change: Option<ImpedanceChange>,
    /// What "trusted" means for a window.
    pub trust_definition: String,
    /// Seed 003's T_k study ([`interval_sweep`]), when the recording holds
    /// several interpolation intervals.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub intervals: Vec<IntervalRow>,
}

/// Relative precision a trusted window needs: twice the standard error of K
/// within 10 % of K (relative Frobenius norm), of D within 25 % of D.
pub const SWEEP_TOLERANCE_K: f64 = 0.10;
/// The same for D.
pub const SWEEP_TOLERANCE_D: f64 = 0.25;
/// Windows this close (ms) count as neighbours for the stability test.
pub const NEIGHBOURHOOD_MS: f64 = 10.0;
/// Jackknife z above which a change of K or D within the trials is real.
pub const CHANGE_Z: f64 = 3.0;

/// Columns of the split model: `trial_rows` with D and K duplicated into a
/// "before sample `split`" and an "after" copy (xi shared).
fn split_rows(t: &PlanarTrial, n: usize, split: usize, xi: Option<[f64; 3]>) -> DMatrix<f64> {
    let base = trial_rows(t, n, xi);
    let p = base.ncols() - 1;
    let first = p - 8;
    let mut a = DMatrix::<f64>::zeros(base.nrows(), p + 9);
    for row in 0..base.nrows() {
        for c in 0..first {
            a[(row, c)] = base[(row, c)];
        }
        let off = if row / 2 < split { first } else { first + 8 };
        for c in 0..8 {
            a[(row, off + c)] = base[(row, first + c)];
        }
        a[(row, p + 8)] = base[(row, p)];
    }
    a
}

/// Least squares on per-trial blocks `[W | y]` (columns scaled to unit RMS,
/// tall-skinny QR), with delete-one-trial jackknife replicates.
struct BlockSolution {
    theta: DVector<f64>,
    condition_number_scaled: f64,
    replicates: Vec<DVector<f64>>,
}

fn solve_blocks(blocks: &[DMatrix<f64>]) -> std::result::Result<BlockSolution, String> {
    let q = blocks.first().map_or(1, |b| b.ncols());
    let p = q - 1;
    let rows: usize = blocks.iter().map(|b| b.nrows()).sum();
    let mut scales = vec![0.0; q];
    for b in blocks {
        for (j, s) in scales.iter_mut().enumerate() {
            *s += b.column(j).norm_squared();
        }
    }
    for s in &mut scales {
        *s = (*s / rows.max(1) as f64).sqrt();
        if *s == 0.0 {
            *s = 1.0;
        }
    }
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
    // the linear estimator's triangle solver, with one right-hand side and no noise compensation
    let no_noise = DMatrix::<f64>::zeros(p, p);
    let solve = |r_aug: &DMatrix<f64>| {
        solve_triangle(r_aug, p, 1, &scales, &no_noise, rows as f64)
            .map(|s| (s.theta.column(0).into_owned(), s.condition_number))
            .map_err(|_| "the observation matrix W is rank-deficient: the perturbations do not excite every parameter".to_string())
    };
    let (theta, condition_number_scaled) = solve(&merge(tris.iter(), q))?;
    let replicates: Vec<DVector<f64>> = crate::lsq::leave_one_out(&tris, q)
        .par_iter()
        .filter_map(|t| solve(t).ok().map(|s| s.0))
        .collect();
    Ok(BlockSolution {
        theta,
        condition_number_scaled,
        replicates,
    })
}

/// Jackknife standard deviation of replicate values.
fn jackknife_sd(values: &[f64]) -> f64 {
    let g = values.len() as f64;
    if g < 2.0 {
        return f64::INFINITY;
    }
    let mean = values.iter().sum::<f64>() / g;
    ((g - 1.0) / g * values.iter().map(|v| (v - mean).powi(2)).sum::<f64>()).sqrt()
}

/// Scan the split time over the longest window: where K or D before and
/// after differ most clearly (seed 003 §IV: reflexes bound the observation
/// window). None when no split shows a change beyond the tolerance and
/// [`CHANGE_Z`] jackknife standard errors.
pub fn impedance_change(
    data: &PlanarData,
    trials: &[usize],
    longest: usize,
    step: usize,
    xi: Option<[f64; 3]>,
) -> Option<ImpedanceChange> {
    let margin = ((0.03 * data.fs).round() as usize).max(1);
    let first = if xi.is_some() { 0 } else { 3 };
    let rel = |th: &DVector<f64>, before: usize| {
        let b = th.rows(before, 4);
        (th.rows(before + 8, 4) - b).norm() / b.norm().max(1e-300)
    };
    let splits: Vec<usize> = (margin..=longest.saturating_sub(margin))
        .step_by(step.max(1))
        .collect();
    splits
        .par_iter()
        .filter_map(|&split| {
            let blocks: Vec<DMatrix<f64>> = trials
                .iter()
                .map(|&i| split_rows(&data.trials[i], longest, split, xi))
                .collect();
            let sol = solve_blocks(&blocks).ok()?;
            // relative jackknife SE of the 4 parameters from `at` (||SE|| / ||value||)
            let rel_se = |at: usize| {
                let var: f64 = (at..at + 4)
                    .map(|j| {
                        let v: Vec<f64> = sol.replicates.iter().map(|t| t[j]).collect();
                        jackknife_sd(&v).powi(2)
                    })
                    .sum();
                var.sqrt() / sol.theta.rows(at, 4).norm().max(1e-300)
            };
            // a change counts only between two precise estimates: a part
            // without motion (the hold) or only a few samples long identifies nothing
            let precise =
                |at: usize, tol: f64| rel_se(at) <= tol / 2.0 && rel_se(at + 8) <= tol / 2.0;
            let (k, d) = (rel(&sol.theta, first + 4), rel(&sol.theta, first));
            let kr: Vec<f64> = sol.replicates.iter().map(|t| rel(t, first + 4)).collect();
            let dr: Vec<f64> = sol.replicates.iter().map(|t| rel(t, first)).collect();
            let zk = if k > SWEEP_TOLERANCE_K / 2.0 && precise(first + 4, SWEEP_TOLERANCE_K) {
                k / jackknife_sd(&kr)
            } else {
                0.0
            };
            let zd = if d > SWEEP_TOLERANCE_D / 2.0 && precise(first, SWEEP_TOLERANCE_D) {
                d / jackknife_sd(&dr)
            } else {
                0.0
            };
            let z = zk.max(zd);
            (z > CHANGE_Z).then(|| ImpedanceChange {
                onset_ms: 1000.0 * split as f64 / data.fs,
                stiffness_change: k,
                damping_change: d,
                z,
            })
        })
        .max_by(|a, b| a.z.total_cmp(&b.z))
}

/// Relative change below which a parameter group counts as constant.
pub const QUASI_CONSTANT: f64 = 0.05;

/// Estimates over T_obs = from..=to in steps (ms), each with its criteria.
pub fn window_sweep(
    data: &PlanarData,
    from_ms: f64,
    to_ms: f64,
    step_ms: f64,
    xi: Option<[f64; 3]>,
) -> Result<Sweep> {
    if let Some(xi) = &xi {
        check_inertial_parameters(xi)?;
    }
    if !(from_ms > 0.0 && step_ms > 0.0 && to_ms >= from_ms) {
        return Err(Error::invalid(
            "window range",
            format!(
                "expected 0 < from <= to and step > 0, found {from_ms}..{to_ms} step {step_ms} ms"
            ),
        ));
    }
    let max_ms = 1000.0 * data.max_window_s();
    let count = (to_ms.min(max_ms) - from_ms) / step_ms;
    if count > MAX_SWEEP_WINDOWS as f64 {
        return Err(Error::invalid(
            "window range",
            format!("{from_ms}..{to_ms} ms in steps of {step_ms} ms makes {count:.3e} windows; at most {MAX_SWEEP_WINDOWS}"),
        ));
    }
    let mut windows = Vec::new();
    let mut t = from_ms;
    while t <= to_ms.min(max_ms) + 1e-9 {
        windows.push(t);
        t += step_ms;
    }
    if windows.is_empty() {
        return Err(Error::invalid(
            "window range",
            format!("the trials hold only {max_ms:.0} ms after the onset, less than {from_ms} ms"),
        ));
    }
    let all: Vec<usize> = (0..data.trials.len()).collect();
    let rows: Vec<SweepRow> = windows
        .par_iter()
        .filter_map(|ms| {
            let n = (ms * data.fs / 1000.0).round() as usize;
            // the traces of 36 windows would only bloat the sweep's JSON
            fit_planar(data, n, xi, &all).ok().map(|estimate| SweepRow {
                observation_window_ms: *ms,
                estimate: PlanarEstimate {
                    traces: None,
                    ..estimate
                },
                trusted: false,
                reasons: Vec::new(),
            })
        })
        .collect();
    let mut rows = rows;
    let longest = rows.last().map_or(0, |r| {
        (r.observation_window_ms * data.fs / 1000.0).round() as usize
    });
    // split times on a grid of the sweep's step, at least 10 ms
    let step = ((step_ms.max(10.0) * data.fs / 1000.0).round() as usize).max(1);
    let change = impedance_change(data, &all, longest, step, xi);
    judge_windows(&mut rows, change.as_ref());
    let from_which = |ok: &dyn Fn(&PlanarEstimate) -> bool| -> Option<f64> {
        let mut first = None;
        for r in rows.iter().rev() {
            if ok(&r.estimate) {
                first = Some(r.observation_window_ms);
            } else {
                break;
            }
        }
        first
    };
    let last = rows.last().map(|r| r.estimate.clone());
    let rel = |a: &Matrix, b: &Matrix| (&a.0 - &b.0).norm() / b.norm().max(1e-300);
    let constant = |e: &PlanarEstimate| match &last {
        Some(l) => {
            let xi_change = (0..3)
                .map(|i| (e.inertial_parameters[i] - l.inertial_parameters[i]).powi(2))
                .sum::<f64>()
                .sqrt()
                / l.inertial_parameters
                    .iter()
                    .map(|v| v * v)
                    .sum::<f64>()
                    .sqrt()
                    .max(1e-300);
            rel(&e.stiffness, &l.stiffness) < QUASI_CONSTANT
                && rel(&e.damping, &l.damping) < QUASI_CONSTANT
                && xi_change < QUASI_CONSTANT
        }
        None => false,
    };
    let intervals = interval_sweep(data, xi, step);
    Ok(Sweep {
        intervals,
        shortest_trusted_ms: rows
            .iter()
            .find(|r| r.trusted)
            .map(|r| r.observation_window_ms),
        impedance_change: change,
        trust_definition: format!(
            "the estimate's own criteria met (well-conditioned, K and D positive definite and quasi-symmetric, physical inertial parameters); 2 SE of K within {:.0} % and of D within {:.0} % (relative Frobenius norm); K within {:.0} % and D within {:.1} % of every window within {NEIGHBOURHOOD_MS} ms; and the window ends before any change of K or D within the trials (a reflex)",
            100.0 * SWEEP_TOLERANCE_K,
            100.0 * SWEEP_TOLERANCE_D,
            100.0 * SWEEP_TOLERANCE_K / 2.0,
            100.0 * SWEEP_TOLERANCE_D / 2.0,
        ),
        min_positive_definite_ms: from_which(&|e| e.criteria.stiffness_positive_definite),
        min_quasi_symmetric_ms: from_which(&|e| e.criteria.stiffness_symmetry_ratio < QUASI_SYMMETRIC && e.criteria.damping_symmetry_ratio < QUASI_SYMMETRIC),
        min_quasi_constant_ms: from_which(&constant),
        quasi_constant_definition: format!(
            "K, D and the inertial parameters each within {:.0} % (relative Frobenius norm) of their estimate at the longest window, for this and every longer window",
            100.0 * QUASI_CONSTANT
        ),
        leave_one_out_vaf: leave_one_out_vaf(data, longest, xi)?,
        rows,
    })
}

/// Mark each window trusted or not, with the reasons.
fn judge_windows(rows: &mut [SweepRow], change: Option<&ImpedanceChange>) {
    let rel = |a: &Matrix, b: &Matrix| (&a.0 - &b.0).norm() / b.norm().max(1e-300);
    let verdicts: Vec<Vec<String>> = rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let e = &r.estimate;
            let mut why = e.criteria.reasons.clone();
            let (k_se, d_se) = (
                e.standard_errors.stiffness.norm() / e.stiffness.norm().max(1e-300),
                e.standard_errors.damping.norm() / e.damping.norm().max(1e-300),
            );
            if k_se.is_nan() || 2.0 * k_se > SWEEP_TOLERANCE_K {
                why.push(format!(
                    "imprecise: 2 SE of K are {:.0} % of K (at most {:.0} %)",
                    200.0 * k_se,
                    100.0 * SWEEP_TOLERANCE_K
                ));
            }
            if d_se.is_nan() || 2.0 * d_se > SWEEP_TOLERANCE_D {
                why.push(format!(
                    "imprecise: 2 SE of D are {:.0} % of D (at most {:.0} %)",
                    200.0 * d_se,
                    100.0 * SWEEP_TOLERANCE_D
                ));
            }
            let (mut dk, mut dd) = (0.0f64, 0.0f64);
            // rows are in increasing T_obs: the neighbours are a contiguous run around row i
            let near = |o: &&SweepRow| {
                (o.observation_window_ms - r.observation_window_ms).abs() <= NEIGHBOURHOOD_MS + 1e-9
            };
            let before = rows[..i].iter().rev().take_while(near);
            let after = rows[i..].iter().take_while(near);
            for o in before.chain(after) {
                dk = dk.max(rel(&o.estimate.stiffness, &e.stiffness));
                dd = dd.max(rel(&o.estimate.damping, &e.damping));
            }
            if dk.is_nan() || dk > SWEEP_TOLERANCE_K / 2.0 || dd.is_nan() || dd > SWEEP_TOLERANCE_D / 2.0 {
                why.push(format!(
                    "unstable: within {NEIGHBOURHOOD_MS} ms K changes by {:.0} % and D by {:.0} %",
                    100.0 * dk,
                    100.0 * dd
                ));
            }
            if let Some(c) = change {
                if r.observation_window_ms > c.onset_ms {
                    why.push(format!(
                        "the window reaches past a change of the impedance at {:.0} ms (a reflex?): K changes by {:.0} %, D by {:.0} %",
                        c.onset_ms,
                        100.0 * c.stiffness_change,
                        100.0 * c.damping_change
                    ));
                }
            }
            why
        })
        .collect();
    for (r, why) in rows.iter_mut().zip(verdicts) {
        r.trusted = why.is_empty();
        r.reasons = why;
    }
}

pub use limpid_core::criteria::{MAX_CONDITION, QUASI_SYMMETRIC};

/// Most windows one sweep evaluates.
pub const MAX_SWEEP_WINDOWS: usize = 10_000;

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

#[cfg(test)]
mod tests {
    use super::*;

    fn crit(k: [[f64; 2]; 2], d: [[f64; 2]; 2], cond: f64, scaled: f64) -> PlanarCriteria {
        let zero = Matrix::zeros(2, 2);
        criteria(&k.into(), &d.into(), (&zero, &zero), true, cond, scaled)
    }

    #[test]
    fn regressor_matches_inverse_dynamics() {
        // Ψ = M q'' + (C + D) q' + K Δq must equal X ζ, and C must follow from M
        let xi = [0.35, 0.14, 0.15];
        let d = [[1.8, 0.6], [0.5, 1.4]];
        let k = [[38.0, 9.0], [9.5, 10.0]];
        let zeta = [
            xi[0], xi[1], xi[2], d[0][0], d[0][1], d[1][0], d[1][1], k[0][0], k[0][1], k[1][0],
            k[1][1],
        ];
        let (q2, qd, qdd, dq) = (0.9, [0.7, -1.1], [3.0, -2.0], [0.02, -0.01]);
        let x = regressor(q2, qd, qdd, dq);
        let psi = mass_matrix(q2, xi) * Vector2::new(qdd[0], qdd[1])
            + coriolis(q2, qd, xi)
            + Matrix2::new(d[0][0], d[0][1], d[1][0], d[1][1]) * Vector2::new(qd[0], qd[1])
            + Matrix2::new(k[0][0], k[0][1], k[1][0], k[1][1]) * Vector2::new(dq[0], dq[1]);
        for r in 0..2 {
            let xz: f64 = (0..11).map(|j| x[r][j] * zeta[j]).sum();
            assert!((xz - psi[r]).abs() < 1e-12, "row {r}: {xz} vs {}", psi[r]);
        }
        // Coriolis from the Christoffel symbols of M by finite differences: c_i = Σ_jk (∂M_ij/∂q_k - ½ ∂M_jk/∂q_i) q'_j q'_k
        let h = 1e-6;
        let dm = (mass_matrix(q2 + h, xi) - mass_matrix(q2 - h, xi)) / (2.0 * h); // only q2 matters
        let mut c = [0.0; 2];
        for i in 0..2 {
            for j in 0..2 {
                for kk in 0..2 {
                    let dmij_dqk = if kk == 1 { dm[(i, j)] } else { 0.0 };
                    let dmjk_dqi = if i == 1 { dm[(j, kk)] } else { 0.0 };
                    c[i] += (dmij_dqk - 0.5 * dmjk_dqi) * qd[j] * qd[kk];
                }
            }
        }
        let cor = coriolis(q2, qd, xi);
        assert!(
            (c[0] - cor[0]).abs() < 1e-6 && (c[1] - cor[1]).abs() < 1e-6,
            "{c:?} vs {cor}"
        );
    }

    #[test]
    fn a_nan_anywhere_is_never_trusted() {
        let good_k = [[30.0, 8.0], [8.0, 12.0]];
        let good_d = [[2.0, 0.4], [0.4, 1.5]];
        for c in [
            crit([[f64::NAN, 8.0], [8.0, 12.0]], good_d, 50.0, 20.0),
            crit(good_k, [[2.0, f64::NAN], [0.4, 1.5]], 50.0, 20.0),
            crit(good_k, good_d, 50.0, f64::NAN),
        ] {
            assert!(!c.trusted, "{:?}", c.reasons);
        }
    }

    #[test]
    fn criteria_flags_hand_made_matrices() {
        let good = crit(
            [[30.0, 8.0], [8.0, 12.0]],
            [[2.0, 0.4], [0.4, 1.5]],
            50.0,
            20.0,
        );
        assert!(good.trusted, "{:?}", good.reasons);
        let indefinite = crit(
            [[30.0, 25.0], [25.0, 12.0]],
            [[2.0, 0.4], [0.4, 1.5]],
            50.0,
            20.0,
        );
        assert!(!indefinite.stiffness_positive_definite && !indefinite.trusted);
        let skew = crit(
            [[30.0, 8.0], [2.0, 12.0]],
            [[2.0, 0.4], [0.4, 1.5]],
            50.0,
            20.0,
        );
        assert!(skew.stiffness_symmetry_ratio > QUASI_SYMMETRIC && !skew.trusted);
        let ill = crit(
            [[30.0, 8.0], [8.0, 12.0]],
            [[2.0, 0.4], [0.4, 1.5]],
            1e6,
            5e3,
        );
        assert!(!ill.trusted && ill.reasons[0].contains("ill-conditioned"));
    }
}
