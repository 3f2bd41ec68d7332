//! Lab files written by other programs (issue 40): each fixture under
//! `tests/fixtures/formats` is made by its `make_*.py` (written from the
//! format's specification or by the format's own Python library), which
//! also writes `<file>.expected.json`: the FORMAT.md columns the fixture's
//! channel map must give, computed with numpy. Every value is checked.

use std::path::{Path, PathBuf};

use limpid_io::map::ChannelMap;

pub(crate) fn fixture(name: &str) -> PathBuf {
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
    assert_matches_expected(file, map, file)
}

/// `file` through `map` gives the columns of `{stem}.expected.json` to 1e-9
/// of each column's largest value (several fixtures may share one).
pub(crate) fn assert_matches_expected(file: &str, map: &str, stem: &str) -> limpid_core::Recording {
    let map = ChannelMap::read(&fixture(map)).unwrap();
    let rec = limpid_io::read_recording_mapped(fixture(file), Some(&map)).unwrap();
    for (column, want) in expected(stem) {
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

/// Every cut of `file` (every `step` bytes) is refused or read, never a panic,
/// and refusals are one line naming the file.
fn survives_cuts(file: &str, step: usize) {
    let whole = std::fs::read(fixture(file)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(file);
    for cut in (0..whole.len()).step_by(step) {
        std::fs::write(&path, &whole[..cut]).unwrap();
        if let Err(e) = limpid_io::sources::read_source(&path) {
            let e = e.to_string();
            assert_eq!(e.lines().count(), 1, "{file} cut at {cut}: {e}");
            assert!(e.contains(file), "{file} cut at {cut}: {e}");
        }
    }
}

#[test]
fn truncated_lab_files_are_refused_in_one_line() {
    survives_cuts("rig.xdf", 37);
    survives_cuts("rig.c3d", 61);
    survives_cuts("rig.tdms", 29);
    survives_cuts("rig73.mat", 211);
    survives_cuts("rig_v5struct.mat", 53);
}

fn patched(file: &str, at: usize, bytes: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let mut whole = std::fs::read(fixture(file)).unwrap();
    whole[at..at + bytes.len()].copy_from_slice(bytes);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(file);
    std::fs::write(&path, whole).unwrap();
    (dir, path)
}

#[test]
fn declared_sizes_beyond_the_file_are_refused_without_allocating_them() {
    // XDF: the first chunk (the file header) claims 2^60 bytes
    let (_d, p) = patched("rig.xdf", 4, &[8]);
    let mut bytes = std::fs::read(&p).unwrap();
    bytes.splice(5..6, (1u64 << 60).to_le_bytes());
    std::fs::write(&p, &bytes).unwrap();
    let e = limpid_io::sources::read_source(&p).unwrap_err().to_string();
    assert!(
        e.contains("byte 4") && e.contains("left in the file"),
        "{e}"
    );
    // TDMS: the first segment declares 2^31 objects
    let (_d, p) = patched("rig.tdms", 28, &0x8000_0000u32.to_le_bytes());
    let e = limpid_io::sources::read_source(&p).unwrap_err().to_string();
    assert!(e.contains("objects declared"), "{e}");
    // C3D: the header claims 65535 frames (last_frame, word 5) of data that is not there
    let (_d, p) = patched("rig.c3d", 8, &[0xff, 0xff]);
    match limpid_io::sources::read_source(&p) {
        Ok(s) => assert!(
            s.streams[0].len() <= 50,
            "{} frames read",
            s.streams[0].len()
        ),
        Err(e) => assert_eq!(e.to_string().lines().count(), 1, "{e}"),
    }
}

#[test]
fn a_c3d_file_declaring_frames_of_nothing_is_refused_before_the_decoder() {
    // POINT:USED and ANALOG:USED set to 0 and the header's analog samples
    // per frame too: its frames hold no byte
    let mut whole = std::fs::read(fixture("rig.c3d")).unwrap();
    whole[2..4].copy_from_slice(&[0, 0]);
    whole[4..6].copy_from_slice(&[0, 0]);
    let found: Vec<usize> = whole
        .windows(4)
        .enumerate()
        .filter(|(i, w)| {
            *w == b"USED" && (whole[i - 2] as i8).unsigned_abs() == 4 && whole[i + 6] == 2
        })
        .map(|(i, _)| i)
        .collect();
    assert!(found.len() >= 2, "POINT:USED and ANALOG:USED");
    for i in found {
        // name (its length negative when locked), 2-byte offset to the next record, type 2, 0 dimensions, the value
        assert_eq!(whole[i + 6], 2);
        whole[i + 8..i + 10].copy_from_slice(&[0, 0]);
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nothing.c3d");
    std::fs::write(&path, whole).unwrap();
    let e = limpid_io::sources::read_source(&path)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("nothing.c3d") && e.contains("no point and no analog channel"),
        "{e}"
    );
    assert_eq!(e.lines().count(), 1);
}

#[test]
fn an_hdf5_group_that_links_to_itself_is_read_once() {
    let source = limpid_io::sources::read_source(&fixture("cyclic.mat")).unwrap();
    let names: Vec<&str> = source.streams[0]
        .channels
        .iter()
        .map(|c| c.name.as_str())
        .collect();
    assert_eq!(names, ["rec.x"]);
}

/// An XDF file of one unlabelled double64 channel (read as `ch1`) in stream "robot" with these stamps.
fn xdf_with_stamps(stamps: &[f64]) -> Vec<u8> {
    fn chunk(out: &mut Vec<u8>, tag: u16, content: &[u8]) {
        out.push(4);
        out.extend_from_slice(&((content.len() + 2) as u32).to_le_bytes());
        out.extend_from_slice(&tag.to_le_bytes());
        out.extend_from_slice(content);
    }
    let mut out = b"XDF:".to_vec();
    let xml = "<info><name>robot</name><channel_count>1</channel_count><nominal_srate>100</nominal_srate><channel_format>double64</channel_format></info>";
    chunk(
        &mut out,
        2,
        &[&1u32.to_le_bytes()[..], xml.as_bytes()].concat(),
    );
    let mut samples = 1u32.to_le_bytes().to_vec();
    samples.extend_from_slice(&[4]);
    samples.extend_from_slice(&(stamps.len() as u32).to_le_bytes());
    for (i, t) in stamps.iter().enumerate() {
        samples.push(8);
        samples.extend_from_slice(&t.to_le_bytes());
        samples.extend_from_slice(&(i as f64).to_le_bytes());
    }
    chunk(&mut out, 3, &samples);
    out
}

#[test]
fn an_xdf_clock_reset_is_reported_by_stream_sample_and_time_and_the_longest_stretch_read() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("back.xdf");
    std::fs::write(&path, xdf_with_stamps(&[1.0, 1.01, 1.02, 1.015, 1.03])).unwrap();
    let source = limpid_io::sources::read_source(&path).unwrap();
    let notes = source.notes.join("\n");
    assert!(
        notes.contains("stream \"robot\": the clock jumps back 1 time(s)")
            && notes.contains("at sample 4 back by 0.005 s (from 1.02 s to 1.015 s)")
            && notes.contains("samples 1 to 3"),
        "{notes}"
    );
    assert_eq!(source.streams[0].channels[0].values, [0.0, 1.0, 2.0]);
    // a clock that stands still is refused, naming stream and sample
    std::fs::write(&path, xdf_with_stamps(&[1.0, 1.01, 1.01, 1.03])).unwrap();
    let e = limpid_io::sources::read_source(&path)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("back.xdf")
            && e.contains("stream \"robot\", sample 3")
            && e.contains("stands still"),
        "{e}"
    );
    // a drop-out in the time base is named too, not interpolated over
    std::fs::write(&path, xdf_with_stamps(&[1.0, 1.01, 1.02, 1.08, 1.09])).unwrap();
    let map = ChannelMap::parse("[columns]\nx = \"ch1\"").unwrap();
    let e = limpid_io::read_recording_mapped(&path, Some(&map))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("stream \"robot\", sample 4") && e.contains("dropped samples"),
        "{e}"
    );
}

