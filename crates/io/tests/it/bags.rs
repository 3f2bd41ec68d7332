//! ROS 2 bags (issue 62). `tests/fixtures/formats/rig.mcap` and `rig_db3/`
//! are written by mcap-ros2-support and rosbags (`make_bags.py`), with the
//! columns `rig_bag.toml` must give computed by numpy. The hostile bags are
//! written here with the `mcap` crate's writer around CDR bytes made by hand:
//! each unusual topic is listed and skipped with its reason, never a reason
//! to refuse the bag or a panic.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::Path;

use crate::formats::fixture;

use limpid_io::map::ChannelMap;
use limpid_io::sources::read_source;
use mcap::records::MessageHeader;

fn assert_converts(bag: &str) -> limpid_core::Recording {
    crate::formats::assert_matches_expected(bag, "rig_bag.toml", "rig_bag")
}

#[test]
fn an_mcap_bag_converts_to_the_values_written() {
    let rec = assert_converts("rig.mcap");
    assert!((rec.sample_rate() - 500.0).abs() < 1e-6);
}

#[test]
fn a_rosbag2_sqlite_folder_converts_to_the_values_written() {
    // its /point topic is big-endian CDR
    assert_converts("rig_db3");
    // the .db3 file alone reads the same
    let source = read_source(&fixture("rig_db3/rig_db3.db3")).unwrap();
    assert_eq!(source.format, "rosbag2 (SQLite)");
}

#[test]
fn inspect_lists_topics_types_clocks_and_skipped_topics() {
    let source = read_source(&fixture("rig.mcap")).unwrap();
    let found = limpid_io::inspect::inspect(&source);
    let stream = |name: &str| {
        found
            .streams
            .iter()
            .find(|s| s.name == name)
            .unwrap_or_else(|| panic!("no stream {name}"))
    };
    let joints = stream("/joint_states");
    assert_eq!(joints.kind.as_deref(), Some("sensor_msgs/msg/JointState"));
    assert_eq!(joints.samples, 101);
    assert_eq!(joints.clock.as_deref(), Some("header stamps"));
    let ankle = joints
        .channels
        .iter()
        .find(|c| c.name == "/joint_states.position[ankle]")
        .unwrap();
    assert_eq!(ankle.also.as_deref(), Some("/joint_states.position[1]"));
    assert_eq!(stream("/force_z").clock.as_deref(), Some("log time"));
    let rate = stream("/ft_sensor").effective_rate_hz.unwrap();
    assert!((rate - 1000.0).abs() < 1e-6, "{rate}");
    assert_eq!(stream("/events").markers[0].count, 2);
    // the image is listed, with why, and not read
    assert!(found.streams.iter().all(|s| s.name != "/camera"));
    let notes = found.notes.join("\n");
    assert!(
        notes.contains("/camera (sensor_msgs/msg/Image)") && notes.contains("an image"),
        "{notes}"
    );
    // a custom type from its stored definition: fixed array, constant, comment
    let handle = source.streams.iter().find(|s| s.name == "/handle").unwrap();
    let names: Vec<&str> = handle.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "/handle.position[0]",
            "/handle.position[1]",
            "/handle.position[2]",
            "/handle.grip"
        ]
    );
    assert_eq!(
        handle.channels[1].values,
        [0.0, -0.2, -0.4, -0.6000000000000001, -0.8]
    );
    // the proposed map names the pose and wrench fields
    let proposed = found.proposed_map.unwrap();
    assert!(
        proposed.contains("x = { channel = \"/hand_pose.pose.position.x\""),
        "{proposed}"
    );
}

#[test]
fn a_map_naming_a_skipped_topic_says_why() {
    let map =
        ChannelMap::parse("[time]\nstream = \"/hand_pose\"\n[columns]\nx = \"/camera.data[0]\"\n")
            .unwrap();
    let e = limpid_io::read_recording_mapped(fixture("rig.mcap"), Some(&map))
        .unwrap_err()
        .to_string();
    assert!(e.contains("an image"), "{e}");
    assert_eq!(e.lines().count(), 1);
}

/// One hand-made MCAP file: `topics` are (topic, type, schema encoding,
/// definition, message encoding, messages as (log ns, CDR bytes)).
type Topic<'a> = (
    &'a str,
    &'a str,
    &'a str,
    &'a str,
    &'a str,
    Vec<(u64, Vec<u8>)>,
);

