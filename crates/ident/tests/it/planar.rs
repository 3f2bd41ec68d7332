//! Planar arm (seed 003) on the planar examples (limpid-made, and the outside
//! generator's with `LIMPID_EXAMPLES`): stiffness within 5 %, damping within
//! 15 %, inertial parameters within 10 % (issue 5).

use limpid_core::truth::PlanarTruth;
use limpid_ident::planar::{fit_planar, prepare_planar, Arm, PlanarPrepare};

use std::path::Path;

fn truth(dir: &Path, case: &str) -> PlanarTruth {
    limpid_testkit::planar_truth(&dir.join(format!("{case}.truth.json")))
}

fn rel(est: &limpid_core::Matrix, t: &limpid_core::Matrix) -> f64 {
    limpid_testkit::rel_err(est, t)
}

#[test]
fn planar_examples_recover_truth() {
    for (set, dir) in limpid_testkit::example_sets("planar") {
        for name in ["ex_joint_180", "ex_endpoint_220"] {
            let case = &format!("{set}/{name}");
            let t = truth(&dir, name);
            let l = t.link_lengths;
            let s = t.shoulder.expect("the examples state the shoulder");
            let rec = limpid_io::read_recording(dir.join(format!("{name}.csv"))).unwrap();
            let data = prepare_planar(
                &rec,
                &PlanarPrepare {
                    arm: Arm {
                        l1: l[0],
                        l2: l[1],
                        shoulder: [s[0], s[1]],
                    },
                    cutoff_hz: None,
                    order: 4,
                    elbow_positive: true,
                },
            )
            .unwrap();
            let all: Vec<usize> = (0..data.trials.len()).collect();
            let est = fit_planar(&data, usize::MAX, None, &all).unwrap();
            let ek = rel(&est.stiffness, &t.stiffness);
            let ed = rel(&est.damping, &t.damping);
            let xi = t.inertial_parameters;
            let exi = (0..3)
                .map(|i| (est.inertial_parameters[i] - xi[i]).powi(2))
                .sum::<f64>()
                .sqrt()
                / xi.iter().map(|v| v * v).sum::<f64>().sqrt();
            eprintln!(
                "{case}: K {ek:.4} D {ed:.4} xi {exi:.4} est {:?} {:?} {:?} window {} crit {:?}",
                est.stiffness,
                est.damping,
                est.inertial_parameters,
                est.observation_window_ms,
                est.criteria.reasons
            );
            assert!(ek < 0.05, "{case}: stiffness error {ek}");
            assert!(ed < 0.15, "{case}: damping error {ed}");
            assert!(exi < 0.10, "{case}: inertial parameter error {exi}");
        }
    }
}

fn seed003_arm() -> Arm {
    Arm {
        l1: 0.28,
        l2: 0.35,
        shoulder: [0.0, 0.0],
    }
}

/// Seed 003's preparation: its arm, no extra low-pass, 4th-order filter.
fn seed003_prepare() -> PlanarPrepare {
    PlanarPrepare {
        arm: seed003_arm(),
        cutoff_hz: None,
        order: 4,
        elbow_positive: true,
    }
}

fn prepare_seed003(rec: &limpid_core::Recording) -> limpid_ident::planar::PlanarData {
    prepare_planar(rec, &seed003_prepare()).unwrap()
}

#[test]
fn virtual_arm_without_reflex_is_recovered_and_constant_over_windows() {
    use limpid_ident::planar::window_sweep;
    use limpid_lab::planar::{simulate_planar, PlanarProtocol, PlanarSubject};
    let subject = PlanarSubject::seed003();
    let rec = simulate_planar(&subject, &PlanarProtocol::seed003(), 0.02, 1e-5, 3).unwrap();
    let data = prepare_seed003(&rec);
    let sweep = window_sweep(&data, 100.0, 400.0, 50.0, None).unwrap();
    for row in &sweep.rows {
        let k = &row.estimate.stiffness;
        assert!(
            (k[(0, 0)] / subject.stiffness[(0, 0)] - 1.0).abs() < 0.05,
            "T_obs {}: K11 {}",
            row.observation_window_ms,
            k[(0, 0)]
        );
    }
    assert!(sweep.min_quasi_constant_ms.is_some());
}

