//! MATLAB `-v7.3` MAT-files: HDF5 files (after a 512-byte MATLAB header)
//! whose datasets carry a `MATLAB_class` attribute, read with the pure-Rust
//! `hdf5-reader` crate (no system HDF5; bounds-checked, cycle- and
//! depth-limited traversal).
//!
//! Channels are the real numeric vectors (any numeric class or logical),
//! named by their dotted path from the top-level variable (`rec.EndEffX`,
//! `rec.force.fx`; structs are HDF5 groups). MATLAB writes arrays
//! column-major, so an N x 1 vector is stored 1 x N: either way it is a
//! vector. The stream holds the vectors of the most common length; others
//! (and scalars, matrices, strings) are listed in a note. Refused with the
//! variable's name and class when named by a map: cell arrays, sparse and
//! complex arrays. MATLAB objects (classdef, `table`, `timetable`: datasets
//! with `MATLAB_object_decode` 3) are resolved through `#subsystem#/MCOS`
//! as in level-5 files ([`crate::mcos`], issue 62).

use std::path::Path;

use hdf5_reader::group::Group;
use hdf5_reader::{Dataset, Datatype, Hdf5File};

use super::Source;
use limpid_core::{Error, Result};

/// Deepest struct nesting followed.
const MAX_DEPTH: usize = 32;
/// Most datasets listed.
const MAX_OBJECTS: usize = 100_000;
/// Most bytes decoded from one file's numeric vectors, all together.
const MAX_DECODED_BYTES: u64 = 512 << 20;
/// Most bytes decoded per byte of the file: deflate expands at most about
/// 1032 times; more is a dataset declared larger than what it stores (HDF5
/// fills unstored chunks), which the decoder would allocate whole (issue 56).
const MAX_EXPANSION: u64 = 1100;

/// What is left of the bytes one file may decode to.
struct Budget {
    left: u64,
    limit: u64,
    file_bytes: u64,
}

impl Budget {
    fn new(file_bytes: usize) -> Self {
        let file_bytes = file_bytes as u64;
        let limit = MAX_DECODED_BYTES.min(file_bytes.saturating_mul(MAX_EXPANSION));
        Budget {
            left: limit,
            limit,
            file_bytes,
        }
    }

    /// Take `bytes` for `what`, or say why not before anything is allocated.
    fn take(&mut self, what: &str, bytes: u64) -> std::result::Result<(), String> {
        if bytes > self.left {
            let mb = |b: u64| limpid_core::error::significant(b as f64 / 1048576.0, 3);
            let why = if self.limit < MAX_DECODED_BYTES {
                format!(
                    "more than {MAX_EXPANSION} times the file's {} bytes: it declares data it does not store",
                    self.file_bytes
                )
            } else {
                format!(
                    "more than the {} MB limpid decodes from one MAT-file",
                    mb(MAX_DECODED_BYTES)
                )
            };
            return Err(format!(
                "{what}: {} MB decoded with the fields before it, {why}",
                mb(self.limit - self.left + bytes)
            ));
        }
        self.left -= bytes;
        Ok(())
    }
}

/// Bytes a dataset declares (its shape times its element size): what its
/// decoder would allocate, whatever the file holds.
fn declared_bytes(d: &Dataset) -> u64 {
    let elements = d.shape().iter().fold(1u64, |a, &b| a.saturating_mul(b));
    let size = d.raw_element_size().map_or(8, |s| s as u64).max(1);
    elements.saturating_mul(size)
}

/// Bytes of one element of a numeric dataset.
fn element_bytes(d: &Dataset) -> u64 {
    match d.dtype() {
        Datatype::FloatingPoint { size, .. } | Datatype::FixedPoint { size, .. } => {
            u64::from(*size).max(1)
        }
        _ => 8,
    }
}

use super::Found;
use crate::mat::{Opaque, Variable};

fn class_of_dataset(d: &Dataset) -> Option<String> {
    d.attribute("MATLAB_class")
        .ok()
        .and_then(|a| a.read_string().ok())
}

