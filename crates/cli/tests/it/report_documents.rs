//! Reports of result documents read back: they name their recording, and a
//! document whose arrays disagree is refused on read, naming the field.

use crate::common::*;
use serde_json::Value;

#[test]
fn reports_name_the_recording() {
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("r.html");
    let out = limpid(&[
        "estimate",
        "linear",
        examples("cartesian_slow")
            .join("ex_cubic.csv")
            .to_str()
            .unwrap(),
        "--report",
        page.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(
        html.contains("Linear estimate: ex_cubic.csv"),
        "section not named after the recording"
    );
    assert!(!html.contains("result 1"));
    assert!(
        html.contains("500 Hz") && html.contains("trials"),
        "recording details"
    );
    // how it was made: the file with its size and date, the command, the version
    assert!(html.contains("How this result was made"));
    let bytes = std::fs::metadata(examples("cartesian_slow").join("ex_cubic.csv"))
        .unwrap()
        .len();
    let kib = if bytes >= 1 << 20 {
        format!(
            "{} MiB",
            limpid_core::significant(bytes as f64 / 1048576.0, 4)
        )
    } else {
        format!("{} KiB", limpid_core::significant(bytes as f64 / 1024.0, 4))
    };
    assert!(html.contains(&kib), "size {kib}");
    assert!(html.contains(", modified 20"), "modification date");
    assert!(html.contains("estimate linear") && html.contains("--report"));
    assert!(html.contains(&format!("by limpid {}", env!("CARGO_PKG_VERSION"))));
    // and the JSON document carries it, so `limpid report` shows it too
    let doc = json(&[
        "estimate",
        "linear",
        examples("cartesian_slow")
            .join("ex_cubic.csv")
            .to_str()
            .unwrap(),
        "--json",
    ]);
    assert_eq!(doc["run"]["inputs"][0]["bytes"].as_u64(), Some(bytes));
    assert!(doc["run"]["command_line"]
        .as_str()
        .unwrap()
        .contains("--json"));
    let saved = dir.path().join("r.json");
    std::fs::write(&saved, doc.to_string()).unwrap();
    let again = dir.path().join("again.html");
    assert_eq!(
        limpid(&[
            "report",
            saved.to_str().unwrap(),
            "-o",
            again.to_str().unwrap()
        ])
        .code,
        0
    );
    let html = std::fs::read_to_string(&again).unwrap();
    assert!(html.contains("How this result was made") && html.contains(&kib));
    // and what was read of the recording: samples, rate, length
    let input = &doc["run"]["inputs"][0];
    // (the rate as the report rounds it: 499.99999999999955 Hz reads 500 Hz)
    let read = format!(
        "{} samples at {} Hz",
        input["samples"],
        input["sample_rate_hz"].as_f64().unwrap().round()
    );
    assert!(html.contains(&read), "{read}");
    // results without a recording field are named after the file the command read
    let out = limpid(&[
        "window-sweep",
        examples("planar")
            .join("ex_joint_180.csv")
            .to_str()
            .unwrap(),
        "--link-lengths",
        "0.28,0.35",
        "--report",
        page.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains("Observation-window sweep: ex_joint_180.csv"));
}

/// Result documents whose arrays disagree in length crashed the report in six
/// places (issue 36); they are refused on read, naming the field. (Long:
/// one table of cases, each a mutation and the message it must give.)
#[test]
fn a_result_whose_arrays_disagree_is_refused_naming_the_field() {
    let stochastic = json(&[
        "estimate",
        "stochastic",
        examples("stochastic").join("ex_sa3.csv").to_str().unwrap(),
        "--json",
    ]);
    let linear = json(&[
        "estimate",
        "linear",
        examples("cartesian_slow")
            .join("ex_cubic.csv")
            .to_str()
            .unwrap(),
        "--json",
    ]);
    let spectra = json(&[
        "spectra",
        examples("stochastic").join("ex_sa3.csv").to_str().unwrap(),
        "--inputs",
        "ux,uz",
        "--outputs",
        "x",
        "--nfft",
        "256",
        "--json",
    ]);
    // a small window-sweep document (the fuzzer's seed, made by limpid)
    let sweep: Value = serde_json::from_str(
        &std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../fuzz/corpus/seeds/result-window_sweep.json"),
        )
        .unwrap(),
    )
    .unwrap();
    type Mutation = fn(&mut Value);
    let cases: Vec<(&str, &Value, Mutation, &str)> = vec![
        (
            "a partial coherence one frequency short",
            &spectra,
            |v| {
                v["partial_coherence"][0][1].as_array_mut().unwrap().pop();
            },
            "partial_coherence[0][1]: 128 entries, expected 129 (one per entry of frequencies)",
        ),
        (
            "a sweep row's stiffness one row short (found by the fuzzer)",
            &sweep,
            |v| {
                v["rows"][1]["estimate"]["stiffness"]
                    .as_array_mut()
                    .unwrap()
                    .pop();
            },
            "rows[1].estimate.stiffness: 1 x 2, expected 2 x 2",
        ),
        (
            "a change with a probability of 1.5",
            &sweep,
            |v| {
                v["impedance_change"] = serde_json::json!({"onset_ms": 90.0,
                    "significant_from_ms": 80.0, "stiffness_change": 0.3,
                    "damping_change": 0.1, "p_value": 1.5, "z": 2.0});
            },
            "impedance_change.p_value: 1.5, expected a probability in [0, 1]",
        ),
        (
            "a change significant from a negative time",
            &sweep,
            |v| {
                v["impedance_change"] = serde_json::json!({"onset_ms": 90.0,
                    "significant_from_ms": -40.0, "stiffness_change": 0.3,
                    "damping_change": 0.1, "p_value": 0.001, "z": 3.1});
            },
            "impedance_change.significant_from_ms: -40",
        ),
        (
            "a tissue time constant below zero",
            &sweep,
            |v| {
                v["series_compliance"] = serde_json::json!({
                    "compliance": [[0.01, 0.0], [0.0, 0.01]],
                    "time_constant_s": -0.01, "residual_ratio": 30.0});
            },
            "series_compliance.time_constant_s: -0.01",
        ),
        (
            "an ellipsoid axis of 1e307 (drew NaN coordinates)",
            &linear,
            |v| v["ellipsoids"]["stiffness"]["axes"][0][0] = serde_json::json!(1e307),
            "ellipsoids.stiffness.axes: not a rotation",
        ),
        (
            "empty partial",
            &stochastic,
            |v| v["coherence"]["partial"] = serde_json::json!([]),
            "coherence.partial: 0 entries",
        ),
        (
            "short impedance row",
            &stochastic,
            |v| {
                v["impedance"][5][1].as_array_mut().unwrap().pop();
            },
            "impedance[5][1]: 2 entries",
        ),
        (
            "missing multiple coherence",
            &stochastic,
            |v| {
                v["coherence"]["multiple"].as_array_mut().unwrap().pop();
            },
            "coherence.multiple: 5 entries",
        ),
        (
            "missing SE row",
            &stochastic,
            |v| {
                v["standard_errors"]["stiffness"]
                    .as_array_mut()
                    .unwrap()
                    .pop();
            },
            "standard_errors.stiffness: 2 x 3",
        ),
        (
            "short VAF",
            &linear,
            |v| {
                v["fit"]["vaf"].as_array_mut().unwrap().pop();
            },
            "fit.vaf: 2 entries, expected 3",
        ),
        (
            "1000-row inertia",
            &linear,
            |v| {
                let row = v["inertia"][0].clone();
                v["inertia"] = Value::Array(vec![row; 1000]);
            },
            "inertia: 1000 x 3, expected 3 x 3",
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (what, base, mutate, says) in cases {
        let mut doc = base.clone();
        mutate(&mut doc);
        let path = dir.path().join("bad.json");
        std::fs::write(&path, doc.to_string()).unwrap();
        let html = dir.path().join("bad.html");
        let out = limpid(&[
            "report",
            path.to_str().unwrap(),
            "-o",
            html.to_str().unwrap(),
        ]);
        assert_eq!(out.code, 2, "{what}: {}", out.stderr);
        assert!(
            out.stderr.contains("bad.json") && out.stderr.contains(says),
            "{what}: {}",
            out.stderr
        );
        assert_eq!(
            out.stderr.trim().lines().count(),
            1,
            "{what}: {}",
            out.stderr
        );
        assert!(!html.exists(), "{what}: a report was written");
    }
    // the unmutated documents still read
    for base in [&stochastic, &linear, &sweep] {
        let path = dir.path().join("good.json");
        std::fs::write(&path, base.to_string()).unwrap();
        let html = dir.path().join("good.html");
        let out = limpid(&[
            "report",
            path.to_str().unwrap(),
            "-o",
            html.to_str().unwrap(),
        ]);
        assert_eq!(out.code, 0, "{}", out.stderr);
    }
}
