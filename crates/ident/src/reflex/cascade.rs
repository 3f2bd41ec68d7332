//! Kearney et al. (1997)'s parallel cascade, non-parametric part: decimation with anti-aliasing, the intrinsic and reflex impulse responses by pseudo-inverse, the iteration between the pathways, VAF.

use super::{Decimated, ReflexParams};
use limpid_core::Result;
use limpid_dsp::LowPass;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::ops::Range;

use super::segments::gather;

pub(crate) fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

pub(crate) fn variance(x: &[f64]) -> f64 {
    let m = mean(x);
    x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / x.len().max(1) as f64
}

pub(crate) fn centre(x: &mut [f64]) {
    let m = mean(x);
    x.iter_mut().for_each(|v| *v -= m);
}

/// `100 (1 - var(y - yhat) / var(y))` over every segment's samples past its
/// first `skip` (the rows whose prediction has its input history).
pub(crate) fn vaf_in(y: &[f64], yhat: &[f64], skip: usize, segments: &[Range<usize>]) -> f64 {
    if let [whole] = segments {
        return vaf(&y[whole.clone()], &yhat[whole.clone()], skip);
    }
    let y = gather(y, segments, skip);
    let yhat = gather(yhat, segments, skip);
    vaf(&y, &yhat, 0)
}

/// `100 (1 - var(y - yhat) / var(y))` over `y[skip..]`.
pub fn vaf(y: &[f64], yhat: &[f64], skip: usize) -> f64 {
    let y = &y[skip.min(y.len())..];
    let yhat = &yhat[skip.min(yhat.len())..];
    let e: Vec<f64> = y.iter().zip(yhat).map(|(a, b)| a - b).collect();
    let vy = variance(y);
    if vy > 0.0 {
        100.0 * (1.0 - variance(&e) / vy)
    } else {
        0.0
    }
}

/// The decimation step: every `ratio`-th recorded sample is kept.
pub(crate) fn decimation_ratio(fs: f64, p: &ReflexParams) -> usize {
    ((fs / p.rate_hz).round() as usize).max(1)
}

/// The zero-phase anti-alias filter before keeping every `ratio`-th sample:
/// 8th-order Butterworth at 0.8 of the new Nyquist frequency.
pub(crate) fn anti_alias(fs: f64, ratio: usize) -> Result<LowPass> {
    LowPass::butterworth(8, 0.8 * (fs / ratio as f64) / 2.0, fs)
}

/// Anti-alias and decimate angle, torque, velocity and acceleration, with the
/// rectified velocity in both orders: `[p.rectify_first's order, the other]`
/// (the two share every filtered column but the rectified ones).
pub(crate) fn decimate(q: &[f64], tq: &[f64], fs: f64, p: &ReflexParams) -> Result<[Decimated; 2]> {
    let ratio = decimation_ratio(fs, p);
    let fsd = fs / ratio as f64;
    let velocity = limpid_dsp::central_first(q, 1.0 / fs);
    let acceleration = limpid_dsp::central_second(q, 1.0 / fs);
    let rectify =
        |v: &[f64], sign: f64| -> Vec<f64> { v.iter().map(|x| (sign * x).max(0.0)).collect() };
    // rectified before anti-aliasing: the physical order
    let (pos_raw, neg_raw) = (rectify(&velocity, 1.0), rectify(&velocity, -1.0));
    let columns: Vec<Vec<f64>> = vec![
        q.to_vec(),
        tq.to_vec(),
        velocity,
        acceleration,
        pos_raw,
        neg_raw,
    ];
    let mut filtered: Vec<Vec<f64>> = if ratio > 1 {
        let lp = anti_alias(fs, ratio)?;
        columns
            .par_iter()
            .map(|x| lp.filtfilt(x))
            .collect::<Result<Vec<_>>>()?
    } else {
        columns
    };
    // rectified after anti-aliasing, so that every decimation phase of it
    // is the rectified decimated velocity (Kearney et al.)
    let after = [rectify(&filtered[2], 1.0), rectify(&filtered[2], -1.0)];
    let negative = filtered.pop().unwrap_or_default();
    let positive = filtered.pop().unwrap_or_default();
    let before = [positive, negative];
    let pick = |x: &[f64]| -> Vec<f64> {
        let mut d: Vec<f64> = x.iter().step_by(ratio).copied().collect();
        centre(&mut d);
        d
    };
    let with = |[positive, negative]: [Vec<f64>; 2]| Decimated {
        fs: fsd,
        ratio,
        segments: std::iter::once(0..q.len().div_ceil(ratio)).collect(),
        position: pick(&filtered[0]),
        velocity: pick(&filtered[2]),
        acceleration: pick(&filtered[3]),
        torque: pick(&filtered[1]),
        rectified: [pick(&positive), pick(&negative)],
        rectified_full: [positive, negative],
    };
    Ok(if p.rectify_first {
        [with(before), with(after)]
    } else {
        [with(after), with(before)]
    })
}

