//! The section of a linear estimate (seeds 000, 001): Tables I-II layout, ellipsoids, measured against predicted force.

use crate::{
    fmt, force_unit, kind_unit, matrix_table, messages, Chart, EllipsoidView, Figure, Section,
    Series, Stroke, Table, PALETTE,
};
use limpid_analysis::linear::{LinearResult, MatrixKind};
use limpid_analysis::result::demo::DemoPoint;
use limpid_analysis::Ellipsoid;

pub(crate) fn ellipsoids_of(
    point: &str,
    centre: [f64; 3],
    result: &LinearResult,
) -> Vec<EllipsoidView> {
    MatrixKind::ALL
        .iter()
        .filter_map(|kind| {
            let e = result.ellipsoids.get(*kind).as_ref()?;
            ellipsoid_view(point, kind.name(), centre, e)
        })
        .collect()
}

/// One 3-D ellipsoid at `centre` (none for 2-D ones).
pub(crate) fn ellipsoid_view(
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

pub(crate) fn linear_tables(v: &LinearResult, truth: Option<&DemoPoint>) -> Vec<Table> {
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
pub(crate) fn fit_figures(prefix: &str, v: &LinearResult) -> Vec<Figure> {
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

pub(crate) fn linear_section(name: &str, v: &LinearResult) -> Section {
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
