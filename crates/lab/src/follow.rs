//! Limbs that follow a position command (issue 59): the planar two-link arm
//! (seed 003 eq. 9) and the 3-D end point (seed 000's M, B, K), for periodic
//! protocols with several channels. (One joint channel plays on the virtual
//! ankle, `crate::ankle`, which has a stretch reflex.)
//!
//! Each commanded coordinate is tracked by a second-order position servo
//! (natural frequency `servo_hz`, damping ratio 0.7), integrated with
//! semi-implicit Euler on a grid 10x finer than the samples, with the
//! command interpolated linearly between samples. The limb is held rigidly,
//! so it moves as the servo does, and the force or torque measured is its
//! dynamics along that motion:
//!
//! - planar arm: `τ = M(q) q'' + C(q, q') q' + D q' + K Δq + k2 Δq² + k3 Δq³ + τ0`,
//! - end point: `f = M a + B v + K Δx + k2 Δx² + k3 Δx³`,
//!
//! Δ the displacement from the posture; the quadratic and cubic terms act
//! per coordinate (0 unless a subject sets `quadratic` or `cubic`). The
//! arm's Coriolis and centripetal term is quadratic in the velocity: a small
//! even distortion of a real arm that the linear impedance does not hold.
//! Each sample is the mean of position and force over its sample period (an
//! integrating converter, as the ankle's), plus white position and force noise.

use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use limpid_core::arm::{coriolis, mass_matrix};
use limpid_core::{Error, Result};

/// Integration steps per sample.
const SUBSTEPS: usize = 10;

/// The servo and the sensors' white noise.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rig {
    /// Natural frequency of each coordinate's position servo (Hz).
    #[serde(default = "default_servo_hz")]
    pub servo_hz: f64,
    /// Standard deviation of white force noise (N, or N m for joints).
    pub force_noise_std: f64,
    /// Standard deviation of white position noise (m, or rad for joints).
    pub position_noise_std: f64,
}

fn default_servo_hz() -> f64 {
    30.0
}

impl Rig {
    /// End point: 0.2 N and 20 µm of white noise, a 30 Hz servo.
    pub fn endpoint() -> Self {
        Rig {
            servo_hz: default_servo_hz(),
            force_noise_std: 0.2,
            position_noise_std: 2e-5,
        }
    }

    /// Planar arm: 0.02 N m and 10 µrad of white noise (the planar
    /// simulator's), a 30 Hz servo.
    pub fn joint() -> Self {
        Rig {
            servo_hz: default_servo_hz(),
            force_noise_std: 0.02,
            position_noise_std: 1e-5,
        }
    }

    fn check(&self) -> Result<()> {
        let ok = self.servo_hz.is_finite()
            && self.servo_hz > 0.0
            && self.force_noise_std.is_finite()
            && self.force_noise_std >= 0.0
            && self.position_noise_std.is_finite()
            && self.position_noise_std >= 0.0;
        if ok {
            Ok(())
        } else {
            Err(Error::invalid(
                "rig",
                "servo_hz must be positive and the noise standard deviations at least 0",
            ))
        }
    }
}

/// A planar arm following a joint command (TOML subject of a two-channel joint protocol).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanarFollower {
    /// Base inertial parameters ξ1..ξ3 (kg m^2, seed 003 eq. 9).
    pub xi: [f64; 3],
    /// Joint stiffness K (N m/rad).
    pub stiffness: [[f64; 2]; 2],
    /// Joint damping D (N m s/rad).
    pub damping: [[f64; 2]; 2],
    /// Posture q0 (rad).
    #[serde(default = "seed003_posture")]
    pub q0: [f64; 2],
    /// Joint torques at the posture (N m).
    #[serde(default)]
    pub tau0: [f64; 2],
    /// k2 per joint (N m/rad^2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quadratic: Option<[f64; 2]>,
    /// k3 per joint (N m/rad^3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cubic: Option<[f64; 2]>,
    /// Servo and noise.
    #[serde(default = "Rig::joint")]
    pub rig: Rig,
}

fn seed003_posture() -> [f64; 2] {
    crate::planar::PlanarSubject::seed003().q0
}

