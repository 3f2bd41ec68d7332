//! MATLAB MAT-files (issue 2's optional reader): the fixtures are made from
//! `small.csv` by `fixtures/make_mat.py` (scipy.io.savemat), so every column
//! must come back bit for bit as the CSV has it.

use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

#[test]
fn level5_and_compressed_v7_files_read_as_their_csv() {
    let csv = limpid_io::read_recording(fixture("small.csv")).unwrap();
    for name in ["small_v5.mat", "small_v7.mat"] {
        let mat = limpid_io::read_recording(fixture(name)).unwrap();
        // scalars (fs), matrices (note) and strings (subject) are skipped
        let names: Vec<&str> = mat.columns().map(|(n, _)| n).collect();
        assert_eq!(
            names,
            ["t", "x", "y", "z", "fx", "fy", "fz", "trial"],
            "{name}"
        );
        for (column, values) in csv.columns() {
            assert_eq!(mat.column(column).unwrap(), values, "{name}: {column}");
        }
        assert_eq!(mat.sample_rate(), csv.sample_rate());
    }
}

#[test]
fn mat_files_that_cannot_be_a_recording_are_refused_in_one_line() {
    let message = |name: &str| {
        let e = limpid_io::read_recording(fixture(name))
            .unwrap_err()
            .to_string();
        assert_eq!(e.lines().count(), 1, "{e}");
        assert!(e.contains(name), "{e}");
        e
    };
    assert!(message("complex.mat").contains("variable fx: complex values"));
    let e = message("nothing.mat");
    assert!(
        e.contains("no numeric vector variable") && e.contains("note (3 x 3)"),
        "{e}"
    );
    // a CSV saved under a .mat name, and a v7.3 (HDF5) header
    let dir = tempfile::tempdir().unwrap();
    let fake = dir.path().join("fake.mat");
    std::fs::copy(fixture("small.csv"), &fake).unwrap();
    let e = limpid_io::read_recording(&fake).unwrap_err().to_string();
    assert!(
        e.contains("fake.mat") && e.contains("not a MAT-file"),
        "{e}"
    );
    let hdf5 = dir.path().join("v73.mat");
    let mut bytes = b"MATLAB 7.3 MAT-file, Platform: GLNXA64".to_vec();
    bytes.resize(512, b' ');
    std::fs::write(&hdf5, bytes).unwrap();
    let e = limpid_io::read_recording(&hdf5).unwrap_err().to_string();
    // a v7.3 header without its HDF5 part: read since issue 40, refused as corrupt
    assert!(e.contains("v7.3") && e.contains("HDF5"), "{e}");
    // a truncated file
    let cut = dir.path().join("cut.mat");
    let whole = std::fs::read(fixture("small_v7.mat")).unwrap();
    std::fs::write(&cut, &whole[..whole.len() / 2]).unwrap();
    match limpid_io::read_recording(&cut) {
        Ok(rec) => panic!("a truncated file read as {} columns", rec.columns().count()),
        Err(e) => assert!(
            e.to_string().contains("cut.mat") && e.to_string().contains("truncated"),
            "{e}"
        ),
    }
    // writing .mat is refused rather than writing CSV under that name
    let rec = limpid_io::read_recording(fixture("small.csv")).unwrap();
    let e = limpid_io::write_recording(&rec, dir.path().join("out.mat"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("does not write"), "{e}");
}

#[test]
fn cut_or_damaged_mat_files_give_errors_not_panics() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("damaged.mat");
    for name in ["small_v5.mat", "small_v7.mat"] {
        let whole = std::fs::read(fixture(name)).unwrap();
        for cut in [60, 130, 1000, whole.len() / 3, whole.len() - 1] {
            std::fs::write(&path, &whole[..cut]).unwrap();
            let e = limpid_io::read_recording(&path)
                .err()
                .unwrap_or_else(|| panic!("{name} cut at {cut} bytes was read"));
            assert!(e.to_string().contains("damaged.mat"), "{e}");
        }
        // single damaged bytes anywhere after the header: an error or a table
        // that passed every check, never a panic
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        for _ in 0..300 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let mut bytes = whole.clone();
            let at = 128 + (state as usize % (whole.len() - 128));
            bytes[at] ^= (state >> 32) as u8 | 1;
            std::fs::write(&path, &bytes).unwrap();
            let _ = limpid_io::read_recording(&path);
        }
    }
}

