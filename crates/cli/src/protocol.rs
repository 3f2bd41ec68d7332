//! `limpid protocol new|check` and `limpid simulate` (virtual lab, centre-out protocols).

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use limpid_lab::design::{check, Design, DesignReport, PlanarDesign, StochasticDesign};
use limpid_lab::planar::simulate_planar;
use limpid_lab::protocol::Protocol;
use limpid_lab::robot::Robot;
use limpid_lab::session::{simulate_design, RigController, SubjectText};
use limpid_lab::{seed000_subject1, simulate_centre_out, NoiseModel};
use nalgebra::Matrix3;

use crate::table::num;
use crate::CliResult;

#[derive(Subcommand)]
pub enum ProtocolCommand {
    /// Print a preset protocol as TOML: artemiadis-3d, patel-cocontraction (centre-out), lakatos-planar (planar), park-stochastic (stochastic).
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
    /// optionally a `[noise]` table; default seed 000 Table I subject 1, posture i at
    /// start point i. Planar: `xi` (3), 2 x 2 `stiffness`, `damping`, `tau0` (2),
    /// optional `[reflex]` (latency_s, stiffness_gain, damping_gain); default the
    /// seed 003 subject. Stochastic: a spring set `springs` (8 values, N/m, k1a..k4b);
    /// default set SA3 of ../shared/examples.
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
    /// IMBIC (seed 004 eq. 11-14); `pd`: the same robot under a plain PD law.
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

/// The robot of a centre-out protocol, placed as the protocol says.
fn placed_robot(name: &str, p: &Protocol) -> CliResult<Robot> {
    let robot = Robot::by_name(name)?;
    Ok(match p.robot_base {
        Some(b) => robot.placed(b.xyz_m, b.rpy_rad),
        None => robot,
    })
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
        } => match (read_design(&protocol)?.0, robot) {
            (Design::CentreOut(p), Some(robot)) => export(&p, &robot, &output),
            (Design::CentreOut(_), None) => {
                Err("a centre-out protocol is exported for a robot: add --robot kuka-lwr4|puma3|FILE.urdf".into())
            }
            (Design::Planar(p), _) => export_planar(&p, &output),
            (Design::Stochastic(p), _) => export_stochastic(&p, &output),
        },
        ProtocolCommand::Check { protocol, json } => {
            let (d, report) = read_design(&protocol)?;
            let predicted = predicted_condition(&d)?;
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
        _ => {}
    }
}

fn print_ratios(c: &[f64; 3]) {
    println!(
        "  conditioning ratios C12, C13, C23 (seed 003 eq. 17): {}, {}, {}",
        num(c[0]),
        num(c[1]),
        num(c[2])
    );
}

/// The condition number the estimator meets when the protocol is run on a
/// nominal subject without noise: the scaled 27-parameter regressor of seed 000
/// on the first start point (seed 000 Table I posture 1), or the planar
/// regressor W of seed 003 eq. (19) with unit-RMS columns on the seed 003
/// subject. None for stochastic protocols (their conditioning is the input
/// coherence, reported above).
fn predicted_condition(d: &Design) -> CliResult<Option<f64>> {
    match d {
        Design::CentreOut(p) => {
            let mut posture = seed000_subject1().remove(0);
            posture.start = p.start_points()[0];
            let rec = simulate_centre_out(&posture, &p.centre_out(), &NoiseModel::none(), 1)?;
            let prepared = limpid_ident::prepare(&rec, &limpid_ident::PrepareParams::default())?;
            let est = limpid_ident::fit_linear(&prepared, &limpid_ident::LinearParams::default())?;
            Ok(Some(est.condition_number))
        }
        Design::Planar(p) => {
            let subject = p.nominal_subject();
            let rec = simulate_planar(&subject, &p.simulation(), 0.0, 0.0, p.seed)?;
            let data = limpid_ident::planar::prepare_planar(&rec, &planar_prepare(p))?;
            let all: Vec<usize> = (0..data.trials.len()).collect();
            let est = limpid_ident::planar::fit_planar(&data, usize::MAX, Some(subject.xi), &all)?;
            Ok(Some(est.criteria.condition_number_scaled))
        }
        Design::Stochastic(_) => Ok(None),
    }
}

fn planar_prepare(p: &PlanarDesign) -> limpid_ident::planar::PlanarPrepare {
    limpid_ident::planar::PlanarPrepare {
        arm: limpid_ident::planar::Arm {
            l1: p.link_lengths_m[0],
            l2: p.link_lengths_m[1],
            shoulder: [0.0, 0.0],
        },
        cutoff_hz: None,
        order: 4,
        elbow_positive: true,
    }
}

