//! The design rows of the parameter-varying fit: per contiguous segment the
//! filtered signals, then every product `T_i(σ) × regressor` detrended.

use rayon::prelude::*;

use limpid_core::{Error, Recording, Result};
use limpid_dsp::LowPass;

use super::{VaryingParams, FILTER_ORDER, REFLEX_VELOCITY_HZ};
use crate::varying::{derivatives, MAX_BASIS_ORDER};

/// Full-rate signals of one contiguous segment.
pub(super) struct Segment {
    /// `[x'' (d), x' (d), x (d)]` then forces (d), low-passed, not detrended.
    pub(super) signals: Vec<Vec<f64>>,
    /// Velocity of the first coordinate for the reflex drive, from the position
    /// low-passed only against noise (rectification turns what a low-pass
    /// removes into low-frequency torque, so the drive keeps it).
    pub(super) reflex_velocity: Vec<f64>,
    /// The schedule.
    pub(super) sigma: Vec<f64>,
    /// Indices kept (trimmed, decimated).
    pub(super) kept: Vec<usize>,
    /// `T_i(σ)` at every sample, degrees `0..=top` (filled once the range is known).
    pub(super) basis: Vec<Vec<f64>>,
    /// Samples left out at each end.
    pub(super) trim: usize,
    /// How the operating point is taken out of this segment.
    pub(super) trend: Trend,
}

/// The operating point of a segment, removed from every column of it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Trend {
    /// What varies slower than `slow_hz` (a zero-phase low-pass).
    Slow,
    /// A straight line (least squares): a segment too short for the slow
    /// low-pass (Ludvig & Perreault's short segments), whose operating point
    /// is constant or drifts slowly within it.
    Line,
}

impl Segment {
    /// `x` minus its operating point (see [`Trend`]).
    pub(super) fn detrend(&self, slow: &LowPass, x: &[f64]) -> Result<Vec<f64>> {
        match self.trend {
            Trend::Slow => detrend(slow, x),
            Trend::Line => Ok(remove_line(x)),
        }
    }
}

/// `x` minus its least-squares straight line.
pub(super) fn remove_line(x: &[f64]) -> Vec<f64> {
    let n = x.len() as f64;
    let centre = (n - 1.0) / 2.0;
    let mean = x.iter().sum::<f64>() / n;
    let (mut stt, mut sxt) = (0.0, 0.0);
    for (t, v) in x.iter().enumerate() {
        let u = t as f64 - centre;
        stt += u * u;
        sxt += u * v;
    }
    let slope = if stt > 0.0 { sxt / stt } else { 0.0 };
    x.iter()
        .enumerate()
        .map(|(t, v)| v - mean - slope * (t as f64 - centre))
        .collect()
}

/// The design at the highest order: per kept sample, every product column
/// `T_i(σ) × regressor`, each detrended (minus its zero-phase low-pass at
/// `slow_hz`) at the full rate; the forces likewise.
pub(super) struct Rows {
    pub(super) d: usize,
    pub(super) top: usize,
    pub(super) width: usize,
    pub(super) x: Vec<f64>,
    pub(super) f: Vec<f64>,
    pub(super) sigma: Vec<f64>,
    pub(super) block: Vec<usize>,
    pub(super) lo: f64,
    pub(super) span: f64,
    pub(super) segments: Vec<Segment>,
    /// Whether the offset `c(σ)` is fitted: not when every segment's
    /// straight line (its operating point) already holds it (a schedule
    /// constant or linear within each short segment).
    pub(super) offset: bool,
}

impl Rows {
    pub(super) fn len(&self) -> usize {
        self.sigma.len()
    }

    pub(super) fn basis(&self, sigma: f64, p: usize, out: &mut [f64]) {
        let u = (2.0 * (sigma - self.lo) / self.span - 1.0).clamp(-1.0, 1.0);
        chebyshev(u, p, out);
    }
}

/// How the stiffness columns are formed (see [`crate::varying::ScheduleAngle`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum AngleReading {
    /// `T_i(σ) x`: K multiplies the displacement.
    Linear,
    /// `∫ T_i(u(θ)) dθ` up to the whole angle θ (its lower end is slow and
    /// detrends away): θ = x (`offset` false) or σ + x (`offset` true: the
    /// schedule is added to the coordinate before anything else, so velocity
    /// and acceleration are the whole angle's too, ramps included). A
    /// stiffness that varies with the angle is then K(σ) at the operating
    /// angle, not the mean slope over the angles the perturbation sweeps.
    Integrated { offset: bool },
    /// A schedule that may or may not be the operating angle: formed as
    /// `Linear`; the estimator fits the `offset` reading beside it and its
    /// standard errors carry the difference.
    Unknown,
}

