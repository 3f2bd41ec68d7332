//! Issue 81: a researcher's first hour. The README's command block runs top
//! to bottom in an empty folder, and each friction of the issue is replayed:
//! a lab's own column names, a MAT struct, time in milliseconds.

use std::path::Path;
use std::process::Command;

/// The lines of the README's first `sh` block under "From the command line".
fn readme_commands() -> Vec<String> {
    let readme = include_str!("../../../../README.md");
    let section = &readme[readme
        .find("## From the command line")
        .expect("the README has its command-line section")..];
    let block = &section[section.find("```sh\n").expect("a sh block") + 6..];
    let block = &block[..block.find("```").expect("the block ends")];
    block
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(String::from)
        .collect()
}

#[test]
fn the_readme_s_command_block_runs_top_to_bottom_in_an_empty_folder() {
    let dir = tempfile::tempdir().unwrap();
    let bin = Path::new(env!("CARGO_BIN_EXE_limpid")).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let commands = readme_commands();
    assert!(commands.len() >= 20, "{commands:?}");
    for line in &commands {
        assert!(line.starts_with("limpid "), "{line}");
        let out = Command::new("sh")
            .arg("-c")
            .arg(line)
            .current_dir(dir.path())
            .env("PATH", &path)
            .env_remove("LIMPID_EXAMPLES")
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "README line failed: {line}\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// The issue's ankle recording with a lab's own names.
fn lab_csv(dir: &Path) -> std::path::PathBuf {
    let protocol = crate::common::preset(dir, "ankle-prbs");
    let rec = dir.join("ankle.csv");
    let out = crate::common::limpid(&[
        "simulate",
        protocol.to_str().unwrap(),
        "-o",
        rec.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let text = std::fs::read_to_string(&rec).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (t, q, tq) = (at("t"), at("q1"), at("tau1"));
    let mut lab = String::from("time_s,angle_rad,torque_Nm\n");
    for l in lines {
        let f: Vec<&str> = l.split(',').collect();
        lab.push_str(&format!("{},{},{}\n", f[t], f[q], f[tq]));
    }
    let path = dir.join("lab.csv");
    std::fs::write(&path, lab).unwrap();
    path
}

#[test]
fn a_lab_s_own_column_names_are_read_in_one_step() {
    let dir = tempfile::tempdir().unwrap();
    let lab = lab_csv(dir.path());
    let lab = lab.to_str().unwrap();
    // the issue's first attempt: the error names the fix
    let out = crate::common::limpid(&[
        "estimate",
        "reflex",
        lab,
        "--position",
        "angle_rad",
        "--torque",
        "torque_Nm",
    ]);
    let err = &out.stderr;
    assert_eq!(out.code, 2, "{err}");
    assert!(err.contains("missing required column t"), "{err}");
    assert!(err.contains("--column t=time_s"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    // ... which works, with the other columns named by the estimator's flags
    let named = crate::common::json(&[
        "estimate",
        "reflex",
        lab,
        "--column",
        "t=time_s",
        "--position",
        "angle_rad",
        "--torque",
        "torque_Nm",
        "--json",
    ]);
    let k = named["intrinsic"]["stiffness"].as_f64().unwrap();
    assert!((k - 80.0).abs() < 4.0, "K {k}");
    // the run block keeps the names, so that `rerun` reads the file again
    assert_eq!(named["run"]["columns"]["t"], "time_s");
    let saved = dir.path().join("named.json");
    std::fs::write(&saved, named.to_string()).unwrap();
    let again = crate::common::json(&["rerun", saved.to_str().unwrap(), "--json"]);
    assert_eq!(
        again["intrinsic"]["stiffness"],
        named["intrinsic"]["stiffness"]
    );
    // or all three by flag
    let all = crate::common::json(&[
        "estimate",
        "reflex",
        lab,
        "--column",
        "t=time_s",
        "--column",
        "q1=angle_rad",
        "--column",
        "tau1=torque_Nm",
        "--json",
    ]);
    assert_eq!(
        all["intrinsic"]["stiffness"],
        named["intrinsic"]["stiffness"]
    );
    // inspect's template, saved as it is, reads the file
    let out = crate::common::limpid(&["inspect", lab, "--map-template"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let template = out.stdout.clone();
    for line in [
        "t = { channel = \"time_s\" }",
        "q1 = { channel = \"angle_rad\" }",
        "tau1 = { channel = \"torque_Nm\" }",
    ] {
        assert!(template.contains(line), "{template}");
    }
    let map = dir.path().join("rig.toml");
    std::fs::write(&map, template).unwrap();
    let mapped = crate::common::json(&[
        "--map",
        map.to_str().unwrap(),
        "estimate",
        "reflex",
        lab,
        "--json",
    ]);
    assert_eq!(
        mapped["intrinsic"]["stiffness"],
        named["intrinsic"]["stiffness"]
    );
    // a bad pair is one line naming the flag
    let out = crate::common::limpid(&["estimate", "reflex", lab, "--column", "t"]);
    let err = &out.stderr;
    assert_eq!(out.code, 2);
    assert!(
        err.contains("--column") && err.contains("NAME=CHANNEL"),
        "{err}"
    );
}

#[test]
fn time_in_milliseconds_is_blamed_on_the_file_not_on_a_flag_nobody_gave() {
    let dir = tempfile::tempdir().unwrap();
    let lab = lab_csv(dir.path());
    let text = std::fs::read_to_string(&lab).unwrap();
    let mut ms = String::from("t,q1,tau1\n");
    for l in text.lines().skip(1) {
        let (t, rest) = l.split_once(',').unwrap();
        ms.push_str(&format!("{},{rest}\n", t.parse::<f64>().unwrap() * 1000.0));
    }
    let path = dir.path().join("ms.csv");
    std::fs::write(&path, ms).unwrap();
    let out = crate::common::limpid(&["estimate", "reflex", path.to_str().unwrap()]);
    let err = &out.stderr;
    assert_eq!(out.code, 2, "{err}");
    assert!(!err.contains("--rate"), "{err}");
    assert!(err.contains("milliseconds"), "{err}");
}

/// Run a tutorial as a newcomer would, in an empty folder: every `sh` block's
/// lines in order (each must succeed), and every output block that follows
/// one (plain or `text`) checked line by line against what those commands
/// printed (lines with `...` are elisions). Python blocks are left to the
/// notebook tests.
fn run_tutorial(name: &str) {
    let path = format!(
        "{}/../../docs/src/tutorials/{name}.md",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let bin = Path::new(env!("CARGO_BIN_EXE_limpid")).parent().unwrap();
    let path_var = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut lines = text.lines();
    let mut printed = String::new();
    let mut blocks = 0;
    while let Some(line) = lines.next() {
        let fence = line.trim_end();
        if !fence.starts_with("```") {
            continue;
        }
        let language = fence.trim_start_matches('`');
        let body: Vec<&str> = lines
            .by_ref()
            .take_while(|l| !l.starts_with("```"))
            .collect();
        match language {
            "sh" => {
                printed.clear();
                for command in body
                    .iter()
                    .map(|l| l.trim())
                    .filter(|l| !l.is_empty() && !l.starts_with('#'))
                {
                    let out = Command::new("sh")
                        .arg("-c")
                        .arg(command)
                        .current_dir(dir.path())
                        .env("PATH", &path_var)
                        .output()
                        .unwrap();
                    let (stdout, stderr) = (
                        String::from_utf8_lossy(&out.stdout),
                        String::from_utf8_lossy(&out.stderr),
                    );
                    assert!(
                        out.status.success(),
                        "{name}.md: `{command}` failed: {stderr}"
                    );
                    printed.push_str(&stdout);
                    printed.push_str(&stderr);
                }
                blocks += 1;
            }
            "" | "text" => {
                for expected in body
                    .iter()
                    .map(|l| l.trim())
                    .filter(|l| !l.is_empty() && !l.contains("..."))
                {
                    assert!(
                        printed.lines().any(|l| l.trim() == expected),
                        "{name}.md quotes a line its commands do not print:\n  {expected}\nthey printed:\n{printed}"
                    );
                }
            }
            _ => {}
        }
    }
    assert!(blocks > 0, "{name}.md has no sh block");
}

#[test]
fn the_reflex_tutorial_runs_and_prints_what_it_says() {
    run_tutorial("reflex");
}

#[test]
fn the_stochastic_tutorial_runs_and_prints_what_it_says() {
    run_tutorial("stochastic");
}

#[test]
fn the_cocontraction_tutorial_runs_and_prints_what_it_says() {
    run_tutorial("cocontraction");
}

#[test]
fn the_endpoint_3d_tutorial_runs_and_prints_what_it_says() {
    run_tutorial("endpoint-3d");
}

#[test]
fn the_planar_tutorial_runs_and_prints_what_it_says() {
    run_tutorial("planar");
}

#[test]
fn the_walking_tutorial_runs_and_prints_what_it_says() {
    run_tutorial("walking");
}

#[test]
fn help_names_what_the_readme_names() {
    // the README says `reproduce artemiadis2010`; --help said 000, 001, 003, 004
    let help = crate::common::limpid(&["reproduce", "--help"]);
    for name in ["artemiadis2010", "patel2013", "lakatos2011", "park2011"] {
        assert!(help.stdout.contains(name), "{name}: {}", help.stdout);
    }
    let top = crate::common::limpid(&["--help"]);
    assert!(top.stdout.contains("artemiadis2010"), "{}", top.stdout);
}

#[test]
fn a_parameter_varying_file_sent_to_the_ensemble_names_its_schedule() {
    // one repetition with an operating-point column: the error says --schedule sv
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("t,q1,tau1,sv,trial\n");
    for i in 0..3000 {
        let t = i as f64 / 1000.0;
        let q = 0.01 * (7.0 * t).sin() + 0.003 * (31.0 * t).sin();
        text.push_str(&format!("{t},{q},{},{},1\n", 50.0 * q, 0.1 * t));
    }
    let path = dir.path().join("pv.csv");
    std::fs::write(&path, text).unwrap();
    let out = crate::common::limpid(&["estimate", "varying", path.to_str().unwrap()]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("--schedule sv"), "{}", out.stderr);
    assert_eq!(out.stderr.trim().lines().count(), 1, "{}", out.stderr);
}
