//! The one error type shared by every limpid crate.
//!
//! Messages are lowercase, one line, and say where (file, row, column) and
//! what was expected versus found. Rows are counted as in a spreadsheet or
//! text editor: the header is row 1, the first sample is row 2.

use std::path::PathBuf;

/// Everything that can go wrong between a file on disk and an estimate.
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The file could not be opened or read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not a table of the expected format.
    #[error("{path}: {message}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong, in words.
        message: String,
    },
    /// The file has no content at all.
    #[error("{path}: the file is empty; expected a header row and samples")]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// The file has a header but no sample.
    #[error("{path}: the file has a header row but no samples")]
    HeaderOnly {
        /// The file.
        path: PathBuf,
    },
    /// A column name appears twice in the header.
    #[error(
        "{path}: row 1, column {column}: duplicate column name (columns {first} and {second})"
    )]
    DuplicateColumn {
        /// The file.
        path: PathBuf,
        /// The column's name.
        column: String,
        /// Position of its first occurrence (1-based).
        first: usize,
        /// Position of its second occurrence (1-based).
        second: usize,
    },
    /// A required column is absent.
    #[error("{path}: missing required column {column} ({why}); found columns: {found}")]
    MissingColumn {
        /// The file.
        path: PathBuf,
        /// The column's name.
        column: String,
        /// What the column is needed for.
        why: String,
        /// What was found.
        found: String,
    },
    /// A cell does not hold a number.
    #[error("{path}: row {row}, column {column}: expected a number, found {found:?}")]
    NotANumber {
        /// The file.
        path: PathBuf,
        /// Row, counted as in a spreadsheet (the CSV header is row 1).
        row: usize,
        /// The column's name.
        column: String,
        /// What was found.
        found: String,
    },
    /// A cell holds NaN or an infinity.
    #[error("{path}: row {row}, column {column}: expected a finite number, found {found}")]
    NotFinite {
        /// The file.
        path: PathBuf,
        /// Row, counted as in a spreadsheet (the CSV header is row 1).
        row: usize,
        /// The column's name.
        column: String,
        /// What was found.
        found: String,
    },
    /// A finite value too large for its unit (a corrupt sample, or the wrong unit).
    #[error("{path}: row {row}, column {column}: implausible value {found:e}: limpid accepts magnitudes up to {limit} in this column (SI units, docs/src/format.md)")]
    Implausible {
        /// The file.
        path: PathBuf,
        /// Row, counted as in a spreadsheet (the CSV header is row 1).
        row: usize,
        /// The column's name.
        column: String,
        /// The value found.
        found: f64,
        /// The largest magnitude accepted, with its unit.
        limit: String,
    },
    /// A row has more or fewer cells than the header.
    #[error("{path}: row {row}: expected {expected} cells like the header, found {found}")]
    RaggedRow {
        /// The file.
        path: PathBuf,
        /// Row, counted as in a spreadsheet (the CSV header is row 1).
        row: usize,
        /// Cells expected (those of the header).
        expected: usize,
        /// How many were found.
        found: usize,
    },
    /// Time goes backwards or stands still.
    #[error("{path}: row {row}, column t: time must be strictly increasing, found {found} after {previous}")]
    TimeNotIncreasing {
        /// The file.
        path: PathBuf,
        /// Row, counted as in a spreadsheet (the CSV header is row 1).
        row: usize,
        /// The time of the row before (s).
        previous: f64,
        /// The value found.
        found: f64,
    },
    /// One sampling interval differs from the typical one by more than 1 %.
    #[error("{path}: row {row}, column t: non-uniform sampling, interval {found_s:.6} s differs from the median {median_s:.6} s by more than 1 %")]
    NonUniformSampling {
        /// The file.
        path: PathBuf,
        /// Row, counted as in a spreadsheet (the CSV header is row 1).
        row: usize,
        /// The interval found (s).
        found_s: f64,
        /// The median interval (s).
        median_s: f64,
    },
    /// Not enough samples for what was asked.
    #[error("{path}: {found} samples usable for {what}, but at least {needed} are needed")]
    TooFewSamples {
        /// The file.
        path: PathBuf,
        /// What the samples are for.
        what: String,
        /// How many are needed.
        needed: usize,
        /// How many were found.
        found: usize,
    },
    /// A perturbation starts without a rest period before it.
    #[error("{path}: row {row}, column {column}: trial {trial} has no rest before its perturbation onset (found {rest_samples} rest samples, need {needed}); start each trial at rest")]
    NoRestBeforeOnset {
        /// The file.
        path: PathBuf,
        /// Row, counted as in a spreadsheet (the CSV header is row 1).
        row: usize,
        /// The column's name.
        column: String,
        /// The trial id.
        trial: i64,
        /// Rest samples before the onset.
        rest_samples: usize,
        /// How many are needed.
        needed: usize,
    },
    /// A parameter given by the user is out of range.
    #[error("invalid {name}: {message}")]
    InvalidParameter {
        /// The setting.
        name: String,
        /// What was expected and found.
        message: String,
    },
    /// The numerical problem cannot be solved (e.g. a singular regressor).
    #[error("{path}: {message}")]
    Numerical {
        /// The recording.
        path: PathBuf,
        /// What failed, in words.
        message: String,
    },
}