#[test]
fn an_xdf_file_cut_off_is_read_to_its_last_whole_chunk() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.xdf");
    // header and a samples chunk of two, then a second samples chunk cut short
    let header_end = xdf_with_stamps(&[]).len() - 16;
    let mut bytes = xdf_with_stamps(&[1.0, 1.01]);
    let second = xdf_with_stamps(&[1.02, 1.03]);
    bytes.extend_from_slice(&second[header_end..second.len() - 3]);
    std::fs::write(&path, &bytes).unwrap();
    let source = limpid_io::sources::read_source(&path).unwrap();
    let notes = source.notes.join("\n");
    let at = xdf_with_stamps(&[1.0, 1.01]).len();
    assert!(
        notes.contains(&format!("the file ends inside the chunk at byte {at}")),
        "{notes}"
    );
    assert_eq!(source.streams[0].len(), 2);
    // cut inside the length field of the next chunk
    std::fs::write(&path, &bytes[..at + 2]).unwrap();
    let source = limpid_io::sources::read_source(&path).unwrap();
    assert!(source.notes.join(" ").contains("ends inside the chunk"));
    // before any stream header: nothing to read, one line
    std::fs::write(&path, &bytes[..10]).unwrap();
    let e = limpid_io::sources::read_source(&path)
        .unwrap_err()
        .to_string();
    assert_eq!(e.lines().count(), 1, "{e}");
}

