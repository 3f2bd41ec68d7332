//! Gravity compensation of recorded F/T sensor readings: seed 004's two steps
//! (§II-B, eq. (4)-(9): bias in the sensor frame, weight in the reference
//! frame; [`GravityCompensation`]) or limpid's payload calibration from
//! still poses ([`PayloadCalibration`]). The one path behind
//! `limpid gravity-compensate` and Python's `limpid.gravity_compensate`.
//!
//! Input columns `sensor_fx..z` (the hand's force on the sensor, sensor
//! frame) and optionally `sensor_tx..z`; output columns `fx, fy, fz` (force
//! applied to the limb, reference frame) and `taux, tauy, tauz`. The sensor's
//! orientation per sample comes from a robot's joint angles (`robot_q*`),
//! else from `theta` (rotation about y, seed 004's rig), else it is fixed.
//!
//! Torques, which the seed leaves out, get the same two steps: bias in the
//! sensor frame, the load's moment held constant in the reference frame. That
//! moment really turns with the sensor: a load of weight W whose centre of
//! mass sits a distance h along the sensor axis normal to W and to the
//! rotation axis leaves a torque of W h sin(dθ), a spurious rotational
//! stiffness W h (N m/rad). The calibration from still poses removes it.

use limpid_core::frame::GravityCompensation;
use limpid_core::{Error, PayloadCalibration, Recording, Result};
use nalgebra::{Matrix3, Vector3};

use limpid_robot::Robot;

/// Where the load and biases come from.
pub enum LoadSource<'a> {
    /// Seed 004's two steps: readings in a gravity-free pose, and the first
    /// `initial_s` seconds of the test (still, unperturbed).
    TwoSteps {
        /// Readings in a gravity-free pose.
        bias: &'a Recording,
        /// Still, unperturbed seconds at the start of the test.
        initial_s: f64,
    },
    /// Still readings in several orientations ([`PayloadCalibration`]).
    Calibration(&'a Recording),
}

