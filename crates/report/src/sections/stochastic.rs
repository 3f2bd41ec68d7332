//! The section of a stochastic MIMO estimate (seed 004): Bode plots of Z(f) with the parametric fit (Fig. 9), multiple and partial coherences (Fig. 10), criteria and verdicts.

use crate::{
    element_unit, fmt, kind_unit, matrix_element_unit, matrix_table, messages, Chart, Figure,
    Section, Series, Stroke, Table, PALETTE,
};
use limpid_analysis::linear::{MatrixKind, MatrixVerdict};
use limpid_core::Matrix;
use limpid_ident::stochastic::StochasticEstimate;
use std::fmt::Write;

/// The stochastic estimate's verdicts and the criteria behind them (seed 004
/// §III: coherences, input coherence, fit of the parametric model).
pub(crate) fn stochastic_criteria_table(v: &StochasticEstimate) -> Table {
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
        if v.periodic.is_some() {
            vec![
                "inputs at each other's lines".into(),
                fmt(c.max_input_coherence),
                "largest power of another input (command, or displacement without commands) at an input's excited line, relative to its own (0: zippered)".into(),
            ]
        } else {
            vec![
                "largest input coherence".into(),
                fmt(c.max_input_coherence),
                "between two perturbation inputs; Park & Chang (2011) asks below 0.6".into(),
            ]
        },
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
            if v.periodic.is_some() {
                "periods"
            } else {
                "Welch"
            }
            .into(),
            format!(
                "{} {} of {} samples",
                c.segments,
                if v.periodic.is_some() {
                    "whole periods"
                } else {
                    "segments"
                },
                c.nperseg
            ),
            format!("resolution {} Hz", fmt(c.frequency_resolution_hz)),
        ],
    ]);
    Table {
        caption: "Verdicts and the criteria behind them".into(),
        header: vec!["item".into(), "value".into(), "meaning".into()],
        rows,
    }
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

/// Phase traces drawn together on one branch: the reference trace (the
/// smooth parametric fit) is unwrapped along frequency and every other trace
/// is moved, point by point, by whole turns to lie within 180° of the
/// reference at the same frequency. An estimate at +179° and its fit at
/// -181° are the same phase; drawn on different branches they look like a
/// failed fit. Where the reference is not finite the last finite value
/// serves; without any, each trace is unwrapped on its own.
pub(crate) fn on_one_branch(mut traces: Vec<Vec<f64>>, reference: usize) -> Vec<Vec<f64>> {
    let Some(r) = traces.get(reference) else {
        return traces;
    };
    let mut anchor = f64::NAN;
    let guide: Vec<f64> = unwrap_degrees(r.iter().copied())
        .into_iter()
        .map(|v| {
            if v.is_finite() {
                anchor = v;
            }
            anchor
        })
        .collect();
    if guide.iter().all(|v| !v.is_finite()) {
        return traces
            .into_iter()
            .map(|t| unwrap_degrees(t.iter().copied()))
            .collect();
    }
    let first = guide.iter().copied().find(|v| v.is_finite()).unwrap_or(0.0);
    for (k, t) in traces.iter_mut().enumerate() {
        if k == reference {
            *t = unwrap_degrees(t.iter().copied());
            continue;
        }
        for (n, v) in t.iter_mut().enumerate() {
            let g = guide
                .get(n)
                .copied()
                .filter(|g| g.is_finite())
                .unwrap_or(first);
            if v.is_finite() {
                *v -= 360.0 * ((*v - g) / 360.0).round();
            }
        }
    }
    traces
}

/// Z(f) element (i, j) of a model M, B, K: K - ω² M + j ω B.
pub(crate) fn model_z(
    m: &Matrix,
    b: &Matrix,
    k: &Matrix,
    i: usize,
    j: usize,
    f: f64,
) -> (f64, f64) {
    let w = 2.0 * std::f64::consts::PI * f;
    (k[(i, j)] - w * w * m[(i, j)], w * b[(i, j)])
}

