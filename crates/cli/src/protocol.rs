//! `limpid protocol new|check` and `limpid simulate` (virtual lab, centre-out protocols).

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use limpid_lab::protocol::{check, preset, Protocol};
use limpid_lab::{seed000_subject1, simulate_centre_out, CentreOut, NoiseModel, Posture};
use nalgebra::Matrix3;
use serde::Deserialize;

use crate::table::num;
use crate::CliResult;

#[derive(Subcommand)]
pub enum ProtocolCommand {
    /// Print a preset protocol as TOML (artemiadis-3d, patel-cocontraction).
    New {
        #[arg(long)]
        preset: String,
        /// Write to this file instead of standard output.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// End-effector poses and joint trajectories of a protocol for a robot, at the protocol's rate (CSV or Parquet).
    Export {
        protocol: PathBuf,
        /// kuka-lwr4 or puma3.
        #[arg(long)]
        robot: String,
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Check a protocol against its safety limits and report what it will excite.
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
    /// Subject (TOML with 3 x 3 `inertia`, `damping`, `stiffness`, SI); default:
    /// seed 000 Table I, subject 1, posture i at start point i.
    #[arg(long)]
    pub subject: Option<PathBuf>,
    /// Output recording (.csv or .parquet); with several start points `_S<i>` is added before the extension.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Random seed of the sensor noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SubjectFile {
    inertia: [[f64; 3]; 3],
    damping: [[f64; 3]; 3],
    stiffness: [[f64; 3]; 3],
}

fn read_protocol(path: &Path) -> CliResult<Protocol> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(Protocol::from_toml(&text, path)?)
}

pub fn run(cmd: ProtocolCommand) -> CliResult {
    match cmd {
        ProtocolCommand::New {
            preset: name,
            output,
        } => {
            let text = format!(
                "# limpid protocol (preset {name}); units: m, s, Hz, N\n{}",
                preset(&name)?.to_toml()
            );
            match output {
                Some(p) => std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))?,
                None => print!("{text}"),
            }
            Ok(())
        }
        ProtocolCommand::Export {
            protocol,
            robot,
            output,
        } => export(&protocol, &robot, &output),
        ProtocolCommand::Check { protocol, json } => {
            let p = read_protocol(&protocol)?;
            let r = check(&p).map_err(|e| format!("{}: {e}", protocol.display()))?;
            if json {
                println!("{}", serde_json::to_string_pretty(&r)?);
                return Ok(());
            }
            println!("protocol {}: within its limits", protocol.display());
            println!(
                "  {} trials of {} samples; {} target directions, minimum angular separation {:.2} deg",
                r.trials, r.samples_per_trial, p.targets.count, r.min_separation_deg
            );
            println!(
                "  peaks: displacement {} m, velocity {} m/s, acceleration {} m/s^2, expected force {} N",
                num(r.peak_displacement_m), num(r.peak_velocity_m_s), num(r.peak_acceleration_m_s2), num(r.peak_force_n)
            );
            println!(
                "  conditioning ratios C12, C13, C23 (seed 003 eq. 17): {}, {}, {}",
                num(r.conditioning_ratios[0]),
                num(r.conditioning_ratios[1]),
                num(r.conditioning_ratios[2])
            );
            Ok(())
        }
    }
}

/// Every phase of every trial (rest, centre-out, hold, return by the same
/// profile reversed, relax), tracked by the robot with the orientation of its
/// home pose held (seeds 000, 001).
fn export(path: &Path, robot: &str, output: &Path) -> CliResult {
    let p = read_protocol(path)?;
    check(&p).map_err(|e| format!("{}: {e}", path.display()))?;
    let robot = limpid_lab::robot::Robot::by_name(robot)?;
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
            .track(&[*start], &orientation, &home)
            .map_err(|e| format!("start point {}: {e}", si + 1))?
            .remove(0);
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

pub fn run_simulate(args: SimulateArgs) -> CliResult {
    let p = read_protocol(&args.protocol)?;
    check(&p).map_err(|e| format!("{}: {e}", args.protocol.display()))?;
    let given: Option<SubjectFile> = match &args.subject {
        Some(path) => {
            let text =
                std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
            Some(toml::from_str(&text).map_err(|e| {
                format!(
                    "{}: {}",
                    path.display(),
                    e.to_string().lines().next().unwrap_or("")
                )
            })?)
        }
        None => None,
    };
    let table = seed000_subject1();
    let starts = p.start_points();
    let protocol = CentreOut {
        profile: p.phases.profile,
        radius_m: p.targets.radius_m,
        directions: p.directions(),
        rest_s: p.phases.rest_s,
        motion_s: p.phases.centre_out_s,
        hold_s: if p.phases.record_hold_and_return {
            p.phases.hold_s
        } else {
            0.0
        },
        return_s: if p.phases.record_hold_and_return {
            p.phases.return_s
        } else {
            0.0
        },
        sample_rate: p.sample_rate_hz,
    };
    let noise = NoiseModel::default();
    if let Some(dir) = args.output.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    for (i, start) in starts.iter().enumerate() {
        let m3 = |a: &[[f64; 3]; 3]| Matrix3::from_fn(|r, c| a[r][c]);
        let mut posture: Posture = table[i % table.len()].clone();
        if let Some(s) = &given {
            posture.inertia = m3(&s.inertia);
            posture.damping = m3(&s.damping);
            posture.stiffness = m3(&s.stiffness);
        }
        posture.start = *start;
        posture.name = format!("S{}", i + 1);
        let rec = simulate_centre_out(
            &posture,
            &protocol,
            &noise,
            args.seed.wrapping_mul(1000) + i as u64,
        )?;
        let out = if starts.len() > 1 {
            with_suffix(&args.output, &format!("_S{}", i + 1))
        } else {
            args.output.clone()
        };
        limpid_io::write_recording(&rec, &out)?;
        let rows = |m: &Matrix3<f64>| {
            (0..3)
                .map(|r| (0..3).map(|c| m[(r, c)]).collect::<Vec<f64>>())
                .collect::<Vec<_>>()
        };
        let truth = serde_json::json!({
            "method": "cartesian",
            "sample_rate": p.sample_rate_hz,
            "inertia": rows(&posture.inertia),
            "damping": rows(&posture.damping),
            "stiffness": rows(&posture.stiffness),
            "equilibrium": [start.x, start.y, start.z],
            "profile": p.phases.profile,
            "noise": noise,
            "protocol": {"trials": protocol.directions.len(), "rest_s": protocol.rest_s, "motion_s": protocol.motion_s, "radius_m": protocol.radius_m},
            "notes": ["f = M a + B v + K (x - S) + offset_trial + drift + white; force applied to the limb", "made by limpid simulate"],
        });
        let truth_path = out.with_extension("truth.json");
        std::fs::write(&truth_path, serde_json::to_string_pretty(&truth)?)
            .map_err(|e| format!("{}: {e}", truth_path.display()))?;
        println!(
            "wrote {} ({} samples) and {}",
            out.display(),
            rec.len(),
            truth_path.display()
        );
    }
    Ok(())
}