#[test]
fn reflex_after_60_ms_makes_the_stiffness_estimate_grow_with_the_window() {
    use limpid_ident::planar::window_sweep;
    use limpid_lab::planar::{simulate_planar, PlanarProtocol, PlanarSubject, Reflex};
    let mut subject = PlanarSubject::seed003();
    subject.reflex = Some(Reflex {
        latency_s: 0.06,
        stiffness_gain: 0.5,
        damping_gain: 0.0,
    });
    let rec = simulate_planar(&subject, &PlanarProtocol::seed003(), 0.02, 1e-5, 4).unwrap();
    let data = prepare_seed003(&rec);
    let sweep = window_sweep(&data, 50.0, 400.0, 10.0, None).unwrap();
    let k11: Vec<f64> = sweep
        .rows
        .iter()
        .map(|r| r.estimate.stiffness[(0, 0)])
        .collect();
    let (first, last) = (k11[0], *k11.last().unwrap());
    let k0 = subject.stiffness[(0, 0)];
    // before the reflex (50 ms) the estimate is at most the intrinsic stiffness; with
    // longer windows the post-reflex (1.5 K) data dominates: the estimate drifts upwards
    assert!(first < 1.1 * k0, "K11 at 50 ms: {first}");
    assert!(last > 1.3 * k0 && last < 1.6 * k0, "K11 at 400 ms: {last}");
    // and the sweep does not call the parameters constant before the reflex has acted
    let quasi = sweep.min_quasi_constant_ms.unwrap_or(f64::INFINITY);
    assert!(
        quasi > 60.0,
        "quasi-constant from {quasi} ms despite the reflex at 60 ms"
    );
}

/// Every window the sweep trusts has K within 10 % and D within 25 % of the truth.
fn assert_trusted_windows_are_right(
    sweep: &limpid_ident::planar::Sweep,
    k: &limpid_core::Matrix,
    d: &limpid_core::Matrix,
) -> usize {
    let mut trusted = 0;
    for r in sweep.rows.iter().filter(|r| r.trusted) {
        trusted += 1;
        let ek = limpid_testkit::rel_err(&r.estimate.stiffness, k);
        let ed = limpid_testkit::rel_err(&r.estimate.damping, d);
        assert!(
            ek <= 0.10 && ed <= 0.25,
            "{} ms trusted with K error {ek}, D error {ed}",
            r.observation_window_ms
        );
    }
    trusted
}

#[test]
fn the_sweep_trusts_precise_stable_windows_and_none_past_a_reflex() {
    use limpid_ident::planar::window_sweep;
    use limpid_lab::planar::{simulate_planar, PlanarProtocol, PlanarSubject, Reflex};
    // the example: trusted from a window where K is precise, never the 50-80 ms ones (K11 +46 % at 50 ms)
    for (set, dir) in limpid_testkit::example_sets("planar") {
        let t = truth(&dir, "ex_joint_180");
        let rec = limpid_io::read_recording(dir.join("ex_joint_180.csv")).unwrap();
        let data = prepare_planar(&rec, &PlanarPrepare::new(0.28, 0.35)).unwrap();
        let sweep = window_sweep(&data, 50.0, 400.0, 10.0, None).unwrap();
        let (k, d) = (t.stiffness, t.damping);
        assert!(
            assert_trusted_windows_are_right(&sweep, &k, &d) >= 10,
            "{set}"
        );
        let first = sweep.shortest_trusted_ms.unwrap();
        assert!(
            (80.0..=120.0).contains(&first),
            "{set}: trusted from {first} ms"
        );
        assert!(sweep.impedance_change.is_none(), "{set}");
    }
    // a reflex raising K and D by 50 % after 60 ms: detected, and no window trusted
    let mut subject = PlanarSubject::seed003();
    subject.reflex = Some(Reflex {
        latency_s: 0.06,
        stiffness_gain: 0.5,
        damping_gain: 0.5,
    });
    let rec = simulate_planar(&subject, &PlanarProtocol::seed003(), 0.02, 1e-5, 4).unwrap();
    let data = prepare_planar(&rec, &PlanarPrepare::new(0.28, 0.35)).unwrap();
    let sweep = window_sweep(&data, 50.0, 400.0, 10.0, None).unwrap();
    let change = sweep
        .impedance_change
        .as_ref()
        .expect("the reflex is detected");
    assert!(
        (50.0..=100.0).contains(&change.onset_ms),
        "change at {} ms",
        change.onset_ms
    );
    let (k, d) = (
        limpid_core::Matrix::from(subject.stiffness),
        limpid_core::Matrix::from(subject.damping),
    );
    assert_trusted_windows_are_right(&sweep, &k, &d);
    assert!(sweep
        .rows
        .iter()
        .all(|r| r.observation_window_ms <= change.onset_ms || !r.trusted));
}

