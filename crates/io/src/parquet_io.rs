//! Parquet recordings: batched reads with a row cap, every compression the format allows, columns that cannot be a recording's left out with a warning, pages checked before they are decoded (issue 13), and the writer.

use super::Table;
use limpid_core::{Error, Recording, Result};
use parquet::basic::Repetition;
use parquet::basic::Type as PhysicalType;
use parquet::column::reader::ColumnReader;
use parquet::data_type::DoubleType;
use parquet::file::properties::WriterProperties;
use parquet::file::reader::FileReader;
use parquet::file::reader::SerializedFileReader;
use parquet::file::writer::SerializedFileWriter;
use parquet::schema::types::Type;
use rayon::prelude::*;
use std::path::Path;
use std::sync::Arc;

/// Most rows read from one Parquet file (the footer could claim any number).
pub const MAX_PARQUET_ROWS: i64 = 1 << 32;

/// Read a Parquet recording: flat numeric columns (double, float, int32,
/// int64), no nulls; any compression the parquet crate decodes (snappy,
/// zstd, gzip, lz4, brotli). Timestamp columns are converted to seconds;
/// nested, repeated, decimal and date columns are refused. A panic inside the
/// parquet crate (a corrupt file) becomes an error naming the file.
pub fn read_parquet(path: &Path) -> Result<Recording> {
    #[cfg(unix)]
    {
        let file = StrictFile::open(path)?;
        limpid_core::error::catch_panic(
            path,
            "Parquet decoder (corrupt or unsupported file)",
            || read_parquet_source(path, file),
        )
    }
    #[cfg(not(unix))]
    {
        let bytes = limpid_core::files::read_bytes(path, MAX_PARQUET_BYTES)?;
        read_recording_bytes(path, bytes)
    }
}

/// Largest Parquet file read (bytes; it is decoded from memory).
pub const MAX_PARQUET_BYTES: u64 = 8 << 30;

pub(crate) fn read_parquet_source<R: parquet::file::reader::ChunkReader + 'static>(
    path: &Path,
    file: R,
) -> Result<Recording> {
    read_parquet_table(path, file)?.into_recording(path)
}

/// A Parquet decoder's error, and any other message, as a format error naming `path`.
fn errors(
    path: &Path,
) -> (
    impl Fn(parquet::errors::ParquetError) -> Error + Copy + '_,
    impl Fn(String) -> Error + Copy + '_,
) {
    (
        move |e| Error::Format {
            path: path.to_path_buf(),
            message: format!("not a readable Parquet file: {e}"),
        },
        crate::sources::format_error(path),
    )
}

/// The flat numeric columns of a Parquet file as a table.
pub(crate) fn read_parquet_table<R: parquet::file::reader::ChunkReader + 'static>(
    path: &Path,
    file: R,
) -> Result<Table> {
    let (pq_err, fail) = errors(path);
    let reader = SerializedFileReader::new(file).map_err(pq_err)?;
    let meta = reader.metadata();
    let schema = meta.file_metadata().schema_descr();
    let Readable {
        names,
        unit_s,
        kept,
        skipped,
    } = readable_columns(schema);
    if names.is_empty() {
        if let Some(first) = skipped.first() {
            return Err(fail(format!("{first}, and no other column to read")));
        }
    }
    let total = meta.file_metadata().num_rows();
    if !(0..=MAX_PARQUET_ROWS).contains(&total) {
        return Err(fail(format!(
            "the footer claims {total} rows; limpid reads at most {MAX_PARQUET_ROWS}"
        )));
    }
    let reserve = (total as usize).min(1 << 24);
    // columns are independent: each decoded (over all row groups) on its own task
    let groups: Vec<_> = (0..reader.num_row_groups())
        .map(|g| reader.get_row_group(g).map_err(pq_err))
        .collect::<Result<_>>()?;
    let decoder = ColumnDecoder {
        path,
        schema,
        groups: &groups,
        reserve,
    };
    // every column decoded, then the first error in column order: a
    // short-circuiting collect named whichever failing column finished first
    let decoded: Vec<Result<Vec<f64>>> = (0..names.len())
        .into_par_iter()
        .map(|k| decoder.decode(kept[k], &names[k], unit_s[k]))
        .collect();
    let columns = decoded.into_iter().collect::<Result<Vec<_>>>()?;
    let mut warnings: Vec<String> = skipped.iter().map(|r| format!("{r}: not read")).collect();
    for (name, per_s) in names.iter().zip(&unit_s) {
        if per_s.is_some() {
            warnings.push(format!(
                "column {name}: a Parquet timestamp, converted to seconds since the first sample"
            ));
        }
    }
    Ok(Table {
        names,
        columns,
        first_row: 1,
        warnings,
    })
}

