//! The walking ankle (issue 61): a position-controlled platform or ankle
//! robot moves the ankle through a stride-to-stride varying gait trajectory
//! while the limb's impedance changes with gait phase (Rouse et al. 2014;
//! Lee & Hogan 2015; Shorter & Rouse 2018 measured stance stiffness rising
//! several-fold, from tens to some 400 N m/rad).
//!
//! Per stride k (duration `T_k`, phase `φ = (t - t_k) / T_k`):
//!
//! `tau = I q'' + r_k B(φ) (q - q_ref)' + r_k K(φ) (q - q_ref) + g_k T_bg(φ + d_k) + drift + noise`,
//! `q_ref = a_k Q(φ + d_k) + o_k`,
//!
//! with `r_k`, `a_k`, `g_k` ~ N(1, sd), `d_k` a timing jitter (phase) and
//! `o_k` an offset, blended into the next stride's values over phase
//! 0.85-1. The device follows `q_ref + u` through a second-order servo
//! (integrated on a 10x finer grid), so the servo's lag on the gait
//! trajectory itself is a real, phase-locked deviation from `q_ref` that the
//! limb answers: it belongs to the baseline. `u` is a ramp-and-hold pulse on
//! a share of the strides (`perturbation` column 1 while it runs) or a
//! smoothed random telegraph on every stride. The truth is K, B and I
//! against gait phase for `r = 1` (the population mean). Heel-strike events
//! can be missed or doubled on purpose, to test the stride checks.

use limpid_core::truth::{About, VaryingTruth, VaryingTruthPoint};
use limpid_core::{Error, Matrix, Recording, Result};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use super::{ACTUATOR_DAMPING, SUBSTEPS};

/// A periodic profile over gait phase: control points `(phase, value)`,
/// joined by smoothsteps (C1, flat at each point), wrapping from the last
/// point to the first at phase 1.
pub type Profile = Vec<[f64; 2]>;

fn profile_at(p: &Profile, phase: f64) -> f64 {
    let x = phase.rem_euclid(1.0);
    let n = p.len();
    let i = p.partition_point(|c| c[0] <= x);
    // before the first point or after the last: between the last and the first, wrapped
    let (a, b) = if i == 0 || i == n {
        (p[n - 1], [p[0][0] + 1.0, p[0][1]])
    } else {
        (p[i - 1], p[i])
    };
    let x = if i == 0 { x + 1.0 } else { x };
    let u = ((x - a[0]) / (b[0] - a[0])).clamp(0.0, 1.0);
    a[1] + (b[1] - a[1]) * u * u * (3.0 - 2.0 * u)
}

/// The walking ankle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WalkingAnkle {
    /// I: foot and device (kg m^2).
    pub inertia: f64,
    /// K(phase) (N m/rad).
    pub stiffness: Profile,
    /// B(phase) (N m s/rad).
    pub damping: Profile,
    /// The gait angle trajectory Q(phase) (rad, dorsiflexion +).
    pub angle: Profile,
    /// The background torque T_bg(phase) (N m).
    pub background: Profile,
    /// Stride-to-stride SD of the impedance's scale r_k.
    pub impedance_scale_sd: f64,
}

impl Default for WalkingAnkle {
    /// Stiffness from 50 N m/rad at heel strike to 380 at push-off (phase
    /// 0.52), 30 in swing; background torque to 100 N m.
    fn default() -> Self {
        WalkingAnkle {
            inertia: 0.03,
            stiffness: vec![
                [0.0, 50.0],
                [0.1, 60.0],
                [0.3, 160.0],
                [0.52, 380.0],
                [0.62, 120.0],
                [0.7, 30.0],
                [0.95, 30.0],
            ],
            damping: vec![
                [0.0, 1.2],
                [0.1, 1.3],
                [0.3, 2.0],
                [0.52, 3.2],
                [0.65, 1.2],
                [0.75, 0.7],
                [0.95, 0.8],
            ],
            angle: vec![
                [0.0, 0.0],
                [0.08, -0.09],
                [0.2, 0.0],
                [0.45, 0.15],
                [0.55, 0.08],
                [0.65, -0.2],
                [0.75, -0.08],
                [0.88, 0.02],
            ],
            background: vec![
                [0.0, 0.0],
                [0.05, -4.0],
                [0.15, 5.0],
                [0.3, 40.0],
                [0.5, 100.0],
                [0.6, 30.0],
                [0.66, 0.0],
                [0.95, 0.0],
            ],
            impedance_scale_sd: 0.05,
        }
    }
}

