//! Parallel-cascade estimator (Kearney et al. 1997): ground truth on the
//! virtual ankle, and the real REKLAB ankle recordings.

use limpid_core::criteria::ParameterVerdict;
use limpid_ident::reflex::{estimate_reflex, Polarity, ReflexParams, ReflexRequest};
use limpid_lab::ankle::{simulate_ankle, AnkleExperiment, AnkleReflex, AnkleSubject};

#[test]
fn virtual_ankle_reflex_delay_and_gains_are_recovered() {
    for (seed, delay, gain, k, positive) in [
        (1u64, 0.045, 30.0, 80.0, true),
        (2, 0.060, 20.0, 120.0, true),
        (3, 0.035, 40.0, 50.0, false),
    ] {
        let mut s = AnkleSubject {
            stiffness: k,
            ..AnkleSubject::default()
        };
        if let Some(r) = s.reflex.as_mut() {
            r.delay_s = delay;
            r.gain = gain;
            r.positive = positive;
        }
        let rec = simulate_ankle(&s, &AnkleExperiment::default(), seed).unwrap();
        let e = estimate_reflex(&rec, &ReflexParams::default()).unwrap();
        let r = &e.reflex;
        let label = format!("seed {seed}: {e:?}");
        assert_eq!(
            r.polarity,
            if positive {
                Polarity::Positive
            } else {
                Polarity::Negative
            },
            "{label}"
        );
        assert!(
            (r.delay_s - delay).abs() <= 0.005,
            "delay {} vs {delay}",
            r.delay_s
        );
        assert!(r.delay_identifiable, "{:?}", e.warnings);
        // a clear reflex on a clean virtual ankle: every parameter trusted
        // (its error within 2 SE is checked below), the low-pass without an SE
        let v = e.verdicts();
        for (name, got) in [
            ("K", v.stiffness),
            ("B", v.damping),
            ("I", v.inertia),
            ("gain", v.gain),
            ("delay", v.delay),
        ] {
            assert_eq!(got, ParameterVerdict::Trusted, "{name}: {label}");
        }
        assert_eq!(v.low_pass, ParameterVerdict::NoStandardError);
        assert!(
            r.delay_interval_s[0] <= r.delay_s && r.delay_s <= r.delay_interval_s[1],
            "{:?}",
            r.delay_interval_s
        );
        assert!(
            (r.gain - gain).abs() / gain < 0.1,
            "gain {} vs {gain}",
            r.gain
        );
        assert!(
            (r.natural_frequency_hz - 2.0).abs() < 0.3,
            "{}",
            r.natural_frequency_hz
        );
        // the physical rectifier order (default): K within 2 %, gain within 4 %
        let ki = e.intrinsic.stiffness;
        assert!((ki - k).abs() / k < 0.02, "intrinsic K {ki} vs {k}");
        assert!((r.gain - gain).abs() / gain < 0.04, "gain {}", r.gain);
        assert!((r.delay_s - delay).abs() <= 0.0015, "{}", r.delay_s);
        // and the truth within 2 SE (jackknife, profile region, grid floor)
        let se = e.intrinsic.standard_errors.stiffness;
        assert!((ki - k).abs() <= 2.0 * se, "K {ki} +- {se} vs {k}");
        assert!(
            (r.gain - gain).abs() <= 2.0 * r.gain_se,
            "G {} +- {} vs {gain}",
            r.gain,
            r.gain_se
        );
        assert!(
            r.delay_interval_s[0] <= delay + 1e-9 && delay <= r.delay_interval_s[1] + 1e-9,
            "delay {delay} outside {:?}",
            r.delay_interval_s
        );
        assert!(
            e.fit.vaf_total > 99.0 && e.cross_validated_vaf > 99.0,
            "{:?}",
            e.fit
        );
        // the reflex-free fit puts reflex torque into K: the cascade is the closer
        assert!(
            (e.reflex_free.parameters.stiffness - k).abs() > (ki - k).abs(),
            "plain {} vs cascade {ki}",
            e.reflex_free.parameters.stiffness
        );
        // Kearney et al.'s order (with their rectifier) is further off, and
        // its standard errors carry the difference to the physical order,
        // so 2 SE still hold K
        let after = estimate_reflex(
            &rec,
            &ReflexRequest {
                rectify_first: false,
                nonlinearity: limpid_ident::reflex::Nonlinearity::Rectifier,
                ..ReflexRequest::default()
            }
            .check()
            .unwrap(),
        )
        .unwrap();
        let ka = after.intrinsic.stiffness;
        let sa = after.intrinsic.standard_errors.stiffness;
        assert!((ka - k).abs() / k < 0.1, "after: K {ka} vs {k}");
        assert!((ka - k).abs() > (ki - k).abs(), "after: K {ka}, first {ki}");
        assert!((ka - k).abs() <= 2.0 * sa, "after: K {ka} +- {sa} vs {k}");
        let other = e
            .other_rectifier_order
            .expect("the other order is reported");
        assert!(!other.rectify_first);
        assert!((other.intrinsic.stiffness - ka).abs() < 1e-9 * k);
    }
}

