//! `--print-request`, the request in the run block, and `limpid rerun`.

use crate::common::{examples, json, limpid};

#[test]
fn a_result_records_its_request_and_rerun_makes_it_again() {
    let d = tempfile::tempdir().unwrap();
    let rec = examples("stochastic").join("ex_sa3.csv");
    let rec = rec.to_str().unwrap();
    let args = [
        "estimate",
        "stochastic",
        rec,
        "--nfft",
        "2048",
        "--band",
        "1,8",
    ];
    let request: serde_json::Value =
        serde_json::from_str(&limpid(&[&args[..], &["--print-request"]].concat()).stdout).unwrap();
    assert_eq!(request["nperseg"], 2048);
    assert_eq!(request["band_hz"], serde_json::json!([1.0, 8.0]));
    let first = json(&[&args[..], &["--json"]].concat());
    assert_eq!(first["run"]["request"], request);
    let saved = d.path().join("first.json");
    std::fs::write(&saved, first.to_string()).unwrap();
    let again = json(&["rerun", saved.to_str().unwrap(), "--json"]);
    for key in ["stiffness", "damping", "inertia", "frequencies", "criteria"] {
        assert_eq!(again[key], first[key], "{key}");
    }
    assert_eq!(again["run"]["request"], request);
    // the text of a rerun is the original command's text
    let text = limpid(&["rerun", saved.to_str().unwrap()]);
    assert_eq!(text.code, 0, "{}", text.stderr);
    assert!(
        text.stdout.starts_with("limpid estimate stochastic: "),
        "{}",
        text.stdout
    );
}

#[test]
fn rerun_refuses_results_without_a_request_in_one_line() {
    let d = tempfile::tempdir().unwrap();
    let rec = examples("ankle").join("ex_ankle.csv");
    let mut old = json(&["estimate", "reflex", rec.to_str().unwrap(), "--json"]);
    old["run"].as_object_mut().unwrap().remove("request");
    let p = d.path().join("old.json");
    std::fs::write(&p, old.to_string()).unwrap();
    let out = limpid(&["rerun", p.to_str().unwrap()]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert_eq!(out.stderr.lines().count(), 1, "{}", out.stderr);
    assert!(out.stderr.contains("holds no request"), "{}", out.stderr);
    assert!(out.stderr.contains("estimate reflex"), "{}", out.stderr);
    let out = limpid(&["rerun", d.path().join("missing.json").to_str().unwrap()]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("missing.json"), "{}", out.stderr);
}

/// `spectra` records its request too: a rerun gives the same spectra, and
/// its text is the same CSV.
#[test]
fn spectra_reruns_from_its_result() {
    let d = tempfile::tempdir().unwrap();
    let rec = examples("stochastic").join("ex_sa3.csv");
    let args = [
        "spectra",
        rec.to_str().unwrap(),
        "--inputs",
        "ux,uz",
        "--outputs",
        "x",
        "--nfft",
        "1024",
        "--window",
        "hamming",
    ];
    let first = json(&[&args[..], &["--json"]].concat());
    let request = &first["run"]["request"];
    assert_eq!(request["method"], "spectra");
    assert_eq!(request["outputs"], serde_json::json!(["x"]));
    assert_eq!(request["window"], "hamming");
    assert_eq!(first["segment_samples"], 1024);
    let saved = d.path().join("spectra.json");
    std::fs::write(&saved, first.to_string()).unwrap();
    let again = json(&["rerun", saved.to_str().unwrap(), "--json"]);
    for key in ["frequencies", "psd", "coherence", "partial_coherence"] {
        assert_eq!(again[key], first[key], "{key}");
    }
    let text = limpid(&["rerun", saved.to_str().unwrap()]);
    assert_eq!(text.stdout, limpid(&args).stdout);
    assert!(text.stdout.starts_with("frequency_hz,psd_ux,"));
}
