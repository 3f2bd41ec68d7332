//! Short data segments: one joint seen through many short, separate
//! stretches of a session (Ludvig & Perreault 2012, IEEE TBME 59(12)).
//!
//! Each `trial` window of a recording is a segment with its own initial
//! conditions. Nothing is computed across a cut: derivatives, the
//! anti-alias filter and decimation run inside each segment; correlations
//! pair samples of one segment; an IRF is applied to each segment with no
//! input before its start; every segment has its own constant (the
//! background torque and the operating point differ from segment to
//! segment). The start-up of a segment, where the reflex answers motion
//! from before the cut, is left out of the parametric fit up to the delay
//! found (plus the filters' settling); the low-pass's unknown state there
//! is two nuisance regressors per segment, its free responses (the
//! transient terms of Ludvig & Perreault). Choices in
//! docs/src/reference/estimate-reflex.md ("Short segments").

use std::borrow::Cow;
use std::ops::Range;

use limpid_core::{Error, Recording, Result, Warning, WarningCode};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::cascade::{anti_alias, decimate, decimation_ratio};
use super::{Decimated, ReflexParams};

/// How a recording of short segments was used.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct SegmentUse {
    /// Segments in the recording (its `trial` windows).
    pub count: usize,
    /// Segments fitted; the others are shorter than `shortest_usable_s`.
    pub used: usize,
    /// A segment shorter than this (s) holds no row of the delay scan.
    pub shortest_usable_s: f64,
    /// Durations of the fitted segments (s): shortest, median, longest.
    pub durations_s: [f64; 3],
    /// Left out at each segment's start by the fit of I, B, K and the
    /// reflex gain (s): the delay interval's end, the anti-alias filter's
    /// settling and the derivative's edge. The delay scan leaves out the
    /// longest delay scanned instead.
    pub start_left_out_s: f64,
    /// Length of the nonparametric reflex IRF (s): at most half the median
    /// segment, whatever was asked (an IRF needs its input history inside
    /// the segment).
    pub reflex_irf_s: f64,
}

/// Lengths in decimated samples.
pub(crate) struct Layout {
    /// Half-width of the two-sided intrinsic IRF.
    pub(crate) half: usize,
    /// Length of the reflex IRF (also the samples left out of each segment's VAF).
    pub(crate) n_reflex: usize,
    /// Samples left out at each segment's start by the parametric delay scan.
    pub(crate) fit_skip: usize,
}

/// Rows a segment must keep past its start-up to be fitted.
const MIN_ROWS: usize = 5;

/// The shortest delay scan (s) limpid shortens to for short segments: no
/// stretch reflex of a limb is faster.
const MIN_SCANNED_DELAY_S: f64 = 0.02;

/// The settings for these segments: when fewer than half of them are long
/// enough for the delay scan asked, the scan ends where it leaves half the
/// median segment to the fit (not below [`MIN_SCANNED_DELAY_S`]), with a
/// warning.
fn fit_to_segments(
    p: &ReflexParams,
    cuts: &[Range<usize>],
    (fs, ratio): (f64, usize),
    warnings: &mut Vec<Warning>,
) -> Option<ReflexParams> {
    let min_len = |max_delay: usize| {
        (start_up(max_delay, ratio).saturating_add(MIN_ROWS)).saturating_mul(ratio)
    };
    let asked = (p.max_delay_s * fs).round() as usize;
    let usable = cuts.iter().filter(|c| c.len() >= min_len(asked)).count();
    if 2 * usable >= cuts.len() {
        return None;
    }
    let mut lengths: Vec<usize> = cuts.iter().map(|c| c.len()).collect();
    lengths.sort_unstable();
    let median = lengths[lengths.len() / 2];
    // the longest delay whose start-up leaves half the median segment (at
    // least MIN_ROWS rows) to the scan: with only a few rows a segment the
    // low-pass is not determined (K 159 for 85 on the outside example with
    // 5 rows, 83 with half)
    let rows = (median / ratio / 2)
        .max(MIN_ROWS)
        .min((median / ratio).checked_sub(MIN_ROWS)?);
    let delay = (rows * ratio)
        .checked_sub(settling(ratio))?
        .min(asked.saturating_sub(1));
    debug_assert!(min_len(delay) <= median);
    if (delay as f64) < MIN_SCANNED_DELAY_S * fs {
        return None;
    }
    warnings.push(Warning::new(
        WarningCode::NotIdentifiable,
        format!(
            "reflex delays scanned up to {} ms, not the {} ms asked (max_delay_s): the segments (median {:.3} s) are too short for longer ones; a longer reflex delay cannot be identified from them, and a best delay at the end of this scan is called not identifiable",
            limpid_core::short_number(delay as f64 / fs * 1e3),
            limpid_core::short_number(p.max_delay_s * 1e3),
            median as f64 / fs
        ),
    ));
    Some(p.with_max_delay(delay as f64 / fs))
}

