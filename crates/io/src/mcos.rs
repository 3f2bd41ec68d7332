//! MATLAB objects in level-5 MAT-files (issue 62): classdef objects (REKLAB's
//! `nldat`, user classes) saved through MATLAB's MCOS subsystem, decoded by
//! our own reader. MathWorks does not publish the layout; it is the one
//! documented by the open readers that reverse-engineered it (the mat-io
//! package's notes): facts about the format, not code, carry over.
//!
//! A variable holding an object is *opaque* (class 17): its metadata is a
//! `uint32` array `[0xDD000000, ndims, dims..., object ids..., class id]`.
//! The properties live in the file's *subsystem*: the last variable, which
//! has no name, a `uint8` array that is itself a MAT-file body (4 bytes of
//! version and endian indicator, 4 of padding, then data elements) holding
//! a struct whose `MCOS` field is an opaque `FileWrapper__` whose metadata
//! is a cell array:
//!
//! - cell 1, `uint8`: version (2-4), the number of names, eight region
//!   offsets, the names (NUL-terminated), then the regions, all `u32`:
//!   1. classes, 4 words each: namespace name, class name (1-based name
//!      indexes), 0, 0 (entry 0 unused);
//!   2. properties of objects saved through `saveobj`, as region 4;
//!   3. objects, 6 words each: class id, 0, 0, saveobj record, property
//!      record, dependency id (entry 0 unused);
//!   4. property records: a count, then per property (name index, kind,
//!      value) with kind 0 an enumeration name (a name index), 1 a saved
//!      value (an index into the cells below), 2 an integer or logical; each
//!      record padded to an even number of words;
//! - cells 3 .. (the last, less one more per version after 2): the saved
//!   property values;
//! - the last cell: per class, a struct of the class's default property
//!   values, which stand for the properties an object does not store.
//!
//! Bounds: every offset and index is checked against the region it points
//! into; objects nested in properties are resolved to [`MAX_DEPTH`] levels,
//! and an object met again inside itself is left as a reference.

use crate::mat::{Opaque, Variable};

/// The MCOS metadata's first word.
const MAGIC: u32 = 0xDD00_0000;

/// Deepest nesting of objects in properties.
const MAX_DEPTH: usize = 16;

/// The decoded subsystem.
struct Subsystem {
    names: Vec<String>,
    classes: Vec<u32>,
    objects: Vec<u32>,
    saveobj: Vec<u32>,
    records: Vec<u32>,
    values: Vec<Variable>,
    defaults: Vec<Variable>,
}

/// Replace every MCOS object among `vars` by a variable whose fields are
/// its properties (defaults of its class for those it does not store), and
/// drop the subsystem. What could not be resolved stays opaque and is named
/// in the notes.
pub(crate) fn resolve(vars: Vec<Variable>, little: bool, notes: &mut Vec<String>) -> Vec<Variable> {
    let (subsystem, vars): (Vec<Variable>, Vec<Variable>) = vars
        .into_iter()
        .partition(|v| v.name.is_empty() && v.class == "uint8");
    if !vars.iter().any(|v| is_mcos(v.opaque.as_deref())) {
        return vars;
    }
    let wrapper = match subsystem.last() {
        Some(s) => wrapper_of(s, little),
        None => Err("the file has objects but no subsystem to hold their properties".into()),
    };
    resolve_with(vars, wrapper, notes)
}

/// [`resolve`] with the FileWrapper__'s cells found another way (a v7.3
/// file's `#subsystem#/MCOS`), or why there are none.
pub(crate) fn resolve_with(
    mut vars: Vec<Variable>,
    wrapper: Result<(Vec<Variable>, bool), String>,
    notes: &mut Vec<String>,
) -> Vec<Variable> {
    let parsed = wrapper.and_then(|(cells, little)| Subsystem::from_cells(cells, little));
    let sub = match parsed {
        Ok(sub) => sub,
        Err(m) => {
            notes.push(format!("MATLAB objects not read: {m}"));
            return vars;
        }
    };
    for v in &mut vars {
        if is_mcos(v.opaque.as_deref()) {
            match sub.object(v, &mut Vec::new()) {
                Ok(obj) => *v = obj,
                Err(m) => notes.push(format!("{}: {m}", v.name)),
            }
        }
    }
    vars
}

