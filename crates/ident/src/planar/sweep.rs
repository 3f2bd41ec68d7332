//! Seed 003 §IV (Fig. 4-5): estimates against the observation window T_obs, the interpolation-interval study, and the scan for a change of K or D within the trials (a reflex).

use super::compliance::{fit_series_compliance, SeriesCompliance, SERIES_COMPLIANCE_RATIO};
use super::fit::{
    check_inertial_parameters, fit_planar, leave_one_out_vaf, solve_blocks, trial_rows,
    BlockSolution, PlanarEstimate,
};
use super::noise::RegressorNoise;
use super::prepare::PlanarData;
use super::PlanarTrial;
use limpid_core::criteria::QUASI_SYMMETRIC;
use limpid_core::{Error, Matrix, Result};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
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
pub(crate) const MOTION_SPEED_SHARE: f64 = 0.05;

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
            reasons.extend(change_untestable(trials.len()));
            if let Some(c) = change.filter(|c| window_ms > c.significant_from_ms) {
                reasons.push(format!(
                    "the window reaches past a change of the impedance from {:.0} ms on (a reflex, or soft tissue in series?)",
                    c.significant_from_ms
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
    /// The earliest split time at which the change is significant (ms):
    /// windows reaching past it are not trusted.
    #[serde(default)]
    pub significant_from_ms: f64,
    /// ||K_after - K_before|| / ||K_before|| (relative Frobenius norm).
    pub stiffness_change: f64,
    /// The same for D.
    pub damping_change: f64,
    /// Probability of so clear a change somewhere in the scan if K and D did
    /// not change (Hotelling's test on the jackknife covariance, Bonferroni
    /// over the split times scanned).
    #[serde(default)]
    pub p_value: f64,
    /// The same as a standard normal deviate (one-sided).
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
    /// Soft tissue in series with the handle, when a change was found and a
    /// compliance in series explains the trials at least
    /// [`SERIES_COMPLIANCE_RATIO`] times better than the rigid model: the
    /// change is then likely the tissue, and a reflex behind it cannot be
    /// told apart.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub series_compliance: Option<SeriesCompliance>,
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

/// Largest probability, allowing for the scan over split times, at which a
/// change of K or D within the trials counts as real (issue 37: the largest
/// of some 40 jackknife z-values over 3 had cried "reflex" on most
/// reflex-free arms with noisy angles).
pub const CHANGE_P: f64 = 0.01;

/// Columns of the split model: `trial_rows` with D and K duplicated into a
/// "before sample `split`" and an "after" copy (xi shared).
pub(crate) fn split_rows(
    t: &PlanarTrial,
    n: usize,
    split: usize,
    xi: Option<[f64; 3]>,
) -> DMatrix<f64> {
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

/// The regressors' noise of [`split_rows`]: the samples before `split`
/// load the "before" copies of D and K, the rest the "after" copies.
pub(crate) fn split_noise(
    model: &RegressorNoise,
    t: &PlanarTrial,
    n: usize,
    split: usize,
    xi: Option<[f64; 3]>,
) -> Option<DMatrix<f64>> {
    let n = n.min(t.dq[0].len());
    let split = split.min(n);
    let parts = [model.over(t, 0..split)?, model.over(t, split..n)?];
    let p = parts[0].ncols() - 1;
    let first = if xi.is_some() { 0 } else { 3 };
    let column = |c: usize, part: usize| {
        if c < first {
            c
        } else if c < p {
            c + 8 * part
        } else {
            p + 8
        }
    };
    let mut out = DMatrix::<f64>::zeros(p + 9, p + 9);
    for (part, noise) in parts.iter().enumerate() {
        for i in 0..=p {
            for j in 0..=p {
                out[(column(i, part), column(j, part))] += noise[(i, j)];
            }
        }
    }
    Some(out)
}

/// Jackknife standard deviation of replicate values.
pub(crate) fn jackknife_sd(values: &[f64]) -> f64 {
    let g = values.len() as f64;
    if g < 2.0 {
        return f64::INFINITY;
    }
    let mean = values.iter().sum::<f64>() / g;
    ((g - 1.0) / g * values.iter().map(|v| (v - mean).powi(2)).sum::<f64>()).sqrt()
}

/// Fewest trials the change test needs: Hotelling's T² of 4 elements from
/// g jackknife replicates needs g > 5.
pub const MIN_TRIALS_FOR_CHANGE_TEST: usize = 6;

/// Why no window of `trials` trials can be trusted: with fewer than
/// [`MIN_TRIALS_FOR_CHANGE_TEST`] a change within the trials (a reflex)
/// cannot be tested, so it cannot be excluded.
fn change_untestable(trials: usize) -> Option<String> {
    (trials < MIN_TRIALS_FOR_CHANGE_TEST).then(|| {
        format!(
            "a change of the impedance within the trials (a reflex) cannot be excluded: the test needs at least {MIN_TRIALS_FOR_CHANGE_TEST} trials, found {trials}"
        )
    })
}

/// Hotelling's test of a change `Δ` (k elements) with jackknife replicates:
/// `T² = Δᵀ V⁻¹ Δ`, `V` the jackknife covariance from `g` replicates, and
/// `(g - k) / (k (g - 1)) T² ~ F(k, g - k)` under "no change". The upper
/// tail probability; None with too few replicates or a singular `V`.
pub(crate) fn hotelling_p(
    change: &DVector<f64>,
    replicates: &[DVector<f64>],
    systematic: Option<&DMatrix<f64>>,
) -> Option<f64> {
    use statrs::distribution::{ContinuousCDF, FisherSnedecor};
    let (k, g) = (change.len(), replicates.len());
    if g <= k + 1 {
        return None;
    }
    let gf = g as f64;
    let mean = replicates.iter().fold(DVector::zeros(k), |a, r| a + r) / gf;
    let cov = replicates.iter().fold(DMatrix::zeros(k, k), |a, r| {
        let d = r - &mean;
        a + &d * d.transpose()
    }) * ((gf - 1.0) / gf);
    let cov = match systematic {
        Some(extra) => cov + extra,
        None => cov,
    };
    let t2 = cov.cholesky()?.solve(change).dot(change);
    let f = (gf - k as f64) / (k as f64 * (gf - 1.0)) * t2;
    let dist = FisherSnedecor::new(k as f64, gf - k as f64).ok()?;
    Some(dist.sf(f)).filter(|p| p.is_finite())
}

/// Share of the torques' RMS taken as a misfit common to every trial at
/// least.
pub const SYSTEMATIC_TORQUE_ERROR: f64 = 0.01;

/// The parameters' covariance from a misfit common to every trial (model or
/// processing error: filtering, differences, the rigid-body model), which a
/// jackknife over trials cannot see: the per-sample variance of the mean
/// residual beyond what the trials' own scatter explains, `ε²`, through one
/// mean trial's normal matrix, `ε² (Σ_i A_iᵀ A_i / g)⁻¹` (the solution's
/// `gram_inverse` times g). None when the trials differ in length.
pub(crate) fn systematic_covariance(
    blocks: &[DMatrix<f64>],
    sol: &BlockSolution,
) -> Option<DMatrix<f64>> {
    let rows = blocks.first()?.nrows();
    let theta = &sol.theta;
    let p = theta.len();
    if blocks.len() < 2
        || blocks
            .iter()
            .any(|b| b.nrows() != rows || b.ncols() != p + 1)
    {
        return None;
    }
    let g = blocks.len() as f64;
    let residuals: Vec<DVector<f64>> = blocks
        .iter()
        .map(|b| b.columns(0, p) * theta - b.column(p))
        .collect();
    let mean = residuals.iter().fold(DVector::zeros(rows), |a, r| a + r) / g;
    let scatter: f64 = residuals
        .iter()
        .map(|r| (r - &mean).norm_squared())
        .sum::<f64>()
        / (g - 1.0);
    let measured = ((mean.norm_squared() - scatter / g) / rows as f64).max(0.0);
    let torque_ms = blocks
        .iter()
        .map(|b| b.column(p).norm_squared())
        .sum::<f64>()
        / (g * rows as f64);
    let eps2 = measured + (SYSTEMATIC_TORQUE_ERROR.powi(2) * torque_ms);
    let inverse = sol.gram_inverse.as_ref()?;
    Some(inverse * (g * eps2)).filter(|c| c.iter().all(|v| v.is_finite()))
}

/// Scan the split time over the longest window: where K or D before and
/// after differ most clearly, and from which split on they differ
/// significantly (seed 003 §IV: reflexes bound the observation window). Each split is tested by [`hotelling_p`] on the change of K and of
/// D (the smaller probability, doubled), the clearest split's probability
/// multiplied by the number of splits scanned (Bonferroni); a change counts
/// when that is below [`CHANGE_P`], the change exceeds half the tolerance and
/// both parts are precise. Precision and the test add to the jackknife a
/// misfit common to every trial ([`systematic_covariance`]): on noise-free
/// data the jackknife is zero, and the few per cent by which filtering and
/// differences bias a barely excited part (K in the first 30 ms, D in the
/// hold) had read as a change in every reflex-free sweep. None otherwise.
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
    let model = RegressorNoise::new(&data.angle_noise, xi);
    let scanned = splits.len() as f64;
    let found: Vec<ImpedanceChange> = splits
        .par_iter()
        .filter_map(|&split| {
            let blocks: Vec<DMatrix<f64>> = trials
                .iter()
                .map(|&i| split_rows(&data.trials[i], longest, split, xi))
                .collect();
            let noise: Vec<Option<DMatrix<f64>>> = trials
                .iter()
                .map(|&i| split_noise(&model, &data.trials[i], longest, split, xi))
                .collect();
            let sol = solve_blocks(&blocks, &noise).ok()?;
            let systematic = systematic_covariance(&blocks, &sol);
            let sys_var = |j: usize| systematic.as_ref().map_or(0.0, |c| c[(j, j)]);
            // relative jackknife SE of the 4 parameters from `at` (||SE|| / ||value||)
            let rel_se = |at: usize| {
                let var: f64 = (at..at + 4)
                    .map(|j| {
                        let v: Vec<f64> = sol.replicates.iter().map(|t| t[j]).collect();
                        jackknife_sd(&v).powi(2) + sys_var(j)
                    })
                    .sum();
                var.sqrt() / sol.theta.rows(at, 4).norm().max(1e-300)
            };
            // a change counts only between two precise estimates: a part
            // without motion (the hold) or only a few samples long identifies
            // nothing, nor one whose motion is mostly angle noise
            let reliable = |at: usize| {
                (at..at + 4)
                    .chain(at + 8..at + 12)
                    .all(|j| sol.reliability[j] >= crate::linear::MIN_RELIABILITY)
            };
            let precise = |at: usize, tol: f64| {
                rel_se(at) <= tol / 2.0 && rel_se(at + 8) <= tol / 2.0 && reliable(at)
            };
            let delta = |t: &DVector<f64>, at: usize| t.rows(at + 8, 4) - t.rows(at, 4);
            let p_of = |at: usize, change: f64, tol: f64| {
                if change > tol / 2.0 && precise(at, tol) {
                    let reps: Vec<DVector<f64>> =
                        sol.replicates.iter().map(|t| delta(t, at)).collect();
                    // the change's systematic covariance: after minus before
                    let extra = systematic.as_ref().map(|c| {
                        DMatrix::from_fn(4, 4, |i, j| {
                            c[(at + 8 + i, at + 8 + j)] + c[(at + i, at + j)]
                                - c[(at + 8 + i, at + j)]
                                - c[(at + i, at + 8 + j)]
                        })
                    });
                    hotelling_p(&delta(&sol.theta, at), &reps, extra.as_ref())
                } else {
                    None
                }
            };
            let (k, d) = (rel(&sol.theta, first + 4), rel(&sol.theta, first));
            let p = [
                p_of(first + 4, k, SWEEP_TOLERANCE_K),
                p_of(first, d, SWEEP_TOLERANCE_D),
            ]
            .into_iter()
            .flatten()
            .fold(f64::INFINITY, f64::min);
            let p_value = (2.0 * scanned * p).min(1.0);
            (p_value < CHANGE_P).then(|| ImpedanceChange {
                onset_ms: 1000.0 * split as f64 / data.fs,
                significant_from_ms: 1000.0 * split as f64 / data.fs,
                stiffness_change: k,
                damping_change: d,
                p_value,
                z: normal_deviate(p_value),
            })
        })
        .collect();
    // the clearest split dates the change; the earliest significant one
    // bounds the windows (every split before a change sees it in its "after"
    // part, so the clearest may come late)
    let first = found.iter().map(|c| c.onset_ms).min_by(f64::total_cmp)?;
    let clearest = found
        .into_iter()
        .min_by(|a, b| a.p_value.total_cmp(&b.p_value))?;
    Some(ImpedanceChange {
        significant_from_ms: first,
        ..clearest
    })
}

/// The standard normal deviate with upper tail probability `p` (at most
/// 37.5: below 1e-300 double precision ends).
pub(crate) fn normal_deviate(p: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::standard().inverse_cdf(p.max(1e-300)).abs()
}

/// Relative change below which a parameter group counts as constant.
pub const QUASI_CONSTANT: f64 = 0.05;

/// Estimates over T_obs = from..=to in steps (ms), each with its criteria.
///
/// # Example
///
/// The shortest trustworthy observation window of Lakatos et al. (2011)'s
/// arm in the virtual lab, with torque noise of 0.02 N m and angle noise of
/// 1e-5 rad: a few hundred ms at most.
///
/// ```
/// use limpid_ident::planar::{prepare_planar, window_sweep, PlanarPrepare};
/// use limpid_lab::planar::{simulate_planar, PlanarProtocol, PlanarSubject};
///
/// let (subject, protocol) = (PlanarSubject::seed003(), PlanarProtocol::seed003());
/// let rec = simulate_planar(&subject, &protocol, 0.02, 1e-5, 1)?;
/// let data = prepare_planar(&rec, &PlanarPrepare::new(0.32, 0.31))?;
/// let sweep = window_sweep(&data, 50.0, 400.0, 10.0, None)?;
/// let shortest = sweep.shortest_trusted_ms.expect("a trusted window");
/// println!("{shortest} ms");
/// assert!((50.0..=400.0).contains(&shortest));
/// # Ok::<(), limpid_core::Error>(())
/// ```
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
    let windows = sweep_windows(data, from_ms, to_ms, step_ms)?;
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
    // a change the rigid model shows may be tissue in series (a cuff)
    let series_compliance = change
        .as_ref()
        .and_then(|_| fit_series_compliance(data, longest, xi))
        .filter(|c| c.residual_ratio >= SERIES_COMPLIANCE_RATIO);
    judge_windows(&mut rows, change.as_ref());
    if let Some(why) = change_untestable(all.len()) {
        for r in &mut rows {
            r.trusted = false;
            r.reasons.push(why.clone());
        }
    }
    let from_which = |ok: &dyn Fn(&PlanarEstimate) -> bool| shortest_from(&rows, ok);
    let last = rows.last().map(|r| r.estimate.clone());
    let constant = |e: &PlanarEstimate| last.as_ref().is_some_and(|l| quasi_constant(e, l));
    let intervals = interval_sweep(data, xi, step);
    Ok(Sweep {
        intervals,
        shortest_trusted_ms: rows
            .iter()
            .find(|r| r.trusted)
            .map(|r| r.observation_window_ms),
        impedance_change: change,
        series_compliance,
        trust_definition: format!(
            "the estimate's own criteria met (well-conditioned, K and D positive definite and quasi-symmetric, physical inertial parameters); 2 SE of K within {:.0} % and of D within {:.0} % (relative Frobenius norm); K within {:.0} % and D within {:.1} % of every window within {NEIGHBOURHOOD_MS} ms; and the window ends before any change of K or D within the trials (a reflex, or soft tissue in series with the handle), tested on at least {MIN_TRIALS_FOR_CHANGE_TEST} trials",
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

/// The observation windows of a sweep (ms): from..=to in steps, up to the
/// longest every trial holds; refused when empty or over MAX_SWEEP_WINDOWS.
fn sweep_windows(data: &PlanarData, from_ms: f64, to_ms: f64, step_ms: f64) -> Result<Vec<f64>> {
    if !(from_ms > 0.0 && step_ms > 0.0 && to_ms >= from_ms) {
        return Err(Error::invalid(
            "from_ms/to_ms/step_ms",
            format!(
                "expected 0 < from <= to and step > 0, found {from_ms}..{to_ms} step {step_ms} ms"
            ),
        ));
    }
    let max_ms = 1000.0 * data.max_window_s();
    let count = (to_ms.min(max_ms) - from_ms) / step_ms;
    if count > MAX_SWEEP_WINDOWS as f64 {
        return Err(Error::invalid(
            "from_ms/to_ms/step_ms",
            format!(
                "{}..{} ms in steps of {} ms makes {} windows; at most {MAX_SWEEP_WINDOWS}",
                limpid_core::error::Num(from_ms),
                limpid_core::error::Num(to_ms),
                limpid_core::error::Num(step_ms),
                limpid_core::error::Num(count)
            ),
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
            "from_ms/to_ms/step_ms",
            format!("the trials hold only {max_ms:.0} ms after the onset, less than {from_ms} ms"),
        ));
    }
    Ok(windows)
}

/// The shortest window from which on every longer one satisfies `ok` (ms).
fn shortest_from(rows: &[SweepRow], ok: &dyn Fn(&PlanarEstimate) -> bool) -> Option<f64> {
    let mut first = None;
    for r in rows.iter().rev() {
        if ok(&r.estimate) {
            first = Some(r.observation_window_ms);
        } else {
            break;
        }
    }
    first
}

/// K, D and the inertial parameters each within QUASI_CONSTANT (relative
/// Frobenius norm) of the longest window's estimate `last`.
fn quasi_constant(e: &PlanarEstimate, last: &PlanarEstimate) -> bool {
    let rel = |a: &Matrix, b: &Matrix| (&a.0 - &b.0).norm() / b.norm().max(1e-300);
    let norm = |v: &[f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let difference: [f64; 3] =
        std::array::from_fn(|i| e.inertial_parameters[i] - last.inertial_parameters[i]);
    let xi_change = norm(&difference) / norm(&last.inertial_parameters).max(1e-300);
    rel(&e.stiffness, &last.stiffness) < QUASI_CONSTANT
        && rel(&e.damping, &last.damping) < QUASI_CONSTANT
        && xi_change < QUASI_CONSTANT
}

/// Mark each window trusted or not, with the reasons.
pub(crate) fn judge_windows(rows: &mut [SweepRow], change: Option<&ImpedanceChange>) {
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
                if r.observation_window_ms > c.significant_from_ms {
                    why.push(format!(
                        "the window reaches past a change of the impedance from {:.0} ms on (a reflex, or soft tissue in series?): K changes by {:.0} %, D by {:.0} %",
                        c.significant_from_ms,
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

/// Most windows one sweep evaluates.
pub const MAX_SWEEP_WINDOWS: usize = 10_000;
