//! The online estimator against virtual perturbation trials of known impedance.

use super::*;

/// A 3-D mass-spring-damper pushed by ramp-and-hold perturbations along
/// changing directions, with a different force offset per perturbation.
fn run(k: [[f64; 3]; 3], trials: usize, est: &mut OnlineImpedance) {
    let (m, b) = (1.5, 15.0);
    let fs = 1000.0;
    let dirs = [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.6, 0.8, 0.0],
        [0.0, 0.6, -0.8],
        [0.57, -0.57, 0.57],
    ];
    let rest = [0.3, -0.2, 0.05];
    let mut n = 0usize;
    for t in 0..trials {
        let d = dirs[t % dirs.len()];
        let offset = [
            3.0 * ((t * 7) % 5) as f64 - 6.0,
            2.0 - (t % 3) as f64,
            1.5 * (t % 2) as f64,
        ];
        // rest 50 ms, minimum-jerk out 100 ms, hold 500 ms, back 100 ms
        let len = 750;
        for i in 0..len {
            let s = i as f64 / fs;
            let (p, v, a) = profile(s);
            let x: [f64; 3] = std::array::from_fn(|j| rest[j] + 0.008 * d[j] * p);
            let f: [f64; 3] = std::array::from_fn(|o| {
                let mut fo = offset[o] + m * 0.008 * d[o] * a + b * 0.008 * d[o] * v;
                for j in 0..3 {
                    fo += k[o][j] * (x[j] - rest[j]);
                }
                fo
            });
            est.update(x, f);
            n += 1;
        }
    }
    // 30 ms of rest: the last perturbation is over
    let offset = [0.0; 3];
    for _ in 0..30 {
        est.update(rest, offset);
    }
    assert!(n > 0);
}

/// Position, velocity and acceleration of rest / out / hold / back.
fn profile(s: f64) -> (f64, f64, f64) {
    let mj = |u: f64| {
        let u = u.clamp(0.0, 1.0);
        (
            10.0 * u.powi(3) - 15.0 * u.powi(4) + 6.0 * u.powi(5),
            (30.0 * u.powi(2) - 60.0 * u.powi(3) + 30.0 * u.powi(4)) / 0.1,
            (60.0 * u - 180.0 * u.powi(2) + 120.0 * u.powi(3)) / 0.01,
        )
    };
    if s < 0.05 {
        (0.0, 0.0, 0.0)
    } else if s < 0.15 {
        mj((s - 0.05) / 0.1)
    } else if s < 0.65 {
        (1.0, 0.0, 0.0)
    } else {
        let (p, v, a) = mj((s - 0.65) / 0.1);
        (1.0 - p, -v, -a)
    }
}

#[test]
fn recovers_stiffness_damping_and_inertia_despite_offsets_per_perturbation() {
    let k = [
        [900.0, -300.0, 50.0],
        [-300.0, 1500.0, 100.0],
        [50.0, 100.0, 700.0],
    ];
    let mut est = OnlineImpedance::new(OnlineSettings::new(1000.0)).unwrap();
    run(k, 2, &mut est);
    assert!(
        matches!(est.state(), OnlineState::Waiting(w) if w.contains("2 of 3")),
        "{:?}",
        est.state()
    );
    run(k, 6, &mut est);
    let e = est.estimate().expect("estimating after 8 perturbations");
    assert_eq!(e.trials, 8);
    for o in 0..3 {
        for j in 0..3 {
            assert!(
                (e.stiffness[o][j] - k[o][j]).abs() < 0.02 * 1500.0,
                "K{o}{j} = {} (true {})",
                e.stiffness[o][j],
                k[o][j]
            );
        }
        assert!(
            (e.damping[o][o] - 15.0).abs() < 1.5,
            "B{o}{o} = {}",
            e.damping[o][o]
        );
        assert!(
            (e.inertia[o][o] - 1.5).abs() < 0.15,
            "M{o}{o} = {}",
            e.inertia[o][o]
        );
        assert!(e.vaf[o].unwrap() > 99.0);
    }
    assert_eq!(est.perturbations, 8);
}

#[test]
fn one_direction_only_is_not_identifiable_and_says_so() {
    let mut est = OnlineImpedance::new(OnlineSettings::new(1000.0)).unwrap();
    for _ in 0..4 {
        for i in 0..780 {
            let (p, _, _) = profile(i as f64 / 1000.0);
            est.update([0.3 + 0.008 * p, -0.2, 0.05], [800.0 * 0.008 * p, 0.0, 0.0]);
        }
    }
    assert_eq!(est.perturbations, 4);
    assert!(est.estimate().is_none());
    assert!(
        matches!(est.state(), OnlineState::Waiting(w) if w.contains("directions")),
        "{:?}",
        est.state()
    );
}

#[test]
fn extreme_samples_do_not_poison_the_estimate() {
    let k = [[900.0, 0.0, 0.0], [0.0, 600.0, 0.0], [0.0, 0.0, 400.0]];
    let mut est = OnlineImpedance::new(OnlineSettings::new(1000.0)).unwrap();
    run(k, 6, &mut est);
    est.update([f64::NAN, 0.0, 0.0], [0.0; 3]);
    est.update([0.3, -0.2, 0.05], [1e300, 0.0, 0.0]);
    run(k, 12, &mut est);
    assert_eq!(est.rejected, 2);
    assert_eq!(est.dropped, 0, "at rest no segment was open");
    let e = est.estimate().expect("estimating");
    for o in 0..3 {
        assert!(
            (e.stiffness[o][o] - k[o][o]).abs() < 0.02 * k[o][o],
            "K{o}{o} = {}",
            e.stiffness[o][o]
        );
    }
}

#[test]
fn a_reset_forgets_the_old_level() {
    let mut est = OnlineImpedance::new(OnlineSettings::new(1000.0)).unwrap();
    run(
        [[900.0, 0.0, 0.0], [0.0, 600.0, 0.0], [0.0, 0.0, 400.0]],
        6,
        &mut est,
    );
    est.reset();
    assert!(est.estimate().is_none());
    let k2 = [[1800.0, 0.0, 0.0], [0.0, 1200.0, 0.0], [0.0, 0.0, 800.0]];
    run(k2, 4, &mut est);
    let e = est.estimate().expect("estimating");
    assert_eq!(e.trials, 4);
    for o in 0..3 {
        assert!(
            (e.stiffness[o][o] - k2[o][o]).abs() < 0.02 * k2[o][o],
            "K{o}{o} = {}",
            e.stiffness[o][o]
        );
    }
}