/// Seed 003 §IV varies the interpolation interval T_k and observes each over
/// T_obs = T_k + 70 ms: a recording holding several T_k gets one row per T_k,
/// the T_k measured from the trials' motion, and every trusted row right.
#[test]
fn the_sweep_runs_over_the_interpolation_intervals_a_recording_holds() {
    use limpid_ident::planar::{interpolation_interval_s, window_sweep};
    use limpid_lab::planar::{simulate_planar_intervals, PlanarProtocol, PlanarSubject};
    let subject = PlanarSubject::seed003();
    let protocol = PlanarProtocol {
        trials: 36,
        after_s: 0.45,
        ..PlanarProtocol::seed003()
    };
    let intervals = [0.06, 0.15, 0.3];
    let rec = simulate_planar_intervals(&subject, &protocol, &intervals, 0.02, 1e-5, 11).unwrap();
    let data = prepare_planar(&rec, &PlanarPrepare::new(0.28, 0.35)).unwrap();
    for (i, t) in data.trials.iter().enumerate() {
        let tk = interpolation_interval_s(t, data.fs).unwrap();
        let truth = intervals[i % 3];
        assert!(
            (tk - truth).abs() < 0.006,
            "trial {i}: T_k {tk} s, truth {truth} s"
        );
    }
    let sweep = window_sweep(&data, 50.0, 400.0, 10.0, None).unwrap();
    let found: Vec<(f64, f64, usize)> = sweep
        .intervals
        .iter()
        .map(|r| (r.interpolation_ms, r.observation_window_ms, r.trials))
        .collect();
    assert_eq!(
        found,
        vec![(60.0, 130.0, 12), (150.0, 220.0, 12), (300.0, 370.0, 12)]
    );
    for r in &sweep.intervals {
        let k = &r.estimate.stiffness;
        let d = &r.estimate.damping;
        let ek = (&k.0 - limpid_core::Matrix::from(subject.stiffness).0).norm()
            / subject.stiffness.norm();
        let ed =
            (&d.0 - limpid_core::Matrix::from(subject.damping).0).norm() / subject.damping.norm();
        eprintln!(
            "T_k {} ms: K error {:.1} %, D error {:.1} %, trusted {} {:?}",
            r.interpolation_ms,
            100.0 * ek,
            100.0 * ed,
            r.trusted,
            r.reasons
        );
        if r.trusted {
            assert!(
                ek < 0.10 && ed < 0.25,
                "trusted T_k {} ms is wrong",
                r.interpolation_ms
            );
        }
    }
    // the change search can still see a "change" where the motion ends (150 ms
    // here, a false alarm that costs trust, not correctness)
    assert!(sweep.intervals.iter().filter(|r| r.trusted).count() >= 2);
}

/// A subject's slow torque fluctuation (0.15 N m below 3 Hz, as a subject
/// holding 5 N would show) moves the torques out of their white-noise band
/// during the rest: the onset must still come from the robot's motion, and
/// the estimate stay close to the truth.
#[test]
fn slow_torque_fluctuation_during_rest_does_not_move_the_onset() {
    use limpid_lab::planar::{simulate_planar, PlanarProtocol, PlanarSubject};
    use rand::{Rng, SeedableRng};
    let subject = PlanarSubject::seed003();
    let mut rec = simulate_planar(&subject, &PlanarProtocol::seed003(), 0.02, 1e-5, 5).unwrap();
    let prep = seed003_prepare();
    let clean = prepare_planar(&rec, &prep).unwrap();
    let t = rec.t().to_vec();
    let mut rng = rand::rngs::StdRng::seed_from_u64(9);
    for name in ["tau1", "tau2"] {
        // a sum of sinusoids between 0.2 and 3 Hz with random phases, 0.15 N m rms
        let parts: Vec<(f64, f64)> = (0..8)
            .map(|_| {
                (
                    rng.random_range(0.2..3.0),
                    rng.random_range(0.0..std::f64::consts::TAU),
                )
            })
            .collect();
        let amp = 0.15 * (2.0f64 / parts.len() as f64).sqrt();
        let tau: Vec<f64> = rec
            .column(name)
            .unwrap()
            .iter()
            .zip(&t)
            .map(|(v, ti)| {
                v + amp
                    * parts
                        .iter()
                        .map(|(f, p)| (std::f64::consts::TAU * f * ti + p).sin())
                        .sum::<f64>()
            })
            .collect();
        rec.set_column(name, tau).unwrap();
    }
    let data = prepare_planar(&rec, &prep).expect("the motion marks the onset");
    assert_eq!(data.trials.len(), clean.trials.len());
    // onsets within 10 ms of those without the fluctuation
    for (a, b) in data.trials.iter().zip(&clean.trials) {
        let (na, nb) = (a.dq[0].len() as f64, b.dq[0].len() as f64);
        assert!(
            (na - nb).abs() <= 0.01 * data.fs,
            "trial {}: {na} vs {nb} samples after onset",
            a.id
        );
    }
    let all: Vec<usize> = (0..data.trials.len()).collect();
    let est = fit_planar(&data, usize::MAX, None, &all).unwrap();
    let ek = limpid_testkit::rel_err(
        &est.stiffness,
        &limpid_core::Matrix::from(subject.stiffness),
    );
    assert!(ek < 0.1, "stiffness error {ek}");
}

