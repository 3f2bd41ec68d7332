//! An in-process mutation fuzzer on stable Rust (issue 13).
//!
//! Each execution takes an input of the corpus (`corpus/seeds`: small
//! recordings as CSV, Parquet and MAT-files, lab files (XDF, C3D, TDMS,
//! MAT v7.3, MATLAB objects, ROS 2 bags as MCAP and SQLite), protocol TOML files, live
//! datagrams; `corpus/regressions`: inputs that once failed), mutates it
//! (bit flips, byte runs, cuts, and for text the replacement of numbers by
//! extreme values: 1e307, nan, 1e-320, i64::MAX, ...), and runs it through
//! what a user's file would meet: the reader chosen by its extension, then
//! every estimator the columns allow (linear, planar, stochastic, reflex,
//! co-contraction), or the protocol parser and its check, or the datagram
//! decoder and the live processor; a request (`request-*.json`, what flags
//! and Python keywords become) is checked and run on its method's seed
//! recording; a result document (`result-*.json`) is read back and rendered
//! as the HTML report and its figures (issue 36: flags and result documents);
//! a channel map (`map-*.toml`) is applied to the XDF seed, and a list of
//! input and output paths (`*.paths`) is checked and written in a fresh
//! folder, where an input overwritten is a finding (issue 56). A *finding* is a panic, a non-finite or
//! null number in a result, or (in the binary) an execution over 10 s; an
//! input refused with an error is the right answer, not a finding.

use std::path::{Path, PathBuf};

use rand::rngs::StdRng;
use rand::{Rng, RngCore};
use serde_json::Value;

/// What one execution did.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Refused with an error (the contract for bad input).
    Refused,
    /// Accepted, and every result was finite.
    Accepted,
    /// A panic or a non-finite/null number in a result: a bug.
    Finding(String),
}

/// The corpus folder of this crate.
pub fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus")
}

/// Every file of the corpus (seeds and regressions), with its name.
pub fn corpus() -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for sub in ["seeds", "regressions"] {
        let Ok(dir) = std::fs::read_dir(corpus_dir().join(sub)) else {
            continue;
        };
        let mut files: Vec<PathBuf> = dir.filter_map(|e| e.ok().map(|e| e.path())).collect();
        files.sort();
        for p in files {
            if let Ok(bytes) = std::fs::read(&p) {
                let name = p
                    .file_name()
                    .unwrap_or_default()
                    .to_string_lossy()
                    .into_owned();
                out.push((name, bytes));
            }
        }
    }
    out
}

/// The kind of input, from the file name's extension.
fn kind(name: &str) -> &str {
    name.rsplit('.').next().unwrap_or("")
}

/// Run one input, catching panics.
pub fn execute(name: &str, bytes: &[u8]) -> Outcome {
    let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match kind(name) {
        "toml" if name.starts_with("map-") => channel_map(bytes),
        "toml" if name.starts_with("prior-") => design_prior(name, bytes),
        "toml" => protocol(name, bytes),
        "paths" => output_paths(bytes),
        "wire" => datagrams(bytes),
        "xdf" | "c3d" | "tdms" | "mcap" | "db3" => lab_file(name, bytes),
        "mat" if name.starts_with("rig") => lab_file(name, bytes),
        "json" if name.starts_with("request") => request(bytes),
        "json" => result_document(bytes),
        _ => recording(name, bytes),
    }));
    match run {
        Ok(o) => o,
        Err(payload) => Outcome::Finding(format!(
            "panic: {}",
            limpid_core::error::panic_message(payload.as_ref())
        )),
    }
}

/// The first null or non-finite number in `v`, with its path (JSON turns NaN into null).
/// `allowed` lists keys whose null means "absent" by design (documented Options).
fn first_null(v: &Value, path: &str, allowed: &[&str]) -> Option<String> {
    match v {
        Value::Null => {
            let absent = allowed.iter().any(|a| path.ends_with(&format!(".{a}")));
            (!absent).then(|| format!("null at {path}"))
        }
        Value::Number(n) => n
            .as_f64()
            .filter(|f| !f.is_finite())
            .map(|_| format!("non-finite at {path}")),
        Value::Array(a) => a
            .iter()
            .enumerate()
            .find_map(|(i, x)| first_null(x, &format!("{path}[{i}]"), allowed)),
        // a point of a varying estimate that the data do not support has
        // its matrices absent (null) by design
        Value::Object(o) if o.get("identifiable") == Some(&Value::Bool(false)) => None,
        Value::Object(o) => o
            .iter()
            .find_map(|(k, x)| first_null(x, &format!("{path}.{k}"), allowed)),
        _ => None,
    }
}

