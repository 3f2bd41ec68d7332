//! The reflex pathway of the parameter-varying fit: its drives, and the scan
//! and pattern search that choose its delay, low-pass and polarity.

use nalgebra::DMatrix;
use rayon::prelude::*;

use limpid_core::Result;
use limpid_dsp::LowPass;

use super::design::Design;
use super::rows::{remove_line, Rows, Trend};
use super::{solve_scaled, VaryingParams, REFLEX_DAMPING, REFLEX_NATURAL_HZ};

/// Reflex columns at the kept rows (`top + 1` per row): each degree's
/// drive (see [`reflex_drives`]) detrended.
pub(super) fn reflex_columns(
    rows: &Rows,
    drives: &[Vec<Vec<f64>>],
    slow: &LowPass,
) -> Result<Vec<f64>> {
    let p1 = rows.top + 1;
    let mut out = vec![0.0; rows.len() * p1];
    let mut row0 = 0;
    for (seg, degrees) in rows.segments.iter().zip(drives) {
        for (i, drive) in degrees.iter().enumerate().take(p1) {
            let col = seg.detrend(slow, drive)?;
            for (k, &t) in seg.kept.iter().enumerate() {
                out[(row0 + k) * p1 + i] = col[t];
            }
        }
        row0 += seg.kept.len();
    }
    Ok(out)
}

/// The reflex drives of one low-pass and polarity, per segment and degree
/// `i <= order`: `± LP2(T_i(σ(t)) rect(±x'(t - d)))`. The gain multiplies the
/// rectified velocity before the low-pass (the motoneurons' gain, ahead of
/// the muscle's activation dynamics), so a gain that changes during a ramp
/// of the schedule is modelled as it acts.
pub(super) fn reflex_drives(
    rows: &Rows,
    (natural_hz, zeta, positive): (f64, f64, bool),
    order: usize,
    delay_quarters: usize,
    fs: f64,
) -> Vec<Vec<Vec<f64>>> {
    let sign = if positive { 1.0 } else { -1.0 };
    rows.segments
        .iter()
        .map(|seg| {
            let v = &seg.reflex_velocity;
            let rect: Vec<f64> = (0..v.len())
                .map(|t| {
                    let x = delayed(v, t, delay_quarters);
                    if positive {
                        x.max(0.0)
                    } else {
                        (-x).max(0.0)
                    }
                })
                .collect();
            seg.basis
                .iter()
                .take(order + 1)
                .map(|b| {
                    let product: Vec<f64> = b.iter().zip(&rect).map(|(x, r)| x * r).collect();
                    crate::reflex::low_pass(&product, natural_hz, zeta, fs)
                        .into_iter()
                        .map(|v| sign * v)
                        .collect()
                })
                .collect()
        })
        .collect()
}

/// `x(t - q/4)`, linearly interpolated (the drive is low-passed far below
/// the sample rate); the start of the segment repeats before it.
pub(super) fn delayed(x: &[f64], t: usize, quarters: usize) -> f64 {
    let whole = quarters / 4;
    let frac = (quarters % 4) as f64 / 4.0;
    let a = x[t.saturating_sub(whole)];
    let b = x[t.saturating_sub(whole + 1)];
    a + frac * (b - a)
}

pub(super) struct ReflexChoice {
    pub(super) natural_hz: f64,
    pub(super) damping_ratio: f64,
    pub(super) positive: bool,
    /// Delay in quarter samples.
    pub(super) delay: usize,
    /// The delay chosen is the longest scanned: the true one may lie beyond.
    pub(super) at_scan_end: bool,
    pub(super) columns: Vec<f64>,
}

/// Residuals of the fit with one candidate reflex pathway added to the
/// intrinsic design: the intrinsic part's cross products are formed once,
/// each candidate adds only its own columns' (a bordered Gram matrix).
struct BorderedFit<'a> {
    rows: &'a Rows,
    /// Intrinsic regressors, row-major, `intrinsic` per row.
    regressors: Vec<f64>,
    intrinsic: usize,
    gram: DMatrix<f64>,
    moment: DMatrix<f64>,
    force_ss: f64,
    /// Reflex columns (`order + 1`).
    reflex: usize,
}

/// A reflex drive per segment and degree, detrended, full rate.
type Products = Vec<Vec<Vec<f64>>>;

