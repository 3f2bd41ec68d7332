//! limpid-report: one self-contained HTML file from limpid's typed results
//! ([`limpid_analysis::result::Estimate`]).
//!
//! What it shows, as the results allow:
//! - the trust verdict and warnings of every result, in words, at the top;
//! - an interactive 3-D view of the stiffness, damping and inertia ellipsoids
//!   at their start points (seed 000 Fig. 4, seed 001 Fig. 5): radii
//!   proportional to the eigenvalues of the symmetric part (seed 001's
//!   convention), one scale per kind, with scale bars; our own small
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

#![warn(missing_docs)]

pub mod ellipse;
pub mod png;
pub mod reproduce;
pub mod svg;
mod varying;

use std::fmt::Write as _;

use limpid_analysis::cocontraction::CocontractionResult;
use limpid_analysis::demo::{DemoPoint, DemoResult};
use limpid_analysis::linear::{LinearResult, MatrixKind, MatrixVerdict};
use limpid_analysis::result::Estimate;
use limpid_analysis::study::StudyResult;
use limpid_analysis::Ellipsoid;
use limpid_core::{Matrix, Warning};
use limpid_ident::planar::{PlanarEstimate, Sweep};
use limpid_ident::stochastic::StochasticEstimate;
use serde::Serialize;
use serde_json::Value;
use svg::{escape, Chart, Series, Stroke, PALETTE};

/// A table: caption, header, rows of text cells.
#[derive(Debug, Clone, Serialize)]
pub struct Table {
    /// Caption above the table.
    pub caption: String,
    /// Column headings.
    pub header: Vec<String>,
    /// Rows of cells.
    pub rows: Vec<Vec<String>>,
}

/// One ellipsoid for the 3-D view.
#[derive(Debug, Clone, Serialize)]
pub struct EllipsoidView {
    /// Start point or level the ellipsoid belongs to.
    pub point: String,
    /// `stiffness`, `damping` or `inertia`.
    pub kind: String,
    /// Where it is drawn (m).
    pub centre: [f64; 3],
    /// Eigenvalues of the symmetric part, largest first.
    pub eigenvalues: [f64; 3],
    /// Principal axes as columns (row-major).
    pub axes: [[f64; 3]; 3],
}

/// A named figure.
#[derive(Debug, Clone, Serialize)]
pub struct Figure {
    /// HTML id of the figure.
    pub id: String,
    /// The chart.
    pub chart: Chart,
}

/// One section per input result.
#[derive(Debug, Clone, Serialize)]
pub struct Section {
    /// Section heading (kind and name of the result).
    pub heading: String,
    /// The verdict in words.
    pub verdict: String,
    /// The result's warnings.
    pub warnings: Vec<String>,
    /// Tables of the section.
    pub tables: Vec<Table>,
    /// Figures of the section.
    pub figures: Vec<Figure>,
    /// Ellipsoids for the 3-D view.
    pub ellipsoids: Vec<EllipsoidView>,
    /// Pre-drawn SVG figures (ellipsoid grids, ellipses), equal in x and y.
    pub drawings: Vec<Drawing>,
}

/// A figure drawn directly as SVG (not a line chart).
#[derive(Debug, Clone, Serialize)]
pub struct Drawing {
    /// HTML id and file name stem.
    pub id: String,
    /// The standalone `<svg>` element.
    pub svg: String,
}

/// The whole report.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Title of the page.
    pub title: String,
    /// One section per result.
    pub sections: Vec<Section>,
}

/// Build the report from named results (`limpid ... --json`, `demo.json`,
/// `study.json`, read with [`Document::from_json`], or passed in directly).
pub fn build(inputs: &[(String, Estimate)]) -> Report {
    let sections = inputs
        .iter()
        .map(|(name, e)| match e {
            Estimate::Linear(r) => linear_section(name, r),
            Estimate::Demo(r) => demo_section(name, r),
            Estimate::Stochastic(r) => stochastic_section(name, r),
            Estimate::Reflex(r) => reflex_section(name, r),
            Estimate::WindowSweep(r) => sweep_section(name, r),
            Estimate::Planar(r) => planar_section(name, r),
            Estimate::Study(r) => study_section(name, r),
            Estimate::Cocontraction(r) => cocontraction_section(name, r),
            Estimate::Calibration(r) => calibration_section(name, r),
            Estimate::Varying(r) => varying::section(name, r),
        })
        .collect();
    Report {
        title: "limpid report".into(),
        sections,
    }
}

/// A number to 4 significant digits; NaN is said in words.
fn fmt(v: f64) -> String {
    limpid_core::significant(v, 4)
}

/// Unit of a force-like signal for these coordinates (forces on positions, torques on angles).
fn force_unit(coords: &[String]) -> &'static str {
    if coords.iter().all(|c| c == "theta" || c.starts_with('q')) {
        "N m"
    } else {
        "N"
    }
}

/// Unit of one element of a matrix kind for these coordinates.
fn kind_unit(kind: MatrixKind, coords: &[String]) -> &'static str {
    let (m, b, k) = limpid_ident::linear::units(coords);
    match kind {
        MatrixKind::Inertia => m,
        MatrixKind::Damping => b,
        MatrixKind::Stiffness => k,
    }
}

/// Unit of the impedance element Z[i][j]: the force or torque on coordinate
/// `row` per unit displacement of coordinate `column`.
fn element_unit(row: &str, column: &str) -> &'static str {
    let angular = |c: &str| c == "theta" || c.starts_with('q');
    match (angular(row), angular(column)) {
        (false, false) => "N/m",
        (false, true) => "N/rad",
        (true, false) => "N m/m",
        (true, true) => "N m/rad",
    }
}

/// Unit of element (row, column) of K, B or M when the coordinates mix
/// positions and angles: the row's force (N) or torque (N m) per the
/// column's displacement (m or rad), velocity or acceleration.
pub fn matrix_element_unit(kind: MatrixKind, row: &str, column: &str) -> String {
    let angular = |c: &str| c == "theta" || c.starts_with('q');
    let force = if angular(row) { "N m" } else { "N" };
    let per = if angular(column) { "rad" } else { "m" };
    match (kind, angular(row), angular(column)) {
        (MatrixKind::Stiffness, ..) => format!("{force}/{per}"),
        (MatrixKind::Damping, ..) => format!("{force} s/{per}"),
        (MatrixKind::Inertia, false, false) => "kg".into(),
        (MatrixKind::Inertia, true, true) => "kg m²".into(),
        (MatrixKind::Inertia, ..) => format!("{force} s²/{per}"),
    }
}

/// The stochastic estimate's verdicts and the criteria behind them (seed 004
/// §III: coherences, input coherence, fit of the parametric model).
fn stochastic_criteria_table(v: &StochasticEstimate) -> Table {
    let c = &v.criteria;
    let words = |m: &MatrixVerdict| match m {
        MatrixVerdict::Trusted => "trusted",
        MatrixVerdict::PoorFit => "poor fit: do not use",
        MatrixVerdict::NotIdentifiable => "not identifiable from this data",
        MatrixVerdict::NotPassive => "not passive: symmetric part not positive definite",
        MatrixVerdict::Imprecise => "imprecise: 2 SE exceed the tolerance",
    };
    let mut rows = vec![
        vec![
            "stiffness K".into(),
            words(&c.verdicts.stiffness).into(),
            String::new(),
        ],
        vec![
            "damping B".into(),
            words(&c.verdicts.damping).into(),
            String::new(),
        ],
    ];
    if let Some(m) = &c.verdicts.inertia {
        rows.push(vec!["inertia M".into(), words(m).into(), String::new()]);
    }
    let band = format!("{}-{} Hz", fmt(c.band_hz[0]), fmt(c.band_hz[1]));
    rows.extend([
        vec![
            "mean multiple coherence".into(),
            fmt(c.mean_multiple_coherence),
            format!(
                "over {band}; at least {} for any matrix to be trusted",
                fmt(limpid_ident::stochastic::MIN_MEAN_COHERENCE)
            ),
        ],
        vec![
            "lowest multiple coherence".into(),
            fmt(c.min_multiple_coherence),
            format!("over {band}"),
        ],
        vec![
            "largest input coherence".into(),
            fmt(c.max_input_coherence),
            "between two perturbation inputs; Park & Chang (2011) asks below 0.6".into(),
        ],
        vec![
            "fit VAF".into(),
            format!("{} %", fmt(c.fit_vaf)),
            format!(
                "of Z by the parametric model; at least {} % to trust it",
                fmt(limpid_core::criteria::VAF_FLOOR_PERCENT)
            ),
        ],
        vec![
            "phi_T, Z against the fit".into(),
            fmt(c.phi_t_vs_fit),
            "Park & Chang (2011) eq. (15)".into(),
        ],
        vec![
            "Welch".into(),
            format!("{} segments of {} samples", c.segments, c.nperseg),
            format!("resolution {} Hz", fmt(c.frequency_resolution_hz)),
        ],
    ]);
    Table {
        caption: "Verdicts and the criteria behind them".into(),
        header: vec!["item".into(), "value".into(), "meaning".into()],
        rows,
    }
}