/// `sum_t a[t] b[t + k] / n`.
pub(crate) fn correlation(a: &[f64], b: &[f64], k: isize) -> f64 {
    lagged_sum(a, b, k) / a.len() as f64
}

/// [`correlation`] over the pairs inside one segment: never across a cut.
pub(crate) fn correlation_in(a: &[f64], b: &[f64], k: isize, segments: &[Range<usize>]) -> f64 {
    if let [whole] = segments {
        return correlation(&a[whole.clone()], &b[whole.clone()], k);
    }
    let s: f64 = segments
        .iter()
        .map(|r| lagged_sum(&a[r.clone()], &b[r.clone()], k))
        .sum();
    s / segments.iter().map(|r| r.len()).sum::<usize>().max(1) as f64
}

/// `sum_t a[t] b[t + k]`.
fn lagged_sum(a: &[f64], b: &[f64], k: isize) -> f64 {
    let n = a.len();
    if k >= 0 {
        let k = k as usize;
        a[..n - k.min(n)]
            .iter()
            .zip(&b[k.min(n)..])
            .map(|(x, y)| x * y)
            .sum()
    } else {
        let k = (-k) as usize;
        a[k.min(n)..]
            .iter()
            .zip(&b[..n - k.min(n)])
            .map(|(x, y)| x * y)
            .sum()
    }
}

/// IRF with lags `first..first + lags` from `u` to `y` by the Toeplitz
/// pseudo-inverse; modes kept in order of output variance, their number by
/// minimum description length. Returns the per-sample IRF and the order.
/// Correlations are taken inside each segment only.
pub(crate) fn irf_pinv(
    u: &[f64],
    y: &[f64],
    (first, lags): (isize, usize),
    segments: &[Range<usize>],
) -> (Vec<f64>, usize) {
    let n = segments.iter().map(|r| r.len()).sum::<usize>() as f64;
    let auto: Vec<f64> = (0..lags)
        .map(|k| correlation_in(u, u, k as isize, segments))
        .collect();
    let cross: Vec<f64> = (0..lags)
        .map(|j| correlation_in(u, y, first + j as isize, segments))
        .collect();
    let toeplitz = DMatrix::from_fn(lags, lags, |i, j| auto[i.abs_diff(j)]);
    let Some(eig) = limpid_core::linalg::symmetric_eigen(toeplitz) else {
        return (vec![0.0; lags], 0);
    };
    let smax = eig.eigenvalues.iter().fold(0.0_f64, |m, v| m.max(*v));
    let c = eig.eigenvectors.transpose() * DVector::from_column_slice(&cross);
    let mut modes: Vec<(usize, f64)> = (0..lags)
        .filter(|&i| eig.eigenvalues[i] > smax * 1e-12)
        .map(|i| (i, c[i] * c[i] / eig.eigenvalues[i]))
        .collect();
    modes.sort_by(|a, b| b.1.total_cmp(&a.1));
    let yy = correlation_in(y, y, 0, segments);
    let mut explained = 0.0;
    let mut order = 0;
    let mut best = yy;
    for (k, (_, v)) in modes.iter().enumerate() {
        explained += v;
        let mdl = (1.0 + (k + 1) as f64 * n.ln() / n) * (yy - explained);
        if mdl < best {
            best = mdl;
            order = k + 1;
        }
    }
    let mut h = vec![0.0; lags];
    for &(i, _) in &modes[..order] {
        let w = c[i] / eig.eigenvalues[i];
        for (hj, vj) in h.iter_mut().zip(eig.eigenvectors.column(i).iter()) {
            *hj += w * vj;
        }
    }
    (h, order)
}

