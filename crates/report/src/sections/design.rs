//! The section of a designed protocol (`limpid protocol design`, issue 60):
//! predicted against baseline precision, the margins to the limits, one
//! perturbation of the command and its frequency content against the limits.

use limpid_analysis::result::design::{DesignResult, LimitMargin, Prediction};

use std::fmt::Write as _;

use crate::svg::{escape, Chart, Series, Stroke, PALETTE};
use crate::{fmt, Drawing, Figure, Section, Table};

/// The end-point methods' three matrices and their units.
const MATRICES: [(&str, &str); 3] = [("K", "N/m"), ("B", "N s/m"), ("M", "kg")];
/// The planar method's joint K and D and inertial parameters ξ.
const JOINT_GROUPS: [(&str, &str); 3] = [("K", "N m/rad"), ("D", "N m s/rad"), ("ξ", "kg m²")];

fn prediction_rows(label: &str, p: &Prediction, groups: &[(&str, &str); 3]) -> Vec<Vec<String>> {
    (0..3)
        .map(|m| {
            vec![
                label.to_string(),
                format!("{} ({})", groups[m].0, groups[m].1),
                fmt(p.pooled.se[m]),
                format!("{:.1}", p.pooled.se_percent[m]),
                format!("{:.1}", p.pooled.error_percent[m]),
                format!("{:.0}", 100.0 * p.identifiable_share[m]),
                format!("{:.1}", p.duration_s),
            ]
        })
        .collect()
}

/// The largest value a protocol reaches against each limit.
fn margins_table(limits: &[LimitMargin]) -> Table {
    Table {
        caption: "Largest value reached against each limit".into(),
        header: ["quantity", "peak", "limit", "unit", "margin %"]
            .map(String::from)
            .to_vec(),
        rows: limits
            .iter()
            .map(|m| {
                vec![
                    m.quantity.clone(),
                    fmt(m.peak),
                    fmt(m.limit),
                    m.unit.clone(),
                    format!("{:.1}", m.margin_percent),
                ]
            })
            .collect(),
    }
}

/// Predicted relative SEs of the three groups (`names`: K, B, M) as bars,
/// the design's beside the baseline's, on a log scale (percent of the RMS
/// element).
fn se_bars(design: &Prediction, baseline: Option<&Prediction>, names: [&str; 3]) -> String {
    let (width, height, left, bottom, top) = (460.0, 240.0, 60.0, 40.0, 36.0);
    let values: Vec<f64> = design
        .pooled
        .se_percent
        .iter()
        .chain(baseline.iter().flat_map(|b| b.pooled.se_percent.iter()))
        .copied()
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    let hi = values
        .iter()
        .fold(1.0f64, |a, v| a.max(*v))
        .log10()
        .ceil()
        .max(1.0);
    let lo = values
        .iter()
        .fold(hi, |a, v| a.min(v.log10()))
        .floor()
        .min(hi - 1.0);
    let y =
        |v: f64| top + (height - top - bottom) * (hi - v.max(10f64.powf(lo)).log10()) / (hi - lo);
    let title = format!(
        "Predicted SE of {}, {} and {} (% of the RMS element; n/i: mostly not identifiable)",
        names[0], names[1], names[2]
    );
    let mut s = format!(
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="12"><title>{}</title><rect width="{width}" height="{height}" fill="#fff"/><text x="{}" y="18" text-anchor="middle" font-weight="bold">{}</text>"##,
        escape(&title),
        width / 2.0,
        escape(&title)
    );
    let mut decade = lo;
    while decade <= hi + 1e-9 {
        let yy = y(10f64.powf(decade));
        let _ = write!(
            s,
            r##"<line x1="{left}" x2="{}" y1="{yy:.1}" y2="{yy:.1}" stroke="#ddd"/><text x="{}" y="{:.1}" text-anchor="end">{}</text>"##,
            width - 10.0,
            left - 6.0,
            yy + 4.0,
            fmt(10f64.powf(decade))
        );
        decade += 1.0;
    }
    let group = (width - left - 10.0) / 3.0;
    let bars: Vec<(&str, &Prediction, &str)> = std::iter::once(("design", design, PALETTE[0]))
        .chain(baseline.map(|b| ("baseline", b, PALETTE[1])))
        .collect();
    let bar = group * 0.7 / bars.len() as f64;
    for (m, name) in names.iter().enumerate() {
        let x0 = left + group * m as f64 + group * 0.15;
        for (k, (label, p, colour)) in bars.iter().enumerate() {
            let v = p.pooled.se_percent[m];
            if !(v.is_finite() && v > 0.0) {
                continue;
            }
            let (x, yy) = (x0 + bar * k as f64, y(v));
            // a spread of estimates the criteria mostly call not identifiable is
            // the estimator's prior, not the data: drawn faint and labelled n/i
            let identified = p.identifiable_share[m] >= 0.5;
            let (opacity, text) = if identified {
                ("1", format!("{v:.1}"))
            } else {
                ("0.3", format!("{v:.1} n/i"))
            };
            let _ = write!(
                s,
                r##"<rect x="{x:.1}" y="{yy:.1}" width="{:.1}" height="{:.1}" fill="{colour}" fill-opacity="{opacity}"><title>{label} {name}: {v:.1} %</title></rect><text x="{:.1}" y="{:.1}" text-anchor="middle" font-size="10">{text}</text>"##,
                bar - 2.0,
                (height - bottom - yy).max(0.0),
                x + bar / 2.0 - 1.0,
                yy - 3.0
            );
        }
        let _ = write!(
            s,
            r##"<text x="{:.1}" y="{:.1}" text-anchor="middle">{name}</text>"##,
            left + group * (m as f64 + 0.5),
            height - bottom + 16.0
        );
    }
    for (k, (label, _, colour)) in bars.iter().enumerate() {
        let x = left + 10.0 + 110.0 * k as f64;
        let _ = write!(
            s,
            r##"<rect x="{x}" y="{}" width="10" height="10" fill="{colour}"/><text x="{}" y="{}">{label}</text>"##,
            height - 14.0,
            x + 14.0,
            height - 5.0
        );
    }
    s.push_str("</svg>");
    s
}