/// The usable segments decimated and laid end to end, their layout and
/// use; segments too short for one row of the delay scan are left out
/// with a warning.
pub(crate) fn prepare(
    rec: &Recording,
    (q, tq): (&[f64], &[f64]),
    p: &ReflexParams,
    cuts: &[Range<usize>],
    warnings: &mut Vec<Warning>,
) -> Result<(Layout, [Decimated; 2], SegmentUse, Option<ReflexParams>)> {
    let fs = rec.sample_rate();
    let ratio = decimation_ratio(fs, p);
    let shortened = fit_to_segments(p, cuts, (fs, ratio), warnings);
    let p = shortened.as_ref().unwrap_or(p);
    let fsd = fs / ratio as f64;
    let lag = |s: f64| (s * fsd).round() as usize;
    let half = lag(p.intrinsic_lags_s).max(1);
    let fit_skip = start_up((p.max_delay_s * fs).round() as usize, ratio);
    // the zero-phase filter's odd extension needs more samples than its padding
    let padding = if ratio > 1 {
        anti_alias(fs, ratio)?.padlen() + 1
    } else {
        0
    };
    let min_len = (fit_skip.saturating_add(MIN_ROWS))
        .saturating_mul(ratio)
        .max(padding);
    let used: Vec<Range<usize>> = cuts
        .iter()
        .filter(|c| c.len() >= min_len)
        .cloned()
        .collect();
    let seconds = |len: usize| len as f64 / fs;
    if used.is_empty() {
        return Err(Error::TooFewSamples {
            path: rec.path().to_path_buf(),
            what: format!(
                "the parallel-cascade method on short segments: no segment (trial) is {:.3} s long, the longest reflex delay scanned (max_delay_s {}) plus the anti-alias filter's settling plus {MIN_ROWS} samples at {} Hz",
                seconds(min_len),
                limpid_core::short_number(p.max_delay_s),
                limpid_core::short_number(fsd)
            ),
            needed: min_len,
            found: cuts.iter().map(|c| c.len()).max().unwrap_or(0),
        });
    }
    if used.len() < cuts.len() {
        warnings.push(Warning::new(
            WarningCode::FewTrials,
            format!(
                "{} of {} segments (trials) left out: shorter than {:.3} s, the longest reflex delay scanned plus the filters' settling",
                cuts.len() - used.len(),
                cuts.len(),
                seconds(min_len)
            ),
        ));
    }
    let mut lengths: Vec<usize> = used.iter().map(|c| c.len() / ratio).collect();
    lengths.sort_unstable();
    let median = lengths[lengths.len() / 2];
    let asked = lag(p.reflex_lags_s).max(2);
    let n_reflex = asked.min(median / 2).max(2);
    if n_reflex < asked {
        warnings.push(Warning::new(
            WarningCode::NotIdentifiable,
            format!(
                "the nonparametric reflex IRF spans {:.2} s, not the {} s asked: the segments (median {:.2} s) hold no longer input history; the parametric reflex pathway (delay, gain, low-pass) is the estimate, and the nonparametric VAF split leaves out each segment's first {:.2} s",
                n_reflex as f64 / fsd,
                limpid_core::short_number(p.reflex_lags_s),
                median as f64 / fsd,
                n_reflex as f64 / fsd
            ),
        ));
    }
    let cascade_rows: usize = lengths.iter().map(|l| l.saturating_sub(n_reflex)).sum();
    let needed = 5 * n_reflex.max(2 * half + 1);
    if cascade_rows < needed {
        return Err(Error::TooFewSamples {
            path: rec.path().to_path_buf(),
            what: format!(
                "the parallel-cascade method on {} short segments at {} Hz (5 IRF lengths past each segment's first {:.2} s)",
                used.len(),
                limpid_core::short_number(fsd),
                n_reflex as f64 / fsd
            ),
            needed: needed * ratio,
            found: cascade_rows * ratio,
        });
    }
    let decimated = decimate_each(q, tq, fs, p, &used)?;
    let durations: Vec<f64> = {
        let mut d: Vec<f64> = used.iter().map(|c| seconds(c.len())).collect();
        d.sort_by(f64::total_cmp);
        d
    };
    let segment_use = SegmentUse {
        count: cuts.len(),
        used: used.len(),
        shortest_usable_s: seconds(min_len),
        durations_s: [
            durations[0],
            durations[durations.len() / 2],
            durations[durations.len() - 1],
        ],
        start_left_out_s: fit_skip as f64 / fsd,
        reflex_irf_s: n_reflex as f64 / fsd,
    };
    Ok((
        Layout {
            half,
            n_reflex,
            fit_skip,
        },
        decimated,
        segment_use,
        shortened,
    ))
}

