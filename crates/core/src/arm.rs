//! Planar two-link arm (seed 003 §II, eq. (9)): kinematics with q1 the
//! shoulder angle and q2 the relative elbow angle, and the rigid-body terms
//! with base inertial parameters ξ: M(q, ξ) and C(q, q', ξ) q'. Shared by the
//! estimator (limpid-ident) and the virtual lab (limpid-lab).

use nalgebra::{Matrix2, Vector2, Vector3};
use serde::Serialize;

/// Planar arm geometry: link lengths (m) and shoulder position (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Arm {
    /// Upper-arm length (m).
    pub l1: f64,
    /// Forearm length (m).
    pub l2: f64,
    /// Shoulder position in the plane (m).
    pub shoulder: [f64; 2],
}

impl Arm {
    /// End-point position of joint angles `q` (rad).
    pub fn fk(&self, q: [f64; 2]) -> [f64; 2] {
        [
            self.shoulder[0] + self.l1 * q[0].cos() + self.l2 * (q[0] + q[1]).cos(),
            self.shoulder[1] + self.l1 * q[0].sin() + self.l2 * (q[0] + q[1]).sin(),
        ]
    }

    /// Jacobian dx/dq.
    pub fn jacobian(&self, q: [f64; 2]) -> Matrix2<f64> {
        let (s1, c1) = q[0].sin_cos();
        let (s12, c12) = (q[0] + q[1]).sin_cos();
        Matrix2::new(
            -self.l1 * s1 - self.l2 * s12,
            -self.l2 * s12,
            self.l1 * c1 + self.l2 * c12,
            self.l2 * c12,
        )
    }

    /// Analytical inverse kinematics; `elbow_positive` picks the branch q2 > 0.
    /// `None` when the point is out of reach.
    pub fn ik(&self, x: [f64; 2], elbow_positive: bool) -> Option<[f64; 2]> {
        let (dx, dy) = (x[0] - self.shoulder[0], x[1] - self.shoulder[1]);
        let c2 =
            (dx * dx + dy * dy - self.l1 * self.l1 - self.l2 * self.l2) / (2.0 * self.l1 * self.l2);
        if !(-1.0..=1.0).contains(&c2) {
            return None;
        }
        let s2 = (1.0 - c2 * c2).sqrt() * if elbow_positive { 1.0 } else { -1.0 };
        let q2 = s2.atan2(c2);
        let q1 = dy.atan2(dx) - (self.l2 * s2).atan2(self.l1 + self.l2 * c2);
        Some([q1, q2])
    }
}

/// Mass matrix M(q, ξ).
pub fn mass_matrix(q2: f64, xi: [f64; 3]) -> Matrix2<f64> {
    let c = q2.cos();
    Matrix2::new(
        xi[0] + 2.0 * xi[1] * c,
        xi[2] + xi[1] * c,
        xi[2] + xi[1] * c,
        xi[2],
    )
}

/// Coriolis/centrifugal torques C(q, q') q'.
pub fn coriolis(q2: f64, qd: [f64; 2], xi: [f64; 3]) -> Vector2<f64> {
    let s = q2.sin();
    Vector2::new(
        -xi[1] * s * (2.0 * qd[0] * qd[1] + qd[1] * qd[1]),
        xi[1] * s * qd[0] * qd[0],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinematics_round_trip() {
        let arm = Arm {
            l1: 0.3,
            l2: 0.32,
            shoulder: [0.1, -0.2],
        };
        for q in [[0.08, 1.0], [-0.5, 0.3], [1.2, 2.0]] {
            let x = arm.fk(q);
            let back = arm.ik(x, true).unwrap();
            assert!(
                (back[0] - q[0]).abs() < 1e-12 && (back[1] - q[1]).abs() < 1e-12,
                "{q:?} -> {back:?}"
            );
            // Jacobian against finite differences
            let j = arm.jacobian(q);
            let h = 1e-7;
            for c in 0..2 {
                let mut qp = q;
                qp[c] += h;
                let xp = arm.fk(qp);
                for r in 0..2 {
                    assert!(((xp[r] - x[r]) / h - j[(r, c)]).abs() < 1e-5);
                }
            }
        }
        assert!(arm.ik([5.0, 5.0], true).is_none());
    }
}

/// The 3-D arm configuration from tracked markers (seed 000 §II-A: trackers at
/// the elbow and the wrist, reference frame on the shoulder; seed 001: motion
/// capture of the arm). Angles in rad:
///
/// - `shoulder_elevation`: angle between the upper arm and the downward vertical
///   (0 arm hanging, π/2 horizontal);
/// - `shoulder_azimuth`: direction of the upper arm's horizontal projection, measured
///   about the vertical from the first horizontal axis (x when z is vertical);
/// - `humeral_rotation`: rotation of the forearm's plane about the upper arm, 0 when
///   the forearm points upward in the vertical plane through the upper arm (ill-defined
///   when the elbow is straight or the arm vertical: then `None`);
/// - `elbow_flexion`: 0 with the arm straight;
/// - segment lengths (m), which a rigid marker set keeps constant.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ArmConfiguration {
    /// Elevation of the upper arm from the downward vertical (rad).
    pub shoulder_elevation: f64,
    /// Azimuth of the upper arm about the vertical (rad).
    pub shoulder_azimuth: f64,
    /// Rotation of the humerus about its axis (rad); `None` when undefined.
    pub humeral_rotation: Option<f64>,
    /// Elbow flexion (rad); 0 with the arm straight.
    pub elbow_flexion: f64,
    /// Shoulder-elbow distance (m).
    pub upper_arm_length: f64,
    /// Elbow-wrist distance (m).
    pub forearm_length: f64,
}

