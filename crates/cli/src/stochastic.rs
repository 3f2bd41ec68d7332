//! `limpid estimate stochastic` and `limpid spectra` (seed 004).

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::{Args, ValueEnum};
use limpid_app::estimate::Estimated;
use limpid_ident::request::{Request, SpectraRequest, StochasticRequest};

use limpid_ident::spectra::SpectraResult;
use limpid_ident::stochastic::StochasticEstimate;

use crate::context::{CliResult, Context};
use crate::table::num;

#[derive(Args)]
pub struct StochasticArgs {
    /// Recording(s) with commanded inputs u* (one per coordinate), positions
    /// and forces; several repeated trials are pooled (their Welch segments
    /// averaged together, Park & Chang (2011) §III-F).
    #[arg(required = true, num_args = 1..)]
    pub recordings: Vec<PathBuf>,
    #[command(flatten)]
    pub settings: StochasticRequest,
    #[command(flatten)]
    pub output: crate::emit::OutputArgs,
}

#[derive(Args)]
pub struct SpectraArgs {
    /// Recording.
    pub recording: PathBuf,
    #[command(flatten)]
    pub settings: SpectraRequest,
    #[command(flatten)]
    pub output: crate::emit::OutputArgs,
}

pub fn run_estimate(args: StochasticArgs, cx: &Context) -> CliResult {
    crate::emit::estimate(
        cx,
        Request::Stochastic(args.settings),
        &args.recordings,
        args.output.output(),
    )
}

/// A segment window as the text names it (`Hann`), from its flag's value.
fn window_name(w: limpid_ident::request::SegmentWindow) -> String {
    let name = w
        .to_possible_value()
        .map_or_else(String::new, |v| v.get_name().to_string());
    let mut chars = name.chars();
    chars.next().map_or_else(String::new, |c| {
        c.to_uppercase().chain(chars).collect::<String>()
    })
}

/// `limpid estimate stochastic`'s text.
pub fn stochastic_text(
    est: &StochasticEstimate,
    e: &Estimated,
    r: &StochasticRequest,
    paths: &[PathBuf],
) -> CliResult {
    let band = (r.band_hz[0], r.band_hz[1]);
    let posture = &e.posture;
    let c = &est.criteria;
    let coords = &est.coordinates;
    let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    println!(
        "limpid estimate stochastic: {}{}",
        names.join(", "),
        if names.len() > 1 {
            format!(" (pooled: {} recordings)", names.len())
        } else {
            String::new()
        }
    );
    match &est.periodic {
        Some(p) => println!(
            "coordinates {} {} | periodic: {} periods of {} samples (resolution {:.3} Hz; {}) | fit band {}-{} Hz at {} excited lines",
            coords.join(", "),
            if &est.inputs == coords {
                "(no commanded forces: the displacements classify the lines)".to_string()
            } else {
                format!("driven by {}", est.inputs.join(", "))
            },
            c.segments,
            c.nperseg,
            c.frequency_resolution_hz,
            p.transient,
            num(band.0),
            num(band.1),
            p.impedance.as_ref().map_or(0, |z| z.lines)
        ),
        None => println!(
            "coordinates {} driven by {} | Welch: {} segments of {} samples (resolution {:.3} Hz), {} | fit band {}-{} Hz",
            coords.join(", "), est.inputs.join(", "), c.segments, c.nperseg, c.frequency_resolution_hz, window_name(r.window), num(band.0), num(band.1)
        ),
    }
    if let Some(p) = &est.periodic {
        println!("{}", periodic_summary(p));
    }
    if let Some(p) = &posture {
        println!(
            "shoulder joint space (Park & Chang 2011, eq. (3)), before estimation: q1 flexion, q2 abduction from the hand's X, Z (tau = J_h^T F){} | posture: flexion {} deg, abduction {} deg, rotation {} deg, elbow {} deg | angles in rad, torques in N m",
            if coords.len() > 2 { ", q3 internal rotation = the hand's theta" } else { "" },
            num(p.angles_deg[0]), num(p.angles_deg[1]), num(p.angles_deg[2]), num(p.elbow_deg)
        );
    }
    let v = &c.verdicts;
    for (title, m, se, verdict) in [
        (
            "Stiffness K",
            &est.stiffness,
            &est.standard_errors.stiffness,
            Some(v.stiffness),
        ),
        (
            "Damping B",
            &est.damping,
            &est.standard_errors.damping,
            Some(v.damping),
        ),
        (
            "Inertia M",
            &est.inertia,
            &est.standard_errors.inertia,
            v.inertia,
        ),
    ] {
        let flag = verdict.map_or("", crate::table::verdict_flag);
        println!("{title} (SI, per coordinate pair){flag}");
        for (i, name) in coords.iter().enumerate().take(m.nrows()) {
            let cells: String = (0..m.ncols())
                .map(|j| {
                    format!(
                        "{:>24}",
                        limpid_core::with_standard_error(m[(i, j)], se[(i, j)])
                    )
                })
                .collect();
            println!("  {name:<6}{cells}");
        }
    }
    let inputs = if est.periodic.is_some() {
        if c.max_input_coherence < 1e-12 {
            "the commands share no line".to_string()
        } else {
            format!(
                "another command's power at a command's lines up to {} of its own",
                limpid_core::significant(c.max_input_coherence, 2)
            )
        }
    } else {
        format!("input coherence max {:.3}", c.max_input_coherence)
    };
    println!(
        "quality ({}): multiple coherence mean {:.3}, min {:.3} in the band; {inputs}; fit VAF {:.2} %; phi_T(Z vs fit) {}",
        est.standard_errors.method, c.mean_multiple_coherence, c.min_multiple_coherence, c.fit_vaf, num(c.phi_t_vs_fit)
    );
    if let Some(a) = &est.accuracy {
        let cells: Vec<String> = a
            .phi_ij
            .rows()
            .iter()
            .map(|r| r.iter().map(|v| num(*v)).collect::<Vec<_>>().join(" "))
            .collect();
        println!(
            "accuracy vs expected model: phi_T {} (mean relative error {:.2} %), phi_ij [{}]",
            num(a.phi_t),
            100.0 * a.mean_relative_error,
            cells.join("; ")
        );
    }
    for w in &est.warnings {
        println!("warning: {w}");
    }
    Ok(())
}

