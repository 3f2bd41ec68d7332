//! Closed-loop rigs (issue 79): the commanded reference as an instrument.
//!
//! On a robot of finite impedance (a compliant position servo, an
//! admittance-controlled robot) the subject's own force fluctuations move
//! the limb, so the measured motion is correlated with the equation error
//! and least squares on it is pulled towards the robot's impedance
//! (Westwick & Perreault 2011, IEEE TBME 58(3)). The commanded reference is
//! independent of the subject: the motion it predicts is an instrument.
//!
//! What limpid does: every position column is predicted by its projection
//! on the recorded references — a two-sided FIR
//! from every reference column to the position, lags
//! [`LAGS_BEFORE_S`]..[`LAGS_AFTER_S`], fitted by least squares. The
//! parallel cascade's joint parametric model builds its instruments from
//! the predicted motion ([`ClosedLoopFit::InstrumentalVariables`]); the
//! other estimators run as usual on the predicted motion
//! ([`ClosedLoopFit::PredictedMotion`]). For a model linear in
//! the motion (I-B-K, the linear end-point model) this is the
//! two-stage least-squares (instrumental-variable) estimate: consistent in
//! closed loop, whatever the colour of the subject's noise. Its VAF is the
//! share of the force the *reference-driven* motion explains. Choices:
//! - lags: 20 ms before to 400 ms after the reference (a servo's or an
//!   admittance robot's closed-loop response settles well within that; the
//!   lead absorbs a reference logged late by a few samples); at most
//!   [`MAX_LAGS`] per reference, spaced evenly above that;
//! - segments (`trial` windows) are projected apart; before a segment's start
//!   and after its end the reference is held at its edge value (a trial
//!   starts and ends at the reference's rest);
//! - normal equations: exact, by the shift recursion of lagged inner products
//!   (O(samples x lags) rather than O(samples x lags^2)), solved by Cholesky
//!   with a ridge of 1e-10 of the mean diagonal (a band-limited reference
//!   makes them nearly singular at high frequency, where the motion has
//!   nothing to predict);
//! - a nonlinear pathway (the rectified-velocity reflex) is built from the
//!   projected motion too: consistent to the extent that the reference
//!   drives the motion ([`ClosedLoop::reference_driven_percent`]).

use std::borrow::Cow;
use std::ops::Range;

use limpid_core::{Error, Recording, Result, Warning, WarningCode};
use limpid_dsp::LowPass;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Earliest lag of the reference-to-motion FIR (s): the reference may lead.
pub const LAGS_BEFORE_S: f64 = 0.02;
/// Latest lag of the reference-to-motion FIR (s).
pub const LAGS_AFTER_S: f64 = 0.4;
/// Most lags per reference column (spaced evenly above this).
pub const MAX_LAGS: usize = 420;
/// Below this share (%) of the motion driven by the reference the
/// instrument is weak: the estimate is consistent but imprecise, and a
/// warning says so.
pub const WEAK_INSTRUMENT_PERCENT: f64 = 30.0;

/// How a closed-loop recording was estimated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ClosedLoop {
    /// The commanded reference columns used as instruments.
    pub references: Vec<String>,
    /// The position columns replaced by the motion the references predict.
    pub positions: Vec<String>,
    /// Share (%) of each position's variance the references predict; the
    /// rest is the motion the subject (and sensor noise) caused.
    pub reference_driven_percent: Vec<f64>,
    /// First and last lag (s) of the reference-to-motion FIR.
    pub lags_s: [f64; 2],
    /// How the predicted motion entered the fit.
    pub fit: ClosedLoopFit,
    /// With [`ClosedLoopFit::PredictedMotion`]: the share (%) of each
    /// position's velocity and acceleration (low-passed as the estimator
    /// prepares them) that the predicted motion's holds. A derivative the
    /// reference barely drives (sensor noise, the subject's own motion)
    /// cannot pin its parameter down: the estimator says so.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub derivative_percent: Option<Vec<[f64; 2]>>,
}

/// How the motion a reference predicts enters a closed-loop fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ClosedLoopFit {
    /// Regressors from the measured motion, instruments from the predicted
    /// motion; the VAF is that of the measured motion's fit (low when the
    /// subject moves the limb: its own torque is left in the residual).
    InstrumentalVariables,
    /// The model fitted on the predicted motion (two-stage least squares;
    /// exact for models linear in the motion); the VAF is that of the force
    /// the reference-driven motion explains.
    PredictedMotion,
}

