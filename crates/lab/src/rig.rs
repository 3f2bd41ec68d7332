//! The mechanical spring array of seed 004 (§III-A2) and a virtual
//! stochastic experiment on it.
//!
//! Stiffness, eq. (10), in SI (N/m, N/rad, N m/m, N m/rad) for coordinates
//! (x, z, θ about y). The geometry enters through four constants, which the
//! paper does not list: `r_hv` and `r_d` (free length over l of the
//! horizontal/vertical and diagonal springs), `c1 = L - l` and `c2 = (L - l) L`.
//! [`Geometry::from_k_sa1`] holds the values that reproduce the paper's K_sa1,
//! inferred from it (as in the outside examples (`stochastic/*.truth.json`)).
//!
//! Stochastic input (§III-C): independent uniform white noise per channel
//! through a causal 8th-order Butterworth low-pass at 15 Hz, scaled to a peak.
//! Virtual experiment: a force-controlled robot with desired impedance
//! `M_rd x'' + B_rd x' + K_rd x = u - f` coupled to the array
//! `f = M x'' + B x' + K x`, discretised exactly with a zero-order hold.

use nalgebra::{DMatrix, DVector, Matrix3};
use rand::{rngs::StdRng, Rng, SeedableRng};
use rand_distr::{Distribution, Normal};

use limpid_core::{Recording, Result};
use limpid_dsp::LowPass;

/// Spring constants (N/m) of the eight mounts: `[k1a, k1b, k2a, k2b, k3a, k3b, k4a, k4b]`.
pub type Springs = [f64; 8];

/// Seed 004 Table II, configuration sa1.
pub const SA1: Springs = [38.0615, 38.0615, 38.0615, 38.0615, 0.0, 0.0, 0.0, 66.3707];
/// Seed 004 Table II, configuration sa2 (springs 4a and 4b exchanged).
pub const SA2: Springs = [38.0615, 38.0615, 38.0615, 38.0615, 0.0, 0.0, 66.3707, 0.0];
/// The spring set of the outside examples (`stochastic/ex_sa3`) (N/m, k1a..k4b).
pub const SPRING_SET_SA3: Springs = [50.0, 50.0, 30.0, 30.0, 0.0, 66.3707, 0.0, 0.0];

/// Geometry constants of eq. (10).
#[derive(Debug, Clone, Copy)]
pub struct Geometry {
    /// Free length over l of the horizontal and vertical springs.
    pub r_hv: f64,
    /// Free length over l of the diagonal springs.
    pub r_d: f64,
    /// c1 = L - l (m).
    pub c1: f64,
    /// c2 = (L - l) L (m^2).
    pub c2: f64,
}

impl Geometry {
    /// The constants that reproduce the paper's K_sa1.
    pub fn from_k_sa1() -> Self {
        Geometry {
            r_hv: 0.4750009852475596,
            r_d: 0.6349979918095346,
            c1: -0.03199946677935429,
            c2: 0.003584029407480477,
        }
    }
}

/// Linearised stiffness of the spring array, eq. (10), SI units.
pub fn spring_array_stiffness(k: &Springs, g: &Geometry) -> Matrix3<f64> {
    let [k1a, k1b, k2a, k2b, k3a, k3b, k4a, k4b] = *k;
    let hv = 1.0 - g.r_hv;
    let d_half = 1.0 - g.r_d / (2.0 * 2f64.sqrt());
    let d_full = 1.0 - g.r_d / 2f64.sqrt();
    let diag = k3a + k3b + k4a + k4b;
    let k11 = k1a + k1b + (k2a + k2b) * hv + diag * d_half;
    let k22 = (k1a + k1b) * hv + k2a + k2b + diag * d_half;
    let k12 = (-k3a - k3b + k4a + k4b) * g.r_d / (2.0 * 2f64.sqrt());
    let k13 = g.c1 * ((-k2a + k2b) * hv + (-k3a + k3b + k4a - k4b) * d_full);
    let k23 = g.c1 * ((-k1a + k1b) * hv + (-k3a + k3b - k4a + k4b) * d_full);
    let k33 = g.c2 * ((k1a + k1b + k2a + k2b) * hv + 2.0 * diag * d_full);
    Matrix3::new(k11, k12, k13, k12, k22, k23, k13, k23, k33)
}

/// The paper's K_sa1 as printed (cN/cm, cN/deg, cN cm/cm, cN cm/deg), converted to SI.
pub fn k_sa1_paper_si() -> Matrix3<f64> {
    let per_deg = 180.0 / std::f64::consts::PI; // 1/deg -> 1/rad
    let cn = 0.01; // cN -> N
    let cm = 0.01; // cm -> m
    Matrix3::new(
        167.5576 * cn / cm,
        14.9006 * cn / cm,
        2.0424 * cn * per_deg,
        14.9006 * cn / cm,
        167.5576 * cn / cm,
        -2.0424 * cn * per_deg,
        117.0200 * cn * cm / cm,
        -117.0200 * cn * cm / cm,
        95.7488 * cn * cm * per_deg,
    )
}

