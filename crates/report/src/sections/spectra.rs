//! The section of `limpid spectra` (seed 004 eq. 3-6): power spectral
//! densities of the named columns and, per output, its multiple coherence on
//! all inputs and its ordinary and partial coherence with each input (as the
//! stochastic estimate draws them, Fig. 10).

#[allow(unused_imports)]
use crate::*;
use limpid_ident::spectra::SpectraResult;

/// Coherence charts over the frequencies `fx` (bins `positive`): the
/// multiple coherence of every output in one chart, then per output its
/// partial coherence with each input (solid) and, where given, the ordinary
/// coherence (dashed). A coherence that does not exist is NaN: a gap.
pub(crate) fn coherence_figures(
    fx: &[f64],
    positive: &[usize],
    names: (&[String], &[String]),
    multiple: &dyn Fn(usize, usize) -> f64,
    partial: &dyn Fn(usize, usize, usize) -> f64,
    ordinary: Option<&dyn Fn(usize, usize, usize) -> f64>,
) -> Vec<Figure> {
    let (inputs, outputs) = names;
    let chart = |title: String, series: Vec<Series>| Chart {
        title,
        x_label: "frequency (Hz)".into(),
        y_label: "coherence".into(),
        x_log: true,
        y_log: false,
        y_range: Some((0.0, 1.0)),
        series,
    };
    let series = |name: String, y: Vec<f64>, stroke: Stroke, color: usize| Series {
        name,
        x: fx.to_vec(),
        y,
        stroke,
        color: PALETTE[color % PALETTE.len()].into(),
    };
    let mut figures = vec![Figure {
        id: "coherence-multiple".into(),
        chart: chart(
            "Multiple coherence of each output on all inputs".into(),
            outputs
                .iter()
                .enumerate()
                .map(|(o, name)| {
                    let y = positive.iter().map(|&f| multiple(o, f)).collect();
                    series(name.clone(), y, Stroke::Solid, o)
                })
                .collect(),
        ),
    }];
    for (o, name) in outputs.iter().enumerate() {
        let mut lines: Vec<Series> = inputs
            .iter()
            .enumerate()
            .map(|(u, input)| {
                let y = positive.iter().map(|&f| partial(o, u, f)).collect();
                let label = if ordinary.is_some() {
                    format!("{input} (partial)")
                } else {
                    input.clone()
                };
                series(label, y, Stroke::Solid, u)
            })
            .collect();
        if let Some(ordinary) = ordinary {
            lines.extend(inputs.iter().enumerate().map(|(u, input)| {
                let y = positive.iter().map(|&f| ordinary(o, u, f)).collect();
                series(format!("{input} (ordinary)"), y, Stroke::Dashed, u)
            }));
        }
        let title = if ordinary.is_some() {
            format!("Partial and ordinary coherence of {name} with each input")
        } else {
            format!("Partial coherence of {name} with each input")
        };
        figures.push(Figure {
            id: format!("coherence-partial-{name}"),
            chart: chart(title, lines),
        });
    }
    figures
}

/// `1 input`, `2 inputs`.
fn count(n: usize, noun: &str) -> String {
    format!("{n} {noun}{}", if n == 1 { "" } else { "s" })
}

/// The spectra section: PSDs, coherences and a table of the band means.
pub(crate) fn spectra_section(name: &str, r: &SpectraResult) -> Section {
    let positive: Vec<usize> = (0..r.frequencies.len())
        .filter(|&i| r.frequencies[i] > 0.0)
        .collect();
    let fx: Vec<f64> = positive.iter().map(|&i| r.frequencies[i]).collect();
    let psd = Figure {
        id: "psd".into(),
        chart: Chart {
            title: "Power spectral density of each signal".into(),
            x_label: "frequency (Hz)".into(),
            y_label: "PSD (unit² / Hz)".into(),
            x_log: true,
            y_log: true,
            y_range: None,
            series: r
                .signals
                .iter()
                .enumerate()
                .map(|(s, signal)| Series {
                    name: signal.clone(),
                    x: fx.clone(),
                    // a zero density has no place on a log axis: a gap
                    y: positive
                        .iter()
                        .map(|&f| Some(r.psd[s][f]).filter(|v| *v > 0.0).unwrap_or(f64::NAN))
                        .collect(),
                    stroke: Stroke::Solid,
                    color: PALETTE[s % PALETTE.len()].into(),
                })
                .collect(),
        },
    };
    let gap = |v: Option<f64>| v.unwrap_or(f64::NAN);
    let mut figures = vec![psd];
    figures.extend(coherence_figures(
        &fx,
        &positive,
        (&r.inputs, &r.outputs),
        &|o, f| gap(r.multiple_coherence[o][f]),
        &|o, u, f| gap(r.partial_coherence[o][u][f]),
        Some(&|o, u, f| r.coherence[o][u][f]),
    ));
    // per output: the widest band of consecutive frequencies whose multiple
    // coherence is at least 0.9 (where the inputs explain the output)
    let mut rows = Vec::new();
    let mut singular = 0;
    for (o, output) in r.outputs.iter().enumerate() {
        let values: Vec<Option<f64>> = positive
            .iter()
            .map(|&f| r.multiple_coherence[o][f])
            .collect();
        singular = singular.max(values.iter().filter(|v| v.is_none()).count());
        let (mut best, mut start) = (None::<(usize, usize)>, None::<usize>);
        for (k, v) in values.iter().chain([&None]).enumerate() {
            match (v.is_some_and(|c| c >= 0.9), start) {
                (true, None) => start = Some(k),
                (false, Some(s0)) => {
                    if best.is_none_or(|(a, b)| k - s0 > b - a) {
                        best = Some((s0, k));
                    }
                    start = None;
                }
                _ => {}
            }
        }
        rows.push(match best {
            Some((a, b)) => {
                let inside: Vec<f64> = values[a..b].iter().flatten().copied().collect();
                vec![
                    output.clone(),
                    format!("{}-{}", fmt(fx[a]), fmt(fx[b - 1])),
                    fmt(inside.iter().sum::<f64>() / inside.len() as f64),
                ]
            }
            None => vec![output.clone(), "none".into(), "n/a".into()],
        });
    }
    let mut warnings = Vec::new();
    if singular > 0 {
        warnings.push(format!(
            "at {singular} of {} frequencies the inputs' spectral matrix is singular (an input without power there): the multiple and partial coherences do not exist there and are left out",
            positive.len()
        ));
    }
    Section {
        heading: format!("Spectra: {name}"),
        verdict: format!(
            "Welch spectra of {} and {}, {} samples per segment (resolution {} Hz), {} overlapping",
            count(r.inputs.len(), "input"),
            count(r.outputs.len(), "output"),
            r.segment_samples,
            fmt(r.frequencies.get(1).copied().unwrap_or(0.0)),
            r.overlap_samples
        ),
        warnings,
        tables: vec![Table {
            caption: "Multiple coherence of each output on all inputs: the widest band where it is at least 0.9".into(),
            header: vec!["output".into(), "band (Hz)".into(), "mean coherence in the band".into()],
            rows,
        }],
        figures,
        ellipsoids: vec![],
        drawings: vec![],
    }
}
