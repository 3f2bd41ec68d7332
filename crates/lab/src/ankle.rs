//! A virtual ankle with a known stretch reflex: the ground truth for the
//! parallel-cascade estimator (Kearney, Stein & Parameswaran 1997, IEEE TBME
//! 44(6)).
//!
//! A position servo imposes a pseudo-random binary sequence (PRBS) on the
//! joint, as in the REKLAB ankle experiments (the real ankle recordings (`LIMPID_REAL_DATA`)):
//! the command switches between +-`amplitude_rad` with probability 1/2 every
//! `switch_s`, and the actuator follows it as a second-order system. The
//! torque applied to the joint is
//!
//! `tau = I q'' + B q' + K q + k2 q^2 + k3 q^3 + LP2(f(q'(t - d))) + noise`,
//!
//! the intrinsic pathway (k2 and k3 are 0 unless a subject sets `quadratic`
//! or `cubic`) plus a reflex pathway: velocity delayed by `d` through a
//! static curve `f` (by default the half-wave rectifier times the gain `G`,
//! N m s/rad; [`ReflexCurve`] adds a threshold, saturation or a smooth
//! ceiling) and low-passed by a unit-DC second-order system. Defaults are of the order of the real ankle:
//! I 0.015 kg m^2, B 0.8 N m s/rad, K 80 N m/rad, reflex delay 45 ms,
//! G 30 N m s/rad, low-pass 2 Hz / 0.7. States are integrated on a 10x finer
//! grid so the delay and derivatives are exact to 0.1 ms at 1 kHz. Each
//! sample is the mean of angle and torque over its sample period on that
//! grid (an integrating converter): the command switches on the sample
//! clock, and a torque sampled at the switch would carry the actuator's full
//! acceleration step where the angle's second difference sees half of it,
//! which read as B about 2 % too high and I 7 % too high in every estimator.

use rand::{rngs::StdRng, Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use limpid_core::{Error, Recording, Result};

/// The stretch reflex of a virtual ankle.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnkleReflex {
    /// DC gain on rectified velocity (N m s/rad).
    pub gain: f64,
    /// Delay (s).
    pub delay_s: f64,
    /// Natural frequency of the low-pass (Hz).
    pub natural_hz: f64,
    /// Damping ratio of the low-pass.
    pub damping_ratio: f64,
    /// True: the reflex answers positive velocity (`max(q', 0)`); false: negative.
    pub positive: bool,
    /// The static curve from the answered half of the velocity to torque
    /// (before the low-pass); the plain rectifier by default (issue 78).
    #[serde(default, skip_serializing_if = "ReflexCurve::is_rectifier")]
    pub curve: ReflexCurve,
}

/// The reflex's static nonlinearity: how the answered half of the delayed
/// velocity `v+` (rad/s, `max(q', 0)` or `max(-q', 0)`) becomes torque
/// before the unit-DC low-pass. Real stretch reflexes have thresholds and
/// saturate (issue 78).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
pub enum ReflexCurve {
    /// `G v+`.
    #[default]
    Rectifier,
    /// `G max(v+ - threshold, 0)`: no answer below a velocity threshold.
    Threshold {
        /// Velocity threshold (rad/s).
        threshold_rad_s: f64,
    },
    /// `min(G max(v+ - threshold, 0), saturation)`: a threshold and a hard ceiling.
    Clipped {
        /// Velocity threshold (rad/s).
        threshold_rad_s: f64,
        /// Largest torque (N m).
        saturation_nm: f64,
    },
    /// `S tanh(G v+ / S)`: slope G at rest, saturating smoothly at S.
    Tanh {
        /// Saturation torque S (N m).
        saturation_nm: f64,
    },
}

impl ReflexCurve {
    fn is_rectifier(&self) -> bool {
        *self == ReflexCurve::Rectifier
    }
}

impl AnkleReflex {
    /// The static torque (N m, before the low-pass) for a velocity `v` (rad/s):
    /// the curve of the answered half; zero for the other half.
    pub fn static_torque(&self, v: f64) -> f64 {
        let half = if self.positive { v } else { -v }.max(0.0);
        let g = self.gain;
        match self.curve {
            ReflexCurve::Rectifier => g * half,
            ReflexCurve::Threshold { threshold_rad_s } => g * (half - threshold_rad_s).max(0.0),
            ReflexCurve::Clipped {
                threshold_rad_s,
                saturation_nm,
            } => (g * (half - threshold_rad_s).max(0.0)).min(saturation_nm),
            ReflexCurve::Tanh { saturation_nm } => {
                saturation_nm * (g * half / saturation_nm).tanh()
            }
        }
    }
}