/// End-point positions through the inverse kinematics make noisy angles,
/// which leave their noise band tens of ms after the torque has left rest.
/// The torque still marks the onset (the filtered angles show the motion
/// under way): otherwise the rest torque took in the perturbation's first
/// 30 ms and biased K by 10 % at 6 SE (issue 37, a trusted window wrong).
#[test]
fn noisy_end_point_angles_do_not_delay_the_onset() {
    use limpid_lab::planar::{simulate_planar, to_endpoint, PlanarProtocol, PlanarSubject};
    let mut subject = PlanarSubject::seed003();
    subject.stiffness = nalgebra::Matrix2::new(24.8, 1.4, 1.4, 32.9);
    let mut protocol = PlanarProtocol::seed003();
    protocol.trials = 31;
    let clean = simulate_planar(&subject, &protocol, 0.0, 0.0, 7).unwrap();
    let reference = prepare_seed003(&to_endpoint(&clean, &seed003_arm(), 0.0, 0.0, 7).unwrap());
    let noisy = prepare_seed003(&to_endpoint(&clean, &seed003_arm(), 6e-5, 0.0, 7).unwrap());
    for (a, b) in noisy.trials.iter().zip(&reference.trials) {
        let (na, nb) = (a.dq[0].len() as f64, b.dq[0].len() as f64);
        assert!(
            (na - nb).abs() <= 0.005 * noisy.fs,
            "trial {}: {na} vs {nb} samples after onset",
            a.id
        );
    }
    let all: Vec<usize> = (0..noisy.trials.len()).collect();
    let n = (0.3 * noisy.fs) as usize;
    let est = fit_planar(&noisy, n, None, &all).unwrap();
    let truth = limpid_core::Matrix::from(subject.stiffness);
    let ek = limpid_testkit::rel_err(&est.stiffness, &truth);
    let se = est.standard_errors.stiffness.norm() / est.stiffness.norm();
    assert!(
        ek < 0.03 && ek < 3.0 * se.max(0.003),
        "K error {ek}, SE {se}"
    );
}

/// Noise-free data: the jackknife over trials is zero, so a scan without a
/// floor for the misfit every trial shares read the few per cent by which
/// filtering and differences bias K in the first 30 ms (and D in the hold)
/// as a change, and trusted no window (issue 37). A reflex is still found.
#[test]
fn noise_free_trials_show_no_change_but_a_reflex_does() {
    use limpid_ident::planar::window_sweep;
    use limpid_lab::planar::{simulate_planar, PlanarProtocol, PlanarSubject, Reflex};
    let mut subject = PlanarSubject::seed003();
    let rec = simulate_planar(&subject, &PlanarProtocol::seed003(), 0.0, 0.0, 1).unwrap();
    let sweep = window_sweep(&prepare_seed003(&rec), 50.0, 400.0, 10.0, None).unwrap();
    assert!(
        sweep.impedance_change.is_none(),
        "{:?}",
        sweep.impedance_change
    );
    let truth = limpid_core::Matrix::from(subject.stiffness);
    let trusted: Vec<&limpid_ident::planar::SweepRow> =
        sweep.rows.iter().filter(|r| r.trusted).collect();
    assert!(trusted.len() > 20, "{} windows trusted", trusted.len());
    for r in trusted {
        let ek = limpid_testkit::rel_err(&r.estimate.stiffness, &truth);
        assert!(ek < 0.1, "{} ms: K error {ek}", r.observation_window_ms);
    }
    subject.reflex = Some(Reflex {
        latency_s: 0.06,
        stiffness_gain: 0.3,
        damping_gain: 0.3,
    });
    let rec = simulate_planar(&subject, &PlanarProtocol::seed003(), 0.0, 0.0, 1).unwrap();
    let sweep = window_sweep(&prepare_seed003(&rec), 50.0, 400.0, 10.0, None).unwrap();
    let change = sweep.impedance_change.expect("the reflex is found");
    assert!((40.0..=110.0).contains(&change.onset_ms), "{change:?}");
}