#[test]
fn without_a_reflex_the_delay_is_not_identifiable_and_k_is_right() {
    let s = AnkleSubject {
        reflex: None,
        ..AnkleSubject::default()
    };
    let rec = simulate_ankle(&s, &AnkleExperiment::default(), 7).unwrap();
    let e = estimate_reflex(&rec, &ReflexParams::default()).unwrap();
    assert!(!e.reflex.delay_identifiable);
    // no reflex: a gain not distinguishable from zero, no delay or low-pass
    // to speak of, and an intrinsic pathway still trusted
    let v = e.verdicts();
    assert_eq!(
        v.gain,
        ParameterVerdict::NotDistinguishableFromZero,
        "{e:?}"
    );
    assert_eq!(v.delay, ParameterVerdict::NotIdentifiable);
    assert_eq!(v.low_pass, ParameterVerdict::NotIdentifiable);
    assert_eq!(v.stiffness, ParameterVerdict::Trusted, "{e:?}");
    // a result saved before verdicts existed is judged by the same rules on reading
    let mut saved = serde_json::to_value(&e).unwrap();
    saved.as_object_mut().unwrap().remove("verdicts");
    let older: limpid_ident::reflex::ReflexEstimate = serde_json::from_value(saved).unwrap();
    assert!(older.verdicts.is_none());
    assert_eq!(older.verdicts(), v);
    assert!(e
        .warnings
        .iter()
        .any(|w| w.message.contains("not identifiable")));
    assert!(
        (e.intrinsic.stiffness - 80.0).abs() / 80.0 < 0.05,
        "{}",
        e.intrinsic.stiffness
    );
    assert!(e.fit.vaf_total - e.fit.vaf_intrinsic < 1.0, "{:?}", e.fit);
}

#[test]
fn real_ankle_recordings_match_the_method_s_known_behaviour() {
    let Some(real) = crate::common::real_data("reklab_ankle") else {
        return;
    };
    for name in ["df", "df2", "df3", "pf", "pf2"] {
        let rec = limpid_io::read_recording(real.join(format!("{name}.csv"))).unwrap();
        let e = estimate_reflex(&rec, &ReflexParams::default()).unwrap();
        // total VAF 86-96 %, well above the reflex-free fit's
        assert!(
            (85.0..97.0).contains(&e.fit.vaf_total),
            "{name}: {:?}",
            e.fit
        );
        assert!(e.fit.vaf_total > e.reflex_free.vaf + 1.0, "{name}");
        assert!(
            e.cross_validated_vaf > e.fit.vaf_total - 5.0,
            "{name}: over-fitted"
        );
        // intrinsic K below the reflex-free fit's (the reflex torque leaves it)
        let drop = 1.0 - e.intrinsic.stiffness / e.reflex_free.parameters.stiffness;
        assert!((0.05..0.5).contains(&drop), "{name}: K drop {drop}");
        // inertia of foot and actuator, of the order of 0.015-0.02 kg m^2
        assert!((0.008..0.03).contains(&e.intrinsic.inertia), "{name}");
        if name.starts_with("pf") {
            assert!(
                (0.035..0.065).contains(&e.reflex.delay_s),
                "{name}: delay {}",
                e.reflex.delay_s
            );
        }
        // issue 81: the dorsiflexed ankles' delay sits at the scan's edge
        // (best 0 ms): judged not identifiable, never a 0 ms delay; df2's gain
        // (about 5 +- 3) is not distinguishable from zero
        let v = e.verdicts();
        if name.starts_with("df") {
            assert_eq!(v.delay, ParameterVerdict::NotIdentifiable, "{name}");
            assert_eq!(v.low_pass, ParameterVerdict::NotIdentifiable, "{name}");
        }
        assert_eq!(
            v.gain == ParameterVerdict::NotDistinguishableFromZero,
            name == "df2",
            "{name}: gain {} +- {}",
            e.reflex.gain,
            e.reflex.gain_se
        );
        assert_eq!(v.damping, ParameterVerdict::Trusted, "{name}");
    }
}

