//! `limpid protocol` and `limpid simulate` (issue 3, first part).

mod common;
use common::*;

#[test]
fn preset_checks_simulates_and_estimates_back_to_its_truth() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("p.toml");
    let out = limpid(&[
        "protocol",
        "new",
        "--preset",
        "artemiadis-3d",
        "-o",
        p.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let check = limpid(&["protocol", "check", p.to_str().unwrap()]);
    assert_eq!(check.code, 0, "{}", check.stderr);
    assert!(
        check.stdout.contains("96 trials") && check.stdout.contains("minimum angular separation"),
        "{}",
        check.stdout
    );
    let rec = dir.path().join("rec.parquet");
    let sim = limpid(&[
        "simulate",
        p.to_str().unwrap(),
        "-o",
        rec.to_str().unwrap(),
        "--seed",
        "5",
    ]);
    assert_eq!(sim.code, 0, "{}", sim.stderr);
    for s in 1..=6 {
        let r = dir.path().join(format!("rec_S{s}.parquet"));
        let truth = read_json(&dir.path().join(format!("rec_S{s}.truth.json")));
        let est = json(&["estimate", "linear", r.to_str().unwrap(), "--json"]);
        let ek = rel_err(&mat(&est["stiffness"]), &mat(&truth["stiffness"]));
        assert!(ek < 0.03, "S{s}: stiffness error {ek}");
    }
}

#[test]
fn over_fast_protocol_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("fast.toml");
    let text = limpid(&["protocol", "new", "--preset", "patel-cocontraction"])
        .stdout
        .replace("centre_out_s = 0.1", "centre_out_s = 0.02");
    std::fs::write(&p, text).unwrap();
    let out = limpid(&["protocol", "check", p.to_str().unwrap()]);
    assert_eq!(out.code, 2);
    let line = out.stderr.trim_end();
    assert!(
        line.starts_with(&format!(
            "limpid: {}: invalid protocol: acceleration (m/s^2) ",
            p.display()
        )),
        "{line}"
    );
    assert!(
        line.contains("exceeds the limit 8 at start point 1, target 1"),
        "{line}"
    );
    let unknown = limpid(&["protocol", "new", "--preset", "nope"]);
    assert_eq!(unknown.code, 2);
    assert!(unknown
        .stderr
        .contains("presets: artemiadis-3d, patel-cocontraction"));
}