/// REKLAB's `stiffnessID/experimental_data.mat` (reklab/reklab_public,
/// GPL-2.0, kept out of this repository): five `nldat` objects saved by
/// MATLAB, read through the MCOS subsystem. Each converts to the samples of
/// the CSV in `$LIMPID_REAL_DATA/reklab_ankle` to its 8 printed digits
/// (`tau1` is the negative of `dataSet(:,2)`). Set `LIMPID_REKLAB_MAT` to
/// the file's path to run it.
#[test]
fn reklab_nldat_objects_convert_to_the_real_ankle_csvs() {
    let (Some(mat), Some(real)) = (
        std::env::var_os("LIMPID_REKLAB_MAT"),
        std::env::var_os("LIMPID_REAL_DATA"),
    ) else {
        eprintln!("skipped: LIMPID_REKLAB_MAT or LIMPID_REAL_DATA is not set");
        return;
    };
    let mat = std::path::PathBuf::from(mat);
    let source = limpid_io::sources::read_source(&mat).unwrap();
    let notes = source.notes.join("\n");
    assert!(
        notes.contains("z_df: a nldat object; properties"),
        "{notes}"
    );
    for name in ["df", "df2", "df3", "pf", "pf2"] {
        let map = limpid_io::map::ChannelMap::parse(&format!(
            "[time]\nincrement = \"z_{name}.domainIncr\"\n[columns]\nq1 = \"z_{name}.dataSet(:,1)\"\ntau1 = {{ channel = \"z_{name}.dataSet(:,2)\", scale = -1.0 }}\n"
        ))
        .unwrap();
        let got = limpid_io::read_recording_mapped(&mat, Some(&map)).unwrap();
        let want = limpid_io::read_recording(
            std::path::Path::new(&real).join(format!("reklab_ankle/{name}.csv")),
        )
        .unwrap();
        assert_eq!(got.len(), want.len(), "{name}: samples");
        for column in ["t", "q1", "tau1"] {
            let (g, w) = (got.column(column).unwrap(), want.column(column).unwrap());
            for (i, (a, b)) in g.iter().zip(w).enumerate() {
                // 8 significant digits printed (t to 4 decimals)
                let tolerance = if column == "t" {
                    5.1e-5
                } else {
                    5.1e-8 * b.abs().max(1e-3)
                };
                assert!(
                    (a - b).abs() <= tolerance,
                    "{name} {column}[{i}]: {a} vs {b}"
                );
            }
        }
    }
}

mod objects {
    //! MATLAB objects (issue 62): classdef objects, tables and timetables in
    //! level-5 files written by mat-io (`fixtures/formats/make_mcos.py`).

    use limpid_io::map::ChannelMap;
    use limpid_io::sources::read_source;
    use std::path::{Path, PathBuf};

    fn fixture(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures/formats")
            .join(name)
    }

