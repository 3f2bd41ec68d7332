//! The text renderings of results that have one beside the HTML report:
//! a study's tables (Markdown, CSV), a reproduction's table, the demo's CSV.
//! The CLI, Python and the workflows print or write these; no front-end
//! keeps its own copy.

use std::fmt::Write as _;

use limpid_analysis::linear::MatrixKind;
use limpid_analysis::result::demo::DemoResult;
use limpid_analysis::result::reproduction::{citation, sig, Reproduction};
use limpid_analysis::result::study::{cell, StudyResult};
use limpid_core::CsvNumber;

/// Seed 001's tables as Markdown.
pub fn study_markdown(r: &StudyResult) -> String {
    // a value no recording has is a dash, never "NaN"
    let cell = |v: Option<f64>, decimals: usize| cell(v, decimals, "-");
    let mut md = format!("# {}\n\n", r.name);
    let mut levels: Vec<f64> = r.levels.iter().map(|l| l.level).collect();
    levels.sort_by(f64::total_cmp);
    levels.dedup();
    for (i, level) in levels.iter().enumerate() {
        let _ = writeln!(
            md,
            "## Table {}: stiffness at co-contraction level {level}, mean ± sd across subjects (N/m)\n",
            i + 1
        );
        md.push_str("| configuration | subjects | C | Kxx | Kyy | Kzz | K_maxA | K1 | K2 | K3 |\n|---|---|---|---|---|---|---|---|---|---|\n");
        let pm =
            |v: Option<f64>, sd: Option<f64>, decimals: usize| match sd.filter(|s| s.is_finite()) {
                Some(sd) if v.is_some() => format!("{} ± {sd:.decimals$}", cell(v, decimals)),
                _ => cell(v, decimals),
            };
        for l in r.levels.iter().filter(|l| l.level == *level) {
            let d = &l.sd;
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                l.configuration,
                l.subjects,
                pm(l.cocontraction_index, d.cocontraction_index, 3),
                pm(l.kxx, d.kxx, 1),
                pm(l.kyy, d.kyy, 1),
                pm(l.kzz, d.kzz, 1),
                pm(l.k_max_a, d.k_max_a, 1),
                pm(l.k1, d.k1, 1),
                pm(l.k2, d.k2, 1),
                pm(l.k3, d.k3, 1)
            );
        }
        md.push('\n');
    }
    let _ = writeln!(md, "## Table {}: rotation of the principal axes and change of the principal stiffnesses, lowest to highest level\n", levels.len() + 1);
    md.push_str("| configuration | subjects | Δθ1 (deg) | Δθ2 (deg) | Δθ3 (deg) | ΔK1 (%) | ΔK2 (%) | ΔK3 (%) |\n|---|---|---|---|---|---|---|---|\n");
    for x in &r.rotation {
        let g = |v: &Vec<f64>, i: usize| v.get(i).map_or("-".to_string(), |x| format!("{x:.1}"));
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            x.configuration,
            x.subjects,
            g(&x.rotation_deg, 0),
            g(&x.rotation_deg, 1),
            g(&x.rotation_deg, 2),
            g(&x.principal_change_percent, 0),
            g(&x.principal_change_percent, 1),
            g(&x.principal_change_percent, 2)
        );
    }
    if !r.failures.is_empty() {
        md.push_str("\n## Recordings left out\n\n");
        for f in &r.failures {
            let _ = writeln!(
                md,
                "- subject {}, configuration {}: {}",
                f.subject, f.configuration, f.error
            );
        }
    }
    md
}

/// A CSV cell: every digit, shortest round trip (exponents for the tiny and
/// huge); a value no recording has is an empty cell, never "NaN".
fn csv_cell(v: Option<f64>) -> String {
    v.filter(|v| v.is_finite())
        .map_or(String::new(), |v| CsvNumber(v).to_string())
}

