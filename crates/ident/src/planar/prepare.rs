//! Seed 003 §IV: trials from a recording (joint space, or end-point data through inverse kinematics and τ = J^T F), rest offsets, onsets, zero-phase filtering and derivatives.

use super::fit::{MAX_LINK_M, MIN_LINK_M};
use super::noise::AngleNoise;
use super::{PlanarPrepare, PlanarTrial};
use crate::prepare::edge_kinds;
use limpid_core::arm::Arm;
use limpid_core::trial::{
    change_floors, detect_onset, noise_sigma, perturbation_onset, windows_from_trial_column,
};
use limpid_core::{Error, Recording, Result};
use limpid_dsp::{central_first, central_second, LowPass};
use nalgebra::Vector2;
impl PlanarPrepare {
    /// Link lengths (m), shoulder at the origin, the elbow flexed (q2 > 0),
    /// the default low-pass and a 4th-order Butterworth.
    pub fn new(l1: f64, l2: f64) -> Self {
        PlanarPrepare {
            arm: Arm {
                l1,
                l2,
                shoulder: [0.0, 0.0],
            },
            cutoff_hz: None,
            order: 4,
            elbow_positive: true,
        }
    }
}

/// Prepared planar data.
#[derive(Debug, Clone)]
pub struct PlanarData {
    /// The recording's path.
    pub path: std::path::PathBuf,
    /// Sample rate (Hz).
    pub fs: f64,
    /// The arm the data were converted with.
    pub arm: Arm,
    /// Prepared trials.
    pub trials: Vec<PlanarTrial>,
    /// True when the recording held end-point data converted to joint space.
    pub from_endpoint: bool,
    /// Low-pass cut-off used (Hz).
    pub cutoff_hz: f64,
    /// The angles' white noise, compensated in every fit (errors in variables).
    pub angle_noise: AngleNoise,
}

impl PlanarData {
    /// Longest observation window available in every trial (s).
    pub fn max_window_s(&self) -> f64 {
        self.trials.iter().map(|t| t.dq[0].len()).min().unwrap_or(0) as f64 / self.fs
    }
}

/// The longest a torque may lead the motion and still mark the onset (s);
/// physically the torque leads by the few ms the quintic needs to move the
/// angles out of their noise band. Noisy angles (end-point positions through
/// the inverse kinematics) leave that band later: the lead allowed grows by
/// how long the filtered angles had been moving before the raw ones left it
/// ([`motion_lag`]), up to [`MAX_ONSET_LEAD_S`].
pub const ONSET_LEAD_S: f64 = 0.03;

/// The longest lead a torque may have over the raw angles' onset when the
/// filtered angles show the motion under way (s).
pub const MAX_ONSET_LEAD_S: f64 = 0.1;

/// How many samples before the raw angles' onset `moved` (trial-relative) the
/// filtered angles `qf` were already moving: traced back from `moved` while
/// some angle stays beyond `threshold[k]` of its rest level, the mean of `qf`
/// before the lead window. Only a motion contiguous with the detected one
/// counts, so a drift at rest does not move the onset.
pub(crate) fn motion_lag(
    qf: &[Vec<f64>; 2],
    moved: usize,
    lead: usize,
    threshold: [f64; 2],
) -> usize {
    let rest_end = moved.saturating_sub(lead);
    if rest_end < 3 || moved >= qf[0].len() {
        return 0;
    }
    let rest: [f64; 2] =
        std::array::from_fn(|k| qf[k][..rest_end].iter().sum::<f64>() / rest_end as f64);
    let moving = |i: usize| (0..2).any(|k| (qf[k][i] - rest[k]).abs() > threshold[k]);
    let mut i = moved;
    while i > 0 && moving(i - 1) {
        i -= 1;
    }
    moved - i
}

