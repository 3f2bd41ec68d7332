//! `limpid estimate varying` (issue 38): simulated ensemble and ramp-and-hold
//! recordings against their truth files, the report, and the refusals.

use crate::common::*;

fn simulate(dir: &std::path::Path, preset: &str, extra: &str) -> std::path::PathBuf {
    let protocol = dir.join(format!("{preset}.toml"));
    let out = limpid(&["protocol", "new", "--preset", preset]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let mut text = out.stdout.clone();
    for line in extra.lines() {
        let key = line.split('=').next().unwrap().trim();
        text = text
            .lines()
            .filter(|l| l.split('=').next().unwrap().trim() != key)
            .map(|l| format!("{l}\n"))
            .collect();
        text.push_str(&format!("{line}\n"));
    }
    std::fs::write(&protocol, text).unwrap();
    let rec = dir.join(format!("{preset}.csv"));
    let out = limpid(&[
        "simulate",
        protocol.to_str().unwrap(),
        "-o",
        rec.to_str().unwrap(),
        "--seed",
        "7",
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    rec
}

#[test]
fn ensemble_json_follows_the_truth_file_and_the_report_draws_it() {
    let dir = tempfile::tempdir().unwrap();
    let rec = simulate(dir.path(), "ensemble", "");
    let truth = limpid_testkit::varying_truth(&rec.with_extension("truth.json"));
    let html = dir.path().join("v.html");
    let v = json(&[
        "estimate",
        "varying",
        rec.to_str().unwrap(),
        "--json",
        "--report",
        html.to_str().unwrap(),
    ]);
    validate(&v);
    assert_eq!(v["kind"], "varying");
    assert_eq!(v["schedule"]["name"], "time since trial start");
    let truth_k = |t: f64| {
        let pts = &truth.points;
        let i = ((t / 0.01).round() as usize).min(pts.len() - 1);
        pts[i].stiffness[(0, 0)]
    };
    let points = v["points"].as_array().unwrap();
    let mut good = 0;
    let mut n = 0;
    for p in points.iter().filter(|p| p["identifiable"] == true) {
        let t = p["sigma"].as_f64().unwrap();
        let k = p["stiffness"][0][0].as_f64().unwrap();
        n += 1;
        good += usize::from((k - truth_k(t)).abs() < 0.15 * truth_k(t));
    }
    assert!(n > 50 && good as f64 >= 0.9 * n as f64, "{good} of {n}");
    // the instants near the ends are named, not given numbers
    assert_eq!(points[0]["identifiable"], false);
    assert!(points[0]["stiffness"].is_null());
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("Varying impedance") && page.contains("± 2 SE"));
    assert!(!page.contains("NaN"));
    // text
    let out = limpid(&["estimate", "varying", rec.to_str().unwrap()]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains("not identifiable: within") && out.stdout.contains("K11"));
    assert!(!out.stdout.contains("NaN"));
}

#[test]
fn ramp_and_hold_holds_only_with_gaps_recovers_k_and_the_reflex() {
    let dir = tempfile::tempdir().unwrap();
    let rec = simulate(dir.path(), "ankle-ramp-and-hold", "keep_ramps = false\n");
    let v = json(&[
        "estimate",
        "varying",
        rec.to_str().unwrap(),
        "--schedule",
        "sv",
        "--reflex",
        "--grid",
        "13",
        "--json",
    ]);
    validate(&v);
    let truth = limpid_testkit::varying_truth(&rec.with_extension("truth.json"));
    assert!(v["reflex"]["detected"].as_bool().unwrap());
    let delay = v["reflex"]["delay_s"].as_f64().unwrap();
    assert!(
        (delay - truth.reflex_delay_s.unwrap()).abs() < 0.01,
        "{delay}"
    );
    let at = |s: f64| {
        // the truth grid and the result's span the same schedule range
        truth
            .points
            .iter()
            .min_by(|a, b| (a.sigma - s).abs().total_cmp(&(b.sigma - s).abs()))
            .unwrap()
    };
    for p in v["points"].as_array().unwrap() {
        let s = p["sigma"].as_f64().unwrap();
        if p["identifiable"] != true {
            continue;
        }
        let truth_point = at(s);
        if (truth_point.sigma - s).abs() > 0.01 {
            continue;
        }
        let (k, kt) = (
            p["stiffness"][0][0].as_f64().unwrap(),
            truth_point.stiffness[(0, 0)],
        );
        assert!((k - kt).abs() < 0.1 * kt, "K({s}) = {k}, truth {kt}");
        let g = p["reflex"]["gain"].as_f64().unwrap();
        let gt = truth_point.reflex_gain.unwrap();
        assert!(
            (g - gt).abs() < 0.25 * gt.max(4.0),
            "G({s}) = {g}, truth {gt}"
        );
    }
}

#[test]
fn varying_refusals_name_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("flat.csv");
    let mut text = String::from("t,q1,tau1,sv\n");
    for i in 0..20_000 {
        let t = i as f64 / 1000.0;
        text.push_str(&format!(
            "{t},{},{},0.1\n",
            (t * 9.0).sin() * 0.01,
            (t * 9.0).sin()
        ));
    }
    std::fs::write(&rec, text).unwrap();
    let r = rec.to_str().unwrap();
    // two joints on a varying schedule: the schedule is not one joint's angle
    let two = dir.path().join("two.csv");
    let mut text = String::from("t,q1,q2,tau1,tau2,sv\n");
    for i in 0..20_000 {
        let t = i as f64 / 1000.0;
        let (a, b) = ((t * 9.0).sin(), (t * 7.0).cos());
        text.push_str(&format!(
            "{t},{},{},{a},{b},{}\n",
            0.01 * a,
            0.01 * b,
            t / 20.0
        ));
    }
    std::fs::write(&two, text).unwrap();
    let two = two.to_str().unwrap();
    for (args, want) in [
        (
            vec![
                "estimate",
                "varying",
                two,
                "--schedule",
                "sv",
                "--schedule-angle",
                "offset",
            ],
            "--schedule-angle",
        ),
        (vec!["estimate", "varying", r], "trial"),
        (
            vec!["estimate", "varying", r, "--schedule", "sv"],
            "does not vary",
        ),
        (vec!["estimate", "varying", r, "--schedule", "nope"], "nope"),
        (
            vec!["estimate", "varying", r, "--window-ms", "0"],
            "--window-ms",
        ),
        (
            vec!["estimate", "varying", r, "--order", "9", "--schedule", "sv"],
            "--order",
        ),
        (vec!["estimate", "varying", r, "--reflex"], "--reflex"),
        (
            vec!["estimate", "varying", r, "--schedule", "sv", "--slow", "-1"],
            "--slow",
        ),
        (
            vec![
                "estimate",
                "varying",
                r,
                "--schedule",
                "sv",
                "--cutoff",
                "900",
            ],
            "half the sample rate",
        ),
        (
            vec!["estimate", "varying", r, "--grid", "1", "--schedule", "sv"],
            "--grid",
        ),
    ] {
        let out = limpid(&args);
        assert_eq!(out.code, 2, "{args:?}: {}", out.stderr);
        assert!(
            out.stderr.contains(want) && out.stderr.lines().count() == 1,
            "{args:?}: {}",
            out.stderr
        );
    }
}

#[test]
fn linear_takes_holds_of_a_continuous_perturbation_as_trials() {
    let dir = tempfile::tempdir().unwrap();
    let subject = dir.path().join("ankle.toml");
    std::fs::write(
        &subject,
        "inertia = 0.015\nstiffness = [70.0, 0.0, 0.0]\ndamping = [0.8, 0.0, 0.0]\nbackground = [2.0, 10.0, 0.0]\n",
    )
    .unwrap();
    let protocol = dir.path().join("p.toml");
    let out = limpid(&["protocol", "new", "--preset", "ankle-ramp-and-hold"]);
    std::fs::write(
        &protocol,
        out.stdout
            .replace("keep_ramps = true", "keep_ramps = false"),
    )
    .unwrap();
    let rec = dir.path().join("holds.csv");
    let out = limpid(&[
        "simulate",
        protocol.to_str().unwrap(),
        "--subject",
        subject.to_str().unwrap(),
        "-o",
        rec.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    // with rests expected, every hold is refused
    let out = limpid(&[
        "estimate",
        "linear",
        rec.to_str().unwrap(),
        "--window",
        "trials",
    ]);
    assert_eq!(out.code, 2, "{}", out.stdout);
    let v = json(&[
        "estimate",
        "linear",
        rec.to_str().unwrap(),
        "--window",
        "continuous-trials",
        "--json",
    ]);
    let k = v["stiffness"][0][0].as_f64().unwrap();
    let b = v["damping"][0][0].as_f64().unwrap();
    assert!((k - 70.0).abs() < 0.03 * 70.0, "K {k}");
    assert!((b - 0.8).abs() < 0.1 * 0.8, "B {b}");
}

#[test]
fn extreme_windows_and_rates_are_refused_or_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let ens = simulate(dir.path(), "ensemble", "repetitions = 12\n");
    let e = ens.to_str().unwrap();
    // 1e307 ms saturated a sample count into the message; a step longer than a repetition left one edge point
    for (flag, value) in [("--window-ms", "1e307"), ("--step", "1e307")] {
        let out = limpid(&["estimate", "varying", e, flag, value]);
        assert_eq!(out.code, 2, "{flag}: {}", out.stdout);
        assert!(
            out.stderr.contains(flag)
                && out
                    .stderr
                    .contains("not shorter than the repetitions (1200 ms)")
                && out.stderr.lines().count() == 1,
            "{}",
            out.stderr
        );
    }
    // --rate 1e-300 looped over 2^64 decimation factors; it decimates as far as the low-pass allows
    let flat = dir.path().join("slow.csv");
    let mut text = String::from("t,q1,tau1,sv\n");
    for i in 0..20_000 {
        let t = i as f64 / 1000.0;
        let q = (t * 9.0).sin() * 0.01 + (t * 37.0).sin() * 0.004;
        text.push_str(&format!("{t},{q},{},{}\n", 50.0 * q, 0.1 * t));
    }
    std::fs::write(&flat, text).unwrap();
    let v = json(&[
        "estimate",
        "varying",
        flat.to_str().unwrap(),
        "--schedule",
        "sv",
        "--rate",
        "1e-300",
        "--order",
        "1",
        "--json",
    ]);
    assert_eq!(v["kind"], "varying");
}

/// Walking (issue 61): the CLI end to end on a simulated walk (its result
/// validates against the schema, the report draws the gait figures), and
/// each class of bad walking input refused in one line naming what is wrong.
#[test]
fn walking_estimate_reports_flawed_strides_and_refuses_bad_events() {
    let dir = tempfile::tempdir().unwrap();
    // the keys go before the [perturbation] table: set them in place
    let protocol = preset(dir.path(), "walking-pulses");
    let text = std::fs::read_to_string(&protocol)
        .unwrap()
        .replace("strides = 300", "strides = 80")
        .replace("missed_events = 0.0", "missed_events = 0.05");
    std::fs::write(&protocol, text).unwrap();
    let rec = dir.path().join("walk.csv");
    let out = limpid(&[
        "simulate",
        protocol.to_str().unwrap(),
        "-o",
        rec.to_str().unwrap(),
        "--seed",
        "3",
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let html = dir.path().join("w.html");
    let r = rec.to_str().unwrap();
    let v = json(&[
        "estimate",
        "varying",
        r,
        "--event",
        "heel_strike",
        "--json",
        "--report",
        html.to_str().unwrap(),
    ]);
    validate(&v);
    assert_eq!(v["method"], "pulses");
    assert_eq!(v["schedule"]["unit"], "fraction of the stride");
    let flawed = v["gait"]["flawed"].as_array().unwrap();
    assert!(flawed.iter().any(|f| f["kind"] == "missed"), "{flawed:?}");
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("stance | swing") && page.contains("Strides with flawed events"));

    // the walking file with one bad cell at a time
    let text = std::fs::read_to_string(&rec).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let write = |name: &str, column: &str, value: &str| {
        let c = header.iter().position(|h| *h == column).unwrap();
        let body: String = text
            .lines()
            .enumerate()
            .map(|(i, l)| {
                if i == 101 {
                    let mut cells: Vec<&str> = l.split(',').collect();
                    cells[c] = value;
                    format!("{}\n", cells.join(","))
                } else {
                    format!("{l}\n")
                }
            })
            .collect();
        let p = dir.path().join(name);
        std::fs::write(&p, body).unwrap();
        p
    };
    let refused = |args: &[&str], needles: &[&str]| {
        let out = limpid(args);
        assert_ne!(out.code, 0, "{args:?} was accepted");
        assert!(
            !out.stderr.contains("panicked") && out.stderr.trim().lines().count() == 1,
            "{}",
            out.stderr
        );
        for n in needles {
            assert!(out.stderr.contains(n), "{args:?}: {} lacks {n}", out.stderr);
        }
    };
    // a detector chattering on every other sample: refused, not 80 000 flawed strides listed
    let hs = header.iter().position(|h| *h == "heel_strike").unwrap();
    let chatter: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 0 {
                return format!("{l}\n");
            }
            let mut cells: Vec<String> = l.split(',').map(String::from).collect();
            cells[hs] = (i % 2).to_string();
            format!("{}\n", cells.join(","))
        })
        .collect();
    let chattering = dir.path().join("chatter.csv");
    std::fs::write(&chattering, chatter).unwrap();
    refused(
        &[
            "estimate",
            "varying",
            chattering.to_str().unwrap(),
            "--event",
            "heel_strike",
        ],
        &["--event", "check the event column"],
    );
    let two = write("two.csv", "heel_strike", "2");
    refused(
        &[
            "estimate",
            "varying",
            two.to_str().unwrap(),
            "--event",
            "heel_strike",
        ],
        &["row 102", "heel_strike", "0 or 1"],
    );
    let half = write("half.csv", "perturbation", "0.5");
    refused(
        &[
            "estimate",
            "varying",
            half.to_str().unwrap(),
            "--event",
            "heel_strike",
        ],
        &["row 102", "perturbation"],
    );
    refused(
        &["estimate", "varying", r, "--event", "toe_off"],
        &["toe_off"],
    );
    refused(
        &["estimate", "varying", r, "--event", "tau1>abc"],
        &["--event", "abc"],
    );
    refused(
        &["estimate", "varying", r, "--event", "tau1"],
        &["--event", "tau1"],
    );
    refused(
        &["estimate", "varying", r, "--event", "t<-1"],
        &["event(s)"],
    );
    refused(
        &["estimate", "varying", r, "--trigger", "perturbation"],
        &["--trigger", "--event"],
    );
    refused(
        &[
            "estimate",
            "varying",
            r,
            "--event",
            "heel_strike",
            "--bin",
            "0.7",
        ],
        &["--bin"],
    );
    refused(
        &[
            "estimate",
            "varying",
            r,
            "--event",
            "heel_strike",
            "--refractory",
            "1e307",
        ],
        &["--refractory"],
    );
    refused(
        &[
            "estimate",
            "varying",
            r,
            "--event",
            "heel_strike",
            "--neighbours",
            "2",
        ],
        &["--neighbours", "3 to 1000"],
    );
    refused(
        &[
            "estimate",
            "varying",
            r,
            "--event",
            "heel_strike",
            "--stance-end",
            "1",
        ],
        &["--stance-end"],
    );
    refused(
        &[
            "estimate",
            "varying",
            r,
            "--event",
            "heel_strike",
            "--schedule",
            "sv",
        ],
        &["--schedule"],
    );
}
