//! `limpid estimate reflex`: intrinsic and reflex stiffness by the parallel
//! cascade (Kearney et al. 1997), on joint (`q1`, `tau1`) or end-point data.

use limpid_ident::reflex::CurveStructure;
use std::path::PathBuf;

use clap::Args;
use limpid_ident::request::{ReflexRequest, Request};

use limpid_ident::reflex::ReflexEstimate;

use crate::context::{CliResult, Context};
use crate::table::num;
use limpid_core::with_standard_error;

#[derive(Args)]
pub struct ReflexArgs {
    /// Recording under a stochastic position perturbation (joint angle and torque).
    pub recording: PathBuf,
    #[command(flatten)]
    pub settings: ReflexRequest,
    #[command(flatten)]
    pub output: crate::emit::OutputArgs,
}

impl ReflexArgs {
    /// The request these flags make.
    pub fn request(&self) -> Request {
        Request::Reflex(self.settings.clone())
    }
}

pub fn run(args: ReflexArgs, cx: &Context) -> CliResult {
    crate::emit::estimate(
        cx,
        args.request(),
        std::slice::from_ref(&args.recording),
        args.output.output(),
    )
}

/// `limpid estimate reflex`'s text.
pub fn reflex_text(e: &ReflexEstimate, paths: &[PathBuf]) -> CliResult {
    let (i, r, u) = (&e.intrinsic, &e.reflex, &e.units);
    println!("limpid estimate reflex: {}", paths[0].display());
    println!(
        "{} s at {} Hz, decimated to {} Hz | {} alternations",
        num(e.duration_s),
        num(e.sample_rate_hz),
        num(e.decimated_rate_hz),
        e.iterations
    );
    if let Some(s) = &e.segments {
        println!(
            "{} of {} segments (trials) of {}-{} s (median {} s), each from its own start: its first {} s left out of I, B, K and the gain (the reflex in flight at the cut fitted), reflex IRF {} s",
            s.used,
            s.count,
            num(s.durations_s[0]),
            num(s.durations_s[2]),
            num(s.durations_s[1]),
            num(s.start_left_out_s),
            num(s.reflex_irf_s)
        );
    }
    let vd = &e.verdicts();
    println!("intrinsic pathway (joint parametric model, ± standard error) [verdict]:");
    println!(
        "  I = {} {} [{}]   B = {} {} [{}]   K = {} {} [{}]",
        with_standard_error(i.inertia, i.standard_errors.inertia),
        u.inertia,
        vd.inertia.words(),
        with_standard_error(i.damping, i.standard_errors.damping),
        u.damping,
        vd.damping.words(),
        with_standard_error(i.stiffness, i.standard_errors.stiffness),
        u.stiffness,
        vd.stiffness.words()
    );
    println!(
        "  reflex-free I-B-K fit: K = {} {} (VAF {} %)",
        num(e.reflex_free.parameters.stiffness),
        u.stiffness,
        num(e.reflex_free.vaf)
    );
    match &r.curve {
        Some(c) if c.structure == CurveStructure::PiecewiseLinear => println!(
            "reflex pathway: velocity -> delay -> piecewise-linear static curve ({} knots, estimated) -> 2nd-order low-pass; gain = the closest {:?} rectifier's slope",
            c.knots_rad_s.len(),
            r.polarity
        ),
        _ => println!(
            "reflex pathway: {:?} velocity rectified -> delay -> gain -> 2nd-order low-pass",
            r.polarity
        ),
    }
    println!(
        "  gain {} {} [{}]",
        with_standard_error(r.gain, r.gain_se),
        u.damping,
        vd.gain.words()
    );
    if vd.delay.has_value() {
        println!(
            "  delay {:.1} ms (95 % interval {:.1}-{:.1} ms) [{}]   low-pass {} Hz, damping ratio {} [{}]",
            r.delay_s * 1e3,
            r.delay_interval_s[0] * 1e3,
            r.delay_interval_s[1] * 1e3,
            vd.delay.words(),
            num(r.natural_frequency_hz),
            num(r.damping_ratio),
            vd.low_pass.words()
        );
    } else {
        println!(
            "  delay and low-pass [{}]: the fit is as good for delays {:.0}-{:.0} ms (best {:.0} ms; see the warnings)",
            vd.delay.words(),
            r.delay_interval_s[0] * 1e3,
            r.delay_interval_s[1] * 1e3,
            r.delay_s * 1e3
        );
    }
    if let Some(c) = &r.curve {
        print_curve(c, u);
    }
    println!(
        "VAF: total {} %  intrinsic alone {} %  reflex alone {} %  joint parametric {} %  cross-validated {} %",
        num(e.fit.vaf_total),
        num(e.fit.vaf_intrinsic),
        num(e.fit.vaf_reflex),
        num(e.fit.vaf_parametric),
        num(e.cross_validated_vaf)
    );
    if let Some(why) = e.fit.shares_note() {
        println!("  {why}");
    }
    if let Some(z) = &e.frequency_response {
        print_frequency_response(z, u);
    }
    for w in &e.warnings {
        println!("warning: {w}");
    }
    Ok(())
}

