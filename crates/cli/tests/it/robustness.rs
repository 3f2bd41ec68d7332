//! Issue 56, the third hostile-input campaign, replayed through the
//! `limpid` command: each case ends in a one-line error (exit 2), a warning
//! with a result that is not trusted, or the correct result; nothing a
//! command reads is overwritten by what it writes.

use crate::common::*;

use std::path::{Path, PathBuf};

fn one_line_error(out: &Output) -> String {
    assert_eq!(out.code, 2, "stdout {} stderr {}", out.stdout, out.stderr);
    let line = out.stderr.trim_end();
    assert_eq!(line.lines().count(), 1, "{line}");
    assert!(line.starts_with("limpid: "), "{line}");
    assert!(
        !line.contains("panicked") && !line.contains("internal error"),
        "{line}"
    );
    // one number formatter: no run of 16 or more digits in a message
    let longest = line
        .split_whitespace()
        .filter(|word| !word.contains('/')) // paths keep their digits
        .flat_map(|word| word.split(|c: char| !c.is_ascii_digit()))
        .map(str::len)
        .max()
        .unwrap_or(0);
    assert!(longest < 16, "a long number in: {line}");
    line.to_string()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A 3-D centre-out recording of the seed's protocol (start point S1) and its truth.
fn centre_out(dir: &Path) -> (PathBuf, serde_json::Value) {
    let protocol = dir.join("p.toml");
    let out = limpid(&[
        "protocol",
        "new",
        "--preset",
        "artemiadis-3d",
        "-o",
        s(&protocol),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let out = limpid(&["simulate", s(&protocol), "-o", s(&dir.join("rec.csv"))]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let rec = dir.join("rec_S1.csv");
    let truth = read_json(&rec.with_extension("truth.json"));
    (rec, truth)
}

#[test]
fn an_output_that_is_an_input_is_refused_and_the_input_kept() {
    let d = tempfile::tempdir().unwrap();
    let rec = examples("cartesian_slow").join("ex_cubic.csv");
    let copy = d.path().join("rec.csv");
    std::fs::copy(&rec, &copy).unwrap();
    let before = std::fs::read(&copy).unwrap();
    let map = d.path().join("map.toml");
    std::fs::write(&map, "[columns]\nt = \"t\"\nx = \"x\"\ny = \"y\"\nz = \"z\"\nfx = \"fx\"\nfy = \"fy\"\nfz = \"fz\"\ntrial = \"trial\"\n").unwrap();
    let map_before = std::fs::read(&map).unwrap();
    // the same file by another name counts too
    let dotted = d.path().join(".").join("rec.csv");
    for args in [
        vec!["convert", s(&copy), "-o", s(&copy)],
        vec!["convert", s(&copy), "-o", s(&dotted)],
        vec!["estimate", "linear", s(&copy), "--report", s(&copy)],
        vec![
            "--map",
            s(&map),
            "estimate",
            "linear",
            s(&copy),
            "--report",
            s(&map),
        ],
        vec!["--map", s(&map), "convert", s(&copy), "-o", s(&map)],
    ] {
        let line = one_line_error(&limpid(&args));
        assert!(
            line.contains("is both") && line.contains("would replace the input"),
            "{args:?}: {line}"
        );
    }
    assert_eq!(std::fs::read(&copy).unwrap(), before);
    assert_eq!(std::fs::read(&map).unwrap(), map_before);
    // a result: report -o RESULT, rerun RESULT --report RESULT
    let result = d.path().join("r.json");
    let v = json(&["estimate", "linear", s(&copy), "--json"]);
    std::fs::write(&result, v.to_string()).unwrap();
    let result_before = std::fs::read(&result).unwrap();
    for args in [
        vec!["report", s(&result), "-o", s(&result)],
        vec!["rerun", s(&result), "--report", s(&result)],
    ] {
        let line = one_line_error(&limpid(&args));
        assert!(line.contains("is both"), "{args:?}: {line}");
    }
    assert_eq!(std::fs::read(&result).unwrap(), result_before);
    // a protocol: export and simulate onto it
    let protocol = d.path().join("p.toml");
    let out = limpid(&[
        "protocol",
        "new",
        "--preset",
        "lakatos-planar",
        "-o",
        s(&protocol),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let protocol_before = std::fs::read(&protocol).unwrap();
    for args in [
        vec!["protocol", "export", s(&protocol), "-o", s(&protocol)],
        vec!["simulate", s(&protocol), "-o", s(&protocol)],
    ] {
        let line = one_line_error(&limpid(&args));
        assert!(line.contains("is both"), "{args:?}: {line}");
    }
    assert_eq!(std::fs::read(&protocol).unwrap(), protocol_before);
}

#[test]
fn a_report_and_its_figures_at_one_path_are_refused_before_anything_is_written() {
    let d = tempfile::tempdir().unwrap();
    let rec = examples("cartesian_slow").join("ex_cubic.csv");
    let result = d.path().join("r.json");
    let v = json(&["estimate", "linear", s(&rec), "--json"]);
    std::fs::write(&result, v.to_string()).unwrap();
    let html = d.path().join("r.html");
    let line = one_line_error(&limpid(&[
        "report",
        s(&result),
        "-o",
        s(&html),
        "--figures",
        s(&html),
    ]));
    assert!(line.contains("named both as"), "{line}");
    let left: Vec<String> = std::fs::read_dir(d.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, ["r.json"], "left behind: {left:?}");
}

#[cfg(unix)]
#[test]
fn outputs_that_are_fifos_without_a_reader_do_not_block() {
    let d = tempfile::tempdir().unwrap();
    let rec = examples("cartesian_slow").join("ex_cubic.csv");
    let fifo = d.path().join("pipe");
    let c = std::ffi::CString::new(s(&fifo)).unwrap();
    // SAFETY: mkfifo on a fresh path in our own temporary folder.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let result = d.path().join("r.json");
    std::fs::write(
        &result,
        json(&["estimate", "linear", s(&rec), "--json"]).to_string(),
    )
    .unwrap();
    for args in [
        vec!["convert", s(&rec), "-o", s(&fifo)],
        vec!["estimate", "linear", s(&rec), "--report", s(&fifo)],
        vec!["report", s(&result), "-o", s(&fifo)],
    ] {
        let started = std::time::Instant::now();
        let line = one_line_error(&limpid(&args));
        assert!(line.contains("FIFO that nothing reads"), "{args:?}: {line}");
        assert!(started.elapsed() < std::time::Duration::from_secs(60));
    }
}

#[cfg(unix)]
#[test]
fn help_and_version_to_a_full_or_closed_output_fail() {
    use std::os::unix::process::CommandExt;
    for flag in ["--help", "--version"] {
        if let Ok(full) = std::fs::File::options().write(true).open("/dev/full") {
            let out = std::process::Command::new(env!("CARGO_BIN_EXE_limpid"))
                .arg(flag)
                .stdout(full)
                .output()
                .unwrap();
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{flag}: {stderr}");
            assert!(stderr.contains("No space left on device"), "{stderr}");
        }
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_limpid"));
        cmd.arg(flag);
        // SAFETY: only close(2) between fork and exec.
        unsafe {
            cmd.pre_exec(|| {
                libc::close(1);
                Ok(())
            });
        }
        let out = cmd.output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{flag}: {stderr}");
        assert!(stderr.contains("standard output is closed"), "{stderr}");
    }
    // to an ordinary pipe both still work
    assert_eq!(limpid(&["--version"]).code, 0);
    assert!(limpid(&["--help"]).stdout.contains("limpid"));
}

#[test]
fn a_report_of_a_result_whose_provenance_disagrees_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let rec = examples("cartesian_slow").join("ex_cubic.csv");
    let v = json(&["estimate", "linear", s(&rec), "--json"]);
    for (field, value) in [
        ("coordinates", serde_json::json!(["x"])),
        ("force_columns", serde_json::json!(["fx", "fy"])),
    ] {
        let mut edited = v.clone();
        edited["provenance"][field] = value;
        let path = d.path().join(format!("{field}.json"));
        std::fs::write(&path, edited.to_string()).unwrap();
        let line = one_line_error(&limpid(&[
            "report",
            s(&path),
            "-o",
            s(&d.path().join("r.html")),
        ]));
        assert!(line.contains(&format!("provenance.{field}")), "{line}");
    }
    // the same inside a co-contraction level
    let co = examples("cocontraction");
    let v = json(&[
        "estimate",
        "cocontraction",
        s(&co.join("ex_config4.csv")),
        "--mvc",
        s(&co.join("ex_config4.mvc.csv")),
        "--json",
    ]);
    let mut edited = v.clone();
    edited["levels"][0]["estimate"]["provenance"]["coordinates"] = serde_json::json!(["x"]);
    let path = d.path().join("co.json");
    std::fs::write(&path, edited.to_string()).unwrap();
    let line = one_line_error(&limpid(&[
        "report",
        s(&path),
        "-o",
        s(&d.path().join("r.html")),
    ]));
    assert!(
        line.contains("levels[0].estimate.provenance.coordinates"),
        "{line}"
    );
}

#[test]
fn coherences_from_too_few_welch_segments_are_refused() {
    let rec = examples("stochastic").join("ex_sa3.csv");
    let head = std::fs::read_to_string(&rec).unwrap();
    let (inputs, outputs) = ("ux,uz", "x,z");
    let rows = head.lines().count() - 1;
    let line = one_line_error(&limpid(&[
        "spectra",
        s(&rec),
        "--inputs",
        inputs,
        "--outputs",
        outputs,
        "--nfft",
        &(rows - 10).to_string(),
    ]));
    assert!(
        line.contains("Welch segment") && line.contains("biased towards 1"),
        "{line}"
    );
    // several segments: the spectra are given
    let out = limpid(&["spectra", s(&rec), "--inputs", inputs, "--outputs", outputs]);
    assert_eq!(out.code, 0, "{}", out.stderr);
}

/// Rewrite the position columns of a CSV recording: each value held for
/// `factor` samples (`held`) or linearly interpolated between values
/// `factor` samples apart; a `factor` that is not whole keeps the values at
/// rows `round(j factor)` (a stream whose rate is not a whole fraction of
/// the recording's: its knots fall 4 or 5 rows apart for 4.1).
fn resample_positions(from: &Path, to: &Path, factor: f64, held: bool) {
    resample_columns(from, to, &["x", "y", "z"], factor, held);
}

/// [`resample_positions`] for the columns `names`.
fn resample_columns(from: &Path, to: &Path, names: &[&str], factor: f64, held: bool) {
    let text = std::fs::read_to_string(from).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    let cols: Vec<usize> = names
        .iter()
        .filter_map(|c| header.iter().position(|h| h == c))
        .collect();
    let value = |i: usize, c: usize| rows[i][c].parse::<f64>().unwrap();
    // the knots restart with each trial: the virtual lab's trials jump from
    // the target back to the start, which a real stream never does
    let trial = header.iter().position(|h| *h == "trial");
    let mut starts = vec![0];
    if let Some(t) = trial {
        starts.extend((1..rows.len()).filter(|&i| rows[i][t] != rows[i - 1][t]));
    }
    starts.push(rows.len());
    let mut out = header.join(",") + "\n";
    for piece in starts.windows(2) {
        let (start, end) = (piece[0], piece[1]);
        let knot = |j: usize| (start + (j as f64 * factor).round() as usize).min(end - 1);
        let mut j = 0;
        for (i, original) in rows.iter().enumerate().take(end).skip(start) {
            while knot(j + 1) <= i && knot(j + 1) > knot(j) {
                j += 1;
            }
            let (k, next) = (knot(j), knot(j + 1));
            let mut row = original.clone();
            for &c in &cols {
                let v = if held || next == k {
                    value(k, c)
                } else {
                    let f = (i - k) as f64 / (next - k) as f64;
                    value(k, c) * (1.0 - f) + value(next, c) * f
                };
                row[c] = format!("{v:e}");
            }
            out.push_str(&row.join(","));
            out.push('\n');
        }
    }
    std::fs::write(to, out).unwrap();
}

#[test]
fn held_or_interpolated_positions_give_the_native_rate_answer() {
    let d = tempfile::tempdir().unwrap();
    let (rec, truth) = centre_out(d.path());
    let native = json(&["estimate", "linear", s(&rec), "--json"]);
    assert_eq!(native["criteria"]["identifiable"]["damping"], true);
    let element = |v: &serde_json::Value, m: &str, i: usize| {
        (
            v[m][i][i].as_f64().unwrap(),
            v["standard_errors"][m][i][i].as_f64().unwrap(),
        )
    };
    // held, interpolated, and interpolated from a stream at 1/4.1 of the
    // rate (knots 4 or 5 rows apart: issue 58's irregular knots)
    for (held, factor) in [(true, 4.0), (false, 4.0), (false, 4.1)] {
        let path = d.path().join(format!("resampled-{held}-{factor}.csv"));
        resample_positions(&rec, &path, factor, held);
        let v = json(&["estimate", "linear", s(&path), "--json"]);
        let message = v["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .find(|w| w["code"] == "resampled_signal")
            .expect("a resampled_signal warning")["message"]
            .as_str()
            .unwrap()
            .to_string();
        assert!(
            message.contains(match (held, factor == 4.0) {
                (true, _) => "held for 4 samples",
                (false, true) => "interpolated between values 4 samples apart",
                (false, false) => "interpolated between values about 4 samples apart",
            }),
            "{message}"
        );
        assert!(
            message.contains(if factor == 4.0 {
                "estimated from the measured samples only, at 125 Hz"
            } else {
                "estimated from one sample in every second measured interval, at about 62.5 Hz"
            }),
            "{message}"
        );
        // the native-rate answer (issue 58): K and B within their SEs of the
        // native estimate, SEs alike, both still identifiable; the truth within 3 SE
        assert_eq!(
            v["criteria"]["identifiable"]["damping"], true,
            "held {held}"
        );
        for m in ["stiffness", "damping"] {
            for i in 0..3 {
                let (x, se) = element(&v, m, i);
                let (x0, se0) = element(&native, m, i);
                let t = truth[m][i][i].as_f64().unwrap();
                assert!(
                    (x - x0).abs() < 2.0 * se0 && (0.5..2.0).contains(&(se / se0)),
                    "held {held}: {m}[{i}] {x} ± {se}, native {x0} ± {se0}"
                );
                assert!(
                    (x - t).abs() < 3.0 * se + 0.01 * t.abs(),
                    "held {held}: {m}[{i}] {x} ± {se}, truth {t}"
                );
            }
        }
    }
}

#[test]
fn a_held_joint_angle_gives_the_reflex_estimate_of_its_measured_samples() {
    let d = tempfile::tempdir().unwrap();
    let ankle = examples("ankle").join("ex_ankle.csv");
    let held = d.path().join("held.csv");
    resample_columns(&ankle, &held, &["q1"], 4.0, true);
    // the measured samples themselves, as a recording at the sensor's rate
    let text = std::fs::read_to_string(&ankle).unwrap();
    let measured: String = text
        .lines()
        .take(1)
        .chain(text.lines().skip(1).step_by(4))
        .map(|l| format!("{l}\n"))
        .collect();
    let native = d.path().join("measured.csv");
    std::fs::write(&native, measured).unwrap();
    let native = json(&["estimate", "reflex", s(&native), "--json"]);
    let v = json(&["estimate", "reflex", s(&held), "--json"]);
    assert!(
        v["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w["code"] == "resampled_signal"
                && w["message"]
                    .as_str()
                    .unwrap()
                    .contains("q1 (each value held for 4 samples)")),
        "{}",
        v["warnings"]
    );
    for part in ["stiffness", "damping"] {
        let (x, x0) = (&v["intrinsic"][part], &native["intrinsic"][part]);
        assert_eq!(
            x, x0,
            "{part}: the held log's estimate is the measured samples'"
        );
    }
}

#[test]
fn non_finite_and_implausible_flags_are_refused_in_short_numbers() {
    let planar = examples("planar").join("ex_joint_180.csv");
    let co = examples("cocontraction");
    let cubic = examples("cartesian_slow").join("ex_cubic.csv");
    let ankle = examples("ankle").join("ex_ankle.csv");
    let links = ["--link-lengths", "0.32,0.31"];
    for (args, says) in [
        (
            vec![
                "window-sweep",
                s(&planar),
                links[0],
                links[1],
                "--step",
                "inf",
            ],
            "--step",
        ),
        (
            vec![
                "window-sweep",
                s(&planar),
                links[0],
                links[1],
                "--to",
                "inf",
            ],
            "--to",
        ),
        (
            vec![
                "window-sweep",
                s(&planar),
                links[0],
                links[1],
                "--step",
                "1e-300",
            ],
            "1e-300",
        ),
        (
            vec![
                "estimate",
                "planar",
                s(&planar),
                links[0],
                links[1],
                "--window-ms",
                "inf",
            ],
            "--window-ms",
        ),
        (
            vec!["window-sweep", s(&planar), "--link-lengths", "3,4.9e-324"],
            "4.94066e-324",
        ),
        (
            vec!["estimate", "linear", s(&cubic), "--cutoff", "1e308"],
            "1e308 Hz",
        ),
        (
            vec![
                "estimate",
                "varying",
                s(&ankle),
                "--schedule",
                "q1",
                "--slow",
                "1e308",
            ],
            "1e308 Hz",
        ),
        (
            vec![
                "estimate",
                "cocontraction",
                s(&co.join("ex_config4.csv")),
                "--mvc",
                s(&co.join("ex_config4.mvc.csv")),
                "--tolerance",
                "inf",
            ],
            "--tolerance",
        ),
    ] {
        let line = one_line_error(&limpid(&args));
        assert!(line.contains(says), "{args:?}: {line}");
    }
}

#[test]
fn a_recording_whose_clock_is_implausibly_fast_is_named_as_such() {
    let d = tempfile::tempdir().unwrap();
    for (name, dt) in [("ns.csv", 1e-9), ("tiny.csv", 1e-300)] {
        let path = d.path().join(name);
        let mut text = String::from("t,x,fx\n");
        for i in 0..2000 {
            let t = i as f64 * dt;
            text.push_str(&format!(
                "{t:e},{},{}\n",
                (i as f64 * 0.01).sin() * 0.01,
                (i as f64 * 0.01).sin()
            ));
        }
        std::fs::write(&path, text).unwrap();
        for args in [
            vec!["estimate", "linear", s(&path)],
            vec!["spectra", s(&path), "--inputs", "fx", "--outputs", "x"],
            vec!["convert", s(&path), "-o", s(&d.path().join("out.csv"))],
        ] {
            let line = one_line_error(&limpid(&args));
            assert!(
                line.contains(name) && line.contains("column t: implausible sample rate"),
                "{args:?}: {line}"
            );
        }
        assert!(!d.path().join("out.csv").exists());
    }
}

#[test]
fn a_constant_coordinate_and_a_fractional_trial_id_are_refused_by_name() {
    let d = tempfile::tempdir().unwrap();
    let rec = examples("cartesian_slow").join("ex_cubic.csv");
    let text = std::fs::read_to_string(&rec).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let x = header.iter().position(|h| *h == "x").unwrap();
    let trial = header.iter().position(|h| *h == "trial").unwrap();
    let edit = |f: &dyn Fn(usize, &mut Vec<String>)| -> String {
        let mut out = header.join(",") + "\n";
        for (i, l) in text.lines().skip(1).enumerate() {
            let mut row: Vec<String> = l.split(',').map(str::to_string).collect();
            f(i, &mut row);
            out.push_str(&row.join(","));
            out.push('\n');
        }
        out
    };
    let constant = d.path().join("constant.csv");
    std::fs::write(&constant, edit(&|_, r| r[x] = "0.3".into())).unwrap();
    let line = one_line_error(&limpid(&["estimate", "linear", s(&constant)]));
    assert!(
        line.contains("column x holds 0.3 in every sample"),
        "{line}"
    );
    let fractional = d.path().join("fractional.csv");
    std::fs::write(
        &fractional,
        edit(&|i, r| {
            if i == 4 {
                r[trial] = "1.5".into()
            }
        }),
    )
    .unwrap();
    let line = one_line_error(&limpid(&["estimate", "linear", s(&fractional)]));
    assert!(
        line.contains("row 6, column trial: expected an integer trial id, found 1.5"),
        "{line}"
    );
}

#[test]
fn varying_refuses_its_own_torque_as_schedule_and_distrusts_a_delay_at_the_scan_end() {
    let ankle = examples("ankle").join("ex_ankle.csv");
    let line = one_line_error(&limpid(&[
        "estimate",
        "varying",
        s(&ankle),
        "--schedule",
        "tau1",
    ]));
    assert!(line.contains("cannot be its own schedule"), "{line}");
    let line = one_line_error(&limpid(&[
        "estimate",
        "reflex",
        s(&ankle),
        "--position",
        "t",
    ]));
    assert!(
        line.contains("--position") && line.contains("not a joint signal"),
        "{line}"
    );
    // a reflex at 45 ms scanned only to 20 ms (the ramp-and-hold ankle)
    let d = tempfile::tempdir().unwrap();
    let protocol = d.path().join("ank.toml");
    let out = limpid(&[
        "protocol",
        "new",
        "--preset",
        "ankle-ramp-and-hold",
        "-o",
        s(&protocol),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let rec = d.path().join("ank.csv");
    let out = limpid(&["simulate", s(&protocol), "-o", s(&rec), "--seed", "3"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let truth: serde_json::Value = read_json(&rec.with_extension("truth.json"));
    assert!(truth["reflex_delay_s"].as_f64().unwrap() > 0.03);
    let v = json(&[
        "estimate",
        "varying",
        s(&rec),
        "--schedule",
        "sv",
        "--reflex",
        "--max-delay",
        "0.02",
        "--grid",
        "9",
        "--json",
    ]);
    let trusted = v["points"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["identifiable"] == true)
        .count();
    assert_eq!(trusted, 0, "{v}");
    let warned = v["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .any(|w| w.as_str().unwrap().contains("longest scanned"));
    assert!(warned, "{}", v["warnings"]);
    // and a too-low decimation rate is said, not raised in silence
    let out = limpid(&[
        "estimate",
        "varying",
        s(&rec),
        "--schedule",
        "sv",
        "--rate",
        "1e-9",
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(
        out.stdout.contains("rate_hz 1e-9 Hz: decimated to"),
        "{}",
        out.stdout
    );
}

#[test]
fn a_map_that_reads_one_channel_twice_or_names_no_samples_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let rec = examples("ankle").join("ex_ankle.csv");
    let map = d.path().join("twice.toml");
    std::fs::write(&map, "[columns]\nt = \"t\"\nq1 = \"q1\"\ntau1 = \"q1\"\n").unwrap();
    let line = one_line_error(&limpid(&["--map", s(&map), "estimate", "reflex", s(&rec)]));
    assert!(
        line.contains("columns q1 and tau1 both read channel \"q1\""),
        "{line}"
    );
    // a t column and a [time] rate: two times
    let map = d.path().join("two-times.toml");
    std::fs::write(
        &map,
        "[time]\nrate = 1000.0\n\n[columns]\nt = \"t\"\nq1 = \"q1\"\ntau1 = \"tau1\"\n",
    )
    .unwrap();
    let line = one_line_error(&limpid(&["--map", s(&map), "estimate", "reflex", s(&rec)]));
    assert!(line.contains("both a t column and [time] rate"), "{line}");
    // a stream a CSV does not have
    let map = d.path().join("stream.toml");
    std::fs::write(
        &map,
        "[columns]\nt = \"t\"\nq1 = { channel = \"q1\", stream = \"robot\" }\ntau1 = \"tau1\"\n",
    )
    .unwrap();
    let line = one_line_error(&limpid(&["--map", s(&map), "estimate", "reflex", s(&rec)]));
    assert!(line.contains("no stream \"robot\""), "{line}");
}

#[test]
fn messages_say_what_the_flags_and_files_are() {
    let d = tempfile::tempdir().unwrap();
    let file = d.path().join("not-a-folder");
    std::fs::write(&file, "x").unwrap();
    let manifest = d.path().join("study.toml");
    std::fs::write(&manifest, "[study]\n").unwrap();
    let line = one_line_error(&limpid(&["study", "run", s(&manifest), "--out", s(&file)]));
    assert!(line.contains("exists and is not a folder"), "{line}");
    let map = d.path().join("m.toml");
    std::fs::write(&map, "[columns]\nt = \"t\"\n").unwrap();
    let line = one_line_error(&limpid(&[
        "--map",
        s(&map),
        "study",
        "run",
        s(&manifest),
        "--out",
        s(&d.path().join("o")),
    ]));
    assert!(line.contains("manifest"), "{line}");
    let line = one_line_error(&limpid(&["--map", s(&map), "rerun", s(&manifest)]));
    assert!(line.contains("run block"), "{line}");
    // an output format limpid does not write
    let rec = examples("cartesian_slow").join("ex_cubic.csv");
    let line = one_line_error(&limpid(&[
        "convert",
        s(&rec),
        "-o",
        s(&d.path().join("x.xdf")),
    ]));
    assert!(line.contains("not .xdf"), "{line}");
    assert!(!d.path().join("x.xdf").exists());
    // live: channels without names or named twice
    for (channels, says) in [
        ("", "has no name"),
        ("a,,b", "has no name"),
        ("a,a", "named twice"),
    ] {
        let line = one_line_error(&limpid(&["live", "--channels", channels, "--rate", "1000"]));
        assert!(line.contains(says), "{channels:?}: {line}");
    }
}

#[test]
fn rerun_reads_only_files_named_like_recordings_and_echoes_none() {
    let d = tempfile::tempdir().unwrap();
    let rec = examples("cartesian_slow").join("ex_cubic.csv");
    let mut v = json(&["estimate", "linear", s(&rec), "--json"]);
    v["run"]["inputs"][0]["path"] = "/etc/passwd".into();
    let result = d.path().join("r.json");
    std::fs::write(&result, v.to_string()).unwrap();
    let line = one_line_error(&limpid(&["rerun", s(&result)]));
    assert!(line.contains("not named like a recording"), "{line}");
    assert!(!line.contains("root"), "{line}");
}

#[test]
fn swapped_recording_and_mvc_are_named() {
    let co = examples("cocontraction");
    let line = one_line_error(&limpid(&[
        "estimate",
        "cocontraction",
        s(&co.join("ex_config4.mvc.csv")),
        "--mvc",
        s(&co.join("ex_config4.csv")),
    ]));
    assert!(line.contains("are the two swapped"), "{line}");
}

#[test]
fn an_ensemble_of_identical_repetitions_identifies_nothing() {
    let d = tempfile::tempdir().unwrap();
    let protocol = d.path().join("e.toml");
    let out = limpid(&[
        "protocol",
        "new",
        "--preset",
        "ensemble",
        "-o",
        s(&protocol),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let text = std::fs::read_to_string(&protocol)
        .unwrap()
        .replace("repetitions = 100", "repetitions = 40");
    std::fs::write(&protocol, text).unwrap();
    let rec = d.path().join("e.csv");
    let out = limpid(&["simulate", s(&protocol), "-o", s(&rec)]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    // every repetition replaced by the first (times and trial ids kept)
    let text = std::fs::read_to_string(&rec).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    let trial = header.iter().position(|h| *h == "trial").unwrap();
    let t = header.iter().position(|h| *h == "t").unwrap();
    let first: Vec<&Vec<String>> = rows.iter().filter(|r| r[trial] == rows[0][trial]).collect();
    let mut out = header.join(",") + "\n";
    let mut k = 0;
    for (i, r) in rows.iter().enumerate() {
        if i > 0 && r[trial] != rows[i - 1][trial] {
            k = 0;
        }
        let mut row = first[k.min(first.len() - 1)].clone();
        row[t] = r[t].clone();
        row[trial] = r[trial].clone();
        out.push_str(&row.join(","));
        out.push('\n');
        k += 1;
    }
    let same = d.path().join("same.csv");
    std::fs::write(&same, out).unwrap();
    let v = json(&["estimate", "varying", s(&same), "--json"]);
    let points = v["points"].as_array().unwrap();
    assert!(points.iter().all(|p| p["identifiable"] == false), "{v}");
    assert!(
        points
            .iter()
            .any(|p| p["reason"].as_str().unwrap_or("").contains("do not differ")),
        "{v}"
    );
    // the real ensemble still identifies its middle
    let v = json(&["estimate", "varying", s(&rec), "--json"]);
    assert!(v["points"]
        .as_array()
        .unwrap()
        .iter()
        .any(|p| p["identifiable"] == true));
}

#[test]
fn a_map_whose_time_scale_makes_nanoseconds_is_named_as_an_implausible_rate() {
    let d = tempfile::tempdir().unwrap();
    let rec = examples("ankle").join("ex_ankle.csv");
    let map = d.path().join("ns.toml");
    std::fs::write(
        &map,
        "[columns]\nt = { channel = \"t\", scale = 1e-6 }\nq1 = \"q1\"\ntau1 = \"tau1\"\n",
    )
    .unwrap();
    let line = one_line_error(&limpid(&["--map", s(&map), "estimate", "reflex", s(&rec)]));
    assert!(
        line.contains("column t: implausible sample rate 1e9 Hz"),
        "{line}"
    );
}