fn series(name: &str, x: &[f64], y: &[f64], stroke: Stroke, colour: usize) -> Series {
    Series {
        name: name.into(),
        x: x.to_vec(),
        y: y.iter()
            .map(|&v| if v > 0.0 { v } else { f64::NAN })
            .collect(),
        stroke,
        color: PALETTE[colour % PALETTE.len()].into(),
    }
}

pub(crate) fn section(name: &str, r: &DesignResult) -> Section {
    let mut verdict = format!(
        "{}: {:.1} s of the {} s budget at ({}, {}, {}) m. Predicted on the prior ({} simulated recordings): K ± {:.1} %, B ± {:.1} %, M ± {:.1} % (RMS element s.d. relative to the RMS element).",
        r.chosen.describe(fmt),
        r.chosen.duration_s(),
        fmt(r.budget_s),
        fmt(r.start_m[0]),
        fmt(r.start_m[1]),
        fmt(r.start_m[2]),
        r.predicted.runs,
        r.predicted.pooled.se_percent[0],
        r.predicted.pooled.se_percent[1],
        r.predicted.pooled.se_percent[2],
    );
    if let Some(b) = &r.baseline {
        verdict += &format!(
            " The protocol it replaces: K ± {:.1} %, B ± {:.1} %, M ± {:.1} % in {:.1} s.",
            b.pooled.se_percent[0], b.pooled.se_percent[1], b.pooled.se_percent[2], b.duration_s
        );
    }
    if let Some(v) = &r.verify {
        verdict += &format!(
            " Checked on {} subjects drawn from the prior: predicted/achieved spread K {:.2}, B {:.2}, M {:.2}; K within 5 % and B within 20 %, both identifiable, in {:.0} % of them.",
            v.runs, v.ratio[0], v.ratio[1], v.ratio[2], 100.0 * v.within_tolerance_share
        );
    }
    let mut rows = prediction_rows("design", &r.predicted, &MATRICES);
    if let Some(b) = &r.baseline {
        rows.extend(prediction_rows("baseline", b, &MATRICES));
    }
    let precision = Table {
        caption: "Predicted precision on the prior subject: RMS standard error of the nine elements, relative to the RMS element, mean relative Frobenius error and share of recordings called identifiable".into(),
        header: ["protocol", "matrix", "SE", "SE %", "error %", "identifiable %", "duration (s)"]
            .map(String::from)
            .to_vec(),
        rows,
    };
    let margins = margins_table(&r.limits);
    let cmd = &r.command;
    let peak = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs())).max(1e-300);
    let (dp, vp, ap) = (
        peak(&cmd.displacement_m),
        peak(&cmd.velocity_m_s),
        peak(&cmd.acceleration_m_s2),
    );
    let command = Figure {
        id: "design-command".into(),
        chart: Chart {
            title: if r.family == "multisine" {
                "One period of x, relative to each peak".into()
            } else {
                "One perturbation, relative to each peak".into()
            },
            x_label: if r.family == "multisine" {
                "time from the period's start (s)".into()
            } else {
                "time from the trial's start (s)".into()
            },
            y_label: "share of the peak".into(),
            x_log: false,
            y_log: false,
            y_range: Some((-1.05, 1.05)),
            series: vec![
                Series {
                    name: format!("displacement (peak {} mm)", fmt(dp * 1e3)),
                    x: cmd.t_s.clone(),
                    y: cmd.displacement_m.iter().map(|v| v / dp).collect(),
                    stroke: Stroke::Solid,
                    color: PALETTE[0].into(),
                },
                Series {
                    name: format!("velocity (peak {} m/s)", fmt(vp)),
                    x: cmd.t_s.clone(),
                    y: cmd.velocity_m_s.iter().map(|v| v / vp).collect(),
                    stroke: Stroke::Dashed,
                    color: PALETTE[1].into(),
                },
                Series {
                    name: format!("acceleration (peak {} m/s²)", fmt(ap)),
                    x: cmd.t_s.clone(),
                    y: cmd.acceleration_m_s2.iter().map(|v| v / ap).collect(),
                    stroke: Stroke::Dotted,
                    color: PALETTE[2].into(),
                },
            ],
        },
    };
    let s = &r.spectrum;
    let mut lines = vec![
        series(
            "design",
            &s.frequency_hz,
            &s.designed_m,
            // a multisine's spectrum is its excited lines
            if r.family == "multisine" {
                Stroke::Points
            } else {
                Stroke::Solid
            },
            0,
        ),
        series(
            "limits: min(d, v/ω, a/ω²)",
            &s.frequency_hz,
            &s.limit_m,
            Stroke::Dashed,
            6,
        ),
    ];
    if let Some(b) = &s.baseline_m {
        lines.push(series("baseline", &s.frequency_hz, b, Stroke::Solid, 1));
    }
    let spectrum = Figure {
        id: "design-spectrum".into(),
        chart: Chart {
            title: "Amplitude 2|X(f)|/T and the limits".into(),
            x_label: "frequency (Hz)".into(),
            y_label: "amplitude (m)".into(),
            x_log: true,
            y_log: true,
            y_range: None,
            series: lines,
        },
    };
    Section {
        heading: format!("Designed protocol: {name}"),
        verdict,
        warnings: vec![],
        tables: vec![precision, margins],
        figures: vec![command, spectrum],
        ellipsoids: vec![],
        drawings: vec![Drawing {
            id: "design-se".into(),
            svg: se_bars(&r.predicted, r.baseline.as_ref(), ["K", "B", "M"]),
        }],
    }
}

