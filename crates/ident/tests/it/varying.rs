//! Varying impedance (issue 38) against the virtual lab's truth.

use limpid_ident::varying::{estimate_varying, VaryingEstimate, VaryingParams, VaryingRequest};
use limpid_lab::varying::{
    simulate_ensemble, simulate_scheduled_ankle, EnsembleExperiment, EnsembleSubject, RampAndHold,
    ScheduledAnkle,
};

/// Fraction of identifiable points whose element (j, k) of `pick` is within `tol` (relative) of `truth`.
fn within(
    e: &VaryingEstimate,
    pick: impl Fn(&limpid_ident::varying::VaryingPoint) -> Option<(f64, f64)>,
    truth: impl Fn(f64) -> f64,
    tol: f64,
) -> (f64, f64, usize) {
    let mut n = 0;
    let (mut ok, mut covered) = (0, 0);
    for p in e.points.iter().filter(|p| p.identifiable) {
        let (v, se) = pick(p).expect("identifiable points carry numbers");
        let t = truth(p.sigma);
        n += 1;
        ok += usize::from((v - t).abs() <= tol * t.abs());
        covered += usize::from((v - t).abs() <= 2.0 * se);
    }
    assert!(n > 0, "no identifiable point");
    (ok as f64 / n as f64, covered as f64 / n as f64, n)
}

fn el(
    m: &Option<limpid_core::Matrix>,
    s: &Option<limpid_core::Matrix>,
    j: usize,
    k: usize,
) -> Option<(f64, f64)> {
    Some((m.as_ref()?[(j, k)], s.as_ref()?[(j, k)]))
}

/// [`within`] for K and B of a scheduled ankle's first joint at tolerances
/// `(k, b)`: `(K within, K covered, points, B within, B covered)`.
fn scheduled_within(
    est: &VaryingEstimate,
    s: &ScheduledAnkle,
    (k, b): (f64, f64),
) -> (f64, f64, usize, f64, f64) {
    let (kok, kcov, n) = within(
        est,
        |p| el(&p.stiffness, &p.stiffness_se, 0, 0),
        |x| s.at(x)[0],
        k,
    );
    let (bok, bcov, _) = within(
        est,
        |p| el(&p.damping, &p.damping_se, 0, 0),
        |x| s.at(x)[1],
        b,
    );
    (kok, kcov, n, bok, bcov)
}

/// `s` simulated over ramp-and-hold holds (no ramps), cut into segments of
/// 0.5-1 s, each its own trial with its own background torque; estimated
/// on `sv`, with the reflex pathway when `reflex`.
fn segmented_scheduled(s: &ScheduledAnkle, seed: u64, reflex: bool) -> VaryingEstimate {
    let p = RampAndHold {
        keep_ramps: false,
        ..RampAndHold::default()
    };
    let rec = simulate_scheduled_ankle(s, &p, seed).unwrap();
    let cut = limpid_lab::ankle::cut_into_segments(&rec, (0.5, 1.0), seed).unwrap();
    let params = VaryingRequest {
        schedule: "sv".into(),
        reflex,
        ..VaryingRequest::default()
    }
    .check()
    .unwrap();
    estimate_varying(&cut, &params).unwrap()
}

#[test]
fn ensemble_follows_a_150_ms_stiffness_change_of_one_joint() {
    let s = EnsembleSubject::joint();
    let e = EnsembleExperiment::default();
    let rec = simulate_ensemble(&s, &e, 11).unwrap();
    let est = estimate_varying(&rec, &VaryingParams::default()).unwrap();
    assert_eq!(est.repetitions, Some(100));
    let k = |t: f64| s.truth_at(t)[2][0][0];
    let b = |t: f64| s.truth_at(t)[1][0][0];
    let (kok, kcov, n) = within(&est, |p| el(&p.stiffness, &p.stiffness_se, 0, 0), k, 0.15);
    let (bok, bcov, _) = within(&est, |p| el(&p.damping, &p.damping_se, 0, 0), b, 0.30);
    assert!(n >= 60, "identifiable points: {n}");
    assert!(
        kok >= 0.9 && bok >= 0.8,
        "K within 15 %: {kok}, B within 30 %: {bok}"
    );
    assert!(
        kcov >= 0.8 && bcov >= 0.8,
        "±2 SE coverage K {kcov}, B {bcov}"
    );
    // the peak is resolved: the estimate at the centre is near double the baseline
    let peak = est
        .points
        .iter()
        .filter(|p| p.identifiable)
        .min_by(|a, b| (a.sigma - 0.6).abs().total_cmp(&(b.sigma - 0.6).abs()))
        .unwrap();
    let kp = peak.stiffness.as_ref().unwrap()[(0, 0)];
    assert!(
        (kp - k(peak.sigma)).abs() < 0.1 * k(peak.sigma),
        "K at the peak {kp} vs {}",
        k(peak.sigma)
    );
    assert!(est.fit.cross_validated_vaf > 80.0, "{:?}", est.fit);
}

