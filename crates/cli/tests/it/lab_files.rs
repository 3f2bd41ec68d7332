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
            .contains("--map: it applies to the commands that read recordings"),
        "{}",
        out.stderr
    );
}

/// The streams a rig would record for `rec`: robot pose and force (mm, N),
/// EMG (uV) and, where the recording has trials, markers for each trial's
/// start and level.
fn rig_streams(rec: &limpid_core::Recording) -> Vec<XdfStream> {
    let t = rec.t();
    let lsl = |t: &f64| 5000.0 + t;
    let mut out = Vec::new();
    let robot: Vec<&str> = ["x", "y", "z", "fx", "fy", "fz"]
        .into_iter()
        .filter(|c| rec.has(c))
        .collect();
    if !robot.is_empty() {
        out.push(XdfStream {
            name: "robot".into(),
            kind: "Position".into(),
            rate: rec.sample_rate(),
            channels: robot
                .iter()
                .map(|c| {
                    (
                        format!("EE.{c}"),
                        if c.starts_with('f') { "N" } else { "mm" }.to_string(),
                    )
                })
                .collect(),
            stamps: t.iter().map(lsl).collect(),
            values: robot
                .iter()
                .map(|c| {
                    let k = if c.starts_with('f') { 1.0 } else { 1e3 };
                    rec.column(c).unwrap().iter().map(|v| v * k).collect()
                })
                .collect(),
            texts: Vec::new(),
            clock_offsets: Vec::new(),
        });
    }
    let emg: Vec<&String> = rec
        .names()
        .iter()
        .filter(|n| n.starts_with("emg_"))
        .collect();
    out.push(XdfStream {
        name: "emg".into(),
        kind: "EMG".into(),
        rate: rec.sample_rate(),
        channels: emg
            .iter()
            .map(|n| (n[4..].to_string(), "uV".to_string()))
            .collect(),
        stamps: t.iter().map(lsl).collect(),
        values: emg
            .iter()
            .map(|n| rec.column(n).unwrap().iter().map(|v| v * 1e6).collect())
            .collect(),
        texts: Vec::new(),
        clock_offsets: Vec::new(),
    });
    if let (Some(trial), Some(level)) = (rec.column("trial"), rec.column("level")) {
        let starts: Vec<usize> = (0..t.len())
            .filter(|&i| i == 0 || trial[i] != trial[i - 1])
            .collect();
        out.push(XdfStream {
            name: "events".into(),
            kind: "Markers".into(),
            rate: 0.0,
            channels: Vec::new(),
            stamps: starts
                .iter()
                .flat_map(|&i| [lsl(&t[i]), lsl(&t[i])])
                .collect(),
            values: Vec::new(),
            texts: starts
                .iter()
                .flat_map(|&i| ["start".to_string(), format!("level {}", level[i])])
                .collect(),
            clock_offsets: Vec::new(),
        });
    }
    out
}

