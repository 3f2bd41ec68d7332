//! Standard errors from few trials (issue 37): a jackknife over g trials has
//! g - 1 degrees of freedom, and fewer than 8 trials leave only pieces of the
//! data to resample. The estimate says so, with the interval to use.

use limpid_core::WarningCode;
use limpid_ident::{fit_linear, prepare, LinearParams, PrepareParams};
use limpid_lab::{simulate_centre_out, CentreOut, NoiseModel, Posture, Profile};
use nalgebra::{Matrix3, Vector3};

/// The end point both tests perturb.
fn posture() -> Posture {
    Posture {
        name: "S".into(),
        start: Vector3::new(0.4, 0.0, 0.0),
        inertia: Matrix3::from_diagonal_element(1.0),
        damping: Matrix3::new(20.0, 2.0, 1.0, 2.0, 15.0, 0.5, 1.0, 0.5, 10.0),
        stiffness: Matrix3::new(600.0, 50.0, 20.0, 50.0, 400.0, 30.0, 20.0, 30.0, 250.0),
    }
}

fn warning_with(trials: usize) -> Option<String> {
    let posture = posture();
    let mut protocol = CentreOut::seed000(Profile::Cubic);
    protocol.directions = limpid_lab::sphere::even_directions(trials);
    let rec = simulate_centre_out(&posture, &protocol, &NoiseModel::default(), 1).unwrap();
    let data = prepare(&rec, &PrepareParams::default()).unwrap();
    assert_eq!(data.windows.len(), trials);
    let est = fit_linear(&data, &LinearParams::default()).unwrap();
    est.warnings
        .iter()
        .find(|w| w.code == WarningCode::FewTrials)
        .map(|w| w.message.clone())
}

#[test]
fn few_trials_are_named_with_the_interval_to_use() {
    let six = warning_with(6).expect("6 trials are too few");
    assert!(
        six.contains("only 6 trials") && six.contains("(contiguous pieces)"),
        "{six}"
    );
    // Student's t with 7 degrees of freedom: 2.36, already in the SEs
    let eight = warning_with(8).expect("8 trials are few");
    assert!(
        eight.contains("±2.36 jackknife SE") && eight.contains("±2 SE is a 95 % interval"),
        "{eight}"
    );
    assert_eq!(warning_with(16), None);
}

/// Issue 58: physiological tremor (8-12 Hz) moves the force at rest by more
/// than its sensor's white noise, which second differences barely see; the
/// onset is still the perturbation's (the force's band is its spread at
/// rest), not a tremor swing inside the rest.
#[test]
fn tremor_at_rest_does_not_move_the_onset() {
    let posture = posture();
    let protocol = CentreOut::seed000(Profile::Cubic);
    let rest = |noise: &NoiseModel| -> Vec<usize> {
        let rec = simulate_centre_out(&posture, &protocol, noise, 3).unwrap();
        let data = prepare(&rec, &PrepareParams::default()).unwrap();
        data.windows.iter().map(|w| w.rest_samples).collect()
    };
    let quiet = rest(&NoiseModel::default());
    let shaking = rest(&NoiseModel {
        tremor_std_n: 0.5,
        tremor_hz: 9.0,
        ..NoiseModel::default()
    });
    // 500 Hz: within 20 ms of the tremor-free onset in every trial
    for (trial, (a, b)) in quiet.iter().zip(&shaking).enumerate() {
        assert!(
            a.abs_diff(*b) <= 10,
            "trial {}: rest {a} vs {b} samples",
            trial + 1
        );
    }
}
