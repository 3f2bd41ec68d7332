//! `limpid demo`: seed 000's 3-D study on a built-in virtual subject.
//!
//! Six start points, 16 centre-out perturbations each (3 cm, 3 s; 6 s for the
//! sinusoid), a position-controlled robot, F/T sensor with per-trial offset,
//! drift and noise; every start point estimated with the linear estimator and
//! compared with the subject's true matrices (seed 000 Table I, subject 1).

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use limpid_analysis::report::{linear_result, LinearResult};
use limpid_ident::{fit_linear, prepare, LinearParams, PrepareParams};
use limpid_lab::{seed000_subject1, simulate_centre_out, CentreOut, NoiseModel, Posture, Profile};
use nalgebra::Matrix3;
use rayon::prelude::*;
use serde::Serialize;

use crate::table::num;
use crate::CliResult;

#[derive(Clone, Copy, ValueEnum)]
pub enum ProfileArg {
    Cubic,
    Trapezoid,
    Sinusoid,
}

#[derive(Args)]
pub struct DemoArgs {
    /// Perturbation profile of the centre-out phase.
    #[arg(long, value_enum, default_value_t = ProfileArg::Cubic)]
    pub profile: ProfileArg,
    /// Folder for results (JSON and CSV).
    #[arg(long, default_value = "limpid-demo")]
    pub out: PathBuf,
    /// Random seed of the sensor noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print the comparison as JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Where to write the HTML report (default: report.html in the output folder).
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
}

/// One start point: truth, estimate, errors.
#[derive(Serialize)]
pub struct DemoPoint {
    pub start_point: String,
    pub position: [f64; 3],
    pub true_stiffness: Vec<Vec<f64>>,
    pub true_damping: Vec<Vec<f64>>,
    pub true_inertia: Vec<Vec<f64>>,
    /// Relative Frobenius errors, percent.
    pub stiffness_error_percent: f64,
    pub damping_error_percent: f64,
    pub inertia_error_percent: f64,
    pub estimate: LinearResult,
}

fn rel_err(est: &[Vec<f64>], truth: &Matrix3<f64>) -> f64 {
    let mut num = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            num += (est[i][j] - truth[(i, j)]).powi(2);
        }
    }
    100.0 * num.sqrt() / truth.norm()
}

fn run_point(p: &Posture, protocol: &CentreOut, seed: u64) -> CliResult<DemoPoint> {
    let rec = simulate_centre_out(p, protocol, &NoiseModel::default(), seed)?;
    let prepared = prepare(&rec, &PrepareParams::default())?;
    let est = fit_linear(&prepared, &LinearParams::default())?;
    let result = linear_result(&est, &prepared);
    Ok(DemoPoint {
        start_point: p.name.clone(),
        position: [p.start.x, p.start.y, p.start.z],
        true_stiffness: limpid_lab::session::rows(&p.stiffness),
        true_damping: limpid_lab::session::rows(&p.damping),
        true_inertia: limpid_lab::session::rows(&p.inertia),
        stiffness_error_percent: rel_err(&result.stiffness, &p.stiffness),
        damping_error_percent: rel_err(&result.damping, &p.damping),
        inertia_error_percent: rel_err(&result.inertia, &p.inertia),
        estimate: result,
    })
}