/// Convert, cut into trials, take baselines, filter and differentiate.
pub fn prepare_planar(rec: &Recording, p: &PlanarPrepare) -> Result<PlanarData> {
    let arm = p.arm;
    check_arm(&arm)?;
    let from_endpoint = !rec.has("q1");
    // positions logged faster than they were measured: their measured
    // samples (issue 58; a planar estimate has no warnings yet to say so in,
    // its sample rate in the result does)
    let positions: Vec<String> = if from_endpoint {
        ["x", "y"]
    } else {
        ["q1", "q2"]
    }
    .iter()
    .map(|c| c.to_string())
    .collect();
    let (rec, _) = crate::prepare::at_measured_rate(std::borrow::Cow::Borrowed(rec), &positions)?;
    let rec = rec.as_ref();
    let fs = rec.sample_rate();
    if from_endpoint {
        refuse_out_of_plane(rec)?;
    }
    let (q, tau) = joint_signals(rec, p, from_endpoint)?;
    let cutoff = p
        .cutoff_hz
        .unwrap_or_else(|| crate::prepare::default_cutoff(fs));
    let lp = LowPass::butterworth(p.order, cutoff, fs)?;
    let signals: Vec<&[f64]> = vec![&q[0], &q[1], &tau[0], &tau[1]];
    let sigmas: Vec<f64> = signals.iter().map(|c| noise_sigma(c)).collect();
    let floors = change_floors(&signals);
    let windows = windows_from_trial_column(rec, "trial")?;
    let dt = 1.0 / fs;
    let gains = crate::prepare::noise_gains(crate::prepare::Derivative::Central, &lp, 0, dt)?;
    let angle_noise = AngleNoise::estimate(&q, gains);
    // the filtered angles' white-noise s.d., for the onset's motion lag
    let filtered_sigma = [sigmas[0] * gains[0].sqrt(), sigmas[1] * gains[0].sqrt()];
    let min_rest = ((0.02 * fs).round() as usize).max(3);
    let cutter = TrialCutter {
        rec,
        q: &q,
        tau: &tau,
        signals: &signals,
        sigmas: &sigmas,
        floors: &floors,
        lp: &lp,
        cutoff,
        min_rest,
        filtered_sigma,
    };
    let trials = windows
        .iter()
        .map(|w| cutter.trial(w))
        .collect::<Result<Vec<_>>>()?;
    if trials.len() < 2 {
        return Err(Error::TooFewSamples {
            path: rec.path().to_path_buf(),
            what: "a planar estimate (trials)".into(),
            needed: 2,
            found: trials.len(),
        });
    }
    Ok(PlanarData {
        path: rec.path().to_path_buf(),
        fs,
        arm,
        trials,
        from_endpoint,
        cutoff_hz: cutoff,
        angle_noise,
    })
}

/// Refuse an arm no human has: segments outside the plausible lengths (a
/// 4.9e-324 m forearm made every end-point stiffness null, issue 36) or a
/// shoulder beyond the recordings' own position limit.
fn check_arm(arm: &Arm) -> Result<()> {
    if ![arm.l1, arm.l2]
        .iter()
        .all(|l| (MIN_LINK_M..=MAX_LINK_M).contains(l))
    {
        return Err(Error::invalid(
            "link_lengths",
            format!(
                "expected two lengths from {MIN_LINK_M} to {MAX_LINK_M} m, found {}, {}",
                limpid_core::error::Num(arm.l1),
                limpid_core::error::Num(arm.l2)
            ),
        ));
    }
    let (limit, _) = limpid_core::recording::magnitude_limit("x");
    if !arm
        .shoulder
        .iter()
        .all(|v| v.is_finite() && v.abs() <= limit)
    {
        return Err(Error::invalid(
            "shoulder",
            format!(
                "expected a position within {limit} m, found {}, {}",
                arm.shoulder[0], arm.shoulder[1]
            ),
        ));
    }
    Ok(())
}

/// Refuse end-point data whose hand moves out of the plane (z) by more than
/// a tenth of its in-plane range: a planar estimate would ignore that motion.
fn refuse_out_of_plane(rec: &Recording) -> Result<()> {
    if let (Some(x), Some(y), Some(z)) = (rec.column("x"), rec.column("y"), rec.column("z")) {
        let range = |c: &[f64]| {
            let (lo, hi) = c
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                    (l.min(*v), h.max(*v))
                });
            hi - lo
        };
        let (rz, rxy) = (range(z), range(x).max(range(y)));
        if rz > 0.1 * rxy {
            return Err(Error::Format {
                path: rec.path().to_path_buf(),
                message: format!(
                    "the end point moves in z (range {rz:.4} m against {rxy:.4} m in x, y): a planar estimate would ignore that motion; use estimate linear for 3-D data"
                ),
            });
        }
    }
    Ok(())
}

/// Shoulder and elbow samples of one quantity.
type JointPair = [Vec<f64>; 2];

/// The joint angles and torques: the `q1,q2,tau1,tau2` columns, or the
/// end-point `x,y,fx,fy` through inverse kinematics and τ = J^T F.
fn joint_signals(
    rec: &Recording,
    p: &PlanarPrepare,
    from_endpoint: bool,
) -> Result<(JointPair, JointPair)> {
    let arm = p.arm;
    Ok(if from_endpoint {
        let x = rec.require("x", "end-point position (or give q1,q2 joint angles)")?;
        let y = rec.require("y", "end-point position")?;
        let fx = rec.require("fx", "end-point force")?;
        let fy = rec.require("fy", "end-point force")?;
        let mut q = [Vec::with_capacity(rec.len()), Vec::with_capacity(rec.len())];
        let mut tau = [Vec::with_capacity(rec.len()), Vec::with_capacity(rec.len())];
        for i in 0..rec.len() {
            let qi = arm.ik([x[i], y[i]], p.elbow_positive).ok_or_else(|| Error::Numerical {
                path: rec.path().to_path_buf(),
                message: format!(
                    "row {}, columns x,y: ({}, {}) is out of reach of links {} + {} m from the shoulder at ({}, {})",
                    rec.row_of(i), x[i], y[i], arm.l1, arm.l2, arm.shoulder[0], arm.shoulder[1]
                ),
            })?;
            let t = arm.jacobian(qi).transpose() * Vector2::new(fx[i], fy[i]);
            for k in 0..2 {
                q[k].push(qi[k]);
                tau[k].push(t[k]);
            }
        }
        (q, tau)
    } else {
        let get = |n: &str, why: &str| rec.require(n, why).map(<[f64]>::to_vec);
        (
            [
                get("q1", "shoulder angle")?,
                get("q2", "relative elbow angle")?,
            ],
            [
                get("tau1", "shoulder torque")?,
                get("tau2", "elbow torque")?,
            ],
        )
    })
}

