//! Virtual co-contraction experiments (seed 001 "Procedure and Tasks").
//!
//! Per level (0, 0.5, 0.75, 1 by default) the robot moves the hand 8 mm to
//! each of 18 evenly spread targets in 100 ms (cubic), holds 500 ms, returns
//! in 100 ms; each trial window starts with 50 ms of rest (the 1 s rests
//! between trials are not recorded, as in the outside examples (`cocontraction`)).
//! Stiffness depends on the level, piecewise linear between knots (the clean
//! population: K(c) = K0 + c dK; the realistic subject of
//! [`seed001_realistic_population`]: seed 001 Tables 1-4 at 0, 50, 75, 100 %);
//! six EMG channels follow emg_m = a_m (0.02 + activation_m) N(0,1) + N(0,
//! 5 µV), with activation the level times a muscle gain near 1 (times a slow
//! wobble of the held level for the realistic subject). The MVC recording
//! holds 5 s: rest, ramp, full activation for 3 s, ramp, rest.

use nalgebra::{Matrix3, Vector3};
use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, Normal};

use crate::profile::Profile;
use crate::realistic::{seed001_stiffness, StretchReflex, SEED001_TABLES};
use limpid_core::{Recording, Result};

/// The six muscles of seed 001.
pub const MUSCLES: [&str; 6] = [
    "emg_deltoid_anterior",
    "emg_deltoid_posterior",
    "emg_pectoralis",
    "emg_trapezius",
    "emg_biceps",
    "emg_triceps_long",
];

/// A subject in one arm configuration.
#[derive(Debug, Clone)]
pub struct CocontractionSubject {
    /// Configuration name.
    pub name: String,
    /// Start point (m).
    pub start: Vector3<f64>,
    /// M (kg).
    pub inertia: Matrix3<f64>,
    /// B (N s/m).
    pub damping: Matrix3<f64>,
    /// Stiffness (N/m) at levels in increasing order; linear between them,
    /// constant beyond the ends.
    pub stiffness_knots: Vec<(f64, Matrix3<f64>)>,
    /// EMG amplitude per muscle at full activation (V).
    pub emg_amplitude: [f64; 6],
    /// Activation per unit level, per muscle (about 1).
    pub activation_gain: [f64; 6],
    /// Stretch reflex, if any.
    pub reflex: Option<crate::realistic::StretchReflex>,
    /// s.d. of the slow wobble of the held activation (fraction of the level;
    /// 0: held exactly).
    pub activation_wobble: f64,
}

impl CocontractionSubject {
    /// Stiffness at a level.
    pub fn stiffness(&self, level: f64) -> Matrix3<f64> {
        let knots = &self.stiffness_knots;
        let Some(first) = knots.first() else {
            return Matrix3::zeros();
        };
        if level <= first.0 {
            return first.1;
        }
        for pair in knots.windows(2) {
            let ((l0, k0), (l1, k1)) = (pair[0], pair[1]);
            if level <= l1 {
                let t = (level - l0) / (l1 - l0);
                return k0 + (k1 - k0) * t;
            }
        }
        knots[knots.len() - 1].1
    }
}

/// Protocol of a co-contraction session.
#[derive(Debug, Clone)]
pub struct CocontractionProtocol {
    /// Co-contraction levels (fraction of MVC), one block of trials each.
    pub levels: Vec<f64>,
    /// Unit target directions.
    pub directions: Vec<Vector3<f64>>,
    /// Perturbation amplitude (m).
    pub radius_m: f64,
    /// Rest before each motion (s).
    pub rest_s: f64,
    /// Duration of the motion (s).
    pub move_s: f64,
    /// Hold at the target (s).
    pub hold_s: f64,
    /// Sample rate (Hz).
    pub sample_rate: f64,
}

impl CocontractionProtocol {
    /// Seed 001: 4 levels, 18 directions at 8 mm, 50 ms rest, 100 ms out, 500 ms hold, 100 ms back, 1 kHz.
    pub fn seed001() -> Self {
        CocontractionProtocol {
            levels: vec![0.0, 0.5, 0.75, 1.0],
            directions: crate::sphere::even_directions(18),
            radius_m: 0.008,
            rest_s: 0.05,
            move_s: 0.1,
            hold_s: 0.5,
            sample_rate: 1000.0,
        }
    }
}