fn class_of_group(g: &Group) -> Option<String> {
    g.attribute("MATLAB_class")
        .ok()
        .and_then(|a| a.read_string().ok())
}

fn numeric_class(class: &str) -> bool {
    matches!(
        class,
        "double"
            | "single"
            | "int8"
            | "uint8"
            | "int16"
            | "uint16"
            | "int32"
            | "uint32"
            | "int64"
            | "uint64"
            | "logical"
    )
}

/// The values of a numeric dataset as f64.
fn read_f64(d: &Dataset) -> std::result::Result<Vec<f64>, String> {
    let e = |e: hdf5_reader::error::Error| e.to_string();
    Ok(match d.dtype() {
        Datatype::FloatingPoint { size: 8, .. } => {
            d.read_array::<f64>().map_err(e)?.into_iter().collect()
        }
        Datatype::FloatingPoint { size: 4, .. } => d
            .read_array::<f32>()
            .map_err(e)?
            .into_iter()
            .map(f64::from)
            .collect(),
        Datatype::FixedPoint { size, signed, .. } => match (size, signed) {
            (1, true) => d
                .read_array::<i8>()
                .map_err(e)?
                .into_iter()
                .map(f64::from)
                .collect(),
            (1, false) => d
                .read_array::<u8>()
                .map_err(e)?
                .into_iter()
                .map(f64::from)
                .collect(),
            (2, true) => d
                .read_array::<i16>()
                .map_err(e)?
                .into_iter()
                .map(f64::from)
                .collect(),
            (2, false) => d
                .read_array::<u16>()
                .map_err(e)?
                .into_iter()
                .map(f64::from)
                .collect(),
            (4, true) => d
                .read_array::<i32>()
                .map_err(e)?
                .into_iter()
                .map(f64::from)
                .collect(),
            (4, false) => d
                .read_array::<u32>()
                .map_err(e)?
                .into_iter()
                .map(f64::from)
                .collect(),
            (8, true) => d
                .read_array::<i64>()
                .map_err(e)?
                .into_iter()
                .map(|v| v as f64)
                .collect(),
            (8, false) => d
                .read_array::<u64>()
                .map_err(e)?
                .into_iter()
                .map(|v| v as f64)
                .collect(),
            _ => return Err(format!("integers of {size} bytes")),
        },
        Datatype::Compound { .. } => {
            return Err("complex values; a recording holds real numbers".into())
        }
        other => return Err(format!("HDF5 type {other:?}")),
    })
}