/// The section of a PRBS designed for the reflex method.
pub(crate) fn reflex_section(
    name: &str,
    r: &limpid_analysis::result::design::ReflexDesignResult,
) -> Section {
    let c = &r.chosen;
    let mut verdict = format!(
        "PRBS of {} rad, {} ms switching, order {}, {} periods with a fade-in and a fade-out period: {:.1} s of the {} s budget. Predicted reflex gain spread {} N m s/rad ({} simulated recordings; the estimator's own SE {} on average)",
        fmt(c.amplitude_rad),
        fmt(c.switch_interval_s * 1e3),
        c.order,
        c.periods,
        c.duration_s,
        fmt(r.budget_s),
        fmt(r.predicted.gain_sd),
        r.predicted.runs,
        fmt(r.predicted.gain_se_mean)
    );
    if let (Some(b), Some(ratio)) = (&r.baseline, r.gain_spread_ratio) {
        verdict += &format!(
            "; the protocol it replaces: {} (the design's spread is {:.2} of it)",
            fmt(b.gain_sd),
            ratio
        );
    }
    verdict.push('.');
    let row = |label: &str, p: &limpid_analysis::result::design::ReflexPrediction| {
        vec![
            label.to_string(),
            fmt(p.gain_sd),
            fmt(p.gain_se_mean),
            format!("{:.2}", p.gain_error_percent),
            fmt(p.intrinsic_sd[0]),
            fmt(p.intrinsic_sd[1]),
            format!("{:.1}", p.duration_s),
        ]
    };
    let mut rows = vec![row("design", &r.predicted)];
    if let Some(b) = &r.baseline {
        rows.push(row("baseline", b));
    }
    Section {
        heading: format!("Designed PRBS for the reflex gain: {name}"),
        verdict,
        warnings: vec![],
        tables: vec![
            Table {
                caption: "Predicted on the prior ankle: spread of the reflex gain, the estimator's mean SE, mean error, spread of the intrinsic K and B".into(),
                header: [
                    "protocol",
                    "gain s.d. (N m s/rad)",
                    "gain SE (N m s/rad)",
                    "gain error %",
                    "K s.d. (N m/rad)",
                    "B s.d. (N m s/rad)",
                    "duration (s)",
                ]
                .map(String::from)
                .to_vec(),
                rows,
            },
            margins_table(&r.limits),
        ],
        figures: reflex_figures(r),
        ellipsoids: vec![],
        drawings: vec![],
    }
}

