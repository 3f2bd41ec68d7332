//! XDF, the file format of Lab Streaming Layer's recorder (LabRecorder),
//! read by our own decoder of the specification
//! (github.com/sccn/xdf/wiki/Specifications, version 1.0).
//!
//! The file is `XDF:` followed by chunks: a length of 1, 4 or 8 bytes (its
//! width in the byte before it), a 2-byte tag, then the content. Tags: 1 file
//! header (XML), 2 stream header (stream id + XML `<info>`), 3 samples, 4
//! clock offset (stream id, collection time, offset value), 5 boundary, 6
//! stream footer. A samples chunk holds a count (width byte + value), then
//! per sample a time-stamp width (0 or 8) and stamp, then the values in the
//! stream's `channel_format` (little-endian numbers, or strings of a width
//! byte, a length and UTF-8 bytes).
//!
//! Choices (the specification leaves them to the reader):
//! - a sample without a stamp gets the last written stamp + k/nominal rate,
//!   k samples after it (the specification's previous + 1/rate, without the
//!   rounding drift of repeated additions);
//! - clock offsets are applied as pyxdf does without jitter removal:
//!   corrected = stamp + offset, the offset interpolated linearly between
//!   the collection times of the ClockOffset records (held beyond them);
//! - a string stream becomes markers (its first channel's text); a numeric
//!   stream whose corrected clock jumps back (a reset) keeps its longest
//!   stretch without a jump, the jumps reported by stream, sample and time;
//!   one that stands still (a stamp twice) is refused;
//! - a stream without clock offsets, in a file of several streams, is used
//!   on its own clock, with a warning;
//! - a file that ends inside a chunk (a recording cut off, no footers) is
//!   read up to its last whole chunk, with a warning naming the byte.
//!
//! Bounds: every length is checked against the bytes that are there before
//! anything is allocated; the file is read whole up to [`MAX_XDF_BYTES`].

use std::collections::BTreeMap;
use std::path::Path;

use super::cursor::Cursor;
use super::{Channel, Marker, Source, Stream};
use limpid_core::Result;

/// Largest XDF file read (bytes).
pub const MAX_XDF_BYTES: u64 = 4 << 30;

/// Most channels one stream may declare.
const MAX_CHANNELS: usize = 100_000;

/// Read an XDF file.
pub fn read(path: &Path) -> Result<Source> {
    let bytes = limpid_core::files::read_bytes(path, MAX_XDF_BYTES)?;
    read_bytes(path, &bytes)
}

#[derive(Clone, Copy, PartialEq)]
enum Format {
    Float32,
    Double64,
    Int8,
    Int16,
    Int32,
    Int64,
    Text,
}

impl Format {
    fn parse(text: &str) -> Option<Format> {
        Some(match text {
            "float32" => Format::Float32,
            "double64" => Format::Double64,
            "int8" => Format::Int8,
            "int16" => Format::Int16,
            "int32" => Format::Int32,
            "int64" => Format::Int64,
            "string" => Format::Text,
            _ => return None,
        })
    }

    /// Bytes per value (strings: at least the width byte).
    fn width(self) -> usize {
        match self {
            Format::Int8 | Format::Text => 1,
            Format::Int16 => 2,
            Format::Float32 | Format::Int32 => 4,
            Format::Double64 | Format::Int64 => 8,
        }
    }
}

/// A stream while its chunks are read.
struct Building {
    stream: Stream,
    format: Format,
    channel_count: usize,
    /// Raw (uncorrected) stamps.
    stamps: Vec<f64>,
    texts: Vec<String>,
    /// (collection time, offset) records.
    offsets: Vec<(f64, f64)>,
    /// The last written stamp and its sample index: deduced stamps count
    /// from it (k / rate, not k additions of 1 / rate, which drift).
    anchor: Option<(f64, usize)>,
}

impl Cursor<'_> {
    /// A variable-width count: a width byte (1, 4 or 8), then the value.
    fn varlen(&mut self, what: &str) -> std::result::Result<u64, String> {
        let at = self.base + self.at;
        let width = self.u8(what)?;
        let b = match width {
            1 | 4 | 8 => self.take(width as usize, what)?,
            w => {
                return Err(format!(
                    "byte {at}: {what}: a length field of {w} bytes (the specification allows 1, 4 or 8)"
                ))
            }
        };
        let mut v = [0u8; 8];
        v[..b.len()].copy_from_slice(b);
        Ok(u64::from_le_bytes(v))
    }
}