#[test]
fn ensemble_of_few_repetitions_is_not_identifiable() {
    let s = EnsembleSubject::joint();
    let e = EnsembleExperiment {
        repetitions: 6,
        ..EnsembleExperiment::default()
    };
    let rec = simulate_ensemble(&s, &e, 2).unwrap();
    let est = estimate_varying(&rec, &VaryingParams::default()).unwrap();
    assert!(est
        .points
        .iter()
        .all(|p| !p.identifiable && p.stiffness.is_none()));
    assert!(est.points[0]
        .reason
        .as_deref()
        .unwrap()
        .contains("6 repetitions"));
}

#[test]
fn ensemble_of_a_planar_arm_in_joint_and_endpoint_coordinates() {
    for endpoint in [false, true] {
        let s = EnsembleSubject::planar(endpoint);
        let e = EnsembleExperiment {
            repetitions: 60,
            amplitude_rad: 0.03,
            switch_s: 0.15,
            actuator_hz: 6.0,
            torque_noise_nm: 0.02,
            ..EnsembleExperiment::default()
        };
        let rec = simulate_ensemble(&s, &e, 5).unwrap();
        let est = estimate_varying(&rec, &VaryingParams::default()).unwrap();
        // K as a matrix (relative Frobenius error), each element's ±2 SE
        let (mut ok, mut n) = (0, 0);
        for p in est.points.iter().filter(|p| p.identifiable) {
            let k = p.stiffness.as_ref().unwrap();
            let t = s.truth_at(p.sigma)[2].clone();
            let (mut err, mut norm) = (0.0, 0.0);
            for j in 0..2 {
                for c in 0..2 {
                    err += (k[(j, c)] - t[j][c]).powi(2);
                    norm += t[j][c].powi(2);
                }
            }
            n += 1;
            ok += usize::from(err.sqrt() <= 0.15 * norm.sqrt());
        }
        assert!(
            n >= 60 && ok as f64 >= 0.9 * n as f64,
            "endpoint {endpoint}: K within 15 % at {ok} of {n}"
        );
        for (j, k) in [(0, 0), (1, 1), (0, 1), (1, 0)] {
            let kt = |t: f64| s.truth_at(t)[2][j][k];
            let (_, kcov, _) = within(&est, |p| el(&p.stiffness, &p.stiffness_se, j, k), kt, 0.15);
            assert!(kcov >= 0.8, "endpoint {endpoint}: K{j}{k} coverage {kcov}");
        }
        for (j, k) in [(0, 0), (1, 1)] {
            let bt = |t: f64| s.truth_at(t)[1][j][k];
            let (bok, _, _) = within(&est, |p| el(&p.damping, &p.damping_se, j, k), bt, 0.30);
            assert!(
                bok >= 0.8,
                "endpoint {endpoint}: B{j}{k} within 30 % at {bok}"
            );
        }
    }
}

