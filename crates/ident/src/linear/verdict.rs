//! What the linear fit can claim: identifiability per matrix element (|value| against 2 SE), fit statistics (r, VAF, RMSE) and the warnings they call for.

use super::{sub, units, FitQuality, Identifiable, MIN_RELIABILITY};
use limpid_core::criteria::MatrixKind;
use limpid_core::{Matrix, Warning, WarningCode};
use rayon::prelude::*;
/// The column of a matrix kind's regressors in the per-coordinate
/// reliabilities `[acceleration, velocity, displacement]`.
pub(crate) fn regressor_column(kind: MatrixKind) -> usize {
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
pub(crate) fn identified(
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
pub(crate) fn quality_warnings(
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
