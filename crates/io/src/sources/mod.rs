//! Lab files as they come off a rig: one or more *streams*, each a set of
//! named channels on its own clock, plus text markers (issue 40).
//!
//! A [`Source`] is what a reader found in a file, before any renaming, unit
//! conversion or alignment; [`crate::map::ChannelMap`] turns it into a
//! FORMAT.md [`limpid_core::Recording`]. Tables (CSV, Parquet, MAT) are one
//! stream without time stamps; XDF files have one stream per LSL outlet with
//! clock-corrected stamps.

use std::path::{Path, PathBuf};

use limpid_core::{Error, Result};

pub mod c3d;
mod cursor;
pub mod mat73;
pub mod ros2;
pub mod tdms;
pub mod xdf;

/// Everything a reader found in one file.
#[derive(Debug, Clone)]
pub struct Source {
    /// The file.
    pub path: PathBuf,
    /// Its format, as a user names it (`XDF`, `CSV`, ...).
    pub format: &'static str,
    /// Its streams, in file order.
    pub streams: Vec<Stream>,
    /// What the reader noticed and the user should know (one line each).
    pub notes: Vec<String>,
    /// Variables present but not read as channels (a matrix, a cell, an
    /// empty array), each with why: a map that names one is told its shape.
    pub unread: Vec<(String, String)>,
    /// Real scalars by path (a MAT file's sample increment), for a map's
    /// `[time] increment`.
    pub scalars: Vec<(String, f64)>,
}

/// One stream: channels sampled together on one clock.
#[derive(Debug, Clone, Default)]
pub struct Stream {
    /// The stream's name (XDF `<name>`, TDMS group, C3D `analog`/`points`;
    /// empty for a table).
    pub name: String,
    /// Its declared content type (XDF `<type>`), if any.
    pub kind: Option<String>,
    /// Its declared sample rate (Hz); `None` for irregular or unknown.
    pub nominal_rate: Option<f64>,
    /// Time of each sample (s), clock-corrected; `None` when the file gives
    /// no time base (a table: its time is one of its channels).
    pub stamps: Option<Vec<f64>>,
    /// Numeric channels, each with one value per sample.
    pub channels: Vec<Channel>,
    /// Text samples of a string-valued stream, in time order.
    pub markers: Vec<Marker>,
    /// How many clock-offset records were applied to the stamps.
    pub clock_offsets: usize,
    /// Where the stamps come from when the file offers a choice (a bag's
    /// `header stamps` or `log time`).
    pub clock: Option<String>,
    /// The other clock's stamps (a bag topic's log times beside its header
    /// stamps), for a map's `clock = "log"`.
    pub log_stamps: Option<Vec<f64>>,
    /// Other names of channels (`position[0]` for `position[ankle]`), with
    /// the channel's index.
    pub aliases: Vec<(String, usize)>,
}

/// One numeric channel.
#[derive(Debug, Clone)]
pub struct Channel {
    /// Its name in the file.
    pub name: String,
    /// The unit the file declares for it, if any.
    pub unit: Option<String>,
    /// Its samples, as stored (no unit conversion).
    pub values: Vec<f64>,
}

/// One text sample of a marker stream.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// Its time (s, on the same clock as the numeric streams' stamps).
    pub time: f64,
    /// Its text.
    pub text: String,
}

impl Stream {
    /// Number of samples (numeric or text).
    pub fn len(&self) -> usize {
        self.stamps
            .as_ref()
            .map(Vec::len)
            .or_else(|| self.channels.first().map(|c| c.values.len()))
            .unwrap_or(self.markers.len())
    }

    /// True without any sample.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The stream as a user names it in messages.
    pub fn label(&self) -> String {
        if self.name.is_empty() {
            "the table".into()
        } else {
            format!("stream {:?}", self.name)
        }
    }

    /// Gaps in the stamps: (sample index after the gap, gap length in s)
    /// where an interval exceeds 1.5 nominal intervals (the median interval
    /// when no rate is declared).
    pub fn gaps(&self) -> Vec<(usize, f64)> {
        let Some(stamps) = &self.stamps else {
            return Vec::new();
        };
        let Some(step) = self.interval() else {
            return Vec::new();
        };
        stamps
            .windows(2)
            .enumerate()
            .filter(|(_, w)| w[1] - w[0] > 1.5 * step)
            .map(|(i, w)| (i + 1, w[1] - w[0]))
            .collect()
    }

    /// The sampling interval (s): 1 / nominal rate, else the median interval.
    pub fn interval(&self) -> Option<f64> {
        if let Some(rate) = self.nominal_rate.filter(|r| *r > 0.0) {
            return Some(1.0 / rate);
        }
        let stamps = self.stamps.as_ref()?;
        if stamps.len() < 2 {
            return None;
        }
        let mut d: Vec<f64> = stamps.windows(2).map(|w| w[1] - w[0]).collect();
        let mid = d.len() / 2;
        let (_, m, _) = d.select_nth_unstable_by(mid, f64::total_cmp);
        (*m > 0.0).then_some(*m)
    }
}

