//! `limpid estimate`: its methods, and the linear and co-contraction
//! commands, whose flags are their request types' fields.

use std::path::PathBuf;

use clap::{Args, Subcommand};
use limpid_ident::request::{CocontractionRequest, LinearRequest, Request};

use limpid_analysis::cocontraction::CocontractionResult;
use limpid_analysis::linear::LinearResult;

use crate::context::{CliResult, Context};
use crate::table;

#[derive(Subcommand)]
pub enum Method {
    /// Linear model M x'' + B x' + K (x - x_eq) = f by least squares (Artemiadis et al. 2010; Patel et al. 2013).
    Linear(LinearArgs),
    /// Co-contraction index and impedance per level, compared with the lowest level (Patel et al. 2013).
    Cocontraction(CocontractionArgs),
    /// Planar two-link arm in joint space: inertial parameters, K, D, confidence criteria (Lakatos et al. 2011).
    Planar(crate::planar::PlanarArgs),
    /// Stochastic MIMO impedance Z = T R^-1 from Welch spectra, with a parametric fit (Park & Chang 2011).
    Stochastic(crate::stochastic::StochasticArgs),
    /// Intrinsic and reflex joint stiffness by the parallel cascade (Kearney et al. 1997): IRFs, delay, gain, VAF split.
    Reflex(crate::reflex::ReflexArgs),
    /// Impedance that varies: against time within repeated trials (ensemble) or a measured schedule column (parameter-varying, optional reflex gain).
    Varying(crate::varying::VaryingArgs),
}

#[derive(Args)]
pub struct LinearArgs {
    /// Recording (CSV, Parquet or MATLAB .mat; the recording format: docs/src/format.md).
    pub recording: PathBuf,
    #[command(flatten)]
    pub settings: LinearRequest,
    #[command(flatten)]
    pub output: crate::emit::OutputArgs,
}

#[derive(Args)]
pub struct CocontractionArgs {
    /// Recording with `level` and `emg_*` columns (Patel et al. 2013).
    pub recording: PathBuf,
    /// Maximum voluntary co-contraction recording with the same EMG channels.
    #[arg(long)]
    pub mvc: PathBuf,
    #[command(flatten)]
    pub settings: CocontractionRequest,
    #[command(flatten)]
    pub output: crate::emit::OutputArgs,
}

pub fn run(method: Method, cx: &Context) -> CliResult {
    match method {
        Method::Linear(args) => crate::emit::estimate(
            cx,
            Request::Linear(args.settings),
            std::slice::from_ref(&args.recording),
            args.output.output(),
        ),
        Method::Planar(args) => crate::planar::run_estimate(args, cx),
        Method::Stochastic(args) => crate::stochastic::run_estimate(args, cx),
        Method::Reflex(args) => crate::reflex::run(args, cx),
        Method::Varying(args) => crate::varying::run(args, cx),
        Method::Cocontraction(args) => crate::emit::estimate(
            cx,
            Request::Cocontraction(args.settings),
            &[args.recording.clone(), args.mvc.clone()],
            args.output.output(),
        ),
    }
}

/// `limpid estimate cocontraction`'s text.
pub fn cocontraction_text(result: &CocontractionResult) -> CliResult {
    print!("{}", table::cocontraction_text(result));
    Ok(())
}

/// `limpid estimate linear`'s text: the matrices, the arm, the shoulder.
pub fn linear_text(result: &LinearResult) -> CliResult {
    print!("{}", table::linear_text(result));
    if let Some(a) = &result.arm_configuration {
        print!("{}", table::arm_configuration_text(a));
    }
    if let Some(s) = &result.shoulder {
        let row = |m: &limpid_core::Matrix, i: usize| {
            (0..3)
                .map(|j| table::num(m[(i, j)]))
                .collect::<Vec<_>>()
                .join(", ")
        };
        println!("shoulder joint stiffness J_h^T K J_h (N m/rad; flexion, abduction, rotation):");
        for i in 0..3 {
            println!("  [{}]", row(&s.stiffness, i));
        }
        println!("shoulder joint damping J_h^T B J_h (N m s/rad):");
        for i in 0..3 {
            println!("  [{}]", row(&s.damping, i));
        }
        println!("note: {}", s.note);
    }
    Ok(())
}