/// Bode plots of every element of Z (seed 004 Fig. 9): the estimate with its
/// 95 % band from the coherences, the parametric fit and, with `--expected`,
/// the expected model, over the frequencies `fx` (bins `positive`).
fn bode_figures(v: &StochasticEstimate, positive: &[usize], fx: &[f64]) -> Vec<Figure> {
    let coords = &v.coordinates;
    let n = coords.len();
    let expected = v.accuracy.as_ref().map(|a| &a.expected);
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
            // the fit is curves[FIT_CURVE]: the other phases are drawn on its branch
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
            let eps = coherence_errors(v, positive, i, j);
            let element = format!("Z[{},{}]", coords[i], coords[j]);
            let unit = element_unit(&coords[i], &coords[j]);
            let mk = |phase: bool| bode_chart(&element, unit, &curves, fx, phase);
            figures.push(Figure {
                id: format!("bode-mag-{}{}", coords[i], coords[j]),
                chart: with_band(mk(false), &eps, fx, false),
            });
            figures.push(Figure {
                id: format!("bode-phase-{}{}", coords[i], coords[j]),
                chart: with_band(mk(true), &eps, fx, true),
            });
        }
    }
    figures
}

/// The random error of Z[i][j] per frequency from the coherences (Bendat &
/// Piersol's gain-factor error sqrt(1 - g^2) / (|g| sqrt(2 n_d)) of the force
/// i and position j outputs, added in quadrature); the band is ± 2 errors.
fn coherence_errors(v: &StochasticEstimate, positive: &[usize], i: usize, j: usize) -> Vec<f64> {
    let n = v.coordinates.len();
    let nd = v.criteria.segments.max(1) as f64;
    let error = |o: usize, f: usize| {
        let g2 = v.coherence.multiple.get(o).and_then(|m| m.get(f)).copied();
        g2.filter(|g| *g > 0.0 && *g <= 1.0)
            .map_or(f64::INFINITY, |g| ((1.0 - g) / (2.0 * nd * g)).sqrt())
    };
    positive
        .iter()
        .map(|&f| error(n + i, f).hypot(error(j, f)))
        .collect()
}

/// The chart with its 95 % band (± 2 errors `eps`) around the estimate.
fn with_band(mut chart: Chart, eps: &[f64], fx: &[f64], phase: bool) -> Chart {
    let y = chart.series[0].y.clone();
    for sign in [1.0, -1.0] {
        let band: Vec<f64> = y
            .iter()
            .zip(eps)
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
                x: fx.to_vec(),
                y: band,
                stroke: Stroke::Dotted,
                color: PALETTE[0].into(),
            },
        );
    }
    chart
}

/// Index of the parametric fit among a Bode chart's curves.
const FIT_CURVE: usize = 1;

/// A curve of Z: label, `(re, im)` per frequency, stroke, colour.
type Curve<'a> = (&'a str, Vec<(f64, f64)>, Stroke, &'a str);

