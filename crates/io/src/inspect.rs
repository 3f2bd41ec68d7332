//! What is in a lab file: streams, channels, rates, units, gaps, markers,
//! and a proposed channel map where names are recognisable (`limpid inspect`).

use serde::Serialize;

use crate::sources::{Source, Stream};

/// A file's content, for people and for `--json`.
#[derive(Debug, Clone, Serialize)]
pub struct Inspection {
    /// The file.
    pub file: String,
    /// Its format.
    pub format: &'static str,
    /// Its streams.
    pub streams: Vec<StreamSummary>,
    /// What the reader noticed.
    pub notes: Vec<String>,
    /// A channel map for the channels whose names say what they are (TOML),
    /// if any; to be checked and completed by the user.
    pub proposed_map: Option<String>,
}

/// One stream's summary.
#[derive(Debug, Clone, Serialize)]
pub struct StreamSummary {
    /// Name.
    pub name: String,
    /// Declared type.
    pub kind: Option<String>,
    /// Samples (numeric or text).
    pub samples: usize,
    /// Declared rate (Hz).
    pub nominal_rate_hz: Option<f64>,
    /// Rate from the stamps: (samples - 1) / duration (Hz).
    pub effective_rate_hz: Option<f64>,
    /// First stamp (s).
    pub start_s: Option<f64>,
    /// Last minus first stamp (s).
    pub duration_s: Option<f64>,
    /// Intervals longer than 1.5 sampling intervals.
    pub gaps: usize,
    /// The longest of them (s).
    pub longest_gap_s: Option<f64>,
    /// Clock-offset records applied.
    pub clock_offsets: usize,
    /// Where the stamps come from when the file offers a choice (a bag
    /// topic's `header stamps` or `log time`).
    pub clock: Option<String>,
    /// Numeric channels.
    pub channels: Vec<ChannelSummary>,
    /// Distinct marker texts with their counts.
    pub markers: Vec<MarkerCount>,
}

/// One channel's summary.
#[derive(Debug, Clone, Serialize)]
pub struct ChannelSummary {
    /// Name in the file.
    pub name: String,
    /// Declared unit.
    pub unit: Option<String>,
    /// Another name a map may use for it (a JointState element's index
    /// form, `/joint_states.position[0]` for `/joint_states.position[ankle]`).
    pub also: Option<String>,
    /// Smallest finite value.
    pub min: Option<f64>,
    /// Largest finite value.
    pub max: Option<f64>,
    /// Samples that are NaN or infinite.
    pub non_finite: usize,
}

/// A marker text and how often it occurs.
#[derive(Debug, Clone, Serialize)]
pub struct MarkerCount {
    /// The text.
    pub text: String,
    /// Occurrences.
    pub count: usize,
}

/// Summarise a source.
pub fn inspect(source: &Source) -> Inspection {
    let streams = source.streams.iter().map(summary).collect();
    Inspection {
        file: source.path.display().to_string(),
        format: source.format,
        streams,
        notes: source.notes.clone(),
        proposed_map: propose(source),
    }
}

fn summary(s: &Stream) -> StreamSummary {
    let stamps = s.stamps.as_deref().unwrap_or(&[]);
    let duration = (stamps.len() > 1).then(|| stamps[stamps.len() - 1] - stamps[0]);
    let gaps = if s.channels.is_empty() {
        Vec::new()
    } else {
        s.gaps()
    };
    let mut counts: std::collections::BTreeMap<&str, usize> = Default::default();
    for m in &s.markers {
        *counts.entry(m.text.as_str()).or_default() += 1;
    }
    StreamSummary {
        name: s.name.clone(),
        kind: s.kind.clone(),
        samples: s.len(),
        nominal_rate_hz: s.nominal_rate,
        effective_rate_hz: duration
            .filter(|d| *d > 0.0 && !s.channels.is_empty())
            .map(|d| (stamps.len() - 1) as f64 / d),
        start_s: stamps.first().copied(),
        duration_s: duration,
        gaps: gaps.len(),
        longest_gap_s: gaps.iter().map(|g| g.1).reduce(f64::max),
        clock_offsets: s.clock_offsets,
        clock: s.clock.clone(),
        channels: s
            .channels
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let finite = c.values.iter().filter(|v| v.is_finite());
                ChannelSummary {
                    name: c.name.clone(),
                    unit: c.unit.clone(),
                    also: s
                        .aliases
                        .iter()
                        .find(|(_, i)| *i == k)
                        .map(|(a, _)| a.clone()),
                    min: finite.clone().copied().reduce(f64::min),
                    max: finite.copied().reduce(f64::max),
                    non_finite: c.values.iter().filter(|v| !v.is_finite()).count(),
                }
            })
            .collect(),
        markers: counts
            .into_iter()
            .map(|(text, count)| MarkerCount {
                text: text.to_string(),
                count,
            })
            .collect(),
    }
}