fn is_mcos(o: Option<&Opaque>) -> bool {
    o.is_some_and(|o| o.type_system == "MCOS" && o.class_name != "FileWrapper__")
}

/// Words of a `uint32` array (its values arrive as f64, exactly).
fn words(v: &Variable) -> Option<Vec<u32>> {
    let real = v.real.as_ref()?;
    real.iter()
        .map(|x| (x.fract() == 0.0 && (0.0..=u32::MAX as f64).contains(x)).then_some(*x as u32))
        .collect()
}

/// The object ids and class id of MCOS metadata, if it is one.
fn reference(metadata: &Variable) -> Option<(Vec<u32>, Vec<u32>, u32)> {
    if metadata.class != "uint32" {
        return None;
    }
    let w = words(metadata)?;
    if w.len() < 3 || w[0] != MAGIC {
        return None;
    }
    let ndims = w[1] as usize;
    let dims = w.get(2..2 + ndims)?.to_vec();
    let count = dims
        .iter()
        .try_fold(1usize, |a, d| a.checked_mul(*d as usize))?;
    let ids = w.get(2 + ndims..2 + ndims + count)?.to_vec();
    let class = *w.get(2 + ndims + count)?;
    Some((dims, ids, class))
}

/// The FileWrapper__'s cells of a level-5 subsystem (a `uint8` array that
/// is a MAT-file body), and its byte order.
fn wrapper_of(sub: &Variable, little: bool) -> Result<(Vec<Variable>, bool), String> {
    let bytes: Vec<u8> = sub
        .real
        .as_ref()
        .map(|r| r.iter().map(|v| *v as u8).collect())
        .unwrap_or_default();
    if bytes.len() < 8 {
        return Err("the subsystem is shorter than its 8-byte header".into());
    }
    let little = match &bytes[2..4] {
        b"IM" => true,
        b"MI" => false,
        _ => little,
    };
    let inner = crate::mat::body(&bytes, 8, little, &mut 0)
        .map_err(|m| format!("the subsystem does not decode: {m}"))?;
    let wrapper = inner
        .into_iter()
        .flat_map(|v| v.fields)
        .find(|f| f.name == "MCOS")
        .and_then(|f| f.opaque)
        .filter(|o| o.class_name == "FileWrapper__")
        .ok_or("the subsystem holds no MCOS FileWrapper__")?;
    Ok((wrapper.metadata.cells, little))
}