/// Seed 003 §IV-A's cuff: soft tissue in series between robot and arm. A
/// very stiff cuff gives back the rigid arm; the seed's cuff delays the
/// criteria to windows of a few hundred ms, as seed 003 Fig. 4 shows, where
/// the rigid arm meets them within 100 ms.
#[test]
fn a_cuff_in_series_lengthens_the_window_the_criteria_need() {
    use limpid_ident::planar::window_sweep;
    use limpid_lab::planar::{simulate_planar, Cuff, PlanarProtocol, PlanarSubject};
    let rigid = PlanarSubject::seed003();
    let arm = seed003_arm();
    let protocol = PlanarProtocol::seed003();
    let run = |cuff: Option<Cuff>| {
        let subject = PlanarSubject {
            cuff,
            ..rigid.clone()
        };
        simulate_planar(&subject, &protocol, 0.0, 0.0, 5).unwrap()
    };
    // 1e7 N/m: the arm follows the cuff to within micrometres
    let stiff = run(Some(Cuff::at_hand(&arm, rigid.q0, 1e7, 2e3)));
    let none = run(None);
    let torque_scale = none
        .column("tau1")
        .unwrap()
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    for name in ["tau1", "tau2"] {
        let worst = stiff
            .column(name)
            .unwrap()
            .iter()
            .zip(none.column(name).unwrap())
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(worst < 0.02 * torque_scale, "{name}: {worst} N m apart");
    }
    // the seed 003 cuff, noise as the examples
    let with_noise = |cuff: Option<Cuff>| {
        let subject = PlanarSubject {
            cuff,
            ..rigid.clone()
        };
        let rec = simulate_planar(&subject, &protocol, 0.02, 1e-5, 5).unwrap();
        let data = prepare_seed003(&rec);
        window_sweep(&data, 50.0, 430.0, 10.0, None).unwrap()
    };
    let rigid_sweep = with_noise(None);
    let cuff_sweep = with_noise(Some(Cuff::seed003(&arm, rigid.q0)));
    let pd = |s: &limpid_ident::planar::Sweep| s.min_positive_definite_ms.unwrap_or(f64::INFINITY);
    assert!(
        pd(&rigid_sweep) <= 100.0,
        "rigid arm: K PD from {:?}",
        rigid_sweep.min_positive_definite_ms
    );
    assert!(
        (150.0..=430.0).contains(&pd(&cuff_sweep)),
        "with the cuff: K PD from {:?}",
        cuff_sweep.min_positive_definite_ms
    );
    // long windows see the cuff and the arm in series: a softer K than the arm's
    let last = cuff_sweep.rows.last().unwrap();
    let k11 = last.estimate.stiffness[(0, 0)];
    assert!(
        k11 < rigid.stiffness[(0, 0)] && k11 > 0.3 * rigid.stiffness[(0, 0)],
        "K11 {k11}"
    );
}

