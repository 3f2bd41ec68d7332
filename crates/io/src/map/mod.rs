//! Channel maps: a rig's file (any stream, channel names, units and signs)
//! turned into a FORMAT.md recording (issue 40).
//!
//! A map is TOML, written once per rig:
//!
//! ```toml
//! [time]
//! stream = "robot"          # the stream whose stamps are the recording's t
//! # rate = 1000 (Hz), or increment = "z.domainIncr" (a scalar in the file, s),
//! # for a table without a time column
//! [columns]
//! x  = { channel = "EndEff.X", unit = "mm" }
//! fx = { channel = "Force.Fx", unit = "N", scale = -1.0 }
//! emg_biceps = { channel = "EMG1", stream = "emg", unit = "mV" }
//! trial = { marker = "perturbation_start" }
//! level = { marker_prefix = "level=" }
//! [streams."/wrench"]       # optional, per stream
//! clock = "log"             # a bag topic's log times instead of its header stamps
//! dejitter = true           # stamps replaced by a straight-line fit (pyxdf's option)
//! ```
//!
//! value = convert(raw, unit) x scale + offset (offset in SI). The unit
//! defaults to the one the file declares for the channel, else SI. Channels
//! of other streams are interpolated linearly, as raw samples, onto the
//! time-base stream's stamps; the table is cut to the span every stream
//! covers; gaps are reported. A `marker` rule numbers trials 1, 2, ... at
//! each marker of exactly that text; a `marker_prefix` rule sets a value
//! (the number after the prefix) from each such marker on; samples before
//! the first marker of a rule are dropped.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use limpid_core::error::significant;
use limpid_core::{Error, Result};
use serde::Deserialize;

use crate::sources::{Source, Stream};

mod apply;
mod units;

pub use apply::{apply, apply_partial, Converted};
use units::Quantity;
pub use units::{nearest_hint, unit_factor};

/// A parsed, checked channel map.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelMap {
    /// Where the recording's time comes from.
    #[serde(default)]
    pub time: TimeSpec,
    /// FORMAT.md column name -> where its values come from.
    pub columns: BTreeMap<String, ColumnSpec>,
    /// Per-stream treatment of the stamps, by stream name.
    #[serde(default)]
    pub streams: BTreeMap<String, StreamRule>,
    /// The file the map was read from (for messages).
    #[serde(skip)]
    pub path: Option<PathBuf>,
}

/// The `[time]` table.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// The stream whose stamps become `t` (XDF stream name, TDMS group,
    /// C3D `analog` or `points`).
    pub stream: Option<String>,
    /// Sample rate (Hz) of a table without a time column.
    pub rate: Option<f64>,
    /// Or the file's own scalar that holds the sampling interval in
    /// seconds (a MAT object's `z.domainIncr`).
    pub increment: Option<String>,
}

/// A `[streams."name"]` table: how a stream's stamps are taken.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StreamRule {
    /// `"header"` (a bag message's header stamp, the default) or `"log"`
    /// (the time the recorder logged it).
    pub clock: Option<String>,
    /// Replace the stamps by a least-squares line through them, piece by
    /// piece between breaks (gaps over 1 s and 500 sampling intervals, or
    /// backward jumps), as pyxdf's `dejitter_timestamps` does.
    #[serde(default)]
    pub dejitter: bool,
}

/// One column's source: a channel, or a marker rule.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum ColumnSpec {
    /// Just the channel's name.
    Channel(String),
    /// The full form.
    Full(ColumnRule),
}

/// The full form of a column's source.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColumnRule {
    /// The channel's name in the file.
    pub channel: Option<String>,
    /// The stream that holds it (needed when names repeat across streams).
    pub stream: Option<String>,
    /// Its unit in the file (defaults to the declared one, else SI).
    pub unit: Option<String>,
    /// Multiplies the converted value (e.g. -1 for a sensor that reads the hand's force).
    pub scale: Option<f64>,
    /// Added after scaling, in SI units.
    pub offset: Option<f64>,
    /// Trials start at each marker of exactly this text.
    pub marker: Option<String>,
    /// Markers starting with this text carry the column's value after it.
    pub marker_prefix: Option<String>,
    /// For an `env_<muscle>` column: the low-pass cut-off (Hz) of the EMG
    /// envelope made at the channel's native rate (default 8 Hz, seed 001).
    pub envelope_hz: Option<f64>,
}

