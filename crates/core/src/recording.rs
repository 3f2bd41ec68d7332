//! `Recording`: one table of uniformly sampled time series (FORMAT.md v1).
//!
//! The whole table is checked once, when it is built: unique column names,
//! finite values, a `t` column that is strictly increasing and uniform to
//! within 1 %. Everything downstream can then trust it.

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
        for (i, name) in names.iter().enumerate() {
            if let Some(j) = names[..i].iter().position(|n| n == name) {
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
        for (name, col) in names.iter().zip(&columns) {
            if col.len() != n {
                return Err(Error::Format {
                    path,
                    message: format!(
                        "column {name} has {} samples, column {} has {n}",
                        col.len(),
                        names[0]
                    ),
                });
            }
            if let Some(i) = col.iter().position(|v| !v.is_finite()) {
                return Err(Error::NotFinite {
                    path,
                    row: i + first_row,
                    column: name.clone(),
                    found: col[i].to_string(),
                });
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
        let sample_rate = check_time(&path, &columns[time_index], first_row)?;
        Ok(Recording {
            path,
            names,
            columns,
            time_index,
            sample_rate,
            first_row,
        })
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
        i + self.first_row
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

/// Check that `t` is strictly increasing and uniform; return the sample rate (Hz).
fn check_time(path: &Path, t: &[f64], first_row: usize) -> Result<f64> {
    if t.len() < 2 {
        return Err(Error::TooFewSamples {
            path: path.to_path_buf(),
            what: "deriving the sample rate".into(),
            needed: 2,
            found: t.len(),
        });
    }
    for i in 1..t.len() {
        if t[i] <= t[i - 1] {
            return Err(Error::TimeNotIncreasing {
                path: path.to_path_buf(),
                row: i + first_row,
                previous: t[i - 1],
                found: t[i],
            });
        }
    }
    let mut dt: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let mid = dt.len() / 2;
    let median = *dt.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1;
    for i in 1..t.len() {
        let d = t[i] - t[i - 1];
        if (d - median).abs() > SAMPLING_TOLERANCE * median {
            return Err(Error::NonUniformSampling {
                path: path.to_path_buf(),
                row: i + first_row,
                found_s: d,
                median_s: median,
            });
        }
    }
    Ok(1.0 / median)
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