/// The columns of a Parquet schema a recording can hold, and why the others are left out.
struct Readable {
    names: Vec<String>,
    /// Stored ticks per second, for timestamp columns.
    unit_s: Vec<Option<f64>>,
    /// The schema's index of each column read.
    kept: Vec<usize>,
    /// "column NAME: reason" of each column left out.
    skipped: Vec<String>,
}

/// Columns that cannot be a recording's (nested, text, dates...) are left
/// out, as unknown columns are; timestamps are read as seconds.
fn readable_columns(schema: &parquet::schema::types::SchemaDescriptor) -> Readable {
    use parquet::basic::{LogicalType, TimeUnit};
    let mut names = Vec::with_capacity(schema.num_columns());
    // stored ticks per second, for timestamp columns
    let mut unit_s: Vec<Option<f64>> = Vec::with_capacity(schema.num_columns());
    let mut kept: Vec<usize> = Vec::with_capacity(schema.num_columns());
    let mut skipped: Vec<String> = Vec::new();
    for (index, c) in schema.columns().iter().enumerate() {
        let name = c.path().string();
        let not_numbers = match c.logical_type_ref() {
            Some(LogicalType::Decimal { .. })
            | Some(LogicalType::Date)
            | Some(LogicalType::Time(_))
            | Some(LogicalType::String)
            | Some(LogicalType::Uuid) => Some(format!(
                "a {} column; a recording's columns are plain numbers in SI units",
                c.logical_type_ref()
                    .map(|l| format!("{l:?}"))
                    .unwrap_or_default()
            )),
            _ => match c.physical_type() {
                PhysicalType::DOUBLE
                | PhysicalType::FLOAT
                | PhysicalType::INT32
                | PhysicalType::INT64 => None,
                other => Some(format!(
                    "a {other} column; a recording's columns are plain numbers"
                )),
            },
        };
        let reason = if c.path().parts().len() > 1 || c.max_rep_level() > 0 {
            Some(
                "a nested or repeated (struct/list) column; a recording has flat numeric columns"
                    .to_string(),
            )
        } else {
            not_numbers
        };
        if let Some(reason) = reason {
            skipped.push(format!("column {name}: {reason}"));
            continue;
        }
        let scale = match c.logical_type_ref() {
            Some(LogicalType::Timestamp(ts)) => Some(match ts.unit {
                TimeUnit::MILLIS => 1e3,
                TimeUnit::MICROS => 1e6,
                TimeUnit::NANOS => 1e9,
            }),
            _ => None,
        };
        names.push(name);
        unit_s.push(scale);
        kept.push(index);
    }
    Readable {
        names,
        unit_s,
        kept,
        skipped,
    }
}

/// Values decoded per batch.
const BATCH: usize = 1 << 16;

/// What decoding one column over every row group needs.
struct ColumnDecoder<'a> {
    path: &'a Path,
    schema: &'a parquet::schema::types::SchemaDescriptor,
    groups: &'a [Box<dyn parquet::file::reader::RowGroupReader + 'a>],
    /// Samples to reserve room for.
    reserve: usize,
}