/// Options that are `None` by design (documented in their types).
const ABSENT_BY_DESIGN: &[&str] = &[
    "equilibrium",
    "variance_inflation",
    "constant",
    "ellipsoid",
    "arm_configuration",
    "shoulder",
    "expected",
    "accuracy",
    "parametric",
    // window sweep: no window trusted, no change within the trials
    "shortest_trusted_ms",
    "impedance_change",
];

fn check(what: &str, v: &impl serde::Serialize) -> Option<String> {
    let value = serde_json::to_value(v).ok()?;
    first_null(&value, what, ABSENT_BY_DESIGN)
}

/// The channel maps of the lab-file seeds (the fixtures of limpid-io).
fn seed_map(name: &str) -> &'static str {
    match kind(name) {
        "xdf" => include_str!("../../io/tests/fixtures/formats/rig_xdf.toml"),
        "c3d" => include_str!("../../io/tests/fixtures/formats/rig_c3d.toml"),
        "tdms" => include_str!("../../io/tests/fixtures/formats/rig_tdms.toml"),
        "mcap" | "db3" => include_str!("../../io/tests/fixtures/formats/rig_bag.toml"),
        "mat" if name.starts_with("rig-mcos") => {
            include_str!("../../io/tests/fixtures/formats/rig_mcos.toml")
        }
        _ => include_str!("../../io/tests/fixtures/formats/rig_mat73.toml"),
    }
}

/// A lab file (XDF, C3D, TDMS, MAT with structs): read, inspected, converted
/// by its seed's channel map, then estimated as any recording. Accepted when
/// the conversion succeeds.
fn lab_file(name: &str, bytes: &[u8]) -> Outcome {
    let path = Path::new(name);
    let Ok(source) = limpid_io::sources::read_source_bytes(path, bytes) else {
        return Outcome::Refused;
    };
    let inspection = limpid_io::inspect::inspect(&source);
    if let Some(map) = &inspection.proposed_map {
        if let Err(e) = limpid_io::map::ChannelMap::parse(map) {
            return Outcome::Finding(format!("the proposed map does not parse ({e}): {map}"));
        }
    }
    let map = limpid_io::map::ChannelMap::parse(seed_map(name)).expect("the seed maps parse");
    match limpid_io::map::apply(&source, &map) {
        Ok(converted) => match estimate_all(&converted.recording).0.into_iter().next() {
            Some(f) => Outcome::Finding(f),
            None => Outcome::Accepted,
        },
        Err(_) => Outcome::Refused,
    }
}

/// A channel map (`map-*.toml`, issue 56): parsed, then applied to the XDF
/// seed and its recording estimated. Accepted when the conversion succeeds.
fn channel_map(bytes: &[u8]) -> Outcome {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return Outcome::Refused;
    };
    let Ok(map) = limpid_io::map::ChannelMap::parse(text) else {
        return Outcome::Refused;
    };
    let xdf: &[u8] = include_bytes!("../corpus/seeds/rig.xdf");
    let source = limpid_io::sources::read_source_bytes(Path::new("rig.xdf"), xdf)
        .expect("the XDF seed reads");
    match limpid_io::map::apply(&source, &map) {
        Ok(converted) => match estimate_all(&converted.recording).0.into_iter().next() {
            Some(f) => Outcome::Finding(f),
            None => Outcome::Accepted,
        },
        Err(_) => Outcome::Refused,
    }
}

