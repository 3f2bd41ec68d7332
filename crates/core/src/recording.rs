//! `Recording`: one table of uniformly sampled time series (FORMAT.md v1).
//!
//! The whole table is checked once, when it is built: unique column names,
//! finite values of a plausible size for their unit ([`magnitude_limit`]), a
//! `t` column that is strictly increasing and uniform to within 1 % inside
//! each trial (FORMAT.md: where the `trial` id changes a longer gap is
//! allowed). Everything downstream can then trust it. What is accepted but
//! suspicious (a `t` that looks like milliseconds, a column name that looks
//! like a FORMAT.md name in another alphabet) is kept in [`Recording::warnings`].

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Largest allowed relative deviation of one sampling interval from the median (FORMAT.md).
pub const SAMPLING_TOLERANCE: f64 = 0.01;

/// A checked recording: time `t` (s) plus named `f64` columns in SI units.
#[derive(Debug, Clone)]
pub struct Recording {
    path: PathBuf,
    names: Vec<String>,
    columns: Vec<Vec<f64>>,
    time_index: usize,
    sample_rate: f64,
    first_row: usize,
    /// Source rows between consecutive samples (1 unless [`Recording::every`] kept every n-th).
    row_step: usize,
    warnings: Vec<String>,
}

/// Largest magnitude accepted in a column, by its FORMAT.md unit, with the unit.
///
/// The limits are far beyond any limb or robot (a position of 100 m, a force
/// of 1 MN) but keep every square and sum of squares far from overflow, so a
/// corrupt sample (1e307) is refused with its row and column instead of
/// turning an estimate into NaN. Columns limpid does not know get 1e15.
pub fn magnitude_limit(name: &str) -> (f64, &'static str) {
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let marker_axis = name
        .rsplit_once('_')
        .is_some_and(|(m, a)| !m.is_empty() && matches!(a, "x" | "y" | "z"));
    match name {
        "t" => (1e10, "s"),
        "x" | "y" | "z" | "rx" | "ry" | "rz" => (100.0, "m"),
        "theta" | "rtheta" => (1e4, "rad"),
        "fx" | "fy" | "fz" | "ux" | "uy" | "uz" => (1e6, "N"),
        "sensor_fx" | "sensor_fy" | "sensor_fz" => (1e6, "N"),
        "taux" | "tauy" | "tauz" | "utheta" | "sensor_tx" | "sensor_ty" | "sensor_tz" => {
            (1e6, "N m")
        }
        _ if marker_axis => (100.0, "m"),
        _ if name.strip_prefix("robot_q").is_some_and(digits) => (1e4, "rad"),
        _ if name.strip_prefix('q').is_some_and(digits) => (1e4, "rad"),
        _ if name.strip_prefix('r').is_some_and(digits) => (1e4, "rad"),
        _ if name.strip_prefix("tau").is_some_and(digits) => (1e6, "N m"),
        "trial" | "level" => (1e12, ""),
        _ if name.starts_with("emg_") || name.starts_with("env_") => (1e6, "V"),
        _ => (1e15, ""),
    }
}

/// True for a column name FORMAT.md defines (with a unit limpid knows), or an EMG channel.
pub fn is_format_column(name: &str) -> bool {
    magnitude_limit(name).0 < 1e15 || name.starts_with("emg_")
}

/// FORMAT.md's fixed column names, for the look-alike check.
const KNOWN_NAMES: [&str; 20] = [
    "t", "x", "y", "z", "fx", "fy", "fz", "theta", "tauy", "ux", "uy", "uz", "utheta", "trial",
    "level", "q1", "q2", "tau1", "tau2", "taux",
];

/// The ASCII letter a non-ASCII look-alike stands for (Cyrillic and Greek
/// letters that render like Latin ones), if any.
fn ascii_lookalike(c: char) -> Option<char> {
    Some(match c {
        'а' => 'a',
        'е' => 'e',
        'о' | 'ο' => 'o',
        'р' | 'ρ' => 'p',
        'с' => 'c',
        'у' => 'y',
        'х' | 'χ' => 'x',
        'і' => 'i',
        'τ' => 't',
        'ք' => 'q',
        'ԛ' => 'q',
        'ν' => 'v',
        'ѕ' => 's',
        'ᴢ' | 'ż' => 'z',
        'ƒ' => 'f',
        _ => return None,
    })
}

