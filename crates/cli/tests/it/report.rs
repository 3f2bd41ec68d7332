//! The HTML report (issue 7): figure data against committed snapshots, no
//! external URL, and the pages of `limpid demo` and of a stochastic example
//! opened in headless Chromium (Debian's `chromium`, installed by .ci/run).

use crate::common::*;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn example(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// A compact summary of every figure: id, and per trace its name, point count
/// and values at three positions.
fn figure_summary(report: &limpid_report::Report) -> Value {
    let figures: Vec<Value> = report
        .sections
        .iter()
        .flat_map(|s| s.figures.iter())
        .map(|f| {
            let traces: Vec<Value> = f
                .chart
                .series
                .iter()
                .map(|s| {
                    let n = s.y.len();
                    let pick = |i: usize| s.y.get(i).copied().filter(|v| v.is_finite());
                    serde_json::json!({"name": s.name, "points": n, "y": [pick(0), pick(n / 2), pick(n.saturating_sub(1))]})
                })
                .collect();
            serde_json::json!({"id": f.id, "traces": traces})
        })
        .collect();
    serde_json::json!(figures)
}

/// Equal up to a relative 1e-3 in every number (thread scheduling may change
/// the last bits of parallel sums).
fn close(a: &Value, b: &Value, at: &str) {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!(
                (x - y).abs() <= 1e-3 * x.abs().max(y.abs()).max(1e-9),
                "{at}: {x} vs {y}"
            );
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}: lengths");
            for (i, (p, q)) in x.iter().zip(y).enumerate() {
                close(p, q, &format!("{at}[{i}]"));
            }
        }
        (Value::Object(x), Value::Object(y)) => {
            assert_eq!(
                x.keys().collect::<Vec<_>>(),
                y.keys().collect::<Vec<_>>(),
                "{at}: keys"
            );
            for (k, p) in x {
                close(p, &y[k], &format!("{at}.{k}"));
            }
        }
        _ => assert_eq!(a, b, "{at}"),
    }
}

fn check_snapshot(name: &str, got: &Value) {
    let path = example(&format!("tests/snapshots/{name}.json"));
    if std::env::var_os("LIMPID_UPDATE_SNAPSHOTS").is_some() {
        std::fs::write(&path, serde_json::to_string_pretty(got).unwrap()).unwrap();
    }
    let want: Value = read_json(&path);
    close(got, &want, name);
}

#[test]
fn stochastic_report_figure_data_matches_its_snapshot() {
    let est = json(&[
        "estimate",
        "stochastic",
        examples("stochastic").join("ex_sa3.csv").to_str().unwrap(),
        "--expected",
        examples("stochastic")
            .join("ex_sa3.truth.json")
            .to_str()
            .unwrap(),
        "--json",
    ]);
    let report = limpid_report::build(&[("ex_sa3".into(), document(&est))]);
    let summary = figure_summary(&report);
    // 3 x 3 elements x (magnitude, phase), the multiple coherence, 6 partial coherences
    assert_eq!(summary.as_array().unwrap().len(), 18 + 1 + 6);
    for f in summary.as_array().unwrap().iter().take(18) {
        assert_eq!(
            f["traces"].as_array().unwrap().len(),
            5,
            "{}: estimate, its 95 % band (2 lines), fit, expected",
            f["id"]
        );
    }
    // the coherence band encloses the estimate
    for f in report.sections.iter().flat_map(|s| &s.figures) {
        if f.id.starts_with("bode-") {
            let s = &f.chart.series;
            assert_eq!(s[1].name, "95 % band (coherence)");
            for k in 0..s[0].y.len() {
                let (lo, v, hi) = (s[1].y[k], s[0].y[k], s[2].y[k]);
                assert!(
                    lo.is_nan() || (lo <= v && v <= hi),
                    "{} at {} Hz: {lo} <= {v} <= {hi}",
                    f.id,
                    s[0].x[k]
                );
            }
        }
    }
    // seed 004's Bode phase, unwrapped: no jump above 180 degrees between neighbouring points
    for f in report.sections.iter().flat_map(|s| &s.figures) {
        if f.id.starts_with("bode-phase") {
            // estimate, fit and truth drawn in the same turn
            let start = |k: usize| f.chart.series[k].y[0];
            for k in 1..f.chart.series.len() {
                assert!(
                    (start(k) - start(0)).abs() <= 180.0,
                    "{}: {} starts at {} degrees, the estimate at {}",
                    f.id,
                    f.chart.series[k].name,
                    start(k),
                    start(0)
                );
            }
            for series in &f.chart.series {
                for w in series.y.windows(2) {
                    assert!(
                        (w[1] - w[0]).abs() <= 180.0,
                        "{} {}: phase jumps from {} to {} degrees",
                        f.id,
                        series.name,
                        w[0],
                        w[1]
                    );
                }
            }
        }
    }
    check_snapshot("report_ex_sa3", &summary);
}