#[test]
fn a_cocontraction_session_and_its_mvc_recording_read_through_one_map() {
    let dir = examples("cocontraction");
    let (csv, mvc_csv) = (dir.join("ex_config4.csv"), dir.join("ex_config4.mvc.csv"));
    let rec = limpid_io::read_recording(&csv).unwrap();
    let mvc = limpid_io::read_recording(&mvc_csv).unwrap();
    let d = tempfile::tempdir().unwrap();
    let (session, mvc_xdf) = (d.path().join("session.xdf"), d.path().join("mvc.xdf"));
    write(&session, &rig_streams(&rec)).unwrap();
    // the MVC contractions recorded by the EMG amplifier alone
    let emg_only: Vec<XdfStream> = rig_streams(&mvc)
        .into_iter()
        .filter(|s| s.name == "emg")
        .collect();
    write(&mvc_xdf, &emg_only).unwrap();
    let map = d.path().join("rig.toml");
    let mut text = String::from("[time]\nstream = \"robot\"\n[columns]\ntrial = { marker = \"start\" }\nlevel = { marker_prefix = \"level \" }\n");
    for c in ["x", "y", "z", "fx", "fy", "fz"] {
        text += &format!("{c} = \"EE.{c}\"\n");
    }
    for n in rec.names().iter().filter(|n| n.starts_with("emg_")) {
        text += &format!("{n} = {{ channel = \"{}\", stream = \"emg\" }}\n", &n[4..]);
    }
    std::fs::write(&map, text).unwrap();
    let from_csv = json(&[
        "estimate",
        "cocontraction",
        csv.to_str().unwrap(),
        "--mvc",
        mvc_csv.to_str().unwrap(),
        "--json",
    ]);
    let out = limpid(&[
        "estimate",
        "cocontraction",
        session.to_str().unwrap(),
        "--mvc",
        mvc_xdf.to_str().unwrap(),
        "--map",
        map.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    // the MVC file has no robot stream and no markers: the map's other columns are left out, said once
    assert!(
        out.stderr.contains("mvc.xdf") && out.stderr.contains("left out"),
        "{}",
        out.stderr
    );
    let from_xdf: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
    let (a, b) = (
        from_csv["levels"].as_array().unwrap(),
        from_xdf["levels"].as_array().unwrap(),
    );
    assert_eq!(a.len(), b.len());
    for (la, lb) in a.iter().zip(b) {
        let (ia, ib) = (
            la["cocontraction_index"].as_f64().unwrap(),
            lb["cocontraction_index"].as_f64().unwrap(),
        );
        assert!((ia - ib).abs() <= 1e-9, "index {ia} vs {ib}");
        let (ka, kb) = (&la["stiffness"], &lb["stiffness"]);
        for (ra, rb) in ka.as_array().unwrap().iter().zip(kb.as_array().unwrap()) {
            for (x, y) in ra.as_array().unwrap().iter().zip(rb.as_array().unwrap()) {
                let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
                assert!(
                    (x - y).abs() <= 1e-6 * x.abs().max(1.0),
                    "stiffness {x} vs {y}"
                );
            }
        }
    }
}

#[test]
fn a_study_manifest_reads_its_lab_files_through_its_map() {
    let ex = examples("cocontraction");
    let d = tempfile::tempdir().unwrap();
    let rec = limpid_io::read_recording(ex.join("ex_config4.csv")).unwrap();
    let mvc = limpid_io::read_recording(ex.join("ex_config4.mvc.csv")).unwrap();
    write(&d.path().join("s1.xdf"), &rig_streams(&rec)).unwrap();
    let emg_only: Vec<XdfStream> = rig_streams(&mvc)
        .into_iter()
        .filter(|s| s.name == "emg")
        .collect();
    write(&d.path().join("s1_mvc.xdf"), &emg_only).unwrap();
    let mut map = String::from("[time]\nstream = \"robot\"\n[columns]\ntrial = { marker = \"start\" }\nlevel = { marker_prefix = \"level \" }\n");
    for c in ["x", "y", "z", "fx", "fy", "fz"] {
        map += &format!("{c} = \"EE.{c}\"\n");
    }
    for n in rec.names().iter().filter(|n| n.starts_with("emg_")) {
        map += &format!("{n} = {{ channel = \"{}\", stream = \"emg\" }}\n", &n[4..]);
    }
    std::fs::write(d.path().join("rig.toml"), map).unwrap();
    let entry = |file: &str, mvc: &str| {
        format!("[[recording]]\nsubject = \"1\"\nconfiguration = \"4\"\nfile = \"{file}\"\nmvc = \"{mvc}\"\n")
    };
    let lab = d.path().join("lab.toml");
    std::fs::write(
        &lab,
        format!(
            "[study]\nname = \"lab\"\nmap = \"rig.toml\"\n\n{}",
            entry("s1.xdf", "s1_mvc.xdf")
        ),
    )
    .unwrap();
    let csv = d.path().join("csv.toml");
    let (a, b) = (ex.join("ex_config4.csv"), ex.join("ex_config4.mvc.csv"));
    std::fs::write(
        &csv,
        format!(
            "[study]\nname = \"csv\"\n\n{}",
            entry(a.to_str().unwrap(), b.to_str().unwrap())
        ),
    )
    .unwrap();
    let run = |manifest: &std::path::Path, out: &str| {
        let o = limpid(&[
            "study",
            "run",
            manifest.to_str().unwrap(),
            "--out",
            d.path().join(out).to_str().unwrap(),
        ]);
        assert_eq!(o.code, 0, "{}", o.stderr);
        assert!(
            o.stdout.contains("1 of 1 recordings processed"),
            "{}",
            o.stdout
        );
        std::fs::read_to_string(d.path().join(out).join("tables.csv")).unwrap()
    };
    let (from_lab, from_csv) = (run(&lab, "lab"), run(&csv, "csv"));
    for (l, c) in from_lab.lines().zip(from_csv.lines()).skip(1) {
        let nums = |s: &str| {
            s.split(',')
                .skip(2)
                .filter_map(|v| v.parse::<f64>().ok())
                .collect::<Vec<_>>()
        };
        for (x, y) in nums(l).iter().zip(nums(c)) {
            assert!((x - y).abs() <= 1e-6 * y.abs().max(1.0), "{l}\n{c}");
        }
    }
    // a manifest whose map has a mistake is refused before any recording is read
    std::fs::write(
        d.path().join("rig.toml"),
        "[columns]\nx = { channel = \"a\", unit = \"parsec\" }\n",
    )
    .unwrap();
    let o = limpid(&[
        "study",
        "run",
        lab.to_str().unwrap(),
        "--out",
        d.path().join("bad").to_str().unwrap(),
    ]);
    assert_eq!(o.code, 2);
    assert!(
        o.stderr.contains("rig.toml") && o.stderr.contains("parsec"),
        "{}",
        o.stderr
    );
}