impl Recording {
    /// Build a recording from named columns and check it.
    ///
    /// `first_row` is the row number of the first sample in the source, used in
    /// error messages (2 for CSV, whose header is row 1; 1 for Parquet).
    pub fn new(
        path: impl AsRef<Path>,
        names: Vec<String>,
        columns: Vec<Vec<f64>>,
        first_row: usize,
    ) -> Result<Self> {
        let path = path.as_ref().to_path_buf();
        if names.is_empty() {
            return Err(Error::Empty { path });
        }
        let mut seen = std::collections::HashMap::with_capacity(names.len());
        for (i, name) in names.iter().enumerate() {
            if let Some(j) = seen.insert(name.as_str(), i) {
                return Err(Error::DuplicateColumn {
                    path,
                    column: name.clone(),
                    first: j + 1,
                    second: i + 1,
                });
            }
        }
        let n = columns.first().map_or(0, Vec::len);
        if n == 0 {
            return Err(Error::HeaderOnly { path });
        }
        if let Some((name, col)) = names.iter().zip(&columns).find(|(_, c)| c.len() != n) {
            return Err(Error::Format {
                path,
                message: format!(
                    "column {name} has {} samples, column {} has {n}",
                    col.len(),
                    names[0]
                ),
            });
        }
        let offending = out_of_range_columns(&names, &columns);
        for ((name, col), bad) in names.iter().zip(&columns).zip(offending) {
            let (limit, unit) = magnitude_limit(name);
            if let Some(i) = bad {
                if !col[i].is_finite() {
                    return Err(Error::NotFinite {
                        path,
                        row: i + first_row,
                        column: name.clone(),
                        found: col[i].to_string(),
                    });
                }
                let unit = if unit.is_empty() {
                    String::new()
                } else {
                    format!(" {unit}")
                };
                let limit = if limit < 1e4 {
                    format!("{limit}")
                } else {
                    format!("{limit:e}")
                };
                return Err(Error::Implausible {
                    path,
                    row: i + first_row,
                    column: name.clone(),
                    found: col[i],
                    limit: format!("{limit}{unit}"),
                });
            }
        }
        let mut warnings = Vec::new();
        for name in &names {
            if name.is_ascii() {
                continue;
            }
            let spelt: String = name
                .chars()
                .map(|c| ascii_lookalike(c).unwrap_or(c))
                .collect();
            if spelt != *name
                && (KNOWN_NAMES.contains(&spelt.as_str()) || spelt.starts_with("emg_"))
            {
                warnings.push(format!(
                    "column {name:?} is not a recording-format name but looks like {spelt:?} written with non-Latin letters; it is ignored"
                ));
            }
        }
        let time_index =
            names
                .iter()
                .position(|n| n == "t")
                .ok_or_else(|| Error::MissingColumn {
                    path: path.clone(),
                    column: "t".into(),
                    why: "sample time in s".into(),
                    found: names.join(","),
                })?;
        let trial = names
            .iter()
            .position(|n| n == "trial")
            .map(|i| columns[i].as_slice());
        let sample_rate = check_time(&path, &columns[time_index], trial, first_row)?;
        if let Some(unit) = time_unit_hint(sample_rate) {
            warnings.push(format!(
                "column t looks like it is in {unit} (sample rate {} Hz); the recording format (docs/src/format.md) wants seconds",
                crate::display_round(sample_rate)
            ));
        }
        Ok(Recording {
            path,
            names,
            columns,
            time_index,
            sample_rate,
            first_row,
            row_step: 1,
            warnings,
        })
    }

    /// What was accepted but looks wrong (one line each), for the front-ends to show.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Add a warning (readers: what they skipped and why).
    pub fn warn(&mut self, message: impl Into<String>) {
        self.warnings.push(message.into());
    }

