//! The reflex pathway's static nonlinearity, estimated from the data (issue 78).
//!
//! Kearney, Stein & Parameswaran (1997) fix the reflex's static curve to a
//! half-wave rectifier; the field's reference toolbox (REKLAB NLID,
//! `PC_stiffnessID` with `'sls'`) estimates it instead (a Hammerstein system:
//! velocity -> polynomial -> linear IRF). Real reflexes have thresholds and
//! saturate, which a rectifier can only absorb into its gain and into the
//! intrinsic parameters.
//!
//! Here the joint parametric model's reflex term `G LP2(rect v)(t - d)` is
//! generalised to `LP2(f(v))(t - d)` with `f` continuous and piecewise
//! linear in the velocity: `f(v) = a v + sum_j c_j h_j(v)`, hinges
//! `max(v - k, 0)` at knots `k >= 0` and `max(-k - v, 0)` at `-k`. Because the
//! low-pass is linear, `LP2(f(v)) = a LP2(v) + sum_j c_j LP2(h_j(v))`, so for
//! the delay and low-pass of the rectifier's scan the model stays linear in
//! I, B, K and the curve's coefficients: one least-squares fit per structure.
//!
//! Choices (docs/src/reference/estimate-reflex.md "The reflex's static curve"):
//! - piecewise linear rather than NLID's Tchebyshev polynomial: a threshold
//!   and a ceiling are its natural shapes, the rectifier is nested in it (one
//!   knot at 0), and it does not swing at the sparse extreme velocities;
//! - knots at 0 and at the `j/(m+1)` quantiles of each half of the velocity
//!   (`m` = 0..=4 knots per half), so each hinge sees data;
//! - the delay and low-pass those of the rectifier's scan (its profile
//!   interval stands): refitting the delay per structure moved it by up to
//!   15 ms on real ankles, trading delay against the curve's shape, and did
//!   not improve it on virtual ones with thresholds;
//! - the structure chosen by 10-fold blocked cross-validation, the simplest
//!   whose held-out squared error is within one standard error (of the
//!   paired per-fold difference) of the best one's (the one-standard-error
//!   rule); the structures inside that band are those the data cannot tell
//!   apart, and their largest difference in I, B, K is added to the standard
//!   errors in quadrature;
//! - standard errors of the curve by the same 10-block delete-one jackknife
//!   as the other parameters (the held-out folds are its blocks);
//! - the reported gain for a curve: the rectifier slope closest to it over
//!   the recorded velocities (`sum f(v) r(v) / sum r(v)^2`), so that gains
//!   compare across structures; the rectifier's own gain for the rectifier.

use super::cascade::{centre, mean};
use super::parametric::{delayed, low_pass, phases, Fixed};
use super::{CurveCandidate, CurveStructure, Ibk, StaticCurve};
use crate::planar::jackknife_sd;
use limpid_core::Result;
use limpid_dsp::LowPass;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Folds of the cross-validation and blocks of the jackknife.
const BLOCKS: usize = 10;
/// Knots per half of the velocity, at most.
pub(crate) const MAX_KNOTS_PER_HALF: usize = 8;
/// Points of the reported curve.
const GRID: usize = 81;

/// One basis function of the curve.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Basis {
    /// `v`.
    Linear,
    /// `max(v - k, 0)`.
    Right(f64),
    /// `max(-k - v, 0)`.
    Left(f64),
}

impl Basis {
    fn eval(self, v: f64) -> f64 {
        match self {
            Basis::Linear => v,
            Basis::Right(k) => (v - k).max(0.0),
            Basis::Left(k) => (-k - v).max(0.0),
        }
    }
}

/// A candidate structure: its description and basis.
struct Candidate {
    structure: CurveStructure,
    knots: Vec<f64>,
    basis: Vec<Basis>,
}

