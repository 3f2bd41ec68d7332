//! `limpid estimate planar` and `limpid window-sweep` (seed 003).

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;
use limpid_app::estimate::Estimated;
use limpid_core::Matrix;
use limpid_ident::planar::PlanarEstimate;
use limpid_ident::request::{PlanarRequest, Request, SweepRequest};

use limpid_ident::planar::Sweep;

use crate::context::{CliResult, Context};
use crate::emit::Output;
use crate::table::num;

#[derive(Args)]
pub struct PlanarArgs {
    /// Recording: joint space (q1,q2,tau1,tau2) or end point (x,y,fx,fy), with a trial column.
    pub recording: PathBuf,
    #[command(flatten)]
    pub settings: PlanarRequest,
    #[command(flatten)]
    pub output: crate::emit::OutputArgs,
}

#[derive(Args)]
pub struct SweepArgs {
    /// Recording: joint space (q1,q2,tau1,tau2) or end point (x,y,fx,fy), with a trial column.
    pub recording: PathBuf,
    #[command(flatten)]
    pub settings: SweepRequest,
    /// Print the table as CSV.
    #[arg(long, conflicts_with = "json")]
    pub csv: bool,
    #[command(flatten)]
    pub output: crate::emit::OutputArgs,
}

fn m2(m: &Matrix, se: &Matrix) -> String {
    let mut s = String::new();
    for i in 0..2 {
        let _ = writeln!(
            s,
            "    {:>20}{:>20}",
            limpid_core::with_standard_error(m[(i, 0)], se[(i, 0)]),
            limpid_core::with_standard_error(m[(i, 1)], se[(i, 1)])
        );
    }
    s
}

fn text(e: &PlanarEstimate, path: &std::path::Path, from_endpoint: bool) -> String {
    let loo = e.leave_one_out_vaf.unwrap_or([f64::NAN; 2]);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "limpid estimate planar: {} ({} trials, {} samples, T_obs {} ms, {} data)",
        path.display(),
        e.trials,
        e.samples,
        num(e.observation_window_ms),
        if from_endpoint {
            "end-point"
        } else {
            "joint-space"
        }
    );
    let xi = &e.inertial_parameters;
    if e.inertial_parameters_fixed {
        let _ = writeln!(
            s,
            "inertial parameters (given): {}, {}, {} kg m²",
            num(xi[0]),
            num(xi[1]),
            num(xi[2])
        );
    } else {
        let se = &e.standard_errors.inertial_parameters;
        let _ = writeln!(
            s,
            "inertial parameters xi1..xi3: {} ± {}, {} ± {}, {} ± {} kg m²",
            num(xi[0]),
            num(se[0]),
            num(xi[1]),
            num(se[1]),
            num(xi[2]),
            num(se[2])
        );
    }
    let _ = write!(
        s,
        "joint stiffness K (N m/rad)\n{}",
        m2(&e.stiffness, &e.standard_errors.stiffness)
    );
    let _ = write!(
        s,
        "joint damping D (N m s/rad)\n{}",
        m2(&e.damping, &e.standard_errors.damping)
    );
    let kx = &e.endpoint_stiffness;
    let _ = writeln!(
        s,
        "end-point stiffness J^-T K J^-1 (N/m): [[{}, {}], [{}, {}]]",
        num(kx[(0, 0)]),
        num(kx[(0, 1)]),
        num(kx[(1, 0)]),
        num(kx[(1, 1)])
    );
    let c = &e.criteria;
    let _ = writeln!(
        s,
        "fit: VAF {:.1} / {:.1} %, r {:.3} / {:.3}; leave-one-trial-out VAF {:.1} / {:.1} %",
        e.fit.vaf[0], e.fit.vaf[1], e.fit.r[0], e.fit.r[1], loo[0], loo[1]
    );
    let _ = writeln!(s, "criteria: cond(W) {} (scaled {}), K eigenvalues {} / {}, D eigenvalues {} / {}, symmetry ratio K {:.3}, D {:.3}", num(c.condition_number), num(c.condition_number_scaled), num(c.stiffness_eigenvalues[0]), num(c.stiffness_eigenvalues[1]), num(c.damping_eigenvalues[0]), num(c.damping_eigenvalues[1]), c.stiffness_symmetry_ratio, c.damping_symmetry_ratio);
    if c.trusted {
        let _ = writeln!(
            s,
            "verdict: trusted (the fit explains the torques; well-conditioned; K and D identified, precise, positive definite and quasi-symmetric)"
        );
    } else {
        let _ = writeln!(s, "verdict: NOT TRUSTED: {}", c.reasons.join("; "));
    }
    s
}

