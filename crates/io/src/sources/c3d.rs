//! C3D motion-capture files (c3d.org), read with the `c3dio` crate.
//!
//! Two streams: `points` (each marker `<POINT:LABEL>` as channels
//! `<label>.X`, `.Y`, `.Z` at the point rate, unit from `POINT:UNITS`) and
//! `analog` (each `ANALOG:LABELS` channel, labels trimmed, at the analog
//! rate, values (raw - OFFSET) x SCALE x GEN_SCALE as the format defines,
//! unit from `ANALOG:UNITS`). Both streams start at the first frame,
//! t = (frame - 1) / rate. A point whose residual is negative (the
//! format's "invalid") is NaN, so a map that uses it is refused at that
//! sample rather than fed the zeros the file holds there.
//!
//! Bounds: the file is read whole up to [`MAX_C3D_BYTES`]; before the crate
//! sees it, limpid reads the header and parameter sizes itself (points,
//! ANALOG:USED, samples per frame, frames) and refuses a file whose declared
//! data is not all there (cut short, or a corrupt size the crate would
//! allocate from); a panic inside the crate is an error naming the file.

use std::path::Path;

use super::{Channel, Source, Stream};
use limpid_core::Result;

/// Largest C3D file read (bytes).
pub const MAX_C3D_BYTES: u64 = 2 << 30;

/// Read a C3D file.
pub fn read(path: &Path) -> Result<Source> {
    let bytes = limpid_core::files::read_bytes(path, MAX_C3D_BYTES)?;
    read_bytes(path, &bytes)
}

/// How the file's numbers are stored (C3D processor types 84, 85, 86).
#[derive(Clone, Copy, PartialEq)]
enum Processor {
    Intel,
    Dec,
    Mips,
}

impl Processor {
    fn u16(self, b: [u8; 2]) -> u16 {
        match self {
            Processor::Mips => u16::from_be_bytes(b),
            _ => u16::from_le_bytes(b),
        }
    }

    /// A 4-byte float: IEEE in either byte order, or DEC's VAX F (words
    /// swapped, exponent biased by 2 more).
    fn f32(self, b: [u8; 4]) -> f32 {
        match self {
            Processor::Intel => f32::from_le_bytes(b),
            Processor::Mips => f32::from_be_bytes(b),
            Processor::Dec => f32::from_le_bytes([b[2], b[3], b[0], b[1]]) / 4.0,
        }
    }
}

/// The sizes a C3D file declares, read from its header and parameter
/// section by limpid itself: the decoder sizes its grids from them before
/// comparing them with the data (issue 56: ANALOG:USED = 32767 asked for
/// 6.7 GB, a header's analog samples per channel of 65535 for 18.8 GB).
#[derive(Debug, Default)]
struct Layout {
    /// POINT:USED (the header's count when absent).
    points: usize,
    /// ANALOG:USED.
    analog_used: usize,
    /// The header's analog samples per frame, all channels together.
    analog_per_frame: usize,
    /// The header's analog samples per channel per frame.
    analog_per_channel: usize,
    /// Frames, by the decoder's own rule (POINT:FRAMES, TRIAL:ACTUAL_*_FIELD, POINT:LONG_FRAMES).
    frames: usize,
    /// Bytes per value: 4 (float, negative scale) or 2 (integer).
    value_bytes: usize,
    /// Bytes of data after the data start.
    data_bytes: usize,
    /// POINT:RATE, when the file has it.
    point_rate: Option<f64>,
    /// The header's point count (word 2) and frame rate (words 11-12).
    header_points: usize,
    header_rate: f64,
}

/// One parameter's values: integers (as read, 16-bit), floats, or bytes.
enum ParameterValues {
    Integers(Vec<u16>),
    Floats(Vec<f32>),
    Other,
}

