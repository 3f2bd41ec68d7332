//! Property: a noiseless linear system M x'' + B x' + K x = f is recovered
//! exactly (1e-6 relative) in 1, 2 and 3 coordinates, from exact kinematics;
//! and end to end through preparation (filter + differences) to 1e-3.

use limpid_ident::prepare::PreparedWindow;
use limpid_ident::{fit_linear, prepare, LinearParams, PrepareParams, Prepared, Windowing};
use nalgebra::DMatrix;
use proptest::prelude::*;

/// A random symmetric positive definite matrix (diagonal d plus small couplings) plus an antisymmetric part.
fn matrix(n: usize, diag: &[f64], off: &[f64], skew: f64) -> DMatrix<f64> {
    let mut m = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(&diag[..n]));
    let mut k = 0;
    for i in 0..n {
        for j in i + 1..n {
            let c = off[k] * (diag[i] * diag[j]).sqrt() * 0.3;
            m[(i, j)] = c + skew * c;
            m[(j, i)] = c - skew * c;
            k += 1;
        }
    }
    m
}

/// One signal per coordinate.
type Signals = Vec<Vec<f64>>;

/// Multi-sine motion per coordinate with exact derivatives.
fn kinematics(n: usize, len: usize, fs: f64, phases: &[f64]) -> (Signals, Signals, Signals) {
    let freqs = [0.7, 1.9, 3.3, 5.1, 7.7];
    let mut x = vec![vec![0.0; len]; n];
    let mut v = x.clone();
    let mut a = x.clone();
    for c in 0..n {
        for i in 0..len {
            let t = i as f64 / fs;
            for (k, f) in freqs.iter().enumerate() {
                let w = 2.0 * std::f64::consts::PI * f * (1.0 + 0.13 * c as f64);
                let ph = phases[(c * freqs.len() + k) % phases.len()] + c as f64;
                let amp = 0.002 / (1.0 + k as f64);
                x[c][i] += amp * (w * t + ph).sin();
                v[c][i] += amp * w * (w * t + ph).cos();
                a[c][i] -= amp * w * w * (w * t + ph).sin();
            }
        }
    }
    (x, v, a)
}

fn forces(
    m: &DMatrix<f64>,
    b: &DMatrix<f64>,
    k: &DMatrix<f64>,
    x: &[Vec<f64>],
    v: &[Vec<f64>],
    a: &[Vec<f64>],
) -> Vec<Vec<f64>> {
    let n = x.len();
    let len = x[0].len();
    (0..n)
        .map(|r| {
            (0..len)
                .map(|i| {
                    (0..n)
                        .map(|c| m[(r, c)] * a[c][i] + b[(r, c)] * v[c][i] + k[(r, c)] * x[c][i])
                        .sum()
                })
                .collect()
        })
        .collect()
}

fn rel(est: &DMatrix<f64>, truth: &DMatrix<f64>) -> f64 {
    limpid_testkit::rel_err(est, truth)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn exact_kinematics_recover_exactly(n in 1usize..=3,
                                        mdiag in proptest::collection::vec(0.1f64..2.0, 3),
                                        bdiag in proptest::collection::vec(5.0f64..80.0, 3),
                                        kdiag in proptest::collection::vec(100.0f64..2000.0, 3),
                                        off in proptest::collection::vec(-1.0f64..1.0, 3),
                                        skew in -0.1f64..0.1,
                                        phases in proptest::collection::vec(0.0f64..std::f64::consts::TAU, 15)) {
        let fs = 500.0;
        let len = 4000;
        let (m, b, k) = (matrix(n, &mdiag, &off, skew), matrix(n, &bdiag, &off, skew), matrix(n, &kdiag, &off, skew));
        let (x, v, a) = kinematics(n, len, fs, &phases);
        let f = forces(&m, &b, &k, &x, &v, &a);
        let coords: Vec<String> = ["x", "y", "z"][..n].iter().map(|s| s.to_string()).collect();
        let data = Prepared {
            path: "synthetic".into(),
            coordinates: coords.clone(),
            force_columns: coords.iter().map(|c| format!("f{c}")).collect(),
            fs,
            disp: x,
            vel: v,
            acc: a,
            force: f,
            windows: vec![PreparedWindow { id: 1, samples: 0..len, rows: 0..len, rest_samples: 0, force_offset: vec![0.0; n], reference: vec![0.0; n] }],
            continuous: true,
            demeaned: false,
            cutoff_hz: 30.0,
            filter_order: 4,
            derivative: limpid_ident::Derivative::Central,
            trim: 0,
            reference: vec![0.0; n],
            position_range: vec![(0.0, 0.0); n],
            position_noise: vec![0.0; n],
            resampled: vec![None; n],
            measured_rate: None,
            closed_loop: None,
            regressor_noise_var: vec![[0.0; 4]; n],
        };
        let est = fit_linear(&data, &LinearParams::default()).unwrap();
        prop_assert!(rel(&est.stiffness, &k) < 1e-6, "K {:?}", est.stiffness);
        prop_assert!(rel(&est.damping, &b) < 1e-6, "B {:?}", est.damping);
        prop_assert!(rel(&est.inertia, &m) < 1e-6, "M {:?}", est.inertia);
        prop_assert!(est.fit.vaf.iter().all(|v| *v > 99.9999));
    }
}