pub fn run_estimate(args: PlanarArgs, cx: &Context) -> CliResult {
    crate::emit::estimate(
        cx,
        Request::Planar(args.settings),
        std::slice::from_ref(&args.recording),
        args.output.output(),
    )
}

/// `limpid estimate planar`'s text.
pub fn planar_text(est: &PlanarEstimate, e: &Estimated, paths: &[PathBuf]) -> CliResult {
    print!(
        "{}",
        text(est, &paths[0], e.from_endpoint.unwrap_or_default())
    );
    Ok(())
}

pub fn run_sweep(args: SweepArgs, cx: &Context) -> CliResult {
    crate::emit::estimate(
        cx,
        Request::WindowSweep(args.settings),
        std::slice::from_ref(&args.recording),
        Output {
            csv: args.csv,
            ..args.output.output()
        },
    )
}

/// `limpid window-sweep`'s table (CSV with `--csv`).
pub fn sweep_text(sweep: &Sweep, e: &Estimated, paths: &[PathBuf], csv: bool) -> CliResult {
    if csv {
        print!("{}", sweep_csv(sweep));
        return Ok(());
    }
    println!(
        "limpid window-sweep: {} ({} trials)",
        paths[0].display(),
        e.trials.unwrap_or_default()
    );
    println!(
        "{:>8} {:>10} {:>9} {:>9} {:>9} {:>9} {:>8} {:>8} {:>8}  verdict",
        "T_obs", "cond(W)s", "K11", "K22", "D11", "D22", "xi1", "Kmin", "K asym"
    );
    for r in &sweep.rows {
        let e = &r.estimate;
        let c = &e.criteria;
        println!(
            "{:>8} {:>10} {:>9} {:>9} {:>9} {:>9} {:>8} {:>8} {:>8.3}  {}",
            num(r.observation_window_ms),
            num(c.condition_number_scaled),
            num(e.stiffness[(0, 0)]),
            num(e.stiffness[(1, 1)]),
            num(e.damping[(0, 0)]),
            num(e.damping[(1, 1)]),
            num(e.inertial_parameters[0]),
            num(c.stiffness_eigenvalues[1]),
            c.stiffness_symmetry_ratio,
            trust_cell(r.trusted, &r.reasons)
        );
    }
    print_sweep_summary(sweep);
    print_intervals(&sweep.intervals);
    Ok(())
}

/// The sweep as CSV, one row per window.
fn sweep_csv(sweep: &limpid_ident::planar::Sweep) -> String {
    let mut s = String::from("t_obs_ms,cond_w,cond_w_scaled,xi1,xi2,xi3,k11,k12,k21,k22,d11,d12,d21,d22,k_eig_min,d_eig_min,k_sym_ratio,d_sym_ratio,vaf1,vaf2,trusted\n");
    for r in &sweep.rows {
        let e = &r.estimate;
        let c = &e.criteria;
        let _ = writeln!(
            s,
            "{},{:.4e},{:.4e},{:.5},{:.5},{:.5},{:.4},{:.4},{:.4},{:.4},{:.5},{:.5},{:.5},{:.5},{:.4},{:.5},{:.4},{:.4},{:.2},{:.2},{}",
            r.observation_window_ms, c.condition_number, c.condition_number_scaled,
            e.inertial_parameters[0], e.inertial_parameters[1], e.inertial_parameters[2],
            e.stiffness[(0, 0)], e.stiffness[(0, 1)], e.stiffness[(1, 0)], e.stiffness[(1, 1)],
            e.damping[(0, 0)], e.damping[(0, 1)], e.damping[(1, 0)], e.damping[(1, 1)],
            c.stiffness_eigenvalues[1], c.damping_eigenvalues[1], c.stiffness_symmetry_ratio, c.damping_symmetry_ratio,
            e.fit.vaf[0], e.fit.vaf[1], c.trusted
        );
    }
    s
}

