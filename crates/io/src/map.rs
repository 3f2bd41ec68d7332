//! Channel maps: a rig's file (any stream, channel names, units and signs)
//! turned into a FORMAT.md recording (issue 40).
//!
//! A map is TOML, written once per rig:
//!
//! ```toml
//! [time]
//! stream = "robot"          # the stream whose stamps are the recording's t
//! [columns]
//! x  = { channel = "EndEff.X", unit = "mm" }
//! fx = { channel = "Force.Fx", unit = "N", scale = -1.0 }
//! emg_biceps = { channel = "EMG1", stream = "emg", unit = "mV" }
//! trial = { marker = "perturbation_start" }
//! level = { marker_prefix = "level=" }
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
use limpid_core::recording::magnitude_limit;
use limpid_core::{Error, Recording, Result};
use serde::Deserialize;

use crate::sources::{Marker, Source, Stream};

/// A parsed, checked channel map.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelMap {
    /// Where the recording's time comes from.
    #[serde(default)]
    pub time: TimeSpec,
    /// FORMAT.md column name -> where its values come from.
    pub columns: BTreeMap<String, ColumnSpec>,
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

/// The physical quantity of a FORMAT.md column, from its unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Quantity {
    Time,
    Length,
    Angle,
    Force,
    Torque,
    Voltage,
    Number,
}

impl Quantity {
    fn of(column: &str) -> Quantity {
        match magnitude_limit(column).1 {
            "s" => Quantity::Time,
            "m" => Quantity::Length,
            "rad" => Quantity::Angle,
            "N" => Quantity::Force,
            "N m" => Quantity::Torque,
            "V" => Quantity::Voltage,
            _ => Quantity::Number,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Quantity::Time => "a time (s)",
            Quantity::Length => "a length (m)",
            Quantity::Angle => "an angle (rad)",
            Quantity::Force => "a force (N)",
            Quantity::Torque => "a torque (N m)",
            Quantity::Voltage => "a voltage (V)",
            Quantity::Number => "a number without unit",
        }
    }

    /// Units limpid converts, with their factor to SI.
    fn units(self) -> &'static [(&'static str, f64)] {
        const DEG: f64 = std::f64::consts::PI / 180.0;
        const LBF: f64 = 4.448_221_615_260_5;
        match self {
            Quantity::Time => &[
                ("s", 1.0),
                ("ms", 1e-3),
                ("us", 1e-6),
                ("µs", 1e-6),
                ("min", 60.0),
            ],
            Quantity::Length => &[
                ("m", 1.0),
                ("cm", 1e-2),
                ("mm", 1e-3),
                ("um", 1e-6),
                ("µm", 1e-6),
                ("in", 0.0254),
                ("ft", 0.3048),
            ],
            Quantity::Angle => &[
                ("rad", 1.0),
                ("mrad", 1e-3),
                ("deg", DEG),
                ("degree", DEG),
                ("degrees", DEG),
                ("°", DEG),
            ],
            Quantity::Force => &[
                ("N", 1.0),
                ("kN", 1e3),
                ("mN", 1e-3),
                ("lbf", LBF),
                ("kgf", 9.806_65),
            ],
            Quantity::Torque => &[
                ("N m", 1.0),
                ("N*m", 1.0),
                ("N.m", 1.0),
                ("N·m", 1.0),
                ("Nm", 1.0),
                ("N mm", 1e-3),
                ("N*mm", 1e-3),
                ("N.mm", 1e-3),
                ("Nmm", 1e-3),
                ("mN m", 1e-3),
                ("mN*m", 1e-3),
                ("mNm", 1e-3),
                ("kN m", 1e3),
                ("lbf in", LBF * 0.0254),
                ("lbf*in", LBF * 0.0254),
            ],
            Quantity::Voltage => &[
                ("V", 1.0),
                ("mV", 1e-3),
                ("uV", 1e-6),
                ("µV", 1e-6),
                ("kV", 1e3),
            ],
            Quantity::Number => &[("1", 1.0), ("", 1.0), ("count", 1.0)],
        }
    }

    /// The factor to SI of `unit`, or why it cannot be converted.
    fn factor(self, unit: &str) -> std::result::Result<f64, String> {
        let unit = unit.trim();
        if let Some((_, f)) = self.units().iter().find(|(u, _)| *u == unit) {
            return Ok(*f);
        }
        // a unit of another quantity is a different mistake than a typo
        for other in [
            Quantity::Time,
            Quantity::Length,
            Quantity::Angle,
            Quantity::Force,
            Quantity::Torque,
            Quantity::Voltage,
        ] {
            if other != self && other.units().iter().any(|(u, _)| *u == unit) {
                return Err(format!(
                    "unit {unit:?} is {}, but the column is {}",
                    other.name(),
                    self.name()
                ));
            }
        }
        let names: Vec<&str> = self
            .units()
            .iter()
            .map(|(u, _)| *u)
            .filter(|u| !u.is_empty())
            .collect();
        Err(format!(
            "unknown unit {unit:?} for {}{}",
            self.name(),
            nearest_hint(unit, &names)
        ))
    }
}