/// A unit written as the last word of a channel's name (`time_ms`,
/// `angle_deg`, `torque_Nm`): the channel's name without it, and the unit
/// as a map spells it (None for the SI unit the format wants anyway).
fn unit_suffix(tokens: &[&str]) -> Option<(usize, Option<&'static str>)> {
    let (&last, rest) = tokens.split_last()?;
    if rest.is_empty() {
        return None;
    }
    let unit = match last {
        "s" | "sec" | "rad" | "m" | "n" | "nm" | "v" => None,
        "ms" | "msec" => Some("ms"),
        "us" => Some("us"),
        "deg" | "degree" | "degrees" => Some("deg"),
        "mrad" => Some("mrad"),
        "mm" => Some("mm"),
        "cm" => Some("cm"),
        "kn" => Some("kN"),
        "nmm" => Some("N mm"),
        "mv" => Some("mV"),
        "uv" => Some("uV"),
        _ => return None,
    };
    Some((rest.len(), unit))
}

/// The FORMAT.md column a channel's name suggests, if any, with the unit
/// its name declares (`time_ms` -> `t` in ms).
fn suggest(stream: &Stream, channel: &str) -> Option<(String, Option<&'static str>)> {
    let lower = channel.to_lowercase();
    let all: Vec<&str> = lower
        .split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|t| !t.is_empty())
        .collect();
    // a MAT struct's fields: the path before the last dot says little
    let all = match channel.rsplit_once('.') {
        Some((_, leaf)) if !leaf.is_empty() && stream.name.is_empty() => {
            let skip = all.len()
                - leaf
                    .to_lowercase()
                    .split(|c: char| !c.is_ascii_alphanumeric())
                    .filter(|t| !t.is_empty())
                    .count();
            all[skip..].to_vec()
        }
        _ => all,
    };
    let (tokens, unit) = match unit_suffix(&all) {
        Some((n, unit)) => (&all[..n], unit),
        None => (&all[..], None),
    };
    let column = suggest_name(stream, tokens)?;
    Some((column, unit))
}

fn suggest_name(stream: &Stream, tokens: &[&str]) -> Option<String> {
    let last = *tokens.last()?;
    let joined = tokens.join("_");
    let marker_axis = tokens.len() > 1 && matches!(last, "x" | "y" | "z");
    if limpid_core::recording::is_format_column(&joined)
        && !joined.starts_with("emg_")
        && !marker_axis
    {
        return Some(joined);
    }
    let context = format!(
        "{} {} {}",
        stream.name.to_lowercase(),
        stream.kind.clone().unwrap_or_default().to_lowercase(),
        tokens[..tokens.len() - 1].join(" ")
    );
    let has = |words: &[&str]| words.iter().any(|w| context.contains(w));
    if let Some(rest) = joined.strip_prefix("emg") {
        let rest = rest.trim_start_matches('_');
        return Some(if rest.is_empty() {
            "emg_1".into()
        } else {
            format!("emg_{rest}")
        });
    }
    if has(&["emg"]) {
        return Some(format!("emg_{last}"));
    }
    // a name that ends in its axis: EndEffX, HandY, ForceZ, FX
    if last.len() > 1 {
        let (stem, axis) = last.split_at(last.len() - 1);
        if matches!(axis, "x" | "y" | "z") {
            let position = ["pos", "endeff", "hand", "ee", "cart", "handle", "end"];
            if ["force", "f", "ft", "load"].contains(&stem) {
                return Some(format!("f{axis}"));
            }
            if position.iter().any(|w| stem.contains(w)) {
                return Some(axis.into());
            }
        }
    }
    // a single joint: its angle and torque (an ankle, an elbow)
    let joint_angle = ["angle", "ang", "theta", "joint", "q", "jointangle"];
    let joint_torque = ["torque", "tau", "moment", "trq", "tq"];
    if tokens.iter().any(|t| joint_torque.contains(t)) {
        return Some("tau1".into());
    }
    if tokens.iter().any(|t| joint_angle.contains(t)) && !has(&["velocity", "vel"]) {
        return Some("q1".into());
    }
    match last {
        "time" | "timestamp" | "t" | "times" if stream.stamps.is_none() => Some("t".into()),
        "trial" | "trialno" | "trialnumber" | "trialnum" => Some("trial".into()),
        "level" => Some("level".into()),
        "x" | "y" | "z" if has(&["force", "ft", "load"]) => Some(format!("f{last}")),
        "x" | "y" | "z"
            if has(&[
                "pos", "endeff", "end", "hand", "ee", "cart", "mocap", "handle",
            ]) =>
        {
            Some(last.into())
        }
        "fx" | "fy" | "fz" => Some(last.into()),
        _ => None,
    }
}