/// The candidates: the rectifier of the scan's polarity, then piecewise
/// linear curves with 0..=4 knots per half (by increasing parameter count).
fn candidates(sorted: &[f64], positive: bool) -> Vec<Candidate> {
    // each half of the velocity, ascending in its own magnitude
    let rest = sorted.partition_point(|v| *v <= 0.0);
    let pos = &sorted[rest..];
    let neg: Vec<f64> = sorted[..sorted.partition_point(|v| *v < 0.0)]
        .iter()
        .rev()
        .map(|v| -v)
        .collect();
    let at = |h: &[f64], q: f64| {
        h.get(((h.len() as f64 - 1.0) * q).round() as usize)
            .copied()
    };
    let mut out = vec![Candidate {
        structure: CurveStructure::Rectifier,
        knots: vec![0.0],
        basis: vec![if positive {
            Basis::Right(0.0)
        } else {
            Basis::Left(0.0)
        }],
    }];
    for m in 0..=MAX_KNOTS_PER_HALF {
        let levels: Vec<f64> = (1..=m).map(|j| j as f64 / (m + 1) as f64).collect();
        let right: Vec<f64> = levels.iter().filter_map(|&q| at(pos, q)).collect();
        let left: Vec<f64> = levels.iter().filter_map(|&q| at(&neg, q)).collect();
        let mut basis = vec![Basis::Linear, Basis::Right(0.0)];
        basis.extend(right.iter().map(|&k| Basis::Right(k)));
        basis.extend(left.iter().map(|&k| Basis::Left(k)));
        let mut knots: Vec<f64> = left.iter().rev().map(|k| -k).collect();
        knots.push(0.0);
        knots.extend(&right);
        out.push(Candidate {
            structure: CurveStructure::PiecewiseLinear,
            knots,
            basis,
        });
    }
    out
}

/// What the curve's columns are made from: the recorded velocity, the
/// anti-alias filter and the order of rectifying and anti-aliasing, the
/// scan's low-pass and the decimation.
pub(crate) struct CurveInput<'a> {
    /// Central-difference velocity at the recorded rate (rad/s).
    pub(crate) velocity: &'a [f64],
    pub(crate) anti_alias: Option<&'a LowPass>,
    pub(crate) rectify_first: bool,
    pub(crate) fs: f64,
    pub(crate) ratio: usize,
    /// Low-pass of the scan: natural frequency (Hz), damping ratio.
    pub(crate) low_pass: (f64, f64),
    /// Delay of the scan (recorded samples).
    pub(crate) delay: usize,
    /// Decimated rows left out at the start (one continuous record).
    pub(crate) skip: usize,
    /// Decimated samples.
    pub(crate) n: usize,
}

/// One structure's fit.
struct StructureFit {
    /// `[I, B, K, coefficients..]`.
    theta: Vec<f64>,
    /// Delete-one-block solutions.
    replicates: Vec<Vec<f64>>,
    /// Held-out squared error per fold.
    held_out: [f64; BLOCKS],
    rss: f64,
}

/// The decimated phases of each basis function of `input`'s velocity,
/// low-passed (one per distinct basis function of all candidates).
fn basis_phases(input: &CurveInput, basis: &[Basis]) -> Result<Vec<Vec<Vec<f64>>>> {
    let (w, z) = input.low_pass;
    // Kearney et al.'s order applies the nonlinearity after anti-aliasing:
    // the velocity is filtered once for every basis function
    let after = match (input.anti_alias, input.rectify_first) {
        (Some(lp), false) => Some(lp.filtfilt(input.velocity)?),
        _ => None,
    };
    basis
        .par_iter()
        .map(|&b| {
            let filtered: Vec<f64> = match (&after, input.anti_alias) {
                (Some(v), _) => v.iter().map(|&v| b.eval(v)).collect(),
                (None, lp) => {
                    let raw: Vec<f64> = input.velocity.iter().map(|&v| b.eval(v)).collect();
                    match lp {
                        Some(lp) => lp.filtfilt(&raw)?,
                        None => raw,
                    }
                }
            };
            Ok(phases(
                &low_pass(&filtered, w, z, input.fs),
                input.ratio,
                input.n,
            ))
        })
        .collect()
}