/// The factor that converts `unit` to the SI unit of FORMAT.md column
/// `column`, or why it cannot.
pub fn unit_factor(column: &str, unit: &str) -> std::result::Result<f64, String> {
    Quantity::of(column).factor(unit)
}

/// ", nearest: a, b" (the closest names by edit distance), or the list of all when few.
pub fn nearest_hint(wanted: &str, names: &[&str]) -> String {
    if names.is_empty() {
        return String::new();
    }
    let mut scored: Vec<(usize, &str)> = names
        .iter()
        .map(|n| {
            let d = strsim::levenshtein(&wanted.to_lowercase(), &n.to_lowercase());
            (d, *n)
        })
        .collect();
    scored.sort();
    let close: Vec<&str> = scored.iter().take(3).map(|(_, n)| *n).collect();
    format!("; nearest: {}", close.join(", "))
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
            },
            columns,
            path: None,
        })
    }
}

/// The stream called `name`, or an error naming the nearest streams.
fn named_stream<'a>(source: &'a Source, name: &str, what: &str) -> Result<&'a Stream> {
    source
        .streams
        .iter()
        .find(|s| s.name == name)
        .ok_or_else(|| {
            let names: Vec<&str> = source.streams.iter().map(|s| s.name.as_str()).collect();
            source.error(format!(
                "{what}: no stream {name:?} in the file{}",
                nearest_hint(name, &names)
            ))
        })
}

/// A channel found in a source.
struct Found<'a> {
    stream: &'a Stream,
    values: &'a [f64],
    declared_unit: Option<&'a str>,
}

fn find_channel<'a>(
    source: &'a Source,
    column: &str,
    channel: &str,
    stream: Option<&str>,
) -> Result<Found<'a>> {
    let candidates: Vec<&Stream> = match stream {
        Some(name) => {
            vec![named_stream(source, name, &format!("map column {column}"))?]
        }
        None => source.streams.iter().collect(),
    };
    let hits: Vec<(&Stream, &crate::sources::Channel)> = candidates
        .iter()
        .flat_map(|s| {
            s.channels
                .iter()
                .filter(|c| c.name == channel)
                .map(move |c| (*s, c))
        })
        .collect();
    match hits.as_slice() {
        [(s, c)] => Ok(Found {
            stream: s,
            values: &c.values,
            declared_unit: c.unit.as_deref(),
        }),
        [] => {
            let all: Vec<&str> = candidates
                .iter()
                .flat_map(|s| s.channels.iter().map(|c| c.name.as_str()))
                .collect();
            Err(source.error(format!(
                "map column {column}: no channel {channel:?}{}{}",
                stream
                    .map(|s| format!(" in stream {s:?}"))
                    .unwrap_or_default(),
                nearest_hint(channel, &all)
            )))
        }
        _ => {
            let names: Vec<String> = hits.iter().map(|(s, _)| format!("{:?}", s.name)).collect();
            Err(source.error(format!(
                "map column {column}: channel {channel:?} is in several streams ({}); name one with stream = ...",
                names.join(", ")
            )))
        }
    }
}

