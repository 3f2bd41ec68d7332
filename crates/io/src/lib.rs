//! limpid-io: recordings from and to files (FORMAT.md v1).
//!
//! CSV with a header row, or Parquet with the same column names; the format
//! is chosen by the file extension (`.parquet`/`.pq` for Parquet, `.mat` for
//! MATLAB, anything else is read as CSV). Every value is parsed as `f64`; the
//! table is then checked once by [`Recording::new`]. Errors name file, row and
//! column.
//!
//! MATLAB files (read only): level-5 MAT-files, i.e. MATLAB's `-v6` and
//! default `-v7` (compressed) formats, read by our own bounded decoder
//! (`mat.rs`). Each
//! column is a real numeric vector variable (row or column, any numeric
//! class) named like the column; scalars, matrices, strings, structs and
//! cells are skipped. `-v7.3` files (HDF5) are read the same way, their
//! top-level vectors as columns (`sources::mat73`). In errors, "row" counts
//! samples from 1, as MATLAB indexes them.
//!
//! Lab files (issue 40): XDF, C3D, TDMS and MAT files with structs are read
//! as streams ([`sources`]) and turned into recordings by a channel map
//! ([`map`]); [`inspect`] summarises them. [`read_recording_mapped`] and
//! [`convert`] are the entry points.

#![warn(missing_docs)]

use std::path::Path;

pub mod inspect;
pub mod map;
mod mat;
mod mcos;
pub mod sources;

use limpid_core::{Error, Recording, Result};

mod csv_io;
mod parquet_io;

pub use csv_io::{read_csv, write_csv};
use csv_io::{read_csv_from, read_csv_table};
pub use parquet_io::{read_parquet, write_parquet, MAX_PARQUET_BYTES, MAX_PARQUET_ROWS};
use parquet_io::{read_parquet_source, read_parquet_table, StrictBytes, StrictFile};

/// True when the path names a Parquet file.
pub fn is_parquet(path: &Path) -> bool {
    matches!(
        path.extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref(),
        Some("parquet" | "pq")
    )
}

/// True when the path names a MATLAB MAT-file.
pub fn is_mat(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("mat"))
}

/// Whether `path` is named like a file limpid reads as a recording
/// (CSV/TSV/text, Parquet, MAT, XDF, C3D, TDMS, a ROS 2 bag). `limpid rerun` reads only
/// such files from a result's run block: a hand-edited result naming
/// `/etc/passwd` had its first line echoed in the error (issue 56).
pub fn named_like_a_recording(path: &Path) -> bool {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    matches!(
        ext.as_deref(),
        Some(
            "csv"
                | "tsv"
                | "txt"
                | "parquet"
                | "pq"
                | "mat"
                | "xdf"
                | "c3d"
                | "tdms"
                | "mcap"
                | "db3"
        )
    ) || sources::is_bag_folder(path)
}

/// Read a recording, choosing the format by extension.
pub fn read_recording(path: impl AsRef<Path>) -> Result<Recording> {
    let path = path.as_ref();
    if sources::is_lab_file(path) {
        convert(path, None).map(|c| c.recording)
    } else if is_parquet(path) {
        read_parquet(path)
    } else if is_mat(path) {
        read_mat(path).or_else(|e| read_mat_struct(path, e))
    } else {
        read_csv(path)
    }
}

