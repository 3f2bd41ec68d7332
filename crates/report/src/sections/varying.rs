//! The report section of impedance that varies (issue 38): K, B (and the
//! reflex gain) against time or the schedule, ±2 SE bands, a table per grid
//! point, the points the data do not support left blank with their reason.

use limpid_core::{significant, with_standard_error, Matrix};
use limpid_ident::varying::{VaryingEstimate, VaryingMethod, VaryingPoint};

use crate::svg::{Chart, Series, Stroke, PALETTE};
use crate::{Figure, Section, Table};

fn schedule_label(v: &VaryingEstimate) -> String {
    if v.schedule.unit.is_empty() {
        v.schedule.name.clone()
    } else {
        format!("{} ({})", v.schedule.name, v.schedule.unit)
    }
}

type Pick = fn(&VaryingPoint) -> (Option<&Matrix>, Option<&Matrix>);

/// One figure per quantity: each element (diagonal first) with its ±2 SE band dashed.
fn element_figure(
    v: &VaryingEstimate,
    id: &str,
    (symbol, word): (&str, &str),
    unit: &str,
    pick: Pick,
) -> Figure {
    let d = v.coordinates.len();
    let x: Vec<f64> = v.points.iter().map(|p| p.sigma).collect();
    let mut series = Vec::new();
    let mut elements: Vec<(usize, usize)> = (0..d).map(|i| (i, i)).collect();
    for i in 0..d {
        for j in 0..d {
            if i != j {
                elements.push((i, j));
            }
        }
    }
    for (k, (i, j)) in elements.into_iter().enumerate() {
        let color = PALETTE[k % PALETTE.len()].to_string();
        let at = |m: Option<&Matrix>| m.map_or(f64::NAN, |m| m[(i, j)]);
        let value: Vec<f64> = v.points.iter().map(|p| at(pick(p).0)).collect();
        let se: Vec<f64> = v.points.iter().map(|p| at(pick(p).1)).collect();
        let name = if d == 1 {
            symbol.to_string()
        } else {
            format!("{symbol}{}{}", i + 1, j + 1)
        };
        for sign in [2.0, -2.0] {
            series.push(Series {
                name: "± 2 SE".into(),
                x: x.clone(),
                y: value.iter().zip(&se).map(|(v, e)| v + sign * e).collect(),
                stroke: Stroke::Dashed,
                color: color.clone(),
            });
        }
        series.push(Series {
            name,
            x: x.clone(),
            y: value,
            stroke: Stroke::Solid,
            color,
        });
    }
    series.extend(stance_boundary(v, &series));
    Figure {
        id: id.into(),
        chart: Chart {
            title: format!(
                "{word} {symbol} against {} (± 2 SE dashed)",
                v.schedule.name
            ),
            x_label: schedule_label(v),
            y_label: format!("{symbol} ({unit})"),
            x_log: false,
            y_log: false,
            y_range: None,
            series,
        },
    }
}

/// Walking on gait phase: a dotted vertical line where stance ends, over the
/// span of the figure's other series.
fn stance_boundary(v: &VaryingEstimate, series: &[Series]) -> Option<Series> {
    let g = v.gait.as_ref()?;
    if v.schedule.unit != "fraction of the stride" {
        return None;
    }
    let ys = series
        .iter()
        .flat_map(|s| s.y.iter())
        .filter(|y| y.is_finite());
    let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
        (a.min(y), b.max(y))
    });
    (lo < hi).then(|| Series {
        name: format!("stance | swing ({})", significant(g.stance_end, 2)),
        x: vec![g.stance_end, g.stance_end],
        y: vec![lo, hi],
        stroke: Stroke::Dotted,
        color: "#777777".into(),
    })
}

/// Walking: the strides or perturbations behind each point.
fn support_figure(v: &VaryingEstimate) -> Option<Figure> {
    v.gait.as_ref()?;
    let what = if v.method == VaryingMethod::Pulses {
        "Perturbations behind each point"
    } else {
        "Strides behind each point"
    };
    let x: Vec<f64> = v.points.iter().map(|p| p.sigma).collect();
    // counts from zero: a flat 300 must not read as a spread around 300
    let top = v.points.iter().map(|p| p.support).fold(1.0, f64::max) * 1.1;
    let mut series = vec![Series {
        name: "count".into(),
        x,
        y: v.points.iter().map(|p| p.support).collect(),
        stroke: Stroke::Points,
        color: PALETTE[0].into(),
    }];
    series.extend(stance_boundary(v, &series));
    Some(Figure {
        id: "varying-support".into(),
        chart: Chart {
            title: format!("{what} against {}", v.schedule.name),
            x_label: schedule_label(v),
            y_label: "count".into(),
            x_log: false,
            y_log: false,
            y_range: Some((0.0, top)),
            series,
        },
    })
}