impl ColumnDecoder<'_> {
    /// The schema's column `index` (named `name`; timestamps at `per_s` ticks
    /// per second) as numbers: a null is refused by row, and more than
    /// MAX_PARQUET_ROWS values by name.
    fn decode(&self, index: usize, name: &str, per_s: Option<f64>) -> Result<Vec<f64>> {
        let (path, schema, groups, reserve) = (self.path, self.schema, self.groups, self.reserve);
        let (pq_err, fail) = errors(path);
        let mut out = column_buffer(reserve);
        let mut origin: Option<i64> = None;
        for group in groups {
            let mut defs: Vec<i16> = Vec::new();
            // pages pass a size check before the decoder sees them: a corrupt
            // dictionary page claiming 2^31 values made it reserve 6 GB (fuzzer)
            let descr = schema.column(index);
            let width = match descr.physical_type() {
                PhysicalType::INT64 | PhysicalType::DOUBLE => 8,
                _ => 4,
            };
            let pages = CheckedPages {
                inner: group.get_column_page_reader(index).map_err(pq_err)?,
                max_values: group.metadata().num_rows().max(0) as u64,
                width,
            };
            let column_reader = parquet::column::reader::get_column_reader(descr, Box::new(pages));
            macro_rules! read_all {
                ($r:expr, $t:ty) => {{
                    let mut r = $r;
                    let mut vals: Vec<$t> = Vec::with_capacity(BATCH);
                    loop {
                        vals.clear();
                        defs.clear();
                        let (n_rec, _, _) = r
                            .read_records(BATCH, Some(&mut defs), None, &mut vals)
                            .map_err(pq_err)?;
                        if n_rec == 0 {
                            break;
                        }
                        if vals.len() != n_rec {
                            let missing = defs.iter().position(|d| *d == 0).unwrap_or(0);
                            return Err(Error::NotANumber {
                                path: path.to_path_buf(),
                                row: out.len() + missing + 1,
                                column: name.to_string(),
                                found: "null".into(),
                            });
                        }
                        match per_s {
                            // timestamps: integer ticks since the first sample, then
                            // seconds (epoch seconds in f64 would lose the sampling interval)
                            Some(per_s) => {
                                let first = *origin.get_or_insert(vals[0] as i64);
                                out.extend(
                                    vals.iter()
                                        .map(|v| (*v as i64).saturating_sub(first) as f64 / per_s),
                                )
                            }
                            None => out.extend(vals.iter().map(|v| *v as f64)),
                        }
                        if out.len() as i64 > MAX_PARQUET_ROWS {
                            return Err(fail(format!(
                                "column {}: more than {MAX_PARQUET_ROWS} rows",
                                name
                            )));
                        }
                    }
                }};
            }
            match column_reader {
                // doubles in seconds go straight into the column, without a
                // batch buffer and its copy (issue 82)
                ColumnReader::DoubleColumnReader(mut r) if per_s.is_none() => loop {
                    defs.clear();
                    let before = out.len();
                    let (n_rec, _, _) = r
                        .read_records(BATCH, Some(&mut defs), None, &mut out)
                        .map_err(pq_err)?;
                    if n_rec == 0 {
                        break;
                    }
                    if out.len() - before != n_rec {
                        let missing = defs.iter().position(|d| *d == 0).unwrap_or(0);
                        return Err(Error::NotANumber {
                            path: path.to_path_buf(),
                            row: before + missing + 1,
                            column: name.to_string(),
                            found: "null".into(),
                        });
                    }
                    if out.len() as i64 > MAX_PARQUET_ROWS {
                        return Err(fail(format!(
                            "column {name}: more than {MAX_PARQUET_ROWS} rows"
                        )));
                    }
                },
                ColumnReader::DoubleColumnReader(r) => read_all!(r, f64),
                ColumnReader::FloatColumnReader(r) => read_all!(r, f32),
                ColumnReader::Int32ColumnReader(r) => read_all!(r, i32),
                ColumnReader::Int64ColumnReader(r) => read_all!(r, i64),
                _ => {
                    return Err(Error::Format {
                        path: path.to_path_buf(),
                        message: format!("column {}: expected a numeric column", name),
                    })
                }
            }
        }
        Ok(out)
    }
}

/// An empty column with room for `capacity` samples. On Linux the kernel is
/// asked to back it with 2 MB pages (transparent huge pages, `madvise`
/// mode): filling the 115 MB of a 60-minute recording's columns then takes
/// about 60 page faults instead of 28 000, which cost a fifth of `estimate
/// linear`'s time in the kernel (issue 16). Only advice: ignored where
/// unsupported or disabled.
pub(crate) fn column_buffer(capacity: usize) -> Vec<f64> {
    let column: Vec<f64> = Vec::with_capacity(capacity);
    #[cfg(target_os = "linux")]
    {
        const HUGE: usize = 2 << 20;
        let start = column.as_ptr() as usize;
        let end = start + capacity * std::mem::size_of::<f64>();
        // the whole 2 MB pages inside the allocation
        let (first, last) = (start.next_multiple_of(HUGE), end / HUGE * HUGE);
        if last > first {
            // SAFETY: advice on pages of an allocation this function owns; it
            // neither reads nor changes their contents.
            unsafe {
                libc::madvise(
                    first as *mut libc::c_void,
                    last - first,
                    libc::MADV_HUGEPAGE,
                );
            }
        }
    }
    column
}