/// The static curve's choice: each structure's held-out VAF and K, and the
/// curve at a few velocities with its standard error.
fn print_curve(c: &limpid_ident::reflex::StaticCurve, u: &limpid_ident::units::Units) {
    println!("  static curve, structures tried (10-fold cross-validated VAF of the joint model; * = within one SE of the best):");
    for k in &c.candidates {
        let name = match k.structure {
            CurveStructure::Rectifier => "rectifier".to_string(),
            CurveStructure::PiecewiseLinear => format!(
                "piecewise linear, {} knot{}",
                k.knots_rad_s.len(),
                if k.knots_rad_s.len() == 1 { "" } else { "s" }
            ),
        };
        let chosen = k.structure == c.structure && k.knots_rad_s == c.knots_rad_s;
        println!(
            "    {}{name:<28} {} %  K = {} {}{}",
            if k.within_one_se { "* " } else { "  " },
            num(k.cross_validated_vaf),
            num(k.intrinsic.stiffness),
            u.stiffness,
            if chosen {
                "   <- chosen (simplest within one SE)"
            } else {
                ""
            }
        );
    }
    let n = c.velocity_rad_s.len();
    let points: Vec<String> = [0, n / 4, n / 2, 3 * n / 4, n - 1]
        .iter()
        .filter(|&&i| i < n)
        .map(|&i| {
            format!(
                "{} -> {}",
                num(c.velocity_rad_s[i]),
                with_standard_error(c.torque[i], c.torque_se[i])
            )
        })
        .collect();
    println!(
        "  curve (velocity -> torque {}): {}",
        u.force,
        points.join(", ")
    );
}

/// The position-to-torque response at a few frequencies beside the
/// intrinsic model, and where the coherence is high.
fn print_frequency_response(
    z: &limpid_ident::reflex::JointFrequencyResponse,
    u: &limpid_ident::units::Units,
) {
    let at: Vec<String> = [1.0, 3.0, 10.0]
        .iter()
        .filter_map(|&f| {
            let k = z
                .frequency_hz
                .iter()
                .enumerate()
                .min_by(|a, b| (a.1 - f).abs().total_cmp(&(b.1 - f).abs()))?
                .0;
            Some(format!(
                "{:.1} Hz {} (model {})",
                z.frequency_hz[k],
                with_standard_error(z.magnitude[k], z.magnitude_se[k]),
                num(z.intrinsic_model_magnitude[k])
            ))
        })
        .collect();
    let coherent: Vec<f64> = z
        .frequency_hz
        .iter()
        .zip(&z.coherence)
        .filter(|(_, c)| **c >= 0.9)
        .map(|(f, _)| *f)
        .collect();
    let band = match (coherent.first(), coherent.last()) {
        (Some(a), Some(b)) => format!(
            "coherence >= 0.9 at {} of {} frequencies between {:.1} and {:.1} Hz",
            coherent.len(),
            z.frequency_hz.len(),
            a,
            b
        ),
        _ => "coherence below 0.9 everywhere: the position explains the torque poorly as a linear system".into(),
    };
    println!(
        "frequency response, position to torque (|Z| in {}, ± SE; model: the intrinsic I-B-K alone, the reflex adds the rest): {}; {band}",
        u.stiffness,
        at.join(", ")
    );
}