    /// Where the recording came from (used in every error message).
    pub fn path(&self) -> &Path {
        &self.path
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.columns[0].len()
    }
    /// True when there is no sample (never, for a checked recording).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Sample rate in Hz, from the median sampling interval.
    pub fn sample_rate(&self) -> f64 {
        self.sample_rate
    }
    /// Sample times in s.
    pub fn t(&self) -> &[f64] {
        &self.columns[self.time_index]
    }
    /// Column names in file order.
    pub fn names(&self) -> &[String] {
        &self.names
    }
    /// Row number of sample `i` in the source file, for messages.
    pub fn row_of(&self, i: usize) -> usize {
        i * self.row_step + self.first_row
    }

    /// Every `step`-th sample from sample `phase`: what a sensor `step` times
    /// slower than the logging measured (issue 58). Row numbers in messages
    /// stay the source's.
    pub fn every(&self, phase: usize, step: usize) -> Result<Recording> {
        let step = step.max(1);
        let columns = self
            .columns
            .iter()
            .map(|c| c.iter().skip(phase).step_by(step).copied().collect())
            .collect();
        let mut kept = Recording::new(&self.path, self.names.clone(), columns, self.row_of(phase))?;
        kept.row_step = self.row_step * step;
        kept.warnings = self.warnings.clone();
        Ok(kept)
    }
    /// A column by name.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| self.columns[i].as_slice())
    }
    /// True when the column exists.
    pub fn has(&self, name: &str) -> bool {
        self.names.iter().any(|n| n == name)
    }
    /// A column that must be there; `why` says what it is needed for.
    pub fn require(&self, name: &str, why: &str) -> Result<&[f64]> {
        self.column(name).ok_or_else(|| Error::MissingColumn {
            path: self.path.clone(),
            column: name.into(),
            why: why.into(),
            found: self.names.join(","),
        })
    }
    /// Replace a column's values (same length), e.g. after a frame change.
    pub fn set_column(&mut self, name: &str, values: Vec<f64>) -> Result<()> {
        if values.len() != self.len() {
            return Err(Error::invalid(
                name,
                format!("expected {} samples, got {}", self.len(), values.len()),
            ));
        }
        match self.names.iter().position(|n| n == name) {
            Some(i) => self.columns[i] = values,
            None => {
                self.names.push(name.into());
                self.columns.push(values);
            }
        }
        Ok(())
    }
    /// All columns, in file order, with their names.
    pub fn columns(&self) -> impl Iterator<Item = (&str, &[f64])> {
        self.names
            .iter()
            .map(String::as_str)
            .zip(self.columns.iter().map(Vec::as_slice))
    }
}

/// Fastest sample rate accepted (Hz): beyond any force or motion sensor.
pub const MAX_SAMPLE_RATE_HZ: f64 = 1e6;

/// Check that `t` is strictly increasing and uniform inside each trial;
/// return the sample rate (Hz). Intervals where the `trial` id changes may be
/// longer (FORMAT.md: recordings may keep only the perturbation windows).
fn check_time(path: &Path, t: &[f64], trial: Option<&[f64]>, first_row: usize) -> Result<f64> {
    if t.len() < 2 {
        return Err(Error::TooFewSamples {
            path: path.to_path_buf(),
            what: "deriving the sample rate".into(),
            needed: 2,
            found: t.len(),
        });
    }
    if let Some(i) = first_in_blocks(1..t.len(), |i| t[i] <= t[i - 1]) {
        return Err(Error::TimeNotIncreasing {
            path: path.to_path_buf(),
            row: i + first_row,
            previous: t[i - 1],
            found: t[i],
        });
    }
    let boundary = |i: usize| trial.is_some_and(|id| id[i] != id[i - 1]);
    let intervals = || {
        (1..t.len())
            .filter(move |&i| !boundary(i))
            .map(|i| t[i] - t[i - 1])
    };
    let Some(median) = median_interval(intervals) else {
        return Err(Error::TooFewSamples {
            path: path.to_path_buf(),
            what: "deriving the sample rate (two samples of one trial)".into(),
            needed: 2,
            found: 1,
        });
    };
    let off_the_clock = |i: usize| {
        let d = t[i] - t[i - 1];
        let gap_allowed = boundary(i) && d > median;
        !gap_allowed && (d - median).abs() > SAMPLING_TOLERANCE * median
    };
    if let Some(i) = first_in_blocks(1..t.len(), off_the_clock) {
        return Err(Error::NonUniformSampling {
            path: path.to_path_buf(),
            row: i + first_row,
            found_s: t[i] - t[i - 1],
            median_s: median,
        });
    }
    let rate = 1.0 / median;
    // a step of 1 ns or 1e-300 s is a unit or scale mistake; downstream it
    // read as a filter with an infinite Nyquist frequency (issue 56)
    if !(rate.is_finite() && rate <= MAX_SAMPLE_RATE_HZ) {
        return Err(Error::Format {
            path: path.to_path_buf(),
            message: format!(
                "column t: implausible sample rate {} Hz (median interval {} s); limpid reads recordings sampled at up to {} Hz: is t in seconds?",
                crate::error::Num(rate),
                crate::error::Num(median),
                crate::error::Num(MAX_SAMPLE_RATE_HZ)
            ),
        });
    }
    Ok(rate)
}