/// How a result was made (limpid_analysis::result::Run) as the first table
/// of its section: the files read (size, modification time), the command
/// line, limpid's version and when.
pub fn run_table(run: &limpid_analysis::result::Run) -> Table {
    let mut rows: Vec<Vec<String>> = run
        .inputs
        .iter()
        .map(|f| {
            let size = f.bytes.map_or_else(
                || "unreadable".to_string(),
                |b| {
                    if b >= 1 << 20 {
                        format!("{} MiB", fmt(b as f64 / f64::from(1 << 20)))
                    } else if b >= 1 << 10 {
                        format!("{} KiB", fmt(b as f64 / 1024.0))
                    } else {
                        format!("{b} bytes")
                    }
                },
            );
            let modified = f
                .modified_utc
                .as_deref()
                .map_or(String::new(), |m| format!(", modified {m}"));
            vec!["input".into(), format!("{} ({size}{modified})", f.path)]
        })
        .collect();
    rows.push(vec!["command".into(), run.command_line.clone()]);
    rows.push(vec![
        "made".into(),
        format!("{} by limpid {}", run.created_utc, run.limpid_version),
    ]);
    Table {
        caption: "How this result was made".into(),
        header: vec!["item".into(), "value".into()],
        rows,
    }
}

/// "mean ± sd", rounded to the sd; the mean alone when there is no spread
/// (one subject).
fn mean_sd(mean: Option<f64>, sd: Option<f64>) -> String {
    match (mean, sd) {
        (Some(m), Some(s)) if s.is_finite() && s > 0.0 => limpid_core::with_standard_error(m, s),
        (Some(m), _) => fmt(m),
        (None, _) => "n/a".into(),
    }
}

fn messages(w: &[Warning]) -> Vec<String> {
    w.iter().map(|w| w.message.clone()).collect()
}

/// Warnings of several results, one line per kind: messages that differ only
/// in their first parenthesis (the numbers) share a line, which names the
/// results and gives each one's numbers
/// (`S1-S6: inertia is not identifiable ... — S1 (Mzz = ...); S3 (...)`).
pub fn group_warnings(items: &[(String, String)]) -> Vec<String> {
    struct Group<'a> {
        key: String,
        first: &'a str,
        members: Vec<(&'a str, Option<&'a str>)>,
    }
    let mut groups: Vec<Group> = Vec::new();
    for (id, message) in items {
        let (key, numbers) = match (message.find(" ("), message.find(')')) {
            (Some(a), Some(b)) if b > a => (
                format!("{}{}", &message[..a], &message[b + 1..]),
                Some(&message[a + 2..b]),
            ),
            _ => (message.clone(), None),
        };
        match groups.iter_mut().find(|g| g.key == key) {
            Some(g) => {
                if !g.members.contains(&(id.as_str(), numbers)) {
                    g.members.push((id, numbers));
                }
            }
            None => groups.push(Group {
                key,
                first: message,
                members: vec![(id, numbers)],
            }),
        }
    }
    groups
        .into_iter()
        .map(|g| {
            let mut ids: Vec<&str> = g.members.iter().map(|(m, _)| *m).collect();
            ids.dedup();
            let same = g.members.windows(2).all(|w| w[0].1 == w[1].1);
            if same {
                return format!("{}: {}", id_range(&ids), g.first);
            }
            let detail: Vec<String> = g
                .members
                .iter()
                .filter_map(|(m, n)| n.map(|n| format!("{m} ({n})")))
                .collect();
            format!("{}: {} — {}", id_range(&ids), g.key, detail.join("; "))
        })
        .collect()
}

/// `S1, S2, S3` as `S1-S3` when they are consecutive numbers with one prefix.
fn id_range(ids: &[&str]) -> String {
    let split = |s: &str| {
        let digits = s.trim_start_matches(|c: char| !c.is_ascii_digit());
        let prefix = &s[..s.len() - digits.len()];
        digits.parse::<u64>().ok().map(|n| (prefix.to_string(), n))
    };
    let parsed: Option<Vec<(String, u64)>> = ids.iter().map(|s| split(s)).collect();
    if let Some(p) = parsed {
        let consecutive = p.len() > 2
            && p.windows(2)
                .all(|w| w[0].0 == w[1].0 && w[1].1 == w[0].1 + 1);
        if consecutive {
            return format!("{}-{}", ids[0], ids[ids.len() - 1]);
        }
    }
    ids.join(", ")
}