/// Read XDF bytes; `path` names the file in errors.
pub fn read_bytes(path: &Path, bytes: &[u8]) -> Result<Source> {
    let fail = super::format_error(path);
    super::check_start(path, bytes, b"XDF:", "an XDF")?;
    let mut file = Cursor {
        bytes,
        at: 4,
        base: 0,
    };
    let mut streams: BTreeMap<u32, Building> = BTreeMap::new();
    let mut order: Vec<u32> = Vec::new();
    let mut notes = Vec::new();
    while file.left() > 0 {
        let chunk_at = file.at;
        let length = match file.varlen("chunk length") {
            Ok(length) => length,
            Err(_) if !order.is_empty() => {
                notes.push(cut_note(chunk_at, None, file.bytes.len()));
                break;
            }
            Err(m) => return Err(fail(m)),
        };
        if length >= 2 && length > file.left() as u64 && !order.is_empty() {
            notes.push(cut_note(chunk_at, Some(length), file.bytes.len()));
            break;
        }
        if length < 2 || length > file.left() as u64 {
            return Err(fail(format!(
                "byte {chunk_at}: a chunk of {length} bytes, but {} are left in the file{}",
                file.left(),
                if length < 2 {
                    " (a chunk holds at least its 2-byte tag)"
                } else {
                    " (truncated file?)"
                }
            )));
        }
        let content = file.take(length as usize, "chunk").map_err(&fail)?;
        let tag = u16::from_le_bytes([content[0], content[1]]);
        let mut c = Cursor {
            bytes: &content[2..],
            at: 0,
            base: file.at - content.len() + 2,
        };
        match tag {
            1 | 5 => {}
            2 => {
                let id = c.u32("stream id").map_err(&fail)?;
                let xml = std::str::from_utf8(&c.bytes[c.at..]).map_err(|_| {
                    fail(format!(
                        "byte {chunk_at}: stream header {id}: the XML is not UTF-8"
                    ))
                })?;
                let building =
                    header(id, xml).map_err(|m| fail(format!("byte {chunk_at}: {m}")))?;
                if streams.insert(id, building).is_some() {
                    return Err(fail(format!(
                        "byte {chunk_at}: stream id {id} has two stream headers"
                    )));
                }
                order.push(id);
            }
            3 => {
                let id = c.u32("stream id").map_err(&fail)?;
                let s = streams.get_mut(&id).ok_or_else(|| {
                    fail(format!(
                        "byte {chunk_at}: samples of stream id {id}, which has no stream header before them"
                    ))
                })?;
                samples(s, &mut c).map_err(&fail)?;
            }
            4 => {
                let id = c.u32("stream id").map_err(&fail)?;
                let collected = c.f64("collection time").map_err(&fail)?;
                let offset = c.f64("offset value").map_err(&fail)?;
                if let Some(s) = streams.get_mut(&id) {
                    if collected.is_finite() && offset.is_finite() {
                        s.offsets.push((collected, offset));
                    } else {
                        notes.push(format!(
                            "byte {chunk_at}: a clock offset of stream {:?} that is not a finite number was ignored",
                            s.stream.name
                        ));
                    }
                }
            }
            6 => {}
            other => notes.push(format!(
                "byte {chunk_at}: a chunk with unknown tag {other} was skipped"
            )),
        }
    }
    if order.is_empty() {
        return Err(fail("the XDF file holds no stream header".into()));
    }
    let several = order.len() > 1;
    let mut own_clock = Vec::new();
    let mut out = Vec::with_capacity(order.len());
    for id in order {
        let b = streams.remove(&id).expect("stream of the order list");
        if several && b.offsets.is_empty() {
            own_clock.push(format!("{:?}", b.stream.name));
        }
        out.push(finish(b, &mut notes).map_err(&fail)?);
    }
    if !own_clock.is_empty() {
        notes.push(format!(
            "no clock offsets for stream(s) {}: used on their own clock, uncorrected (aligned with the others only if they share one machine's clock)",
            own_clock.join(", ")
        ));
    }
    Ok(Source {
        path: path.to_path_buf(),
        format: "XDF",
        streams: out,
        notes,
        unread: Vec::new(),
        scalars: Vec::new(),
    })
}

