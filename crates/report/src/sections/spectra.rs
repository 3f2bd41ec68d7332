//! The section of `limpid spectra` (seed 004 eq. 3-6): power spectral
//! densities of the named columns and, per output, its multiple coherence on
//! all inputs and its ordinary and partial coherence with each input (as the
//! stochastic estimate draws them, Fig. 10).

use crate::{fmt, Chart, Figure, Section, Series, Stroke, Table, PALETTE};
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
    // with whole periods as segments, only the excited lines carry the
    // inputs: the others would zig-zag between signal and noise
    let resolution = r.frequencies.get(1).copied().unwrap_or(0.0);
    let excited: Option<Vec<f64>> = r
        .periodic
        .as_ref()
        .filter(|p| resolution > 0.0 && (resolution * p.period_s - 1.0).abs() < 1e-6)
        .map(|p| {
            p.lines
                .iter()
                .filter(|l| l.kind == "excited")
                .map(|l| l.frequency_hz)
                .collect()
        });
    let positive: Vec<usize> = (0..r.frequencies.len())
        .filter(|&i| r.frequencies[i] > 0.0)
        .filter(|&i| {
            excited.as_ref().is_none_or(|lines| {
                lines
                    .iter()
                    .any(|f| (f - r.frequencies[i]).abs() < 0.25 * resolution)
            })
        })
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
    let mut tables = vec![Table {
        caption: "Multiple coherence of each output on all inputs: the widest band where it is at least 0.9".into(),
        header: vec!["output".into(), "band (Hz)".into(), "mean coherence in the band".into()],
        rows,
    }];
    let mut verdict_extra = String::new();
    if let Some(p) = &r.periodic {
        figures.splice(0..0, periodic_figures(p));
        tables.insert(0, periodic_table(p));
        if let Some(z) = &p.impedance {
            let at = tables.len().min(1);
            let how = format!(
                "fitted at {} excited lines, VAF {} %, residual ratio {}",
                z.lines,
                fmt(z.fit_vaf),
                fmt(z.residual_ratio)
            );
            let fitted = super::stochastic::parametric_tables(
                &r.inputs,
                &z.standard_errors,
                [&z.stiffness, &z.damping, &z.inertia],
                None,
                &how,
            );
            tables.splice(at..at, fitted);
        }
        verdict_extra = format!(
            "; periodic: {} periods of {} s ({})",
            p.periods,
            fmt(p.period_s),
            p.distortion
                .as_ref()
                .map_or("no detection line".to_string(), |d| d.verdict.clone())
        );
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
            "Welch spectra of {} and {}, {} samples per segment (resolution {} Hz), {} overlapping{verdict_extra}",
            count(r.inputs.len(), "input"),
            count(r.outputs.len(), "output"),
            r.segment_samples,
            fmt(r.frequencies.get(1).copied().unwrap_or(0.0)),
            r.overlap_samples
        ),
        warnings,
        tables,
        figures,
        ellipsoids: vec![],
        drawings: vec![],
    }
}

