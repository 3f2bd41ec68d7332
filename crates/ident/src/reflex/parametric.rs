//! The parametric models of the pathways: intrinsic I, B, K by least squares, the reflex (rectified velocity, delay, gain, second-order low-pass) fitted jointly over delays, with jackknife standard errors inflated for autocorrelated residuals.

use super::cascade::{centre, correlation, mean, vaf, variance};
use super::instrumental::{fixed_iv, joint_fit_iv, joint_jackknife_iv, residual_iv, FixedIv};
use super::segments::{gather, groups};
use super::transients::{GroupSums, SegmentRows};
use super::{Decimated, Ibk, ReflexParams};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::borrow::Cow;
use std::ops::Range;
/// The torque of the intrinsic I-B-K model (centred).
pub(crate) fn parametric_intrinsic(d: &Decimated, p: &Ibk) -> Vec<f64> {
    (0..d.torque.len())
        .map(|t| {
            p.inertia * d.acceleration[t] + p.damping * d.velocity[t] + p.stiffness * d.position[t]
        })
        .collect()
}

/// I-B-K (with a constant) by least squares on `rows[skip..]`, with
/// 10-block jackknife standard errors, and the fit's VAF.
pub(crate) fn ibk_fit(regressors: &[&[f64]; 3], y: &[f64], skip: usize) -> (Ibk, Ibk, f64) {
    let n = y.len();
    let rows = skip..n;
    let scale: Vec<f64> = regressors
        .iter()
        .map(|x| variance(&x[rows.clone()]).sqrt().max(f64::MIN_POSITIVE))
        .collect();
    let blocks = 10;
    let len = rows.len();
    let mut grams = vec![(DMatrix::<f64>::zeros(4, 4), DVector::<f64>::zeros(4)); blocks];
    for (b, (g, r)) in grams.iter_mut().enumerate() {
        for t in skip + b * len / blocks..skip + (b + 1) * len / blocks {
            let x = [
                regressors[0][t] / scale[0],
                regressors[1][t] / scale[1],
                regressors[2][t] / scale[2],
                1.0,
            ];
            for i in 0..4 {
                r[i] += x[i] * y[t];
                for j in 0..4 {
                    g[(i, j)] += x[i] * x[j];
                }
            }
        }
    }
    let solve = |skip_block: Option<usize>| -> [f64; 3] {
        let mut g = DMatrix::<f64>::zeros(4, 4);
        let mut r = DVector::<f64>::zeros(4);
        for (b, (gb, rb)) in grams.iter().enumerate() {
            if Some(b) != skip_block {
                g += gb;
                r += rb;
            }
        }
        let th = g
            .clone()
            .cholesky()
            .map(|c| c.solve(&r))
            .or_else(|| g.lu().solve(&r));
        match th {
            Some(th) => [th[0] / scale[0], th[1] / scale[1], th[2] / scale[2]],
            None => [f64::NAN; 3],
        }
    };
    let full = solve(None);
    let reps: Vec<[f64; 3]> = (0..blocks).map(|b| solve(Some(b))).collect();
    let se: Vec<f64> = (0..3)
        .map(|k| {
            let m = reps.iter().map(|r| r[k]).sum::<f64>() / blocks as f64;
            let ss: f64 = reps.iter().map(|r| (r[k] - m).powi(2)).sum();
            (ss * (blocks - 1) as f64 / blocks as f64).sqrt()
        })
        .collect();
    let fitted: Vec<f64> = (0..n)
        .map(|t| {
            full[0] * regressors[0][t] + full[1] * regressors[1][t] + full[2] * regressors[2][t]
        })
        .collect();
    let v = vaf(y, &fitted, skip);
    (
        Ibk {
            inertia: full[0],
            damping: full[1],
            stiffness: full[2],
        },
        Ibk {
            inertia: se[0],
            damping: se[1],
            stiffness: se[2],
        },
        v,
    )
}