fn walk(
    group: &Group,
    prefix: &str,
    depth: usize,
    seen: &mut std::collections::HashSet<u64>,
    budget: &mut Budget,
    out: &mut Vec<Found>,
) -> std::result::Result<(), String> {
    // a group linked from two places (or from inside itself: a cycle) is read once
    if !seen.insert(group.address()) {
        return Ok(());
    }
    if depth > MAX_DEPTH {
        return Err(format!(
            "{prefix}: structs nested deeper than {MAX_DEPTH} levels"
        ));
    }
    let (groups, datasets) = group
        .members()
        .map_err(|e| format!("{}: {e}", if prefix.is_empty() { "/" } else { prefix }))?;
    for d in datasets {
        if out.len() >= MAX_OBJECTS {
            return Err(format!("more than {MAX_OBJECTS} variables and fields"));
        }
        let name = d.name().to_string();
        if name.starts_with('#') {
            continue; // MATLAB's #refs# and #subsystem#
        }
        let path = if prefix.is_empty() {
            name
        } else {
            format!("{prefix}.{name}")
        };
        let class = class_of_dataset(&d).unwrap_or_else(|| "unknown".into());
        let shape: Vec<u64> = d.shape().to_vec();
        let dims: Vec<String> = shape.iter().rev().map(u64::to_string).collect();
        let described = format!("{path} ({}, {class})", dims.join(" x "));
        let elements: u64 = shape.iter().fold(1u64, |a, &b| a.saturating_mul(b));
        let vector =
            shape.len() <= 2 && elements > 1 && shape.iter().filter(|s| **s > 1).count() == 1;
        let empty = d.attribute("MATLAB_empty").is_ok();
        let sparse = d.attribute("MATLAB_sparse").is_ok();
        let why_not = if sparse {
            Some(format!("{described}: a sparse array"))
        } else if class == "cell" {
            Some(format!(
                "{described}: a cell array (save each column as a numeric vector)"
            ))
        } else if !numeric_class(&class) {
            Some(format!(
                "{described}: class {class} is not a numeric vector{}",
                if class == "table" || class == "timetable" {
                    " (save a table with table2struct(T, 'ToScalar', true), or writetable to CSV)"
                } else {
                    ""
                }
            ))
        } else if empty || !vector {
            Some(format!("{described}: not a vector"))
        } else {
            None
        };
        let values = match why_not {
            None => {
                // decoded size, as f64 and as stored, checked before the decoder allocates
                let bytes = elements.saturating_mul(8 + element_bytes(&d));
                budget.take(&described, bytes)?;
                Some(read_f64(&d).map_err(|m| format!("{described}: {m}"))?)
            }
            Some(_) => None,
        };
        out.push(Found {
            path,
            values,
            why_not,
            scalar: None,
            listing: Default::default(),
            events: Vec::new(),
        });
    }
    for g in groups {
        let name = g.name().to_string();
        if name.starts_with('#') {
            continue;
        }
        let path = if prefix.is_empty() {
            name
        } else {
            format!("{prefix}.{name}")
        };
        match class_of_group(&g).as_deref() {
            Some("struct") | None => walk(&g, &path, depth + 1, seen, budget, out)?,
            Some(class) => out.push(Found {
                why_not: Some(format!(
                    "{path} ({class}): a MATLAB object, not a struct{}",
                    if class == "table" {
                        " (save it with table2struct(T, 'ToScalar', true))"
                    } else {
                        ""
                    }
                )),
                path,
                values: None,
                scalar: None,
                listing: Default::default(),
                events: Vec::new(),
            }),
        }
    }
    Ok(())
}

/// Read a v7.3 MAT-file held in memory.
pub fn read_bytes(path: &Path, bytes: &[u8]) -> Result<Source> {
    let fail = |message: String| Error::Format {
        path: path.to_path_buf(),
        message,
    };
    let file = limpid_core::error::catch_panic(path, "HDF5 decoder (corrupt file)", || {
        Hdf5File::from_bytes(bytes).map_err(|e| {
            fail(format!(
                "a MAT-file v7.3 whose HDF5 part cannot be read: {e}"
            ))
        })
    })?;
    let mut found = Vec::new();
    let mut notes = Vec::new();
    limpid_core::error::catch_panic(path, "HDF5 decoder (corrupt file)", || {
        let root = file
            .root_group()
            .map_err(|e| fail(format!("HDF5 root group: {e}")))?;
        let mut budget = Budget::new(bytes.len());
        walk(
            &root,
            "",
            0,
            &mut Default::default(),
            &mut budget,
            &mut found,
        )
        .map_err(|m| fail(format!("variable {m}")))?;
        // MATLAB objects replace what the walk said of them
        let objects = objects(&root, &mut budget, &mut notes).map_err(fail)?;
        found.retain(|f| !objects.iter().any(|o| o.path == f.path));
        found.extend(objects);
        Ok(())
    })?;
    let mut source =
        super::vectors_source(path, "MAT v7.3", found).map_err(|e| super::with_notes(e, &notes))?;
    source.notes.extend(notes);
    Ok(source)
}