/// `text` as a TOML basic string: quotes and backslashes escaped, control
/// characters as `\uXXXX` (Rust's `{:?}` writes `\u{8}`, which TOML refuses).
fn quote(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => out.push_str(&format!("\\u{:04X}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A proposed map: the recognisable channels, their declared units (or the
/// unit their name ends in), the time base the stream holding most of them,
/// a trial rule when a marker stream exists, and the other channels as
/// comments to fill in. Saved as it is, it reads the file
/// (`limpid inspect FILE --map-template > rig.toml`).
pub fn propose(source: &Source) -> Option<String> {
    let mut lines: Vec<(String, String)> = Vec::new();
    let mut unknown: Vec<String> = Vec::new();
    let mut per_stream: Vec<(usize, &str)> = Vec::new();
    for s in &source.streams {
        let mut n = 0;
        for c in &s.channels {
            let mut fields = vec![format!("channel = {}", quote(&c.name))];
            if source.streams.len() > 1 {
                fields.push(format!("stream = {}", quote(&s.name)));
            }
            let guess = suggest(s, &c.name).filter(|(col, named_unit)| {
                if lines.iter().any(|(k, _)| k == col) {
                    return false;
                }
                // a declared unit of another quantity means the guess is wrong
                let declared = c.unit.as_deref().filter(|u| !u.trim().is_empty());
                declared
                    .or(*named_unit)
                    .is_none_or(|u| crate::map::unit_factor(col, u).is_ok())
            });
            match guess {
                Some((col, named_unit)) => {
                    n += 1;
                    if let Some(u) = c.unit.as_deref().filter(|u| !u.trim().is_empty()) {
                        fields.push(format!("unit = {}", quote(u)));
                    } else if let Some(u) = named_unit {
                        fields.push(format!("unit = {}", quote(u)));
                    }
                    lines.push((col, format!("{{ {} }}", fields.join(", "))));
                }
                None => unknown.push(format!("{{ {} }}", fields.join(", "))),
            }
        }
        per_stream.push((n, s.name.as_str()));
    }
    if lines.is_empty() {
        return None;
    }
    let mut text = String::from("# proposed by limpid inspect: check every line (units, signs: fx is the force on the limb)\n");
    if source.streams.len() > 1 {
        let best = per_stream
            .iter()
            .max_by_key(|p| p.0)
            .map(|p| p.1)
            .unwrap_or("");
        text.push_str(&format!("[time]\nstream = {}\n", quote(best)));
    }
    text.push_str("[columns]\n");
    for (col, spec) in &lines {
        text.push_str(&format!("{col} = {spec}\n"));
    }
    for spec in &unknown {
        text.push_str(&format!(
            "# ? = {spec}   # not recognised: name its column or leave it out\n"
        ));
    }
    let marker_texts: Vec<(&str, usize)> = {
        let mut counts: std::collections::BTreeMap<&str, usize> = Default::default();
        for s in &source.streams {
            for m in &s.markers {
                *counts.entry(m.text.as_str()).or_default() += 1;
            }
        }
        let mut v: Vec<_> = counts.into_iter().collect();
        v.sort_by_key(|m| std::cmp::Reverse(m.1));
        v
    };
    if let Some((most, _)) = marker_texts.first() {
        text.push_str(&format!(
            "# trial = {{ marker = {} }}   # a trial starts at each such marker\n",
            quote(most)
        ));
    }
    Some(text)
}