/// A recording made from a source by a map, and what the conversion did.
pub struct Converted {
    /// The FORMAT.md recording.
    pub recording: Recording,
    /// What was done that the user should know (trimmed spans, dropped samples, resampled streams).
    pub notes: Vec<String>,
}

/// Linear interpolation of `values` sampled at `stamps` (increasing) at `at`
/// (increasing, inside the stamps' span).
fn interpolate(stamps: &[f64], values: &[f64], at: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(at.len());
    let mut k = 0;
    for &t in at {
        while k + 2 < stamps.len() && stamps[k + 1] < t {
            k += 1;
        }
        let (t0, t1) = (stamps[k], stamps[(k + 1).min(stamps.len() - 1)]);
        let (v0, v1) = (values[k], values[(k + 1).min(values.len() - 1)]);
        out.push(if t1 > t0 {
            v0 + (v1 - v0) * ((t - t0) / (t1 - t0)).clamp(0.0, 1.0)
        } else {
            v0
        });
    }
    out
}

/// Apply `map` to a file that records less than the main one (an MVC
/// recording beside a co-contraction session, calibration poses): columns
/// whose channel or markers the file lacks are left out (reported), and when
/// the map's time-base stream is absent the stream holding most of the
/// remaining channels sets the time. An error when nothing of the map is
/// in the file.
pub fn apply_partial(source: &Source, map: &ChannelMap) -> Result<Converted> {
    let mut kept = BTreeMap::new();
    let mut left_out = Vec::new();
    let mut per_stream: Vec<(usize, String)> = Vec::new();
    for (column, spec) in &map.columns {
        let r = spec.rule();
        let present = match &r.channel {
            Some(ch) => match find_channel(source, column, ch, r.stream.as_deref()) {
                Ok(found) => {
                    match per_stream.iter_mut().find(|p| p.1 == found.stream.name) {
                        Some(p) => p.0 += 1,
                        None => per_stream.push((1, found.stream.name.clone())),
                    }
                    true
                }
                Err(_) => false,
            },
            None => source.streams.iter().any(|s| {
                s.markers
                    .iter()
                    .any(|m| match (&r.marker, &r.marker_prefix) {
                        (Some(text), _) => &m.text == text,
                        (_, Some(prefix)) => m.text.starts_with(prefix.as_str()),
                        _ => false,
                    })
            }),
        };
        if present {
            kept.insert(column.clone(), spec.clone());
        } else {
            left_out.push(column.clone());
        }
    }
    if kept.is_empty() {
        return Err(source
            .error("none of the channel map's channels or markers is in this file".to_string()));
    }
    let time_present = map
        .time
        .stream
        .as_ref()
        .is_some_and(|name| source.streams.iter().any(|s| &s.name == name));
    let stream = if time_present || map.time.stream.is_none() {
        map.time.stream.clone()
    } else {
        per_stream.iter().max_by_key(|p| p.0).map(|p| p.1.clone())
    };
    let partial = ChannelMap {
        time: TimeSpec {
            stream,
            rate: map.time.rate,
        },
        columns: kept,
        path: map.path.clone(),
    };
    let mut converted = apply(source, &partial)?;
    if !left_out.is_empty() {
        let note = format!(
            "columns of the map this file does not record were left out: {}",
            left_out.join(", ")
        );
        converted.recording.warn(note.clone());
        converted.notes.push(note);
    }
    Ok(converted)
}