/// Default envelope cut-off of `env_` columns (Hz): seed 001's 8 Hz.
pub const ENVELOPE_HZ: f64 = 8.0;

impl ColumnSpec {
    fn rule(&self) -> ColumnRule {
        match self {
            ColumnSpec::Channel(name) => ColumnRule {
                channel: Some(name.clone()),
                ..ColumnRule::default()
            },
            ColumnSpec::Full(rule) => rule.clone(),
        }
    }
}

impl ChannelMap {
    /// Read and check a map file.
    pub fn read(path: &Path) -> Result<ChannelMap> {
        let bytes = limpid_core::files::read_bytes(path, 1 << 20)?;
        let text = String::from_utf8(bytes).map_err(|_| Error::Format {
            path: path.to_path_buf(),
            message: "a channel map is UTF-8 text (TOML)".into(),
        })?;
        let mut map = ChannelMap::parse(&text).map_err(|message| Error::Format {
            path: path.to_path_buf(),
            message,
        })?;
        map.path = Some(path.to_path_buf());
        Ok(map)
    }

    /// Parse and check map text (TOML).
    pub fn parse(text: &str) -> std::result::Result<ChannelMap, String> {
        let map: ChannelMap = toml::from_str(text).map_err(|e| {
            let msg = e.message().to_string();
            match e.span() {
                Some(span) => {
                    let line = text[..span.start.min(text.len())].matches('\n').count() + 1;
                    format!("line {line}: {msg}")
                }
                None => msg,
            }
        })?;
        map.check()?;
        Ok(map)
    }

    /// A map built another way (e.g. deserialised from Python), checked as
    /// [`ChannelMap::parse`] checks the TOML form.
    pub fn checked(self) -> std::result::Result<ChannelMap, String> {
        self.check()?;
        Ok(self)
    }

    fn check(&self) -> std::result::Result<(), String> {
        if self.columns.is_empty() {
            return Err("[columns] names no column".into());
        }
        for (name, rule) in &self.streams {
            if let Some(clock) = &rule.clock {
                if clock != "header" && clock != "log" {
                    return Err(format!(
                        "[streams.{name:?}] clock = {clock:?}: \"header\" or \"log\""
                    ));
                }
            }
        }
        if self.time.rate.is_some() && self.time.increment.is_some() {
            return Err("[time] gives both rate and increment; keep one".into());
        }
        if let Some(rate) = self.time.rate {
            if !(rate.is_finite() && rate > 0.0 && rate <= 1e7) {
                return Err(format!(
                    "[time] rate = {}: a sample rate in Hz, above 0 and at most 1e7",
                    significant(rate, 6)
                ));
            }
        }
        for (column, spec) in &self.columns {
            let r = spec.rule();
            let at = |m: String| format!("[columns] {column}: {m}");
            if column.is_empty() || column.chars().any(|c| c.is_control() || c == ',') {
                return Err(format!("[columns] {column:?}: not a usable column name"));
            }
            let sources = [
                r.channel.is_some(),
                r.marker.is_some(),
                r.marker_prefix.is_some(),
            ]
            .iter()
            .filter(|b| **b)
            .count();
            if sources != 1 {
                return Err(at(
                    "give exactly one of channel, marker or marker_prefix".into()
                ));
            }
            if r.channel.as_deref() == Some("") || r.marker.as_deref() == Some("") {
                return Err(at("an empty channel or marker name".into()));
            }
            if r.channel.is_none() {
                if r.unit.is_some() || r.scale.is_some() || r.offset.is_some() {
                    return Err(at(
                        "unit, scale and offset apply to channels, not to marker rules".into(),
                    ));
                }
                if column == "t" {
                    return Err(at("time cannot come from markers".into()));
                }
            }
            for (name, v) in [("scale", r.scale), ("offset", r.offset)] {
                if let Some(v) = v {
                    if !v.is_finite() || v.abs() > 1e15 {
                        return Err(at(format!(
                            "{name} = {} is not a usable finite number",
                            significant(v, 6)
                        )));
                    }
                }
            }
            if r.scale == Some(0.0) {
                return Err(at("scale = 0 would erase the channel".into()));
            }
            if let Some(unit) = &r.unit {
                Quantity::of(column).factor(unit).map_err(at)?;
            }
            if let Some(hz) = r.envelope_hz {
                if !column.starts_with("env_") {
                    return Err(at(
                        "envelope_hz applies to env_<muscle> columns (an EMG envelope made at the native rate)".into(),
                    ));
                }
                if !(hz.is_finite() && hz > 0.0) {
                    return Err(at(format!(
                        "envelope_hz = {}: a cut-off in Hz above 0",
                        significant(hz, 6)
                    )));
                }
            }
        }
        Ok(())
    }

