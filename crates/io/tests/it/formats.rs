//! Lab files written by other programs (issue 40): each fixture under
//! `tests/fixtures/formats` is made by its `make_*.py` (written from the
//! format's specification or by the format's own Python library), which
//! also writes `<file>.expected.json`: the FORMAT.md columns the fixture's
//! channel map must give, computed with numpy. Every value is checked.

use std::path::{Path, PathBuf};

use limpid_io::map::ChannelMap;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/formats")
        .join(name)
}

fn expected(name: &str) -> Vec<(String, Vec<f64>)> {
    let text = std::fs::read_to_string(fixture(&format!("{name}.expected.json"))).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v.as_object()
        .unwrap()
        .iter()
        .map(|(k, v)| {
            let vals = v
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            (k.clone(), vals)
        })
        .collect()
}

fn assert_matches(file: &str, map: &str) -> limpid_core::Recording {
    let map = ChannelMap::read(&fixture(map)).unwrap();
    let rec = limpid_io::read_recording_mapped(fixture(file), Some(&map)).unwrap();
    for (column, want) in expected(file) {
        let got = rec
            .column(&column)
            .unwrap_or_else(|| panic!("{file}: no column {column} in {:?}", rec.names()));
        assert_eq!(got.len(), want.len(), "{file}: {column}: samples");
        let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
            assert!(
                (g - w).abs() <= 1e-9 * scale,
                "{file}: {column}[{i}]: {g} != {w}"
            );
        }
    }
    rec
}

#[test]
fn an_xdf_file_converts_to_the_values_written() {
    let rec = assert_matches("rig.xdf", "rig_xdf.toml");
    assert!(
        (rec.sample_rate() - 500.0).abs() < 1e-6,
        "{}",
        rec.sample_rate()
    );
    // the conversion says what it left out
    let warnings = rec.warnings().join("\n");
    assert!(warnings.contains("before the first marker"), "{warnings}");
    assert!(warnings.contains("outside the span"), "{warnings}");
}

#[test]
fn inspect_lists_streams_markers_and_proposes_a_map() {
    let source = limpid_io::sources::read_source(&fixture("rig.xdf")).unwrap();
    let found = limpid_io::inspect::inspect(&source);
    let names: Vec<&str> = found.streams.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["robot", "emg", "markers"]);
    let emg = &found.streams[1];
    assert_eq!(emg.nominal_rate_hz, Some(2000.0));
    assert_eq!(emg.clock_offsets, 2);
    assert!(
        (emg.start_s.unwrap() - 999.95).abs() < 1e-9,
        "{:?}",
        emg.start_s
    );
    assert_eq!(emg.channels[0].unit.as_deref(), Some("mV"));
    let markers = &found.streams[2].markers;
    let starts = markers
        .iter()
        .find(|m| m.text == "perturbation_start")
        .unwrap();
    assert_eq!(starts.count, 2);
    let proposed = found.proposed_map.unwrap();
    assert!(
        proposed.contains("x = { channel = \"EndEff.X\""),
        "{proposed}"
    );
    assert!(
        proposed.contains("fx = { channel = \"Force.Fx\""),
        "{proposed}"
    );
    assert!(proposed.contains("emg_1"), "{proposed}");
    // the proposal parses as a map
    ChannelMap::parse(&proposed).unwrap();
}

fn map_error(file: &str, map: &str) -> String {
    let map = ChannelMap::parse(map).map_err(|e| e.to_string());
    let map = match map {
        Ok(m) => m,
        Err(e) => return e,
    };
    let e = limpid_io::read_recording_mapped(fixture(file), Some(&map))
        .unwrap_err()
        .to_string();
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(e.contains(file), "{e}");
    e
}