/// Seed 000 Table I: every element with its standard error, and the truth if given.
fn matrix_table(
    caption: &str,
    coords: &[String],
    est: &Matrix,
    se: Option<&Matrix>,
    truth: Option<&Matrix>,
) -> Table {
    let mut header = vec!["".to_string()];
    header.extend(coords.iter().cloned());
    let rows = (0..est.nrows())
        .map(|i| {
            let mut cells = vec![coords[i].clone()];
            for j in 0..est.ncols() {
                let mut c = match se {
                    Some(se) => limpid_core::with_standard_error(est[(i, j)], se[(i, j)]),
                    None => fmt(est[(i, j)]),
                };
                if let Some(t) = truth {
                    let _ = write!(c, " (true {})", fmt(t[(i, j)]));
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

fn ellipsoids_of(point: &str, centre: [f64; 3], result: &LinearResult) -> Vec<EllipsoidView> {
    MatrixKind::ALL
        .iter()
        .filter_map(|kind| {
            let e = result.ellipsoids.get(*kind).as_ref()?;
            ellipsoid_view(point, kind.name(), centre, e)
        })
        .collect()
}

/// One 3-D ellipsoid at `centre` (none for 2-D ones).
fn ellipsoid_view(
    point: &str,
    kind: &str,
    centre: [f64; 3],
    e: &Ellipsoid,
) -> Option<EllipsoidView> {
    if e.axes.shape() != (3, 3) || e.eigenvalues.len() != 3 {
        return None;
    }
    let a = &e.axes;
    Some(EllipsoidView {
        point: point.into(),
        kind: kind.into(),
        centre,
        eigenvalues: [e.eigenvalues[0], e.eigenvalues[1], e.eigenvalues[2]],
        axes: [
            [a[(0, 0)], a[(0, 1)], a[(0, 2)]],
            [a[(1, 0)], a[(1, 1)], a[(1, 2)]],
            [a[(2, 0)], a[(2, 1)], a[(2, 2)]],
        ],
    })
}

fn linear_tables(v: &LinearResult, truth: Option<&DemoPoint>) -> Vec<Table> {
    let coords = &v.provenance.coordinates;
    let mut tables: Vec<Table> = MatrixKind::ALL
        .iter()
        .map(|&kind| {
            matrix_table(
                &format!(
                    "{} ({}, {}) ± standard error",
                    kind.symbol(),
                    kind.name(),
                    kind_unit(kind, coords)
                ),
                coords,
                v.matrix(kind),
                Some(v.standard_error(kind)),
                truth.map(|t| t.truth(kind)),
            )
        })
        .collect();
    // in the order of the JSON keys: damping, inertia, stiffness
    let rows = [
        MatrixKind::Damping,
        MatrixKind::Inertia,
        MatrixKind::Stiffness,
    ]
    .iter()
    .map(|&kind| {
        let q = v.table_ii.get(kind);
        vec![
            kind.name().to_string(),
            format!(
                "max_antisymmetric {}, max_symmetric {}, min_symmetric {}",
                fmt(q.max_antisymmetric),
                fmt(q.max_symmetric),
                fmt(q.min_symmetric)
            ),
        ]
    })
    .collect();
    tables.push(Table {
        caption: "Artemiadis et al. (2010) Table II quantities".into(),
        header: vec!["matrix".into(), "quantities".into()],
        rows,
    });
    tables
}

/// Measured vs predicted force per coordinate, with r and VAF in the title.
fn fit_figures(prefix: &str, v: &LinearResult) -> Vec<Figure> {
    let tr = &v.fit.traces;
    let coords = &v.provenance.coordinates;
    (0..tr.measured.len().min(coords.len()))
        .map(|a| {
            let series = |y: &[f64], label: &str, stroke, color: &str| Series {
                name: label.into(),
                x: tr.time.clone(),
                y: y.to_vec(),
                stroke,
                color: color.into(),
            };
            Figure {
                id: format!("fit-{prefix}{}", coords[a]),
                chart: Chart {
                    title: format!(
                        "{prefix}{}: measured vs predicted force (r {}, VAF {} %)",
                        coords[a],
                        fmt(v.fit.r[a]),
                        fmt(v.fit.vaf[a])
                    ),
                    x_label: "time along the first windows (s)".into(),
                    y_label: format!("force ({})", force_unit(coords)),
                    x_log: false,
                    y_log: false,
                    y_range: None,
                    series: vec![
                        series(&tr.measured[a], "measured", Stroke::Solid, PALETTE[0]),
                        series(&tr.predicted[a], "predicted", Stroke::Dashed, PALETTE[1]),
                    ],
                },
            }
        })
        .collect()
}

fn linear_section(name: &str, v: &LinearResult) -> Section {
    let centre = match v.equilibrium.as_deref() {
        Some(&[x, y, z]) => [x, y, z],
        _ => [0.0; 3],
    };
    let p = &v.provenance;
    let source = Table {
        caption: "Recording and settings".into(),
        header: vec!["item".into(), "value".into()],
        rows: vec![
            vec!["recording".into(), p.recording.clone()],
            vec![
                "sample rate".into(),
                format!("{} Hz", fmt(p.sample_rate_hz)),
            ],
            vec![
                "windows".into(),
                if p.continuous {
                    "one continuous window".into()
                } else {
                    format!("{} trials", p.windows)
                },
            ],
            vec![
                "low-pass".into(),
                format!(
                    "Butterworth order {} at {} Hz, zero-phase; derivatives {}",
                    p.filter_order,
                    fmt(p.cutoff_hz),
                    p.derivative
                ),
            ],
            vec!["force offsets".into(), p.offsets.clone()],
        ],
    };
    let mut tables = vec![source];
    tables.extend(linear_tables(v, None));
    Section {
        heading: format!("Linear estimate: {name}"),
        verdict: v.verdict(),
        warnings: messages(&v.warnings),
        tables,
        figures: fit_figures("", v),
        ellipsoids: ellipsoids_of("estimate", centre, v),
        drawings: vec![],
    }
}

fn calibration_section(name: &str, v: &limpid_analysis::calibrate::Calibration) -> Section {
    let (header, rows) = v.table();
    let w = &v.window_sweep;
    Section {
        heading: format!("Calibration of standard errors and verdicts: {name}"),
        verdict: format!(
            "{} virtual recordings per method (seed {}); window sweep: {} of {} trusted windows beyond K 10 % / D 25 % of the truth",
            v.recordings_per_method, v.seed, w.trusted_but_wrong, w.trusted_windows
        ),
        warnings: vec![],
        tables: vec![Table {
            caption: "Per method and matrix: truth within ±2 reported SE, and how often a verdict is wrong".into(),
            header,
            rows,
        }],
        figures: vec![],
        ellipsoids: vec![],
        drawings: vec![],
    }
}

fn demo_section(name: &str, v: &DemoResult) -> Section {
    let mut section = Section {
        heading: format!("Virtual Artemiadis et al. (2010) study: {name}"),
        verdict: String::new(),
        warnings: vec![],
        tables: vec![],
        figures: vec![],
        ellipsoids: vec![],
        drawings: vec![],
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
    // (start point, warning), grouped below
    let mut grouped: Vec<(String, String)> = Vec::new();
    for p in &v.points {
        let id = &p.start_point;
        let est = &p.estimate;
        // an error against the truth means nothing for a matrix the data do not identify
        let error = |kind: MatrixKind, percent: f64| {
            if est.criteria.verdict_of(kind) == MatrixVerdict::NotIdentifiable {
                "n/i".to_string()
            } else {
                fmt(percent)
            }
        };
        errors.rows.push(vec![
            id.clone(),
            error(MatrixKind::Stiffness, p.stiffness_error_percent),
            error(MatrixKind::Damping, p.damping_error_percent),
            error(MatrixKind::Inertia, p.inertia_error_percent),
            est.verdict(),
        ]);
        section
            .ellipsoids
            .extend(ellipsoids_of(id, p.position, est));
        if section.figures.is_empty() {
            section.figures = fit_figures(&format!("{id} "), est);
        }
        for mut t in linear_tables(est, Some(p)).into_iter().take(3) {
            t.caption = format!("{id}: {}", t.caption);
            section.tables.push(t);
        }
        for w in &est.warnings {
            grouped.push((id.clone(), w.message.clone()));
        }
    }
    section.warnings = group_warnings(&grouped);
    errors.caption.push_str("; n/i: the matrix is not identifiable from the data (its error against the truth is not meaningful)");
    section.verdict = match v.worst_error_percent(MatrixKind::Stiffness) {
        Some(e) => format!(
            "{} start points; worst stiffness error {} % against the known truth",
            v.points.len(),
            fmt(e)
        ),
        None => format!(
            "{} start points; stiffness not identifiable at any of them",
            v.points.len()
        ),
    };
    section.tables.insert(0, errors);
    section
}

/// Phase along frequency without ±360° jumps: each point is moved by whole
/// turns to lie within 180° of the previous one (numpy's `unwrap`, degrees).
pub fn unwrap_degrees(phase: impl IntoIterator<Item = f64>) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::new();
    for p in phase {
        let v = match out.last() {
            Some(prev) if p.is_finite() && prev.is_finite() => {
                p - 360.0 * ((p - prev) / 360.0).round()
            }
            _ => p,
        };
        out.push(v);
    }
    out
}

/// Phase traces drawn together, each moved by whole turns so that it starts
/// within 180° of the first trace (an estimate at -179° and its fit at +180°
/// are the same phase); magnitudes (`phase` false) are returned as they are.
fn align_turns(mut traces: Vec<Vec<f64>>, phase: bool) -> Vec<Vec<f64>> {
    let first = |t: &[f64]| t.iter().copied().find(|v| v.is_finite());
    if let (true, Some(reference)) = (phase, traces.first().and_then(|t| first(t))) {
        for t in traces.iter_mut().skip(1) {
            if let Some(start) = first(t) {
                let turns = 360.0 * ((reference - start) / 360.0).round();
                t.iter_mut().for_each(|v| *v += turns);
            }
        }
    }
    traces
}

/// Z(f) element (i, j) of a model M, B, K: K - ω² M + j ω B.
fn model_z(m: &Matrix, b: &Matrix, k: &Matrix, i: usize, j: usize, f: f64) -> (f64, f64) {
    let w = 2.0 * std::f64::consts::PI * f;
    (k[(i, j)] - w * w * m[(i, j)], w * b[(i, j)])
}

fn stochastic_section(name: &str, v: &StochasticEstimate) -> Section {
    let freqs = &v.frequencies;
    let coords = &v.coordinates;
    let n = coords.len();
    let expected = v.accuracy.as_ref().map(|a| &a.expected);
    let band = (v.criteria.band_hz[0], v.criteria.band_hz[1]);
    let positive: Vec<usize> = (0..freqs.len()).filter(|&i| freqs[i] > 0.0).collect();
    let fx: Vec<f64> = positive.iter().map(|&i| freqs[i]).collect();
    let mut figures = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let est: Vec<(f64, f64)> = positive
                .iter()
                .map(|&f| {
                    let c = v.impedance[f][i][j];
                    (c[0], c[1])
                })
                .collect();
            let fit: Vec<(f64, f64)> = fx
                .iter()
                .map(|&f| model_z(&v.inertia, &v.damping, &v.stiffness, i, j, f))
                .collect();
            let mut curves = vec![
                ("estimate Z", est, Stroke::Solid, PALETTE[0]),
                ("parametric fit", fit, Stroke::Dashed, PALETTE[1]),
            ];
            if let Some(t) = expected {
                curves.push((
                    "expected",
                    fx.iter()
                        .map(|&f| model_z(&t.inertia, &t.damping, &t.stiffness, i, j, f))
                        .collect(),
                    Stroke::Dotted,
                    PALETTE[6],
                ));
            }
            // random error of Z[i][j] from the coherences (Bendat & Piersol's
            // gain-factor error sqrt(1 - g^2) / (|g| sqrt(2 n_d)) of the force
            // i and position j outputs, added in quadrature); band = +- 2 errors
            let nd = v.criteria.segments.max(1) as f64;
            let error = |o: usize, f: usize| {
                let g2 = v.coherence.multiple.get(o).and_then(|m| m.get(f)).copied();
                g2.filter(|g| *g > 0.0 && *g <= 1.0)
                    .map_or(f64::INFINITY, |g| ((1.0 - g) / (2.0 * nd * g)).sqrt())
            };
            let eps: Vec<f64> = positive
                .iter()
                .map(|&f| error(n + i, f).hypot(error(j, f)))
                .collect();
            let element = format!("Z[{},{}]", coords[i], coords[j]);
            let with_band = |mut chart: Chart, phase: bool| {
                let y = chart.series[0].y.clone();
                for sign in [1.0, -1.0] {
                    let band: Vec<f64> = y
                        .iter()
                        .zip(&eps)
                        .map(|(v, e)| {
                            if phase {
                                v + sign * (2.0 * e).min(std::f64::consts::FRAC_PI_2).to_degrees()
                            } else {
                                let r = v * (1.0 + sign * 2.0 * e);
                                if r > 0.0 {
                                    r
                                } else {
                                    f64::NAN
                                }
                            }
                        })
                        .collect();
                    chart.series.insert(
                        1,
                        Series {
                            name: "95 % band (coherence)".into(),
                            x: fx.clone(),
                            y: band,
                            stroke: Stroke::Dotted,
                            color: PALETTE[0].into(),
                        },
                    );
                }
                chart
            };
            let mk = |phase: bool| Chart {
                title: format!("{element} {}", if phase { "phase" } else { "magnitude" }),
                x_label: "frequency (Hz)".into(),
                y_label: if phase {
                    "phase (deg)".into()
                } else {
                    format!("|Z| ({})", element_unit(&coords[i], &coords[j]))
                },
                x_log: true,
                y_log: !phase,
                y_range: None,
                series: curves
                    .iter()
                    .zip(align_turns(
                        curves
                            .iter()
                            .map(|(_, c, _, _)| {
                                if phase {
                                    unwrap_degrees(
                                        c.iter().map(|(re, im)| im.atan2(*re).to_degrees()),
                                    )
                                } else {
                                    c.iter().map(|(re, im)| re.hypot(*im)).collect()
                                }
                            })
                            .collect(),
                        phase,
                    ))
                    .map(|((label, _, stroke, color), y)| Series {
                        name: (*label).into(),
                        x: fx.clone(),
                        y,
                        stroke: *stroke,
                        color: (*color).into(),
                    })
                    .collect(),
            };
            figures.push(Figure {
                id: format!("bode-mag-{}{}", coords[i], coords[j]),
                chart: with_band(mk(false), false),
            });
            figures.push(Figure {
                id: format!("bode-phase-{}{}", coords[i], coords[j]),
                chart: with_band(mk(true), true),
            });
        }
    }
    // coherences (seed 004 Fig. 10)
    let outputs = &v.coherence.outputs;
    let multiple = &v.coherence.multiple;
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
                    y: positive.iter().map(|&f| multiple[o][f]).collect(),
                    stroke: Stroke::Solid,
                    color: PALETTE[o % PALETTE.len()].into(),
                })
                .collect(),
        },
    });
    let partial = &v.coherence.partial;
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
                series: v
                    .inputs
                    .iter()
                    .enumerate()
                    .map(|(u, input)| Series {
                        name: input.clone(),
                        x: fx.clone(),
                        y: positive.iter().map(|&f| partial[o][u][f]).collect(),
                        stroke: Stroke::Solid,
                        color: PALETTE[u % PALETTE.len()].into(),
                    })
                    .collect(),
            },
        });
    }
    let c = &v.criteria;
    let mut verdict = format!(
        "mean multiple coherence {} (lowest {}) over {}-{} Hz; largest input coherence {}; parametric fit VAF {} %",
        fmt(c.mean_multiple_coherence),
        fmt(c.min_multiple_coherence),
        fmt(band.0),
        fmt(band.1),
        fmt(c.max_input_coherence),
        fmt(c.fit_vaf)
    );
    if let Some(a) = &v.accuracy {
        let _ = write!(
            verdict,
            "; mean relative error vs. the expected model {} %",
            fmt(100.0 * a.mean_relative_error)
        );
    }
    let se = &v.standard_errors;
    let matrix_tables = [
        (
            MatrixKind::Stiffness,
            "K",
            &v.stiffness,
            &se.stiffness,
            expected.map(|e| &e.stiffness),
        ),
        (
            MatrixKind::Damping,
            "B",
            &v.damping,
            &se.damping,
            expected.map(|e| &e.damping),
        ),
        (
            MatrixKind::Inertia,
            "M",
            &v.inertia,
            &se.inertia,
            expected.map(|e| &e.inertia),
        ),
    ]
    .into_iter()
    .map(|(kind, sym, m, se, truth)| {
        let mixed = kind_unit(kind, coords) == "SI";
        let unit = if mixed {
            "unit per element".to_string()
        } else {
            kind_unit(kind, coords).to_string()
        };
        let mut t = matrix_table(
            &format!(
                "{sym} ({}, {unit}, parametric fit over the band) ± standard error",
                kind.name()
            ),
            coords,
            m,
            Some(se),
            truth,
        );
        if mixed {
            for (i, row) in t.rows.iter_mut().enumerate() {
                for (j, cell) in row.iter_mut().skip(1).enumerate() {
                    let _ = write!(
                        cell,
                        " {}",
                        matrix_element_unit(kind, &coords[i], &coords[j])
                    );
                }
            }
        }
        t
    })
    .collect::<Vec<_>>();
    let mut tables = vec![stochastic_criteria_table(v)];
    tables.extend(matrix_tables);
    Section {
        heading: format!("Stochastic estimate: {name}"),
        verdict,
        warnings: messages(&v.warnings),
        tables,
        figures,
        ellipsoids: vec![],
        drawings: vec![],
    }
}

