//! The example writer (`limpid-test-examples DIR`): every family, each case a
//! recording with its truth. Also makes `cargo test` build the writer, which
//! `scripts/test.sh` then runs for the Python tests.

#[test]
fn the_writer_puts_every_family_in_the_folder_it_is_given() {
    let dir = std::env::temp_dir().join(format!("limpid-written-examples-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_limpid-test-examples"))
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for family in limpid_testkit::examples::FAMILIES {
        let cases: Vec<String> = std::fs::read_dir(dir.join(family))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        let recordings = cases
            .iter()
            .filter(|c| c.ends_with(".csv") && !c.ends_with(".mvc.csv"));
        for rec in recordings {
            let truth = rec.replace(".csv", ".truth.json");
            assert!(cases.contains(&truth), "{family}/{rec} has no {truth}");
            // every truth reads through its type and has a stiffness
            let t = limpid_testkit::read_truth(&dir.join(family).join(&truth));
            let k = t
                .stiffness()
                .unwrap_or_else(|| panic!("{family}/{truth}: no stiffness"));
            assert!(k.nrows() > 0, "{family}/{truth}");
            let r = limpid_io::read_recording(dir.join(family).join(rec)).unwrap();
            assert!(r.len() > 1000, "{family}/{rec}: {} samples", r.len());
        }
        assert!(!cases.is_empty(), "{family} is empty");
    }
    // a wrong call is one line and exit 2
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_limpid-test-examples"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).unwrap();
}