impl Subsystem {
    fn from_cells(mut cells: Vec<Variable>, little: bool) -> Result<Subsystem, String> {
        if cells.len() < 3 {
            return Err(format!(
                "the FileWrapper__ holds {} cells, fewer than 3",
                cells.len()
            ));
        }
        let meta: Vec<u8> = cells[0]
            .real
            .as_ref()
            .map(|r| r.iter().map(|v| *v as u8).collect())
            .ok_or("the FileWrapper__ metadata is not a byte array")?;
        let word = |i: usize| -> Result<u32, String> {
            let b: [u8; 4] = meta
                .get(i..i + 4)
                .and_then(|s| s.try_into().ok())
                .ok_or_else(|| format!("the object metadata ends at byte {}", meta.len()))?;
            Ok(if little {
                u32::from_le_bytes(b)
            } else {
                u32::from_be_bytes(b)
            })
        };
        let version = word(0)?;
        if !(2..=4).contains(&version) {
            return Err(format!(
                "object metadata of version {version} (versions 2 to 4 are read)"
            ));
        }
        let count = word(4)? as usize;
        let mut offsets = [0usize; 8];
        for (k, o) in offsets.iter_mut().enumerate() {
            *o = word(8 + 4 * k)? as usize;
        }
        let names_end = offsets[0];
        let names: Vec<String> = meta
            .get(40..names_end)
            .ok_or("the object metadata's names run past it")?
            .split(|b| *b == 0)
            .filter(|s| !s.is_empty())
            .map(|s| String::from_utf8_lossy(s).into_owned())
            .collect();
        if names.len() != count {
            return Err(format!(
                "the object metadata declares {count} names and holds {}",
                names.len()
            ));
        }
        let region = |k: usize| -> Result<Vec<u32>, String> {
            let (a, z) = (offsets[k], offsets[k + 1]);
            if a > z || z > meta.len() || !(z - a).is_multiple_of(4) {
                return Err(format!("object metadata region {} is corrupt", k + 1));
            }
            (a..z).step_by(4).map(word).collect()
        };
        let trailing = match version {
            2 => 1,
            3 => 2,
            _ => 3,
        };
        // [metadata, ?, saved values..., (1 to 2 more cells by version), defaults]
        let total = cells.len();
        let end = total
            .checked_sub(trailing)
            .filter(|e| *e >= 2)
            .ok_or_else(|| {
                format!("the FileWrapper__ holds {total} cells, too few for version {version}")
            })?;
        let defaults = std::mem::take(&mut cells[total - 1].cells);
        let values: Vec<Variable> = cells.drain(2..end).collect();
        Ok(Subsystem {
            names,
            classes: region(0)?,
            saveobj: region(1)?,
            objects: region(2)?,
            records: region(3)?,
            values,
            defaults,
        })
    }

    fn name(&self, index: u32) -> Result<&str, String> {
        index
            .checked_sub(1)
            .and_then(|i| self.names.get(i as usize))
            .map(String::as_str)
            .ok_or_else(|| format!("a name index {index} beyond the {} names", self.names.len()))
    }

    fn class_name(&self, class: u32) -> Result<String, String> {
        let at = class as usize * 4;
        let entry = self
            .classes
            .get(at..at + 4)
            .ok_or_else(|| format!("class id {class} is not in the class table"))?;
        let name = self.name(entry[1])?;
        Ok(if entry[0] == 0 {
            name.to_string()
        } else {
            format!("{}.{name}", self.name(entry[0])?)
        })
    }

    /// The (name index, kind, value) triples of record `id` of `region`.
    fn record(region: &[u32], id: u32) -> Result<Vec<[u32; 3]>, String> {
        let mut at = region.first().copied().unwrap_or(0) as usize;
        for _ in 0..id {
            let n = *region
                .get(at)
                .ok_or_else(|| format!("property record {id} lies beyond its region"))?
                as usize;
            at = at
                .checked_add(1 + 3 * n)
                .ok_or("a property record's count overflows")?;
            at += at % 2;
        }
        let n = *region
            .get(at)
            .ok_or_else(|| format!("property record {id} lies beyond its region"))?
            as usize;
        let triples = region
            .get(at + 1..at + 1 + 3 * n)
            .ok_or_else(|| format!("property record {id} runs past its region"))?;
        Ok(triples
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect())
    }