/// Simulate the session (`t,x,y,z,fx,fy,fz,trial,level,emg_*`) and its MVC recording.
pub fn simulate_cocontraction(
    subject: &CocontractionSubject,
    protocol: &CocontractionProtocol,
    noise: &crate::NoiseModel,
    seed: u64,
) -> Result<(Recording, Recording)> {
    let mut rng = StdRng::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).expect("unit normal is valid");
    let fs = protocol.sample_rate;
    let trial_s = protocol.rest_s + 2.0 * protocol.move_s + protocol.hold_s;
    let per = (trial_s * fs).round() as usize;
    let trials = protocol.levels.len() * protocol.directions.len();
    let total = per * trials;
    let mut cols: Vec<Vec<f64>> = (0..9 + MUSCLES.len())
        .map(|_| Vec::with_capacity(total))
        .collect();
    let back_start = protocol.rest_s + protocol.move_s + protocol.hold_s;
    let subject_noise = noise.disturbances(total, fs, &mut rng)?;
    // the held level wobbles slowly (feedback keeps it near the target)
    let wobble = crate::simulate::slow_noise(total, fs, 0.5, subject.activation_wobble, &mut rng)?;
    // commanded displacement (fraction of the radius), rate, acceleration in a trial
    let motion = |t: f64| {
        let (s1, v1, a1) = Profile::Cubic.eval(t - protocol.rest_s, protocol.move_s);
        let (s2, v2, a2) = Profile::Cubic.eval(t - back_start, protocol.move_s);
        (s1 - s2, v1 - v2, a1 - a2)
    };
    let mut sensor = noise.force_sensor(fs);
    for (li, level) in protocol.levels.iter().enumerate() {
        let k = subject.stiffness(*level);
        for (di, dir) in protocol.directions.iter().enumerate() {
            let trial = li * protocol.directions.len() + di;
            let offset =
                Vector3::from_fn(|_, _| noise.offset_per_trial_std_n * unit.sample(&mut rng));
            let (k_factor, b_factor) = noise.trial_factors(&mut rng);
            for i in 0..per {
                let idx = trial * per + i;
                let t = i as f64 / fs;
                let (s, sd, sdd) = motion(t);
                let disp = dir * (protocol.radius_m * s);
                let vel = dir * (protocol.radius_m * sd);
                let intrinsic = subject.damping * vel * b_factor + k * disp * k_factor;
                // stretch reflex: opposes the velocity of `delay` earlier
                let reflex = subject.reflex.map_or(Vector3::zeros(), |r| {
                    let earlier = dir * (protocol.radius_m * motion(t - r.delay_s).1);
                    subject.damping * earlier * r.gain(*level)
                });
                let f = subject.inertia * dir * (protocol.radius_m * sdd)
                    + intrinsic
                    + reflex
                    + offset
                    + subject_noise.force(idx, &intrinsic, &k);
                let f = sensor.as_mut().map_or(f, |s| s.read(f));
                cols[0].push(idx as f64 / fs);
                for a in 0..3 {
                    cols[1 + a].push(
                        subject.start[a] + disp[a] + noise.position_std_m * unit.sample(&mut rng),
                    );
                    cols[4 + a].push(
                        noise.quantise_force(f[a] + noise.white_std_n * unit.sample(&mut rng)),
                    );
                }
                cols[7].push((trial + 1) as f64);
                cols[8].push(*level);
                let held = level * (1.0 + wobble[0][idx]);
                for (m, col) in cols[9..].iter_mut().enumerate() {
                    let act = (held * subject.activation_gain[m]).max(0.0);
                    col.push(emg_sample(subject.emg_amplitude[m], act, &unit, &mut rng));
                }
            }
        }
    }
    let mut names: Vec<String> = ["t", "x", "y", "z", "fx", "fy", "fz", "trial", "level"]
        .map(String::from)
        .to_vec();
    names.extend(MUSCLES.iter().map(|m| m.to_string()));
    let rec = Recording::new(format!("virtual:{}", subject.name), names.clone(), cols, 2)?;

    // MVC: 0.5 s rest, 0.5 s ramp, 3 s full, 0.5 s ramp, 0.5 s rest; arm still
    let n = (5.0 * fs) as usize;
    let mut mvc: Vec<Vec<f64>> = (0..names.len()).map(|_| Vec::with_capacity(n)).collect();
    for i in 0..n {
        let t = i as f64 / fs;
        let act = match t {
            t if t < 0.5 => 0.0,
            t if t < 1.0 => (t - 0.5) / 0.5,
            t if t < 4.0 => 1.0,
            t if t < 4.5 => (4.5 - t) / 0.5,
            _ => 0.0,
        };
        mvc[0].push(t);
        for a in 0..3 {
            mvc[1 + a].push(subject.start[a] + noise.position_std_m * unit.sample(&mut rng));
            mvc[4 + a].push(noise.quantise_force(noise.white_std_n * unit.sample(&mut rng)));
        }
        mvc[7].push(0.0);
        mvc[8].push(1.0);
        for (m, col) in mvc[9..].iter_mut().enumerate() {
            col.push(emg_sample(subject.emg_amplitude[m], act, &unit, &mut rng));
        }
    }
    let mvc = Recording::new(format!("virtual:{}.mvc", subject.name), names, mvc, 2)?;
    Ok((rec, mvc))
}