/// The bilinear transform's coefficients `(b, a1, a2)` of [`low_pass`].
pub(crate) fn low_pass_coefficients(natural_hz: f64, zeta: f64, fs: f64) -> ([f64; 3], f64, f64) {
    let w = 2.0 * std::f64::consts::PI * natural_hz;
    let k = w / (w / (2.0 * fs)).tan();
    let a0 = k * k + 2.0 * zeta * w * k + w * w;
    let b = [w * w / a0, 2.0 * w * w / a0, w * w / a0];
    let a1 = (2.0 * w * w - 2.0 * k * k) / a0;
    let a2 = (k * k - 2.0 * zeta * w * k + w * w) / a0;
    (b, a1, a2)
}

/// Unit-DC second-order low-pass by the bilinear transform, prewarped at its natural frequency.
pub(crate) fn low_pass(x: &[f64], natural_hz: f64, zeta: f64, fs: f64) -> Vec<f64> {
    let (b, a1, a2) = low_pass_coefficients(natural_hz, zeta, fs);
    let mut y = vec![0.0; x.len()];
    // start in the steady state of the first sample (unit DC gain)
    let x0 = x.first().copied().unwrap_or(0.0);
    let (mut x1, mut x2, mut y1, mut y2) = (x0, x0, x0, x0);
    for (yi, &xi) in y.iter_mut().zip(x) {
        let v = b[0] * xi + b[1] * x1 + b[2] * x2 - a1 * y1 - a2 * y2;
        x2 = x1;
        x1 = xi;
        y2 = y1;
        y1 = v;
        *yi = v;
    }
    y
}

pub(crate) struct Parametric {
    pub(crate) intrinsic: Ibk,
    pub(crate) intrinsic_se: Ibk,
    pub(crate) gain: f64,
    pub(crate) gain_se: f64,
    pub(crate) delay_s: f64,
    pub(crate) interval: [f64; 2],
    pub(crate) interval_contiguous: bool,
    pub(crate) at_scan_edge: bool,
    pub(crate) natural_hz: f64,
    pub(crate) damping_ratio: f64,
    pub(crate) total_vaf: f64,
    pub(crate) intrinsic_only_vaf: f64,
    pub(crate) scan_delays_s: Vec<f64>,
    pub(crate) scan_vaf: Vec<f64>,
    /// Decimated samples left out at each segment's start by the fit of I, B, K, G.
    pub(crate) start_left_out: usize,
    /// What the delay and low-pass inside their 95 % profile region move
    /// I, B, K, G by (already in the standard errors).
    pub(crate) profile_shift: [f64; 4],
}

/// The I-B-K regressors over the fitted rows, centred (per segment), with
/// their Gram matrix inverse, the I-B-K-only solution and its residual.
pub(crate) struct Fixed {
    /// Each segment's rows among the fitted rows (one group for a continuous record).
    pub(crate) groups: Vec<Range<usize>>,
    pub(crate) columns: [Vec<f64>; 3],
    pub(crate) gram_inv: nalgebra::Matrix3<f64>,
    pub(crate) theta: nalgebra::Vector3<f64>,
    pub(crate) residual: Vec<f64>,
    pub(crate) rss: f64,
    pub(crate) total_ss: f64,
}

impl Fixed {
    /// The centred torque over the fitted rows: the I-B-K fit plus its residual.
    pub(crate) fn torque(&self) -> Vec<f64> {
        (0..self.residual.len())
            .map(|t| {
                self.residual[t]
                    + self.theta.dot(&nalgebra::Vector3::new(
                        self.columns[0][t],
                        self.columns[1][t],
                        self.columns[2][t],
                    ))
            })
            .collect()
    }
}

pub(crate) fn fixed_fit(d: &Decimated, skip: usize) -> Option<Fixed> {
    let groups = groups(&d.segments, skip);
    let centred = |x: &[f64]| {
        let mut c = gather(x, &d.segments, skip).into_owned();
        for g in &groups {
            centre(&mut c[g.clone()]);
        }
        c
    };
    let columns = [
        centred(&d.acceleration),
        centred(&d.velocity),
        centred(&d.position),
    ];
    fixed_from(columns, centred(&d.torque), groups)
}

