//! Issue 20: CSV output with the shortest round-trip numbers, exponents for tiny and huge values.
use limpid_core::Recording;

#[test]
fn tiny_and_huge_values_are_written_with_exponents_and_read_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("r.csv");
    let t = vec![0.0, 0.002, 0.004];
    let x = vec![1.2895775544584347e-16, 0.1 + 0.2, -7.5e-9];
    let rec = Recording::new(&path, vec!["t".into(), "x".into()], vec![t, x.clone()], 2).unwrap();
    limpid_io::write_recording(&rec, &path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("1.2895775544584347e-16"), "{text}");
    assert!(text.contains("-7.5e-9"), "{text}");
    assert!(!text.contains("0.0000000"), "{text}");
    let back = limpid_io::read_recording(&path).unwrap();
    assert_eq!(back.column("x").unwrap(), x.as_slice());
}