fn emg_sample(amplitude: f64, activation: f64, unit: &Normal<f64>, rng: &mut StdRng) -> f64 {
    amplitude * (0.02 + activation) * unit.sample(rng) + 5e-6 * unit.sample(rng)
}

/// A virtual study population: `subjects` x the 7 configurations of seed 001.
///
/// Level 0 has seed 001 Table 1's principal stiffnesses (times a subject
/// factor 0.9-1.1) with a random orientation; at level 1 each principal
/// stiffness grows to Table 4's value, the increase being applied along axes
/// turned by 15 degrees about the primary axis, so the secondary and tertiary
/// axes rotate and the primary one hardly does (seed 001 Table 5).
pub fn seed001_population(subjects: usize, seed: u64) -> Vec<(usize, usize, CocontractionSubject)> {
    let mut rng = StdRng::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).expect("unit normal is valid");
    let mut out = Vec::new();
    for s in 0..subjects {
        let factor = 0.9 + 0.2 * (s as f64 + 0.5) / subjects as f64;
        for (c, (first, last)) in SEED001_TABLES[0].iter().zip(&SEED001_TABLES[3]).enumerate() {
            let (k0, k1) = (&first[4..7], &last[4..7]);
            let axis = Vector3::from_fn(|_, _| unit.sample(&mut rng));
            let angle = unit.sample(&mut rng);
            let r0 =
                nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle)
                    .into_inner();
            let d0 = Matrix3::from_diagonal(&Vector3::new(k0[0], k0[1], k0[2])) * factor;
            let gain = Vector3::new(k1[0] - k0[0], k1[1] - k0[1], k1[2] - k0[2]) * factor;
            let turn = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), 15f64.to_radians())
                .into_inner();
            let r1 = r0 * turn;
            let inertia = Matrix3::from_diagonal(&Vector3::new(1.6, 1.7, 1.5)) * factor;
            let damping = Matrix3::from_diagonal(&Vector3::new(16.0, 19.0, 18.0)) * factor;
            let amp = |m: usize| 3e-4 + 1e-4 * ((s * 7 + c * 3 + m) % 6) as f64;
            out.push((
                s + 1,
                c + 1,
                CocontractionSubject {
                    name: format!("s{}_c{}", s + 1, c + 1),
                    start: Vector3::new(0.3, -0.2 + 0.02 * c as f64, 0.05),
                    inertia,
                    damping,
                    stiffness_knots: vec![
                        (0.0, r0 * d0 * r0.transpose()),
                        (
                            1.0,
                            r0 * d0 * r0.transpose()
                                + r1 * Matrix3::from_diagonal(&gain) * r1.transpose(),
                        ),
                    ],
                    emg_amplitude: [amp(0), amp(1), amp(2), amp(3), amp(4), amp(5)],
                    activation_gain: [1.0, 0.97, 1.03, 0.98, 1.02, 1.0],
                    reflex: None,
                    activation_wobble: 0.0,
                },
            ));
        }
    }
    out
}

/// The realistic seed 001 population: `subjects` x 7 configurations with
/// seed 001 Tables 1-5's stiffness per configuration and level
/// ([`seed001_stiffness`]; subject factors 0.9-1.1 averaging 1), a stretch
/// reflex ([`StretchReflex::typical`]), a 5 % wobble of the held level, and
/// the inertia, damping and EMG of [`seed001_population`].
pub fn seed001_realistic_population(
    subjects: usize,
    seed: u64,
) -> Vec<(usize, usize, CocontractionSubject)> {
    let tables: Vec<_> = (0..7).map(seed001_stiffness).collect();
    seed001_population(subjects, seed)
        .into_iter()
        .map(|(s, c, mut subject)| {
            let factor = 0.9 + 0.2 * (s as f64 - 0.5) / subjects as f64;
            subject.stiffness_knots = tables[c - 1]
                .knots
                .iter()
                .map(|(l, k)| (*l, k * factor))
                .collect();
            subject.reflex = Some(StretchReflex::typical());
            subject.activation_wobble = 0.05;
            (s, c, subject)
        })
        .collect()
}
