//! Trials: the windows a recording is cut into before estimation.
//!
//! FORMAT.md: consecutive samples with the same `trial` id form one
//! perturbation window that starts at rest. Without a `trial` column the
//! windows are found from the motion (seed 000 §II-B: a centre-out motion
//! starts from rest at the start point), or the recording is one continuous
//! window (stochastic data, seed 004).
//!
//! Onset detection: the position noise σ of each coordinate is estimated from
//! the median absolute second difference (robust to smooth motion); the onset
//! is the first of three samples in a row whose deviation from the initial
//! rest (mean of the first 10 samples) exceeds 6σ on any signal. Slow motions
//! are found late, but then the force they cause before detection is tiny;
//! steps (of force, with a step of acceleration) are found at once. Choice
//! made here, not in the seeds.

use std::ops::Range;

use crate::error::{Error, Result};
use crate::recording::Recording;

/// One estimation window: samples `range` (indices into the recording).
#[derive(Debug, Clone, PartialEq)]
pub struct Window {
    /// Trial id (from the `trial` column, or counted from 1).
    pub id: i64,
    /// Sample indices of the window.
    pub range: Range<usize>,
    /// Absolute index of the perturbation onset; `None` for a continuous window.
    pub onset: Option<usize>,
}

impl Window {
    /// Samples of rest before the onset (0 for a continuous window).
    pub fn rest_len(&self) -> usize {
        self.onset.map_or(0, |o| o - self.range.start)
    }
}

/// Robust noise standard deviation of a smooth signal from its second differences.
pub fn noise_sigma(x: &[f64]) -> f64 {
    if x.len() < 3 {
        return 0.0;
    }
    let med = f64::from_bits(median_bits(x.len() - 2, &SecondDifferences(x)));
    // second difference of white noise has variance 6 sigma^2; MAD -> sigma factor 0.6745
    med / (0.6745 * 6f64.sqrt())
}

/// A signal logged faster than it was measured: each value held for
/// `factor` samples (a 250 Hz encoder logged at 1 kHz), or interpolated
/// linearly between values `factor` samples apart (a stream put on a faster
/// clock).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Resampled {
    /// Samples per measured value.
    pub factor: usize,
    /// Held (repeated) rather than linearly interpolated.
    pub held: bool,
    /// Index of the first sample of a new measured value (0..factor); with
    /// `irregular` the first one's.
    pub phase: usize,
    /// The measured values came at irregular times (a stream's own clock put
    /// on another, as XDF and ROS readers do): `factor` is the mean spacing
    /// (the samples kept are [`Resampled::stride`] apart).
    pub irregular: bool,
}

impl Resampled {
    /// Samples between those kept to stand for the measured values: the
    /// factor, or twice it at irregular times, where a sample `factor`
    /// after another may blend the same two measured values (their noise
    /// then correlated: B came out 8 % low at 3 SE on a stream at 1/4.1 of
    /// the clock, at twice the stride within 1.3 SE of the native answer).
    pub fn stride(&self) -> usize {
        if self.irregular {
            2 * self.factor
        } else {
            self.factor
        }
    }

    /// "held for 4 samples" or "linearly interpolated over 4 samples".
    pub fn describe(&self) -> String {
        let about = if self.irregular { "about " } else { "" };
        if self.held {
            format!("each value held for {about}{} samples", self.factor)
        } else {
            format!(
                "linearly interpolated between values {about}{} samples apart",
                self.factor
            )
        }
    }
}

/// Largest resampling factor looked for.
const MAX_RESAMPLING: usize = 32;

