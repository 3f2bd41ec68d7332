//! Planar two-link arm (seed 003 §II, eq. (9)): kinematics with q1 the
//! shoulder angle and q2 the relative elbow angle, and the rigid-body terms
//! with base inertial parameters ξ: M(q, ξ) and C(q, q', ξ) q'. Shared by the
//! estimator (limpid-ident) and the virtual lab (limpid-lab).

use nalgebra::{Matrix2, Vector2};
use serde::Serialize;

/// Planar arm geometry: link lengths (m) and shoulder position (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Arm {
    pub l1: f64,
    pub l2: f64,
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
