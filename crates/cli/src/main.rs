//! `limpid`: the command-line tool. Glue only: argument handling, then calls
//! into the library crates, then printing. Errors print as `limpid: <chain>`
//! and exit with status 2.

mod calibrate;
mod context;
mod demo;
mod emit;
mod estimate;
mod files;
mod gravity;
mod live;
mod planar;
mod protocol;
mod reflex;
mod report;
mod reproduce;
mod rerun;
mod stochastic;
mod study;
mod table;
mod text;
mod varying;

use std::process::ExitCode;

use clap::{CommandFactory, Parser, Subcommand};
use context::{CliResult, Context};

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
    /// Channel map (TOML) for commands that read recordings: which channel of a lab file (XDF, C3D, TDMS, MAT, ROS 2 bag, CSV) is which column, in which unit and sign.
    #[arg(long, global = true, value_name = "MAP.toml")]
    map: Option<std::path::PathBuf>,
    /// Name a column of the recording by its channel in the file, e.g. --column t=time_s --column q1=angle_rad (repeat it; the other columns keep their names; with --map, added to the map).
    #[arg(long = "column", global = true, value_name = "NAME=CHANNEL")]
    columns: Vec<String>,
    /// Threads the estimators run on [default: one a core, or RAYON_NUM_THREADS].
    #[arg(long, global = true, value_name = "N")]
    threads: Option<std::num::NonZeroUsize>,
}

#[derive(Subcommand)]
enum Command {
    /// Estimate impedance from a recording.
    Estimate {
        #[command(subcommand)]
        method: estimate::Method,
    },
    /// Run Artemiadis et al. (2010)'s 3-D study on a built-in virtual subject and compare with the truth.
    Demo(demo::DemoArgs),
    /// Planar-arm estimates over a range of observation windows, with the minimum trustworthy window (Lakatos et al. 2011).
    WindowSweep(planar::SweepArgs),
    /// Design and check perturbation protocols (TOML).
    Protocol {
        #[command(subcommand)]
        command: protocol::ProtocolCommand,
    },
    /// Simulate a protocol on a virtual subject: a recording and its truth file.
    Simulate(protocol::SimulateArgs),
    /// Live co-contraction feedback and online stiffness: a web page fed over UDP or by a replay (Patel et al. 2013, Fig. 3).
    Live(live::LiveArgs),
    /// One self-contained HTML report (ellipsoids, tables, Bode and coherence plots) from JSON results.
    Report(report::ReportArgs),
    /// Turn F/T sensor readings into the force (and torque) on the limb: bias and weight removed in two steps (Park & Chang 2011, eq. 4-9) or by a calibration from still poses.
    GravityCompensate(gravity::GravityArgs),
    /// Welch PSD, coherence, multiple and partial coherence of outputs on inputs, as CSV.
    Spectra(stochastic::SpectraArgs),
    /// Check that standard errors cover the truth and verdicts hold, by Monte Carlo over virtual subjects of every method.
    Calibrate(calibrate::CalibrateArgs),
    /// Run a paper's experiment on the virtual lab and print its tables beside the paper's (artemiadis2010, patel2013, lakatos2011, park2011 or all).
    Reproduce(reproduce::ReproduceArgs),
    /// Run the request recorded in a result's run block again, on the same input files.
    Rerun(rerun::RerunArgs),
    /// Show the streams, channels, rates, units, gaps and markers of a lab file (XDF, C3D, TDMS, MAT, ROS 2 bag, CSV, Parquet), with a proposed channel map.
    Inspect(files::InspectArgs),
    /// Convert a lab file to a recording (CSV or Parquet) through a channel map (--map).
    Convert(files::ConvertArgs),
    /// Whole co-contraction studies: tables across subjects and configurations (Patel et al. 2013).
    Study {
        #[command(subcommand)]
        command: study::StudyCommand,
    },
}

/// Every command, with negative numbers taken as values (`--cutoff -5` is
/// a bad cut-off, not an unknown flag `-5`).
fn command_accepting_negative_numbers(cmd: clap::Command) -> clap::Command {
    cmd.allow_negative_numbers(true)
        .mut_subcommands(command_accepting_negative_numbers)
}

