//! Virtual co-contraction experiments (seed 001 "Procedure and Tasks").
//!
//! Per level (0, 0.5, 0.75, 1 by default) the robot moves the hand 8 mm to
//! each of 18 evenly spread targets in 100 ms (cubic), holds 500 ms, returns
//! in 100 ms; each trial window starts with 50 ms of rest (the 1 s rests
//! between trials are not recorded, as in `../shared/examples/cocontraction`).
//! Stiffness depends on the level, K(c) = K0 + c dK; six EMG channels follow
//! emg_m = a_m (0.02 + activation_m) N(0,1) + N(0, 5 µV), with activation the
//! level times a muscle gain near 1. The MVC recording holds 5 s: rest,
//! ramp, full activation for 3 s, ramp, rest.

use nalgebra::{Matrix3, Vector3};
use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, Normal};

use crate::profile::Profile;
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
    /// Stiffness at level 0 (N/m).
    pub stiffness0: Matrix3<f64>,
    /// Stiffness added per unit level (N/m).
    pub stiffness_gain: Matrix3<f64>,
    /// EMG amplitude per muscle at full activation (V).
    pub emg_amplitude: [f64; 6],
    /// Activation per unit level, per muscle (about 1).
    pub activation_gain: [f64; 6],
}

impl CocontractionSubject {
    /// Stiffness at a level.
    pub fn stiffness(&self, level: f64) -> Matrix3<f64> {
        self.stiffness0 + self.stiffness_gain * level
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
    for (li, level) in protocol.levels.iter().enumerate() {
        let k = subject.stiffness(*level);
        for (di, dir) in protocol.directions.iter().enumerate() {
            let trial = li * protocol.directions.len() + di;
            let offset =
                Vector3::from_fn(|_, _| noise.offset_per_trial_std_n * unit.sample(&mut rng));
            for i in 0..per {
                let idx = trial * per + i;
                let t = i as f64 / fs;
                let (s1, v1, a1) = Profile::Cubic.eval(t - protocol.rest_s, protocol.move_s);
                let (s2, v2, a2) = Profile::Cubic.eval(t - back_start, protocol.move_s);
                let (s, sd, sdd) = (s1 - s2, v1 - v2, a1 - a2);
                let disp = dir * (protocol.radius_m * s);
                let f = subject.inertia * dir * (protocol.radius_m * sdd)
                    + subject.damping * dir * (protocol.radius_m * sd)
                    + k * disp
                    + offset;
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
                for (m, col) in cols[9..].iter_mut().enumerate() {
                    let act = level * subject.activation_gain[m];
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

/// Principal stiffnesses (K1, K2, K3) of seed 001 Table 1 (0 %) and Table 4
/// (100 % co-contraction), configurations 1-7, N/m.
pub const SEED001_PRINCIPAL: [([f64; 3], [f64; 3]); 7] = [
    ([2202.1, 711.5, 188.7], [2406.5, 910.1, 414.2]),
    ([2740.1, 661.3, 146.6], [2924.1, 1090.4, 355.2]),
    ([2807.6, 476.6, 268.1], [2955.3, 579.3, 374.0]),
    ([2046.6, 663.4, 471.1], [2182.5, 845.5, 608.0]),
    ([2550.1, 484.3, 301.1], [2827.8, 642.2, 393.4]),
    ([3264.9, 505.1, 247.7], [3471.0, 627.6, 417.7]),
    ([2549.9, 845.9, 368.3], [2701.0, 1191.2, 667.5]),
];

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
        for (c, (k0, k1)) in SEED001_PRINCIPAL.iter().enumerate() {
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
                    stiffness0: r0 * d0 * r0.transpose(),
                    stiffness_gain: r1 * Matrix3::from_diagonal(&gain) * r1.transpose(),
                    emg_amplitude: [amp(0), amp(1), amp(2), amp(3), amp(4), amp(5)],
                    activation_gain: [1.0, 0.97, 1.03, 0.98, 1.02, 1.0],
                },
            ));
        }
    }
    out
}
