//! The sections of the planar arm (seed 003): one estimate (joint and end-point stiffness, criteria) and the window sweep (criteria against T_obs, Fig. 4-5).

use crate::{
    ellipse, fmt, matrix_table, Chart, Drawing, EllipsoidView, Figure, Section, Series, Stroke,
    Table, PALETTE,
};
use limpid_core::Matrix;
use limpid_ident::planar::{PlanarEstimate, Sweep};
use std::fmt::Write;

pub(crate) fn planar_section(name: &str, v: &PlanarEstimate) -> Section {
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
pub(crate) fn endpoint_ellipse(k: &Matrix) -> Option<EllipsoidView> {
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
pub(crate) fn planar_quality_tables(v: &PlanarEstimate) -> Vec<Table> {
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

pub(crate) fn sweep_section(name: &str, v: &Sweep) -> Section {
    let mut figures = matrix_figures(v);
    figures.extend(criteria_figures(v));
    Section {
        heading: format!("Observation-window sweep: {name}"),
        verdict: sweep_verdict(v),
        warnings: vec![],
        tables: vec![],
        figures,
        ellipsoids: vec![],
        drawings: vec![],
    }
}

/// A sweep's line of the criterion (seed 003 §V) against the observation window.
fn window_series(v: &Sweep, name: &str, y: Vec<f64>, k: usize) -> Series {
    Series {
        name: name.into(),
        x: v.rows.iter().map(|r| r.observation_window_ms).collect(),
        y,
        stroke: Stroke::Solid,
        color: PALETTE[k].into(),
    }
}

/// Seed 003 Fig. 4-5: the joint K and D entries against T_obs, ± 1 SE
/// dashed, the shortest trusted window as a vertical line.
fn matrix_figures(v: &Sweep) -> Vec<Figure> {
    let t: Vec<f64> = v.rows.iter().map(|r| r.observation_window_ms).collect();
    let series = |name: &str, y: Vec<f64>, k: usize| window_series(v, name, y, k);
    let mut figures = Vec::new();
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
    figures
}

/// The conditioning, positive definiteness and symmetry against T_obs.
fn criteria_figures(v: &Sweep) -> [Figure; 3] {
    let crit = |f: &dyn Fn(&limpid_ident::planar::PlanarCriteria) -> f64| -> Vec<f64> {
        v.rows.iter().map(|r| f(&r.estimate.criteria)).collect()
    };
    let series = |name: &str, y: Vec<f64>, k: usize| window_series(v, name, y, k);
    [
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
    ]
}

/// The shortest windows by each criterion, and any change within the trials.
fn sweep_verdict(v: &Sweep) -> String {
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
            "; the impedance changes from about {} ms after the onset (a reflex, or soft tissue in series with the handle?): K by {} %, D by {} %",
            fmt(c.onset_ms),
            // significant digits: a change beyond f64 as a percentage reads n/a, not inf (fuzzer, issue 56)
            limpid_core::error::significant(100.0 * c.stiffness_change, 2),
            limpid_core::error::significant(100.0 * c.damping_change, 2)
        );
        if let Some(t) = &v.series_compliance {
            let _ = write!(
                verdict,
                "; a compliance in series explains the trials {:.0} times better than the rigid model: likely soft tissue under the cuff, not a reflex",
                t.residual_ratio
            );
        }
    }
    verdict
}
