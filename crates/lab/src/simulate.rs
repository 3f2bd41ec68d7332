//! A position-controlled robot imposes centre-out perturbations on a linear
//! virtual subject (seed 000 §II-B): for each target direction, a rest at the
//! start point, then the motion; the recording holds these windows back to
//! back, one `trial` id each, like the outside examples (`cartesian_slow`).
//!
//! Force applied to the limb: f = M x'' + B x' + K (x - S) + offset_trial +
//! drift + white noise, from exact kinematics of the profile; the recorded
//! position carries white noise (tracker/encoder).

use nalgebra::{Matrix3, Vector3};
use rand::{rngs::StdRng, Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use crate::profile::Profile;
use crate::subject::Posture;
use limpid_core::{Error, Recording, Result};
use limpid_dsp::LowPass;

/// Noise added by the virtual sensors (defaults: those of the outside examples).
///
/// | Name | Default | Purpose |
/// |---|---|---|
/// | `position_std_m` | 2e-5 m | white position noise |
/// | `offset_per_trial_std_n` | 3 N | per-trial force offset (sensor bias, arm weight) |
/// | `white_std_n` | 0.1 N | white force noise |
/// | `drift_std_n` | 0.05 N | slow force drift, continuous over the recording |
/// | `drift_lowpass_hz` | 0.5 Hz | bandwidth of the drift |
/// | `force_quantum_n` | 1/160 N | F/T sensor resolution (ATI-type 16-bit count; forces are rounded to it) |
/// | `servo_bandwidth_hz` | 30 Hz | the position-controlled robot follows its command through a critically damped 2nd-order servo of this natural frequency (tracking error ≈ velocity x 2/ω); 0: ideal tracking, the inertial force averaged over each sample period (a velocity step shows as M Δv / dt) |
/// | `force_noise_fraction` | 0 | signal-dependent force noise: s.d. this fraction of the subject's own force |K (x - S) + B x'|, per axis (motor noise grows with force, Harris & Wolpert 1998) |
/// | `force_noise_hz` | 2 Hz | bandwidth of that noise (motor-unit and voluntary fluctuations, low-passed) |
/// | `posture_drift_std_m` | 0 | the subject's equilibrium wanders by this s.d. (m), adding -K δ(t) to the force |
/// | `posture_drift_hz` | 0.3 Hz | bandwidth of the posture drift |
/// | `trial_impedance_std` | 0 | the subject changes from trial to trial: each trial's K and B are the posture's times 1 + this s.d. (fraction) x a unit normal, drawn per trial and matrix; the truth stays the posture's |
/// | `tremor_std_n` | 0 | physiological tremor: force noise of this s.d. (N) in a band of ±2 Hz around `tremor_hz` |
/// | `tremor_hz` | 10 Hz | the tremor's centre frequency |
/// | `force_sensor_hz` | 0 | the force sensor's own first-order low-pass (Hz; its lag reads as less damping, K τ with τ = 1/(2π f)); 0: ideal |
///
/// [`NoiseModel::realistic`] sets the last four to values that give seed
/// 000's fit correlations (0.87-0.94).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NoiseModel {
    /// Position noise (m, s.d.).
    pub position_std_m: f64,
    /// Force offset per trial (N, s.d.).
    pub offset_per_trial_std_n: f64,
    /// White force noise (N, s.d.).
    pub white_std_n: f64,
    /// Slow force drift (N, s.d.).
    pub drift_std_n: f64,
    /// Bandwidth of the drift (Hz).
    pub drift_lowpass_hz: f64,
    /// Force resolution (N); forces are rounded to it.
    pub force_quantum_n: f64,
    /// Natural frequency of the robot's position servo (Hz); 0: ideal tracking.
    pub servo_bandwidth_hz: f64,
    /// Signal-dependent force noise (fraction of the subject's own force).
    pub force_noise_fraction: f64,
    /// Bandwidth of the signal-dependent noise (Hz).
    pub force_noise_hz: f64,
    /// Drift of the subject's equilibrium posture (m, s.d.).
    pub posture_drift_std_m: f64,
    /// Bandwidth of the posture drift (Hz).
    pub posture_drift_hz: f64,
    /// Trial-to-trial change of the subject's K and B (relative s.d.).
    pub trial_impedance_std: f64,
    /// Tremor force noise (N, s.d.).
    pub tremor_std_n: f64,
    /// Tremor centre frequency (Hz).
    pub tremor_hz: f64,
    /// First-order low-pass of the force sensor (Hz); 0: ideal.
    pub force_sensor_hz: f64,
}

