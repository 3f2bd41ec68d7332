//! limpid-report: one self-contained HTML file from limpid's JSON results.
//!
//! What it shows, as the results allow:
//! - the trust verdict and warnings of every result, in words, at the top;
//! - an interactive 3-D view of the stiffness, damping and inertia ellipsoids
//!   at their start points (seed 000 Fig. 4, seed 001 Fig. 5): radii
//!   proportional to the eigenvalues of the symmetric part (seed 001's
//!   convention), one scale per kind, with a scale sphere; our own small
//!   viewer (`viewer.js`, no library, no network);
//! - tables in the layout of seed 000 Tables I-II (estimate ± standard error,
//!   and the truth where known);
//! - Bode magnitude and phase of Z(f) per element with the parametric fit and,
//!   where known, the expected model (seed 004 Fig. 9), and the multiple and
//!   partial coherences (Fig. 10);
//! - criteria against the observation window (seed 003 Fig. 4-5).
//!
//! Figures are static SVG written by [`svg`]; every trace is a
//! `<path class="trace">`, so the figure data can be checked without pixels.

pub mod svg;

use std::fmt::Write as _;

use serde::Serialize;
use serde_json::Value;
use svg::{escape, Chart, Series, Stroke, PALETTE};

/// A table: caption, header, rows of text cells.
#[derive(Debug, Clone, Serialize)]
pub struct Table {
    pub caption: String,
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

/// One ellipsoid for the 3-D view.
#[derive(Debug, Clone, Serialize)]
pub struct EllipsoidView {
    pub point: String,
    pub kind: String,
    pub centre: [f64; 3],
    pub eigenvalues: [f64; 3],
    /// Principal axes as columns (row-major).
    pub axes: [[f64; 3]; 3],
}

/// A named figure.
#[derive(Debug, Clone, Serialize)]
pub struct Figure {
    pub id: String,
    pub chart: Chart,
}

/// One section per input result.
#[derive(Debug, Clone, Serialize)]
pub struct Section {
    pub heading: String,
    pub verdict: String,
    pub warnings: Vec<String>,
    pub tables: Vec<Table>,
    pub figures: Vec<Figure>,
    pub ellipsoids: Vec<EllipsoidView>,
}

/// The whole report.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    pub title: String,
    pub sections: Vec<Section>,
}

/// Build the report from named JSON results (`limpid ... --json`, `demo.json`,
/// `study.json`). Unknown shapes are an error naming the input.
pub fn build(inputs: &[(String, Value)]) -> Result<Report, String> {
    let mut sections = Vec::new();
    for (name, v) in inputs {
        let section = if v.is_array() && v[0].get("start_point").is_some() {
            demo_section(name, v)
        } else if v.get("impedance").is_some() && v.get("frequencies").is_some() {
            stochastic_section(name, v)
        } else if v.get("rows").is_some() && v.get("min_positive_definite_ms").is_some() {
            sweep_section(name, v)
        } else if v.get("inertial_parameters").is_some() && v.get("criteria").is_some() {
            planar_section(name, v)
        } else if v.get("recordings").is_some() && v.get("rotation").is_some() {
            study_section(name, v)
        } else if v.get("levels").is_some() && v.get("comparisons").is_some() {
            cocontraction_section(name, v)
        } else if v.get("ellipsoids").is_some() && v.get("stiffness").is_some() {
            linear_section(name, v)
        } else {
            return Err(format!(
                "{name}: not a limpid result this report knows (linear, demo, stochastic, planar, co-contraction, study, window-sweep JSON)"
            ));
        };
        sections.push(section?);
    }
    Ok(Report {
        title: "limpid report".into(),
        sections,
    })
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

fn matrix(v: &Value) -> Option<Vec<Vec<f64>>> {
    v.as_array()?
        .iter()
        .map(|r| r.as_array().map(|r| r.iter().map(num).collect()))
        .collect()
}

/// A number as a short string; NaN and missing values are said in words.
fn fmt(v: f64) -> String {
    if !v.is_finite() {
        return "n/a".into();
    }
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    }
}