impl WalkingAnkle {
    /// (K, B) at gait phase `phase` for the population mean.
    pub fn at(&self, phase: f64) -> [f64; 2] {
        [
            profile_at(&self.stiffness, phase),
            profile_at(&self.damping, phase),
        ]
    }

    fn validate(&self) -> Result<()> {
        let bad = |why: String| Err(Error::invalid("walking ankle", why));
        for (name, p) in [
            ("stiffness", &self.stiffness),
            ("damping", &self.damping),
            ("angle", &self.angle),
            ("background", &self.background),
        ] {
            if p.len() < 2 || p.len() > 1000 {
                return bad(format!(
                    "{name}: expected 2 to 1000 control points (phase, value), found {}",
                    p.len()
                ));
            }
            if p.iter().any(|c| {
                !c[0].is_finite()
                    || !c[1].is_finite()
                    || !(0.0..1.0).contains(&c[0])
                    || c[1].abs() > 1e6
            }) {
                return bad(format!(
                    "{name}: control points are (phase in [0, 1), a finite value of at most 1e6)"
                ));
            }
            if p.windows(2).any(|w| w[1][0] <= w[0][0]) {
                return bad(format!("{name}: phases must increase"));
            }
        }
        if !(self.inertia > 0.0 && self.inertia < 10.0) {
            return bad(format!(
                "inertia must lie in (0, 10) kg m^2, found {}",
                self.inertia
            ));
        }
        if !(0.0..0.5).contains(&self.impedance_scale_sd) {
            return bad("impedance_scale_sd must lie in [0, 0.5)".into());
        }
        Ok(())
    }
}

/// The perturbation of a walking experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum WalkingPerturbation {
    /// One ramp-and-hold of the angle command on a share of the strides.
    Pulses {
        /// Share of the strides perturbed.
        share: f64,
        /// Amplitude range (rad); the sign is random.
        amplitude_rad: [f64; 2],
        /// Ramp duration range (s), minimum jerk.
        ramp_s: [f64; 2],
        /// Hold duration range (s).
        hold_s: [f64; 2],
        /// Onset phase range.
        onset_phase: [f64; 2],
    },
    /// A random telegraph on every stride, smoothed twice by a moving average.
    Continuous {
        /// Half-swing (rad).
        amplitude_rad: f64,
        /// Dwell range between switches (s).
        dwell_s: [f64; 2],
        /// Width of each moving average (s).
        smoothing_s: f64,
    },
}

/// The walking experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WalkingExperiment {
    /// Full strides recorded.
    pub strides: usize,
    /// Mean stride duration (s).
    pub stride_s: f64,
    /// Stride-to-stride SD of the duration (s).
    pub stride_sd_s: f64,
    /// Change of walking speed: the stride duration goes from (1 - x/2) to (1 + x/2) of the mean over the record.
    pub speed_change: f64,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Bandwidth of the device's position servo (Hz).
    pub servo_hz: f64,
    /// The perturbation.
    pub perturbation: WalkingPerturbation,
    /// SD of the stride's angle amplitude a_k, torque amplitude g_k (relative), timing d_k (phase) and angle offset o_k (rad).
    pub variability: [f64; 4],
    /// White torque noise (N m).
    pub torque_noise_nm: f64,
    /// Slowly coloured torque noise, 3 Hz low-pass (N m RMS).
    pub coloured_noise_nm: f64,
    /// Slow drift of the torque sensor (N m amplitude, 100-300 s).
    pub drift_nm: f64,
    /// White angle noise (rad).
    pub angle_noise_rad: f64,
    /// Share of heel strikes missing from the event column.
    pub missed_events: f64,
    /// Share of strides with an extra event 50-500 ms after the heel strike.
    pub double_events: f64,
}

impl Default for WalkingExperiment {
    fn default() -> Self {
        WalkingExperiment {
            strides: 300,
            stride_s: 1.1,
            stride_sd_s: 0.04,
            speed_change: 0.0,
            rate_hz: 500.0,
            servo_hz: 30.0,
            perturbation: WalkingExperiment::pulses(),
            variability: [0.02, 0.03, 0.002, 0.001],
            torque_noise_nm: 0.3,
            coloured_noise_nm: 0.3,
            drift_nm: 1.0,
            angle_noise_rad: 1e-4,
            missed_events: 0.0,
            double_events: 0.0,
        }
    }
}

