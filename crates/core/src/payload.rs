//! Payload calibration of a force/torque sensor from still poses — a limpid
//! extension of seed 004's gravity compensation (§II-B, eq. (4)-(9)) for
//! robots that turn the sensor in space.
//!
//! The two steps of [`crate::GravityCompensation`] hold the load's weight
//! constant in the reference frame, which is exact for forces but leaves the
//! moment of a load whose centre of mass is off the rotation axis. Here the
//! sensor is held still in several orientations R_k (sensor to reference)
//! and the load is identified by linear least squares:
//!
//! - forces:  F_k = R_k^T W + b_F           (unknowns W, b_F: 6)
//! - torques: τ_k = p × (R_k^T W) + b_τ     (unknowns p, b_τ: 6)
//!
//! with W the weight the sensor carries (reference frame, N), b_F and b_τ
//! the sensor biases and p the load's centre of mass (sensor frame, m). Then
//! the force and torque applied to the limb, in the reference frame, are
//! -(R (F - b_F) - W) and -(R (τ - b_τ) - (R p) × W).
//!
//! Poses that turn about one axis only cannot separate the parts of W and b_F
//! along that axis (nor p along it); the fit then keeps the minimum-norm
//! solution, which compensates exactly for rotations about that axis, and
//! says so in `unidentified`.

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use crate::error::{Error, Result};

/// Singular values below this fraction of the largest are treated as zero.
const RANK_TOLERANCE: f64 = 1e-9;

/// The identified load and biases, with the quality of the fit.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PayloadCalibration {
    /// W: the weight the sensor carries, reference frame (N).
    pub weight_ref: [f64; 3],
    /// b_F: force bias, sensor frame (N).
    pub force_bias: [f64; 3],
    /// p: the load's centre of mass, sensor frame (m); with torque readings.
    pub centre_of_mass: Option<[f64; 3]>,
    /// b_τ: torque bias, sensor frame (N m); with torque readings.
    pub torque_bias: Option<[f64; 3]>,
    /// RMS of the force residuals (N) and, with torques, of the torque residuals (N m).
    pub force_rms_residual: f64,
    /// RMS of the torque residuals (N m), with torque readings.
    pub torque_rms_residual: Option<f64>,
    /// Readings used.
    pub samples: usize,
    /// Combinations the poses could not separate (empty when fully identified).
    pub unidentified: Vec<String>,
}

fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Least squares through the SVD with small singular values dropped: the
/// solution, the RMS residual and the rank deficiency.
fn solve(a: DMatrix<f64>, b: DVector<f64>) -> Result<(DVector<f64>, f64, usize)> {
    let svd = crate::linalg::svd(a.clone(), true, true).ok_or_else(|| {
        Error::invalid(
            "payload calibration",
            "the readings are not finite or too large for double precision",
        )
    })?;
    let largest = svd.singular_values.max();
    if largest <= 0.0 || !largest.is_finite() {
        return Err(Error::invalid(
            "payload calibration",
            "the readings carry no information (all zero or not finite)",
        ));
    }
    let deficiency = svd
        .singular_values
        .iter()
        .filter(|s| **s <= RANK_TOLERANCE * largest)
        .count();
    let x = svd
        .solve(&b, RANK_TOLERANCE * largest)
        .map_err(|e| Error::invalid("payload calibration", e.to_string()))?;
    let residual = &a * &x - &b;
    let rms = (residual.norm_squared() / b.len() as f64).sqrt();
    Ok((x, rms, deficiency))
}

impl PayloadCalibration {
    /// Fit from still readings `forces` (and `torques`) in the sensor frame
    /// with the sensor-to-reference rotation of each.
    pub fn fit(
        rotations: &[Matrix3<f64>],
        forces: &[Vector3<f64>],
        torques: Option<&[Vector3<f64>]>,
    ) -> Result<Self> {
        let n = forces.len();
        if n < 2 || rotations.len() != n || torques.is_some_and(|t| t.len() != n) {
            return Err(Error::invalid(
                "payload calibration",
                format!(
                    "needs at least two readings with one rotation each (found {n} readings, {} rotations)",
                    rotations.len()
                ),
            ));
        }
        let mut a = DMatrix::zeros(3 * n, 6);
        let mut b = DVector::zeros(3 * n);
        for (k, (r, f)) in rotations.iter().zip(forces).enumerate() {
            a.view_mut((3 * k, 0), (3, 3)).copy_from(&r.transpose());
            a.view_mut((3 * k, 3), (3, 3))
                .copy_from(&Matrix3::identity());
            b.rows_mut(3 * k, 3).copy_from(f);
        }
        let (x, force_rms, force_deficiency) = solve(a, b)?;
        let weight = Vector3::new(x[0], x[1], x[2]);
        let mut unidentified = Vec::new();
        if force_deficiency > 0 {
            unidentified.push(format!(
                "{force_deficiency} combination(s) of weight and force bias: the poses turn about fewer than two axes; the compensation holds for rotations about the axes the poses used"
            ));
        }
        let mut out = PayloadCalibration {
            weight_ref: weight.into(),
            force_bias: [x[3], x[4], x[5]],
            centre_of_mass: None,
            torque_bias: None,
            force_rms_residual: force_rms,
            torque_rms_residual: None,
            samples: n,
            unidentified,
        };
        if let Some(torques) = torques {
            let mut a = DMatrix::zeros(3 * n, 6);
            let mut b = DVector::zeros(3 * n);
            for (k, (r, t)) in rotations.iter().zip(torques).enumerate() {
                let g = r.transpose() * weight;
                a.view_mut((3 * k, 0), (3, 3)).copy_from(&(-skew(&g)));
                a.view_mut((3 * k, 3), (3, 3))
                    .copy_from(&Matrix3::identity());
                b.rows_mut(3 * k, 3).copy_from(t);
            }
            let (x, torque_rms, torque_deficiency) = solve(a, b)?;
            if torque_deficiency > 0 {
                out.unidentified.push(format!(
                    "{torque_deficiency} combination(s) of centre of mass and torque bias: the weight took fewer than two directions in the sensor frame"
                ));
            }
            out.centre_of_mass = Some([x[0], x[1], x[2]]);
            out.torque_bias = Some([x[3], x[4], x[5]]);
            out.torque_rms_residual = Some(torque_rms);
        }
        Ok(out)
    }

