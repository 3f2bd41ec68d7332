//! `limpid protocol new|check` and `limpid simulate` (virtual lab, centre-out protocols).

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use limpid_lab::design::{check, Design, DesignReport, PlanarDesign, StochasticDesign};
use limpid_lab::export::placed_robot;
use limpid_lab::protocol::Protocol;
use limpid_lab::session::{simulate_design, RigController, SubjectText};

use crate::context::CliResult;
use crate::table::num;

#[derive(Subcommand)]
pub enum ProtocolCommand {
    /// Print a preset protocol as TOML: artemiadis-3d, patel-cocontraction (centre-out), lakatos-planar (planar), park-stochastic (stochastic), ensemble (ensemble), ankle-ramp-and-hold (ramp-and-hold).
    New {
        #[arg(long)]
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
        /// Centre-out only: kuka-lwr4, puma3 or a .urdf file.
        #[arg(long)]
        robot: Option<String>,
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Check a protocol against its safety limits and report what it will excite,
    /// with the condition number the estimator will meet on a nominal subject.
    Check {
        protocol: PathBuf,
        #[arg(long)]
        json: bool,
    },
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

pub fn run(cmd: ProtocolCommand) -> CliResult {
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
                Some(p) => limpid_core::files::write_file(&p, text.as_bytes())?,
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
            (Design::CentreOut(_), None) => {
                Err("a centre-out protocol is exported for a robot: add --robot kuka-lwr4|puma3|FILE.urdf".into())
            }
            (Design::Planar(p), _) => export_planar(&p, &output),
            (Design::Periodic(p), None) => export_periodic(&p, &output),
            (Design::Periodic(_), Some(_)) => Err(
                "a multisine or PRBS is exported in its own coordinates (t, the channels, period): leave out --robot".into(),
            ),
            (Design::Stochastic(p), _) => export_stochastic(&p, &output),
            (Design::Ensemble(_) | Design::RampAndHold(_), _) => Err(
                "ensemble and ramp-and-hold protocols are for `limpid simulate`; exporting them to a robot is not supported yet".into(),
            ),
            }
        }
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
    let rec = limpid_lab::export::centre_out_schedule(p, &robot, source)?;
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
    let end = schedule.last().map(|s| s.0 + p.after_s).unwrap_or(0.0);
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
    limpid_core::files::refuse_overwriting_inputs(&[(&args.output, "the output (-o)")], &inputs)?;
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
    for run in runs {
        let out = match &run.label {
            Some(label) => with_suffix(&args.output, &format!("_{label}")),
            None => args.output.clone(),
        };
        limpid_io::write_recording(&run.recording, &out)?;
        write_truth(&out, run.recording.len(), &run.truth)?;
    }
    Ok(())
}