/// `∫_0^u T_i(s) ds` up to a constant: `u`, `u²/2`, then
/// `T_{i+1}/(2(i+1)) - T_{i-1}/(2(i-1))`. Unclamped: the whole angle may
/// leave the schedule's range by the perturbation's swing.
fn chebyshev_integral(u: f64, i: usize) -> f64 {
    match i {
        0 => u,
        1 => 0.5 * u * u,
        _ => {
            let mut t = [0.0; MAX_BASIS_ORDER + 3];
            chebyshev(u, i + 1, &mut t);
            t[i + 1] / (2.0 * (i + 1) as f64) - t[i - 1] / (2.0 * (i - 1) as f64)
        }
    }
}

pub(super) fn chebyshev(u: f64, p: usize, out: &mut [f64]) {
    out[0] = 1.0;
    if p >= 1 {
        out[1] = u;
    }
    for i in 2..=p {
        out[i] = 2.0 * u * out[i - 1] - out[i - 2];
    }
}

pub(super) fn detrend(slow: &LowPass, x: &[f64]) -> Result<Vec<f64>> {
    let s = slow.filtfilt(x)?;
    Ok(x.iter().zip(&s).map(|(a, b)| a - b).collect())
}

/// Samples left out at each end of a segment: `(short, slow)`. A segment too
/// short for the slow low-pass's ends takes a straight line as its
/// operating point, and leaves out only what the delay and the low-pass
/// need (`short`).
fn trims(params: &VaryingParams, fs: f64, cutoff: f64) -> (usize, usize) {
    let short = ((params.max_delay_s * fs).ceil() + 1.0).max((fs / cutoff).ceil()) as usize;
    let slow = ((fs / (4.0 * params.slow_hz)).ceil() as usize).max(short);
    (short, slow)
}

/// The shortest segment (samples) whose operating point is the slow
/// low-pass (its trims at both ends and the filters' padding); a shorter one
/// takes a straight line ([`Trend::Line`]).
pub(super) fn shortest_slow_segment(
    params: &VaryingParams,
    (fs, cutoff): (f64, f64),
    slow: &LowPass,
) -> Result<usize> {
    let lp = LowPass::butterworth(FILTER_ORDER, cutoff, fs)?;
    Ok(2 * trims(params, fs, cutoff).1 + slow.padlen().max(lp.padlen()) + 2)
}

