//! ROS 2 bags (issue 62): an MCAP file (`ros2 bag record`'s default since
//! Iron), a rosbag2 SQLite file (`.db3`, before), or a rosbag2 folder holding
//! either (with its `metadata.yaml`).
//!
//! Every topic is a stream named by the topic (`/wrench`); its channels are
//! the numeric fields of its messages, named `/topic.field.path`
//! (`/wrench.wrench.force.x`), array elements by index (`/joint_states.effort[0]`)
//! and, where the message carries a `name` array of the same length (a
//! JointState), by name (`/joint_states.position[ankle]`, the index form
//! kept as another name). A topic of text messages (std_msgs/String) is a
//! marker stream. Messages are decoded from CDR ([`cdr`]) by their type's
//! definition ([`msg`]): the one stored in the bag where present, else the
//! built-in standard types.
//!
//! Time: a message's header stamp when its type starts with a
//! `std_msgs/Header`, else the time the recorder logged it; both are kept in
//! integer nanoseconds until the bag's start (its earliest log time) is
//! subtracted. A topic whose header stamps lie far from its log times (a
//! simulated clock, an unsynchronised sensor) is noted; a map's
//! `[streams."/topic"] clock = "log"` then uses the log times instead.
//!
//! A topic is listed and skipped, never a reason to refuse the bag, when its
//! type has no known definition, its encoding is not CDR, its messages carry
//! no number or more than [`MAX_FIELDS`] (an image), or their arrays change
//! length from message to message in more than [`MAX_SHAPES`] ways. Messages
//! of one topic whose array lengths differ (a JointState topic fed by two
//! publishers with different joints) form one stream per shape:
//! `/joint_states`, `/joint_states#2`, ...

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::{Channel, Marker, Source, Stream};
use limpid_core::{Error, Result};

mod cdr;
mod container;
mod msg;

pub use container::{read, read_bytes};

/// Most numeric fields one message may have to be read (more: an image, a
/// point cloud).
pub const MAX_FIELDS: usize = 4096;

/// Most distinct array shapes one topic may have.
pub const MAX_SHAPES: usize = 8;

/// Header stamps further than this from the log times are on another clock (ns).
const OTHER_CLOCK_NS: i64 = 60 * 1_000_000_000;

/// Most numbers (values and two stamps a message, one for a message not
/// kept; 8 bytes of text count as one) kept from one bag file: 1 GiB of f64, an hour of a 1 kHz
/// JointState of 7 joints with room to spare.
pub const MAX_DECODED_NUMBERS: u64 = 1 << 27;

/// Most bytes of numbers kept per byte of a bag file. Recorded signals
/// compress a few times over; a chunk of millions of equal messages is a
/// compression bomb (368 KB became 1.5 GB; issue 76).
pub const MAX_DECODED_RATIO: u64 = 256;

/// The numbers a file may yield: its ratio's worth, at least 2^20 (8 MiB:
/// a small file harms nobody), at most [`MAX_DECODED_NUMBERS`].
fn decoded_budget(file_bytes: usize) -> u64 {
    (file_bytes as u64)
        .saturating_mul(MAX_DECODED_RATIO / 8)
        .clamp(1 << 20, MAX_DECODED_NUMBERS)
}

/// One shape of a topic's messages: their columns.
struct Group {
    shape: Vec<u64>,
    names: Vec<(String, Option<String>)>,
    columns: Vec<Vec<f64>>,
    stamps_ns: Vec<i64>,
    log_ns: Vec<i64>,
}

impl Group {
    /// Keep the messages `rows`, in that order (a reordering or a selection).
    fn select(&mut self, rows: &[usize]) {
        fn pick<T: Copy>(v: &[T], rows: &[usize]) -> Vec<T> {
            rows.iter().map(|&i| v[i]).collect()
        }
        for c in &mut self.columns {
            *c = pick(c, rows);
        }
        self.stamps_ns = pick(&self.stamps_ns, rows);
        self.log_ns = pick(&self.log_ns, rows);
    }
}

enum Content {
    /// Not decided: no message yet.
    Empty,
    Numeric(Vec<Group>),
    Markers(Vec<(i64, i64, String)>),
    Unread(String),
}

struct Topic {
    name: String,
    /// As the bag names it (`geometry_msgs/msg/WrenchStamped`).
    type_name: String,
    /// Normalised (`geometry_msgs/WrenchStamped`).
    root: String,
    messages: usize,
    has_header: bool,
    content: Content,
    /// Messages that could not be decoded after the first: count, first reason.
    failed: (usize, Option<String>),
}

/// Gathers the messages of one bag (over its files) into streams.
pub(crate) struct Collector {
    registry: msg::Registry,
    topics: Vec<Topic>,
    by_name: HashMap<String, usize>,
    scratch: cdr::Decoded,
    notes: Vec<String>,
    /// The file being read, the numbers kept from it and its budget.
    file: PathBuf,
    file_bytes: usize,
    kept: u64,
    budget: u64,
}

