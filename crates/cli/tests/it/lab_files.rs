//! Lab files through the CLI (issue 40): `inspect`, `convert`, `--map` on an
//! estimating command, the map recorded for `rerun`, and `--map` refused
//! where no recording is read.

use crate::common::{examples, json, limpid};
use limpid_testkit::xdf::{write, XdfStream};

fn fixture(name: &str) -> String {
    format!(
        "{}/../io/tests/fixtures/formats/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

#[test]
fn inspect_and_convert_a_lab_file() {
    let v = json(&["inspect", &fixture("rig.xdf"), "--json"]);
    let streams: Vec<&str> = v["streams"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(streams, ["robot", "emg", "markers"]);
    assert!(v["proposed_map"].as_str().unwrap().contains("EndEff.X"));
    let text = limpid(&["inspect", &fixture("rig.tdms")]);
    assert_eq!(text.code, 0, "{}", text.stderr);
    assert!(
        text.stdout.contains("stream \"DAQ\"") && text.stdout.contains("nominal 2000 Hz"),
        "{}",
        text.stdout
    );
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("rig.parquet");
    let v = json(&[
        "convert",
        &fixture("rig.c3d"),
        "--map",
        &fixture("rig_c3d.toml"),
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(v["samples"], 491);
    let rec = limpid_io::read_recording(&out).unwrap();
    assert_eq!(rec.names(), ["t", "x", "y", "fx", "fy", "emg_biceps"]);
    // the map is read before anything else: its mistakes name the map file and line
    let bad = d.path().join("bad.toml");
    std::fs::write(
        &bad,
        "[columns]\nx = { channel = \"a\", scale = \"minus one\" }\n",
    )
    .unwrap();
    let e = limpid(&[
        "convert",
        &fixture("rig.c3d"),
        "--map",
        bad.to_str().unwrap(),
        "-o",
        "x.csv",
    ]);
    assert_eq!(e.code, 2);
    assert!(
        e.stderr.contains("bad.toml") && e.stderr.contains("line 2"),
        "{}",
        e.stderr
    );
    assert_eq!(e.stderr.lines().count(), 1, "{}", e.stderr);
}

#[test]
fn an_estimate_from_an_xdf_file_through_a_map_equals_the_csv_one_and_reruns() {
    // the 3-D example as a rig records it: pose and force in mm and N at the
    // recording's rate, stamps on the LSL clock, a marker per perturbation
    let csv = examples("cartesian_slow").join("ex_cubic.csv");
    let rec = limpid_io::read_recording(&csv).unwrap();
    let t = rec.t();
    let trial = rec.column("trial").unwrap();
    let cols = ["x", "y", "z", "fx", "fy", "fz"];
    let robot = XdfStream {
        name: "robot".into(),
        kind: "Position".into(),
        rate: rec.sample_rate(),
        channels: cols
            .iter()
            .map(|c| {
                (
                    format!("EE.{c}"),
                    if c.starts_with('f') { "N" } else { "mm" }.to_string(),
                )
            })
            .collect(),
        stamps: t.iter().map(|t| 700.0 + t).collect(),
        values: cols
            .iter()
            .map(|c| {
                let k = if c.starts_with('f') { 1.0 } else { 1e3 };
                rec.column(c).unwrap().iter().map(|v| v * k).collect()
            })
            .collect(),
        texts: Vec::new(),
        clock_offsets: Vec::new(),
    };
    let starts: Vec<usize> = (0..t.len())
        .filter(|&i| i == 0 || trial[i] != trial[i - 1])
        .collect();
    let markers = XdfStream {
        name: "events".into(),
        kind: "Markers".into(),
        rate: 0.0,
        channels: Vec::new(),
        stamps: starts.iter().map(|&i| 700.0 + t[i]).collect(),
        values: Vec::new(),
        texts: starts.iter().map(|_| "go".to_string()).collect(),
        clock_offsets: Vec::new(),
    };
    let d = tempfile::tempdir().unwrap();
    let xdf = d.path().join("session.xdf");
    write(&xdf, &[robot, markers]).unwrap();
    let map = d.path().join("rig.toml");
    let mut text =
        String::from("[time]\nstream = \"robot\"\n[columns]\ntrial = { marker = \"go\" }\n");
    for c in cols {
        text += &format!("{c} = \"EE.{c}\"\n");
    }
    std::fs::write(&map, text).unwrap();
    let from_csv = json(&["estimate", "linear", csv.to_str().unwrap(), "--json"]);
    let from_xdf = json(&[
        "estimate",
        "linear",
        xdf.to_str().unwrap(),
        "--map",
        map.to_str().unwrap(),
        "--json",
    ]);
    for key in ["stiffness", "damping", "inertia"] {
        let (a, b) = (&from_csv[key], &from_xdf[key]);
        for (ra, rb) in a.as_array().unwrap().iter().zip(b.as_array().unwrap()) {
            for (x, y) in ra.as_array().unwrap().iter().zip(rb.as_array().unwrap()) {
                let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
                assert!(
                    (x - y).abs() <= 1e-6 * x.abs().max(1.0),
                    "{key}: {x} vs {y}"
                );
            }
        }
    }
    assert_eq!(
        from_xdf["run"]["channel_map"]["path"],
        map.to_str().unwrap()
    );
    let saved = d.path().join("result.json");
    std::fs::write(&saved, from_xdf.to_string()).unwrap();
    let again = json(&["rerun", saved.to_str().unwrap(), "--json"]);
    assert_eq!(again["stiffness"], from_xdf["stiffness"]);
}

#[test]
fn map_is_refused_where_no_recording_is_read() {
    let out = limpid(&["demo", "--map", &fixture("rig_xdf.toml")]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr
            .contains("--map applies to the commands that read recordings"),
        "{}",
        out.stderr
    );
}
