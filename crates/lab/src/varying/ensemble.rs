//! The ensemble subject: impedance that changes in time within a repeated
//! task (Kearney & MacNeil's ensembles), and its truth.

use super::{ACTUATOR_DAMPING, SUBSTEPS};
use limpid_core::arm::{coriolis, mass_matrix, Arm};
use limpid_core::truth::{About, VaryingTruth, VaryingTruthPoint};
use limpid_core::{Error, Matrix, Recording, Result};
use nalgebra::{Matrix2, Vector2};
use rand::rngs::StdRng;
use rand::Rng;
use rand::SeedableRng;
use rand_distr::Distribution;
use rand_distr::Normal;
use serde::{Deserialize, Serialize};
/// A raised-cosine change of impedance in time: `1 + gain × bump(t)`, the
/// bump 1 at `centre_s` and 0 beyond `± width_s` (so `width_s` is its full
/// width at half height).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeChange {
    /// Centre of the change (s after the repetition's start).
    pub centre_s: f64,
    /// Full width at half height (s).
    pub width_s: f64,
    /// Relative change of stiffness at the centre (1.0: doubles).
    pub stiffness_gain: f64,
    /// Relative change of damping at the centre.
    pub damping_gain: f64,
}

impl TimeChange {
    /// `bump(t)` in 0..=1.
    pub fn bump(&self, t: f64) -> f64 {
        let u = (t - self.centre_s) / self.width_s;
        if u.abs() >= 1.0 {
            0.0
        } else {
            0.5 * (1.0 + (std::f64::consts::PI * u).cos())
        }
    }
}

/// The body the ensemble subject's impedance acts on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EnsembleBody {
    /// One joint of inertia `inertia` (kg m^2) that moves by `movement_rad`
    /// (minimum jerk) during the middle 60 % of each repetition.
    Joint {
        /// I (kg m^2).
        inertia: f64,
        /// Amplitude of the repeated movement (rad).
        movement_rad: f64,
    },
    /// A planar 2-link arm holding a posture (seed 003's rigid-body model).
    Planar {
        /// Upper arm and forearm (m).
        link_lengths: [f64; 2],
        /// Base inertial parameters ξ1..ξ3 (kg m^2).
        inertial_parameters: [f64; 3],
        /// Shoulder and elbow angles held (rad).
        posture: [f64; 2],
        /// Record the hand (`x, y, fx, fy`) instead of the joints.
        endpoint: bool,
    },
}

/// A subject whose impedance changes during each repetition of a task.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnsembleSubject {
    /// The body.
    pub body: EnsembleBody,
    /// Joint stiffness outside the change (N m/rad), d x d.
    pub stiffness: Vec<Vec<f64>>,
    /// Joint damping outside the change (N m s/rad), d x d.
    pub damping: Vec<Vec<f64>>,
    /// How K and B change in time.
    pub change: TimeChange,
}

impl EnsembleSubject {
    /// One joint (I 0.015 kg m^2, B 0.8, K 60) whose stiffness doubles and
    /// damping rises by half over 150 ms in the middle of a 1.2 s repetition
    /// with a 0.3 rad movement.
    pub fn joint() -> Self {
        EnsembleSubject {
            body: EnsembleBody::Joint {
                inertia: 0.015,
                movement_rad: 0.3,
            },
            stiffness: vec![vec![60.0]],
            damping: vec![vec![0.8]],
            change: TimeChange {
                centre_s: 0.6,
                width_s: 0.15,
                stiffness_gain: 1.0,
                damping_gain: 0.5,
            },
        }
    }

    /// A planar arm at seed 003's posture whose joint stiffness rises by 80 %.
    pub fn planar(endpoint: bool) -> Self {
        EnsembleSubject {
            body: EnsembleBody::Planar {
                link_lengths: [0.3, 0.35],
                inertial_parameters: [0.25, 0.06, 0.05],
                posture: [0.6, 1.6],
                endpoint,
            },
            stiffness: vec![vec![15.0, 4.0], vec![4.0, 10.0]],
            damping: vec![vec![0.8, 0.2], vec![0.2, 0.6]],
            change: TimeChange {
                centre_s: 0.6,
                width_s: 0.2,
                stiffness_gain: 0.8,
                damping_gain: 0.4,
            },
        }
    }

    /// Degrees of freedom.
    pub fn dof(&self) -> usize {
        match self.body {
            EnsembleBody::Joint { .. } => 1,
            EnsembleBody::Planar { .. } => 2,
        }
    }