impl Collector {
    pub(crate) fn new() -> Collector {
        Collector {
            registry: msg::Registry::standard(),
            topics: Vec::new(),
            by_name: HashMap::new(),
            scratch: cdr::Decoded::default(),
            notes: Vec::new(),
            file: PathBuf::new(),
            file_bytes: 0,
            kept: 0,
            budget: MAX_DECODED_NUMBERS,
        }
    }

    /// A bag file of `bytes` bytes starts: its budget of numbers.
    pub(crate) fn start_file(&mut self, path: &Path, bytes: usize) {
        self.file = path.to_path_buf();
        self.file_bytes = bytes;
        self.kept = 0;
        self.budget = decoded_budget(bytes);
    }

    /// A message of no declared topic: it counts against the budget too.
    pub(crate) fn count_unkept(&mut self) {
        self.kept += 1;
    }

    /// Refuse the file once the messages kept from it exceed its budget.
    pub(crate) fn check_budget(&self) -> Result<()> {
        if self.kept <= self.budget {
            return Ok(());
        }
        let mib = |numbers: u64| (numbers * 8) >> 20;
        Err(Error::Format {
            path: self.file.clone(),
            message: format!(
                "its messages decode to more than {} MiB of numbers from a file of {} bytes (limpid keeps {} bytes of numbers per byte of a bag file, at least 8 MiB, at most {} MiB): a compression bomb, or a bag to split (ros2 bag convert)",
                mib(self.budget),
                self.file_bytes,
                MAX_DECODED_RATIO,
                mib(MAX_DECODED_NUMBERS)
            ),
        })
    }

    /// A definition stored in the bag (`ros2msg` text) for `type_name`.
    pub(crate) fn definition(&mut self, type_name: &str, encoding: &str, text: &str) {
        if encoding != "ros2msg" {
            return;
        }
        if let Err(m) = self.registry.add_stored(type_name, text) {
            self.notes.push(format!(
                "the stored definition of {type_name} was not understood ({m}); the built-in one is used where there is one"
            ));
        }
    }

    /// A topic; `encoding` is its serialisation (`cdr`). Returns its index.
    pub(crate) fn topic(&mut self, name: &str, type_name: &str, encoding: &str) -> usize {
        if let Some(&k) = self.by_name.get(name) {
            return k;
        }
        let root = msg::normalise(type_name);
        let content = if encoding != "cdr" {
            Content::Unread(format!("messages encoded as {encoding:?}, not CDR"))
        } else {
            Content::Empty
        };
        self.topics.push(Topic {
            name: name.to_string(),
            type_name: type_name.to_string(),
            root,
            messages: 0,
            has_header: false,
            content,
            failed: (0, None),
        });
        self.by_name.insert(name.to_string(), self.topics.len() - 1);
        self.topics.len() - 1
    }

    /// One message of topic `k`, logged at `log_ns`.
    pub(crate) fn message(&mut self, k: usize, log_ns: i64, data: &[u8]) {
        // every message counts once, kept or not: millions of messages of a
        // topic that is not read still cost their decompression
        self.kept += 1;
        let topic = &mut self.topics[k];
        topic.messages += 1;
        if matches!(topic.content, Content::Unread(_)) {
            return;
        }
        if self.registry.get(&topic.root).is_none() {
            topic.content = Content::Unread(format!(
                "no definition of {} is stored in the bag or built in",
                topic.type_name
            ));
            return;
        }
        let first = matches!(topic.content, Content::Empty);
        let out = &mut self.scratch;
        // names are made for a topic's first message and each new shape
        let mut decoded = cdr::decode(&self.registry, &topic.root, data, first, out);
        if decoded.is_ok() {
            if let Content::Numeric(groups) = &topic.content {
                if !groups.iter().any(|g| g.shape == out.shape) && groups.len() < MAX_SHAPES {
                    decoded = cdr::decode(&self.registry, &topic.root, data, true, out);
                }
            }
        }
        if let Err(m) = decoded {
            if first {
                topic.content = Content::Unread(format!("message 1 does not decode: {m}"));
            } else {
                topic.failed.0 += 1;
                topic
                    .failed
                    .1
                    .get_or_insert(format!("message {}: {m}", topic.messages));
            }
            return;
        }
        let stamp = out.stamp_ns.unwrap_or(log_ns);
        if first {
            topic.has_header = out.stamp_ns.is_some();
            topic.content = if out.values.is_empty() {
                match out.text.take() {
                    Some(text) => Content::Markers(vec![(stamp, log_ns, text)]),
                    None => Content::Unread("its messages hold no number and no text".into()),
                }
            } else if out.values.len() > MAX_FIELDS {
                Content::Unread(format!(
                    "{} numbers per message (an image or a point cloud?): more than the {MAX_FIELDS} read",
                    out.values.len()
                ))
            } else {
                Content::Numeric(Vec::new())
            };
            if !matches!(topic.content, Content::Numeric(_)) {
                return;
            }
        }
        match &mut topic.content {
            Content::Markers(m) => {
                if let Some(text) = out.text.take() {
                    self.kept += 1 + text.len() as u64 / 8;
                    m.push((stamp, log_ns, text));
                }
            }
            Content::Numeric(groups) => {
                let g = match groups.iter().position(|g| g.shape == out.shape) {
                    Some(g) => g,
                    None if groups.len() < MAX_SHAPES => {
                        let names = out.names.take().unwrap_or_default();
                        groups.push(Group {
                            shape: out.shape.clone(),
                            columns: vec![Vec::new(); names.len()],
                            names,
                            stamps_ns: Vec::new(),
                            log_ns: Vec::new(),
                        });
                        groups.len() - 1
                    }
                    None => {
                        topic.content = Content::Unread(format!(
                            "its arrays change length in more than {MAX_SHAPES} ways from message to message"
                        ));
                        return;
                    }
                };
                let group = &mut groups[g];
                if group.columns.len() != out.values.len() {
                    // one shape, one set of leaves; kept as a guard
                    topic.failed.0 += 1;
                    return;
                }
                self.kept += 1 + out.values.len() as u64;
                for (column, v) in group.columns.iter_mut().zip(&out.values) {
                    column.push(*v);
                }
                group.stamps_ns.push(stamp);
                group.log_ns.push(log_ns);
            }
            Content::Empty | Content::Unread(_) => {}
        }
    }