/// Output paths against input paths (`*.paths`, issue 56): each line is
/// `in NAME` or `out NAME`, a path inside a fresh folder (`..`, links and
/// absolute paths are taken as written after the folder). Inputs are made
/// as files; when [`limpid_core::files::refuse_overwriting_inputs`] lets the
/// outputs through, each is written, and an input whose bytes then changed
/// is a finding.
fn output_paths(bytes: &[u8]) -> Outcome {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return Outcome::Refused;
    };
    let Ok(dir) = tempfile::tempdir() else {
        return Outcome::Refused;
    };
    let root = dir.path();
    let (mut inputs, mut outputs) = (Vec::new(), Vec::new());
    // a name inside the folder, or none: never absolute, never leaving it
    // through `..` (the fuzzer runs as root: nothing outside may be written)
    let inside = |name: &str| -> Option<PathBuf> {
        let name = name.trim_start_matches('/');
        let ok = !name.is_empty()
            && name.len() <= 200
            && !name.contains('\0')
            && !name.contains('\\')
            && name.split('/').all(|part| part != "..");
        ok.then(|| root.join(name))
    };
    for line in text.lines().take(16) {
        let Some((role, name)) = line.split_once(' ') else {
            continue;
        };
        match role {
            "in" => inputs.extend(inside(name)),
            "out" => outputs.extend(inside(name)),
            "link" => {
                // `link A=B`: A is a symbolic link to B, both inside the folder
                #[cfg(unix)]
                if let Some((a, b)) = name.split_once('=') {
                    if let (Some(a), Some(b)) = (inside(a), inside(b)) {
                        let _ = std::os::unix::fs::symlink(b, a);
                    }
                }
            }
            _ => {}
        }
    }
    for (i, p) in inputs.iter().enumerate() {
        if let Some(parent) = p.parent() {
            let _ = std::fs::create_dir_all(parent);
        }
        let _ = std::fs::write(p, format!("input {i}"));
    }
    let before: Vec<Option<Vec<u8>>> = inputs.iter().map(|p| std::fs::read(p).ok()).collect();
    let ins: Vec<(&Path, &str)> = inputs.iter().map(|p| (p.as_path(), "an input")).collect();
    let outs: Vec<(&Path, &str)> = outputs.iter().map(|p| (p.as_path(), "an output")).collect();
    if limpid_core::files::refuse_overwriting_inputs(&outs, &ins).is_err() {
        return Outcome::Refused;
    }
    for p in &outputs {
        let _ = limpid_core::files::write_file(p, b"output");
    }
    for (p, was) in inputs.iter().zip(&before) {
        if was.is_some() && std::fs::read(p).ok() != *was {
            return Outcome::Finding(format!("input {} was overwritten", p.display()));
        }
    }
    Outcome::Accepted
}

/// The seed recording a method's requests run on (co-contraction: also its MVC).
fn request_recordings(request: &limpid_ident::request::Request) -> Vec<&'static [u8]> {
    use limpid_ident::request::Request;
    let csv: &'static [u8] = match request {
        Request::Linear(_) => include_bytes!("../corpus/seeds/linear3d.csv"),
        Request::Cocontraction(_) => include_bytes!("../corpus/seeds/cocontraction.csv"),
        // walking: a recording of 40 strides with heel strikes and pulses
        Request::Varying(v) if v.event.is_some() => include_bytes!("../corpus/seeds/walk.csv"),
        Request::Planar(_) | Request::WindowSweep(_) | Request::Varying(_) => {
            include_bytes!("../corpus/seeds/joint2.csv")
        }
        Request::Stochastic(_) | Request::Spectra(_) => {
            include_bytes!("../corpus/seeds/stochastic.csv")
        }
        Request::Reflex(_) => include_bytes!("../corpus/seeds/ankle.csv"),
    };
    match request {
        Request::Cocontraction(_) => vec![csv, csv],
        _ => vec![csv],
    }
}

/// A request as JSON: parsed, checked, run on its method's seed recording.
/// Accepted when it runs; the result must be finite and render as a report.
fn request(bytes: &[u8]) -> Outcome {
    let Ok(request) = serde_json::from_slice::<limpid_ident::request::Request>(bytes) else {
        return Outcome::Refused;
    };
    let Ok(checked) = request.check() else {
        return Outcome::Refused;
    };
    let mut recordings = Vec::new();
    for csv in request_recordings(checked.request()) {
        match limpid_io::read_recording_bytes("seed.csv", csv.to_vec()) {
            Ok(r) => recordings.push(r),
            Err(e) => return Outcome::Finding(format!("the seed recording is refused: {e}")),
        }
    }
    match limpid_app::estimate::run(&checked, recordings) {
        Ok(estimated) => {
            let doc = estimated.document;
            if let Some(f) = check("result", &doc) {
                return Outcome::Finding(f);
            }
            match render(&doc.estimate, "") {
                Some(f) => Outcome::Finding(f),
                None => Outcome::Accepted,
            }
        }
        Err(_) => Outcome::Refused,
    }
}