/// Result with limpid's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A number rounded to 9 decimals for messages (500 Hz, not 499.99999999999955 Hz).
pub fn display_round(v: f64) -> f64 {
    (v * 1e9).round() / 1e9
}

/// Run `f`, turning a panic inside it (a third-party decoder on a corrupt
/// file) into an error naming `path` instead of aborting the process.
pub fn catch_panic<T>(
    path: &std::path::Path,
    what: &str,
    f: impl FnOnce() -> Result<T>,
) -> Result<T> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => Err(Error::Format {
            path: path.to_path_buf(),
            message: format!(
                "the {what} failed unexpectedly ({})",
                panic_message(payload.as_ref()).replace('\n', "; ")
            ),
        }),
    }
}

/// The text of a panic payload.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}

impl Error {
    /// A settings file (TOML, JSON) that does not parse: one line, with the
    /// line and column of `span` (a byte range of `text`) when the parser gives one.
    pub fn settings(
        path: &std::path::Path,
        text: &str,
        span: Option<std::ops::Range<usize>>,
        message: &str,
    ) -> Self {
        let message = message.trim().replace('\n', "; ");
        let message = match span {
            Some(span) => {
                let before = &text[..span.start.min(text.len())];
                let line = before.matches('\n').count() + 1;
                let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
                format!("line {line}, column {column}: {message}")
            }
            None => message,
        };
        Error::Format {
            path: path.to_path_buf(),
            message,
        }
    }

    /// Shorthand for [`Error::InvalidParameter`].
    pub fn invalid(name: impl Into<String>, message: impl Into<String>) -> Self {
        Error::InvalidParameter {
            name: name.into(),
            message: message.into(),
        }
    }
}

/// A number as a short string for people: four decimals without trailing
/// zeros, or three significant decimals in scientific notation outside
/// 1e-3..1e5; a NaN or infinity is written "n/a" (never passed off as a number).
pub fn short_number(v: f64) -> String {
    if !v.is_finite() {
        return "n/a".into();
    }
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    }
}

/// A number in a message (an error, a warning, a note): six significant
/// digits, trailing zeros dropped, an exponent outside 1e-3..1e6 (`1e308`,
/// not 309 digits; `1000 Hz`, not `1000.0000000001102 Hz`); NaN and
/// infinities as `NaN`, `inf`, `-inf` (issue 56: one formatter for every message).
#[derive(Debug, Clone, Copy)]
pub struct Num(pub f64);

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = self.0;
        if v.is_nan() {
            return f.write_str("NaN");
        }
        if v.is_infinite() {
            return f.write_str(if v > 0.0 { "inf" } else { "-inf" });
        }
        if v == 0.0 {
            return f.write_str("0");
        }
        let e = v.abs().log10().floor() as i32;
        if (-3..6).contains(&e) {
            let text = significant(v, 6);
            // rounding may carry to 1e6 (999999.7): that is the exponent form
            if !text.trim_start_matches('-').starts_with("1000000") {
                return f.write_str(&text);
            }
        }
        let text = format!("{v:.5e}");
        let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        write!(f, "{mantissa}e{exponent}")
    }
}

