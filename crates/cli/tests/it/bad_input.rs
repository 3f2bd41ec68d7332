//! Every class of bad input: a one-line error naming file, row and column,
//! exit status 2, never a panic (issue 2). Messages are pinned exactly.

use crate::common::*;

use std::path::PathBuf;

fn write(dir: &tempfile::TempDir, name: &str, content: &str) -> PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, content).unwrap();
    p
}

/// A valid 1-DoF recording body (t, q1, tau1) of `n` rows at 1 kHz.
fn rows(n: usize) -> String {
    let mut s = String::from("t,q1,tau1\n");
    for i in 0..n {
        let t = i as f64 * 0.001;
        let q = 0.01 * (7.0 * t).sin() + 0.004 * (23.0 * t).sin();
        s.push_str(&format!("{t:.3},{q},{}\n", 50.0 * q));
    }
    s
}

fn fails_with(path: &std::path::Path, extra: &[&str], expected: &str) {
    let mut args = vec!["estimate", "linear", path.to_str().unwrap()];
    args.extend_from_slice(extra);
    let out = limpid(&args);
    assert_eq!(
        out.code, 2,
        "exit code for {expected:?}; stderr {}",
        out.stderr
    );
    let line = out.stderr.trim_end();
    assert_eq!(line.lines().count(), 1, "one line: {line}");
    let want = format!("limpid: {}: {expected}", path.display());
    assert_eq!(line, want);
    assert!(out.stdout.is_empty());
}

#[test]
fn missing_required_column() {
    let d = tempfile::tempdir().unwrap();
    let p = write(&d, "r.csv", &rows(50).replace("tau1", "torque"));
    fails_with(&p, &[], "missing required column tau1 (torque paired with joint angle q1); found columns: t,q1,torque");
}

#[test]
fn non_numeric_cell() {
    let d = tempfile::tempdir().unwrap();
    let body = rows(50);
    let mut lines: Vec<String> = body.lines().map(String::from).collect();
    lines[3] = "0.002,n/a,0.1".into();
    let p = write(&d, "r.csv", &(lines.join("\n") + "\n"));
    fails_with(
        &p,
        &[],
        "row 4, column q1: expected a number, found \"n/a\"",
    );
}

#[test]
fn nan_and_infinity() {
    let d = tempfile::tempdir().unwrap();
    for (cell, shown) in [("NaN", "NaN"), ("inf", "inf"), ("-Infinity", "-inf")] {
        let body = rows(50);
        let mut lines: Vec<String> = body.lines().map(String::from).collect();
        lines[10] = format!("0.009,0.001,{cell}");
        let p = write(&d, "r.csv", &(lines.join("\n") + "\n"));
        fails_with(
            &p,
            &[],
            &format!("row 11, column tau1: expected a finite number, found {shown}"),
        );
    }
}

#[test]
fn empty_file_and_header_only() {
    let d = tempfile::tempdir().unwrap();
    let p = write(&d, "empty.csv", "");
    fails_with(
        &p,
        &[],
        "the file is empty; expected a header row and samples",
    );
    let p = write(&d, "header.csv", "t,q1,tau1\n");
    fails_with(&p, &[], "the file has a header row but no samples");
}

#[test]
fn duplicate_column() {
    let d = tempfile::tempdir().unwrap();
    let p = write(&d, "r.csv", "t,q1,tau1,q1\n0,0,0,0\n0.001,0,0,0\n");
    fails_with(
        &p,
        &[],
        "row 1, column q1: duplicate column name (columns 2 and 4)",
    );
}

#[test]
fn time_not_strictly_increasing() {
    let d = tempfile::tempdir().unwrap();
    let body = rows(50);
    let mut lines: Vec<String> = body.lines().map(String::from).collect();
    lines[20] = "0.018,0.001,0.05".into(); // after 0.018: stands still
    let p = write(&d, "r.csv", &(lines.join("\n") + "\n"));
    fails_with(
        &p,
        &[],
        "row 21, column t: time must be strictly increasing, found 0.018 after 0.018",
    );
}

#[test]
fn non_uniform_sampling() {
    let d = tempfile::tempdir().unwrap();
    let body = rows(50);
    let mut lines: Vec<String> = body.lines().map(String::from).collect();
    lines[30] = "0.02905,0.001,0.05".into(); // 1.05 ms after the previous sample, 0.95 ms before the next
    let p = write(&d, "r.csv", &(lines.join("\n") + "\n"));
    fails_with(&p, &[], "row 31, column t: non-uniform sampling, interval 0.001050 s differs from the median 0.001000 s by more than 1 %");
}