#[test]
fn report_command_writes_html_without_external_urls_and_svg_figures() {
    let dir = tempfile::tempdir().unwrap();
    let res = dir.path().join("sweep.json");
    let sweep = limpid(&[
        "window-sweep",
        examples("planar")
            .join("ex_joint_180.csv")
            .to_str()
            .unwrap(),
        "--link-lengths",
        "0.28,0.35",
        "--json",
    ]);
    assert_eq!(sweep.code, 0, "{}", sweep.stderr);
    std::fs::write(&res, &sweep.stdout).unwrap();
    let html = dir.path().join("r.html");
    let figs = dir.path().join("figs");
    let out = limpid(&[
        "report",
        res.to_str().unwrap(),
        "-o",
        html.to_str().unwrap(),
        "--figures",
        figs.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let text = std::fs::read_to_string(&html).unwrap();
    assert!(
        !text.contains("src=") && !text.contains("href="),
        "no src/href at all"
    );
    assert!(text.contains("shortest trusted window"));
    let mut names: Vec<String> = std::fs::read_dir(&figs)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let svgs: Vec<&String> = names.iter().filter(|n| n.ends_with(".svg")).collect();
    assert_eq!(
        svgs.len(),
        5,
        "K and D against T_obs, condition number, eigenvalues, symmetry"
    );
    // each also as a PNG at 3 x the journal size (560 x 360 px)
    for svg in svgs {
        let png = std::fs::read(figs.join(svg.replace(".svg", ".png"))).unwrap();
        assert!(png.starts_with(b"\x89PNG"), "{svg}");
        let dim = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
        assert_eq!(
            (dim(&png[16..20]), dim(&png[20..24])),
            (1680, 1080),
            "{svg}"
        );
    }
    assert_eq!(names.len(), 10);
    // seed 003 Fig. 4-5: K against T_obs with the shortest trusted window drawn
    let k = std::fs::read_to_string(figs.join("s1-sweep-k.svg")).unwrap();
    for name in ["K11", "K22", "± 1 SE", "shortest trusted window ("] {
        assert!(
            k.contains(&format!("data-name=\"{name}")),
            "{name} in the K figure"
        );
    }
    // something that is not a result: one line naming the file
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, "{\"hello\": 1}").unwrap();
    let out = limpid(&[
        "report",
        bad.to_str().unwrap(),
        "-o",
        html.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("bad.json: not a limpid result"),
        "{}",
        out.stderr
    );
}

/// Headless Chromium: the DOM after the page's scripts ran, the console, a screenshot.
fn open_in_chromium(page: &Path, shot: &Path) -> (String, String) {
    let url = format!("file://{}?all", page.display());
    let (dom, log) = chromium(&url, &["--dump-dom".into()]);
    chromium(
        &url,
        &[
            format!("--screenshot={}", shot.display()),
            "--window-size=1300,1800".into(),
        ],
    );
    (dom, log)
}

fn no_console_errors(log: &str) {
    for line in log.lines() {
        assert!(
            !(line.contains("CONSOLE")
                || line.contains("Uncaught")
                || line.contains("SyntaxError")),
            "console: {line}"
        );
    }
}

fn screenshot_ok(shot: &Path) {
    let png = std::fs::read(shot).expect("a screenshot was written");
    assert!(
        png.starts_with(b"\x89PNG") && png.len() > 10_000,
        "screenshot {} bytes",
        png.len()
    );
}

#[test]
fn demo_and_stochastic_reports_render_in_headless_chromium() {
    let dir = tempfile::tempdir().unwrap();
    // the demo's report
    let out = limpid(&["demo", "--out", dir.path().to_str().unwrap()]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let page = dir.path().join("report.html");
    let shot = dir.path().join("demo.png");
    let (dom, log) = open_in_chromium(&page, &shot);
    no_console_errors(&log);
    for kind in ["stiffness", "damping", "inertia"] {
        for p in 1..=6 {
            let tag = format!("class=\"ellipsoid\" data-kind=\"{kind}\" data-point=\"S{p}\"");
            assert_eq!(dom.matches(&tag).count(), 1, "{tag}");
        }
    }
    assert_eq!(dom.matches("class=\"ellipsoid\"").count(), 18);
    screenshot_ok(&shot);
    std::fs::copy(&shot, std::env::temp_dir().join("limpid-report-demo.png")).unwrap();

    // a stochastic example's report
    let page = dir.path().join("st.html");
    let out = limpid(&[
        "estimate",
        "stochastic",
        examples("stochastic").join("ex_sa3.csv").to_str().unwrap(),
        "--expected",
        examples("stochastic")
            .join("ex_sa3.truth.json")
            .to_str()
            .unwrap(),
        "--report",
        page.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let shot = dir.path().join("st.png");
    let (dom, log) = open_in_chromium(&page, &shot);
    no_console_errors(&log);
    let magnitude = dom
        .split("<figure id=\"bode-mag-")
        .skip(1)
        .collect::<Vec<_>>();
    assert_eq!(magnitude.len(), 9, "one magnitude panel per element");
    for panel in magnitude {
        let panel = panel.split("</figure>").next().unwrap();
        assert_eq!(
            panel.matches("class=\"trace\"").count(),
            5,
            "estimate, its band (2), fit, expected"
        );
    }
    screenshot_ok(&shot);
    std::fs::copy(
        &shot,
        std::env::temp_dir().join("limpid-report-stochastic.png"),
    )
    .unwrap();
}

#[test]
fn cocontraction_report_has_per_level_ellipsoids_and_tables() {
    let case = examples("cocontraction").join("ex_config4");
    let est = json(&[
        "estimate",
        "cocontraction",
        case.with_extension("csv").to_str().unwrap(),
        "--mvc",
        case.with_extension("mvc.csv").to_str().unwrap(),
        "--json",
    ]);
    let report = limpid_report::build(&[("ex_config4".into(), document(&est))]);
    let s = &report.sections[0];
    // 4 levels side by side, stiffness, damping and inertia each
    assert_eq!(s.ellipsoids.len(), 12);
    let points: std::collections::BTreeSet<_> =
        s.ellipsoids.iter().map(|e| e.point.clone()).collect();
    assert_eq!(
        points.into_iter().collect::<Vec<_>>(),
        ["level 0", "level 0.5", "level 0.75", "level 1"]
    );
    // index table, comparisons, one K table per level
    assert_eq!(s.tables.len(), 2 + 4);
    assert_eq!(s.tables[0].rows.len(), 4);
    assert_eq!(s.tables[1].rows.len(), 3);
    // the verdict quotes each level's index as the estimate gives it
    let index = est["levels"][1]["cocontraction_index"].as_f64().unwrap();
    let quoted = format!("{index:.4} at level 0.5");
    assert!(s.verdict.contains(&quoted), "{quoted} not in {}", s.verdict);
}

#[test]
fn linear_report_draws_measured_against_predicted_force() {
    let est = json(&[
        "estimate",
        "linear",
        examples("cartesian_slow")
            .join("ex_cubic.csv")
            .to_str()
            .unwrap(),
        "--json",
    ]);
    let report = limpid_report::build(&[("ex_cubic".into(), document(&est))]);
    let figs = &report.sections[0].figures;
    let ids: Vec<&str> = figs.iter().map(|f| f.id.as_str()).collect();
    assert_eq!(ids, ["fit-x", "fit-y", "fit-z"]);
    for (a, f) in figs.iter().enumerate() {
        let (measured, predicted) = (&f.chart.series[0].y, &f.chart.series[1].y);
        assert!(measured.len() <= 1500 && measured.len() > 100);
        // the traces are the fit's own: their VAF is close to the reported one
        let m = measured.iter().sum::<f64>() / measured.len() as f64;
        let var_f: f64 = measured.iter().map(|v| (v - m).powi(2)).sum();
        let e: Vec<f64> = measured.iter().zip(predicted).map(|(y, p)| y - p).collect();
        let me = e.iter().sum::<f64>() / e.len() as f64;
        let var_e: f64 = e.iter().map(|v| (v - me).powi(2)).sum();
        let vaf = 100.0 * (1.0 - var_e / var_f);
        let reported = est["fit"]["vaf"][a].as_f64().unwrap();
        assert!(
            (vaf - reported).abs() < 1.0,
            "axis {a}: VAF of the traces {vaf}, reported {reported}"
        );
    }
}

#[test]
fn study_run_writes_a_report_with_every_configuration() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study");
    assert_eq!(
        limpid(&["study", "simulate", "--out", study.to_str().unwrap()]).code,
        0
    );
    let html = dir.path().join("study.html");
    let out = limpid(&[
        "study",
        "run",
        study.join("study.toml").to_str().unwrap(),
        "--out",
        dir.path().join("out").to_str().unwrap(),
        "--report",
        html.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let text = std::fs::read_to_string(&html).unwrap();
    // 7 configurations x 4 levels in the table, one k1 trace per configuration
    let k1 = text
        .split("<figure id=\"study-k1\">")
        .nth(1)
        .unwrap()
        .split("</figure>")
        .next()
        .unwrap();
    assert_eq!(k1.matches("class=\"trace\"").count(), 7);
    assert!(text.contains("28 recordings analysed, 0 failed; 7 configurations"));

    // one mean stiffness ellipsoid per configuration and level (seed 001 Fig. 5):
    // the mean over the subjects' matrices, with eigenvalues of its own
    let result = read_json(&dir.path().join("out").join("study.json"));
    let row = &result["levels"][5];
    let (config, level) = (row["configuration"].clone(), row["level"].as_f64().unwrap());
    let mut sum = nalgebra::DMatrix::<f64>::zeros(3, 3);
    let mut subjects = 0.0;
    for r in result["recordings"].as_array().unwrap() {
        if r["configuration"] != config {
            continue;
        }
        for l in r["result"]["levels"].as_array().unwrap() {
            if l["level"].as_f64() == Some(level) {
                sum += &mat(&l["stiffness"]).0;
                subjects += 1.0;
            }
        }
    }
    assert_eq!(subjects, row["subjects"].as_f64().unwrap());
    let mean = mat(&row["stiffness"]);
    for (m, s) in mean.iter().zip(sum.iter()) {
        assert!((m - s / subjects).abs() < 1e-9 * s.abs().max(1.0));
    }
    let eig: f64 = row["ellipsoid"]["eigenvalues"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .sum();
    let trace = mean.trace();
    assert!(
        (eig - trace).abs() < 1e-9 * trace,
        "eigenvalues sum {eig}, trace {trace}"
    );
    let report = limpid_report::build(&[("study".into(), document(&result))]);
    let views = &report.sections[0].ellipsoids;
    assert_eq!(views.len(), 28);
    assert!(views.iter().all(|e| e.kind == "stiffness"));
    assert!(text.contains("ellipsoid-data"));
}

/// Issue 20: units instead of "SI", values rounded to their standard error,
/// warnings grouped across start points, "n/i" for unidentified matrices.
#[test]
fn demo_report_reads_like_a_paper_table() {
    let dir = tempfile::tempdir().unwrap();
    let out = limpid(&["demo", "--out", dir.path().to_str().unwrap()]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let demo: Value = read_json(&dir.path().join("demo.json"));
    let report = limpid_report::build(&[("demo".into(), document(&demo))]);
    let s = &report.sections[0];
    // one line per kind of warning, naming the start points
    assert!(s.warnings.len() <= 6, "{:#?}", s.warnings);
    assert!(
        s.warnings.iter().any(|w| w.starts_with("S1-S6: ")),
        "{:#?}",
        s.warnings
    );
    // inertia is flagged not identifiable in every start point: no error percentage for it
    let errors = &s.tables[0];
    for row in &errors.rows {
        let verdict = &row[4];
        if verdict.contains("inertia NOT identifiable") {
            assert_eq!(row[3], "n/i", "{row:?}");
        } else {
            assert_ne!(row[3], "n/i", "{row:?}");
        }
    }
    // K tables: unit in the caption, each cell "value ± se (true t)" with a 2-digit SE
    let k = s
        .tables
        .iter()
        .find(|t| t.caption.starts_with("S1: K"))
        .expect("S1's K table");
    assert!(k.caption.contains("N/m"), "{}", k.caption);
    for cell in k.rows.iter().flat_map(|r| r.iter().skip(1)) {
        let (value, rest) = cell.split_once(" ± ").expect(cell);
        let se = rest.split(' ').next().unwrap();
        let digits = |t: &str| t.split('.').nth(1).map_or(0, str::len);
        assert_eq!(
            digits(value),
            digits(se),
            "{cell}: value and SE to one decimal place"
        );
        let significant: String = se
            .chars()
            .filter(char::is_ascii_digit)
            .collect::<String>()
            .trim_start_matches('0')
            .to_string();
        assert_eq!(
            significant.len(),
            2,
            "{cell}: two significant digits of the SE"
        );
    }
    let html = limpid_report::to_html(&report);
    assert!(
        !html.contains("(SI)") && !html.contains(", SI)"),
        "a unit written as SI"
    );
}

/// The VAF (%) of `predicted` as a model of `measured`.
fn vaf(measured: &[f64], predicted: &[f64]) -> f64 {
    let var = |v: &[f64]| {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        v.iter().map(|x| (x - m).powi(2)).sum::<f64>()
    };
    let e: Vec<f64> = measured.iter().zip(predicted).map(|(y, p)| y - p).collect();
    100.0 * (1.0 - var(&e) / var(measured))
}

/// Issue 20: the planar, window-sweep, co-contraction, study and stochastic
/// reports each open in Chromium without a script error, with the figures a
/// reader of the seeds expects; screenshots are kept in the temp folder
/// (`limpid-report-<kind>.png`) for a person to look at. (Long: one browser
/// session over every kind, each kind's expected figures listed in turn.)
#[test]
fn every_kind_of_report_renders_with_its_figures() {
    let dir = tempfile::tempdir().unwrap();
    let d = |name: &str| dir.path().join(name);
    let joint = examples("planar").join("ex_joint_180.csv");
    let cc = examples("cocontraction").join("ex_config4");
    let study = d("study");
    assert_eq!(
        limpid(&[
            "study",
            "simulate",
            "--subjects",
            "2",
            "--out",
            study.to_str().unwrap()
        ])
        .code,
        0
    );
    let runs: Vec<(&str, Vec<String>)> = vec![
        (
            "planar",
            [
                "estimate",
                "planar",
                joint.to_str().unwrap(),
                "--link-lengths",
                "0.28,0.35",
                "--report",
            ]
            .map(String::from)
            .to_vec(),
        ),
        (
            "sweep",
            [
                "window-sweep",
                joint.to_str().unwrap(),
                "--link-lengths",
                "0.28,0.35",
                "--report",
            ]
            .map(String::from)
            .to_vec(),
        ),
        (
            "cocontraction",
            vec![
                "estimate".into(),
                "cocontraction".into(),
                cc.with_extension("csv").display().to_string(),
                "--mvc".into(),
                cc.with_extension("mvc.csv").display().to_string(),
                "--report".into(),
            ],
        ),
        (
            "study",
            vec![
                "study".into(),
                "run".into(),
                study.join("study.toml").display().to_string(),
                "--out".into(),
                d("out").display().to_string(),
                "--report".into(),
            ],
        ),
        (
            "stochastic",
            vec![
                "estimate".into(),
                "stochastic".into(),
                examples("stochastic")
                    .join("ex_sa3.csv")
                    .display()
                    .to_string(),
                "--report".into(),
            ],
        ),
    ];
    for (kind, mut args) in runs {
        let page = d(&format!("{kind}.html"));
        args.push(page.display().to_string());
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = limpid(&args);
        assert_eq!(out.code, 0, "{kind}: {}", out.stderr);
        let shot = d(&format!("{kind}.png"));
        let (dom, log) = open_in_chromium(&page, &shot);
        no_console_errors(&log);
        screenshot_ok(&shot);
        std::fs::copy(
            &shot,
            std::env::temp_dir().join(format!("limpid-report-{kind}.png")),
        )
        .unwrap();
        let figure = |id: &str| {
            dom.split(&format!("<figure id=\"{id}\""))
                .nth(1)
                .unwrap_or_else(|| panic!("{kind}: no figure {id}"))
                .split("</figure>")
                .next()
                .unwrap()
                .to_string()
        };
        match kind {
            "planar" => {
                for j in 1..=2 {
                    assert_eq!(
                        figure(&format!("fit-dtau{j}"))
                            .matches("class=\"trace\"")
                            .count(),
                        2
                    );
                }
                assert_eq!(
                    figure("endpoint-stiffness-ellipse")
                        .matches("class=\"ellipsoid\"")
                        .count(),
                    1
                );
                assert!(dom.contains("Confidence criteria (Lakatos et al. 2011, §III-C)"));
                assert!(dom.contains("base inertial parameters (kg m²)"));
            }
            "sweep" => {
                assert!(dom.matches("class=\"trace\"").count() >= 4, "{kind}");
            }
            "cocontraction" => {
                let grid = figure("stiffness-ellipsoids");
                assert_eq!(grid.matches("class=\"ellipsoid\"").count(), 4);
                assert!(
                    grid.contains("N/m (semi-axis)</text>"),
                    "a scale bar with its unit"
                );
                // every kind shown (?all): 12 names, more than 8, so shown on hover only
                assert_eq!(
                    dom.matches("class=\"label\" visibility=\"hidden\"").count(),
                    12
                );
            }
            "study" => {
                let grid = figure("study-stiffness-ellipsoids");
                assert_eq!(grid.matches("class=\"ellipsoid\"").count(), 28);
                for c in 1..=7 {
                    assert!(grid.contains(&format!(">configuration {c}</text>")));
                }
                // 28 viewer labels, hidden until hovered
                assert_eq!(
                    dom.matches("class=\"label\" visibility=\"hidden\"").count(),
                    28
                );
                // mean ± sd per cell
                assert!(dom.contains("Mean ± sd over subjects"));
                assert!(dom.matches(" ± ").count() >= 28 * 8);
            }
            "stochastic" => {
                assert!(dom.contains("Verdicts and the criteria behind them"));
                assert!(dom.contains("lowest multiple coherence"));
                // mixed x/z/theta coordinates: a unit in every cell, never "SI"
                assert!(!dom.contains("SI"), "{kind}: SI in the page");
                assert!(dom.contains(" N/rad</td>") && dom.contains(" N m/rad</td>"));
            }
            _ => unreachable!(),
        }
    }
    // the planar traces are the fit's own
    let est = json(&[
        "estimate",
        "planar",
        joint.to_str().unwrap(),
        "--link-lengths",
        "0.28,0.35",
        "--json",
    ]);
    let tr = &est["traces"];
    for j in 0..2 {
        let m: Vec<f64> = serde_json::from_value(tr["measured"][j].clone()).unwrap();
        let p: Vec<f64> = serde_json::from_value(tr["predicted"][j].clone()).unwrap();
        assert!(m.len() > 500 && m.len() <= 1500);
        let reported = est["fit"]["vaf"][j].as_f64().unwrap();
        assert!((vaf(&m, &p) - reported).abs() < 0.5, "joint {j}");
    }
}
