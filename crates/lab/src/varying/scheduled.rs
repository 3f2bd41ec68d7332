//! The scheduled ankle: impedance and a stretch reflex that vary with the
//! operating angle on a ramp-and-hold schedule (Sobhani Tehrani & Kearney's
//! parameter-varying ankle), and its truth.

use super::{ACTUATOR_DAMPING, SUBSTEPS};
use limpid_core::truth::{About, VaryingTruth, VaryingTruthPoint};
use limpid_core::{Error, Matrix, Recording, Result};
use rand::rngs::StdRng;
use rand::Rng;
use rand::SeedableRng;
use rand_distr::Distribution;
use rand_distr::Normal;
use serde::{Deserialize, Serialize};
/// A coefficient triple `c0 + c1 s + c2 s^2` of the operating angle `s` (rad).
pub type Quadratic = [f64; 3];

fn quadratic(c: &Quadratic, s: f64) -> f64 {
    c[0] + c[1] * s + c[2] * s * s
}

/// The stretch reflex of the scheduled ankle: a gain that depends on the
/// operating angle, on positive (dorsiflexing) velocity.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScheduledReflex {
    /// G(s): DC gain from rectified velocity to torque (N m s/rad).
    pub gain: Quadratic,
    /// Delay (s).
    pub delay_s: f64,
    /// Natural frequency of the unit-DC low-pass (Hz).
    pub natural_hz: f64,
    /// Its damping ratio.
    pub damping_ratio: f64,
}

/// An ankle whose impedance depends on its operating angle (parameter-varying).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScheduledAnkle {
    /// I (kg m^2), constant.
    pub inertia: f64,
    /// K(θ) (N m/rad) of the joint's angle θ, times `exp(stiffness_growth θ)`.
    pub stiffness: Quadratic,
    /// Exponential growth of K with the angle (1/rad; 0: K is the quadratic).
    /// A real ankle's K rises roughly exponentially towards dorsiflexion.
    #[serde(default)]
    pub stiffness_growth: f64,
    /// B(θ) (N m s/rad) of the joint's angle.
    pub damping: Quadratic,
    /// Passive torque holding the operating angle (N m).
    pub background: Quadratic,
    /// The reflex, if any.
    pub reflex: Option<ScheduledReflex>,
}

impl Default for ScheduledAnkle {
    /// K 54 -> 90 N m/rad and reflex gain 2 -> 17 N m s/rad from -0.4 to
    /// +0.2 rad, of the order the real ankle shows.
    fn default() -> Self {
        ScheduledAnkle {
            inertia: 0.015,
            stiffness: [70.0, 80.0, 100.0],
            stiffness_growth: 0.0,
            damping: [0.8, 0.5, 0.0],
            background: [2.0, 10.0, 0.0],
            reflex: Some(ScheduledReflex {
                gain: [12.0, 25.0, 0.0],
                delay_s: 0.045,
                natural_hz: 3.0,
                damping_ratio: 0.7,
            }),
        }
    }
}

impl ScheduledAnkle {
    /// (K, B, G) at the angle `s`; G is 0 without a reflex.
    pub fn at(&self, s: f64) -> [f64; 3] {
        [
            self.stiffness_at(s),
            quadratic(&self.damping, s),
            self.reflex.map_or(0.0, |r| quadratic(&r.gain, s)),
        ]
    }

    /// Refuse a subject that cannot be simulated.
    pub fn validate(&self) -> Result<()> {
        let coefficients = self
            .stiffness
            .iter()
            .chain(&self.damping)
            .chain(&self.background)
            .chain(self.reflex.iter().flat_map(|r| r.gain.iter()));
        let finite = coefficients
            .clone()
            .all(|v| v.is_finite() && v.abs() <= 1e6);
        if !(finite
            && self.inertia.is_finite()
            && self.inertia > 0.0
            && self.inertia <= 1e3
            && self.stiffness_growth.is_finite()
            && self.stiffness_growth.abs() <= 20.0)
        {
            return Err(Error::invalid(
                "scheduled ankle",
                "coefficients finite and at most 1e6 in size, inertia in (0, 1000] kg m^2, stiffness_growth within ±20 per rad",
            ));
        }
        Ok(())
    }

    fn stiffness_at(&self, angle: f64) -> f64 {
        quadratic(&self.stiffness, angle) * (self.stiffness_growth * angle).exp()
    }