/// True when the path names a file that [`read_source`] reads as a
/// multi-stream lab file (not a FORMAT.md table).
pub fn is_lab_file(path: &Path) -> bool {
    matches!(
        extension(path).as_deref(),
        Some("xdf" | "c3d" | "tdms" | "mcap" | "db3")
    ) || is_bag_folder(path)
}

/// True for a folder that holds a rosbag2 bag (its `metadata.yaml`, or
/// `.mcap`/`.db3` files).
pub fn is_bag_folder(path: &Path) -> bool {
    path.is_dir()
        && (path.join("metadata.yaml").is_file()
            || std::fs::read_dir(path).is_ok_and(|entries| {
                entries
                    .flatten()
                    .any(|e| matches!(extension(&e.path()).as_deref(), Some("mcap" | "db3")))
            }))
}

fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

/// Read any file limpid knows as a [`Source`], choosing the reader by
/// extension: `.xdf` (Lab Streaming Layer), `.c3d` (motion capture), `.tdms` (LabVIEW),
/// `.mcap`, `.db3` or a rosbag2 folder (ROS 2 bags), else a table (CSV, Parquet, MAT)
/// as one stream without stamps.
pub fn read_source(path: &Path) -> Result<Source> {
    if is_bag_folder(path) {
        return ros2::read(path);
    }
    match extension(path).as_deref() {
        Some("mcap" | "db3") => ros2::read(path),
        Some("xdf") => xdf::read(path),
        Some("c3d") => c3d::read(path),
        Some("tdms") => tdms::read(path),
        Some("mat") => {
            let bytes = limpid_core::files::read_bytes(path, crate::MAX_MAT_BYTES)?;
            if is_mat73(&bytes) {
                mat73::read_bytes(path, &bytes)
            } else {
                crate::read_mat_source(path, &bytes)
            }
        }
        _ => {
            let table = crate::read_table(path)?;
            Ok(Source::from_table(path, table))
        }
    }
}

/// One variable or struct field of a MAT-file, by dotted path.
pub struct Found {
    /// `rec.force.fx`.
    pub path: String,
    /// Its values when it is a real numeric vector.
    pub values: Option<Vec<f64>>,
    /// Why it is not a channel otherwise.
    pub why_not: Option<String>,
    /// Its value when it is a real scalar.
    pub scalar: Option<f64>,
    /// How it is listed in the notes when it is not a channel.
    pub listing: Listing,
    /// Text events at times (s): a timetable's text variable, read as a
    /// marker stream named by the path.
    pub events: Vec<(f64, String)>,
}

/// How a variable that is not a channel appears in the notes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Listing {
    /// In the note of variables not read.
    #[default]
    Unread,
    /// A MATLAB object: a note of its own (class and properties).
    Object,
    /// A property of an object already described: not listed again.
    Quiet,
}

/// A MAT-file's vectors as one stream: those of the most common length;
/// the rest listed in a note.
pub fn vectors_source(path: &Path, format: &'static str, found: Vec<Found>) -> Result<Source> {
    let mut lengths: Vec<(usize, usize)> = Vec::new();
    for f in &found {
        if let Some(v) = &f.values {
            match lengths.iter_mut().find(|(n, _)| *n == v.len()) {
                Some(slot) => slot.1 += 1,
                None => lengths.push((v.len(), 1)),
            }
        }
    }
    // a file of MATLAB objects without any vector is still listed (inspect)
    let objects_only = lengths.is_empty() && found.iter().any(|f| f.listing == Listing::Object);
    let chosen = lengths
        .iter()
        .max_by_key(|(n, count)| (*count, *n))
        .map(|l| l.0)
        .or(objects_only.then_some(0));
    let Some(length) = chosen else {
        let listed: Vec<&str> = found
            .iter()
            .filter_map(|f| f.why_not.as_deref())
            .take(10)
            .collect();
        return Err(Error::Format {
            path: path.to_path_buf(),
            message: format!(
                "no numeric vector to read as a channel (found: {})",
                if listed.is_empty() {
                    "nothing".to_string()
                } else {
                    listed.join("; ")
                }
            ),
        });
    };
    let mut skipped = Vec::new();
    let mut unread = Vec::new();
    let mut channels = Vec::new();
    let mut scalars = Vec::new();
    let mut objects = Vec::new();
    let mut marker_streams = Vec::new();
    for f in found {
        if !f.events.is_empty() {
            marker_streams.push(Stream {
                name: f.path.clone(),
                kind: Some("markers".into()),
                stamps: Some(f.events.iter().map(|e| e.0).collect()),
                markers: f
                    .events
                    .into_iter()
                    .map(|(time, text)| Marker { time, text })
                    .collect(),
                ..Stream::default()
            });
            continue;
        }
        if let Some(v) = f.scalar {
            scalars.push((f.path.clone(), v));
        }
        match f.values {
            Some(values) if values.len() == length => channels.push(Channel {
                name: f.path,
                unit: None,
                values,
            }),
            Some(values) => {
                let why = format!("{} ({} samples, not {length})", f.path, values.len());
                unread.push((f.path, why.clone()));
                if f.listing != Listing::Quiet {
                    skipped.push(why);
                }
            }
            None => {
                let why = f.why_not.unwrap_or_else(|| f.path.clone());
                unread.push((f.path, why.clone()));
                match f.listing {
                    Listing::Unread => skipped.push(why),
                    Listing::Object => objects.push(format!("MATLAB object {why}")),
                    Listing::Quiet => {}
                }
            }
        }
    }
    let mut notes = objects;
    if !skipped.is_empty() {
        notes.push(format!(
            "MAT variables not read as channels: {}",
            skipped.join("; ")
        ));
    }
    Ok(Source {
        path: path.to_path_buf(),
        format,
        streams: std::iter::once(Stream {
            channels,
            ..Stream::default()
        })
        .chain(marker_streams)
        .collect(),
        notes,
        unread,
        scalars,
    })
}