/// The arm configuration from shoulder, elbow and wrist positions, with `up`
/// the unit upward vertical of the frame. None if two markers coincide.
pub fn arm_configuration(
    shoulder: Vector3<f64>,
    elbow: Vector3<f64>,
    wrist: Vector3<f64>,
    up: Vector3<f64>,
) -> Option<ArmConfiguration> {
    let upper = elbow - shoulder;
    let fore = wrist - elbow;
    let (lu, lf) = (upper.norm(), fore.norm());
    if lu < 1e-9 || lf < 1e-9 {
        return None;
    }
    let u = upper / lu;
    let f = fore / lf;
    let angle = |a: &Vector3<f64>, b: &Vector3<f64>| a.cross(b).norm().atan2(a.dot(b));
    // horizontal axes: the first frame axis not parallel to `up`, made orthogonal
    let seed = if up.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let h1 = (seed - up * seed.dot(&up)).normalize();
    let h2 = up.cross(&h1);
    let u_perp_up = |v: Vector3<f64>| v - u * v.dot(&u);
    let reference = u_perp_up(up);
    let forearm_perp = u_perp_up(f);
    let humeral_rotation = (reference.norm() > 1e-6 && forearm_perp.norm() > 1e-6).then(|| {
        let (r, p) = (reference.normalize(), forearm_perp.normalize());
        r.cross(&p).dot(&u).atan2(r.dot(&p))
    });
    Some(ArmConfiguration {
        shoulder_elevation: angle(&u, &(-up)),
        shoulder_azimuth: u.dot(&h2).atan2(u.dot(&h1)),
        humeral_rotation,
        elbow_flexion: angle(&u, &f),
        upper_arm_length: lu,
        forearm_length: lf,
    })
}

#[cfg(test)]
mod configuration_tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn arm_configuration_of_known_postures() {
        let up = Vector3::z();
        let s = Vector3::new(0.1, 0.2, 0.3);
        // upper arm horizontal along +y, forearm pointing up: elbow at 90 deg, no rotation
        let c = arm_configuration(
            s,
            s + Vector3::new(0.0, 0.3, 0.0),
            s + Vector3::new(0.0, 0.3, 0.25),
            up,
        )
        .unwrap();
        assert!((c.shoulder_elevation - FRAC_PI_2).abs() < 1e-12);
        assert!((c.shoulder_azimuth - FRAC_PI_2).abs() < 1e-12);
        assert!((c.elbow_flexion - FRAC_PI_2).abs() < 1e-12);
        assert!(c.humeral_rotation.unwrap().abs() < 1e-12);
        assert!(
            (c.upper_arm_length - 0.3).abs() < 1e-12 && (c.forearm_length - 0.25).abs() < 1e-12
        );
        // the forearm turned to point along +x: rotated by +90 deg about +y (right-handed)
        let c = arm_configuration(
            s,
            s + Vector3::new(0.0, 0.3, 0.0),
            s + Vector3::new(0.25, 0.3, 0.0),
            up,
        )
        .unwrap();
        assert!((c.humeral_rotation.unwrap() - FRAC_PI_2).abs() < 1e-12);
        // arm hanging straight down: elevation 0, elbow 0, rotation undefined
        let c = arm_configuration(s, s - up * 0.3, s - up * 0.55, up).unwrap();
        assert!(c.shoulder_elevation.abs() < 1e-12 && c.elbow_flexion.abs() < 1e-12);
        assert!(c.humeral_rotation.is_none());
        assert!(arm_configuration(s, s, s + up, up).is_none());
    }
}