/// A stream header's `<info>`.
fn header(id: u32, xml: &str) -> std::result::Result<Building, String> {
    let doc = roxmltree::Document::parse(xml)
        .map_err(|e| format!("stream header {id}: the XML does not parse ({e})"))?;
    let info = doc.root_element();
    let child = |node: roxmltree::Node, name: &str| -> Option<String> {
        node.children()
            .find(|n| n.has_tag_name(name))
            .map(|n| n.text().unwrap_or("").trim().to_string())
    };
    let name = child(info, "name").unwrap_or_else(|| format!("stream{id}"));
    let what = format!("stream header {id} ({name:?})");
    let channel_count: usize = child(info, "channel_count")
        .ok_or_else(|| format!("{what}: no <channel_count>"))?
        .parse()
        .map_err(|_| format!("{what}: <channel_count> is not a count"))?;
    if channel_count == 0 || channel_count > MAX_CHANNELS {
        return Err(format!(
            "{what}: {channel_count} channels (limpid reads 1 to {MAX_CHANNELS})"
        ));
    }
    let format_text = child(info, "channel_format").unwrap_or_default();
    let format = Format::parse(&format_text)
        .ok_or_else(|| format!("{what}: channel_format {format_text:?} is not one of float32, double64, int8, int16, int32, int64, string"))?;
    let rate: f64 = child(info, "nominal_srate")
        .unwrap_or_else(|| "0".into())
        .parse()
        .map_err(|_| format!("{what}: <nominal_srate> is not a number"))?;
    if !rate.is_finite() || !(0.0..=1e7).contains(&rate) {
        return Err(format!("{what}: nominal_srate {rate} is not a rate limpid reads (0 for irregular, up to 10 MHz)"));
    }
    let mut labels: Vec<(String, Option<String>)> = info
        .children()
        .find(|n| n.has_tag_name("desc"))
        .and_then(|d| d.children().find(|n| n.has_tag_name("channels")))
        .map(|chs| {
            chs.children()
                .filter(|n| n.has_tag_name("channel"))
                .map(|ch| {
                    (
                        child(ch, "label").unwrap_or_default(),
                        child(ch, "unit").filter(|u| !u.is_empty()),
                    )
                })
                .collect()
        })
        .unwrap_or_default();
    labels.truncate(channel_count);
    let mut channels = Vec::with_capacity(channel_count);
    for k in 0..channel_count {
        let (label, unit) = labels.get(k).cloned().unwrap_or_default();
        let label = if label.is_empty() {
            format!("ch{}", k + 1)
        } else {
            label
        };
        channels.push(Channel {
            name: label,
            unit,
            values: Vec::new(),
        });
    }
    let mut seen = std::collections::HashSet::new();
    for ch in &channels {
        if !seen.insert(ch.name.as_str()) {
            return Err(format!("{what}: two channels are labelled {:?}", ch.name));
        }
    }
    Ok(Building {
        stream: Stream {
            name,
            kind: child(info, "type").filter(|t| !t.is_empty()),
            nominal_rate: (rate > 0.0).then_some(rate),
            stamps: None,
            channels: if format == Format::Text {
                Vec::new()
            } else {
                channels
            },
            markers: Vec::new(),
            ..Stream::default()
        },
        format,
        channel_count,
        stamps: Vec::new(),
        texts: Vec::new(),
        offsets: Vec::new(),
        anchor: None,
    })
}

/// One samples chunk, appended to its stream.
fn samples(s: &mut Building, c: &mut Cursor) -> std::result::Result<(), String> {
    let name = s.stream.name.clone();
    let count = c.varlen("sample count")?;
    // each sample takes at least its stamp-width byte and one width per value
    let least = 1 + s.channel_count * s.format.width();
    if count > (c.left() / least) as u64 {
        return Err(format!(
            "byte {}: stream {name:?}: a chunk declares {count} samples but holds {} bytes (truncated or corrupt)",
            c.base + c.at,
            c.left()
        ));
    }
    let rate = s.stream.nominal_rate;
    for _ in 0..count {
        let at = c.base + c.at;
        let index = s.stamps.len() + 1;
        let stamp = match c.u8("time-stamp width")? {
            0 => match (s.anchor, rate) {
                (Some((t0, i0)), Some(rate)) => t0 + (s.stamps.len() - i0) as f64 / rate,
                (None, Some(rate)) => s.stamps.len() as f64 / rate,
                _ => {
                    return Err(format!(
                        "byte {at}: stream {name:?}, sample {index}: no time stamp, and the stream has no nominal rate to deduce one"
                    ))
                }
            },
            8 => {
                let t = c.f64("time stamp")?;
                s.anchor = Some((t, s.stamps.len()));
                t
            }
            w => {
                return Err(format!(
                    "byte {at}: stream {name:?}, sample {index}: a time-stamp width of {w} bytes (0 or 8)"
                ))
            }
        };
        if !stamp.is_finite() {
            return Err(format!(
                "byte {at}: stream {name:?}, sample {index}: the time stamp is {stamp}"
            ));
        }
        s.stamps.push(stamp);
        if s.format == Format::Text {
            for k in 0..s.channel_count {
                let len = c.varlen("string length")?;
                if len > c.left() as u64 {
                    return Err(format!(
                        "byte {}: stream {name:?}, sample {index}: a string of {len} bytes, {} are left",
                        c.base + c.at,
                        c.left()
                    ));
                }
                let text = c.take(len as usize, "string")?;
                if k == 0 {
                    s.texts.push(String::from_utf8_lossy(text).into_owned());
                }
            }
            continue;
        }
        for ch in &mut s.stream.channels {
            let b = c.take(s.format.width(), "value")?;
            let v = match s.format {
                Format::Float32 => f64::from(f32::from_le_bytes(b.try_into().expect("4"))),
                Format::Double64 => f64::from_le_bytes(b.try_into().expect("8")),
                Format::Int8 => f64::from(b[0] as i8),
                Format::Int16 => f64::from(i16::from_le_bytes(b.try_into().expect("2"))),
                Format::Int32 => f64::from(i32::from_le_bytes(b.try_into().expect("4"))),
                Format::Int64 => i64::from_le_bytes(b.try_into().expect("8")) as f64,
                Format::Text => unreachable!("strings are read above"),
            };
            ch.values.push(v);
        }
    }
    Ok(())
}

