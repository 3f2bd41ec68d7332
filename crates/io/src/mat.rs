//! MATLAB level-5 MAT-files (MATLAB's `-v6` and default `-v7`), read by our
//! own decoder of the published format ("MAT-File Format", MathWorks, ch. 1):
//! a 128-byte header, then data elements, each an 8-byte tag (type, byte
//! count; or the 4-byte "small element" form) followed by its data, padded
//! to 8 bytes; `miCOMPRESSED` elements hold one zlib-compressed element
//! (decompressed with flate2). A variable is an `miMATRIX` element: array
//! flags (class, complex bit), dimensions, name, real part, imaginary part.
//!
//! Why not the `matfile` crate (used until issue 13): it prints debug lines to
//! stdout and stderr (which broke `--json`), inflates compressed elements
//! without a size bound, and skips structs and cells without naming them.
//! This decoder is bounded: every size is checked against the bytes that are
//! there, and decompression stops at the size the element declares and at
//! [`MAX_DECODED_BYTES`] in all.

use std::io::Read;

/// Most bytes the decompressed variables of one file may take.
pub const MAX_DECODED_BYTES: usize = 4 << 30;

const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;

/// One variable of the file.
#[derive(Clone)]
pub struct Variable {
    pub name: String,
    /// MATLAB class name (`double`, `struct`, `char`, ...).
    pub class: &'static str,
    pub dims: Vec<usize>,
    /// Real values (column-major) of a real numeric array; `None` otherwise.
    pub real: Option<Vec<f64>>,
    pub complex: bool,
    /// Real and imaginary parts of a complex numeric array.
    pub complex_parts: Option<(Vec<f64>, Vec<f64>)>,
    /// The exact words of a `uint64` array.
    pub words: Option<Vec<u64>>,
    /// The fields of a 1 x 1 struct (or object), each named by its field name.
    pub fields: Vec<Variable>,
    /// The elements of a cell array, column-major.
    pub cells: Vec<Variable>,
    /// The text of a char array (rows joined by newlines).
    pub text: Option<String>,
    /// An opaque value (MATLAB objects: classdef, table, string, datetime).
    pub opaque: Option<Box<Opaque>>,
    /// The class name of an object (classdef or old-style).
    pub object_class: Option<String>,
    /// Text events of a timetable: (column, row time in s, text), from its
    /// string, categorical and cellstr variables.
    pub events: Vec<(String, f64, String)>,
}

/// An opaque value's header: its type system (`MCOS` for classdef objects),
/// its class, and its metadata array (for MCOS: object ids and class id).
#[derive(Clone)]
pub struct Opaque {
    pub type_system: String,
    pub class_name: String,
    pub metadata: Variable,
}

impl Variable {
    /// An empty double array (a zero-length element: MATLAB's `[]`).
    pub fn empty(name: &str) -> Variable {
        Variable {
            name: name.to_string(),
            class: "double",
            dims: vec![0, 0],
            real: Some(Vec::new()),
            complex: false,
            complex_parts: None,
            words: None,
            fields: Vec::new(),
            cells: Vec::new(),
            text: None,
            opaque: None,
            object_class: None,
            events: Vec::new(),
        }
    }

    /// Its dimensions as MATLAB writes them: `60000 x 2`.
    pub fn shape(&self) -> String {
        let dims: Vec<String> = self.dims.iter().map(usize::to_string).collect();
        dims.join(" x ")
    }
}

/// Deepest struct nesting decoded.
const MAX_DEPTH: usize = 32;
const MX_CELL: u32 = 1;
const MX_STRUCT: u32 = 2;
const MX_OBJECT: u32 = 3;
const MX_CHAR: u32 = 4;
const MX_OPAQUE: u32 = 17;

struct Reader<'a> {
    bytes: &'a [u8],
    little: bool,
}

