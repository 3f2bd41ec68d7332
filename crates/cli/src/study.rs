//! `limpid study run` and `limpid study simulate` (seed 001 Tables 1-5).

use std::path::PathBuf;

use clap::{Args, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use limpid_app::study::{load_manifest, run_study_staged, simulate_study, stage_tables};

use crate::context::CliResult;

#[derive(Subcommand)]
pub enum StudyCommand {
    /// Process every recording of a manifest and write the study tables.
    Run(RunArgs),
    /// Write a virtual Patel, O'Neill & Artemiadis (2013) study (recordings, MVC files, study.toml) with known truth.
    Simulate(SimulateArgs),
}

#[derive(Args)]
pub struct RunArgs {
    /// Study manifest (TOML).
    pub manifest: PathBuf,
    /// Output folder for tables.csv, rotation.csv, study.json, tables.md.
    #[arg(long)]
    pub out: PathBuf,
    /// Print the Markdown tables to standard output too.
    #[arg(long)]
    pub print: bool,
    /// Also write the HTML report (tables, stiffness and index against level) to this file.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
}

#[derive(Args)]
pub struct SimulateArgs {
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Number of subjects (each in Patel et al. 2013's 7 configurations).
    #[arg(long, default_value_t = 4)]
    pub subjects: usize,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Virtual subjects: realistic (Patel et al. 2013, Tables 1-5 with reflex,
    /// force fluctuation and one MVC from configuration 5) or ideal (clean,
    /// linear in the level, an MVC per recording).
    #[arg(long, value_enum, default_value_t = crate::demo::SubjectArg::Realistic)]
    pub subject: crate::demo::SubjectArg,
}

fn bar(len: usize, msg: &'static str) -> CliResult<ProgressBar> {
    let bar = ProgressBar::new(len as u64);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} ({elapsed})")
            .map_err(|e| e.to_string())?
            .progress_chars("=> "),
    );
    bar.set_message(msg);
    Ok(bar)
}

pub fn run(cmd: StudyCommand) -> CliResult {
    match cmd {
        StudyCommand::Run(args) => {
            limpid_core::files::check_output_folder(&args.out)?;
            if let Some(path) = &args.report {
                limpid_core::files::refuse_overwriting_inputs(
                    &[(path, "the report (--report)")],
                    &[(&args.manifest, "the study manifest")],
                )?;
            }
            let manifest = load_manifest(&args.manifest)?;
            if let Some(path) = &args.report {
                limpid_core::files::check_output_path(path)?;
            }
            let progress = bar(manifest.recording.len(), "processing recordings")?;
            // every output of the study is one set, committed at the end: a
            // full disk or an unwritable --report leaves none of them (issue 36)
            let mut outputs = limpid_core::files::OutputSet::new();
            let result = run_study_staged(&manifest, &args.out, &mut outputs, &|| progress.inc(1))?;
            progress.finish_and_clear();
            let ok = result.recordings.len();
            if ok == 0 {
                let first = result
                    .failures
                    .first()
                    .map_or(String::new(), |f| format!(": {}", f.error));
                return Err(
                    format!("no recording could be processed (nothing written){first}").into(),
                );
            }
            let tables = stage_tables(&result, &args.out, &mut outputs)?;
            let doc = limpid_analysis::result::Document::new(
                limpid_analysis::result::Estimate::Study(result),
            )
            .with_run(limpid_analysis::result::Run::of_this_process(&[
                &args.manifest
            ]));
            if let Some(path) = &args.report {
                outputs.add(path, limpid_report::page(&doc).as_bytes())?;
            }
            outputs.commit()?;
            if let Some(path) = &args.report {
                eprintln!("report: {}", path.display());
            }
            let limpid_analysis::result::Estimate::Study(result) = &doc.estimate else {
                unreachable!("made above")
            };
            println!(
                "study {}: {ok} of {} recordings processed, {} configurations",
                result.name,
                manifest.recording.len(),
                result.rotation.len()
            );
            for f in &result.failures {
                println!(
                    "failed: subject {}, configuration {}: {}",
                    f.subject, f.configuration, f.error
                );
            }
            if args.print {
                println!("\n{}", limpid_report::text::study_markdown(result));
            }
            println!(
                "wrote {} and {} per-recording results in {}",
                tables
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                ok,
                args.out.join("recordings").display()
            );
            Ok(())
        }
        StudyCommand::Simulate(args) => {
            if !(1..=1000).contains(&args.subjects) {
                return Err(limpid_core::Error::invalid(
                    "subjects",
                    format!("expected 1 to 1000, found {}", args.subjects),
                )
                .into());
            }
            let progress = bar(7 * args.subjects, "simulating recordings")?;
            let (recordings, path) = simulate_study(
                &args.out,
                args.subjects,
                matches!(args.subject, crate::demo::SubjectArg::Realistic),
                args.seed,
                &|| progress.inc(1),
            )?;
            progress.finish_and_clear();
            println!("wrote {} recordings and {}", recordings, path.display());
            Ok(())
        }
    }
}