/// A result document as `limpid report` reads it back: accepted documents
/// must render (page and figures) without a panic or a printed NaN.
fn result_document(bytes: &[u8]) -> Outcome {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return Outcome::Refused;
    };
    match limpid_analysis::result::Document::from_json("result.json", text) {
        Ok(doc) => match render(&doc.estimate, text) {
            Some(f) => Outcome::Finding(f),
            None => Outcome::Accepted,
        },
        Err(_) => Outcome::Refused,
    }
}

/// The report of one result, page and figures; a finding when a number
/// shows as NaN or infinite. JSON numbers cannot be either, so a pattern
/// that `input` holds came from its text fields (a warning, a reason) and
/// is not looked for.
fn render(estimate: &limpid_analysis::result::Estimate, input: &str) -> Option<String> {
    let report = limpid_report::build(&[("result".into(), estimate.clone())]);
    let html = limpid_report::to_html(&report);
    let figures = limpid_report::figure_files(&report);
    let shown = |text: &str| {
        ["NaN", "inf<", ">inf", " inf ", "e2147483647"]
            .into_iter()
            .filter(|bad| !input.contains(bad.trim_matches(['<', '>', ' '])))
            .find(|bad| text.contains(bad))
    };
    if let Some(bad) = shown(&html) {
        return Some(format!("the report shows {bad:?}"));
    }
    figures
        .iter()
        .find_map(|(stem, svg)| shown(svg).map(|bad| format!("figure {stem} shows {bad:?}")))
}

fn recording(name: &str, bytes: &[u8]) -> Outcome {
    let Ok(rec) = limpid_io::read_recording_bytes(name, bytes.to_vec()) else {
        return Outcome::Refused;
    };
    let (findings, any) = estimate_all(&rec);
    match findings.into_iter().next() {
        Some(f) => Outcome::Finding(f),
        None if any => Outcome::Accepted,
        None => Outcome::Refused,
    }
}

/// Every estimator the recording's columns allow: the findings, and whether any ran.
fn estimate_all(rec: &limpid_core::Recording) -> (Vec<String>, bool) {
    let rec = rec.clone();
    let mut findings = Vec::new();
    let mut any = false;
    // linear (3-D, planar end-point, joint, rig coordinates)
    let params = limpid_ident::PrepareParams::default();
    if let Ok(prepared) = limpid_ident::prepare(&rec, &params) {
        if let Ok(est) = limpid_ident::fit_linear(&prepared, &limpid_ident::LinearParams::default())
        {
            any = true;
            let result = limpid_analysis::linear::linear_result(&est, &prepared);
            findings.extend(check("linear", &result));
        }
    }
    // planar arm (seed 003)
    if rec.has("q2") || (rec.has("x") && rec.has("y") && !rec.has("z")) {
        use limpid_ident::planar::{fit_planar, prepare_planar, PlanarPrepare};
        let setup = PlanarPrepare::new(0.30, 0.33);
        if let Ok(data) = prepare_planar(&rec, &setup) {
            let all: Vec<usize> = (0..data.trials.len()).collect();
            if let Ok(est) = fit_planar(&data, usize::MAX, None, &all) {
                any = true;
                findings.extend(check("planar", &est));
            }
        }
    }
    // stochastic (seed 004)
    if rec.has("ux") || rec.has("uz") {
        use limpid_ident::stochastic::{estimate_stochastic, StochasticParams};
        let p = StochasticParams::default();
        if let Ok(est) = estimate_stochastic(&rec, &p) {
            any = true;
            findings.extend(check("stochastic", &est));
        }
    }
    // parallel cascade (Kearney et al. 1997) on joint angle and torque
    if rec.has("q1") && rec.has("tau1") {
        use limpid_ident::reflex::{estimate_reflex, ReflexParams};
        if let Ok(est) = estimate_reflex(&rec, &ReflexParams::default()) {
            any = true;
            findings.extend(check("reflex", &est));
        }
    }
    // co-contraction (seed 001), the recording as its own MVC
    if rec.has("level") && rec.names().iter().any(|n| n.starts_with("emg_")) {
        let emg = limpid_analysis::emg::EmgParams::default();
        if let Ok(r) =
            limpid_analysis::cocontraction::estimate_cocontraction(&rec, &rec, &params, &emg)
        {
            any = true;
            findings.extend(check("cocontraction", &r));
        }
    }
    (findings, any)
}