pub fn run(args: DemoArgs) -> CliResult {
    let profile = match args.profile {
        ProfileArg::Cubic => Profile::Cubic,
        ProfileArg::Trapezoid => Profile::Trapezoid,
        ProfileArg::Sinusoid => Profile::Sinusoid,
    };
    let protocol = CentreOut::seed000(profile);
    let subject = seed000_subject1();
    let bar = ProgressBar::new(subject.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} start points ({elapsed})")
            .map_err(|e| e.to_string())?
            .progress_chars("=> "),
    );
    bar.set_message("simulating and estimating");
    let points: Vec<DemoPoint> = subject
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let r = run_point(p, &protocol, args.seed.wrapping_mul(1000) + i as u64);
            bar.inc(1);
            r
        })
        .collect::<CliResult<_>>()?;
    bar.finish_and_clear();

    std::fs::create_dir_all(&args.out).map_err(|e| format!("{}: {e}", args.out.display()))?;
    let json_path = args.out.join("demo.json");
    limpid_core::files::write_file(
        &json_path,
        serde_json::to_string_pretty(&points)?.as_bytes(),
    )?;
    let csv_path = args.out.join("demo.csv");
    limpid_core::files::write_file(&csv_path, demo_csv(&points).as_bytes())?;
    let report_path = args
        .report
        .clone()
        .unwrap_or_else(|| args.out.join("report.html"));
    crate::report::write(&[serde_json::to_value(&points)?], &report_path)?;

    if args.json {
        println!("{}", serde_json::to_string_pretty(&points)?);
        return Ok(());
    }
    println!(
        "limpid demo: seed 000 protocol on a virtual subject (Table I, subject 1): 6 start points x {} {} perturbations of {} cm, {} s, {} Hz",
        protocol.directions.len(),
        format!("{profile:?}").to_lowercase(),
        protocol.radius_m * 100.0,
        protocol.motion_s,
        protocol.sample_rate
    );
    println!(
        "sensor noise: per-trial force offset 3 N, drift 0.05 N, white 0.1 N, position 20 um\n"
    );
    println!(
        "{:<6}{:<10}{:>30}{:>30}{:>10}{:>10}  inertia",
        "point", "", "Kxx Kyy Kzz (N/m)", "Bxx Byy Bzz (N s/m)", "K err %", "B err %"
    );
    for d in &points {
        let diag = |m: &Vec<Vec<f64>>| {
            format!(
                "{:>9} {:>9} {:>9}",
                num(m[0][0]),
                num(m[1][1]),
                num(m[2][2])
            )
        };
        let e = &d.estimate;
        let inertia = if e.criteria.identifiable.inertia {
            format!("identified, error {:.1} %", d.inertia_error_percent)
        } else {
            "not identifiable (too slow)".to_string()
        };
        println!(
            "{:<6}{:<10}{:>30}{:>30}",
            d.start_point,
            "true",
            diag(&d.true_stiffness),
            diag(&d.true_damping)
        );
        println!(
            "{:<6}{:<10}{:>30}{:>30}{:>10.2}{:>10.1}  {}",
            "",
            "estimated",
            diag(&e.stiffness),
            diag(&e.damping),
            d.stiffness_error_percent,
            d.damping_error_percent,
            inertia
        );
    }
    let worst_k = points
        .iter()
        .map(|d| d.stiffness_error_percent)
        .fold(0.0, f64::max);
    let worst_b = points
        .iter()
        .map(|d| d.damping_error_percent)
        .fold(0.0, f64::max);
    println!("\nworst stiffness error {worst_k:.2} %, worst damping error {worst_b:.1} % (relative Frobenius norm)");
    println!(
        "results: {} and {}",
        json_path.display(),
        csv_path.display()
    );
    Ok(())
}

fn demo_csv(points: &[DemoPoint]) -> String {
    let mut s = String::from("start_point,x,y,z,kind,true_xx,true_yy,true_zz,est_xx,est_yy,est_zz,error_percent,identifiable\n");
    for d in points {
        let e = &d.estimate;
        for (kind, t, m, err, ok) in [
            (
                "stiffness",
                &d.true_stiffness,
                &e.stiffness,
                d.stiffness_error_percent,
                e.criteria.identifiable.stiffness,
            ),
            (
                "damping",
                &d.true_damping,
                &e.damping,
                d.damping_error_percent,
                e.criteria.identifiable.damping,
            ),
            (
                "inertia",
                &d.true_inertia,
                &e.inertia,
                d.inertia_error_percent,
                e.criteria.identifiable.inertia,
            ),
        ] {
            s.push_str(&format!(
                "{},{},{},{},{kind},{},{},{},{},{},{},{err:.4},{ok}\n",
                d.start_point,
                d.position[0],
                d.position[1],
                d.position[2],
                t[0][0],
                t[1][1],
                t[2][2],
                m[0][0],
                m[1][1],
                m[2][2]
            ));
        }
    }
    s
}