/// The median (the element of rank len/2) of the sampling intervals, `None`
/// when there is none. A clock's intervals take a handful of distinct values
/// (one step and its rounding): counted, they give the median exactly
/// without a copy of the 1.8 M intervals and a selection (issue 82); more
/// than 64 distinct values (a jittered clock) are copied and selected.
fn median_interval<I: Iterator<Item = f64>>(intervals: impl Fn() -> I) -> Option<f64> {
    const MOST_DISTINCT: usize = 64;
    let mut counts: Vec<(u64, usize)> = Vec::with_capacity(MOST_DISTINCT);
    let mut total = 0usize;
    let mut few = true;
    // the value seen last is the likeliest next
    let mut last = 0;
    for d in intervals() {
        total += 1;
        let bits = d.to_bits();
        if counts.get(last).is_some_and(|(b, _)| *b == bits) {
            counts[last].1 += 1;
            continue;
        }
        match counts.iter().position(|(b, _)| *b == bits) {
            Some(k) => {
                counts[k].1 += 1;
                last = k;
            }
            None if counts.len() < MOST_DISTINCT => {
                last = counts.len();
                counts.push((bits, 1));
            }
            None => {
                few = false;
                break;
            }
        }
    }
    if !few {
        let mut dt: Vec<f64> = intervals().collect();
        let mid = dt.len() / 2;
        return Some(*dt.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1);
    }
    let mut below = 0;
    counts.sort_by(|a, b| f64::from_bits(a.0).total_cmp(&f64::from_bits(b.0)));
    counts.into_iter().find_map(|(bits, c)| {
        below += c;
        (below > total / 2).then(|| f64::from_bits(bits))
    })
}

/// The first index of `range` where `bad` holds. Blocks of 1 024 are tested
/// without branches first (they vectorise; an early-exit loop over 1.8 M
/// samples does not), then the first bad block is searched (issue 82).
fn first_in_blocks(range: std::ops::Range<usize>, bad: impl Fn(usize) -> bool) -> Option<usize> {
    const BLOCK: usize = 1024;
    let mut start = range.start;
    while start < range.end {
        let end = (start + BLOCK).min(range.end);
        if (start..end).fold(false, |any, i| any | bad(i)) {
            return (start..end).find(|&i| bad(i));
        }
        start = end;
    }
    None
}

/// Each column's first sample out of its range ([`first_out_of_range`]).
/// A long recording's columns are checked on two threads of their own,
/// when rayon would use more than one (not rayon's pool: a recording is
/// also made where that pool may not be used, and a forked Python child
/// inherits it without its threads and waits for ever).
fn out_of_range_columns(names: &[String], columns: &[Vec<f64>]) -> Vec<Option<usize>> {
    let check =
        |(name, col): (&String, &Vec<f64>)| first_out_of_range(col, magnitude_limit(name).0);
    let samples: usize = columns.iter().map(Vec::len).sum();
    if samples < 1 << 20 || columns.len() < 2 || rayon::current_num_threads() < 2 {
        return names.iter().zip(columns).map(check).collect();
    }
    let half = columns.len() / 2;
    std::thread::scope(|scope| {
        let second = scope.spawn(|| {
            names[half..]
                .iter()
                .zip(&columns[half..])
                .map(check)
                .collect::<Vec<_>>()
        });
        let mut found: Vec<Option<usize>> = names[..half]
            .iter()
            .zip(&columns[..half])
            .map(check)
            .collect();
        match second.join() {
            Ok(rest) => found.extend(rest),
            // (a panic there cannot happen: a comparison of numbers)
            Err(_) => found.extend(names[half..].iter().zip(&columns[half..]).map(check)),
        }
        found
    })
}