/// A MAT-file without top-level vectors whose struct fields are named like
/// FORMAT.md columns (`rec.t`, `rec.q1`, `rec.tau1`): read through the map
/// that names each column by its field (issue 81). Fields named otherwise
/// get an error that says how to name them; a file without struct fields
/// keeps `vectors_error`.
fn read_mat_struct(path: &Path, vectors_error: Error) -> Result<Recording> {
    let Ok(source) = sources::read_source(path) else {
        return Err(vectors_error);
    };
    let fields: Vec<&str> = source
        .streams
        .iter()
        .flat_map(|s| &s.channels)
        .map(|c| c.name.as_str())
        .filter(|n| n.contains('.'))
        .collect();
    if fields.is_empty() {
        return Err(vectors_error);
    }
    let mut columns: Vec<(String, String)> = Vec::new();
    for field in &fields {
        let leaf = field.rsplit('.').next().unwrap_or(field);
        if !limpid_core::recording::is_format_column(leaf) {
            continue;
        }
        // two structs with the same field names (rec1.t, rec2.t): which is
        // the recording is the user's to say, never the first one silently
        if let Some((_, other)) = columns.iter().find(|(c, _)| c == leaf) {
            return Err(Error::Format {
                path: path.to_path_buf(),
                message: format!(
                    "fields {other} and {field} could both be column {leaf}: name the columns with --column {leaf}={other} ... (Python: columns={{'{leaf}': '{other}', ...}}), or save a channel map with `limpid inspect {} --map-template > rig.toml`",
                    path.display()
                ),
            });
        }
        columns.push((leaf.to_string(), field.to_string()));
    }
    if columns.is_empty() {
        let shown: Vec<&str> = fields.iter().take(4).copied().collect();
        return Err(Error::Format {
            path: path.to_path_buf(),
            message: format!(
                "its columns are struct fields ({}{}) not named like FORMAT.md columns: name them with --column t={} --column q1=... (Python: columns={{'t': '{}', ...}}), or save a channel map with `limpid inspect {} --map-template > rig.toml` and pass --map rig.toml",
                shown.join(", "),
                if fields.len() > shown.len() { ", ..." } else { "" },
                shown[0],
                shown[0],
                path.display()
            ),
        });
    }
    let map = map::ChannelMap {
        time: map::TimeSpec::default(),
        columns: columns
            .into_iter()
            .map(|(c, f)| (c, map::ColumnSpec::Channel(f)))
            .collect(),
        streams: Default::default(),
        path: None,
    };
    Ok(map::apply(&source, &map)?.recording)
}

/// Read a recording through a channel map, or as [`read_recording`] does
/// without one. Lab files (XDF) without a map get [`map::ChannelMap::implicit`].
pub fn read_recording_mapped(
    path: impl AsRef<Path>,
    map: Option<&map::ChannelMap>,
) -> Result<Recording> {
    Ok(convert(path, map)?.recording)
}

/// A recording through a channel map, with what the conversion did.
pub fn convert(path: impl AsRef<Path>, map: Option<&map::ChannelMap>) -> Result<map::Converted> {
    let path = path.as_ref();
    match map {
        Some(map) => map::apply(&sources::read_source(path)?, map),
        None if sources::is_lab_file(path) => {
            let source = sources::read_source(path)?;
            map::apply(&source, &map::ChannelMap::implicit(&source)?)
        }
        None => Ok(map::Converted {
            recording: read_recording(path)?,
            notes: Vec::new(),
        }),
    }
}

/// `NAME=CHANNEL` pairs (`--column t=time_s`), checked: a usable FORMAT.md
/// or free column name, a non-empty channel, each name once.
pub fn parse_columns(pairs: &[String]) -> Result<Vec<(String, String)>> {
    let mut out: Vec<(String, String)> = Vec::new();
    for pair in pairs {
        let bad = |why: &str| Error::InvalidParameter {
            name: "--column".into(),
            message: format!("{pair:?}: {why}"),
        };
        let (name, channel) = pair
            .split_once('=')
            .ok_or_else(|| bad("expected NAME=CHANNEL, e.g. --column t=time_s"))?;
        let (name, channel) = (name.trim(), channel.trim());
        if name.is_empty() || channel.is_empty() {
            return Err(bad("expected NAME=CHANNEL, e.g. --column t=time_s"));
        }
        if out.iter().any(|(n, _)| n == name) {
            return Err(bad(&format!("column {name} is named twice")));
        }
        out.push((name.to_string(), channel.to_string()));
    }
    Ok(out)
}

/// A recording with some of its columns named on the command line
/// (`--column NAME=CHANNEL`, [`map::ChannelMap::with_columns`]), through
/// `map` when one is given; as [`convert`] without columns.
pub fn convert_with_columns(
    path: impl AsRef<Path>,
    map: Option<&map::ChannelMap>,
    columns: &[(String, String)],
) -> Result<map::Converted> {
    if columns.is_empty() {
        return convert(path, map);
    }
    let source = sources::read_source(path.as_ref())?;
    let map = map::ChannelMap::with_columns(map, &source, columns)?;
    map::apply(&source, &map)
}

/// [`read_recording_mapped`] for a file beside the main recording (an MVC
/// recording, calibration poses): with a map, columns the file does not
/// record are left out ([`map::apply_partial`]).
pub fn read_supporting_recording(
    path: impl AsRef<Path>,
    map: Option<&map::ChannelMap>,
) -> Result<Recording> {
    let path = path.as_ref();
    match map {
        Some(map) => Ok(map::apply_partial(&sources::read_source(path)?, map)?.recording),
        None => read_recording_mapped(path, None),
    }
}

