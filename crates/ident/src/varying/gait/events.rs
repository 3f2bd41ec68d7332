//! Strides from events (issue 61): heel strikes from a 0/1 event column or
//! from a threshold crossing of a force column (with hysteresis and a
//! refractory time), cut into strides, and every stride whose duration says
//! an event was missed, doubled or is otherwise wrong reported by number and
//! left out, never averaged in.
//!
//! Choices (the walking literature leaves them to each lab):
//! - events closer than the refractory time to the one before are dropped
//!   (reported as double detections);
//! - a stride is judged against the median duration of the 21 strides around
//!   it, so a change of walking speed is not mistaken for flawed events;
//! - a stride shorter than 0.6 median whose sum with a neighbour lies within
//!   0.8-1.25 median was split by an extra event: the event is ignored and the
//!   two parts are one stride again;
//! - a stride within 0.3 of a whole number (2 or more) of medians missed
//!   events; any other stride outside 0.75-1.33 median is an outlier; both
//!   are left out, and the strides after one that missed events are numbered
//!   as if the events had been found.

use limpid_core::{Error, Recording, Result};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// How the stride events are found.
#[derive(Debug, Clone, PartialEq)]
pub enum EventRule {
    /// A column that is 1 on each event's sample(s) and 0 elsewhere.
    Column(String),
    /// The column rising above the level.
    Above(String, f64),
    /// The column falling below the level.
    Below(String, f64),
}

impl EventRule {
    /// `COLUMN`, `COLUMN>LEVEL` or `COLUMN<LEVEL`.
    pub fn parse(text: &str) -> Result<EventRule> {
        let bad = |why: String| Error::invalid("event", why);
        let split = |sep: char| -> Result<Option<(String, f64)>> {
            let Some((c, l)) = text.split_once(sep) else {
                return Ok(None);
            };
            let level: f64 = l.trim().parse().map_err(|_| {
                bad(format!(
                    "`{text}`: expected COLUMN{sep}LEVEL with a number after `{sep}`, found `{}`",
                    l.trim()
                ))
            })?;
            if !level.is_finite() || level.abs() > 1e12 {
                return Err(bad(format!(
                    "`{text}`: the level must be a finite number of at most 1e12"
                )));
            }
            let c = c.trim();
            if c.is_empty() {
                return Err(bad(format!("`{text}`: no column before `{sep}`")));
            }
            Ok(Some((c.to_string(), level)))
        };
        if let Some((c, l)) = split('>')? {
            return Ok(EventRule::Above(c, l));
        }
        if let Some((c, l)) = split('<')? {
            return Ok(EventRule::Below(c, l));
        }
        let c = text.trim();
        if c.is_empty() {
            return Err(bad(
                "expected a column name, COLUMN>LEVEL or COLUMN<LEVEL".into()
            ));
        }
        Ok(EventRule::Column(c.to_string()))
    }

    /// The column read.
    pub fn column(&self) -> &str {
        match self {
            EventRule::Column(c) | EventRule::Above(c, _) | EventRule::Below(c, _) => c,
        }
    }
}

/// A stride left out, or an event ignored, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct StrideFlaw {
    /// The stride's number, from 1 at the first event: extra events do not
    /// count and a stride that missed an event counts as the strides it spans,
    /// so the number is the stride's place in the walk.
    pub stride: usize,
    /// The same counted from 0.
    pub index: usize,
    /// Its first sample's time (s).
    pub start_s: f64,
    /// Its first sample's row in the file.
    pub start_row: usize,
    /// Its duration (s).
    pub duration_s: f64,
    /// `double` (an extra event: ignored, the parts joined), `missed` (a
    /// stride spanning two: left out), `outlier` (left out).
    pub kind: String,
    /// What was found and done, in words.
    pub note: String,
}

impl StrideFlaw {
    /// The flaw of the samples `a..b` of `rec`; its number is given later
    /// (0 until then) when the events around it are still being sorted out.
    fn new(
        rec: &Recording,
        (a, b): (usize, usize),
        number: usize,
        kind: &str,
        note: String,
    ) -> Self {
        let fs = rec.sample_rate();
        StrideFlaw {
            stride: number,
            index: number.saturating_sub(1),
            start_s: a as f64 / fs,
            start_row: rec.row_of(a),
            duration_s: (b - a) as f64 / fs,
            kind: kind.into(),
            note,
        }
    }
}