/// The estimate of `s` over a session of `seconds` cut into segments of
/// `lengths` (s), each with its own background torque.
fn segmented_estimate(
    s: &AnkleSubject,
    seconds: f64,
    lengths: (f64, f64),
    seed: u64,
) -> limpid_ident::reflex::ReflexEstimate {
    let experiment = AnkleExperiment {
        duration_s: seconds,
        ..AnkleExperiment::default()
    };
    let rec = simulate_ankle(s, &experiment, seed).unwrap();
    let cut = limpid_lab::ankle::cut_into_segments(&rec, lengths, seed).unwrap();
    estimate_reflex(&cut, &ReflexParams::default()).unwrap()
}

/// Issue 80's tolerances: intrinsic K within 7 %, B within 20 %.
fn assert_intrinsic_within_tolerance(e: &limpid_ident::reflex::ReflexEstimate, s: &AnkleSubject) {
    let i = &e.intrinsic;
    assert!(
        (i.stiffness - s.stiffness).abs() < 0.07 * s.stiffness,
        "K {}",
        i.stiffness
    );
    assert!(
        (i.damping - s.damping).abs() < 0.2 * s.damping,
        "B {}",
        i.damping
    );
}

/// Ludvig & Perreault (2012): one joint from many short segments of a
/// session, each with its own start and background torque.
#[test]
fn short_segments_of_a_virtual_ankle_give_its_intrinsic_stiffness() {
    let (mut covered, mut judged) = (0, 0);
    for (seed, lengths) in [
        (1u64, (0.5, 1.0)),
        (2, (0.3, 0.6)),
        (3, (0.5, 1.0)),
        (4, (0.3, 0.6)),
    ] {
        let s = AnkleSubject::default();
        let e = segmented_estimate(&s, 90.0, lengths, seed);
        let used = e.segments.as_ref().expect("segments reported");
        let i = &e.intrinsic;
        let se = &i.standard_errors;
        let g = s.reflex.as_ref().unwrap().gain;
        eprintln!(
            "seed {seed} {lengths:?}: {} of {} segments; K {:.2} ({:+.1} %, {:.1} SE) B {:.4} ({:+.1} %, {:.1} SE) I {:.5} ({:+.1} %) G {:.2} ({:+.1} %) delay {:.3}",
            used.used,
            used.count,
            i.stiffness,
            100.0 * (i.stiffness / s.stiffness - 1.0),
            (i.stiffness - s.stiffness) / se.stiffness,
            i.damping,
            100.0 * (i.damping / s.damping - 1.0),
            (i.damping - s.damping) / se.damping,
            i.inertia,
            100.0 * (i.inertia / s.inertia - 1.0),
            e.reflex.gain,
            100.0 * (e.reflex.gain / g - 1.0),
            e.reflex.delay_s
        );
        assert_intrinsic_within_tolerance(&e, &s);
        for (v, truth, se) in [
            (i.stiffness, s.stiffness, se.stiffness),
            (i.damping, s.damping, se.damping),
            (i.inertia, s.inertia, se.inertia),
            (e.reflex.gain, g, e.reflex.gain_se),
        ] {
            judged += 1;
            covered += usize::from((v - truth).abs() <= 2.0 * se);
        }
    }
    // measured: 14 of 16 (the reflex gain of the shortest segments 2.7 % high, 2-3 SE)
    assert!(covered >= 13, "±2 SE covered {covered} of {judged}");
}