/// Walking: the strides left out or joined, by number.
fn flawed_table(v: &VaryingEstimate) -> Option<Table> {
    let g = v.gait.as_ref()?;
    if g.flawed.is_empty() {
        return None;
    }
    Some(Table {
        caption: format!(
            "Strides with flawed events ({} of {} between detected events)",
            g.flawed.len(),
            g.strides_found
        ),
        header: vec![
            "stride".into(),
            "start (s)".into(),
            "row".into(),
            "duration (s)".into(),
            "kind".into(),
            "what was done".into(),
        ],
        rows: g
            .flawed
            .iter()
            .map(|f| {
                vec![
                    f.stride.to_string(),
                    format!("{:.3}", f.start_s),
                    f.start_row.to_string(),
                    format!("{:.3}", f.duration_s),
                    f.kind.clone(),
                    f.note.clone(),
                ]
            })
            .collect(),
    })
}

/// I for joint coordinates (angles: q1, theta), M for end-point ones, as
/// Python's display names them.
fn inertia_symbol(v: &VaryingEstimate) -> &'static str {
    if v.coordinates
        .iter()
        .all(|c| c == "theta" || c.starts_with('q'))
    {
        "I"
    } else {
        "M"
    }
}

fn cell(m: Option<&Matrix>, se: Option<&Matrix>, i: usize, j: usize) -> String {
    match (m, se) {
        (Some(m), Some(se)) => with_standard_error(m[(i, j)], se[(i, j)]),
        _ => "—".into(),
    }
}

/// The varying section: verdict, figures, per-point table.
pub(crate) fn section(name: &str, v: &VaryingEstimate) -> Section {
    let (mu, bu, ku) = limpid_ident::linear::units(&v.coordinates);
    let mut figures = vec![
        element_figure(v, "varying-stiffness", ("K", "Stiffness"), ku, |p| {
            (p.stiffness.as_ref(), p.stiffness_se.as_ref())
        }),
        element_figure(v, "varying-damping", ("B", "Damping"), bu, |p| {
            (p.damping.as_ref(), p.damping_se.as_ref())
        }),
        element_figure(
            v,
            "varying-inertia",
            (inertia_symbol(v), "Inertia"),
            mu,
            |p| (p.inertia.as_ref(), p.inertia_se.as_ref()),
        ),
    ];
    figures.extend(reflex_gain_figure(v));
    figures.extend(support_figure(v));
    let mut tables = vec![points_table(v)];
    tables.extend(flawed_table(v));
    Section {
        heading: format!("Varying impedance: {name}"),
        verdict: verdict(v),
        warnings: v.warnings.clone(),
        tables,
        figures,
        ellipsoids: vec![],
        drawings: vec![],
    }
}

/// The method, how many points are identifiable, the fit and the reflex.
fn verdict(v: &VaryingEstimate) -> String {
    let identifiable = v.points.iter().filter(|p| p.identifiable).count();
    let method = match v.method {
        VaryingMethod::Ensemble => format!(
            "ensemble of {} {}",
            v.repetitions.unwrap_or_default(),
            if v.gait.is_some() {
                "strides"
            } else {
                "repetitions"
            }
        ),
        VaryingMethod::ParameterVarying => format!(
            "parameter-varying on {}, Chebyshev order {}",
            v.schedule.name,
            v.basis_order.unwrap_or_default()
        ),
        VaryingMethod::Pulses => format!(
            "perturbed minus unperturbed strides, {} perturbations",
            v.repetitions.unwrap_or_default()
        ),
    };
    let method = match &v.gait {
        Some(g) => format!(
            "{method} ({} of {} strides used, median {} s; {}; verdicts against walking tolerances K {} %, B {} %)",
            g.strides_used,
            g.strides_found,
            significant(g.stride_s[0], 3),
            g.baseline,
            significant(100.0 * g.tolerances[0], 2),
            significant(100.0 * g.tolerances[1], 2)
        ),
        None => method,
    };
    let mut verdict = format!(
        "{method}: {identifiable} of {} points identifiable; VAF {} % (cross-validated {} %); {}",
        v.points.len(),
        significant(v.fit.vaf, 3),
        significant(v.fit.cross_validated_vaf, 3),
        v.resolution_note
    );
    if let Some(angle) = &v.schedule.angle {
        verdict.push_str("; ");
        verdict.push_str(angle);
    }
    if let Some(r) = &v.reflex {
        verdict.push_str(&if r.detected {
            format!(
                "; reflex detected: delay {} ms, low-pass {} Hz, {} velocity, cross-validated VAF +{} points",
                significant(r.delay_s * 1e3, 3),
                significant(r.natural_hz, 2),
                r.polarity,
                significant(r.cross_validated_gain, 2)
            )
        } else {
            "; no reflex detected".to_string()
        });
    }
    verdict
}