impl Default for PlanarFollower {
    /// Seed 003's arm (the `ex_joint_180` truth) at its posture, without a reflex.
    fn default() -> Self {
        let s = crate::planar::PlanarSubject::seed003();
        let rows = |m: Matrix2<f64>| [[m[(0, 0)], m[(0, 1)]], [m[(1, 0)], m[(1, 1)]]];
        PlanarFollower {
            xi: s.xi,
            stiffness: rows(s.stiffness),
            damping: rows(s.damping),
            q0: s.q0,
            tau0: s.tau0,
            quadratic: None,
            cubic: None,
            rig: Rig::joint(),
        }
    }
}

impl PlanarFollower {
    /// The joint inertia at the posture, M(q0) (kg m^2).
    pub fn inertia_at_posture(&self) -> Matrix2<f64> {
        mass_matrix(self.q0[1], self.xi)
    }
}

/// A 3-D end point following a Cartesian command (TOML subject of an end-point protocol).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EndpointFollower {
    /// M (kg).
    pub inertia: [[f64; 3]; 3],
    /// B (N s/m).
    pub damping: [[f64; 3]; 3],
    /// K (N/m).
    pub stiffness: [[f64; 3]; 3],
    /// The posture (m).
    #[serde(default = "seed000_start")]
    pub equilibrium: [f64; 3],
    /// k2 per axis (N/m^2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quadratic: Option<[f64; 3]>,
    /// k3 per axis (N/m^3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cubic: Option<[f64; 3]>,
    /// Servo and noise.
    #[serde(default = "Rig::endpoint")]
    pub rig: Rig,
}

fn seed000_start() -> [f64; 3] {
    let s = &crate::seed000_subject1()[0].start;
    [s.x, s.y, s.z]
}

impl Default for EndpointFollower {
    /// Seed 000 Table I, subject 1 at start point S1.
    fn default() -> Self {
        let p = &crate::seed000_subject1()[0];
        let rows = |m: &Matrix3<f64>| std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]));
        EndpointFollower {
            inertia: rows(&p.inertia),
            damping: rows(&p.damping),
            stiffness: rows(&p.stiffness),
            equilibrium: seed000_start(),
            quadratic: None,
            cubic: None,
            rig: Rig::endpoint(),
        }
    }
}

/// What the rig recorded: absolute positions and the forces on the limb, per coordinate.
#[derive(Debug, Clone)]
pub struct Followed {
    /// Position per coordinate (the posture plus the displacement; m or rad).
    pub position: Vec<Vec<f64>>,
    /// Force or torque on the limb per coordinate (N or N m).
    pub force: Vec<Vec<f64>>,
}

/// The elastic force beyond the linear stiffness: k2 d² + k3 d³ per coordinate.
fn nonlinear(d: f64, k2: Option<f64>, k3: Option<f64>) -> f64 {
    (k2.unwrap_or(0.0) + k3.unwrap_or(0.0) * d) * d * d
}

/// The planar arm following `command` (displacements from `q0` per joint, rad, one per sample).
pub fn follow_planar(
    s: &PlanarFollower,
    command: &[Vec<f64>; 2],
    rate_hz: f64,
    seed: u64,
) -> Result<Followed> {
    let m2 = |a: &[[f64; 2]; 2]| Matrix2::from_fn(|r, c| a[r][c]);
    let (k, d) = (m2(&s.stiffness), m2(&s.damping));
    let (q0, tau0) = (Vector2::from(s.q0), Vector2::from(s.tau0));
    let offset = s.q0.to_vec();
    follow(
        command,
        &offset,
        rate_hz,
        &s.rig,
        seed,
        |dq, qd, qdd, out: &mut [f64]| {
            let q = q0 + Vector2::new(dq[0], dq[1]);
            let dq = Vector2::new(dq[0], dq[1]);
            let (qd, qdd) = (Vector2::new(qd[0], qd[1]), Vector2::new(qdd[0], qdd[1]));
            let tau = mass_matrix(q[1], s.xi) * qdd
                + coriolis(q[1], [qd[0], qd[1]], s.xi)
                + d * qd
                + k * dq
                + tau0;
            for j in 0..2 {
                out[j] =
                    tau[j] + nonlinear(dq[j], s.quadratic.map(|v| v[j]), s.cubic.map(|v| v[j]));
            }
        },
    )
}