/// Apply `map` to `source`: a FORMAT.md recording.
pub fn apply(source: &Source, map: &ChannelMap) -> Result<Converted> {
    let mut notes = Vec::new();
    let map_name = map
        .path
        .as_ref()
        .map(|p| format!("map {}", p.display()))
        .unwrap_or_else(|| "the implicit map".into());
    // the time base
    let rules: Vec<(&String, ColumnRule)> =
        map.columns.iter().map(|(c, s)| (c, s.rule())).collect();
    let time_rule = rules.iter().find(|(c, _)| c.as_str() == "t");
    let base: &Stream = if let Some((_, r)) = time_rule {
        find_channel(
            source,
            "t",
            r.channel.as_deref().unwrap_or(""),
            r.stream.as_deref(),
        )?
        .stream
    } else if let Some(name) = &map.time.stream {
        named_stream(source, name, &format!("{map_name}: [time]"))?
    } else if source.streams.len() == 1 {
        &source.streams[0]
    } else {
        let names: Vec<String> = source
            .streams
            .iter()
            .map(|s| format!("{:?}", s.name))
            .collect();
        return Err(source.error(format!(
            "{map_name}: the file has {} streams ({}); name the one that sets the time base with [time] stream = ...",
            names.len(),
            names.join(", ")
        )));
    };
    if base.channels.is_empty() {
        return Err(source.error(format!(
            "{map_name}: {} holds text markers, not samples; the time base is a numeric stream",
            base.label()
        )));
    }
    let n = base.len();
    let base_time: Vec<f64> = if let Some((_, r)) = time_rule {
        let found = find_channel(
            source,
            "t",
            r.channel.as_deref().unwrap_or(""),
            r.stream.as_deref(),
        )?;
        convert(source, "t", r, &found)?
    } else if let Some(stamps) = &base.stamps {
        stamps.clone()
    } else if let Some(rate) = map.time.rate {
        (0..n).map(|i| i as f64 / rate).collect()
    } else {
        return Err(source.error(format!(
            "{map_name}: {} has no time stamps; map a t column (t = {{ channel = \"...\", unit = \"s\" }}) or give [time] rate = <Hz>",
            base.label()
        )));
    };
    // the span every used stream covers
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    let mut used: Vec<&Stream> = Vec::new();
    for (column, r) in &rules {
        if let Some(ch) = &r.channel {
            let found = find_channel(source, column, ch, r.stream.as_deref())?;
            if !std::ptr::eq(found.stream, base) {
                let stamps = found.stream.stamps.as_ref().ok_or_else(|| {
                    source.error(format!(
                        "map column {column}: {} has no time stamps to align it with the time base",
                        found.stream.label()
                    ))
                })?;
                if stamps.len() < 2 {
                    return Err(source.error(format!(
                        "map column {column}: {} has {} sample(s); at least 2 are needed to interpolate",
                        found.stream.label(),
                        stamps.len()
                    )));
                }
                lo = lo.max(stamps[0]);
                hi = hi.min(stamps[stamps.len() - 1]);
                if !used.iter().any(|s| std::ptr::eq(*s, found.stream)) {
                    used.push(found.stream);
                }
            }
        }
    }
    let first = base_time.partition_point(|t| *t < lo);
    let last = base_time.partition_point(|t| *t <= hi);
    if first >= last {
        return Err(source.error(format!(
            "{map_name}: the streams do not overlap in time ({} spans {} to {} s; the others {} to {} s)",
            base.label(),
            base_time.first().copied().unwrap_or(0.0),
            base_time.last().copied().unwrap_or(0.0),
            lo,
            hi
        )));
    }
    if first > 0 || last < n {
        notes.push(format!(
            "{} samples of {} outside the span of the other streams were left out ({} at the start, {} at the end)",
            first + (n - last),
            base.label(),
            first,
            n - last
        ));
    }
    let mut keep: Vec<bool> = vec![false; n];
    keep[first..last].iter_mut().for_each(|k| *k = true);
    let t_span = &base_time[first..last];
    for s in &used {
        let gaps = s.gaps();
        if !gaps.is_empty() {
            let stamps = s.stamps.as_ref().expect("used streams have stamps");
            let longest = gaps.iter().map(|g| g.1).fold(0.0, f64::max);
            let (i, _) = gaps
                .iter()
                .copied()
                .find(|g| g.1 == longest)
                .expect("a gap");
            notes.push(format!(
                "{} has {} gap(s) (drop-outs), the longest {:.4} s before sample {} (t = {:.4} s); the time base is interpolated across them",
                s.label(),
                gaps.len(),
                longest,
                i + 1,
                stamps[i]
            ));
        }
    }
    // columns
    let mut names = Vec::new();
    let mut columns: Vec<Vec<f64>> = Vec::new();
    let mut before_markers = 0usize;
    for (column, r) in &rules {
        let values: Vec<f64> = if let Some(ch) = &r.channel {
            let found = find_channel(source, column, ch, r.stream.as_deref())?;
            if found.values.len() != found.stream.len() {
                return Err(source.error(format!(
                    "{} channel {ch:?}: {} values for {} samples",
                    found.stream.label(),
                    found.values.len(),
                    found.stream.len()
                )));
            }
            if column.as_str() == "t" {
                base_time[first..last].to_vec()
            } else {
                let mut v = convert(source, column, r, &found)?;
                if column.starts_with("env_") {
                    v = envelope(source, column, r, &found, v)?;
                }
                if std::ptr::eq(found.stream, base) {
                    v[first..last].to_vec()
                } else {
                    let stamps = found.stream.stamps.as_ref().expect("checked above");
                    let (native, target) = (found.stream.interval(), base.interval());
                    if let (Some(native), Some(target)) = (native, target) {
                        if column.starts_with("emg_") && native * 1.5 < target {
                            notes.push(format!(
                                "{column}: raw EMG at {} Hz picked at the time base's {} Hz (aliased); map it as env_{} to make the envelope at the native rate",
                                limpid_core::error::significant(1.0 / native, 6),
                                limpid_core::error::significant(1.0 / target, 6),
                                &column[4..]
                            ));
                        }
                    }
                    interpolate(stamps, &v, t_span)
                }
            }
        } else {
            let markers = markers_for(source, column, r)?;
            let (vals, before) =
                marker_column(column, r, &markers, t_span).map_err(|m| source.error(m))?;
            before_markers = before_markers.max(before);
            vals
        };
        names.push(column.to_string());
        columns.push(values);
    }
    if before_markers >= t_span.len() {
        return Err(source.error(format!("{map_name}: no sample follows the first marker")));
    }
    if before_markers > 0 {
        notes.push(format!(
            "{before_markers} samples before the first marker were left out"
        ));
        for c in &mut columns {
            c.drain(..before_markers);
        }
    }
    let names_had_t = names.iter().any(|n| n == "t");
    if !names_had_t {
        names.insert(0, "t".into());
        let t0 = t_span[before_markers];
        columns.insert(0, t_span[before_markers..].iter().map(|t| t - t0).collect());
    }
    let origin = t_span[before_markers];
    let mut order: Vec<usize> = (0..names.len()).collect();
    order.sort_by_key(|&i| (column_rank(&names[i]), names[i].clone()));
    let names: Vec<String> = order.iter().map(|&i| names[i].clone()).collect();
    let mut slots: Vec<Option<Vec<f64>>> = columns.into_iter().map(Some).collect();
    let columns: Vec<Vec<f64>> = order
        .iter()
        .map(|&i| slots[i].take().expect("each once"))
        .collect();
    gap_in_base(source, base, &names, &columns)?;
    let mut recording = Recording::new(&source.path, names, columns, 1)?;
    for note in source.notes.iter().chain(&notes) {
        // the reader of the warnings names the file (CLI, Python)
        recording.warn(note.clone());
    }
    // where t starts is worth saying in a conversion, not a warning on every read
    if !names_had_t && origin != 0.0 {
        notes.push(format!(
            "t counts from the first sample kept ({origin} s on the file's clock)"
        ));
    }
    Ok(Converted { recording, notes })
}