#[test]
fn scheduled_ankle_recovers_stiffness_and_reflex_gain_against_the_operating_angle() {
    let s = ScheduledAnkle::default();
    let p = RampAndHold::default();
    let rec = simulate_scheduled_ankle(&s, &p, 3).unwrap();
    let params = VaryingRequest {
        schedule: "sv".into(),
        reflex: true,
        ..VaryingRequest::default()
    }
    .check()
    .unwrap();
    let est = estimate_varying(&rec, &params).unwrap();
    let (kok, kcov, n, bok, _) = scheduled_within(&est, &s, (0.15, 0.30));
    assert!(n >= 15, "identifiable {n}");
    assert!(
        kok >= 0.9 && bok >= 0.8,
        "K {kok}, B {bok}; {:?}",
        est.points
            .iter()
            .map(|p| (p.sigma, p.stiffness.as_ref().map(|m| m[(0, 0)])))
            .collect::<Vec<_>>()
    );
    // the reflex pathway's small mismatch (1 ms delay steps) biases K by
    // about 2 %, more than its standard error: coverage is not claimed here
    let _ = kcov;
    let r = est.reflex.as_ref().unwrap();
    assert!(r.detected, "{r:?}");
    assert!((r.delay_s - 0.045).abs() <= 0.010, "delay {}", r.delay_s);
    // the gain's trend: rising with the angle, within 25 % at the ends
    let pts: Vec<_> = est.points.iter().filter(|p| p.identifiable).collect();
    let g = |p: &&limpid_ident::varying::VaryingPoint| p.reflex.as_ref().unwrap().gain;
    let (first, last) = (pts.first().unwrap(), pts.last().unwrap());
    assert!(g(last) > g(first) * 2.0, "gain {} -> {}", g(first), g(last));
    assert!(
        (g(last) - s.at(last.sigma)[2]).abs() < 0.25 * s.at(last.sigma)[2],
        "gain at the top {} vs {}",
        g(last),
        s.at(last.sigma)[2]
    );
}

#[test]
fn scheduled_ankle_without_reflex_claims_none() {
    let s = ScheduledAnkle {
        reflex: None,
        ..ScheduledAnkle::default()
    };
    let p = RampAndHold {
        keep_ramps: false,
        ..RampAndHold::default()
    };
    let rec = simulate_scheduled_ankle(&s, &p, 4).unwrap();
    let params = VaryingRequest {
        schedule: "sv".into(),
        reflex: true,
        ..VaryingRequest::default()
    }
    .check()
    .unwrap();
    let est = estimate_varying(&rec, &params).unwrap();
    assert!(!est.reflex.as_ref().unwrap().detected, "{:?}", est.reflex);
    let (kok, kcov, _, bok, bcov) = scheduled_within(&est, &s, (0.15, 0.30));
    assert!(kok >= 0.9 && bok >= 0.8, "K {kok} B {bok}");
    assert!(kcov >= 0.8 && bcov >= 0.8, "coverage K {kcov} B {bcov}");
}

/// Two real ankle recordings at different operating angles joined as two
/// trials: the fit across both, linear in the angle, gives at each file's
/// angle what the constant fit of that file alone gives.
#[test]
fn varying_on_real_ankle_recordings_agrees_with_per_file_fits() {
    let Some(dir) = limpid_testkit::real_data("reklab_ankle") else {
        return;
    };
    let read = |name: &str| limpid_io::read_recording(dir.join(format!("{name}.csv"))).unwrap();
    let (a, b) = (read("df3"), read("df2"));
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); 4];
    let mut t0 = 0.0;
    for (k, rec) in [&a, &b].into_iter().enumerate() {
        for i in 0..rec.len() {
            cols[0].push(t0 + rec.t()[i]);
            cols[1].push(rec.column("q1").unwrap()[i]);
            cols[2].push(rec.column("tau1").unwrap()[i]);
            cols[3].push((k + 1) as f64);
        }
        t0 = cols[0].last().unwrap() + 1.0;
    }
    let names = ["t", "q1", "tau1", "trial"].map(String::from).to_vec();
    let joined = limpid_core::Recording::new("df3+df2", names, cols, 2).unwrap();
    let params = |order| {
        VaryingRequest {
            schedule: "q1".into(),
            basis_order: Some(order),
            grid_points: 41,
            ..VaryingRequest::default()
        }
        .check()
        .unwrap()
    };
    let both = estimate_varying(&joined, &params(1)).unwrap();
    for rec in [&a, &b] {
        let alone = estimate_varying(rec, &params(0)).unwrap();
        let q = rec.column("q1").unwrap();
        let mean = q.iter().sum::<f64>() / q.len() as f64;
        let p = alone.points.iter().find(|p| p.identifiable).unwrap();
        let at = both
            .points
            .iter()
            .filter(|p| p.identifiable)
            .min_by(|x, y| (x.sigma - mean).abs().total_cmp(&(y.sigma - mean).abs()))
            .unwrap();
        for (name, x, y) in [
            ("K", &p.stiffness, &at.stiffness),
            ("B", &p.damping, &at.damping),
        ] {
            let (x, y) = (x.as_ref().unwrap()[(0, 0)], y.as_ref().unwrap()[(0, 0)]);
            assert!(
                (x - y).abs() < 0.15 * x.abs(),
                "{name} at {mean:.3} rad: alone {x}, joined {y}"
            );
        }
    }
}