/// The end point following `command` (displacements from the equilibrium per axis, m).
pub fn follow_endpoint(
    s: &EndpointFollower,
    command: &[Vec<f64>; 3],
    rate_hz: f64,
    seed: u64,
) -> Result<Followed> {
    let m3 = |a: &[[f64; 3]; 3]| Matrix3::from_fn(|r, c| a[r][c]);
    let (m, b, k) = (m3(&s.inertia), m3(&s.damping), m3(&s.stiffness));
    follow(
        command,
        &s.equilibrium,
        rate_hz,
        &s.rig,
        seed,
        |dx, v, a, out: &mut [f64]| {
            let (dx, v, a) = (
                Vector3::new(dx[0], dx[1], dx[2]),
                Vector3::new(v[0], v[1], v[2]),
                Vector3::new(a[0], a[1], a[2]),
            );
            let f = m * a + b * v + k * dx;
            for j in 0..3 {
                out[j] = f[j] + nonlinear(dx[j], s.quadratic.map(|v| v[j]), s.cubic.map(|v| v[j]));
            }
        },
    )
}

/// Each coordinate of `command` through the servo; `force(displacement,
/// velocity, acceleration, out)` writes the limb's force along that motion.
fn follow(
    command: &[Vec<f64>],
    posture: &[f64],
    rate_hz: f64,
    rig: &Rig,
    seed: u64,
    mut force: impl FnMut(&[f64], &[f64], &[f64], &mut [f64]),
) -> Result<Followed> {
    rig.check()?;
    let dims = command.len();
    let n = command.first().map_or(0, Vec::len);
    if n == 0
        || command
            .iter()
            .any(|c| c.len() != n || c.iter().any(|v| !v.is_finite()))
    {
        return Err(Error::invalid(
            "command",
            "expected finite displacements, as many for every coordinate",
        ));
    }
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(Error::invalid("sample rate", "expected a positive rate"));
    }
    let h = 1.0 / (rate_hz * SUBSTEPS as f64);
    let w = 2.0 * std::f64::consts::PI * rig.servo_hz;
    let zeta = 0.7;
    let mut rng = StdRng::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).expect("the unit normal is valid");
    let (mut q, mut qd, mut qdd) = (vec![0.0; dims], vec![0.0; dims], vec![0.0; dims]);
    let (mut f, mut v_now) = (vec![0.0; dims], vec![0.0; dims]);
    let (mut q_sum, mut f_sum) = (vec![0.0; dims], vec![0.0; dims]);
    let mut position: Vec<Vec<f64>> = (0..dims).map(|_| Vec::with_capacity(n)).collect();
    let mut forces: Vec<Vec<f64>> = (0..dims).map(|_| Vec::with_capacity(n)).collect();
    for k in 0..n * SUBSTEPS {
        let (i, frac) = (k / SUBSTEPS, (k % SUBSTEPS) as f64 / SUBSTEPS as f64);
        for j in 0..dims {
            let u = command[j][i] * (1.0 - frac) + command[j][(i + 1).min(n - 1)] * frac;
            qdd[j] = w * w * (u - q[j]) - 2.0 * zeta * w * qd[j];
        }
        // semi-implicit Euler's velocity lags its position by half a step:
        // taken as it is, B h/2 of the damping would read as less inertia
        for j in 0..dims {
            v_now[j] = qd[j] + 0.5 * h * qdd[j];
        }
        force(&q, &v_now, &qdd, &mut f);
        for j in 0..dims {
            q_sum[j] += q[j];
            f_sum[j] += f[j];
        }
        if k % SUBSTEPS == SUBSTEPS - 1 {
            for j in 0..dims {
                position[j].push(
                    posture[j]
                        + q_sum[j] / SUBSTEPS as f64
                        + rig.position_noise_std * unit.sample(&mut rng),
                );
                forces[j]
                    .push(f_sum[j] / SUBSTEPS as f64 + rig.force_noise_std * unit.sample(&mut rng));
                (q_sum[j], f_sum[j]) = (0.0, 0.0);
            }
        }
        // semi-implicit Euler on the fine grid
        for j in 0..dims {
            qd[j] += h * qdd[j];
            q[j] += h * qd[j];
        }
    }
    Ok(Followed {
        position,
        force: forces,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sine(n: usize, rate: f64, hz: f64, amplitude: f64) -> Vec<f64> {
        (0..n)
            .map(|i| amplitude * (2.0 * std::f64::consts::PI * hz * i as f64 / rate).sin())
            .collect()
    }

    #[test]
    fn a_noise_free_end_point_at_rest_needs_only_its_stiffness() {
        // a slow ramp-free command: the force is K d to the servo's lag
        let s = EndpointFollower {
            rig: Rig {
                force_noise_std: 0.0,
                position_noise_std: 0.0,
                ..Rig::endpoint()
            },
            ..EndpointFollower::default()
        };
        let n = 4000;
        let command = [vec![0.01; n], vec![0.0; n], vec![0.0; n]];
        let out = follow_endpoint(&s, &command, 1000.0, 1).unwrap();
        // settled: x moved by 1 cm, the force is the first column of K times it
        let last = n - 1;
        assert!((out.position[0][last] - s.equilibrium[0] - 0.01).abs() < 1e-9);
        for r in 0..3 {
            let want = s.stiffness[r][0] * 0.01;
            assert!(
                (out.force[r][last] - want).abs() < 1e-6 * want.abs().max(1.0),
                "f{r} {} vs {want}",
                out.force[r][last]
            );
        }
    }

    #[test]
    fn a_cubic_joint_adds_its_cube_and_the_arm_starts_at_its_posture() {
        let mut s = PlanarFollower {
            rig: Rig {
                force_noise_std: 0.0,
                position_noise_std: 0.0,
                ..Rig::joint()
            },
            ..PlanarFollower::default()
        };
        let n = 3000;
        let command = [vec![0.05; n], vec![0.0; n]];
        let linear = follow_planar(&s, &command, 1000.0, 1).unwrap();
        s.cubic = Some([2000.0, 0.0]);
        let cubic = follow_planar(&s, &command, 1000.0, 1).unwrap();
        assert!((linear.position[1][0] - s.q0[1]).abs() < 1e-9);
        let extra = cubic.force[0][n - 1] - linear.force[0][n - 1];
        assert!((extra - 2000.0 * 0.05f64.powi(3)).abs() < 1e-6, "{extra}");
        // the torque at rest is K dq + tau0
        let want = s.stiffness[1][0] * 0.05 + s.tau0[1];
        assert!((linear.force[1][n - 1] - want).abs() < 1e-6);
    }

    #[test]
    fn the_servo_follows_a_slow_sine_and_the_noise_has_its_size() {
        let s = EndpointFollower::default();
        let n = 20_000;
        let command = [sine(n, 1000.0, 1.0, 0.005), vec![0.0; n], vec![0.0; n]];
        let out = follow_endpoint(&s, &command, 1000.0, 3).unwrap();
        // y is commanded to rest: its spread is the position noise
        let y = &out.position[1];
        let mean = y.iter().sum::<f64>() / n as f64;
        let sd = (y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
        assert!((sd / s.rig.position_noise_std - 1.0).abs() < 0.05, "{sd}");
        // x follows the 1 Hz sine to within the servo's lag
        let peak = out.position[0]
            .iter()
            .fold(0.0f64, |m, v| m.max((v - s.equilibrium[0]).abs()));
        assert!((peak / 0.005 - 1.0).abs() < 0.02, "{peak}");
    }

    #[test]
    fn bad_commands_and_rigs_are_refused() {
        let s = EndpointFollower::default();
        let bad = [vec![0.0, f64::NAN], vec![0.0; 2], vec![0.0; 2]];
        assert!(follow_endpoint(&s, &bad, 1000.0, 1).is_err());
        let ragged = [vec![0.0; 3], vec![0.0; 2], vec![0.0; 2]];
        assert!(follow_endpoint(&s, &ragged, 1000.0, 1).is_err());
        let rig = EndpointFollower {
            rig: Rig {
                servo_hz: 0.0,
                ..Rig::endpoint()
            },
            ..EndpointFollower::default()
        };
        let ok = [vec![0.0; 2], vec![0.0; 2], vec![0.0; 2]];
        assert!(follow_endpoint(&rig, &ok, 1000.0, 1).is_err());
    }
}