/// What cutting one trial out of the recording needs.
struct TrialCutter<'a> {
    rec: &'a Recording,
    q: &'a [Vec<f64>; 2],
    tau: &'a [Vec<f64>; 2],
    /// The angles then the torques, for the onset.
    signals: &'a [&'a [f64]],
    sigmas: &'a [f64],
    floors: &'a [f64],
    lp: &'a LowPass,
    cutoff: f64,
    /// Fewest rest samples before the onset.
    min_rest: usize,
    /// White-noise s.d. of the filtered angles.
    filtered_sigma: [f64; 2],
}

impl TrialCutter<'_> {
    /// One trial from its onset on: rest offsets removed, filtered, differentiated.
    fn trial(&self, w: &limpid_core::trial::Window) -> Result<PlanarTrial> {
        let TrialCutter {
            rec,
            q,
            tau,
            signals,
            sigmas,
            floors,
            lp,
            cutoff,
            min_rest,
            filtered_sigma,
        } = *self;
        let fs = rec.sample_rate();
        let dt = 1.0 / fs;
        let qs: Vec<&[f64]> = vec![&q[0], &q[1]];
        let r = w.range.clone();
        let span = ((fs / cutoff).round() as usize).max(3);
        let (left, right) = edge_kinds(&qs, r.clone(), span, dt);
        if r.len() <= lp.padlen() + 1 {
            return Err(Error::TooFewSamples {
                path: rec.path().to_path_buf(),
                what: format!("trial {} with zero-phase filtering", w.id),
                needed: lp.padlen() + 2,
                found: r.len(),
            });
        }
        let extra = ((3.0 * fs / cutoff).round() as usize).min(r.len() - 1);
        let qf = [
            lp.filtfilt_edges(&q[0][r.clone()], left, right, extra)?,
            lp.filtfilt_edges(&q[1][r.clone()], left, right, extra)?,
        ];
        // Onset: the first of the angles and torques to leave rest, as
        // long as the torque leads the motion by at most ONSET_LEAD_S plus
        // the time the filtered angles were moving before the raw ones left
        // their noise band
        let lead_max = (ONSET_LEAD_S * fs).round() as usize;
        let moved = detect_onset(&signals[..2], r.clone(), &sigmas[..2], &floors[..2]);
        let threshold = std::array::from_fn(|k| (3.0 * filtered_sigma[k]).max(floors[k]));
        let lag = moved.map_or(0, |m| motion_lag(&qf, m - r.start, lead_max, threshold));
        let lead = (lead_max + lag).min((MAX_ONSET_LEAD_S * fs).round() as usize);
        let onset = perturbation_onset(signals, 2, r.clone(), sigmas, floors, (lead, min_rest))
            .unwrap_or(r.end);
        if onset - r.start < min_rest {
            return Err(Error::NoRestBeforeOnset {
                path: rec.path().to_path_buf(),
                row: rec.row_of(r.start),
                column: "trial".into(),
                trial: w.id,
                rest_samples: onset - r.start,
                needed: min_rest,
            });
        }
        let rest_end = onset.saturating_sub(2).max(r.start + 1);
        let mut t = PlanarTrial {
            id: w.id,
            q: Default::default(),
            qd: Default::default(),
            qdd: Default::default(),
            dq: Default::default(),
            dtau: Default::default(),
            q0: [0.0; 2],
            tau0: [0.0; 2],
        };
        let start = onset - r.start;
        for k in 0..2 {
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            t.q0[k] = mean(&q[k][r.start..rest_end]);
            t.tau0[k] = mean(&tau[k][r.start..rest_end]);
            let qf = &qf[k];
            let tf = lp.filtfilt_edges(&tau[k][r.clone()], left, right, extra)?;
            let qd = central_first(qf, dt);
            let qdd = central_second(qf, dt);
            t.dq[k] = qf[start..].iter().map(|v| v - t.q0[k]).collect();
            t.dtau[k] = tf[start..].iter().map(|v| v - t.tau0[k]).collect();
            t.q[k] = qf[start..].to_vec();
            t.qd[k] = qd[start..].to_vec();
            t.qdd[k] = qdd[start..].to_vec();
        }
        Ok(t)
    }
}