/// Whether `x` was held or linearly interpolated from a slower signal
/// (issue 56): its first differences (held) or second differences
/// (interpolated) are zero, to rounding, except on one sample in every
/// `factor`, always at the same phase. A quantised signal at its native
/// rate also has many zero differences, but where its value changes falls
/// anywhere, not on a grid; so at least 20 changes are needed, 99 % of
/// them on one residue.
pub fn resampling(x: &[f64]) -> Option<Resampled> {
    // a logging rate holds for the whole signal: its start is enough (and
    // bounds the cost on long recordings)
    let x = &x[..x.len().min(1 << 16)];
    let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if x.len() < 8 * MAX_RESAMPLING || !(scale.is_finite() && scale > 0.0) {
        return None;
    }
    let tolerance = 1e-9 * scale;
    // held: first differences; interpolated: second differences
    for held in [true, false] {
        let changes: Vec<usize> = if held {
            (1..x.len())
                .filter(|&i| (x[i] - x[i - 1]).abs() > tolerance)
                .collect()
        } else {
            (2..x.len())
                .filter(|&i| (x[i] - 2.0 * x[i - 1] + x[i - 2]).abs() > tolerance)
                // the knot sits one sample before the second difference that sees it
                .map(|i| i - 1)
                .collect()
        };
        if changes.len() < 20 {
            continue;
        }
        // 99 % of the changes on one residue of k allows at most
        // len/k + 1 of them there: a signal that changes on most samples
        // (every natively sampled one) is on no grid, and counting its
        // residues for 31 factors took 5 ms a column (issue 82)
        let on_one_residue = |k: usize| 0.99 * changes.len() as f64 <= (x.len() / k + 1) as f64;
        let on_grid = |k: usize| -> Option<usize> {
            if !on_one_residue(k) {
                return None;
            }
            let mut count = vec![0usize; k];
            for &i in &changes {
                count[i % k] += 1;
            }
            let (phase, most) = count
                .iter()
                .enumerate()
                .max_by_key(|(_, c)| **c)
                .map(|(p, c)| (p, *c))?;
            (most as f64 >= 0.99 * changes.len() as f64).then_some(phase)
        };
        if let Some((factor, phase)) = (2..=MAX_RESAMPLING)
            .rev()
            .find_map(|k| on_grid(k).map(|p| (k, p)))
        {
            return Some(Resampled {
                factor,
                held,
                phase,
                irregular: false,
            });
        }
        if let Some(r) = irregular_knots(&changes, held) {
            return Some(r);
        }
    }
    None
}

/// Measured values at irregular times (issue 58: an XDF stream's samples
/// carry their own jittered stamps, and a stream whose rate is not a whole
/// fraction of the clock it is put on has its knots 4 or 5 samples apart):
/// the changes come in short clusters (a held value changes on one sample,
/// an interpolated knot bends the line on one or two, two knots close
/// together on up to four) spaced so regularly (coefficient of variation
/// under 0.5) that they are a clock's, not a quantised signal's (whose
/// steps fall where the motion puts them: a spread near 1).
fn irregular_knots(changes: &[usize], held: bool) -> Option<Resampled> {
    let longest_cluster = if held { 1 } else { 4 };
    let mut knots: Vec<usize> = Vec::new();
    let mut run = 1;
    for (k, &i) in changes.iter().enumerate() {
        if k > 0 && changes[k - 1] + 1 == i {
            run += 1;
            if run > longest_cluster {
                return None;
            }
        } else {
            run = 1;
            knots.push(i);
        }
    }
    if knots.len() < 20 {
        return None;
    }
    let gaps: Vec<f64> = knots.windows(2).map(|w| (w[1] - w[0]) as f64).collect();
    let mean = gaps.iter().sum::<f64>() / gaps.len() as f64;
    let sd = (gaps.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / gaps.len() as f64).sqrt();
    let factor = mean.round() as usize;
    (mean >= 2.5 && factor <= MAX_RESAMPLING && sd < 0.5 * mean).then(|| Resampled {
        factor,
        held,
        phase: knots[0] % factor,
        irregular: true,
    })
}

/// Noise standard deviation of `x` at the rate it was measured: from the
/// measured values only when it was held or interpolated ([`resampling`]),
/// whose zero differences would otherwise read as no noise at all.
pub fn native_noise_sigma(x: &[f64]) -> (f64, Option<Resampled>) {
    match resampling(x) {
        Some(r) => {
            let measured: Vec<f64> = x
                .iter()
                .skip(r.phase)
                .step_by(r.stride())
                .copied()
                .collect();
            (noise_sigma(&measured), Some(r))
        }
        None => (noise_sigma(x), None),
    }
}

/// |x[i+2] - 2 x[i+1] + x[i]| of a signal, as bits, given to a visitor as
/// often as asked (each pass computes them anew). Computed in blocks of 64
/// (which vectorise) before each is visited: the per-sample form kept the
/// noise estimate's two passes scalar (issue 82).
struct SecondDifferences<'a>(&'a [f64]);