/// The first sample of `col` that is not finite or exceeds `limit` in
/// magnitude. Blocks are checked without branches first (they vectorise;
/// the early-exit loop over every sample did not, issue 82).
fn first_out_of_range(col: &[f64], limit: f64) -> Option<usize> {
    const BLOCK: usize = 1024;
    // NaN compares false: not within holds for NaN, ±inf and too large
    let within = |v: &f64| v.abs() <= limit;
    col.chunks(BLOCK).enumerate().find_map(|(b, block)| {
        let all = block.iter().fold(true, |ok, v| ok & within(v));
        (!all).then(|| b * BLOCK + block.iter().position(|v| !within(v)).unwrap_or(0))
    })
}

/// "milliseconds" or "microseconds" when the sample rate in s would be below
/// 2 Hz (no impedance recording is sampled so slowly) but sensible in that unit.
fn time_unit_hint(rate: f64) -> Option<&'static str> {
    let dt = 1.0 / rate;
    if rate >= 2.0 {
        None
    } else if dt < 500.0 {
        Some("milliseconds")
    } else if dt < 5e5 {
        Some("microseconds")
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(t: Vec<f64>) -> Result<Recording> {
        let n = t.len();
        Recording::new(
            "r.csv",
            vec!["t".into(), "x".into()],
            vec![t, vec![0.0; n]],
            2,
        )
    }

    #[test]
    fn median_interval_counts_or_selects_the_same_rank() {
        let by_sorting = |v: &[f64]| {
            let mut s = v.to_vec();
            s.sort_by(f64::total_cmp);
            s[s.len() / 2]
        };
        // few distinct values (counted), in every order, odd and even counts
        let few: Vec<f64> = (0..1001)
            .map(|i| [0.002, 0.0020000001, 0.0019999999][i % 7 % 3])
            .collect();
        for v in [&few[..], &few[..1000], &few[..2]] {
            assert_eq!(median_interval(|| v.iter().copied()), Some(by_sorting(v)));
        }
        // many distinct values (selected)
        let many: Vec<f64> = (0..999)
            .map(|i| 0.001 + ((i * 7919) % 1000) as f64 * 1e-9)
            .collect();
        assert_eq!(
            median_interval(|| many.iter().copied()),
            Some(by_sorting(&many))
        );
        assert_eq!(median_interval(std::iter::empty), None);
    }

    #[test]
    fn first_out_of_range_names_the_first_bad_sample() {
        let mut col = vec![1.0; 5000];
        assert_eq!(first_out_of_range(&col, 10.0), None);
        col[3000] = 11.0;
        col[4000] = f64::NAN;
        assert_eq!(first_out_of_range(&col, 10.0), Some(3000));
        col[2047] = f64::NEG_INFINITY;
        assert_eq!(first_out_of_range(&col, 10.0), Some(2047));
        assert_eq!(first_out_of_range(&[f64::NAN], 1e300), Some(0));
    }

    #[test]
    fn sample_rate_from_median_interval() {
        let t: Vec<f64> = (0..100).map(|i| i as f64 * 0.002).collect();
        let r = rec(t).unwrap();
        assert!((r.sample_rate() - 500.0).abs() < 1e-9);
    }

    #[test]
    fn time_going_back_names_row() {
        let e = rec(vec![0.0, 0.001, 0.002, 0.0015]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "r.csv: row 5, column t: time must be strictly increasing, found 0.0015 after 0.002"
        );
    }

    #[test]
    fn jitter_over_one_percent_is_refused() {
        let mut t: Vec<f64> = (0..10).map(|i| i as f64 * 0.001).collect();
        t[6] += 0.00002; // 2 % of an interval
        let e = rec(t).unwrap_err();
        assert!(
            e.to_string()
                .contains("row 8, column t: non-uniform sampling"),
            "{e}"
        );
    }
}