#[test]
fn map_mistakes_are_one_line_naming_the_nearest_names() {
    let base = "[time]\nstream = \"robot\"\n[columns]\n";
    let e = map_error(
        "rig.xdf",
        &format!("{base}x = {{ channel = \"EndEff.Z\" }}"),
    );
    assert!(
        e.contains("no channel \"EndEff.Z\"") && e.contains("EndEff.X"),
        "{e}"
    );
    let e = map_error(
        "rig.xdf",
        &format!("{base}x = {{ channel = \"EndEff.X\", stream = \"robt\" }}"),
    );
    assert!(
        e.contains("no stream \"robt\"") && e.contains("robot"),
        "{e}"
    );
    let e = map_error(
        "rig.xdf",
        &format!("{base}trial = {{ marker = \"start\" }}"),
    );
    assert!(e.contains("perturbation_start"), "{e}");
    let e = map_error("rig.xdf", "[columns]\nx = \"EndEff.X\"");
    assert!(e.contains("3 streams"), "{e}");
    let e = map_error(
        "rig.xdf",
        &format!("{base}x = {{ channel = \"EndEff.X\", unit = \"N\" }}"),
    );
    assert!(e.contains("a force") && e.contains("a length"), "{e}");
    let e = map_error(
        "rig.xdf",
        &format!("{base}x = {{ channel = \"EndEff.X\", unit = \"mmm\" }}"),
    );
    assert!(
        e.contains("unknown unit \"mmm\"") && e.contains("mm"),
        "{e}"
    );
    let e = map_error(
        "rig.xdf",
        &format!("{base}x = {{ channel = \"EndEff.X\", scale = nan }}"),
    );
    assert!(e.contains("scale"), "{e}");
    let e = map_error("rig.xdf", &format!("{base}x = {{ chanel = \"EndEff.X\" }}"));
    assert!(e.contains("line 4"), "{e}");
    let e = map_error(
        "rig.xdf",
        "[time]\nstream = \"markers\"\n[columns]\nx = \"EndEff.X\"",
    );
    assert!(e.contains("text markers"), "{e}");
}

#[test]
fn an_xdf_without_a_map_is_refused_with_the_way_to_write_one() {
    let e = limpid_io::read_recording(fixture("rig.xdf"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("limpid inspect") && e.contains("--map"), "{e}");
}

#[test]
fn a_c3d_file_converts_to_the_values_written() {
    let rec = assert_matches("rig.c3d", "rig_c3d.toml");
    assert!((rec.sample_rate() - 1000.0).abs() < 1e-6);
    let source = limpid_io::sources::read_source(&fixture("rig.c3d")).unwrap();
    let points = &source.streams[0];
    assert_eq!(points.name, "points");
    assert_eq!(points.channels[0].unit.as_deref(), Some("mm"));
    // an invalid point (negative residual) is not passed off as the zeros stored there
    let elbow = points
        .channels
        .iter()
        .find(|c| c.name == "Elbow.X")
        .unwrap();
    assert!(
        elbow.values[10].is_nan() && elbow.values[9] == 250.0,
        "{:?}",
        &elbow.values[8..14]
    );
    let map = ChannelMap::parse("[time]\nstream = \"analog\"\n[columns]\nx = \"Elbow.X\"").unwrap();
    let e = limpid_io::read_recording_mapped(fixture("rig.c3d"), Some(&map))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("stream \"points\", channel \"Elbow.X\", sample 11"),
        "{e}"
    );
    // labels lose the blanks the format pads them with
    let analog = &source.streams[1];
    assert_eq!(analog.channels[0].name, "Fx");
}

#[test]
fn a_tdms_file_converts_to_the_values_written() {
    let rec = assert_matches("rig.tdms", "rig_tdms.toml");
    assert!((rec.sample_rate() - 500.0).abs() < 1e-6);
    let source = limpid_io::sources::read_source(&fixture("rig.tdms")).unwrap();
    let names: Vec<&str> = source.streams.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["Robot", "DAQ"]);
    assert_eq!(source.streams[0].channels[0].unit.as_deref(), Some("mm"));
    assert_eq!(source.streams[1].nominal_rate, Some(2000.0));
    // a unit the file declares but limpid does not know is named, with the way out
    let map = ChannelMap::parse("[time]\nstream = \"Robot\"\n[columns]\nq2 = \"Elbow\"").unwrap();
    let e = limpid_io::read_recording_mapped(fixture("rig.tdms"), Some(&map))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("\"cdeg\"") && e.contains("the unit the file declares"),
        "{e}"
    );
}

#[test]
fn a_level5_mat_file_with_a_nested_struct_converts_by_the_same_paths() {
    assert_matches("rig_v5struct.mat", "rig_mat73.toml");
}