impl SecondDifferences<'_> {
    fn visit(&self, mut each: impl FnMut(u64)) {
        const BLOCK: usize = 64;
        let x = self.0;
        let mut bits = [0u64; BLOCK];
        let mut blocks = x.windows(BLOCK + 2).step_by(BLOCK);
        let mut done = 0;
        for w in &mut blocks {
            for (k, b) in bits.iter_mut().enumerate() {
                *b = (w[k + 2] - 2.0 * w[k + 1] + w[k]).abs().to_bits();
            }
            bits.iter().for_each(|b| each(*b));
            done += BLOCK;
        }
        for w in x[done..].windows(3) {
            each((w[2] - 2.0 * w[1] + w[0]).abs().to_bits());
        }
    }
}

/// The element of rank `count / 2` of `count` non-negative floats given as
/// bits (which sort as the floats do), by radix selection: a histogram of
/// the top 16 bits, then a selection among the values of the median's
/// bucket only. Two passes of the visitor and no copy of the whole
/// signal (a sort-based selection of 1.8 M values took 20 ms, issue 16).
fn median_bits(count: usize, values: &SecondDifferences) -> u64 {
    let mid = count / 2;
    let mut histogram = vec![0usize; 1 << 16];
    values.visit(|v| histogram[(v >> 48) as usize] += 1);
    let mut below = 0;
    let mut bucket = 0;
    for (b, c) in histogram.iter().enumerate() {
        if below + c > mid {
            bucket = b as u64;
            break;
        }
        below += c;
    }
    let mut inside: Vec<u64> = Vec::new();
    values.visit(|v| {
        if v >> 48 == bucket {
            inside.push(v)
        }
    });
    *inside.select_nth_unstable(mid - below).1
}

/// The smallest and largest of `x`, NaN left out ((inf, -inf) when
/// nothing is left); eight lanes of plain comparisons, which vectorise where
/// `f64::min`'s NaN rule does not (a 1.8 M-sample column in 1 ms instead of
/// 4, issue 82).
pub fn extremes(x: &[f64]) -> (f64, f64) {
    const LANES: usize = 8;
    let mut lo = [f64::INFINITY; LANES];
    let mut hi = [f64::NEG_INFINITY; LANES];
    let mut blocks = x.chunks_exact(LANES);
    for block in &mut blocks {
        for k in 0..LANES {
            lo[k] = if block[k] < lo[k] { block[k] } else { lo[k] };
            hi[k] = if block[k] > hi[k] { block[k] } else { hi[k] };
        }
    }
    let rest = blocks.remainder().iter();
    let lo = lo
        .iter()
        .chain(rest.clone())
        .fold(f64::INFINITY, |m, v| m.min(*v));
    let hi = hi
        .iter()
        .chain(rest)
        .fold(f64::NEG_INFINITY, |m, v| m.max(*v));
    (lo, hi)
}

/// Smallest change that counts as an onset, per signal: 0.1 % of its range.
pub fn change_floors(signals: &[&[f64]]) -> Vec<f64> {
    signals
        .iter()
        .map(|c| {
            let (lo, hi) = extremes(c);
            if hi > lo {
                1e-3 * (hi - lo)
            } else {
                1e-12
            }
        })
        .collect()
}

/// The sample ranges of a recording's contiguous segments: its `trial`
/// windows, or the whole record without the column.
pub fn segment_ranges(rec: &Recording) -> Result<Vec<Range<usize>>> {
    if !rec.has("trial") {
        return Ok(std::iter::once(0..rec.len()).collect());
    }
    Ok(windows_from_trial_column(rec, "trial")?
        .into_iter()
        .map(|w| w.range)
        .collect())
}

/// A finite whole number. `fract` is a libm call on baseline x86-64 (no
/// SSE4.1 rounding): a conversion round trip tests 1.8 M trial ids in a
/// fraction of its time (issue 82); from 2^52 up every double is whole.
fn is_whole(x: f64) -> bool {
    x.is_finite() && (x.abs() >= 4_503_599_627_370_496.0 || (x as i64) as f64 == x)
}

/// Split the recording by its integer `trial` column into consecutive runs.
pub fn windows_from_trial_column(rec: &Recording, column: &str) -> Result<Vec<Window>> {
    let ids = rec.require(column, "trial ids")?;
    let mut out: Vec<Window> = Vec::new();
    let mut start = 0;
    for i in 0..=ids.len() {
        if i < ids.len() && !is_whole(ids[i]) {
            return Err(Error::Format {
                path: rec.path().to_path_buf(),
                message: format!(
                    "row {}, column {column}: expected an integer trial id, found {}",
                    rec.row_of(i),
                    crate::error::Num(ids[i])
                ),
            });
        }
        if i == ids.len() || ids[i] != ids[start] {
            out.push(Window {
                id: ids[start] as i64,
                range: start..i,
                onset: None,
            });
            start = i;
        }
    }
    Ok(out)
}