/// A virtual ankle (joint space).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnkleSubject {
    /// I (kg m^2).
    pub inertia: f64,
    /// B (N m s/rad).
    pub damping: f64,
    /// K (N m/rad).
    pub stiffness: f64,
    /// The reflex pathway, if any.
    pub reflex: Option<AnkleReflex>,
    /// Quadratic stiffness k2 (N m/rad^2): the elastic torque adds k2 q^2,
    /// an even nonlinearity (issue 59's nonlinear subjects); 0 by default.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub quadratic: f64,
    /// Cubic stiffness k3 (N m/rad^3): the elastic torque adds k3 q^3, an
    /// odd nonlinearity (a joint stiffening with the angle); 0 by default.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub cubic: f64,
    /// The rig, when it is a position servo of finite stiffness rather than
    /// an actuator that imposes the motion (issue 79): `limpid simulate`
    /// then records the servo's reference `r1` ([`simulate_ankle_servo_following`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub servo: Option<Servo>,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

impl Default for AnkleSubject {
    fn default() -> Self {
        AnkleSubject {
            inertia: 0.015,
            damping: 0.8,
            stiffness: 80.0,
            reflex: Some(AnkleReflex {
                gain: 30.0,
                delay_s: 0.045,
                natural_hz: 2.0,
                damping_ratio: 0.7,
                positive: true,
                curve: ReflexCurve::Rectifier,
            }),
            quadratic: 0.0,
            cubic: 0.0,
            servo: None,
        }
    }
}

/// The perturbation and recording.
#[derive(Debug, Clone, Copy)]
pub struct AnkleExperiment {
    /// PRBS half-swing (rad).
    pub amplitude_rad: f64,
    /// PRBS switching interval (s).
    pub switch_s: f64,
    /// Actuator bandwidth (Hz), second order with damping ratio 0.7.
    pub actuator_hz: f64,
    /// Length (s).
    pub duration_s: f64,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Standard deviation of white torque noise (N m).
    pub torque_noise_nm: f64,
}

impl Default for AnkleExperiment {
    fn default() -> Self {
        AnkleExperiment {
            amplitude_rad: 0.02,
            switch_s: 0.15,
            actuator_hz: 15.0,
            duration_s: 60.0,
            rate_hz: 1000.0,
            torque_noise_nm: 0.1,
        }
    }
}

/// Simulate `e` on `s`: a recording with columns `t`, `q1` (rad), `tau1` (N m, applied to the joint).
pub fn simulate_ankle(s: &AnkleSubject, e: &AnkleExperiment, seed: u64) -> Result<Recording> {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    if !(ok(e.amplitude_rad)
        && ok(e.switch_s)
        && ok(e.actuator_hz)
        && ok(e.duration_s)
        && ok(e.rate_hz)
        && e.torque_noise_nm.is_finite()
        && e.torque_noise_nm >= 0.0)
    {
        return Err(Error::invalid(
            "ankle experiment",
            "amplitude, switching interval, actuator bandwidth, duration and rate must be positive",
        ));
    }
    crate::validate::check_size(e.duration_s * e.rate_hz, "ankle recording")?;
    let n = (e.duration_s * e.rate_hz).round() as usize;
    integrate(s, e, n, seed, prbs(e))
}

/// The PRBS command of `e` on the integration grid: it switches with
/// probability 1/2 on its own grid (the draw comes first in each step, as
/// the torque noise's come after it).
fn prbs(e: &AnkleExperiment) -> impl FnMut(usize, &mut StdRng) -> f64 {
    let h = 1.0 / (e.rate_hz * SUBSTEPS as f64);
    let switch_every = (e.switch_s / h).round().max(1.0) as usize;
    let mut u = e.amplitude_rad;
    move |k, rng| {
        if k % switch_every == 0 && rng.random::<bool>() {
            u = -u;
        }
        u
    }
}

/// A command given per sample, linearly interpolated on the integration
/// grid; refused unless it holds finite angles.
fn interpolated(command: &[f64]) -> Result<impl FnMut(usize, &mut StdRng) -> f64 + '_> {
    if command.iter().any(|v| !v.is_finite()) || command.is_empty() {
        return Err(Error::invalid("command", "expected finite angles"));
    }
    let n = command.len();
    Ok(move |k: usize, _: &mut StdRng| {
        let (i, f) = (k / SUBSTEPS, (k % SUBSTEPS) as f64 / SUBSTEPS as f64);
        let next = command[(i + 1).min(n - 1)];
        command[i] * (1.0 - f) + next * f
    })
}