fn write_mcap(topics: &[Topic]) -> Vec<u8> {
    let mut w = mcap::Writer::new(Cursor::new(Vec::new())).unwrap();
    for (topic, ty, schema_encoding, definition, encoding, messages) in topics {
        let schema = w
            .add_schema(ty, schema_encoding, definition.as_bytes())
            .unwrap();
        let channel = w
            .add_channel(schema, topic, encoding, &BTreeMap::new())
            .unwrap();
        for (k, (log, data)) in messages.iter().enumerate() {
            w.write_to_known_channel(
                &MessageHeader {
                    channel_id: channel,
                    sequence: k as u32,
                    log_time: *log,
                    publish_time: *log,
                },
                data,
            )
            .unwrap();
        }
    }
    w.finish().unwrap();
    w.into_inner().into_inner()
}

/// CDR (little-endian) of a std_msgs/Float64.
fn float64(v: f64) -> Vec<u8> {
    let mut b = vec![0, 1, 0, 0, 0, 0, 0, 0];
    b.extend(v.to_le_bytes());
    b
}

fn good_topic<'a>() -> Topic<'a> {
    let messages = (0..50)
        .map(|k| (1_000_000_000 + k * 2_000_000, float64(k as f64 * 0.001)))
        .collect();
    (
        "/x",
        "std_msgs/msg/Float64",
        "ros2msg",
        "float64 data",
        "cdr",
        messages,
    )
}

fn read_bag(bytes: &[u8]) -> limpid_core::Result<limpid_io::sources::Source> {
    limpid_io::sources::read_source_bytes(Path::new("hostile.mcap"), bytes)
}

#[test]
fn hostile_topics_are_listed_and_skipped_not_a_reason_to_refuse_the_bag() {
    let mut huge_sequence = vec![0, 1, 0, 0];
    huge_sequence.extend(u32::MAX.to_le_bytes());
    let empties = vec![0, 1, 0, 0, 0, 0, 0, 0];
    let one = |data: Vec<u8>| vec![(1_000_000_000, data)];
    let topics: Vec<Topic> = vec![
        good_topic(),
        // a type that contains itself
        (
            "/loop",
            "lab_msgs/msg/Loop",
            "ros2msg",
            "Loop next",
            "cdr",
            one(float64(1.0)),
        ),
        // a sequence count far beyond the bytes
        (
            "/seq",
            "std_msgs/msg/Float64MultiArray",
            "ros2msg",
            "float64[] data",
            "cdr",
            one(huge_sequence),
        ),
        // a million empty messages in 4 bytes
        (
            "/empty",
            "lab_msgs/msg/Many",
            "ros2msg",
            "Nothing[1000000] items\n================\nMSG: lab_msgs/Nothing\n",
            "cdr",
            one(empties),
        ),
        // another serialisation
        (
            "/json",
            "std_msgs/msg/Float64",
            "ros2msg",
            "float64 data",
            "json",
            one(b"{\"data\": 1}".to_vec()),
        ),
        // a type neither stored nor built in
        (
            "/unknown",
            "lab_msgs/msg/Secret",
            "ros2idl",
            "",
            "cdr",
            one(float64(1.0)),
        ),
        // XCDR2
        (
            "/xcdr2",
            "std_msgs/msg/Float64",
            "ros2msg",
            "float64 data",
            "cdr",
            one(vec![0, 7, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8]),
        ),
        // wide strings
        (
            "/wide",
            "lab_msgs/msg/Wide",
            "ros2msg",
            "wstring label\nfloat64 v",
            "cdr",
            one(vec![0, 1, 0, 0, 1, 0, 0, 0, 65, 0]),
        ),
        // a definition that does not parse
        (
            "/garbled",
            "lab_msgs/msg/Garbled",
            "ros2msg",
            "float64[x] v",
            "cdr",
            one(float64(1.0)),
        ),
    ];
    let bytes = write_mcap(&topics);
    let source = read_bag(&bytes).unwrap();
    let names: Vec<&str> = source.streams.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["/x"]);
    assert_eq!(source.streams[0].channels[0].values.len(), 50);
    let notes = source.notes.join("\n");
    for (topic, why) in [
        ("/loop", "nested more than"),
        ("/seq", "a sequence of 4294967295 elements"),
        ("/empty", "more elements than its bytes"),
        ("/json", "not CDR"),
        ("/unknown", "no definition of lab_msgs/msg/Secret"),
        ("/xcdr2", "only plain CDR"),
        ("/wide", "wstring"),
        ("/garbled", "no definition"),
    ] {
        let line = source
            .unread
            .iter()
            .find(|(t, _)| t == topic)
            .unwrap_or_else(|| panic!("{topic} not listed: {notes}"));
        assert!(line.1.contains(why), "{topic}: {}", line.1);
    }
    assert!(notes.contains("Garbled was not understood"), "{notes}");
}