/// Least squares of `y` on the intrinsic columns and `x` per block: the fit,
/// its delete-one-block solutions and held-out errors. None when singular.
fn fit_blocks(f: &Fixed, y: &[f64], x: &[Vec<f64>]) -> Option<StructureFit> {
    let m = y.len();
    let p = 3 + x.len();
    let column = |j: usize| -> &[f64] {
        if j < 3 {
            &f.columns[j]
        } else {
            &x[j - 3]
        }
    };
    let scale: Vec<f64> = (0..p)
        .map(|j| {
            let c = column(j);
            (c.iter().map(|v| v * v).sum::<f64>() / m as f64)
                .sqrt()
                .max(f64::MIN_POSITIVE)
        })
        .collect();
    let blocks: Vec<(DMatrix<f64>, DVector<f64>, f64)> = (0..BLOCKS)
        .into_par_iter()
        .map(|b| {
            let rows = b * m / BLOCKS..(b + 1) * m / BLOCKS;
            let xb = DMatrix::from_fn(rows.len(), p, |i, j| column(j)[rows.start + i] / scale[j]);
            let yb = DVector::from_column_slice(&y[rows.clone()]);
            let yy = yb.dot(&yb);
            (xb.tr_mul(&xb), xb.tr_mul(&yb), yy)
        })
        .collect();
    let solve = |skip: Option<usize>| -> Option<DVector<f64>> {
        let mut g = DMatrix::<f64>::zeros(p, p);
        let mut r = DVector::<f64>::zeros(p);
        for (b, (gb, rb, _)) in blocks.iter().enumerate() {
            if Some(b) != skip {
                g += gb;
                r += rb;
            }
        }
        g.clone()
            .cholesky()
            .map(|c| c.solve(&r))
            .or_else(|| g.lu().solve(&r))
    };
    let full = solve(None)?;
    let (mut held_out, mut replicates) = ([0.0; BLOCKS], Vec::with_capacity(BLOCKS));
    for (b, (gb, rb, yy)) in blocks.iter().enumerate() {
        let th = solve(Some(b))?;
        held_out[b] = (yy - 2.0 * th.dot(rb) + (th.transpose() * gb * &th)[0]).max(0.0);
        replicates.push((0..p).map(|j| th[j] / scale[j]).collect());
    }
    let (mut g, mut r, mut yy) = (DMatrix::<f64>::zeros(p, p), DVector::<f64>::zeros(p), 0.0);
    for (gb, rb, y2) in &blocks {
        g += gb;
        r += rb;
        yy += y2;
    }
    let rss = (yy - 2.0 * full.dot(&r) + (full.transpose() * &g * &full)[0]).max(0.0);
    Some(StructureFit {
        theta: (0..p).map(|j| full[j] / scale[j]).collect(),
        replicates,
        held_out,
        rss,
    })
}

/// The estimated curve and, for the chosen structure, the I-B-K, gain and
/// their standard errors (jackknife, plus the spread over structures the
/// data cannot tell apart) and the in-sample VAF.
pub(crate) struct CurveFit {
    pub(crate) curve: StaticCurve,
    pub(crate) intrinsic: Ibk,
    pub(crate) intrinsic_se: Ibk,
    /// Largest change of I, B, K over the structures inside the band.
    pub(crate) spread: Ibk,
    pub(crate) gain: f64,
    pub(crate) gain_se: f64,
    pub(crate) vaf: f64,
    /// The chosen curve applied to the recorded velocity (for the cascade).
    pub(crate) applied: Vec<f64>,
}

/// Which structures to consider.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Choice {
    Auto,
    Rectifier,
    PiecewiseLinear,
}

