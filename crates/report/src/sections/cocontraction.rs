//! The section of a co-contraction estimate (seed 001): one linear estimate per level, the index and the ellipsoid changes.

use super::linear::{ellipsoid_view, ellipsoids_of};
use crate::{ellipse, fmt, matrix_table, mean_sd, messages, Drawing, Section, Table};
use limpid_analysis::cocontraction::CocontractionResult;

/// Seed 001: index and stiffness per co-contraction level, ellipsoids side by side (Fig. 5).
pub(crate) fn cocontraction_section(name: &str, v: &CocontractionResult) -> Section {
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