/// The MATLAB objects among the top-level variables (datasets with
/// `MATLAB_object_decode` 3: their MCOS metadata), resolved through the
/// FileWrapper__ in `#subsystem#/MCOS` whose cells are references into
/// `#refs#`, then listed as the level-5 reader lists them ([`crate::mcos`]).
fn objects(
    root: &Group,
    budget: &mut Budget,
    notes: &mut Vec<String>,
) -> std::result::Result<Vec<Found>, String> {
    let (_, datasets) = root.members().map_err(|e| e.to_string())?;
    let top: Vec<&Dataset> = datasets
        .iter()
        .filter(|d| !d.name().starts_with('#') && d.attribute("MATLAB_object_decode").is_ok())
        .collect();
    if top.is_empty() {
        return Ok(Vec::new());
    }
    let mut reader = Refs {
        refs: root.group("#refs#").ok(),
        offset_size: root.offset_size(),
        budget,
        seen: Vec::new(),
    };
    let mut vars = Vec::new();
    for d in top {
        vars.push(reader.dataset(d, d.name(), 0)?);
    }
    let wrapper = match root.group("#subsystem#").and_then(|g| g.dataset("MCOS")) {
        Ok(d) => reader.cells(&d, 0).map(|cells| (cells, true)),
        Err(_) => {
            Err("the file has objects but no #subsystem#/MCOS to hold their properties".into())
        }
    };
    let vars = crate::mcos::resolve_with(vars, wrapper, notes);
    let mut found = Vec::new();
    crate::mat::flatten(vars, "", &mut found);
    Ok(found)
}

/// Builds level-5 style variables from a v7.3 file's datasets and groups,
/// following cell references into `#refs#` (each referenced object once
/// per path: a cycle ends; depth bounded).
struct Refs<'a> {
    refs: Option<Group>,
    offset_size: u8,
    budget: &'a mut Budget,
    seen: Vec<u64>,
}

fn static_class(class: &str) -> &'static str {
    const CLASSES: [&str; 16] = [
        "double",
        "single",
        "int8",
        "uint8",
        "int16",
        "uint16",
        "int32",
        "uint32",
        "int64",
        "uint64",
        "logical",
        "char",
        "cell",
        "struct",
        "function_handle",
        "canonical empty",
    ];
    CLASSES
        .iter()
        .find(|c| **c == class)
        .copied()
        .unwrap_or("object")
}

