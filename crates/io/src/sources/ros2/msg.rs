//! ROS 2 message definitions (`.msg` text) parsed into field lists.
//!
//! A definition is one line per field, `type name [default]`, or a constant
//! `type NAME=value`; `#` starts a comment. Types are primitives (`bool`,
//! `byte`, `char`, `int8`..`uint64`, `float32`, `float64`, `string`,
//! `wstring`, `string<=N`), other messages (`pkg/Type`, `pkg/msg/Type`, or a
//! bare `Type` of the same package; `Header` is `std_msgs/Header`), each
//! optionally an array: `T[]` (a sequence), `T[<=N]` (a bounded sequence),
//! `T[N]` (fixed). A bag's stored definition (MCAP schema `ros2msg`, rosbag2's
//! `message_definitions` table) is the main type's text followed by each
//! dependency after a line of `=` and a `MSG: pkg/Type` line.
//!
//! The standard types limpid maps (JointState, the geometry_msgs stamped
//! types, std_msgs numbers, arrays and strings) are built in, so a bag that
//! stores no definitions (rosbag2 before Jazzy) is read as well.

use std::collections::HashMap;

/// A primitive field type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Primitive {
    Bool,
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
    Text,
    WideText,
}

impl Primitive {
    fn parse(word: &str) -> Option<Primitive> {
        Some(match word {
            "bool" => Primitive::Bool,
            "int8" => Primitive::I8,
            "uint8" | "byte" | "char" => Primitive::U8,
            "int16" => Primitive::I16,
            "uint16" => Primitive::U16,
            "int32" => Primitive::I32,
            "uint32" => Primitive::U32,
            "int64" => Primitive::I64,
            "uint64" => Primitive::U64,
            "float32" => Primitive::F32,
            "float64" => Primitive::F64,
            "string" => Primitive::Text,
            "wstring" => Primitive::WideText,
            w if w.starts_with("string<=") => Primitive::Text,
            w if w.starts_with("wstring<=") => Primitive::WideText,
            _ => return None,
        })
    }

    pub(crate) fn is_text(self) -> bool {
        matches!(self, Primitive::Text | Primitive::WideText)
    }
}

/// A field's element type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Element {
    Primitive(Primitive),
    /// Another message, by its normalised name `pkg/Type`.
    Message(String),
}

/// How many elements a field holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Count {
    One,
    Fixed(usize),
    /// A sequence (its length precedes it), bounded or not.
    Sequence,
}

/// One field of a message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Field {
    pub name: String,
    pub element: Element,
    pub count: Count,
}

/// Largest fixed array accepted in a definition.
const MAX_FIXED: usize = 1 << 20;

/// `pkg/msg/Type`, `pkg/Type` -> `pkg/Type`.
pub(crate) fn normalise(name: &str) -> String {
    let parts: Vec<&str> = name.trim().split('/').collect();
    match parts.as_slice() {
        [pkg, "msg", ty] => format!("{pkg}/{ty}"),
        _ => name.trim().to_string(),
    }
}

/// Message definitions by normalised name.
#[derive(Debug, Clone, Default)]
pub(crate) struct Registry {
    types: HashMap<String, Vec<Field>>,
}

impl Registry {
    /// The built-in standard types.
    pub(crate) fn standard() -> Registry {
        let mut r = Registry::default();
        for (name, text) in STANDARD {
            r.add_one(name, text)
                .expect("the built-in definitions parse");
        }
        r
    }

    /// The definition of `name`, if known.
    pub(crate) fn get(&self, name: &str) -> Option<&[Field]> {
        self.types.get(name).map(Vec::as_slice)
    }

    /// Add a stored definition of `main` (with its dependencies after `=`
    /// lines and `MSG:` headers). Stored definitions replace built-in ones.
    pub(crate) fn add_stored(&mut self, main: &str, text: &str) -> Result<(), String> {
        let mut name = normalise(main);
        let mut block = String::new();
        for line in text.lines() {
            let trimmed = line.trim();
            if trimmed.len() >= 3 && trimmed.chars().all(|c| c == '=') {
                self.add_one(&name, &block)?;
                block.clear();
                name.clear();
                continue;
            }
            if let Some(dep) = trimmed.strip_prefix("MSG:") {
                name = normalise(dep);
                continue;
            }
            block.push_str(line);
            block.push('\n');
        }
        if !name.is_empty() {
            self.add_one(&name, &block)?;
        }
        Ok(())
    }