impl WalkingExperiment {
    /// Ramp-and-holds of 30-50 mrad on a third of the strides, onset in the first half of the stride.
    pub fn pulses() -> WalkingPerturbation {
        WalkingPerturbation::Pulses {
            share: 1.0 / 3.0,
            amplitude_rad: [0.03, 0.05],
            ramp_s: [0.02, 0.03],
            hold_s: [0.1, 0.2],
            onset_phase: [0.0, 0.5],
        }
    }

    /// A ±20 mrad telegraph, dwell 50-150 ms, smoothed over 15 ms twice.
    pub fn continuous() -> WalkingPerturbation {
        WalkingPerturbation::Continuous {
            amplitude_rad: 0.02,
            dwell_s: [0.05, 0.15],
            smoothing_s: 0.015,
        }
    }

    /// Refuse settings that cannot be simulated.
    pub fn validate(&self) -> Result<()> {
        let bad = |why: &str| Err(Error::invalid("walking experiment", why));
        let range = |r: [f64; 2], lo: f64, hi: f64| {
            r[0].is_finite() && r[1].is_finite() && lo <= r[0] && r[0] <= r[1] && r[1] <= hi
        };
        if !(3..=100_000).contains(&self.strides) {
            return bad("strides: expected 3 to 100000");
        }
        let stride_ok = self.stride_s > 0.2 && self.stride_s < 10.0;
        if !(stride_ok && (0.0..0.2 * self.stride_s).contains(&self.stride_sd_s)) {
            return bad("stride_s must lie in (0.2, 10) s and stride_sd_s in [0, 20 % of it)");
        }
        if !(0.0..=1.0).contains(&self.speed_change) {
            return bad("speed_change must lie in [0, 1]");
        }
        let rate_ok = (100.0..=20_000.0).contains(&self.rate_hz);
        if !(rate_ok && self.servo_hz > 1.0 && self.servo_hz < self.rate_hz / 4.0) {
            return bad("rate_hz must lie in [100, 20000] and servo_hz in (1, rate / 4)");
        }
        let v = self.variability;
        if v.iter().any(|x| !x.is_finite() || *x < 0.0)
            || v[0] > 0.3
            || v[1] > 0.3
            || v[2] > 0.05
            || v[3] > 0.1
        {
            return bad("variability: [angle scale <= 0.3, torque scale <= 0.3, timing <= 0.05, offset <= 0.1 rad], none negative");
        }
        for x in [
            self.torque_noise_nm,
            self.coloured_noise_nm,
            self.drift_nm,
            self.angle_noise_rad,
        ] {
            if !(x.is_finite() && (0.0..1e3).contains(&x)) {
                return bad("noise levels must be finite, >= 0 and below 1000");
            }
        }
        if !(0.0..0.3).contains(&self.missed_events) || !(0.0..0.3).contains(&self.double_events) {
            return bad("missed_events and double_events are shares in [0, 0.3)");
        }
        match &self.perturbation {
            WalkingPerturbation::Pulses {
                share,
                amplitude_rad,
                ramp_s,
                hold_s,
                onset_phase,
            } => {
                let ok = *share > 0.0
                    && *share < 1.0
                    && range(*amplitude_rad, 0.0, 0.5)
                    && range(*ramp_s, 0.001, 1.0)
                    && range(*hold_s, 0.0, 2.0)
                    && range(*onset_phase, 0.0, 0.95);
                if !ok {
                    return bad("pulses: share in (0, 1), amplitude_rad within [0, 0.5], ramp_s within [0.001, 1], hold_s within [0, 2], onset_phase within [0, 0.95], each [low, high]");
                }
            }
            WalkingPerturbation::Continuous {
                amplitude_rad,
                dwell_s,
                smoothing_s,
            } => {
                let ok = *amplitude_rad > 0.0
                    && *amplitude_rad <= 0.5
                    && range(*dwell_s, 0.005, 5.0)
                    && (0.0..=1.0).contains(smoothing_s);
                if !ok {
                    return bad("continuous: amplitude_rad in (0, 0.5], dwell_s within [0.005, 5], smoothing_s in [0, 1]");
                }
            }
        }
        crate::validate::check_size(
            self.strides as f64 * self.stride_s * self.rate_hz,
            "walking recording",
        )
    }
}