impl Reader<'_> {
    fn u32_at(&self, at: usize) -> Result<u32, String> {
        let b: [u8; 4] = self
            .bytes
            .get(at..at + 4)
            .and_then(|s| s.try_into().ok())
            .ok_or_else(|| format!("truncated: the file ends inside the tag at byte {at}"))?;
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    /// The element at `at`: (type, data range, next element offset).
    fn element(&self, at: usize) -> Result<(u32, std::ops::Range<usize>, usize), String> {
        let first = self.u32_at(at)?;
        if first >> 16 != 0 {
            // small data element: size in the upper 16 bits, data in the next 4 bytes
            let (kind, size) = (first & 0xffff, (first >> 16) as usize);
            if size > 4 || at + 8 > self.bytes.len() {
                return Err(format!("corrupt small element at byte {at}"));
            }
            return Ok((kind, at + 4..at + 4 + size, at + 8));
        }
        let size = self.u32_at(at + 4)? as usize;
        let start = at + 8;
        let end = start
            .checked_add(size)
            .filter(|e| *e <= self.bytes.len())
            .ok_or_else(|| {
                format!(
                    "truncated: the element at byte {at} needs {} bytes, the file has {}",
                    size + 8,
                    self.bytes.len() - at
                )
            })?;
        let next = if first == MI_COMPRESSED {
            end
        } else {
            end.div_ceil(8) * 8
        };
        Ok((first, start..end, next.min(self.bytes.len()).max(end)))
    }

    /// Numbers of any numeric MAT type as f64.
    fn numbers(&self, kind: u32, data: &[u8]) -> Result<Vec<f64>, String> {
        macro_rules! conv {
            ($t:ty, $n:expr) => {
                data.chunks_exact($n)
                    .map(|c| {
                        let b: [u8; $n] = c.try_into().unwrap_or([0; $n]);
                        (if self.little {
                            <$t>::from_le_bytes(b)
                        } else {
                            <$t>::from_be_bytes(b)
                        }) as f64
                    })
                    .collect()
            };
        }
        Ok(match kind {
            1 => data.iter().map(|b| *b as i8 as f64).collect(),
            2 => data.iter().map(|b| *b as f64).collect(),
            3 => conv!(i16, 2),
            4 => conv!(u16, 2),
            5 => conv!(i32, 4),
            6 => conv!(u32, 4),
            7 => conv!(f32, 4),
            9 => conv!(f64, 8),
            12 => conv!(i64, 8),
            13 => conv!(u64, 8),
            other => {
                return Err(format!(
                    "data of MAT type {other} where numbers were expected"
                ))
            }
        })
    }
}

fn class_name(class: u32) -> &'static str {
    match class {
        1 => "cell",
        2 => "struct",
        3 => "object",
        4 => "char",
        5 => "sparse",
        6 => "double",
        7 => "single",
        8 => "int8",
        9 => "uint8",
        10 => "int16",
        11 => "uint16",
        12 => "int32",
        13 => "uint32",
        14 => "int64",
        15 => "uint64",
        16 => "function handle",
        17 => "opaque",
        _ => "unknown class",
    }
}

/// The variables of a level-5 MAT-file (after the header checks of the
/// caller). A file with MATLAB objects ends in a variable without a name:
/// the subsystem ([`crate::mcos`]) that holds their properties.
pub fn variables(bytes: &[u8]) -> Result<Vec<Variable>, String> {
    const HEADER: usize = 128;
    if bytes.len() < HEADER {
        return Err(format!(
            "truncated: {} bytes, shorter than the 128-byte header",
            bytes.len()
        ));
    }
    let little = match &bytes[126..128] {
        b"IM" => true,
        b"MI" => false,
        _ => return Err("not a MAT-file: no endian indicator (IM or MI) at byte 126".into()),
    };
    body(bytes, HEADER, little, &mut 0)
}

/// The variables of a MAT-file body: data elements from `start` to the end.
pub(crate) fn body(
    bytes: &[u8],
    start: usize,
    little: bool,
    decoded: &mut usize,
) -> Result<Vec<Variable>, String> {
    let file = Reader { bytes, little };
    let mut out = Vec::new();
    let mut at = start;
    while at < bytes.len() {
        let (kind, range, next) = file.element(at)?;
        match kind {
            MI_MATRIX => out.push(matrix(&file, range, at, 0)?),
            MI_COMPRESSED => {
                let inflated = inflate(&bytes[range], little, at, decoded)?;
                let inner = Reader {
                    bytes: &inflated,
                    little,
                };
                let (kind, range, _) = inner.element(0)?;
                if kind == MI_MATRIX {
                    out.push(matrix(&inner, range, at, 0)?);
                }
            }
            _ => {} // other top-level elements carry no variable
        }
        at = next;
    }
    Ok(out)
}