/// The parameters limpid needs, `GROUP:NAME` -> values; every length and
/// offset checked against the section.
fn read_parameters(
    bytes: &[u8],
    processor: Processor,
) -> std::result::Result<std::collections::HashMap<String, ParameterValues>, String> {
    let start = (usize::from(bytes[0]).max(1) - 1) * 512;
    let mut groups: std::collections::HashMap<i8, String> = std::collections::HashMap::new();
    let mut records: Vec<(i8, String, ParameterValues)> = Vec::new();
    let mut at = start + 4;
    // a record is at least 5 bytes: the walk ends within the file
    while at + 2 <= bytes.len() {
        let name_len = usize::from((bytes[at] as i8).unsigned_abs());
        let id = bytes[at + 1] as i8;
        if name_len == 0 || id == 0 {
            break;
        }
        let name_end = at + 2 + name_len;
        let Some(name) = bytes.get(at + 2..name_end) else {
            break;
        };
        let name = String::from_utf8_lossy(name).trim().to_uppercase();
        let Some(next) = bytes.get(name_end..name_end + 2) else {
            break;
        };
        let next = usize::from(processor.u16([next[0], next[1]]));
        if id < 0 {
            groups.insert(-id, name);
        } else {
            // a parameter's values lie inside its record: one that claims more
            // is corrupt, and the decoder's own parser ran for minutes and
            // gigabytes on such records (fuzzer, issue 56)
            let name = groups
                .get(&id)
                .map_or_else(|| name.clone(), |g| format!("{g}:{name}"));
            let values_end = parameter_end(bytes, name_end + 2)
                .ok_or_else(|| format!("parameter {name} runs past the end of the file"))?;
            if next != 0 && values_end > name_end + next {
                return Err(format!(
                    "parameter {name} declares {} bytes of values, more than its record holds ({} bytes): corrupt parameter section",
                    values_end - (name_end + 2),
                    next.saturating_sub(2)
                ));
            }
            if let Some(values) = parameter_values(bytes, name_end + 2, processor) {
                records.push((id, name, values));
            }
        }
        if next == 0 {
            break;
        }
        at = name_end + next;
    }
    // names carry their group where it came first (as it does in every writer's files)
    Ok(records
        .into_iter()
        .filter_map(|(id, name, v)| {
            if name.contains(':') {
                Some((name, v))
            } else {
                groups.get(&id).map(|g| (format!("{g}:{name}"), v))
            }
        })
        .collect())
}

/// Where a parameter's values and description end, from its type byte at
/// `at`, or None when they run past the file.
fn parameter_end(bytes: &[u8], at: usize) -> Option<usize> {
    let kind = (*bytes.get(at)? as i8).unsigned_abs() as usize;
    let dims = usize::from(*bytes.get(at + 1)?);
    let shape = bytes.get(at + 2..at + 2 + dims)?;
    let count: usize = shape.iter().map(|&d| usize::from(d)).product();
    let description = at + 2 + dims + count * kind;
    let length = usize::from(*bytes.get(description)?);
    let end = description + 1 + length;
    (end <= bytes.len()).then_some(end)
}

/// A parameter's values at `at` (its type byte), or None when they run past the file.
fn parameter_values(bytes: &[u8], at: usize, processor: Processor) -> Option<ParameterValues> {
    let kind = *bytes.get(at)? as i8;
    let dims = usize::from(*bytes.get(at + 1)?);
    let shape = bytes.get(at + 2..at + 2 + dims)?;
    let count: usize = shape.iter().map(|&d| usize::from(d)).product();
    let data = at + 2 + dims;
    Some(match kind {
        2 => {
            let raw = bytes.get(data..data + 2 * count)?;
            ParameterValues::Integers(
                raw.chunks_exact(2)
                    .map(|c| processor.u16([c[0], c[1]]))
                    .collect(),
            )
        }
        4 => {
            let raw = bytes.get(data..data + 4 * count)?;
            ParameterValues::Floats(
                raw.chunks_exact(4)
                    .map(|c| processor.f32([c[0], c[1], c[2], c[3]]))
                    .collect(),
            )
        }
        _ => ParameterValues::Other,
    })
}

impl ParameterValues {
    /// The first value as a count (a float truncated as the decoder does).
    fn first(&self) -> Option<usize> {
        match self {
            ParameterValues::Integers(v) => v.first().map(|&x| usize::from(x)),
            ParameterValues::Floats(v) => v
                .first()
                .filter(|x| x.is_finite() && **x >= 0.0)
                .map(|&x| x as usize),
            ParameterValues::Other => None,
        }
    }
}