/// Every phase of every trial (rest, centre-out, hold, return by the same
/// profile reversed, relax), tracked by the robot with the orientation of its
/// home pose held (seeds 000, 001).
fn export(p: &Protocol, robot: &str, output: &Path) -> CliResult {
    let robot = placed_robot(robot, p)?;
    let home = robot.home();
    let orientation: Matrix3<f64> = robot.fk(&home).fixed_view::<3, 3>(0, 0).into();
    let fs = p.sample_rate_hz;
    let ph = &p.phases;
    let total_s = ph.rest_s + ph.centre_out_s + ph.hold_s + ph.return_s + ph.relax_s;
    let per = (total_s * fs).round() as usize;
    let dirs = p.directions();
    let n = robot.dof();
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); 6 + n];
    let mut sample = 0usize;
    for (si, start) in p.start_points().iter().enumerate() {
        let mut q = robot
            .reach(start, &orientation, &home)
            .map_err(|e| format!("{}: start point {}: {e}", robot.name, si + 1))?;
        for (ti, dir) in dirs.iter().enumerate() {
            let positions: Vec<nalgebra::Vector3<f64>> = (0..per)
                .map(|i| {
                    let t = i as f64 / fs - ph.rest_s;
                    let out = ph.profile.eval(t, ph.centre_out_s).0;
                    let back = ph
                        .profile
                        .eval(t - ph.centre_out_s - ph.hold_s, ph.return_s)
                        .0;
                    start + dir * (p.targets.radius_m * (out - back))
                })
                .collect();
            let joints = robot
                .track(&positions, &orientation, &q)
                .map_err(|e| format!("start point {}, target {}: {e}", si + 1, ti + 1))?;
            robot
                .check_joint_trajectory(&joints, 1.0 / fs)
                .map_err(|e| {
                    format!(
                        "{}: start point {}, target {}: {e}",
                        robot.name,
                        si + 1,
                        ti + 1
                    )
                })?;
            for (x, qk) in positions.iter().zip(&joints) {
                cols[0].push(sample as f64 / fs);
                cols[1].push((si + 1) as f64);
                cols[2].push((ti + 1) as f64);
                for a in 0..3 {
                    cols[3 + a].push(x[a]);
                }
                for (j, v) in qk.iter().enumerate() {
                    cols[6 + j].push(*v);
                }
                sample += 1;
            }
            q = joints.last().cloned().unwrap_or(q);
            // seed 001: a longer rest between sets, holding the start point
            let set = p.phases.trials_per_set;
            if set > 0 && (ti + 1) % set == 0 && ti + 1 < dirs.len() {
                for _ in 0..(p.phases.set_rest_s * fs).round() as usize {
                    cols[0].push(sample as f64 / fs);
                    cols[1].push((si + 1) as f64);
                    cols[2].push(0.0);
                    for a in 0..3 {
                        cols[3 + a].push(start[a]);
                    }
                    for (j, v) in q.iter().enumerate() {
                        cols[6 + j].push(*v);
                    }
                    sample += 1;
                }
            }
        }
    }
    let mut names: Vec<String> = ["t", "start_point", "trial", "x", "y", "z"]
        .map(String::from)
        .to_vec();
    names.extend((1..=n).map(|i| format!("robot_q{i}")));
    let rec = limpid_core::Recording::new(output, names, cols, 2)?;
    limpid_io::write_recording(&rec, output)?;
    println!(
        "wrote {}: {} samples of end-effector positions and {} joint angles ({})",
        output.display(),
        rec.len(),
        n,
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

/// Seed 003's session: the posture held through random waits, each followed by
/// a quintic displacement held for `after_s`; `trial` is 0 during waits.
fn export_planar(p: &PlanarDesign, output: &Path) -> CliResult {
    let fs = p.sample_rate_hz;
    let schedule = p.schedule();
    let end = schedule.last().map(|s| s.0 + p.after_s).unwrap_or(0.0);
    let n = (end * fs).round() as usize + 1;
    let mut cols: Vec<Vec<f64>> = (0..4).map(|_| Vec::with_capacity(n)).collect();
    let mut next = 0;
    for k in 0..n {
        let t = k as f64 / fs;
        while next + 1 < schedule.len() && t >= schedule[next + 1].0 - 1e-12 {
            next += 1;
        }
        let (onset, d) = schedule[next];
        let in_trial = t >= onset - 1e-12 && t < onset + p.after_s;
        let s = if t >= onset - 1e-12 {
            limpid_lab::Profile::Quintic
                .eval(t - onset, p.interpolation_s)
                .0
        } else {
            0.0
        };
        let s = if in_trial { s } else { 0.0 };
        let dq = p.displacements_rad[d];
        cols[0].push(t);
        cols[1].push(if in_trial { (next + 1) as f64 } else { 0.0 });
        cols[2].push(p.posture_rad[0] + dq[0] * s);
        cols[3].push(p.posture_rad[1] + dq[1] * s);
    }
    let names = ["t", "trial", "q1", "q2"].map(String::from).to_vec();
    let rec = limpid_core::Recording::new(output, names, cols, 2)?;
    limpid_io::write_recording(&rec, output)?;
    println!(
        "wrote {}: {} samples ({:.1} s) of joint angles for {} perturbations",
        output.display(),
        rec.len(),
        end,
        schedule.len()
    );
    Ok(())
}

/// Seed 004's commanded inputs, one column per channel.
fn export_stochastic(p: &StochasticDesign, output: &Path) -> CliResult {
    let u = p.inputs()?;
    let fs = p.sample_rate_hz;
    let mut cols = vec![(0..u[0].len()).map(|k| k as f64 / fs).collect::<Vec<f64>>()];
    cols.extend(u);
    let mut names = vec!["t".to_string()];
    names.extend(p.channels.iter().cloned());
    let rec = limpid_core::Recording::new(output, names, cols, 2)?;
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
fn write_truth(recording: &Path, samples: usize, truth: &serde_json::Value) -> CliResult {
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
    if let Some(dir) = args.output.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
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
