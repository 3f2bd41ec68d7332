//! Virtual planar-arm experiments (seed 003 §IV-B): a robot holds the arm at
//! q0, waits, then imposes a quintic (minimum-jerk, eq. (16)) joint-space
//! displacement in one of six directions over the interpolation interval T_k
//! and holds. The torque the robot applies is the inverse dynamics of eq. (9)
//! plus the baseline τ0, with an optional reflex: after a latency the
//! stiffness and damping are scaled (seed 003 §I-B: reflexes act after
//! 25-110 ms). Each trial window holds `rest_s` before the onset and `after_s`
//! after it.
//!
//! With a [`Cuff`] the robot no longer moves the arm itself: it moves a cuff
//! (seed 003 §IV-A: "connected to the human arm via a plastic cuff") that
//! holds the forearm through soft tissue, a spring and damper in series.
//! The arm's motion then follows from its dynamics (eq. (9) with the cuff's
//! torque as input, integrated at 20 kHz), and the recording holds what the
//! robot measures: its own position and the force in the cuff. The rigid
//! model of seed 003 does not describe that until the cuff's fast dynamics
//! have passed: the criteria then need windows of a few hundred ms, as the
//! seed's did (`limpid reproduce 003`), where a rigid arm meets them within
//! 100 ms.

use nalgebra::{Matrix2, Vector2};
use rand::{rngs::StdRng, seq::SliceRandom, SeedableRng};
use rand_distr::{Distribution, Normal};

use crate::profile::Profile;
use limpid_core::arm::{coriolis, mass_matrix};
use limpid_core::{Recording, Result};

/// A reflex: after `latency_s`, K and D are multiplied by `1 + gain`.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Reflex {
    /// Delay from the onset to the reflex (s).
    pub latency_s: f64,
    /// Relative change of K after the latency.
    pub stiffness_gain: f64,
    /// Relative change of D after the latency.
    pub damping_gain: f64,
}

/// [`Cuff::seed003`]'s stiffness (N/m) and damping (N s/m) at the hand.
pub const SEED003_CUFF: (f64, f64) = (2000.0, 20.0);

/// Soft tissue between the robot's cuff and the arm: a spring and damper in
/// series, in joint space.
#[derive(Debug, Clone, Copy)]
pub struct Cuff {
    /// Joint-space stiffness of the tissue (N m/rad).
    pub stiffness: Matrix2<f64>,
    /// Joint-space damping of the tissue (N m s/rad).
    pub damping: Matrix2<f64>,
}

impl Cuff {
    /// An isotropic tissue at the hand, `stiffness_n_per_m` and
    /// `damping_ns_per_m`, seen in joint space through the arm's Jacobian at
    /// `q0` (J^T k J; small motions).
    pub fn at_hand(
        arm: &limpid_core::arm::Arm,
        q0: [f64; 2],
        stiffness_n_per_m: f64,
        damping_ns_per_m: f64,
    ) -> Self {
        let j = arm.jacobian(q0);
        let jtj = j.transpose() * j;
        Cuff {
            stiffness: jtj * stiffness_n_per_m,
            damping: jtj * damping_ns_per_m,
        }
    }

    /// Seed 003's plastic cuff on the forearm: 2000 N/m and 20 N s/m at the
    /// hand. The seeds give no value; this is an order of magnitude for soft
    /// tissue pressed by a rigid cuff (hand-held interfaces are stiffer, a
    /// loose strap softer); `limpid reproduce 003` states it.
    pub fn seed003(arm: &limpid_core::arm::Arm, q0: [f64; 2]) -> Self {
        Cuff::at_hand(arm, q0, SEED003_CUFF.0, SEED003_CUFF.1)
    }
}

/// A planar subject in joint space.
#[derive(Debug, Clone)]
pub struct PlanarSubject {
    /// Base inertial parameters ξ1..ξ3 (kg m^2).
    pub xi: [f64; 3],
    /// Joint stiffness K (N m/rad).
    pub stiffness: Matrix2<f64>,
    /// Joint damping D (N m s/rad).
    pub damping: Matrix2<f64>,
    /// Posture q0 (rad).
    pub q0: [f64; 2],
    /// Joint torques at q0 (N m).
    pub tau0: [f64; 2],
    /// A stretch reflex, if any.
    pub reflex: Option<Reflex>,
    /// Soft tissue between cuff and arm; `None`: the robot moves the arm rigidly.
    pub cuff: Option<Cuff>,
}

impl PlanarSubject {
    /// The `ex_joint_180` truth of the outside examples (`planar`) (seed 003's posture q0 = (0.08, 1.0)).
    pub fn seed003() -> Self {
        PlanarSubject {
            xi: [0.356, 0.143, 0.147],
            stiffness: Matrix2::new(37.95, 9.31, 9.31, 10.14),
            damping: Matrix2::new(1.854, 0.590, 0.590, 1.435),
            q0: [0.08, 1.0],
            tau0: [0.37, 0.41],
            reflex: None,
            cuff: None,
        }
    }
}