    /// Force applied to the limb (reference frame) from a sensor reading and
    /// the sensor-to-reference rotation.
    pub fn force_on_limb(&self, reading: &Vector3<f64>, rotation: &Matrix3<f64>) -> Vector3<f64> {
        let (w, b) = (
            Vector3::from(self.weight_ref),
            Vector3::from(self.force_bias),
        );
        -(rotation * (reading - b) - w)
    }

    /// Torque applied to the limb about the sensor origin (reference frame);
    /// `None` without a torque calibration.
    pub fn torque_on_limb(
        &self,
        reading: &Vector3<f64>,
        rotation: &Matrix3<f64>,
    ) -> Option<Vector3<f64>> {
        let (p, b) = (self.centre_of_mass?, self.torque_bias?);
        let w = Vector3::from(self.weight_ref);
        let moment = (rotation * Vector3::from(p)).cross(&w);
        Some(-(rotation * (reading - Vector3::from(b)) - moment))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    fn readings(
        rotations: &[Matrix3<f64>],
        w: Vector3<f64>,
        p: Vector3<f64>,
        bf: Vector3<f64>,
        bt: Vector3<f64>,
    ) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
        rotations
            .iter()
            .map(|r| {
                let g = r.transpose() * w;
                (g + bf, p.cross(&g) + bt)
            })
            .unzip()
    }

    #[test]
    fn poses_in_space_identify_weight_centre_of_mass_and_biases() {
        let rotations: Vec<Matrix3<f64>> = [
            (0.0, 0.0, 0.0),
            (0.6, 0.0, 0.0),
            (0.0, -0.7, 0.2),
            (0.3, 0.4, -1.0),
            (-0.5, 0.2, 2.0),
        ]
        .iter()
        .map(|&(r, p, y)| *Rotation3::from_euler_angles(r, p, y).matrix())
        .collect();
        let (w, p) = (
            Vector3::new(0.0, 0.0, -7.5),
            Vector3::new(0.01, -0.02, 0.06),
        );
        let (bf, bt) = (
            Vector3::new(0.4, -0.3, 1.2),
            Vector3::new(0.02, 0.05, -0.01),
        );
        let (f, t) = readings(&rotations, w, p, bf, bt);
        let c = PayloadCalibration::fit(&rotations, &f, Some(&t)).unwrap();
        assert!(c.unidentified.is_empty(), "{:?}", c.unidentified);
        assert!((Vector3::from(c.weight_ref) - w).norm() < 1e-10);
        assert!((Vector3::from(c.force_bias) - bf).norm() < 1e-10);
        assert!((Vector3::from(c.centre_of_mass.unwrap()) - p).norm() < 1e-10);
        assert!((Vector3::from(c.torque_bias.unwrap()) - bt).norm() < 1e-10);
        // a new orientation with the limb pushing: force and torque recovered
        let r = *Rotation3::from_euler_angles(-0.2, 0.9, 0.4).matrix();
        let (f_limb, t_limb) = (Vector3::new(1.0, -2.0, 0.5), Vector3::new(0.1, 0.0, -0.3));
        let g = r.transpose() * w;
        let reading_f = g - r.transpose() * f_limb + bf;
        let reading_t = p.cross(&g) - r.transpose() * t_limb + bt;
        assert!((c.force_on_limb(&reading_f, &r) - f_limb).norm() < 1e-10);
        assert!((c.torque_on_limb(&reading_t, &r).unwrap() - t_limb).norm() < 1e-10);
    }

    #[test]
    fn one_axis_of_rotation_is_said_and_still_compensated_about_it() {
        let about_y = |a: f64| *Rotation3::from_euler_angles(0.0, a, 0.0).matrix();
        let rotations: Vec<Matrix3<f64>> = [-0.4, -0.1, 0.2, 0.5].map(about_y).to_vec();
        let (w, p) = (Vector3::new(0.0, 0.0, -6.0), Vector3::new(0.0, 0.0, 0.05));
        let (bf, bt) = (
            Vector3::new(0.2, -0.1, 0.4),
            Vector3::new(0.03, -0.05, 0.02),
        );
        let (f, t) = readings(&rotations, w, p, bf, bt);
        let c = PayloadCalibration::fit(&rotations, &f, Some(&t)).unwrap();
        assert!(!c.unidentified.is_empty());
        assert!(c.force_rms_residual < 1e-10 && c.torque_rms_residual.unwrap() < 1e-10);
        let r = about_y(0.3);
        let g = r.transpose() * w;
        let reading_t = p.cross(&g) + bt;
        let t = c.torque_on_limb(&reading_t, &r).unwrap();
        assert!(t.norm() < 1e-10, "torque left {t}");
        // every reading in one pose: nothing can be separated
        let same = vec![Matrix3::identity(); 3];
        let (f, _) = readings(&same, w, p, bf, bt);
        let c = PayloadCalibration::fit(&same, &f, None).unwrap();
        assert!(
            c.unidentified[0].contains("3 combination"),
            "{:?}",
            c.unidentified
        );
    }
}