/// The strides of a record.
#[derive(Debug, Clone)]
pub struct Strides {
    /// The strides kept (sample ranges, from one event to the next).
    pub kept: Vec<std::ops::Range<usize>>,
    /// Their numbers (as in [`StrideFlaw::stride`]).
    pub numbers: Vec<usize>,
    /// The events after double detections were ignored (sample indices).
    pub events: Vec<usize>,
    /// Full strides between detected events.
    pub found: usize,
    /// What was left out or ignored.
    pub flaws: Vec<StrideFlaw>,
    /// Of the flaws, the events ignored within the refractory time (a
    /// detector's bounce: harmless, not a repair of the strides).
    pub bounces: usize,
}

impl Strides {
    /// Median duration of the kept strides (samples).
    pub fn median_len(&self) -> usize {
        let mut l: Vec<usize> = self.kept.iter().map(|r| r.len()).collect();
        l.sort_unstable();
        l.get(l.len() / 2).copied().unwrap_or(0)
    }
}

/// Events and strides of `rec` by `rule`.
pub fn strides(
    rec: &Recording,
    rule: &EventRule,
    hysteresis: Option<f64>,
    refractory_s: f64,
) -> Result<Strides> {
    let fs = rec.sample_rate();
    let column = rule.column();
    let values = rec.require(column, "stride events (heel strikes)")?;
    let raw = detect(rec, rule, values, hysteresis)?;
    let refractory = (refractory_s * fs).round() as usize;
    let mut flaws = Vec::new();
    let mut events: Vec<usize> = Vec::with_capacity(raw.len());
    for &e in &raw {
        match events.last() {
            Some(&last) if e - last < refractory => flaws.push(StrideFlaw::new(
                rec,
                (last, e),
                0,
                "double",
                format!(
                    "a second event {} ms after the one at row {} (within the refractory time): ignored",
                    crate::varying::round_ms((e - last) as f64 / fs),
                    rec.row_of(last)
                ),
            )),
            _ => events.push(e),
        }
    }
    if events.len() < 4 {
        return Err(Error::invalid(
            "event",
            format!(
                "{}: {} event(s) in column {column}: walking analysis needs at least 3 full strides (4 events)",
                rec.path().display(),
                events.len()
            ),
        ));
    }
    refractory_within_a_stride(&events, &raw, refractory, refractory_s)?;
    let bounces = flaws.len();
    let mut bounds: Vec<(usize, usize)> = events.windows(2).map(|w| (w[0], w[1])).collect();
    let found = bounds.len();
    join_split_strides(rec, &mut bounds, &mut flaws);
    let lens: Vec<f64> = bounds.iter().map(|&(a, b)| (b - a) as f64).collect();
    let ratios: Vec<f64> = (0..lens.len())
        .map(|i| lens[i] / local_median(&lens, i))
        .collect();
    // near a whole number of strides, two or more: events were missed
    let missed = |r: f64| r >= 1.6 && (r - r.round()).abs() <= 0.3;
    // a stride's place in the walk: one that missed an event spans two
    let mut number_of = Vec::with_capacity(bounds.len());
    let mut next = 1;
    for &r in &ratios {
        number_of.push(next);
        next += if missed(r) { r.round() as usize } else { 1 };
    }
    let mut kept = Vec::new();
    let mut numbers = Vec::new();
    for (i, &(a, b)) in bounds.iter().enumerate() {
        let (ratio, n) = (ratios[i], number_of[i]);
        let flaw = |kind: &str, note: String| StrideFlaw::new(rec, (a, b), n, kind, note);
        if missed(ratio) {
            flaws.push(flaw("missed", format!("{ratio:.2} times the median stride around it: {} event(s) probably missed; left out", ratio.round() - 1.0)));
        } else if !(0.75..=1.33).contains(&ratio) {
            flaws.push(flaw(
                "outlier",
                format!("{ratio:.2} times the median stride around it; left out"),
            ));
        } else {
            kept.push(a..b);
            numbers.push(n);
        }
    }
    // the extra events found before the numbering: the number of the stride they fell in
    for f in flaws.iter_mut().filter(|f| f.stride == 0) {
        let sample = (f.start_s * fs).round() as usize;
        let i = bounds
            .partition_point(|&(a, _)| a <= sample)
            .saturating_sub(1);
        f.stride = number_of[i];
        f.index = f.stride - 1;
    }
    flaws.sort_by_key(|f| f.start_row);
    // a detector this wrong is not walking data with a few flawed events
    if flaws.len() > 20 && 2 * flaws.len() > raw.len() {
        return Err(Error::invalid(
            "event",
            format!(
                "{}: {} of the {} events in column {column} are doubled, missed or outliers (the first at row {}): check the event column or threshold",
                rec.path().display(),
                flaws.len(),
                raw.len(),
                flaws[0].start_row
            ),
        ));
    }
    if kept.len() < 3 {
        return Err(Error::invalid(
            "event",
            format!(
                "{}: only {} of {found} strides have a plausible duration (see the events in column {column})",
                rec.path().display(),
                kept.len()
            ),
        ));
    }
    Ok(Strides {
        kept,
        numbers,
        events: bounds
            .iter()
            .map(|b| b.0)
            .chain(bounds.last().map(|b| b.1))
            .collect(),
        found,
        flaws,
        bounces,
    })
}

