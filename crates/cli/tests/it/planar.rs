//! `limpid estimate planar` and `limpid window-sweep` (issue 5).

use crate::common::*;

fn m2(v: &serde_json::Value) -> limpid_core::Matrix {
    mat(v)
}

#[test]
fn planar_examples_through_the_cli() {
    for (case, lengths) in [
        ("ex_joint_180", "0.28,0.35"),
        ("ex_endpoint_220", "0.32,0.31"),
    ] {
        for (set, dir) in example_sets("planar") {
            let name = case;
            let case = &format!("{set}/{name}");
            let t = read_json(&dir.join(format!("{name}.truth.json")));
            let rec = dir.join(format!("{name}.csv"));
            let r = json(&[
                "estimate",
                "planar",
                rec.to_str().unwrap(),
                "--link-lengths",
                lengths,
                "--json",
            ]);
            assert!(
                rel_err(&m2(&r["stiffness"]), &mat(&t["stiffness"])) < 0.05,
                "{case}"
            );
            assert!(
                rel_err(&m2(&r["damping"]), &mat(&t["damping"])) < 0.15,
                "{case}"
            );
            let xi: Vec<f64> = r["inertial_parameters"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            let xt: Vec<f64> = t["inertial_parameters"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            let row = |v: &[f64]| nalgebra::DMatrix::from_row_slice(1, v.len(), v);
            assert!(rel_err(&row(&xi), &row(&xt)) < 0.10, "{case}");
            assert_eq!(r["criteria"]["trusted"], true);
            for key in [
                "endpoint_stiffness",
                "standard_errors",
                "fit",
                "leave_one_out_vaf",
            ] {
                assert!(!r[key].is_null(), "{key}");
            }
            // the reduced model with the true inertial parameters gives the same K
            let given = xt
                .iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(",");
            let red = json(&[
                "estimate",
                "planar",
                rec.to_str().unwrap(),
                "--link-lengths",
                lengths,
                "--inertial-parameters",
                &given,
                "--json",
            ]);
            assert_eq!(red["inertial_parameters_fixed"], true);
            assert!(
                rel_err(&m2(&red["stiffness"]), &mat(&t["stiffness"])) < 0.05,
                "{case} reduced"
            );
        }
    }
}

#[test]
fn window_sweep_reports_minimum_windows() {
    let rec = examples("planar").join("ex_joint_180.csv");
    let out = limpid(&[
        "window-sweep",
        rec.to_str().unwrap(),
        "--link-lengths",
        "0.28,0.35",
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    for needle in [
        "K positive definite from T_obs",
        "quasi-symmetric",
        "quasi-constant",
        "leave-one-trial-out VAF",
    ] {
        assert!(out.stdout.contains(needle), "{needle}:\n{}", out.stdout);
    }
    let csv = limpid(&[
        "window-sweep",
        rec.to_str().unwrap(),
        "--link-lengths",
        "0.28,0.35",
        "--csv",
    ])
    .stdout;
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].starts_with("t_obs_ms,cond_w"));
    // 50 ms up to the last 10 ms step inside what the trials hold after the
    // onset (250 ms: 50..240, 20 rows)
    let truth = read_json(&examples("planar").join("ex_joint_180.truth.json"));
    let held = truth["observation_window_ms"].as_f64().unwrap();
    let rows = ((held - 10.0 - 50.0) / 10.0).floor() as usize + 1;
    assert_eq!(held, 250.0);
    assert_eq!(lines.len() - 1, rows);
}

#[test]
fn planar_bad_inputs() {
    let rec = examples("planar").join("ex_endpoint_220.csv");
    let out = limpid(&[
        "estimate",
        "planar",
        rec.to_str().unwrap(),
        "--link-lengths",
        "0.1,0.1",
    ]);
    assert_eq!(out.code, 2);
    let line = out.stderr.trim_end();
    assert!(
        line.starts_with(&format!("limpid: {}: row 2, columns x,y: (", rec.display()))
            && line.contains("is out of reach of links 0.1 + 0.1 m"),
        "{line}"
    );
    let out = limpid(&[
        "estimate",
        "planar",
        rec.to_str().unwrap(),
        "--link-lengths",
        "0.3",
    ]);
    assert_eq!(out.code, 2);
    assert_eq!(
        out.stderr.trim_end(),
        "limpid: invalid value '0.3' for '--link-lengths <L1,L2>': expected 2 numbers separated by commas, found 1; see --help"
    );
    // numbers that gave null or NaN estimates with exit 0 (issue 36)
    let joint = examples("planar").join("ex_joint_180.csv");
    for (verb, flag, value, says) in [
        (
            "planar",
            "--link-lengths",
            "3,4.9e-324",
            "invalid --link-lengths: expected two lengths from 0.01 to 2 m",
        ),
        (
            "window-sweep",
            "--link-lengths",
            "3,4.9e-324",
            "invalid --link-lengths",
        ),
        (
            "planar",
            "--inertial-parameters",
            "nan,0.1,0.1",
            "invalid --inertial-parameters: expected three positive values",
        ),
        (
            "planar",
            "--inertial-parameters",
            "inf,0.1,0.1",
            "invalid --inertial-parameters",
        ),
        (
            "window-sweep",
            "--inertial-parameters",
            "1e308,0.1,0.1",
            "invalid --inertial-parameters",
        ),
        // 1 ms: 30 samples for 11 parameters gave K at 120x the truth (issue 36)
        (
            "planar",
            "--window-ms",
            "1",
            "--window-ms: the observation window holds 1 sample(s) of each trial",
        ),
    ] {
        let mut args = vec![verb];
        if verb == "planar" {
            args.insert(0, "estimate");
        }
        let lengths = if flag == "--link-lengths" {
            value
        } else {
            "0.28,0.35"
        };
        args.extend([joint.to_str().unwrap(), "--link-lengths", lengths]);
        if flag != "--link-lengths" {
            args.extend([flag, value]);
        }
        let out = limpid(&args);
        assert_eq!(out.code, 2, "{args:?}: {}", out.stderr);
        assert!(out.stderr.contains(says), "{args:?}: {}", out.stderr);
        assert_eq!(out.stderr.trim().lines().count(), 1, "{}", out.stderr);
    }
}