fn strings(v: &Value) -> Vec<String> {
    v.as_array()
        .map(|a| {
            a.iter()
                .filter_map(|s| s.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default()
}

fn coordinates(v: &Value, n: usize) -> Vec<String> {
    let c = strings(&v["coordinates"]);
    if c.len() == n {
        c
    } else {
        ["x", "y", "z"]
            .iter()
            .take(n)
            .map(|s| s.to_string())
            .collect()
    }
}

/// Seed 000 Table I: every element with its standard error, and the truth if given.
fn matrix_table(
    caption: &str,
    coords: &[String],
    est: &[Vec<f64>],
    se: Option<&Vec<Vec<f64>>>,
    truth: Option<&Vec<Vec<f64>>>,
) -> Table {
    let mut header = vec!["".to_string()];
    header.extend(coords.iter().cloned());
    let rows = est
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let mut cells = vec![coords[i].clone()];
            for (j, v) in row.iter().enumerate() {
                let mut c = fmt(*v);
                if let Some(se) = se {
                    let _ = write!(c, " ± {}", fmt(se[i][j]));
                }
                if let Some(t) = truth {
                    let _ = write!(c, " (true {})", fmt(t[i][j]));
                }
                cells.push(c);
            }
            cells
        })
        .collect();
    Table {
        caption: caption.into(),
        header,
        rows,
    }
}

const KINDS: [(&str, &str); 3] = [("stiffness", "K"), ("damping", "B"), ("inertia", "M")];

fn ellipsoids_of(point: &str, centre: [f64; 3], result: &Value) -> Vec<EllipsoidView> {
    KINDS
        .iter()
        .filter_map(|(kind, _)| ellipsoid_view(point, kind, centre, &result["ellipsoids"][kind]))
        .collect()
}

/// One 3-D ellipsoid (`eigenvalues`, `axes` of an ellipsoid JSON) at `centre`.
fn ellipsoid_view(point: &str, kind: &str, centre: [f64; 3], e: &Value) -> Option<EllipsoidView> {
    let (axes, ev) = (matrix(&e["axes"])?, e["eigenvalues"].as_array()?);
    if axes.len() != 3 || axes.iter().any(|r| r.len() != 3) || ev.len() != 3 {
        return None;
    }
    Some(EllipsoidView {
        point: point.into(),
        kind: kind.into(),
        centre,
        eigenvalues: [num(&ev[0]), num(&ev[1]), num(&ev[2])],
        axes: [
            [axes[0][0], axes[0][1], axes[0][2]],
            [axes[1][0], axes[1][1], axes[1][2]],
            [axes[2][0], axes[2][1], axes[2][2]],
        ],
    })
}

/// The verdict of a linear result, in words.
fn linear_verdict(v: &Value) -> String {
    let c = &v["criteria"];
    let mut parts = Vec::new();
    for (kind, _) in KINDS {
        let ident = c["identifiable"][kind].as_bool().unwrap_or(false);
        let pd = c["matrices"][kind]["positive_definite"]
            .as_bool()
            .unwrap_or(false);
        parts.push(match (ident, pd) {
            (true, true) => format!("{kind} trusted (identifiable, positive definite)"),
            (true, false) => {
                format!("{kind} identified but not positive definite: not a passive impedance")
            }
            (false, _) => format!("{kind} NOT identifiable from this data: treat it as unknown"),
        });
    }
    let vaf = c.get("vaf").or(v["fit"].get("vaf"));
    let vafs: Vec<String> = vaf
        .and_then(|a| a.as_array())
        .map(|a| a.iter().map(|x| format!("{} %", fmt(num(x)))).collect())
        .unwrap_or_default();
    format!("{}; fit VAF {}", parts.join("; "), vafs.join(" / "))
}

fn linear_tables(v: &Value, truth: Option<&Value>) -> Vec<Table> {
    let Some(k) = matrix(&v["stiffness"]) else {
        return vec![];
    };
    let coords = coordinates(v, k.len());
    let mut tables = Vec::new();
    for (kind, sym) in KINDS {
        let Some(m) = matrix(&v[kind]) else { continue };
        let se = matrix(&v["standard_errors"][kind]);
        let t = truth.and_then(|t| matrix(&t[kind]));
        tables.push(matrix_table(
            &format!("{sym} ({kind}, SI) ± standard error"),
            &coords,
            &m,
            se.as_ref(),
            t.as_ref(),
        ));
    }
    if let Some(obj) = v["table_ii"].as_object() {
        let mut rows = Vec::new();
        for (kind, q) in obj {
            if let Some(q) = q.as_object() {
                rows.push(
                    std::iter::once(kind.clone())
                        .chain(q.iter().map(|(name, val)| {
                            format!(
                                "{name} {}",
                                val.as_f64().map(fmt).unwrap_or_else(|| val.to_string())
                            )
                        }))
                        .collect(),
                );
            }
        }
        if !rows.is_empty() {
            tables.push(Table {
                caption: "Seed 000 Table II quantities".into(),
                header: vec!["matrix".into(), "quantities".into()],
                rows: rows
                    .into_iter()
                    .map(|r: Vec<String>| vec![r[0].clone(), r[1..].join(", ")])
                    .collect(),
            });
        }
    }
    tables
}

/// Measured vs predicted force per coordinate, with r and VAF in the title.
fn fit_figures(prefix: &str, v: &Value) -> Vec<Figure> {
    let tr = &v["fit"]["traces"];
    let Some(time) = tr["time"].as_array() else {
        return vec![];
    };
    let t: Vec<f64> = time.iter().map(num).collect();
    let n = tr["measured"].as_array().map_or(0, Vec::len);
    let coords = coordinates(v, n);
    (0..n)
        .map(|a| {
            let series = |key: &str, label: &str, stroke, color: &str| Series {
                name: label.into(),
                x: t.clone(),
                y: tr[key][a]
                    .as_array()
                    .map(|s| s.iter().map(num).collect())
                    .unwrap_or_default(),
                stroke,
                color: color.into(),
            };
            Figure {
                id: format!("fit-{prefix}{}", coords[a]),
                chart: Chart {
                    title: format!(
                        "{prefix}{}: measured vs predicted force (r {}, VAF {} %)",
                        coords[a],
                        fmt(num(&v["fit"]["r"][a])),
                        fmt(num(&v["fit"]["vaf"][a]))
                    ),
                    x_label: "time along the first windows (s)".into(),
                    y_label: "force (SI)".into(),
                    x_log: false,
                    y_log: false,
                    y_range: None,
                    series: vec![
                        series("measured", "measured", Stroke::Solid, PALETTE[0]),
                        series("predicted", "predicted", Stroke::Dashed, PALETTE[1]),
                    ],
                },
            }
        })
        .collect()
}

fn linear_section(name: &str, v: &Value) -> Result<Section, String> {
    let centre = v["equilibrium"]
        .as_array()
        .filter(|a| a.len() == 3)
        .map(|a| [num(&a[0]), num(&a[1]), num(&a[2])])
        .unwrap_or([0.0; 3]);
    Ok(Section {
        heading: format!("Linear estimate: {name}"),
        verdict: linear_verdict(v),
        warnings: strings(&v["warnings"]),
        tables: linear_tables(v, None),
        figures: fit_figures("", v),
        ellipsoids: ellipsoids_of("estimate", centre, v),
    })
}

fn demo_section(name: &str, v: &Value) -> Result<Section, String> {
    let points = v.as_array().ok_or("demo result is not a list")?;
    let mut section = Section {
        heading: format!("Virtual seed 000 study: {name}"),
        verdict: String::new(),
        warnings: vec![],
        tables: vec![],
        figures: vec![],
        ellipsoids: vec![],
    };
    let mut errors = Table {
        caption: "Estimated vs. true (relative Frobenius error)".into(),
        header: vec![
            "start point".into(),
            "stiffness error %".into(),
            "damping error %".into(),
            "inertia error %".into(),
            "verdict".into(),
        ],
        rows: vec![],
    };
    let mut worst_k: f64 = 0.0;
    for p in points {
        let id = p["start_point"].as_str().unwrap_or("?").to_string();
        let pos = p["position"]
            .as_array()
            .map(|a| [num(&a[0]), num(&a[1]), num(&a[2])])
            .unwrap_or([0.0; 3]);
        let est = &p["estimate"];
        worst_k = worst_k.max(num(&p["stiffness_error_percent"]));
        errors.rows.push(vec![
            id.clone(),
            fmt(num(&p["stiffness_error_percent"])),
            fmt(num(&p["damping_error_percent"])),
            fmt(num(&p["inertia_error_percent"])),
            linear_verdict(est),
        ]);
        section.ellipsoids.extend(ellipsoids_of(&id, pos, est));
        if section.figures.is_empty() {
            section.figures = fit_figures(&format!("{id} "), est);
        }
        let truth = serde_json::json!({
            "stiffness": p["true_stiffness"], "damping": p["true_damping"], "inertia": p["true_inertia"],
        });
        for mut t in linear_tables(est, Some(&truth)).into_iter().take(3) {
            t.caption = format!("{id}: {}", t.caption);
            section.tables.push(t);
        }
        for w in strings(&est["warnings"]) {
            let w = format!("{id}: {w}");
            if !section.warnings.contains(&w) {
                section.warnings.push(w);
            }
        }
    }
    section.verdict = format!(
        "{} start points; worst stiffness error {} % against the known truth",
        points.len(),
        fmt(worst_k)
    );
    section.tables.insert(0, errors);
    Ok(section)
}

/// Z(f) element (i, j) of a model M, B, K: K - ω² M + j ω B.
fn model_z(
    m: &[Vec<f64>],
    b: &[Vec<f64>],
    k: &[Vec<f64>],
    i: usize,
    j: usize,
    f: f64,
) -> (f64, f64) {
    let w = 2.0 * std::f64::consts::PI * f;
    (k[i][j] - w * w * m[i][j], w * b[i][j])
}

fn stochastic_section(name: &str, v: &Value) -> Result<Section, String> {
    let freqs: Vec<f64> = v["frequencies"]
        .as_array()
        .ok_or("frequencies")?
        .iter()
        .map(num)
        .collect();
    let coords = strings(&v["coordinates"]);
    let n = coords.len();
    let z = v["impedance"].as_array().ok_or("impedance")?;
    let (m, b, k) = (
        matrix(&v["inertia"]).ok_or("inertia")?,
        matrix(&v["damping"]).ok_or("damping")?,
        matrix(&v["stiffness"]).ok_or("stiffness")?,
    );
    let expected = &v["accuracy"]["expected"];
    let truth = match (
        matrix(&expected["inertia"]),
        matrix(&expected["damping"]),
        matrix(&expected["stiffness"]),
    ) {
        (Some(m), Some(b), Some(k)) => Some((m, b, k)),
        _ => None,
    };
    let band = v["criteria"]["band_hz"]
        .as_array()
        .map(|a| (num(&a[0]), num(&a[1])))
        .unwrap_or((0.5, 10.0));
    let positive: Vec<usize> = (0..freqs.len()).filter(|&i| freqs[i] > 0.0).collect();
    let fx: Vec<f64> = positive.iter().map(|&i| freqs[i]).collect();
    let mut figures = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let est: Vec<(f64, f64)> = positive
                .iter()
                .map(|&f| {
                    let c = &z[f][i][j];
                    (num(&c[0]), num(&c[1]))
                })
                .collect();
            let fit: Vec<(f64, f64)> = fx.iter().map(|&f| model_z(&m, &b, &k, i, j, f)).collect();
            let mut curves = vec![
                ("estimate Z", est, Stroke::Solid, PALETTE[0]),
                ("parametric fit", fit, Stroke::Dashed, PALETTE[1]),
            ];
            if let Some((tm, tb, tk)) = &truth {
                curves.push((
                    "expected",
                    fx.iter().map(|&f| model_z(tm, tb, tk, i, j, f)).collect(),
                    Stroke::Dotted,
                    PALETTE[6],
                ));
            }
            let element = format!("Z[{},{}]", coords[i], coords[j]);
            let mk = |phase: bool| Chart {
                title: format!("{element} {}", if phase { "phase" } else { "magnitude" }),
                x_label: "frequency (Hz)".into(),
                y_label: if phase {
                    "phase (deg)".into()
                } else {
                    "|Z| (SI)".into()
                },
                x_log: true,
                y_log: !phase,
                y_range: if phase { Some((-180.0, 180.0)) } else { None },
                series: curves
                    .iter()
                    .map(|(label, c, stroke, color)| Series {
                        name: (*label).into(),
                        x: fx.clone(),
                        y: c.iter()
                            .map(|(re, im)| {
                                if phase {
                                    im.atan2(*re).to_degrees()
                                } else {
                                    re.hypot(*im)
                                }
                            })
                            .collect(),
                        stroke: *stroke,
                        color: (*color).into(),
                    })
                    .collect(),
            };
            figures.push(Figure {
                id: format!("bode-mag-{}{}", coords[i], coords[j]),
                chart: mk(false),
            });
            figures.push(Figure {
                id: format!("bode-phase-{}{}", coords[i], coords[j]),
                chart: mk(true),
            });
        }
    }
    // coherences (seed 004 Fig. 10)
    let outputs = strings(&v["coherence"]["outputs"]);
    let inputs = strings(&v["inputs"]);
    let multiple = &v["coherence"]["multiple"];
    figures.push(Figure {
        id: "coherence-multiple".into(),
        chart: Chart {
            title: "Multiple coherence of each output on all inputs".into(),
            x_label: "frequency (Hz)".into(),
            y_label: "coherence".into(),
            x_log: true,
            y_log: false,
            y_range: Some((0.0, 1.0)),
            series: outputs
                .iter()
                .enumerate()
                .map(|(o, name)| Series {
                    name: name.clone(),
                    x: fx.clone(),
                    y: positive.iter().map(|&f| num(&multiple[o][f])).collect(),
                    stroke: Stroke::Solid,
                    color: PALETTE[o % PALETTE.len()].into(),
                })
                .collect(),
        },
    });
    let partial = &v["coherence"]["partial"];
    for (o, name) in outputs.iter().enumerate() {
        figures.push(Figure {
            id: format!("coherence-partial-{name}"),
            chart: Chart {
                title: format!("Partial coherence of {name} with each input"),
                x_label: "frequency (Hz)".into(),
                y_label: "coherence".into(),
                x_log: true,
                y_log: false,
                y_range: Some((0.0, 1.0)),
                series: inputs
                    .iter()
                    .enumerate()
                    .map(|(u, input)| Series {
                        name: input.clone(),
                        x: fx.clone(),
                        y: positive.iter().map(|&f| num(&partial[o][u][f])).collect(),
                        stroke: Stroke::Solid,
                        color: PALETTE[u % PALETTE.len()].into(),
                    })
                    .collect(),
            },
        });
    }
    let c = &v["criteria"];
    let mut verdict = format!(
        "mean multiple coherence {} (lowest {}) over {}-{} Hz; largest input coherence {}; parametric fit VAF {} %",
        fmt(num(&c["mean_multiple_coherence"])),
        fmt(num(&c["min_multiple_coherence"])),
        fmt(band.0),
        fmt(band.1),
        fmt(num(&c["max_input_coherence"])),
        fmt(num(&c["fit_vaf"]))
    );
    if let Some(rel) = v["accuracy"]["mean_relative_error"].as_f64() {
        let _ = write!(
            verdict,
            "; mean relative error vs. the expected model {} %",
            fmt(100.0 * rel)
        );
    }
    let se = &v["standard_errors"];
    let tables = KINDS
        .iter()
        .filter_map(|(kind, sym)| {
            let mat = matrix(&v[*kind])?;
            Some(matrix_table(
                &format!("{sym} ({kind}, SI, parametric fit over the band) ± standard error"),
                &coords,
                &mat,
                matrix(&se[*kind]).as_ref(),
                matrix(&expected[*kind]).as_ref(),
            ))
        })
        .collect();
    Ok(Section {
        heading: format!("Stochastic estimate: {name}"),
        verdict,
        warnings: strings(&v["warnings"]),
        tables,
        figures,
        ellipsoids: vec![],
    })
}