/// Read a recording held in memory; `path` names it in errors and picks the
/// format by its extension, as [`read_recording`] does (used by the fuzzer).
pub fn read_recording_bytes(path: impl AsRef<Path>, bytes: Vec<u8>) -> Result<Recording> {
    let path = path.as_ref();
    if bytes.is_empty() {
        return Err(Error::Empty {
            path: path.to_path_buf(),
        });
    }
    if sources::is_lab_file(path) {
        let source = sources::read_source_bytes(path, &bytes)?;
        map::apply(&source, &map::ChannelMap::implicit(&source)?).map(|c| c.recording)
    } else if is_parquet(path) {
        let data = StrictBytes(bytes::Bytes::from(bytes));
        limpid_core::error::catch_panic(
            path,
            "Parquet decoder (corrupt or unsupported file)",
            || read_parquet_source(path, data),
        )
    } else if is_mat(path) {
        read_mat_bytes(path, &bytes)
    } else {
        read_csv_from(path, bytes.as_slice())
    }
}

/// A table as read, before the checks of [`Recording::new`]: named numeric
/// columns of one length, and what the reader noticed.
#[derive(Debug, Clone)]
pub struct Table {
    /// Column names, in file order.
    pub names: Vec<String>,
    /// Column values, as stored.
    pub columns: Vec<Vec<f64>>,
    /// Row number of the first sample in the file (2 for CSV, whose header is row 1).
    pub first_row: usize,
    /// What was accepted but skipped or converted.
    pub warnings: Vec<String>,
}

impl Table {
    /// Check the table as a FORMAT.md recording.
    pub fn into_recording(self, path: &Path) -> Result<Recording> {
        let mut rec = Recording::new(path, self.names, self.columns, self.first_row)?;
        for w in self.warnings {
            rec.warn(w);
        }
        Ok(rec)
    }
}

/// Read a CSV, Parquet or MAT file as a table (by extension), without the
/// FORMAT.md checks: what a channel map reads.
pub fn read_table(path: &Path) -> Result<Table> {
    if is_parquet(path) {
        #[cfg(unix)]
        {
            let file = StrictFile::open(path)?;
            limpid_core::error::catch_panic(
                path,
                "Parquet decoder (corrupt or unsupported file)",
                || read_parquet_table(path, file),
            )
        }
        #[cfg(not(unix))]
        {
            let bytes = limpid_core::files::read_bytes(path, MAX_PARQUET_BYTES)?;
            read_parquet_table(path, StrictBytes(bytes::Bytes::from(bytes)))
        }
    } else if is_mat(path) {
        let bytes = limpid_core::files::read_bytes(path, MAX_MAT_BYTES)?;
        if bytes.is_empty() {
            return Err(Error::Empty {
                path: path.to_path_buf(),
            });
        }
        read_mat_table(path, &bytes)
    } else {
        let file = limpid_core::files::open_input(path)?;
        if file.metadata().map_err(io_err(path))?.len() == 0 {
            return Err(Error::Empty {
                path: path.to_path_buf(),
            });
        }
        read_csv_table(path, file)
    }
}

/// Write a recording, choosing the format by extension (CSV or Parquet).
pub fn write_recording(rec: &Recording, path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    if is_parquet(path) {
        write_parquet(rec, path)
    } else if is_mat(path) {
        Err(Error::Format {
            path: path.to_path_buf(),
            message: "limpid reads MAT-files but does not write them; write .csv or .parquet (MATLAB reads both: readtable, parquetread)".into(),
        })
    } else if let Some(ext) = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .filter(|e| !matches!(e.as_str(), "csv" | "txt"))
    {
        // issue 56: `-o x.xdf` wrote CSV under an XDF name
        Err(Error::Format {
            path: path.to_path_buf(),
            message: format!(
                "limpid writes recordings as .csv or .parquet, not .{ext}; name the output with one of those"
            ),
        })
    } else {
        write_csv(rec, path)
    }
}

/// Largest MAT-file read (bytes).
pub const MAX_MAT_BYTES: u64 = 4 << 30;

