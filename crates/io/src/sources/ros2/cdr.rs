//! CDR, the serialisation of ROS 2 messages in bags (OMG CDR as written by
//! rmw: XCDR version 1), decoded from a [`Registry`] definition.
//!
//! A message is a 4-byte encapsulation header (`00 01` little-endian,
//! `00 00` big-endian, then two option bytes) and the fields in order. Each
//! primitive is aligned to its size (8 for 64-bit types) counted from the end
//! of the header; a string is a `u32` length that counts its terminating NUL,
//! then the bytes; a sequence is a `u32` element count, then the elements; a
//! fixed array is its elements alone.
//!
//! Bounds: every read is checked against the bytes left; a sequence count
//! larger than the bytes left is refused before its loop; nesting is limited
//! to [`MAX_DEPTH`] (a definition that contains itself) and the elements
//! visited to a budget proportional to the message's size (empty structs).

use super::msg::{Count, Element, Field, Primitive, Registry};
use crate::sources::cursor::Cursor;

/// Deepest nesting of message types.
const MAX_DEPTH: usize = 32;

/// What one message decodes to (reused across messages of a topic).
#[derive(Debug, Default)]
pub(crate) struct Decoded {
    /// Numeric leaves outside the top-level header, in definition order.
    pub values: Vec<f64>,
    /// Sequence lengths, and a hash of each `name` string sequence: messages
    /// of one shape have the same leaves.
    pub shape: Vec<u64>,
    /// The top-level header's stamp (ns), when the type starts with one.
    pub stamp_ns: Option<i64>,
    /// The first text leaf outside the header (a marker's text).
    pub text: Option<String>,
    /// Leaf names (`wrench.force.x`, `position[ankle]`) and their other
    /// names (`position[0]`), made only when asked.
    pub names: Option<Vec<(String, Option<String>)>>,
}

impl Decoded {
    fn clear(&mut self, naming: bool) {
        self.values.clear();
        self.shape.clear();
        self.stamp_ns = None;
        self.text = None;
        self.names = naming.then(Vec::new);
    }
}

struct Reader<'a> {
    /// The shared bounds-checked reader (XDF, TDMS): every read against the bytes left.
    bytes: Cursor<'a>,
    little: bool,
    budget: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        self.bytes.take(n, what)
    }

    fn align(&mut self, n: usize) -> Result<(), String> {
        let off = self.bytes.at - 4;
        let pad = (n - off % n) % n;
        self.take(pad, "alignment padding").map(|_| ())
    }

    fn word<const N: usize>(&mut self, what: &str) -> Result<[u8; N], String> {
        self.align(N)?;
        let b: [u8; N] = self.take(N, what)?.try_into().expect("N bytes");
        Ok(b)
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        let b = self.word::<4>(what)?;
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    fn number(&mut self, p: Primitive, what: &str) -> Result<f64, String> {
        let little = self.little;
        macro_rules! num {
            ($t:ty, $n:literal) => {{
                let b = self.word::<$n>(what)?;
                (if little {
                    <$t>::from_le_bytes(b)
                } else {
                    <$t>::from_be_bytes(b)
                }) as f64
            }};
        }
        Ok(match p {
            Primitive::Bool | Primitive::U8 => self.take(1, what)?[0] as f64,
            Primitive::I8 => self.take(1, what)?[0] as i8 as f64,
            Primitive::I16 => num!(i16, 2),
            Primitive::U16 => num!(u16, 2),
            Primitive::I32 => num!(i32, 4),
            Primitive::U32 => num!(u32, 4),
            Primitive::I64 => num!(i64, 8),
            Primitive::U64 => num!(u64, 8),
            Primitive::F32 => num!(f32, 4),
            Primitive::F64 => num!(f64, 8),
            Primitive::Text | Primitive::WideText => unreachable!("text is read by text()"),
        })
    }

    fn text(&mut self, p: Primitive, what: &str) -> Result<&'a [u8], String> {
        if p == Primitive::WideText {
            return Err(format!("{what}: wstring fields are not read"));
        }
        let n = self.u32(what)? as usize;
        let bytes = self.take(n, what)?;
        // the length counts the terminating NUL
        Ok(bytes.strip_suffix(&[0]).unwrap_or(bytes))
    }

    fn spend(&mut self, n: usize) -> Result<(), String> {
        self.budget = self.budget.checked_sub(n).ok_or_else(|| {
            "more elements than its bytes can hold (a sequence of empty messages?)".to_string()
        })?;
        Ok(())
    }
}

