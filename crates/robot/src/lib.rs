//! limpid-robot: serial robot kinematics, for the virtual lab (seeds 000,
//! 001, 004) and for real recordings whose pose comes from joint angles
//! (`--robot`):
//! Denavit-Hartenberg models in the standard and Craig's modified convention,
//! forward kinematics, the geometric Jacobian, and damped least-squares
//! inverse kinematics that holds the end-effector orientation (seeds 000
//! and 001 keep roll, pitch and yaw fixed during perturbations).
//!
//! Built-in models: the KUKA LWR4+ (7 DoF) with the DH table commonly used
//! for it (standard convention; d1 = 0.3105, d3 = 0.4, d5 = 0.39,
//! d7 = 0.078 m), and a 3-DoF PUMA-type arm after seed 004 Table I (Craig's
//! convention; the link lengths are not printed in the seed, limpid uses
//! a1 = 0.15 m, a2 = 0.35 m, d3 = 0.10 m).

use nalgebra::{
    DMatrix, DVector, Isometry3, Matrix3, Matrix4, Rotation3, Translation3, Unit, Vector3,
};
use serde::{Deserialize, Serialize};

use limpid_core::{Error, Recording, Result};

mod urdf;

pub use urdf::{MAX_URDF_DEPTH, MAX_URDF_OFFSET_M};

/// Which DH convention a table uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Convention {
    /// T_i = Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i).
    Standard,
    /// Craig: T_i = Rx(α_{i-1}) Tx(a_{i-1}) Rz(θ_i) Tz(d_i).
    Modified,
}

/// One revolute joint of a DH table: DH parameters (m, rad), joint offset, limits.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct Joint {
    /// DH link length a (m).
    pub a: f64,
    /// DH link twist α (rad).
    pub alpha: f64,
    /// DH link offset d (m).
    pub d: f64,
    /// Added to the joint angle.
    pub theta_offset: f64,
    /// Lower joint limit (rad).
    pub min: f64,
    /// Upper joint limit (rad).
    pub max: f64,
    /// Largest joint speed (rad/s).
    pub max_speed: f64,
}

/// A revolute joint in the form every model is reduced to:
/// T_i = before · Rot(axis, q_i + offset) · after.
#[derive(Debug, Clone)]
pub struct RevoluteJoint {
    /// Joint name.
    pub name: String,
    /// Fixed transform before the joint's rotation.
    pub before: Matrix4<f64>,
    /// Unit rotation axis in the joint frame.
    pub axis: Vector3<f64>,
    /// Fixed transform after the rotation.
    pub after: Matrix4<f64>,
    /// Added to the joint angle (rad).
    pub offset: f64,
    /// Lower joint limit (rad).
    pub min: f64,
    /// Upper joint limit (rad).
    pub max: f64,
    /// Largest joint speed (rad/s).
    pub max_speed: f64,
}

/// A joint's world axis (unit) and a point on it.
type JointAxis = (Vector3<f64>, Vector3<f64>);

/// A serial robot of revolute joints, placed in the lab by `base`.
#[derive(Debug, Clone)]
pub struct Robot {
    /// Robot name.
    pub name: String,
    /// Pose of the robot's base in the lab (protocol) frame.
    pub base: Matrix4<f64>,
    /// Joints, base to tip.
    pub joints: Vec<RevoluteJoint>,
    /// Fixed transform from the last joint to the end effector.
    pub tip: Matrix4<f64>,
}

fn rot_x(a: f64) -> Matrix4<f64> {
    let (s, c) = a.sin_cos();
    Matrix4::new(
        1.0, 0.0, 0.0, 0.0, 0.0, c, -s, 0.0, 0.0, s, c, 0.0, 0.0, 0.0, 0.0, 1.0,
    )
}
fn trans(x: f64, z: f64) -> Matrix4<f64> {
    let mut t = Matrix4::identity();
    t[(0, 3)] = x;
    t[(2, 3)] = z;
    t
}