/// A stride's own draws.
struct Stride {
    start: f64,
    duration: f64,
    r: f64,
    a: f64,
    g: f64,
    d: f64,
    o: f64,
}

/// One pulse: onset (s), amplitude, ramp, hold.
struct Pulse {
    onset: f64,
    amplitude: f64,
    ramp: f64,
    hold: f64,
}

impl Pulse {
    fn at(&self, t: f64) -> f64 {
        let s = t - self.onset;
        let mj = |u: f64| {
            let u = u.clamp(0.0, 1.0);
            u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)
        };
        if s <= 0.0 || s >= 2.0 * self.ramp + self.hold {
            0.0
        } else if s < self.ramp {
            self.amplitude * mj(s / self.ramp)
        } else if s < self.ramp + self.hold {
            self.amplitude
        } else {
            self.amplitude * (1.0 - mj((s - self.ramp - self.hold) / self.ramp))
        }
    }
    fn end(&self) -> f64 {
        self.onset + 2.0 * self.ramp + self.hold
    }
}

fn uniform(rng: &mut StdRng, r: [f64; 2]) -> f64 {
    if r[1] > r[0] {
        rng.random_range(r[0]..r[1])
    } else {
        r[0]
    }
}

fn normal(sd: f64) -> Normal<f64> {
    Normal::new(0.0, sd).expect("sd checked finite and >= 0")
}