    /// The properties of object `id`: its class's defaults, then what it stores.
    fn properties(&self, id: u32, seen: &mut Vec<u32>) -> Result<(String, Vec<Variable>), String> {
        let at = id as usize * 6;
        let entry = self
            .objects
            .get(at..at + 6)
            .ok_or_else(|| format!("object id {id} is not in the object table"))?;
        let (class, saveobj, normal) = (entry[0], entry[3], entry[4]);
        let class_name = self.class_name(class)?;
        let mut props: Vec<Variable> = self
            .defaults
            .get(class as usize)
            .map(|d| d.fields.clone())
            .unwrap_or_default();
        let triples = if saveobj != 0 {
            Self::record(&self.saveobj, saveobj)?
        } else {
            Self::record(&self.records, normal)?
        };
        for [name, kind, value] in triples {
            let name = self.name(name)?.to_string();
            let mut v = match kind {
                1 => self.values.get(value as usize).cloned().ok_or_else(|| {
                    format!(
                        "property {name}: saved value {value} of {}",
                        self.values.len()
                    )
                })?,
                2 => {
                    let mut v = Variable::empty(&name);
                    v.dims = vec![1, 1];
                    v.real = Some(vec![f64::from(value)]);
                    v
                }
                _ => {
                    let mut v = Variable::empty(&name);
                    v.class = "char";
                    v.real = None;
                    v.text = Some(self.name(value)?.to_string());
                    v
                }
            };
            v.name = name.clone();
            match props.iter_mut().find(|p| p.name == name) {
                Some(slot) => *slot = v,
                None => props.push(v),
            }
        }
        // objects inside properties
        for p in &mut props {
            self.nested(p, seen)?;
        }
        Ok((class_name, props))
    }

    /// Resolve an object reference held in `v` (a property or a cell), in place.
    fn nested(&self, v: &mut Variable, seen: &mut Vec<u32>) -> Result<(), String> {
        if seen.len() >= MAX_DEPTH {
            return Ok(());
        }
        // a saved property holds a nested object as its bare metadata array
        let target = match &v.opaque {
            Some(o) if is_mcos(Some(o)) => reference(&o.metadata),
            None => reference(v),
            _ => None,
        };
        if let Some((dims, ids, _)) = target {
            if let [id] = ids.as_slice() {
                if !seen.contains(id) {
                    seen.push(*id);
                    let (class, fields) = self.properties(*id, seen)?;
                    seen.pop();
                    v.fields = fields;
                    v.object_class = Some(class);
                    v.class = "object";
                    v.dims = dims.iter().map(|d| *d as usize).collect();
                    v.opaque = None;
                    tabular(v);
                }
            }
            return Ok(());
        }
        for c in &mut v.cells {
            self.nested(c, seen)?;
        }
        for f in &mut v.fields {
            self.nested(f, seen)?;
        }
        Ok(())
    }

    /// A top-level object variable resolved, or why not.
    fn object(&self, v: &Variable, seen: &mut Vec<u32>) -> Result<Variable, String> {
        let (dims, ids, _) = v
            .opaque
            .as_ref()
            .and_then(|o| reference(&o.metadata))
            .ok_or("its object metadata is not an MCOS reference")?;
        let [id] = ids.as_slice() else {
            return Err(format!(
                "an array of {} objects (limpid reads single objects)",
                ids.len()
            ));
        };
        let (class, fields) = self.properties(*id, seen)?;
        Ok(tabulated(Variable {
            name: v.name.clone(),
            class: "object",
            dims: dims.iter().map(|d| *d as usize).collect(),
            real: None,
            complex: false,
            complex_parts: None,
            words: None,
            fields,
            cells: Vec::new(),
            text: None,
            opaque: None,
            object_class: Some(class),
            events: Vec::new(),
        }))
    }
}

fn tabulated(mut v: Variable) -> Variable {
    tabular(&mut v);
    v
}