/// The outside generator's segmented ankle (`$LIMPID_EXAMPLES/segments`):
/// 28 segments of 0.5-1 s with a reflex, each starting with the actuator,
/// the background and the reflex in flight.
#[test]
fn outside_segmented_ankle_gives_its_intrinsic_stiffness() {
    let Some(dir) = limpid_testkit::outside_examples("segments") else {
        return;
    };
    let rec = limpid_io::read_recording(dir.join("ex_segments_reflex.csv")).unwrap();
    let truth = crate::common::truth(&dir.join("ex_segments_reflex.truth.json"));
    let e = estimate_reflex(&rec, &ReflexParams::default()).unwrap();
    let i = &e.intrinsic;
    let k = truth["stiffness"].as_f64().unwrap();
    let b = truth["damping"].as_f64().unwrap();
    let g = truth["reflex"]["gain"].as_f64().unwrap();
    eprintln!(
        "K {:.2} vs {k:.2} ({:.1} SE), B {:.4} vs {b:.4} ({:.1} SE), G {:.2} vs {g:.2}",
        i.stiffness,
        (i.stiffness - k) / i.standard_errors.stiffness,
        i.damping,
        (i.damping - b) / i.standard_errors.damping,
        e.reflex.gain
    );
    // measured: K -2.9 %, B -8.2 %, G -0.4 %
    assert!((i.stiffness - k).abs() < 0.07 * k, "K {}", i.stiffness);
    assert!((i.damping - b).abs() < 0.2 * b, "B {}", i.damping);
    assert!((e.reflex.gain - g).abs() < 0.1 * g, "G {}", e.reflex.gain);
    assert_eq!(e.segments.as_ref().map(|s| s.used), Some(28));
}

/// Issue 80 on real data: 20 segments of 0.5-1 s of Kearney's laboratory's
/// `pf` (each with a background torque added) give the whole record's K
/// within their joint standard error (joined as one record they gave +49 %).
#[test]
fn twenty_short_segments_of_a_real_ankle_agree_with_the_whole_record() {
    let Some(dir) = limpid_testkit::real_data("reklab_ankle") else {
        return;
    };
    let rec = limpid_io::read_recording(dir.join("pf.csv")).unwrap();
    let whole = estimate_reflex(&rec, &ReflexParams::default()).unwrap();
    for seed in [1u64, 2, 3] {
        let cut = limpid_lab::ankle::cut_into_segments(&rec, (0.5, 1.0), seed).unwrap();
        let twenty = limpid_lab::ankle::first_segments(&cut, 20).unwrap();
        let e = estimate_reflex(&twenty, &ReflexParams::default()).unwrap();
        let (k, kw) = (e.intrinsic.stiffness, whole.intrinsic.stiffness);
        let se = e
            .intrinsic
            .standard_errors
            .stiffness
            .hypot(whole.intrinsic.standard_errors.stiffness);
        eprintln!(
            "seed {seed}: K {k:.1} ± {:.1} vs whole {kw:.1}",
            e.intrinsic.standard_errors.stiffness
        );
        assert_eq!(e.segments.as_ref().map(|s| s.used), Some(20));
        assert!((k - kw).abs() <= 2.0 * se, "K {k} vs {kw} (joint SE {se})");
    }
}

/// Segments of an ankle without a reflex claim none, and long segments
/// (3-5 s, the control) give what short ones give.
#[test]
fn segments_without_a_reflex_claim_none_and_long_segments_agree() {
    for (seed, reflex, lengths) in [
        (5u64, false, (0.3, 0.6)),
        (6, false, (0.5, 1.0)),
        (7, true, (3.0, 5.0)),
    ] {
        let mut s = AnkleSubject::default();
        if !reflex {
            s.reflex = None;
        }
        let e = segmented_estimate(&s, 90.0, lengths, seed);
        let i = &e.intrinsic;
        let se = &i.standard_errors;
        eprintln!(
            "seed {seed} reflex {reflex} {lengths:?}: K {:.2} ({:.1} SE) B {:.4} ({:.1} SE) G {:.2} identifiable {} vaf gain {:.2} warnings {:?}",
            i.stiffness,
            (i.stiffness - s.stiffness) / se.stiffness,
            i.damping,
            (i.damping - s.damping) / se.damping,
            e.reflex.gain,
            e.reflex.delay_identifiable,
            e.fit.vaf_parametric - e.fit.vaf_parametric_intrinsic,
            e.warnings
        );
        assert_intrinsic_within_tolerance(&e, &s);
        assert!(
            (i.stiffness - s.stiffness).abs() <= 2.0 * se.stiffness,
            "K {} ± {}",
            i.stiffness,
            se.stiffness
        );
        assert_eq!(e.reflex.delay_identifiable, reflex, "{:?}", e.warnings);
    }
}

