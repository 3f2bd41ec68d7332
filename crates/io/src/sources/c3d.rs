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
//! Bounds: the file is read whole up to [`MAX_C3D_BYTES`]; the crate's
//! frame count is capped by the data present; a panic inside the crate (a
//! header that disagrees with its data) is an error naming the file.

use std::path::Path;

use super::{Channel, Source, Stream};
use limpid_core::{Error, Result};

/// Largest C3D file read (bytes).
pub const MAX_C3D_BYTES: u64 = 2 << 30;

/// Read a C3D file.
pub fn read(path: &Path) -> Result<Source> {
    let bytes = limpid_core::files::read_bytes(path, MAX_C3D_BYTES)?;
    read_bytes(path, &bytes)
}

/// The header's frame layout against the data the file holds, before the
/// crate allocates its grids from the declared sizes (a corrupt header once
/// made it fault in gigabytes): points x 4 values + analog samples per frame,
/// 2 bytes each (integer format) or 4 (float, negative scale).
fn check_frame_size(bytes: &[u8]) -> std::result::Result<(), String> {
    let param_block = usize::from(bytes[0]).max(1);
    // processor type: byte 3 of the parameter section, 83 + (1 Intel, 2 DEC, 3 MIPS)
    let big_endian = bytes.get((param_block - 1) * 512 + 3) == Some(&86);
    let word = |i: usize| {
        let b = [bytes[2 * i], bytes[2 * i + 1]];
        usize::from(if big_endian {
            u16::from_be_bytes(b)
        } else {
            u16::from_le_bytes(b)
        })
    };
    let (points, analog) = (word(1), word(2));
    let (first, last) = (word(3), word(4));
    let scale_bytes: [u8; 4] = bytes[12..16].try_into().expect("4 bytes");
    let scale = if big_endian {
        f32::from_be_bytes(scale_bytes)
    } else {
        f32::from_le_bytes(scale_bytes)
    };
    let value_bytes = if scale < 0.0 { 4 } else { 2 };
    let data_start = word(8).max(1);
    let data_bytes = bytes.len().saturating_sub((data_start - 1) * 512);
    let frame = (points * 4 + analog) * value_bytes;
    if frame > data_bytes {
        return Err(format!(
            "the header declares frames of {frame} bytes ({points} points, {analog} analog samples each), more than the {data_bytes} bytes of data in the file (corrupt header?)"
        ));
    }
    if last >= first && frame > 0 {
        let frames = last - first + 1;
        if frames.saturating_mul(frame) > data_bytes.saturating_mul(2) + (1 << 20) {
            // a long recording keeps its frame count in POINT:FRAMES; the crate caps
            // the count by the data, but not before an analog grid is sized from it
            return Err(format!(
                "the header declares {frames} frames of {frame} bytes, far more than the {data_bytes} bytes of data in the file (corrupt header?)"
            ));
        }
    }
    Ok(())
}

/// Read C3D bytes; `path` names the file in errors.
pub fn read_bytes(path: &Path, bytes: &[u8]) -> Result<Source> {
    let fail = super::format_error(path);
    if bytes.is_empty() {
        return Err(Error::Empty {
            path: path.to_path_buf(),
        });
    }
    if bytes.len() < 512 || bytes[1] != 0x50 {
        return Err(fail(
            "not a C3D file: the header's second byte is not 0x50 (the C3D key)".into(),
        ));
    }
    check_frame_size(bytes).map_err(fail)?;
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