/// A whole seed 001 study: means over subjects per configuration and level,
/// ellipsoid rotation from level 0 to 1, and the stiffness against the index.
fn study_section(name: &str, v: &Value) -> Result<Section, String> {
    let rows = v["levels"].as_array().ok_or("levels")?;
    let cols = [
        "configuration",
        "level",
        "subjects",
        "cocontraction_index",
        "kxx",
        "kyy",
        "kzz",
        "k_max_a",
        "k1",
        "k2",
        "k3",
    ];
    let cell = |r: &Value, c: &str| match &r[c] {
        Value::String(s) => s.clone(),
        other => other.as_f64().map(fmt).unwrap_or_else(|| "n/a".into()),
    };
    let levels = Table {
        caption: "Means over subjects per configuration and level (seed 001 Tables 1-5): index, diagonal stiffness, largest antisymmetric element, principal stiffnesses (N/m)".into(),
        header: cols.map(String::from).to_vec(),
        rows: rows.iter().map(|r| cols.iter().map(|c| cell(r, c)).collect()).collect(),
    };
    let rot_cols = ["configuration", "from_level", "to_level", "subjects"];
    let list = |x: &Value| {
        x.as_array()
            .map(|a| {
                a.iter()
                    .map(|v| fmt(num(v)))
                    .collect::<Vec<_>>()
                    .join(" / ")
            })
            .unwrap_or_default()
    };
    let rotation = Table {
        caption: "Stiffness ellipsoid from the lowest to the highest level: axis rotations and principal changes".into(),
        header: ["configuration", "from", "to", "subjects", "rotation (deg)", "principal change %"].map(String::from).to_vec(),
        rows: v["rotation"]
            .as_array()
            .into_iter()
            .flatten()
            .map(|r| {
                let mut row: Vec<String> = rot_cols.iter().map(|c| cell(r, c)).collect();
                row.push(list(&r["rotation_deg"]));
                row.push(list(&r["principal_change_percent"]));
                row
            })
            .collect(),
    };
    let mut configs: Vec<String> = rows.iter().map(|r| cell(r, "configuration")).collect();
    configs.dedup();
    // mean stiffness ellipsoids: levels side by side along x, configurations down z (seed 001 Fig. 5)
    let mut ellipsoids = Vec::new();
    for (i, c) in configs.iter().enumerate() {
        let at: Vec<&Value> = rows
            .iter()
            .filter(|r| cell(r, "configuration") == *c)
            .collect();
        for (j, r) in at.iter().enumerate() {
            let point = format!("configuration {c}, level {}", cell(r, "level"));
            let centre = [0.15 * j as f64, 0.0, -0.15 * i as f64];
            ellipsoids.extend(ellipsoid_view(&point, "stiffness", centre, &r["ellipsoid"]));
        }
    }
    let per_config = |key: &str| -> Vec<Series> {
        configs
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let pts: Vec<&Value> = rows
                    .iter()
                    .filter(|r| cell(r, "configuration") == *c)
                    .collect();
                Series {
                    name: format!("configuration {c}"),
                    x: pts.iter().map(|r| num(&r["cocontraction_index"])).collect(),
                    y: pts.iter().map(|r| num(&r[key])).collect(),
                    stroke: Stroke::Solid,
                    color: PALETTE[k % PALETTE.len()].into(),
                }
            })
            .collect()
    };
    let figures = vec![Figure {
        id: "study-k1".into(),
        chart: Chart {
            title: "Largest principal stiffness against the co-contraction index".into(),
            x_label: "co-contraction index (fraction of MVC)".into(),
            y_label: "k1 (N/m)".into(),
            x_log: false,
            y_log: false,
            y_range: None,
            series: per_config("k1"),
        },
    }];
    let failures: Vec<String> = v["failures"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|f| {
            format!(
                "subject {}, configuration {}: {}",
                cell(f, "subject"),
                cell(f, "configuration"),
                f["error"].as_str().unwrap_or("")
            )
        })
        .collect();
    Ok(Section {
        heading: format!("Study {}: {name}", v["name"].as_str().unwrap_or("")),
        verdict: format!(
            "{} recordings analysed, {} failed; {} configurations",
            v["recordings"].as_array().map_or(0, Vec::len),
            failures.len(),
            configs.len()
        ),
        warnings: failures,
        tables: vec![levels, rotation],
        figures,
        ellipsoids,
    })
}

