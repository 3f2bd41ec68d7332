//! LabVIEW TDMS files, read by our own decoder of NI's published layout
//! ("TDMS File Format Internal Structure"): the `tdms` crate (0.3) reads no
//! properties (units, `wf_increment`) and calls itself a work in progress.
//!
//! A file is a sequence of segments: a 28-byte lead-in (`TDSm`, table of
//! contents flags, version, the offsets of the next segment and of the raw
//! data), metadata (objects `/'group'/'channel'` with their raw-data index
//! and properties), then raw data in chunks (per object its values in
//! turn, or interleaved sample by sample). An object's index may say "as in
//! the previous segment"; without the new-object-list flag a segment keeps
//! the previous segment's objects.
//!
//! Streams are the groups; channels the group's channels with their
//! `unit_string`; time `wf_start_offset + i x wf_increment` when the
//! channels carry `wf_increment`. Read: little-endian files; numeric types
//! (integers, floats, with or without unit), booleans, time stamps (as
//! seconds since the channel's first stamp). Refused, naming the object:
//! big-endian files, DAQmx raw data, channels of one group with different
//! lengths or increments. Every size is checked against the bytes present.

use std::collections::HashMap;
use std::path::Path;

use super::cursor::Cursor;
use super::{Channel, Source, Stream};
use limpid_core::Result;

/// Largest TDMS file read (bytes).
pub const MAX_TDMS_BYTES: u64 = 4 << 30;

const TOC_META_DATA: u32 = 1 << 1;
const TOC_NEW_OBJ_LIST: u32 = 1 << 2;
const TOC_RAW_DATA: u32 = 1 << 3;
const TOC_INTERLEAVED: u32 = 1 << 5;
const TOC_BIG_ENDIAN: u32 = 1 << 6;
const TOC_DAQMX: u32 = 1 << 7;

/// Read a TDMS file.
pub fn read(path: &Path) -> Result<Source> {
    let bytes = limpid_core::files::read_bytes(path, MAX_TDMS_BYTES)?;
    read_bytes(path, &bytes)
}

/// A channel's raw-data layout in a segment.
#[derive(Clone, Copy, Debug)]
struct Index {
    data_type: u32,
    values: u64,
}

/// Everything known about one object (channel) across segments.
#[derive(Default)]
struct Object {
    index: Option<Index>,
    values: Vec<f64>,
    unit: Option<String>,
    increment: Option<f64>,
    start_offset: Option<f64>,
}

fn type_size(t: u32) -> Option<usize> {
    Some(match t {
        1 | 5 | 0x21 => 1,
        2 | 6 => 2,
        3 | 7 | 9 | 0x19 => 4,
        4 | 8 | 10 | 0x1A => 8,
        0x44 => 16,
        _ => return None,
    })
}

fn type_name(t: u32) -> String {
    match t {
        0x20 => "string".into(),
        0x08000c | 0x10000d => "complex".into(),
        0 => "void".into(),
        11 | 0x1B => "extended float".into(),
        t => format!("data type 0x{t:x}"),
    }
}

impl Cursor<'_> {
    fn string(&mut self, what: &str) -> std::result::Result<String, String> {
        let n = self.u32(what)? as usize;
        let b = self.take(n, what)?;
        String::from_utf8(b.to_vec()).map_err(|_| format!("byte {}: {what} is not UTF-8", self.at))
    }
}

/// One value of a property: numbers as f64, strings as text, others skipped.
enum Property {
    Number(f64),
    Text(String),
    Other,
}

fn property(c: &mut Cursor, data_type: u32) -> std::result::Result<Property, String> {
    if data_type == 0x20 {
        return Ok(Property::Text(c.string("property string")?));
    }
    let size = match data_type {
        11 | 0x1B => 10,
        0x08000c => 8,
        0x10000d => 16,
        t => type_size(t)
            .ok_or_else(|| format!("byte {}: a property of unknown {}", c.at, type_name(t)))?,
    };
    let b = c.take(size, "property value")?;
    Ok(match data_type {
        0x44 | 0x21 | 11 | 0x1B | 0x08000c | 0x10000d => Property::Other,
        t => Property::Number(number(t, b)),
    })
}