/// The three sensor columns `prefix` x, y, z (forces `sensor_f`, torques `sensor_t`).
fn readings(rec: &Recording, prefix: &str) -> Result<Vec<Vector3<f64>>> {
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

/// Sensor-to-reference rotation per sample.
fn rotations(rec: &Recording, robot: Option<&Robot>) -> Result<Vec<Matrix3<f64>>> {
    if let Some(robot) = robot {
        return Ok(robot
            .poses(rec, "robot joint angles for the sensor's orientation")?
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

type Compensated = (Vec<Vector3<f64>>, Option<Vec<Vector3<f64>>>, Vec<String>);

/// Compensate `rec` in place: writes `fx, fy, fz` (and `taux, tauy, tauz`
/// when the sensor's torque columns are there). Returns what was found, in
/// lines for the user (weights, biases, residuals, warnings).
pub fn compensate(
    rec: &mut Recording,
    source: LoadSource,
    robot: Option<&Robot>,
) -> Result<Vec<String>> {
    let with_torques = ["sensor_tx", "sensor_ty", "sensor_tz"]
        .iter()
        .any(|c| rec.has(c));
    let forces = readings(rec, "sensor_f")?;
    let torques = if with_torques {
        Some(readings(rec, "sensor_t")?)
    } else {
        None
    };
    let rot = rotations(rec, robot)?;
    let (force_out, torque_out, summary) = match source {
        LoadSource::Calibration(cal) => calibrated(cal, robot, &rot, &forces, torques.as_deref())?,
        LoadSource::TwoSteps { bias, initial_s } => {
            two_steps(bias, initial_s, rec, &rot, &forces, torques.as_deref())?
        }
    };
    let mut columns = vec![(["fx", "fy", "fz"], force_out)];
    columns.extend(torque_out.map(|t| (["taux", "tauy", "tauz"], t)));
    for (names, values) in columns {
        for (a, name) in names.iter().enumerate() {
            rec.set_column(name, values.iter().map(|v| v[a]).collect())?;
        }
    }
    Ok(summary)
}

/// Seed 004's two steps, for forces and (the same way) torques.
fn two_steps(
    bias: &Recording,
    initial_s: f64,
    rec: &Recording,
    rot: &[Matrix3<f64>],
    forces: &[Vector3<f64>],
    torques: Option<&[Vector3<f64>]>,
) -> Result<Compensated> {
    let initial = (initial_s * rec.sample_rate()).round() as usize;
    if initial_s.is_nan() || initial_s <= 0.0 || initial == 0 || initial > rec.len() {
        return Err(Error::invalid(
            "initial seconds (--initial-s)",
            format!(
                "{} s must be positive and within the recording ({:.3} s)",
                initial_s,
                rec.len() as f64 / rec.sample_rate()
            ),
        ));
    }
    // step 2 uses the orientation at the start, which must be still
    let compensate = |read: &[Vector3<f64>], prefix: &str| -> Result<_> {
        let comp =
            GravityCompensation::calibrate(&readings(bias, prefix)?, &read[..initial], &rot[0])?;
        let out: Vec<Vector3<f64>> = read
            .iter()
            .zip(rot)
            .map(|(r, m)| comp.force_on_limb(r, m))
            .collect();
        Ok((out, comp))
    };
    let (force_out, f) = compensate(forces, "sensor_f")?;
    let mut summary = vec![format!(
        "two steps: sensor bias [{:.4}, {:.4}, {:.4}] N, weight term [{:.4}, {:.4}, {:.4}] N",
        f.bias_sensor[0],
        f.bias_sensor[1],
        f.bias_sensor[2],
        f.gravity_ref[0],
        f.gravity_ref[1],
        f.gravity_ref[2]
    )];
    let torque_out = match torques {
        Some(t) => {
            let (out, c) = compensate(t, "sensor_t")?;
            summary.push(format!(
                "torque bias [{:.4}, {:.4}, {:.4}] N m, weight moment [{:.4}, {:.4}, {:.4}] N m, held constant (a load off the rotation axis leaves W h sin(dtheta); a calibration from still poses removes it)",
                c.bias_sensor[0], c.bias_sensor[1], c.bias_sensor[2],
                c.gravity_ref[0], c.gravity_ref[1], c.gravity_ref[2]
            ));
            Some(out)
        }
        None => None,
    };
    Ok((force_out, torque_out, summary))
}

/// Residual (N rms) a calibration may leave whatever its weight: a sensor's
/// noise without any payload.
const CALIBRATION_NOISE_N: f64 = 0.5;

/// Weight, centre of mass and biases fitted from still poses
/// ([`PayloadCalibration`]); refused when the weight explains less than it
/// leaves (residual above the weight and above [`CALIBRATION_NOISE_N`]).
fn calibrated(
    cal: &Recording,
    robot: Option<&Robot>,
    rot: &[Matrix3<f64>],
    forces: &[Vector3<f64>],
    torques: Option<&[Vector3<f64>]>,
) -> Result<Compensated> {
    let cal_rot = rotations(cal, robot)?;
    let cal_torques = match torques {
        Some(_) => Some(readings(cal, "sensor_t")?),
        None => None,
    };
    let c = PayloadCalibration::fit(
        &cal_rot,
        &readings(cal, "sensor_f")?,
        cal_torques.as_deref(),
    )
    .map_err(|e| Error::Format {
        path: cal.path().to_path_buf(),
        message: e.to_string(),
    })?;
    let weight = Vector3::from(c.weight_ref).norm();
    if c.force_rms_residual > weight.max(CALIBRATION_NOISE_N) {
        // pure noise fitted a 2.7 N weight beside a 50 N residual and was used (issue 36)
        return Err(Error::Format {
            path: cal.path().to_path_buf(),
            message: format!(
                "the still poses do not show a weight: the fitted weight ({weight:.3} N) is smaller than what it leaves unexplained ({:.3} N rms); check that the readings are still and from the same sensor",
                c.force_rms_residual
            ),
        });
    }
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
    let mut summary = vec![format!(
        "calibration ({} still readings): weight {:.4} N ({:.4} kg at 9.81 m/s^2), force bias [{:.4}, {:.4}, {:.4}] N, force residual {:.3e} N rms",
        c.samples,
        w.norm(),
        w.norm() / 9.81,
        c.force_bias[0], c.force_bias[1], c.force_bias[2],
        c.force_rms_residual
    )];
    if let (Some(p), Some(b), Some(res)) = (c.centre_of_mass, c.torque_bias, c.torque_rms_residual)
    {
        summary.push(format!(
            "centre of mass [{:.4}, {:.4}, {:.4}] m (sensor frame), torque bias [{:.4}, {:.4}, {:.4}] N m, torque residual {res:.3e} N m rms",
            p[0], p[1], p[2], b[0], b[1], b[2]
        ));
    }
    for u in &c.unidentified {
        summary.push(format!("warning: not separated by the poses: {u}"));
    }
    Ok((force_out, torque_out, summary))
}
