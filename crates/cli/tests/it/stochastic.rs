//! `limpid estimate stochastic` and `limpid spectra` (issue 6).

use crate::common::*;

#[test]
fn stochastic_examples_through_the_cli() {
    for (set, dir) in example_sets("stochastic") {
        for name in ["ex_sa3", "ex_sa4"] {
            let case = &format!("{set}/{name}");
            let truth_path = dir.join(format!("{name}.truth.json"));
            let truth = limpid_testkit::stochastic_truth(&truth_path);
            let rec = dir.join(format!("{name}.csv"));
            let r = json(&[
                "estimate",
                "stochastic",
                rec.to_str().unwrap(),
                "--expected",
                truth_path.to_str().unwrap(),
                "--json",
            ]);
            let rel = r["accuracy"]["mean_relative_error"].as_f64().unwrap();
            assert!(rel < 0.10, "{case}: mean relative impedance error {rel}");
            let ek = rel_err(&mat(&r["stiffness"]), &truth.stiffness);
            assert!(ek < 0.05, "{case}: stiffness error {ek}");
            let nf = r["frequencies"].as_array().unwrap().len();
            assert_eq!(r["impedance"].as_array().unwrap().len(), nf);
            assert_eq!(r["impedance"][0].as_array().unwrap().len(), 3);
            assert_eq!(r["coherence"]["multiple"].as_array().unwrap().len(), 6);
            assert_eq!(r["coherence"]["partial"][0].as_array().unwrap().len(), 3);
            for key in ["inertia", "damping", "standard_errors", "criteria"] {
                assert!(!r[key].is_null(), "{key}");
            }
        }
    }
}