/// The shoulder as a 3-DoF ball joint (seed 004 §I: flexion/extension about
/// the transverse axis, abduction/adduction about the antero-posterior axis,
/// internal/external rotation about the humerus), with the elbow held at a
/// fixed flexion. Frame: x forward, y to the subject's left, z up, origin at
/// the shoulder's centre; a right arm; all angles 0 with the arm hanging and
/// the forearm forward of the elbow by `elbow_rad` (π/2: horizontal).
/// Hand torques and impedance follow from the hand Jacobian J_h:
/// τ = J_h^T F, Z_joint = J_h^T Z_hand J_h (small motions about a posture; the
/// term (∂J_h^T/∂q) F of a static load is left out).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Shoulder {
    /// Upper-arm length (m).
    pub upper_arm_m: f64,
    /// Forearm length (m).
    pub forearm_m: f64,
    /// Elbow flexion (rad).
    pub elbow_rad: f64,
}

fn rot_x(a: f64) -> nalgebra::Matrix3<f64> {
    nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), a).into_inner()
}
fn rot_y(a: f64) -> nalgebra::Matrix3<f64> {
    nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), a).into_inner()
}
fn rot_z(a: f64) -> nalgebra::Matrix3<f64> {
    nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), a).into_inner()
}

impl Shoulder {
    /// Hand position for [flexion, abduction, internal rotation] (rad):
    /// R = Ry(-flexion) Rx(-abduction) Rz(rotation) applied to the hanging arm.
    pub fn hand(&self, angles: [f64; 3]) -> Vector3<f64> {
        let r = rot_y(-angles[0]) * rot_x(-angles[1]) * rot_z(angles[2]);
        let upper = Vector3::new(0.0, 0.0, -self.upper_arm_m);
        let fore = Vector3::new(self.elbow_rad.sin(), 0.0, -self.elbow_rad.cos()) * self.forearm_m;
        r * (upper + fore)
    }

    /// J_h = ∂hand/∂angles (central differences, step 1e-6 rad: error ~1e-12 m).
    pub fn jacobian(&self, angles: [f64; 3]) -> nalgebra::Matrix3<f64> {
        let h = 1e-6;
        let mut j = nalgebra::Matrix3::zeros();
        for c in 0..3 {
            let (mut up, mut down) = (angles, angles);
            up[c] += h;
            down[c] -= h;
            j.set_column(c, &((self.hand(up) - self.hand(down)) / (2.0 * h)));
        }
        j
    }

    /// Joint-space impedance J_h^T Z J_h of a hand impedance matrix Z.
    pub fn joint_impedance(
        &self,
        hand: &nalgebra::Matrix3<f64>,
        angles: [f64; 3],
    ) -> nalgebra::Matrix3<f64> {
        let j = self.jacobian(angles);
        j.transpose() * hand * j
    }

    /// Joint torques τ = J_h^T F of a hand force.
    pub fn torques(&self, force: &Vector3<f64>, angles: [f64; 3]) -> Vector3<f64> {
        self.jacobian(angles).transpose() * force
    }

    /// The hand's X-Z Jacobian ∂(X, Z)/∂(flexion, abduction) (rows X and Z,
    /// columns 1-2 of [`Shoulder::jacobian`]): seed 004's J_h of eq. (3).
    pub fn jacobian_xz(&self, angles: [f64; 3]) -> nalgebra::Matrix2<f64> {
        let j = self.jacobian(angles);
        nalgebra::Matrix2::new(j[(0, 0)], j[(0, 1)], j[(2, 0)], j[(2, 1)])
    }

