//! Helpers shared by the CLI tests.
#![allow(dead_code, unused_imports)]

use std::process::Command;

use serde_json::Value;

pub use limpid_testkit::{
    example_sets, examples, mat, outside_examples, read_json, real_data, rel_err,
};

/// A result document (CLI `--json` output or a written JSON file) as the
/// typed result the report renders.
pub fn document(v: &Value) -> limpid_analysis::result::Estimate {
    limpid_analysis::result::Document::from_json("test result", &v.to_string())
        .unwrap_or_else(|e| panic!("{e}"))
        .estimate
}

pub struct Output {
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

pub fn limpid(args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_limpid"))
        .args(args)
        .output()
        .expect("limpid runs");
    Output {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// The output of a `--json` command; a result document (it has a `schema`
/// key) is validated against the committed JSON Schema on the way.
pub fn json(args: &[&str]) -> Value {
    let out = limpid(args);
    assert_eq!(out.code, 0, "limpid {args:?} failed: {}", out.stderr);
    let v: Value = serde_json::from_str(&out.stdout).expect("valid JSON");
    if v.get("schema").is_some() {
        validate(&v);
    }
    v
}

/// The committed schema of result documents (`schema/`), compiled once.
fn validator() -> &'static jsonschema::Validator {
    static VALIDATOR: std::sync::OnceLock<jsonschema::Validator> = std::sync::OnceLock::new();
    VALIDATOR.get_or_init(|| {
        let schema = read_json(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../schema/limpid-result.v1.schema.json"
        ));
        jsonschema::validator_for(&schema).expect("the committed schema compiles")
    })
}

/// Assert that `v` is a valid result document.
pub fn validate(v: &Value) {
    let errors: Vec<String> = validator()
        .iter_errors(v)
        .take(5)
        .map(|e| format!("{e} (at {})", e.instance_path))
        .collect();
    assert!(
        errors.is_empty(),
        "the result does not match schema/limpid-result.v1.schema.json:\n{}",
        errors.join("\n")
    );
}

/// Headless Chromium (Debian's `chromium`, installed by .ci/run) with the
/// flags this machine needs (no sandbox as root, no background networking on a
/// closed network, console messages on stderr) and a fresh profile, kept alive
/// by the returned directory; then `url` with `extra` flags. Returns stdout, stderr.
pub fn chromium(url: &str, extra: &[String]) -> (String, String) {
    let binary = ["/usr/bin/chromium", "/usr/bin/chromium-browser"]
        .into_iter()
        .find(|p| std::path::Path::new(p).exists())
        .expect(
            "headless Chromium is needed for this test: apt-get install chromium (.ci/run does)",
        );
    let profile = tempfile::tempdir().unwrap();
    let out = Command::new(binary)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--enable-logging=stderr",
            "--v=0",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .args(extra)
        .arg(url)
        .output()
        .expect("chromium runs");
    (
        String::from_utf8_lossy(&out.stdout).to_string(),
        String::from_utf8_lossy(&out.stderr).to_string(),
    )
}

/// A preset's protocol from `protocol new`, written to `dir` as `NAME.toml`.
pub fn preset(dir: &std::path::Path, name: &str) -> std::path::PathBuf {
    let path = dir.join(format!("{name}.toml"));
    let out = limpid(&[
        "protocol",
        "new",
        "--preset",
        name,
        "-o",
        path.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    path
}