/// The reflex gain against the schedule (± 2 SE dashed), when a reflex was fitted.
fn reflex_gain_figure(v: &VaryingEstimate) -> Option<Figure> {
    v.reflex.as_ref()?;
    let x: Vec<f64> = v.points.iter().map(|p| p.sigma).collect();
    let g: Vec<(f64, f64)> = v
        .points
        .iter()
        .map(|p| {
            p.reflex
                .as_ref()
                .map_or((f64::NAN, f64::NAN), |r| (r.gain, r.gain_se))
        })
        .collect();
    let line = |name: &str, y: Vec<f64>, stroke| Series {
        name: name.into(),
        x: x.clone(),
        y,
        stroke,
        color: PALETTE[0].into(),
    };
    Some(Figure {
        id: "varying-reflex".into(),
        chart: Chart {
            title: format!("Reflex gain against {} (± 2 SE dashed)", v.schedule.name),
            x_label: schedule_label(v),
            y_label: "G (N m s/rad)".into(),
            x_log: false,
            y_log: false,
            y_range: None,
            series: vec![
                line(
                    "± 2 SE",
                    g.iter().map(|(a, s)| a + 2.0 * s).collect(),
                    Stroke::Dashed,
                ),
                line(
                    "± 2 SE",
                    g.iter().map(|(a, s)| a - 2.0 * s).collect(),
                    Stroke::Dashed,
                ),
                line("G", g.iter().map(|(a, _)| *a).collect(), Stroke::Solid),
            ],
        },
    })
}

/// The impedance at each point: diagonal elements, value ± standard error.
fn points_table(v: &VaryingEstimate) -> Table {
    let (mu, bu, ku) = limpid_ident::linear::units(&v.coordinates);
    let d = v.coordinates.len();
    let mut header = vec![schedule_label(v)];
    let diag: Vec<(usize, usize)> = (0..d).map(|i| (i, i)).collect();
    for (q, unit) in [("K", ku), ("B", bu), (inertia_symbol(v), mu)] {
        for &(i, _) in &diag {
            let el = if d == 1 {
                q.to_string()
            } else {
                format!("{q}{}{}", i + 1, i + 1)
            };
            header.push(format!("{el} ({unit})"));
        }
    }
    if v.reflex.is_some() {
        header.push("G (N m s/rad)".into());
    }
    header.push("VAF (%)".into());
    header.push("note".into());
    let rows = v
        .points
        .iter()
        .map(|p| {
            let mut row = vec![significant(p.sigma, 4)];
            for (m, se) in [
                (p.stiffness.as_ref(), p.stiffness_se.as_ref()),
                (p.damping.as_ref(), p.damping_se.as_ref()),
                (p.inertia.as_ref(), p.inertia_se.as_ref()),
            ] {
                for &(i, j) in &diag {
                    row.push(cell(m, se, i, j));
                }
            }
            if v.reflex.is_some() {
                row.push(
                    p.reflex
                        .as_ref()
                        .map_or("—".into(), |r| with_standard_error(r.gain, r.gain_se)),
                );
            }
            row.push(p.vaf.map_or("—".into(), |x| significant(x, 3)));
            row.push(p.reason.clone().unwrap_or_default());
            row
        })
        .collect();
    Table {
        caption: format!(
            "Impedance at each point (value ± standard error{}; — : not identifiable)",
            if d > 1 {
                ", diagonal elements; the JSON has every element"
            } else {
                ""
            }
        ),
        header,
        rows,
    }
}