/// The file's bytes for the Parquet decoder, whose readers fail at the end of
/// the data instead of returning 0 bytes: the decoder's skipping of a
/// corrupt header with a claimed list of 2^31 elements otherwise looped on
/// end-of-file for minutes (fuzzer).
pub(crate) struct StrictBytes(pub(crate) bytes::Bytes);

/// A reader over [`StrictBytes`] from an offset.
pub(crate) struct StrictRead(bytes::Bytes);

impl std::io::Read for StrictRead {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if buf.is_empty() {
            return Ok(0);
        }
        if self.0.is_empty() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::UnexpectedEof,
                "read past the end of the Parquet file",
            ));
        }
        let n = buf.len().min(self.0.len());
        buf[..n].copy_from_slice(&self.0[..n]);
        self.0 = self.0.slice(n..);
        Ok(n)
    }
}

impl parquet::file::reader::Length for StrictBytes {
    fn len(&self) -> u64 {
        self.0.len() as u64
    }
}

impl parquet::file::reader::ChunkReader for StrictBytes {
    type T = StrictRead;
    fn get_read(&self, start: u64) -> parquet::errors::Result<StrictRead> {
        let start = usize::try_from(start).unwrap_or(usize::MAX);
        if start > self.0.len() {
            return Err(parquet::errors::ParquetError::EOF(format!(
                "offset {start} beyond the file's {} bytes",
                self.0.len()
            )));
        }
        Ok(StrictRead(self.0.slice(start..)))
    }
    fn get_bytes(&self, start: u64, length: usize) -> parquet::errors::Result<bytes::Bytes> {
        self.0.get_bytes(start, length)
    }
}

/// A Parquet file read where the decoder asks, column chunk by column chunk
/// (the columns are decoded in parallel), instead of whole into memory
/// first: the file's bytes no longer add to the decoded columns in the peak
/// memory (issue 16). Reads past the end fail, as for [`StrictBytes`].
#[cfg(unix)]
pub(crate) struct StrictFile {
    pub(crate) file: std::sync::Arc<std::fs::File>,
    pub(crate) len: u64,
}

#[cfg(unix)]
impl StrictFile {
    pub(crate) fn open(path: &Path) -> Result<Self> {
        let file = limpid_core::files::open_input(path)?;
        let len = file
            .metadata()
            .map_err(|source| Error::Io {
                path: path.to_path_buf(),
                source,
            })?
            .len();
        if len == 0 {
            return Err(Error::Empty {
                path: path.to_path_buf(),
            });
        }
        if len > MAX_PARQUET_BYTES {
            return Err(Error::Format {
                path: path.to_path_buf(),
                message: format!(
                    "larger than the {MAX_PARQUET_BYTES} bytes limpid reads for this kind of file"
                ),
            });
        }
        Ok(StrictFile {
            file: std::sync::Arc::new(file),
            len,
        })
    }
}

/// A reader of [`StrictFile`] from an offset (positioned reads, so that
/// threads share the file without sharing a cursor).
#[cfg(unix)]
pub(crate) struct StrictFileRead {
    pub(crate) file: std::sync::Arc<std::fs::File>,
    pub(crate) pos: u64,
    pub(crate) len: u64,
}

#[cfg(unix)]
impl std::io::Read for StrictFileRead {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        use std::os::unix::fs::FileExt;
        if buf.is_empty() {
            return Ok(0);
        }
        let left = self.len.saturating_sub(self.pos);
        if left == 0 {
            return Err(std::io::Error::new(
                std::io::ErrorKind::UnexpectedEof,
                "read past the end of the Parquet file",
            ));
        }
        let want = buf.len().min(usize::try_from(left).unwrap_or(usize::MAX));
        let got = self.file.read_at(&mut buf[..want], self.pos)?;
        if got == 0 {
            return Err(std::io::Error::new(
                std::io::ErrorKind::UnexpectedEof,
                "the Parquet file ended early (truncated while read?)",
            ));
        }
        self.pos += got as u64;
        Ok(got)
    }
}

#[cfg(unix)]
impl parquet::file::reader::Length for StrictFile {
    fn len(&self) -> u64 {
        self.len
    }
}