/// A whole seed 001 study: means over subjects per configuration and level,
/// ellipsoid rotation from level 0 to 1, and the stiffness against the index.
fn study_section(name: &str, v: &StudyResult) -> Section {
    let levels = Table {
        caption: "Mean ± sd over subjects per configuration and level (Patel et al. 2013, Tables 1-5): co-contraction index (fraction of MVC), diagonal stiffness, largest antisymmetric element, principal stiffnesses (N/m)".into(),
        header: [
            "configuration",
            "level",
            "subjects (n)",
            "index C",
            "Kxx",
            "Kyy",
            "Kzz",
            "K_maxA",
            "K1",
            "K2",
            "K3",
        ]
        .map(String::from)
        .to_vec(),
        rows: v
            .levels
            .iter()
            .map(|r| {
                let sd = &r.sd;
                vec![
                    r.configuration.clone(),
                    fmt(r.level),
                    r.subjects.to_string(),
                    mean_sd(r.cocontraction_index, sd.cocontraction_index),
                    mean_sd(r.kxx, sd.kxx),
                    mean_sd(r.kyy, sd.kyy),
                    mean_sd(r.kzz, sd.kzz),
                    mean_sd(r.k_max_a, sd.k_max_a),
                    mean_sd(r.k1, sd.k1),
                    mean_sd(r.k2, sd.k2),
                    mean_sd(r.k3, sd.k3),
                ]
            })
            .collect(),
    };
    let list = |x: &[f64]| x.iter().map(|v| fmt(*v)).collect::<Vec<_>>().join(" / ");
    let rotation = Table {
        caption: "Stiffness ellipsoid from the lowest to the highest level: axis rotations and principal changes".into(),
        header: ["configuration", "from", "to", "subjects", "rotation (deg)", "principal change %"].map(String::from).to_vec(),
        rows: v
            .rotation
            .iter()
            .map(|r| {
                vec![
                    r.configuration.clone(),
                    fmt(r.from_level),
                    fmt(r.to_level),
                    r.subjects.to_string(),
                    list(&r.rotation_deg),
                    list(&r.principal_change_percent),
                ]
            })
            .collect(),
    };
    let mut configs: Vec<&String> = v.levels.iter().map(|r| &r.configuration).collect();
    configs.dedup();
    // mean stiffness ellipsoids: levels side by side along x, configurations down z (seed 001 Fig. 5)
    let mut ellipsoids = Vec::new();
    for (i, c) in configs.iter().enumerate() {
        let at = v.levels.iter().filter(|r| &r.configuration == *c);
        for (j, r) in at.enumerate() {
            let point = format!("configuration {c}, level {}", fmt(r.level));
            let centre = [0.15 * j as f64, 0.0, -0.15 * i as f64];
            if let Some(e) = &r.ellipsoid {
                ellipsoids.extend(ellipsoid_view(&point, "stiffness", centre, e));
            }
        }
    }
    // small multiples: configurations down, levels across (seed 001 Fig. 5)
    let mut level_values: Vec<f64> = v.levels.iter().map(|r| r.level).collect();
    level_values.sort_by(f64::total_cmp);
    level_values.dedup();
    let cells: Vec<Vec<Option<EllipsoidView>>> = configs
        .iter()
        .map(|c| {
            level_values
                .iter()
                .map(|level| {
                    let r = v
                        .levels
                        .iter()
                        .find(|r| &r.configuration == *c && r.level == *level)?;
                    let point = format!("configuration {c}, level {}", fmt(*level));
                    ellipsoid_view(&point, "stiffness", [0.0; 3], r.ellipsoid.as_ref()?)
                })
                .collect()
        })
        .collect();
    let drawings =
        vec![Drawing {
        id: "study-stiffness-ellipsoids".into(),
        svg: ellipse::grid(
            "Mean stiffness ellipsoid per configuration and co-contraction level (Patel et al. 2013, Fig. 5)",
            &configs.iter().map(|c| format!("configuration {c}")).collect::<Vec<_>>(),
            &level_values.iter().map(|l| format!("level {}", fmt(*l))).collect::<Vec<_>>(),
            &cells,
            "N/m",
            ellipse::View::DEFAULT,
        ),
    }];
    let series: Vec<Series> = configs
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let pts: Vec<_> = v.levels.iter().filter(|r| &r.configuration == *c).collect();
            Series {
                name: format!("configuration {c}"),
                x: pts
                    .iter()
                    .map(|r| r.cocontraction_index.unwrap_or(f64::NAN))
                    .collect(),
                y: pts.iter().map(|r| r.k1.unwrap_or(f64::NAN)).collect(),
                stroke: Stroke::Solid,
                color: PALETTE[k % PALETTE.len()].into(),
            }
        })
        .collect();
    let figures = vec![Figure {
        id: "study-k1".into(),
        chart: Chart {
            title: "Largest principal stiffness against the co-contraction index".into(),
            x_label: "co-contraction index (fraction of MVC)".into(),
            y_label: "k1 (N/m)".into(),
            x_log: false,
            y_log: false,
            y_range: None,
            series,
        },
    }];
    let failures: Vec<String> = v
        .failures
        .iter()
        .map(|f| {
            format!(
                "subject {}, configuration {}: {}",
                f.subject, f.configuration, f.error
            )
        })
        .collect();
    Section {
        heading: format!("Study {}: {name}", v.name),
        verdict: format!(
            "{} recordings analysed, {} failed; {} configurations",
            v.recordings.len(),
            failures.len(),
            configs.len()
        ),
        warnings: failures,
        tables: vec![levels, rotation],
        figures,
        ellipsoids,
        drawings,
    }
}

