//! `limpid`: the command-line tool. Glue only: argument handling, then calls
//! into the library crates, then printing. Errors print as `limpid: <chain>`
//! and exit with status 2.

mod demo;
mod estimate;
mod planar;
mod study;
mod table;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// limpid — limb impedance identification.
#[derive(Parser)]
#[command(name = "limpid", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Estimate impedance from a recording.
    Estimate {
        #[command(subcommand)]
        method: estimate::Method,
    },
    /// Run seed 000's 3-D study on a built-in virtual subject and compare with the truth.
    Demo(demo::DemoArgs),
    /// Planar-arm estimates over a range of observation windows, with the minimum trustworthy window (seed 003).
    WindowSweep(planar::SweepArgs),
    /// Whole co-contraction studies: tables across subjects and configurations (seed 001).
    Study {
        #[command(subcommand)]
        command: study::StudyCommand,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Estimate { method } => estimate::run(method),
        Command::Demo(args) => demo::run(args),
        Command::Study { command } => study::run(command),
        Command::WindowSweep(args) => planar::run_sweep(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let mut msg = e.to_string();
            let mut source = std::error::Error::source(&*e);
            while let Some(s) = source {
                let text = s.to_string();
                if !msg.contains(&text) {
                    msg.push_str(": ");
                    msg.push_str(&text);
                }
                source = s.source();
            }
            eprintln!("limpid: {msg}");
            ExitCode::from(2)
        }
    }
}

/// Errors of any crate, boxed for the CLI.
pub type CliResult<T = ()> = Result<T, Box<dyn std::error::Error + Send + Sync>>;