/// The perturbation protocol.
#[derive(Debug, Clone)]
pub struct PlanarProtocol {
    /// Displacements Δq_f (rad), seed 003: (±0.05, 0), (0, ±0.05), ±(0.05, -0.05).
    pub directions: Vec<[f64; 2]>,
    /// Number of perturbations.
    pub trials: usize,
    /// Interpolation interval T_k (s).
    pub interpolation_s: f64,
    /// Rest recorded before each onset (s).
    pub rest_s: f64,
    /// Recorded after each onset (s).
    pub after_s: f64,
    /// Sample rate (Hz).
    pub sample_rate: f64,
}

impl PlanarProtocol {
    /// Seed 003: 30 trials over the six directions, T_k = 200 ms, 0.3 s rest, 0.45 s after onset, 1 kHz.
    pub fn seed003() -> Self {
        PlanarProtocol {
            directions: vec![
                [0.05, 0.0],
                [-0.05, 0.0],
                [0.0, 0.05],
                [0.0, -0.05],
                [0.05, -0.05],
                [-0.05, 0.05],
            ],
            trials: 30,
            interpolation_s: 0.2,
            rest_s: 0.3,
            after_s: 0.45,
            sample_rate: 1000.0,
        }
    }
}

/// Integration steps per sample of the arm behind a [`Cuff`] (20 kHz at 1 kHz).
const CUFF_SUBSTEPS: usize = 20;

/// Simulate `t,q1,q2,tau1,tau2,trial` with white torque and angle noise.
pub fn simulate_planar(
    subject: &PlanarSubject,
    protocol: &PlanarProtocol,
    torque_std: f64,
    angle_std: f64,
    seed: u64,
) -> Result<Recording> {
    simulate_planar_intervals(
        subject,
        protocol,
        &[protocol.interpolation_s],
        torque_std,
        angle_std,
        seed,
    )
}

/// [`simulate_planar`] with trial `i` using the interpolation interval
/// `intervals_s[i % len]` instead of the protocol's (seed 003 §IV varies T_k
/// from 50 to 300 ms); every trial records `protocol.after_s` after its onset.
pub fn simulate_planar_intervals(
    subject: &PlanarSubject,
    protocol: &PlanarProtocol,
    intervals_s: &[f64],
    torque_std: f64,
    angle_std: f64,
    seed: u64,
) -> Result<Recording> {
    if intervals_s.is_empty() || intervals_s.iter().any(|t| !(t.is_finite() && *t > 0.0)) {
        return Err(limpid_core::Error::invalid(
            "interpolation intervals",
            "expected at least one positive duration",
        ));
    }
    let mut rng = StdRng::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).expect("unit normal is valid");
    let mut order: Vec<usize> = (0..protocol.trials)
        .map(|i| i % protocol.directions.len().max(1))
        .collect();
    order.shuffle(&mut rng);
    let fs = protocol.sample_rate;
    let per = ((protocol.rest_s + protocol.after_s) * fs).round() as usize;
    let mut cols: Vec<Vec<f64>> = (0..6)
        .map(|_| Vec::with_capacity(per * order.len()))
        .collect();
    let impedance_at = |t_on: f64| match subject.reflex {
        Some(r) if t_on > r.latency_s => (
            subject.stiffness * (1.0 + r.stiffness_gain),
            subject.damping * (1.0 + r.damping_gain),
        ),
        _ => (subject.stiffness, subject.damping),
    };
    let q0 = Vector2::new(subject.q0[0], subject.q0[1]);
    let tau0 = Vector2::new(subject.tau0[0], subject.tau0[1]);
    for (trial, &d) in order.iter().enumerate() {
        let dir = Vector2::new(protocol.directions[d][0], protocol.directions[d][1]);
        let tk = intervals_s[trial % intervals_s.len()];
        // the robot's (or cuff's) joint-space trajectory: position, velocity, acceleration
        let robot = |t_on: f64| {
            let (s, sd, sdd) = Profile::Quintic.eval(t_on, tk);
            (q0 + dir * s, dir * sd, dir * sdd)
        };
        // with a cuff: the arm's state, at rest where the cuff carries τ0
        let mut arm = subject.cuff.map(|c| {
            let rest = c.stiffness.try_inverse().map_or(q0, |inv| q0 - inv * tau0);
            (c, rest, rest, Vector2::<f64>::zeros())
        });
        for i in 0..per {
            let t_on = i as f64 / fs - protocol.rest_s;
            let (q, qd, qdd) = robot(t_on);
            let tau = match &mut arm {
                None => {
                    let (kk, dd) = impedance_at(t_on);
                    mass_matrix(q[1], subject.xi) * qdd
                        + coriolis(q[1], [qd[0], qd[1]], subject.xi)
                        + dd * qd
                        + kk * (q - q0)
                        + tau0
                }
                Some((cuff, rest, qa, qad)) => {
                    let measured = cuff.stiffness * (q - *qa) + cuff.damping * (qd - *qad);
                    // eq. (9) of the arm, driven by the cuff, until the next sample
                    for k in 0..CUFF_SUBSTEPS {
                        let t = t_on + k as f64 / (fs * CUFF_SUBSTEPS as f64);
                        let (qr, qrd, _) = robot(t);
                        let (kk, dd) = impedance_at(t);
                        let on_arm = cuff.stiffness * (qr - *qa) + cuff.damping * (qrd - *qad);
                        let rhs = on_arm
                            - tau0
                            - coriolis(qa[1], [qad[0], qad[1]], subject.xi)
                            - dd * *qad
                            - kk * (*qa - *rest);
                        let qadd = mass_matrix(qa[1], subject.xi)
                            .try_inverse()
                            .map_or(Vector2::zeros(), |m| m * rhs);
                        let h = 1.0 / (fs * CUFF_SUBSTEPS as f64);
                        *qad += qadd * h;
                        *qa += *qad * h;
                    }
                    measured
                }
            };
            cols[0].push((trial * per + i) as f64 / fs);
            cols[1].push(q[0] + angle_std * unit.sample(&mut rng));
            cols[2].push(q[1] + angle_std * unit.sample(&mut rng));
            cols[3].push(tau[0] + torque_std * unit.sample(&mut rng));
            cols[4].push(tau[1] + torque_std * unit.sample(&mut rng));
            cols[5].push((trial + 1) as f64);
        }
    }
    let names = ["t", "q1", "q2", "tau1", "tau2", "trial"]
        .map(String::from)
        .to_vec();
    Recording::new("virtual:planar", names, cols, 2)
}