/// The picture of a periodic analysis (Pintelon & Schoukens): the output
/// at the excited lines, at the odd and even detection lines, and the noise
/// of the period average, in dB relative to the excited lines; then |G| at
/// each input's excited lines with its ±2 SE band.
pub(crate) fn periodic_figures(p: &limpid_ident::spectra::PeriodicResult) -> Vec<Figure> {
    let points = |kind: &str, color: usize, name: &str| Series {
        name: name.into(),
        x: p.lines
            .iter()
            .filter(|l| l.kind == kind)
            .map(|l| l.frequency_hz)
            .collect(),
        y: p.lines
            .iter()
            .filter(|l| l.kind == kind)
            .map(|l| l.output_level)
            .collect(),
        stroke: Stroke::Points,
        color: PALETTE[color].into(),
    };
    let mut levels = vec![
        points("excited", 0, "excited"),
        points("odd_detection", 1, "odd detection"),
        points("even_detection", 2, "even detection"),
    ];
    levels.retain(|s| !s.x.is_empty());
    levels.push(Series {
        name: "noise".into(),
        x: p.lines.iter().map(|l| l.frequency_hz).collect(),
        y: p.lines.iter().map(|l| l.noise_level).collect(),
        stroke: Stroke::Dashed,
        color: PALETTE[7].into(),
    });
    let mut figures = vec![Figure {
        id: "periodic-lines".into(),
        chart: Chart {
            title: "Output at excited and detection lines".into(),
            x_label: "frequency (Hz)".into(),
            y_label: "output (dB re excited)".into(),
            x_log: true,
            y_log: false,
            y_range: None,
            series: levels,
        },
    }];
    for (n, f) in p.frf.iter().enumerate() {
        let band = |sign: f64| -> Vec<f64> {
            f.magnitude
                .iter()
                .zip(&f.magnitude_se)
                .map(|(m, se)| m + sign * 2.0 * se)
                .map(|v| if v > 0.0 { v } else { f64::NAN })
                .collect()
        };
        figures.push(Figure {
            id: format!("periodic-frf-{}-{}", f.input, f.output),
            chart: Chart {
                title: format!("|G| {} to {} at excited lines", f.input, f.output),
                x_label: "frequency (Hz)".into(),
                y_label: {
                    // FORMAT.md's unit of each column, where the recording format defines it
                    let unit = |c: &str| limpid_core::recording::magnitude_limit(c).1;
                    match (unit(&f.output), unit(&f.input)) {
                        ("", _) | (_, "") => format!("|G| ({} unit / {} unit)", f.output, f.input),
                        (o, i) => format!("|G| ({o}/{i})"),
                    }
                },
                x_log: true,
                y_log: true,
                y_range: None,
                series: vec![
                    Series {
                        name: "|G|".into(),
                        x: f.frequency_hz.clone(),
                        y: f.magnitude.clone(),
                        stroke: Stroke::Points,
                        color: PALETTE[n % PALETTE.len()].into(),
                    },
                    Series {
                        name: "±2 SE".into(),
                        x: f.frequency_hz.clone(),
                        y: band(1.0),
                        stroke: Stroke::Dotted,
                        color: PALETTE[7].into(),
                    },
                    Series {
                        name: "±2 SE".into(),
                        x: f.frequency_hz.clone(),
                        y: band(-1.0),
                        stroke: Stroke::Dotted,
                        color: PALETTE[7].into(),
                    },
                ],
            },
        });
    }
    figures
}

/// The distortion levels in a table.
pub(crate) fn periodic_table(p: &limpid_ident::spectra::PeriodicResult) -> Table {
    let db = |v: Option<f64>| v.map_or("no such line".to_string(), |v| format!("{v:.1}"));
    let excited = p.lines.iter().filter(|l| l.kind == "excited").count();
    let count = |kind: &str| p.lines.iter().filter(|l| l.kind == kind).count();
    let row = match &p.distortion {
        Some(d) => vec![
            format!("{} periods of {} s", p.periods, fmt(p.period_s)),
            excited.to_string(),
            format!("{} / {}", count("odd_detection"), count("even_detection")),
            db(d.odd_db),
            db(d.even_db),
            format!("{:.1}", d.noise_db),
            d.verdict.clone(),
        ],
        None => vec![
            format!("{} periods of {} s", p.periods, fmt(p.period_s)),
            excited.to_string(),
            "0 / 0".into(),
            "no such line".into(),
            "no such line".into(),
            "n/a".into(),
            "every line in the band is excited: use an odd or random-odd multisine".into(),
        ],
    };
    Table {
        caption: format!(
            "Periodic analysis ({}): output power at the detection lines against the noise of the period average, dB relative to the excited lines",
            p.transient
        ),
        header: vec![
            "periods".into(),
            "excited lines".into(),
            "odd / even detection lines".into(),
            "odd (dB)".into(),
            "even (dB)".into(),
            "noise (dB)".into(),
            "verdict".into(),
        ],
        rows: vec![row],
    }
}
