//! `limpid`: the command-line tool. Glue only: argument handling, then calls
//! into the library crates, then printing. Errors print as `limpid: <chain>`
//! and exit with status 2.

mod demo;
mod estimate;
mod gravity;
mod live;
mod planar;
mod protocol;
mod report;
mod stochastic;
mod study;
mod table;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// limpid — limb impedance identification.
#[derive(Parser)]
#[command(
    name = "limpid",
    version,
    about = "limpid: limb impedance identification from robot-perturbation recordings",
    long_about = None
)]
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
    /// Design and check perturbation protocols (TOML).
    Protocol {
        #[command(subcommand)]
        command: protocol::ProtocolCommand,
    },
    /// Simulate a protocol on a virtual subject: a recording and its truth file.
    Simulate(protocol::SimulateArgs),
    /// Live co-contraction feedback and online stiffness: a web page fed over UDP or by a replay (seed 001 Fig. 3).
    Live(live::LiveArgs),
    /// One self-contained HTML report (ellipsoids, tables, Bode and coherence plots) from JSON results.
    Report(report::ReportArgs),
    /// Turn F/T sensor readings into the force (and torque) on the limb: bias and weight removed in two steps (seed 004 eq. 4-9) or by a calibration from still poses.
    GravityCompensate(gravity::GravityArgs),
    /// Welch PSD, coherence, multiple and partial coherence of outputs on inputs, as CSV.
    Spectra(stochastic::SpectraArgs),
    /// Whole co-contraction studies: tables across subjects and configurations (seed 001).
    Study {
        #[command(subcommand)]
        command: study::StudyCommand,
    },
}

fn main() -> ExitCode {
    // Output piped into `head` etc.: end quietly like other Unix tools instead of
    // panicking on a closed pipe.
    #[cfg(unix)]
    // SAFETY: resetting a signal disposition to its default at start-up, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Estimate { method } => estimate::run(method),
        Command::Demo(args) => demo::run(args),
        Command::Study { command } => study::run(command),
        Command::WindowSweep(args) => planar::run_sweep(args),
        Command::Spectra(args) => stochastic::run_spectra(args),
        Command::Protocol { command } => protocol::run(command),
        Command::Simulate(args) => protocol::run_simulate(args),
        Command::GravityCompensate(args) => gravity::run(args),
        Command::Report(args) => report::run(args),
        Command::Live(args) => live::run(args),
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