/// `spectra --json` is a result document (kind `spectra`, in the schema):
/// the PSD integrates to the column's variance (Parseval), the spring array's
/// outputs are explained by its inputs where they have power, the CSV says
/// the same numbers, and the report draws it.
#[test]
fn spectra_json_is_a_result_document_that_integrates_to_the_variance() {
    let rec = examples("stochastic").join("ex_sa3.csv");
    let dir = tempfile::tempdir().unwrap();
    let html = dir.path().join("s.html");
    let args = |extra: &[&str]| {
        let mut a = vec![
            "spectra",
            rec.to_str().unwrap(),
            "--inputs",
            "ux,uz",
            "--outputs",
            "x,z",
        ];
        a.extend_from_slice(extra);
        a.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let with = args(&["--json", "--report", html.to_str().unwrap()]);
    let v = json(&with.iter().map(String::as_str).collect::<Vec<_>>());
    validate(&v);
    assert_eq!(v["kind"], "spectra");
    let f: Vec<f64> = serde_json::from_value(v["frequencies"].clone()).unwrap();
    let psd: Vec<Vec<f64>> = serde_json::from_value(v["psd"].clone()).unwrap();
    let df = f[1] - f[0];
    let ux = limpid_io::read_recording(&rec)
        .unwrap()
        .column("ux")
        .unwrap()
        .to_vec();
    let mean = ux.iter().sum::<f64>() / ux.len() as f64;
    let variance = ux.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / ux.len() as f64;
    let integral = psd[0].iter().sum::<f64>() * df;
    assert!(
        (integral / variance - 1.0).abs() < 0.05,
        "{integral} vs {variance}"
    );
    let multiple: Vec<Vec<Option<f64>>> =
        serde_json::from_value(v["multiple_coherence"].clone()).unwrap();
    for (o, m) in multiple.iter().enumerate() {
        for (k, c) in m.iter().enumerate() {
            if (1.0..=10.0).contains(&f[k]) {
                assert!(c.unwrap() > 0.85, "output {o} at {} Hz: {c:?}", f[k]);
            }
        }
    }
    let text = limpid(&args(&[]).iter().map(String::as_str).collect::<Vec<_>>());
    let row: Vec<f64> = text
        .stdout
        .lines()
        .nth(5)
        .unwrap()
        .split(',')
        .map(|c| c.parse().unwrap())
        .collect();
    assert_eq!(row[0], f[4]);
    assert!((row[1] / psd[0][4] - 1.0).abs() < 1e-12);
    assert!((row[5] - multiple[0][4].unwrap()).abs() < 1e-6);
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(
        page.contains("Power spectral density") && page.contains("Partial and ordinary coherence")
    );
    assert!(!page.contains("NaN"));
}

#[test]
fn spectra_csv_and_bad_band() {
    let rec = examples("stochastic").join("ex_sa4.csv");
    let out = limpid(&[
        "spectra",
        rec.to_str().unwrap(),
        "--inputs",
        "ux,uz",
        "--outputs",
        "x,z",
        "--nfft",
        "1024",
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let lines: Vec<&str> = out.stdout.lines().collect();
    assert_eq!(lines.len(), 1 + 513, "header + nfft/2 + 1 frequencies");
    assert!(lines[0].starts_with("frequency_hz,psd_ux,psd_uz,psd_x,psd_z,multiple_coherence_x"));
    let out = limpid(&[
        "estimate",
        "stochastic",
        rec.to_str().unwrap(),
        "--band",
        "5,600",
    ]);
    assert_eq!(out.code, 2);
    assert_eq!(
        out.stderr.trim_end(),
        "limpid: invalid --band: expected 0 < low < high < 500 Hz, found 5-600 Hz"
    );
    let out = limpid(&[
        "estimate",
        "stochastic",
        examples("cartesian_slow")
            .join("ex_cubic.csv")
            .to_str()
            .unwrap(),
    ]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr
            .contains("missing required column ux (commanded perturbation"),
        "{}",
        out.stderr
    );
}

/// `--shoulder`: seed 004 turns hand X, Z into flexion and abduction before
/// estimating (τ = J_h^T F, eq. (3)) and keeps θ_y as internal rotation; the
/// joint stiffness must be the truth seen through J = diag(J_h, 1).
#[test]
fn shoulder_joint_space_before_estimation_matches_the_mapped_truth() {
    let dir = examples("stochastic");
    let truth = limpid_testkit::stochastic_truth(&dir.join("ex_sa3.truth.json"));
    let rec = dir.join("ex_sa3.csv");
    let r = json(&[
        "estimate",
        "stochastic",
        rec.to_str().unwrap(),
        "--shoulder",
        "0.3,0.35,90,30,45,0",
        "--json",
    ]);
    assert_eq!(r["coordinates"], serde_json::json!(["q1", "q2", "q3"]));
    assert_eq!(r["inputs"], serde_json::json!(["u1", "u2", "u3"]));
    let j = limpid_analysis::shoulder::task_jacobian(&limpid_analysis::linear::ShoulderPosture {
        upper_arm_m: 0.3,
        forearm_m: 0.35,
        elbow_deg: 90.0,
        angles_deg: [30.0, 45.0, 0.0],
    })
    .unwrap();
    let k = truth.stiffness;
    let k = nalgebra::Matrix3::from_fn(|a, b| k[(a, b)]);
    let m = j.transpose() * k * j;
    let expected = nalgebra::DMatrix::from_fn(3, 3, |a, b| m[(a, b)]);
    let e = rel_err(&mat(&r["stiffness"]), &expected);
    assert!(
        e < 0.05,
        "joint stiffness error {e}: {} vs {expected}",
        r["stiffness"]
    );
}

/// An overlap one sample short of the segment kept 46,000 segment spectra
/// (past 4 GB); the size is bounded before anything is computed.
#[test]
fn an_overlap_that_would_need_gigabytes_is_refused_in_one_line() {
    let rec = examples("stochastic").join("ex_sa3.csv");
    let started = std::time::Instant::now();
    let out = limpid(&[
        "estimate",
        "stochastic",
        rec.to_str().unwrap(),
        "--nfft",
        "4096",
        "--overlap",
        "4095",
    ]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("invalid overlap") && out.stderr.contains("GB of spectra"),
        "{}",
        out.stderr
    );
    assert_eq!(out.stderr.trim().lines().count(), 1, "{}", out.stderr);
    // a hang guard, not a timing assertion: refusing takes milliseconds
    assert!(started.elapsed().as_secs() < 60);
    // an ordinary overlap still works
    let ok = limpid(&[
        "estimate",
        "stochastic",
        rec.to_str().unwrap(),
        "--nfft",
        "4096",
        "--overlap",
        "3072",
    ]);
    assert_eq!(ok.code, 0, "{}", ok.stderr);
}

/// `spectra` with a column named twice, or an input that never varies,
/// printed NaN coherences with exit 0 (issue 36).
#[test]
fn spectra_refuses_repeated_columns_and_constant_inputs() {
    let rec = examples("stochastic").join("ex_sa3.csv");
    let rec = rec.to_str().unwrap();
    for (inputs, outputs) in [("ux,ux", "x"), ("ux", "x,x"), ("ux,uz", "ux")] {
        let out = limpid(&["spectra", rec, "--inputs", inputs, "--outputs", outputs]);
        assert_eq!(out.code, 2, "{inputs} {outputs}: {}", out.stderr);
        assert!(out.stderr.contains("is named twice"), "{}", out.stderr);
        assert_eq!(out.stderr.trim().lines().count(), 1, "{}", out.stderr);
    }
    let dir = tempfile::tempdir().unwrap();
    let flat = dir.path().join("flat.csv");
    let mut text = String::from("t,ux,x\n");
    for i in 0..5000 {
        text.push_str(&format!(
            "{},{},{}\n",
            i as f64 * 0.001,
            1.5,
            (i as f64 * 0.37).sin()
        ));
    }
    std::fs::write(&flat, text).unwrap();
    let out = limpid(&[
        "spectra",
        flat.to_str().unwrap(),
        "--inputs",
        "ux",
        "--outputs",
        "x",
    ]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("flat.csv") && out.stderr.contains("column ux: the input never varies"),
        "{}",
        out.stderr
    );
}