/// Seed 001: index and stiffness per co-contraction level, ellipsoids side by side (Fig. 5).
fn cocontraction_section(name: &str, v: &CocontractionResult) -> Section {
    let mut section = Section {
        heading: format!("Co-contraction levels: {name}"),
        verdict: String::new(),
        warnings: messages(&v.warnings),
        tables: vec![],
        figures: vec![],
        ellipsoids: vec![],
        drawings: vec![],
    };
    let mut index_table = Table {
        caption: "Co-contraction index and stiffness per level (Patel et al. 2013, Tables 1-5)"
            .into(),
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
    for (k, l) in v.levels.iter().enumerate() {
        let id = format!("level {}", fmt(l.level));
        let ev: Vec<String> = l
            .ellipsoid
            .as_ref()
            .map(|e| e.eigenvalues.iter().map(|x| fmt(*x)).collect())
            .unwrap_or_default();
        index_table.rows.push(vec![
            fmt(l.level),
            mean_sd(Some(l.cocontraction_index), Some(l.cocontraction_sd)),
            format!("{} %", fmt(100.0 * l.cocontraction_within_band)),
            ev.join(" / "),
            l.estimate.verdict(),
        ]);
        summary.push(format!(
            "{} at level {}",
            fmt(l.cocontraction_index),
            fmt(l.level)
        ));
        // side by side along x, 0.15 m apart (seed 001 Fig. 5)
        section
            .ellipsoids
            .extend(ellipsoids_of(&id, [0.15 * k as f64, 0.0, 0.0], &l.estimate));
        section.tables.push(matrix_table(
            &format!("{id}: K (N/m) ± standard error"),
            &l.estimate.provenance.coordinates,
            &l.stiffness,
            Some(&l.estimate.standard_errors.stiffness),
            None,
        ));
    }
    let mut comparisons = Table {
        caption: "Stiffness ellipsoid against the reference level: principal changes and rotations (direction-matched axes)".into(),
        header: ["level", "reference", "principal change %", "axis rotation (deg)", "ambiguous axes"].map(String::from).to_vec(),
        rows: vec![],
    };
    let list = |x: &[f64]| x.iter().map(|v| fmt(*v)).collect::<Vec<_>>().join(" / ");
    for c in &v.comparisons {
        comparisons.rows.push(vec![
            fmt(c.level),
            fmt(c.reference_level),
            list(&c.principal_change_percent),
            list(&c.rotation_deg),
            c.ambiguous
                .iter()
                .map(|b| b.to_string())
                .collect::<Vec<_>>()
                .join(" / "),
        ]);
    }
    section.verdict = format!("co-contraction index {}", summary.join(", "));
    let columns: Vec<String> = v
        .levels
        .iter()
        .map(|l| format!("level {}", fmt(l.level)))
        .collect();
    let cells = vec![v
        .levels
        .iter()
        .map(|l| {
            l.ellipsoid.as_ref().and_then(|e| {
                ellipsoid_view(&format!("level {}", fmt(l.level)), "stiffness", [0.0; 3], e)
            })
        })
        .collect()];
    section.drawings.push(Drawing {
        id: "stiffness-ellipsoids".into(),
        svg: ellipse::grid(
            "Stiffness ellipsoid per co-contraction level (Patel et al. 2013, Fig. 5)",
            &[name.to_string()],
            &columns,
            &cells,
            "N/m",
            ellipse::View::DEFAULT,
        ),
    });
    section.tables.insert(0, index_table);
    section.tables.insert(1, comparisons);
    section
}

fn reflex_section(name: &str, v: &limpid_ident::reflex::ReflexEstimate) -> Section {
    let r = &v.reflex;
    let i = &v.intrinsic;
    let verdict = if r.delay_identifiable {
        format!(
            "reflex identified: delay {} ms (95 % interval {}-{} ms), gain {} ± {} N m s/rad; total VAF {} % (cross-validated {} %)",
            fmt(r.delay_s * 1e3), fmt(r.delay_interval_s[0] * 1e3), fmt(r.delay_interval_s[1] * 1e3),
            fmt(r.gain), fmt(r.gain_se), fmt(v.fit.vaf_total), fmt(v.cross_validated_vaf)
        )
    } else {
        format!(
            "reflex delay NOT identifiable; total VAF {} % (cross-validated {} %)",
            fmt(v.fit.vaf_total),
            fmt(v.cross_validated_vaf)
        )
    };
    let row = |what: &str, value: f64, se: Option<f64>, unit: &str| {
        vec![
            what.to_string(),
            fmt(value),
            se.map_or_else(|| "".into(), fmt),
            unit.to_string(),
        ]
    };
    let parameters = Table {
        caption: "Parallel-cascade model (Kearney et al. 1997)".into(),
        header: vec![
            "parameter".into(),
            "value".into(),
            "standard error".into(),
            "unit".into(),
        ],
        rows: vec![
            row(
                "intrinsic inertia I",
                i.inertia,
                Some(i.standard_errors.inertia),
                "kg m²",
            ),
            row(
                "intrinsic damping B",
                i.damping,
                Some(i.standard_errors.damping),
                "N m s/rad",
            ),
            row(
                "intrinsic stiffness K",
                i.stiffness,
                Some(i.standard_errors.stiffness),
                "N m/rad",
            ),
            row(
                "reflex-free fit: K",
                v.reflex_free.parameters.stiffness,
                None,
                "N m/rad",
            ),
            row("reflex gain G", r.gain, Some(r.gain_se), "N m s/rad"),
            row("reflex delay", r.delay_s * 1e3, None, "ms"),
            row(
                "reflex low-pass natural frequency",
                r.natural_frequency_hz,
                None,
                "Hz",
            ),
            row("reflex low-pass damping ratio", r.damping_ratio, None, ""),
        ],
    };
    let vafs = Table {
        caption: "Variance accounted for (decimated torque, first reflex-IRF length left out)"
            .into(),
        header: vec!["model".into(), "VAF (%)".into()],
        rows: vec![
            vec!["intrinsic + reflex pathways".into(), fmt(v.fit.vaf_total)],
            vec!["intrinsic pathway alone".into(), fmt(v.fit.vaf_intrinsic)],
            vec!["reflex pathway alone".into(), fmt(v.fit.vaf_reflex)],
            vec!["joint parametric model".into(), fmt(v.fit.vaf_parametric)],
            vec![
                "cross-validated (fit 2/3, predict 1/3)".into(),
                fmt(v.cross_validated_vaf),
            ],
            vec!["reflex-free I-B-K fit".into(), fmt(v.reflex_free.vaf)],
        ],
    };
    let line = |id: &str, title: &str, x_label: &str, y_label: &str, series: Vec<Series>| Figure {
        id: id.into(),
        chart: Chart {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            x_log: false,
            y_log: false,
            y_range: None,
            series,
        },
    };
    let s = |name: &str, x: &[f64], y: Vec<f64>, k: usize| Series {
        name: name.into(),
        x: x.to_vec(),
        y,
        stroke: Stroke::Solid,
        color: PALETTE[k].into(),
    };
    let ms = |x: &[f64]| x.iter().map(|t| t * 1e3).collect::<Vec<_>>();
    let (rect_in, rect_out): (Vec<f64>, Vec<f64>) = (-20..=20)
        .map(|k| {
            let x = k as f64 / 20.0;
            let y = match r.polarity {
                limpid_ident::reflex::Polarity::Positive => x.max(0.0),
                limpid_ident::reflex::Polarity::Negative => (-x).max(0.0),
            };
            (x, y)
        })
        .unzip();
    let t = &v.traces.t_s;
    let figures = vec![
        line(
            "reflex-intrinsic-irf",
            "Intrinsic IRF (position to torque)",
            "lag (ms)",
            "N m/rad/s",
            vec![s(
                "intrinsic IRF",
                &ms(&i.irf.lags_s),
                i.irf.values.clone(),
                0,
            )],
        ),
        line(
            "reflex-reflex-irf",
            "Reflex IRF (rectified velocity to torque)",
            "lag (ms)",
            "N m s/rad/s",
            vec![s("reflex IRF", &ms(&r.irf.lags_s), r.irf.values.clone(), 1)],
        ),
        line(
            "reflex-nonlinearity",
            "Static nonlinearity: half-wave rectifier",
            "velocity (relative)",
            "rectified (relative)",
            vec![s("rectifier", &rect_in, rect_out, 2)],
        ),
        line(
            "reflex-delay-scan",
            "Joint parametric fit against reflex delay",
            "delay (ms)",
            "total VAF (%)",
            vec![s(
                "VAF",
                &ms(&r.delay_scan.delays_s),
                r.delay_scan.vaf.clone(),
                0,
            )],
        ),
        line(
            "reflex-torque",
            "Measured and predicted torque (10 s)",
            "time (s)",
            "torque (N m)",
            vec![
                s("measured", t, v.traces.measured.clone(), 0),
                s(
                    "intrinsic + reflex",
                    t,
                    v.traces
                        .intrinsic
                        .iter()
                        .zip(&v.traces.reflex)
                        .map(|(a, b)| a + b)
                        .collect(),
                    1,
                ),
                s("intrinsic", t, v.traces.intrinsic.clone(), 2),
                s("reflex", t, v.traces.reflex.clone(), 3),
            ],
        ),
    ];
    Section {
        heading: format!("Intrinsic and reflex stiffness: {name}"),
        verdict,
        warnings: v.warnings.iter().map(|w| w.message.clone()).collect(),
        tables: vec![parameters, vafs],
        figures,
        ellipsoids: vec![],
        drawings: vec![],
    }
}

fn planar_section(name: &str, v: &PlanarEstimate) -> Section {
    let c = &v.criteria;
    let verdict = if c.trusted {
        "trusted: well-conditioned, K and D positive definite and quasi-symmetric".to_string()
    } else {
        format!("NOT TRUSTED: {}", c.reasons.join("; "))
    };
    let coords = vec!["q1".to_string(), "q2".to_string()];
    let se = &v.standard_errors;
    let tables = [
        ("stiffness", &v.stiffness, &se.stiffness),
        ("damping", &v.damping, &se.damping),
    ]
    .into_iter()
    .map(|(kind, m, se)| {
        let unit = if kind == "stiffness" {
            "N m/rad"
        } else {
            "N m s/rad"
        };
        matrix_table(
            &format!("joint {kind} ({unit}) ± standard error"),
            &coords,
            m,
            Some(se),
            None,
        )
    })
    .collect();
    let mut tables: Vec<Table> = tables;
    tables.extend(planar_quality_tables(v));
    let kx = &v.endpoint_stiffness;
    tables.push(matrix_table(
        "end-point stiffness J⁻ᵀ K J⁻¹ at the mean posture (N/m)",
        &["x".to_string(), "y".to_string()],
        kx,
        None,
        None,
    ));
    let figures = v.traces.as_ref().map_or_else(Vec::new, |tr| {
        (0..tr.measured.len().min(2))
            .map(|r| Figure {
                id: format!("fit-dtau{}", r + 1),
                chart: Chart {
                    title: format!(
                        "joint {}: measured vs predicted Δτ (r {}, VAF {} %)",
                        r + 1,
                        fmt(v.fit.r[r]),
                        fmt(v.fit.vaf[r])
                    ),
                    x_label: "time along the observation windows (s)".into(),
                    y_label: format!("Δτ{} (N m)", r + 1),
                    x_log: false,
                    y_log: false,
                    y_range: None,
                    series: vec![
                        Series {
                            name: "measured".into(),
                            x: tr.time.clone(),
                            y: tr.measured[r].clone(),
                            stroke: Stroke::Solid,
                            color: PALETTE[0].into(),
                        },
                        Series {
                            name: "predicted".into(),
                            x: tr.time.clone(),
                            y: tr.predicted[r].clone(),
                            stroke: Stroke::Dashed,
                            color: PALETTE[1].into(),
                        },
                    ],
                },
            })
            .collect()
    });
    let drawings = endpoint_ellipse(kx)
        .map(|e| Drawing {
            id: "endpoint-stiffness-ellipse".into(),
            svg: ellipse::grid(
                "End-point stiffness ellipse (symmetric part, seen from above)",
                &[name.to_string()],
                &[format!(
                    "{} trials, T_obs {} ms",
                    v.trials,
                    fmt(v.observation_window_ms)
                )],
                &[vec![Some(e)]],
                "N/m",
                ellipse::View::Top,
            ),
        })
        .into_iter()
        .collect();
    Section {
        heading: format!("Planar-arm estimate: {name}"),
        verdict,
        warnings: vec![],
        tables,
        figures,
        ellipsoids: vec![],
        drawings,
    }
}

/// The symmetric part of a 2x2 matrix as a flat ellipsoid in the x-y plane
/// (None when not finite).
fn endpoint_ellipse(k: &Matrix) -> Option<EllipsoidView> {
    let e = limpid_analysis::ellipsoid(k)?;
    if e.eigenvalues.len() != 2 {
        return None;
    }
    let a = &e.axes;
    Some(EllipsoidView {
        point: "end point".into(),
        kind: "stiffness".into(),
        centre: [0.0; 3],
        eigenvalues: [e.eigenvalues[0], e.eigenvalues[1], 0.0],
        axes: [
            [a[(0, 0)], a[(0, 1)], 0.0],
            [a[(1, 0)], a[(1, 1)], 0.0],
            [0.0, 0.0, 1.0],
        ],
    })
}

/// Seed 003's quality of a planar estimate: inertial parameters, fit and the
/// confidence criteria (§III-C).
fn planar_quality_tables(v: &PlanarEstimate) -> Vec<Table> {
    let se = &v.standard_errors;
    let xi = Table {
        caption: if v.inertial_parameters_fixed {
            "base inertial parameters (kg m²), given: reduced model (eq. 23-25)".into()
        } else {
            "base inertial parameters (kg m²) ± standard error".into()
        },
        header: vec!["ξ1".into(), "ξ2".into(), "ξ3".into()],
        rows: vec![(0..3)
            .map(|k| {
                if v.inertial_parameters_fixed {
                    fmt(v.inertial_parameters[k])
                } else {
                    limpid_core::with_standard_error(
                        v.inertial_parameters[k],
                        se.inertial_parameters[k],
                    )
                }
            })
            .collect()],
    };
    let c = &v.criteria;
    let yes = |b: bool| if b { "yes" } else { "NO" };
    let mut rows = vec![
        vec![
            "observation window".into(),
            format!("{} ms", fmt(v.observation_window_ms)),
            format!("{} trials, {} samples per joint", v.trials, v.samples),
        ],
        vec![
            "fit VAF, joint 1 / 2".into(),
            format!("{} % / {} %", fmt(v.fit.vaf[0]), fmt(v.fit.vaf[1])),
            format!("r {} / {}", fmt(v.fit.r[0]), fmt(v.fit.r[1])),
        ],
    ];
    if let Some(l) = v.leave_one_out_vaf {
        rows.push(vec![
            "leave-one-trial-out VAF".into(),
            format!("{} % / {} %", fmt(l[0]), fmt(l[1])),
            "each trial predicted by the others (Lakatos et al. 2011, Fig. 6)".into(),
        ]);
    }
    rows.extend([
        vec![
            "condition number of W".into(),
            fmt(c.condition_number),
            format!("with unit-RMS columns: {}", fmt(c.condition_number_scaled)),
        ],
        vec![
            "K positive definite".into(),
            yes(c.stiffness_positive_definite).into(),
            format!(
                "eigenvalues {} / {} N m/rad",
                fmt(c.stiffness_eigenvalues[0]),
                fmt(c.stiffness_eigenvalues[1])
            ),
        ],
        vec![
            "D positive definite".into(),
            yes(c.damping_positive_definite).into(),
            format!(
                "eigenvalues {} / {} N m s/rad",
                fmt(c.damping_eigenvalues[0]),
                fmt(c.damping_eigenvalues[1])
            ),
        ],
        vec![
            "symmetry of K, D".into(),
            format!(
                "{} / {}",
                fmt(c.stiffness_symmetry_ratio),
                fmt(c.damping_symmetry_ratio)
            ),
            "‖antisymmetric part‖ / ‖symmetric part‖; quasi-symmetric when small (Lakatos et al. 2011, §III-C)"
                .into(),
        ],
    ]);
    vec![
        xi,
        Table {
            caption: "Confidence criteria (Lakatos et al. 2011, §III-C)".into(),
            header: vec!["criterion".into(), "value".into(), "detail".into()],
            rows,
        },
    ]
}

fn sweep_section(name: &str, v: &Sweep) -> Section {
    let t: Vec<f64> = v.rows.iter().map(|r| r.observation_window_ms).collect();
    let crit = |f: &dyn Fn(&limpid_ident::planar::PlanarCriteria) -> f64| -> Vec<f64> {
        v.rows.iter().map(|r| f(&r.estimate.criteria)).collect()
    };
    let series = |name: &str, y: Vec<f64>, k: usize| Series {
        name: name.into(),
        x: t.clone(),
        y,
        stroke: Stroke::Solid,
        color: PALETTE[k].into(),
    };
    let mut figures = Vec::new();
    // seed 003 Fig. 4-5: the joint K and D entries against T_obs, ± 1 SE
    // dashed, the shortest trusted window as a vertical line
    for (kind, unit, pick) in [
        (
            "K",
            "N m/rad",
            (|e: &PlanarEstimate| (&e.stiffness, &e.standard_errors.stiffness))
                as fn(&PlanarEstimate) -> (&Matrix, &Matrix),
        ),
        ("D", "N m s/rad", |e: &PlanarEstimate| {
            (&e.damping, &e.standard_errors.damping)
        }),
    ] {
        let mut lines = Vec::new();
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (k, (i, j)) in [(0, 0), (0, 1), (1, 0), (1, 1)].into_iter().enumerate() {
            let value: Vec<f64> = v.rows.iter().map(|r| pick(&r.estimate).0[(i, j)]).collect();
            let se: Vec<f64> = v.rows.iter().map(|r| pick(&r.estimate).1[(i, j)]).collect();
            let name = format!("{kind}{}{}", i + 1, j + 1);
            for sign in [1.0, -1.0] {
                let y: Vec<f64> = value.iter().zip(&se).map(|(v, e)| v + sign * e).collect();
                lines.push(Series {
                    name: "± 1 SE".into(),
                    x: t.clone(),
                    y,
                    stroke: Stroke::Dashed,
                    color: PALETTE[k].into(),
                });
            }
            for y in value.iter().chain(&se) {
                if y.is_finite() {
                    lo = lo.min(*y);
                    hi = hi.max(*y);
                }
            }
            lines.push(series(&name, value, k));
        }
        if let (Some(ts), true) = (v.shortest_trusted_ms, lo < hi) {
            lines.push(Series {
                name: format!("shortest trusted window ({} ms)", fmt(ts)),
                x: vec![ts, ts],
                y: vec![lo, hi],
                stroke: Stroke::Dotted,
                color: "#000000".into(),
            });
        }
        figures.push(Figure {
            id: format!("sweep-{}", kind.to_lowercase()),
            chart: Chart {
                title: format!("Joint {kind} against the observation window (± 1 SE dashed)"),
                x_label: "T_obs (ms)".into(),
                y_label: format!("{kind} ({unit})"),
                x_log: false,
                y_log: false,
                y_range: None,
                series: lines,
            },
        });
    }
    figures.extend([
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
                    series("cond(W)", crit(&|c| c.condition_number), 0),
                    series(
                        "cond(W), unit-RMS columns",
                        crit(&|c| c.condition_number_scaled),
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
                y_label: "eigenvalue (N m/rad; N m s/rad)".into(),
                x_log: false,
                y_log: false,
                y_range: None,
                series: vec![
                    series("K, smallest", crit(&|c| c.stiffness_eigenvalues[1]), 0),
                    series("D, smallest", crit(&|c| c.damping_eigenvalues[1]), 1),
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
                    series("K", crit(&|c| c.stiffness_symmetry_ratio), 0),
                    series("D", crit(&|c| c.damping_symmetry_ratio), 1),
                ],
            },
        },
    ]);
    let never = |x: Option<f64>| x.map_or_else(|| "never".into(), fmt);
    let mut verdict = format!(
        "shortest trusted window: {} ms (precise, stable across neighbouring windows, before any change of the impedance within the trials); positive definite from {} ms, quasi-symmetric from {} ms, quasi-constant from {} ms",
        never(v.shortest_trusted_ms),
        never(v.min_positive_definite_ms),
        never(v.min_quasi_symmetric_ms),
        never(v.min_quasi_constant_ms),
    );
    if let Some(c) = &v.impedance_change {
        let _ = write!(
            verdict,
            "; the impedance changes at about {} ms after the onset (a reflex?): K by {:.0} %, D by {:.0} %",
            fmt(c.onset_ms),
            100.0 * c.stiffness_change,
            100.0 * c.damping_change
        );
    }
    Section {
        heading: format!("Observation-window sweep: {name}"),
        verdict,
        warnings: vec![],
        tables: vec![],
        figures,
        ellipsoids: vec![],
        drawings: vec![],
    }
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
    for kind in MatrixKind::ALL.map(MatrixKind::name) {
        let max = ellipsoids
            .iter()
            .filter(|e| e.kind == kind)
            .flat_map(|e| e.eigenvalues.iter().map(|v| v.abs()))
            .fold(0.0, f64::max);
        if max > 0.0 {
            kinds.push(kind);
            scale.insert(kind.into(), (0.4 * spacing / max).into());
            // a round number not above the largest eigenvalue
            let round = ellipse::round_down(max);
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
        // a round length for the position scale bar: about a fifth of the view
        "length_value": ellipse::round_down(0.2 * span),
        "units": {"stiffness": "N/m", "damping": "N s/m", "inertia": "kg"},
        "colors": {"stiffness": PALETTE[0], "damping": PALETTE[1], "inertia": PALETTE[2]},
    })
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1400px;margin:1em auto;padding:0 1em;color:#222}\
h1{font-size:1.5em}h2{font-size:1.2em;border-bottom:1px solid #ccc;margin-top:2em}\
.verdict{background:#eef5ee;border-left:4px solid #2a7;padding:.5em 1em}\
.warnings{background:#fff6e5;border-left:4px solid #e90;padding:.5em 1em}\
table{border-collapse:collapse;margin:.8em 0;font-size:.9em}td,th{border:1px solid #ccc;padding:2px 6px;text-align:left}td.num{text-align:right;font-variant-numeric:tabular-nums}\
caption{text-align:left;font-weight:bold;padding:2px;min-width:32em}.figures{display:flex;flex-wrap:wrap;gap:8px}figure{margin:0}\
#ellipsoid-kinds button{margin:2px;border:1px solid #888;background:#fff}#ellipsoid-kinds button.on{background:#cde}\
.ok{color:#1a7f37;font-weight:bold}.bad{color:#b42318;font-weight:bold}";

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
        h.push_str("<h2>Ellipsoids</h2><p>Each at its start point; co-contraction levels side by side along x, study configurations down z. Radii proportional to the eigenvalues of the symmetric part (one scale per kind, shown by the scale bars); drag to rotate, hover an ellipsoid for its name and principal values, click a kind to show or hide it.</p><div id=\"ellipsoid-kinds\"></div><div id=\"ellipsoid-view\"></div>");
        let data = viewer_data(&ellipsoids).to_string().replace("</", "<\\/");
        let _ = write!(
            h,
            "<script type=\"application/json\" id=\"ellipsoid-data\">{data}</script>"
        );
        let _ = write!(h, "<script>{}</script>", include_str!("viewer.js"));
    }
    for s in &report.sections {
        let _ = write!(h, "<h2>{}</h2>", escape(&s.heading));
        for d in &s.drawings {
            let _ = write!(
                h,
                "<figure id=\"{}\" class=\"drawing\">{}</figure>",
                escape(&d.id),
                d.svg
            );
        }
        if !s.figures.is_empty() {
            h.push_str("<div class=\"figures\">");
            for f in &s.figures {
                let _ = write!(
                    h,
                    "<figure id=\"{}\">{}</figure>",
                    escape(&f.id),
                    f.chart.to_svg(660.0, 300.0)
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
                    // numbers right-aligned, words left
                    let numeric = c
                        .split_whitespace()
                        .next()
                        .is_some_and(|w| w.parse::<f64>().is_ok());
                    if numeric {
                        let _ = write!(h, "<td class=\"num\">{}</td>", escape(c));
                    } else {
                        let _ = write!(h, "<td>{}</td>", escape(c));
                    }
                }
                h.push_str("</tr>");
            }
            h.push_str("</table>");
        }
    }
    h.push_str("<p><small>Made by limpid; opens offline.</small></p></body></html>");
    h
}

/// Size of an exported chart (px) and its text: at one journal column
/// (89 mm) the 15 px text prints at about 7 pt.
pub const EXPORT_SIZE: (f64, f64, f64) = (560.0, 360.0, 15.0);

/// Every figure as (file name stem, SVG) for `--figures DIR`, in the export
/// style ([`EXPORT_SIZE`]); [`png::svg_to_png`] makes the bitmaps.
pub fn figure_files(report: &Report) -> Vec<(String, String)> {
    let (w, h, font) = EXPORT_SIZE;
    report
        .sections
        .iter()
        .enumerate()
        .flat_map(|(i, s)| {
            s.figures
                .iter()
                .map(move |f| {
                    (
                        format!("s{}-{}", i + 1, f.id),
                        f.chart.to_svg_styled(w, h, font),
                    )
                })
                .chain(
                    s.drawings
                        .iter()
                        .map(move |d| (format!("s{}-{}", i + 1, d.id), d.svg.clone())),
                )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::unwrap_degrees;

    #[test]
    fn phase_is_unwrapped_by_whole_turns() {
        let u = unwrap_degrees([170.0, -175.0, -160.0, 179.0, -179.0, f64::NAN, 10.0]);
        assert_eq!(&u[..5], &[170.0, 185.0, 200.0, 179.0, 181.0]);
        assert!(u[5].is_nan() && u[6] == 10.0);
    }

    #[test]
    fn traces_drawn_together_start_within_half_a_turn() {
        let t = super::align_turns(vec![vec![-179.0, -178.0], vec![180.0, 181.0]], true);
        assert_eq!(t[1], vec![-180.0, -179.0]);
        let m = super::align_turns(vec![vec![1.0], vec![500.0]], false);
        assert_eq!(m[1], vec![500.0]);
    }
}
