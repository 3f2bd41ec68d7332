//! Frame changes of positions and forces (seed 000 eq. (1); seed 001 "Data
//! Processing": homogeneous transform robot base -> human-centred frame).
//!
//! A transform maps coordinates in the recording's frame to the frame in
//! which impedance is reported: p' = R p + t for positions, f' = R f for
//! forces. Impedance matrices transform as Z' = R Z R^T.

use nalgebra::{Matrix3, Vector3};

use crate::error::{Error, Result};
use crate::recording::Recording;

/// A rigid (homogeneous) transform: rotation `rotation` and translation `translation` (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameTransform {
    /// Rotation (det +1).
    pub rotation: Matrix3<f64>,
    /// Translation (m).
    pub translation: Vector3<f64>,
}

impl FrameTransform {
    /// No change.
    pub fn identity() -> Self {
        FrameTransform {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
        }
    }

    /// Seed 000 eq. (1): robot axes [X_R Y_R Z_R] = [-Y_H Z_H -X_H].
    ///
    /// Coordinates measured along the robot axes map to the human frame as
    /// x_H = -z_R, y_H = -x_R, z_H = y_R.
    pub fn seed000_robot_to_human() -> Self {
        FrameTransform {
            rotation: Matrix3::new(0.0, 0.0, -1.0, -1.0, 0.0, 0.0, 0.0, 1.0, 0.0),
            translation: Vector3::zeros(),
        }
    }

    /// A general transform from 12 numbers: the rotation row by row, then the translation.
    /// The rotation must be orthonormal with determinant +1 (to 1e-6).
    pub fn from_values(v: &[f64]) -> Result<Self> {
        if v.len() != 12 {
            return Err(Error::invalid(
                "transform",
                format!(
                    "expected 12 numbers (r11..r33, tx, ty, tz), found {}",
                    v.len()
                ),
            ));
        }
        // NaN would pass the orthonormality test below (NaN > tol is false)
        if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(Error::invalid(
                "transform",
                format!("expected finite numbers, found {x} as number {}", i + 1),
            ));
        }
        if let Some(t) = v[9..].iter().find(|t| t.abs() > 1e3) {
            return Err(Error::invalid(
                "transform",
                format!("a translation of {t} m is not a lab's frame (at most 1000 m)"),
            ));
        }
        let rotation = Matrix3::from_row_slice(&v[..9]);
        let err = (rotation * rotation.transpose() - Matrix3::identity()).norm();
        if err > 1e-6 || (rotation.determinant() - 1.0).abs() > 1e-6 {
            return Err(Error::invalid(
                "transform",
                "the rotation part must be orthonormal with determinant +1",
            ));
        }
        Ok(FrameTransform {
            rotation,
            translation: Vector3::new(v[9], v[10], v[11]),
        })
    }

    /// Apply to the `x,y,z` and `fx,fy,fz` columns of a recording (both must be present).
    pub fn apply(&self, rec: &mut Recording) -> Result<()> {
        for (names, translate) in [(["x", "y", "z"], true), (["fx", "fy", "fz"], false)] {
            let cols: Vec<Vec<f64>> = names
                .iter()
                .map(|n| rec.require(n, "a 3-D frame change").map(<[f64]>::to_vec))
                .collect::<Result<_>>()?;
            let mut out = vec![vec![0.0; rec.len()]; 3];
            for i in 0..rec.len() {
                let p = self.rotation * Vector3::new(cols[0][i], cols[1][i], cols[2][i]);
                let p = if translate { p + self.translation } else { p };
                for k in 0..3 {
                    out[k][i] = p[k];
                }
            }
            for (name, col) in names.iter().zip(out) {
                rec.set_column(name, col)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed000_permutation_is_a_right_handed_rotation() {
        let r = FrameTransform::seed000_robot_to_human().rotation;
        assert!((r.determinant() - 1.0).abs() < 1e-12);
        // a robot-x displacement is a negative human-y displacement
        let p = r * Vector3::new(1.0, 0.0, 0.0);
        assert_eq!(p, Vector3::new(0.0, -1.0, 0.0));
    }

    #[test]
    fn improper_rotation_refused() {
        let mut v = vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0];
        v.extend([0.0; 3]);
        assert!(FrameTransform::from_values(&v).is_err());
    }
}

/// Gravity compensation of a force/torque sensor in two steps (seed 004
/// §II-B, eq. (4)-(9)): the sensor's intrinsic bias is constant in the
/// sensor frame, the weight of handle and limb is constant in the reference
/// frame, so they are removed separately.
///
/// Step 1: `bias_sensor`, the mean sensor reading in a pose where gravity does
/// not load the sensor axes. Step 2: at the start of the test (no perturbation
/// yet), the bias-free reading rotated into the reference frame is the
/// gravity term `gravity_ref` (= -F_G). During the test,
/// `R (reading - bias) - gravity_ref` is the force the limb exerts on the
/// sensor (eq. (9): -F_sΔ); its negative is the force applied to the limb.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GravityCompensation {
    /// Sensor bias, sensor frame (N).
    pub bias_sensor: Vector3<f64>,
    /// The weight term -F_G in the reference frame (N).
    pub gravity_ref: Vector3<f64>,
}