#[cfg(unix)]
impl parquet::file::reader::ChunkReader for StrictFile {
    // page headers are read a few bytes at a time: buffered
    type T = std::io::BufReader<StrictFileRead>;
    fn get_read(&self, start: u64) -> parquet::errors::Result<Self::T> {
        if start > self.len {
            return Err(parquet::errors::ParquetError::EOF(format!(
                "offset {start} beyond the file's {} bytes",
                self.len
            )));
        }
        Ok(std::io::BufReader::with_capacity(
            1024,
            StrictFileRead {
                file: self.file.clone(),
                pos: start,
                len: self.len,
            },
        ))
    }
    fn get_bytes(&self, start: u64, length: usize) -> parquet::errors::Result<bytes::Bytes> {
        use std::io::Read;
        let end = start.checked_add(length as u64).filter(|e| *e <= self.len);
        if end.is_none() {
            return Err(parquet::errors::ParquetError::EOF(format!(
                "{length} bytes from offset {start} run beyond the file's {} bytes",
                self.len
            )));
        }
        let mut out = vec![0u8; length];
        StrictFileRead {
            file: self.file.clone(),
            pos: start,
            len: self.len,
        }
        .read_exact(&mut out)
        .map_err(|e| parquet::errors::ParquetError::External(Box::new(e)))?;
        Ok(bytes::Bytes::from(out))
    }
}

/// A page reader that refuses pages whose declared value count cannot be
/// true: a dictionary holding more values than its bytes can store, or a
/// data page with more values than its row group has rows.
pub(crate) struct CheckedPages {
    pub(crate) inner: Box<dyn parquet::column::page::PageReader>,
    pub(crate) max_values: u64,
    pub(crate) width: usize,
}

impl CheckedPages {
    pub(crate) fn check(&self, page: &parquet::column::page::Page) -> parquet::errors::Result<()> {
        use parquet::column::page::Page;
        let bad = |what: String| Err(parquet::errors::ParquetError::General(what));
        match page {
            Page::DictionaryPage {
                buf, num_values, ..
            } if (*num_values as usize).saturating_mul(self.width) > buf.len() => bad(format!(
                "a dictionary page claims {num_values} values in {} bytes",
                buf.len()
            )),
            Page::DataPage { num_values, .. } | Page::DataPageV2 { num_values, .. }
                if u64::from(*num_values) > self.max_values =>
            {
                bad(format!(
                    "a data page claims {num_values} values in a row group of {} rows",
                    self.max_values
                ))
            }
            _ => Ok(()),
        }
    }
}

impl Iterator for CheckedPages {
    type Item = parquet::errors::Result<parquet::column::page::Page>;
    fn next(&mut self) -> Option<Self::Item> {
        use parquet::column::page::PageReader;
        self.get_next_page().transpose()
    }
}

impl parquet::column::page::PageReader for CheckedPages {
    fn get_next_page(&mut self) -> parquet::errors::Result<Option<parquet::column::page::Page>> {
        let page = self.inner.get_next_page()?;
        if let Some(p) = &page {
            self.check(p)?;
        }
        Ok(page)
    }
    fn peek_next_page(
        &mut self,
    ) -> parquet::errors::Result<Option<parquet::column::page::PageMetadata>> {
        self.inner.peek_next_page()
    }
    fn skip_next_page(&mut self) -> parquet::errors::Result<()> {
        self.inner.skip_next_page()
    }
    fn supports_deferred_dictionary(&self) -> bool {
        self.inner.supports_deferred_dictionary()
    }
    fn take_deferred_dictionary(
        &mut self,
    ) -> parquet::errors::Result<Option<parquet::column::page::Page>> {
        let page = self.inner.take_deferred_dictionary()?;
        if let Some(p) = &page {
            self.check(p)?;
        }
        Ok(page)
    }
    fn at_record_boundary(&mut self) -> parquet::errors::Result<bool> {
        self.inner.at_record_boundary()
    }
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
    limpid_core::files::write_atomic(path, |file| {
        let mut writer = SerializedFileWriter::new(file, schema, props).map_err(pq_err)?;
        const ROWS_PER_GROUP: usize = 1 << 20;
        let n = rec.len();
        let cols: Vec<&[f64]> = rec.columns().map(|c| c.1).collect();
        let mut start = 0;
        while start < n {
            let end = (start + ROWS_PER_GROUP).min(n);
            let mut group = writer.next_row_group().map_err(pq_err)?;
            for c in &cols {
                let mut col =
                    group
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
    })
}