/// The reference column FORMAT.md pairs with a position column: `q1` ->
/// `r1`, `theta` -> `rtheta`, `x` -> `rx`.
pub fn reference_column(position: &str) -> Option<String> {
    if let Some(k) = position.strip_prefix('q') {
        if !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()) {
            return Some(format!("r{k}"));
        }
    }
    matches!(position, "x" | "y" | "z" | "theta").then(|| format!("r{position}"))
}

/// The recording with its position columns replaced by the motion the
/// commanded reference predicts, when it has a reference column for any of
/// them and `open_loop` is false; else the recording as it is. With a
/// `lowpass`, the shares of the velocity and acceleration (filtered by it)
/// the predicted motion holds are measured too.
pub fn instrumented<'r>(
    rec: Cow<'r, Recording>,
    positions: &[String],
    (open_loop, lowpass): (bool, Option<&LowPass>),
) -> Result<(Cow<'r, Recording>, Option<ClosedLoop>)> {
    let Some((predicted, mut closed)) =
        predicted_motion(&rec, positions, (open_loop, ClosedLoopFit::PredictedMotion))?
    else {
        return Ok((rec, None));
    };
    if let Some(lp) = lowpass {
        let segments = limpid_core::trial::segment_ranges(&rec)?;
        let dt = 1.0 / rec.sample_rate();
        closed.derivative_percent = Some(
            positions
                .par_iter()
                .zip(&predicted)
                .map(|(name, p)| {
                    let measured = rec.column(name).unwrap_or(&[]);
                    derivative_shares(measured, p, &segments, (lp, dt))
                })
                .collect(),
        );
    }
    let mut out = rec.into_owned();
    for (name, column) in positions.iter().zip(predicted) {
        out.set_column(name, column)?;
    }
    Ok((Cow::Owned(out), Some(closed)))
}

/// The share (%) of the measured velocity's and acceleration's variance
/// (each segment low-passed and differentiated) that the predicted
/// motion's holds: `100 (1 - |d - d^|^2 / |d - mean|^2)`. Segments too short
/// for the filter are left out.
fn derivative_shares(
    measured: &[f64],
    predicted: &[f64],
    segments: &[Range<usize>],
    (lp, dt): (&LowPass, f64),
) -> [f64; 2] {
    let mut sums = [[0.0f64; 3]; 2];
    let mut count = 0usize;
    for seg in segments {
        let (Ok(m), Ok(p)) = (
            lp.filtfilt(&measured[seg.clone()]),
            lp.filtfilt(&predicted[seg.clone()]),
        ) else {
            continue;
        };
        count += seg.len();
        let derivatives = [
            (
                limpid_dsp::central_first(&m, dt),
                limpid_dsp::central_first(&p, dt),
            ),
            (
                limpid_dsp::central_second(&m, dt),
                limpid_dsp::central_second(&p, dt),
            ),
        ];
        for (s, (dm, dp)) in sums.iter_mut().zip(&derivatives) {
            for (a, b) in dm.iter().zip(dp) {
                s[0] += (a - b) * (a - b);
                s[1] += a * a;
                s[2] += a;
            }
        }
    }
    let count = count.max(1) as f64;
    sums.map(|[left, squares, sum]| {
        let total = squares - sum * sum / count;
        if total > 0.0 {
            100.0 * (1.0 - left / total)
        } else {
            0.0
        }
    })
}

/// The motion each position column's commanded references predict (in the
/// order of `positions`), when the recording has a reference column for
/// any of them and `open_loop` is false.
pub fn predicted_motion(
    rec: &Recording,
    positions: &[String],
    (open_loop, fit): (bool, ClosedLoopFit),
) -> Result<Option<(Vec<Vec<f64>>, ClosedLoop)>> {
    let references: Vec<String> = positions
        .iter()
        .filter_map(|p| reference_column(p))
        .filter(|r| rec.has(r))
        .collect();
    if open_loop || references.is_empty() {
        return Ok(None);
    }
    let path = rec.path().display().to_string();
    let refs: Vec<&[f64]> = references
        .iter()
        .map(|r| rec.column(r).unwrap_or(&[]))
        .collect();
    if let Some((name, _)) = references
        .iter()
        .zip(&refs)
        .find(|(_, r)| r.iter().all(|v| *v == r[0]))
    {
        return Err(Error::invalid(
            path,
            format!("the reference column {name} never changes, so it cannot serve as an instrument: leave it out, or pass --open-loop if the robot imposed the motion"),
        ));
    }
    let outputs: Vec<&[f64]> = positions
        .iter()
        .map(|p| rec.require(p, "position"))
        .collect::<Result<_>>()?;
    // a measured position written as the reference instruments nothing: it
    // would silently be least squares again
    for (p, q) in positions.iter().zip(&outputs) {
        let same = reference_column(p)
            .and_then(|r| rec.column(&r).map(|c| (r, c)))
            .filter(|(_, c)| c == q);
        if let Some((r, _)) = same {
            return Err(Error::invalid(
                path,
                format!("the reference column {r} holds the same values as {p}: it must be the position the robot was commanded to, not the one it measured (or pass --open-loop)"),
            ));
        }
    }
    let segments = limpid_core::trial::segment_ranges(rec)?;
    let lags = Lags::at(rec.sample_rate());
    let projection = project(&refs, &outputs, &segments, &lags).ok_or_else(|| {
        Error::invalid(
            path.clone(),
            "the motion's projection on the reference columns did not give finite numbers (degenerate reference)",
        )
    })?;
    let fs = rec.sample_rate();
    let (predicted, shares): (Vec<Vec<f64>>, Vec<f64>) = projection.into_iter().unzip();
    Ok(Some((
        predicted,
        ClosedLoop {
            references,
            positions: positions.to_vec(),
            reference_driven_percent: shares,
            lags_s: [
                lags.offsets.first().copied().unwrap_or(0) as f64 / fs,
                lags.offsets.last().copied().unwrap_or(0) as f64 / fs,
            ],
            fit,
            derivative_percent: None,
        },
    )))
}