/// Simulate the ankle following a position `command` (rad, one value per
/// sample at `e.rate_hz`, linearly interpolated between samples) through
/// the same actuator and with the same reflex and noise as [`simulate_ankle`]
/// (whose PRBS fields are not used): a periodic protocol's command (issue 59).
pub fn simulate_ankle_following(
    s: &AnkleSubject,
    e: &AnkleExperiment,
    command: &[f64],
    seed: u64,
) -> Result<Recording> {
    let follow = interpolated(command)?;
    integrate(s, e, command.len(), seed, follow)
}

/// Integration steps per sample.
const SUBSTEPS: usize = 10;

/// The ankle under the actuator following `command(step, rng)` for `n` samples.
fn integrate(
    s: &AnkleSubject,
    e: &AnkleExperiment,
    n: usize,
    seed: u64,
    mut command: impl FnMut(usize, &mut StdRng) -> f64,
) -> Result<Recording> {
    let sub = SUBSTEPS;
    let h = 1.0 / (e.rate_hz * sub as f64);
    let mut rng = StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, e.torque_noise_nm.max(f64::MIN_POSITIVE))
        .map_err(|err| Error::invalid("torque noise", err.to_string()))?;
    let wa = 2.0 * std::f64::consts::PI * e.actuator_hz;
    let za = 0.7;
    let (mut q, mut qd) = (0.0f64, 0.0f64);
    let delay = s.reflex.map_or(0, |r| (r.delay_s / h).round() as usize);
    let mut history = vec![0.0f64; delay + 1];
    let (mut z, mut zd) = (0.0f64, 0.0f64);
    let (mut q_sum, mut tau_sum) = (0.0f64, 0.0f64);
    let (mut t_col, mut q_col, mut tau_col) = (
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    );
    for k in 0..n * sub {
        let u = command(k, &mut rng);
        let qdd = wa * wa * (u - q) - 2.0 * za * wa * qd;
        let reflex = if s.reflex.is_some() { z } else { 0.0 };
        q_sum += q;
        // semi-implicit Euler's velocity lags its position by half a step;
        // taken as it is, B h/2 read as 0.27 % less inertia (issue 59)
        tau_sum += s.inertia * qdd
            + s.damping * (qd + 0.5 * h * qdd)
            + (s.stiffness + (s.quadratic + s.cubic * q) * q) * q
            + reflex;
        if k % sub == sub - 1 {
            t_col.push((k / sub) as f64 / e.rate_hz);
            q_col.push(q_sum / sub as f64);
            let eps = if e.torque_noise_nm > 0.0 {
                noise.sample(&mut rng)
            } else {
                0.0
            };
            tau_col.push(tau_sum / sub as f64 + eps);
            (q_sum, tau_sum) = (0.0, 0.0);
        }
        // reflex low-pass driven by the delayed rectified velocity
        history[k % (delay + 1)] = qd;
        if let Some(r) = s.reflex {
            let v = if k >= delay {
                history[(k - delay) % (delay + 1)]
            } else {
                0.0
            };
            let wr = 2.0 * std::f64::consts::PI * r.natural_hz;
            let zdd = wr * wr * (r.static_torque(v) - z) - 2.0 * r.damping_ratio * wr * zd;
            zd += h * zdd;
            z += h * zd;
        }
        // semi-implicit Euler on the 10x grid
        qd += h * qdd;
        q += h * qd;
    }
    Recording::new(
        "virtual ankle",
        vec!["t".into(), "q1".into(), "tau1".into()],
        vec![t_col, q_col, tau_col],
        2,
    )
}

/// A robot of finite impedance (issue 79): a position servo that pulls the
/// joint towards its commanded reference `r` with `tau_robot = K_e (r - q) +
/// B_e (r' - q')`, while the subject's own torque fluctuations (white noise
/// band-passed to `subject_band_hz`) move the joint too. With `K_e` many
/// times the joint's K the robot imposes the motion (open loop); near K the
/// motion is correlated with the subject's torque and least squares on it is
/// biased (Westwick & Perreault 2011).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Servo {
    /// K_e (N m/rad).
    pub stiffness: f64,
    /// B_e (N m s/rad).
    pub damping: f64,
    /// Standard deviation of the subject's own torque (N m).
    #[serde(default = "Servo::default_subject_torque")]
    pub subject_torque_nm: f64,
    /// Band of the subject's torque (Hz): a first-order high-pass at the
    /// first, a second-order (damping 0.7) low-pass at the second.
    #[serde(default = "Servo::default_band")]
    pub subject_band_hz: (f64, f64),
}