    /// The elastic torque from the operating angle `from` to the angle `to`:
    /// ∫ K(θ) dθ (three-point Gauss-Legendre: exact for the quadratic, and
    /// to about (growth (to - from))^6 with the exponential). K varies with
    /// the angle itself, so a perturbation of swing `a` sees its mean slope
    /// over `[s - a, s + a]`, not K(s): the truth is K(s), the local slope.
    fn elastic_torque(&self, from: f64, to: f64) -> f64 {
        let (middle, half) = (0.5 * (from + to), 0.5 * (to - from));
        let node = (0.6f64).sqrt() * half;
        half * (5.0 * self.stiffness_at(middle - node)
            + 8.0 * self.stiffness_at(middle)
            + 5.0 * self.stiffness_at(middle + node))
            / 9.0
    }
}

/// A ramp-and-hold schedule of operating angles with a continuous random
/// perturbation on top.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RampAndHold {
    /// Operating angles held, in order (rad).
    pub angles_rad: Vec<f64>,
    /// Hold duration (s).
    pub hold_s: f64,
    /// Ramp duration between holds (s).
    pub ramp_s: f64,
    /// Half-swing of the binary perturbation (rad).
    pub amplitude_rad: f64,
    /// Mean interval between its switches (s).
    pub switch_s: f64,
    /// Actuator bandwidth (Hz).
    pub actuator_hz: f64,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// White torque noise (N m).
    pub torque_noise_nm: f64,
    /// Keep the ramps; false: only the holds, each its own `trial`, with gaps.
    pub keep_ramps: bool,
    /// Write `q1` as the angle's offset from `sv` (REKLAB's parameter-varying
    /// recordings) instead of the whole angle.
    pub offset_angle: bool,
}

impl Default for RampAndHold {
    fn default() -> Self {
        RampAndHold {
            angles_rad: vec![
                -0.1, -0.4, 0.1, -0.25, 0.2, -0.05, -0.35, 0.15, -0.2, 0.05, -0.3, 0.0,
            ],
            hold_s: 6.0,
            ramp_s: 1.0,
            amplitude_rad: 0.015,
            switch_s: 0.1,
            actuator_hz: 15.0,
            rate_hz: 1000.0,
            torque_noise_nm: 0.1,
            keep_ramps: true,
            offset_angle: false,
        }
    }
}

impl RampAndHold {
    /// Refuse settings that cannot be simulated.
    pub fn validate(&self) -> Result<()> {
        let p = self;
        if let Some(a) = p
            .angles_rad
            .iter()
            .find(|a| !a.is_finite() || a.abs() > 3.2)
        {
            return Err(Error::invalid(
                "ramp-and-hold schedule",
                format!(
                    "angles_rad: {} is not within ±3.2 rad",
                    limpid_core::error::Num(*a)
                ),
            ));
        }
        if p.angles_rad.is_empty() {
            return Err(Error::invalid(
                "ramp-and-hold schedule",
                "angles_rad: expected at least one angle",
            ));
        }
        // an actuator of 1e-300 Hz never moved (q1 held at -0.1 rad; issue 76)
        crate::validate::fields_within(
            "ramp-and-hold schedule",
            &[
                ("rate_hz", p.rate_hz, 50.0, 1e5),
                ("actuator_hz", p.actuator_hz, 0.1, p.rate_hz / 4.0),
                ("hold_s", p.hold_s, 4.0 / p.rate_hz, 1e4),
                ("ramp_s", p.ramp_s, 0.0, 1e4),
                ("amplitude_rad", p.amplitude_rad, 1e-6, 1.0),
                ("switch_s", p.switch_s, 2.0 / p.rate_hz, 1e3),
                ("torque_noise_nm", p.torque_noise_nm, 0.0, 1e3),
            ],
        )?;
        crate::validate::check_size(self.duration_s() * p.rate_hz, "scheduled ankle recording")
    }

    /// Length of the schedule (s).
    pub fn duration_s(&self) -> f64 {
        self.angles_rad.len() as f64 * (self.hold_s + self.ramp_s) - self.ramp_s
    }
}

/// The operating angle at `t` s: holds joined by cosine ramps, and the index of the hold (None on a ramp).
fn operating_angle(p: &RampAndHold, t: f64) -> (f64, Option<usize>) {
    let period = p.hold_s + p.ramp_s;
    let k = ((t / period).floor() as usize).min(p.angles_rad.len() - 1);
    let within = t - k as f64 * period;
    if within < p.hold_s || k + 1 >= p.angles_rad.len() {
        return (p.angles_rad[k], Some(k));
    }
    let u = (within - p.hold_s) / p.ramp_s;
    let w = 0.5 * (1.0 - (std::f64::consts::PI * u).cos());
    (p.angles_rad[k] * (1.0 - w) + p.angles_rad[k + 1] * w, None)
}