/// The filtered segments that are long enough, the decimation and the trim
/// (samples left out at each end of a segment).
#[allow(clippy::too_many_arguments)]
fn segments(
    rec: &Recording,
    params: &VaryingParams,
    coords: &[String],
    forces: &[String],
    cutoff: f64,
    slow: &LowPass,
    reading: AngleReading,
    warnings: &mut Vec<String>,
) -> Result<(Vec<Segment>, usize, usize)> {
    let fs = rec.sample_rate();
    let dt = 1.0 / fs;
    let lp = LowPass::butterworth(FILTER_ORDER, cutoff, fs)?;
    // the reflex drive's velocity: low-passed at 0.45 x the rate only when that is above the estimation cut-off
    let wide = (params.reflex && REFLEX_VELOCITY_HZ < 0.45 * fs)
        .then(|| LowPass::butterworth(FILTER_ORDER, REFLEX_VELOCITY_HZ, fs))
        .transpose()?;
    let schedule = rec.require(&params.schedule, "the schedule (--schedule)")?;
    let schedule_is_coordinate = coords.contains(&params.schedule);
    let ranges = limpid_core::trial::segment_ranges(rec)?;
    let (short_trim, slow_trim) = trims(params, fs, cutoff);
    // as close to rate_hz as the low-pass allows (cutoff at most half the decimated rate)
    let dec = (fs / params.rate_hz)
        .min(0.5 * fs / cutoff)
        .floor()
        .max(1.0) as usize;
    let achieved = fs / dec as f64;
    let wanted = fs / params.rate_hz;
    if wanted < 1.0 || wanted > (0.5 * fs / cutoff).floor().max(1.0) + 1.0 {
        // said, not done silently (issue 56: --rate 1e-9 ran at 60 Hz without a word)
        warnings.push(format!(
            "rate_hz {} Hz: decimated to {} Hz instead ({} at {} Hz sampling, and at least twice the {} Hz low-pass)",
            limpid_core::error::Num(params.rate_hz),
            limpid_core::error::Num(achieved),
            if dec == 1 { "no decimation".to_string() } else { format!("every {dec}th sample") },
            limpid_core::error::Num(fs),
            limpid_core::error::Num(cutoff)
        ));
    }
    let min_slow = shortest_slow_segment(params, (fs, cutoff), slow)?;
    let min_len = 2 * short_trim + lp.padlen() + 2;
    let d = coords.len();
    let (mut pos, frc) = (
        crate::prepare::columns(rec, coords),
        crate::prepare::columns(rec, forces),
    );
    let whole_angle: Vec<f64>;
    if reading == (AngleReading::Integrated { offset: true }) {
        whole_angle = pos[0].iter().zip(schedule).map(|(x, s)| x + s).collect();
        pos[0] = &whole_angle;
    }
    let mut segments = Vec::new();
    let mut skipped = 0usize;
    for seg in ranges {
        if seg.len() < min_len {
            skipped += 1;
            continue;
        }
        let mut signals = vec![Vec::new(); 4 * d];
        for k in 0..d {
            let x = lp.filtfilt(&pos[k][seg.clone()])?;
            let (v, a) = derivatives(&x, dt);
            signals[k] = a;
            signals[d + k] = v;
            signals[2 * d + k] = x;
            signals[3 * d + k] = lp.filtfilt(&frc[k][seg.clone()])?;
        }
        let reflex_velocity = match &wide {
            Some(w) => derivatives(&w.filtfilt(&pos[0][seg.clone()])?, dt).0,
            None => derivatives(&pos[0][seg.clone()], dt).0,
        };
        let (trend, trim) = if seg.len() >= min_slow {
            (Trend::Slow, slow_trim)
        } else {
            (Trend::Line, short_trim)
        };
        let sigma = match (schedule_is_coordinate, trend) {
            (true, Trend::Slow) => slow.filtfilt(&schedule[seg.clone()])?,
            (true, Trend::Line) => {
                let line = remove_line(&schedule[seg.clone()]);
                schedule[seg.clone()]
                    .iter()
                    .zip(line)
                    .map(|(s, l)| s - l)
                    .collect()
            }
            (false, _) => schedule[seg.clone()].to_vec(),
        };
        let kept = (trim..seg.len() - trim).step_by(dec).collect();
        segments.push(Segment {
            signals,
            reflex_velocity,
            sigma,
            kept,
            basis: Vec::new(),
            trim,
            trend,
        });
    }
    if skipped > 0 {
        warnings.push(format!(
            "{skipped} segment(s) left out: shorter than {min_len} samples, what filtering and the reflex delay need"
        ));
    }
    let lines = segments.iter().filter(|s| s.trend == Trend::Line).count();
    if lines > 0 {
        warnings.push(format!(
            "{lines} of {} segment(s) shorter than {:.2} s, too short for the {} Hz slow low-pass: each takes a straight line as its operating point (and the schedule's line as its value)",
            segments.len(),
            min_slow as f64 / fs,
            limpid_core::error::Num(params.slow_hz)
        ));
    }
    let trim = segments.iter().map(|s| s.trim).min().unwrap_or(slow_trim);
    Ok((segments, dec, trim))
}