    fn check(&self) -> Result<()> {
        let d = self.dof();
        let square = |m: &Vec<Vec<f64>>| {
            m.len() == d
                && m.iter()
                    .all(|r| r.len() == d && r.iter().all(|v| v.is_finite()))
        };
        let c = &self.change;
        if !square(&self.stiffness) || !square(&self.damping) {
            return Err(Error::invalid(
                "ensemble subject",
                format!("stiffness and damping must be {d} x {d} finite matrices"),
            ));
        }
        if !(c.width_s > 0.0
            && c.centre_s.is_finite()
            && c.stiffness_gain > -1.0
            && c.damping_gain > -1.0
            && c.stiffness_gain.is_finite()
            && c.damping_gain.is_finite())
        {
            return Err(Error::invalid(
                "ensemble subject",
                "the change needs a positive width and gains above -1",
            ));
        }
        Ok(())
    }

    /// The truth at `t` s into a repetition, in the recorded coordinates:
    /// (inertia, damping, stiffness), each d x d.
    pub fn truth_at(&self, t: f64) -> [Vec<Vec<f64>>; 3] {
        let bump = self.change.bump(t);
        let scale = |m: &Vec<Vec<f64>>, g: f64| -> Vec<Vec<f64>> {
            m.iter()
                .map(|r| r.iter().map(|v| v * (1.0 + g * bump)).collect())
                .collect()
        };
        let k = scale(&self.stiffness, self.change.stiffness_gain);
        let b = scale(&self.damping, self.change.damping_gain);
        match self.body {
            EnsembleBody::Joint { inertia, .. } => [vec![vec![inertia]], b, k],
            EnsembleBody::Planar {
                link_lengths,
                inertial_parameters,
                posture,
                endpoint,
            } => {
                let m = mass_matrix(posture[1], inertial_parameters);
                let to = |v: &Vec<Vec<f64>>| Matrix2::new(v[0][0], v[0][1], v[1][0], v[1][1]);
                let back =
                    |m: Matrix2<f64>| vec![vec![m[(0, 0)], m[(0, 1)]], vec![m[(1, 0)], m[(1, 1)]]];
                if endpoint {
                    let arm = Arm {
                        l1: link_lengths[0],
                        l2: link_lengths[1],
                        shoulder: [0.0, 0.0],
                    };
                    let jinv = arm
                        .jacobian(posture)
                        .try_inverse()
                        .unwrap_or_else(Matrix2::zeros);
                    let map = |m: Matrix2<f64>| jinv.transpose() * m * jinv;
                    [back(map(m)), back(map(to(&b))), back(map(to(&k)))]
                } else {
                    [back(m), b, k]
                }
            }
        }
    }
}

/// The perturbation and recording of an ensemble experiment.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EnsembleExperiment {
    /// Repetitions of the task.
    pub repetitions: usize,
    /// Length of one repetition (s).
    pub duration_s: f64,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Half-swing of the binary command (rad).
    pub amplitude_rad: f64,
    /// Mean interval between switches (s); the instants are random.
    pub switch_s: f64,
    /// Actuator bandwidth (Hz).
    pub actuator_hz: f64,
    /// White torque noise (N m).
    pub torque_noise_nm: f64,
    /// White position noise (rad, or m for end-point recordings).
    pub position_noise: f64,
}

impl Default for EnsembleExperiment {
    fn default() -> Self {
        EnsembleExperiment {
            repetitions: 100,
            duration_s: 1.2,
            rate_hz: 1000.0,
            amplitude_rad: 0.02,
            switch_s: 0.05,
            actuator_hz: 20.0,
            torque_noise_nm: 0.05,
            position_noise: 0.0,
        }
    }
}

/// A random binary command through a second-order actuator: position,
/// velocity and acceleration at every sample (one per coordinate).
fn servo_path(
    n: usize,
    fs: f64,
    amplitude: f64,
    switch_s: f64,
    actuator_hz: f64,
    rng: &mut StdRng,
) -> [Vec<f64>; 3] {
    let h = 1.0 / (fs * SUBSTEPS as f64);
    let w = 2.0 * std::f64::consts::PI * actuator_hz;
    let p_switch = (h / switch_s).min(1.0);
    let mut u = if rng.random::<bool>() {
        amplitude
    } else {
        -amplitude
    };
    let (mut p, mut pd) = (0.0f64, 0.0f64);
    let mut out = [
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    ];
    for k in 0..n * SUBSTEPS {
        if rng.random::<f64>() < p_switch {
            u = -u;
        }
        let pdd = w * w * (u - p) - 2.0 * ACTUATOR_DAMPING * w * pd;
        if k % SUBSTEPS == 0 {
            out[0].push(p);
            out[1].push(pd);
            out[2].push(pdd);
        }
        pd += h * pdd;
        p += h * pd;
    }
    out
}