/// Segments too short for the delay scan asked (0.15-0.3 s against 0.26 s
/// for 150 ms): the scan is shortened to leave half the median segment to
/// the fit, and the result says so.
#[test]
fn very_short_segments_shorten_the_delay_scan_and_say_so() {
    let s = AnkleSubject::default();
    let e = segmented_estimate(&s, 120.0, (0.15, 0.3), 8);
    let i = &e.intrinsic;
    eprintln!(
        "K {:.2} ± {:.2}, B {:.4} ± {:.4}, delay {} ({:?}), used {:?}; {:?}",
        i.stiffness,
        i.standard_errors.stiffness,
        i.damping,
        i.standard_errors.damping,
        e.reflex.delay_s,
        e.reflex.delay_identifiable,
        e.segments.as_ref().map(|u| (u.used, u.count)),
        e.warnings
    );
    assert!(e
        .warnings
        .iter()
        .any(|w| w.message.contains("reflex delays scanned up to")));
    assert!(*e.reflex.delay_scan.delays_s.last().unwrap() < 0.15);
    assert_intrinsic_within_tolerance(&e, &s);
}

/// Normalised RMS (% of the true curve's range over the grid) of the
/// estimated static curve, weighted by where the recorded velocities are.
fn curve_error(curve: &limpid_ident::reflex::StaticCurve, r: &AnkleReflex) -> f64 {
    let truth: Vec<f64> = curve
        .velocity_rad_s
        .iter()
        .map(|&v| r.static_torque(v))
        .collect();
    // a grid point weighs the samples of the cells on either side of it
    let weight = |i: usize| {
        let h = &curve.histogram;
        (i.checked_sub(1).map_or(0, |j| h[j]) + h.get(i).copied().unwrap_or(0)) as f64
    };
    let (mut num, mut den) = (0.0, 0.0);
    for (i, (e, t)) in curve.torque.iter().zip(&truth).enumerate() {
        num += weight(i) * (e - t).powi(2);
        den += weight(i);
    }
    let range = truth.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
        - truth.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    100.0 * (num / den).sqrt() / range
}

#[test]
fn thresholded_and_saturating_reflexes_give_their_curve_and_the_intrinsic_parameters() {
    use limpid_ident::reflex::CurveStructure;
    use limpid_lab::ankle::ReflexCurve;
    let rectifier = AnkleSubject::default().reflex.unwrap();
    for (seed, curve, gain, positive) in [
        (
            11u64,
            ReflexCurve::Threshold {
                threshold_rad_s: 0.2,
            },
            40.0,
            true,
        ),
        (
            12,
            ReflexCurve::Clipped {
                threshold_rad_s: 0.1,
                saturation_nm: 6.0,
            },
            50.0,
            true,
        ),
        (13, ReflexCurve::Tanh { saturation_nm: 5.0 }, 40.0, false),
        (
            14,
            ReflexCurve::Threshold {
                threshold_rad_s: 0.3,
            },
            35.0,
            false,
        ),
    ] {
        let reflex = AnkleReflex {
            curve,
            gain,
            positive,
            ..rectifier
        };
        let s = AnkleSubject {
            reflex: Some(reflex),
            ..AnkleSubject::default()
        };
        let rec = simulate_ankle(&s, &AnkleExperiment::default(), seed).unwrap();
        let e = estimate_reflex(&rec, &ReflexParams::default()).unwrap();
        let c = e
            .reflex
            .curve
            .as_ref()
            .expect("a continuous record's curve");
        let label = format!("{curve:?}: {:?}", c.candidates);
        assert_eq!(c.structure, CurveStructure::PiecewiseLinear, "{label}");
        let err = curve_error(c, &reflex);
        assert!(err < 15.0, "curve off by {err:.1} %: {label}");
        let (k, b) = (e.intrinsic.stiffness, e.intrinsic.damping);
        assert!(
            (k - s.stiffness).abs() < 0.05 * s.stiffness,
            "K {k}: {label}"
        );
        assert!((b - s.damping).abs() < 0.2 * s.damping, "B {b}: {label}");
        let se = e.intrinsic.standard_errors.stiffness;
        assert!(
            (k - s.stiffness).abs() <= 2.0 * se,
            "K {k} +- {se}: {label}"
        );
        // the rectifier alone is worse on held-out data
        let rect = &c.candidates[0];
        assert_eq!(rect.structure, CurveStructure::Rectifier);
        assert!(!rect.within_one_se, "{label}");
        assert!(e.reflex.delay_identifiable, "{:?}", e.warnings);
        assert!((e.reflex.delay_s - reflex.delay_s).abs() < 0.005, "{label}");
    }
    // the plain rectifier: its curve, K within 1 %
    let s = AnkleSubject::default();
    let rec = simulate_ankle(&s, &AnkleExperiment::default(), 15).unwrap();
    let e = estimate_reflex(&rec, &ReflexParams::default()).unwrap();
    let c = e.reflex.curve.as_ref().unwrap();
    let err = curve_error(c, &rectifier);
    assert!(err < 3.0, "rectifier curve off by {err:.1} %");
    assert!(
        (e.intrinsic.stiffness - 80.0).abs() < 0.8,
        "{}",
        e.intrinsic.stiffness
    );
    assert!(
        (e.reflex.gain - rectifier.gain).abs() < 0.05 * rectifier.gain,
        "{}",
        e.reflex.gain
    );
}