/// [`apply`] to each segment on its own: zero input outside the segment.
pub(crate) fn apply_in(h: &[f64], first: isize, u: &[f64], segments: &[Range<usize>]) -> Vec<f64> {
    if let [whole] = segments {
        if *whole == (0..u.len()) {
            return apply(h, first, u);
        }
    }
    let mut y = vec![0.0; u.len()];
    for r in segments {
        y[r.clone()].copy_from_slice(&apply(h, first, &u[r.clone()]));
    }
    y
}

/// `y[t] = sum_j h[j] u[t - (first + j)]`, zero input outside the record.
pub(crate) fn apply(h: &[f64], first: isize, u: &[f64]) -> Vec<f64> {
    let n = u.len() as isize;
    let mut y = vec![0.0; u.len()];
    for (j, &hj) in h.iter().enumerate() {
        let l = first + j as isize;
        let (lo, hi) = (l.max(0), (n + l).min(n));
        for t in lo..hi {
            y[t as usize] += hj * u[(t - l) as usize];
        }
    }
    y
}

pub(crate) struct Cascade {
    pub(crate) intrinsic: Vec<f64>,
    pub(crate) intrinsic_order: usize,
    pub(crate) reflex: Vec<f64>,
    pub(crate) reflex_order: usize,
    pub(crate) intrinsic_torque: Vec<f64>,
    pub(crate) reflex_torque: Vec<f64>,
    pub(crate) vaf_total: f64,
    pub(crate) iterations: usize,
}

/// Alternate the two pathways, each on the other's residual (Kearney et al.
/// 1997), inside each segment; `skip` samples of each segment's start lack
/// input history and are left out of the VAF.
pub(crate) fn cascade(
    [position, rectified, torque]: [&[f64]; 3],
    (half, n_reflex, skip): (usize, usize, usize),
    segments: &[Range<usize>],
) -> Cascade {
    let mut reflex_torque = vec![0.0; torque.len()];
    let mut best: Option<Cascade> = None;
    for iteration in 1..=super::MAX_ITERATIONS {
        let target: Vec<f64> = torque
            .iter()
            .zip(&reflex_torque)
            .map(|(t, r)| t - r)
            .collect();
        let (hi, oi) = irf_pinv(
            position,
            &target,
            (-(half as isize), 2 * half + 1),
            segments,
        );
        let intrinsic_torque = apply_in(&hi, -(half as isize), position, segments);
        let target: Vec<f64> = torque
            .iter()
            .zip(&intrinsic_torque)
            .map(|(t, i)| t - i)
            .collect();
        let (hr, or) = irf_pinv(rectified, &target, (0, n_reflex), segments);
        reflex_torque = apply_in(&hr, 0, rectified, segments);
        let total: Vec<f64> = intrinsic_torque
            .iter()
            .zip(&reflex_torque)
            .map(|(a, b)| a + b)
            .collect();
        let v = vaf_in(torque, &total, skip, segments);
        let previous = best.as_ref().map_or(f64::NEG_INFINITY, |b| b.vaf_total);
        let done = v - previous < super::TOLERANCE_VAF;
        if v >= previous {
            best = Some(Cascade {
                intrinsic: hi,
                intrinsic_order: oi,
                reflex: hr,
                reflex_order: or,
                intrinsic_torque,
                reflex_torque: reflex_torque.clone(),
                vaf_total: v,
                iterations: iteration,
            });
        }
        if done {
            break;
        }
    }
    best.expect("at least one iteration")
}