/// Seed 004 §III-C: uniform noise through a causal Butterworth low-pass
/// (8th order, `cutoff_hz`), each channel scaled so that its largest
/// magnitude is `peak[c]`.
pub fn stochastic_input(
    n: usize,
    fs: f64,
    peak: &[f64],
    cutoff_hz: f64,
    seed: u64,
) -> Result<Vec<Vec<f64>>> {
    let lp = LowPass::butterworth(8, cutoff_hz, fs)?;
    let mut rng = StdRng::seed_from_u64(seed);
    Ok(peak
        .iter()
        .map(|p| {
            let w: Vec<f64> = (0..n).map(|_| rng.random::<f64>() * 2.0 - 1.0).collect();
            let y = lp.filter_causal(&w);
            let max = y.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
            y.iter().map(|v| v / max * p).collect()
        })
        .collect())
}

/// The rig and robot of a virtual stochastic experiment (3 coordinates x, z, θ).
#[derive(Debug, Clone)]
pub struct RigExperiment {
    /// Inertia of the rig (SI).
    pub inertia: Matrix3<f64>,
    /// Damping of the rig (SI).
    pub damping: Matrix3<f64>,
    /// Stiffness of the spring array (SI).
    pub stiffness: Matrix3<f64>,
    /// Desired robot impedance (seed 004 §III-B).
    pub robot_inertia: Matrix3<f64>,
    /// Desired robot damping (SI).
    pub robot_damping: Matrix3<f64>,
    /// Desired robot stiffness (SI).
    pub robot_stiffness: Matrix3<f64>,
    /// Duration (s).
    pub seconds: f64,
    /// Sample rate (Hz).
    pub sample_rate: f64,
    /// Peak commanded force/torque per channel (N, N, N m).
    pub peak: [f64; 3],
    /// Cut-off of the inputs' 8th-order Butterworth low-pass (Hz).
    pub cutoff_hz: f64,
}

impl RigExperiment {
    /// Spring array `springs` with the handle's mass 0.6028 kg and inertia
    /// 3.4492 kg cm², damping ratio 0.01; the robot of the outside examples (`stochastic`).
    pub fn spring_array(springs: &Springs) -> Self {
        let k = spring_array_stiffness(springs, &Geometry::from_k_sa1());
        let m = Matrix3::from_diagonal(&nalgebra::Vector3::new(0.6028, 0.6028, 3.4492e-4));
        let b = Matrix3::from_fn(|i, j| {
            if i == j {
                2.0 * 0.01 * (k[(i, i)] * m[(i, i)]).sqrt()
            } else {
                0.0
            }
        });
        RigExperiment {
            inertia: m,
            damping: b,
            stiffness: k,
            robot_inertia: Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, 0.01)),
            robot_damping: Matrix3::from_diagonal(&nalgebra::Vector3::new(40.0, 60.0, 0.4)),
            robot_stiffness: Matrix3::from_diagonal(&nalgebra::Vector3::new(100.0, 100.0, 2.0)),
            seconds: 50.0,
            sample_rate: 1000.0,
            peak: [40.0, 40.0, 4.9],
            cutoff_hz: 15.0,
        }
    }
}

