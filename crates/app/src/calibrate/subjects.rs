//! Random subjects and sensors of `limpid calibrate`: realistic ranges of
//! stiffness, damping and inertia with random orientations, and sensor noise.

use limpid_lab::planar::{PlanarSubject, Reflex};
use limpid_lab::NoiseModel;
use nalgebra::{Matrix2, Matrix3, Rotation3, Unit, Vector3};
use rand::rngs::StdRng;
use rand::Rng;
pub(super) fn uniform(rng: &mut StdRng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

pub(super) fn random_rotation(rng: &mut StdRng) -> Matrix3<f64> {
    let axis = Vector3::new(
        uniform(rng, -1.0, 1.0),
        uniform(rng, -1.0, 1.0),
        uniform(rng, -1.0, 1.0),
    );
    let axis = if axis.norm() > 1e-6 {
        axis
    } else {
        Vector3::x()
    };
    Rotation3::from_axis_angle(
        &Unit::new_normalize(axis),
        uniform(rng, 0.0, std::f64::consts::PI),
    )
    .into_inner()
}

/// A 3 x 3 matrix with eigenvalues in lo..hi, a random orientation and an
/// antisymmetric part of 1-3 % of its norm.
pub(super) fn random_matrix3(rng: &mut StdRng, lo: f64, hi: f64) -> Matrix3<f64> {
    let r = random_rotation(rng);
    let d = Matrix3::from_diagonal(&Vector3::from_fn(|_, _| uniform(rng, lo, hi)));
    let s = r * d * r.transpose();
    let w = Vector3::from_fn(|_, _| uniform(rng, -1.0, 1.0));
    let a = w.cross_matrix();
    let share = uniform(rng, 0.01, 0.03);
    s + a * (share * s.norm() / a.norm().max(1e-12))
}

/// Sensors of the end-point subjects (issue 37: coverage on subjects unlike
/// the calibration generator's): half the outside examples' noise, half
/// drawn from wider ranges: white force noise 0.05-0.5 N, a force offset
/// drifting within the trials (0-0.5 N below 0.2-2 Hz), force noise
/// proportional to the force (0-5 %, coloured below 2 Hz), a coarser force
/// resolution (1/160-1/20 N), position noise 5-50 µm, a posture drifting
/// by 0-0.5 mm and (issue 58) K and B changing from trial to trial by 0-5 %,
/// 0-0.3 N of 8-12 Hz tremor, and in half of them a force sensor low-passed
/// at 200-1000 Hz.
pub(super) fn sensors(rng: &mut StdRng) -> NoiseModel {
    let base = NoiseModel::default();
    if rng.random::<bool>() {
        return base;
    }
    NoiseModel {
        white_std_n: uniform(rng, 0.05, 0.5),
        drift_std_n: uniform(rng, 0.0, 0.5),
        drift_lowpass_hz: uniform(rng, 0.2, 2.0),
        force_noise_fraction: uniform(rng, 0.0, 0.05),
        force_quantum_n: 1.0 / uniform(rng, 20.0, 160.0),
        position_std_m: uniform(rng, 5e-6, 5e-5),
        posture_drift_std_m: uniform(rng, 0.0, 5e-4),
        // issue 58: a subject that changes from trial to trial, tremor, a
        // force sensor with its own low-pass
        trial_impedance_std: uniform(rng, 0.0, 0.05),
        tremor_std_n: uniform(rng, 0.0, 0.3),
        tremor_hz: uniform(rng, 8.0, 12.0),
        force_sensor_hz: if rng.random::<bool>() {
            uniform(rng, 200.0, 1000.0)
        } else {
            0.0
        },
        ..base
    }
}

/// A symmetric 2 x 2 matrix with eigenvalues in lo..hi and a random orientation.
pub(super) fn random_matrix2(rng: &mut StdRng, lo: f64, hi: f64) -> Matrix2<f64> {
    let a = uniform(rng, 0.0, std::f64::consts::PI);
    let r = Matrix2::new(a.cos(), -a.sin(), a.sin(), a.cos());
    let d = Matrix2::new(uniform(rng, lo, hi), 0.0, 0.0, uniform(rng, lo, hi));
    r * d * r.transpose()
}

pub(super) fn planar_subject(rng: &mut StdRng, reflex: bool) -> PlanarSubject {
    let base = PlanarSubject::seed003();
    PlanarSubject {
        xi: base.xi.map(|v| v * uniform(rng, 0.8, 1.2)),
        stiffness: random_matrix2(rng, 5.0, 50.0),
        damping: random_matrix2(rng, 0.5, 3.0),
        reflex: reflex.then(|| Reflex {
            latency_s: uniform(rng, 0.04, 0.08),
            stiffness_gain: uniform(rng, 0.3, 0.6),
            damping_gain: uniform(rng, 0.3, 0.6),
        }),
        ..base
    }
}

/// Seed 003's torque and angle noise (the outside examples (`planar`)).
pub(super) const PLANAR_NOISE: (f64, f64) = (0.02, 1e-5);
