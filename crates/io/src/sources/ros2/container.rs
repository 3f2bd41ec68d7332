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
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default().with_record_length_limit(MAX_RECORD_BYTES),
    );
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
                        }
                        None => unknown_channel += 1,
                    },
                    _ => {}
                }
            }
            Err(e) => {
                let at = bytes.len() - rest.len();
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
    let mut db = rusqlite::Connection::open_in_memory().map_err(sql)?;
    db.deserialize_read_exact(rusqlite::MAIN_DB, bytes, bytes.len(), true)
        .map_err(sql)?;
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
            Some(&k) => c.message(k, time, bytes),
            None => orphans += 1,
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
