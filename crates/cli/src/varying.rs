//! `limpid estimate varying`: impedance against time within repeated trials
//! (ensemble) or against a measured schedule column (parameter-varying).

use std::path::PathBuf;

use clap::Args;
use limpid_core::{significant, with_standard_error};
use limpid_ident::request::{Request, VaryingRequest};
use limpid_ident::varying::VaryingMethod;

use limpid_ident::varying::VaryingEstimate;

use crate::context::{CliResult, Context};

#[derive(Args)]
pub struct VaryingArgs {
    /// Recording: repetitions of a task with a `trial` column (--schedule time), or a record with the schedule column.
    pub recording: PathBuf,
    #[command(flatten)]
    pub settings: VaryingRequest,
    #[command(flatten)]
    pub output: crate::emit::OutputArgs,
}

impl VaryingArgs {
    /// The request these flags make.
    pub fn request(&self) -> Request {
        Request::Varying(self.settings.clone())
    }
}

pub fn run(args: VaryingArgs, cx: &Context) -> CliResult {
    crate::emit::estimate(
        cx,
        args.request(),
        std::slice::from_ref(&args.recording),
        args.output.output(),
    )
}

/// `limpid estimate varying`'s text: one line per grid point, diagonal elements.
pub fn varying_text(e: &VaryingEstimate, paths: &[PathBuf]) -> CliResult {
    println!("limpid estimate varying: {}", paths[0].display());
    match e.method {
        VaryingMethod::Ensemble => println!(
            "ensemble of {} {} at {} Hz, low-pass {} Hz",
            e.repetitions.unwrap_or_default(),
            if e.gait.is_some() {
                "strides"
            } else {
                "repetitions"
            },
            significant(e.sample_rate_hz, 4),
            significant(e.cutoff_hz, 3)
        ),
        VaryingMethod::ParameterVarying => println!(
            "parameter-varying on {}: Chebyshev order {}, low-pass {} Hz",
            e.schedule.name,
            e.basis_order.unwrap_or_default(),
            significant(e.cutoff_hz, 3)
        ),
        VaryingMethod::Pulses => println!(
            "perturbed minus unperturbed strides: {} perturbations at {} Hz, low-pass {} Hz",
            e.repetitions.unwrap_or_default(),
            significant(e.sample_rate_hz, 4),
            significant(e.cutoff_hz, 3)
        ),
    }
    if let Some(g) = &e.gait {
        println!(
            "strides: {} of {} used (median {} s, {} to {} s); baseline: {}; verdicts against walking tolerances K {} %, B {} %",
            g.strides_used,
            g.strides_found,
            significant(g.stride_s[0], 3),
            significant(g.stride_s[1], 3),
            significant(g.stride_s[2], 3),
            g.baseline,
            significant(100.0 * g.tolerances[0], 2),
            significant(100.0 * g.tolerances[1], 2)
        );
        for f in &g.flawed {
            println!(
                "  stride {} (t = {} s, row {}, {} s): {}: {}",
                f.stride,
                significant(f.start_s, 6),
                f.start_row,
                significant(f.duration_s, 3),
                f.kind,
                f.note
            );
        }
    }
    println!("resolution: {}", e.resolution_note);
    if let Some(angle) = &e.schedule.angle {
        println!("angle: {angle}");
    }
    let d = e.coordinates.len();
    let (mu, bu, ku) = limpid_ident::linear::units(&e.coordinates);
    let sched = if e.schedule.unit.is_empty() {
        e.schedule.name.clone()
    } else {
        format!("{} ({})", e.schedule.name, e.schedule.unit)
    };
    println!(
        "{sched}: K [{ku}], B [{bu}], M [{mu}] (diagonal, ± standard error){}",
        if e.reflex.is_some() {
            ", G [N m s/rad]"
        } else {
            ""
        }
    );
    for p in &e.points {
        let mut line = format!("  {:>9}", significant(p.sigma, 4));
        match (
            &p.stiffness,
            &p.stiffness_se,
            &p.damping,
            &p.damping_se,
            &p.inertia,
            &p.inertia_se,
        ) {
            (Some(k), Some(ks), Some(b), Some(bs), Some(m), Some(ms)) => {
                for i in 0..d {
                    line.push_str(&format!(
                        "  K{0}{0} {1}  B{0}{0} {2}  M{0}{0} {3}",
                        i + 1,
                        with_standard_error(k[(i, i)], ks[(i, i)]),
                        with_standard_error(b[(i, i)], bs[(i, i)]),
                        with_standard_error(m[(i, i)], ms[(i, i)])
                    ));
                }
                if let Some(r) = &p.reflex {
                    line.push_str(&format!("  G {}", with_standard_error(r.gain, r.gain_se)));
                }
                if let Some(v) = &p.verdicts {
                    line.push_str(&point_verdict(v));
                }
            }
            _ => line.push_str(&format!(
                "  not identifiable: {}",
                p.reason.as_deref().unwrap_or("no estimate")
            )),
        }
        println!("{line}");
    }
    let judged: Vec<&limpid_ident::varying::PointVerdicts> = e
        .points
        .iter()
        .filter_map(|p| p.verdicts.as_ref())
        .collect();
    if !judged.is_empty() {
        let trusted = |f: fn(&limpid_ident::varying::PointVerdicts) -> bool| {
            judged.iter().filter(|v| f(v)).count()
        };
        println!(
            "verdicts: K trusted at {} of {} points, B at {}, M at {} (the rest marked on their line)",
            trusted(|v| v.stiffness.trusted()),
            e.points.len(),
            trusted(|v| v.damping.trusted()),
            trusted(|v| v.inertia.trusted())
        );
    }
    println!(
        "VAF {} % (cross-validated {} %)",
        significant(e.fit.vaf, 3),
        significant(e.fit.cross_validated_vaf, 3)
    );
    if let Some(r) = &e.reflex {
        println!(
            "reflex: {} (delay {} ms, low-pass {} Hz, {} velocity; cross-validated VAF {:+.1} points, Wald {:.1} on {} df)",
            if r.detected { "detected" } else { "not detected" },
            significant(r.delay_s * 1e3, 3),
            significant(r.natural_hz, 2),
            r.polarity,
            r.cross_validated_gain,
            r.wald,
            r.wald_dof
        );
    }
    for w in &e.warnings {
        println!("warning: {w}");
    }
    Ok(())
}

/// A point's verdicts after its values: `[trusted]`, or what is not.
fn point_verdict(v: &limpid_ident::varying::PointVerdicts) -> String {
    let not: Vec<String> = [("K", v.stiffness), ("B", v.damping), ("M", v.inertia)]
        .iter()
        .filter(|(_, verdict)| !verdict.trusted())
        .map(|(symbol, verdict)| format!("{symbol} {}", verdict.words()))
        .collect();
    if not.is_empty() {
        "  [trusted]".into()
    } else {
        format!("  [{}]", not.join(", "))
    }
}
