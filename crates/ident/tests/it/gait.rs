//! Impedance during walking (issue 61) against the walking ankle's truth and,
//! with `LIMPID_EXAMPLES`, the outside generator's walking recordings.

use limpid_core::criteria::MatrixVerdict;
use limpid_ident::varying::gait::GaitMethod;
use limpid_ident::varying::{estimate_varying, VaryingEstimate, VaryingRequest};
use limpid_lab::varying::{simulate_walking, WalkingAnkle, WalkingExperiment};
use limpid_testkit::outside_examples;

/// The judged stance range (where the designs excite the ankle).
const STANCE: (f64, f64) = (0.05, 0.55);

/// Over the identifiable stance points: shares with K within 20 %, B within
/// 40 %, K and B within 2 SE, and the count of trusted values beyond their
/// tolerance.
struct Score {
    points: usize,
    k_ok: f64,
    b_ok: f64,
    k_covered: f64,
    b_covered: f64,
    confidently_wrong: usize,
}

fn score(e: &VaryingEstimate, truth: impl Fn(f64) -> (f64, f64)) -> Score {
    let (mut n, mut k_ok, mut b_ok, mut kc, mut bc, mut wrong) = (0, 0, 0, 0, 0, 0);
    for p in e
        .points
        .iter()
        .filter(|p| p.identifiable && (STANCE.0..=STANCE.1).contains(&p.sigma))
    {
        let (kt, bt) = truth(p.sigma);
        let k = p.stiffness.as_ref().unwrap()[(0, 0)];
        let ks = p.stiffness_se.as_ref().unwrap()[(0, 0)];
        let b = p.damping.as_ref().unwrap()[(0, 0)];
        let bs = p.damping_se.as_ref().unwrap()[(0, 0)];
        n += 1;
        let (ke, be) = ((k - kt).abs() / kt, (b - bt).abs() / bt);
        k_ok += usize::from(ke <= 0.2);
        b_ok += usize::from(be <= 0.4);
        kc += usize::from((k - kt).abs() <= 2.0 * ks);
        bc += usize::from((b - bt).abs() <= 2.0 * bs);
        let v = p.verdicts.as_ref().unwrap();
        wrong += usize::from((v.stiffness == MatrixVerdict::Trusted) && ke > 0.2)
            + usize::from((v.damping == MatrixVerdict::Trusted) && be > 0.4);
    }
    let share = |x: usize| x as f64 / n.max(1) as f64;
    Score {
        points: n,
        k_ok: share(k_ok),
        b_ok: share(b_ok),
        k_covered: share(kc),
        b_covered: share(bc),
        confidently_wrong: wrong,
    }
}

fn walking(method: Option<GaitMethod>) -> VaryingRequest {
    VaryingRequest {
        event: Some("heel_strike".into()),
        gait_method: method,
        ..VaryingRequest::default()
    }
}

fn assert_done(case: &str, s: &Score, min_points: usize) {
    eprintln!(
        "{case}: {} points, K within 20 % {:.2}, B within 40 % {:.2}, covered K {:.2} B {:.2}, confidently wrong {}",
        s.points, s.k_ok, s.b_ok, s.k_covered, s.b_covered, s.confidently_wrong
    );
    assert!(
        s.points >= min_points,
        "{case}: {} identifiable stance points",
        s.points
    );
    assert!(
        s.k_ok >= 0.9 && s.b_ok >= 0.8,
        "{case}: K {} B {}",
        s.k_ok,
        s.b_ok
    );
    assert!(
        s.k_covered >= 0.8 && s.b_covered >= 0.8,
        "{case}: coverage K {} B {}",
        s.k_covered,
        s.b_covered
    );
    assert_eq!(s.confidently_wrong, 0, "{case}");
}

#[test]
fn pulses_and_continuous_perturbation_give_stiffness_against_gait_phase() {
    let ankle = WalkingAnkle::default();
    let truth = |phase: f64| {
        let [k, b] = ankle.at(phase);
        (k, b)
    };
    let pulses = WalkingExperiment::default();
    let rec = simulate_walking(&ankle, &pulses, 11).unwrap();
    let est = estimate_varying(&rec, &walking(None).check().unwrap()).unwrap();
    assert!(
        est.schedule.name.contains("phase")
            && est.schedule.values.iter().all(|s| (0.0..1.0).contains(s))
    );
    let gait = est.gait.as_ref().unwrap();
    assert_eq!(
        gait.trigger.as_deref(),
        Some("perturbation"),
        "the method follows the data: pulses"
    );
    assert_eq!(gait.strides_used, pulses.strides);
    assert_done("pulses", &score(&est, truth), 9);
    // swing carries no perturbation: not identifiable, and said why
    let swing = est.points.iter().find(|p| p.sigma > 0.8).unwrap();
    assert!(!swing.identifiable && swing.reason.as_deref().unwrap().contains("perturbation"));

    let continuous = WalkingExperiment {
        perturbation: WalkingExperiment::continuous(),
        ..WalkingExperiment::default()
    };
    let rec = simulate_walking(&ankle, &continuous, 12).unwrap();
    let est = estimate_varying(&rec, &walking(None).check().unwrap()).unwrap();
    assert_eq!(
        est.gait.as_ref().unwrap().trigger,
        None,
        "no trigger column: the ensemble"
    );
    assert_done("continuous", &score(&est, truth), 30);
}