/// Threshold settings of onset detection, in multiples of the noise σ.
const ONSET_SIGMA: f64 = 6.0;

/// Find the perturbation onset inside `range` (absolute index), or `None` if nothing moves.
///
/// `floors` are the smallest changes that count, one per signal, so that
/// noiseless or smooth (drifting) signals still have a finite threshold.
pub fn detect_onset(
    coords: &[&[f64]],
    range: Range<usize>,
    sigmas: &[f64],
    floors: &[f64],
) -> Option<usize> {
    let n = range.len();
    if n < 4 {
        return None;
    }
    let k0 = 10.min(n / 4).max(1);
    let base: Vec<f64> = coords
        .iter()
        .map(|c| c[range.start..range.start + k0].iter().sum::<f64>() / k0 as f64)
        .collect();
    let over = |i: usize| {
        let m = ONSET_SIGMA;
        coords
            .iter()
            .zip(&base)
            .zip(sigmas.iter().zip(floors))
            .any(|((c, b), (s, floor))| (c[i] - b).abs() > (m * s).max(*floor))
    };
    let mut run = 0;
    for i in range.clone() {
        if over(i) {
            run += 1;
            if run == 3 {
                return Some(i - 2);
            }
        } else {
            run = 0;
        }
    }
    None
}

/// The perturbation onset inside `range` from motion and force: the first of
/// all `signals` (the first `motion` of them positions, the rest forces) to
/// leave rest, as long as a force leads the motion by at most `lead_max`
/// samples. A force that leaves earlier is the subject's slow fluctuation,
/// grip drift or a coarse sensor's step, not the perturbation: the motion
/// decides then, refined by the forces against their level just before the
/// lead window (a fluctuation moves little in 40 ms). So does the motion when
/// a force leaves rest within the first `min_rest` samples: a perturbation
/// starts from rest.
pub fn perturbation_onset(
    signals: &[&[f64]],
    motion: usize,
    range: Range<usize>,
    sigmas: &[f64],
    floors: &[f64],
    (lead_max, min_rest): (usize, usize),
) -> Option<usize> {
    let any = detect_onset(signals, range.clone(), sigmas, floors);
    let moved = detect_onset(
        &signals[..motion],
        range.clone(),
        &sigmas[..motion],
        &floors[..motion],
    );
    match (any, moved) {
        (Some(a), Some(m)) if m - a <= lead_max && a - range.start >= min_rest => Some(a),
        (_, Some(m)) => {
            let from = m.saturating_sub(lead_max + 10).max(range.start);
            match detect_onset(signals, from..range.end, sigmas, floors) {
                Some(a) if a + lead_max >= m && a >= from + 10 => Some(a),
                _ => Some(m),
            }
        }
        (a, None) => a,
    }
}

