//! Issue 13 through the `limpid` command: each class of hostile input ends
//! in one line on stderr and exit 2, or in an honest result; never a panic,
//! a hang, a NaN, or a partial file.

use crate::common::*;

use std::path::{Path, PathBuf};

fn one_line_error(out: &Output) -> &str {
    assert_eq!(out.code, 2, "stdout {} stderr {}", out.stdout, out.stderr);
    let line = out.stderr.trim_end();
    assert_eq!(line.lines().count(), 1, "{line}");
    assert!(line.starts_with("limpid: "), "{line}");
    assert!(
        !line.contains("panicked") && !line.contains("internal error"),
        "{line}"
    );
    line
}

fn edit(p: &Path, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string(p).unwrap();
    assert!(text.contains(from), "{from} not in {}", p.display());
    let q = p.with_file_name(format!(
        "edited-{}",
        p.file_name().unwrap().to_string_lossy()
    ));
    std::fs::write(&q, text.replacen(from, to, 1)).unwrap();
    q
}

#[test]
fn nan_limits_cannot_switch_a_safety_check_off() {
    let d = tempfile::tempdir().unwrap();
    let p = preset(d.path(), "artemiadis-3d");
    for key in [
        "max_displacement_m = 0.05",
        "max_velocity_m_s = 0.1",
        "max_acceleration_m_s2 = 1.0",
        "max_force_n = 60.0",
        "nominal_stiffness_n_per_m = 1000.0",
    ] {
        let name = key.split(" = ").next().unwrap();
        for bad in ["nan", "inf", "-1.0", "0.0"] {
            let q = edit(&p, key, &format!("{name} = {bad}"));
            for cmd in [
                vec!["protocol", "check", q.to_str().unwrap()],
                vec![
                    "simulate",
                    q.to_str().unwrap(),
                    "-o",
                    d.path().join("r.csv").to_str().unwrap(),
                ],
            ] {
                let out = limpid(&cmd);
                let line = one_line_error(&out);
                assert!(
                    line.contains(&format!("key limits.{name}: expected a"))
                        && line.contains("line "),
                    "{line}"
                );
            }
            assert!(!d.path().join("r.csv").exists());
        }
    }
    // a planar step faster than a sample: refused, not "peak velocity 0"
    let p = preset(d.path(), "lakatos-planar");
    let q = edit(&p, "interpolation_s = 0.2", "interpolation_s = 1e-9");
    let line = one_line_error(&limpid(&["protocol", "check", q.to_str().unwrap()])).to_string();
    assert!(
        line.contains("interpolation_s") && line.contains("4 samples"),
        "{line}"
    );
    // zero link lengths: refused by check and by simulate alike
    let q = edit(
        &p,
        "link_lengths_m = [0.3, 0.33]",
        "link_lengths_m = [0.0, 0.33]",
    );
    for cmd in [
        vec!["protocol", "check", q.to_str().unwrap()],
        vec![
            "simulate",
            q.to_str().unwrap(),
            "-o",
            d.path().join("p.csv").to_str().unwrap(),
        ],
    ] {
        let line = one_line_error(&limpid(&cmd)).to_string();
        assert!(
            line.contains("key link_lengths_m: expected a positive number, found 0"),
            "{line}"
        );
    }
}