    /// The map of `--column NAME=CHANNEL` (Python `columns={NAME: CHANNEL}`):
    /// `base` (a map file) or, without one, every channel of a one-stream
    /// file (a table, a MAT file) under its own name (of several streams:
    /// those named like FORMAT.md columns), with each named column read from
    /// its channel instead, a renamed channel no longer under its own name.
    pub fn with_columns(
        base: Option<&ChannelMap>,
        source: &Source,
        columns: &[(String, String)],
    ) -> Result<ChannelMap> {
        let mut map = match base {
            Some(map) => map.clone(),
            None => {
                let numeric: Vec<&Stream> = source
                    .streams
                    .iter()
                    .filter(|s| !s.channels.is_empty())
                    .collect();
                match numeric.as_slice() {
                    [only] => ChannelMap {
                        time: TimeSpec::default(),
                        columns: only
                            .channels
                            .iter()
                            .filter(|c| {
                                !c.name.is_empty()
                                    && !c.name.chars().any(|ch| ch.is_control() || ch == ',')
                            })
                            .map(|c| (c.name.clone(), ColumnSpec::Channel(c.name.clone())))
                            .collect(),
                        streams: BTreeMap::new(),
                        path: None,
                    },
                    _ => ChannelMap::implicit(source).unwrap_or(ChannelMap {
                        time: TimeSpec::default(),
                        columns: BTreeMap::new(),
                        streams: BTreeMap::new(),
                        path: None,
                    }),
                }
            }
        };
        for (_, channel) in columns {
            // the channel is read once, under its new name
            map.columns
                .retain(|_, spec| spec.rule().channel.as_deref() != Some(channel.as_str()));
        }
        for (name, channel) in columns {
            map.columns
                .insert(name.clone(), ColumnSpec::Channel(channel.clone()));
        }
        map.check()
            .map_err(|m| source.error(format!("--column: {m}")))?;
        Ok(map)
    }

    /// The map a file without one gets: every channel named like a FORMAT.md
    /// column, the time base the stream holding most of them.
    pub fn implicit(source: &Source) -> Result<ChannelMap> {
        let count = |s: &Stream| {
            s.channels
                .iter()
                .filter(|c| limpid_core::recording::is_format_column(&c.name))
                .count()
        };
        let best = source
            .streams
            .iter()
            .max_by_key(|s| count(s))
            .filter(|s| count(s) > 0)
            .ok_or_else(|| {
                source.error(format!(
                    "no channel is named like a FORMAT.md column (t, x, fx, q1, emg_..., ...); write a channel map (`limpid inspect {}` proposes one) and pass it with --map",
                    source.path.display()
                ))
            })?;
        let mut columns = BTreeMap::new();
        for s in std::iter::once(best).chain(source.streams.iter()) {
            for c in &s.channels {
                if limpid_core::recording::is_format_column(&c.name)
                    && !columns.contains_key(&c.name)
                {
                    columns.insert(
                        c.name.clone(),
                        ColumnSpec::Full(ColumnRule {
                            channel: Some(c.name.clone()),
                            stream: Some(s.name.clone()),
                            ..ColumnRule::default()
                        }),
                    );
                }
            }
        }
        Ok(ChannelMap {
            time: TimeSpec {
                stream: Some(best.name.clone()),
                rate: None,
                increment: None,
            },
            columns,
            streams: BTreeMap::new(),
            path: None,
        })
    }
}