/// Inflate one compressed element: its tag first, then exactly the bytes it declares.
fn inflate(data: &[u8], little: bool, at: usize, decoded: &mut usize) -> Result<Vec<u8>, String> {
    let bad = |e: std::io::Error| format!("compressed variable at byte {at} is corrupt ({e})");
    let mut z = flate2::read::ZlibDecoder::new(data);
    let mut tag = [0u8; 8];
    z.read_exact(&mut tag).map_err(bad)?;
    let word = |b: [u8; 4]| {
        if little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        }
    };
    let first = word([tag[0], tag[1], tag[2], tag[3]]);
    let size = if first >> 16 != 0 {
        0
    } else {
        word([tag[4], tag[5], tag[6], tag[7]]) as usize
    };
    *decoded = decoded.saturating_add(size + 8);
    if *decoded > MAX_DECODED_BYTES {
        return Err(format!(
            "the variables decompress to more than {MAX_DECODED_BYTES} bytes; limpid reads at most that much"
        ));
    }
    let mut out = tag.to_vec();
    let got = z.take(size as u64).read_to_end(&mut out).map_err(bad)?;
    if got < size {
        return Err(format!(
            "truncated: the compressed variable at byte {at} declares {size} bytes and holds {got}"
        ));
    }
    Ok(out)
}

/// Decode an `miMATRIX` element's sub-elements.
fn matrix(
    r: &Reader,
    range: std::ops::Range<usize>,
    at: usize,
    depth: usize,
) -> Result<Variable, String> {
    if depth > MAX_DEPTH {
        return Err(format!(
            "the variable at byte {at}: structs nested deeper than {MAX_DEPTH} levels"
        ));
    }
    let end = range.end;
    let sub = Reader {
        bytes: &r.bytes[..end],
        little: r.little,
    };
    let p = std::cell::Cell::new(range.start);
    let next = || -> Result<(u32, std::ops::Range<usize>), String> {
        if p.get() >= end {
            return Err(format!("the variable at byte {at} ends before its parts"));
        }
        let (kind, range, n) = sub.element(p.get())?;
        p.set(n);
        Ok((kind, range))
    };
    if range.is_empty() {
        // MATLAB's canonical empty array (a cell element or field left [])
        return Ok(Variable::empty(""));
    }
    let (_, flags) = next()?;
    let flags = r.numbers(6, &r.bytes[flags])?;
    let flags = *flags
        .first()
        .ok_or(format!("variable at byte {at} has no array flags"))? as u32;
    let class = flags & 0xff;
    let complex = flags & 0x0800 != 0;
    let text =
        |range: std::ops::Range<usize>| String::from_utf8_lossy(&r.bytes[range]).into_owned();
    if class == MX_OPAQUE {
        // no dimensions: name, type system, class name, then the metadata array
        let (_, name) = next()?;
        let (_, system) = next()?;
        let (_, class_name) = next()?;
        let (kind, metadata) = next()?;
        if kind != MI_MATRIX {
            return Err(format!("the object at byte {at} has no metadata array"));
        }
        let mut var = Variable::empty(&text(name));
        var.class = "opaque";
        var.dims = Vec::new();
        var.real = None;
        var.opaque = Some(Box::new(Opaque {
            type_system: text(system),
            class_name: text(class_name),
            metadata: matrix(r, metadata, at, depth + 1)?,
        }));
        return Ok(var);
    }
    let (_, dims) = next()?;
    let dims: Vec<usize> = r
        .numbers(5, &r.bytes[dims])?
        .into_iter()
        .map(|d| d.max(0.0) as usize)
        .collect();
    let (_, name) = next()?;
    let name = String::from_utf8_lossy(&r.bytes[name]).into_owned();
    let numeric = (6..=15).contains(&class);
    let expected = dims.iter().try_fold(1usize, |a, d| a.checked_mul(*d));
    // 64-bit words kept exact too (a MATLAB string packs UTF-16 into them)
    let words = std::cell::RefCell::new(None);
    let part = || -> Result<Vec<f64>, String> {
        let (kind, data) = next()?;
        let values = r.numbers(kind, &r.bytes[data.clone()])?;
        if expected != Some(values.len()) {
            return Err(format!(
                "variable {name}: {} values for dimensions {dims:?}",
                values.len()
            ));
        }
        if kind == 13 {
            *words.borrow_mut() = Some(
                r.bytes[data]
                    .chunks_exact(8)
                    .map(|c| {
                        let b: [u8; 8] = c.try_into().expect("8 bytes");
                        if r.little {
                            u64::from_le_bytes(b)
                        } else {
                            u64::from_be_bytes(b)
                        }
                    })
                    .collect(),
            );
        }
        Ok(values)
    };
    let (real, complex_parts) = match (numeric, complex) {
        (true, false) => (Some(part()?), None),
        // a complex array is no channel, but a MATLAB datetime keeps its
        // milliseconds in the real part and their fraction in the imaginary
        (true, true) => {
            let re = part()?;
            (None, Some((re, part()?)))
        }
        _ => (None, None),
    };
    let count = dims.iter().try_fold(1usize, |a, d| a.checked_mul(*d));
    let mut object_class = None;
    if class == MX_OBJECT {
        let (_, class_name) = next()?;
        object_class = Some(text(class_name));
    }
    let mut cells = Vec::new();
    if class == MX_CELL {
        // each element is an miMATRIX of at least its 8-byte tag
        let n = count.filter(|n| *n <= (end - p.get()) / 8).ok_or_else(|| {
            format!("cell array {name}: dimensions {dims:?} for the bytes it holds")
        })?;
        for _ in 0..n {
            let (kind, range) = next()?;
            if kind != MI_MATRIX {
                return Err(format!(
                    "cell array {name}: an element is not a MATLAB array"
                ));
            }
            cells.push(matrix(r, range, at, depth + 1)?);
        }
    }
    let mut chars = None;
    if class == MX_CHAR && !complex && p.get() < end {
        let (kind, data) = next()?;
        let units: Vec<u32> = match kind {
            16 => String::from_utf8_lossy(&r.bytes[data])
                .chars()
                .map(u32::from)
                .collect(),
            1 | 2 | 17 => r.bytes[data].iter().map(|b| u32::from(*b)).collect(),
            _ => r
                .numbers(kind, &r.bytes[data])?
                .into_iter()
                .map(|v| v as u32)
                .collect(),
        };
        // the rows come from the dimensions: no more than there are characters
        let rows = dims
            .first()
            .copied()
            .unwrap_or(1)
            .clamp(1, units.len().max(1));
        let cols = units.len() / rows;
        let lines: Vec<String> = (0..rows)
            .map(|i| {
                (0..cols)
                    .filter_map(|j| char::from_u32(units[j * rows + i]))
                    .collect()
            })
            .collect();
        chars = Some(lines.join("\n"));
    }
    let mut fields = Vec::new();
    // a struct without its field parts (an empty struct) has no fields
    if (class == MX_STRUCT || class == MX_OBJECT) && count == Some(1) && p.get() < end {
        // field name length, the names (each that many bytes, NUL-padded), then one miMATRIX per field
        let (kind, len) = next()?;
        let len = r
            .numbers(kind, &r.bytes[len])?
            .first()
            .copied()
            .unwrap_or(0.0) as usize;
        let (_, names) = next()?;
        let names = &r.bytes[names];
        if len == 0 || !names.len().is_multiple_of(len) {
            return Err(format!(
                "struct {name}: field names of {} bytes do not split into names of {len}",
                names.len()
            ));
        }
        for raw in names.chunks(len) {
            let field =
                String::from_utf8_lossy(raw.split(|b| *b == 0).next().unwrap_or(&[])).into_owned();
            let (kind, range) = next()?;
            if kind != MI_MATRIX {
                return Err(format!(
                    "struct {name}: field {field} is not a MATLAB array"
                ));
            }
            let mut v = matrix(r, range, at, depth + 1)?;
            v.name = field;
            fields.push(v);
        }
    }
    Ok(Variable {
        name,
        class: class_name(class),
        dims,
        real,
        complex,
        complex_parts,
        words: words.into_inner(),
        fields,
        cells,
        text: chars,
        opaque: None,
        object_class,
        events: Vec::new(),
    })
}

