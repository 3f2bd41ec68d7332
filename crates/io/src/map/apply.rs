//! A channel map applied to a lab file: channels found by stream and name, converted to SI, interpolated onto the time-base stream, cut to the common span, markers turned into trial and level columns, EMG envelopes made at their native rate.

use super::{nearest_hint, ChannelMap, ColumnRule, Quantity, TimeSpec, ENVELOPE_HZ};
use crate::sources::{Marker, Source, Stream};
use limpid_core::{Recording, Result};
use std::borrow::Cow;
use std::collections::BTreeMap;

/// The stream called `name`, or an error naming the nearest streams.
pub(crate) fn named_stream<'a>(source: &'a Source, name: &str, what: &str) -> Result<&'a Stream> {
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
pub(crate) struct Found<'a> {
    pub(crate) stream: &'a Stream,
    pub(crate) values: &'a [f64],
    pub(crate) declared_unit: Option<&'a str>,
}

pub(crate) fn find_channel<'a>(
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
            let aliased = s
                .aliases
                .iter()
                .filter(|(a, _)| a == channel)
                .filter_map(|(_, k)| s.channels.get(*k));
            s.channels
                .iter()
                .filter(|c| c.name == channel)
                .chain(aliased)
                .map(move |c| (*s, c))
        })
        .collect();
    // a bag topic that was not read holds the channel by its prefix
    let unread = source.unread.iter().find(|(p, _)| {
        p == channel
            || (p.starts_with('/')
                && channel
                    .strip_prefix(p.as_str())
                    .is_some_and(|rest| rest.starts_with('.')))
    });
    match hits.as_slice() {
        [(s, c)] => Ok(Found {
            stream: s,
            values: &c.values,
            declared_unit: c.unit.as_deref(),
        }),
        [] if unread.is_some() => {
            // present but not a vector: say what it is (issue 56)
            let why = unread.map_or("", |(_, w)| w.as_str());
            Err(source.error(format!(
                "map column {column}: {why}; a column needs a numeric vector"
            )))
        }
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
pub(crate) fn interpolate(stamps: &[f64], values: &[f64], at: &[f64]) -> Vec<f64> {
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
            increment: map.time.increment.clone(),
        },
        columns: kept,
        // rules of streams this file lacks do not apply to it
        streams: map
            .streams
            .iter()
            .filter(|(name, _)| source.streams.iter().any(|s| &s.name == *name))
            .map(|(n, r)| (n.clone(), r.clone()))
            .collect(),
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
    let adjusted = stream_rules(source, map, &mut notes)?;
    let source: &Source = &adjusted;
    let map_name = map
        .path
        .as_ref()
        .map(|p| format!("map {}", p.display()))
        .unwrap_or_else(|| "the implicit map".into());
    // the time base
    let rules: Vec<(&String, ColumnRule)> =
        map.columns.iter().map(|(c, s)| (c, s.rule())).collect();
    refuse_shared_channels(source, &rules, &map_name)?;
    let (base, base_time) = time_base(source, map, &rules, &map_name)?;
    let n = base.len();
    let (first, last, used) = common_span(source, &rules, base, &base_time, &map_name)?;
    if first > 0 || last < n {
        notes.push(format!(
            "{} samples of {} outside the span of the other streams were left out ({} at the start, {} at the end)",
            first + (n - last),
            base.label(),
            first,
            n - last
        ));
    }
    let t_span = &base_time[first..last];
    notes.extend(used.iter().filter_map(|s| gap_note(s)));
    // columns
    let mut names = Vec::new();
    let mut columns: Vec<Vec<f64>> = Vec::new();
    let mut before_markers = 0usize;
    for (column, r) in &rules {
        let values: Vec<f64> = if let Some(ch) = &r.channel {
            let base_span = (&base_time[..], first..last);
            channel_column(source, (column, ch, r), base, base_span, &mut notes)?
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
    let (names, columns) = in_format_order(names, columns);
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

/// Two columns read from one channel (issue 56: `q1` and `tau1` from the
/// same channel fitted with a VAF of 100 % and a "trusted" inertia; the same
/// columns named by flag are refused). An EMG envelope (`env_...`) may share
/// its raw channel with the EMG column.
fn refuse_shared_channels(
    source: &Source,
    rules: &[(&String, ColumnRule)],
    map_name: &str,
) -> Result<()> {
    let mut read: Vec<(&str, *const f64)> = Vec::new();
    for (column, r) in rules {
        let Some(ch) = &r.channel else { continue };
        if column.starts_with("env_") {
            continue;
        }
        // a channel the file lacks is reported where it is read
        let Ok(found) = find_channel(source, column, ch, r.stream.as_deref()) else {
            continue;
        };
        if found.values.is_empty() {
            // said as it is, not as streams that "do not overlap" from -inf to inf (issue 56)
            return Err(source.error(format!(
                "map column {column}: channel {ch:?} of {} holds no samples",
                found.stream.label()
            )));
        }
        let id = found.values.as_ptr();
        if let Some((other, _)) = read.iter().find(|(_, p)| *p == id) {
            return Err(source.error(format!(
                "{map_name}: columns {other} and {column} both read channel {ch:?}; each column needs its own channel"
            )));
        }
        read.push((column.as_str(), id));
    }
    Ok(())
}

/// The stream that sets the time base, and its times: a mapped `t`
/// channel, the stream's stamps, or samples at `[time] rate`.
fn time_base<'s>(
    source: &'s Source,
    map: &ChannelMap,
    rules: &[(&String, ColumnRule)],
    map_name: &str,
) -> Result<(&'s Stream, Vec<f64>)> {
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
    } else if let [only] = source
        .streams
        .iter()
        .filter(|s| !s.channels.is_empty())
        .collect::<Vec<_>>()
        .as_slice()
    {
        // one numeric stream beside marker streams sets the time
        only
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
    if time_rule.is_some() {
        if let Some(rate) = map.time.rate {
            return Err(source.error(format!(
                "{map_name}: both a t column and [time] rate = {} Hz give the time; keep one",
                limpid_core::error::Num(rate)
            )));
        }
    }
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
        (0..base.len()).map(|i| i as f64 / rate).collect()
    } else if let Some(name) = &map.time.increment {
        let step = scalar_increment(source, name, map_name)?;
        (0..base.len()).map(|i| i as f64 * step).collect()
    } else {
        return Err(source.error(format!(
            "{map_name}: {} has no time stamps; map a t column (t = {{ channel = \"...\", unit = \"s\" }}) or give [time] rate = <Hz> (or increment = \"<a scalar of the file, in s>\")",
            base.label()
        )));
    };
    Ok((base, base_time))
}

/// The sampling interval (s) a map's `[time] increment` names: a real
/// scalar of the file, above 0 and finite.
fn scalar_increment(source: &Source, name: &str, map_name: &str) -> Result<f64> {
    let found = source.scalars.iter().find(|(p, _)| p == name);
    match found {
        Some((_, v)) if v.is_finite() && *v > 0.0 && *v <= 1e6 => Ok(*v),
        Some((_, v)) => Err(source.error(format!(
            "{map_name}: [time] increment = {name:?} is {}, not a sampling interval in seconds",
            limpid_core::error::Num(*v)
        ))),
        None => {
            let names: Vec<&str> = source.scalars.iter().map(|(p, _)| p.as_str()).collect();
            Err(source.error(format!(
                "{map_name}: [time] increment: no scalar {name:?} in the file{}",
                nearest_hint(name, &names)
            )))
        }
    }
}

/// The rows of the time base `first..last` that every other used stream
/// covers, and those streams (each once).
fn common_span<'s>(
    source: &'s Source,
    rules: &[(&String, ColumnRule)],
    base: &Stream,
    base_time: &[f64],
    map_name: &str,
) -> Result<(usize, usize, Vec<&'s Stream>)> {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    let mut used: Vec<&Stream> = Vec::new();
    for (column, r) in rules {
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
    Ok((first, last, used))
}

/// A note on a stream's drop-outs (its longest gap), when it has any.
fn gap_note(s: &Stream) -> Option<String> {
    let gaps = s.gaps();
    if gaps.is_empty() {
        return None;
    }
    let stamps = s.stamps.as_ref().expect("used streams have stamps");
    let longest = gaps.iter().map(|g| g.1).fold(0.0, f64::max);
    let (i, _) = gaps
        .iter()
        .copied()
        .find(|g| g.1 == longest)
        .expect("a gap");
    Some(format!(
        "{} has {} gap(s) (drop-outs), the longest {:.4} s before sample {} (t = {:.4} s); the time base is interpolated across them",
        s.label(),
        gaps.len(),
        longest,
        i + 1,
        stamps[i]
    ))
}

/// A mapped channel's values on the time base's rows `first..last`:
/// converted to SI, made an envelope (`env_*`), and interpolated from its
/// own stream's stamps when it is not the time base's.
fn channel_column(
    source: &Source,
    (column, ch, r): (&str, &str, &ColumnRule),
    base: &Stream,
    (base_time, span): (&[f64], std::ops::Range<usize>),
    notes: &mut Vec<String>,
) -> Result<Vec<f64>> {
    let (first, last) = (span.start, span.end);
    let t_span = &base_time[first..last];
    let found = find_channel(source, column, ch, r.stream.as_deref())?;
    if found.values.len() != found.stream.len() {
        return Err(source.error(format!(
            "{} channel {ch:?}: {} values for {} samples",
            found.stream.label(),
            found.values.len(),
            found.stream.len()
        )));
    }
    if column == "t" {
        Ok(base_time[first..last].to_vec())
    } else {
        let mut v = convert(source, column, r, &found)?;
        if column.starts_with("env_") {
            v = envelope(source, column, r, &found, v)?;
        }
        if std::ptr::eq(found.stream, base) {
            Ok(v[first..last].to_vec())
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
            Ok(interpolate(stamps, &v, t_span))
        }
    }
}

/// Columns sorted as FORMAT.md lists them (then by name).
fn in_format_order(names: Vec<String>, columns: Vec<Vec<f64>>) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut order: Vec<usize> = (0..names.len()).collect();
    order.sort_by_key(|&i| (column_rank(&names[i]), names[i].clone()));
    let names: Vec<String> = order.iter().map(|&i| names[i].clone()).collect();
    let mut slots: Vec<Option<Vec<f64>>> = columns.into_iter().map(Some).collect();
    let columns: Vec<Vec<f64>> = order
        .iter()
        .map(|&i| slots[i].take().expect("each once"))
        .collect();
    (names, columns)
}

