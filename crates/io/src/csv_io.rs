//! CSV recordings: the header, numbers by row and column with one-line errors, and the writer (shortest round-trip digits).

use super::{io_err, Table};
use limpid_core::{Error, Recording, Result};
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

/// Read a CSV recording: header row, then one sample per row.
pub fn read_csv(path: &Path) -> Result<Recording> {
    let file = limpid_core::files::open_input(path)?;
    if file.metadata().map_err(io_err(path))?.len() == 0 {
        return Err(Error::Empty {
            path: path.to_path_buf(),
        });
    }
    read_csv_from(path, file)
}

/// Read CSV text from `file`; `path` names it in errors.
pub(crate) fn read_csv_from(path: &Path, file: impl std::io::Read) -> Result<Recording> {
    read_csv_table(path, file)?.into_recording(path)
}

/// The cells of a CSV table, every one parsed as a number.
pub(crate) fn read_csv_table(path: &Path, file: impl std::io::Read) -> Result<Table> {
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
    Ok(Table {
        names,
        columns,
        first_row: 2,
        warnings: Vec::new(),
    })
}

/// Write a CSV recording with full round-trip precision.
pub fn write_csv(rec: &Recording, path: &Path) -> Result<()> {
    limpid_core::files::write_atomic(path, |w| write_csv_to(rec, path, w))
}

pub(crate) fn write_csv_to(rec: &Recording, path: &Path, w: &mut impl Write) -> Result<()> {
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
            let _ = write!(line, "{}", limpid_core::CsvNumber(c[i]));
        }
        line.push('\n');
        w.write_all(line.as_bytes()).map_err(io_err(path))?;
    }
    w.flush().map_err(io_err(path))
}
