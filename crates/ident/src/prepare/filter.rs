//! Zero-phase filtering and derivatives of a window (seed 000 §II-C), and
//! the noise they pass to the regressors.

use super::Derivative;
use limpid_core::Result;
use limpid_dsp::{central_first, central_second, savgol, Edge, LowPass};
use std::ops::Range;
/// One window's displacement, velocity, acceleration and force per
/// coordinate (`signals`: the n displacements, then the n forces): zero-phase
/// low-pass with extended edges (all 2n signals filtered together) and
/// central differences, or Savitzky-Golay (cubic) smoothing and derivatives.
pub(super) fn filter_and_differentiate(
    signals: &[Vec<f64>],
    derivative: Derivative,
    lowpass: &LowPass,
    (left, right, extra): (Edge, Edge, usize),
    sg_window: usize,
    dt: f64,
) -> Result<Vec<[Vec<f64>; 4]>> {
    let n = signals.len() / 2;
    match derivative {
        Derivative::Central => {
            let refs: Vec<&[f64]> = signals.iter().map(Vec::as_slice).collect();
            let mut filtered = lowpass.filtfilt_edges_many(&refs, left, right, extra)?;
            let forces = filtered.split_off(n);
            Ok(filtered
                .into_iter()
                .zip(forces)
                .map(|(xs, f)| {
                    let v = central_first(&xs, dt);
                    let a = central_second(&xs, dt);
                    [xs, v, a, f]
                })
                .collect())
        }
        Derivative::Savgol => (0..n)
            .map(|k| {
                let (x, f) = (&signals[k], &signals[n + k]);
                Ok([
                    savgol(x, sg_window, 3, 0, dt)?,
                    savgol(x, sg_window, 3, 1, dt)?,
                    savgol(x, sg_window, 3, 2, dt)?,
                    savgol(f, sg_window, 3, 0, dt)?,
                ])
            })
            .collect(),
    }
}

/// Extension for each window end (start, end): a mirror where the limb is
/// (nearly) still there, a point reflection where it still moves. The speed at
/// an end is the slope of a least-squares line through its `span` samples,
/// compared with the window's largest such slope (one scan for both ends).
pub(crate) fn edge_kinds(
    pos: &[&[f64]],
    window: Range<usize>,
    span: usize,
    dt: f64,
) -> (Edge, Edge) {
    let span = span.min(window.len() / 4).max(2);
    let tm = (span as f64 - 1.0) / 2.0;
    let weights: Vec<f64> = (0..span).map(|k| k as f64 - tm).collect();
    let den: f64 = weights.iter().map(|w| w.powi(2)).sum();
    // Σ (k - tm)(v - xm) = Σ (k - tm) v, the weights summing to zero
    let slope = |c: &[f64], s: usize| {
        let num: f64 = c[s..s + span]
            .iter()
            .zip(&weights)
            .map(|(v, w)| w * v)
            .sum();
        num / den / dt
    };
    let (mut left_moving, mut right_moving) = (false, false);
    for c in pos {
        let mut peak = 0.0f64;
        let mut s = window.start;
        while s + span <= window.end {
            peak = peak.max(slope(c, s).abs());
            s += span / 2;
        }
        if peak > 0.0 {
            left_moving |= slope(c, window.start).abs() > 0.2 * peak;
            right_moving |= slope(c, window.end - span).abs() > 0.2 * peak;
        }
    }
    let kind = |moving: bool| if moving { Edge::Odd } else { Edge::Even };
    (kind(left_moving), kind(right_moving))
}

/// Savitzky-Golay window (odd, samples) whose cubic smoother has about the given cut-off.
///
/// Uses the approximation f_c / f_s ≈ (N + 1) / (6.4 M - 9.2) for polynomial
/// order N = 3 and window 2M + 1 (Schafer, "What is a Savitzky-Golay filter?", 2011).
pub fn savgol_window(fs: f64, cutoff: f64) -> usize {
    let m = ((4.0 * fs / cutoff + 9.2) / 6.4).round().max(3.0) as usize;
    2 * m + 1
}

/// Sum of squared impulse responses of the displacement, velocity and
/// acceleration operators: white noise of variance σ² in a position comes out
/// with variance σ² × gain.
pub(crate) fn noise_gains(
    derivative: Derivative,
    lowpass: &LowPass,
    sg_window: usize,
    dt: f64,
) -> Result<[f64; 4]> {
    let n = 4001;
    let mut impulse = vec![0.0; n];
    impulse[n / 2] = 1.0;
    let (x, v, a) = match derivative {
        Derivative::Central => {
            let x = lowpass.filtfilt(&impulse)?;
            let v = central_first(&x, dt);
            let a = central_second(&x, dt);
            (x, v, a)
        }
        Derivative::Savgol => (
            savgol(&impulse, sg_window, 3, 0, dt)?,
            savgol(&impulse, sg_window, 3, 1, dt)?,
            savgol(&impulse, sg_window, 3, 2, dt)?,
        ),
    };
    let ss = |y: &[f64]| y.iter().map(|v| v * v).sum::<f64>();
    let cross = x.iter().zip(&a).map(|(p, q)| p * q).sum::<f64>();
    Ok([ss(&x), ss(&v), ss(&a), cross])
}
