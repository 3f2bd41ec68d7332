//! `limpid gravity-compensate`: seed 004 §II-B, eq. (4)-(9). The F/T sensor's
//! readings (`sensor_fx`, `sensor_fy`, `sensor_fz`: the force of the hand on
//! the sensor, in the sensor frame) become the force applied to the limb in
//! the reference frame (`fx`, `fy`, `fz`, FORMAT.md): the intrinsic bias comes
//! from a recording in a pose where gravity does not load the sensor (step 1),
//! the weight of handle and limb from the first seconds of the test (step 2).
//! The sensor's orientation per sample comes from the robot's joint angles
//! (`--robot`, placed by `--robot-base`), else from `theta` (rotation about y,
//! seed 004's rig), else it is fixed.
//!
//! Torques (`sensor_tx..tz` → `taux`, `tauy`, `tauz`), which the seed leaves
//! out, get the same two steps: bias in the sensor frame, the load's moment
//! held constant in the reference frame. That moment really turns with the
//! sensor: a load of weight W whose centre of mass sits a distance h along
//! the sensor axis normal to W and to the rotation axis leaves a torque of
//! about W h dθ, i.e. a spurious rotational stiffness W h (N m/rad).

use std::path::PathBuf;

use clap::Args;
use limpid_core::frame::GravityCompensation;
use limpid_core::{Error, Recording};
use nalgebra::{Matrix3, Vector3};

use crate::estimate::RobotArgs;
use crate::CliResult;

#[derive(Args)]
pub struct GravityArgs {
    /// The test recording with `sensor_fx`, `sensor_fy`, `sensor_fz`.
    pub recording: PathBuf,
    /// Step 1: readings in a pose where gravity does not load the sensor axes.
    #[arg(long)]
    pub bias: PathBuf,
    /// Step 2: the first seconds of the test, before any perturbation.
    #[arg(long, default_value_t = 1.0)]
    pub initial_s: f64,
    /// Sensor orientation from the robot_q columns by forward kinematics.
    #[command(flatten)]
    pub robot: RobotArgs,
    /// Output recording with fx, fy, fz written (CSV or Parquet).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// The three sensor columns `prefix` x, y, z (forces `sensor_f`, torques `sensor_t`).
fn readings(rec: &Recording, prefix: &str) -> CliResult<Vec<Vector3<f64>>> {
    let why = "F/T sensor readings for gravity compensation";
    let c = [
        rec.require(&format!("{prefix}x"), why)?,
        rec.require(&format!("{prefix}y"), why)?,
        rec.require(&format!("{prefix}z"), why)?,
    ];
    Ok((0..rec.len())
        .map(|k| Vector3::new(c[0][k], c[1][k], c[2][k]))
        .collect())
}

fn rotations(rec: &Recording, robot: &RobotArgs) -> CliResult<Vec<Matrix3<f64>>> {
    if let Some(poses) = robot.poses(rec)? {
        return Ok(poses
            .iter()
            .map(|t| t.fixed_view::<3, 3>(0, 0).into())
            .collect());
    }
    Ok(match rec.column("theta") {
        Some(theta) => theta
            .iter()
            .map(|a| {
                let (s, c) = a.sin_cos();
                Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
            })
            .collect(),
        None => vec![Matrix3::identity(); rec.len()],
    })
}

pub fn run(args: GravityArgs) -> CliResult {
    let mut rec = limpid_io::read_recording(&args.recording)?;
    let bias = limpid_io::read_recording(&args.bias)?;
    // forces, and torques when the sensor's torque columns are there
    let mut channels = vec![(
        readings(&rec, "sensor_f")?,
        readings(&bias, "sensor_f")?,
        ["fx", "fy", "fz"],
    )];
    if ["sensor_tx", "sensor_ty", "sensor_tz"]
        .iter()
        .any(|c| rec.has(c))
    {
        channels.push((
            readings(&rec, "sensor_t")?,
            readings(&bias, "sensor_t")?,
            ["taux", "tauy", "tauz"],
        ));
    }
    let initial = (args.initial_s * rec.sample_rate()).round() as usize;
    if args.initial_s.is_nan() || args.initial_s <= 0.0 || initial == 0 || initial > rec.len() {
        return Err(Error::invalid(
            "--initial-s",
            format!(
                "{} s must be positive and within the recording ({:.3} s)",
                args.initial_s,
                rec.len() as f64 / rec.sample_rate()
            ),
        )
        .into());
    }
    let rot = rotations(&rec, &args.robot)?;
    // the same two steps for forces and torques; step 2 uses the orientation
    // at the start, which must be still
    let mut calibrations = Vec::new();
    for (read, bias_read, names) in channels {
        let comp = GravityCompensation::calibrate(&bias_read, &read[..initial], &rot[0])?;
        let mut out: Vec<Vec<f64>> = (0..3).map(|_| Vec::with_capacity(rec.len())).collect();
        for (r, m) in read.iter().zip(&rot) {
            let f = comp.force_on_limb(r, m);
            for a in 0..3 {
                out[a].push(f[a]);
            }
        }
        for (name, col) in names.iter().zip(out) {
            rec.set_column(name, col)?;
        }
        calibrations.push(comp);
    }
    limpid_io::write_recording(&rec, &args.output)?;
    let comp = &calibrations[0];
    println!(
        "wrote {}: fx, fy, fz = force on the limb in the reference frame; sensor bias [{:.4}, {:.4}, {:.4}] N, weight term [{:.4}, {:.4}, {:.4}] N",
        args.output.display(),
        comp.bias_sensor[0], comp.bias_sensor[1], comp.bias_sensor[2],
        comp.gravity_ref[0], comp.gravity_ref[1], comp.gravity_ref[2]
    );
    if let Some(t) = calibrations.get(1) {
        println!(
            "taux, tauy, tauz = torque on the limb in the reference frame; sensor bias [{:.4}, {:.4}, {:.4}] N m, weight moment [{:.4}, {:.4}, {:.4}] N m (held constant: see the README)",
            t.bias_sensor[0], t.bias_sensor[1], t.bias_sensor[2],
            t.gravity_ref[0], t.gravity_ref[1], t.gravity_ref[2]
        );
    }
    Ok(())
}