#[test]
fn a_bad_message_after_good_ones_is_left_out_and_counted() {
    let (topic, ty, enc, def, menc, mut messages) = good_topic();
    messages[10].1.truncate(6);
    let bytes = write_mcap(&[(topic, ty, enc, def, menc, messages)]);
    let source = read_bag(&bytes).unwrap();
    assert_eq!(source.streams[0].channels[0].values.len(), 49);
    let notes = source.notes.join("\n");
    assert!(
        notes.contains("1 of 50 messages could not be decoded") && notes.contains("message 11"),
        "{notes}"
    );
}

#[test]
fn a_bag_cut_off_is_read_to_its_last_whole_record_or_refused_in_one_line() {
    let bytes = write_mcap(&[good_topic()]);
    let mut read_some = 0;
    for cut in (0..bytes.len()).step_by(7) {
        match read_bag(&bytes[..cut]) {
            Ok(source) => {
                read_some += 1;
                let notes = source.notes.join("\n");
                assert!(notes.contains("read up to byte"), "cut {cut}: {notes}");
            }
            Err(e) => {
                let e = e.to_string();
                assert_eq!(e.lines().count(), 1, "cut {cut}: {e}");
                assert!(e.contains("hostile.mcap"), "{e}");
            }
        }
    }
    assert!(read_some > 0, "a file cut after some chunks is read");
}

#[test]
fn header_stamps_on_another_clock_are_noted_and_a_map_can_take_log_times() {
    // PointStamped stamped from 0 (simulated time), logged on the wall clock
    let messages: Vec<(u64, Vec<u8>)> = (0..100u64)
        .map(|k| {
            let ns = k * 10_000_000;
            let mut b = vec![0, 1, 0, 0];
            b.extend(((ns / 1_000_000_000) as i32).to_le_bytes());
            b.extend(((ns % 1_000_000_000) as u32).to_le_bytes());
            b.extend(1u32.to_le_bytes());
            b.extend([0, 0, 0, 0]); // the NUL of an empty frame_id, then padding to 8
            for v in [k as f64 * 0.001, 0.0, 0.0] {
                b.extend(v.to_le_bytes());
            }
            (1_700_000_000_000_000_000 + ns + 300_000, b)
        })
        .collect();
    let bytes = write_mcap(&[(
        "/p",
        "geometry_msgs/msg/PointStamped",
        "ros2msg",
        "",
        "cdr",
        messages,
    )]);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sim.mcap");
    std::fs::write(&path, &bytes).unwrap();
    let source = read_source(&path).unwrap();
    assert!(
        source.notes.join("\n").contains("another clock"),
        "{:?}",
        source.notes
    );
    let map =
        ChannelMap::parse("[columns]\nx = \"/p.point.x\"\n[streams.\"/p\"]\nclock = \"log\"\n")
            .unwrap();
    let rec = limpid_io::read_recording_mapped(&path, Some(&map)).unwrap();
    assert_eq!(rec.len(), 100);
    assert!((rec.sample_rate() - 100.0).abs() < 1e-6);
    // a stream with one clock refuses clock = "log"
    let map =
        ChannelMap::parse("[columns]\nx = \"/p.point.x\"\n[streams.\"/p\"]\nclock = \"log\"\n")
            .unwrap();
    let plain = dir.path().join("plain.mcap");
    std::fs::write(
        &plain,
        write_mcap(&[(
            "/p",
            "std_msgs/msg/Float64",
            "ros2msg",
            "float64 data",
            "cdr",
            good_topic().5,
        )]),
    )
    .unwrap();
    let e = limpid_io::read_recording_mapped(&plain, Some(&map))
        .unwrap_err()
        .to_string();
    assert!(e.contains("one clock only"), "{e}");
    assert!(ChannelMap::parse("[columns]\nx = \"a\"\n[streams.s]\nclock = \"wall\"\n").is_err());
}