#[test]
fn ragged_row() {
    let d = tempfile::tempdir().unwrap();
    let body = rows(50);
    let mut lines: Vec<String> = body.lines().map(String::from).collect();
    lines[5] = "0.004,0.001".into();
    let p = write(&d, "r.csv", &(lines.join("\n") + "\n"));
    fails_with(&p, &[], "row 6: expected 3 cells like the header, found 2");
}

#[test]
fn fewer_samples_than_the_model_needs() {
    let d = tempfile::tempdir().unwrap();
    let p = write(&d, "r.csv", &rows(12));
    fails_with(&p, &["--cutoff", "100"], "12 samples usable for trial 1 (rows 2-13) with zero-phase filtering and differences, but at least 16 are needed");
}

#[test]
fn trial_without_rest_before_onset() {
    let d = tempfile::tempdir().unwrap();
    let mut s = String::from("t,x,fx,trial\n");
    let n = 400;
    for i in 0..2 * n {
        let t = i as f64 * 0.002;
        let k = i % n;
        // trial 1 rests 100 samples first; trial 2 moves from its first sample
        let moving = if i < n { k >= 100 } else { true };
        let x = if moving {
            0.01 * ((k as f64 - if i < n { 100.0 } else { 0.0 }) * 0.01).sin()
        } else {
            0.0
        };
        s.push_str(&format!("{t},{x},{},{}\n", 300.0 * x, 1 + i / n));
    }
    let p = write(&d, "r.csv", &s);
    fails_with(&p, &[], "row 402, column trial: trial 2 has no rest before its perturbation onset (found 0 rest samples, need 10); start each trial at rest");
}

#[test]
fn unreadable_files() {
    let d = tempfile::tempdir().unwrap();
    let missing = d.path().join("absent.csv");
    let out = limpid(&["estimate", "linear", missing.to_str().unwrap()]);
    assert_eq!(out.code, 2);
    assert_eq!(
        out.stderr.trim_end(),
        format!(
            "limpid: {}: No such file or directory (os error 2)",
            missing.display()
        )
    );
    let garbage = write(&d, "bad.parquet", "this is not parquet");
    let out = limpid(&["estimate", "linear", garbage.to_str().unwrap()]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.starts_with(&format!(
            "limpid: {}: not a readable Parquet file",
            garbage.display()
        )),
        "{}",
        out.stderr
    );
    assert_eq!(out.stderr.trim_end().lines().count(), 1);
}

#[test]
fn bad_parameters() {
    let d = tempfile::tempdir().unwrap();
    let p = write(&d, "r.csv", &rows(300));
    let out = limpid(&["estimate", "linear", p.to_str().unwrap(), "--cutoff", "700"]);
    assert_eq!(out.code, 2);
    assert_eq!(
        out.stderr.trim_end(),
        "limpid: invalid --cutoff: expected 0 < cut-off < 500 Hz (Nyquist), found 700 Hz"
    );
    let out = limpid(&["estimate", "linear", p.to_str().unwrap(), "--level", "0.5"]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("missing required column level"),
        "{}",
        out.stderr
    );
    let out = limpid(&[
        "estimate",
        "linear",
        p.to_str().unwrap(),
        "--transform",
        "1,0,0,0,1,0,0,0,-1,0,0,0",
    ]);
    assert_eq!(out.code, 2);
    assert_eq!(
        out.stderr.trim_end(),
        // the field is named by its flag, as every setting's (issue 57)
        "limpid: invalid --transform: the rotation part must be orthonormal with determinant +1"
    );
    // the co-contraction analysis estimates every level: a level filter was ignored without a word
    let out = limpid(&[
        "estimate",
        "cocontraction",
        p.to_str().unwrap(),
        "--mvc",
        p.to_str().unwrap(),
        "--level",
        "0.2",
        "--print-request",
    ]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.starts_with(
            "limpid: invalid --level: the co-contraction analysis estimates every level"
        ),
        "{}",
        out.stderr
    );
}