impl Servo {
    fn default_subject_torque() -> f64 {
        0.9
    }

    fn default_band() -> (f64, f64) {
        (0.3, 5.0)
    }

    /// A servo `ratio` times as stiff as `subject`, damped to a closed-loop
    /// damping ratio of 0.6, with a 0.9 N m subject torque in 0.3-5 Hz.
    pub fn relative_to(subject: &AnkleSubject, ratio: f64) -> Servo {
        let k = subject.stiffness * (1.0 + ratio);
        let damping = (2.0 * 0.6 * (k * subject.inertia).sqrt() - subject.damping).max(0.0);
        Servo {
            stiffness: ratio * subject.stiffness,
            damping,
            subject_torque_nm: Servo::default_subject_torque(),
            subject_band_hz: Servo::default_band(),
        }
    }
}

/// Simulate the ankle on a servo of finite impedance: the PRBS of `e`
/// through its actuator filter is the commanded reference, recorded as `r1`
/// (rad) beside `t`, `q1` and `tau1` (the robot's torque on the joint, with
/// `e.torque_noise_nm` of sensor noise).
pub fn simulate_ankle_servo(
    s: &AnkleSubject,
    e: &AnkleExperiment,
    servo: &Servo,
    seed: u64,
) -> Result<Recording> {
    check_servo(e, servo)?;
    integrate_servo(s, e, servo, seed, prbs(e))
}

/// [`simulate_ankle_servo`] with the servo's command a position `command`
/// (rad, one value per sample at `e.rate_hz`, linearly interpolated), as
/// [`simulate_ankle_following`]: a designed protocol on a compliant rig.
pub fn simulate_ankle_servo_following(
    s: &AnkleSubject,
    e: &AnkleExperiment,
    servo: &Servo,
    command: &[f64],
    seed: u64,
) -> Result<Recording> {
    let follow = interpolated(command)?;
    let e = AnkleExperiment {
        duration_s: command.len() as f64 / e.rate_hz,
        ..*e
    };
    check_servo(&e, servo)?;
    integrate_servo(s, &e, servo, seed, follow)
}

fn check_servo(e: &AnkleExperiment, servo: &Servo) -> Result<()> {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    let (lo, hi) = servo.subject_band_hz;
    if !(ok(e.amplitude_rad)
        && ok(e.switch_s)
        && ok(e.actuator_hz)
        && ok(e.duration_s)
        && ok(e.rate_hz)
        && ok(servo.stiffness)
        && servo.damping.is_finite()
        && servo.damping >= 0.0
        && servo.subject_torque_nm.is_finite()
        && servo.subject_torque_nm >= 0.0
        && e.torque_noise_nm.is_finite()
        && e.torque_noise_nm >= 0.0
        && ok(lo)
        && hi > lo
        && hi < 0.5 * e.rate_hz)
    {
        return Err(Error::invalid(
            "servo",
            "amplitude, switching interval, bandwidth, duration, rate and servo stiffness must be positive, the servo damping and the noises not negative, the subject's band increasing and below half the sample rate",
        ));
    }
    crate::validate::check_size(e.duration_s * e.rate_hz, "ankle recording")
}

/// A joint angle beyond this (rad) on a servo: the loop is unstable.
pub const UNSTABLE_RAD: f64 = 10.0;

