//! Virtual subjects whose impedance varies (issue 38): in time during a
//! repeated task, for ensemble time-varying identification, and with an
//! operating angle, for parameter-varying identification.
//!
//! Both are position-controlled, as in the REKLAB experiments the methods come
//! from (Kearney & MacNeil's ensembles; Sobhani Tehrani & Kearney's
//! parameter-varying ankle): a servo imposes the joint angle, so the torque
//! applied to the limb follows in closed form from the imposed motion,
//!
//! `tau = M(q) q'' + C(q, q') q' + B(s) q' + K(s) (q - q_eq) + [G(s) LP2(rect(q'(t - d)))] + noise`,
//!
//! where `s` is time within the repetition or the operating angle. The servo
//! follows a random binary command whose switching instants are random
//! (Poisson, mean interval `switch_s`): a command that switched on a fixed
//! clock would switch at the same instants in every repetition and leave the
//! ensemble without velocity and acceleration variation there. The actuator
//! is second order (damping ratio 0.7) and integrated on a 10x finer grid, so
//! the recorded `q`, `q'`, `q''` are exact to the sample.

/// Integration steps of the actuator per sample.
const SUBSTEPS: usize = 10;
/// Damping ratio of the second-order actuator.
const ACTUATOR_DAMPING: f64 = 0.7;

mod ensemble;
mod scheduled;
mod walking;

pub use ensemble::{
    ensemble_truth, simulate_ensemble, EnsembleBody, EnsembleExperiment, EnsembleSubject,
    TimeChange,
};
pub use scheduled::{
    scheduled_truth, simulate_scheduled_ankle, Quadratic, RampAndHold, ScheduledAnkle,
    ScheduledReflex,
};
pub use walking::{
    simulate_walking, walking_truth, WalkingAnkle, WalkingExperiment, WalkingPerturbation,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ensemble_recording_has_its_repetitions_and_the_change() {
        let s = EnsembleSubject::joint();
        let e = EnsembleExperiment {
            repetitions: 3,
            ..EnsembleExperiment::default()
        };
        let rec = simulate_ensemble(&s, &e, 1).unwrap();
        assert_eq!(rec.len(), 3 * 1200);
        assert_eq!(rec.column("trial").unwrap()[1200], 2.0);
        let k = |t: f64| s.truth_at(t)[2][0][0];
        assert!((k(0.6) - 120.0).abs() < 1e-9 && (k(0.1) - 60.0).abs() < 1e-12);
        assert!(
            (k(0.6 + 0.075) - 90.0).abs() < 1e-9,
            "half height at half the width"
        );
    }

    #[test]
    fn scheduled_ankle_holds_its_angles() {
        let p = RampAndHold {
            angles_rad: vec![-0.3, 0.1],
            hold_s: 2.0,
            ramp_s: 0.5,
            keep_ramps: false,
            ..RampAndHold::default()
        };
        let rec = simulate_scheduled_ankle(&ScheduledAnkle::default(), &p, 2).unwrap();
        assert_eq!(rec.len(), 4000);
        let sv = rec.column("sv").unwrap();
        assert_eq!((sv[0], sv[3999]), (-0.3, 0.1));
        let q = rec.column("q1").unwrap();
        let mean_dev = q[500..2000]
            .iter()
            .zip(&sv[500..2000])
            .map(|(a, b)| a - b)
            .sum::<f64>()
            / 1500.0;
        assert!(
            mean_dev.abs() < 0.01,
            "the perturbation is centred on the hold: {mean_dev}"
        );
    }
}