/// The texts of a MATLAB `string` array (its `any` words: version 1, the
/// number of dimensions, the dimensions, each string's length in UTF-16
/// units or `u64::MAX` for `<missing>`, then the units packed four to a
/// word), a `categorical` (each code's category name; code 0, undefined,
/// is `None`), or a cell array of char vectors.
fn texts_of(v: &Variable) -> Option<Vec<Option<String>>> {
    let field = |n: &str| v.fields.iter().find(|f| f.name == n);
    match v.object_class.as_deref() {
        Some("string") => {
            let w = field("any")?.words.as_ref()?;
            if *w.first()? != 1 {
                return None;
            }
            let ndims = usize::try_from(*w.get(1)?).ok()?;
            let dims = w.get(2..2 + ndims)?;
            let count = dims
                .iter()
                .try_fold(1usize, |a, d| a.checked_mul(usize::try_from(*d).ok()?))?;
            let lengths = w.get(2 + ndims..(2 + ndims).checked_add(count)?)?;
            let units: Vec<u16> = w[2 + ndims + count..]
                .iter()
                .flat_map(|x| (0..4).map(move |k| (x >> (16 * k)) as u16))
                .collect();
            let mut at = 0usize;
            let mut out = Vec::with_capacity(count);
            for &n in lengths {
                if n == u64::MAX {
                    out.push(None);
                    continue;
                }
                let end = at.checked_add(usize::try_from(n).ok()?)?;
                out.push(Some(String::from_utf16_lossy(units.get(at..end)?)));
                at = end;
            }
            Some(out)
        }
        Some("categorical") => {
            let codes = field("codes")?.real.as_ref()?;
            let names: Vec<String> = field("categoryNames")?
                .cells
                .iter()
                .map(|c| c.text.clone())
                .collect::<Option<_>>()?;
            Some(
                codes
                    .iter()
                    .map(|&c| {
                        (c >= 1.0)
                            .then(|| names.get(c as usize - 1).cloned())
                            .flatten()
                    })
                    .collect(),
            )
        }
        None if v.class == "cell" && !v.cells.is_empty() => {
            v.cells.iter().map(|c| c.text.clone().map(Some)).collect()
        }
        _ => None,
    }
}

/// A variable of texts: a char scalar for one, a cell of chars for more.
fn text_variable(name: &str, texts: Vec<Option<String>>) -> Variable {
    let mut v = Variable::empty(name);
    v.real = None;
    if let [one] = texts.as_slice() {
        v.class = "char";
        v.dims = vec![1, one.as_ref().map_or(0, |t| t.chars().count())];
        v.text = Some(one.clone().unwrap_or_default());
    } else {
        v.class = "cell";
        v.dims = vec![texts.len(), 1];
        v.cells = texts
            .into_iter()
            .map(|t| text_variable("", vec![t]))
            .collect();
    }
    v
}

/// A MATLAB `table` or `timetable` object's properties replaced by its
/// variables, each named by its variable name (`T.Angle`; a duration or
/// datetime variable in seconds as row times are), and a
/// timetable's row times by its first dimension name (`TT.Time`) in
/// seconds: a `duration` as stored, a `datetime` counted from the first
/// row. The properties sit on the object or, saved through `saveobj`, in
/// its struct field `any`. Left as it is when the layout is not that.
fn tabular(v: &mut Variable) {
    let class = v.object_class.as_deref().unwrap_or("");
    if class == "string" {
        if let Some(texts) = texts_of(v) {
            let name = v.name.clone();
            *v = text_variable(&name, texts);
        }
        return;
    }
    if class != "table" && class != "timetable" {
        return;
    }
    let props: &[Variable] = match v.fields.iter().find(|f| f.name == "any") {
        Some(any) if !any.fields.is_empty() => &any.fields,
        _ => &v.fields,
    };
    let get = |names: &[&str]| props.iter().find(|p| names.contains(&p.name.as_str()));
    let texts = |p: Option<&Variable>| -> Option<Vec<String>> {
        p?.cells.iter().map(|c| c.text.clone()).collect()
    };
    // MATLAB 2026b (save version 8) keeps names over 63 characters whole in
    // varNames2048, the truncated ones in varNames
    let long_names = get(&["useVarNames2048"])
        .and_then(scalar)
        .is_some_and(|u| u != 0.0);
    let names = if long_names {
        texts(get(&["varNames2048"]))
    } else {
        None
    }
    .or_else(|| texts(get(&["varnames", "varNames"])));
    let (Some(data), Some(names)) = (get(&["data"]), names) else {
        return;
    };
    if data.cells.len() != names.len() {
        return;
    }
    // variables by name; durations and datetimes as seconds
    let mut fields: Vec<Variable> = data
        .cells
        .iter()
        .zip(&names)
        .map(|(c, n)| {
            let mut c = match row_seconds(c) {
                Some(seconds) => {
                    let mut t = Variable::empty(n);
                    t.dims = vec![seconds.len(), 1];
                    t.real = Some(seconds);
                    t
                }
                None => c.clone(),
            };
            c.name = n.clone();
            c
        })
        .collect();
    let mut events = Vec::new();
    if class == "timetable" {
        let time_name = texts(get(&["dimNames", "dimnames"]))
            .and_then(|d| d.into_iter().next())
            .unwrap_or_else(|| "Time".into());
        let rows = data
            .cells
            .first()
            .map_or(0, |c| c.dims.first().copied().unwrap_or(0));
        let rows = get(&["numRows"])
            .and_then(scalar)
            .map_or(rows, |n| n as usize);
        if let Some(times) =
            get(&["rowTimes"]).and_then(|r| row_seconds(r).or_else(|| regular_row_times(r, rows)))
        {
            // text variables (strings, categoricals, cellstr): events at the row times
            for f in &mut fields {
                if let Some(texts) = texts_of(f).filter(|t| t.len() == times.len()) {
                    for (time, text) in times.iter().zip(&texts) {
                        if let Some(text) = text.as_ref().filter(|t| !t.is_empty()) {
                            events.push((f.name.clone(), *time, text.clone()));
                        }
                    }
                    let name = f.name.clone();
                    *f = text_variable(&name, texts);
                }
            }
            let mut t = Variable::empty(&time_name);
            t.dims = vec![times.len(), 1];
            t.real = Some(times);
            fields.insert(0, t);
        }
    }
    v.fields = fields;
    v.events = events;
}