/// Read a MATLAB level-5 MAT-file: one real numeric vector per column.
///
/// A variable named like a FORMAT.md column that is not a real numeric vector
/// (a struct, cell, string, matrix or complex array called `x`) is refused;
/// other variables that are not vectors are skipped with a warning.
pub fn read_mat(path: &Path) -> Result<Recording> {
    let bytes = limpid_core::files::read_bytes(path, MAX_MAT_BYTES)?;
    read_mat_bytes(path, &bytes)
}

/// [`read_mat`] on the file's bytes.
fn read_mat_bytes(path: &Path, bytes: &[u8]) -> Result<Recording> {
    read_mat_table(path, bytes)?.into_recording(path)
}

/// A level-5 MAT-file as a source: numeric vectors by dotted struct path.
pub(crate) fn read_mat_source(path: &Path, bytes: &[u8]) -> Result<sources::Source> {
    if bytes.is_empty() {
        return Err(sources::empty_lab_file(path, "MAT"));
    }
    if !bytes.starts_with(b"MATLAB 5.0 MAT-file") {
        return Err(Error::Format {
            path: path.to_path_buf(),
            message: "not a MAT-file: the header does not start with \"MATLAB 5.0 MAT-file\""
                .into(),
        });
    }
    let vars = mat::variables(bytes).map_err(|message| Error::Format {
        path: path.to_path_buf(),
        message,
    })?;
    let mut notes = Vec::new();
    let vars = mcos::resolve(vars, &bytes[126..128] == b"IM", &mut notes);
    let mut found = Vec::new();
    mat::flatten(vars, "", &mut found);
    let mut source =
        sources::vectors_source(path, "MAT", found).map_err(|e| sources::with_notes(e, &notes))?;
    source.notes.extend(notes);
    Ok(source)
}

/// The numeric vectors of a MAT-file as a table.
pub(crate) fn read_mat_table(path: &Path, bytes: &[u8]) -> Result<Table> {
    if bytes.is_empty() {
        return Err(Error::Empty {
            path: path.to_path_buf(),
        });
    }
    let fail = |message: String| Error::Format {
        path: path.to_path_buf(),
        message,
    };
    let header = String::from_utf8_lossy(&bytes[..bytes.len().min(116)]);
    if sources::is_mat73(bytes) {
        // v7.3: its top-level numeric vectors of one length are the table
        let source = sources::mat73::read_bytes(path, bytes)?;
        let stream = source.streams.into_iter().next().expect("one stream");
        let (names, columns) = stream
            .channels
            .into_iter()
            .filter(|c| !c.name.contains('.'))
            .map(|c| (c.name, c.values))
            .unzip();
        return Ok(Table {
            names,
            columns,
            first_row: 1,
            warnings: source.notes,
        });
    }
    if !header.starts_with("MATLAB 5.0 MAT-file") {
        return Err(fail(
            "not a MAT-file: the header does not start with \"MATLAB 5.0 MAT-file\"".into(),
        ));
    }
    let variables = mat::variables(bytes).map_err(fail)?;
    let (mut names, mut columns, mut skipped) = (Vec::new(), Vec::new(), Vec::new());
    for var in variables {
        let samples: usize = var.dims.iter().product();
        let vector = var.dims.len() == 2 && var.dims.contains(&1) && samples > 1;
        let dims: Vec<String> = var.dims.iter().map(usize::to_string).collect();
        let shape = format!("{} ({}), {}", var.name, dims.join(" x "), var.class);
        if var.complex && vector {
            return Err(fail(format!(
                "variable {}: complex values; a recording holds real numbers",
                var.name
            )));
        }
        match var.real {
            Some(values) if vector => {
                names.push(var.name);
                columns.push(values);
            }
            _ if limpid_core::recording::is_format_column(&var.name) => {
                return Err(fail(format!(
                    "variable {shape}: a column must be a real numeric vector (save each column, e.g. x, as an N x 1 double)"
                )));
            }
            _ => skipped.push(shape),
        }
    }
    if names.is_empty() {
        return Err(fail(format!(
            "no numeric vector variable to read as a column (found {}); save each column (t, x, fx, ...) as a vector",
            if skipped.is_empty() {
                "no numeric variable".to_string()
            } else {
                skipped.join("; ")
            }
        )));
    }
    let mut warnings = Vec::new();
    if !skipped.is_empty() {
        // the reader of the warnings names the file (CLI, Python)
        warnings.push(format!(
            "skipped MAT variables that are not numeric vectors: {}",
            skipped.join("; ")
        ));
    }
    Ok(Table {
        names,
        columns,
        first_row: 1,
        warnings,
    })
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}
