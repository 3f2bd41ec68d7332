//! The containers of a ROS 2 bag: MCAP (read with the `mcap` crate's
//! sans-io reader, every record's length bounded) and rosbag2's SQLite file
//! (`rusqlite`, the file deserialised read-only into memory: nothing is
//! written beside it, so a read-only folder works).
//!
//! A rosbag2 folder is read file by file, in the order of the split index
//! in their names (`bag_0.db3`, `bag_1.db3`, ...); its `metadata.yaml` is
//! not needed (a recorder killed before closing never writes it).

use std::path::{Path, PathBuf};

use mcap::records::Record;
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

use super::Collector;
use crate::sources::Source;
use limpid_core::{Error, Result};

/// Largest bag file read (bytes).
pub const MAX_BAG_BYTES: u64 = 4 << 30;

/// Largest MCAP record, or decompressed chunk, accepted (bytes).
const MAX_RECORD_BYTES: usize = 256 << 20;

/// Read a bag: an `.mcap` file, a `.db3` file, or a rosbag2 folder.
pub fn read(path: &Path) -> Result<Source> {
    if path.is_dir() {
        let files = bag_files(path)?;
        let mut collector = Collector::new();
        let mut kinds = (false, false);
        for f in &files {
            let bytes = limpid_core::files::read_bytes(f, MAX_BAG_BYTES)?;
            if is_sqlite(&bytes) {
                kinds.0 = true;
                read_db3(f, &bytes, &mut collector)?;
            } else {
                kinds.1 = true;
                read_mcap(f, &bytes, &mut collector)?;
            }
        }
        let format = match kinds {
            (true, false) => "rosbag2 (SQLite)",
            (false, true) => "rosbag2 (MCAP)",
            _ => "rosbag2",
        };
        return collector.finish(path, format);
    }
    let bytes = limpid_core::files::read_bytes(path, MAX_BAG_BYTES)?;
    read_bytes(path, &bytes)
}

/// Read one bag file held in memory (MCAP or SQLite, told by its first bytes).
pub fn read_bytes(path: &Path, bytes: &[u8]) -> Result<Source> {
    let mut collector = Collector::new();
    if is_sqlite(bytes) {
        read_db3(path, bytes, &mut collector)?;
        collector.finish(path, "rosbag2 (SQLite)")
    } else {
        read_mcap(path, bytes, &mut collector)?;
        collector.finish(path, "MCAP")
    }
}

fn is_sqlite(bytes: &[u8]) -> bool {
    bytes.starts_with(b"SQLite format 3\0")
}

fn format_error(path: &Path, message: String) -> Error {
    Error::Format {
        path: path.to_path_buf(),
        message,
    }
}

/// The bag's files, in split order.
fn bag_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| format_error(dir, format!("cannot list the bag folder: {e}")))?;
    let mut files: Vec<(u64, String, PathBuf)> = Vec::new();
    for entry in entries.flatten() {
        let p = entry.path();
        let ext = p
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        if matches!(ext.as_deref(), Some("mcap" | "db3")) && p.is_file() {
            let stem = p
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or_default()
                .to_string();
            let split = stem
                .rsplit('_')
                .next()
                .and_then(|n| n.parse().ok())
                .unwrap_or(0);
            files.push((split, stem, p));
        }
    }
    if files.is_empty() {
        return Err(format_error(
            dir,
            "a folder read as a ROS 2 bag holds no .mcap or .db3 file".into(),
        ));
    }
    files.sort();
    Ok(files.into_iter().map(|f| f.2).collect())
}

