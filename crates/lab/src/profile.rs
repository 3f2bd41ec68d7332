//! Perturbation profiles along a direction (seed 000 §II-B; seed 003 eq. (16)).
//!
//! Each profile gives the normalised path `s(t)` (0 at rest, 1 at the target
//! for point-to-point profiles) and its first two time derivatives, so that a
//! virtual subject's force can be computed from exact kinematics.

use serde::{Deserialize, Serialize};

/// Shape of the centre-out motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Profile {
    /// Third-order polynomial with zero end velocities (seed 000, seed 001).
    Cubic,
    /// Fifth-order minimum-jerk polynomial, zero end velocity and acceleration (seed 003 eq. (16)).
    Quintic,
    /// Trapezoidal velocity with 10 % acceleration and deceleration ramps (seed 000).
    Trapezoid,
    /// Two full periods of a sine of amplitude 1 around the start (seed 000).
    Sinusoid,
}

impl Profile {
    /// `(s, ds/dt, d2s/dt2)` at time `t` (s) of a motion lasting `duration` (s).
    /// Before 0 the path is at rest at 0; after `duration` it stays at its end value.
    pub fn eval(self, t: f64, duration: f64) -> (f64, f64, f64) {
        if t <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        if t >= duration {
            return (self.eval_inside(1.0, duration).0, 0.0, 0.0);
        }
        self.eval_inside(t / duration, duration)
    }

    /// Peak |displacement|, |velocity| and |acceleration| of a unit-amplitude
    /// motion of `duration`, on a grid of 4001 points including both ends
    /// (so a motion shorter than a sample period is still checked).
    pub fn peaks(self, duration: f64) -> (f64, f64, f64) {
        (0..=4000).fold((0.0f64, 0.0f64, 0.0f64), |(x, v, a), k| {
            let (px, pv, pa) = self.eval_inside(k as f64 / 4000.0, duration);
            (x.max(px.abs()), v.max(pv.abs()), a.max(pa.abs()))
        })
    }

    fn eval_inside(self, tau: f64, d: f64) -> (f64, f64, f64) {
        match self {
            Profile::Cubic => (
                3.0 * tau * tau - 2.0 * tau.powi(3),
                (6.0 * tau - 6.0 * tau * tau) / d,
                (6.0 - 12.0 * tau) / (d * d),
            ),
            Profile::Quintic => (
                10.0 * tau.powi(3) - 15.0 * tau.powi(4) + 6.0 * tau.powi(5),
                (30.0 * tau * tau - 60.0 * tau.powi(3) + 30.0 * tau.powi(4)) / d,
                (60.0 * tau - 180.0 * tau * tau + 120.0 * tau.powi(3)) / (d * d),
            ),
            Profile::Trapezoid => {
                // ramps of r = 10 % of the duration; peak velocity vmax = 1 / (1 - r) (normalised)
                let r = 0.1;
                let vmax = 1.0 / (1.0 - r);
                let acc = vmax / r;
                if tau < r {
                    (0.5 * acc * tau * tau, acc * tau / d, acc / (d * d))
                } else if tau <= 1.0 - r {
                    (0.5 * acc * r * r + vmax * (tau - r), vmax / d, 0.0)
                } else {
                    let u = 1.0 - tau;
                    (1.0 - 0.5 * acc * u * u, acc * u / d, -acc / (d * d))
                }
            }
            Profile::Sinusoid => {
                let w = 2.0 * std::f64::consts::TAU; // two periods over the duration
                (
                    (w * tau).sin(),
                    w * (w * tau).cos() / d,
                    -w * w * (w * tau).sin() / (d * d),
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boundary_conditions() {
        for p in [Profile::Cubic, Profile::Quintic, Profile::Trapezoid] {
            let (s0, v0, _) = p.eval_inside(0.0, 2.0);
            let (s1, v1, _) = p.eval_inside(1.0, 2.0);
            assert!(s0.abs() < 1e-12 && (s1 - 1.0).abs() < 1e-12, "{p:?}");
            assert!(v0.abs() < 1e-12 && v1.abs() < 1e-12, "{p:?}");
        }
        let (_, _, a0) = Profile::Quintic.eval_inside(0.0, 1.0);
        let (_, _, a1) = Profile::Quintic.eval_inside(1.0, 1.0);
        assert!(a0.abs() < 1e-12 && a1.abs() < 1e-12);
        let (s, _, _) = Profile::Sinusoid.eval_inside(1.0, 6.0);
        assert!(s.abs() < 1e-12);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        for p in [
            Profile::Cubic,
            Profile::Quintic,
            Profile::Trapezoid,
            Profile::Sinusoid,
        ] {
            let d = 3.0;
            let h = 1e-6;
            for t in [0.13, 0.9, 1.7, 2.95] {
                let (sm, vm, _) = p.eval(t - h, d);
                let (sp, vp, _) = p.eval(t + h, d);
                let (_, v, a) = p.eval(t, d);
                assert!(((sp - sm) / (2.0 * h) - v).abs() < 1e-6, "{p:?} v at {t}");
                assert!(((vp - vm) / (2.0 * h) - a).abs() < 1e-4, "{p:?} a at {t}");
            }
        }
    }
}