/// The parsed command line; a usage error is one line on stderr and exit 2
/// (clap's own text is several lines with the usage), help and version as clap prints them.
fn parse_arguments() -> Result<Cli, ExitCode> {
    use clap::FromArgMatches;
    let cmd = command_accepting_negative_numbers(Cli::command());
    let parsed = cmd
        .try_get_matches()
        .and_then(|m| Cli::from_arg_matches(&m));
    parsed.map_err(|e| {
        use clap::error::ErrorKind;
        if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
            // written and flushed here: clap's own exit ignores a full or
            // closed standard output and exits 0 having printed nothing (issue 56)
            use std::io::Write;
            let text = e.render().to_string();
            let mut out = std::io::stdout().lock();
            return match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
                Ok(()) => ExitCode::SUCCESS,
                Err(io) => {
                    eprintln!("limpid: cannot write the output to standard output: {io}");
                    ExitCode::from(2)
                }
            };
        }
        if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
            e.exit()
        }
        eprintln!("limpid: {}", usage_error_line(&e.to_string()));
        ExitCode::from(2)
    })
}

/// clap's error text as one line: the error itself, its tip if any, and where
/// help is.
fn usage_error_line(text: &str) -> String {
    // the first paragraph is the error (a list of missing arguments follows its colon)
    let first: Vec<&str> = text
        .lines()
        .map(str::trim)
        .take_while(|l| !l.is_empty())
        .collect();
    let error = first.join(" ");
    let error = error.trim_start_matches("error: ");
    let tip = text
        .lines()
        .map(str::trim)
        .find(|l| l.starts_with("tip: "))
        .map(|t| format!(" ({})", t.trim_start_matches("tip: ")))
        .unwrap_or_default();
    let error = if error.is_empty() {
        "invalid arguments"
    } else {
        error
    };
    format!("{error}{tip}; see --help")
}

/// Where and why the last panic happened (set by the quiet panic hook).
static PANIC: std::sync::Mutex<Option<String>> = std::sync::Mutex::new(None);

fn main() -> ExitCode {
    // Output piped into `head` etc.: end quietly like other Unix tools instead of
    // panicking on a closed pipe.
    #[cfg(unix)]
    // SAFETY: resetting a signal disposition to its default at start-up, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    // A command started with its standard output closed would exit 0 having
    // printed nothing: Rust's runtime reopens a closed descriptor 1 on
    // /dev/null (read-write, which a shell's `> /dev/null` never is). Say so,
    // before `--help` or `--version` too (issue 56).
    #[cfg(unix)]
    if stdout_was_closed() {
        eprintln!("limpid: standard output is closed: nothing could be printed");
        return ExitCode::from(2);
    }
    let cli = match parse_arguments() {
        Ok(cli) => cli,
        Err(code) => return code,
    };
    // a panic is a bug or an unwritable output: one line and exit 2, never a backtrace
    std::panic::set_hook(Box::new(|info| {
        let message = limpid_core::error::panic_message(info.payload());
        let place = info
            .location()
            .map(|l| format!(" (at {}:{})", l.file(), l.line()))
            .unwrap_or_default();
        if let Ok(mut slot) = PANIC.lock() {
            *slot = Some(format!("{message}{place}"));
        }
    }));
    let result = std::panic::catch_unwind(|| in_thread_pool(cli)).unwrap_or_else(|_| {
        let what = PANIC
            .lock()
            .ok()
            .and_then(|mut s| s.take())
            .unwrap_or_else(|| "unknown panic".into());
        Err(
            if let Some(io) = what.strip_prefix("failed printing to stdout: ") {
                let io = io.split(" (at ").next().unwrap_or(io);
                format!("cannot write the output to standard output: {io}").into()
            } else {
                format!(
                    "internal error, please report it: {}",
                    what.replace('\n', "; ")
                )
                .into()
            },
        )
    });
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
            eprintln!("limpid: {}", limpid_core::error::tidy_numbers(&msg));
            ExitCode::from(2)
        }
    }
}

/// Whether descriptor 1 was closed when the process started, recorded by
/// [`RECORD_STDOUT_AT_START`] before Rust's start-up code reopens a closed
/// descriptor on /dev/null.
#[cfg(target_os = "linux")]
static STDOUT_CLOSED_AT_START: std::sync::atomic::AtomicBool =
    std::sync::atomic::AtomicBool::new(false);

/// Run by the loader with the program's other constructors, before `main`
/// and before the Rust runtime's own start-up (which is called from the C
/// `main`): the state of descriptor 1 as the process was given it.
#[cfg(target_os = "linux")]
#[used]
#[link_section = ".init_array"]
static RECORD_STDOUT_AT_START: extern "C" fn() = {
    extern "C" fn record() {
        // SAFETY: F_GETFD only reads the descriptor table.
        let closed = unsafe { libc::fcntl(libc::STDOUT_FILENO, libc::F_GETFD) } == -1;
        STDOUT_CLOSED_AT_START.store(closed, std::sync::atomic::Ordering::Relaxed);
    }
    record
};

