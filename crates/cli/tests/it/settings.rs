//! Issue 57 through the `limpid` command: every settings error names the
//! flag that sets it (one rule for every method: the flag whose id is the
//! request's field), and the thread count is the caller's without changing
//! a number.

use crate::common::*;

fn without_run(stdout: &str) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_str(stdout).expect("JSON result");
    v.as_object_mut().expect("an object").remove("run");
    v
}

#[test]
fn every_settings_error_names_the_flag_that_sets_it() {
    let rec = examples("cartesian_slow").join("ex_cubic.csv");
    let rec = rec.to_str().unwrap();
    for (args, says) in [
        (
            vec!["estimate", "reflex", rec, "--rate", "10"],
            "invalid --rate: ",
        ),
        (
            vec!["estimate", "reflex", rec, "--max-delay", "2"],
            "invalid --max-delay: ",
        ),
        (
            vec!["estimate", "varying", rec, "--step", "-1"],
            "invalid --step: ",
        ),
        (
            vec![
                "estimate",
                "varying",
                rec,
                "--order",
                "9",
                "--schedule",
                "x",
            ],
            "invalid --order: ",
        ),
        (
            vec!["estimate", "varying", rec, "--grid", "1", "--schedule", "x"],
            "invalid --grid: ",
        ),
        (
            vec!["estimate", "linear", rec, "--cutoff", "-5"],
            "invalid --cutoff: ",
        ),
        (
            vec![
                "window-sweep",
                rec,
                "--link-lengths",
                "0.3,0.3",
                "--from",
                "-1",
            ],
            "invalid --from: ",
        ),
        (
            vec!["spectra", rec, "--inputs", "x", "--outputs", "x"],
            "invalid --inputs/--outputs: ",
        ),
        (
            vec![
                "spectra",
                rec,
                "--inputs",
                "x",
                "--outputs",
                "fx",
                "--period",
                "-1",
            ],
            "invalid --period: ",
        ),
    ] {
        let out = limpid(&args);
        assert_eq!(out.code, 2, "{args:?}: {}", out.stderr);
        assert!(out.stderr.contains(says), "{args:?}: {}", out.stderr);
        assert_eq!(out.stderr.trim_end().lines().count(), 1, "{}", out.stderr);
    }
}

#[test]
fn the_thread_count_is_the_callers_and_changes_no_number() {
    let rec = examples("cartesian_slow").join("ex_cubic.csv");
    let rec = rec.to_str().unwrap();
    let default = limpid(&["estimate", "linear", rec, "--json"]);
    assert_eq!(default.code, 0, "{}", default.stderr);
    let one = limpid(&["--threads", "1", "estimate", "linear", rec, "--json"]);
    assert_eq!(one.code, 0, "{}", one.stderr);
    assert_eq!(without_run(&one.stdout), without_run(&default.stdout));
    let zero = limpid(&["--threads", "0", "estimate", "linear", rec]);
    assert_eq!(zero.code, 2, "{}", zero.stderr);
    assert!(zero.stderr.contains("--threads"), "{}", zero.stderr);
    assert_eq!(zero.stderr.trim_end().lines().count(), 1, "{}", zero.stderr);
}