/// [`Fixed`] of centred columns and torque.
pub(crate) fn fixed_from(
    columns: [Vec<f64>; 3],
    y: Vec<f64>,
    groups: Vec<Range<usize>>,
) -> Option<Fixed> {
    let mut g = nalgebra::Matrix3::<f64>::zeros();
    let mut r = nalgebra::Vector3::<f64>::zeros();
    for i in 0..3 {
        r[i] = dot(&columns[i], &y);
        for j in 0..3 {
            g[(i, j)] = dot(&columns[i], &columns[j]);
        }
    }
    let gram_inv = g.try_inverse()?;
    let theta = gram_inv * r;
    let residual: Vec<f64> = (0..y.len())
        .map(|t| {
            y[t] - theta[0] * columns[0][t] - theta[1] * columns[1][t] - theta[2] * columns[2][t]
        })
        .collect();
    Some(Fixed {
        groups,
        rss: dot(&residual, &residual),
        total_ss: dot(&y, &y),
        columns,
        gram_inv,
        theta,
        residual,
    })
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Residual sum of squares and `[I, B, K, G]` of the joint model
/// `tq = I q'' + B q' + K q + G x + c` (a constant `c` per segment) for one
/// reflex regressor `x` (over the fitted rows).
pub(crate) fn joint_fit(f: &Fixed, x: &[f64]) -> (f64, [f64; 4]) {
    let [c0, c1, c2] = &f.columns;
    let (mut xx, mut xe, mut b0, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    // the segments' constants: sum over segments of (sum of x)^2 / rows
    let mut between = 0.0;
    for g in &f.groups {
        let m = g.len() as f64;
        let mut sx = 0.0;
        let g = g.clone();
        // one pass over memory: the six sums the Schur complement needs
        for ((((&xv, &e), &a0), &a1), &a2) in x[g.clone()]
            .iter()
            .zip(&f.residual[g.clone()])
            .zip(&c0[g.clone()])
            .zip(&c1[g.clone()])
            .zip(&c2[g])
        {
            sx += xv;
            xx += xv * xv;
            xe += xv * e;
            b0 += xv * a0;
            b1 += xv * a1;
            b2 += xv * a2;
        }
        between += sx * sx / m;
    }
    let b = nalgebra::Vector3::new(b0, b1, b2);
    let xx_resid = xx - between - (b.transpose() * f.gram_inv * b)[0];
    if xx_resid <= 1e-12 * xx {
        return (f.rss, [f.theta[0], f.theta[1], f.theta[2], 0.0]);
    }
    let gain = xe / xx_resid;
    let t = f.theta - f.gram_inv * b * gain;
    ((f.rss - xe * gain).max(0.0), [t[0], t[1], t[2], gain])
}

/// Decimation phases of `y`: `phases[r][k] = y[k ratio - r]` (zero before the record).
pub(crate) fn phases(y: &[f64], ratio: usize, n: usize) -> Vec<Vec<f64>> {
    (0..ratio)
        .map(|r| {
            (0..n)
                .map(|k| {
                    if k * ratio >= r {
                        y.get(k * ratio - r).copied().unwrap_or(0.0)
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect()
}

/// The reflex regressor over the fitted rows (each segment's past its first
/// `skip`) for a delay of `delay` recorded samples: one decimation phase,
/// a slice of it for a continuous record.
pub(crate) fn delayed<'a>(
    phases: &'a [Vec<f64>],
    ratio: usize,
    delay: usize,
    skip: usize,
    segments: &[Range<usize>],
) -> Cow<'a, [f64]> {
    let (m, r) = (delay / ratio, delay % ratio);
    match segments {
        [whole] if whole.start == 0 => Cow::Borrowed(&phases[r][skip - m..whole.end - m]),
        _ => Cow::Owned(
            segments
                .iter()
                .flat_map(|s| (s.start + skip).min(s.end) - m..s.end - m)
                .map(|k| phases[r][k])
                .collect(),
        ),
    }
}

/// [`low_pass`] of each segment on its own (full-rate ranges).
pub(crate) fn low_pass_in(
    x: &[f64],
    (natural_hz, zeta, fs): (f64, f64, f64),
    segments: &[Range<usize>],
) -> Vec<f64> {
    match segments {
        [whole] if *whole == (0..x.len()) => low_pass(x, natural_hz, zeta, fs),
        _ => {
            let mut y = vec![0.0; x.len()];
            for s in segments {
                y[s.clone()].copy_from_slice(&low_pass(&x[s.clone()], natural_hz, zeta, fs));
            }
            y
        }
    }
}

/// The fully parametric model, fitted jointly: intrinsic I-B-K plus
/// rectified velocity -> delay -> gain -> unit-DC second-order low-pass. For
/// a given delay and low-pass the model is linear in I, B, K, G; delay and
/// low-pass are scanned (delays on the recorded rate's grid).
///
/// With `instrument` (the decimated motion a commanded reference predicts,
/// closed loop, one continuous record) the fits are instrumental-variable
/// ones ([`super::instrumental`]).
pub(crate) fn reflex_parametric(
    d: &Decimated,
    polarity: usize,
    skip: usize,
    p: &ReflexParams,
    (fs, instrument): (f64, Option<&Decimated>),
) -> Option<Parametric> {
    let f = fixed_fit(d, skip)?;
    let iv = match instrument {
        // (one continuous record: the least-squares fit's centred columns are the measured ones)
        Some(di) => Some(fixed_iv(&f, (d, di), skip)?),
        None => None,
    };
    let full_z = instrument.map(|di| &di.rectified_full[polarity][..]);
    let n = d.torque.len();
    let full = &d.rectified_full[polarity];
    let full_segments = match d.segments.as_slice() {
        [_] => std::iter::once(0..full.len()).collect(),
        many => super::segments::full_rate(many, d.ratio),
    };
    let max_delay = (p.max_delay_s * fs).round() as usize;
    let delays = max_delay + 1;
    // several segments: every fit with the reflex in flight at each cut
    let rows = (d.segments.len() > 1).then(|| SegmentRows::new(d, skip));
    let sums = rows.as_ref().map(SegmentRows::sums);
    let Scan { combos, fits } = scan_low_pass_and_delay(
        d,
        (&f, rows.as_ref().zip(sums.as_deref())),
        (full, &full_segments),
        iv.as_ref().zip(full_z),
        max_delay,
        (skip, fs),
    )?;
    let (rss_min, ci, delay) = best(&fits);
    let (w, z) = combos[ci];
    let profile: Vec<f64> = (0..delays)
        .map(|dl| {
            fits.iter()
                .map(|row| row[dl].0)
                .fold(f64::INFINITY, f64::min)
        })
        .collect();

    // the joint fit at the optimum, its residual and jackknife errors
    let ph = phases(&low_pass_in(full, (w, z, fs), &full_segments), d.ratio, n);
    let x = delayed(&ph, d.ratio, delay, skip, &d.segments);
    let at_best = fits[ci][delay].1;
    // the low-pass's free responses: only short segments fit them
    let free = rows
        .as_ref()
        .map(|_| SegmentRows::free_phases(d, (w, z, fs), &full_segments));
    let z_best = full_z.map(|zf| {
        let ph = phases(&low_pass_in(zf, (w, z, fs), &full_segments), d.ratio, n);
        delayed(&ph, d.ratio, delay, skip, &d.segments).into_owned()
    });
    let resid = match (rows.as_ref().zip(free.as_ref()), iv.as_ref()) {
        (_, Some(iv)) => residual_iv(iv, &x, at_best),
        (None, None) => joint_residual(&f, &x, at_best),
        (Some((rows, free)), None) => {
            let (g, x) = rows.fit(d, (&ph, free), delay)?;
            joint_residual(&g, &x, at_best)
        }
    };
    let inflation = autocorrelation_inflation(&resid);
    let m = x.len() as f64;
    let n_eff = (m / inflation).max(5.0);
    let threshold = rss_min * (1.0 + 3.84 / n_eff);
    let (lo, hi, contiguous) = delay_interval(&profile, threshold, delay);
    let (params, mut se, start_left_out) = match (&free, iv.as_ref().zip(z_best.as_deref())) {
        (_, Some((iv, zb))) => (at_best, joint_jackknife_iv(iv, &x, zb), skip),
        (None, None) => (at_best, joint_jackknife(&f, &x), skip),
        (Some(free), None) => {
            // the scan left out every segment's start up to the longest
            // delay scanned; the fit at the optimum needs it left out only
            // up to the delay interval's end
            let settled = super::segments::start_up(hi, d.ratio).min(skip);
            let (g, x) = SegmentRows::new(d, settled).fit(d, (&ph, free), delay)?;
            (joint_fit(&g, &x).1, joint_jackknife(&g, &x), settled)
        }
    };
    // the jackknife holds the delay and low-pass fixed: add what they move
    let shift = profile_region_shift(&fits, threshold, at_best);
    for (e, s) in se.iter_mut().zip(shift) {
        *e = e.hypot(s);
    }
    Some(Parametric {
        profile_shift: shift,
        intrinsic: Ibk {
            inertia: params[0],
            damping: params[1],
            stiffness: params[2],
        },
        intrinsic_se: Ibk {
            inertia: se[0],
            damping: se[1],
            stiffness: se[2],
        },
        gain: params[3],
        gain_se: se[3],
        delay_s: delay as f64 / fs,
        interval: [lo as f64 / fs, hi as f64 / fs],
        interval_contiguous: contiguous,
        at_scan_edge: delay == 0 || delay == max_delay,
        natural_hz: w,
        damping_ratio: z,
        total_vaf: 100.0 * (1.0 - rss_min / f.total_ss),
        intrinsic_only_vaf: 100.0 * (1.0 - iv.as_ref().map_or(f.rss, |iv| iv.rss) / f.total_ss),
        scan_delays_s: (0..delays).map(|i| i as f64 / fs).collect(),
        scan_vaf: profile
            .iter()
            .map(|r| 100.0 * (1.0 - r / f.total_ss))
            .collect(),
        start_left_out,
    })
}

/// The joint model's residual at `[I, B, K, G]`, from the I-B-K-only fit's
/// (each segment's constant refitted).
fn joint_residual(f: &Fixed, x: &[f64], [i, b, k, gain]: [f64; 4]) -> Vec<f64> {
    let theta = nalgebra::Vector3::new(i, b, k);
    let mut resid = Vec::with_capacity(x.len());
    for g in &f.groups {
        let xm = mean(&x[g.clone()]);
        resid.extend(g.clone().map(|t| {
            f.residual[t] - gain * (x[t] - xm)
                + (f.theta - theta).dot(&nalgebra::Vector3::new(
                    f.columns[0][t],
                    f.columns[1][t],
                    f.columns[2][t],
                ))
        }));
    }
    resid
}

/// RSS and `[I, B, K, G]` per low-pass (row) and delay (column); delays a
/// stage did not fit have an infinite RSS.
type ScanFits = Vec<Vec<(f64, [f64; 4])>>;

/// The low-passes `(natural frequency Hz, damping ratio)` scanned and their fits.
struct Scan {
    combos: Vec<(f64, f64)>,
    fits: ScanFits,
}

/// The lowest RSS of a scan: (RSS, low-pass index, delay).
fn best(fits: &[Vec<(f64, [f64; 4])>]) -> (f64, usize, usize) {
    let mut b = (f64::INFINITY, 0, 0);
    for (ci, row) in fits.iter().enumerate() {
        for (dl, &(rss, _)) in row.iter().enumerate() {
            if rss < b.0 {
                b = (rss, ci, dl);
            }
        }
    }
    b
}

/// Scan the reflex low-pass and delay in three stages: a coarse grid of 10
/// natural frequencies x 5 damping ratios at every delay, 8-10 % steps around
/// its best, then 1 % steps at the delays within 10 samples of the best.
/// None when no low-pass of the grid lies below the decimated Nyquist frequency.
fn scan_low_pass_and_delay(
    d: &Decimated,
    (f, rows): (&Fixed, Option<(&SegmentRows, &[GroupSums])>),
    (full, full_segments): (&[f64], &[Range<usize>]),
    iv: Option<(&FixedIv<'_>, &[f64])>,
    max_delay: usize,
    (skip, fs): (usize, f64),
) -> Option<Scan> {
    let n = d.torque.len();
    let delays = max_delay + 1;
    let nyquist = d.fs / 2.0;
    // RSS and [I, B, K, G] per low-pass and delay; delays outside `near` are
    // not fitted (infinite RSS)
    let scan_near = |combos: &[(f64, f64)], near: std::ops::RangeInclusive<usize>| {
        combos
            .par_iter()
            .map(|&(w, z)| {
                let ph = phases(&low_pass_in(full, (w, z, fs), full_segments), d.ratio, n);
                let free = rows.map(|_| SegmentRows::free_phases(d, (w, z, fs), full_segments));
                let instrument = iv.map(|(iv, zf)| {
                    let ph = phases(&low_pass_in(zf, (w, z, fs), full_segments), d.ratio, n);
                    (iv, ph)
                });
                (0..delays)
                    .map(|dl| match (near.contains(&dl), rows.zip(free.as_ref())) {
                        (false, _) => (f64::INFINITY, [0.0; 4]),
                        (true, _) if instrument.is_some() => {
                            let (iv, phz) = instrument.as_ref().expect("checked");
                            joint_fit_iv(
                                iv,
                                &delayed(&ph, d.ratio, dl, skip, &d.segments),
                                &delayed(phz, d.ratio, dl, skip, &d.segments),
                            )
                        }
                        (true, None) => joint_fit(f, &delayed(&ph, d.ratio, dl, skip, &d.segments)),
                        (true, Some(((rows, sums), free))) => {
                            rows.scan_fit(sums, d, (&ph, free), dl)
                        }
                    })
                    .collect::<Vec<_>>()
            })
            .collect::<Vec<_>>()
    };
    let scan = |combos: &[(f64, f64)]| scan_near(combos, 0..=max_delay);
    let mut combos: Vec<(f64, f64)> = (0..10)
        .map(|i| 0.8 * 25f64.powf(i as f64 / 9.0))
        .filter(|w| *w < 0.45 * nyquist)
        .flat_map(|w| [0.3, 0.5, 0.75, 1.1, 1.6].map(|z| (w, z)))
        .collect();
    if combos.is_empty() {
        return None;
    }
    let mut fits = scan(&combos);
    let (_, c0, _) = best(&fits);
    let (w0, z0) = combos[c0];
    let local: Vec<(f64, f64)> = (-2..=2)
        .flat_map(|i| (-2..=2).map(move |j| (w0 * 1.08f64.powi(i), z0 * 1.1f64.powi(j))))
        .filter(|(w, _)| *w < 0.45 * nyquist)
        .collect();
    fits.extend(scan(&local));
    combos.extend(local);
    // and once more at 1 % steps: the 8-10 % steps left an error in the
    // low-pass that leaked into B (1 % median) and K (0.3 %), several times
    // their jackknife standard errors
    let (_, c1, d1) = best(&fits);
    let (w1, z1) = combos[c1];
    // (the delays within 10 samples of the best: the low-pass moves little)
    let near = d1.saturating_sub(10)..=(d1 + 10).min(max_delay);
    let fine: Vec<(f64, f64)> = (-4..=4)
        .flat_map(|i| (-4..=4).map(move |j| (w1 * 1.01f64.powi(i), z1 * 1.012f64.powi(j))))
        .filter(|(w, _)| *w < 0.45 * nyquist)
        .collect();
    fits.extend(scan_near(&fine, near));
    combos.extend(fine);
    Some(Scan { combos, fits })
}

/// The delays whose profile RSS is under the threshold, grown from the best
/// delay: (first, last, whether no delay outside them is under it too).
fn delay_interval(profile: &[f64], threshold: f64, delay: usize) -> (usize, usize, bool) {
    let max_delay = profile.len() - 1;
    let inside: Vec<bool> = profile.iter().map(|r| *r <= threshold).collect();
    let (mut lo, mut hi) = (delay, delay);
    while lo > 0 && inside[lo - 1] {
        lo -= 1;
    }
    while hi < max_delay && inside[hi + 1] {
        hi += 1;
    }
    let contiguous = inside
        .iter()
        .enumerate()
        .all(|(i, &v)| !v || (lo..=hi).contains(&i));
    (lo, hi, contiguous)
}

/// The jackknife holds the delay and the low-pass fixed; B, K, I and G move
/// with them (the rectified velocity's linear half is collinear with the
/// velocity), so the largest change over their joint 95 % profile region
/// (every scanned delay and low-pass with an RSS under the threshold) is
/// added to the standard errors in quadrature.
fn profile_region_shift(fits: &ScanFits, threshold: f64, at_best: [f64; 4]) -> [f64; 4] {
    let mut shift = [0.0f64; 4];
    for (_, params) in fits.iter().flatten().filter(|(rss, _)| *rss <= threshold) {
        for ((s, o), v) in shift.iter_mut().zip(params).zip(at_best) {
            *s = s.max((o - v).abs());
        }
    }
    shift
}

/// The jackknife's blocks of rows: whole segments when there are as many
/// segments as blocks (each segment's constant is fitted inside it, and
/// neighbouring samples share their noise), else equal runs of rows.
fn jackknife_blocks(groups: &[Range<usize>], m: usize, blocks: usize) -> Vec<Range<usize>> {
    if groups.len() >= blocks {
        let g = groups.len();
        (0..blocks)
            .map(|b| groups[b * g / blocks].start..groups[(b + 1) * g / blocks - 1].end)
            .collect()
    } else {
        (0..blocks)
            .map(|b| b * m / blocks..(b + 1) * m / blocks)
            .collect()
    }
}

/// 10-block delete-one jackknife standard errors of (I, B, K, G) of the joint model.
pub(crate) fn joint_jackknife(f: &Fixed, x: &[f64]) -> [f64; 4] {
    let blocks = 10;
    let m = x.len();
    let y = f.torque();
    let scale: Vec<f64> = f
        .columns
        .iter()
        .map(|c| c.as_slice())
        .chain([x])
        .map(|c| (dot(c, c) / m as f64).sqrt().max(f64::MIN_POSITIVE))
        .collect();
    let row = |t: usize| {
        [
            f.columns[0][t] / scale[0],
            f.columns[1][t] / scale[1],
            f.columns[2][t] / scale[2],
            x[t] / scale[3],
            1.0,
        ]
    };
    let mut grams = vec![
        (
            nalgebra::SMatrix::<f64, 5, 5>::zeros(),
            nalgebra::SVector::<f64, 5>::zeros()
        );
        blocks
    ];
    for ((g, r), rows) in grams.iter_mut().zip(jackknife_blocks(&f.groups, m, blocks)) {
        #[allow(clippy::needless_range_loop)] // row(t) reads five columns at t
        for t in rows {
            let v = nalgebra::SVector::<f64, 5>::from(row(t));
            *g += v * v.transpose();
            *r += v * y[t];
        }
    }
    delete_one_jackknife(&grams, &scale)
}

/// Normal equations (or their IV form `Z'X`, `Z'y`) per block, of columns
/// scaled by `scale`: the delete-one jackknife standard errors of the first
/// four parameters (I, B, K, G) in their own units.
pub(crate) fn delete_one_jackknife(
    blocks: &[(nalgebra::SMatrix<f64, 5, 5>, nalgebra::SVector<f64, 5>)],
    scale: &[f64],
) -> [f64; 4] {
    let count = blocks.len();
    let reps: Vec<[f64; 4]> = (0..count)
        .map(|skip| {
            let mut g = nalgebra::SMatrix::<f64, 5, 5>::zeros();
            let mut r = nalgebra::SVector::<f64, 5>::zeros();
            for (b, (gb, rb)) in blocks.iter().enumerate() {
                if b != skip {
                    g += gb;
                    r += rb;
                }
            }
            match g.lu().solve(&r) {
                Some(th) => [0, 1, 2, 3].map(|k| th[k] / scale[k]),
                None => [f64::NAN; 4],
            }
        })
        .collect();
    [0, 1, 2, 3].map(|k| {
        let mk = reps.iter().map(|r| r[k]).sum::<f64>() / count as f64;
        let ss: f64 = reps.iter().map(|r| (r[k] - mk).powi(2)).sum();
        (ss * (count - 1) as f64 / count as f64).sqrt()
    })
}

/// `1 + 2 sum rho_k` over the residual's autocorrelation, summed until it first turns negative (at most 200 lags).
pub(crate) fn autocorrelation_inflation(e: &[f64]) -> f64 {
    let v = correlation(e, e, 0);
    if v <= 0.0 {
        return 1.0;
    }
    let mut s = 1.0;
    for k in 1..200.min(e.len() / 4) {
        let r = correlation(e, e, k as isize) / v;
        if r <= 0.0 {
            break;
        }
        s += 2.0 * r;
    }
    s
}