#[test]
fn few_strides_at_a_changing_speed_are_never_confidently_wrong() {
    let ankle = WalkingAnkle::default();
    let truth = |phase: f64| {
        let [k, b] = ankle.at(phase);
        (k, b)
    };
    for (seed, perturbation) in [
        (21, WalkingExperiment::pulses()),
        (22, WalkingExperiment::continuous()),
    ] {
        let e = WalkingExperiment {
            strides: 45,
            speed_change: 0.3,
            perturbation,
            ..WalkingExperiment::default()
        };
        let rec = simulate_walking(&ankle, &e, seed).unwrap();
        let est = estimate_varying(&rec, &walking(None).check().unwrap()).unwrap();
        let s = score(&est, truth);
        eprintln!(
            "45 strides, seed {seed}: {} points, wrong {}, K ok {:.2}",
            s.points, s.confidently_wrong, s.k_ok
        );
        assert_eq!(s.confidently_wrong, 0);
    }
}

#[test]
fn missed_and_doubled_heel_strikes_are_reported_by_stride_number() {
    let ankle = WalkingAnkle::default();
    for (missed, doubled) in [(0.05, 0.0), (0.0, 0.05)] {
        let e = WalkingExperiment {
            strides: 120,
            missed_events: missed,
            double_events: doubled,
            ..WalkingExperiment::default()
        };
        let rec = simulate_walking(&ankle, &e, 5).unwrap();
        let detected = rec
            .column("heel_strike")
            .unwrap()
            .iter()
            .filter(|&&x| x == 1.0)
            .count();
        let est = estimate_varying(&rec, &walking(None).check().unwrap()).unwrap();
        let g = est.gait.as_ref().unwrap();
        let count = |kind: &str| g.flawed.iter().filter(|f| f.kind == kind).count();
        // 121 heel strikes in the record (120 full strides)
        if missed > 0.0 {
            // events missed inside the record (one missed at either end only shortens it)
            let spans: usize = g
                .flawed
                .iter()
                .filter(|f| f.kind == "missed")
                .map(|f| (f.duration_s / 1.1).round() as usize - 1)
                .sum();
            assert!(
                spans + 2 >= 121 - detected && spans <= 121 - detected,
                "{spans} vs {}: {:?}",
                121 - detected,
                g.flawed
            );
            assert_eq!(count("outlier"), 0, "{:?}", g.flawed);
            assert_eq!(count("double"), 0);
            // numbering counts the strides a missed event merged: the last stride is the 120th
            let last = g.flawed.iter().map(|f| f.stride).max().unwrap();
            assert!(last <= 120);
        } else {
            assert_eq!(count("double"), detected - 121, "{:?}", g.flawed);
            assert_eq!(count("missed"), 0);
            assert_eq!(
                g.strides_used, 120,
                "extra events are ignored, their strides joined"
            );
        }
        assert!(
            est.warnings[0].contains("flawed events"),
            "{:?}",
            est.warnings
        );
    }
}

/// The outside generator's truth: K and B on a phase grid, linearly interpolated.
pub(crate) fn outside_truth(path: &std::path::Path) -> impl Fn(f64) -> (f64, f64) {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let arr = |k: &str| -> Vec<f64> {
        v[k].as_array()
            .unwrap()
            .iter()
            .map(|x| {
                x.as_array()
                    .map_or_else(|| x.as_f64().unwrap(), |m| m[0][0].as_f64().unwrap())
            })
            .collect()
    };
    let (grid, k, b) = (arr("grid"), arr("stiffness"), arr("damping"));
    move |s: f64| {
        let i = grid.partition_point(|g| *g <= s).clamp(1, grid.len() - 1);
        let u = (s - grid[i - 1]) / (grid[i] - grid[i - 1]);
        (
            k[i - 1] + u * (k[i] - k[i - 1]),
            b[i - 1] + u * (b[i] - b[i - 1]),
        )
    }
}

#[test]
fn outside_walking_recordings() {
    let Some(dir) = outside_examples("gait") else {
        return;
    };
    for (case, min_points) in [("ex_pulses", 9), ("ex_continuous", 30)] {
        let rec = limpid_io::read_recording(dir.join(format!("{case}.csv"))).unwrap();
        let est = estimate_varying(&rec, &walking(None).check().unwrap()).unwrap();
        let s = score(&est, outside_truth(&dir.join(format!("{case}.truth.json"))));
        assert_done(case, &s, min_points);
    }
}