    fn channel<'a>(source: &'a limpid_io::sources::Source, name: &str) -> &'a [f64] {
        &source.streams[0]
            .channels
            .iter()
            .find(|c| c.name == name)
            .unwrap_or_else(|| panic!("no channel {name}"))
            .values
    }

    #[test]
    fn a_classdef_object_reads_its_properties_matrix_columns_and_nested_objects() {
        let source = read_source(&fixture("obj_v7.mat")).unwrap();
        for k in [0, 57, 199] {
            let t = k as f64 / 500.0;
            let x = 0.1 * (2.0 * std::f64::consts::PI * 2.0 * t).sin();
            let f = 5.0 * (2.0 * std::f64::consts::PI * 2.0 * t).cos();
            assert!((channel(&source, "z.dataSet(:,1)")[k] - x).abs() < 1e-15);
            assert!((channel(&source, "z.dataSet(:,2)")[k] - f).abs() < 1e-14);
        }
        assert_eq!(
            source.scalars,
            [
                ("z.domainIncr".to_string(), 0.002),
                ("z.calibration.gain".to_string(), 2.5),
                ("fs".to_string(), 500.0)
            ]
        );
        let notes = source.notes.join("\n");
        assert!(
            notes.contains("MATLAB object z: a nldatlike object; properties dataSet (200 x 2, double), domainIncr = 0.002, chanNames = {'pos', 'tq'}, calibration (lab.Calibration object)"),
            "{notes}"
        );
        assert!(
            notes.contains(
                "z.calibration: a lab.Calibration object; properties gain = 2.5, label = 'sensor'"
            ),
            "{notes}"
        );
        // the time from the object's increment
        let map = ChannelMap::parse(
            "[time]\nincrement = \"z.domainIncr\"\n[columns]\nq1 = \"z.dataSet(:,1)\"\ntau1 = { channel = \"z.dataSet(:,2)\", scale = -1.0 }\n",
        )
        .unwrap();
        let rec = limpid_io::read_recording_mapped(fixture("obj_v7.mat"), Some(&map)).unwrap();
        assert!((rec.sample_rate() - 500.0).abs() < 1e-9);
        assert_eq!(rec.column("tau1").unwrap()[0], -5.0);
        // a map naming the object, or a missing scalar, is told what there is
        let map =
            ChannelMap::parse("[time]\nincrement = \"z.domainIncr\"\n[columns]\nq1 = \"z\"\n")
                .unwrap();
        let e = limpid_io::read_recording_mapped(fixture("obj_v7.mat"), Some(&map))
            .unwrap_err()
            .to_string();
        assert!(e.contains("z: a nldatlike object"), "{e}");
        let map = ChannelMap::parse(
            "[time]\nincrement = \"z.domainInc\"\n[columns]\nq1 = \"z.dataSet(:,1)\"\n",
        )
        .unwrap();
        let e = limpid_io::read_recording_mapped(fixture("obj_v7.mat"), Some(&map))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no scalar \"z.domainInc\"") && e.contains("z.domainIncr"),
            "{e}"
        );
    }

    #[test]
    fn the_same_object_in_a_v73_file_reads_the_same() {
        // mat-io writes -v7.3 with a v5 header text before the HDF5 part: found by the HDF5 signature
        let seed =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/seeds/rig-mcos73.mat");
        let v73 = read_source(&seed).unwrap();
        let v7 = read_source(&fixture("obj_v7.mat")).unwrap();
        assert_eq!(v73.format, "MAT v7.3");
        for name in ["z.dataSet(:,1)", "z.dataSet(:,2)"] {
            assert_eq!(channel(&v73, name), channel(&v7, name));
        }
        assert!(v73
            .notes
            .join("\n")
            .contains("z.calibration: a lab.Calibration object; properties gain = 2.5"));
    }

    #[test]
    fn tables_and_timetables_convert_to_their_variables_values() {
        let table = read_source(&fixture("table_v7.mat")).unwrap();
        assert_eq!(
            channel(&table, "T.Angle"),
            [0.0, 0.1, 0.2, 0.30000000000000004, 0.4]
        );
        assert_eq!(channel(&table, "T.Torque"), [0.0, 2.0, 4.0, 6.0, 8.0]);
        for file in ["tt_dur.mat", "tt_dt.mat"] {
            let tt = read_source(&fixture(file)).unwrap();
            let time = channel(&tt, "TT.Time");
            // mat-io stores a datetime's milliseconds without their fraction
            // (MATLAB keeps it in the imaginary part): 0.24 us resolution in 2024
            for (k, t) in time.iter().enumerate() {
                assert!((t - k as f64 * 0.002).abs() < 3e-7, "{file}: {time:?}");
            }
            assert_eq!(channel(&tt, "TT.Torque")[5], 10.0);
            let map = ChannelMap::parse(
                "[columns]\nt = \"TT.Time\"\nq1 = \"TT.Angle\"\ntau1 = \"TT.Torque\"\n",
            )
            .unwrap();
            let rec = limpid_io::read_recording_mapped(fixture(file), Some(&map)).unwrap();
            assert!((rec.sample_rate() - 500.0).abs() < 1e-6, "{file}");
        }
    }

    fn matlab(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures/matlab")
            .join(name)
    }

    /// Files MATLAB wrote (mat-io's test data), with mat-io's expected values.
    #[test]
    fn matlab_written_objects_tables_and_timetables_read_as_mat_io_reads_them() {
        let tables = read_source(&matlab("test_tables_v7.mat")).unwrap();
        assert_eq!(channel(&tables, "table_numeric.Var1"), [1.1, 2.2, 3.3]);
        assert_eq!(channel(&tables, "table_numeric.Var2"), [4.4, 5.5, 6.6]);
        assert_eq!(channel(&tables, "table_var_names.X"), [10.0, 20.0, 30.0]);
        for version in ["v7", "v73"] {
            // MATLAB 2026b's timetable (version 8): datetimes 2023-01-01 .. 03
            let tt = read_source(&matlab(&format!("test_timetablev8_{version}.mat"))).unwrap();
            assert_eq!(channel(&tt, "timetable_v8.Time"), [0.0, 86400.0, 172800.0]);
            assert_eq!(channel(&tt, "timetable_v8.data1"), [1.0, 2.0, 3.0]);
            // its objects hold no vector: listed all the same
            let objects =
                read_source(&matlab(&format!("test_user_defined_{version}.mat"))).unwrap();
            assert!(objects.streams[0].channels.is_empty());
            let notes = objects.notes.join("\n");
            for expected in [
                "obj_with_vals: a TestClasses.BasicClass object; properties a = 10",
                "obj_with_nested_props.a: a TestClasses.BasicClass object; properties a = 1, b = 'Obj1'",
                "obj_with_nested_props.c.InnerProp: a TestClasses.BasicClass object; properties a = 2, b = 'Obj2'",
                "obj_with_default_val: a TestClasses.DefaultClass object; properties a = 'Default String', b = 10",
            ] {
                assert!(notes.contains(expected), "{version}: {expected}\n{notes}");
            }
        }
        // a categorical variable: its codes, and its categories named
        let cat = read_source(&matlab("test_table_categorical_v7.mat")).unwrap();
        assert_eq!(channel(&cat, "table_categorical.Value"), [1.0, 2.0, 3.0]);
        assert!(cat
            .notes
            .join("\n")
            .contains("categoryNames = {'high', 'low'}"));
    }

    /// Issue 76: timetables made with `SampleRate` or `TimeStep` store no
    /// row times (mat-io's test data, saved by MATLAB): they are made from
    /// the origin and the rate or step (calendar months from the origin's
    /// date); a name over 63 characters is read whole from varNames2048.
    #[test]
    fn timetables_without_stored_row_times_get_them_from_their_rate_or_step() {
        for version in ["v7", "v73"] {
            let source =
                read_source(&matlab(&format!("test_timetable_steps_{version}.mat"))).unwrap();
            let time = |name: &str| -> Vec<f64> {
                source
                    .streams
                    .iter()
                    .flat_map(|s| &s.channels)
                    .find(|c| c.name == format!("{name}.Time"))
                    .unwrap_or_else(|| panic!("{version}: no {name}.Time"))
                    .values
                    .clone()
            };
            let close = |a: &[f64], b: &[f64]| {
                a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6)
            };
            let year = 365.2425 * 86_400.0;
            for (name, expected) in [
                ("timetable_step_millis", vec![0.0, 0.01, 0.02]),
                ("timetable_step_start_offset", vec![0.0, 1.0, 2.0]),
                ("timetable_step_years", vec![0.0, year, 2.0 * year]),
                ("timetable_step_caldays", vec![0.0, 86_400.0, 172_800.0]),
                // 2020-01-15, 02-15 (31 days later), 03-15 (29 more: a leap year)
                (
                    "timetable_step_calmonths",
                    vec![0.0, 31.0 * 86_400.0, 60.0 * 86_400.0],
                ),
            ] {
                let t = time(name);
                assert!(close(&t, &expected), "{version} {name}: {t:?}");
            }
            // the 4-row timetable at 3 Hz is not of the file's one length:
            // listed with its made row times
            let notes = source.notes.join("\n");
            assert!(
                notes.contains(
                    "timetable_sample_rate: a timetable object; properties Time (4 x 1, double)"
                ),
                "{version}: {notes}"
            );
            // a map naming the synthesised time converts
            let map = ChannelMap::parse(
                "[columns]\nt = \"timetable_step_millis.Time\"\nq1 = \"timetable_step_millis.data1\"\n",
            )
            .unwrap();
            let rec = limpid_io::read_recording_mapped(
                matlab(&format!("test_timetable_steps_{version}.mat")),
                Some(&map),
            )
            .unwrap();
            assert!((rec.sample_rate() - 100.0).abs() < 1e-6, "{version}");
            let long = read_source(&matlab(&format!("test_timetablev8_{version}.mat"))).unwrap();
            let name = format!("timetable_v8_long_varname.{}", "A".repeat(100));
            assert_eq!(channel_anywhere(&long, &name), [1.0, 2.0, 3.0], "{version}");
        }
    }

    fn channel_anywhere<'a>(source: &'a limpid_io::sources::Source, name: &str) -> &'a [f64] {
        &source
            .streams
            .iter()
            .flat_map(|s| &s.channels)
            .find(|c| c.name == name)
            .unwrap_or_else(|| panic!("no channel {name}"))
            .values
    }

    #[test]
    fn a_timetables_text_variables_are_marker_streams_at_its_row_times() {
        let source = read_source(&fixture("tt_events.mat")).unwrap();
        let markers = |name: &str| -> Vec<(f64, String)> {
            source
                .streams
                .iter()
                .find(|s| s.name == name)
                .unwrap_or_else(|| panic!("no stream {name}"))
                .markers
                .iter()
                .map(|m| (m.time, m.text.clone()))
                .collect()
        };
        let close = |a: &[(f64, String)], b: &[(f64, &str)]| {
            a.len() == b.len()
                && a.iter()
                    .zip(b)
                    .all(|(x, y)| (x.0 - y.0).abs() < 1e-9 && x.1 == y.1)
        };
        let events = markers("TT.Event");
        assert!(
            close(&events, &[(0.0, "start"), (0.006, "start")]),
            "{events:?}"
        );
        let levels = markers("TT.Level");
        assert!(
            close(
                &levels,
                &[
                    (0.0, "low"),
                    (0.002, "low"),
                    (0.004, "low"),
                    (0.006, "high"),
                    (0.008, "high"),
                    (0.01, "high")
                ]
            ),
            "{levels:?}"
        );
        // a marker rule numbers the trials; the numeric stream sets the time
        let map = ChannelMap::parse(
            "[columns]\nt = \"TT.Time\"\nq1 = \"TT.Angle\"\ntau1 = \"TT.Torque\"\ntrial = { marker = \"start\" }\n",
        )
        .unwrap();
        let rec = limpid_io::read_recording_mapped(fixture("tt_events.mat"), Some(&map)).unwrap();
        assert_eq!(rec.column("trial").unwrap(), [1.0, 1.0, 1.0, 2.0, 2.0, 2.0]);
    }

    #[test]
    fn corrupt_object_data_ends_in_a_note_or_a_one_line_error() {
        // the fuzzer's uncompressed copy: every third byte flipped in turn
        let seed = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/seeds/rig-mcos.mat");
        let bytes = std::fs::read(seed).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("flip.mat");
        let mut refused = 0;
        for at in (128..bytes.len()).step_by(3) {
            let mut b = bytes.clone();
            b[at] ^= 0x5a;
            std::fs::write(&path, &b).unwrap();
            if let Err(e) = read_source(&path) {
                refused += 1;
                let e = e.to_string();
                assert_eq!(e.lines().count(), 1, "byte {at}: {e}");
            }
        }
        assert!(refused > 0);
    }
}
