//! limpid-io: recordings from and to files (FORMAT.md v1).
//!
//! CSV with a header row, or Parquet with the same column names; the format
//! is chosen by the file extension (`.parquet`/`.pq` for Parquet, `.mat` for
//! MATLAB, anything else is read as CSV). Every value is parsed as `f64`; the
//! table is then checked once by [`Recording::new`]. Errors name file, row and
//! column.
//!
//! MATLAB files (read only): level-5 MAT-files, i.e. MATLAB's `-v6` and
//! default `-v7` (compressed) formats, read with the `matfile` crate. Each
//! column is a real numeric vector variable (row or column, any numeric
//! class) named like the column; scalars, matrices, strings, structs and
//! cells are skipped. `-v7.3` files are HDF5 and are refused with a hint. In
//! errors, "row" counts samples from 1, as MATLAB indexes them.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::sync::Arc;

use limpid_core::{Error, Recording, Result};
use parquet::basic::{Repetition, Type as PhysicalType};
use parquet::column::reader::ColumnReader;
use parquet::data_type::DoubleType;
use parquet::file::properties::WriterProperties;
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::file::writer::SerializedFileWriter;
use parquet::schema::types::Type;

/// True when the path names a Parquet file.
pub fn is_parquet(path: &Path) -> bool {
    matches!(
        path.extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref(),
        Some("parquet" | "pq")
    )
}

/// True when the path names a MATLAB MAT-file.
pub fn is_mat(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("mat"))
}

/// Read a recording, choosing the format by extension.
pub fn read_recording(path: impl AsRef<Path>) -> Result<Recording> {
    let path = path.as_ref();
    if is_parquet(path) {
        read_parquet(path)
    } else if is_mat(path) {
        read_mat(path)
    } else {
        read_csv(path)
    }
}

/// Write a recording, choosing the format by extension (CSV or Parquet).
pub fn write_recording(rec: &Recording, path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    if is_parquet(path) {
        write_parquet(rec, path)
    } else if is_mat(path) {
        Err(Error::Format {
            path: path.to_path_buf(),
            message: "limpid reads MAT-files but does not write them; write .csv or .parquet (MATLAB reads both: readtable, parquetread)".into(),
        })
    } else {
        write_csv(rec, path)
    }
}

/// Read a MATLAB level-5 MAT-file: one real numeric vector per column.
pub fn read_mat(path: &Path) -> Result<Recording> {
    let bytes = std::fs::read(path).map_err(io_err(path))?;
    if bytes.is_empty() {
        return Err(Error::Empty {
            path: path.to_path_buf(),
        });
    }
    let fail = |message: String| Error::Format {
        path: path.to_path_buf(),
        message,
    };
    let header = String::from_utf8_lossy(&bytes[..bytes.len().min(116)]);
    if header.starts_with("MATLAB 7.3 MAT-file") {
        return Err(fail(
            "a MAT-file v7.3 (HDF5) is not read; save it with save(..., '-v7') or as CSV/Parquet"
                .into(),
        ));
    }
    if !header.starts_with("MATLAB 5.0 MAT-file") {
        return Err(fail(
            "not a MAT-file: the header does not start with \"MATLAB 5.0 MAT-file\"".into(),
        ));
    }
    check_mat_elements(&bytes).map_err(fail)?;
    let mat = matfile::MatFile::parse(bytes.as_slice())
        .map_err(|e| fail(format!("not a readable MAT-file: {e}")))?;
    let (mut names, mut columns, mut skipped) = (Vec::new(), Vec::new(), Vec::new());
    for array in mat.arrays() {
        let size = array.size();
        let samples: usize = size.iter().product();
        let vector = size.len() == 2 && size.contains(&1) && samples > 1;
        if !vector {
            let dims: Vec<String> = size.iter().map(usize::to_string).collect();
            skipped.push(format!("{} ({})", array.name(), dims.join(" x ")));
            continue;
        }
        let values = mat_real_values(array.data()).ok_or_else(|| {
            fail(format!(
                "variable {}: complex values; a recording holds real numbers",
                array.name()
            ))
        })?;
        names.push(array.name().to_string());
        columns.push(values);
    }
    if names.is_empty() {
        return Err(fail(format!(
            "no numeric vector variable to read as a column (found {}); save each column (t, x, fx, ...) as a vector",
            if skipped.is_empty() {
                "no numeric variable".to_string()
            } else {
                skipped.join(", ")
            }
        )));
    }
    Recording::new(path, names, columns, 1)
}