/// The one number of a 1 x 1 numeric (or logical) array.
fn scalar(v: &Variable) -> Option<f64> {
    match (&v.real, &v.words) {
        (Some(r), _) if r.len() == 1 => Some(r[0]),
        (_, Some(w)) if w.len() == 1 => Some(w[0] as f64),
        _ => None,
    }
}

/// The row times a timetable does not store (made with `SampleRate` or
/// `TimeStep`): its `rowTimes` is then a struct of `origin` (a duration or
/// datetime), `specifiedAsRate`, `sampleRate` (Hz) and `stepSize` (a
/// duration, or a calendarDuration of months, days and milliseconds).
/// Seconds as for stored row times: a duration origin as it is, a datetime
/// origin counted from the first row; row k at k / rate (no drift from a
/// rounded step), at k steps, or at k calendar months from the origin's date.
fn regular_row_times(r: &Variable, rows: usize) -> Option<Vec<f64>> {
    let field = |n: &str| r.fields.iter().find(|f| f.name == n);
    let origin = field("origin")?;
    let origin_field = |n: &str| origin.fields.iter().find(|f| f.name == n);
    let (start_s, epoch_ms) = match origin.object_class.as_deref() {
        Some("duration") => (scalar(origin_field("millis")?)? / 1000.0, None),
        Some("datetime") => {
            let data = origin_field("data")?;
            let ms = match (&data.real, &data.complex_parts) {
                (Some(re), _) if re.len() == 1 => re[0],
                (None, Some((re, im))) if re.len() == 1 => re[0] + im[0],
                _ => return None,
            };
            (0.0, Some(ms))
        }
        _ => return None,
    };
    if field("specifiedAsRate")
        .and_then(scalar)
        .is_some_and(|a| a != 0.0)
    {
        let fs = scalar(field("sampleRate")?)?;
        if !(fs.is_finite() && fs > 0.0) {
            return None;
        }
        return Some((0..rows).map(|k| start_s + k as f64 / fs).collect());
    }
    let step = field("stepSize")?;
    let step_field = |n: &str| step.fields.iter().find(|f| f.name == n);
    let step_s = match step.object_class.as_deref() {
        Some("duration") => scalar(step_field("millis")?)? / 1000.0,
        Some("calendarDuration") => {
            let parts = step_field("components")?;
            let part = |n: &str| {
                parts
                    .fields
                    .iter()
                    .find(|f| f.name == n)
                    .and_then(scalar)
                    .unwrap_or(0.0)
            };
            let (months, days, millis) = (part("months"), part("days"), part("millis"));
            if months != 0.0 {
                // calendar months are of unequal length: from the origin's date
                let origin_ms = epoch_ms?;
                if days != 0.0 || millis != 0.0 || months.fract() != 0.0 {
                    return None;
                }
                return Some(
                    (0..rows)
                        .map(|k| {
                            (add_months(origin_ms, months as i64 * k as i64) - origin_ms) / 1000.0
                        })
                        .collect(),
                );
            }
            days * 86_400.0 + millis / 1000.0
        }
        _ => return None,
    };
    if !(step_s.is_finite() && step_s > 0.0) {
        return None;
    }
    Some((0..rows).map(|k| start_s + k as f64 * step_s).collect())
}

