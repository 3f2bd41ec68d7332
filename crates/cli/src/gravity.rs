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
use limpid_core::PayloadCalibration;
use limpid_core::{Error, Recording};
use nalgebra::{Matrix3, Vector3};

use crate::estimate::RobotArgs;
use crate::CliResult;

#[derive(Args)]
#[command(group(clap::ArgGroup::new("load").required(true).args(["bias", "calibration"])))]
pub struct GravityArgs {
    /// The test recording with `sensor_fx`, `sensor_fy`, `sensor_fz` (and `sensor_tx`, `sensor_ty`, `sensor_tz`).
    pub recording: PathBuf,
    /// Seed 004's two steps. Step 1: readings in a pose where gravity does not
    /// load the sensor axes.
    #[arg(
        long,
        required_unless_present = "calibration",
        conflicts_with = "calibration"
    )]
    pub bias: Option<PathBuf>,
    /// Step 2: the first seconds of the test, before any perturbation.
    #[arg(long, default_value_t = 1.0)]
    pub initial_s: f64,
    /// Instead of the two steps: still readings in several orientations (the
    /// same sensor and orientation columns), from which the weight, the load's
    /// centre of mass and the biases are fitted (a limpid extension; see the README).
    #[arg(long, value_name = "RECORDING")]
    pub calibration: Option<PathBuf>,
    /// Sensor orientation from the robot_q columns by forward kinematics.
    #[command(flatten)]
    pub robot: RobotArgs,
    /// Output recording with fx, fy, fz (and taux, tauy, tauz) written (CSV or Parquet).
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
    let with_torques = ["sensor_tx", "sensor_ty", "sensor_tz"]
        .iter()
        .any(|c| rec.has(c));
    let forces = readings(&rec, "sensor_f")?;
    let torques = if with_torques {
        Some(readings(&rec, "sensor_t")?)
    } else {
        None
    };
    let rot = rotations(&rec, &args.robot)?;
    let (force_out, torque_out, summary) = match (&args.calibration, &args.bias) {
        (Some(path), _) => calibrated(path, &args.robot, &rot, &forces, torques.as_deref())?,
        (None, Some(path)) => two_steps(path, &args, &rec, &rot, &forces, torques.as_deref())?,
        (None, None) => return Err("give --bias (two steps) or --calibration".into()),
    };
    let mut columns = vec![(["fx", "fy", "fz"], force_out)];
    columns.extend(torque_out.map(|t| (["taux", "tauy", "tauz"], t)));
    for (names, values) in columns {
        for (a, name) in names.iter().enumerate() {
            rec.set_column(name, values.iter().map(|v| v[a]).collect())?;
        }
    }
    limpid_io::write_recording(&rec, &args.output)?;
    println!(
        "wrote {}: fx, fy, fz{} = force{} on the limb in the reference frame",
        args.output.display(),
        if with_torques {
            ", taux, tauy, tauz"
        } else {
            ""
        },
        if with_torques { " and torque" } else { "" }
    );
    print!("{summary}");
    Ok(())
}

type Compensated = (Vec<Vector3<f64>>, Option<Vec<Vector3<f64>>>, String);

/// Seed 004's two steps, for forces and (the same way) torques.
fn two_steps(
    bias_path: &std::path::Path,
    args: &GravityArgs,
    rec: &Recording,
    rot: &[Matrix3<f64>],
    forces: &[Vector3<f64>],
    torques: Option<&[Vector3<f64>]>,
) -> CliResult<Compensated> {
    let bias = limpid_io::read_recording(bias_path)?;
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
    // step 2 uses the orientation at the start, which must be still
    let compensate = |read: &[Vector3<f64>], prefix: &str| -> CliResult<_> {
        let comp =
            GravityCompensation::calibrate(&readings(&bias, prefix)?, &read[..initial], &rot[0])?;
        let out: Vec<Vector3<f64>> = read
            .iter()
            .zip(rot)
            .map(|(r, m)| comp.force_on_limb(r, m))
            .collect();
        Ok((out, comp))
    };
    let (force_out, f) = compensate(forces, "sensor_f")?;
    let mut summary = format!(
        "two steps: sensor bias [{:.4}, {:.4}, {:.4}] N, weight term [{:.4}, {:.4}, {:.4}] N\n",
        f.bias_sensor[0],
        f.bias_sensor[1],
        f.bias_sensor[2],
        f.gravity_ref[0],
        f.gravity_ref[1],
        f.gravity_ref[2]
    );
    let torque_out = match torques {
        Some(t) => {
            let (out, c) = compensate(t, "sensor_t")?;
            summary.push_str(&format!(
                "torque bias [{:.4}, {:.4}, {:.4}] N m, weight moment [{:.4}, {:.4}, {:.4}] N m, held constant (a load off the rotation axis leaves W h sin(dtheta); --calibration removes it)\n",
                c.bias_sensor[0], c.bias_sensor[1], c.bias_sensor[2],
                c.gravity_ref[0], c.gravity_ref[1], c.gravity_ref[2]
            ));
            Some(out)
        }
        None => None,
    };
    Ok((force_out, torque_out, summary))
}

/// Weight, centre of mass and biases fitted from still poses ([`PayloadCalibration`]).
fn calibrated(
    path: &std::path::Path,
    robot: &RobotArgs,
    rot: &[Matrix3<f64>],
    forces: &[Vector3<f64>],
    torques: Option<&[Vector3<f64>]>,
) -> CliResult<Compensated> {
    let cal = limpid_io::read_recording(path)?;
    let cal_rot = rotations(&cal, robot)?;
    let cal_torques = match torques {
        Some(_) => Some(readings(&cal, "sensor_t")?),
        None => None,
    };
    let c = PayloadCalibration::fit(
        &cal_rot,
        &readings(&cal, "sensor_f")?,
        cal_torques.as_deref(),
    )
    .map_err(|e| format!("{}: {e}", path.display()))?;
    let force_out = forces
        .iter()
        .zip(rot)
        .map(|(r, m)| c.force_on_limb(r, m))
        .collect();
    let torque_out = torques.map(|t| {
        t.iter()
            .zip(rot)
            .map(|(r, m)| c.torque_on_limb(r, m).unwrap_or_default())
            .collect()
    });
    let w = Vector3::from(c.weight_ref);
    let mut summary = format!(
        "calibration ({} still readings): weight {:.4} N ({:.4} kg at 9.81 m/s^2), force bias [{:.4}, {:.4}, {:.4}] N, force residual {:.3e} N rms\n",
        c.samples,
        w.norm(),
        w.norm() / 9.81,
        c.force_bias[0], c.force_bias[1], c.force_bias[2],
        c.force_rms_residual
    );
    if let (Some(p), Some(b), Some(res)) = (c.centre_of_mass, c.torque_bias, c.torque_rms_residual)
    {
        summary.push_str(&format!(
            "centre of mass [{:.4}, {:.4}, {:.4}] m (sensor frame), torque bias [{:.4}, {:.4}, {:.4}] N m, torque residual {res:.3e} N m rms\n",
            p[0], p[1], p[2], b[0], b[1], b[2]
        ));
    }
    for u in &c.unidentified {
        summary.push_str(&format!("warning: not separated by the poses: {u}\n"));
    }
    Ok((force_out, torque_out, summary))
}