    fn add_one(&mut self, name: &str, text: &str) -> Result<(), String> {
        // a stored text without fields (a writer that stores none) keeps
        // the built-in definition
        if self.types.contains_key(name)
            && text
                .lines()
                .all(|l| l.split('#').next().unwrap_or("").trim().is_empty())
        {
            return Ok(());
        }
        let package = name.split('/').next().unwrap_or("");
        let mut fields = Vec::new();
        for (k, raw) in text.lines().enumerate() {
            let line = raw.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let mut words = line.split_whitespace();
            let (Some(ty), Some(field)) = (words.next(), words.next()) else {
                return Err(format!(
                    "{name} line {}: {line:?} is not `type name`",
                    k + 1
                ));
            };
            // constants: `int32 X=1`, `int32 X = 1`, `string S="a"`
            if field.contains('=') || words.next().is_some_and(|w| w.starts_with('=')) {
                continue;
            }
            fields.push(parse_field(package, ty, field).map_err(|m| format!("{name}: {m}"))?);
        }
        self.types.insert(name.to_string(), fields);
        Ok(())
    }
}

fn parse_field(package: &str, ty: &str, name: &str) -> Result<Field, String> {
    let (base, count) = match ty.find('[') {
        Some(open) => {
            let inside = ty[open + 1..]
                .strip_suffix(']')
                .ok_or_else(|| format!("field {name}: type {ty:?} lacks its ']'"))?;
            let count = if inside.is_empty() || inside.starts_with("<=") {
                Count::Sequence
            } else {
                let n: usize = inside
                    .parse()
                    .map_err(|_| format!("field {name}: array size {inside:?} is not a number"))?;
                if n > MAX_FIXED {
                    return Err(format!("field {name}: a fixed array of {n} elements"));
                }
                Count::Fixed(n)
            };
            (&ty[..open], count)
        }
        None => (ty, Count::One),
    };
    let element = match Primitive::parse(base) {
        Some(p) => Element::Primitive(p),
        None if base == "Header" => Element::Message("std_msgs/Header".into()),
        None if base.contains('/') => Element::Message(normalise(base)),
        None if base.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') && !base.is_empty() => {
            Element::Message(format!("{package}/{base}"))
        }
        None => {
            return Err(format!(
                "field {name}: type {base:?} is not a ROS type name"
            ))
        }
    };
    Ok(Field {
        name: name.to_string(),
        element,
        count,
    })
}

/// The standard types limpid reads without a stored definition.
const STANDARD: &[(&str, &str)] = &[
    ("builtin_interfaces/Time", "int32 sec\nuint32 nanosec"),
    ("builtin_interfaces/Duration", "int32 sec\nuint32 nanosec"),
    (
        "std_msgs/Header",
        "builtin_interfaces/Time stamp\nstring frame_id",
    ),
    ("std_msgs/String", "string data"),
    ("std_msgs/Bool", "bool data"),
    ("std_msgs/Float64", "float64 data"),
    ("std_msgs/Float32", "float32 data"),
    ("std_msgs/Int32", "int32 data"),
    ("std_msgs/Int64", "int64 data"),
    (
        "std_msgs/MultiArrayDimension",
        "string label\nuint32 size\nuint32 stride",
    ),
    (
        "std_msgs/MultiArrayLayout",
        "MultiArrayDimension[] dim\nuint32 data_offset",
    ),
    (
        "std_msgs/Float64MultiArray",
        "MultiArrayLayout layout\nfloat64[] data",
    ),
    (
        "std_msgs/Float32MultiArray",
        "MultiArrayLayout layout\nfloat32[] data",
    ),
    ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z"),
    ("geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z"),
    (
        "geometry_msgs/Quaternion",
        "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
    ),
    ("geometry_msgs/Pose", "Point position\nQuaternion orientation"),
    ("geometry_msgs/Wrench", "Vector3 force\nVector3 torque"),
    ("geometry_msgs/Twist", "Vector3 linear\nVector3 angular"),
    ("geometry_msgs/PoseStamped", "std_msgs/Header header\nPose pose"),
    ("geometry_msgs/PointStamped", "std_msgs/Header header\nPoint point"),
    (
        "geometry_msgs/WrenchStamped",
        "std_msgs/Header header\nWrench wrench",
    ),
    ("geometry_msgs/TwistStamped", "std_msgs/Header header\nTwist twist"),
    (
        "geometry_msgs/Vector3Stamped",
        "std_msgs/Header header\nVector3 vector",
    ),
    (
        "sensor_msgs/JointState",
        "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort",
    ),
];