/// Read an MCAP file's schemas, channels and messages, in file order. A file
/// cut off (a recorder killed) is read up to its last whole record, with a
/// note.
fn read_mcap(path: &Path, bytes: &[u8], c: &mut Collector) -> Result<()> {
    if !bytes.starts_with(b"\x89MCAP0\r\n") {
        return Err(format_error(
            path,
            "not an MCAP file (it lacks the MCAP magic) nor a rosbag2 SQLite file".into(),
        ));
    }
    // a chunk whose CRC disagrees yields no message (a flipped bit read as
    // data changed q1 from 0.0109 to 1.67e-7 in silence; issue 76)
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_record_length_limit(MAX_RECORD_BYTES)
            .with_prevalidate_chunk_crcs(true)
            .with_validate_data_section_crc(true)
            .with_validate_summary_section_crc(true),
    );
    c.start_file(path, bytes.len());
    let mut schemas: std::collections::HashMap<u16, (String, String, String)> = Default::default();
    let mut channels: std::collections::HashMap<u16, usize> = Default::default();
    let mut rest = bytes;
    let mut messages = 0usize;
    let mut unknown_channel = 0usize;
    while let Some(event) = reader.next_event() {
        match event {
            Ok(LinearReadEvent::ReadRequest(need)) => {
                let n = need.min(rest.len());
                reader.insert(n).copy_from_slice(&rest[..n]);
                reader.notify_read(n);
                rest = &rest[n..];
            }
            // only the records read are parsed: the crate's parser of others
            // (an attachment whose body leaves no room for its CRC) can panic
            Ok(LinearReadEvent::Record { opcode, .. })
                if ![
                    mcap::records::op::SCHEMA,
                    mcap::records::op::CHANNEL,
                    mcap::records::op::MESSAGE,
                ]
                .contains(&opcode) => {}
            Ok(LinearReadEvent::Record { data, opcode }) => {
                let record = mcap::parse_record(opcode, data).map_err(|e| {
                    format_error(
                        path,
                        format!(
                            "byte {}: a record does not parse: {e}",
                            bytes.len() - rest.len()
                        ),
                    )
                })?;
                match record {
                    Record::Schema { header, data } => {
                        let text = String::from_utf8_lossy(&data).into_owned();
                        schemas.insert(header.id, (header.name, header.encoding, text));
                    }
                    Record::Channel(ch) => {
                        let type_name = match schemas.get(&ch.schema_id) {
                            Some((name, encoding, text)) => {
                                c.definition(name, encoding, text);
                                name.clone()
                            }
                            None => String::from("(no schema)"),
                        };
                        let k = c.topic(&ch.topic, &type_name, &ch.message_encoding);
                        channels.insert(ch.id, k);
                    }
                    Record::Message { header, data } => match channels.get(&header.channel_id) {
                        Some(&k) => {
                            messages += 1;
                            c.message(k, clamp_ns(header.log_time), &data);
                            c.check_budget()?;
                        }
                        None => {
                            unknown_channel += 1;
                            c.count_unkept();
                            c.check_budget()?;
                        }
                    },
                    _ => {}
                }
            }
            Err(e) => {
                let at = bytes.len() - rest.len();
                if let mcap::McapError::BadChunkCrc { saved, calculated }
                | mcap::McapError::BadDataCrc { saved, calculated }
                | mcap::McapError::BadSummaryCrc { saved, calculated } = e
                {
                    let what = match e {
                        mcap::McapError::BadChunkCrc { .. } => "the chunk read up to this byte",
                        mcap::McapError::BadDataCrc { .. } => "the data section",
                        _ => "the summary section",
                    };
                    return Err(format_error(
                        path,
                        format!(
                            "byte {at}: {what} is corrupt: its CRC is {saved:#010x} but its bytes give {calculated:#010x}"
                        ),
                    ));
                }
                if messages == 0 {
                    return Err(format_error(
                        path,
                        format!("byte {at}: not a readable MCAP file: {e}"),
                    ));
                }
                c.notes.push(format!(
                    "{}: read up to byte {at} of {} ({messages} messages): the rest is not whole ({e}) — a recording cut off?",
                    path.display(),
                    bytes.len()
                ));
                break;
            }
        }
    }
    if unknown_channel > 0 {
        c.notes.push(format!(
            "{}: {unknown_channel} messages name a channel the file never declares; left out",
            path.display()
        ));
    }
    Ok(())
}

fn clamp_ns(ns: u64) -> i64 {
    i64::try_from(ns).unwrap_or(i64::MAX)
}