/// Per segment, the low-pass's two free responses from its start (full
/// rate, each segment's straight line removed), for the segments whose
/// operating point is a line (too short for the slow low-pass): the reflex
/// in flight at the cut, answering motion before it (Ludvig & Perreault
/// 2012's transient terms). `None` for a long segment, whose first 0.5 s are
/// left out instead.
pub(super) type Free = Vec<Option<[Vec<f64>; 2]>>;

/// A candidate pathway's drives and its transients.
type Drives = (Products, Free);

/// [`Free`] of the low-pass `(natural Hz, damping ratio)`.
pub(super) fn free_drives(rows: &Rows, (natural_hz, zeta): (f64, f64), fs: f64) -> Free {
    rows.segments
        .iter()
        .map(|seg| {
            (seg.trend == Trend::Line).then(|| {
                let n = seg.sigma.len();
                let whole: Vec<std::ops::Range<usize>> = std::iter::once(0..n).collect();
                crate::reflex::free_responses((natural_hz, zeta, fs), &whole, n)
                    .map(|h| remove_line(&h))
            })
        })
        .collect()
}

/// The free responses of `free` delayed by `delay` quarter samples at a
/// segment's kept rows (then its line removed there), orthonormalised.
fn transients(seg: &super::rows::Segment, free: &[Vec<f64>; 2], delay: usize) -> Vec<Vec<f64>> {
    let at_kept = |h: &Vec<f64>| -> Vec<f64> {
        let shifted: Vec<f64> = (0..h.len()).map(|t| delayed(h, t, delay)).collect();
        let line = remove_line(&shifted);
        seg.kept.iter().map(|&t| line[t]).collect()
    };
    crate::reflex::orthonormal(&free.each_ref().map(at_kept))
}

/// Projects the reflex in flight at each short segment's cut (see [`Free`])
/// out of the rows' products and forces and the reflex columns (`p1` per
/// row), in place: the fit then carries two free coefficients per segment.
pub(super) fn project_transients(
    rows: &mut Rows,
    others: &mut [&mut Rows],
    columns: &mut [f64],
    p1: usize,
    (free, delay): (&Free, usize),
) {
    let mut row0 = 0;
    for (s, seg_free) in free.iter().enumerate() {
        let kept = rows.segments[s].kept.len();
        if let Some(h) = seg_free {
            let basis = transients(&rows.segments[s], h, delay);
            let project = |data: &mut [f64], stride: usize| {
                for c in 0..stride {
                    for b in &basis {
                        let k: f64 = (0..kept)
                            .map(|r| data[(row0 + r) * stride + c] * b[r])
                            .sum();
                        for (r, bv) in b.iter().enumerate() {
                            data[(row0 + r) * stride + c] -= k * bv;
                        }
                    }
                }
            };
            let (width, d) = (rows.width, rows.d);
            project(&mut rows.x, width);
            project(&mut rows.f, d);
            project(columns, p1);
            for other in others.iter_mut() {
                project(&mut other.x, width);
                project(&mut other.f, d);
            }
        }
        row0 += kept;
    }
}

impl<'a> BorderedFit<'a> {
    fn new(rows: &'a Rows, order: usize) -> Self {
        let base = Design {
            rows,
            order,
            reflex: None,
        };
        let intrinsic = base.columns();
        let mut regressors = vec![0.0; rows.len() * intrinsic];
        for (r, row) in regressors.chunks_mut(intrinsic).enumerate() {
            base.row(r, row);
        }
        let (gram, moment, yy) = base.folds(1).swap_remove(0);
        BorderedFit {
            rows,
            regressors,
            intrinsic,
            gram,
            moment,
            force_ss: yy[0],
            reflex: order + 1,
        }
    }