#[test]
fn files_that_are_not_bags_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in [
        ("empty.mcap", Vec::new()),
        ("text.mcap", b"not a bag at all".to_vec()),
        ("text.db3", b"SQLite format 3\0 and then nothing".to_vec()),
        ("nothing.mcap", write_mcap(&[])),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, &bytes).unwrap();
        let e = limpid_io::read_recording(&path).unwrap_err().to_string();
        assert_eq!(e.lines().count(), 1, "{name}: {e}");
        assert!(e.contains(name), "{name}: {e}");
    }
    // an empty folder named as a recording
    let folder = dir.path().join("bag");
    std::fs::create_dir(&folder).unwrap();
    std::fs::write(
        folder.join("metadata.yaml"),
        "rosbag2_bagfile_information: {}\n",
    )
    .unwrap();
    let e = limpid_io::read_recording(&folder).unwrap_err().to_string();
    assert!(e.contains("no .mcap or .db3 file"), "{e}");
}

#[test]
fn dejitter_recovers_a_regular_clock_piece_by_piece() {
    // the time base: 1 kHz with up to ±0.3 ms of jitter for 2.5 s; a second
    // stream at 500 Hz, jittered too, with a 1.5 s pause (two pieces)
    let jitter = |k: usize| 3e-4 * ((k * 7919 % 13) as f64 / 6.0 - 1.0);
    let at = |t: f64, v: f64| ((1e9 + t * 1e9) as u64, float64(v));
    let base: Vec<(u64, Vec<u8>)> = (0..2500)
        .map(|k| at(k as f64 * 1e-3 + jitter(k), k as f64))
        .collect();
    let other: Vec<(u64, Vec<u8>)> = (0..500)
        .map(|k| {
            let t = if k < 250 {
                k as f64 * 2e-3
            } else {
                2.0 + (k - 250) as f64 * 2e-3
            };
            at(t + jitter(k + 3), 1.0)
        })
        .collect();
    let topics = vec![
        (
            "/j",
            "std_msgs/msg/Float64",
            "ros2msg",
            "float64 data",
            "cdr",
            base,
        ),
        (
            "/k",
            "std_msgs/msg/Float64",
            "ros2msg",
            "float64 data",
            "cdr",
            other,
        ),
    ];
    let map = ChannelMap::parse(
        "[time]\nstream = \"/j\"\n[columns]\nx = \"/j.data\"\nfx = \"/k.data\"\n[streams.\"/j\"]\ndejitter = true\n[streams.\"/k\"]\ndejitter = true\n",
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("j.mcap");
    std::fs::write(&path, write_mcap(&topics)).unwrap();
    let converted = limpid_io::convert(&path, Some(&map)).unwrap();
    let notes = converted.notes.join("\n");
    assert!(
        notes.contains("\"/j\": stamps replaced by a line fit in 1 piece(s)"),
        "{notes}"
    );
    assert!(
        notes.contains("\"/k\": stamps replaced by a line fit in 2 piece(s)"),
        "{notes}"
    );
    let t = converted.recording.column("t").unwrap();
    for k in 1..t.len() {
        assert!(
            (t[k] - t[k - 1] - 1e-3).abs() < 1e-6,
            "{k}: {}",
            t[k] - t[k - 1]
        );
    }
}

/// CDR of a std_msgs/Float64 as ROS 2 writes it: the encapsulation header,
/// then the value (aligned from the end of the header: no padding).
fn float64_cdr(v: f64) -> Vec<u8> {
    let mut b = vec![0, 1, 0, 0];
    b.extend(v.to_le_bytes());
    b
}

/// An MCAP of one topic whose messages (log time, CDR bytes) all sit in one
/// chunk of the compression given, without message indexes (which would
/// add 16 bytes a message outside the chunk).
fn one_chunk(
    type_name: &str,
    definition: &[u8],
    compression: Option<mcap::Compression>,
    messages: impl Iterator<Item = (u64, Vec<u8>)>,
) -> Vec<u8> {
    let mut w = mcap::Writer::with_options(
        Cursor::new(Vec::new()),
        mcap::WriteOptions::new()
            .chunk_size(Some(1 << 30))
            .compression(compression)
            .emit_message_indexes(false),
    )
    .unwrap();
    let schema = w.add_schema(type_name, "ros2msg", definition).unwrap();
    let channel = w
        .add_channel(schema, "/x", "cdr", &BTreeMap::new())
        .unwrap();
    for (log_time, data) in messages {
        // sequence numbers are not read; one value keeps a bomb small
        w.write_to_known_channel(
            &MessageHeader {
                channel_id: channel,
                sequence: 0,
                log_time,
                publish_time: log_time,
            },
            &data,
        )
        .unwrap();
    }
    w.finish().unwrap();
    w.into_inner().into_inner()
}

/// Issue 76: one chunk of millions of equal messages is a compression
/// bomb (368 KB decoded to 1.5 GB, 40 chunks aborted at 5.7 GB): the
/// numbers kept from one file are budgeted by its size, and the file is
/// refused in one line once they exceed it.
#[test]
fn a_compression_bomb_is_refused_by_the_numbers_it_would_decode() {
    // equal messages at one time compress to a few bytes each
    let bytes = one_chunk(
        "std_msgs/msg/Float64",
        b"float64 data",
        Some(mcap::Compression::Zstd),
        std::iter::repeat_n((1_000_000_000, float64_cdr(0.5)), 1_000_000),
    );
    assert!(bytes.len() < 200_000, "{} bytes", bytes.len());
    let e = read_bag(&bytes).unwrap_err().to_string();
    assert!(
        e.contains("hostile.mcap") && e.contains("compression bomb") && e.lines().count() == 1,
        "{e}"
    );
}

/// Issue 76: a flipped bit inside a chunk was converted in silence (q1
/// 0.0109 -> 1.67e-7); the chunk's CRC now refuses it, naming the byte.
#[test]
fn a_chunk_whose_crc_disagrees_is_refused() {
    let mut bytes = one_chunk(
        "std_msgs/msg/Float64",
        b"float64 data",
        None,
        (0..50u64).map(|k| {
            (
                1_000_000_000 + k * 2_000_000,
                float64_cdr(0.0109 + k as f64),
            )
        }),
    );
    assert!(read_bag(&bytes).is_ok());
    let value = (0.0109f64 + 7.0).to_le_bytes();
    let at = bytes
        .windows(8)
        .position(|b| b == value)
        .expect("the value is stored uncompressed");
    bytes[at + 6] ^= 0x10;
    let e = read_bag(&bytes).unwrap_err().to_string();
    assert!(
        e.contains("hostile.mcap") && e.contains("is corrupt: its CRC") && e.lines().count() == 1,
        "{e}"
    );
}

/// Issue 76: an Attachment record whose body leaves no room for its CRC
/// panicked inside the mcap crate ("slice index starts at 34 but ends at
/// 32"); records limpid does not read are not parsed.
#[test]
fn an_attachment_too_short_for_its_crc_is_no_panic() {
    let mut bytes = b"\x89MCAP0\r\n".to_vec();
    let record = |bytes: &mut Vec<u8>, opcode: u8, body: &[u8]| {
        bytes.push(opcode);
        bytes.extend((body.len() as u64).to_le_bytes());
        bytes.extend(body);
    };
    // header: profile "ros2", library ""
    let mut header = 4u32.to_le_bytes().to_vec();
    header.extend(b"ros2");
    header.extend(0u32.to_le_bytes());
    record(&mut bytes, 0x01, &header);
    // attachment: log and create times, empty name and media type, data length 0, no CRC
    let mut attachment = vec![0u8; 16];
    attachment.extend(0u32.to_le_bytes());
    attachment.extend(0u32.to_le_bytes());
    attachment.extend(0u64.to_le_bytes());
    attachment.extend([0u8; 2]);
    record(&mut bytes, 0x09, &attachment);
    let e = read_bag(&bytes).unwrap_err().to_string();
    assert!(
        e.contains("hostile.mcap") && !e.contains("panic") && e.lines().count() == 1,
        "{e}"
    );
    // and a good bag with such an attachment after its messages reads
    let good = write_mcap(&[good_topic()]);
    assert!(read_bag(&good).is_ok());
}

/// A rosbag2 SQLite bag of `n` std_msgs/Float64 messages at 500 Hz, each
/// written `copies` times, in the journal mode given; returns the folder
/// holding `bag.db3` (and, in WAL mode with `keep_log`, `bag.db3-wal`
/// copied while the writer was open, so its last transactions live there).
fn write_db3(dir: &Path, wal: bool, keep_log: bool, copies: usize) -> std::path::PathBuf {
    let work = dir.join("writing");
    std::fs::create_dir_all(&work).unwrap();
    let db_path = work.join("bag.db3");
    let db = rusqlite::Connection::open(&db_path).unwrap();
    if wal {
        db.query_row("PRAGMA journal_mode=WAL", [], |_| Ok(()))
            .unwrap();
        db.execute_batch("PRAGMA wal_autocheckpoint=0").unwrap();
    }
    db.execute_batch(
        "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT, type TEXT, serialization_format TEXT, offered_qos_profiles TEXT);
         CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER, timestamp INTEGER, data BLOB);
         INSERT INTO topics VALUES (1, '/x', 'std_msgs/msg/Float64', 'cdr', '');",
    )
    .unwrap();
    for k in 0..200i64 {
        for _ in 0..copies {
            db.execute(
                "INSERT INTO messages(topic_id, timestamp, data) VALUES (1, ?1, ?2)",
                rusqlite::params![1_000_000_000 + k * 2_000_000, float64_cdr(k as f64 * 0.001)],
            )
            .unwrap();
        }
    }
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    if !keep_log {
        drop(db); // closing checkpoints the log into the file
        std::fs::copy(&db_path, out.join("bag.db3")).unwrap();
        return out.join("bag.db3");
    }
    std::fs::copy(&db_path, out.join("bag.db3")).unwrap();
    {
        let mut log = db_path.clone().into_os_string();
        log.push("-wal");
        let log = std::path::PathBuf::from(log);
        assert!(
            std::fs::metadata(&log).unwrap().len() > 32,
            "the log holds frames"
        );
        std::fs::copy(&log, out.join("bag.db3-wal")).unwrap();
    }
    drop(db);
    out.join("bag.db3")
}