#[test]
fn the_end_point_version_of_a_session_gives_the_joint_estimate() {
    // limpid's lab writes what a robot handle records (x = FK(q), f = J^-T tau,
    // position and force noise); the estimate through inverse kinematics and
    // tau = J^T f must agree with the joint-space one and with the truth
    use limpid_lab::planar::{simulate_planar, to_endpoint, PlanarProtocol, PlanarSubject};
    let subject = PlanarSubject::seed003();
    let joint = simulate_planar(&subject, &PlanarProtocol::seed003(), 0.0, 0.0, 11).unwrap();
    let endpoint = to_endpoint(&joint, &seed003_arm(), 2e-5, 0.1, 11).unwrap();
    assert!(endpoint.has("x") && endpoint.has("fy") && !endpoint.has("q1"));
    let fit = |rec: &limpid_core::Recording| {
        let data = prepare_seed003(rec);
        let all: Vec<usize> = (0..data.trials.len()).collect();
        (
            data.from_endpoint,
            fit_planar(&data, usize::MAX, None, &all).unwrap(),
        )
    };
    let (from_joint, j) = fit(&joint);
    let (from_endpoint, e) = fit(&endpoint);
    assert!(!from_joint && from_endpoint);
    let truth_k = limpid_core::Matrix::from(subject.stiffness);
    let truth_d = limpid_core::Matrix::from(subject.damping);
    let rel = |a: &limpid_core::Matrix, b: &limpid_core::Matrix| (&a.0 - &b.0).norm() / b.norm();
    assert!(rel(&j.stiffness, &truth_k) < 0.01, "{:?}", j.stiffness);
    assert!(rel(&e.stiffness, &truth_k) < 0.05, "{:?}", e.stiffness);
    assert!(rel(&e.damping, &truth_d) < 0.15, "{:?}", e.damping);
    assert!(rel(&e.stiffness, &j.stiffness) < 0.05);
    // a singular arm (elbow straight) cannot carry end-point forces: an error, not inf
    let mut straight = joint.clone();
    let n = straight.len();
    straight.set_column("q2", vec![0.0; n]).unwrap();
    let err = to_endpoint(&straight, &seed003_arm(), 0.0, 0.0, 1).unwrap_err();
    assert!(err.to_string().contains("singular"), "{err}");
}

/// Noisy angles bias the fit (errors in the regressors): the shared inertia
/// came out attenuated and its error entered K with opposite signs while the
/// arm accelerated and decelerated, which the change scan read as a reflex
/// (issue 37). With the noise compensated, reflex-free arms with 50 µrad
/// angle noise (or 50 µm at the hand) show no change, and a reflex still does.
#[test]
fn angle_noise_is_compensated_and_not_read_as_a_reflex() {
    use limpid_ident::planar::{window_sweep, AngleNoise};
    use limpid_lab::planar::{simulate_planar, to_endpoint, PlanarProtocol, PlanarSubject, Reflex};
    let subject = PlanarSubject::seed003();
    let truth_k = limpid_core::Matrix::from(subject.stiffness);
    let mut uncompensated_claims = 0;
    for seed in [21, 22, 23] {
        let joint =
            simulate_planar(&subject, &PlanarProtocol::seed003(), 0.02, 5e-5, seed).unwrap();
        let endpoint = {
            let clean =
                simulate_planar(&subject, &PlanarProtocol::seed003(), 0.0, 0.0, seed).unwrap();
            to_endpoint(&clean, &seed003_arm(), 5e-5, 0.1, seed).unwrap()
        };
        for rec in [&joint, &endpoint] {
            let mut data = prepare_seed003(rec);
            let noise = data.angle_noise.covariance;
            assert!(
                noise[0][0] > 1e-10 && noise[1][1] > 1e-10,
                "seed {seed}: angle noise {noise:?}"
            );
            let sweep = window_sweep(&data, 50.0, 400.0, 10.0, None).unwrap();
            assert!(
                sweep.impedance_change.is_none(),
                "seed {seed}, end point {}: {:?}",
                data.from_endpoint,
                sweep.impedance_change
            );
            let k = &sweep.rows.last().unwrap().estimate.stiffness;
            let ek = limpid_testkit::rel_err(k, &truth_k);
            assert!(ek < 0.05, "seed {seed}: K error {ek}");
            // the same data without the compensation: the bias the scan used to see
            data.angle_noise = AngleNoise::default();
            let plain = window_sweep(&data, 50.0, 400.0, 10.0, None).unwrap();
            uncompensated_claims += usize::from(plain.impedance_change.is_some());
        }
    }
    assert!(uncompensated_claims >= 3, "{uncompensated_claims} of 6");
    // a reflex through the same noise is still found
    let mut reflexive = subject.clone();
    reflexive.reflex = Some(Reflex {
        latency_s: 0.06,
        stiffness_gain: 0.4,
        damping_gain: 0.4,
    });
    let rec = simulate_planar(&reflexive, &PlanarProtocol::seed003(), 0.02, 5e-5, 24).unwrap();
    let sweep = window_sweep(&prepare_seed003(&rec), 50.0, 400.0, 10.0, None).unwrap();
    let change = sweep.impedance_change.expect("the reflex is detected");
    assert!((40.0..=110.0).contains(&change.onset_ms), "{change:?}");
}