#[test]
fn xdf_streams_without_clock_offsets_are_named_in_a_warning() {
    let source = limpid_io::sources::read_source(&fixture("rig.xdf")).unwrap();
    let notes = source.notes.join("\n");
    // rig.xdf: the EMG stream has ClockOffset records, the robot and marker streams none
    assert!(
        notes.contains(
            "no clock offsets for stream(s) \"robot\", \"markers\": used on their own clock"
        ),
        "{notes}"
    );
}

#[test]
fn a_file_beside_the_main_one_takes_the_same_map_without_the_columns_it_lacks() {
    // an MVC recording made by the same rig records only EMG: the session's
    // map applies, its robot columns and marker rules are left out, and the
    // EMG stream sets the time
    let map = ChannelMap::read(&fixture("rig_xdf.toml")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mvc.xdf");
    std::fs::write(&path, xdf_with_stamps(&[1.0, 1.01, 1.02, 1.03, 1.04])).unwrap();
    // this file's only stream is called robot and its channel ch1: nothing of the map
    let e = limpid_io::read_supporting_recording(&path, Some(&map))
        .unwrap_err()
        .to_string();
    assert!(e.contains("none of the channel map's channels"), "{e}");
    let partial = ChannelMap::parse(
        "[time]\nstream = \"robot\"\n[columns]\nx = { channel = \"EndEff.X\", stream = \"arm\" }\nemg_biceps = \"ch1\"\ntrial = { marker = \"go\" }",
    )
    .unwrap();
    let rec = limpid_io::read_supporting_recording(&path, Some(&partial)).unwrap();
    assert_eq!(rec.names(), ["t", "emg_biceps"]);
    let warnings = rec.warnings().join(" ");
    assert!(warnings.contains("left out: trial, x"), "{warnings}");
    // the main recording keeps the strict reading
    assert!(limpid_io::read_recording_mapped(&path, Some(&partial)).is_err());
}

#[test]
fn a_mat_v73_file_converts_by_dotted_struct_paths() {
    let rec = assert_matches("rig73.mat", "rig_mat73.toml");
    assert!((rec.sample_rate() - 500.0).abs() < 1e-6);
    let source = limpid_io::sources::read_source(&fixture("rig73.mat")).unwrap();
    let names: Vec<&str> = source.streams[0]
        .channels
        .iter()
        .map(|c| c.name.as_str())
        .collect();
    assert_eq!(
        names,
        ["rec.EndEffX", "rec.Time", "rec.TrialNo", "rec.Force.Fx"]
    );
    // what is not a channel is named with its class
    let notes = source.notes.join(" ");
    assert!(
        notes.contains("notes (1 x 2, cell): a cell array"),
        "{notes}"
    );
    assert!(notes.contains("subject (1 x 3, char)"), "{notes}");
    // names that end in their axis are recognised, and the proposal parses
    let proposed = limpid_io::inspect::inspect(&source).proposed_map.unwrap();
    assert!(
        proposed.contains("x = { channel = \"rec.EndEffX\" }"),
        "{proposed}"
    );
    assert!(
        proposed.contains("fx = { channel = \"rec.Force.Fx\" }"),
        "{proposed}"
    );
    ChannelMap::parse(&proposed).unwrap();
    let map = ChannelMap::parse("[time]\nrate = 500\n[columns]\nx = \"rec.EndEfX\"").unwrap();
    let e = limpid_io::read_recording_mapped(fixture("rig73.mat"), Some(&map))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no channel \"rec.EndEfX\"") && e.contains("rec.EndEffX"),
        "{e}"
    );
}