/// The PRBS's first seconds and its lines against the limits (results
/// written before these were kept have neither).
fn reflex_figures(r: &limpid_analysis::result::design::ReflexDesignResult) -> Vec<Figure> {
    let mut figures = Vec::new();
    if let Some(cmd) = &r.command {
        figures.push(joint_command_figure(
            "reflex-design-command",
            "The start of one period, relative to each peak",
            "time from the period's start (s)",
            cmd,
        ));
    }
    if let Some(s) = &r.spectrum {
        let mut lines = vec![
            series(
                "design",
                &s.frequency_hz,
                &s.designed_rad,
                Stroke::Points,
                0,
            ),
            series(
                "limits: min(d, v/ω, a/ω²)",
                &s.frequency_hz,
                &s.limit_rad,
                Stroke::Dashed,
                6,
            ),
        ];
        if let (Some(f), Some(b)) = (&s.baseline_frequency_hz, &s.baseline_rad) {
            lines.push(series("baseline", f, b, Stroke::Points, 1));
        }
        figures.push(Figure {
            id: "reflex-design-spectrum".into(),
            chart: Chart {
                title: "Amplitude of each line of one period, 2|X_k|/n, and the limits".into(),
                x_label: "frequency (Hz)".into(),
                y_label: "amplitude (rad)".into(),
                x_log: true,
                y_log: true,
                y_range: None,
                series: lines,
            },
        });
    }
    figures
}

/// A joint command's displacement, velocity and acceleration, each relative to its peak.
fn joint_command_figure(
    id: &str,
    title: &str,
    x_label: &str,
    cmd: &limpid_analysis::result::design::JointCommandTrace,
) -> Figure {
    let peak = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs())).max(1e-300);
    let relative = |v: &[f64]| {
        let p = peak(v);
        (p, v.iter().map(|x| x / p).collect::<Vec<f64>>())
    };
    let (dp, d) = relative(&cmd.displacement_rad);
    let (vp, v) = relative(&cmd.velocity_rad_s);
    let (ap, a) = relative(&cmd.acceleration_rad_s2);
    Figure {
        id: id.into(),
        chart: Chart {
            title: title.into(),
            x_label: x_label.into(),
            y_label: "share of the peak".into(),
            x_log: false,
            y_log: false,
            y_range: Some((-1.05, 1.05)),
            series: [
                (
                    format!("displacement (peak {} rad)", fmt(dp)),
                    d,
                    Stroke::Solid,
                ),
                (
                    format!("velocity (peak {} rad/s)", fmt(vp)),
                    v,
                    Stroke::Dashed,
                ),
                (
                    format!("acceleration (peak {} rad/s²)", fmt(ap)),
                    a,
                    Stroke::Dotted,
                ),
            ]
            .into_iter()
            .enumerate()
            .map(|(k, (name, y, stroke))| Series {
                name,
                x: cmd.t_s.clone(),
                y,
                stroke,
                color: PALETTE[k].into(),
            })
            .collect(),
        },
    }
}