/// Seed 001: index and stiffness per co-contraction level, ellipsoids side by side (Fig. 5).
fn cocontraction_section(name: &str, v: &Value) -> Result<Section, String> {
    let levels = v["levels"].as_array().ok_or("levels")?;
    let mut section = Section {
        heading: format!("Co-contraction levels: {name}"),
        verdict: String::new(),
        warnings: strings(&v["warnings"]),
        tables: vec![],
        figures: vec![],
        ellipsoids: vec![],
    };
    let mut index_table = Table {
        caption: "Co-contraction index and stiffness per level (seed 001 Tables 1-5)".into(),
        header: [
            "level",
            "index (mean ± sd)",
            "within band",
            "K eigenvalues (N/m)",
            "verdict",
        ]
        .map(String::from)
        .to_vec(),
        rows: vec![],
    };
    let mut summary = Vec::new();
    for (k, l) in levels.iter().enumerate() {
        let level = num(&l["level"]);
        let id = format!("level {}", fmt(level));
        let ev: Vec<String> = l["ellipsoid"]["eigenvalues"]
            .as_array()
            .map(|a| a.iter().map(|x| fmt(num(x))).collect())
            .unwrap_or_default();
        index_table.rows.push(vec![
            fmt(level),
            format!(
                "{} ± {}",
                fmt(num(&l["cocontraction_index"])),
                fmt(num(&l["cocontraction_sd"]))
            ),
            format!("{} %", fmt(100.0 * num(&l["cocontraction_within_band"]))),
            ev.join(" / "),
            linear_verdict(&l["estimate"]),
        ]);
        summary.push(format!(
            "{} at level {}",
            fmt(num(&l["cocontraction_index"])),
            fmt(level)
        ));
        // side by side along x, 0.15 m apart (seed 001 Fig. 5)
        section.ellipsoids.extend(ellipsoids_of(
            &id,
            [0.15 * k as f64, 0.0, 0.0],
            &l["estimate"],
        ));
        if let Some(kmat) = matrix(&l["stiffness"]) {
            let se = matrix(&l["estimate"]["standard_errors"]["stiffness"]);
            section.tables.push(matrix_table(
                &format!("{id}: K (N/m) ± standard error"),
                &coordinates(&l["estimate"], kmat.len()),
                &kmat,
                se.as_ref(),
                None,
            ));
        }
    }
    let mut comparisons = Table {
        caption: "Stiffness ellipsoid against the reference level: principal changes and rotations (direction-matched axes)".into(),
        header: ["level", "reference", "principal change %", "axis rotation (deg)", "ambiguous axes"].map(String::from).to_vec(),
        rows: vec![],
    };
    for c in v["comparisons"].as_array().into_iter().flatten() {
        let list = |key: &str| {
            c[key]
                .as_array()
                .map(|a| {
                    a.iter()
                        .map(|x| x.as_f64().map(fmt).unwrap_or_else(|| x.to_string()))
                        .collect::<Vec<_>>()
                        .join(" / ")
                })
                .unwrap_or_default()
        };
        comparisons.rows.push(vec![
            fmt(num(&c["level"])),
            fmt(num(&c["reference_level"])),
            list("principal_change_percent"),
            list("rotation_deg"),
            list("ambiguous"),
        ]);
    }
    section.verdict = format!("co-contraction index {}", summary.join(", "));
    section.tables.insert(0, index_table);
    section.tables.insert(1, comparisons);
    Ok(section)
}

