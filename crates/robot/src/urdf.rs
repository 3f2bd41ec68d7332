//! Robots from URDF files (`urdf-rs`): the serial chain from the root to
//! the end effector, fixed joints folded into the next revolute one; files a
//! human-limb robot cannot be are refused, naming the joint.

use nalgebra::{Matrix4, Vector3};

use limpid_core::{Error, Result};

use super::{pose, RevoluteJoint, Robot};

/// Deepest element nesting a URDF may have (a URDF needs 4).
pub const MAX_URDF_DEPTH: usize = 64;

/// Largest joint offset a URDF may have (m): the recordings' position limit.
pub const MAX_URDF_OFFSET_M: f64 = 100.0;

/// The line at which `xml`'s elements first nest deeper than `max`, if they
/// do. Counts start tags against end tags; comments, declarations,
/// processing instructions and CDATA do not count.
fn xml_nesting_beyond(xml: &str, max: usize) -> Option<usize> {
    let bytes = xml.as_bytes();
    let (mut depth, mut line, mut i) = (0usize, 1usize, 0usize);
    while i < bytes.len() {
        match bytes[i] {
            b'\n' => line += 1,
            b'<' => {
                let rest = &xml[i..];
                let skip_to = |end: &str| rest.find(end).map(|k| k + end.len());
                let skipped = if rest.starts_with("<!--") {
                    skip_to("-->")
                } else if rest.starts_with("<![CDATA[") {
                    skip_to("]]>")
                } else if rest.starts_with("<?") || rest.starts_with("<!") {
                    skip_to(">")
                } else {
                    None
                };
                if let Some(k) = skipped {
                    line += rest[..k].bytes().filter(|b| *b == b'\n').count();
                    i += k;
                    continue;
                }
                let close = rest.find('>').unwrap_or(rest.len());
                let tag = &rest[..close];
                line += tag.bytes().filter(|b| *b == b'\n').count();
                if tag.starts_with("</") {
                    depth = depth.saturating_sub(1);
                } else if !tag.ends_with('/') {
                    depth += 1;
                    if depth > max {
                        return Some(line);
                    }
                }
                i += close.max(1);
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    None
}

impl Robot {
    /// A robot from a URDF file (parsed by `urdf-rs`): the chain of revolute
    /// and continuous joints from the root link to `tip_link` (default: the
    /// only leaf). Fixed joints are folded into the neighbouring transforms;
    /// any other joint type on the chain is refused.
    pub fn from_urdf(path: &std::path::Path, tip_link: Option<&str>) -> Result<Self> {
        let fail = |message: String| Error::Format {
            path: path.to_path_buf(),
            message,
        };
        // through the capped reader: a FIFO or device is refused, not read for ever
        let text = limpid_core::files::read_text(path)?;
        // the XML parser recurses per element: a deeply nested file would
        // overflow the stack before it could say what is wrong
        if let Some(line) = xml_nesting_beyond(&text, MAX_URDF_DEPTH) {
            return Err(fail(format!(
                "line {line}: elements nested more than {MAX_URDF_DEPTH} deep; a URDF needs 4"
            )));
        }
        let urdf = urdf_rs::read_from_string(&text).map_err(|e| {
            fail(
                e.to_string()
                    .lines()
                    .next()
                    .unwrap_or("not a URDF file")
                    .to_string(),
            )
        })?;
        let tip = end_effector(&urdf, tip_link).map_err(fail)?;
        let chain = chain_to(&urdf, &tip).map_err(fail)?;
        let mut joints = Vec::new();
        let mut pending = Matrix4::identity();
        for j in chain {
            check_joint_numbers(j).map_err(fail)?;
            let (xyz, rpy) = (*j.origin.xyz, *j.origin.rpy);
            let origin = pose(xyz, rpy);
            match j.joint_type {
                urdf_rs::JointType::Fixed => pending *= origin,
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => {
                    let axis = Vector3::from(*j.axis.xyz);
                    let norm = axis.norm();
                    if norm < 1e-12 {
                        return Err(fail(format!("joint {:?} has a zero axis", j.name)));
                    }
                    let continuous = j.joint_type == urdf_rs::JointType::Continuous;
                    joints.push(RevoluteJoint {
                        name: j.name.clone(),
                        before: pending * origin,
                        axis: axis / norm,
                        after: Matrix4::identity(),
                        offset: 0.0,
                        min: if continuous {
                            f64::NEG_INFINITY
                        } else {
                            j.limit.lower
                        },
                        max: if continuous {
                            f64::INFINITY
                        } else {
                            j.limit.upper
                        },
                        max_speed: if j.limit.velocity > 0.0 {
                            j.limit.velocity
                        } else {
                            f64::INFINITY
                        },
                    });
                    pending = Matrix4::identity();
                }
                ref other => {
                    return Err(fail(format!(
                        "joint {:?} is {other:?}; limpid models serial chains of revolute joints",
                        j.name
                    )))
                }
            }
        }
        Ok(Robot {
            name: urdf.name,
            base: Matrix4::identity(),
            joints,
            tip: pending,
        })
    }
}

/// The end effector: the named link, else the tree's one leaf.
fn end_effector(
    urdf: &urdf_rs::Robot,
    tip_link: Option<&str>,
) -> std::result::Result<String, String> {
    let parents: std::collections::HashSet<&str> =
        urdf.joints.iter().map(|j| j.parent.link.as_str()).collect();
    match tip_link {
        Some(t) => Ok(t.to_string()),
        None => {
            let leaves: Vec<&str> = urdf
                .joints
                .iter()
                .map(|j| j.child.link.as_str())
                .filter(|c| !parents.contains(c))
                .collect();
            match leaves.as_slice() {
                [one] => Ok(one.to_string()),
                [] => Err("no leaf link: the joints form a loop".into()),
                _ => Err(format!(
                    "the tree has {} leaf links ({}); name the end effector",
                    leaves.len(),
                    leaves.join(", ")
                )),
            }
        }
    }
}

/// The joints from the root to `tip`, in order.
fn chain_to<'u>(
    urdf: &'u urdf_rs::Robot,
    tip: &str,
) -> std::result::Result<Vec<&'u urdf_rs::Joint>, String> {
    let mut chain = Vec::new();
    let mut link = tip.to_string();
    while let Some(j) = urdf.joints.iter().find(|j| j.child.link == link) {
        chain.push(j);
        link = j.parent.link.clone();
        if chain.len() > urdf.joints.len() {
            return Err("the joints form a loop".into());
        }
    }
    if chain.is_empty() {
        return Err(format!("no joint leads to link {tip:?}"));
    }
    chain.reverse();
    Ok(chain)
}

/// A limb-sized robot: every offset within the recordings' 100 m
/// plausibility limit, every number finite (a 1e9 m link asked the exporter
/// for terabytes).
fn check_joint_numbers(j: &urdf_rs::Joint) -> std::result::Result<(), String> {
    let xyz = *j.origin.xyz;
    let rpy = *j.origin.rpy;
    if xyz.iter().chain(&rpy).any(|v| !v.is_finite())
        || xyz.iter().any(|v| v.abs() > MAX_URDF_OFFSET_M)
    {
        return Err(format!(
        "joint {:?}: origin xyz {xyz:?} m, rpy {rpy:?} rad; limpid accepts finite values and offsets up to {MAX_URDF_OFFSET_M} m",
        j.name
    ));
    }
    if [
        j.limit.lower,
        j.limit.upper,
        j.limit.velocity,
        j.axis.xyz[0],
        j.axis.xyz[1],
        j.axis.xyz[2],
    ]
    .iter()
    .any(|v| !v.is_finite())
    {
        return Err(format!(
            "joint {:?}: a limit or axis is not a finite number",
            j.name
        ));
    }
    Ok(())
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    pub(crate) fn fixture(name: &str) -> std::path::PathBuf {
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures")
            .join(name)
    }

    #[test]
    fn urdf_chain_equals_the_dh_model_it_was_written_from() {
        let dh = Robot::kuka_lwr4();
        let urdf = Robot::from_urdf(&fixture("kuka_lwr4.urdf"), None).unwrap();
        assert_eq!(urdf.dof(), 7);
        assert_eq!(urdf.name, "kuka_lwr4_dh");
        assert!((urdf.joints[1].max - 120f64.to_radians()).abs() < 1e-12);
        for k in 0..20 {
            let q: Vec<f64> = (0..7)
                .map(|i| ((k * 7 + i) as f64 * 0.77).sin() * 2.0)
                .collect();
            let err = (dh.fk(&q) - urdf.fk(&q)).norm();
            assert!(err < 1e-12, "pose difference {err:e} at {q:?}");
        }
    }

    #[test]
    fn bad_urdf_files_are_refused_with_their_path() {
        let dir = std::env::temp_dir().join(format!("limpid-urdf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let cases = [
            (
                "broken.urdf",
                "<robot name=\"x\"><link name=\"a\"/>",
                "broken.urdf",
            ),
            (
                "prismatic.urdf",
                r#"<robot name="p"><link name="a"/><link name="b"/>
                   <joint name="slide" type="prismatic"><parent link="a"/><child link="b"/>
                   <axis xyz="1 0 0"/><limit lower="0" upper="1" effort="1" velocity="1"/></joint></robot>"#,
                "joint \"slide\" is Prismatic",
            ),
            (
                "huge.urdf",
                r#"<robot name="h"><link name="a"/><link name="b"/>
                   <joint name="j1" type="revolute"><parent link="a"/><child link="b"/>
                   <origin xyz="1e9 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>
                   <limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"#,
                "joint \"j1\": origin xyz [1000000000.0, 0.0, 0.0] m",
            ),
            (
                "nan.urdf",
                r#"<robot name="n"><link name="a"/><link name="b"/>
                   <joint name="j1" type="revolute"><parent link="a"/><child link="b"/>
                   <origin xyz="0 0 0" rpy="NaN 0 0"/><axis xyz="0 0 1"/>
                   <limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"#,
                "limpid accepts finite values",
            ),
            (
                "loop.urdf",
                r#"<robot name="l"><link name="a"/><link name="b"/>
                   <joint name="j1" type="revolute"><parent link="a"/><child link="b"/>
                   <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
                   <joint name="j2" type="revolute"><parent link="b"/><child link="a"/>
                   <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"#,
                "no leaf link: the joints form a loop",
            ),
        ];
        for (name, text, expect) in cases {
            let path = dir.join(name);
            std::fs::write(&path, text).unwrap();
            let e = Robot::from_urdf(&path, None).unwrap_err().to_string();
            assert!(e.contains(expect) && e.contains(name), "{e}");
        }
    }

    /// 100,000 nested elements overflowed the XML parser's stack (a crash);
    /// they are refused first, with the line where the nesting goes too deep.
    #[test]
    fn a_deeply_nested_urdf_is_refused_before_parsing() {
        let dir = std::env::temp_dir().join(format!("limpid-deep-urdf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("deep.urdf");
        let mut text = String::from("<robot name=\"d\">\n<!-- <a><a><a> -->\n");
        text.push_str(&"<link>".repeat(100_000));
        std::fs::write(&path, &text).unwrap();
        let e = Robot::from_urdf(&path, None).unwrap_err().to_string();
        assert!(
            e.contains("deep.urdf") && e.contains("line 3: elements nested more than 64 deep"),
            "{e}"
        );
        // the depth count: self-closing tags, comments and declarations do not nest
        let ok = "<?xml version=\"1.0\"?>\n<!DOCTYPE robot>\n<robot><link name=\"a\"/><!-- <x> --><joint><parent link=\"a\"/></joint></robot>";
        assert_eq!(xml_nesting_beyond(ok, 2), None);
        assert_eq!(xml_nesting_beyond(ok, 1), Some(3));
    }
}