/// Segments, schedule range, and the product columns at order `top`.
#[allow(clippy::too_many_arguments)]
pub(super) fn rows(
    rec: &Recording,
    params: &VaryingParams,
    coords: &[String],
    forces: &[String],
    cutoff: f64,
    top: usize,
    slow: &LowPass,
    reading: AngleReading,
    warnings: &mut Vec<String>,
) -> Result<(Rows, usize, usize)> {
    let (mut segments, dec, trim) =
        segments(rec, params, coords, forces, cutoff, slow, reading, warnings)?;
    let fs = rec.sample_rate();
    let d = coords.len();
    let n: usize = segments.iter().map(|s| s.kept.len()).sum();
    if n < 50 * (3 * d + 1) * (top + 1) {
        return Err(Error::invalid(
            "recording",
            format!(
                "{}: {n} samples remain after trimming the segments' ends; too few for a parameter-varying fit",
                rec.path().display()
            ),
        ));
    }
    let kept_sigma = || {
        segments
            .iter()
            .flat_map(|s| s.kept.iter().map(|&i| s.sigma[i]))
    };
    let lo = kept_sigma().fold(f64::INFINITY, f64::min);
    let hi = kept_sigma().fold(f64::NEG_INFINITY, f64::max);
    let span = hi - lo;
    if span.is_nan() || span <= 1e-9 * lo.abs().max(hi.abs()).max(1e-300) {
        return Err(Error::invalid(
            "schedule",
            format!(
                "{}: column {} does not vary over the samples fitted (it stays at {lo}); nothing to schedule on",
                rec.path().display(),
                params.schedule
            ),
        ));
    }
    let p1 = top + 1;
    // groups: x'' (d), x' (d), x (d), the offset c(σ) (its constant is removed by detrending)
    let width = (3 * d + 1) * p1;
    let mut out = Rows {
        d,
        top,
        width,
        x: vec![0.0; n * width],
        f: vec![0.0; n * d],
        sigma: Vec::with_capacity(n),
        block: Vec::with_capacity(n),
        lo,
        span,
        segments: Vec::new(),
        offset: true,
    };
    let block_len = (fs.round() as usize).max(1);
    let (mut row0, mut block) = (0usize, 0usize);
    let mut phi = vec![0.0; p1];
    for seg in &mut segments {
        let mut b = vec![vec![0.0; seg.sigma.len()]; p1];
        for (t, &sg) in seg.sigma.iter().enumerate() {
            out.basis(sg, top, &mut phi);
            for (column, &v) in b.iter_mut().zip(&phi) {
                column[t] = v;
            }
        }
        seg.basis = b;
    }
    for seg in &segments {
        let len = seg.sigma.len();
        let basis = &seg.basis;
        let columns: Vec<(usize, Vec<f64>)> = (0..width)
            .into_par_iter()
            .filter_map(|c| {
                let (g, i) = (c / p1, c % p1);
                if g == 3 * d && i == 0 {
                    return None; // a constant detrends to zero
                }
                let product: Vec<f64> = if g == 3 * d {
                    basis[i].clone()
                } else if matches!(reading, AngleReading::Integrated { .. }) && g == 2 * d {
                    // the whole angle (the schedule already added to an offset)
                    seg.signals[2 * d]
                        .iter()
                        .map(|theta| {
                            let u = 2.0 * (theta - lo) / span - 1.0;
                            0.5 * span * chebyshev_integral(u, i)
                        })
                        .collect()
                } else {
                    seg.signals[g]
                        .iter()
                        .zip(&basis[i])
                        .map(|(s, b)| s * b)
                        .collect()
                };
                Some(seg.detrend(slow, &product).map(|v| (c, v)))
            })
            .collect::<Result<Vec<_>>>()?
            .into_iter()
            .collect();
        for (c, col) in &columns {
            for (r, &i) in seg.kept.iter().enumerate() {
                out.x[(row0 + r) * width + c] = col[i];
            }
        }
        for k in 0..d {
            let f = seg.detrend(slow, &seg.signals[3 * d + k])?;
            for (r, &i) in seg.kept.iter().enumerate() {
                out.f[(row0 + r) * d + k] = f[i];
            }
        }
        for &i in &seg.kept {
            out.sigma.push(seg.sigma[i]);
            out.block.push(block + (i - seg.trim) / block_len);
        }
        row0 += seg.kept.len();
        block += len / block_len + 1;
    }
    // the offset's columns are what the segments' trends leave of T_i(σ)
    out.offset = segments.iter().any(|s| s.trend == Trend::Slow) || {
        let energy = |c: usize| (0..n).map(|r| out.x[r * width + c].powi(2)).sum::<f64>();
        let column = |i: usize| 3 * d * p1 + i;
        let sigma_ss: f64 = out.sigma.iter().map(|s| ((s - lo) / span).powi(2)).sum();
        (1..p1).any(|i| energy(column(i)) > 1e-6 * sigma_ss)
    };
    out.segments = segments;
    Ok((out, dec, trim))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chebyshev_integral_differentiates_back_to_the_polynomial() {
        let h = 1e-5;
        for i in 0..=MAX_BASIS_ORDER + 1 {
            for &u in &[-1.2, -0.7, 0.0, 0.3, 0.95, 1.1] {
                let slope =
                    (chebyshev_integral(u + h, i) - chebyshev_integral(u - h, i)) / (2.0 * h);
                let mut t = [0.0; MAX_BASIS_ORDER + 3];
                chebyshev(u, i, &mut t);
                assert!(
                    (slope - t[i]).abs() < 1e-6 * t[i].abs().max(1.0),
                    "T_{i}({u}): {slope} vs {}",
                    t[i]
                );
            }
        }
    }
}