impl Refs<'_> {
    fn dataset(
        &mut self,
        d: &Dataset,
        name: &str,
        depth: usize,
    ) -> std::result::Result<Variable, String> {
        if depth > MAX_DEPTH {
            return Err(format!(
                "{name}: cells nested deeper than {MAX_DEPTH} levels"
            ));
        }
        let class = class_of_dataset(d).unwrap_or_else(|| "double".into());
        let dims: Vec<usize> = d.shape().iter().rev().map(|s| *s as usize).collect();
        let mut v = Variable::empty(name);
        v.class = static_class(&class);
        if d.attribute("MATLAB_empty").is_ok() {
            return Ok(v);
        }
        v.dims = dims;
        if d.attribute("MATLAB_object_decode").is_ok() {
            let metadata = if class == "FileWrapper__" {
                let mut cell = Variable::empty("");
                cell.class = "cell";
                cell.real = None;
                cell.cells = self.cells(d, depth + 1)?;
                cell
            } else {
                let mut m = Variable::empty("");
                m.class = "uint32";
                m.dims = v.dims.clone();
                m.real = Some(self.numbers(d, name)?);
                m
            };
            v.class = "opaque";
            v.real = None;
            v.opaque = Some(Box::new(Opaque {
                type_system: "MCOS".into(),
                class_name: class,
                metadata,
            }));
            return Ok(v);
        }
        match class.as_str() {
            "cell" => {
                v.real = None;
                v.cells = self.cells(d, depth + 1)?;
            }
            "char" => {
                v.real = None;
                let units = self.numbers(d, name)?;
                v.text = Some(
                    units
                        .iter()
                        .filter_map(|u| char::from_u32(*u as u32))
                        .collect(),
                );
            }
            c if numeric_class(c) => match d.dtype() {
                // MATLAB's complex doubles: a compound of real and imag
                Datatype::Compound { size: 16, fields }
                    if fields.len() == 2 && fields[1].byte_offset == 8 =>
                {
                    self.budget.take(name, 2 * declared_bytes(d))?;
                    let raw = d.read_raw_bytes().map_err(|e| e.to_string())?;
                    let pairs: Vec<(f64, f64)> = raw
                        .chunks_exact(16)
                        .map(|c| {
                            let f = |b: &[u8]| f64::from_le_bytes(b.try_into().expect("8 bytes"));
                            (f(&c[..8]), f(&c[8..]))
                        })
                        .collect();
                    v.real = None;
                    v.complex = true;
                    v.complex_parts = Some(pairs.into_iter().unzip());
                }
                Datatype::FixedPoint {
                    size: 8,
                    signed: false,
                    ..
                } if class == "uint64" => {
                    // exact words (a MATLAB string packs UTF-16 into them), read
                    // once; the f64 values from them
                    self.budget
                        .take(name, declared_bytes(d).saturating_mul(2))?;
                    let words: Vec<u64> = d
                        .read_array::<u64>()
                        .map_err(|e| format!("{name}: {e}"))?
                        .into_iter()
                        .collect();
                    v.real = Some(words.iter().map(|w| *w as f64).collect());
                    v.words = Some(words);
                }
                _ => v.real = Some(self.numbers(d, name)?),
            },
            _ => v.real = None,
        }
        Ok(v)
    }

    fn numbers(&mut self, d: &Dataset, name: &str) -> std::result::Result<Vec<f64>, String> {
        let elements: u64 = d.shape().iter().fold(1u64, |a, &b| a.saturating_mul(b));
        self.budget
            .take(name, elements.saturating_mul(8 + element_bytes(d)))?;
        read_f64(d).map_err(|m| format!("{name}: {m}"))
    }

    /// The elements a dataset of object references points to.
    fn cells(&mut self, d: &Dataset, depth: usize) -> std::result::Result<Vec<Variable>, String> {
        if depth > MAX_DEPTH {
            return Err(format!("cells nested deeper than {MAX_DEPTH} levels"));
        }
        // the declared size against the budget before the decoder allocates it
        self.budget.take(d.name(), declared_bytes(d))?;
        let raw = d.read_raw_bytes().map_err(|e| e.to_string())?;
        let addresses = hdf5_reader::reference::read_object_references(&raw, self.offset_size)
            .map_err(|e| e.to_string())?;
        let Some(refs) = &self.refs else {
            return Err("a cell refers to #refs#, which the file lacks".into());
        };
        let refs = refs.clone();
        let mut out = Vec::with_capacity(addresses.len().min(MAX_OBJECTS));
        for address in addresses {
            if out.len() >= MAX_OBJECTS {
                return Err(format!("more than {MAX_OBJECTS} cells"));
            }
            if self.seen.contains(&address) {
                out.push(Variable::empty(""));
                continue;
            }
            let name = refs
                .child_name_by_address(address)
                .map_err(|e| e.to_string())?
                .ok_or_else(|| format!("a cell refers to address {address}, outside #refs#"))?;
            self.seen.push(address);
            let v = match refs.dataset(&name) {
                Ok(child) => self.dataset(&child, "", depth),
                Err(_) => match refs.group(&name) {
                    Ok(g) => self.group(&g, "", depth),
                    Err(e) => Err(format!("#refs#/{name}: {e}")),
                },
            };
            self.seen.pop();
            out.push(v?);
        }
        Ok(out)
    }

    /// A struct group's fields.
    fn group(
        &mut self,
        g: &Group,
        name: &str,
        depth: usize,
    ) -> std::result::Result<Variable, String> {
        if depth > MAX_DEPTH {
            return Err(format!(
                "{name}: structs nested deeper than {MAX_DEPTH} levels"
            ));
        }
        let mut v = Variable::empty(name);
        v.class = "struct";
        v.real = None;
        v.dims = vec![1, 1];
        let (groups, datasets) = g.members().map_err(|e| e.to_string())?;
        for d in &datasets {
            v.fields.push(self.dataset(d, d.name(), depth + 1)?);
        }
        for sub in &groups {
            v.fields.push(self.group(sub, sub.name(), depth + 1)?);
        }
        Ok(v)
    }
}
