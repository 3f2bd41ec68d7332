//! `limpid estimate linear` against the examples' truths (limpid-made, and
//! the outside generator's with `LIMPID_EXAMPLES`) and the real ankle data
//! (with `LIMPID_REAL_DATA`) (issue 2 acceptance), and `limpid demo` against
//! its subject.

use crate::common::*;

#[test]
fn cartesian_slow_within_3_percent_stiffness_15_percent_damping() {
    for (set, dir) in example_sets("cartesian_slow") {
        for name in ["ex_cubic", "ex_sinusoid"] {
            let case = &format!("{set}/{name}");
            let truth = read_json(&dir.join(format!("{name}.truth.json")));
            let rec = dir.join(format!("{name}.csv"));
            let r = json(&["estimate", "linear", rec.to_str().unwrap(), "--json"]);
            let ek = rel_err(&mat(&r["stiffness"]), &mat(&truth["stiffness"]));
            let eb = rel_err(&mat(&r["damping"]), &mat(&truth["damping"]));
            assert!(ek < 0.03, "{case}: stiffness error {ek}");
            assert!(eb < 0.15, "{case}: damping error {eb}");
            // seed 000's slow perturbations cannot identify inertia: it must say so
            assert_eq!(r["criteria"]["identifiable"]["inertia"], false, "{case}");
            assert!(r["warnings"]
                .as_array()
                .unwrap()
                .iter()
                .any(|w| w["message"]
                    .as_str()
                    .unwrap()
                    .contains("inertia is not identifiable")
                    || w["message"]
                        .as_str()
                        .unwrap()
                        .contains("acceleration regressors are dominated by position noise")));
            // slow trials get fitted offsets by default, which absorb the equilibrium: it is null, with a reason
            assert!(r["equilibrium"].is_null());
            assert!(r["warnings"]
                .as_array()
                .unwrap()
                .iter()
                .any(|w| w["message"]
                    .as_str()
                    .unwrap()
                    .starts_with("equilibrium not estimated")));
            // with rest offsets (seed 000) the equilibrium is the start point (truth) to within 0.5 mm
            let r = json(&[
                "estimate",
                "linear",
                rec.to_str().unwrap(),
                "--offsets",
                "rest",
                "--json",
            ]);
            assert!(rel_err(&mat(&r["stiffness"]), &mat(&truth["stiffness"])) < 0.03);
            let eq: Vec<f64> = r["equilibrium"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            let te: Vec<f64> = truth["equilibrium"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            // 0.5 mm, or what the slow force drift allows on a soft posture: an
            // offset of 3 drift s.d. over the smallest stiffness (the rest
            // offsets are taken 0.2 s before a motion the drift outlasts)
            let k = mat(&truth["stiffness"]);
            let k = nalgebra::DMatrix::from_fn(3, 3, |a, b| 0.5 * (k[(a, b)] + k[(b, a)]));
            let softest = k.symmetric_eigenvalues().min();
            let noise = &truth["noise"];
            let drift = noise["drift_std_N"]
                .as_f64()
                .or(noise["drift_std_n"].as_f64())
                .unwrap();
            let tolerance = (3.0 * drift / softest).max(5e-4);
            for (a, b) in eq.iter().zip(&te) {
                assert!(
                    (a - b).abs() < tolerance,
                    "{case}: equilibrium {eq:?} vs {te:?} (tolerance {tolerance})"
                );
            }
        }
    }
}

#[test]
fn cocontraction_levels_one_at_a_time() {
    for (set, dir) in example_sets("cocontraction") {
        for name in ["ex_config4", "ex_config7"] {
            let case = &format!("{set}/{name}");
            let truth = read_json(&dir.join(format!("{name}.truth.json")));
            let rec = dir.join(format!("{name}.csv"));
            for level in truth["levels"].as_array().unwrap() {
                let l = level["level"].as_f64().unwrap().to_string();
                let r = json(&[
                    "estimate",
                    "linear",
                    rec.to_str().unwrap(),
                    "--level",
                    &l,
                    "--json",
                ]);
                let ek = rel_err(&mat(&r["stiffness"]), &mat(&level["stiffness"]));
                let eb = rel_err(&mat(&r["damping"]), &mat(&truth["damping"]));
                let em = rel_err(&mat(&r["inertia"]), &mat(&truth["inertia"]));
                assert!(ek < 0.03, "{case} level {l}: stiffness error {ek}");
                assert!(eb < 0.15, "{case} level {l}: damping error {eb}");
                // fast 100 ms perturbations do identify inertia
                assert!(em < 0.05, "{case} level {l}: inertia error {em}");
                assert_eq!(r["criteria"]["identifiable"]["inertia"], true);
            }
        }
    }
}

#[test]
fn real_ankle_inertia_in_physiological_range_and_vaf_at_least_plain_fit() {
    let plain = read_json(
        &std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures/ankle_plain_fit.json"),
    );
    let Some(real) = real_data("reklab_ankle") else {
        return;
    };
    for name in ["df", "df2", "df3", "pf", "pf2"] {
        let rec = real.join(format!("{name}.csv"));
        let r = json(&["estimate", "linear", rec.to_str().unwrap(), "--json"]);
        let inertia = r["inertia"][0][0].as_f64().unwrap();
        assert!(
            (0.01..=0.025).contains(&inertia),
            "{name}: inertia {inertia}"
        );
        let vaf = r["fit"]["vaf"][0].as_f64().unwrap();
        let plain_vaf = plain[name]["vaf"].as_f64().unwrap();
        assert!(
            vaf >= plain_vaf,
            "{name}: VAF {vaf} below the plain fit's {plain_vaf}"
        );
        assert!(r["stiffness"][0][0].as_f64().unwrap() > 0.0);
        // the text report prints the three parameters and VAF
        let text = limpid(&["estimate", "linear", rec.to_str().unwrap()]).stdout;
        for needle in [
            "Inertia M (kg m²)",
            "Damping B (N m s/rad)",
            "Stiffness K (N m/rad)",
            "VAF %",
        ] {
            assert!(text.contains(needle), "{name}: no {needle:?} in\n{text}");
        }
    }
}

#[test]
fn parquet_gives_the_csv_result() {
    let csv = examples("cartesian_slow").join("ex_cubic.csv");
    let rec = limpid_io::read_recording(&csv).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let pq = dir.path().join("ex_cubic.parquet");
    limpid_io::write_recording(&rec, &pq).unwrap();
    let a = json(&["estimate", "linear", csv.to_str().unwrap(), "--json"]);
    let b = json(&["estimate", "linear", pq.to_str().unwrap(), "--json"]);
    assert_eq!(a["stiffness"], b["stiffness"]);
    assert_eq!(a["damping"], b["damping"]);
}

#[test]
fn demo_recovers_all_six_start_points() {
    let dir = tempfile::tempdir().unwrap();
    let out = limpid(&[
        "demo",
        "--subject",
        "ideal",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    for s in ["S1", "S2", "S3", "S4", "S5", "S6"] {
        assert!(out.stdout.contains(s), "{s} missing:\n{}", out.stdout);
    }
    let demo = read_json(&dir.path().join("demo.json"));
    assert_eq!(demo["kind"], "demo");
    let points = demo["points"].as_array().unwrap();
    assert_eq!(points.len(), 6);
    for p in points {
        let k = p["stiffness_error_percent"].as_f64().unwrap();
        assert!(k < 3.0, "{}: stiffness error {k} %", p["start_point"]);
        // the error is measured against the subject's own matrix
        let e = rel_err(
            &mat(&p["estimate"]["stiffness"]),
            &mat(&p["true_stiffness"]),
        );
        assert!((100.0 * e - k).abs() < 1e-9);
    }
    assert!(dir.path().join("demo.csv").exists());
    assert_eq!(demo["subject"], "ideal");
}

#[test]
fn demo_on_the_realistic_subject_recovers_stiffness_within_its_standard_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = limpid(&["demo", "--out", dir.path().to_str().unwrap()]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains("subject: realistic"), "{}", out.stdout);
    let demo = read_json(&dir.path().join("demo.json"));
    assert_eq!(demo["subject"], "realistic");
    let mut within = 0;
    let mut total = 0;
    for p in demo["points"].as_array().unwrap() {
        let k = p["stiffness_error_percent"].as_f64().unwrap();
        assert!(k < 15.0, "{}: stiffness error {k} %", p["start_point"]);
        // the truth includes Table II's antisymmetric part
        let truth = mat(&p["true_stiffness"]);
        assert!((truth[(0, 1)] - truth[(1, 0)]).abs() > 1.0, "{truth:?}");
        let est = mat(&p["estimate"]["stiffness"]);
        let se = mat(&p["estimate"]["standard_errors"]["stiffness"]);
        for i in 0..3 {
            total += 1;
            if (est[(i, i)] - truth[(i, i)]).abs() <= 2.0 * se[(i, i)] {
                within += 1;
            }
        }
    }
    // 2 SE cover the truth for most diagonal elements (binomial slack for 18)
    assert!(
        within >= 14,
        "{within} of {total} diagonal elements within 2 SE"
    );
    // the same minutes designed (issue 60): at S1 damping is identified and
    // close, where the seed's slow cubic leaves it to the force fluctuation
    let d = &demo["designed"];
    assert!(out.stdout.contains("S1    designed"), "{}", out.stdout);
    assert!(d["chosen"]["duration_s"].as_f64().unwrap() <= d["budget_s"].as_f64().unwrap());
    let p = &d["point"];
    let (k, b) = (
        p["stiffness_error_percent"].as_f64().unwrap(),
        p["damping_error_percent"].as_f64().unwrap(),
    );
    let verdicts = &p["estimate"]["criteria"]["verdicts"];
    assert!(k < 5.0 && b < 20.0, "designed: K {k} %, B {b} %");
    assert_ne!(verdicts["damping"], "not_identifiable", "{verdicts}");
    assert_ne!(verdicts["stiffness"], "not_identifiable", "{verdicts}");
}

#[test]
fn onsets_found_without_trial_column() {
    let csv = examples("cartesian_slow").join("ex_cubic.csv");
    let rec = limpid_io::read_recording(&csv).unwrap();
    let keep: Vec<(String, Vec<f64>)> = rec
        .columns()
        .filter(|(n, _)| *n != "trial")
        .map(|(n, c)| (n.to_string(), c.to_vec()))
        .collect();
    let (names, cols): (Vec<String>, Vec<Vec<f64>>) = keep.into_iter().unzip();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no_trial.parquet");
    limpid_io::write_recording(
        &limpid_core::Recording::new(&path, names, cols, 1).unwrap(),
        &path,
    )
    .unwrap();
    let truth = read_json(&examples("cartesian_slow").join("ex_cubic.truth.json"));
    let r = json(&[
        "estimate",
        "linear",
        path.to_str().unwrap(),
        "--window",
        "onsets",
        "--json",
    ]);
    assert_eq!(r["provenance"]["windows"], 16);
    let ek = rel_err(&mat(&r["stiffness"]), &mat(&truth["stiffness"]));
    assert!(ek < 0.03, "stiffness error {ek}");
    // by default, without a trial column, the data is one continuous window
    let c = json(&["estimate", "linear", path.to_str().unwrap(), "--json"]);
    assert_eq!(c["provenance"]["continuous"], true);
}

#[test]
fn seed000_frame_change_recovers_the_human_frame_matrices() {
    let csv = examples("cartesian_slow").join("ex_sinusoid.csv");
    let mut rec = limpid_io::read_recording(&csv).unwrap();
    // express the recording in the robot frame: p_R = R^T p_H
    let r = limpid_core::FrameTransform::seed000_robot_to_human()
        .rotation
        .transpose();
    let mut v: Vec<f64> = r.transpose().iter().copied().collect(); // row-major of r
    v.extend([0.0, 0.0, 0.0]);
    limpid_core::FrameTransform::from_values(&v)
        .unwrap()
        .apply(&mut rec)
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let robot = dir.path().join("robot_frame.csv");
    limpid_io::write_recording(&rec, &robot).unwrap();
    let human = json(&["estimate", "linear", csv.to_str().unwrap(), "--json"]);
    let back = json(&[
        "estimate",
        "linear",
        robot.to_str().unwrap(),
        "--frame",
        "seed000",
        "--json",
    ]);
    let e = rel_err(&mat(&back["stiffness"]), &mat(&human["stiffness"]));
    assert!(e < 1e-9, "frame round trip changed K by {e}");
    let raw = json(&["estimate", "linear", robot.to_str().unwrap(), "--json"]);
    assert!(
        rel_err(&mat(&raw["stiffness"]), &mat(&human["stiffness"])) > 0.1,
        "the robot frame differs"
    );
}

#[test]
fn a_matlab_file_estimates_back_to_its_truth() {
    // crates/io/tests/fixtures: a simulated recording saved by scipy.io.savemat (-v7, compressed)
    let fixtures = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../io/tests/fixtures");
    let est = json(&[
        "estimate",
        "linear",
        fixtures.join("small_v7.mat").to_str().unwrap(),
        "--json",
    ]);
    let truth = read_json(&fixtures.join("small.truth.json"));
    let ek = rel_err(&mat(&est["stiffness"]), &mat(&truth["stiffness"]));
    assert!(ek < 0.03, "stiffness error {ek} from the MAT-file");
}
