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
mod sections;
pub mod svg;
pub mod text;

use std::fmt::Write as _;

use sections::calibration::calibration_section;
use sections::cocontraction::cocontraction_section;
use sections::demo::demo_section;
use sections::design;
use sections::linear::linear_section;
use sections::planar::{planar_section, sweep_section};
use sections::reflex::reflex_section;
use sections::spectra::spectra_section;
use sections::stochastic::stochastic_section;
pub use sections::stochastic::unwrap_degrees;
use sections::study::study_section;
use sections::varying;

use limpid_analysis::linear::MatrixKind;
use limpid_analysis::result::Estimate;
use limpid_core::{Matrix, Warning};
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
            Estimate::Spectra(r) => spectra_section(name, r),
            Estimate::Reflex(r) => reflex_section(name, r),
            Estimate::WindowSweep(r) => sweep_section(name, r),
            Estimate::Planar(r) => planar_section(name, r),
            Estimate::Study(r) => study_section(name, r),
            Estimate::Cocontraction(r) => cocontraction_section(name, r),
            Estimate::Calibration(r) => calibration_section(name, r),
            Estimate::Design(r) => design::section(name, r),
            Estimate::ReflexDesign(r) => design::reflex_section(name, r),
            Estimate::PlanarDesign(r) => design::planar_section(name, r),
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

/// How a result was made (limpid_analysis::result::Run) as the first table
/// of its section: the files read (size, modification time), the command
/// line, limpid's version and when.
/// The report of result documents, each section under its name, with how
/// each was made (the run table) first where the document says.
pub fn build_documents(docs: &[(String, &limpid_analysis::result::Document)]) -> Report {
    let inputs: Vec<(String, Estimate)> = docs
        .iter()
        .map(|(name, d)| (name.clone(), d.estimate.clone()))
        .collect();
    let mut report = build(&inputs);
    for (section, (_, doc)) in report.sections.iter_mut().zip(docs) {
        if let Some(run) = &doc.run {
            section.tables.insert(0, run_table(run));
        }
    }
    report
}

/// The name of the `i`-th result's section: the file name of the recording
/// the result names, else of the first input its run read, else `result i+1`.
pub fn section_name(doc: &limpid_analysis::result::Document, i: usize) -> String {
    use std::path::Path;
    let file_name = |p: &Path| {
        p.file_name().map_or_else(
            || p.display().to_string(),
            |f| f.to_string_lossy().into_owned(),
        )
    };
    let source = doc
        .run
        .as_ref()
        .and_then(|r| r.inputs.first())
        .map(|f| std::path::PathBuf::from(&f.path));
    doc.estimate
        .recording()
        .map(|r| file_name(Path::new(r)))
        .or_else(|| source.as_deref().map(file_name))
        .unwrap_or_else(|| format!("result {}", i + 1))
}

/// The HTML page of one result document (a command's `--report FILE`).
pub fn page(doc: &limpid_analysis::result::Document) -> String {
    to_html(&build_documents(&[(section_name(doc, 0), doc)]))
}

/// The table of how a result was made: version, command line, inputs.
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
            // what was read of a recording: its samples, rate and length
            let read = match (f.samples, f.sample_rate_hz, f.duration_s) {
                (Some(n), Some(fs), Some(d)) => {
                    format!("; {n} samples at {} Hz, {} s", fmt(fs), fmt(d))
                }
                _ => String::new(),
            };
            vec![
                "input".into(),
                format!("{} ({size}{modified}{read})", f.path),
            ]
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
    use super::sections::stochastic::on_one_branch;
    use super::unwrap_degrees;

    #[test]
    fn phase_is_unwrapped_by_whole_turns() {
        let u = unwrap_degrees([170.0, -175.0, -160.0, 179.0, -179.0, f64::NAN, 10.0]);
        assert_eq!(&u[..5], &[170.0, 185.0, 200.0, 179.0, 181.0]);
        assert!(u[5].is_nan() && u[6] == 10.0);
    }

    #[test]
    fn phases_drawn_together_share_the_fits_branch() {
        // the fit wraps from +179 to -179 (unwrapped: 181); the estimate sits
        // at -178 (= 182) and +178: each point lands within 180° of the fit
        let fit = vec![170.0, 179.0, -179.0, -170.0];
        let est = vec![-178.0, 178.0, -178.0, f64::NAN];
        let t = on_one_branch(vec![est, fit], 1);
        assert_eq!(t[1], vec![170.0, 179.0, 181.0, 190.0]);
        assert_eq!(&t[0][..3], &[182.0, 178.0, 182.0]);
        assert!(t[0][3].is_nan());
        // no finite reference: each trace unwrapped on its own
        let u = on_one_branch(vec![vec![170.0, -175.0], vec![f64::NAN, f64::NAN]], 1);
        assert_eq!(u[0], vec![170.0, 185.0]);
    }
}