/// A study's level table as CSV (`tables.csv`): every digit, shortest
/// round trip; a value no recording has is an empty cell, never "NaN".
pub fn study_levels_csv(r: &StudyResult) -> String {
    let mut csv = String::from(
        "configuration,level,subjects,cocontraction_index,cocontraction_index_sd,kxx,kxx_sd,kyy,kyy_sd,kzz,kzz_sd,k_max_a,k_max_a_sd,k1,k1_sd,k2,k2_sd,k3,k3_sd\n",
    );
    for l in &r.levels {
        let values = [
            l.cocontraction_index,
            l.sd.cocontraction_index,
            l.kxx,
            l.sd.kxx,
            l.kyy,
            l.sd.kyy,
            l.kzz,
            l.sd.kzz,
            l.k_max_a,
            l.sd.k_max_a,
            l.k1,
            l.sd.k1,
            l.k2,
            l.sd.k2,
            l.k3,
            l.sd.k3,
        ];
        let cells: Vec<String> = values.into_iter().map(csv_cell).collect();
        let _ = writeln!(
            csv,
            "{},{},{},{}",
            l.configuration,
            l.level,
            l.subjects,
            cells.join(",")
        );
    }
    csv
}

/// A study's rotation table as CSV (`rotation.csv`).
pub fn study_rotation_csv(r: &StudyResult) -> String {
    let mut rot = String::from("configuration,from_level,to_level,subjects,rotation_primary_deg,rotation_secondary_deg,rotation_tertiary_deg,change_primary_percent,change_secondary_percent,change_tertiary_percent\n");
    for x in &r.rotation {
        let g = |v: &Vec<f64>, i: usize| csv_cell(v.get(i).copied());
        let _ = writeln!(
            rot,
            "{},{},{},{},{},{},{},{},{},{}",
            x.configuration,
            x.from_level,
            x.to_level,
            x.subjects,
            g(&x.rotation_deg, 0),
            g(&x.rotation_deg, 1),
            g(&x.rotation_deg, 2),
            g(&x.principal_change_percent, 0),
            g(&x.principal_change_percent, 1),
            g(&x.principal_change_percent, 2)
        );
    }
    rot
}

/// The reproduction as text: one table per seed (item, paper, limpid,
/// difference), then the findings.
pub fn reproduction_text(r: &Reproduction) -> String {
    let mut s = String::new();
    let mut current = String::new();
    for x in &r.rows {
        if x.seed != current {
            current.clone_from(&x.seed);
            let _ = writeln!(
                s,
                "\n{}\n{:<78} {:>10} {:>10} {:>9}  unit",
                citation(&current),
                "item",
                "paper",
                "limpid",
                "diff"
            );
        }
        let f = |v: Option<f64>| v.map_or("-".to_string(), sig);
        let diff = x.difference();
        let _ = write!(
            s,
            "{:<78} {:>10} {:>10} {:>9}  {}",
            x.item,
            f(x.paper),
            f(x.limpid),
            diff,
            x.unit
        );
        if !x.note.is_empty() {
            let _ = write!(s, "  ({})", x.note);
        }
        s.push('\n');
    }
    s.push_str("\nfindings\n");
    for f in &r.findings {
        let _ = writeln!(
            s,
            "[{}] {}: {} — {}",
            if f.holds { "holds" } else { "DIFFERS" },
            citation(&f.seed),
            f.claim,
            f.evidence
        );
    }
    s
}

/// One row per start point and matrix kind: diagonal of truth and estimate,
/// error, identifiability.
pub fn demo_csv(result: &DemoResult) -> String {
    let mut s = String::from("start_point,x,y,z,kind,true_xx,true_yy,true_zz,est_xx,est_yy,est_zz,error_percent,identifiable\n");
    for d in &result.points {
        let e = &d.estimate;
        for kind in MatrixKind::ALL {
            let (t, m) = (d.truth(kind), e.matrix(kind));
            let ok = match kind {
                MatrixKind::Stiffness => e.criteria.identifiable.stiffness,
                MatrixKind::Damping => e.criteria.identifiable.damping,
                MatrixKind::Inertia => e.criteria.identifiable.inertia,
            };
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{},{},{},{},{},{:.4},{ok}",
                d.start_point,
                CsvNumber(d.position[0]),
                CsvNumber(d.position[1]),
                CsvNumber(d.position[2]),
                kind.name(),
                CsvNumber(t[(0, 0)]),
                CsvNumber(t[(1, 1)]),
                CsvNumber(t[(2, 2)]),
                CsvNumber(m[(0, 0)]),
                CsvNumber(m[(1, 1)]),
                CsvNumber(m[(2, 2)]),
                d.error_percent(kind)
            );
        }
    }
    s
}