impl Default for NoiseModel {
    fn default() -> Self {
        NoiseModel {
            position_std_m: 2e-5,
            offset_per_trial_std_n: 3.0,
            white_std_n: 0.1,
            drift_std_n: 0.05,
            drift_lowpass_hz: 0.5,
            force_quantum_n: 1.0 / 160.0,
            servo_bandwidth_hz: 30.0,
            force_noise_fraction: 0.0,
            force_noise_hz: 2.0,
            posture_drift_std_m: 0.0,
            posture_drift_hz: 0.3,
            trial_impedance_std: 0.0,
            tremor_std_n: 0.0,
            tremor_hz: 10.0,
            force_sensor_hz: 0.0,
        }
    }
}

impl NoiseModel {
    /// A force as the sensor reports it: rounded to its resolution.
    pub fn quantise_force(&self, f: f64) -> f64 {
        if self.force_quantum_n > 0.0 {
            (f / self.force_quantum_n).round() * self.force_quantum_n
        } else {
            f
        }
    }

    /// Deviations, resolutions, the noise fraction and the servo bandwidth
    /// must be zero or positive, the bandwidths of the slow noises positive:
    /// a negative deviation or servo bandwidth simulated (issue 36).
    /// `Err` names the first field that is not.
    pub fn check(&self) -> std::result::Result<(), String> {
        // each at most a value no rig or subject comes near: beyond them the
        // simulation overflowed and its errors named a row of the recording
        // instead of this field (drift 3e5 N; issue 76)
        let non_negative = [
            ("position_std_m", self.position_std_m, 0.1),
            ("offset_per_trial_std_n", self.offset_per_trial_std_n, 1e4),
            ("white_std_n", self.white_std_n, 1e4),
            ("drift_std_n", self.drift_std_n, 1e4),
            ("force_quantum_n", self.force_quantum_n, 1e3),
            ("servo_bandwidth_hz", self.servo_bandwidth_hz, 1e5),
            ("force_noise_fraction", self.force_noise_fraction, 10.0),
            ("posture_drift_std_m", self.posture_drift_std_m, 0.1),
            ("trial_impedance_std", self.trial_impedance_std, 1.0),
            ("tremor_std_n", self.tremor_std_n, 1e4),
            ("force_sensor_hz", self.force_sensor_hz, 1e5),
        ];
        let num = limpid_core::error::Num;
        for (name, v, most) in non_negative {
            if !(v >= 0.0 && v <= most) {
                return Err(format!(
                    "{name} = {}: expected zero or a positive number up to {}",
                    num(v),
                    num(most)
                ));
            }
        }
        for (name, v) in [
            ("drift_lowpass_hz", self.drift_lowpass_hz),
            ("force_noise_hz", self.force_noise_hz),
            ("posture_drift_hz", self.posture_drift_hz),
            ("tremor_hz", self.tremor_hz),
        ] {
            if !(1e-3..=1e5).contains(&v) {
                return Err(format!(
                    "{name} = {}: expected a bandwidth of 0.001 to 1e5 Hz",
                    num(v)
                ));
            }
        }
        Ok(())
    }

    /// No noise at all (for exact-recovery tests).
    pub fn none() -> Self {
        NoiseModel {
            position_std_m: 0.0,
            offset_per_trial_std_n: 0.0,
            white_std_n: 0.0,
            drift_std_n: 0.0,
            drift_lowpass_hz: 0.5,
            force_quantum_n: 0.0,
            servo_bandwidth_hz: 0.0,
            force_noise_fraction: 0.0,
            posture_drift_std_m: 0.0,
            ..NoiseModel::default()
        }
    }

    /// The sensors of [`Default`] on a human subject: force fluctuation of
    /// 25 % of the subject's own force below 2 Hz (with slow 3 s motions the
    /// subject's voluntary corrections enter; seed 000 reports fit
    /// correlations of 0.87-0.94, which this reproduces), 0.5 mm of posture
    /// drift below 0.3 Hz and 0.3 N of slow force drift (grip, arm weight).
    pub fn realistic() -> Self {
        NoiseModel {
            drift_std_n: 0.3,
            force_noise_fraction: 0.25,
            force_noise_hz: 2.0,
            posture_drift_std_m: 5e-4,
            posture_drift_hz: 0.3,
            ..NoiseModel::default()
        }
    }

