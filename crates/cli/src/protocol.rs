//! `limpid protocol new|check` and `limpid simulate` (virtual lab, centre-out protocols).

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use limpid_lab::design::{check, Design, DesignReport, PlanarDesign, StochasticDesign};
use limpid_lab::export::placed_robot;
use limpid_lab::protocol::Protocol;
use limpid_lab::session::{simulate_design, RigController, SubjectText};

use crate::context::{CliResult, Context};
use crate::table::num;

#[derive(Subcommand)]
pub enum ProtocolCommand {
    /// Print a preset protocol as TOML (seed 000's artemiadis-3d, seed 001's patel-cocontraction, seed 003's lakatos-planar, seed 004's park-stochastic; ensembles, ramp-and-hold, multisines, PRBS and walking).
    New {
        /// The preset.
        #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(limpid_lab::design::PRESET_NAMES))]
        preset: String,
        /// Write to this file instead of standard output.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// The protocol's schedule at its sample rate (CSV or Parquet): end-effector poses and
    /// joint trajectories for a robot (centre-out), joint angles with the random waits
    /// (planar), or the input signals (stochastic).
    Export {
        protocol: PathBuf,
        /// Centre-out only: kuka-lwr4, puma3 or a .urdf file, for joint angles as well;
        /// without it, the end-point command (t, start_point, trial, x, y, z).
        #[arg(long)]
        robot: Option<String>,
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Design a protocol for an estimate, within the limits at every sample and a time budget:
    /// a centre-out protocol for the linear estimator (profile, radius, speed, hold, rest and
    /// number of perturbations that minimise the predicted variance of K, B, M on a prior
    /// subject), or a PRBS for the reflex method's gain (--method reflex).
    Design(DesignArgs),
    /// Check a protocol against its safety limits and report what it will excite,
    /// with the condition number the estimator will meet on a nominal subject.
    Check {
        protocol: PathBuf,
        #[arg(long)]
        json: bool,
    },
}

#[derive(Args)]
pub struct DesignArgs {
    /// Prior subject (TOML): 3 x 3 `inertia`, `damping`, `stiffness` (SI), optional `start_m`
    /// (the posture), `[other_end]` (the same matrices at the other end of its range: the
    /// design is for the worse end), `[noise]` (default: a human subject's) and `[limits]`.
    /// `demo:S1` .. `demo:S6`: the demo's realistic subject at that start point. Planar
    /// method: an arm, `xi` (3), 2 x 2 joint `stiffness`, `damping`, optional `posture_rad`,
    /// `tau0`, `[other_end]`, `[reflex]`, `[noise]`, `[limits]`; `demo:planar`: seed 003's
    /// arm holding a load, with a reflex at 90 ms.
    #[arg(long)]
    pub prior: String,
    /// Take the limits, workspace and sample rate of this protocol (TOML): centre-out (linear;
    /// stochastic too, its displacement limit kept in the workspace), an end-point periodic
    /// one (stochastic), a PRBS (reflex), a planar one (planar: its links, posture and waits
    /// too; default lakatos-planar's), or a preset's name (e.g. ankle-prbs).
    #[arg(long, value_name = "P.toml")]
    pub limits_from: Option<PathBuf>,
    /// The designed protocol's whole length (s): rests, motions, holds, returns and relaxation
    /// (a periodic protocol's fade-in and fade-out periods).
    #[arg(long, value_name = "S")]
    pub duration: f64,
    /// What matters: `stiffness,damping` or weights, `stiffness=2,damping=1,inertia=0.5`
    /// (linear, stochastic); the reflex method minimises the reflex gain's error (`gain`).
    #[arg(long, default_value = "stiffness,damping")]
    pub objective: String,
    /// Over the prior's range (`[other_end]`): `worst` (the worse end; the prediction is
    /// conservative for the subjects between) or `expected` (the mean over its ends and
    /// midpoint; the prediction is the range's average). Linear, stochastic and planar methods.
    #[arg(long, default_value = "worst", value_name = "worst|expected")]
    pub robust: String,
    /// The family the protocol is chosen from: centre-out (linear; planar: quintic joint steps
    /// out from the posture), multisine (stochastic), prbs (reflex) or any (the method's).
    #[arg(long, default_value = "any")]
    pub family: String,
    /// The estimator the design is for: linear (a centre-out protocol for K, B, M), stochastic
    /// (an end-point multisine for `estimate stochastic --period`; the same priors) or reflex
    /// (a PRBS for the stretch-reflex gain; --prior is an ankle: inertia, damping, stiffness,
    /// [reflex], torque_noise_nm, or demo:ankle; --limits-from a PRBS protocol) or planar
    /// (quintic joint perturbations for `estimate planar`; --prior an arm or demo:planar).
    #[arg(long, default_value = "linear")]
    pub method: String,
    /// The protocol it replaces (TOML; centre-out, an end-point multisine for --method
    /// stochastic, a PRBS for --method reflex, a planar one for --method planar): predicted on
    /// the prior beside the design (a centre-out or planar one at the prior's posture).
    #[arg(long, value_name = "P.toml")]
    pub baseline: Option<PathBuf>,
    /// Linear, stochastic and planar methods: simulate N recordings on subjects drawn from the
    /// prior and print predicted against achieved spread.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub verify: usize,
    /// Simulated recordings behind the prediction.
    #[arg(long, value_name = "N", default_value_t = 40)]
    pub runs: usize,
    /// Seed of the simulated noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the designed protocol (TOML) here.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Print the result as JSON (`kind: design`; `reflex_design` for --method reflex,
    /// `planar_design` for --method planar).
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct SimulateArgs {
    /// Protocol (TOML).
    pub protocol: PathBuf,
    /// Subject (TOML). Centre-out: 3 x 3 `inertia`, `damping`, `stiffness` (SI) and
    /// optionally a `[noise]` table; default Artemiadis et al. (2010) Table I subject 1, posture i at
    /// start point i. Planar: `xi` (3), 2 x 2 `stiffness`, `damping`, `tau0` (2),
    /// optional `[reflex]` (latency_s, stiffness_gain, damping_gain); default the
    /// Lakatos, Petit & van der Smagt (2011) subject. Stochastic: a spring set `springs` (8 values, N/m, k1a..k4b);
    /// default the spring set SA3 (k1a = k1b = 50, k2a = k2b = 30, k3b = 66.37 N/m).
    #[arg(long)]
    pub subject: Option<PathBuf>,
    /// Output recording (.csv or .parquet); with several start points `_S<i>` is added before the extension.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Random seed of the sensor noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Stochastic protocols: who holds the spring array. `ideal`: a linear robot with
    /// the desired impedance; `imbic`: the PUMA-type robot with joint friction under
    /// IMBIC (Park & Chang 2011, eq. 11-14); `pd`: the same robot under a plain PD law.
    #[arg(long, value_enum, default_value_t = ControllerArg::Ideal)]
    pub controller: ControllerArg,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ControllerArg {
    Ideal,
    Imbic,
    Pd,
}

/// Read a protocol and check it against its limits; the report comes along.
fn read_design(path: &Path) -> CliResult<(Design, DesignReport)> {
    let text = limpid_core::files::read_text(path)?;
    let d = Design::from_toml(&text, path)?;
    let report = check(&d).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok((d, report))
}

pub fn run(cmd: ProtocolCommand, cx: &Context) -> CliResult {
    match cmd {
        ProtocolCommand::New {
            preset: name,
            output,
        } => {
            let text = format!(
                "# limpid protocol (preset {name}); units: m, rad, s, Hz, N\n{}",
                Design::preset(&name)?.to_toml()
            );
            match output {
                Some(p) => {
                    toml_output(&p)?;
                    limpid_core::files::write_file(&p, text.as_bytes())?
                }
                None => print!("{text}"),
            }
            Ok(())
        }
        ProtocolCommand::Export {
            protocol,
            robot,
            output,
        } => {
            limpid_core::files::refuse_overwriting_inputs(
                &[(&output, "the output (-o)")],
                &[(&protocol, "the protocol")],
            )?;
            match (read_design(&protocol)?.0, robot) {
            (Design::CentreOut(p), Some(robot)) => export(&p, &robot, &protocol, &output),
            (Design::CentreOut(p), None) => export_command(&p, &protocol, &output),
            (Design::Planar(_) | Design::Stochastic(_), Some(_)) => Err(
                "--robot: a planar or stochastic protocol is exported as its own commands (joint angles; commanded inputs), not through a robot: leave out --robot".into(),
            ),
            (Design::Planar(p), None) => export_planar(&p, &output),
            (Design::Periodic(p), None) => export_periodic(&p, &output),
            (Design::Periodic(_), Some(_)) => Err(
                "a multisine or PRBS is exported in its own coordinates (t, the channels, period): leave out --robot".into(),
            ),
            (Design::Stochastic(p), None) => export_stochastic(&p, &output),
            (Design::Ensemble(_) | Design::RampAndHold(_) | Design::Walking(_), _) => Err(
                "ensemble, ramp-and-hold and walking protocols are for `limpid simulate`; exporting them to a robot is not supported yet".into(),
            ),
            }
        }
        ProtocolCommand::Design(args) => run_design(args, cx),
        ProtocolCommand::Check { protocol, json } => {
            let (d, report) = read_design(&protocol)?;
            let predicted = limpid_app::protocol::predicted_condition(&d)?;
            if json {
                let mut v = serde_json::to_value(&report)?;
                v["predicted_condition_number"] = serde_json::json!(predicted);
                println!("{}", serde_json::to_string_pretty(&v)?);
                return Ok(());
            }
            println!("protocol {}: within its limits", protocol.display());
            print_report(&d, &report);
            if let Some(c) = predicted {
                println!("  condition number of the estimator's scaled regressor on a nominal noise-free subject: {}", num(c));
            }
            Ok(())
        }
    }
}

fn print_report(d: &Design, report: &DesignReport) {
    match (d, report) {
        (Design::CentreOut(p), DesignReport::CentreOut(r)) => {
            println!(
                "  {} trials of {} samples; {} target directions, minimum angular separation {:.2} deg",
                r.trials, r.samples_per_trial, p.targets.count, r.min_separation_deg
            );
            println!(
                "  peaks: displacement {} m, velocity {} m/s, acceleration {} m/s^2, expected force {} N",
                num(r.peak_displacement_m), num(r.peak_velocity_m_s), num(r.peak_acceleration_m_s2), num(r.peak_force_n)
            );
            print_ratios(&r.conditioning_ratios);
        }
        (Design::Planar(_), DesignReport::Planar(r)) => {
            println!(
                "  {} trials in {:.1} s; peaks: joint displacement {} rad, velocity {} rad/s, acceleration {} rad/s^2, expected torque {} N m",
                r.trials, r.session_s, num(r.peak_joint_displacement_rad), num(r.peak_joint_velocity_rad_s), num(r.peak_joint_acceleration_rad_s2), num(r.peak_torque_nm)
            );
            print_ratios(&r.conditioning_ratios);
        }
        (Design::Stochastic(p), DesignReport::Stochastic(r)) => {
            println!(
                "  {} samples per channel; peak inputs {}; predicted peak displacement {} m",
                r.samples,
                p.channels
                    .iter()
                    .zip(&r.peak_force)
                    .map(|(c, v)| format!("{c} {}", num(*v)))
                    .collect::<Vec<_>>()
                    .join(", "),
                num(r.predicted_peak_displacement_m)
            );
            println!(
                "  largest input coherence below {} Hz: {:.3} ({} / {} at {:.2} Hz; limit {})",
                p.cutoff_hz,
                r.max_input_coherence,
                r.max_coherence_pair[0],
                r.max_coherence_pair[1],
                r.max_coherence_hz,
                p.max_input_coherence
            );
        }
        (_, DesignReport::Varying(r)) => {
            println!("  {} samples, {:.1} s recorded", r.samples, r.duration_s);
        }
        (Design::Periodic(p), DesignReport::Periodic(r)) => {
            println!(
                "  {} samples ({:.1} s): a fade-in period, {} periods of {} s, a fade-out period",
                r.samples,
                r.duration_s,
                p.periods,
                num(r.period_s)
            );
            for (i, name) in p.channel_names().iter().enumerate() {
                println!(
                    "  {name}: peaks displacement {}, velocity {}, acceleration {}, force or torque {} (nominal stiffness); crest factor {:.2}; {} excited lines",
                    num(r.peak_displacement[i]),
                    num(r.peak_velocity[i]),
                    num(r.peak_acceleration[i]),
                    num(r.peak_force[i]),
                    r.crest_factor[i],
                    r.excited_lines[i]
                );
            }
            println!(
                "  {} detection lines between the excited ones (for nonlinear distortion); largest input coherence at a shared line {:.3}",
                r.detection_lines, r.max_input_coherence
            );
        }
        _ => {}
    }
}

fn print_ratios(c: &[f64; 3]) {
    println!(
        "  conditioning ratios C12, C13, C23 (Lakatos et al. 2011, eq. 17): {}, {}, {}",
        num(c[0]),
        num(c[1]),
        num(c[2])
    );
}

/// Write a periodic protocol's command in its own coordinates: `t`, the
/// channels (displacement from the posture) and `period` (-1: fade-in and
/// fade-out), any rig or simulator can play it.
fn export_periodic(p: &limpid_lab::periodic::PeriodicDesign, output: &Path) -> CliResult {
    let c = p.command()?;
    let mut names = vec!["t".to_string()];
    names.extend(c.channels.iter().cloned());
    names.push("period".into());
    let mut columns = vec![c.t.clone()];
    columns.extend(c.values.iter().cloned());
    columns.push(c.period.iter().map(|&i| i as f64).collect());
    let rec = limpid_core::Recording::new(output, names, columns, 2)?;
    limpid_io::write_recording(&rec, output)?;
    println!(
        "wrote {}: {} samples of {} with a period column ({} samples a period)",
        output.display(),
        rec.len(),
        c.channels.join(", "),
        c.period_samples
    );
    Ok(())
}

/// Write a centre-out schedule (`limpid_lab::export`) and say so.
fn export(p: &Protocol, robot: &str, protocol: &Path, output: &Path) -> CliResult {
    let urdf = Path::new(robot);
    let is_urdf = urdf
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("urdf"));
    let source = if is_urdf { urdf } else { protocol };
    let robot = placed_robot(robot, p)?;
    let rec = limpid_lab::export::centre_out_schedule(p, Some(&robot), source)?;
    limpid_io::write_recording(&rec, output)?;
    println!(
        "wrote {}: {} samples of end-effector positions and {} joint angles ({})",
        output.display(),
        rec.len(),
        robot.dof(),
        robot.name
    );
    Ok(())
}

/// Write a centre-out protocol's end-point command (no robot) and say so.
fn export_command(p: &Protocol, protocol: &Path, output: &Path) -> CliResult {
    let rec = limpid_lab::export::centre_out_schedule(p, None, protocol)?;
    limpid_io::write_recording(&rec, output)?;
    println!(
        "wrote {}: {} samples ({:.1} s) of end-point positions x, y, z (m) with start_point and trial columns, at rest at the start point at both ends",
        output.display(),
        rec.len(),
        rec.len() as f64 / p.sample_rate_hz
    );
    Ok(())
}

/// A protocol is written as TOML: an output named otherwise (`-o x.xlsx`
/// wrote TOML into a spreadsheet's name; issue 76) is refused.
/// A device or FIFO (`-o /dev/null`, a pipe) is written through as it is.
fn toml_output(path: &Path) -> CliResult {
    let toml = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    let stream = std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir());
    if toml || stream {
        Ok(())
    } else {
        Err(format!(
            "{}: a protocol is written as TOML: name the output NAME.toml",
            path.display()
        )
        .into())
    }
}

fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("recording");
    let ext = path.extension().and_then(|s| s.to_str()).unwrap_or("csv");
    path.with_file_name(format!("{stem}{suffix}.{ext}"))
}

/// Write Lakatos, Petit & van der Smagt (2011)'s planar schedule and say so.
fn export_planar(p: &PlanarDesign, output: &Path) -> CliResult {
    let rec = limpid_lab::export::planar_schedule(p, output)?;
    limpid_io::write_recording(&rec, output)?;
    let schedule = p.schedule();
    let end = schedule
        .last()
        .map(|s| s.0 + p.after_s + p.interpolation_s)
        .unwrap_or(0.0);
    println!(
        "wrote {}: {} samples ({:.1} s) of joint angles for {} perturbations",
        output.display(),
        rec.len(),
        end,
        schedule.len()
    );
    Ok(())
}

/// Write Park & Chang (2011)'s commanded inputs and say so.
fn export_stochastic(p: &StochasticDesign, output: &Path) -> CliResult {
    let rec = limpid_lab::export::stochastic_schedule(p, output)?;
    limpid_io::write_recording(&rec, output)?;
    println!(
        "wrote {}: {} samples of {} input channels",
        output.display(),
        rec.len(),
        p.channels.len()
    );
    Ok(())
}

/// Write `<recording>.truth.json` beside a written recording and say so.
fn write_truth(recording: &Path, samples: usize, truth: &limpid_core::Truth) -> CliResult {
    let path = recording.with_extension("truth.json");
    limpid_core::files::write_file(&path, serde_json::to_string_pretty(truth)?.as_bytes())?;
    println!(
        "wrote {} ({samples} samples) and {}",
        recording.display(),
        path.display()
    );
    Ok(())
}

pub fn run_simulate(args: SimulateArgs) -> CliResult {
    let mut inputs = vec![(args.protocol.as_path(), "the protocol")];
    inputs.extend(
        args.subject
            .as_deref()
            .map(|p| (p, "the subject (--subject)")),
    );
    let truth = args.output.with_extension("truth.json");
    limpid_core::files::refuse_overwriting_inputs(
        &[
            (&args.output, "the output (-o)"),
            (&truth, "the truth file simulate writes beside -o"),
        ],
        &inputs,
    )?;
    if let Some(dir) = args.output.parent().filter(|d| !d.as_os_str().is_empty()) {
        limpid_core::files::create_dir(dir)?;
    }
    let design = read_design(&args.protocol)?.0;
    let subject_file = match &args.subject {
        Some(path) => Some((path, limpid_core::files::read_text(path)?)),
        None => None,
    };
    let subject = subject_file
        .as_ref()
        .map(|(path, text)| SubjectText { text, path });
    let controller = match args.controller {
        ControllerArg::Ideal => RigController::Ideal,
        ControllerArg::Imbic => RigController::Imbic,
        ControllerArg::Pd => RigController::Pd,
    };
    // errors without a file of their own (a parameter) belong to the protocol
    let runs =
        simulate_design(&design, subject.as_ref(), controller, args.seed).map_err(|e| match e {
            limpid_core::Error::InvalidParameter { .. } => {
                format!("{}: {e}", args.protocol.display())
            }
            other => other.to_string(),
        })?;
    // every file the runs derive (recordings `_S1`.., their truth files),
    // by any name or link, before the first is written
    let outputs: Vec<(PathBuf, PathBuf)> = runs
        .iter()
        .map(|run| {
            let out = match &run.label {
                Some(label) => with_suffix(&args.output, &format!("_{label}")),
                None => args.output.clone(),
            };
            let truth = out.with_extension("truth.json");
            (out, truth)
        })
        .collect();
    let named: Vec<(&Path, &str)> = outputs
        .iter()
        .flat_map(|(out, truth)| {
            [
                (out.as_path(), "a recording simulate writes (-o)"),
                (truth.as_path(), "a truth file simulate writes beside -o"),
            ]
        })
        .collect();
    limpid_core::files::refuse_overwriting_inputs(&named, &inputs)?;
    for (run, (out, _)) in runs.into_iter().zip(&outputs) {
        limpid_io::write_recording(&run.recording, out)?;
        write_truth(out, run.recording.len(), &run.truth)?;
    }
    Ok(())
}

/// A design's error: a setting's names its flag by the CLI's one rule
/// ([`Context::with_flag_names`]); the prior file's (a start point outside the
/// workspace, a prior too stiff for the force limit) names the file.
fn design_error(cx: &Context, args: &DesignArgs, e: limpid_core::Error) -> String {
    match e {
        limpid_core::Error::InvalidParameter { name, message }
            if name == "prior" && !args.prior.starts_with("demo:") =>
        {
            format!("{}: {message}", args.prior)
        }
        e => cx.with_flag_names("protocol design", e).to_string(),
    }
}

/// The texts a design reads: the prior (`demo:S1` is its own text), the
/// limits and the baseline protocol, each read once for both methods.
struct DesignTexts {
    prior: String,
    limits: Option<String>,
    baseline: Option<String>,
}

impl DesignTexts {
    fn read(args: &DesignArgs, demo: bool) -> limpid_core::Result<Self> {
        let read = |p: &Path| limpid_core::files::read_text(p);
        Ok(DesignTexts {
            prior: if demo {
                args.prior.clone()
            } else {
                read(Path::new(&args.prior))?
            },
            // a preset's name as Python accepts it (issue 81), unless a file has that name
            limits: args
                .limits_from
                .as_deref()
                .map(|p| match p.to_str() {
                    Some(name)
                        if !p.exists() && limpid_lab::design::PRESET_NAMES.contains(&name) =>
                    {
                        limpid_lab::design::Design::preset(name).map(|d| d.to_toml())
                    }
                    _ => read(p),
                })
                .transpose()?,
            baseline: args.baseline.as_deref().map(read).transpose()?,
        })
    }
}

fn run_design(args: DesignArgs, cx: &Context) -> CliResult {
    let mut inputs: Vec<(&Path, &str)> = Vec::new();
    let prior_path = PathBuf::from(&args.prior);
    let demo = args.prior.starts_with("demo:");
    if !demo {
        inputs.push((&prior_path, "the prior (--prior)"));
    }
    inputs.extend(
        args.limits_from
            .as_deref()
            .map(|p| (p, "the limits (--limits-from)")),
    );
    inputs.extend(
        args.baseline
            .as_deref()
            .map(|p| (p, "the baseline (--baseline)")),
    );
    if let Some(out) = &args.output {
        toml_output(out)?;
        limpid_core::files::refuse_overwriting_inputs(&[(out, "the output (-o)")], &inputs)?;
        // the output's folder before the seconds of designing, as `simulate` makes it
        if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
            limpid_core::files::create_dir(dir)?;
        }
    }
    let families = |method: &str| match method {
        "linear" | "planar" => "centre-out",
        "stochastic" => "multisine",
        _ => "prbs",
    };
    match (args.method.as_str(), args.family.as_str()) {
        ("linear" | "planar", "centre-out" | "any") | ("stochastic", "multisine" | "any") => {}
        ("reflex", "prbs" | "any") => return run_reflex_design(&args, demo, cx),
        (method @ ("linear" | "stochastic" | "reflex" | "planar"), family) => {
            if !["centre-out", "multisine", "prbs", "any"].contains(&family) {
                return Err(format!(
                    "--family {family}: expected centre-out, multisine, prbs or any"
                )
                .into());
            }
            let instead = match (method, family) {
                ("stochastic", "prbs") => "; a PRBS on three axes excites every line from every axis, which one recording's MIMO estimate cannot separate: the zippered multisine gives each axis its own lines (a PRBS is designed for the reflex method)".to_string(),
                _ => ["linear", "stochastic", "reflex"]
                    .into_iter()
                    .find(|m| families(m) == family)
                    .map_or_else(String::new, |m| {
                        format!("; a {family} is designed by --method {m}")
                    }),
            };
            return Err(format!(
                "--family {family}: the {method} method's designs are {}{instead}",
                families(method)
            )
            .into())
        }
        (method, _) => {
            return Err(format!(
                "--method {method}: designs are available for the linear, stochastic, reflex and planar methods"
            )
            .into())
        }
    }
    let DesignTexts {
        prior: prior_text,
        limits: limits_text,
        baseline: baseline_text,
    } = DesignTexts::read(&args, demo)?;
    let named = |e| design_error(cx, &args, e);
    let spinner = working(
        !args.json,
        "designing: every candidate is simulated and estimated on the prior",
    );
    let inputs_read = limpid_app::design::DesignInputs {
        prior: (prior_text.as_str(), prior_path.as_path()),
        limits_from: limits_text.as_deref().zip(args.limits_from.as_deref()),
        baseline: baseline_text.as_deref().zip(args.baseline.as_deref()),
        budget_s: args.duration,
        objective: &args.objective,
        robust: &args.robust,
        runs: args.runs,
        verify: args.verify,
        seed: args.seed,
    };
    let designed = limpid_app::design::design_from_texts(&args.method, &inputs_read);
    if let Some(s) = spinner {
        s.finish_and_clear();
    }
    let (toml, result) = designed.map_err(named)?;
    // the result is read back before anything is written
    let document = limpid_analysis::result::Document::new(result).with_run(
        limpid_analysis::result::Run::of_this_process(
            &inputs.iter().map(|(p, _)| *p).collect::<Vec<_>>(),
        ),
    );
    let json = document
        .to_readable_json_pretty()
        .map_err(|e| format!("the design's result would not read back, nothing written: {e}"))?;
    let result = document.estimate;
    if let Some(out) = &args.output {
        let units = if args.method == "planar" {
            "m, rad, s, Hz, N m"
        } else {
            "m, rad, s, Hz, N"
        };
        let text = format!(
            "# limpid protocol design --method {} (objective {}, budget {} s); units: {units}\n{toml}",
            args.method, args.objective, args.duration,
        );
        limpid_core::files::write_file(out, text.as_bytes())?;
    }
    if args.json {
        println!("{json}");
        return Ok(());
    }
    match &result {
        limpid_analysis::result::Estimate::Design(r) => print_design(r),
        limpid_analysis::result::Estimate::PlanarDesign(r) => print_planar_design(r),
        other => unreachable!("a design method gave a {} result", other.kind()),
    }
    match &args.output {
        Some(out) => {
            let play = match &result {
                limpid_analysis::result::Estimate::PlanarDesign(r) => {
                    let links = r.protocol["link_lengths_m"]
                        .as_array()
                        .map(|l| {
                            l.iter()
                                .filter_map(|v| v.as_f64())
                                .map(num)
                                .collect::<Vec<_>>()
                                .join(",")
                        })
                        .unwrap_or_default();
                    format!("simulate it: limpid simulate {0} -o rec.csv; estimate it with the whole window: limpid estimate planar rec.csv --link-lengths {links}", out.display())
                }
                _ => format!(
                    "play it: limpid protocol export {} -o command.csv",
                    out.display()
                ),
            };
            println!(
                "wrote {0} (check it: limpid protocol check {0}; {play})",
                out.display()
            )
        }
        None => println!("protocol not written: add -o D.toml"),
    }
    Ok(())
}