/// Read a rosbag2 SQLite file: its topics, stored definitions (Jazzy on)
/// and messages in time order.
fn read_db3(path: &Path, bytes: &[u8], c: &mut Collector) -> Result<()> {
    let sql = |e: rusqlite::Error| format_error(path, format!("rosbag2 SQLite file: {e}"));
    c.start_file(path, bytes.len());
    let (db, _copy) = open_db3(path, bytes)?;
    let has_table = |name: &str| -> Result<bool> {
        db.query_row(
            "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = ?1",
            [name],
            |r| r.get::<_, i64>(0),
        )
        .map(|n| n > 0)
        .map_err(sql)
    };
    for table in ["topics", "messages"] {
        if !has_table(table)? {
            return Err(format_error(
                path,
                format!("an SQLite file without a {table:?} table is not a rosbag2 bag"),
            ));
        }
    }
    if has_table("message_definitions")? {
        let mut q = db
            .prepare(
                "SELECT topic_type, encoding, encoded_message_definition FROM message_definitions",
            )
            .map_err(sql)?;
        let rows = q
            .query_map([], |r| {
                Ok((
                    r.get::<_, String>(0)?,
                    r.get::<_, String>(1)?,
                    r.get::<_, String>(2)?,
                ))
            })
            .map_err(sql)?;
        for row in rows {
            let (ty, encoding, text) = row.map_err(sql)?;
            c.definition(&ty, &encoding, &text);
        }
    }
    let mut topics: std::collections::HashMap<i64, usize> = Default::default();
    {
        let mut q = db
            .prepare("SELECT id, name, type, serialization_format FROM topics")
            .map_err(sql)?;
        let rows = q
            .query_map([], |r| {
                Ok((
                    r.get::<_, i64>(0)?,
                    r.get::<_, String>(1)?,
                    r.get::<_, String>(2)?,
                    r.get::<_, String>(3)?,
                ))
            })
            .map_err(sql)?;
        for row in rows {
            let (id, name, ty, encoding) = row.map_err(sql)?;
            topics.insert(id, c.topic(&name, &ty, &encoding));
        }
    }
    let mut q = db
        .prepare("SELECT topic_id, timestamp, data FROM messages ORDER BY timestamp, id")
        .map_err(sql)?;
    let mut rows = q.query([]).map_err(sql)?;
    let mut orphans = 0usize;
    while let Some(row) = rows.next().map_err(sql)? {
        let topic: i64 = row.get(0).map_err(sql)?;
        let time: i64 = row.get(1).map_err(sql)?;
        let data = row.get_ref(2).map_err(sql)?;
        let bytes = match data {
            rusqlite::types::ValueRef::Blob(b) => b,
            _ => {
                return Err(format_error(
                    path,
                    format!("a message of topic id {topic} at {time} ns holds no bytes"),
                ))
            }
        };
        match topics.get(&topic) {
            Some(&k) => {
                c.message(k, time, bytes);
                c.check_budget()?;
            }
            None => {
                orphans += 1;
                c.count_unkept();
                c.check_budget()?;
            }
        }
    }
    if orphans > 0 {
        c.notes.push(format!(
            "{}: {orphans} messages name a topic id the file never declares; left out",
            path.display()
        ));
    }
    Ok(())
}

/// An SQLite file in WAL journal mode (rosbag2's `resilient` preset) says so
/// in its header's read and write versions (bytes 18 and 19 are 2).
fn is_wal_mode(bytes: &[u8]) -> bool {
    bytes.len() >= 20 && bytes[18] == 2 && bytes[19] == 2
}

/// A folder of copies removed when dropped.
struct TempCopy(PathBuf);

impl Drop for TempCopy {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Open a rosbag2 SQLite file read-only. A rollback-journal file is
/// deserialised from memory. A WAL-mode file whose `-wal` file beside it
/// holds frames is copied with it to a temporary folder and opened there,
/// so SQLite itself applies the log (its last transactions, often the
/// bag's last seconds, live only there); without a log it is read from
/// memory as a rollback-journal file (the header's versions set to 1).
fn open_db3(path: &Path, bytes: &[u8]) -> Result<(rusqlite::Connection, Option<TempCopy>)> {
    let sql = |e: rusqlite::Error| format_error(path, format!("rosbag2 SQLite file: {e}"));
    let wal = {
        let mut name = path.as_os_str().to_owned();
        name.push("-wal");
        PathBuf::from(name)
    };
    let wal_frames =
        is_wal_mode(bytes) && std::fs::metadata(&wal).is_ok_and(|m| m.is_file() && m.len() > 32);
    if wal_frames {
        let dir = std::env::temp_dir().join(format!(
            "limpid-bag-{}-{}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos())
        ));
        let copy = TempCopy(dir.clone());
        let io = |e: std::io::Error| {
            format_error(
                path,
                format!(
                    "a WAL-mode SQLite file (rosbag2's resilient preset) with its log {}: cannot copy them to {} to apply the log ({e}); checkpoint it first (sqlite3 FILE 'PRAGMA wal_checkpoint')",
                    wal.display(),
                    dir.display()
                ),
            )
        };
        std::fs::create_dir(&dir).map_err(io)?;
        std::fs::write(dir.join("bag.db3"), bytes).map_err(io)?;
        let log = limpid_core::files::read_bytes(&wal, MAX_BAG_BYTES)?;
        std::fs::write(dir.join("bag.db3-wal"), log).map_err(io)?;
        let db = rusqlite::Connection::open_with_flags(
            dir.join("bag.db3"),
            rusqlite::OpenFlags::SQLITE_OPEN_READ_WRITE | rusqlite::OpenFlags::SQLITE_OPEN_NO_MUTEX,
        )
        .map_err(sql)?;
        return Ok((db, Some(copy)));
    }
    let mut db = rusqlite::Connection::open_in_memory().map_err(sql)?;
    if is_wal_mode(bytes) {
        let mut legacy = bytes.to_vec();
        legacy[18] = 1;
        legacy[19] = 1;
        db.deserialize_read_exact(rusqlite::MAIN_DB, legacy.as_slice(), legacy.len(), true)
            .map_err(sql)?;
    } else {
        db.deserialize_read_exact(rusqlite::MAIN_DB, bytes, bytes.len(), true)
            .map_err(sql)?;
    }
    Ok((db, None))
}