/// Where a column goes in a converted table: FORMAT.md's order (time,
/// end-point, joints, inputs, robot, labels, EMG), then the rest by name.
pub(crate) fn column_rank(name: &str) -> usize {
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
pub(crate) fn gap_in_base(
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
    let new_trial = |i: usize| trial.is_some_and(|tr| tr[i] != tr[i - 1]);
    if let Some(i) = (1..t.len()).find(|&i| t[i] == t[i - 1] && !new_trial(i)) {
        let repeated = (1..t.len()).filter(|&i| t[i] == t[i - 1]).count();
        return Err(source.error(format!(
            "{}, sample {} of the recording (t = {:.6} s): {repeated} samples carry the time stamp of the sample before them (duplicated stamps: messages stored twice, or a clock too coarse for the rate); limpid does not order samples with one stamp",
            base.label(),
            i + 1,
            t[i],
        )));
    }
    for i in 1..t.len() {
        let gap = t[i] - t[i - 1];
        let new_trial = new_trial(i);
        if gap > 1.5 * step && !new_trial {
            // messages the reader left out (an undeclared topic id) are the
            // likely cause: said with the gap, not lost behind it
            let left_out: Vec<&str> = source
                .notes
                .iter()
                .filter(|n| n.contains("left out"))
                .map(String::as_str)
                .collect();
            return Err(source.error(format!(
                "{}, sample {} of the recording (t = {:.6} s): a gap of {:.6} s where samples come every {:.6} s (dropped samples in the time-base stream); limpid does not interpolate the time base{}",
                base.label(),
                i + 1,
                t[i],
                gap,
                step,
                if left_out.is_empty() {
                    String::new()
                } else {
                    format!(" (the reader left messages out: {})", left_out.join("; "))
                }
            )));
        }
    }
    Ok(())
}

/// The values of a channel in SI, scaled and offset; non-finite samples refused.
pub(crate) fn convert(
    source: &Source,
    column: &str,
    r: &ColumnRule,
    found: &Found,
) -> Result<Vec<f64>> {
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
pub(crate) fn envelope(
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
pub(crate) fn markers_for(source: &Source, column: &str, r: &ColumnRule) -> Result<Vec<Marker>> {
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
pub(crate) fn marker_column(
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

/// The map's `[streams]` rules applied: a bag topic's log times in place of
/// its header stamps (`clock = "log"`), stamps replaced by their piecewise
/// straight-line fit (`dejitter`).
fn stream_rules<'s>(
    source: &'s Source,
    map: &ChannelMap,
    notes: &mut Vec<String>,
) -> Result<Cow<'s, Source>> {
    if map.streams.is_empty() {
        return Ok(Cow::Borrowed(source));
    }
    let mut adjusted = source.clone();
    for (name, rule) in &map.streams {
        named_stream(source, name, &format!("[streams.{name:?}]"))?;
        let s = adjusted
            .streams
            .iter_mut()
            .find(|s| &s.name == name)
            .expect("found above");
        if rule.clock.as_deref() == Some("log") {
            let log = s.log_stamps.take().ok_or_else(|| {
                source.error(format!(
                    "[streams.{name:?}] clock = \"log\": the stream has one clock only{}",
                    s.clock
                        .as_ref()
                        .map(|c| format!(" ({c})"))
                        .unwrap_or_default()
                ))
            })?;
            s.stamps = Some(log);
            s.clock = Some("log time".into());
        }
        if rule.dejitter {
            let stamps = s.stamps.as_mut().ok_or_else(|| {
                source.error(format!(
                    "[streams.{name:?}] dejitter: the stream has no stamps to fit"
                ))
            })?;
            let (pieces, rms) = dejitter(stamps);
            notes.push(format!(
                "{}: stamps replaced by a line fit in {pieces} piece(s) (they scattered by {} ms rms about it)",
                s.label(),
                limpid_core::error::significant(rms * 1e3, 3)
            ));
        }
    }
    Ok(Cow::Owned(adjusted))
}

/// Replace `stamps` by least-squares lines of stamp against sample index,
/// one per piece between breaks: an interval longer than 1 s and 500
/// median intervals, or a backward jump. Returns the pieces and the rms
/// of the stamps about the lines (s).
pub(crate) fn dejitter(stamps: &mut [f64]) -> (usize, f64) {
    let n = stamps.len();
    if n < 3 {
        return (1, 0.0);
    }
    let mut intervals: Vec<f64> = stamps.windows(2).map(|w| w[1] - w[0]).collect();
    let mid = intervals.len() / 2;
    let median = *intervals.select_nth_unstable_by(mid, f64::total_cmp).1;
    let limit = (500.0 * median).max(1.0);
    let mut starts = vec![0];
    for i in 1..n {
        let d = stamps[i] - stamps[i - 1];
        if d > limit || d < 0.0 {
            starts.push(i);
        }
    }
    starts.push(n);
    let mut square = 0.0;
    for w in starts.windows(2) {
        let piece = &mut stamps[w[0]..w[1]];
        let m = piece.len() as f64;
        if piece.len() < 2 {
            continue;
        }
        // centred sums: the stamps may be large (a wall clock)
        let i_mean = (m - 1.0) / 2.0;
        let t0 = piece[0];
        let t_mean = piece.iter().map(|t| t - t0).sum::<f64>() / m;
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for (i, t) in piece.iter().enumerate() {
            let di = i as f64 - i_mean;
            sxy += di * (t - t0 - t_mean);
            sxx += di * di;
        }
        let slope = sxy / sxx;
        for (i, t) in piece.iter_mut().enumerate() {
            let fit = t0 + t_mean + slope * (i as f64 - i_mean);
            square += (*t - fit).powi(2);
            *t = fit;
        }
    }
    (starts.len() - 1, (square / n as f64).sqrt())
}