/// Minimum-jerk movement of amplitude `a` over the middle 60 % of `[0, T]`:
/// (position, velocity, acceleration) at `t`.
fn movement(a: f64, total: f64, t: f64) -> [f64; 3] {
    let (t0, d) = (0.2 * total, 0.6 * total);
    let s = ((t - t0) / d).clamp(0.0, 1.0);
    if s <= 0.0 || s >= 1.0 {
        return [if s >= 1.0 { a } else { 0.0 }, 0.0, 0.0];
    }
    let p = 10.0 * s.powi(3) - 15.0 * s.powi(4) + 6.0 * s.powi(5);
    let v = (30.0 * s.powi(2) - 60.0 * s.powi(3) + 30.0 * s.powi(4)) / d;
    let acc = (60.0 * s - 180.0 * s.powi(2) + 120.0 * s.powi(3)) / (d * d);
    [a * p, a * v, a * acc]
}

impl EnsembleExperiment {
    /// Refuse settings that cannot be simulated.
    pub fn validate(&self) -> Result<()> {
        check_experiment(self)
    }
}

fn check_experiment(e: &EnsembleExperiment) -> Result<()> {
    if e.repetitions < 1 {
        return Err(Error::invalid(
            "ensemble experiment",
            "repetitions = 0: expected at least 1",
        ));
    }
    // a rate that holds the actuator's motion and a switch several samples
    // long (rate_hz = 1 simulated one sample a second; issue 76)
    crate::validate::fields_within(
        "ensemble experiment",
        &[
            ("rate_hz", e.rate_hz, 50.0, 1e5),
            ("duration_s", e.duration_s, 4.0 / e.rate_hz, 1e4),
            ("amplitude_rad", e.amplitude_rad, 1e-6, 1.0),
            ("actuator_hz", e.actuator_hz, 0.1, e.rate_hz / 4.0),
            ("switch_s", e.switch_s, 2.0 / e.rate_hz, 1e3),
            ("torque_noise_nm", e.torque_noise_nm, 0.0, 1e3),
            ("position_noise", e.position_noise, 0.0, 0.1),
        ],
    )?;
    crate::validate::check_size(
        e.repetitions as f64 * e.duration_s * e.rate_hz,
        "ensemble recording",
    )
}