/// The header's and parameters' sizes (see [`Layout`]).
fn layout(bytes: &[u8]) -> std::result::Result<Layout, String> {
    let param_block = usize::from(bytes[0]).max(1);
    let processor = match bytes.get((param_block - 1) * 512 + 3) {
        Some(85) => Processor::Dec,
        Some(86) => Processor::Mips,
        _ => Processor::Intel,
    };
    let word = |i: usize| usize::from(processor.u16([bytes[2 * i], bytes[2 * i + 1]]));
    let scale = processor.f32(bytes[12..16].try_into().expect("4 bytes"));
    let parameters = read_parameters(bytes, processor)?;
    let count = |key: &str| parameters.get(key).and_then(ParameterValues::first);
    // the decoder's rule: the header's range, replaced by POINT:FRAMES
    // (0 when absent), by TRIAL:ACTUAL_START/END_FIELD, by a larger POINT:LONG_FRAMES
    let header_frames = (word(4) + 1).saturating_sub(word(3));
    let mut frames = header_frames;
    let point_frames = count("POINT:FRAMES").unwrap_or(0);
    if frames != point_frames {
        frames = point_frames;
    }
    let field = |key: &str| match parameters.get(key) {
        Some(ParameterValues::Integers(v)) if v.len() == 2 => {
            Some(usize::from(v[0]) + usize::from(v[1]) * 65536)
        }
        _ => None,
    };
    if let (Some(a), Some(b)) = (
        field("TRIAL:ACTUAL_START_FIELD"),
        field("TRIAL:ACTUAL_END_FIELD"),
    ) {
        if b >= a {
            frames = b - a + 1;
        }
    }
    if let Some(long) = count("POINT:LONG_FRAMES") {
        frames = frames.max(long);
    }
    let data_start = word(8).max(1);
    let point_rate = match parameters.get("POINT:RATE") {
        Some(ParameterValues::Floats(v)) => v.first().map(|&r| f64::from(r)),
        _ => None,
    };
    Ok(Layout {
        points: count("POINT:USED").unwrap_or(word(1)),
        analog_used: count("ANALOG:USED").unwrap_or(0),
        analog_per_frame: word(2),
        analog_per_channel: word(9),
        frames,
        value_bytes: if scale < 0.0 { 4 } else { 2 },
        data_bytes: bytes.len().saturating_sub((data_start - 1) * 512),
        point_rate,
        header_points: word(1),
        header_rate: f64::from(processor.f32(bytes[20..24].try_into().expect("4 bytes"))),
    })
}

/// Every size the file declares against the data it holds, before the
/// decoder allocates from them; a file cut short is refused, naming how
/// much of it is there (the decoder would read the frames present in silence).
fn check_layout(bytes: &[u8]) -> std::result::Result<(), String> {
    let l = layout(bytes)?;
    // the decoder sizes its point grid by the header's count (65535 for 3
    // asked for 7.9 GB; issue 76): both counts must agree
    if l.header_points != l.points {
        return Err(format!(
            "the header declares {} points but POINT:USED is {} (corrupt header or parameters?)",
            l.header_points, l.points
        ));
    }
    if let Some(rate) = l.point_rate {
        let agree = (l.header_rate - rate).abs() <= 1e-3 * rate.abs().max(1.0);
        if l.points > 0 && rate.is_finite() && l.header_rate.is_finite() && !agree {
            return Err(format!(
                "the header's frame rate {} Hz disagrees with POINT:RATE {} Hz (corrupt header or parameters?)",
                limpid_core::error::Num(l.header_rate),
                limpid_core::error::Num(rate)
            ));
        }
    }
    let channel_samples = l.analog_used.saturating_mul(l.analog_per_channel);
    if l.analog_used > 0 && channel_samples != l.analog_per_frame {
        return Err(format!(
            "ANALOG:USED ({}) x the header's analog samples per channel per frame ({}) disagrees with its analog samples per frame ({}) (corrupt header or parameters?)",
            l.analog_used, l.analog_per_channel, l.analog_per_frame
        ));
    }
    let frame = (l
        .points
        .saturating_mul(4)
        .saturating_add(l.analog_per_frame))
    .saturating_mul(l.value_bytes);
    if frame == 0 {
        // frames of nothing: the decoder would loop over a declared count
        // (up to 2^32 with POINT:LONG_FRAMES) without reading a byte
        return Err(format!(
            "the header and parameters declare {} frames but no point and no analog channel (POINT:USED {}, {} analog samples per frame)",
            l.frames, l.points, l.analog_per_frame
        ));
    }
    if frame > l.data_bytes {
        return Err(format!(
            "the header declares frames of {frame} bytes ({} points, {} analog samples each), more than the {} bytes of data in the file (corrupt header?)",
            l.points, l.analog_per_frame, l.data_bytes
        ));
    }
    let declared = l.frames.saturating_mul(frame);
    if declared > l.data_bytes {
        let present = l.data_bytes.checked_div(frame).unwrap_or(0);
        let seconds = |n: usize| match l.point_rate.filter(|r| r.is_finite() && *r > 0.0) {
            Some(r) => format!(" ({} s)", limpid_core::error::significant(n as f64 / r, 4)),
            None => String::new(),
        };
        return Err(format!(
            "cut short: it declares {} frames{} but holds data for {present}{}; the file is incomplete",
            l.frames,
            seconds(l.frames),
            seconds(present)
        ));
    }
    Ok(())
}