/// The shortest trusted window, any change within the trials, and the paper's criteria.
fn print_sweep_summary(sweep: &limpid_ident::planar::Sweep) {
    let show = |v: Option<f64>| {
        v.map_or("not reached in the sweep".to_string(), |t| {
            format!("{} ms", num(t))
        })
    };
    match sweep.shortest_trusted_ms {
        Some(t) => println!("\nshortest trusted window: {} ms", num(t)),
        None => println!("\nno window earns trust"),
    }
    println!("  (trusted: {})", sweep.trust_definition);
    if let Some(c) = &sweep.impedance_change {
        println!(
            "the impedance changes within the trials, most clearly at {} ms after the onset and significantly from {} ms on (a reflex, or soft tissue in series with the handle?): K by {:.0} %, D by {:.0} % (p = {:.1e} allowing for the scan); windows reaching past {} ms are not trusted",
            num(c.onset_ms),
            num(c.significant_from_ms),
            100.0 * c.stiffness_change,
            100.0 * c.damping_change,
            c.p_value,
            num(c.significant_from_ms)
        );
        if let Some(t) = &sweep.series_compliance {
            println!(
                "  the rigid model leaves {:.0} times the residual of one with soft tissue in series with the handle (time constant {:.0} ms): the change is likely that tissue (a cuff), not a reflex, and a reflex behind it cannot be told apart",
                t.residual_ratio,
                1000.0 * t.time_constant_s
            );
        }
    }
    println!(
        "K positive definite from T_obs = {}",
        show(sweep.min_positive_definite_ms)
    );
    println!(
        "K and D quasi-symmetric (ratio < 0.1) from T_obs = {}",
        show(sweep.min_quasi_symmetric_ms)
    );
    println!(
        "all parameters quasi-constant from T_obs = {} ({})",
        show(sweep.min_quasi_constant_ms),
        sweep.quasi_constant_definition
    );
    println!(
        "leave-one-trial-out VAF at the longest window: {:.1} / {:.1} %",
        sweep.leave_one_out_vaf[0], sweep.leave_one_out_vaf[1]
    );
}

/// Lakatos et al. (2011) §IV's interpolation-interval study, when it was made.
fn print_intervals(intervals: &[limpid_ident::planar::IntervalRow]) {
    if intervals.is_empty() {
        return;
    }
    println!(
        "\ninterpolation-interval study (Lakatos et al. 2011, §IV: the trials of each T_k, observed over T_obs = T_k + 70 ms)"
    );
    println!(
        "{:>6} {:>8} {:>7} {:>10} {:>9} {:>9} {:>9} {:>9} {:>8}  verdict",
        "T_k", "T_obs", "trials", "cond(W)s", "K11", "K22", "D11", "D22", "Kmin"
    );
    for r in intervals {
        let (e, c) = (&r.estimate, &r.estimate.criteria);
        println!(
            "{:>6} {:>8} {:>7} {:>10} {:>9} {:>9} {:>9} {:>9} {:>8}  {}",
            num(r.interpolation_ms),
            num(r.observation_window_ms),
            r.trials,
            num(c.condition_number_scaled),
            num(e.stiffness[(0, 0)]),
            num(e.stiffness[(1, 1)]),
            num(e.damping[(0, 0)]),
            num(e.damping[(1, 1)]),
            num(c.stiffness_eigenvalues[1]),
            trust_cell(r.trusted, &r.reasons)
        );
    }
}

/// A window's verdict in the sweep's tables: "trusted", or why not.
fn trust_cell(trusted: bool, reasons: &[String]) -> String {
    if trusted {
        "trusted".to_string()
    } else {
        format!("not trusted: {}", reasons.join("; "))
    }
}