/// A design prior (`prior-endpoint-*`, `prior-planar-*`, `prior-ankle-*`):
/// read and checked as `protocol design` reads it, before any design runs
/// (a design takes seconds; the prior's refusals are what is fuzzed).
fn design_prior(name: &str, bytes: &[u8]) -> Outcome {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return Outcome::Refused;
    };
    let path = Path::new(name);
    let read = if name.starts_with("prior-planar") {
        limpid_app::design::planar::PlanarPrior::from_toml(text, path).map(|_| ())
    } else if name.starts_with("prior-ankle") {
        limpid_app::design::reflex::ReflexPrior::from_toml(text, path).map(|_| ())
    } else {
        limpid_app::design::Prior::from_toml(text, path).map(|_| ())
    };
    match read {
        Ok(()) => Outcome::Accepted,
        Err(_) => Outcome::Refused,
    }
}

fn protocol(name: &str, bytes: &[u8]) -> Outcome {
    let Ok(text) = std::str::from_utf8(bytes) else {
        return Outcome::Refused;
    };
    let Ok(design) = limpid_lab::design::Design::from_toml(text, Path::new(name)) else {
        return Outcome::Refused;
    };
    match limpid_lab::design::check(&design) {
        Ok(report) => match check("check", &report) {
            Some(f) => Outcome::Finding(f),
            None => Outcome::Accepted,
        },
        Err(_) => Outcome::Refused,
    }
}

/// A `.wire` input: datagrams of 2 EMG channels, each prefixed by its u16 length.
fn datagrams(bytes: &[u8]) -> Outcome {
    let mut p = limpid_live::process::Processor::new(2, 1000.0, Some(vec![1.0, 1.0]))
        .expect("a valid processor");
    let mut rest = bytes;
    let mut accepted = false;
    while rest.len() >= 2 {
        let n = u16::from_le_bytes([rest[0], rest[1]]) as usize;
        let take = n.min(rest.len() - 2);
        let d = &rest[2..2 + take];
        rest = &rest[2 + take..];
        if let Ok(s) = limpid_live::wire::decode(d, 2) {
            accepted = true;
            p.update(&s.emg, s.kinematics.as_ref());
        }
    }
    let shown = p.online.estimate();
    let finite = p
        .envelopes
        .iter()
        .chain(&p.activations)
        .all(|v| v.is_finite())
        && (!accepted || p.index.is_finite())
        && shown.is_none_or(|e| {
            e.stiffness
                .iter()
                .chain(&e.stiffness_se)
                .flatten()
                .all(|v| v.is_finite())
                && e.vaf.iter().flatten().all(|v| (0.0..=100.0).contains(v))
        });
    match (finite, accepted) {
        (false, _) => Outcome::Finding("live state not finite after the datagrams".into()),
        (true, true) => Outcome::Accepted,
        (true, false) => Outcome::Refused,
    }
}

/// Numbers a hostile or mistaken file holds.
const EXTREMES: &[&str] = &[
    "1e307",
    "-1e308",
    "1e308",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "-0",
    "0",
    "1e-320",
    "5e-324",
    "9223372036854775807",
    "18446744073709551616",
    "1e400",
    "",
    "x",
    "1,2",
    "1e15",
    "100.0001",
    "0.5",
    "-1",
    "2",
    "1e6",
    "1000000.5",
    "\"nan\"",
    "[]",
    "1e9",
];