    /// Residual sum of squares with the reflex drives `prod` delayed by
    /// `delay` quarter samples (and, in short segments, the low-pass's free
    /// responses `free` projected out); `None` if the design is singular.
    fn rss(&self, (prod, free): &Drives, delay: usize) -> Option<f64> {
        let (qa, p1) = (self.intrinsic, self.reflex);
        let mut c = DMatrix::<f64>::zeros(qa, p1);
        let mut dd = DMatrix::<f64>::zeros(p1, p1);
        let mut e = DMatrix::<f64>::zeros(p1, 1);
        let mut rv = vec![0.0; p1];
        let mut row0 = 0;
        // what the segments' transients take from the augmented Gram matrix [X R y]
        let q = qa + p1;
        let mut taken = DMatrix::<f64>::zeros(q + 1, q + 1);
        for ((seg, pr), seg_free) in self.rows.segments.iter().zip(prod).zip(free) {
            if let Some(h) = seg_free {
                // Frisch-Waugh per segment: Z'W with Z the orthonormal transients
                for b in transients(seg, h, delay) {
                    let mut zw = vec![0.0; q + 1];
                    for (k, &t) in seg.kept.iter().enumerate() {
                        let r = row0 + k;
                        let bv = b[k];
                        for (m, &x) in self.regressors[r * qa..(r + 1) * qa].iter().enumerate() {
                            zw[m] += bv * x;
                        }
                        for (i, p) in pr.iter().enumerate() {
                            zw[qa + i] += bv * delayed(p, t, delay);
                        }
                        zw[q] += bv * self.rows.f[r];
                    }
                    for i in 0..=q {
                        for j in 0..=q {
                            taken[(i, j)] += zw[i] * zw[j];
                        }
                    }
                }
            }
            for (k, &t) in seg.kept.iter().enumerate() {
                let r = row0 + k;
                for (i, p) in pr.iter().enumerate() {
                    rv[i] = delayed(p, t, delay);
                }
                let ar = &self.regressors[r * qa..(r + 1) * qa];
                let y = self.rows.f[r];
                for i in 0..p1 {
                    let v = rv[i];
                    e[(i, 0)] += v * y;
                    for j in i..p1 {
                        dd[(i, j)] += v * rv[j];
                    }
                    for (m, &x) in ar.iter().enumerate() {
                        c[(m, i)] += x * v;
                    }
                }
            }
            row0 += seg.kept.len();
        }
        let g = DMatrix::from_fn(q, q, |i, j| {
            let v = match (i < qa, j < qa) {
                (true, true) => self.gram[(i, j)],
                (true, false) => c[(i, j - qa)],
                (false, true) => c[(j, i - qa)],
                (false, false) => dd[((i - qa).min(j - qa), (i - qa).max(j - qa))],
            };
            v - taken[(i, j)]
        });
        let h = DMatrix::from_fn(q, 1, |i, _| {
            let v = if i < qa {
                self.moment[(i, 0)]
            } else {
                e[(i - qa, 0)]
            };
            v - taken[(i, q)]
        });
        let force_ss = self.force_ss - taken[(q, q)];
        solve_scaled(&g, &h).map(|t| force_ss - (t.transpose() * &h)[(0, 0)])
    }

    /// The delay of least residual among `delays` (quarter samples), with
    /// that residual; the first of equals.
    fn best_delay(
        &self,
        prod: &Drives,
        delays: impl IntoIterator<Item = usize>,
    ) -> Option<(usize, f64)> {
        let delays: Vec<usize> = delays.into_iter().collect();
        delays
            .par_iter()
            .filter_map(|&dl| self.rss(prod, dl).map(|r| (dl, r)))
            .collect::<Vec<_>>()
            .into_iter()
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }
}