/// Add a subject's slow torque fluctuation to `tau1` and `tau2`: low-pass
/// noise below `max_hz` with `rms_nm` standard deviation per joint, the
/// signal-dependent force fluctuation of a subject holding a load (seed 003
/// §IV: 5 N held at the hand). Changes nothing when `rms_nm` is 0.
pub fn add_torque_fluctuation(
    rec: &mut Recording,
    rms_nm: f64,
    max_hz: f64,
    seed: u64,
) -> Result<()> {
    if rms_nm == 0.0 {
        return Ok(());
    }
    let mut rng = StdRng::seed_from_u64(seed);
    let noise =
        crate::simulate::slow_noise(rec.len(), rec.sample_rate(), max_hz, rms_nm, &mut rng)?;
    for (k, name) in ["tau1", "tau2"].into_iter().enumerate() {
        let tau = rec.require(name, "joint torque")?;
        let with: Vec<f64> = tau.iter().zip(&noise[k]).map(|(t, n)| t + n).collect();
        rec.set_column(name, with)?;
    }
    Ok(())
}

/// The end-point version of a joint-space planar recording (`q1,q2,tau1,tau2`
/// -> `x,y,fx,fy`): hand position x = FK(q) and hand force f = J(q)^-T τ, as
/// a robot handle records them, then white position (m) and force (N) noise.
/// Noise on the joint recording becomes correlated end-point noise; simulate
/// it noise-free to get the end-point sensors' noise only.
pub fn to_endpoint(
    rec: &Recording,
    arm: &limpid_core::arm::Arm,
    position_std: f64,
    force_std: f64,
    seed: u64,
) -> Result<Recording> {
    let mut rng = StdRng::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).expect("unit normal is valid");
    let get = |n: &str| rec.require(n, "a joint-space planar recording");
    let (t, q1, q2, tau1, tau2, trial) = (
        get("t")?,
        get("q1")?,
        get("q2")?,
        get("tau1")?,
        get("tau2")?,
        get("trial")?,
    );
    let mut cols: Vec<Vec<f64>> = (0..6).map(|_| Vec::with_capacity(rec.len())).collect();
    for i in 0..rec.len() {
        let q = [q1[i], q2[i]];
        let x = arm.fk(q);
        let f = arm.jacobian(q).transpose().try_inverse().ok_or_else(|| {
            limpid_core::Error::invalid(
                "arm configuration",
                format!("the Jacobian is singular at q = ({}, {}) rad", q[0], q[1]),
            )
        })? * Vector2::new(tau1[i], tau2[i]);
        cols[0].push(t[i]);
        cols[1].push(x[0] + position_std * unit.sample(&mut rng));
        cols[2].push(x[1] + position_std * unit.sample(&mut rng));
        cols[3].push(f[0] + force_std * unit.sample(&mut rng));
        cols[4].push(f[1] + force_std * unit.sample(&mut rng));
        cols[5].push(trial[i]);
    }
    let names = ["t", "x", "y", "fx", "fy", "trial"]
        .map(String::from)
        .to_vec();
    Recording::new("virtual:planar-endpoint", names, cols, 2)
}
