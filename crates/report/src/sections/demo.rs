//! The section of `limpid demo`: seed 000's study on a virtual subject beside its truth.

use super::linear::{ellipsoids_of, fit_figures, linear_tables};
use crate::{fmt, group_warnings, Section, Table};
use limpid_analysis::linear::{MatrixKind, MatrixVerdict};
use limpid_analysis::result::demo::{DemoPoint, DemoResult};

/// A start point's errors against the truth; "n/i" for a matrix the data do
/// not identify (its error against the truth means nothing).
fn error_row(label: String, p: &DemoPoint) -> Vec<String> {
    let est = &p.estimate;
    let error = |kind: MatrixKind, percent: f64| {
        if est.criteria.verdict_of(kind) == MatrixVerdict::NotIdentifiable {
            "n/i".to_string()
        } else {
            fmt(percent)
        }
    };
    vec![
        label,
        error(MatrixKind::Stiffness, p.stiffness_error_percent),
        error(MatrixKind::Damping, p.damping_error_percent),
        error(MatrixKind::Inertia, p.inertia_error_percent),
        est.verdict(),
    ]
}

pub(crate) fn demo_section(name: &str, v: &DemoResult) -> Section {
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
        errors.rows.push(error_row(id.clone(), p));
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
    if let Some(d) = &v.designed {
        let p = &d.point;
        errors
            .rows
            .push(error_row(format!("{} designed", p.start_point), p));
        let c = &d.chosen;
        section.verdict += &format!(
            ". In the same {} s at {} within the same limits, `limpid protocol design` chooses {} (predicted K ± {:.1} %, B ± {:.1} %): row \"{} designed\"",
            fmt(d.budget_s),
            p.start_point,
            c.describe(fmt),
            d.predicted_se_percent[0],
            d.predicted_se_percent[1],
            p.start_point
        );
    }
    section.tables.insert(0, errors);
    section
}