    /// Flexion and abduction that put the hand at `x`, `z` (m) with the
    /// rotation held at `start[2]`, by Newton's method from `start` (a nearby
    /// posture, e.g. the previous sample's): seed 004's "kinematic
    /// relationship between the shoulder rotation and hand's position". With
    /// the elbow fixed the hand stays on a sphere about the shoulder, so its
    /// position gives two angles, not three. `None` when it does not
    /// converge to 1e-12 m within 50 steps (out of reach, or a posture where
    /// X and Z do not determine the two angles).
    pub fn flexion_abduction_of(&self, x: f64, z: f64, start: [f64; 3]) -> Option<[f64; 3]> {
        let mut q = start;
        let miss = |q: [f64; 3]| {
            let h = self.hand(q);
            nalgebra::Vector2::new(x - h[0], z - h[2])
        };
        for _ in 0..50 {
            let m = miss(q);
            if !m.iter().all(|v| v.is_finite()) {
                return None;
            }
            if m.norm() <= 1e-12 {
                return Some(q);
            }
            let step = self.jacobian_xz(q).lu().solve(&m)?;
            q[0] += step[0];
            q[1] += step[1];
        }
        (miss(q).norm() <= 1e-12).then_some(q)
    }
}

#[cfg(test)]
mod shoulder_tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn shoulder_kinematics_torques_and_impedance() {
        let s = Shoulder {
            upper_arm_m: 0.3,
            forearm_m: 0.35,
            elbow_rad: FRAC_PI_2,
        };
        // hanging arm, forearm forward: hand 0.35 m forward, 0.3 m down
        let h = s.hand([0.0; 3]);
        assert!((h - Vector3::new(0.35, 0.0, -0.3)).norm() < 1e-12);
        // internal rotation by 90 deg turns the forearm across the body (to +y, the left)
        let h = s.hand([0.0, 0.0, FRAC_PI_2]);
        assert!((h - Vector3::new(0.0, 0.35, -0.3)).norm() < 1e-12);
        // flexion by 90 deg lifts the upper arm forward to horizontal
        let h = s.hand([FRAC_PI_2, 0.0, 0.0]);
        assert!((h - Vector3::new(0.3, 0.0, 0.35)).norm() < 1e-12);
        // virtual work: τ · dq = F · dx for a small joint motion
        let q = [0.4, 0.3, -0.2];
        let f = Vector3::new(3.0, -2.0, 5.0);
        let dq = Vector3::new(1e-6, -2e-6, 1.5e-6);
        let dx = s.hand([q[0] + dq[0], q[1] + dq[1], q[2] + dq[2]]) - s.hand(q);
        assert!((s.torques(&f, q).dot(&dq) - f.dot(&dx)).abs() < 1e-10);
        // a hand stiffness maps to a symmetric joint stiffness with the same work
        let k = nalgebra::Matrix3::new(300.0, 20.0, 10.0, 20.0, 200.0, 5.0, 10.0, 5.0, 400.0);
        let kq = s.joint_impedance(&k, q);
        assert!((kq - kq.transpose()).norm() < 1e-9);
        let j = s.jacobian(q);
        let dxl = j * dq;
        assert!((dq.dot(&(kq * dq)) - dxl.dot(&(k * dxl))).abs() < 1e-15);
    }

    #[test]
    fn flexion_abduction_of_inverts_the_hand_x_z_and_refuses_out_of_reach() {
        let s = Shoulder {
            upper_arm_m: 0.3,
            forearm_m: 0.35,
            elbow_rad: FRAC_PI_2,
        };
        let q0 = [0.4, 0.3, -0.2];
        // the hand stays on a sphere: its 3 x 3 Jacobian has rank 2
        assert!(s.jacobian(q0).determinant().abs() < 1e-9);
        let target = s.hand([0.45, 0.27, -0.2]);
        let q = s.flexion_abduction_of(target[0], target[2], q0).unwrap();
        assert!((q[0] - 0.45).abs() < 1e-9 && (q[1] - 0.27).abs() < 1e-9 && q[2] == -0.2);
        // J_h^T F of the X-Z force does the same work as F on a small X-Z motion
        let jxz = s.jacobian_xz(q0);
        let dq = nalgebra::Vector2::new(1e-6, -2e-6);
        let h1 = s.hand([q0[0] + dq[0], q0[1] + dq[1], q0[2]]) - s.hand(q0);
        let f = nalgebra::Vector2::new(3.0, -2.0);
        assert!(((jxz.transpose() * f).dot(&dq) - (f[0] * h1[0] + f[1] * h1[2])).abs() < 1e-11);
        // farther than upper arm + forearm from the shoulder
        assert!(s.flexion_abduction_of(0.0, 2.0, q0).is_none());
    }
}