#[test]
fn huge_counts_and_rates_are_refused_not_allocated() {
    let d = tempfile::tempdir().unwrap();
    let p = preset(d.path(), "artemiadis-3d");
    for (from, to, says) in [
        (
            "count = 16",
            "count = 9223372036854775807",
            "expected at most",
        ),
        ("count = 16", "count = 1000000000", "expected at most"),
        (
            "sample_rate_hz = 500.0",
            "sample_rate_hz = inf",
            "expected a finite number",
        ),
        (
            "sample_rate_hz = 500.0",
            "sample_rate_hz = 1e308",
            "expected at most",
        ),
        (
            "centre_out_s = 3.0",
            "centre_out_s = 1e308",
            "expected at most",
        ),
        ("centre_out_s = 3.0", "centre_out_s = 90000.0", "samples"),
    ] {
        let q = edit(&p, from, to);
        let start = std::time::Instant::now();
        let line = one_line_error(&limpid(&["protocol", "check", q.to_str().unwrap()])).to_string();
        assert!(line.contains(says), "{to}: {line}");
        assert!(
            start.elapsed().as_secs() < 10,
            "{to}: {:?}",
            start.elapsed()
        );
    }
    // settings files: a device is refused before it is read
    let line = one_line_error(&limpid(&["protocol", "check", "/dev/zero"])).to_string();
    assert!(line.contains("not a regular file"), "{line}");
    let line = one_line_error(&limpid(&["estimate", "linear", "/dev/zero"])).to_string();
    assert!(line.contains("not a regular file"), "{line}");
}

#[test]
fn json_to_a_full_stdout_is_one_line_and_exit_2() {
    let rec = examples("planar").join("ex_joint_180.csv");
    let full = std::fs::File::options().write(true).open("/dev/full");
    let Ok(full) = full else {
        return; // no /dev/full on this system
    };
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_limpid"))
        .args(["estimate", "linear", rec.to_str().unwrap(), "--json"])
        .stdout(full)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_eq!(
        stderr.trim_end(),
        "limpid: cannot write the output to standard output: No space left on device (os error 28)"
    );
}

/// A 500 Hz 3-D recording of `minutes` of seed-000-like trials as Parquet.
fn long_recording(path: &Path, minutes: usize, huge_at: Option<usize>) {
    let fs = 500.0;
    let per = 1600; // 0.2 s rest + 3 s motion
    let trials = minutes * 60 * 500 / per;
    let n = trials * per;
    let mut cols: Vec<Vec<f64>> = (0..8).map(|_| Vec::with_capacity(n)).collect();
    let mut seed = 0x2545f4914f6cdd1du64;
    let mut noise = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for k in 0..trials {
        let dir = [(k as f64).cos(), (k as f64).sin(), 0.3];
        for i in 0..per {
            let tau = ((i as f64 - 100.0) / 1500.0).clamp(0.0, 1.0);
            let s = 0.03 * (3.0 * tau * tau - 2.0 * tau.powi(3));
            cols[0].push((k * per + i) as f64 / fs);
            for a in 0..3 {
                let x = [0.4, 0.0, 0.0][a] + dir[a] * s;
                cols[1 + a].push(x + 2e-5 * noise());
                cols[4 + a].push([300.0, 500.0, 700.0][a] * dir[a] * s + 0.1 * noise());
            }
            cols[7].push(k as f64);
        }
    }
    if let Some(i) = huge_at {
        cols[1][i] = 1e307;
    }
    let names = ["t", "x", "y", "z", "fx", "fy", "fz", "trial"];
    // through Recording::new would refuse the huge value: write columns directly
    let rec = limpid_core::Recording::new(
        path,
        names.iter().map(|s| s.to_string()).collect(),
        cols.iter()
            .map(|c| {
                c.iter()
                    .map(|v| if v.abs() > 1e300 { 0.0 } else { *v })
                    .collect()
            })
            .collect(),
        1,
    )
    .unwrap();
    let mut rec = rec;
    rec.set_column("x", cols[1].clone()).unwrap();
    limpid_io::write_recording(&rec, path).unwrap();
}

#[test]
fn a_60_minute_recording_with_one_1e307_sample_is_answered_at_once() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("long.parquet");
    long_recording(&p, 60, Some(1_000_001));
    let start = std::time::Instant::now();
    let out = limpid(&["estimate", "linear", p.to_str().unwrap(), "--json"]);
    let took = start.elapsed();
    let line = one_line_error(&out);
    assert_eq!(
        line,
        format!(
            "limpid: {}: row 1000002, column x: implausible value 1e307: limpid accepts magnitudes up to 100 m in this column (SI units, docs/src/format.md)",
            p.display()
        )
    );
    assert!(out.stdout.is_empty());
    // measured, not a timing assertion (README: about 0.2 s); a hang guard only
    println!("60-minute recording with one 1e307 answered in {took:?}");
    assert!(took.as_secs() < 30);
}