    /// The streams, with times counted from the bag's earliest log time.
    pub(crate) fn finish(self, path: &Path, format: &'static str) -> Result<Source> {
        let mut notes = self.notes;
        let origin = self
            .topics
            .iter()
            .flat_map(|t| match &t.content {
                Content::Numeric(groups) => {
                    groups.iter().flat_map(|g| g.log_ns.iter().copied()).min()
                }
                Content::Markers(m) => m.iter().map(|x| x.1).min(),
                _ => None,
            })
            .min();
        let Some(origin) = origin else {
            let listed: Vec<String> = self
                .topics
                .iter()
                .map(|t| match &t.content {
                    Content::Unread(why) => format!("{} ({}): {why}", t.name, t.type_name),
                    _ => format!("{} ({}): no message", t.name, t.type_name),
                })
                .take(8)
                .collect();
            return Err(Error::Format {
                path: path.to_path_buf(),
                message: if listed.is_empty() {
                    "the bag holds no topic".into()
                } else {
                    format!("no topic could be read: {}", listed.join("; "))
                },
            });
        };
        let seconds = |ns: i64| ((ns as i128 - origin as i128) as f64) * 1e-9;
        let mut streams = Vec::new();
        let mut unread = Vec::new();
        let mut other_clock = Vec::new();
        let mut reordered = Vec::new();
        for t in self.topics {
            if t.failed.0 > 0 {
                notes.push(format!(
                    "{}: {} of {} messages could not be decoded and were left out ({})",
                    t.name,
                    t.failed.0,
                    t.messages,
                    t.failed
                        .1
                        .as_deref()
                        .unwrap_or("a message of another shape")
                ));
            }
            let clock = if t.has_header {
                "header stamps"
            } else {
                "log time"
            };
            match t.content {
                Content::Unread(why) => unread.push((
                    t.name.clone(),
                    format!("{} ({}): {why}", t.name, t.type_name),
                )),
                Content::Empty => unread.push((
                    t.name.clone(),
                    format!("{} ({}): no message", t.name, t.type_name),
                )),
                Content::Markers(mut m) => {
                    m.sort_by_key(|x| x.0);
                    streams.push(Stream {
                        name: t.name.clone(),
                        kind: Some(t.type_name.clone()),
                        stamps: Some(m.iter().map(|x| seconds(x.0)).collect()),
                        markers: m
                            .into_iter()
                            .map(|(ns, _, text)| Marker {
                                time: seconds(ns),
                                text,
                            })
                            .collect(),
                        clock: Some(clock.into()),
                        ..Stream::default()
                    });
                }
                Content::Numeric(groups) => {
                    let several = groups.len() > 1;
                    if several {
                        notes.push(format!(
                            "{}: messages of {} shapes (arrays of other lengths or other joint names) are read as streams {}",
                            t.name,
                            groups.len(),
                            (1..=groups.len())
                                .map(|k| stream_name(&t.name, k))
                                .collect::<Vec<_>>()
                                .join(", ")
                        ));
                    }
                    for (k, mut g) in groups.into_iter().enumerate() {
                        let name = stream_name(&t.name, k + 1);
                        if t.has_header {
                            let mut offsets: Vec<i64> = g
                                .stamps_ns
                                .iter()
                                .zip(&g.log_ns)
                                .map(|(s, l)| s.saturating_sub(*l))
                                .collect();
                            let mid = offsets.len() / 2;
                            let median = *offsets.select_nth_unstable(mid).1;
                            if median.abs() > OTHER_CLOCK_NS {
                                other_clock.push(format!(
                                    "{name} ({} s)",
                                    limpid_core::error::significant(median as f64 * 1e-9, 4)
                                ));
                            }
                        }
                        if g.stamps_ns.windows(2).any(|w| w[1] < w[0]) {
                            let mut order: Vec<usize> = (0..g.stamps_ns.len()).collect();
                            order.sort_by_key(|&i| g.stamps_ns[i]);
                            let moved = order.iter().enumerate().filter(|(a, b)| a != *b).count();
                            reordered.push(format!("{name} ({moved} messages)"));
                            g.select(&order);
                        }
                        let (dropped, clashing) = drop_repeated_messages(&mut g);
                        if dropped > 0 {
                            notes.push(format!(
                                "{name}: {dropped} messages repeat the one before (same stamp, same values: stored twice?) and were dropped"
                            ));
                        }
                        if clashing > 0 {
                            notes.push(format!(
                                "{name}: {clashing} messages carry the stamp of the one before with other values; the stamps do not order them"
                            ));
                        }
                        let full = |leaf: &str| format!("{}.{leaf}", t.name);
                        let aliases = g
                            .names
                            .iter()
                            .enumerate()
                            .filter_map(|(i, (_, other))| other.as_ref().map(|o| (full(o), i)))
                            .collect();
                        streams.push(Stream {
                            name,
                            kind: Some(t.type_name.clone()),
                            stamps: Some(g.stamps_ns.iter().map(|&ns| seconds(ns)).collect()),
                            channels: g
                                .names
                                .iter()
                                .zip(g.columns)
                                .map(|((leaf, _), values)| Channel {
                                    name: full(leaf),
                                    unit: None,
                                    values,
                                })
                                .collect(),
                            clock: Some(clock.into()),
                            log_stamps: t
                                .has_header
                                .then(|| g.log_ns.iter().map(|&ns| seconds(ns)).collect()),
                            aliases,
                            ..Stream::default()
                        });
                    }
                }
            }
        }
        if !other_clock.is_empty() {
            notes.push(format!(
                "header stamps far from the recorder's log times (another clock?): {}; to align such a topic by log time, give it clock = \"log\" in the map's [streams.\"/topic\"]",
                other_clock.join(", ")
            ));
        }
        if !reordered.is_empty() {
            notes.push(format!(
                "messages put in header-stamp order: {}",
                reordered.join(", ")
            ));
        }
        if !unread.is_empty() {
            notes.push(format!(
                "topics not read: {}",
                unread
                    .iter()
                    .map(|(_, why)| why.as_str())
                    .collect::<Vec<_>>()
                    .join("; ")
            ));
        }
        if streams.is_empty() {
            return Err(Error::Format {
                path: path.to_path_buf(),
                message: format!(
                    "no topic could be read: {}",
                    unread
                        .iter()
                        .map(|(_, w)| w.as_str())
                        .take(8)
                        .collect::<Vec<_>>()
                        .join("; ")
                ),
            });
        }
        Ok(Source {
            path: PathBuf::from(path),
            format,
            streams,
            notes,
            unread,
            scalars: Vec::new(),
        })
    }
}

/// Drop each message that repeats the one before it (same stamp, same
/// values: a bag that stored every message twice read as 1000.5 Hz, then as
/// gaps "where samples come every 0 s"; issue 76). Returns the messages
/// dropped and those left that share a stamp with other values.
fn drop_repeated_messages(g: &mut Group) -> (usize, usize) {
    let n = g.stamps_ns.len();
    let repeats = |i: usize, j: usize| {
        g.stamps_ns[i] == g.stamps_ns[j]
            && g.columns.iter().all(|c| c[i].to_bits() == c[j].to_bits())
    };
    // each message compared with the last one kept
    let mut kept: Vec<usize> = Vec::with_capacity(n);
    for i in 0..n {
        if kept.last().is_none_or(|&last| !repeats(i, last)) {
            kept.push(i);
        }
    }
    let dropped = n - kept.len();
    if dropped > 0 {
        g.select(&kept);
    }
    let clashing = g.stamps_ns.windows(2).filter(|w| w[0] == w[1]).count();
    (dropped, clashing)
}

fn stream_name(topic: &str, k: usize) -> String {
    if k == 1 {
        topic.to_string()
    } else {
        format!("{topic}#{k}")
    }
}