#[test]
fn end_to_end_noiseless_recording_recovers_to_1e_3() {
    let n = 3;
    let fs = 1000.0;
    let len = 20_000;
    let off = [0.4, -0.2, 0.3];
    let (m, b, k) = (
        matrix(n, &[1.5, 1.2, 0.9], &off, 0.05),
        matrix(n, &[20.0, 15.0, 25.0], &off, 0.05),
        matrix(n, &[900.0, 400.0, 600.0], &off, 0.05),
    );
    let phases: Vec<f64> = (0..15).map(|i| i as f64 * 0.77).collect();
    let (x, v, a) = kinematics(n, len, fs, &phases);
    let f = forces(&m, &b, &k, &x, &v, &a);
    let mut names = vec!["t".to_string()];
    let mut cols = vec![(0..len).map(|i| i as f64 / fs).collect::<Vec<f64>>()];
    for (c, name) in ["x", "y", "z"].iter().enumerate() {
        names.push(name.to_string());
        cols.push(x[c].clone());
    }
    for (c, name) in ["fx", "fy", "fz"].iter().enumerate() {
        names.push(name.to_string());
        cols.push(f[c].clone());
    }
    let rec = limpid_core::Recording::new("synthetic.csv", names, cols, 2).unwrap();
    let data = prepare(
        &rec,
        &PrepareParams {
            windowing: Windowing::Continuous,
            ..Default::default()
        },
    )
    .unwrap();
    let est = fit_linear(&data, &LinearParams::default()).unwrap();
    assert!(rel(&est.stiffness, &k) < 1e-3, "K {:?}", est.stiffness);
    assert!(rel(&est.damping, &b) < 1e-3, "B {:?}", est.damping);
    assert!(rel(&est.inertia, &m) < 1e-3, "M {:?}", est.inertia);
}

/// A position-controlled robot (30 Hz servo) lags its command; the recorded
/// motion is the actual one, so the noise-free estimate stays exact while the
/// tracking error stays below velocity x 2/ω.
#[test]
fn servo_tracking_error_is_bounded_and_does_not_bias_the_estimate() {
    use limpid_lab::{seed000_subject1, simulate_centre_out, CentreOut, NoiseModel, Profile};
    let posture = seed000_subject1().remove(0);
    let protocol = CentreOut::seed000(Profile::Cubic);
    let ideal = simulate_centre_out(&posture, &protocol, &NoiseModel::none(), 1).unwrap();
    let noise = NoiseModel {
        servo_bandwidth_hz: 30.0,
        ..NoiseModel::none()
    };
    let servo = simulate_centre_out(&posture, &protocol, &noise, 1).unwrap();
    // 3 cm in 3 s by a cubic: peak speed 1.5 cm/s, lag 2/ω = 10.6 ms
    let bound = 0.015 * 2.0 / (2.0 * std::f64::consts::PI * 30.0);
    let mut worst = 0.0f64;
    for c in ["x", "y", "z"] {
        for (a, b) in ideal
            .column(c)
            .unwrap()
            .iter()
            .zip(servo.column(c).unwrap())
        {
            worst = worst.max((a - b).abs());
        }
    }
    assert!(
        worst > 0.2 * bound && worst < bound,
        "tracking error {worst:e} vs bound {bound:e}"
    );
    let data = prepare(&servo, &PrepareParams::default()).unwrap();
    let est = fit_linear(&data, &LinearParams::default()).unwrap();
    let k = DMatrix::from_fn(3, 3, |i, j| posture.stiffness[(i, j)]);
    let b = DMatrix::from_fn(3, 3, |i, j| posture.damping[(i, j)]);
    assert!(rel(&est.stiffness, &k) < 1e-4, "K {:?}", est.stiffness);
    assert!(rel(&est.damping, &b) < 1e-3, "B {:?}", est.damping);
}
