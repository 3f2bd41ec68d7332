//! `limpid demo`: seed 000's 3-D study on a built-in virtual subject
//! ([`limpid_app::demo`] runs it; this prints and writes it).

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use limpid_analysis::linear::MatrixKind;
use limpid_analysis::result::demo::DemoSubject;
use limpid_analysis::result::{Document, Estimate};
use limpid_app::demo::run_demo;
use limpid_core::criteria::MatrixVerdict;
use limpid_core::Matrix;
use limpid_lab::Profile;
use limpid_report::text::demo_csv;

use crate::context::CliResult;
use crate::table::num;

#[derive(Clone, Copy, ValueEnum)]
pub enum ProfileArg {
    Cubic,
    Trapezoid,
    Sinusoid,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum SubjectArg {
    /// Built from the seed's tables, with force fluctuation, drift (and reflexes).
    Realistic,
    /// The clean subject: the typed-in matrices, sensor noise only.
    Ideal,
}

#[derive(Args)]
pub struct DemoArgs {
    /// Virtual subject: realistic (Artemiadis et al. 2010, Tables I-II with signal-dependent
    /// force noise and posture drift) or ideal (Table I, sensor noise only).
    #[arg(long, value_enum, default_value_t = SubjectArg::Realistic)]
    pub subject: SubjectArg,
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
    /// Leave out the designed protocol (`limpid protocol design` for S1 on the same subject,
    /// limits and time), which takes a few seconds.
    #[arg(long)]
    pub no_design: bool,
    /// Where to write the HTML report (default: report.html in the output folder).
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
}

pub fn run(args: DemoArgs) -> CliResult {
    if let Some(path) = &args.report {
        limpid_core::files::check_output_path(path)?;
    }
    let profile = match args.profile {
        ProfileArg::Cubic => Profile::Cubic,
        ProfileArg::Trapezoid => Profile::Trapezoid,
        ProfileArg::Sinusoid => Profile::Sinusoid,
    };
    let bar = ProgressBar::new(6);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} start points ({elapsed})")
            .map_err(|e| e.to_string())?
            .progress_chars("=> "),
    );
    bar.set_message("simulating and estimating");
    let subject = match args.subject {
        SubjectArg::Realistic => DemoSubject::Realistic,
        SubjectArg::Ideal => DemoSubject::Ideal,
    };
    let result = run_demo(profile, subject, args.seed, !args.no_design, &|| bar.inc(1))?;
    bar.finish_and_clear();
    let doc = Document::new(Estimate::Demo(result))
        .with_run(limpid_analysis::result::Run::of_this_process(&[]));
    let Estimate::Demo(result) = &doc.estimate else {
        unreachable!("made above")
    };

    // the result, its table and its report are one set: an unwritable
    // --report path leaves no half-written output folder (issue 36)
    let mut outputs = limpid_core::files::OutputSet::new();
    outputs.create_dir(&args.out)?;
    let json_path = args.out.join("demo.json");
    outputs.add(&json_path, doc.to_json_pretty().as_bytes())?;
    let csv_path = args.out.join("demo.csv");
    outputs.add(&csv_path, demo_csv(result).as_bytes())?;
    let report_path = args
        .report
        .clone()
        .unwrap_or_else(|| args.out.join("report.html"));
    outputs.add(&report_path, limpid_report::page(&doc).as_bytes())?;
    outputs.commit()?;
    eprintln!("report: {}", report_path.display());

    if args.json {
        println!("{}", doc.to_json_pretty());
        return Ok(());
    }
    print_demo(result);
    println!(
        "results: {} and {}",
        json_path.display(),
        csv_path.display()
    );
    Ok(())
}