/// `ms` since 1970-01-01 (UTC, proleptic Gregorian) moved by `months`
/// calendar months, the day of the month and the time of day kept.
fn add_months(ms: f64, months: i64) -> f64 {
    const DAY_MS: f64 = 86_400_000.0;
    let days = (ms / DAY_MS).floor();
    let time_of_day = ms - days * DAY_MS;
    let (y, m, d) = civil_from_days(days as i64);
    let total = y * 12 + (m - 1) + months;
    let (y, m) = (total.div_euclid(12), total.rem_euclid(12) + 1);
    days_from_civil(y, m, d) as f64 * DAY_MS + time_of_day
}

/// Days since 1970-01-01 of a proleptic Gregorian date (the civil-calendar
/// algorithm in eras of 400 years).
fn days_from_civil(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let year_of_era = y - era * 400;
    let month_from_march = (m + 9) % 12;
    let day_of_year = (153 * month_from_march + 2) / 5 + d - 1;
    let day_of_era = year_of_era * 365 + year_of_era / 4 - year_of_era / 100 + day_of_year;
    era * 146_097 + day_of_era - 719_468
}

/// The date of `days` since 1970-01-01 (inverse of [`days_from_civil`]).
fn civil_from_days(days: i64) -> (i64, i64, i64) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let day_of_era = z - era * 146_097;
    let year_of_era =
        (day_of_era - day_of_era / 1460 + day_of_era / 36_524 - day_of_era / 146_096) / 365;
    let day_of_year = day_of_era - (365 * year_of_era + year_of_era / 4 - year_of_era / 100);
    let month_from_march = (5 * day_of_year + 2) / 153;
    let d = day_of_year - (153 * month_from_march + 2) / 5 + 1;
    let m = if month_from_march < 10 {
        month_from_march + 3
    } else {
        month_from_march - 9
    };
    let y = year_of_era + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

/// A timetable's row times in seconds: a duration's `millis`, or a
/// datetime's `data` (ms since 1970, fraction in the imaginary part)
/// counted from the first row.
fn row_seconds(times: &Variable) -> Option<Vec<f64>> {
    let field = |n: &str| times.fields.iter().find(|f| f.name == n);
    match times.object_class.as_deref() {
        Some("duration") => {
            let ms = field("millis")?.real.as_ref()?;
            Some(ms.iter().map(|m| m / 1000.0).collect())
        }
        Some("datetime") => {
            let data = field("data")?;
            let (re, im): (Vec<f64>, Vec<f64>) = match (&data.real, &data.complex_parts) {
                (Some(re), _) => (re.clone(), vec![0.0; re.len()]),
                (None, Some((re, im))) => (re.clone(), im.clone()),
                _ => return None,
            };
            let (re0, im0) = (*re.first()?, im[0]);
            Some(
                re.iter()
                    .zip(&im)
                    .map(|(r, i)| ((r - re0) + (i - im0)) / 1000.0)
                    .collect(),
            )
        }
        _ => None,
    }
}