/// Where a column goes in a converted table: FORMAT.md's order (time,
/// end-point, joints, inputs, robot, labels, EMG), then the rest by name.
fn column_rank(name: &str) -> usize {
    const FIXED: [&str; 15] = [
        "t", "x", "y", "z", "fx", "fy", "fz", "theta", "tauy", "ux", "uy", "uz", "utheta", "trial",
        "level",
    ];
    if let Some(i) = FIXED.iter().position(|f| *f == name) {
        return i * 10;
    }
    if name.starts_with('q') {
        return 85;
    }
    if name.starts_with("tau") {
        return 86;
    }
    if name.starts_with("robot_q") {
        return 125;
    }
    if name.starts_with("emg_") {
        return 200;
    }
    300
}

/// A dropped sample inside a trial of the time-base stream, named by stream
/// and time, before the recording's own check (which names only a row).
fn gap_in_base(
    source: &Source,
    base: &Stream,
    names: &[String],
    columns: &[Vec<f64>],
) -> Result<()> {
    let t = &columns[names.iter().position(|n| n == "t").expect("t column")];
    let trial = names.iter().position(|n| n == "trial").map(|i| &columns[i]);
    let Some(step) = base.interval().or_else(|| {
        let mut d: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        if d.is_empty() {
            return None;
        }
        let mid = d.len() / 2;
        Some(*d.select_nth_unstable_by(mid, f64::total_cmp).1)
    }) else {
        return Ok(());
    };
    for i in 1..t.len() {
        let gap = t[i] - t[i - 1];
        let new_trial = trial.is_some_and(|tr| tr[i] != tr[i - 1]);
        if gap > 1.5 * step && !new_trial {
            return Err(source.error(format!(
                "{}, sample {} of the recording (t = {:.6} s): a gap of {:.6} s where samples come every {:.6} s (dropped samples in the time-base stream); limpid does not interpolate the time base",
                base.label(),
                i + 1,
                t[i],
                gap,
                step
            )));
        }
    }
    Ok(())
}