/// Read C3D bytes; `path` names the file in errors.
pub fn read_bytes(path: &Path, bytes: &[u8]) -> Result<Source> {
    let fail = super::format_error(path);
    if bytes.is_empty() {
        return Err(super::empty_lab_file(path, "C3D"));
    }
    if bytes.len() < 512 || bytes[1] != 0x50 {
        return Err(fail(
            "not a C3D file: the header's second byte is not 0x50 (the C3D key)".into(),
        ));
    }
    check_layout(bytes).map_err(fail)?;
    let c3d = limpid_core::error::catch_panic(path, "C3D decoder (corrupt file)", || {
        c3dio::C3d::from_bytes(bytes).map_err(|e| fail(format!("not a readable C3D file: {e}")))
    })?;
    let mut streams = Vec::new();
    let (point_stream, start_s) = point_stream(&c3d.points).map_err(fail)?;
    streams.extend(point_stream);
    streams.extend(analog_stream(&c3d.analog, start_s).map_err(fail)?);
    if streams.is_empty() {
        return Err(fail(
            "the C3D file holds no point and no analog sample".into(),
        ));
    }
    Ok(Source {
        path: path.to_path_buf(),
        format: "C3D",
        streams,
        notes: Vec::new(),
        unread: Vec::new(),
        scalars: Vec::new(),
    })
}

/// The markers' X, Y, Z (a negative residual: not seen, NaN) at POINT:RATE
/// from the first frame, when there are any; and the time of the first
/// frame (s), where the analog stream starts too.
fn point_stream(
    points: &c3dio::points::Points,
) -> std::result::Result<(Option<Stream>, f64), String> {
    let (frames, markers) = (points.rows(), points.cols());
    let point_rate = f64::from(points.frame_rate);
    let first_frame = f64::from(points.first_frame.max(1)) - 1.0;
    let start_s = if point_rate > 0.0 {
        first_frame / point_rate
    } else {
        0.0
    };
    if markers == 0 || frames == 0 {
        return Ok((None, start_s));
    }
    {
        if !(point_rate.is_finite() && point_rate > 0.0) {
            return Err(format!(
                "POINT:RATE is {point_rate}: the point stream has no sample rate"
            ));
        }
        let unit: String = points
            .units
            .iter()
            .collect::<String>()
            .trim()
            .trim_matches('\0')
            .to_string();
        let mut channels = Vec::with_capacity(3 * markers);
        for m in 0..markers {
            let label = points
                .labels
                .get(m)
                .map(|l| l.trim().to_string())
                .filter(|l| !l.is_empty())
                .unwrap_or_else(|| format!("point{}", m + 1));
            for (axis, name) in ["X", "Y", "Z"].iter().enumerate() {
                let values = (0..frames)
                    .map(|f| {
                        let p = &points.points[(f, m)];
                        if p.residual < 0.0 {
                            f64::NAN
                        } else {
                            f64::from(p.point[axis])
                        }
                    })
                    .collect();
                channels.push(Channel {
                    name: format!("{label}.{name}"),
                    unit: (!unit.is_empty()).then(|| unit.clone()),
                    values,
                });
            }
        }
        Ok((
            Some(Stream {
                name: "points".into(),
                kind: Some("Points".into()),
                nominal_rate: Some(point_rate),
                stamps: Some(
                    (0..frames)
                        .map(|f| (first_frame + f as f64) / point_rate)
                        .collect(),
                ),
                channels,
                ..Stream::default()
            }),
            start_s,
        ))
    }
}

/// The analog channels at ANALOG:RATE from `start_s`, when there are any.
fn analog_stream(
    analog: &c3dio::Analog,
    start_s: f64,
) -> std::result::Result<Option<Stream>, String> {
    let (samples, used) = (analog.analog.rows(), analog.analog.cols());
    if used == 0 || samples == 0 {
        return Ok(None);
    }
    {
        let rate = f64::from(analog.rate);
        if !(rate.is_finite() && rate > 0.0) {
            return Err(format!(
                "ANALOG:RATE is {rate}: the analog stream has no sample rate"
            ));
        }
        let channels = (0..used)
            .map(|k| Channel {
                name: analog
                    .labels
                    .get(k)
                    .map(|l| l.trim().to_string())
                    .filter(|l| !l.is_empty())
                    .unwrap_or_else(|| format!("analog{}", k + 1)),
                unit: analog
                    .units
                    .get(k)
                    .map(|u| u.trim().to_string())
                    .filter(|u| !u.is_empty()),
                values: (0..samples).map(|i| analog.analog[(i, k)]).collect(),
            })
            .collect();
        Ok(Some(Stream {
            name: "analog".into(),
            kind: Some("Analog".into()),
            nominal_rate: Some(rate),
            stamps: Some((0..samples).map(|i| start_s + i as f64 / rate).collect()),
            channels,
            ..Stream::default()
        }))
    }
}