/// A refractory time is for double detections, tens of milliseconds after
/// a heel strike; one longer than a stride swallows every other event and
/// reads double strides as strides (`--refractory 2000` on 1.1 s strides:
/// 150 double strides, K 49-180 % off; issue 76). Refused when the events
/// it ignored lie a median of over half the strides it leaves after the
/// event kept before them.
fn refractory_within_a_stride(
    events: &[usize],
    raw: &[usize],
    refractory: usize,
    refractory_s: f64,
) -> Result<()> {
    let mut ignored_after: Vec<usize> = Vec::new();
    let mut k = 0;
    for &e in raw {
        while k + 1 < events.len() && events[k + 1] <= e {
            k += 1;
        }
        if events[k] < e && e - events[k] < refractory {
            ignored_after.push(e - events[k]);
        }
    }
    if ignored_after.len() < 3 || 4 * ignored_after.len() < raw.len() {
        return Ok(());
    }
    let mut strides: Vec<usize> = events.windows(2).map(|w| w[1] - w[0]).collect();
    let median = |v: &mut Vec<usize>| {
        let mid = v.len() / 2;
        *v.select_nth_unstable(mid).1
    };
    let stride = median(&mut strides);
    let offset = median(&mut ignored_after);
    if 2 * offset > stride {
        let fs = refractory as f64 / refractory_s;
        return Err(Error::invalid(
            "refractory_ms",
            format!(
                "a refractory time of {} ms ignores {} of the {} events, a median of {} ms after the event kept before them, and leaves strides of {} ms: it is longer than a stride (double detections come within tens of ms); shorten it",
                crate::varying::round_ms(refractory_s),
                ignored_after.len(),
                raw.len(),
                crate::varying::round_ms(offset as f64 / fs),
                crate::varying::round_ms(stride as f64 / fs)
            ),
        ));
    }
    Ok(())
}

impl Strides {
    /// Why the strides cannot be trusted as one gait cycle, if so: strides of
    /// about one and two median lengths used together (events removed in
    /// runs drag the 21-stride median along: 1.0-2.27 s strides pooled gave
    /// K at 2-3x the truth, trusted; issue 76), or most strides repaired.
    pub fn doubt(&self) -> Option<String> {
        let median = self.median_len() as f64;
        if median <= 0.0 {
            return None;
        }
        let n = self.kept.len();
        let long = self
            .kept
            .iter()
            .filter(|r| r.len() as f64 >= 1.6 * median)
            .count();
        let short = self
            .kept
            .iter()
            .filter(|r| r.len() as f64 <= median / 1.6)
            .count();
        if 20 * (long + short) >= n {
            return Some(format!(
                "the strides used are of mixed lengths: {long} of {n} at 1.6 times the median stride or more and {short} at 1/1.6 or less (runs of missed or extra events?): one gait cycle cannot be assumed, no point is trusted"
            ));
        }
        let repaired = self.flaws.len() - self.bounces;
        if repaired > n {
            return Some(format!(
                "{repaired} strides needed repair beside {n} used as found: most of the event column is flawed, no point is trusted"
            ));
        }
        None
    }
}