fn planar_section(name: &str, v: &Value) -> Result<Section, String> {
    let c = &v["criteria"];
    let verdict = if c["trusted"].as_bool().unwrap_or(false) {
        "trusted: well-conditioned, K and D positive definite and quasi-symmetric".to_string()
    } else {
        format!("NOT TRUSTED: {}", strings(&c["reasons"]).join("; "))
    };
    let coords = vec!["q1".to_string(), "q2".to_string()];
    let se = &v["standard_errors"];
    let tables = ["stiffness", "damping"]
        .iter()
        .filter_map(|kind| {
            Some(matrix_table(
                &format!("joint {kind} (SI) ± standard error"),
                &coords,
                &matrix(&v[*kind])?,
                matrix(&se[*kind]).as_ref(),
                None,
            ))
        })
        .collect();
    Ok(Section {
        heading: format!("Planar-arm estimate: {name}"),
        verdict,
        warnings: vec![],
        tables,
        figures: vec![],
        ellipsoids: vec![],
    })
}

fn sweep_section(name: &str, v: &Value) -> Result<Section, String> {
    let rows = v["rows"].as_array().ok_or("rows")?;
    let t: Vec<f64> = rows
        .iter()
        .map(|r| num(&r["observation_window_ms"]))
        .collect();
    let crit = |key: &str, idx: Option<usize>| -> Vec<f64> {
        rows.iter()
            .map(|r| {
                let x = &r["estimate"]["criteria"][key];
                match idx {
                    Some(i) => num(&x[i]),
                    None => num(x),
                }
            })
            .collect()
    };
    let series = |name: &str, y: Vec<f64>, k: usize| Series {
        name: name.into(),
        x: t.clone(),
        y,
        stroke: Stroke::Solid,
        color: PALETTE[k].into(),
    };
    let figures = vec![
        Figure {
            id: "sweep-condition".into(),
            chart: Chart {
                title: "Condition number of W against the observation window".into(),
                x_label: "T_obs (ms)".into(),
                y_label: "cond(W)".into(),
                x_log: false,
                y_log: true,
                y_range: None,
                series: vec![
                    series("cond(W)", crit("condition_number", None), 0),
                    series(
                        "cond(W), unit-RMS columns",
                        crit("condition_number_scaled", None),
                        1,
                    ),
                ],
            },
        },
        Figure {
            id: "sweep-eigenvalues".into(),
            chart: Chart {
                title: "Smallest eigenvalues of K and D (positive definiteness)".into(),
                x_label: "T_obs (ms)".into(),
                y_label: "eigenvalue (SI)".into(),
                x_log: false,
                y_log: false,
                y_range: None,
                series: vec![
                    series("K, smallest", crit("stiffness_eigenvalues", Some(1)), 0),
                    series("D, smallest", crit("damping_eigenvalues", Some(1)), 1),
                ],
            },
        },
        Figure {
            id: "sweep-symmetry".into(),
            chart: Chart {
                title: "Symmetry ratio ||Z_a|| / ||Z_s||".into(),
                x_label: "T_obs (ms)".into(),
                y_label: "ratio".into(),
                x_log: false,
                y_log: false,
                y_range: None,
                series: vec![
                    series("K", crit("stiffness_symmetry_ratio", None), 0),
                    series("D", crit("damping_symmetry_ratio", None), 1),
                ],
            },
        },
    ];
    let verdict = format!(
        "shortest trustworthy windows: positive definite from {} ms, quasi-symmetric from {} ms, quasi-constant from {} ms",
        v["min_positive_definite_ms"].as_f64().map(fmt).unwrap_or_else(|| "never".into()),
        v["min_quasi_symmetric_ms"].as_f64().map(fmt).unwrap_or_else(|| "never".into()),
        v["min_quasi_constant_ms"].as_f64().map(fmt).unwrap_or_else(|| "never".into()),
    );
    Ok(Section {
        heading: format!("Observation-window sweep: {name}"),
        verdict,
        warnings: vec![],
        tables: vec![],
        figures,
        ellipsoids: vec![],
    })
}