/// The ankle on the servo, its command `command(step, rng)` through the
/// actuator's second-order filter being the reference.
fn integrate_servo(
    s: &AnkleSubject,
    e: &AnkleExperiment,
    servo: &Servo,
    seed: u64,
    mut command: impl FnMut(usize, &mut StdRng) -> f64,
) -> Result<Recording> {
    let n = (e.duration_s * e.rate_hz).round() as usize;
    let sub = SUBSTEPS;
    let h = 1.0 / (e.rate_hz * sub as f64);
    let mut rng = StdRng::seed_from_u64(seed);
    let subject = subject_torque(servo, n * sub, h, &mut rng);
    let sensor = Normal::new(0.0, e.torque_noise_nm.max(f64::MIN_POSITIVE))
        .map_err(|err| Error::invalid("torque noise", err.to_string()))?;
    let wa = 2.0 * std::f64::consts::PI * e.actuator_hz;
    let (mut r, mut rd) = (0.0f64, 0.0f64);
    let (mut q, mut qd) = (0.0f64, 0.0f64);
    let mut reflex = ReflexState::new(s.reflex, h);
    let mut sums = [0.0f64; 3];
    let mut cols: [Vec<f64>; 4] = std::array::from_fn(|_| Vec::with_capacity(n));
    for (k, n_subject) in subject.iter().enumerate() {
        let u = command(k, &mut rng);
        let robot = servo.stiffness * (r - q) + servo.damping * (rd - qd);
        let elastic = (s.stiffness + (s.quadratic + s.cubic * q) * q) * q;
        let qdd = (robot + n_subject - s.damping * qd - elastic - reflex.torque()) / s.inertia;
        if q.is_nan() || q.abs() > UNSTABLE_RAD {
            return Err(Error::invalid(
                "servo",
                format!(
                    "the joint on this servo is unstable (it passed {UNSTABLE_RAD} rad {:.2} s in): the reflex's delayed feedback through a servo this compliant oscillates and grows; make the servo stiffer or the reflex weaker",
                    k as f64 * h
                ),
            ));
        }
        for (sum, v) in sums.iter_mut().zip([q, robot, r]) {
            *sum += v;
        }
        if k % sub == sub - 1 {
            cols[0].push((k / sub) as f64 / e.rate_hz);
            cols[1].push(sums[0] / sub as f64);
            let eps = if e.torque_noise_nm > 0.0 {
                sensor.sample(&mut rng)
            } else {
                0.0
            };
            cols[2].push(sums[1] / sub as f64 + eps);
            cols[3].push(sums[2] / sub as f64);
            sums = [0.0; 3];
        }
        reflex.step(qd);
        let rdd = wa * wa * (u - r) - 2.0 * 0.7 * wa * rd;
        rd += h * rdd;
        r += h * rd;
        qd += h * qdd;
        q += h * qd;
    }
    Recording::new(
        "virtual ankle on a servo",
        ["t", "q1", "tau1", "r1"].map(String::from).to_vec(),
        cols.to_vec(),
        2,
    )
}

/// The subject's own torque on the fine grid: white noise through a
/// first-order high-pass and a second-order low-pass, scaled to its
/// standard deviation.
fn subject_torque(servo: &Servo, len: usize, h: f64, rng: &mut StdRng) -> Vec<f64> {
    let (lo, hi) = servo.subject_band_hz;
    let a = (-2.0 * std::f64::consts::PI * lo * h).exp();
    let w = 2.0 * std::f64::consts::PI * hi;
    let (mut slow, mut y, mut yd) = (0.0f64, 0.0f64, 0.0f64);
    let mut out: Vec<f64> = (0..len)
        .map(|_| {
            let white: f64 = rng.sample(rand_distr::StandardNormal);
            let ydd = w * w * (white - y) - 2.0 * 0.7 * w * yd;
            yd += h * ydd;
            y += h * yd;
            slow = a * slow + (1.0 - a) * y;
            y - slow
        })
        .collect();
    let sd = (out.iter().map(|v| v * v).sum::<f64>() / len.max(1) as f64).sqrt();
    let scale = if sd > 0.0 {
        servo.subject_torque_nm / sd
    } else {
        0.0
    };
    out.iter_mut().for_each(|v| *v *= scale);
    out
}

/// The reflex pathway's state on the fine grid: the delayed rectified
/// velocity through the unit-DC second-order low-pass, times the gain.
struct ReflexState {
    reflex: Option<AnkleReflex>,
    history: Vec<f64>,
    at: usize,
    h: f64,
    z: f64,
    zd: f64,
}

impl ReflexState {
    fn new(reflex: Option<AnkleReflex>, h: f64) -> ReflexState {
        let delay = reflex.map_or(0, |r| (r.delay_s / h).round() as usize);
        ReflexState {
            reflex,
            history: vec![0.0; delay + 1],
            at: 0,
            h,
            z: 0.0,
            zd: 0.0,
        }
    }

    fn torque(&self) -> f64 {
        if self.reflex.is_some() {
            self.z
        } else {
            0.0
        }
    }