/// Homogeneous transform of a translation and URDF roll-pitch-yaw angles
/// (R = Rz(yaw) Ry(pitch) Rx(roll)).
pub fn pose(xyz: [f64; 3], rpy: [f64; 3]) -> Matrix4<f64> {
    let r = Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2]);
    Isometry3::from_parts(Translation3::new(xyz[0], xyz[1], xyz[2]), r.into()).to_homogeneous()
}

fn rotation_about(axis: &Vector3<f64>, angle: f64) -> Matrix4<f64> {
    Rotation3::from_axis_angle(&Unit::new_unchecked(*axis), angle).to_homogeneous()
}

impl Robot {
    /// A robot from a DH table.
    pub fn from_dh(name: &str, convention: Convention, table: &[Joint]) -> Self {
        let joints = table
            .iter()
            .enumerate()
            .map(|(i, j)| {
                let (before, after) = match convention {
                    Convention::Standard => (
                        Matrix4::identity(),
                        trans(0.0, j.d) * trans(j.a, 0.0) * rot_x(j.alpha),
                    ),
                    Convention::Modified => (rot_x(j.alpha) * trans(j.a, 0.0), trans(0.0, j.d)),
                };
                RevoluteJoint {
                    name: format!("q{}", i + 1),
                    before,
                    axis: Vector3::z(),
                    after,
                    offset: j.theta_offset,
                    min: j.min,
                    max: j.max,
                    max_speed: j.max_speed,
                }
            })
            .collect();
        Robot {
            name: name.into(),
            base: Matrix4::identity(),
            joints,
            tip: Matrix4::identity(),
        }
    }

    /// Place the robot's base at `xyz` (m) with roll-pitch-yaw `rpy` (rad) in the lab frame.
    pub fn placed(mut self, xyz: [f64; 3], rpy: [f64; 3]) -> Self {
        self.base = pose(xyz, rpy);
        self
    }

    /// [`Robot::placed`] from a flat list: X, Y, Z (m), optionally followed by
    /// roll, pitch, yaw (rad), as `--robot-base` and Python's `robot_base` give it.
    pub fn placed_at(self, base: &[f64]) -> Result<Self> {
        match *base {
            [x, y, z] => Ok(self.placed([x, y, z], [0.0; 3])),
            [x, y, z, r, p, w] => Ok(self.placed([x, y, z], [r, p, w])),
            _ => Err(Error::invalid(
                "robot base",
                format!(
                    "expected X,Y,Z or X,Y,Z,ROLL,PITCH,YAW, found {} numbers",
                    base.len()
                ),
            )),
        }
    }

    /// KUKA LWR4+ (7 DoF), standard DH, limits ±170/±120 deg, 1.9 rad/s.
    pub fn kuka_lwr4() -> Self {
        use std::f64::consts::FRAC_PI_2 as H;
        let deg = |v: f64| v.to_radians();
        let j = |alpha: f64, d: f64, lim: f64| Joint {
            a: 0.0,
            alpha,
            d,
            theta_offset: 0.0,
            min: -deg(lim),
            max: deg(lim),
            max_speed: 1.9,
        };
        Robot::from_dh(
            "KUKA LWR4+",
            Convention::Standard,
            &[
                j(H, 0.3105, 170.0),
                j(-H, 0.0, 120.0),
                j(-H, 0.4, 170.0),
                j(H, 0.0, 120.0),
                j(H, 0.39, 170.0),
                j(-H, 0.0, 120.0),
                j(0.0, 0.078, 170.0),
            ],
        )
    }