/// Walk the top-level data elements (8-byte tag: type, byte count) and refuse
/// a file that ends inside one: the parser would return the variables before
/// the cut as if the file were whole.
fn check_mat_elements(bytes: &[u8]) -> std::result::Result<(), String> {
    const HEADER: usize = 128;
    const COMPRESSED: u32 = 15;
    if bytes.len() < HEADER {
        return Err(format!(
            "truncated: {} bytes, shorter than the 128-byte header",
            bytes.len()
        ));
    }
    let little = &bytes[126..128] == b"IM";
    let word = |at: usize| {
        let b = [bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]];
        if little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        }
    };
    let mut at = HEADER;
    while at < bytes.len() {
        if at + 8 > bytes.len() {
            return Err(format!(
                "truncated: the file ends inside the tag at byte {at}"
            ));
        }
        let (kind, size) = (word(at), word(at + 4) as usize);
        let mut next = at + 8 + size;
        if kind != COMPRESSED {
            next = next.div_ceil(8) * 8; // uncompressed elements are padded to 8 bytes
        }
        if next > bytes.len() {
            return Err(format!(
                "truncated: the variable at byte {at} needs {} bytes, the file has {}",
                next - at,
                bytes.len() - at
            ));
        }
        at = next;
    }
    Ok(())
}