    /// Record the velocity of this step and advance the low-pass.
    fn step(&mut self, qd: f64) {
        let Some(r) = self.reflex else { return };
        let len = self.history.len();
        self.history[self.at % len] = qd;
        self.at += 1;
        // the oldest entry is the velocity `delay` steps ago (0 before that)
        let v = self.history[self.at % len];
        let wr = 2.0 * std::f64::consts::PI * r.natural_hz;
        let zdd = wr * wr * (r.static_torque(v) - self.z) - 2.0 * r.damping_ratio * wr * self.zd;
        self.zd += self.h * zdd;
        self.z += self.h * self.zd;
    }
}

/// Short segments of a long recording, as an experiment that keeps only
/// stretches of a session (Ludvig & Perreault 2012): stretches of
/// `shortest_s..longest_s` (uniform) separated by gaps of 0.2-2 s, each its
/// own `trial` (1, 2, ...) keeping its time, with a background torque of
/// 2-6 N m added per segment (the operating point changes between them).
/// No stretch spans a gap of the recording's own.
pub fn cut_into_segments(
    rec: &Recording,
    (shortest_s, longest_s): (f64, f64),
    seed: u64,
) -> Result<Recording> {
    if !(shortest_s > 0.0 && longest_s >= shortest_s && longest_s.is_finite()) {
        return Err(Error::invalid(
            "segments",
            format!("expected 0 < shortest <= longest, found {shortest_s} and {longest_s} s"),
        ));
    }
    let fs = rec.sample_rate();
    let mut rng = StdRng::seed_from_u64(seed);
    // the recording's own trial ids give way to the segments'
    let mut names: Vec<String> = rec
        .names()
        .iter()
        .filter(|n| *n != "trial")
        .cloned()
        .collect();
    let mut columns: Vec<Vec<f64>> = vec![Vec::new(); names.len() + 1];
    let torque = names.iter().position(|n| n.starts_with("tau"));
    let mut at = (rng.random_range(0.2..2.0) * fs) as usize;
    let mut trial = 0.0;
    loop {
        let len = (rng.random_range(shortest_s..=longest_s) * fs).round() as usize;
        if at + len > rec.len() {
            break;
        }
        // a stretch holds no gap of the recording's own
        let t = rec.t();
        if let Some(gap) = (at + 1..at + len).find(|&i| t[i] - t[i - 1] > 1.5 / fs) {
            at = gap;
            continue;
        }
        trial += 1.0;
        let background = rng.random_range(2.0..6.0);
        for (k, name) in names.iter().enumerate() {
            let column = rec.column(name).expect("a named column");
            let offset = if Some(k) == torque { background } else { 0.0 };
            columns[k].extend(column[at..at + len].iter().map(|v| v + offset));
        }
        columns[names.len()].extend(std::iter::repeat_n(trial, len));
        at += len + (rng.random_range(0.2..2.0) * fs) as usize;
    }
    names.push("trial".into());
    Recording::new(rec.path(), names, columns, 2)
}

/// The first `count` segments of a recording [`cut_into_segments`] made
/// (its trials 1 to `count`).
pub fn first_segments(rec: &Recording, count: usize) -> Result<Recording> {
    let ids = rec.require("trial", "the segments' trial ids")?;
    let end = ids
        .iter()
        .position(|&id| id > count as f64)
        .unwrap_or(ids.len());
    let columns = rec
        .names()
        .iter()
        .map(|n| rec.column(n).map_or_else(Vec::new, |c| c[..end].to_vec()))
        .collect();
    Recording::new(rec.path(), rec.names().to_vec(), columns, 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perturbation_and_torque_are_of_the_real_ankle_size() {
        let s = AnkleSubject {
            reflex: None,
            ..AnkleSubject::default()
        };
        let e = AnkleExperiment {
            duration_s: 10.0,
            torque_noise_nm: 0.0,
            ..AnkleExperiment::default()
        };
        let rec = simulate_ankle(&s, &e, 3).unwrap();
        let q = rec.column("q1").unwrap();
        let sd = (q.iter().map(|v| v * v).sum::<f64>() / q.len() as f64).sqrt();
        assert!((0.01..0.025).contains(&sd), "position sd {sd}");
        // torque of the real recordings' size (their sd is 1-3 N m)
        let tau = rec.column("tau1").unwrap();
        let m = tau.iter().sum::<f64>() / tau.len() as f64;
        let tsd = (tau.iter().map(|v| (v - m).powi(2)).sum::<f64>() / tau.len() as f64).sqrt();
        assert!((0.5..5.0).contains(&tsd), "torque sd {tsd}");
    }
}