pub fn run_spectra(args: SpectraArgs, cx: &Context) -> CliResult {
    crate::emit::estimate(
        cx,
        Request::Spectra(args.settings),
        std::slice::from_ref(&args.recording),
        args.output.output(),
    )
}

/// `limpid spectra`'s text: CSV.
pub fn spectra_text(r: &SpectraResult) -> CliResult {
    match &r.periodic {
        Some(p) => {
            print!("{}", periodic_csv(p));
            eprintln!("limpid: {}", periodic_summary(p));
        }
        None => print!("{}", spectra_csv(r)),
    }
    Ok(())
}

/// A periodic analysis in one line: periods, and the distortion verdict.
fn periodic_summary(p: &limpid_ident::spectra::PeriodicResult) -> String {
    let db = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.1} dB"));
    let verdict = match &p.distortion {
        Some(d) => format!(
            "odd detection lines {}, even {}, noise {:.1} dB re the excited lines: {}",
            db(d.odd_db),
            db(d.even_db),
            d.noise_db,
            d.verdict
        ),
        None => "every line in the band is excited: no detection line for nonlinear distortion (use an odd or random-odd multisine)".into(),
    };
    let impedance = match &p.impedance {
        Some(z) => {
            let diagonal = |m: &limpid_core::Matrix, se: &limpid_core::Matrix| {
                (0..m.nrows())
                    .map(|i| limpid_core::with_standard_error(m[(i, i)], se[(i, i)]))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let e = &z.standard_errors;
            let k = format!(
                "K {}",
                crate::table::verdict_flag(z.verdicts.stiffness)
                    .trim()
                    .trim_matches(['[', ']'])
            );
            let trust = if p.distorts_excited_lines() {
                "not trusted: the response is nonlinear, these are its best linear approximation at this amplitude".to_string()
            } else if p.nonlinear() {
                format!("{k}; the distortion is even and stays off the odd excited lines")
            } else {
                k
            };
            format!(
                "; fitted at {} excited lines (VAF {:.1} %, residual ratio {}): diagonal K {}, B {}, M {} [{trust}]",
                z.lines,
                z.fit_vaf,
                limpid_core::significant(z.residual_ratio, 3),
                diagonal(&z.stiffness, &e.stiffness),
                diagonal(&z.damping, &e.damping),
                diagonal(&z.inertia, &e.inertia),
            )
        }
        None => String::new(),
    };
    format!(
        "periodic analysis of {} periods of {} s ({}); {verdict}{impedance}",
        p.periods,
        limpid_core::error::Num(p.period_s),
        p.transient
    )
}

/// The periodic analysis as CSV: one row per line from the lowest to the
/// highest excited one; the response columns are empty where an input does
/// not excite the line.
fn periodic_csv(p: &limpid_ident::spectra::PeriodicResult) -> String {
    let mut out = String::from("frequency_hz,kind,output_level_db,noise_level_db");
    for f in &p.frf {
        let pair = format!("{}_{}", f.input, f.output);
        let _ = write!(
            out,
            ",magnitude_{pair},magnitude_se_{pair},phase_deg_{pair},phase_se_deg_{pair}"
        );
    }
    out.push('\n');
    for line in &p.lines {
        let _ = write!(
            out,
            "{},{},{:.2},{:.2}",
            line.frequency_hz, line.kind, line.output_level, line.noise_level
        );
        for f in &p.frf {
            match f
                .frequency_hz
                .iter()
                .position(|h| (h - line.frequency_hz).abs() < 1e-9 * h.max(1.0))
            {
                Some(k) => {
                    let _ = write!(
                        out,
                        ",{:e},{:e},{:.3},{:.3}",
                        f.magnitude[k], f.magnitude_se[k], f.phase_deg[k], f.phase_se_deg[k]
                    );
                }
                None => out.push_str(",,,,"),
            }
        }
        out.push('\n');
    }
    out
}

/// The spectra as CSV: one row per frequency; an empty cell where the
/// multiple and partial coherences do not exist (singular input matrix).
fn spectra_csv(r: &limpid_ident::spectra::SpectraResult) -> String {
    let mut out = String::from("frequency_hz");
    for n in &r.signals {
        let _ = write!(out, ",psd_{n}");
    }
    for o in &r.outputs {
        let _ = write!(out, ",multiple_coherence_{o}");
        for i in &r.inputs {
            let _ = write!(out, ",coherence_{i}_{o},partial_coherence_{i}_{o}");
        }
    }
    out.push('\n');
    let cell = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.6}"));
    for (k, f) in r.frequencies.iter().enumerate() {
        let _ = write!(out, "{f}");
        for p in &r.psd {
            let _ = write!(out, ",{:e}", p[k]);
        }
        for o in 0..r.outputs.len() {
            let _ = write!(out, ",{}", cell(r.multiple_coherence[o][k]));
            for i in 0..r.inputs.len() {
                let _ = write!(
                    out,
                    ",{:.6},{}",
                    r.coherence[o][i][k],
                    cell(r.partial_coherence[o][i][k])
                );
            }
        }
        out.push('\n');
    }
    out
}