impl ClosedLoop {
    /// What the reader should know: the estimate is the closed-loop one, its
    /// VAF is that of the reference-driven motion, and a weak instrument.
    pub fn warnings(&self) -> Vec<Warning> {
        let shares: Vec<String> = self
            .positions
            .iter()
            .zip(&self.reference_driven_percent)
            .map(|(p, s)| format!("{s:.0} % of {p}'s"))
            .collect();
        let how = match self.fit {
            ClosedLoopFit::InstrumentalVariables => "the motion it predicts instruments the measured motion in the joint parametric fit (instrumental variables), whose VAF is the measured motion's and leaves the subject's own torque in the residual; the nonparametric pathways and their VAF are fitted on the predicted motion",
            ClosedLoopFit::PredictedMotion => "the model was fitted on the motion it predicts (two-stage least squares); the VAF is that of the force the reference-driven motion explains",
        };
        let mut out = vec![Warning::new(
            WarningCode::ClosedLoop,
            format!(
                "closed loop: the commanded reference ({}) drives {} variance; {how}, so the subject's own force moving the limb does not bias the estimate (--open-loop regresses on the measured motion instead)",
                self.references.join(", "),
                shares.join(", ")
            ),
        )];
        for (p, s) in self.positions.iter().zip(&self.reference_driven_percent) {
            if *s < WEAK_INSTRUMENT_PERCENT {
                out.push(Warning::new(
                    WarningCode::ClosedLoop,
                    format!(
                        "weak instrument: the reference drives only {s:.0} % of {p}'s motion (below {WEAK_INSTRUMENT_PERCENT:.0} %); the estimate stays consistent but is imprecise, and its standard errors may understate the error"
                    ),
                ));
            }
        }
        out
    }
}

/// Samples per block when the FIR is applied (in parallel).
const APPLY_BLOCK: usize = 8192;

/// The FIR's lags in samples (negative: the reference leads the motion).
struct Lags {
    /// Lags, increasing, evenly spaced by `stride`.
    offsets: Vec<isize>,
    stride: usize,
    /// Samples held before a segment (the largest lag) and after it (the lead).
    before: usize,
    after: usize,
}

impl Lags {
    fn at(fs: f64) -> Lags {
        let lead = (LAGS_BEFORE_S * fs).round().max(0.0) as usize;
        let late = (LAGS_AFTER_S * fs).round().max(1.0) as usize;
        let span = lead + late + 1;
        let stride = span.div_ceil(MAX_LAGS).max(1);
        let offsets: Vec<isize> = (0..)
            .map(|a: usize| a * stride)
            .take_while(|s| *s <= lead + late)
            .map(|s| s as isize - lead as isize)
            .collect();
        let before = offsets.last().copied().unwrap_or(0).max(0) as usize;
        Lags {
            offsets,
            stride,
            before,
            after: lead,
        }
    }
}

/// A segment of a centred reference held at its edge values for the FIR's
/// lags: sample `i` of the segment is `padded[before + i]`.
fn padded(r: &[f64], mean: f64, seg: &Range<usize>, lags: &Lags) -> Vec<f64> {
    let first = r[seg.start] - mean;
    let last = r[seg.end - 1] - mean;
    let mut out = Vec::with_capacity(lags.before + seg.len() + lags.after);
    out.extend(std::iter::repeat_n(first, lags.before));
    out.extend(r[seg.clone()].iter().map(|v| v - mean));
    out.extend(std::iter::repeat_n(last, lags.after));
    out
}