/// The C3D parameter `GROUP:NAME`'s first value's offset in `bytes`
/// (an integer parameter), found by walking the parameter section.
fn c3d_parameter_offset(bytes: &[u8], group: &str, name: &str) -> usize {
    let start = (usize::from(bytes[0]) - 1) * 512 + 4;
    let mut groups = std::collections::HashMap::new();
    let mut at = start;
    let mut wanted = None;
    loop {
        let len = usize::from((bytes[at] as i8).unsigned_abs());
        let id = bytes[at + 1] as i8;
        if len == 0 {
            break;
        }
        let text = std::str::from_utf8(&bytes[at + 2..at + 2 + len])
            .unwrap()
            .to_string();
        let next = usize::from(u16::from_le_bytes([
            bytes[at + 2 + len],
            bytes[at + 3 + len],
        ]));
        if id < 0 {
            groups.insert(-id, text);
        } else if text == name {
            // type byte, dimension count, dimensions, then the data
            let dims = usize::from(bytes[at + 5 + len]);
            wanted
                .get_or_insert_with(Vec::new)
                .push((id, at + 6 + len + dims));
        }
        if next == 0 {
            break;
        }
        at += 2 + len + next;
    }
    wanted
        .unwrap()
        .into_iter()
        .find(|(id, _)| groups.get(id).map(String::as_str) == Some(group))
        .unwrap()
        .1
}

/// Issue 56: sizes a C3D file declares are checked before the decoder
/// allocates from them (ANALOG:USED = 32767 asked for 6.7 GB, analog
/// samples per channel of 65535 for 18.8 GB), and a file cut short is
/// refused instead of read in part.
#[test]
fn c3d_sizes_are_checked_before_anything_is_allocated() {
    let whole = std::fs::read(fixture("rig.c3d")).unwrap();
    let used = c3d_parameter_offset(&whole, "ANALOG", "USED");
    assert_eq!(u16::from_le_bytes([whole[used], whole[used + 1]]), 3);
    let (_d, p) = patched("rig.c3d", used, &32767u16.to_le_bytes());
    let e = limpid_io::sources::read_source(&p).unwrap_err().to_string();
    assert!(
        e.contains("ANALOG:USED (32767)") && e.lines().count() == 1,
        "{e}"
    );
    // the header's analog samples per channel per frame (word 10)
    let (_d, p) = patched("rig.c3d", 18, &65535u16.to_le_bytes());
    let e = limpid_io::sources::read_source(&p).unwrap_err().to_string();
    assert!(e.contains("(65535)") && e.contains("disagrees"), "{e}");
    // POINT:FRAMES far beyond the data
    let frames = c3d_parameter_offset(&whole, "POINT", "FRAMES");
    let (_d, p) = patched("rig.c3d", frames, &60000u16.to_le_bytes());
    let e = limpid_io::sources::read_source(&p).unwrap_err().to_string();
    assert!(e.contains("cut short") && e.contains("60000 frames"), "{e}");
    // cut at half its data: refused, saying how much is there
    let dir = tempfile::tempdir().unwrap();
    let half = dir.path().join("half.c3d");
    let data_start = 512 * (usize::from(u16::from_le_bytes([whole[16], whole[17]])) - 1);
    std::fs::write(&half, &whole[..data_start + (whole.len() - data_start) / 2]).unwrap();
    let e = limpid_io::sources::read_source(&half)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("half.c3d") && e.contains("cut short") && e.contains("declares 50 frames"),
        "{e}"
    );
    // issue 76: the header's point count (word 2), by which the decoder
    // sizes its grid (65535 for 3 asked for 7.9 GB), against POINT:USED
    let (_d, p) = patched("rig.c3d", 2, &65535u16.to_le_bytes());
    let e = limpid_io::sources::read_source(&p).unwrap_err().to_string();
    assert!(
        e.contains("declares 65535 points but POINT:USED is") && e.lines().count() == 1,
        "{e}"
    );
    // and its frame rate (words 11-12) against POINT:RATE
    let (_d, p) = patched("rig.c3d", 20, &89.5f32.to_le_bytes());
    let e = limpid_io::sources::read_source(&p).unwrap_err().to_string();
    assert!(
        e.contains("frame rate 89.5 Hz disagrees with POINT:RATE"),
        "{e}"
    );
    // the file itself reads whole
    assert_eq!(
        limpid_io::sources::read_source(&fixture("rig.c3d"))
            .unwrap()
            .streams
            .len(),
        2
    );
}

