//! `limpid gravity-compensate`: the command line of `limpid_lab::gravity`
//! (seed 004 §II-B, eq. (4)-(9), and limpid's payload calibration from still
//! poses). Reads the recordings, places the robot, writes the result.

use std::path::PathBuf;

use clap::Args;
use limpid_lab::gravity::{compensate, LoadSource};

use crate::context::{CliResult, Context};

#[derive(Args)]
#[command(group(clap::ArgGroup::new("load").required(true).args(["bias", "calibration"])))]
pub struct GravityArgs {
    /// The test recording with `sensor_fx`, `sensor_fy`, `sensor_fz` (and `sensor_tx`, `sensor_ty`, `sensor_tz`).
    pub recording: PathBuf,
    /// Park & Chang (2011)'s two steps. Step 1: readings in a pose where gravity does not
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
    /// centre of mass and the biases are fitted (a limpid extension; see docs/src/reference/protocol.md).
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
pub fn run(args: GravityArgs, cx: &Context) -> CliResult {
    let mut inputs = vec![(args.recording.as_path(), "the recording")];
    inputs.extend(
        args.bias
            .as_deref()
            .map(|p| (p, "the bias recording (--bias)")),
    );
    inputs.extend(
        args.calibration
            .as_deref()
            .map(|p| (p, "the calibration (--calibration)")),
    );
    cx.refuse_overwriting_inputs(&[(&args.output, "the output (-o)")], &inputs)?;
    let mut rec = cx.read_recording(&args.recording)?;
    let robot = args.robot.robot()?;
    let summary = match (&args.calibration, &args.bias) {
        (Some(path), _) => {
            let cal = cx.read_supporting_recording(path)?;
            compensate(&mut rec, LoadSource::Calibration(&cal), robot.as_ref())?
        }
        (None, Some(path)) => {
            let bias = cx.read_supporting_recording(path)?;
            let source = LoadSource::TwoSteps {
                bias: &bias,
                initial_s: args.initial_s,
            };
            compensate(&mut rec, source, robot.as_ref())?
        }
        (None, None) => return Err("give --bias (two steps) or --calibration".into()),
    };
    limpid_io::write_recording(&rec, &args.output)?;
    let torques = rec.has("tauy");
    println!(
        "wrote {}: fx, fy, fz{} = force{} on the limb in the reference frame",
        args.output.display(),
        if torques { ", taux, tauy, tauz" } else { "" },
        if torques { " and torque" } else { "" }
    );
    for line in summary {
        println!("{line}");
    }
    Ok(())
}

/// `--robot` and `--robot-base`: a robot whose `robot_q1..n` columns give the
/// sensor's orientation by forward kinematics.
#[derive(Args)]
pub struct RobotArgs {
    /// Compute the sensor's orientation from the robot_q1..n columns by this robot's forward kinematics (kuka-lwr4, puma3 or a .urdf file).
    #[arg(long, value_name = "ROBOT")]
    pub robot: Option<String>,
    /// Where the robot's base sits in the lab frame: X,Y,Z (m) or X,Y,Z,ROLL,PITCH,YAW (rad), as a protocol's `robot_base`.
    #[arg(
        long,
        value_name = "POSE",
        value_delimiter = ',',
        requires = "robot",
        allow_hyphen_values = true
    )]
    pub robot_base: Option<Vec<f64>>,
}

impl RobotArgs {
    /// The robot, placed as `--robot-base` says, if `--robot` is given.
    pub fn robot(&self) -> CliResult<Option<limpid_robot::Robot>> {
        let Some(name) = &self.robot else {
            return Ok(None);
        };
        Ok(Some(limpid_app::estimate::placed_robot(
            name,
            self.robot_base.as_deref(),
        )?))
    }
}