/// Start in a padded segment of lag `a`'s column (the reference `offsets[a]` samples earlier).
fn start(lags: &Lags, a: usize) -> usize {
    (lags.before as isize - lags.offsets[a]) as usize
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The exact inner products of every pair of lagged columns of references
/// `i` and `j` over one segment of `n` samples: the first row and column
/// directly, the rest by the shift recursion (moving both lags by one
/// stride adds the products that enter at the start and drops those that
/// leave at the end).
fn gram_block(pi: &[f64], pj: &[f64], n: usize, lags: &Lags) -> DMatrix<f64> {
    let l = lags.offsets.len();
    let mut g = DMatrix::zeros(l, l);
    let col = |p: &[f64], a: usize| p[start(lags, a)..start(lags, a) + n].to_vec();
    let first_i = col(pi, 0);
    let first_j = col(pj, 0);
    // the first row and column: 2 l inner products of the segment's length
    // (most of the work; in parallel)
    let (row, column): (Vec<f64>, Vec<f64>) = (0..l)
        .into_par_iter()
        .map(|a| {
            let s = start(lags, a);
            (dot(&first_i, &pj[s..s + n]), dot(&pi[s..s + n], &first_j))
        })
        .unzip();
    for a in 0..l {
        g[(0, a)] = row[a];
        g[(a, 0)] = column[a];
    }
    let s = lags.stride;
    for a in 1..l {
        for b in 1..l {
            let (sa, sb) = (start(lags, a), start(lags, b));
            // lag a's column starts at sa = start(a-1) - s
            let entering = dot(&pi[sa..sa + s], &pj[sb..sb + s]);
            let leaving = dot(&pi[sa + n..sa + n + s], &pj[sb + n..sb + n + s]);
            g[(a, b)] = g[(a - 1, b - 1)] + entering - leaving;
        }
    }
    g
}

/// Each output's projection on the lagged references, with the share (%) of
/// its variance the projection holds; `None` if the solve fails.
fn project(
    refs: &[&[f64]],
    outputs: &[&[f64]],
    segments: &[Range<usize>],
    lags: &Lags,
) -> Option<Vec<(Vec<f64>, f64)>> {
    let m = refs.len();
    let l = lags.offsets.len();
    let mean = |c: &[f64]| c.iter().sum::<f64>() / c.len() as f64;
    let ref_means: Vec<f64> = refs.iter().map(|r| mean(r)).collect();
    let out_means: Vec<f64> = outputs.iter().map(|o| mean(o)).collect();
    let dim = m * l;
    // normal equations summed over segments, in parallel
    let (gram, cross) = segments
        .par_iter()
        .filter(|s| !s.is_empty())
        .map(|seg| {
            let pads: Vec<Vec<f64>> = refs
                .iter()
                .zip(&ref_means)
                .map(|(r, mu)| padded(r, *mu, seg, lags))
                .collect();
            let n = seg.len();
            let mut g = DMatrix::zeros(dim, dim);
            for i in 0..m {
                for j in i..m {
                    let block = gram_block(&pads[i], &pads[j], n, lags);
                    g.view_mut((i * l, j * l), (l, l)).copy_from(&block);
                    if j != i {
                        g.view_mut((j * l, i * l), (l, l))
                            .copy_from(&block.transpose());
                    }
                }
            }
            let mut c = DMatrix::zeros(dim, outputs.len());
            for (k, (o, mu)) in outputs.iter().zip(&out_means).enumerate() {
                let centred: Vec<f64> = o[seg.clone()].iter().map(|v| v - mu).collect();
                let products: Vec<f64> = (0..dim)
                    .into_par_iter()
                    .map(|ia| {
                        let s = start(lags, ia % l);
                        dot(&pads[ia / l][s..s + n], &centred)
                    })
                    .collect();
                for (ia, v) in products.into_iter().enumerate() {
                    c[(ia, k)] = v;
                }
            }
            (g, c)
        })
        .reduce(
            || (DMatrix::zeros(dim, dim), DMatrix::zeros(dim, outputs.len())),
            |(g1, c1), (g2, c2)| (g1 + g2, c1 + c2),
        );
    let scale = gram.trace() / dim as f64;
    if !(scale.is_finite() && scale > 0.0) {
        return None;
    }
    let coef = (0..4).find_map(|k| {
        let ridge = scale * 1e-10 * 100f64.powi(k);
        let mut a = gram.clone();
        for d in 0..dim {
            a[(d, d)] += ridge;
        }
        a.cholesky().map(|ch| ch.solve(&cross))
    })?;
    let projections: Vec<(Vec<f64>, f64)> = (0..outputs.len())
        .into_par_iter()
        .map(|k| {
            let h = DVector::from_iterator(dim, coef.column(k).iter().copied());
            let mut predicted = vec![out_means[k]; outputs[k].len()];
            for seg in segments.iter().filter(|s| !s.is_empty()) {
                let pads: Vec<Vec<f64>> = refs
                    .iter()
                    .zip(&ref_means)
                    .map(|(r, mu)| padded(r, *mu, seg, lags))
                    .collect();
                // the FIR applied in blocks of samples, in parallel
                predicted[seg.clone()]
                    .par_chunks_mut(APPLY_BLOCK)
                    .enumerate()
                    .for_each(|(b, dest)| {
                        let (at, len) = (b * APPLY_BLOCK, dest.len());
                        for (i, pad) in pads.iter().enumerate() {
                            for a in 0..l {
                                let w = h[i * l + a];
                                let s = start(lags, a) + at;
                                for (d, v) in dest.iter_mut().zip(&pad[s..s + len]) {
                                    *d += w * v;
                                }
                            }
                        }
                    });
            }
            let o = outputs[k];
            let total: f64 = o.iter().map(|v| (v - out_means[k]).powi(2)).sum();
            let left: f64 = o.iter().zip(&predicted).map(|(v, p)| (v - p).powi(2)).sum();
            let share = if total > 0.0 {
                100.0 * (1.0 - left / total)
            } else {
                0.0
            };
            (predicted, share)
        })
        .collect();
    projections
        .iter()
        .all(|(p, s)| s.is_finite() && p.iter().all(|v| v.is_finite()))
        .then_some(projections)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uniform_noise as noise;

    #[test]
    fn the_shift_recursion_gives_the_direct_inner_products() {
        let lags = Lags {
            offsets: vec![-2, 1, 4, 7],
            stride: 3,
            before: 7,
            after: 2,
        };
        let n = 50;
        let pi = noise(n + 9, 1);
        let pj = noise(n + 9, 2);
        let g = gram_block(&pi, &pj, n, &lags);
        for a in 0..4 {
            for b in 0..4 {
                let (sa, sb) = (start(&lags, a), start(&lags, b));
                let direct = dot(&pi[sa..sa + n], &pj[sb..sb + n]);
                assert!((g[(a, b)] - direct).abs() < 1e-12, "{a} {b}");
            }
        }
    }

    #[test]
    fn a_known_fir_is_recovered_and_the_noise_left_out() {
        // q(t) = 0.5 r(t-3) - 0.2 r(t-10) + 0.1 r(t+1) + noise, in two segments
        let n = 20_000;
        let r = noise(n, 7);
        let e = noise(n, 8);
        let mut q = vec![0.0; n];
        let segs = [0..9000, 9000..n];
        for seg in &segs {
            for t in seg.clone() {
                let at = |k: isize| {
                    let u = (t as isize - k).clamp(seg.start as isize, seg.end as isize - 1);
                    r[u as usize]
                };
                q[t] = 0.5 * at(3) - 0.2 * at(10) + 0.1 * at(-1) + 0.3 * e[t];
            }
        }
        let lags = Lags {
            offsets: (-2..=12).collect(),
            stride: 1,
            before: 12,
            after: 2,
        };
        let out = project(&[&r], &[&q], &segs, &lags).unwrap();
        let (predicted, share) = &out[0];
        let signal = 0.5f64.powi(2) + 0.2f64.powi(2) + 0.1f64.powi(2);
        let want = 100.0 * signal / (signal + 0.09);
        assert!((share - want).abs() < 1.5, "{share} vs {want}");
        // the residual is the noise (uncorrelated with the reference)
        let resid: Vec<f64> = q.iter().zip(predicted).map(|(a, b)| a - b).collect();
        let corr = dot(&resid, &e) / (dot(&resid, &resid) * dot(&e, &e)).sqrt();
        assert!(corr > 0.99, "{corr}");
    }

    #[test]
    fn reference_names_follow_the_format() {
        assert_eq!(reference_column("q2").as_deref(), Some("r2"));
        assert_eq!(reference_column("x").as_deref(), Some("rx"));
        assert_eq!(reference_column("theta").as_deref(), Some("rtheta"));
        assert_eq!(reference_column("q"), None);
        assert_eq!(reference_column("angle"), None);
    }
}