/// Issue 58: a stiffness that varies with the angle itself (the elastic
/// torque integrates K over the angle swept) is estimated as its local slope
/// K(σ) when the schedule is read as the operating angle, whichever way the
/// angle is recorded; read as "not an angle", the estimate is the mean slope
/// over the perturbation, high by about K''(σ) a² / 6 for a swing of ±a, and
/// left to `auto` on an offset recording the standard errors carry that.
#[test]
fn a_stiffness_rising_with_the_angle_is_its_local_slope() {
    use limpid_ident::varying::ScheduleAngle;
    let growth = 3.0;
    let s = ScheduledAnkle {
        stiffness: [40.0, 0.0, 0.0],
        stiffness_growth: growth,
        reflex: None,
        ..ScheduledAnkle::default()
    };
    let estimate = |offset_angle: bool, reading: ScheduleAngle| {
        let p = RampAndHold {
            amplitude_rad: 0.04,
            torque_noise_nm: 0.01,
            offset_angle,
            ..RampAndHold::default()
        };
        let rec = simulate_scheduled_ankle(&s, &p, 7).unwrap();
        let params = VaryingRequest {
            schedule: "sv".into(),
            schedule_angle: reading,
            ..VaryingRequest::default()
        }
        .check()
        .unwrap();
        estimate_varying(&rec, &params).unwrap()
    };
    // median relative error of K over the identifiable points, and coverage
    let judge = |e: &VaryingEstimate| {
        let mut errors: Vec<f64> = e
            .points
            .iter()
            .filter(|p| p.identifiable)
            .map(|p| p.stiffness.as_ref().unwrap()[(0, 0)] / s.at(p.sigma)[0] - 1.0)
            .collect();
        errors.sort_by(f64::total_cmp);
        let (_, covered, _) = within(
            e,
            |p| el(&p.stiffness, &p.stiffness_se, 0, 0),
            |x| s.at(x)[0],
            1.0,
        );
        (errors[errors.len() / 2], covered)
    };
    let whole = estimate(false, ScheduleAngle::Auto);
    let (local, covered) = judge(&whole);
    assert!(
        whole
            .schedule
            .angle
            .as_deref()
            .unwrap()
            .contains("whole angle"),
        "{:?}",
        whole.schedule.angle
    );
    let (mean_slope, _) = judge(&estimate(false, ScheduleAngle::None));
    // the swing after the actuator, about 0.038 rad: K'' a² / (6 K) = g² a² / 6
    let predicted = growth * growth * 0.038f64.powi(2) / 6.0;
    assert!(local.abs() < 0.25 * predicted, "local slope off by {local}");
    assert!(covered >= 0.8, "coverage {covered}");
    assert!(
        (mean_slope - local - predicted).abs() < 0.3 * predicted,
        "the mean slope's excess {} vs predicted {predicted}",
        mean_slope - local
    );
    // recorded as the offset from sv: the same estimate when told so (the
    // whole angle's velocity and acceleration too, ramps included)
    let (offset_local, _) = judge(&estimate(true, ScheduleAngle::Offset));
    assert!(
        (offset_local - local).abs() < 1e-9,
        "{offset_local} vs {local}"
    );
    // and left to auto, the mean slope with standard errors that allow for it
    let unknown = estimate(true, ScheduleAngle::Auto);
    let (_, covered) = judge(&unknown);
    assert!(covered >= 0.8, "coverage of the unknown reading {covered}");
    assert!(
        unknown
            .warnings
            .iter()
            .any(|w| w.contains("schedule_angle")),
        "{:?}",
        unknown.warnings
    );
}