/// The scale per kind: the largest |eigenvalue| of a kind is drawn with a
/// radius of 0.4 x the smallest distance between start points (0.1 m for one).
fn viewer_data(ellipsoids: &[EllipsoidView]) -> Value {
    let mut centres: Vec<[f64; 3]> = Vec::new();
    for e in ellipsoids {
        if !centres
            .iter()
            .any(|c| (0..3).all(|k| (c[k] - e.centre[k]).abs() < 1e-9))
        {
            centres.push(e.centre);
        }
    }
    let mut spacing = f64::INFINITY;
    for a in &centres {
        for b in &centres {
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            if d > 1e-9 {
                spacing = spacing.min(d);
            }
        }
    }
    if !spacing.is_finite() {
        spacing = 0.1;
    }
    let mid: Vec<f64> = (0..3)
        .map(|k| {
            let lo = centres.iter().map(|c| c[k]).fold(f64::INFINITY, f64::min);
            let hi = centres
                .iter()
                .map(|c| c[k])
                .fold(f64::NEG_INFINITY, f64::max);
            0.5 * (lo + hi)
        })
        .collect();
    let extent = centres
        .iter()
        .map(|c| {
            ((c[0] - mid[0]).powi(2) + (c[1] - mid[1]).powi(2) + (c[2] - mid[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max);
    let span = 2.0 * extent + 1.2 * spacing;
    let mut kinds = Vec::new();
    let mut scale = serde_json::Map::new();
    let mut scale_value = serde_json::Map::new();
    for (kind, _) in KINDS {
        let max = ellipsoids
            .iter()
            .filter(|e| e.kind == kind)
            .flat_map(|e| e.eigenvalues.iter().map(|v| v.abs()))
            .fold(0.0, f64::max);
        if max > 0.0 {
            kinds.push(kind);
            scale.insert(kind.into(), (0.4 * spacing / max).into());
            // a round number near half the largest eigenvalue
            let mag = 10f64.powf((0.5 * max).log10().floor());
            let round = [1.0, 2.0, 5.0]
                .iter()
                .map(|m| m * mag)
                .filter(|v| *v <= 0.5 * max)
                .fold(mag, f64::max);
            scale_value.insert(kind.into(), round.into());
        }
    }
    serde_json::json!({
        "ellipsoids": ellipsoids,
        "kinds": kinds,
        "centre": mid,
        "span": span,
        "scale": scale,
        "scale_value": scale_value,
        "units": {"stiffness": "N/m", "damping": "N s/m", "inertia": "kg"},
        "colors": {"stiffness": PALETTE[0], "damping": PALETTE[1], "inertia": PALETTE[2]},
    })
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1400px;margin:1em auto;padding:0 1em;color:#222}\
h1{font-size:1.5em}h2{font-size:1.2em;border-bottom:1px solid #ccc;margin-top:2em}\
.verdict{background:#eef5ee;border-left:4px solid #2a7;padding:.5em 1em}\
.warnings{background:#fff6e5;border-left:4px solid #e90;padding:.5em 1em}\
table{border-collapse:collapse;margin:.8em 0;font-size:.9em}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}\
caption{text-align:left;font-weight:bold;padding:2px}.figures{display:flex;flex-wrap:wrap;gap:8px}\
#ellipsoid-kinds button{margin:2px;border:1px solid #888;background:#fff}#ellipsoid-kinds button.on{background:#cde}";

/// The report as one HTML document: no external URL anywhere.
pub fn to_html(report: &Report) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title><style>{STYLE}</style></head><body><h1>{}</h1>",
        escape(&report.title),
        escape(&report.title)
    );
    h.push_str("<div id=\"summary\">");
    for s in &report.sections {
        let _ = write!(
            h,
            "<p class=\"verdict\"><b>{}</b>: {}</p>",
            escape(&s.heading),
            escape(&s.verdict)
        );
        if !s.warnings.is_empty() {
            h.push_str("<ul class=\"warnings\">");
            for w in &s.warnings {
                let _ = write!(h, "<li>{}</li>", escape(w));
            }
            h.push_str("</ul>");
        }
    }
    h.push_str("</div>");
    let ellipsoids: Vec<EllipsoidView> = report
        .sections
        .iter()
        .flat_map(|s| s.ellipsoids.clone())
        .collect();
    if !ellipsoids.is_empty() {
        h.push_str("<h2>Ellipsoids</h2><p>Each at its start point; co-contraction levels side by side along x, study configurations down z. Radii proportional to the eigenvalues of the symmetric part (one scale per kind, shown by the dashed sphere); drag to rotate, click a kind to show or hide it.</p><div id=\"ellipsoid-kinds\"></div><div id=\"ellipsoid-view\"></div>");
        let data = viewer_data(&ellipsoids).to_string().replace("</", "<\\/");
        let _ = write!(
            h,
            "<script type=\"application/json\" id=\"ellipsoid-data\">{data}</script>"
        );
        let _ = write!(h, "<script>{}</script>", include_str!("viewer.js"));
    }
    for s in &report.sections {
        let _ = write!(h, "<h2>{}</h2>", escape(&s.heading));
        if !s.figures.is_empty() {
            h.push_str("<div class=\"figures\">");
            for f in &s.figures {
                let _ = write!(
                    h,
                    "<figure id=\"{}\">{}</figure>",
                    escape(&f.id),
                    f.chart.to_svg(420.0, 280.0)
                );
            }
            h.push_str("</div>");
        }
        for t in &s.tables {
            let _ = write!(h, "<table><caption>{}</caption><tr>", escape(&t.caption));
            for c in &t.header {
                let _ = write!(h, "<th>{}</th>", escape(c));
            }
            h.push_str("</tr>");
            for r in &t.rows {
                h.push_str("<tr>");
                for c in r {
                    let _ = write!(h, "<td>{}</td>", escape(c));
                }
                h.push_str("</tr>");
            }
            h.push_str("</table>");
        }
    }
    h.push_str("<p><small>Made by limpid; opens offline.</small></p></body></html>");
    h
}

/// Every figure as (file name, SVG) for `--figures DIR`.
pub fn figure_files(report: &Report) -> Vec<(String, String)> {
    report
        .sections
        .iter()
        .enumerate()
        .flat_map(|(i, s)| {
            s.figures.iter().map(move |f| {
                (
                    format!("s{}-{}.svg", i + 1, f.id),
                    f.chart.to_svg(560.0, 380.0),
                )
            })
        })
        .collect()
}