/// The section of quintic joint perturbations designed for the planar method.
pub(crate) fn planar_section(
    name: &str,
    r: &limpid_analysis::result::design::PlanarDesignResult,
) -> Section {
    let c = &r.chosen;
    let p = &r.predicted.pooled;
    let mut verdict = format!(
        "{}: {:.1} s of the {} s budget at q0 = ({}, {}) rad. Predicted on the prior arm ({} simulated recordings, errors against its intrinsic K and D): K ± {:.1} %, D ± {:.1} %, ξ ± {:.1} % (RMS element s.d. relative to the RMS element).",
        c.describe(fmt),
        c.duration_s,
        fmt(r.budget_s),
        fmt(r.posture_rad[0]),
        fmt(r.posture_rad[1]),
        r.predicted.runs,
        p.se_percent[0],
        p.se_percent[1],
        p.se_percent[2],
    );
    if let Some(b) = &r.baseline {
        verdict += &format!(
            " The protocol it replaces: K ± {:.1} %, D ± {:.1} %, ξ ± {:.1} % in {:.1} s.",
            b.pooled.se_percent[0], b.pooled.se_percent[1], b.pooled.se_percent[2], b.duration_s
        );
    }
    if let Some(v) = &r.verify {
        verdict += &format!(
            " Checked on {} arms drawn from the prior: predicted/achieved spread K {:.2}, D {:.2}, ξ {:.2}; K within 5 % and D within 20 %, both identifiable, in {:.0} % of them.",
            v.runs, v.ratio[0], v.ratio[1], v.ratio[2], 100.0 * v.within_tolerance_share
        );
    }
    let mut rows = prediction_rows("design", &r.predicted, &JOINT_GROUPS);
    if let Some(b) = &r.baseline {
        rows.extend(prediction_rows("baseline", b, &JOINT_GROUPS));
    }
    let s = &r.spectrum;
    let mut lines = vec![
        series("design", &s.frequency_hz, &s.designed_rad, Stroke::Solid, 0),
        series(
            "limits: min(d, v/ω, a/ω²)",
            &s.frequency_hz,
            &s.limit_rad,
            Stroke::Dashed,
            6,
        ),
    ];
    if let Some(b) = &s.baseline_rad {
        lines.push(series("baseline", &s.frequency_hz, b, Stroke::Solid, 1));
    }
    Section {
        heading: format!("Designed planar perturbations: {name}"),
        verdict,
        warnings: vec![],
        tables: vec![
            Table {
                caption: "Predicted precision on the prior arm: RMS standard error of the elements of joint K, D and of ξ1..ξ3, relative to the RMS element, mean relative error and share of recordings called identifiable".into(),
                header: ["protocol", "parameters", "SE", "SE %", "error %", "identifiable %", "duration (s)"]
                    .map(String::from)
                    .to_vec(),
                rows,
            },
            margins_table(&r.limits),
        ],
        figures: vec![
            joint_command_figure(
                "planar-design-command",
                "One recorded trial (the shoulder direction), relative to each peak",
                "time from the trial's start (s)",
                &r.command,
            ),
            Figure {
                id: "planar-design-spectrum".into(),
                chart: Chart {
                    title: "Amplitude 2|X(f)|/T of one recorded trial and the limits".into(),
                    x_label: "frequency (Hz)".into(),
                    y_label: "amplitude (rad)".into(),
                    x_log: true,
                    y_log: true,
                    y_range: None,
                    series: lines,
                },
            },
        ],
        ellipsoids: vec![],
        drawings: vec![Drawing {
            id: "planar-design-se".into(),
            svg: se_bars(&r.predicted, r.baseline.as_ref(), ["K", "D", "ξ"]),
        }],
    }
}