/// The demo's table: per start point the true and estimated diagonals, the
/// errors where the data identify the matrix, and the worst errors.
fn print_demo(result: &limpid_analysis::result::demo::DemoResult) {
    println!(
        "limpid demo: Artemiadis et al. (2010) protocol on a virtual subject (Table I, subject 1): 6 start points x {} {} perturbations of {} cm, {} s, {} Hz",
        result.directions,
        result.profile,
        result.radius_m * 100.0,
        result.motion_s,
        result.sample_rate_hz
    );
    match result.subject {
        DemoSubject::Realistic => println!(
            "subject: realistic (Table II's antisymmetric stiffness; force fluctuation 25 % of the subject's force below 2 Hz, posture drift 0.5 mm, force drift 0.3 N)\nsensor noise: per-trial force offset 3 N, white 0.1 N, position 20 um\n"
        ),
        DemoSubject::Ideal => println!(
            "subject: ideal (Table I exactly)\nsensor noise: per-trial force offset 3 N, drift 0.05 N, white 0.1 N, position 20 um\n"
        ),
    }
    println!(
        "{:<6}{:<10}{:>30}{:>30}{:>10}{:>10}  inertia",
        "point", "", "Kxx Kyy Kzz (N/m)", "Bxx Byy Bzz (N s/m)", "K err %", "B err %"
    );
    for d in &result.points {
        let diag = |m: &Matrix| {
            format!(
                "{:>9} {:>9} {:>9}",
                num(m[(0, 0)]),
                num(m[(1, 1)]),
                num(m[(2, 2)])
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
        // an error is shown only for a matrix the data identify
        let error = |kind: MatrixKind, v: f64, decimals: usize| {
            if e.criteria.verdicts.get(kind) == &MatrixVerdict::NotIdentifiable {
                "n/i".to_string()
            } else {
                format!("{v:.decimals$}")
            }
        };
        println!(
            "{:<6}{:<10}{:>30}{:>30}{:>10}{:>10}  {}",
            "",
            "estimated",
            diag(&e.stiffness),
            diag(&e.damping),
            error(MatrixKind::Stiffness, d.stiffness_error_percent, 2),
            error(MatrixKind::Damping, d.damping_error_percent, 1),
            inertia
        );
    }
    let worst =
        |kind: MatrixKind, name: &str, decimals: usize| match result.worst_error_percent(kind) {
            Some(v) => format!("worst {name} error {v:.decimals$} %"),
            None => format!("{name} not identifiable at any start point"),
        };
    println!(
        "\n{}, {} (relative Frobenius norm over the identifiable points; n/i: not identifiable from this data, its error is not a measure of limpid)",
        worst(MatrixKind::Stiffness, "stiffness", 2),
        worst(MatrixKind::Damping, "damping", 1)
    );
    if let Some(d) = &result.designed {
        let c = &d.chosen;
        let p = &d.point;
        let e = &p.estimate;
        let verdict = |kind: MatrixKind, v: f64| {
            if e.criteria.verdicts.get(kind) == &MatrixVerdict::NotIdentifiable {
                "not identifiable".to_string()
            } else {
                format!("{v:.1} %")
            }
        };
        println!(
            "\nthe same minutes designed (limpid protocol design, objective K and B): at {} the seed's {:.1} s hold {}, within the same limits",
            p.start_point,
            d.budget_s,
            c.describe(num)
        );
        println!(
            "{:<6}{:<10}{:>30}{:>30}{:>10}{:>10}  inertia {}",
            p.start_point,
            "designed",
            format!(
                "{:>9} {:>9} {:>9}",
                num(e.stiffness[(0, 0)]),
                num(e.stiffness[(1, 1)]),
                num(e.stiffness[(2, 2)])
            ),
            format!(
                "{:>9} {:>9} {:>9}",
                num(e.damping[(0, 0)]),
                num(e.damping[(1, 1)]),
                num(e.damping[(2, 2)])
            ),
            verdict(MatrixKind::Stiffness, p.stiffness_error_percent),
            verdict(MatrixKind::Damping, p.damping_error_percent),
            verdict(MatrixKind::Inertia, p.inertia_error_percent)
        );
        println!(
            "      (predicted for the design: K ± {:.1} %, B ± {:.1} % of the RMS element; `limpid protocol design --prior demo:S1 --limits-from P.toml --duration {:.1}` writes it)",
            d.predicted_se_percent[0], d.predicted_se_percent[1], d.budget_s
        );
    }
}