/// The samples of every segment past its first `skip`, in order.
pub(crate) fn rows(segments: &[Range<usize>], skip: usize) -> impl Iterator<Item = usize> + '_ {
    segments
        .iter()
        .flat_map(move |s| (s.start + skip).min(s.end)..s.end)
}

/// `x` at [`rows`]: borrowed for one segment from the record's start.
pub(crate) fn gather<'a>(x: &'a [f64], segments: &[Range<usize>], skip: usize) -> Cow<'a, [f64]> {
    match segments {
        [whole] if whole.start == 0 => Cow::Borrowed(&x[skip.min(whole.end)..whole.end]),
        _ => Cow::Owned(rows(segments, skip).map(|i| x[i]).collect()),
    }
}

/// Where each segment's rows lie in a [`gather`]ed vector (empty segments left out).
pub(crate) fn groups(segments: &[Range<usize>], skip: usize) -> Vec<Range<usize>> {
    let mut at = 0;
    segments
        .iter()
        .filter_map(|s| {
            let len = s.len().saturating_sub(skip);
            at += len;
            (len > 0).then(|| at - len..at)
        })
        .collect()
}

/// The segments decimated one by one and laid end to end. Each segment is
/// cut to a whole number of decimation steps, so that decimated sample `k`
/// is recorded sample `k * ratio` of the concatenation (the delayed reflex
/// regressor reads the full-rate record by that rule).
pub(crate) fn decimate_each(
    q: &[f64],
    tq: &[f64],
    fs: f64,
    p: &ReflexParams,
    segments: &[Range<usize>],
) -> Result<[Decimated; 2]> {
    let ratio = decimation_ratio(fs, p);
    let mut parts: Vec<[Decimated; 2]> = Vec::with_capacity(segments.len());
    for s in segments {
        let end = s.start + s.len() / ratio * ratio;
        parts.push(decimate(&q[s.start..end], &tq[s.start..end], fs, p)?);
    }
    let join = |k: usize| -> Decimated {
        let mut out = Decimated {
            fs: fs / ratio as f64,
            ratio,
            segments: Vec::new(),
            position: Vec::new(),
            velocity: Vec::new(),
            acceleration: Vec::new(),
            torque: Vec::new(),
            rectified: [Vec::new(), Vec::new()],
            rectified_full: [Vec::new(), Vec::new()],
        };
        for part in &parts {
            let d = &part[k];
            let at = out.position.len();
            out.segments.push(at..at + d.position.len());
            out.position.extend_from_slice(&d.position);
            out.velocity.extend_from_slice(&d.velocity);
            out.acceleration.extend_from_slice(&d.acceleration);
            out.torque.extend_from_slice(&d.torque);
            for side in 0..2 {
                out.rectified[side].extend_from_slice(&d.rectified[side]);
                out.rectified_full[side].extend_from_slice(&d.rectified_full[side]);
            }
        }
        out
    };
    Ok([join(0), join(1)])
}

/// Recorded samples the filters need to settle at a segment's start: two
/// periods of the anti-alias filter's cut-off (0.4 of the decimated rate:
/// five decimated samples), and the derivatives' one-sided first sample.
fn settling(ratio: usize) -> usize {
    if ratio > 1 {
        5 * ratio + 1
    } else {
        1
    }
}

/// Decimated samples left out at a segment's start for a reflex delay of
/// `delay` recorded samples: the delay and the filters' settling.
pub(crate) fn start_up(delay: usize, ratio: usize) -> usize {
    delay.saturating_add(settling(ratio)).div_ceil(ratio)
}

/// The full-rate ranges of decimated segments.
pub(crate) fn full_rate(segments: &[Range<usize>], ratio: usize) -> Vec<Range<usize>> {
    segments
        .iter()
        .map(|s| s.start * ratio..s.end * ratio)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_and_groups_skip_each_segments_start() {
        let segments = [0..5, 5..7, 7..12];
        let r: Vec<usize> = rows(&segments, 2).collect();
        assert_eq!(r, vec![2, 3, 4, 9, 10, 11]);
        assert_eq!(groups(&segments, 2), vec![0..3, 3..6]);
        let x: Vec<f64> = (0..12).map(|i| i as f64).collect();
        assert_eq!(
            &*gather(&x, &segments, 2),
            &[2.0, 3.0, 4.0, 9.0, 10.0, 11.0]
        );
        let whole = std::iter::once(0..12).collect::<Vec<_>>();
        assert!(matches!(gather(&x, &whole, 3), Cow::Borrowed(s) if s.len() == 9));
    }
}