/// Simulate the ensemble experiment: columns `t`, `trial` (1..=R), and
/// `q1[, q2]`, `tau1[, tau2]` (or `x, y, fx, fy` for an end-point planar
/// recording). Repetitions follow each other in time, 0.5 s apart.
pub fn simulate_ensemble(
    s: &EnsembleSubject,
    e: &EnsembleExperiment,
    seed: u64,
) -> Result<Recording> {
    s.check()?;
    check_experiment(e)?;
    let d = s.dof();
    let n = (e.duration_s * e.rate_hz).round() as usize;
    let mut rng = StdRng::seed_from_u64(seed);
    let torque_noise = Normal::new(0.0, e.torque_noise_nm)
        .map_err(|err| Error::invalid("torque noise", err.to_string()))?;
    let position_noise = Normal::new(0.0, e.position_noise)
        .map_err(|err| Error::invalid("position noise", err.to_string()))?;
    let total = e.repetitions * n;
    let mut t_col = Vec::with_capacity(total);
    let mut trial = Vec::with_capacity(total);
    let mut pos = vec![Vec::with_capacity(total); d];
    let mut frc = vec![Vec::with_capacity(total); d];
    let period = e.duration_s + 0.5;
    for r in 0..e.repetitions {
        let paths: Vec<[Vec<f64>; 3]> = (0..d)
            .map(|_| {
                servo_path(
                    n,
                    e.rate_hz,
                    e.amplitude_rad,
                    e.switch_s,
                    e.actuator_hz,
                    &mut rng,
                )
            })
            .collect();
        #[allow(clippy::needless_range_loop)] // i indexes d paths of three signals each
        for i in 0..n {
            let t = i as f64 / e.rate_hz;
            let [_, b, k] = s.truth_at_joint(t);
            t_col.push(r as f64 * period + t);
            trial.push((r + 1) as f64);
            match s.body {
                EnsembleBody::Joint {
                    inertia,
                    movement_rad,
                } => {
                    let [m0, m1, m2] = movement(movement_rad, e.duration_s, t);
                    let [p, pd, pdd] = [paths[0][0][i], paths[0][1][i], paths[0][2][i]];
                    let tau = inertia * (m2 + pdd) + b[(0, 0)] * (m1 + pd) + k[(0, 0)] * p;
                    pos[0].push(m0 + p + position_noise.sample(&mut rng));
                    frc[0].push(tau + torque_noise.sample(&mut rng));
                }
                EnsembleBody::Planar {
                    link_lengths,
                    inertial_parameters,
                    posture,
                    endpoint,
                } => {
                    let q = [posture[0] + paths[0][0][i], posture[1] + paths[1][0][i]];
                    let qd = Vector2::new(paths[0][1][i], paths[1][1][i]);
                    let qdd = Vector2::new(paths[0][2][i], paths[1][2][i]);
                    let dq = Vector2::new(paths[0][0][i], paths[1][0][i]);
                    let tau = mass_matrix(q[1], inertial_parameters) * qdd
                        + coriolis(q[1], [qd[0], qd[1]], inertial_parameters)
                        + b * qd
                        + k * dq;
                    let (p, f) = if endpoint {
                        let arm = Arm {
                            l1: link_lengths[0],
                            l2: link_lengths[1],
                            shoulder: [0.0, 0.0],
                        };
                        let x = arm.fk(q);
                        let jt_inv = arm
                            .jacobian(q)
                            .transpose()
                            .try_inverse()
                            .ok_or_else(|| Error::invalid("posture", "the arm is singular"))?;
                        (Vector2::new(x[0], x[1]), jt_inv * tau)
                    } else {
                        (Vector2::new(q[0], q[1]), tau)
                    };
                    for a in 0..2 {
                        pos[a].push(p[a] + position_noise.sample(&mut rng));
                        frc[a].push(f[a] + torque_noise.sample(&mut rng));
                    }
                }
            }
        }
    }
    let (pn, fn_): (Vec<String>, Vec<String>) = match s.body {
        EnsembleBody::Planar { endpoint: true, .. } => {
            (vec!["x".into(), "y".into()], vec!["fx".into(), "fy".into()])
        }
        _ => (
            (1..=d).map(|k| format!("q{k}")).collect(),
            (1..=d).map(|k| format!("tau{k}")).collect(),
        ),
    };
    let mut names = vec!["t".to_string(), "trial".to_string()];
    names.extend(pn);
    names.extend(fn_);
    let mut columns = vec![t_col, trial];
    columns.extend(pos);
    columns.extend(frc);
    Recording::new("virtual ensemble", names, columns, 2)
}

impl EnsembleSubject {
    /// Joint-space damping and stiffness at `t` (for the simulation).
    fn truth_at_joint(&self, t: f64) -> [Matrix2<f64>; 3] {
        let bump = self.change.bump(t);
        let m = |v: &Vec<Vec<f64>>, g: f64| {
            let s = 1.0 + g * bump;
            let at = |i: usize, j: usize| v.get(i).and_then(|r| r.get(j)).copied().unwrap_or(0.0);
            Matrix2::new(at(0, 0), at(0, 1), at(1, 0), at(1, 1)) * s
        };
        [
            Matrix2::zeros(),
            m(&self.damping, self.change.damping_gain),
            m(&self.stiffness, self.change.stiffness_gain),
        ]
    }
}

/// The ensemble subject's truth every `step_s` over one repetition.
pub fn ensemble_truth(s: &EnsembleSubject, e: &EnsembleExperiment, step_s: f64) -> VaryingTruth {
    let steps = (e.duration_s / step_s).floor() as usize;
    let m = |rows: Vec<Vec<f64>>| Matrix::from_rows(&rows).expect("square truth");
    VaryingTruth {
        about: About {
            notes: vec![format!(
                "ensemble of {} position-perturbed repetitions of {} s; K and B change by a raised cosine {} s wide at {} s",
                e.repetitions, e.duration_s, s.change.width_s, s.change.centre_s
            )],
            ..About::default()
        },
        schedule: "time since trial start".into(),
        reflex_delay_s: None,
        points: (0..=steps)
            .map(|i| {
                let t = i as f64 * step_s;
                let [inertia, damping, stiffness] = s.truth_at(t);
                VaryingTruthPoint {
                    sigma: t,
                    stiffness: m(stiffness),
                    damping: m(damping),
                    inertia: m(inertia),
                    reflex_gain: None,
                }
            })
            .collect(),
    }
}