/// A little-endian value of a numeric type as f64 (time stamps: seconds since 1904).
fn number(t: u32, b: &[u8]) -> f64 {
    match t {
        1 => f64::from(b[0] as i8),
        2 => f64::from(i16::from_le_bytes([b[0], b[1]])),
        3 => f64::from(i32::from_le_bytes(b[..4].try_into().expect("4"))),
        4 => i64::from_le_bytes(b[..8].try_into().expect("8")) as f64,
        5 | 0x21 => f64::from(b[0]),
        6 => f64::from(u16::from_le_bytes([b[0], b[1]])),
        7 => f64::from(u32::from_le_bytes(b[..4].try_into().expect("4"))),
        8 => u64::from_le_bytes(b[..8].try_into().expect("8")) as f64,
        9 | 0x19 => f64::from(f32::from_le_bytes(b[..4].try_into().expect("4"))),
        10 | 0x1A => f64::from_le_bytes(b[..8].try_into().expect("8")),
        0x44 => {
            let fraction = u64::from_le_bytes(b[..8].try_into().expect("8"));
            let seconds = i64::from_le_bytes(b[8..16].try_into().expect("8"));
            seconds as f64 + fraction as f64 / 18_446_744_073_709_551_616.0
        }
        _ => f64::NAN,
    }
}

/// `/'group'/'channel'` split into its names (`''` stands for `'`).
fn split_path(path: &str) -> Vec<String> {
    let mut parts = Vec::new();
    let mut rest = path;
    while let Some(r) = rest.strip_prefix("/'") {
        let mut name = String::new();
        let mut chars = r.char_indices().peekable();
        let mut end = r.len();
        while let Some((i, ch)) = chars.next() {
            if ch == '\'' {
                if matches!(chars.peek(), Some((_, '\''))) {
                    name.push('\'');
                    chars.next();
                    continue;
                }
                end = i + 1;
                break;
            }
            name.push(ch);
        }
        parts.push(name);
        rest = &r[end.min(r.len())..];
    }
    parts
}

/// The objects read so far, in file order, and those the current segment holds.
#[derive(Default)]
struct Segments {
    objects: HashMap<String, Object>,
    order: Vec<String>,
    active: Vec<String>,
}

impl Segments {
    /// A segment's metadata: its objects with their raw-data index and properties.
    fn metadata(
        &mut self,
        m: &mut Cursor<'_>,
        where_: &dyn Fn(&str) -> String,
    ) -> std::result::Result<(), String> {
        let count = m.u32("object count")?;
        if count as usize > (m.bytes.len() - m.at) / 8 {
            return Err(where_(&format!(
                "{count} objects declared in a metadata block too small for them"
            )));
        }
        for _ in 0..count {
            let name = m.string("object path")?;
            let index_len = m.u32("raw data index")?;
            let entry = self.objects.entry(name.clone()).or_default();
            if !self.order.contains(&name) {
                self.order.push(name.clone());
            }
            match index_len {
                0xFFFF_FFFF => self.active.retain(|a| a != &name),
                0 => {
                    if entry.index.is_none() {
                        return Err(where_(&format!(
                            "object {name} reuses a raw-data index it never had"
                        )));
                    }
                    if !self.active.contains(&name) {
                        self.active.push(name.clone());
                    }
                }
                0x6912_0000 | 0x6913_0000 => {
                    return Err(where_(&format!(
                        "object {name}: DAQmx raw data is not read"
                    )));
                }
                _ => {
                    let data_type = m.u32("data type")?;
                    let dimension = m.u32("array dimension")?;
                    let values = m.u64("number of values")?;
                    if data_type == 0x20 {
                        m.u64("string total size")?;
                    }
                    if dimension != 1 {
                        return Err(where_(&format!(
                            "object {name}: array dimension {dimension} (TDMS allows 1)"
                        )));
                    }
                    if type_size(data_type).is_none() && values > 0 {
                        return Err(where_(&format!(
                            "channel {name}: {} values are not read (limpid reads numbers, booleans and time stamps)",
                            type_name(data_type)
                        )));
                    }
                    entry.index = Some(Index { data_type, values });
                    if !self.active.contains(&name) {
                        self.active.push(name.clone());
                    }
                }
            }
            let props = m.u32("property count")?;
            if props as usize > (m.bytes.len() - m.at) / 8 {
                return Err(where_(&format!("object {name}: {props} properties declared in a metadata block too small for them")));
            }
            for _ in 0..props {
                let key = m.string("property name")?;
                let t = m.u32("property type")?;
                let value = property(m, t)?;
                match (key.as_str(), value) {
                    ("unit_string", Property::Text(u)) if !u.trim().is_empty() => {
                        entry.unit = Some(u.trim().to_string())
                    }
                    ("wf_increment", Property::Number(v)) => entry.increment = Some(v),
                    ("wf_start_offset", Property::Number(v)) => entry.start_offset = Some(v),
                    _ => {}
                }
            }
        }
        Ok(())
    }