/// Simulate the scheduled ankle: columns `t`, `q1` (rad), `tau1` (N m,
/// applied to the joint), `sv` (the operating angle commanded, rad) and, when
/// the ramps are left out, `trial` (the hold, 1..).
pub fn simulate_scheduled_ankle(
    s: &ScheduledAnkle,
    p: &RampAndHold,
    seed: u64,
) -> Result<Recording> {
    p.validate()?;
    s.validate()?;
    let duration = p.duration_s();
    let n = (duration * p.rate_hz).round() as usize;
    let h = 1.0 / (p.rate_hz * SUBSTEPS as f64);
    let mut rng = StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, p.torque_noise_nm)
        .map_err(|err| Error::invalid("torque noise", err.to_string()))?;
    let w = 2.0 * std::f64::consts::PI * p.actuator_hz;
    let p_switch = (h / p.switch_s).min(1.0);
    let mut u = p.amplitude_rad;
    let (mut q, mut qd) = (p.angles_rad[0], 0.0f64);
    let delay = s.reflex.map_or(0, |r| (r.delay_s / h).round() as usize);
    let mut history = vec![0.0f64; delay + 1];
    let (mut z, mut zd) = (0.0f64, 0.0f64);
    let mut cols: [Vec<f64>; 5] = Default::default();
    for k in 0..n * SUBSTEPS {
        let t = k as f64 * h;
        if rng.random::<f64>() < p_switch {
            u = -u;
        }
        let (sv, hold) = operating_angle(p, t);
        let qdd = w * w * (sv + u - q) - 2.0 * ACTUATOR_DAMPING * w * qd;
        if k % SUBSTEPS == 0 {
            // K and B of the whole angle; the velocity at the sample's time
            // (semi-implicit Euler's lags by h/2)
            let damp = quadratic(&s.damping, q);
            let tau = s.inertia * qdd
                + damp * (qd + 0.5 * h * qdd)
                + s.elastic_torque(sv, q)
                + quadratic(&s.background, sv)
                + z
                + noise.sample(&mut rng);
            if p.keep_ramps || hold.is_some() {
                cols[0].push(t);
                cols[1].push(if p.offset_angle { q - sv } else { q });
                cols[2].push(tau);
                cols[3].push(sv);
                cols[4].push(hold.map_or(0.0, |i| (i + 1) as f64));
            }
        }
        history[k % (delay + 1)] = qd;
        if let Some(r) = s.reflex {
            let v = if k >= delay {
                history[(k - delay) % (delay + 1)]
            } else {
                0.0
            };
            let wr = 2.0 * std::f64::consts::PI * r.natural_hz;
            let drive = quadratic(&r.gain, sv) * v.max(0.0);
            let zdd = wr * wr * (drive - z) - 2.0 * r.damping_ratio * wr * zd;
            zd += h * zdd;
            z += h * zd;
        }
        qd += h * qdd;
        q += h * qd;
    }
    let mut names: Vec<String> = ["t", "q1", "tau1", "sv", "trial"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let mut columns = cols.to_vec();
    if p.keep_ramps {
        names.pop();
        columns.pop();
    }
    Recording::new("virtual scheduled ankle", names, columns, 2)
}

/// The scheduled ankle's truth at `count` operating angles across the schedule.
pub fn scheduled_truth(s: &ScheduledAnkle, p: &RampAndHold, count: usize) -> VaryingTruth {
    let lo = p.angles_rad.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = p
        .angles_rad
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let count = count.max(2);
    let one = |v: f64| Matrix::from_rows(&[vec![v]]).expect("1 x 1");
    VaryingTruth {
        about: About {
            notes: vec!["ankle under a continuous random position perturbation on a ramp-and-hold schedule of operating angles (column sv)".into()],
            ..About::default()
        },
        schedule: "sv".into(),
        reflex_delay_s: s.reflex.map(|r| r.delay_s),
        points: (0..count)
            .map(|i| {
                let sigma = lo + (hi - lo) * i as f64 / (count - 1) as f64;
                let [k, b, g] = s.at(sigma);
                VaryingTruthPoint {
                    sigma,
                    stiffness: one(k),
                    damping: one(b),
                    inertia: one(s.inertia),
                    reflex_gain: s.reflex.map(|_| g),
                }
            })
            .collect(),
    }
}