    /// [`NoiseModel::check`] at the sample rate `fs` (Hz): a tremor, when
    /// there is one, within the band the rate can hold.
    pub fn check_at(&self, fs: f64) -> std::result::Result<(), String> {
        self.check()?;
        for (name, v) in [
            ("drift_lowpass_hz", self.drift_lowpass_hz),
            ("force_noise_hz", self.force_noise_hz),
            ("posture_drift_hz", self.posture_drift_hz),
        ] {
            if v >= 0.5 * fs {
                return Err(format!(
                    "{name} = {}: at or above half the sample rate of {} Hz",
                    limpid_core::error::Num(v),
                    limpid_core::error::Num(fs)
                ));
            }
        }
        if self.tremor_std_n > 0.0 {
            tremor_band_fits(self.tremor_hz, fs)
                .map_err(|m| format!("tremor_hz = {}: {m}", self.tremor_hz))?;
        }
        Ok(())
    }

    /// The subject's own slow disturbances over `n` samples: signal-dependent
    /// noise factors (unit s.d.) and posture drift (m), three axes each.
    pub(crate) fn disturbances(&self, n: usize, fs: f64, rng: &mut StdRng) -> Result<Disturbances> {
        Ok(Disturbances {
            force_factor: slow_noise(n, fs, self.force_noise_hz, self.force_noise_fraction, rng)?,
            posture: slow_noise(n, fs, self.posture_drift_hz, self.posture_drift_std_m, rng)?,
            tremor: band_noise(n, fs, self.tremor_hz, self.tremor_std_n, rng)?,
        })
    }

    /// This trial's factors on K and B (1 without trial-to-trial change).
    pub(crate) fn trial_factors(&self, rng: &mut StdRng) -> (f64, f64) {
        if self.trial_impedance_std == 0.0 {
            return (1.0, 1.0);
        }
        let unit = Normal::new(0.0, 1.0).expect("unit normal is valid");
        let mut factor = || (1.0 + self.trial_impedance_std * unit.sample(rng)).max(0.1);
        (factor(), factor())
    }

    /// The force sensor's first-order low-pass, one state per axis; `None`
    /// for an ideal sensor.
    pub(crate) fn force_sensor(&self, fs: f64) -> Option<ForceSensor> {
        (self.force_sensor_hz > 0.0).then(|| ForceSensor {
            alpha: 1.0 - (-2.0 * std::f64::consts::PI * self.force_sensor_hz / fs).exp(),
            state: None,
        })
    }
}

/// A force sensor's first-order low-pass (see [`NoiseModel::force_sensor`]).
pub(crate) struct ForceSensor {
    alpha: f64,
    state: Option<Vector3<f64>>,
}

impl ForceSensor {
    /// The sensor's reading of the force `f` at the next sample.
    pub(crate) fn read(&mut self, f: Vector3<f64>) -> Vector3<f64> {
        let y = match self.state {
            Some(y) => y + (f - y) * self.alpha,
            None => f,
        };
        self.state = Some(y);
        y
    }
}

/// The tremor's band (±2 Hz around `hz`) below 0.45 x the sample rate `fs`.
fn tremor_band_fits(hz: f64, fs: f64) -> std::result::Result<(), String> {
    if hz + 2.0 > 0.45 * fs {
        return Err(format!(
            "the tremor's band (±2 Hz around it) must lie below 0.45 x the {} Hz sample rate, found {} Hz",
            limpid_core::error::Num(fs),
            limpid_core::error::Num(hz)
        ));
    }
    Ok(())
}

/// Three channels of noise in a band of ±2 Hz around `hz`, s.d. `std`
/// (the difference of two zero-phase low-passes of the same white noise).
fn band_noise(n: usize, fs: f64, hz: f64, std: f64, rng: &mut StdRng) -> Result<Vec<Vec<f64>>> {
    if std == 0.0 || n < 16 {
        return Ok(vec![vec![0.0; n]; 3]);
    }
    tremor_band_fits(hz, fs).map_err(|message| Error::invalid("tremor_hz", message))?;
    let (upper, lower) = (
        LowPass::butterworth(2, hz + 2.0, fs)?,
        LowPass::butterworth(2, (hz - 2.0).max(0.1), fs)?,
    );
    filtered_noise(n, std, rng, |w| {
        let (a, b) = (upper.filtfilt(w)?, lower.filtfilt(w)?);
        Ok(a.iter().zip(&b).map(|(a, b)| a - b).collect())
    })
}