/// Simulate walking: columns `t`, `q1` (rad), `tau1` (N m, applied to the
/// foot), `heel_strike` (0/1), and for pulses `perturbation` (0/1). The
/// record starts 40 % into a stride and ends 30 % into one.
pub fn simulate_walking(s: &WalkingAnkle, e: &WalkingExperiment, seed: u64) -> Result<Recording> {
    s.validate()?;
    e.validate()?;
    let mut rng = StdRng::seed_from_u64(seed);
    let unit = normal(1.0);
    // strides: one before the record and one after, whole
    let count = e.strides + 2;
    let mut strides = Vec::with_capacity(count);
    let mut start = 0.0;
    for k in 0..count {
        let trend = 1.0 + e.speed_change * (k as f64 / (count - 1) as f64 - 0.5);
        let duration =
            (e.stride_s * trend + e.stride_sd_s * unit.sample(&mut rng)).max(0.5 * e.stride_s);
        let v = e.variability;
        strides.push(Stride {
            start,
            duration,
            r: 1.0 + s.impedance_scale_sd * unit.sample(&mut rng),
            a: 1.0 + v[0] * unit.sample(&mut rng),
            g: 1.0 + v[1] * unit.sample(&mut rng),
            d: v[2] * unit.sample(&mut rng),
            o: v[3] * unit.sample(&mut rng),
        });
        start += duration;
    }
    let t0 = strides[0].start + 0.6 * strides[0].duration;
    let t1 = strides[count - 1].start + 0.3 * strides[count - 1].duration;
    let fs = e.rate_hz;
    let n = ((t1 - t0) * fs).floor() as usize;
    // the perturbation command at every sample (held over the sub-steps)
    let (command, active) = perturbation(e, &strides, t0, n, &mut rng);
    let h = 1.0 / (fs * SUBSTEPS as f64);
    let w = 2.0 * std::f64::consts::PI * e.servo_hz;
    let blend = |x: f64| {
        let u = ((x - 0.85) / 0.15).clamp(0.0, 1.0);
        u * u * (3.0 - 2.0 * u)
    };
    // reference and background of stride k (and its blend into k + 1) at time t
    let at = |t: f64, k: usize| -> (f64, f64, f64, f64) {
        let st = &strides[k];
        let phase = (t - st.start) / st.duration;
        let next = &strides[(k + 1).min(count - 1)];
        let b = blend(phase);
        let mix = |f: &dyn Fn(&Stride) -> f64| (1.0 - b) * f(st) + b * f(next);
        let q_ref = mix(&|x: &Stride| x.a * profile_at(&s.angle, phase + x.d) + x.o);
        let tau_bg = mix(&|x: &Stride| x.g * profile_at(&s.background, phase + x.d));
        (phase, q_ref, tau_bg, st.r)
    };
    let mut k = 0;
    let stride_at = |t: f64, k: &mut usize| {
        while *k + 1 < count && strides[*k + 1].start <= t {
            *k += 1;
        }
    };
    stride_at(t0, &mut k);
    let (_, q_ref0, _, _) = at(t0, k);
    let (mut q, mut qd) = (q_ref0, 0.0f64);
    let mut q_ref_prev = q_ref0;
    // a 100 Hz first-order low-pass of the command, then the servo
    let a_cmd = 1.0 - (-2.0 * std::f64::consts::PI * 100.0 * h).exp();
    let mut cmd = q_ref0;
    let torque_white = normal(e.torque_noise_nm);
    let angle_white = normal(e.angle_noise_rad);
    let coloured_drive = normal(1.0);
    let a_col = (-2.0 * std::f64::consts::PI * 3.0 / fs).exp();
    let col_scale = e.coloured_noise_nm * (1.0 - a_col * a_col).sqrt();
    let mut coloured = 0.0;
    let drift_period = rng.random_range(100.0..300.0);
    let drift_phase = rng.random_range(0.0..std::f64::consts::TAU);
    let mut cols: [Vec<f64>; 3] = [
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    ];
    for i in 0..n * SUBSTEPS {
        let t = t0 + i as f64 * h;
        stride_at(t, &mut k);
        let (phase, q_ref, tau_bg, r) = at(t, k);
        let sample = i / SUBSTEPS;
        cmd += a_cmd * (q_ref + command[sample] - cmd);
        let qdd = w * w * (cmd - q) - 2.0 * ACTUATOR_DAMPING * w * qd;
        if i % SUBSTEPS == 0 {
            let q_ref_d = (q_ref - q_ref_prev) / h;
            let [kk, bb] = s.at(phase);
            coloured = a_col * coloured + col_scale * coloured_drive.sample(&mut rng);
            let drift = e.drift_nm * (std::f64::consts::TAU * t / drift_period + drift_phase).sin();
            let tau = s.inertia * qdd
                + r * bb * (qd - q_ref_d)
                + r * kk * (q - q_ref)
                + tau_bg
                + drift
                + coloured
                + torque_white.sample(&mut rng);
            cols[0].push(t - t0);
            cols[1].push(q + angle_white.sample(&mut rng));
            cols[2].push(tau);
        }
        q_ref_prev = q_ref;
        qd += h * qdd;
        q += h * qd;
    }
    // heel strikes, some missed, some doubled
    let mut events = vec![0.0; n];
    for st in &strides {
        let i = ((st.start - t0) * fs).round();
        if i < 0.0 || i >= n as f64 {
            continue;
        }
        if rng.random::<f64>() >= e.missed_events {
            events[i as usize] = 1.0;
        }
        if rng.random::<f64>() < e.double_events {
            let j = i as usize + (rng.random_range(0.05..0.5) * fs) as usize;
            if j < n {
                events[j] = 1.0;
            }
        }
    }
    let mut names = vec![
        "t".to_string(),
        "q1".into(),
        "tau1".into(),
        "heel_strike".into(),
    ];
    let [t, qs, taus] = cols;
    let mut columns = vec![t, qs, taus, events];
    if let Some(active) = active {
        names.push("perturbation".into());
        columns.push(active);
    }
    Recording::new("virtual walking ankle", names, columns, 3)
}