/// The magnitude (log) or unwrapped phase of each curve `(label, Z, stroke, colour)`.
fn bode_chart(element: &str, unit: &str, curves: &[Curve<'_>], fx: &[f64], phase: bool) -> Chart {
    Chart {
        title: format!("{element} {}", if phase { "phase" } else { "magnitude" }),
        x_label: "frequency (Hz)".into(),
        y_label: if phase {
            "phase (deg)".into()
        } else {
            format!("|Z| ({unit})")
        },
        x_log: true,
        y_log: !phase,
        y_range: None,
        series: curves
            .iter()
            .zip({
                let traces: Vec<Vec<f64>> = curves
                    .iter()
                    .map(|(_, c, _, _)| {
                        if phase {
                            c.iter()
                                .map(|(re, im)| im.atan2(*re).to_degrees())
                                .collect()
                        } else {
                            c.iter().map(|(re, im)| re.hypot(*im)).collect()
                        }
                    })
                    .collect();
                if phase {
                    on_one_branch(traces, FIT_CURVE)
                } else {
                    traces
                }
            })
            .map(|((label, _, stroke, color), y)| Series {
                name: (*label).into(),
                x: fx.to_vec(),
                y,
                stroke: *stroke,
                color: (*color).into(),
            })
            .collect(),
    }
}

pub(crate) fn stochastic_section(name: &str, v: &StochasticEstimate) -> Section {
    let freqs = &v.frequencies;
    let coords = &v.coordinates;
    let expected = v.accuracy.as_ref().map(|a| &a.expected);
    let band = (v.criteria.band_hz[0], v.criteria.band_hz[1]);
    let positive: Vec<usize> = (0..freqs.len()).filter(|&i| freqs[i] > 0.0).collect();
    let fx: Vec<f64> = positive.iter().map(|&i| freqs[i]).collect();
    let mut figures = bode_figures(v, &positive, &fx);
    // coherences (seed 004 Fig. 10)
    let (multiple, partial) = (&v.coherence.multiple, &v.coherence.partial);
    figures.extend(super::spectra::coherence_figures(
        &fx,
        &positive,
        (&v.inputs, &v.coherence.outputs),
        &|o, f| multiple[o][f],
        &|o, u, f| partial[o][u][f],
        None,
    ));
    let c = &v.criteria;
    let inputs = match &v.periodic {
        Some(p) => format!(
            "{} periods of {} s averaged; {}",
            p.periods,
            fmt(p.period_s),
            p.distortion.as_ref().map_or_else(
                || "no detection lines".to_string(),
                |d| format!("the detection lines say {}", d.verdict)
            )
        ),
        None => format!("largest input coherence {}", fmt(c.max_input_coherence)),
    };
    let mut verdict = format!(
        "mean multiple coherence {} (lowest {}) over {}-{} Hz; {inputs}; parametric fit VAF {} %",
        fmt(c.mean_multiple_coherence),
        fmt(c.min_multiple_coherence),
        fmt(band.0),
        fmt(band.1),
        fmt(c.fit_vaf)
    );
    if let Some(a) = &v.accuracy {
        let _ = write!(
            verdict,
            "; mean relative error vs. the expected model {} %",
            fmt(100.0 * a.mean_relative_error)
        );
    }
    let matrix_tables = parametric_tables(
        coords,
        &v.standard_errors,
        [&v.stiffness, &v.damping, &v.inertia],
        expected.map(|e| [&e.stiffness, &e.damping, &e.inertia]),
        "parametric fit over the band",
    );
    let mut tables = vec![stochastic_criteria_table(v)];
    tables.extend(matrix_tables);
    if let Some(p) = &v.periodic {
        // the lines and distortion of the commands' periodic analysis
        tables.push(super::spectra::periodic_table(p));
        figures.extend(super::spectra::periodic_figures(p));
    }
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

/// K, B and M of a parametric fit with their standard errors (and truth),
/// one table each, units per element where the coordinates mix m and rad.
pub(crate) fn parametric_tables(
    coords: &[String],
    se: &limpid_ident::stochastic::ParametricErrors,
    [k, b, m]: [&limpid_core::Matrix; 3],
    truth: Option<[&limpid_core::Matrix; 3]>,
    how: &str,
) -> Vec<Table> {
    [
        (
            MatrixKind::Stiffness,
            "K",
            k,
            &se.stiffness,
            truth.map(|t| t[0]),
        ),
        (
            MatrixKind::Damping,
            "B",
            b,
            &se.damping,
            truth.map(|t| t[1]),
        ),
        (
            MatrixKind::Inertia,
            "M",
            m,
            &se.inertia,
            truth.map(|t| t[2]),
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
            &format!("{sym} ({}, {unit}, {how}) ± standard error", kind.name()),
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
    .collect()
}