/// Below this RMS displacement (m) a human arm's stiffness is its short-range
/// stiffness, higher than at larger motions (a note, not a limit).
const SHORT_RANGE_M: f64 = 1e-3;

fn print_design(r: &limpid_analysis::result::design::DesignResult) {
    println!(
        "designed: {}: {:.1} s of {} s, at ({}, {}, {}) m",
        r.chosen.describe(num),
        r.chosen.duration_s(),
        num(r.budget_s),
        num(r.start_m[0]),
        num(r.start_m[1]),
        num(r.start_m[2])
    );
    if let limpid_analysis::result::design::DesignChoice::Multisine(c) = &r.chosen {
        if c.rms_m < SHORT_RANGE_M {
            println!(
                "note: {} mm RMS is within a human arm's short-range stiffness (about 1 mm), which the prior's linear impedance does not hold: K there may exceed K at larger motions",
                num(c.rms_m * 1e3)
            );
        }
    }
    let on = match r.objective.robust.as_str() {
        "expected" => "the prior (the mean over its range's ends and midpoint)",
        _ => "the prior",
    };
    print_predictions(
        &[("K", "N/m"), ("B", "N s/m"), ("M", "kg")],
        (on, "at this start point"),
        &r.predicted,
        r.baseline.as_ref(),
    );
    print_margins(&r.limits);
    print_verification(r.verify.as_ref(), ["K", "B", "M"], "subjects");
    print_search(&r.search);
}