/// The note for a file that ends inside the chunk starting at `at`.
fn cut_note(at: usize, declared: Option<u64>, size: usize) -> String {
    format!(
        "the file ends inside the chunk at byte {at}{}: read up to there, the last whole chunk (a recording cut off?)",
        declared
            .map(|n| format!(
                " ({n} bytes declared, {} there)",
                size.saturating_sub(at)
            ))
            .unwrap_or_default()
    )
}

/// Apply the clock offsets and check the stamps. A numeric stream whose
/// clock jumps back (a reset) keeps its longest stretch without a jump;
/// the jumps and what was left out are noted.
fn finish(mut b: Building, notes: &mut Vec<String>) -> std::result::Result<Stream, String> {
    let name = b.stream.name.clone();
    b.offsets.sort_by(|a, b| a.0.total_cmp(&b.0));
    if !b.offsets.is_empty() {
        let offs = &b.offsets;
        for t in &mut b.stamps {
            *t += offset_at(offs, *t);
        }
    }
    b.stream.clock_offsets = b.offsets.len();
    if b.format == Format::Text {
        let mut markers: Vec<Marker> = b
            .stamps
            .iter()
            .zip(b.texts)
            .map(|(&time, text)| Marker { time, text })
            .collect();
        markers.sort_by(|a, b| a.time.total_cmp(&b.time));
        b.stream.markers = markers;
        b.stream.stamps = Some(b.stamps);
        return Ok(b.stream);
    }
    let jumps: Vec<usize> = b
        .stamps
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[1] < w[0])
        .map(|(i, _)| i + 1)
        .collect();
    if !jumps.is_empty() {
        let described: Vec<String> = jumps
            .iter()
            .take(5)
            .map(|&i| {
                format!(
                    "at sample {} back by {} s (from {} s to {} s)",
                    i + 1,
                    limpid_core::error::significant(b.stamps[i - 1] - b.stamps[i], 4),
                    limpid_core::error::significant(b.stamps[i - 1], 9),
                    limpid_core::error::significant(b.stamps[i], 9)
                )
            })
            .collect();
        let mut bounds = vec![0];
        bounds.extend(&jumps);
        bounds.push(b.stamps.len());
        let (from, to) = bounds
            .windows(2)
            .map(|w| (w[0], w[1]))
            .max_by_key(|(a, z)| z - a)
            .expect("two bounds at least");
        notes.push(format!(
            "stream {name:?}: the clock jumps back {} time(s) (a clock reset?): {}{}; samples {} to {} ({} s to {} s), the longest stretch without a jump, are read, {} left out",
            jumps.len(),
            described.join("; "),
            if jumps.len() > 5 { "; ..." } else { "" },
            from + 1,
            to,
            limpid_core::error::significant(b.stamps[from], 9),
            limpid_core::error::significant(b.stamps[to - 1], 9),
            b.stamps.len() - (to - from)
        ));
        b.stamps = b.stamps[from..to].to_vec();
        for ch in &mut b.stream.channels {
            ch.values = ch.values[from..to].to_vec();
        }
    }
    if let Some(i) = b.stamps.windows(2).position(|w| w[1] <= w[0]) {
        return Err(format!(
            "stream {name:?}, sample {}: the clock stands still ({} s twice)",
            i + 2,
            b.stamps[i]
        ));
    }
    b.stream.stamps = Some(b.stamps);
    Ok(b.stream)
}

/// The clock offset at time `t`: linear between records, held beyond them.
fn offset_at(offsets: &[(f64, f64)], t: f64) -> f64 {
    let k = offsets.partition_point(|o| o.0 <= t);
    if k == 0 {
        offsets[0].1
    } else if k == offsets.len() {
        offsets[k - 1].1
    } else {
        let (t0, o0) = offsets[k - 1];
        let (t1, o1) = offsets[k];
        if t1 > t0 {
            o0 + (o1 - o0) * (t - t0) / (t1 - t0)
        } else {
            o1
        }
    }
}