#[test]
fn motionless_coordinate_is_explained() {
    let d = tempfile::tempdir().unwrap();
    let mut s = String::from("t,q1,tau1\n");
    for i in 0..500 {
        s.push_str(&format!("{},0.1,2.0\n", i as f64 * 0.001));
    }
    let p = write(&d, "r.csv", &s);
    fails_with(&p, &[], "column q1 holds 0.1 in every sample: that coordinate never moves, so its impedance cannot be estimated; leave the column out (1-, 2- and 3-D recordings are read)");
}

#[test]
fn shoulder_posture_with_the_wrong_count_or_a_1_dof_estimate() {
    let d = tempfile::tempdir().unwrap();
    let p = write(&d, "r.csv", &rows(2000));
    for (extra, expected) in [
        ("0.3,0.35,90,30,20", "invalid value '0.3,0.35,90,30,20' for '--shoulder <L1,L2,E,F,A,R>': expected 6 numbers separated by commas, found 5; see --help"),
        ("0.3,0.35,90,30,20,0", "invalid --shoulder: needs a 3-D estimate (x, y, z)"),
    ] {
        let out = limpid(&["estimate", "linear", p.to_str().unwrap(), "--shoulder", extra]);
        assert_eq!(out.code, 2, "{}", out.stderr);
        assert_eq!(out.stderr.trim_end(), format!("limpid: {expected}"));
    }
}

#[test]
fn stochastic_shoulder_posture_that_is_singular_or_a_recording_without_z() {
    let sa3 = examples("stochastic").join("ex_sa3.csv");
    let sa3 = sa3.to_str().unwrap();
    for (extra, expected) in [
        ("0.3,0.35,90,30", "invalid value '0.3,0.35,90,30' for '--shoulder <L1,L2,E,F,A,R>': expected 6 numbers separated by commas, found 4; see --help"),
        // abduction 0: the arm in the sagittal plane, X and Z both follow flexion only
        ("0.3,0.35,90,30,0,0", "invalid --shoulder: at flexion 30 deg, abduction 0 deg the hand's X and Z do not determine the two angles (condition number of J_h"),
        ("-0.3,0.35,90,30,45,0", "invalid --shoulder: upper arm length must be in [0.01, 2] m, found -0.3"),
        ("0.3,1e307,90,30,45,0", "invalid --shoulder: forearm length must be in [0.01, 2] m, found 1e307"),
        ("0.3,0.35,90,30,nan,0", "invalid --shoulder: angles must be finite degrees"),
        // a nanometre arm made J_h numerically singular ("condition number NaN")
        ("1e-9,0.35,90,30,45,0", "invalid --shoulder: upper arm length must be in [0.01, 2] m, found 1e-9"),
    ] {
        let out = limpid(&["estimate", "stochastic", sa3, "--shoulder", extra]);
        assert_eq!(out.code, 2, "{}", out.stderr);
        assert!(out.stderr.starts_with(&format!("limpid: {expected}")), "{}", out.stderr);
        assert_eq!(out.stderr.lines().count(), 1, "{}", out.stderr);
    }
    // a 2-D x, y recording has no Z to turn into flexion and abduction
    let d = tempfile::tempdir().unwrap();
    let mut s = String::from("t,x,y,fx,fy,ux,uy\n");
    for i in 0..5000 {
        let t = i as f64 * 0.001;
        let (a, b) = ((7.0 * t).sin(), (11.0 * t).cos());
        s.push_str(&format!("{t},{},{},{a},{b},{a},{b}\n", 0.01 * a, 0.01 * b));
    }
    let p = write(&d, "xy.csv", &s);
    let out = limpid(&[
        "estimate",
        "stochastic",
        p.to_str().unwrap(),
        "--shoulder",
        "0.3,0.35,90,30,45,0",
    ]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("xy.csv") && out.stderr.contains("column z"),
        "{}",
        out.stderr
    );
}