/// Soft tissue in series (seed 003's cuff) makes the rigid model's K and D
/// depend on the window, which the change scan finds; a compliance in series
/// explains it (residual ratio far above [`SERIES_COMPLIANCE_RATIO`]), and
/// without a cuff (with or without a reflex) it explains nothing.
#[test]
fn tissue_in_series_is_named_as_the_cause_of_a_change() {
    use limpid_ident::planar::{fit_series_compliance, window_sweep, SERIES_COMPLIANCE_RATIO};
    use limpid_lab::planar::{
        simulate_planar, to_endpoint, Cuff, PlanarProtocol, PlanarSubject, Reflex,
    };
    let arm = seed003_arm();
    for (cuff, reflex, endpoint, seed) in [
        (false, false, false, 31),
        (false, true, false, 32),
        (false, false, true, 33),
        (true, false, false, 34),
        (true, false, true, 35),
        (true, true, false, 36),
    ] {
        let mut subject = PlanarSubject::seed003();
        if cuff {
            subject.cuff = Some(Cuff::seed003(&arm, subject.q0));
        }
        if reflex {
            subject.reflex = Some(Reflex {
                latency_s: 0.06,
                stiffness_gain: 0.4,
                damping_gain: 0.4,
            });
        }
        let rec = if endpoint {
            let joint =
                simulate_planar(&subject, &PlanarProtocol::seed003(), 0.0, 0.0, seed).unwrap();
            to_endpoint(&joint, &arm, 3e-5, 0.15, seed).unwrap()
        } else {
            simulate_planar(&subject, &PlanarProtocol::seed003(), 0.03, 3e-5, seed).unwrap()
        };
        let data = prepare_seed003(&rec);
        let ratio =
            fit_series_compliance(&data, usize::MAX, None).map_or(1.0, |c| c.residual_ratio);
        let case = format!("cuff {cuff}, reflex {reflex}, end point {endpoint}: ratio {ratio}");
        if cuff {
            assert!(ratio > 10.0 * SERIES_COMPLIANCE_RATIO, "{case}");
            let sweep = window_sweep(&data, 50.0, 400.0, 10.0, None).unwrap();
            assert!(sweep.impedance_change.is_some(), "{case}");
            let tissue = sweep.series_compliance.expect("tissue named");
            assert!(
                (0.005..0.02).contains(&tissue.time_constant_s),
                "{case}: T_c {}",
                tissue.time_constant_s
            );
        } else {
            assert!(ratio < SERIES_COMPLIANCE_RATIO / 1.5, "{case}");
            if reflex {
                let sweep = window_sweep(&data, 50.0, 400.0, 10.0, None).unwrap();
                assert!(sweep.impedance_change.is_some(), "{case}");
                assert!(sweep.series_compliance.is_none(), "{case}");
            }
        }
    }
}

/// With five trials the change test (Hotelling's T² of four elements from
/// the jackknife) cannot run, so a reflex within the window cannot be
/// excluded: no window is trusted, and each says why; six trials suffice.
#[test]
fn too_few_trials_to_test_for_a_change_trust_no_window() {
    use limpid_ident::planar::{window_sweep, MIN_TRIALS_FOR_CHANGE_TEST};
    use limpid_lab::planar::{simulate_planar, PlanarProtocol, PlanarSubject};
    for trials in [MIN_TRIALS_FOR_CHANGE_TEST - 1, 12] {
        let protocol = PlanarProtocol {
            trials,
            ..PlanarProtocol::seed003()
        };
        let rec = simulate_planar(&PlanarSubject::seed003(), &protocol, 0.02, 1e-5, 41).unwrap();
        let sweep = window_sweep(&prepare_seed003(&rec), 100.0, 400.0, 10.0, None).unwrap();
        let untestable = |r: &limpid_ident::planar::SweepRow| {
            r.reasons.iter().any(|w| w.contains("cannot be excluded"))
        };
        if trials < MIN_TRIALS_FOR_CHANGE_TEST {
            assert!(sweep.rows.iter().all(|r| !r.trusted && untestable(r)));
            assert!(sweep.shortest_trusted_ms.is_none());
        } else {
            assert!(sweep.rows.iter().all(|r| !untestable(r)));
            assert!(sweep.shortest_trusted_ms.is_some(), "{trials} trials");
        }
    }
}