/// Mutate `input` 1 to 4 times.
pub fn mutate(rng: &mut StdRng, input: &[u8], text: bool) -> Vec<u8> {
    let mut b = input.to_vec();
    // half the inputs get one mutation, so that many still reach the estimators
    let rounds = if rng.random_bool(0.5) {
        1
    } else {
        rng.random_range(2..=4)
    };
    for _ in 0..rounds {
        let choice = rng.random_range(0..if text { 10 } else { 7 });
        let len = b.len();
        match choice {
            0 if len > 0 => {
                let i = rng.random_range(0..len);
                b[i] ^= 1 << rng.random_range(0..8);
            }
            1 if len > 0 => {
                let i = rng.random_range(0..len);
                b[i] = [0u8, 0xff, 0x7f, 0x80, b'9', b'-', b'.', b'e'][rng.random_range(0..8)];
            }
            2 if len > 1 => {
                let i = rng.random_range(0..len);
                let n = rng.random_range(1..=(len - i).min(64));
                b.drain(i..i + n);
            }
            3 if len > 1 => {
                let i = rng.random_range(0..len);
                let n = rng.random_range(1..=(len - i).min(64));
                let copy: Vec<u8> = b[i..i + n].to_vec();
                let at = rng.random_range(0..=len);
                b.splice(at..at, copy);
            }
            4 if len > 0 => b.truncate(rng.random_range(0..len)),
            5 if len >= 8 => {
                // an extreme f64 bit pattern (binary formats store raw doubles)
                let v: f64 = [1e307, -1e308, f64::NAN, f64::INFINITY, 5e-324, 0.0, 1e15]
                    [rng.random_range(0..7)];
                let i = rng.random_range(0..=len - 8);
                b[i..i + 8].copy_from_slice(&v.to_le_bytes());
            }
            6 if len >= 4 => {
                // a length or count field: an extreme integer
                let v: u32 =
                    [0, 1, u32::MAX, 0x7fff_ffff, 0x8000_0000, 65_535][rng.random_range(0..6)];
                let i = rng.random_range(0..=len - 4);
                b[i..i + 4].copy_from_slice(&v.to_le_bytes());
            }
            7 => replace_number(rng, &mut b),
            8 => {
                // delete, duplicate or swap whole lines
                let mut lines: Vec<Vec<u8>> =
                    b.split(|c| *c == b'\n').map(<[u8]>::to_vec).collect();
                if lines.len() > 2 {
                    let i = rng.random_range(0..lines.len());
                    let j = rng.random_range(0..lines.len());
                    match rng.random_range(0..3) {
                        0 => {
                            lines.remove(i);
                        }
                        1 => {
                            let l = lines[i].clone();
                            lines.insert(j, l);
                        }
                        _ => lines.swap(i, j),
                    }
                    b = lines.join(&b'\n');
                }
            }
            9 => {
                // a header name spelt with a look-alike, or renamed
                let names: [&[u8]; 6] = ["х".as_bytes(), b"level", b"trial", b"fx", b"q1", b"ux"];
                let pick = names[rng.random_range(0..names.len())];
                if let Some(i) = b.iter().position(|c| *c == b',') {
                    b.splice(0..i.min(b.len()), pick.iter().copied());
                }
            }
            _ => {
                let i = rng.random_range(0..=len);
                b.insert(i, rng.next_u32() as u8);
            }
        }
    }
    b
}

/// Replace one number-looking token with an extreme value.
fn replace_number(rng: &mut StdRng, b: &mut Vec<u8>) {
    if b.is_empty() {
        return;
    }
    let start = rng.random_range(0..b.len());
    let Some(s) = (start..b.len()).find(|&i| b[i].is_ascii_digit()) else {
        return;
    };
    let s = (0..s)
        .rev()
        .take_while(|&i| matches!(b[i], b'0'..=b'9' | b'.' | b'-' | b'e' | b'E' | b'+'))
        .last()
        .unwrap_or(s);
    let e = (s..b.len())
        .find(|&i| !matches!(b[i], b'0'..=b'9' | b'.' | b'-' | b'e' | b'E' | b'+'))
        .unwrap_or(b.len());
    let with = EXTREMES[rng.random_range(0..EXTREMES.len())];
    b.splice(s..e, with.bytes());
}

/// True for inputs mutated as text.
pub fn is_text(name: &str) -> bool {
    matches!(kind(name), "csv" | "toml" | "json")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_checker_sees_nulls_and_respects_absent_options() {
        let v = serde_json::json!({"stiffness": [[1.0, null]], "equilibrium": null});
        assert_eq!(
            first_null(&v, "r", ABSENT_BY_DESIGN).as_deref(),
            Some("null at r.stiffness[0][1]")
        );
        let v = serde_json::json!({"equilibrium": null, "k": [1.0]});
        assert!(first_null(&v, "r", ABSENT_BY_DESIGN).is_none());
    }
}