/// MATLAB classes whose saved properties are packed words, not numbers.
const OPAQUE_CLASSES: [&str; 3] = ["string", "function_handle", "containers.Map"];

/// Most columns of a matrix read as channels (`m(:,1)` .. `m(:,k)`).
const MAX_COLUMNS: usize = 1024;

/// Every variable, struct field and object property as (dotted path, values
/// of a real numeric vector or `None`, why it is not a channel). A real
/// matrix gives its columns in MATLAB's syntax, `rec.data(:,2)`; a real
/// scalar is kept as a scalar (a sample increment for `[time]`); an object
/// is described with its class and properties, which are read as fields.
pub fn flatten(vars: Vec<Variable>, prefix: &str, out: &mut Vec<crate::sources::Found>) {
    walk(vars, prefix, false, out);
}

fn walk(vars: Vec<Variable>, prefix: &str, in_object: bool, out: &mut Vec<crate::sources::Found>) {
    use crate::sources::Listing;
    for var in vars {
        let path = if prefix.is_empty() {
            var.name.clone()
        } else {
            format!("{prefix}.{}", var.name)
        };
        let samples: usize = var.dims.iter().product();
        let vector = var.dims.len() == 2 && var.dims.contains(&1) && samples > 1;
        let described = format!("{path} ({}, {})", var.shape(), var.class);
        // a timetable's text variables: one marker stream each
        let mut columns: Vec<&str> = var.events.iter().map(|e| e.0.as_str()).collect();
        columns.dedup();
        for column in columns {
            let events = var
                .events
                .iter()
                .filter(|e| e.0 == column)
                .map(|e| (e.1, e.2.clone()))
                .collect();
            out.push(crate::sources::Found {
                path: format!("{path}.{column}"),
                values: None,
                why_not: None,
                scalar: None,
                listing: Listing::Quiet,
                events,
            });
        }
        let is_object = var.object_class.is_some();
        let mut found = |values: Option<Vec<f64>>,
                         why_not: Option<String>,
                         scalar: Option<f64>,
                         path: String| {
            let listing = if is_object {
                Listing::Object
            } else if in_object {
                Listing::Quiet
            } else {
                Listing::Unread
            };
            out.push(crate::sources::Found {
                values,
                path,
                why_not,
                scalar,
                listing,
                events: Vec::new(),
            })
        };
        if let Some(class) = &var.object_class {
            if OPAQUE_CLASSES.contains(&class.as_str()) {
                // stored as packed words (a string's UTF-16 in uint64s): not numbers
                found(
                    None,
                    Some(format!("{path}: a MATLAB {class}, not read as numbers")),
                    None,
                    path.clone(),
                );
                continue;
            }
            let properties: Vec<String> = var.fields.iter().map(property_summary).collect();
            found(
                None,
                Some(format!(
                    "{path}: a {class} object; properties {}",
                    if properties.is_empty() {
                        "none".to_string()
                    } else {
                        properties.join(", ")
                    }
                )),
                None,
                path.clone(),
            );
            walk(var.fields, &path, true, out);
            continue;
        }
        if !var.fields.is_empty() {
            walk(var.fields, &path, in_object, out);
            continue;
        }
        if let Some(o) = &var.opaque {
            found(
                None,
                Some(format!(
                    "{path}: a {} object ({}) whose properties could not be read",
                    o.class_name, o.type_system
                )),
                None,
                path.clone(),
            );
            continue;
        }
        let matrix = var.dims.len() == 2 && var.dims[0] > 1 && var.dims[1] > 1;
        match (&var.real, var.complex) {
            (Some(real), false) if matrix && var.dims[1] <= MAX_COLUMNS => {
                let rows = var.dims[0];
                found(
                    None,
                    Some(format!(
                        "{described}: a matrix; its columns are {path}(:,1) to {path}(:,{})",
                        var.dims[1]
                    )),
                    None,
                    path.clone(),
                );
                for (k, column) in real.chunks_exact(rows).enumerate() {
                    found(
                        Some(column.to_vec()),
                        None,
                        None,
                        format!("{path}(:,{})", k + 1),
                    );
                }
                continue;
            }
            (Some(real), false) if samples == 1 => {
                found(
                    None,
                    Some(format!("{described}: a scalar, not a vector")),
                    Some(real[0]),
                    path.clone(),
                );
                continue;
            }
            _ => {}
        }
        let why_not = if var.complex {
            Some(format!("{described}: complex values"))
        } else if var.real.is_none() {
            Some(format!(
                "{described}: not a numeric array{}",
                if var.class == "cell" {
                    " (a cell array)"
                } else {
                    ""
                }
            ))
        } else if !vector {
            Some(format!("{described}: not a vector"))
        } else {
            None
        };
        found(
            if why_not.is_none() { var.real } else { None },
            why_not,
            None,
            path,
        );
    }
}

/// A property as `limpid inspect` lists it: short text and scalars by value
/// (`domainIncr = 0.001`, `chanNames = {'pos1', 'tq1'}`), the rest by shape
/// and class.
fn property_summary(f: &Variable) -> String {
    let short = |t: &str| {
        let t: String = t.chars().take(40).collect();
        format!("'{t}'")
    };
    if let Some(c) = &f.object_class {
        return format!("{} ({c} object)", f.name);
    }
    if let Some(t) = &f.text {
        return format!("{} = {}", f.name, short(t));
    }
    if let (Some(real), false) = (&f.real, f.complex) {
        if real.len() == 1 {
            return format!("{} = {}", f.name, limpid_core::error::Num(real[0]));
        }
    }
    if !f.cells.is_empty() && f.cells.len() <= 8 && f.cells.iter().all(|c| c.text.is_some()) {
        let texts: Vec<String> = f
            .cells
            .iter()
            .map(|c| short(c.text.as_deref().unwrap_or("")))
            .collect();
        return format!("{} = {{{}}}", f.name, texts.join(", "));
    }
    format!("{} ({}, {})", f.name, f.shape(), f.class)
}