#[test]
fn the_curve_can_be_forced_to_the_rectifier_and_is_not_estimated_from_segments() {
    use limpid_ident::reflex::{CurveStructure, Nonlinearity};
    let rec = simulate_ankle(&AnkleSubject::default(), &AnkleExperiment::default(), 16).unwrap();
    let forced = ReflexRequest {
        nonlinearity: Nonlinearity::Rectifier,
        ..ReflexRequest::default()
    };
    let e = estimate_reflex(&rec, &forced.check().unwrap()).unwrap();
    let c = e.reflex.curve.unwrap();
    assert_eq!(c.structure, CurveStructure::Rectifier);
    // the rectifier's curve is its gain times the answered half
    let i = c.velocity_rad_s.len() - 1;
    let v = c.velocity_rad_s[i];
    assert!(
        (c.torque[i] - e.reflex.gain * v.max(0.0)).abs() < 1e-6 * e.reflex.gain,
        "{c:?}"
    );
    assert!(c.torque_se.iter().all(|s| s.is_finite() && *s >= 0.0));
}

/// The REKLAB NLID toolbox's parallel cascade on the five real ankle
/// recordings (scripts/nlid-reference.m; numbers only): total VAF (%) and
/// intrinsic K (N m/rad, the intrinsic IRF's DC gain), with its estimated
/// reflex nonlinearity ('sls') and with its rectifier ('rect').
const NLID_REFERENCE: [(&str, [f64; 2], [f64; 2]); 5] = [
    ("df", [94.739, 72.115], [93.492, 78.719]),
    ("pf", [88.579, 62.460], [87.821, 69.191]),
    ("df2", [94.832, 53.766], [94.853, 52.932]),
    ("df3", [95.471, 111.336], [93.723, 125.452]),
    ("pf2", [88.086, 111.239], [86.452, 130.294]),
];

#[test]
fn real_ankles_explain_as_much_torque_as_the_field_s_reference_toolbox() {
    let Some(real) = crate::common::real_data("reklab_ankle") else {
        return;
    };
    let mut disagreements = Vec::new();
    for (name, [sls_vaf, sls_k], [rect_vaf, _]) in NLID_REFERENCE {
        let rec = limpid_io::read_recording(real.join(format!("{name}.csv"))).unwrap();
        let e = estimate_reflex(&rec, &ReflexParams::default()).unwrap();
        // at least the reference's VAF (estimated nonlinearity or rectifier,
        // the better), less half a point
        let reference = sls_vaf.max(rect_vaf);
        assert!(
            e.fit.vaf_total >= reference - 0.5,
            "{name}: {:?} vs {reference}",
            e.fit
        );
        let (k, se) = (e.intrinsic.stiffness, e.intrinsic.standard_errors.stiffness);
        if (k - sls_k).abs() > 0.1 * sls_k && (k - sls_k).abs() > 2.0 * se {
            disagreements.push(format!("{name}: K {k:.1} +- {se:.1} vs {sls_k:.1}"));
        }
        // no more than a fifth apart anywhere
        assert!((k - sls_k).abs() < 0.25 * sls_k, "{name}: K {k} vs {sls_k}");
    }
    // pf2: limpid's parametric reflex (delay, unit-DC low-pass) leaves K
    // 20 % above the reference's nonparametric one (the intrinsic IRF's DC
    // gain; limpid's own cascade gives 122); see the reference docs
    assert!(disagreements.len() <= 1, "{disagreements:?}");
}
