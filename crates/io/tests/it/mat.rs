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