/// The centre-out part of a protocol.
#[derive(Debug, Clone, Serialize)]
pub struct CentreOut {
    /// Profile of the motion.
    pub profile: Profile,
    /// Distance from start to target (m).
    pub radius_m: f64,
    /// Unit target directions.
    #[serde(skip)]
    pub directions: Vec<Vector3<f64>>,
    /// Rest before each motion (s).
    pub rest_s: f64,
    /// Duration of the motion (s).
    pub motion_s: f64,
    /// Recorded hold at the target after the motion, then a recorded return
    /// by the same profile (s); 0 and 0 record only rest and motion (seed 000).
    pub hold_s: f64,
    /// Duration of the return (s).
    pub return_s: f64,
    /// Sample rate (Hz).
    pub sample_rate: f64,
}

impl CentreOut {
    /// Seed 000: 16 directions on a 3 cm sphere, 3 s motions (6 s for the sinusoid), 500 Hz.
    pub fn seed000(profile: Profile) -> Self {
        CentreOut {
            profile,
            radius_m: 0.03,
            directions: crate::sphere::even_directions(16),
            rest_s: 0.2,
            motion_s: if profile == Profile::Sinusoid {
                6.0
            } else {
                3.0
            },
            hold_s: 0.0,
            return_s: 0.0,
            sample_rate: 500.0,
        }
    }

    /// Samples per trial window.
    pub fn samples_per_trial(&self) -> usize {
        ((self.rest_s + self.motion_s + self.hold_s + self.return_s) * self.sample_rate).round()
            as usize
    }
}

/// `minutes` of seed 000's cubic trials back to back at 500 Hz (3-D,
/// subject 1, 16 directions in turn, seed 42): the long recording of the
/// performance page, its benchmarks and the speed guard (issue 16, 82).
pub fn back_to_back_cubic_trials(minutes: f64) -> Result<Recording> {
    let mut protocol = CentreOut::seed000(crate::Profile::Cubic);
    let trials = (minutes * 60.0 / (protocol.rest_s + protocol.motion_s)).ceil() as usize;
    let dirs = crate::sphere::even_directions(16);
    protocol.directions = (0..trials).map(|i| dirs[i % dirs.len()]).collect();
    simulate_centre_out(
        &crate::seed000_subject1()[0],
        &protocol,
        &NoiseModel::default(),
        42,
    )
}

/// Simulate one posture's centre-out trials. Returns the recording (columns
/// `t,x,y,z,fx,fy,fz,trial`) and the applied per-trial force offsets.
pub fn simulate_centre_out(
    posture: &Posture,
    protocol: &CentreOut,
    noise: &NoiseModel,
    seed: u64,
) -> Result<Recording> {
    let mut rng = StdRng::seed_from_u64(seed);
    let per = protocol.samples_per_trial();
    let total = per * protocol.directions.len();
    let dt = 1.0 / protocol.sample_rate;
    let mut cols: Vec<Vec<f64>> = (0..8).map(|_| Vec::with_capacity(total)).collect();
    let drift = drift_signal(total, protocol.sample_rate, noise, &mut rng)?;
    let subject_noise = noise.disturbances(total, protocol.sample_rate, &mut rng)?;
    let unit = Normal::new(0.0, 1.0).expect("unit normal is valid");
    let (m, b, k): (Matrix3<f64>, Matrix3<f64>, Matrix3<f64>) =
        (posture.inertia, posture.damping, posture.stiffness);
    let omega = 2.0 * std::f64::consts::PI * noise.servo_bandwidth_hz;
    // commanded displacement (fraction of the radius), rate and acceleration:
    // out, hold, and back by the same profile
    let command_at = |t_in: f64| {
        let (s1, v1, a1) = protocol.profile.eval(t_in, protocol.motion_s);
        let (s2, v2, a2) = if protocol.return_s > 0.0 {
            protocol.profile.eval(
                t_in - protocol.motion_s - protocol.hold_s,
                protocol.return_s,
            )
        } else {
            (0.0, 0.0, 0.0)
        };
        (s1 - s2, v1 - v2, a1 - a2)
    };
    let mut sensor = noise.force_sensor(protocol.sample_rate);
    for (trial, dir) in protocol.directions.iter().enumerate() {
        let offset = Vector3::from_fn(|_, _| noise.offset_per_trial_std_n * unit.sample(&mut rng));
        let (k_factor, b_factor) = noise.trial_factors(&mut rng);
        // the servo's state: actual displacement along `dir` and its rate (starts at rest)
        let (mut servo_s, mut servo_v) = (0.0f64, 0.0f64);
        for i in 0..per {
            let idx = trial * per + i;
            let t_in = i as f64 * dt - protocol.rest_s;
            let (command, command_rate, _) = command_at(t_in);
            let (s, sd, sdd) = if omega == 0.0 {
                // ideal tracking: the force sensor averages over its sample
                // period, so a velocity step (the sinusoid starts and stops
                // moving at full speed) shows as the impulse M Δv / dt, not as
                // nothing (issue 37: without it M came out 0 and K off by -ω² M)
                let rate = |t: f64| command_at(t).1;
                let mean_acceleration = (rate(t_in + dt / 2.0) - rate(t_in - dt / 2.0)) / dt;
                (command, command_rate, mean_acceleration)
            } else {
                // actual motion: s'' = ω² (s_cmd - s) - 2 ω s' with the command
                // continuous in time, 20 semi-implicit Euler steps per sample
                let h = dt / 20.0;
                let accel = |c: f64, p: f64, v: f64| omega * omega * (c - p) - 2.0 * omega * v;
                let now = (servo_s, servo_v, accel(command, servo_s, servo_v));
                for j in 0..20 {
                    let c = command_at(t_in + j as f64 * h).0;
                    servo_v += accel(c, servo_s, servo_v) * h;
                    servo_s += servo_v * h;
                }
                now
            };
            let disp = dir * (protocol.radius_m * s);
            let vel = dir * (protocol.radius_m * sd);
            let acc = dir * (protocol.radius_m * sdd);
            let intrinsic = b * vel * b_factor + k * disp * k_factor;
            let f = m * acc + intrinsic + offset + subject_noise.force(idx, &intrinsic, &k);
            let f = sensor.as_mut().map_or(f, |s| s.read(f));
            let x = posture.start + disp;
            cols[0].push(idx as f64 * dt);
            for a in 0..3 {
                cols[1 + a].push(x[a] + noise.position_std_m * unit.sample(&mut rng));
                cols[4 + a].push(noise.quantise_force(
                    f[a] + drift[a][idx] + noise.white_std_n * unit.sample(&mut rng),
                ));
            }
            cols[7].push((trial + 1) as f64);
        }
    }
    let names = ["t", "x", "y", "z", "fx", "fy", "fz", "trial"]
        .map(String::from)
        .to_vec();
    Recording::new(format!("virtual:{}", posture.name), names, cols, 2)
}