/// The values of a channel in SI, scaled and offset; non-finite samples refused.
fn convert(source: &Source, column: &str, r: &ColumnRule, found: &Found) -> Result<Vec<f64>> {
    let quantity = Quantity::of(column);
    let unit = r.unit.as_deref().or(found.declared_unit);
    let factor = match unit {
        Some(u) => quantity.factor(u).map_err(|m| {
            source.error(format!(
                "map column {column}: {m}{}",
                if r.unit.is_none() {
                    " (the unit the file declares; give unit = ... in the map to override)"
                } else {
                    ""
                }
            ))
        })?,
        None => 1.0,
    };
    let scale = r.scale.unwrap_or(1.0) * factor;
    let offset = r.offset.unwrap_or(0.0);
    let channel = r.channel.as_deref().unwrap_or("");
    let mut out = Vec::with_capacity(found.values.len());
    for (i, v) in found.values.iter().enumerate() {
        let y = v * scale + offset;
        if !y.is_finite() {
            return Err(source.error(format!(
                "{}, channel {channel:?}, sample {}: {} (mapped to column {column})",
                found.stream.label(),
                i + 1,
                if v.is_finite() {
                    format!("{v} overflows when converted")
                } else {
                    format!("the value is {v}")
                }
            )));
        }
        out.push(y);
    }
    Ok(out)
}