/// Issue 58 on the outside parameter-varying ankle (K 16 -> 94 N m/rad,
/// exponential in the whole angle; q1 recorded as the offset from sv): read
/// as the offset from the operating angle, K is the local slope and ±2 SE
/// cover it; left to `auto` the schedule's meaning is unknown and the SEs
/// carry the difference; read as no angle, K is the mean slope over the
/// ±0.038 rad perturbation, about 0.25 % high, which its SEs do not cover.
#[test]
fn outside_parameter_varying_ankle() {
    use limpid_ident::varying::ScheduleAngle;
    let Some(dir) = limpid_testkit::outside_examples("varying") else {
        return;
    };
    let case = "ex_pv_ankle_noreflex";
    let rec = limpid_io::read_recording(dir.join(format!("{case}.csv"))).unwrap();
    let truth = crate::gait::outside_truth(&dir.join(format!("{case}.truth.json")));
    for reflex in [false, true] {
        for reading in [
            ScheduleAngle::Offset,
            ScheduleAngle::Auto,
            ScheduleAngle::None,
        ] {
            let params = VaryingRequest {
                schedule: "sv".into(),
                schedule_angle: reading,
                reflex,
                ..VaryingRequest::default()
            }
            .check()
            .unwrap();
            let est = estimate_varying(&rec, &params).unwrap();
            // the truth's grid spans -0.38..0.18
            let inside =
                |p: &limpid_ident::varying::VaryingPoint| (-0.38..=0.18).contains(&p.sigma);
            let (mut n, mut kc, mut bc, mut worst) = (0, 0, 0, 0.0f64);
            for p in est.points.iter().filter(|p| p.identifiable && inside(p)) {
                let (kt, bt) = truth(p.sigma);
                let (k, ks) = el(&p.stiffness, &p.stiffness_se, 0, 0).unwrap();
                let (b, bs) = el(&p.damping, &p.damping_se, 0, 0).unwrap();
                n += 1;
                kc += usize::from((k - kt).abs() <= 2.0 * ks);
                bc += usize::from((b - bt).abs() <= 2.0 * bs);
                worst = worst.max((k - kt).abs() / kt);
            }
            let (kc, bc) = (kc as f64 / n as f64, bc as f64 / n as f64);
            eprintln!(
                "{reading:?} reflex {reflex}: {n} points, K covered {kc}, B {bc}, worst K {worst}"
            );
            assert!(n >= 15, "{reading:?}: {n} points");
            assert!(worst < 0.02, "{reading:?}: K off by {worst}");
            if reading == ScheduleAngle::None {
                assert!(kc < 0.8, "the mean slope's bias no longer shows: {kc}");
            } else {
                assert!(
                    kc >= 0.9 && bc >= 0.8,
                    "{reading:?} reflex {reflex}: K {kc}, B {bc}"
                );
            }
            assert_eq!(
                reading == ScheduleAngle::Auto,
                est.warnings.iter().any(|w| w.contains("schedule_angle")),
                "{:?}",
                est.warnings
            );
        }
    }
}

/// Short segments (Ludvig & Perreault 2012) of a ramp-and-hold session:
/// 0.5-1 s stretches, each its own trial with its own background torque,
/// too short for the 0.5 Hz slow low-pass: each segment's operating point
/// is its straight line.
#[test]
fn scheduled_ankle_from_short_segments_recovers_stiffness() {
    let s = ScheduledAnkle {
        reflex: None,
        ..ScheduledAnkle::default()
    };
    let est = segmented_scheduled(&s, 5, false);
    let (kok, kcov, _, bok, bcov) = scheduled_within(&est, &s, (0.12, 0.2));
    eprintln!("K within 12 %: {kok}, covered {kcov}; B within 20 %: {bok}, covered {bcov}");
    assert!(kok >= 0.8 && bok >= 0.8, "K {kok} B {bok}");
    assert!(kcov >= 0.85 && bcov >= 0.85, "coverage K {kcov} B {bcov}");
}