/// An error with the reader's notes appended (why its objects were not
/// read, when that left nothing to read).
pub(crate) fn with_notes(e: Error, notes: &[String]) -> Error {
    match e {
        Error::Format { path, message } if !notes.is_empty() => Error::Format {
            path,
            message: format!("{message}; {}", notes.join("; ")),
        },
        other => other,
    }
}

/// True for a MATLAB `-v7.3` (HDF5) MAT-file's bytes.
pub fn is_mat73(bytes: &[u8]) -> bool {
    // some writers (mat-io) keep the v5 header text before the HDF5 part
    bytes.starts_with(b"MATLAB 7.3 MAT-file")
        || (bytes.starts_with(b"MATLAB ") && bytes.get(512..520) == Some(b"\x89HDF\r\n\x1a\n"))
}

/// [`read_source`] for a lab file held in memory (the fuzzer's entry).
pub fn read_source_bytes(path: &Path, bytes: &[u8]) -> Result<Source> {
    match extension(path).as_deref() {
        Some("c3d") => c3d::read_bytes(path, bytes),
        Some("tdms") => tdms::read_bytes(path, bytes),
        Some("mcap" | "db3") => ros2::read_bytes(path, bytes),
        Some("mat") if is_mat73(bytes) => mat73::read_bytes(path, bytes),
        Some("mat") => crate::read_mat_source(path, bytes),
        _ => xdf::read_bytes(path, bytes),
    }
}

/// A lab file of 0 bytes, named by its format (a CSV's "expected a header
/// row" would mislead; issue 56).
pub(crate) fn empty_lab_file(path: &Path, format: &str) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        message: format!("the file is empty (0 bytes): no {format} content"),
    }
}

/// The start every reader shares: an empty file and a file without the
/// format's `magic` bytes are refused, naming the format.
pub(crate) fn check_start(path: &Path, bytes: &[u8], magic: &[u8], format: &str) -> Result<()> {
    if bytes.is_empty() {
        return Err(empty_lab_file(
            path,
            format.trim_start_matches("an ").trim_start_matches("a "),
        ));
    }
    if !bytes.starts_with(magic) {
        return Err(Error::Format {
            path: path.to_path_buf(),
            message: format!(
                "not {format} file: it does not start with {:?}",
                String::from_utf8_lossy(magic)
            ),
        });
    }
    Ok(())
}

/// The error of a reader: `path` and a message.
pub(crate) fn format_error(path: &Path) -> impl Fn(String) -> Error + Copy + '_ {
    move |message| Error::Format {
        path: path.to_path_buf(),
        message,
    }
}

impl Source {
    /// A table as a source of one stream without stamps.
    pub fn from_table(path: &Path, table: crate::Table) -> Source {
        let format = if crate::is_parquet(path) {
            "Parquet"
        } else if crate::is_mat(path) {
            "MAT"
        } else {
            "CSV"
        };
        let channels = table
            .names
            .into_iter()
            .zip(table.columns)
            .map(|(name, values)| Channel {
                name,
                unit: None,
                values,
            })
            .collect();
        Source {
            path: path.to_path_buf(),
            format,
            streams: vec![Stream {
                channels,
                ..Stream::default()
            }],
            notes: table.warnings,
            unread: Vec::new(),
            scalars: Vec::new(),
        }
    }

    /// An error about this file.
    pub fn error(&self, message: impl Into<String>) -> Error {
        Error::Format {
            path: self.path.clone(),
            message: message.into(),
        }
    }
}