/// Median of the durations of the 21 strides centred on `i`.
fn local_median(lens: &[f64], i: usize) -> f64 {
    let lo = i.saturating_sub(10);
    let hi = (i + 11).min(lens.len());
    let mut w: Vec<f64> = lens[lo..hi].to_vec();
    w.sort_by(f64::total_cmp);
    w[w.len() / 2]
}

/// Join a short stride with the neighbour that makes it a whole one (an
/// extra event split it), reporting the event ignored.
fn join_split_strides(
    rec: &Recording,
    bounds: &mut Vec<(usize, usize)>,
    flaws: &mut Vec<StrideFlaw>,
) {
    let fs = rec.sample_rate();
    loop {
        let lens: Vec<f64> = bounds.iter().map(|&(a, b)| (b - a) as f64).collect();
        let mut joined = false;
        for i in 0..bounds.len() {
            let m = local_median(&lens, i);
            if lens[i] >= 0.6 * m {
                continue;
            }
            let whole = |j: usize| {
                let r = (lens[i] + lens[j]) / m;
                (0.8..=1.25).contains(&r).then_some((r - 1.0).abs())
            };
            let before = (i > 0).then(|| whole(i - 1)).flatten();
            let after = (i + 1 < bounds.len()).then(|| whole(i + 1)).flatten();
            let first = match (before, after) {
                (Some(x), Some(y)) if x <= y => i - 1,
                (Some(_), None) => i - 1,
                (_, Some(_)) => i,
                (None, None) => continue,
            };
            let (a, mid) = bounds[first];
            let (_, b) = bounds[first + 1];
            flaws.push(StrideFlaw::new(
                rec,
                (a, b),
                0,
                "double",
                format!(
                    "an extra event at row {} (t = {} s) split it in two: ignored, the parts joined",
                    rec.row_of(mid),
                    limpid_core::significant(mid as f64 / fs, 6)
                ),
            ));
            bounds[first] = (a, b);
            bounds.remove(first + 1);
            joined = true;
            break;
        }
        if !joined {
            return;
        }
    }
}