impl GravityCompensation {
    /// Calibrate from gravity-free readings (step 1) and the first readings of
    /// the test with the sensor-to-reference rotation at that time (step 2).
    pub fn calibrate(
        bias_readings: &[Vector3<f64>],
        initial_readings: &[Vector3<f64>],
        initial_rotation: &Matrix3<f64>,
    ) -> Result<Self> {
        if bias_readings.is_empty() || initial_readings.is_empty() {
            return Err(Error::invalid(
                "gravity compensation",
                "needs at least one bias reading and one initial reading",
            ));
        }
        let mean = |v: &[Vector3<f64>]| v.iter().sum::<Vector3<f64>>() / v.len() as f64;
        let bias_sensor = mean(bias_readings);
        let gravity_ref = initial_rotation * (mean(initial_readings) - bias_sensor);
        Ok(GravityCompensation {
            bias_sensor,
            gravity_ref,
        })
    }

    /// Force applied to the limb (reference frame) from one sensor reading and
    /// the sensor-to-reference rotation at that sample.
    pub fn force_on_limb(&self, reading: &Vector3<f64>, rotation: &Matrix3<f64>) -> Vector3<f64> {
        -(rotation * (reading - self.bias_sensor) - self.gravity_ref)
    }
}

#[cfg(test)]
mod gravity_tests {
    use super::*;

    fn ry(theta: f64) -> Matrix3<f64> {
        Matrix3::new(
            theta.cos(),
            0.0,
            theta.sin(),
            0.0,
            1.0,
            0.0,
            -theta.sin(),
            0.0,
            theta.cos(),
        )
    }

    #[test]
    fn bias_in_sensor_frame_and_gravity_in_reference_frame_are_both_removed() {
        let bias = Vector3::new(0.3, -0.2, 0.15);
        let weight_ref = Vector3::new(0.0, 0.0, -6.0); // -F_G on the sensor, reference frame
                                                       // a sensor reading: R^T (weight + force of the limb on the sensor) + bias
        let read = |theta: f64, limb_on_sensor: Vector3<f64>| {
            ry(theta).transpose() * (weight_ref + limb_on_sensor) + bias
        };
        // step 1: a pose where gravity is along no sensor axis is modelled as zero load
        let bias_readings = vec![bias; 10];
        let g = GravityCompensation::calibrate(
            &bias_readings,
            &[read(0.0, Vector3::zeros())],
            &ry(0.0),
        )
        .unwrap();
        for (theta, f_limb) in [
            (0.0, Vector3::new(1.0, 0.0, 2.0)),
            (0.3, Vector3::new(-2.0, 0.5, 0.7)),
            (-0.6, Vector3::new(0.0, 0.0, -3.0)),
        ] {
            // the robot applies f_limb to the limb, so the limb pushes -f_limb on the sensor
            let f = g.force_on_limb(&read(theta, -f_limb), &ry(theta));
            assert!(
                (f - f_limb).norm() < 1e-12,
                "theta {theta}: {f} vs {f_limb}"
            );
        }
    }
}