    /// 3-DoF PUMA-type arm (seed 004 Table I layout, Craig's convention).
    pub fn puma3() -> Self {
        use std::f64::consts::FRAC_PI_2 as H;
        let j = |a: f64, alpha: f64, d: f64| Joint {
            a,
            alpha,
            d,
            theta_offset: 0.0,
            min: -std::f64::consts::PI,
            max: std::f64::consts::PI,
            max_speed: 3.0,
        };
        Robot::from_dh(
            "PUMA-type 3-DoF",
            Convention::Modified,
            &[j(0.0, 0.0, 0.0), j(0.15, -H, 0.0), j(0.35, H, 0.10)],
        )
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// World axis and a point on it for every joint, and the end-effector pose.
    fn axes(&self, q: &[f64]) -> (Vec<JointAxis>, Matrix4<f64>) {
        let mut t = self.base;
        let mut axes = Vec::with_capacity(self.dof());
        for (j, qi) in self.joints.iter().zip(q) {
            t *= j.before;
            let r = t.fixed_view::<3, 3>(0, 0);
            axes.push((r * j.axis, t.fixed_view::<3, 1>(0, 3).into()));
            t = t * rotation_about(&j.axis, qi + j.offset) * j.after;
        }
        (axes, t * self.tip)
    }

    /// End-effector pose (homogeneous transform in the base frame).
    pub fn fk(&self, q: &[f64]) -> Matrix4<f64> {
        self.axes(q).1
    }

    /// Geometric Jacobian (6 x n): linear velocity over angular velocity.
    pub fn jacobian(&self, q: &[f64]) -> DMatrix<f64> {
        self.pose_and_jacobian(q).1
    }

    /// End-effector pose and geometric Jacobian from one pass over the joints.
    pub fn pose_and_jacobian(&self, q: &[f64]) -> (Matrix4<f64>, DMatrix<f64>) {
        let (axes, end) = self.axes(q);
        let pe: Vector3<f64> = end.fixed_view::<3, 1>(0, 3).into();
        let mut jac = DMatrix::zeros(6, self.dof());
        for (i, (z, p)) in axes.iter().enumerate() {
            let v = z.cross(&(pe - p));
            for k in 0..3 {
                jac[(k, i)] = v[k];
                jac[(3 + k, i)] = z[k];
            }
        }
        (end, jac)
    }

    /// Damped least-squares IK to a target pose (position and orientation;
    /// position only for robots with fewer than 6 joints), starting from `q0`.
    /// Converges to 1e-13 or fails with an error.
    pub fn ik(&self, target: &Matrix4<f64>, q0: &[f64]) -> Result<Vec<f64>> {
        let mut q = q0.to_vec();
        let pt: Vector3<f64> = target.fixed_view::<3, 1>(0, 3).into();
        let rt: Matrix3<f64> = target.fixed_view::<3, 3>(0, 0).into();
        let lambda2 = 1e-4;
        for _ in 0..2000 {
            let t = self.fk(&q);
            let p: Vector3<f64> = t.fixed_view::<3, 1>(0, 3).into();
            let r: Matrix3<f64> = t.fixed_view::<3, 3>(0, 0).into();
            let ep = pt - p;
            // orientation error 0.5 Σ r_i × r_target,i (robust where the rotation is nearly identity)
            let er: Vector3<f64> = (0..3)
                .map(|i| r.column(i).cross(&rt.column(i)))
                .sum::<Vector3<f64>>()
                * 0.5;
            // fewer than 6 joints cannot also hold the orientation: position only
            let full = self.dof() >= 6;
            let rows = if full { 6 } else { 3 };
            let e = DVector::from_iterator(rows, ep.iter().chain(er.iter()).take(rows).copied());
            if ep.norm() < 1e-13 && (!full || er.norm() < 1e-13) {
                return Ok(q);
            }
            let j = self.jacobian(&q).rows(0, rows).into_owned();
            let jjt =
                &j * j.transpose() + DMatrix::identity(rows, rows) * lambda2 * e.norm().min(1.0);
            let step = j.transpose()
                * jjt
                    .lu()
                    .solve(&e)
                    .ok_or_else(|| Error::invalid("inverse kinematics", "singular step"))?;
            // at most 0.2 rad per iteration: far from the solution the linearisation misleads
            let scale = (0.2 / step.amax()).min(1.0);
            for (qi, s) in q.iter_mut().zip(step.iter().map(|s| s * scale)) {
                // keep revolute angles in (-pi, pi]
                let v = *qi + s;
                *qi = v.sin().atan2(v.cos());
            }
        }
        let t = self.fk(&q);
        let err = (pt - Vector3::from(t.fixed_view::<3, 1>(0, 3))).norm();
        if err < 1e-9 {
            Ok(q)
        } else {
            Err(Error::invalid("inverse kinematics", format!("did not converge (position error {err:.3e} m): target out of reach or singular")))
        }
    }

    /// First joint limit or speed limit a joint trajectory (rows = samples) breaks.
    pub fn check_joint_trajectory(&self, q: &[Vec<f64>], dt: f64) -> Result<()> {
        for (k, row) in q.iter().enumerate() {
            for (i, (v, j)) in row.iter().zip(&self.joints).enumerate() {
                if *v < j.min || *v > j.max {
                    return Err(Error::invalid(
                        "joint trajectory",
                        format!(
                            "joint {} at {:.4} rad leaves its range [{:.4}, {:.4}] at sample {k}",
                            i + 1,
                            v,
                            j.min,
                            j.max
                        ),
                    ));
                }
                if k > 0 {
                    let speed = (v - q[k - 1][i]).abs() / dt;
                    if speed > j.max_speed {
                        return Err(Error::invalid(
                            "joint trajectory",
                            format!(
                                "joint {} speed {speed:.3} rad/s exceeds {} rad/s at sample {k}",
                                i + 1,
                                j.max_speed
                            ),
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

impl Robot {
    /// A built-in robot by name: `kuka-lwr4` or `puma3`.
    pub fn by_name(name: &str) -> Result<Self> {
        match name {
            "kuka-lwr4" => Ok(Robot::kuka_lwr4()),
            "puma3" => Ok(Robot::puma3()),
            path if path.ends_with(".urdf") => Robot::from_urdf(std::path::Path::new(path), None),
            other => Err(Error::invalid(
                "robot",
                format!("unknown robot {other:?}; built in: kuka-lwr4, puma3, or a path to a .urdf file"),
            )),
        }
    }

    /// A comfortable joint configuration to start IK from (elbow bent, wrist centred).
    pub fn home(&self) -> Vec<f64> {
        match self.dof() {
            7 => vec![0.0, 0.6, 0.0, -1.4, 0.0, 0.8, 0.0],
            n => (0..n).map(|i| if i == 1 { -0.5 } else { 0.3 }).collect(),
        }
    }

    /// End-effector pose at every sample of a recording's `robot_q1..n`
    /// columns (seed 000 computes the end point so); `why` goes into the
    /// missing-column error.
    pub fn poses(&self, rec: &Recording, why: &str) -> Result<Vec<Matrix4<f64>>> {
        let joints: Vec<&[f64]> = (1..=self.dof())
            .map(|i| rec.require(&format!("robot_q{i}"), why))
            .collect::<Result<_>>()?;
        let mut q = vec![0.0; self.dof()];
        Ok((0..rec.len())
            .map(|k| {
                for (qi, c) in q.iter_mut().zip(&joints) {
                    *qi = c[k];
                }
                self.fk(&q)
            })
            .collect())
    }

    /// Joint angles that put the end effector at `position` with `orientation`,
    /// reached from `q_start` along a straight line in steps of at most 1 cm
    /// (a direct IK jump across the workspace can fall into a singularity).
    pub fn reach(
        &self,
        position: &Vector3<f64>,
        orientation: &Matrix3<f64>,
        q_start: &[f64],
    ) -> Result<Vec<f64>> {
        let from: Vector3<f64> = self.fk(q_start).fixed_view::<3, 1>(0, 3).into();
        let steps = ((position - from).norm() / 0.01).ceil().max(1.0) as usize;
        let path: Vec<Vector3<f64>> = (1..=steps)
            .map(|k| from + (position - from) * (k as f64 / steps as f64))
            .collect();
        Ok(self
            .track(&path, orientation, q_start)?
            .pop()
            .expect("path has at least one point"))
    }

    /// Joint trajectory tracking end-effector positions with the orientation of
    /// `orientation` held; each sample starts IK from the previous solution.
    pub fn track(
        &self,
        positions: &[Vector3<f64>],
        orientation: &Matrix3<f64>,
        q_start: &[f64],
    ) -> Result<Vec<Vec<f64>>> {
        let mut q = q_start.to_vec();
        let mut out = Vec::with_capacity(positions.len());
        for p in positions {
            let mut target = Matrix4::identity();
            target.fixed_view_mut::<3, 3>(0, 0).copy_from(orientation);
            target.fixed_view_mut::<3, 1>(0, 3).copy_from(p);
            q = self.ik(&target, &q)?;
            out.push(q.clone());
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::urdf::tests::fixture;
    use super::*;

    #[test]
    fn jacobian_matches_finite_differences() {
        let urdf = Robot::from_urdf(&fixture("kuka_lwr4.urdf"), None).unwrap();
        let placed = Robot::puma3().placed([0.3, -0.2, 0.1], [0.2, -0.4, 1.1]);
        for robot in [Robot::kuka_lwr4(), Robot::puma3(), urdf, placed] {
            let q: Vec<f64> = (0..robot.dof()).map(|i| 0.3 + 0.2 * i as f64).collect();
            let j = robot.jacobian(&q);
            let h = 1e-7;
            for c in 0..robot.dof() {
                let mut qp = q.clone();
                qp[c] += h;
                let (a, b) = (robot.fk(&q), robot.fk(&qp));
                for k in 0..3 {
                    assert!(
                        ((b[(k, 3)] - a[(k, 3)]) / h - j[(k, c)]).abs() < 1e-5,
                        "{} joint {c}",
                        robot.name
                    );
                }
                // angular part: (R_b R_a^T - I) / h ~ skew(w)
                let ra: Matrix3<f64> = a.fixed_view::<3, 3>(0, 0).into();
                let rb: Matrix3<f64> = b.fixed_view::<3, 3>(0, 0).into();
                let w = (rb * ra.transpose() - Matrix3::identity()) / h;
                assert!(
                    (w[(2, 1)] - j[(3, c)]).abs() < 1e-5
                        && (w[(0, 2)] - j[(4, c)]).abs() < 1e-5
                        && (w[(1, 0)] - j[(5, c)]).abs() < 1e-5
                );
            }
        }
    }

    #[test]
    fn redundant_ik_round_trip_holds_orientation() {
        let robot = Robot::kuka_lwr4();
        let q_true = vec![0.2, 0.6, -0.3, -1.2, 0.4, 0.7, 0.1];
        let start = robot.fk(&q_true);
        // a 3 cm displacement with the orientation held, as in seed 000
        let mut target = start;
        target[(0, 3)] += 0.02;
        target[(1, 3)] -= 0.015;
        target[(2, 3)] += 0.013;
        let q = robot.ik(&target, &q_true).unwrap();
        let got = robot.fk(&q);
        let pos_err = (0..3)
            .map(|k| (got[(k, 3)] - target[(k, 3)]).powi(2))
            .sum::<f64>()
            .sqrt();
        let rot_err = (got.fixed_view::<3, 3>(0, 0) - start.fixed_view::<3, 3>(0, 0)).norm();
        assert!(pos_err < 1e-9, "position error {pos_err:e}");
        assert!(rot_err < 1e-9, "orientation error {rot_err:e}");
        assert!(robot
            .check_joint_trajectory(&[q_true.clone(), q.clone()], 1.0)
            .is_ok());
        // an over-fast step is refused naming the joint
        let e = robot
            .check_joint_trajectory(&[q_true, q], 0.001)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("speed") && e.contains("exceeds 1.9 rad/s at sample 1"),
            "{e}"
        );
    }
}