/// Sample indices of the events, before the refractory rule.
fn detect(
    rec: &Recording,
    rule: &EventRule,
    v: &[f64],
    hysteresis: Option<f64>,
) -> Result<Vec<usize>> {
    let mut out = Vec::new();
    match rule {
        EventRule::Column(c) => {
            for (i, &x) in v.iter().enumerate() {
                if x != 0.0 && x != 1.0 {
                    return Err(Error::Format {
                        path: rec.path().to_path_buf(),
                        message: format!(
                            "row {}, column {c}: expected 0 or 1 (an event column), found {}; for a threshold on a force write --event '{c}>LEVEL'",
                            rec.row_of(i),
                            limpid_core::error::Num(x)
                        ),
                    });
                }
                if x == 1.0 && (i == 0 || v[i - 1] == 0.0) {
                    out.push(i);
                }
            }
        }
        EventRule::Above(_, level) | EventRule::Below(_, level) => {
            let up = matches!(rule, EventRule::Above(..));
            let h = hysteresis.unwrap_or(0.05 * level.abs()).abs();
            // armed once the signal is clearly on the other side of the level
            let mut armed = false;
            for (i, &x) in v.iter().enumerate() {
                let (beyond, back) = if up {
                    (x > *level, x < level - h)
                } else {
                    (x < *level, x > level + h)
                };
                if back {
                    armed = true;
                } else if beyond && armed {
                    out.push(i);
                    armed = false;
                }
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(events: &[usize], n: usize) -> Recording {
        let t: Vec<f64> = (0..n).map(|i| i as f64 / 100.0).collect();
        let mut e = vec![0.0; n];
        for &i in events {
            e[i] = 1.0;
        }
        Recording::new(
            "events",
            vec!["t".into(), "heel_strike".into()],
            vec![t, e],
            2,
        )
        .unwrap()
    }

    #[test]
    fn a_doubled_and_a_missed_event_are_reported_by_stride_number() {
        // strides of 100 samples at 100 Hz; an extra event 30 samples into the
        // 5th stride, and the 10th event missing
        let mut ev: Vec<usize> = (0..20).map(|k| 10 + 100 * k).collect();
        ev.push(10 + 400 + 30);
        ev.retain(|&e| e != 10 + 900);
        ev.sort_unstable();
        let s = strides(
            &record(&ev, 2100),
            &EventRule::Column("heel_strike".into()),
            None,
            0.2,
        )
        .unwrap();
        let kinds: Vec<(&str, usize)> = s
            .flaws
            .iter()
            .map(|f| (f.kind.as_str(), f.stride))
            .collect();
        assert_eq!(kinds, vec![("double", 5), ("missed", 9)], "{:?}", s.flaws);
        // the stride after the missed event is the 11th of the walk
        assert_eq!(s.numbers[8], 11, "{:?}", s.numbers);
        assert_eq!(s.kept.len(), 17);
        assert!(s.kept.iter().all(|r| r.len() == 100));
    }

    /// Issue 76: a bounce after every heel strike (within the refractory
    /// time) is harmless; an extra event splitting most strides is a
    /// repair of most of the walk, and no point is trusted.
    #[test]
    fn bounces_are_no_doubt_but_most_strides_repaired_are() {
        let steady: Vec<usize> = (0..40).map(|k| 10 + 100 * k).collect();
        let mut bouncy = steady.clone();
        bouncy.extend(steady.iter().map(|e| e + 3));
        bouncy.sort_unstable();
        let column = EventRule::Column("heel_strike".into());
        let s = strides(&record(&bouncy, 4100), &column, None, 0.2).unwrap();
        assert_eq!((s.bounces, s.flaws.len()), (40, 40));
        assert_eq!(s.doubt(), None);
        // an extra event 40 samples into 25 of the 39 strides
        let mut split = steady.clone();
        split.extend(steady.iter().take(25).map(|e| e + 40));
        split.sort_unstable();
        // (split this often, the parts are the local median's and the whole
        // strides look like missed events: mixed lengths, said either way)
        let s = strides(&record(&split, 4100), &column, None, 0.2).unwrap();
        assert_eq!(s.bounces, 0);
        let why = s.doubt().expect("most strides flawed");
        assert!(why.contains("no point is trusted"), "{why}");
        // the walk as found: no doubt
        let s = strides(&record(&steady, 4100), &column, None, 0.2).unwrap();
        assert_eq!(s.doubt(), None);
    }

    #[test]
    fn a_threshold_with_hysteresis_finds_one_event_per_rise() {
        let n = 1000;
        let t: Vec<f64> = (0..n).map(|i| i as f64 / 100.0).collect();
        // a force that rises above 50 every 100 samples, with chatter near the level
        let f: Vec<f64> = (0..n)
            .map(|i| {
                let p = i % 100;
                if p < 40 {
                    0.0
                } else if p < 45 {
                    50.0 + if p % 2 == 0 { 1.0 } else { -1.0 }
                } else {
                    200.0
                }
            })
            .collect();
        let rec = Recording::new("f", vec!["t".into(), "fz".into()], vec![t, f], 2).unwrap();
        let rule = EventRule::parse("fz>50").unwrap();
        let s = strides(&rec, &rule, Some(10.0), 0.2).unwrap();
        assert_eq!(s.events.len(), 10, "{:?}", s.events);
        assert!(s.flaws.is_empty());
    }

    #[test]
    fn the_rule_is_parsed_or_refused_by_name() {
        assert_eq!(
            EventRule::parse("fz < -20").unwrap(),
            EventRule::Below("fz".into(), -20.0)
        );
        for bad in ["fz>", ">5", "fz>abc", "fz>1e400", ""] {
            assert!(
                EventRule::parse(bad)
                    .unwrap_err()
                    .to_string()
                    .contains("event"),
                "{bad}"
            );
        }
    }
}