/// Find perturbation windows in a recording without a `trial` column.
///
/// The home position is the mean of the first 10 samples. A sample is "at
/// home" when every coordinate is within max(6σ, 2 % of its largest
/// excursion) of home. A window runs from the start of one stretch of at
/// least `min_rest` samples at home to the start of the next such stretch;
/// its onset is found inside it by [`detect_onset`]. Returns an empty list when
/// fewer than two windows are found.
pub fn detect_windows(coords: &[&[f64]], min_rest: usize) -> Vec<Window> {
    let n = coords.first().map_or(0, |c| c.len());
    if n < 2 * min_rest.max(10) {
        return Vec::new();
    }
    let sigmas: Vec<f64> = coords.iter().map(|c| noise_sigma(c)).collect();
    let home: Vec<f64> = coords
        .iter()
        .map(|c| c[..10].iter().sum::<f64>() / 10.0)
        .collect();
    let tol: Vec<f64> = coords
        .iter()
        .zip(&home)
        .zip(&sigmas)
        .map(|((c, h), s)| {
            let exc = c.iter().fold(0.0f64, |m, v| m.max((v - h).abs()));
            (ONSET_SIGMA * s).max(0.02 * exc).max(1e-12)
        })
        .collect();
    let at_home = |i: usize| {
        coords
            .iter()
            .zip(&home)
            .zip(&tol)
            .all(|((c, h), t)| (c[i] - h).abs() <= *t)
    };
    // starts of stretches at home that last at least min_rest samples
    let mut starts = Vec::new();
    let mut i = 0;
    while i < n {
        if at_home(i) {
            let s = i;
            while i < n && at_home(i) {
                i += 1;
            }
            if i - s >= min_rest && i < n {
                starts.push(s);
            }
        } else {
            i += 1;
        }
    }
    let floors = change_floors(coords);
    let mut out = Vec::new();
    for (k, &s) in starts.iter().enumerate() {
        let end = starts.get(k + 1).copied().unwrap_or(n);
        if let Some(onset) = detect_onset(coords, s..end, &sigmas, &floors) {
            if onset - s >= min_rest {
                out.push(Window {
                    id: out.len() as i64 + 1,
                    range: s..end,
                    onset: Some(onset),
                });
            }
        }
    }
    if out.len() < 2 {
        Vec::new()
    } else {
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn is_whole_agrees_with_fract() {
        for x in [
            0.0,
            -0.0,
            1.0,
            -3.0,
            2.5,
            -2.5,
            1e-300,
            4503599627370495.5,
            9e15,
            1e300,
            -1e300,
        ] {
            assert_eq!(is_whole(x), x.fract() == 0.0, "{x}");
        }
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(!is_whole(x), "{x}");
        }
    }

    #[test]
    fn extremes_are_the_smallest_and_largest_at_every_length() {
        for n in [1, 7, 8, 9, 17, 100] {
            let x: Vec<f64> = (0..n).map(|i| ((i * 37 % 11) as f64 - 5.0) * 0.3).collect();
            let lo = x.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            assert_eq!(extremes(&x), (lo, hi), "n = {n}");
        }
        assert_eq!(extremes(&[]), (f64::INFINITY, f64::NEG_INFINITY));
    }

    /// A slower stream at jittered times interpolated onto a 4x clock
    /// (issue 58): found as irregular, its noise read from every 8th sample.
    #[test]
    fn a_stream_interpolated_from_jittered_times_is_found_and_its_noise_read() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let noise = 1e-3;
        let (stamps, values): (Vec<f64>, Vec<f64>) = (0..2000)
            .map(|j| {
                let t = (j as f64 + 0.6 * (uniform() - 0.5)) / 125.0;
                // sum of uniforms: near-normal noise of s.d. `noise`
                let e: f64 = (0..12).map(|_| uniform() - 0.5).sum::<f64>() * noise;
                (t, 0.02 * (2.0 * std::f64::consts::PI * 0.7 * t).sin() + e)
            })
            .unzip();
        let x: Vec<f64> = (0..7900)
            .map(|i| {
                let t = 0.01 + i as f64 / 500.0;
                let k = stamps.partition_point(|s| *s <= t) - 1;
                let f = (t - stamps[k]) / (stamps[k + 1] - stamps[k]);
                values[k] * (1.0 - f) + values[k + 1] * f
            })
            .collect();
        let r = resampling(&x).expect("found");
        assert!(r.irregular && !r.held && r.factor == 4, "{r:?}");
        let (sigma, _) = native_noise_sigma(&x);
        // every 8th sample is a mix of two measured values: 0.82 of their noise on average
        assert!((0.6 * noise..1.1 * noise).contains(&sigma), "{sigma}");
        assert!(
            noise_sigma(&x) < 0.3 * noise,
            "the plain estimate misses it"
        );
    }

    /// A force sensor that steps by its resolution at rest (a coarse or
    /// drifting sensor) leads the motion by far more than a perturbation
    /// can: the motion decides, and the force's own onset near it is kept.
    #[test]
    fn a_force_leading_the_motion_by_far_does_not_mark_the_onset() {
        let n = 600;
        let motion_at = 400;
        let position: Vec<f64> = (0..n)
            .map(|i| {
                if i < motion_at {
                    0.0
                } else {
                    1e-4 * ((i - motion_at) as f64).powi(2)
                }
            })
            .collect();
        // a 0.05 N step at sample 8, then the perturbation's force 5 ms before the motion
        let force: Vec<f64> = (0..n)
            .map(|i| {
                let step = if i >= 8 { 0.05 } else { 0.0 };
                let push = if i + 5 >= motion_at {
                    0.5 * (i + 5 - motion_at) as f64
                } else {
                    0.0
                };
                step + push
            })
            .collect();
        let signals: Vec<&[f64]> = vec![&position, &force];
        let (sigmas, floors) = ([1e-6, 0.0], [1e-5, 0.01]);
        let any = detect_onset(&signals, 0..n, &sigmas, &floors);
        assert_eq!(any, Some(8), "the step alone marks the onset");
        let onset = perturbation_onset(&signals, 1, 0..n, &sigmas, &floors, (30, 3)).unwrap();
        assert!(
            (motion_at - 6..=motion_at).contains(&onset),
            "onset {onset}"
        );
        // a force leading by less than the limit still marks it
        let onset = perturbation_onset(&signals, 1, 0..n, &sigmas, &floors, (500, 3)).unwrap();
        assert_eq!(onset, 8);
        // ... unless it leaves less rest before it than a perturbation needs:
        // then the motion's own onset
        let onset = perturbation_onset(&signals, 1, 0..n, &sigmas, &floors, (500, 10)).unwrap();
        assert_eq!(onset, motion_at + 1);
    }

    /// The radix selection gives the median a full sort gives, on noise,
    /// on values with many ties, and on a constant signal.
    #[test]
    fn noise_sigma_is_the_sorted_median_of_second_differences() {
        let sorted_sigma = |x: &[f64]| {
            let mut d2: Vec<f64> = x
                .windows(3)
                .map(|w| (w[2] - 2.0 * w[1] + w[0]).abs())
                .collect();
            d2.sort_by(f64::total_cmp);
            d2[d2.len() / 2] / (0.6745 * 6f64.sqrt())
        };
        // deterministic pseudo-random noise on a slow sine
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for len in [3, 4, 5, 65, 66, 67, 101, 130, 10_000, 100_001] {
            let noisy: Vec<f64> = (0..len)
                .map(|i| (i as f64 * 1e-3).sin() + 1e-4 * uniform())
                .collect();
            assert_eq!(noise_sigma(&noisy), sorted_sigma(&noisy), "{len}");
            // quantised: many equal second differences
            let steps: Vec<f64> = noisy.iter().map(|v| (v * 1e3).round() / 1e3).collect();
            assert_eq!(noise_sigma(&steps), sorted_sigma(&steps), "{len}");
        }
        assert_eq!(noise_sigma(&[2.5; 1000]), 0.0);
        assert!(noise_sigma(&[1.0, 3.0, 2.0]) > 0.0);
    }

    /// Issue 56: held and interpolated signals are found with their factor,
    /// and their noise is read at the measured rate; a quantised signal at
    /// its own rate is not mistaken for one.
    #[test]
    fn held_and_interpolated_signals_are_found() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let sigma = 1e-4;
        // white noise of σ: uniform on ±√3 σ
        let native: Vec<f64> = (0..2000)
            .map(|i| 0.01 * (i as f64 * 4e-3).sin() + sigma * 12f64.sqrt() * uniform())
            .collect();
        assert_eq!(resampling(&native), None);
        let held: Vec<f64> = (0..8000).map(|i| native[i / 4]).collect();
        let (s, r) = native_noise_sigma(&held);
        assert_eq!(r.map(|r| (r.factor, r.held)), Some((4, true)));
        assert!((s / sigma - 1.0).abs() < 0.2, "{s}");
        assert!(
            noise_sigma(&held) < 0.1 * sigma,
            "the full-rate estimate is ~0"
        );
        let interpolated: Vec<f64> = (0..7996)
            .map(|i| {
                let (k, f) = (i / 4, (i % 4) as f64 / 4.0);
                native[k] * (1.0 - f) + native[k + 1] * f
            })
            .collect();
        let (s, r) = native_noise_sigma(&interpolated);
        assert_eq!(r.map(|r| (r.factor, r.held)), Some((4, false)));
        assert!((s / sigma - 1.0).abs() < 0.2, "{s}");
        // quantised to 1e-4 at the native rate: many zero differences, no grid
        let quantised: Vec<f64> = native.iter().map(|v| (v * 1e4).round() / 1e4).collect();
        assert_eq!(resampling(&quantised), None);
        // a constant or short signal: nothing to say
        assert_eq!(resampling(&[1.0; 1000]), None);
        assert_eq!(resampling(&held[..100]), None);
    }
}