/// A message with every long decimal number in it written as [`Num`]
/// writes numbers (`1e308` for 309 digits, `1000` for
/// `1000.0000000001102`): the last step before a message reaches a person,
/// for numbers formatted without [`Num`] on the way. A number is a run of
/// digits with a point or an exponent, or of more than 15 digits, that is
/// not part of a word or a path (file names keep their digits).
pub fn tidy_numbers(message: &str) -> String {
    let bytes = message.as_bytes();
    let mut out = String::with_capacity(message.len());
    let mut i = 0;
    let mut copied = 0;
    while i < bytes.len() {
        let starts_number = bytes[i].is_ascii_digit()
            && (i == 0 || !is_word_byte(bytes[i - 1]) && bytes[i - 1] != b'.');
        if !starts_number {
            i += 1;
            continue;
        }
        let start = if i > 0 && bytes[i - 1] == b'-' {
            i - 1
        } else {
            i
        };
        let mut end = i;
        while end < bytes.len() && bytes[end].is_ascii_digit() {
            end += 1;
        }
        let mut decimal = false;
        if end + 1 < bytes.len() && bytes[end] == b'.' && bytes[end + 1].is_ascii_digit() {
            decimal = true;
            end += 1;
            while end < bytes.len() && bytes[end].is_ascii_digit() {
                end += 1;
            }
        }
        if end < bytes.len() && (bytes[end] == b'e' || bytes[end] == b'E') {
            let mut e = end + 1;
            if e < bytes.len() && (bytes[e] == b'-' || bytes[e] == b'+') {
                e += 1;
            }
            if e < bytes.len() && bytes[e].is_ascii_digit() {
                while e < bytes.len() && bytes[e].is_ascii_digit() {
                    e += 1;
                }
                decimal = true;
                end = e;
            }
        }
        let in_word = end < bytes.len() && (is_word_byte(bytes[end]) || bytes[end] == b'/');
        let digits = message[i..end].bytes().filter(u8::is_ascii_digit).count();
        let long = (decimal && digits > 10) || digits > 15;
        if !in_word && long {
            if let Ok(v) = message[start..end].parse::<f64>() {
                out.push_str(&message[copied..start]);
                out.push_str(&Num(v).to_string());
                copied = end;
            }
        }
        i = end;
    }
    out.push_str(&message[copied..]);
    out
}

fn is_word_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_' || b == b'/' || b == b'\\'
}

/// A number for CSV output: the shortest text that reads back to the same
/// double, with an exponent below 1e-4 and from 1e15 in magnitude
/// (`1.2895775544584347e-16`, not 32 zeros and digits).
#[derive(Debug, Clone, Copy)]
pub struct CsvNumber(pub f64);

impl std::fmt::Display for CsvNumber {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = self.0;
        let a = v.abs();
        if v == 0.0 || !v.is_finite() || (1e-4..1e15).contains(&a) {
            write!(f, "{v}")
        } else {
            write!(f, "{v:e}")
        }
    }
}

