//! Standard errors of the linear fit: block jackknife over contiguous blocks, inflation for autocorrelated residuals, and the inertia prior when the data cannot identify M.

use super::regression::Regression;
use super::{
    Solved, CONTIGUOUS_BLOCKS, DERIVATIVE_ERROR_FLOOR, MAX_JACKKNIFE_GROUPS, MIN_CORRECTABLE,
    MIN_JACKKNIFE_BLOCKS, MIN_RELIABILITY, OFF_DIAGONAL_INERTIA_SHARE,
    UNIDENTIFIED_INERTIA_MEAN_KG, UNIDENTIFIED_INERTIA_MEAN_KG_M2, UNIDENTIFIED_INERTIA_SD_KG,
    UNIDENTIFIED_INERTIA_SD_KG_M2,
};
use crate::prepare::Prepared;
use limpid_core::{Warning, WarningCode};
use nalgebra::DMatrix;
use std::fmt::Write;
/// Sensitivity of every parameter row to the inertia columns, unscaled:
/// `dθ_j/dM_k = C_jM (C_MM)^-1` with `C` the unit covariance `(L^T L)^-1`
/// (partitioned inverse: minus the regression of the acceleration columns on
/// the others). Rows 0..n (the inertia itself) are left zero. None when the
/// inertia block of `C` is singular.
pub(crate) fn inertia_sensitivity(reg: &Regression, solved: &Solved) -> Option<DMatrix<f64>> {
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
/// coordinate `k` (end-point kg or joint kg m²).
pub(crate) fn inertia_prior(coords: &[String], k: usize) -> (f64, f64) {
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
pub(crate) fn condition_on_prior_inertia(
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
pub(crate) fn inertia_confounding(sens: &DMatrix<f64>, coords: &[String]) -> DMatrix<f64> {
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
pub(crate) fn jackknife_blocks(
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

/// 1 + 2 Σ_k (1 - k/(L+1)) ρ_k of the residuals, lags not crossing window edges; at least 1.
pub(crate) fn autocorrelation_inflation(
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

/// The regression's own sampling errors by a delete-a-block jackknife, and
/// how they were made (the block unit named for the reader).
pub(crate) fn block_jackknife(
    reg: &Regression,
    triangles: &[DMatrix<f64>],
    blocks: &[std::ops::Range<usize>],
    windows: usize,
) -> (DMatrix<f64>, String) {
    let g = blocks.len();
    let block_rows: Vec<usize> = blocks.iter().map(|b| b.len()).collect();
    let unit = if g == windows {
        "trials"
    } else if windows >= MIN_JACKKNIFE_BLOCKS {
        "groups of consecutive trials"
    } else {
        "contiguous pieces"
    };
    (
        reg.jackknife(triangles, &block_rows),
        format!("jackknife over {g} blocks ({unit})"),
    )
}

/// Widen the sampling errors by what the regression cannot see: an inertia
/// the data do not identify, whose unknown value moves B and K (its prior's
/// effect is added when little of the acceleration the motion does not tie
/// to displacement and velocity is signal); the prior mean inertia B and K
/// are then given for; and the floor of numerical differentiation.
pub(crate) fn widen_for_what_the_regression_cannot_see(
    (se, se_method): (&mut DMatrix<f64>, &mut String),
    theta: &DMatrix<f64>,
    data: &Prepared,
    reg: &Regression,
    solved: &Solved,
    sensitivity: Option<&DMatrix<f64>>,
    prior_inertia: &[String],
) {
    let n = data.dims();
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
    if let Some(sens) =
        sensitivity.filter(|_| partial_reliability.iter().any(|r| *r < MIN_RELIABILITY))
    {
        let extra = inertia_confounding(sens, &data.coordinates);
        se.zip_apply(&extra, |v, e| *v = (*v * *v + e).sqrt());
        let _ = write!(
            se_method,
            "; B and K include an unknown inertia's effect (prior s.d. {UNIDENTIFIED_INERTIA_SD_KG} kg or {UNIDENTIFIED_INERTIA_SD_KG_M2} kg m²): only {:.0} % of the acceleration the motion does not tie to displacement and velocity is signal",
            100.0 * least
        );
    }
    if !prior_inertia.is_empty() {
        let _ = write!(
            se_method,
            "; B and K are given for the prior mean inertia ({UNIDENTIFIED_INERTIA_MEAN_KG} kg or {UNIDENTIFIED_INERTIA_MEAN_KG_M2} kg m² on the diagonal) along {}: the acceleration there is mostly noise",
            prior_inertia.join(", ")
        );
    }
    for j in 0..2 * n {
        for a in 0..n {
            let floor = DERIVATIVE_ERROR_FLOOR * theta[(j, a)].abs();
            se[(j, a)] = se[(j, a)].hypot(floor);
        }
    }
}

/// Fewest trials from which ±2 jackknife SE is read as a 95 % interval
/// without a warning. Measured (`limpid calibrate`'s centre-out subjects,
/// cubic ramps, 100 per count, issue 37): K's diagonal within ±2 SE in 85 %
/// with 6 trials (contiguous pieces), 92 % with 8, 95 % with 10, 93 % with 12
/// and 95 % with 16.
pub const FEW_TRIALS: usize = 10;

/// The warning for an estimate from fewer than [`FEW_TRIALS`] trials: with
/// a jackknife over g trials the SE itself has at most g - 1 degrees of
/// freedom (the SEs are widened to Student's t on them, see
/// `lsq::small_sample_factors`); with fewer trials than a
/// jackknife needs the SEs come from contiguous pieces or the residuals
/// (`se_method` names which), which share each trial's offsets and drifts and
/// may be too small.
pub(crate) fn few_trials_warning(trials: usize, se_method: &str) -> Option<Warning> {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    // one window is a continuous recording: its pieces are its samples' blocks
    if !(2..FEW_TRIALS).contains(&trials) {
        return None;
    }
    let message = if trials >= MIN_JACKKNIFE_BLOCKS {
        let df = (trials - 1) as f64;
        let t = StudentsT::new(0.0, 1.0, df).ok()?.inverse_cdf(0.975);
        format!(
            "only {trials} trials: the standard errors come from a jackknife over them, widened to Student's t on its effective degrees of freedom (at most {trials} - 1: ±{t:.2} jackknife SE) so that ±2 SE is a 95 % interval, but they are themselves uncertain; record at least {FEW_TRIALS} trials"
        )
    } else {
        format!(
            "only {trials} trials, fewer than the {MIN_JACKKNIFE_BLOCKS} a jackknife over trials needs: the standard errors, {se_method}, share each trial's offsets and drifts, and may be too small (on virtual subjects with 6 trials ±2 SE held the true K in 85 % of cases); record at least {FEW_TRIALS} trials"
        )
    };
    Some(Warning::new(WarningCode::FewTrials, message))
}