    /// A segment's raw data: each chunk's values appended to the active objects.
    fn raw_data(
        &mut self,
        raw: &[u8],
        interleaved: bool,
        where_: &dyn Fn(&str) -> String,
    ) -> std::result::Result<(), String> {
        let layout: Vec<(String, Index, usize)> = self
            .active
            .iter()
            .filter_map(|n| {
                let idx = self.objects[n].index?;
                (idx.values > 0).then(|| (n.clone(), idx, type_size(idx.data_type).unwrap_or(0)))
            })
            .collect();
        let chunk: u64 = layout
            .iter()
            .map(|(_, i, s)| i.values.saturating_mul(*s as u64))
            .fold(0u64, u64::saturating_add);
        if let Some(chunks) = (raw.len() as u64).checked_div(chunk) {
            if chunks == 0 {
                return Err(where_(&format!(
                    "raw data of {} bytes, but one chunk of its channels needs {chunk}",
                    raw.len()
                )));
            }
            for k in 0..chunks as usize {
                let base = k * chunk as usize;
                if interleaved {
                    let n = layout[0].1.values as usize;
                    let stride: usize = layout.iter().map(|l| l.2).sum();
                    if layout.iter().any(|l| l.1.values as usize != n) {
                        return Err(where_("interleaved channels with different value counts"));
                    }
                    let mut offset = 0;
                    for (name, idx, size) in &layout {
                        let o = self.objects.get_mut(name).expect("active object");
                        o.values.reserve(n);
                        for i in 0..n {
                            let p = base + i * stride + offset;
                            o.values.push(number(idx.data_type, &raw[p..p + size]));
                        }
                        offset += size;
                    }
                } else {
                    let mut p = base;
                    for (name, idx, size) in &layout {
                        let o = self.objects.get_mut(name).expect("active object");
                        let n = idx.values as usize;
                        o.values.reserve(n);
                        for i in 0..n {
                            let q = p + i * size;
                            o.values.push(number(idx.data_type, &raw[q..q + size]));
                        }
                        p += n * size;
                    }
                }
            }
        }
        Ok(())
    }

    /// Groups become streams, in file order.
    fn streams(&self) -> std::result::Result<Vec<Stream>, String> {
        let mut streams: Vec<Stream> = Vec::new();
        for name in &self.order {
            let parts = split_path(name);
            if parts.len() != 2 {
                continue;
            }
            let o = &self.objects[name];
            if o.index.is_none() {
                continue;
            }
            let (group, channel) = (&parts[0], &parts[1]);
            let timestamps = o.index.is_some_and(|i| i.data_type == 0x44);
            let mut values = o.values.clone();
            if timestamps {
                let first = values.first().copied().unwrap_or(0.0);
                values.iter_mut().for_each(|v| *v -= first);
            }
            let pos = match streams.iter().position(|s| &s.name == group) {
                Some(p) => p,
                None => {
                    streams.push(Stream {
                        name: group.clone(),
                        ..Stream::default()
                    });
                    streams.len() - 1
                }
            };
            let s = &mut streams[pos];
            if let Some(first) = s.channels.first() {
                if first.values.len() != values.len() {
                    return Err(format!(
                        "group {group:?}: channel {channel:?} has {} values, channel {:?} has {}; limpid reads a group as one stream (save channels of other lengths in another group)",
                        values.len(),
                        first.name,
                        first.values.len()
                    ));
                }
            }
            let rate = o
                .increment
                .filter(|i| i.is_finite() && *i > 0.0)
                .map(|i| 1.0 / i);
            if !s.channels.is_empty() && s.nominal_rate != rate {
                return Err(format!(
                    "group {group:?}: channel {channel:?} has another wf_increment than the group's first channel; limpid reads a group as one stream"
                ));
            }
            if s.channels.is_empty() {
                s.nominal_rate = rate;
                if let Some(inc) = o.increment.filter(|i| i.is_finite() && *i > 0.0) {
                    let start = o.start_offset.filter(|v| v.is_finite()).unwrap_or(0.0);
                    s.stamps = Some((0..values.len()).map(|i| start + i as f64 * inc).collect());
                }
            }
            s.channels.push(Channel {
                name: channel.clone(),
                unit: if timestamps {
                    Some("s".into())
                } else {
                    o.unit.clone()
                },
                values,
            });
        }
        Ok(streams)
    }
}