/// Delay, low-pass and polarity of the reflex with the least residual at
/// `order`. The scan shifts the detrended product of the undelayed drive
/// (σ barely moves within a delay); the chosen one is then built exactly.
/// Every low-pass and polarity is scanned in 5 ms steps (damping ratio
/// 0.7); the best of them is refined to a sample, then to a quarter sample,
/// then natural frequency, damping ratio and delay together
/// ([`pattern_search`]).
pub(super) fn scan_reflex(
    rows: &Rows,
    order: usize,
    params: &VaryingParams,
    slow: &LowPass,
    fs: f64,
    trim: usize,
) -> Result<Option<ReflexChoice>> {
    // in quarter samples
    let max_delay = 4 * ((params.max_delay_s * fs).round() as usize).min(trim - 1);
    let step = 4 * ((0.005 * fs).round() as usize).max(1);
    let fit = BorderedFit::new(rows, order);
    // each degree's drive, detrended, full rate, per segment
    let products = |hz: f64, zeta: f64, positive: bool| -> Result<Drives> {
        let prod = reflex_drives(rows, (hz, zeta, positive), order, 0, fs)
            .iter()
            .zip(&rows.segments)
            .map(|(degrees, seg)| degrees.iter().map(|d| seg.detrend(slow, d)).collect())
            .collect::<Result<Products>>()?;
        Ok((prod, free_drives(rows, (hz, zeta), fs)))
    };
    let candidates: Vec<(f64, bool)> = REFLEX_NATURAL_HZ
        .iter()
        .filter(|&&hz| hz < 0.45 * fs)
        .flat_map(|&hz| [(hz, true), (hz, false)])
        .collect();
    // (rss, natural frequency, polarity, delay, drives)
    let mut best: Option<(f64, f64, bool, usize, Drives)> = None;
    for &(natural_hz, positive) in &candidates {
        let prod = products(natural_hz, REFLEX_DAMPING, positive)?;
        if let Some((delay, rss)) = fit.best_delay(&prod, (0..=max_delay).step_by(step)) {
            if best.as_ref().is_none_or(|b| rss < b.0) {
                best = Some((rss, natural_hz, positive, delay, prod));
            }
        }
    }
    let Some((_, natural_hz, positive, coarse_best, prod)) = best else {
        return Ok(None);
    };
    // the delay refined at the coarse low-pass, then all three together
    let near = |around: usize, reach: usize, by: usize| -> usize {
        let delays = (around.saturating_sub(reach)..=(around + reach).min(max_delay)).step_by(by);
        fit.best_delay(&prod, delays).map_or(around, |b| b.0)
    };
    let delay = near(near(coarse_best, step, 4), 3, 1);
    let (natural_hz, zeta, delay) = pattern_search(
        (natural_hz, REFLEX_DAMPING, delay),
        fit.rss(&prod, delay).unwrap_or(f64::INFINITY),
        0.45 * fs,
        max_delay,
        &|hz, zeta| products(hz, zeta, positive),
        &fit,
    )?;
    Ok(Some(ReflexChoice {
        natural_hz,
        damping_ratio: zeta,
        positive,
        delay,
        // within the last sample of the scan
        at_scan_end: delay + 4 > max_delay,
        columns: reflex_columns(
            rows,
            &reflex_drives(rows, (natural_hz, zeta, positive), rows.top, delay, fs),
            slow,
        )?,
    }))
}

/// Pattern search over the low-pass (natural frequency, damping ratio), each
/// candidate with its best delay within 2 samples: a faster low-pass trades
/// off against a longer delay, and refining one at a time had stopped on
/// that ridge 10-17 % and 4-6 ms from the truth, K 10 % high at 4-5 SE
/// (issue 37). Steps start at 2^(1/8) (9 %) and 0.1 and halve when no try
/// improves; the last tried are 2.2 % and 0.025.
fn pattern_search(
    start: (f64, f64, usize),
    start_rss: f64,
    max_hz: f64,
    max_delay: usize,
    products: &(dyn Fn(f64, f64) -> Result<Drives> + Sync),
    fit: &BorderedFit<'_>,
) -> Result<(f64, f64, usize)> {
    // within 2 samples every other quarter, then the quarters beside the best
    let near_best = |prod: &Drives, around: usize| -> Option<(usize, f64)> {
        let lo = around.saturating_sub(8);
        let coarse = fit.best_delay(prod, (lo..=(around + 8).min(max_delay)).step_by(2))?;
        fit.best_delay(
            prod,
            coarse.0.saturating_sub(1)..=(coarse.0 + 1).min(max_delay),
        )
    };
    let (mut at, mut rss) = (start, start_rss);
    let (mut hz_step, mut zeta_step) = (2f64.powf(1.0 / 8.0), 0.1);
    for _ in 0..40 {
        if hz_step < 1.02 && zeta_step < 0.025 {
            break;
        }
        let (hz, zeta, delay) = at;
        let tries: Vec<(f64, f64)> = [
            (hz * hz_step, zeta),
            (hz / hz_step, zeta),
            (hz, zeta + zeta_step),
            (hz, zeta - zeta_step),
        ]
        .into_iter()
        .filter(|&(h, z)| h < max_hz && (0.3..=1.5).contains(&z))
        .collect();
        let found = tries
            .par_iter()
            .map(|&(h, z)| -> Result<Option<(f64, f64, usize, f64)>> {
                let prod = products(h, z)?;
                Ok(near_best(&prod, delay).map(|(dl, r)| (h, z, dl, r)))
            })
            .collect::<Result<Vec<_>>>()?;
        match found
            .into_iter()
            .flatten()
            .min_by(|a, b| a.3.total_cmp(&b.3))
        {
            Some((h, z, dl, r)) if r < rss => {
                (at, rss) = ((h, z, dl), r);
            }
            _ => {
                hz_step = hz_step.sqrt();
                zeta_step /= 2.0;
            }
        }
    }
    Ok(at)
}