/// Issue 56: a map naming a variable that is there but is not a vector is
/// told what it is, not "no channel; nearest ...".
#[test]
fn a_map_naming_a_matrix_is_told_its_shape() {
    let small = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/small_v5.mat");
    let dir = tempfile::tempdir().unwrap();
    let map = dir.path().join("m.toml");
    std::fs::write(&map, "[columns]\nt = \"t\"\nx = \"note\"\nfx = \"fx\"\n").unwrap();
    let map = ChannelMap::read(&map).unwrap();
    let e = limpid_io::read_recording_mapped(&small, Some(&map))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(
            "map column x: note (3 x 2, double): a matrix; its columns are note(:,1) to note(:,2)"
        ),
        "{e}"
    );
    // a column of it names its length
    std::fs::write(
        dir.path().join("c.toml"),
        "[columns]\nt = \"t\"\nx = \"note(:,2)\"\nfx = \"fx\"\n",
    )
    .unwrap();
    let map = ChannelMap::read(&dir.path().join("c.toml")).unwrap();
    let e = limpid_io::read_recording_mapped(&small, Some(&map))
        .unwrap_err()
        .to_string();
    assert!(e.contains("note(:,2) (3 samples, not"), "{e}");
}

/// Issue 56: an empty lab file names its format, not a CSV's header row.
#[test]
fn empty_lab_files_name_their_format() {
    let dir = tempfile::tempdir().unwrap();
    for (name, format) in [
        ("e.xdf", "XDF"),
        ("e.c3d", "C3D"),
        ("e.tdms", "TDMS"),
        ("e.mat", "MAT"),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, b"").unwrap();
        let e = limpid_io::sources::read_source(&p).unwrap_err().to_string();
        assert!(
            e.contains(name)
                && e.contains(&format!("is empty (0 bytes): no {format} content"))
                && !e.contains("header row"),
            "{e}"
        );
    }
}

/// Issue 56: a stream without samples is said to hold none, not to span
/// "-inf to inf".
#[test]
fn a_stream_without_samples_is_named_as_such() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("empty-stream.xdf");
    std::fs::write(&path, xdf_with_stamps(&[])).unwrap();
    let map = dir.path().join("m.toml");
    std::fs::write(
        &map,
        "[columns]\nx = { channel = \"ch1\", stream = \"robot\" }\n",
    )
    .unwrap();
    let map = ChannelMap::read(&map).unwrap();
    let e = match limpid_io::sources::read_source(&path) {
        Err(e) => e.to_string(),
        Ok(source) => match limpid_io::map::apply(&source, &map) {
            Ok(_) => panic!("a stream without samples converted"),
            Err(e) => e.to_string(),
        },
    };
    assert!(
        e.contains("empty-stream.xdf")
            && (e.contains("holds no samples") || e.contains("no sample")),
        "{e}"
    );
    assert!(!e.contains("inf"), "{e}");
}