/// Descriptor 1 was closed when the process started. On Linux as recorded
/// before the runtime's start-up: /dev/null opened read-write is also what
/// Python's `subprocess.DEVNULL` gives, a request to discard the output,
/// which the guess below refused.
#[cfg(target_os = "linux")]
fn stdout_was_closed() -> bool {
    STDOUT_CLOSED_AT_START.load(std::sync::atomic::Ordering::Relaxed)
}

/// Descriptor 1 is /dev/null opened read-write: how Rust's start-up code
/// fills a descriptor that was closed when the process started (elsewhere
/// than on Linux, a guess: a caller may open /dev/null so too).
#[cfg(all(unix, not(target_os = "linux")))]
fn stdout_was_closed() -> bool {
    // SAFETY: fcntl and fstat only read the descriptor's state into local
    // values; the path is a valid C string.
    unsafe {
        let flags = libc::fcntl(libc::STDOUT_FILENO, libc::F_GETFL);
        if flags == -1 {
            return true;
        }
        if flags & libc::O_ACCMODE != libc::O_RDWR {
            return false;
        }
        let mut out: libc::stat = std::mem::zeroed();
        let mut null: libc::stat = std::mem::zeroed();
        libc::fstat(libc::STDOUT_FILENO, &mut out) == 0
            && libc::stat(c"/dev/null".as_ptr(), &mut null) == 0
            && (out.st_mode & libc::S_IFMT) == libc::S_IFCHR
            && out.st_rdev == null.st_rdev
    }
}

/// Run the command on a pool of `--threads` threads, else on rayon's global pool.
fn in_thread_pool(cli: Cli) -> CliResult {
    let n = match cli.threads {
        Some(n) => limpid_core::threads::check_thread_count(n.get() as u128, "--threads")?,
        None => {
            // rayon's global pool reads the same variable: checked here first
            limpid_core::threads::environment_thread_count()?;
            return run(cli);
        }
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(|e| format!("--threads {n}: cannot start the threads: {e}"))?;
    pool.install(|| run(cli))
}

fn run(cli: Cli) -> CliResult {
    if cli.map.is_some() || !cli.columns.is_empty() {
        let flag = if cli.map.is_some() {
            "--map"
        } else {
            "--column"
        };
        let reads_recordings = matches!(
            cli.command,
            Command::Estimate { .. }
                | Command::WindowSweep(_)
                | Command::Spectra(_)
                | Command::GravityCompensate(_)
                | Command::Live(_)
                | Command::Convert(_)
        );
        if !reads_recordings {
            let why = match cli.command {
                Command::Study { .. } => "`study` reads the maps its manifest names ([study] map, or a recording's own map), not --map",
                Command::Rerun(_) => "`rerun` reads the map its result was made with (the run block's channel_map), not --map",
                _ => "it applies to the commands that read recordings (estimate, window-sweep, spectra, gravity-compensate, live, convert); this one reads none",
            };
            return Err(format!("{flag}: {why}").into());
        }
    }
    let cx = Context::new(command_accepting_negative_numbers(Cli::command()));
    let cx = match &cli.map {
        Some(path) => cx.with_map(path)?,
        None => cx,
    };
    let cx = cx.with_columns(limpid_io::parse_columns(&cli.columns)?);
    match cli.command {
        Command::Inspect(args) => files::run_inspect(args),
        Command::Convert(args) => files::run_convert(args, &cx),
        Command::Estimate { method } => estimate::run(method, &cx),
        Command::Demo(args) => demo::run(args),
        Command::Calibrate(args) => calibrate::run(args),
        Command::Study { command } => study::run(command),
        Command::WindowSweep(args) => planar::run_sweep(args, &cx),
        Command::Spectra(args) => stochastic::run_spectra(args, &cx),
        Command::Protocol { command } => protocol::run(command, &cx),
        Command::Simulate(args) => protocol::run_simulate(args),
        Command::GravityCompensate(args) => gravity::run(args, &cx),
        Command::Report(args) => report::run(args),
        Command::Reproduce(args) => reproduce::run(args),
        Command::Live(args) => live::run(args, &cx),
        Command::Rerun(args) => rerun::run(args, &cx),
    }
}