/// The perturbation command per sample and, for pulses, the trigger column.
fn perturbation(
    e: &WalkingExperiment,
    strides: &[Stride],
    t0: f64,
    n: usize,
    rng: &mut StdRng,
) -> (Vec<f64>, Option<Vec<f64>>) {
    let fs = e.rate_hz;
    match &e.perturbation {
        WalkingPerturbation::Pulses {
            share,
            amplitude_rad,
            ramp_s,
            hold_s,
            onset_phase,
        } => {
            let mut command = vec![0.0; n];
            let mut active = vec![0.0; n];
            // the first and last (partial) strides are never perturbed
            for st in &strides[1..strides.len() - 1] {
                if rng.random::<f64>() >= *share {
                    continue;
                }
                let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
                let p = Pulse {
                    onset: st.start + uniform(rng, *onset_phase) * st.duration,
                    amplitude: sign * uniform(rng, *amplitude_rad),
                    ramp: uniform(rng, *ramp_s),
                    hold: uniform(rng, *hold_s),
                };
                let i0 = ((p.onset - t0) * fs).floor().max(0.0) as usize;
                let i1 = (((p.end() - t0) * fs).ceil() as usize).min(n);
                for i in i0..i1 {
                    let t = t0 + i as f64 / fs;
                    command[i] = p.at(t);
                    if t >= p.onset && t < p.end() {
                        active[i] = 1.0;
                    }
                }
            }
            (command, Some(active))
        }
        WalkingPerturbation::Continuous {
            amplitude_rad,
            dwell_s,
            smoothing_s,
        } => {
            let mut raw = vec![0.0; n];
            let mut sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
            let mut next = uniform(rng, *dwell_s) * fs;
            for (i, v) in raw.iter_mut().enumerate() {
                if i as f64 >= next {
                    sign = -sign;
                    next += uniform(rng, *dwell_s) * fs;
                }
                *v = sign * amplitude_rad;
            }
            let width = ((smoothing_s * fs).round() as usize).max(1);
            let smooth = |x: &[f64]| -> Vec<f64> {
                let mut out = vec![0.0; x.len()];
                let mut sum = 0.0;
                for i in 0..x.len() {
                    sum += x[i];
                    if i >= width {
                        sum -= x[i - width];
                    }
                    out[i] = sum / (i + 1).min(width) as f64;
                }
                out
            };
            (smooth(&smooth(&raw)), None)
        }
    }
}

/// The walking ankle's truth on a grid of gait phase 0, 0.01, ..., 0.99.
pub fn walking_truth(s: &WalkingAnkle, e: &WalkingExperiment) -> VaryingTruth {
    let one = |v: f64| Matrix::from_rows(&[vec![v]]).expect("1 x 1");
    let what = match e.perturbation {
        WalkingPerturbation::Pulses { .. } => {
            "ramp-and-hold pulses on a share of the strides (perturbation column)"
        }
        WalkingPerturbation::Continuous { .. } => "a smoothed random telegraph on every stride",
    };
    VaryingTruth {
        about: About {
            notes: vec![format!(
                "walking ankle, {} strides of {} s (SD {} s), {what}; K and B against gait phase (heel_strike to heel_strike), for the population mean of the stride-to-stride impedance scale",
                e.strides, e.stride_s, e.stride_sd_s
            )],
            ..About::default()
        },
        schedule: "gait phase".into(),
        reflex_delay_s: None,
        points: (0..100)
            .map(|i| {
                let phase = i as f64 / 100.0;
                let [k, b] = s.at(phase);
                VaryingTruthPoint {
                    sigma: phase,
                    stiffness: one(k),
                    damping: one(b),
                    inertia: one(s.inertia),
                    reflex_gain: None,
                }
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profiles_pass_through_their_points_and_wrap() {
        let p: Profile = vec![[0.1, 10.0], [0.5, 50.0], [0.8, 20.0]];
        assert_eq!(profile_at(&p, 0.5), 50.0);
        assert!((profile_at(&p, 0.3) - 30.0).abs() < 1e-12);
        // wraps from 0.8 (20) to 1.1 (10): halfway at 0.95
        assert!((profile_at(&p, 0.95) - 15.0).abs() < 1e-12);
        assert!((profile_at(&p, 0.05) - profile_at(&p, 1.05)).abs() < 1e-12);
    }

    #[test]
    fn a_walking_recording_has_its_strides_pulses_and_torque() {
        let e = WalkingExperiment {
            strides: 12,
            ..WalkingExperiment::default()
        };
        let rec = simulate_walking(&WalkingAnkle::default(), &e, 1).unwrap();
        let hs = rec.column("heel_strike").unwrap();
        assert_eq!(hs.iter().filter(|&&x| x == 1.0).count(), 13);
        assert!(rec.column("perturbation").unwrap().contains(&1.0));
        let tau = rec.column("tau1").unwrap();
        let peak = tau.iter().copied().fold(0.0, f64::max);
        assert!(
            peak > 80.0 && peak < 130.0,
            "background torque peaks near 100 N m: {peak}"
        );
    }
}