/// The values of a real numeric array as f64; `None` if it is complex.
fn mat_real_values(data: &matfile::NumericData) -> Option<Vec<f64>> {
    use matfile::NumericData as D;
    macro_rules! real {
        ($real:expr, $imag:expr) => {
            $imag
                .is_none()
                .then(|| $real.iter().map(|v| *v as f64).collect())
        };
    }
    match data {
        D::Int8 { real, imag } => real!(real, imag),
        D::UInt8 { real, imag } => real!(real, imag),
        D::Int16 { real, imag } => real!(real, imag),
        D::UInt16 { real, imag } => real!(real, imag),
        D::Int32 { real, imag } => real!(real, imag),
        D::UInt32 { real, imag } => real!(real, imag),
        D::Int64 { real, imag } => real!(real, imag),
        D::UInt64 { real, imag } => real!(real, imag),
        D::Single { real, imag } => real!(real, imag),
        D::Double { real, imag } => real!(real, imag),
    }
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Read a CSV recording: header row, then one sample per row.
pub fn read_csv(path: &Path) -> Result<Recording> {
    let file = File::open(path).map_err(io_err(path))?;
    if file.metadata().map_err(io_err(path))?.len() == 0 {
        return Err(Error::Empty {
            path: path.to_path_buf(),
        });
    }
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .flexible(true)
        .buffer_capacity(1 << 20)
        .from_reader(file);
    let csv_err = |e: csv::Error| Error::Format {
        path: path.to_path_buf(),
        message: format!("not a readable CSV table: {e}"),
    };
    let names: Vec<String> = reader
        .headers()
        .map_err(csv_err)?
        .iter()
        .map(|h| h.trim().to_string())
        .collect();
    if names.iter().all(String::is_empty) {
        return Err(Error::Empty {
            path: path.to_path_buf(),
        });
    }
    if let Some(i) = names.iter().position(String::is_empty) {
        return Err(Error::Format {
            path: path.to_path_buf(),
            message: format!("row 1, column {}: empty column name", i + 1),
        });
    }
    let mut columns: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
    let mut record = csv::ByteRecord::new();
    let mut row = 1;
    while reader.read_byte_record(&mut record).map_err(csv_err)? {
        row += 1;
        if record.len() == 1 && record[0].iter().all(u8::is_ascii_whitespace) {
            continue; // blank line
        }
        if record.len() != names.len() {
            return Err(Error::RaggedRow {
                path: path.to_path_buf(),
                row,
                expected: names.len(),
                found: record.len(),
            });
        }
        for (k, cell) in record.iter().enumerate() {
            let text = std::str::from_utf8(cell).unwrap_or("").trim();
            match text.parse::<f64>() {
                Ok(v) => columns[k].push(v),
                Err(_) => {
                    return Err(Error::NotANumber {
                        path: path.to_path_buf(),
                        row,
                        column: names[k].clone(),
                        found: String::from_utf8_lossy(cell).into_owned(),
                    })
                }
            }
        }
    }
    Recording::new(path, names, columns, 2)
}

/// Read a Parquet recording: numeric columns (double, float, int32, int64), no nulls.
pub fn read_parquet(path: &Path) -> Result<Recording> {
    let file = File::open(path).map_err(io_err(path))?;
    if file.metadata().map_err(io_err(path))?.len() == 0 {
        return Err(Error::Empty {
            path: path.to_path_buf(),
        });
    }
    let pq_err = |e: parquet::errors::ParquetError| Error::Format {
        path: path.to_path_buf(),
        message: format!("not a readable Parquet file: {e}"),
    };
    let reader = SerializedFileReader::new(file).map_err(pq_err)?;
    let meta = reader.metadata();
    let schema = meta.file_metadata().schema_descr();
    let names: Vec<String> = schema.columns().iter().map(|c| c.path().string()).collect();
    let total = meta.file_metadata().num_rows().max(0) as usize;
    let mut columns: Vec<Vec<f64>> = vec![Vec::with_capacity(total); names.len()];
    for g in 0..reader.num_row_groups() {
        let group = reader.get_row_group(g).map_err(pq_err)?;
        let rows = group.metadata().num_rows().max(0) as usize;
        for (k, out) in columns.iter_mut().enumerate() {
            let start = out.len();
            let mut defs: Vec<i16> = Vec::new();
            let column_reader = group.get_column_reader(k).map_err(pq_err)?;
            macro_rules! read_all {
                ($r:expr, $t:ty) => {{
                    let mut r = $r;
                    let mut vals: Vec<$t> = Vec::with_capacity(rows);
                    let (n_rec, _, _) = r
                        .read_records(rows, Some(&mut defs), None, &mut vals)
                        .map_err(pq_err)?;
                    if vals.len() != n_rec {
                        let missing = defs.iter().position(|d| *d == 0).unwrap_or(0);
                        return Err(Error::NotANumber {
                            path: path.to_path_buf(),
                            row: start + missing + 1,
                            column: names[k].clone(),
                            found: "null".into(),
                        });
                    }
                    out.extend(vals.into_iter().map(|v| v as f64));
                }};
            }
            match column_reader {
                ColumnReader::DoubleColumnReader(r) => read_all!(r, f64),
                ColumnReader::FloatColumnReader(r) => read_all!(r, f32),
                ColumnReader::Int32ColumnReader(r) => read_all!(r, i32),
                ColumnReader::Int64ColumnReader(r) => read_all!(r, i64),
                _ => {
                    return Err(Error::Format {
                        path: path.to_path_buf(),
                        message: format!("column {}: expected a numeric column", names[k]),
                    })
                }
            }
        }
    }
    Recording::new(path, names, columns, 1)
}

/// Write a CSV recording with full round-trip precision.
pub fn write_csv(rec: &Recording, path: &Path) -> Result<()> {
    let file = File::create(path).map_err(io_err(path))?;
    let mut w = BufWriter::new(file);
    let cols: Vec<(&str, &[f64])> = rec.columns().collect();
    let header: Vec<&str> = cols.iter().map(|c| c.0).collect();
    writeln!(w, "{}", header.join(",")).map_err(io_err(path))?;
    let mut line = String::new();
    for i in 0..rec.len() {
        line.clear();
        for (k, (_, c)) in cols.iter().enumerate() {
            if k > 0 {
                line.push(',');
            }
            line.push_str(&format!("{}", c[i]));
        }
        line.push('\n');
        w.write_all(line.as_bytes()).map_err(io_err(path))?;
    }
    w.flush().map_err(io_err(path))
}

/// Write a Parquet recording: one required double column per recording column.
pub fn write_parquet(rec: &Recording, path: &Path) -> Result<()> {
    let pq_err = |e: parquet::errors::ParquetError| Error::Format {
        path: path.to_path_buf(),
        message: format!("cannot write Parquet: {e}"),
    };
    let fields = rec
        .names()
        .iter()
        .map(|n| {
            Type::primitive_type_builder(n, PhysicalType::DOUBLE)
                .with_repetition(Repetition::REQUIRED)
                .build()
                .map(Arc::new)
        })
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(pq_err)?;
    let schema = Arc::new(
        Type::group_type_builder("recording")
            .with_fields(fields)
            .build()
            .map_err(pq_err)?,
    );
    let props = Arc::new(WriterProperties::builder().build());
    let file = File::create(path).map_err(io_err(path))?;
    let mut writer = SerializedFileWriter::new(file, schema, props).map_err(pq_err)?;
    const ROWS_PER_GROUP: usize = 1 << 20;
    let n = rec.len();
    let cols: Vec<&[f64]> = rec.columns().map(|c| c.1).collect();
    let mut start = 0;
    while start < n {
        let end = (start + ROWS_PER_GROUP).min(n);
        let mut group = writer.next_row_group().map_err(pq_err)?;
        for c in &cols {
            let mut col = group
                .next_column()
                .map_err(pq_err)?
                .ok_or_else(|| Error::Format {
                    path: path.to_path_buf(),
                    message: "parquet schema has fewer columns than the recording".into(),
                })?;
            col.typed::<DoubleType>()
                .write_batch(&c[start..end], None, None)
                .map_err(pq_err)?;
            col.close().map_err(pq_err)?;
        }
        group.close().map_err(pq_err)?;
        start = end;
    }
    writer.close().map_err(pq_err)?;
    Ok(())
}