/// Fit every candidate structure at the scan's delay and low-pass and
/// choose one (see the module docs).
pub(crate) fn estimate_curve(
    f: &Fixed,
    input: &CurveInput,
    positive: bool,
    choice: Choice,
) -> Result<Option<CurveFit>> {
    let mut sorted = input.velocity.to_vec();
    sorted.sort_by(f64::total_cmp);
    let cands = candidates(&sorted, positive);
    let mut distinct: Vec<Basis> = Vec::new();
    for c in &cands {
        for b in &c.basis {
            if !distinct.contains(b) {
                distinct.push(*b);
            }
        }
    }
    let ph = basis_phases(input, &distinct)?;
    let y = f.torque();
    let segments: Vec<std::ops::Range<usize>> = std::iter::once(0..input.n).collect();
    let columns_at = |c: &Candidate, delay: usize| -> Vec<Vec<f64>> {
        c.basis
            .iter()
            .map(|b| {
                let k = distinct.iter().position(|d| d == b).expect("collected");
                let mut x = delayed(&ph[k], input.ratio, delay, input.skip, &segments).into_owned();
                centre(&mut x);
                x
            })
            .collect()
    };
    let fits: Vec<Option<StructureFit>> = cands
        .par_iter()
        .map(|c| fit_blocks(f, &y, &columns_at(c, input.delay)))
        .collect();
    let total_ss: f64 = y.iter().map(|v| v * v).sum();
    let cv_error = |fit: &StructureFit| fit.held_out.iter().sum::<f64>();
    let allowed = |c: &Candidate| match choice {
        Choice::Auto => true,
        Choice::Rectifier => c.structure == CurveStructure::Rectifier,
        Choice::PiecewiseLinear => c.structure == CurveStructure::PiecewiseLinear,
    };
    let Some((best, best_fit)) = (0..cands.len())
        .filter(|&i| allowed(&cands[i]))
        .filter_map(|i| fits[i].as_ref().map(|fit| (i, fit)))
        .min_by(|a, b| cv_error(a.1).total_cmp(&cv_error(b.1)))
    else {
        return Ok(None);
    };
    // the one-standard-error band: paired per-fold differences to the best
    let within: Vec<bool> = fits
        .iter()
        .map(|fit| {
            let Some(fit) = fit else { return false };
            let diff: Vec<f64> = (0..BLOCKS)
                .map(|b| fit.held_out[b] - best_fit.held_out[b])
                .collect();
            let se = (crate::reflex::cascade::variance(&diff) * BLOCKS as f64
                / (BLOCKS - 1) as f64)
                .sqrt()
                / (BLOCKS as f64).sqrt();
            mean(&diff) <= se
        })
        .collect();
    let chosen = (0..cands.len())
        .find(|&i| allowed(&cands[i]) && within[i])
        .unwrap_or(best);
    // (inside the band only when fitted)
    let Some(fit) = fits[chosen].as_ref() else {
        return Ok(None);
    };
    let cand = &cands[chosen];
    // the curve on a grid over the recorded velocities
    let at = |q: f64| sorted[((sorted.len() - 1) as f64 * q).round() as usize];
    let (lo, hi) = (at(0.005), at(0.995));
    let grid: Vec<f64> = (0..GRID)
        .map(|i| lo + (hi - lo) * i as f64 / (GRID - 1) as f64)
        .collect();
    let curve_of = |theta: &[f64], v: f64| -> f64 {
        cand.basis
            .iter()
            .zip(&theta[3..])
            .map(|(b, c)| c * b.eval(v))
            .sum()
    };
    let torque: Vec<f64> = grid.iter().map(|&v| curve_of(&fit.theta, v)).collect();
    let torque_se: Vec<f64> = grid
        .iter()
        .map(|&v| {
            let reps: Vec<f64> = fit.replicates.iter().map(|r| curve_of(r, v)).collect();
            jackknife_sd(&reps)
        })
        .collect();
    let mut histogram = vec![0u64; GRID - 1];
    let step = (hi - lo) / (GRID - 1) as f64;
    for &v in input.velocity.iter().step_by(input.ratio.max(1)) {
        if step > 0.0 && (lo..hi).contains(&v) {
            let k = (((v - lo) / step) as usize).min(GRID - 2);
            histogram[k] += 1;
        }
    }
    // the gain: the rectifier slope closest to the curve over the recorded velocities
    let rect = |v: f64| if positive { v } else { -v }.max(0.0);
    let sample: Vec<f64> = input
        .velocity
        .iter()
        .step_by(input.ratio.max(1))
        .copied()
        .collect();
    let rr: f64 = sample.iter().map(|&v| rect(v).powi(2)).sum();
    let gain_of = |theta: &[f64]| -> f64 {
        if rr > 0.0 {
            sample
                .iter()
                .map(|&v| curve_of(theta, v) * rect(v))
                .sum::<f64>()
                / rr
        } else {
            0.0
        }
    };
    let gain_reps: Vec<f64> = fit.replicates.iter().map(|r| gain_of(r)).collect();
    let se_of = |j: usize| {
        let reps: Vec<f64> = fit.replicates.iter().map(|r| r[j]).collect();
        jackknife_sd(&reps)
    };
    let mut spread = [0.0f64; 3];
    for (i, other) in fits.iter().enumerate() {
        if let (true, Some(o)) = (within[i], other) {
            for (j, s) in spread.iter_mut().enumerate() {
                *s = s.max((o.theta[j] - fit.theta[j]).abs());
            }
        }
    }
    let ibk = |t: [f64; 3]| Ibk {
        inertia: t[0],
        damping: t[1],
        stiffness: t[2],
    };
    let vaf_of = |rss: f64| 100.0 * (1.0 - rss / total_ss);
    let candidates: Vec<CurveCandidate> = cands
        .iter()
        .zip(&fits)
        .zip(&within)
        .filter_map(|((c, fit), &w)| {
            let fit = fit.as_ref()?;
            Some(CurveCandidate {
                structure: c.structure,
                knots_rad_s: c.knots.clone(),
                parameters: c.basis.len(),
                cross_validated_vaf: vaf_of(cv_error(fit)),
                vaf: vaf_of(fit.rss),
                intrinsic: ibk([fit.theta[0], fit.theta[1], fit.theta[2]]),
                within_one_se: w,
            })
        })
        .collect();
    let applied: Vec<f64> = input
        .velocity
        .iter()
        .map(|&v| curve_of(&fit.theta, v))
        .collect();
    Ok(Some(CurveFit {
        curve: StaticCurve {
            structure: cand.structure,
            knots_rad_s: cand.knots.clone(),
            velocity_rad_s: grid,
            torque,
            torque_se,
            histogram,
            candidates,
        },
        intrinsic: ibk([fit.theta[0], fit.theta[1], fit.theta[2]]),
        intrinsic_se: ibk([se_of(0), se_of(1), se_of(2)]),
        spread: ibk(spread),
        gain: gain_of(&fit.theta),
        gain_se: jackknife_sd(&gain_reps),
        vaf: vaf_of(fit.rss),
        applied,
    }))
}