/// The outside generator's segmented parameter-varying ankle
/// (`$LIMPID_EXAMPLES/segments`): 52 segments of 0.5-1 s at five operating
/// angles; K within 12 % at the five angles and in their order.
#[test]
fn outside_segmented_ankle_at_five_angles() {
    let Some(dir) = limpid_testkit::outside_examples("segments") else {
        return;
    };
    let rec = limpid_io::read_recording(dir.join("ex_segments_varying.csv")).unwrap();
    let truth = limpid_testkit::read_json(&dir.join("ex_segments_varying.truth.json"));
    let params = VaryingRequest {
        schedule: "sv".into(),
        ..VaryingRequest::default()
    }
    .check()
    .unwrap();
    let est = estimate_varying(&rec, &params).unwrap();
    let (mut within_12, mut covered, mut judged) = (0, 0, 0);
    let mut pairs = Vec::new();
    for point in truth["points"].as_array().unwrap() {
        let sigma = point["sigma"].as_f64().unwrap();
        let p = est
            .points
            .iter()
            .min_by(|a, b| (a.sigma - sigma).abs().total_cmp(&(b.sigma - sigma).abs()))
            .unwrap();
        for (name, value) in [
            ("stiffness", el(&p.stiffness, &p.stiffness_se, 0, 0)),
            ("damping", el(&p.damping, &p.damping_se, 0, 0)),
        ] {
            let (v, se) = value.expect("identifiable");
            let t = point[name].as_f64().unwrap();
            judged += 1;
            covered += usize::from((v - t).abs() <= 2.0 * se);
            if name == "stiffness" {
                within_12 += usize::from((v - t).abs() <= 0.12 * t);
                pairs.push((t, v));
            }
            eprintln!("{name} at {sigma}: {v:.4} ± {se:.4} vs {t:.4}");
        }
    }
    // measured: 5 of 5 within 2 %, ±2 SE covering 9 of 10
    assert!(within_12 >= 4, "K within 12 % at {within_12} of 5 angles");
    assert!(
        pairs
            .windows(2)
            .all(|w| (w[1].1 - w[0].1) * (w[1].0 - w[0].0) > 0.0),
        "order {pairs:?}"
    );
    assert!(
        covered * 100 >= 85 * judged,
        "±2 SE covered {covered} of {judged}"
    );
}

/// Short segments of a scheduled ankle with a reflex whose gain rises with
/// the angle: the reflex is found and K follows the angle.
#[test]
fn scheduled_ankle_with_a_reflex_from_short_segments() {
    let s = ScheduledAnkle::default();
    let est = segmented_scheduled(&s, 6, true);
    let (kok, kcov, n, bok, bcov) = scheduled_within(&est, &s, (0.12, 0.2));
    let r = est.reflex.as_ref().unwrap();
    let pts: Vec<_> = est.points.iter().filter(|p| p.identifiable).collect();
    let g = |p: &&limpid_ident::varying::VaryingPoint| p.reflex.as_ref().unwrap().gain;
    eprintln!(
        "{n} points: K within 12 % {kok} covered {kcov}; B within 20 % {bok} covered {bcov}; reflex detected {} delay {}; gain {} -> {} (truth {} -> {})",
        r.detected,
        r.delay_s,
        g(pts.first().unwrap()),
        g(pts.last().unwrap()),
        s.at(pts.first().unwrap().sigma)[2],
        s.at(pts.last().unwrap().sigma)[2]
    );
    // measured: K and B within tolerance and ±2 SE at all 21 points, gain
    // 2.02 -> 17.03, delay 44.75 ms (without the transients: K within 12 %
    // at 6 of 21, gain 0.30 -> 12.9)
    assert!(r.detected, "{r:?}");
    assert!((r.delay_s - 0.045).abs() <= 0.005, "delay {}", r.delay_s);
    assert!(kok >= 0.8 && bok >= 0.8, "K {kok} B {bok}");
    assert!(kcov >= 0.85 && bcov >= 0.85, "coverage K {kcov} B {bcov}");
    let top = pts.last().unwrap();
    assert!(
        (g(top) - s.at(top.sigma)[2]).abs() < 0.15 * s.at(top.sigma)[2],
        "gain at the top {}",
        g(top)
    );
}
