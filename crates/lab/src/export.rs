//! Protocol schedules as recordings, for a robot controller to play
//! (`limpid protocol export`): centre-out end-effector paths with the joint
//! angles that track them (seeds 000, 001: orientation held, damped
//! least-squares IK), seed 003's planar joint trajectories with their waits,
//! and seed 004's commanded stochastic inputs.

use rayon::prelude::*;
use std::path::Path;

use nalgebra::Matrix3;

use crate::design::{PlanarDesign, StochasticDesign};
use crate::protocol::Protocol;
use limpid_core::{Error, Recording, Result};
use limpid_robot::Robot;

/// The robot of a centre-out protocol, placed where the protocol says.
pub fn placed_robot(name: &str, p: &Protocol) -> Result<Robot> {
    let robot = Robot::by_name(name)?;
    Ok(match p.robot_base {
        Some(b) => robot.placed(b.xyz_m, b.rpy_rad),
        None => robot,
    })
}

/// Every phase of every trial of a centre-out protocol (rest, centre-out,
/// hold, return by the same profile reversed, relax, and seed 001's rests
/// between sets): columns t, start_point, trial, x, y, z, and with a `robot`
/// its joint angles robot_q1..n, tracking the path with the orientation of
/// its home pose held. Without a robot it is the end-point command any rig or
/// simulator can play: at rest at the start point at its first and last
/// sample. `source` is the file errors name: the robot's URDF, or the
/// protocol for a built-in robot (a start point out of reach is theirs, not
/// the output's).
pub fn centre_out_schedule(
    p: &Protocol,
    robot: Option<&Robot>,
    source: &Path,
) -> Result<Recording> {
    let fail = |message: String| Error::Format {
        path: source.to_path_buf(),
        message,
    };
    let fs = p.sample_rate_hz;
    let ph = &p.phases;
    let total_s = ph.rest_s + ph.centre_out_s + ph.hold_s + ph.return_s + ph.relax_s;
    let per = (total_s * fs).round() as usize;
    let dirs = p.directions();
    let n = robot.map_or(0, Robot::dof);
    // start points in parallel (each tracks its trials in order, every trial
    // starting from the joints where the previous one ended); the time column
    // is numbered once they are joined
    let starts = p.start_points();
    let per_start: Vec<Result<Vec<Vec<f64>>>> = starts
        .par_iter()
        .enumerate()
        .map(|(si, start)| {
            let mut cols: Vec<Vec<f64>> = vec![Vec::new(); 5 + n];
            let mut push = |trial: f64, x: &nalgebra::Vector3<f64>, qk: &[f64]| {
                cols[0].push((si + 1) as f64);
                cols[1].push(trial);
                for a in 0..3 {
                    cols[2 + a].push(x[a]);
                }
                for (j, v) in qk.iter().enumerate() {
                    cols[5 + j].push(*v);
                }
            };
            let mut q = match robot {
                Some(robot) => {
                    let home = robot.home();
                    let orientation: Matrix3<f64> = robot.fk(&home).fixed_view::<3, 3>(0, 0).into();
                    let q = robot.reach(start, &orientation, &home).map_err(|e| {
                        fail(format!("{}: start point {}: {e}", robot.name, si + 1))
                    })?;
                    Some((robot, orientation, q))
                }
                None => None,
            };
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
                let joints = match &mut q {
                    Some((robot, orientation, q)) => {
                        let joints = robot.track(&positions, orientation, q).map_err(|e| {
                            fail(format!("start point {}, target {}: {e}", si + 1, ti + 1))
                        })?;
                        robot
                            .check_joint_trajectory(&joints, 1.0 / fs)
                            .map_err(|e| {
                                fail(format!(
                                    "{}: start point {}, target {}: {e}",
                                    robot.name,
                                    si + 1,
                                    ti + 1
                                ))
                            })?;
                        if let Some(last) = joints.last() {
                            *q = last.clone();
                        }
                        joints
                    }
                    None => vec![Vec::new(); positions.len()],
                };
                for (x, qk) in positions.iter().zip(&joints) {
                    push((ti + 1) as f64, x, qk.as_slice());
                }
                // seed 001: a longer rest between sets, holding the start point
                let set = p.phases.trials_per_set;
                if set > 0 && (ti + 1) % set == 0 && ti + 1 < dirs.len() {
                    for _ in 0..(p.phases.set_rest_s * fs).round() as usize {
                        let held = q.as_ref().map_or(&[][..], |(_, _, q)| q.as_slice());
                        push(0.0, start, held);
                    }
                }
            }
            Ok(cols)
        })
        .collect();
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); 6 + n];
    for part in per_start {
        for (dst, src) in cols[1..].iter_mut().zip(part?) {
            dst.extend(src);
        }
    }
    cols[0] = (0..cols[1].len()).map(|i| i as f64 / fs).collect();
    let mut names: Vec<String> = ["t", "start_point", "trial", "x", "y", "z"]
        .map(String::from)
        .to_vec();
    names.extend((1..=n).map(|i| format!("robot_q{i}")));
    Recording::new(source, names, cols, 2)
}

/// Seed 003's session: the posture held through random waits, each followed
/// by a quintic displacement held for `after_s`, then a quintic back to the
/// posture over the same interval (at the start of the next wait, unrecorded:
/// `trial` is 0 during waits and returns). Columns t, trial, q1, q2.
pub fn planar_schedule(p: &PlanarDesign, output: &Path) -> Result<Recording> {
    let fs = p.sample_rate_hz;
    let schedule = p.schedule();
    let tk = p.interpolation_s;
    // the last return is part of the session
    let end = schedule.last().map(|s| s.0 + p.after_s + tk).unwrap_or(0.0);
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
        // out over T_k from the onset, back over T_k from the window's end
        let out = crate::Profile::Quintic.eval(t - onset, tk).0;
        let back = crate::Profile::Quintic.eval(t - onset - p.after_s, tk).0;
        let s = if t >= onset - 1e-12 { out - back } else { 0.0 };
        let dq = p.displacements_rad[d];
        cols[0].push(t);
        cols[1].push(if in_trial { (next + 1) as f64 } else { 0.0 });
        cols[2].push(p.posture_rad[0] + dq[0] * s);
        cols[3].push(p.posture_rad[1] + dq[1] * s);
    }
    let names = ["t", "trial", "q1", "q2"].map(String::from).to_vec();
    Recording::new(output, names, cols, 2)
}

/// Seed 004's commanded inputs, one column per channel after t.
pub fn stochastic_schedule(p: &StochasticDesign, output: &Path) -> Result<Recording> {
    let u = p.inputs()?;
    let fs = p.sample_rate_hz;
    let mut cols = vec![(0..u[0].len()).map(|k| k as f64 / fs).collect::<Vec<f64>>()];
    cols.extend(u);
    let mut names = vec!["t".to_string()];
    names.extend(p.channels.iter().cloned());
    Recording::new(output, names, cols, 2)
}