/// Issue 76: a bag in WAL journal mode (rosbag2's `resilient` preset) was
/// "unable to open database file"; it is read, with the transactions its
/// log holds, and without a log.
#[test]
fn a_wal_mode_sqlite_bag_is_read_with_its_log() {
    let dir = tempfile::tempdir().unwrap();
    let with_log = write_db3(&dir.path().join("a"), true, true, 1);
    let source = read_source(&with_log).unwrap();
    let x = &source.streams[0].channels[0].values;
    assert_eq!(x.len(), 200, "every message, those in the log too");
    assert_eq!(x[199], 0.199);
    // the bag's folder is left as it was (SQLite worked on a copy)
    let names: Vec<_> = std::fs::read_dir(with_log.parent().unwrap())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
    // checkpointed (closed) and read from memory: the header still says WAL
    let closed = write_db3(&dir.path().join("b"), true, false, 1);
    let bytes = std::fs::read(&closed).unwrap();
    assert_eq!(bytes[18], 2, "a WAL-mode header");
    let source = read_source(&closed).unwrap();
    assert_eq!(source.streams[0].channels[0].values.len(), 200);
}

/// Issue 76: every message stored twice read as "effective 1000.5 Hz", then
/// "a gap ... where samples come every 0 s"; repeats are dropped and said.
#[test]
fn messages_stored_twice_are_dropped_and_said() {
    let dir = tempfile::tempdir().unwrap();
    let twice = write_db3(dir.path(), false, false, 2);
    let source = read_source(&twice).unwrap();
    assert_eq!(source.streams[0].channels[0].values.len(), 200);
    let notes = source.notes.join("\n");
    assert!(
        notes.contains("200 messages repeat the one before") && notes.contains("stored twice"),
        "{notes}"
    );
    let map = ChannelMap::parse("[time]\nstream = \"/x\"\n[columns]\nq1 = \"/x.data\"\n").unwrap();
    let rec = limpid_io::read_recording_mapped(&twice, Some(&map)).unwrap();
    assert_eq!(rec.len(), 200);
    assert!(
        (rec.sample_rate() - 500.0).abs() < 1e-6,
        "{}",
        rec.sample_rate()
    );
}

/// A bomb of messages on a topic that is never read (no definition) is
/// refused by the same budget: each message costs its decompression.
#[test]
fn a_bomb_of_unread_messages_is_refused_too() {
    let bytes = one_chunk(
        "my_msgs/msg/Unknown",
        b"",
        Some(mcap::Compression::Zstd),
        std::iter::repeat_n((1_000_000_000, vec![0, 1, 0, 0]), 1_500_000),
    );
    let e = read_bag(&bytes).unwrap_err().to_string();
    assert!(e.contains("compression bomb"), "{e}");
}