/// The subject's own slow disturbances (see [`NoiseModel`]).
pub(crate) struct Disturbances {
    /// Signal-dependent noise: fraction of the subject's force, per axis.
    force_factor: Vec<Vec<f64>>,
    /// Equilibrium drift (m), per axis.
    posture: Vec<Vec<f64>>,
    /// Tremor force (N), per axis.
    tremor: Vec<Vec<f64>>,
}

impl Disturbances {
    /// The force the subject adds at sample `idx` to its own force `own`
    /// (stiffness and damping part) with stiffness `k`.
    pub(crate) fn force(&self, idx: usize, own: &Vector3<f64>, k: &Matrix3<f64>) -> Vector3<f64> {
        let delta = Vector3::from_fn(|a, _| self.posture[a][idx]);
        Vector3::from_fn(|a, _| self.force_factor[a][idx] * own[a].abs() + self.tremor[a][idx])
            - k * delta
    }
}

fn drift_signal(n: usize, fs: f64, noise: &NoiseModel, rng: &mut StdRng) -> Result<Vec<Vec<f64>>> {
    slow_noise(n, fs, noise.drift_lowpass_hz, noise.drift_std_n, rng)
}

/// Three channels of white noise low-passed at `hz` (2nd-order Butterworth,
/// zero-phase) and scaled to s.d. `std`.
pub(crate) fn slow_noise(
    n: usize,
    fs: f64,
    hz: f64,
    std: f64,
    rng: &mut StdRng,
) -> Result<Vec<Vec<f64>>> {
    if std == 0.0 || n < 16 {
        return Ok(vec![vec![0.0; n]; 3]);
    }
    let lp = LowPass::butterworth(2, hz, fs)?;
    filtered_noise(n, std, rng, |w| lp.filtfilt(w))
}

/// Three channels of uniform white noise through `filter`, each scaled to
/// s.d. `std`.
fn filtered_noise(
    n: usize,
    std: f64,
    rng: &mut StdRng,
    filter: impl Fn(&[f64]) -> Result<Vec<f64>>,
) -> Result<Vec<Vec<f64>>> {
    (0..3)
        .map(|_| {
            let w: Vec<f64> = (0..n).map(|_| rng.random::<f64>() - 0.5).collect();
            let y = filter(&w)?;
            let sd = (y.iter().map(|v| v * v).sum::<f64>() / n as f64)
                .sqrt()
                .max(1e-300);
            Ok(y.iter().map(|v| v / sd * std).collect())
        })
        .collect()
}