/// `v` to `digits` significant digits (trailing zeros dropped; exponent
/// form below 1e-3 and from 1e6); a non-finite value is "n/a".
pub fn significant(v: f64, digits: usize) -> String {
    if !v.is_finite() {
        return "n/a".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let digits = digits.max(1);
    let e = v.abs().log10().floor() as i32;
    if !(-3..6).contains(&e) {
        return format!("{v:.*e}", digits - 1);
    }
    let decimals = (digits as i32 - 1 - e).max(0) as usize;
    let text = format!("{v:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// A value with its standard error, rounded to the error: two significant
/// digits of the error and the value to the same decimal place
/// (`1001.3895, 1.2655` -> `1001.4 ± 1.3`); a shared power of ten outside
/// 1e-3..1e6. Without a usable error, the value to 4 significant digits.
pub fn with_standard_error(v: f64, se: f64) -> String {
    if !v.is_finite() {
        return "n/a".into();
    }
    if !(se.is_finite() && se > 0.0) {
        return format!("{} ± n/a", significant(v, 4));
    }
    // an error below the value's precision (1e308 ± 1, a subnormal SE) cannot
    // set its decimal place: both as significant digits (issue 36)
    let ratio = v.abs() / se;
    if ratio.is_nan() || ratio >= 1e15 {
        return format!("{} ± {}", significant(v, 4), significant(se, 2));
    }
    // decimal place of the error's second significant digit
    let place = se.log10().floor() as i32 - 1;
    let unit = 10f64.powi(place);
    let (vr, sr) = ((v / unit).round() * unit, (se / unit).round() * unit);
    // a subnormal unit (an SE near 1e-308) is 0 or not, as powi is inlined or
    // not: both take the significant-digits form
    if !(vr.is_finite() && sr.is_finite() && unit.is_normal()) {
        return format!("{} ± {}", significant(v, 4), significant(se, 2));
    }
    let magnitude = vr.abs().max(sr);
    if !(1e-3..1e6).contains(&magnitude) {
        let e = magnitude.log10().floor() as i32;
        let p = 10f64.powi(e);
        let d = (e - place).max(0) as usize;
        return format!("({:.d$} ± {:.d$})e{e}", vr / p, sr / p);
    }
    let d = (-place).max(0) as usize;
    format!("{vr:.d$} ± {sr:.d$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_numbers_in_messages_are_tidied_and_names_kept() {
        let long = format!("found 3, {}", 4.9e-324f64);
        assert_eq!(tidy_numbers(&long), "found 3, 4.94066e-324");
        let huge = format!("cut-off ({} Hz)", 1e308f64);
        assert_eq!(tidy_numbers(&huge), "cut-off (1e308 Hz)");
        assert_eq!(
            tidy_numbers(
                "rate 1000.0000000001102 Hz and 9.999999999998899 ms, -0.30000000000000004"
            ),
            "rate 1000 Hz and 10 ms, -0.3"
        );
        for kept in [
            "rec_20260101123456789.csv: row 2",
            "/data/1234567890123456789/x.csv",
            "found 0.25 and 25600 samples",
            "v1.2.3",
        ] {
            assert_eq!(tidy_numbers(kept), kept);
        }
    }

    #[test]
    fn message_numbers_are_short() {
        for (v, text) in [
            (1e308, "1e308"),
            (4.9e-324, "4.94066e-324"),
            (1000.0000000001102, "1000"),
            (9.999999999998899, "10"),
            (999999.7, "1e6"),
            (-0.25, "-0.25"),
            (1e-300, "1e-300"),
            (123456.789, "123457"),
            (0.0, "0"),
            (f64::NAN, "NaN"),
            (f64::NEG_INFINITY, "-inf"),
        ] {
            assert_eq!(Num(v).to_string(), text, "{v:e}");
        }
    }

    #[test]
    fn csv_numbers_are_short_and_read_back_exactly() {
        for (v, text) in [
            (1.2895775544584347e-16, "1.2895775544584347e-16"),
            (0.25, "0.25"),
            (-3.0, "-3"),
            (0.0, "0"),
            (6.02e23, "6.02e23"),
            (1e-4, "0.0001"),
        ] {
            let s = CsvNumber(v).to_string();
            assert_eq!(s, text);
            assert_eq!(s.parse::<f64>().unwrap(), v);
        }
    }

    #[test]
    fn values_are_rounded_to_their_standard_error() {
        assert_eq!(with_standard_error(1001.3895, 1.2655), "1001.4 ± 1.3");
        assert_eq!(with_standard_error(0.5, 0.0123), "0.500 ± 0.012");
        assert_eq!(with_standard_error(123456.0, 2345.0), "123500 ± 2300");
        assert_eq!(with_standard_error(-12.3456, 0.98), "-12.35 ± 0.98");
        assert_eq!(with_standard_error(2.5e-5, 3.1e-6), "(2.50 ± 0.31)e-5");
        assert_eq!(with_standard_error(3.0e7, 1.2e5), "(3.000 ± 0.012)e7");
        assert_eq!(with_standard_error(7.0, f64::NAN), "7 ± n/a");
        assert_eq!(with_standard_error(f64::NAN, 1.0), "n/a");
        // extremes printed as (NaN ± 0)e2147483647 and (NaN ± NaN)e0 (issue 36)
        assert_eq!(with_standard_error(1e308, 1.0), "1.000e308 ± 1");
        assert_eq!(with_standard_error(1.0, 5e-324), "1 ± 4.9e-324");
        assert_eq!(with_standard_error(1.7e308, 1.5e308), "(1.7 ± 1.5)e308");
        assert_eq!(with_standard_error(5e-320, 3e-320), "5.000e-320 ± 3.0e-320");
        assert_eq!(significant(99.9847, 4), "99.98");
        assert_eq!(significant(0.5, 4), "0.5");
        assert_eq!(significant(1001.3895, 4), "1001");
        assert_eq!(significant(0.00012895775, 4), "1.290e-4");
        assert_eq!(significant(-0.0, 4), "0");
    }

    #[test]
    fn settings_errors_give_line_and_column_of_the_span() {
        let text = "a = 1\nb = [1,\n  2, x]\n";
        let at = text.find('x').unwrap();
        let e = Error::settings(
            std::path::Path::new("p.toml"),
            text,
            Some(at..at + 1),
            "invalid array\nexpected `]`",
        );
        assert_eq!(
            e.to_string(),
            "p.toml: line 3, column 6: invalid array; expected `]`"
        );
        let e = Error::settings(
            std::path::Path::new("p.toml"),
            text,
            None,
            "missing field `b`",
        );
        assert_eq!(e.to_string(), "p.toml: missing field `b`");
    }
}