/// Outputs (issue 36): a folder that is a file is one line, not "File exists
/// (os error 17)"; a link, FIFO or device is written through, never replaced
/// by a regular file; with standard output closed nothing is silently lost.
#[test]
fn output_paths_that_are_not_plain_files_or_folders() {
    let d = tempfile::tempdir().unwrap();
    let file = write(&d, "not-a-folder", "x");
    let out = limpid(&["demo", "--out", file.to_str().unwrap()]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("not-a-folder") && out.stderr.contains("exists and is not a folder"),
        "{}",
        out.stderr
    );
    assert_eq!(out.stderr.trim().lines().count(), 1, "{}", out.stderr);

    // --report through a symbolic link: the target is written, the link stays
    let rec = examples("cartesian_slow").join("ex_cubic.csv");
    let target = d.path().join("real.html");
    let link = d.path().join("link.html");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let out = limpid(&[
        "estimate",
        "linear",
        rec.to_str().unwrap(),
        "--report",
        link.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert!(std::fs::read_to_string(&target).unwrap().contains("<html"));
    // -o /dev/null: written through; the device stays a device
    let out = limpid(&[
        "protocol",
        "new",
        "--preset",
        "artemiadis-3d",
        "-o",
        "/dev/null",
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::metadata("/dev/null")
        .unwrap()
        .file_type()
        .is_char_device());

    // standard output closed: an error, not exit 0 with nothing printed
    use std::os::unix::process::CommandExt;
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_limpid"));
    cmd.args(["estimate", "linear", rec.to_str().unwrap(), "--json"]);
    // SAFETY: only close(2) between fork and exec.
    unsafe {
        cmd.pre_exec(|| {
            libc::close(1);
            Ok(())
        });
    }
    let out = cmd.output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("standard output is closed"), "{stderr}");

    // /dev/null opened read-write, as Python's subprocess.DEVNULL gives it:
    // the output is discarded on purpose, the command succeeds (on Linux,
    // where the closed descriptor is recorded before the runtime reopens it)
    if cfg!(target_os = "linux") {
        let null = std::fs::File::options()
            .read(true)
            .write(true)
            .open("/dev/null")
            .unwrap();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_limpid"))
            .args(["estimate", "linear", rec.to_str().unwrap(), "--json"])
            .stdout(null)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{stderr}");
    }
}

#[test]
fn usage_errors_are_one_line_and_negative_numbers_are_values() {
    let d = tempfile::tempdir().unwrap();
    let p = write(&d, "r.csv", &rows(2000));
    let p = p.to_str().unwrap();
    for (args, expected) in [
        (
            vec!["estimate", "linear", p, "--cutoff", "-5"],
            "invalid --cutoff: expected a positive number, found -5",
        ),
        (
            vec!["estimate", "linear", p, "--cutoff", "abc"],
            "invalid value 'abc' for '--cutoff <HZ>'",
        ),
        (
            vec!["estimate", "linear", p, "--bogus"],
            "unexpected argument '--bogus'",
        ),
        (vec!["estimate", "planar", p], "--link-lengths"),
        (
            vec!["estimate", "reflex", p, "--rate", "-100"],
            "decimated rate",
        ),
    ] {
        let out = limpid(&args);
        assert_eq!(out.code, 2, "{args:?}: {}", out.stderr);
        assert_eq!(
            out.stderr.trim_end().lines().count(),
            1,
            "{args:?}: {}",
            out.stderr
        );
        assert!(out.stderr.starts_with("limpid: "), "{}", out.stderr);
        assert!(out.stderr.contains(expected), "{args:?}: {}", out.stderr);
    }
    // help is still clap's, on stdout, exit 0
    let out = limpid(&["estimate", "linear", "--help"]);
    assert_eq!(out.code, 0);
    assert!(out.stdout.contains("Usage:"), "{}", out.stdout);
}

#[test]
fn an_expected_model_beyond_any_limb_is_refused_not_compared() {
    // 1e308 N/m made phi_T infinite (printed "inf", null in the JSON, exit 0)
    let sa3 = examples("stochastic").join("ex_sa3.csv");
    let d = tempfile::tempdir().unwrap();
    let zero = "[[0,0,0],[0,0,0],[0,0,0]]";
    let huge = "[[1e308,0,0],[0,1e308,0],[0,0,1e308]]";
    let p = write(
        &d,
        "expected.json",
        &format!("{{\"inertia\": {zero}, \"damping\": {zero}, \"stiffness\": {huge}}}"),
    );
    let out = limpid(&[
        "estimate",
        "stochastic",
        sa3.to_str().unwrap(),
        "--expected",
        p.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 2, "{}", out.stdout);
    assert_eq!(out.stderr.lines().count(), 1, "{}", out.stderr);
    assert!(
        out.stderr
            .contains("expected.json: key stiffness: implausible entry 1e308"),
        "{}",
        out.stderr
    );
}