/// The predicted SEs of the three groups (`groups`: name and unit), the
/// design's and the baseline's; `on` the prior, the baseline `at` its posture.
fn print_predictions(
    groups: &[(&str, &str); 3],
    (on, at): (&str, &str),
    predicted: &limpid_analysis::result::design::Prediction,
    baseline: Option<&limpid_analysis::result::design::Prediction>,
) {
    println!(
        "predicted on {on} ({} simulated recordings each; SE: RMS element s.d., and relative to the RMS element):",
        predicted.runs
    );
    let names = groups.map(|g| g.0);
    println!(
        "  {:<9} {:>22} {:>22} {:>22} {:>9} {:>9} {:>16}",
        "",
        format!("{} SE ({})", groups[0].0, groups[0].1),
        format!("{} SE ({})", groups[1].0, groups[1].1),
        format!("{} SE ({})", groups[2].0, groups[2].1),
        format!("{} err %", names[0]),
        format!("{} err %", names[1]),
        format!("identifiable {}/{}/{} %", names[0], names[1], names[2])
    );
    let row = |label: &str, p: &limpid_analysis::result::design::Prediction| {
        let cell = |m: usize| format!("{} ({:.1} %)", num(p.pooled.se[m]), p.pooled.se_percent[m]);
        println!(
            "  {:<9} {:>22} {:>22} {:>22} {:>9.1} {:>9.1} {:>10.0}/{:.0}/{:.0}",
            label,
            cell(0),
            cell(1),
            cell(2),
            p.pooled.error_percent[0],
            p.pooled.error_percent[1],
            100.0 * p.identifiable_share[0],
            100.0 * p.identifiable_share[1],
            100.0 * p.identifiable_share[2]
        );
    };
    row("design", predicted);
    if let Some(b) = baseline {
        row("baseline", b);
        println!("  (baseline: {:.1} s {at})", b.duration_s);
    }
}