#[test]
fn a_study_keeps_its_good_recordings_and_writes_no_nan_or_nothing_at_all() {
    let d = tempfile::tempdir().unwrap();
    let ex = examples("cocontraction");
    let bad = d.path().join("bad.csv");
    let text = std::fs::read_to_string(ex.join("ex_config7.csv")).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut cells: Vec<String> = lines[500].split(',').map(String::from).collect();
    cells[4] = "1e308".into(); // fx
    lines[500] = cells.join(",");
    std::fs::write(&bad, lines.join("\n") + "\n").unwrap();
    let entry = |s: &str, file: &Path, mvc: &Path| {
        format!(
            "[[recording]]\nsubject = \"{s}\"\nconfiguration = \"7\"\nfile = \"{}\"\nmvc = \"{}\"\n\n",
            file.display(),
            mvc.display()
        )
    };
    let manifest = d.path().join("study.toml");
    std::fs::write(
        &manifest,
        format!(
            "[study]\nname = \"hostile\"\n\n{}{}",
            entry(
                "1",
                &ex.join("ex_config7.csv"),
                &ex.join("ex_config7.mvc.csv")
            ),
            entry("2", &bad, &ex.join("ex_config7.mvc.csv"))
        ),
    )
    .unwrap();
    let out_dir = d.path().join("tables");
    let out = limpid(&[
        "study",
        "run",
        manifest.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(
        out.stdout.contains("1 of 2 recordings processed"),
        "{}",
        out.stdout
    );
    assert!(
        out.stdout
            .contains("row 501, column fx: implausible value 1e308"),
        "{}",
        out.stdout
    );
    for f in ["tables.csv", "rotation.csv", "tables.md", "study.json"] {
        let text = std::fs::read_to_string(out_dir.join(f)).unwrap();
        assert!(
            !text.contains("NaN") && !text.contains("null"),
            "{f}: {text}"
        );
    }
    // nothing processable: an error and no tables at all
    let only_bad = d.path().join("bad-study.toml");
    std::fs::write(
        &only_bad,
        format!(
            "[study]\nname = \"bad\"\n\n{}",
            entry("2", &bad, &ex.join("ex_config7.mvc.csv"))
        ),
    )
    .unwrap();
    let none = d.path().join("none");
    let line = one_line_error(&limpid(&[
        "study",
        "run",
        only_bad.to_str().unwrap(),
        "--out",
        none.to_str().unwrap(),
    ]))
    .to_string();
    assert!(
        line.contains("no recording could be processed (nothing written)"),
        "{line}"
    );
    assert!(!none.join("tables.csv").exists());
}

#[test]
fn corrupt_mat_files_print_one_line_and_nothing_on_stdout() {
    let d = tempfile::tempdir().unwrap();
    let whole = std::fs::read(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../io/tests/fixtures/small_v7.mat"),
    )
    .unwrap();
    // corrupt the compressed stream of each variable in turn
    for at in [200, 400, 1000, 3000, 9000] {
        let mut b = whole.clone();
        for k in 0..16 {
            b[at + k] ^= 0x5a;
        }
        let p = d.path().join(format!("c{at}.mat"));
        std::fs::write(&p, b).unwrap();
        let out = limpid(&["estimate", "linear", p.to_str().unwrap(), "--json"]);
        if out.code == 0 {
            let v: serde_json::Value =
                serde_json::from_str(&out.stdout).expect("stdout is only the JSON");
            assert!(v.is_object());
        } else {
            one_line_error(&out);
            assert!(out.stdout.is_empty(), "{}", out.stdout);
        }
    }
}

#[test]
fn a_look_alike_header_is_said_not_ignored() {
    let d = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(examples("cartesian_slow").join("ex_cubic.csv")).unwrap();
    let p = d.path().join("cyrillic.csv");
    std::fs::write(&p, text.replacen("t,x,", "t,\u{445},", 1)).unwrap();
    let out = limpid(&["estimate", "linear", p.to_str().unwrap()]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr
            .contains("looks like \"x\" written with non-Latin letters"),
        "{}",
        out.stderr
    );
    assert!(
        out.stderr.contains("has force fx but no position x"),
        "{}",
        out.stderr
    );
}

#[test]
fn a_planar_estimate_of_3d_data_is_refused_not_silently_flattened() {
    let rec = examples("cartesian_slow").join("ex_cubic.csv");
    let out = limpid(&[
        "estimate",
        "planar",
        rec.to_str().unwrap(),
        "--link-lengths",
        "0.3,0.33",
    ]);
    let line = one_line_error(&out);
    assert!(
        line.contains("the end point moves in z") && line.contains("estimate linear"),
        "{line}"
    );
}

#[test]
fn methods_refuse_data_they_cannot_use_and_name_what_is_missing() {
    let d = tempfile::tempdir().unwrap();
    // co-contraction without EMG: the index cannot be computed
    let src = std::fs::read_to_string(examples("cocontraction").join("ex_config4.csv")).unwrap();
    let no_emg: String = src
        .lines()
        .map(|l| l.split(',').take(9).collect::<Vec<_>>().join(",") + "\n")
        .collect();
    let rec = d.path().join("no_emg.csv");
    std::fs::write(&rec, no_emg).unwrap();
    let mvc = examples("cocontraction").join("ex_config4.mvc.csv");
    let out = limpid(&[
        "estimate",
        "cocontraction",
        rec.to_str().unwrap(),
        "--mvc",
        mvc.to_str().unwrap(),
    ]);
    let line = one_line_error(&out);
    assert!(
        line.contains("no_emg.csv") && line.contains("emg_"),
        "{line}"
    );
    // stochastic without the commanded inputs: the spectra Z = T R^-1 need them
    let rec = examples("cartesian_slow").join("ex_cubic.csv");
    let out = limpid(&["estimate", "stochastic", rec.to_str().unwrap()]);
    let line = one_line_error(&out);
    assert!(line.contains("missing required column ux"), "{line}");
}

/// A path that is not UTF-8 (legal on Linux) is read, and named in the
/// result's `run` block lossily; it never panics.
#[cfg(unix)]
#[test]
fn a_recording_path_that_is_not_utf8_is_read_and_named() {
    use std::os::unix::ffi::OsStrExt;
    let dir = tempfile::tempdir().unwrap();
    let name = std::ffi::OsStr::from_bytes(b"bad\xff.csv");
    let path = dir.path().join(name);
    std::fs::copy(examples("cartesian_slow").join("ex_cubic.csv"), &path).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_limpid"))
        .args([
            "estimate".as_ref(),
            "linear".as_ref(),
            path.as_os_str(),
            "--json".as_ref(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let named = doc["run"]["inputs"][0]["path"].as_str().unwrap();
    assert!(named.ends_with("bad\u{fffd}.csv"), "{named}");
}

#[test]
fn a_study_refuses_one_recording_listed_twice() {
    // listed again under two more subjects it was counted as four subjects with sd 0 (issue 36)
    let d = tempfile::tempdir().unwrap();
    let ex = examples("cocontraction");
    let (file, mvc) = (ex.join("ex_config7.csv"), ex.join("ex_config7.mvc.csv"));
    let manifest = d.path().join("study.toml");
    let entries: String = ["1", "1", "2", "3"]
        .iter()
        .enumerate()
        .map(|(i, s)| {
            format!(
                "[[recording]]\nsubject = \"{s}\"\nconfiguration = \"{}\"\nfile = \"{}\"\nmvc = \"{}\"\n\n",
                7 + i,
                file.display(),
                mvc.display()
            )
        })
        .collect();
    std::fs::write(&manifest, entries).unwrap();
    let tables = d.path().join("tables");
    let out = limpid(&[
        "study",
        "run",
        manifest.to_str().unwrap(),
        "--out",
        tables.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 2, "{}", out.stdout);
    assert!(
        out.stderr.contains("entries 1 and 2 name the same file")
            && out.stderr.lines().count() == 1,
        "{}",
        out.stderr
    );
}

/// Issue 36: a command's outputs are one set. An output that cannot be
/// written (here: a path under a regular file) leaves none of the others
/// behind: no page without its figures, no tables without their report.
#[test]
fn a_command_writes_all_its_outputs_or_none() {
    let d = tempfile::tempdir().unwrap();
    let blocker = d.path().join("a-file");
    std::fs::write(&blocker, "not a folder").unwrap();
    let under = |name: &str| blocker.join(name).to_str().unwrap().to_string();
    let entries = |p: &Path| std::fs::read_dir(p).map_or(0, |r| r.count());

    // demo: refused before simulating, no output folder
    let demo = d.path().join("demo");
    let out = limpid(&[
        "demo",
        "--out",
        demo.to_str().unwrap(),
        "--report",
        &under("r.html"),
    ]);
    let line = one_line_error(&out);
    assert!(
        line.contains("a-file/r.html") && line.contains("not an existing folder"),
        "{line}"
    );
    assert!(!demo.exists());

    // report --figures under a file: no page either
    let result = d.path().join("result.json");
    let sa3 = examples("stochastic").join("ex_sa3.csv");
    let est = limpid(&["estimate", "stochastic", sa3.to_str().unwrap(), "--json"]);
    assert_eq!(est.code, 0, "{}", est.stderr);
    std::fs::write(&result, &est.stdout).unwrap();
    let page = d.path().join("page.html");
    let out = limpid(&[
        "report",
        result.to_str().unwrap(),
        "-o",
        page.to_str().unwrap(),
        "--figures",
        &under("figures"),
    ]);
    one_line_error(&out);
    assert!(!page.exists());
    // a page whose folder is missing: no figures folder left behind
    let figures = d.path().join("figures");
    let out = limpid(&[
        "report",
        result.to_str().unwrap(),
        "-o",
        d.path().join("missing/page.html").to_str().unwrap(),
        "--figures",
        figures.to_str().unwrap(),
    ]);
    one_line_error(&out);
    assert!(!figures.exists());

    // study run: an unwritable report stops it before any recording; a
    // report that fails only at the end (a folder in its place) leaves no tables
    let sim = d.path().join("sim");
    let out = limpid(&[
        "study",
        "simulate",
        "--subjects",
        "1",
        "--subject",
        "ideal",
        "--out",
        sim.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let manifest = sim.join("study.toml");
    let tables = d.path().join("tables");
    let out = limpid(&[
        "study",
        "run",
        manifest.to_str().unwrap(),
        "--out",
        tables.to_str().unwrap(),
        "--report",
        &under("r.html"),
    ]);
    one_line_error(&out);
    assert!(!tables.exists());
    let busy = d.path().join("busy.html");
    std::fs::create_dir(&busy).unwrap();
    let out = limpid(&[
        "study",
        "run",
        manifest.to_str().unwrap(),
        "--out",
        tables.to_str().unwrap(),
        "--report",
        busy.to_str().unwrap(),
    ]);
    let line = one_line_error(&out);
    assert!(
        line.contains("busy.html") && line.contains("directory"),
        "{line}"
    );
    assert!(!tables.exists(), "{} entries left", entries(&tables));
    // and when every output can be written, all are
    let out = limpid(&[
        "study",
        "run",
        manifest.to_str().unwrap(),
        "--out",
        tables.to_str().unwrap(),
        "--report",
        d.path().join("study.html").to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert_eq!(entries(&tables), 5);
    assert_eq!(entries(&tables.join("recordings")), 7);
    assert!(d.path().join("study.html").exists());
    let hidden: Vec<_> = std::fs::read_dir(&tables)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .collect();
    assert!(hidden.is_empty(), "temporaries left: {hidden:?}");
}