/// Read TDMS bytes; `path` names the file in errors.
pub fn read_bytes(path: &Path, bytes: &[u8]) -> Result<Source> {
    let fail = super::format_error(path);
    super::check_start(path, bytes, b"TDSm", "a TDMS")?;
    let mut segments = Segments::default();
    let mut at = 0usize;
    let mut segment = 0usize;
    while at < bytes.len() {
        segment += 1;
        let mut c = Cursor { bytes, at, base: 0 };
        let tag = c.take(4, "segment tag").map_err(&fail)?;
        if tag != b"TDSm" {
            return Err(fail(format!(
                "byte {at}: segment {segment} does not start with \"TDSm\" (corrupt file?)"
            )));
        }
        let toc = c.u32("table of contents").map_err(&fail)?;
        let _version = c.u32("version").map_err(&fail)?;
        let next = c.u64("next segment offset").map_err(&fail)?;
        let raw_offset = c.u64("raw data offset").map_err(&fail)?;
        let lead_end = at + 28;
        let where_ = |m: &str| format!("segment {segment} (byte {at}): {m}");
        if toc & TOC_BIG_ENDIAN != 0 {
            return Err(fail(where_("a big-endian segment; limpid reads little-endian TDMS files (LabVIEW's default on Windows and Linux)")));
        }
        if toc & TOC_DAQMX != 0 {
            return Err(fail(where_("DAQmx raw data; limpid reads TDMS files with plain channel data (save with \"TDMS Write\", not DAQmx logging), or convert with nptdms")));
        }
        let left = (bytes.len() - lead_end) as u64;
        // the last segment of a file still being written says 0xFFFF...; it ends with the file
        let segment_len = if next == u64::MAX || next > left {
            left
        } else {
            next
        };
        if raw_offset > segment_len {
            return Err(fail(where_(&format!(
                "raw data at {raw_offset} bytes but the segment holds {segment_len}"
            ))));
        }
        if toc & TOC_NEW_OBJ_LIST != 0 {
            segments.active.clear();
        }
        if toc & TOC_META_DATA != 0 {
            let mut m = Cursor {
                bytes: &bytes[..lead_end + raw_offset as usize],
                at: lead_end,
                base: 0,
            };
            segments.metadata(&mut m, &where_).map_err(&fail)?;
        }
        if toc & TOC_RAW_DATA != 0 {
            let raw = &bytes[lead_end + raw_offset as usize..lead_end + segment_len as usize];
            segments
                .raw_data(raw, toc & TOC_INTERLEAVED != 0, &where_)
                .map_err(&fail)?;
        }
        let step = 28usize.saturating_add(segment_len as usize);
        at = at.saturating_add(step);
    }
    let mut streams = segments.streams().map_err(&fail)?;
    streams.retain(|s| !s.channels.is_empty());
    if streams.is_empty() {
        return Err(fail("the TDMS file holds no channel with values".into()));
    }
    Ok(Source {
        path: path.to_path_buf(),
        format: "TDMS",
        streams,
        notes: Vec::new(),
        unread: Vec::new(),
        scalars: Vec::new(),
    })
}