/// An EMG envelope at the channel's native rate: full-wave rectified, then
/// a 2nd-order Butterworth low-pass run forwards and backwards (seed 001's
/// processing, as `limpid_analysis::emg` does for `emg_` columns), so that
/// a slower time base samples the envelope, not aliased raw EMG.
fn envelope(
    source: &Source,
    column: &str,
    r: &ColumnRule,
    found: &Found,
    raw: Vec<f64>,
) -> Result<Vec<f64>> {
    let hz = r.envelope_hz.unwrap_or(ENVELOPE_HZ);
    let fs = found
        .stream
        .interval()
        .map(|dt| 1.0 / dt)
        .or(found.stream.nominal_rate)
        .ok_or_else(|| {
            source.error(format!(
                "map column {column}: {} has no sample rate to make an envelope at",
                found.stream.label()
            ))
        })?;
    let lp = limpid_dsp::LowPass::butterworth(2, hz, fs).map_err(|e| {
        source.error(format!(
            "map column {column}: envelope_hz = {hz} at {fs} Hz: {e}"
        ))
    })?;
    let rectified: Vec<f64> = raw.iter().map(|v| v.abs()).collect();
    lp.filtfilt(&rectified)
        .map_err(|e| source.error(format!("map column {column}: {e}")))
}

/// The markers a marker rule reads: the named stream's, else every marker stream's.
fn markers_for(source: &Source, column: &str, r: &ColumnRule) -> Result<Vec<Marker>> {
    let mut markers: Vec<Marker> = match &r.stream {
        Some(name) => named_stream(source, name, &format!("map column {column}"))?
            .markers
            .clone(),
        None => source
            .streams
            .iter()
            .flat_map(|s| s.markers.iter().cloned())
            .collect(),
    };
    markers.sort_by(|a, b| a.time.total_cmp(&b.time));
    Ok(markers)
}

/// A trial or value column from markers at the times `t`; also how many
/// leading samples precede the first marker that applies.
fn marker_column(
    column: &str,
    r: &ColumnRule,
    markers: &[Marker],
    t: &[f64],
) -> std::result::Result<(Vec<f64>, usize), String> {
    let distinct = || {
        let mut texts: Vec<&str> = markers.iter().map(|m| m.text.as_str()).collect();
        texts.sort_unstable();
        texts.dedup();
        texts
    };
    let events: Vec<(f64, f64)> = if let Some(text) = &r.marker {
        markers
            .iter()
            .filter(|m| &m.text == text)
            .enumerate()
            .map(|(i, m)| (m.time, (i + 1) as f64))
            .collect()
    } else {
        let prefix = r.marker_prefix.as_deref().unwrap_or("");
        let mut out = Vec::new();
        for m in markers.iter().filter(|m| m.text.starts_with(prefix)) {
            let rest = m.text[prefix.len()..].trim();
            let v: f64 = rest.parse().ok().filter(|v: &f64| v.is_finite()).ok_or_else(|| {
                format!(
                    "map column {column}: marker {:?} at {} s: no number after the prefix {prefix:?}",
                    m.text, m.time
                )
            })?;
            out.push((m.time, v));
        }
        out
    };
    if events.is_empty() {
        let texts = distinct();
        let wanted = r
            .marker
            .as_deref()
            .or(r.marker_prefix.as_deref())
            .unwrap_or("");
        return Err(format!(
            "map column {column}: no marker {} {wanted:?} in the file (marker texts found: {})",
            if r.marker.is_some() {
                "of exactly the text"
            } else {
                "starting with"
            },
            if texts.is_empty() {
                "none".to_string()
            } else {
                texts
                    .iter()
                    .take(10)
                    .map(|t| format!("{t:?}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            }
        ));
    }
    let mut out = Vec::with_capacity(t.len());
    let mut k = 0;
    let mut before = 0;
    for &ti in t {
        while k < events.len() && events[k].0 <= ti {
            k += 1;
        }
        if k == 0 {
            before += 1;
            out.push(0.0);
        } else {
            out.push(events[k - 1].1);
        }
    }
    Ok((out, before))
}