fn print_margins(limits: &[limpid_analysis::result::design::LimitMargin]) {
    println!("margins to the limits:");
    for m in limits {
        println!(
            "  {:<40} {} of {} {} ({:.1} % to spare)",
            m.quantity,
            num(m.peak),
            num(m.limit),
            m.unit,
            m.margin_percent
        );
    }
}

/// `--verify`'s line: `names` of the three groups, `who` was drawn from the prior.
fn print_verification(
    v: Option<&limpid_analysis::result::design::Verification>,
    names: [&str; 3],
    who: &str,
) {
    if let Some(v) = v {
        println!(
            "verified on {} {who} drawn from the prior: achieved SE {} {}, {} {}, {} {}; predicted/achieved {:.2}, {:.2}, {:.2}; {} within 5 % and {} within 20 % of the truth, both identifiable: {:.0} %",
            v.runs,
            names[0],
            num(v.achieved_se[0]),
            names[1],
            num(v.achieved_se[1]),
            names[2],
            num(v.achieved_se[2]),
            v.ratio[0],
            v.ratio[1],
            v.ratio[2],
            names[0],
            names[1],
            100.0 * v.within_tolerance_share
        );
    }
}

fn print_search(s: &limpid_analysis::result::design::SearchSummary) {
    println!(
        "search: {} candidates on {} recordings each ({} refused by a limit or the budget)",
        s.candidates, s.runs_per_candidate, s.refused
    );
}

