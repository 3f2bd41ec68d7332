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
pub struct Variable {
    pub name: String,
    /// MATLAB class name (`double`, `struct`, `char`, ...).
    pub class: &'static str,
    pub dims: Vec<usize>,
    /// Real values (column-major) of a real numeric array; `None` otherwise.
    pub real: Option<Vec<f64>>,
    pub complex: bool,
    /// The fields of a 1 x 1 struct, each named by its field name.
    pub fields: Vec<Variable>,
}

/// Deepest struct nesting decoded.
const MAX_DEPTH: usize = 32;
const MX_STRUCT: u32 = 2;

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

/// The variables of a level-5 MAT-file (after the header checks of the caller).
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
    let file = Reader { bytes, little };
    let mut out = Vec::new();
    let mut decoded = 0usize;
    let mut at = HEADER;
    while at < bytes.len() {
        let (kind, range, next) = file.element(at)?;
        match kind {
            MI_MATRIX => out.push(matrix(&file, range, at, 0)?),
            MI_COMPRESSED => {
                let inflated = inflate(&bytes[range], little, at, &mut decoded)?;
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
        return Err(format!("empty variable element at byte {at}"));
    }
    let (_, flags) = next()?;
    let flags = r.numbers(6, &r.bytes[flags])?;
    let flags = *flags
        .first()
        .ok_or(format!("variable at byte {at} has no array flags"))? as u32;
    let class = flags & 0xff;
    let complex = flags & 0x0800 != 0;
    let (_, dims) = next()?;
    let dims: Vec<usize> = r
        .numbers(5, &r.bytes[dims])?
        .into_iter()
        .map(|d| d.max(0.0) as usize)
        .collect();
    let (_, name) = next()?;
    let name = String::from_utf8_lossy(&r.bytes[name]).into_owned();
    let numeric = (6..=15).contains(&class);
    let real = if numeric && !complex {
        let (kind, data) = next()?;
        let values = r.numbers(kind, &r.bytes[data])?;
        let expected = dims.iter().try_fold(1usize, |a, d| a.checked_mul(*d));
        if expected != Some(values.len()) {
            return Err(format!(
                "variable {name}: {} values for dimensions {dims:?}",
                values.len()
            ));
        }
        Some(values)
    } else {
        None
    };
    let mut fields = Vec::new();
    // a struct without its field parts (an empty struct) has no fields
    if class == MX_STRUCT && dims.iter().product::<usize>() == 1 && p.get() < end {
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
        fields,
    })
}

/// Every variable and struct field as (dotted path, values of a real numeric
/// vector or `None`, why it is not a channel).
pub fn flatten(vars: Vec<Variable>, prefix: &str, out: &mut Vec<crate::sources::Found>) {
    for var in vars {
        let path = if prefix.is_empty() {
            var.name.clone()
        } else {
            format!("{prefix}.{}", var.name)
        };
        let samples: usize = var.dims.iter().product();
        let vector = var.dims.len() == 2 && var.dims.contains(&1) && samples > 1;
        let dims: Vec<String> = var.dims.iter().map(usize::to_string).collect();
        let described = format!("{path} ({}, {})", dims.join(" x "), var.class);
        if !var.fields.is_empty() {
            flatten(var.fields, &path, out);
            continue;
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
        out.push(crate::sources::Found {
            values: if why_not.is_none() { var.real } else { None },
            path,
            why_not,
        });
    }
}