/// Decode `data` (a whole CDR message of type `root`) into `out`; names the
/// leaves when `naming`.
pub(crate) fn decode(
    registry: &Registry,
    root: &str,
    data: &[u8],
    naming: bool,
    out: &mut Decoded,
) -> Result<(), String> {
    out.clear(naming);
    if data.len() < 4 {
        return Err(format!(
            "{} bytes: shorter than the 4-byte CDR header",
            data.len()
        ));
    }
    let little = match (data[0], data[1]) {
        (0, 0) => false,
        (0, 1) => true,
        (a, b) => {
            return Err(format!(
                "representation {a:02x} {b:02x}: only plain CDR (00 00, 00 01) is read"
            ))
        }
    };
    let mut r = Reader {
        bytes: Cursor {
            bytes: data,
            at: 4,
            base: 0,
        },
        little,
        budget: 64 * data.len() + 4096,
    };
    let mut path = String::new();
    walk(registry, root, &mut r, &mut path, 0, out)
}

fn walk(
    registry: &Registry,
    ty: &str,
    r: &mut Reader,
    path: &mut String,
    depth: usize,
    out: &mut Decoded,
) -> Result<(), String> {
    if depth > MAX_DEPTH {
        return Err(format!("{ty}: nested more than {MAX_DEPTH} deep"));
    }
    let fields: &[Field] = registry
        .get(ty)
        .ok_or_else(|| format!("no definition of {ty}"))?;
    // labels of a `name` string sequence, for its numeric siblings
    let mut labels: Option<Vec<String>> = None;
    for (k, f) in fields.iter().enumerate() {
        r.spend(1)?;
        let at = path.len();
        if !path.is_empty() {
            path.push('.');
        }
        path.push_str(&f.name);
        let is_header = matches!(&f.element, Element::Message(m) if m == "std_msgs/Header");
        if depth == 0 && k == 0 && is_header && f.count == Count::One {
            let sec = r.number(Primitive::I32, "header.stamp.sec")? as i64;
            let nanosec = r.number(Primitive::U32, "header.stamp.nanosec")? as i64;
            r.text(Primitive::Text, "header.frame_id")?;
            out.stamp_ns = Some(sec * 1_000_000_000 + nanosec);
            path.truncate(at);
            continue;
        }
        let (count, sequence) = match f.count {
            Count::One => (1, false),
            Count::Fixed(n) => (n, false),
            Count::Sequence => {
                let n = r.u32(path)? as usize;
                if n > r.bytes.left() {
                    return Err(format!(
                        "{path}: a sequence of {n} elements in {} bytes left",
                        r.bytes.left()
                    ));
                }
                out.shape.push(n as u64);
                (n, true)
            }
        };
        r.spend(count)?;
        match &f.element {
            Element::Primitive(p) if p.is_text() => {
                let name_sequence = sequence && f.name == "name";
                let mut hash = 0xcbf2_9ce4_8422_2325u64;
                let mut found = Vec::new();
                for _ in 0..count {
                    let bytes = r.text(*p, path)?;
                    if name_sequence {
                        for &b in bytes.iter().chain(&[0xff]) {
                            hash = (hash ^ b as u64).wrapping_mul(0x100_0000_01b3);
                        }
                        if out.names.is_some() {
                            found.push(String::from_utf8_lossy(bytes).into_owned());
                        }
                    } else if out.text.is_none() && depth == 0 {
                        out.text = Some(String::from_utf8_lossy(bytes).into_owned());
                    }
                }
                if name_sequence {
                    out.shape.push(hash);
                    let unique = found.iter().all(|l| {
                        !l.is_empty()
                            && !l.contains([']', '['])
                            && found.iter().filter(|m| *m == l).count() == 1
                    });
                    labels = (out.names.is_some() && unique).then_some(found);
                }
            }
            Element::Primitive(p) => {
                let label = labels.as_ref().filter(|l| sequence && l.len() == count);
                for i in 0..count {
                    out.values.push(r.number(*p, path)?);
                    if let Some(names) = &mut out.names {
                        names.push(match (f.count, label) {
                            (Count::One, _) => (path.clone(), None),
                            (_, Some(l)) => {
                                (format!("{path}[{}]", l[i]), Some(format!("{path}[{i}]")))
                            }
                            _ => (format!("{path}[{i}]"), None),
                        });
                    }
                }
            }
            Element::Message(m) => {
                for i in 0..count {
                    let inner = path.len();
                    if f.count != Count::One {
                        path.push_str(&format!("[{i}]"));
                    }
                    walk(registry, m, r, path, depth + 1, out)?;
                    path.truncate(inner);
                }
            }
        }
        path.truncate(at);
    }
    Ok(())
}