/// Simulate `t, x, z, theta, fx, fz, tauy, ux, uz, utheta` (force on the rig),
/// with position/angle noise of `noise_std` (m, rad).
pub fn simulate_rig(e: &RigExperiment, noise_std: [f64; 2], seed: u64) -> Result<Recording> {
    let fs = e.sample_rate;
    let dt = 1.0 / fs;
    let n = (e.seconds * fs).round() as usize + 1;
    let pre = (5.0 * fs) as usize; // settle, then discard
    let u = stochastic_input(n + pre, fs, &e.peak, e.cutoff_hz, seed)?;
    let mt = e.inertia + e.robot_inertia;
    let bt = e.damping + e.robot_damping;
    let kt = e.stiffness + e.robot_stiffness;
    let mt_inv = mt
        .try_inverse()
        .ok_or_else(|| limpid_core::Error::invalid("rig", "singular total inertia"))?;
    // state s = [x; x'], s' = A s + G u
    let mut a = DMatrix::<f64>::zeros(6, 6);
    let mut g = DMatrix::<f64>::zeros(6, 3);
    for i in 0..3 {
        a[(i, 3 + i)] = 1.0;
    }
    let ak = -mt_inv * kt;
    let ab = -mt_inv * bt;
    for i in 0..3 {
        for j in 0..3 {
            a[(3 + i, j)] = ak[(i, j)];
            a[(3 + i, 3 + j)] = ab[(i, j)];
            g[(3 + i, j)] = mt_inv[(i, j)];
        }
    }
    // exact zero-order hold: exp([[A, G], [0, 0]] dt)
    let mut aug = DMatrix::<f64>::zeros(9, 9);
    aug.view_mut((0, 0), (6, 6)).copy_from(&a);
    aug.view_mut((0, 6), (6, 3)).copy_from(&g);
    let phi = (aug * dt).exp();
    let ad = phi.view((0, 0), (6, 6)).into_owned();
    let gd = phi.view((0, 6), (6, 3)).into_owned();
    let mut rng = StdRng::seed_from_u64(seed.wrapping_add(1));
    let unit = Normal::new(0.0, 1.0).expect("unit normal is valid");
    let mut s = DVector::<f64>::zeros(6);
    let mut cols: Vec<Vec<f64>> = (0..10).map(|_| Vec::with_capacity(n)).collect();
    let force = |s: &DVector<f64>, uk: &DVector<f64>| {
        let x = s.rows(0, 3).into_owned();
        let v = s.rows(3, 3).into_owned();
        let acc = mt_inv * (uk - bt * &v - kt * &x);
        e.inertia * acc + e.damping * v + e.stiffness * x
    };
    for k in 0..n + pre {
        let uk = DVector::from_fn(3, |c, _| u[c][k]);
        if k >= pre {
            // the sampled force is the mean of its limits just before and after the input steps
            let prev = DVector::from_fn(3, |c, _| u[c][k.saturating_sub(1)]);
            let f = (force(&s, &uk) + force(&s, &prev)) * 0.5;
            let i = k - pre;
            cols[0].push(i as f64 * dt);
            cols[1].push(s[0] + noise_std[0] * unit.sample(&mut rng));
            cols[2].push(s[1] + noise_std[0] * unit.sample(&mut rng));
            cols[3].push(s[2] + noise_std[1] * unit.sample(&mut rng));
            for c in 0..3 {
                cols[4 + c].push(f[c]);
                cols[7 + c].push(uk[c]);
            }
        }
        s = &ad * &s + &gd * &uk;
    }
    let names = [
        "t", "x", "z", "theta", "fx", "fz", "tauy", "ux", "uz", "utheta",
    ]
    .map(String::from)
    .to_vec();
    Recording::new("virtual:spring-array", names, cols, 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_k_sa1_is_symmetric_in_si_and_reproduced_by_eq_10() {
        let paper = k_sa1_paper_si();
        assert!(
            (paper[(0, 2)] - paper[(2, 0)]).abs() / paper[(0, 2)].abs() < 1e-4,
            "{paper}"
        );
        assert!((paper[(1, 2)] - paper[(2, 1)]).abs() / paper[(1, 2)].abs() < 1e-4);
        let k = spring_array_stiffness(&SA1, &Geometry::from_k_sa1());
        for i in 0..3 {
            for j in 0..3 {
                let p = 0.5 * (paper[(i, j)] + paper[(j, i)]);
                assert!(
                    (k[(i, j)] - p).abs() <= 1e-4 * p.abs().max(1e-9),
                    "({i},{j}): {} vs {p}",
                    k[(i, j)]
                );
            }
        }
        // sa2 negates the couplings with theta (springs 4a/4b exchanged)
        let k2 = spring_array_stiffness(&SA2, &Geometry::from_k_sa1());
        assert!((k2[(0, 2)] + k[(0, 2)]).abs() < 1e-12 && (k2[(1, 2)] + k[(1, 2)]).abs() < 1e-12);
        assert!((k2[(0, 0)] - k[(0, 0)]).abs() < 1e-12);
    }

    #[test]
    fn input_has_its_peak_and_low_cross_coherence() {
        let u = stochastic_input(50_000, 1000.0, &[4.5, 4.5, 0.1], 15.0, 7).unwrap();
        for (c, p) in u.iter().zip([4.5, 4.5, 0.1]) {
            let max = c.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!((max - p).abs() < 1e-12);
        }
        let w = limpid_dsp::spectral::Welch {
            nperseg: 2048,
            ..limpid_dsp::spectral::Welch::new(1000.0)
        };
        let (f, c) = limpid_dsp::spectral::coherence(&u[0], &u[1], &w).unwrap();
        let worst = f
            .iter()
            .zip(&c)
            .filter(|(f, _)| **f > 0.4 && **f < 15.0)
            .fold(0.0f64, |m, (_, c)| m.max(*c));
        assert!(worst < 0.6, "input coherence {worst}");
    }
}