/// `--method planar`'s design: quintic joint perturbations for the planar method.
fn print_planar_design(r: &limpid_analysis::result::design::PlanarDesignResult) {
    let c = &r.chosen;
    println!(
        "designed: {}: {:.1} s of {} s, at q0 = ({}, {}) rad",
        c.describe(num),
        c.duration_s,
        num(r.budget_s),
        num(r.posture_rad[0]),
        num(r.posture_rad[1])
    );
    print_predictions(
        &[("K", "N m/rad"), ("D", "N m s/rad"), ("ξ", "kg m²")],
        (
            match r.objective.robust.as_str() {
                "expected" => "the prior arm (errors against its intrinsic K and D; the mean over its range's ends and midpoint)",
                _ => "the prior arm (errors against its intrinsic K and D)",
            },
            "at this posture",
        ),
        &r.predicted,
        r.baseline.as_ref(),
    );
    print_margins(&r.limits);
    print_verification(r.verify.as_ref(), ["K", "D", "ξ"], "arms");
    print_search(&r.search);
}

/// `--method reflex`: a PRBS for the reflex gain on a prior ankle.
fn run_reflex_design(args: &DesignArgs, demo: bool, cx: &Context) -> CliResult {
    use limpid_app::design::reflex::{design_reflex, reflex_request_from_texts};
    if args.verify > 0 {
        return Err("--verify is for the linear, stochastic and planar methods: the reflex design's prediction is already the spread over --runs simulated recordings".into());
    }
    if args.robust != "worst" {
        return Err("--robust is for the linear, stochastic and planar methods: a reflex prior has no range".into());
    }
    if !matches!(
        args.objective.as_str(),
        "stiffness,damping" | "gain" | "reflex-gain"
    ) {
        return Err(format!(
            "invalid --objective {:?}: the reflex method's design minimises the reflex gain's error (--objective gain)",
            args.objective
        )
        .into());
    }
    let prior_path = PathBuf::from(&args.prior);
    let DesignTexts {
        prior: prior_text,
        limits: limits_text,
        baseline: baseline_text,
    } = DesignTexts::read(args, demo)?;
    let request = reflex_request_from_texts(
        (&prior_text, &prior_path),
        limits_text.as_deref().zip(args.limits_from.as_deref()),
        baseline_text.as_deref().zip(args.baseline.as_deref()),
        args.duration,
        args.runs,
        args.seed,
    )
    .map_err(|e| design_error(cx, args, e))?;

    let spinner = working(
        !args.json,
        "designing: every candidate PRBS is simulated and estimated on the prior ankle",
    );
    let designed = design_reflex(&request);
    if let Some(s) = spinner {
        s.finish_and_clear();
    }
    let designed = designed.map_err(|e| design_error(cx, args, e))?;
    let json = limpid_analysis::result::Document::new(
        limpid_analysis::result::Estimate::ReflexDesign(designed.result.clone()),
    )
    .with_run(limpid_analysis::result::Run::of_this_process(&[]))
    .to_readable_json_pretty()
    .map_err(|e| format!("the design's result would not read back, nothing written: {e}"))?;

    if let Some(out) = &args.output {
        let text = format!(
            "# limpid protocol design --method reflex (budget {} s); units: rad, s, Hz, N m\n{}",
            args.duration,
            Design::Periodic(designed.protocol).to_toml()
        );
        limpid_core::files::write_file(out, text.as_bytes())?;
    }
    let r = designed.result;
    if args.json {
        println!("{json}");
        return Ok(());
    }
    let c = &r.chosen;
    println!(
        "designed: PRBS {} rad, {} ms switching, order {}, {} periods with a fade-in and a fade-out period: {:.1} s of {} s",
        num(c.amplitude_rad),
        num(c.switch_interval_s * 1e3),
        c.order,
        c.periods,
        c.duration_s,
        num(args.duration)
    );
    println!(
        "predicted on the prior ankle ({} simulated recordings each): reflex gain s.d., the estimator's mean SE, mean error; intrinsic K and B s.d.",
        r.predicted.runs
    );
    let row = |label: &str, p: &limpid_analysis::result::design::ReflexPrediction| {
        println!(
            "  {label:<9} gain s.d. {} N m s/rad (information: {}), SE {}, error {:.2} %; K s.d. {} N m/rad, B s.d. {} N m s/rad ({:.1} s)",
            num(p.gain_sd),
            num(p.gain_se_information),
            num(p.gain_se_mean),
            p.gain_error_percent,
            num(p.intrinsic_sd[0]),
            num(p.intrinsic_sd[1]),
            p.duration_s
        );
    };
    row("design", &r.predicted);
    if let Some(b) = &r.baseline {
        row("baseline", b);
    }
    if let Some(ratio) = r.gain_spread_ratio {
        println!("  the design's gain spread is {ratio:.2} of the baseline's");
    }
    println!(
        "  (the s.d. is the gain's spread over recordings of this one virtual ankle, noise alone: designs are compared by it; the SE is what `estimate reflex` will report, which adds what no simulated noise shows, the model's error floors and the spread over rectifier orders, so it is the larger)"
    );
    println!("margins to the limits:");
    for m in &r.limits {
        println!(
            "  {:<32} {} of {} {} ({:.1} % to spare)",
            m.quantity,
            num(m.peak),
            num(m.limit),
            m.unit,
            m.margin_percent
        );
    }
    match &args.output {
        Some(out) => println!(
            "wrote {0} (next: limpid simulate {0} -o prbs.csv && limpid estimate reflex prbs.csv; on the rig: limpid protocol export {0} -o command.csv)",
            out.display()
        ),
        None => println!("protocol not written: add -o D.toml"),
    }
    Ok(())
}

/// A spinner with the elapsed time on standard error while a command works
/// for seconds, on a terminal only (silent when piped or with `--json`).
fn working(shown: bool, message: &'static str) -> Option<indicatif::ProgressBar> {
    if !(shown && std::io::IsTerminal::is_terminal(&std::io::stderr())) {
        return None;
    }
    let spinner = indicatif::ProgressBar::new_spinner().with_message(message);
    if let Ok(style) = indicatif::ProgressStyle::with_template("{spinner} {msg} ({elapsed})") {
        spinner.set_style(style);
    }
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    Some(spinner)
}
