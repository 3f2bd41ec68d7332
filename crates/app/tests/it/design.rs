//! `limpid protocol design` (issue 60): the designed protocol beats the seed's
//! on the demo's realistic subject, stays within every limit and the budget,
//! and its predicted spread agrees with the spread it achieves.

use limpid_app::design::{design, DesignRequest, Objective, Prior};
use limpid_lab::protocol::{check, preset};

fn request(budget_s: f64, runs: usize, verify: usize, baseline: bool) -> DesignRequest {
    let seed = preset("artemiadis-3d").unwrap();
    DesignRequest {
        prior: Prior::demo(0),
        limits: seed.limits.clone(),
        sample_rate_hz: seed.sample_rate_hz,
        budget_s,
        objective: Objective::default(),
        runs,
        baseline: baseline.then_some(seed),
        verify,
        seed: 7,
    }
}

#[test]
fn the_design_identifies_damping_where_the_seed_protocol_cannot() {
    let d = design(&request(147.2, 16, 16, true)).unwrap();
    let r = &d.result;
    // within the limits at every sample and within the budget
    check(&d.protocol).unwrap();
    assert!(r.chosen.duration_s() <= 147.2, "{}", r.chosen.duration_s());
    assert!(
        r.limits.iter().all(|m| m.margin_percent >= 0.0),
        "{:?}",
        r.limits
    );
    // the seed's slow cubic leaves damping to the force fluctuation; the design does not
    let base = r.baseline.as_ref().unwrap();
    assert!(base.pooled.error_percent[1] > 40.0, "{:?}", base.pooled);
    assert!(
        r.predicted.pooled.error_percent[1] < 10.0,
        "{:?}",
        r.predicted.pooled
    );
    assert!(
        r.predicted.pooled.error_percent[0] < 5.0,
        "{:?}",
        r.predicted.pooled
    );
    assert!(
        r.predicted.pooled.se[0] < 0.75 * base.pooled.se[0],
        "K: {:?} vs {:?}",
        r.predicted.pooled,
        base.pooled
    );
    assert_eq!(r.predicted.identifiable_share[1], 1.0);
    // the prediction holds on fresh seeds: 16 recordings give the ratio to about ±25 %
    let v = r.verify.as_ref().unwrap();
    for m in 0..2 {
        assert!(
            (0.65..1.5).contains(&v.ratio[m]),
            "ratio {m}: {:?}",
            v.ratio
        );
    }
    assert!(v.within_tolerance_share >= 0.8, "{v:?}");
}

#[test]
fn a_budget_too_short_for_six_perturbations_is_refused_with_the_reason() {
    let e = design(&request(3.0, 4, 0, false))
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("at least 6 are needed"), "{e}");
}

#[test]
fn objectives_are_read_with_and_without_weights() {
    let o = Objective::parse("stiffness=2, damping").unwrap();
    assert_eq!((o.stiffness, o.damping, o.inertia), (2.0, 1.0, 0.0));
    for bad in ["stiffnes", "damping=-1", "inertia=x", "stiffness=0", ""] {
        assert!(Objective::parse(bad).is_err(), "{bad}");
    }
}

#[test]
fn a_prior_file_is_checked_field_by_field() {
    let path = std::path::Path::new("prior.toml");
    let eye = "[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]";
    let good =
        format!("inertia = {eye}\ndamping = {eye}\nstiffness = {eye}\nstart_m = [0.4, 0.0, 0.0]\n");
    let p = Prior::from_toml(&good, path).unwrap();
    assert_eq!(p.start().x, 0.4);
    // without start_m the design is for the centre of the limits' workspace
    let centred = Prior::from_toml(&good.replace("start_m = [0.4, 0.0, 0.0]\n", ""), path).unwrap();
    assert!(centred.start.is_none());
    let negative = good.replace("damping = [[1.0", "damping = [[-1.0");
    let e = Prior::from_toml(&negative, path).err().unwrap().to_string();
    assert!(
        e.contains("damping[0][0] = -1") && e.contains("prior.toml"),
        "{e}"
    );
    let unknown = format!("{good}stifness = 3\n");
    let e = Prior::from_toml(&unknown, path).err().unwrap().to_string();
    assert!(e.contains("stifness"), "{e}");
    let nan = good.replace("start_m = [0.4", "start_m = [nan");
    assert!(Prior::from_toml(&nan, path).is_err());
    let huge = good.replace("stiffness = [[1.0", "stiffness = [[1e307");
    let e = Prior::from_toml(&huge, path).err().unwrap().to_string();
    assert!(
        e.contains("stiffness[0][0] = 1e307") && e.contains("below 1e7"),
        "{e}"
    );
    // a prior so stiff that the force limit leaves 12 µm is refused before any simulation
    let stiff = good.replace("stiffness = [[1.0", "stiffness = [[5e6");
    let mut r = request(30.0, 4, 0, false);
    r.prior = Prior::from_toml(&stiff, path).unwrap();
    let e = design(&r).err().unwrap().to_string();
    assert!(e.contains("nothing below 0.0001 m can be designed"), "{e}");
}

/// The reflex method: on a noisy ankle with a weak reflex (within the range
/// `limpid calibrate` draws its reflex subjects from), a designed PRBS at the
/// same amplitude and time estimates the reflex gain with less spread than
/// REKLAB's 0.03 rad / 150 ms PRBS.
#[test]
fn a_designed_prbs_narrows_the_reflex_gain_of_a_noisy_ankle() {
    use limpid_app::design::reflex::{design_reflex, ReflexDesignRequest, ReflexPrior};
    use limpid_lab::ankle::AnkleSubject;
    use limpid_lab::periodic::PeriodicDesign;
    // the preset: order 7, 3 periods and the fades, 95 s at 1 kHz
    let mut baseline = PeriodicDesign::prbs_joint();
    baseline.limits.max_joint_displacement_rad = Some(0.03);
    let budget_s = baseline.check().unwrap().duration_s;
    let mut subject = AnkleSubject::default();
    if let Some(r) = subject.reflex.as_mut() {
        r.gain = 8.0;
    }
    let request = ReflexDesignRequest {
        prior: ReflexPrior {
            subject,
            torque_noise_nm: 0.4,
        },
        limits: baseline.limits.clone(),
        sample_rate_hz: baseline.sample_rate_hz,
        budget_s,
        runs: 10,
        baseline: Some(baseline),
        seed: 3,
    };
    let d = design_reflex(&request).unwrap();
    let r = &d.result;
    d.protocol.check().unwrap();
    assert!(r.chosen.duration_s <= budget_s + 1e-9);
    assert!((r.chosen.amplitude_rad - 0.03).abs() < 0.001);
    assert!(r.chosen.switch_interval_s < 0.15, "{:?}", r.chosen);
    // measured: 0.63 (12 recordings, seed 1); the information's SE says 0.67
    let ratio = r.gain_spread_ratio.unwrap();
    assert!(
        ratio < 0.8,
        "gain spread ratio {ratio}: {:?} vs {:?}",
        r.predicted,
        r.baseline
    );
    let base = r.baseline.as_ref().unwrap();
    assert!(r.predicted.gain_se_information < 0.8 * base.gain_se_information);
    // and no bias for it: the period stays long enough for the cascade's IRFs
    assert!(r.predicted.gain_error_percent < 2.0, "{:?}", r.predicted);
}

/// The stochastic method's design (an end-point multisine) on the demo's
/// realistic subject with the endpoint-multisine preset's limits.
fn stochastic_request(
    budget_s: f64,
    runs: usize,
    verify: usize,
) -> limpid_app::design::stochastic::StochasticDesignRequest {
    let preset = limpid_lab::periodic::PeriodicDesign::multisine_endpoint();
    limpid_app::design::stochastic::StochasticDesignRequest {
        prior: Prior::demo(0),
        limits: preset.limits.clone(),
        sample_rate_hz: preset.sample_rate_hz,
        budget_s,
        objective: Objective::default(),
        runs,
        baseline: Some(preset),
        verify,
        seed: 7,
    }
}

#[test]
fn a_designed_multisine_beats_the_preset_on_stiffness_and_predicts_its_own_spread() {
    use limpid_analysis::result::design::DesignChoice;
    let d = limpid_app::design::stochastic::design_stochastic(&stochastic_request(147.2, 12, 12))
        .unwrap();
    let r = &d.result;
    let report = d.protocol.check().unwrap();
    assert!(report.duration_s <= 147.2, "{}", report.duration_s);
    let DesignChoice::Multisine(c) = &r.chosen else {
        panic!("{:?}", r.chosen)
    };
    assert!(
        c.periods >= limpid_app::design::stochastic::MIN_RECORDED_PERIODS,
        "{c:?}"
    );
    assert!(
        r.limits.iter().all(|m| m.margin_percent >= 0.0),
        "{:?}",
        r.limits
    );
    // at least one limit is reached: the amplitude is the largest allowed
    assert!(
        r.limits.iter().any(|m| m.margin_percent < 1.0),
        "{:?}",
        r.limits
    );
    // the preset (0.2-6 Hz flat, 2 mm RMS, 160 s) puts its power where the
    // subject's slow force fluctuation is; the design does not
    let base = r.baseline.as_ref().unwrap();
    assert!(
        r.predicted.pooled.se[0] < 0.75 * base.pooled.se[0],
        "K: {:?} vs {:?}",
        r.predicted.pooled,
        base.pooled
    );
    assert!(
        r.predicted.pooled.error_percent[0] < 5.0,
        "{:?}",
        r.predicted.pooled
    );
    assert!(
        r.predicted.pooled.error_percent[1] < 5.0,
        "{:?}",
        r.predicted.pooled
    );
    assert_eq!(r.predicted.identifiable_share, [1.0; 3]);
    let v = r.verify.as_ref().unwrap();
    for m in 0..3 {
        assert!(
            (0.65..1.5).contains(&v.ratio[m]),
            "ratio {m}: {:?}",
            v.ratio
        );
    }
    assert_eq!(v.within_tolerance_share, 1.0, "{v:?}");
}

#[test]
fn a_stochastic_budget_too_short_for_its_periods_is_refused_with_the_reason() {
    let e = limpid_app::design::stochastic::design_stochastic(&stochastic_request(20.0, 4, 0))
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("recorded ones and the two fades are needed"),
        "{e}"
    );
}

/// The seed 003 arm holding a load, without a reflex (a prior file's text).
const PLANAR_ARM: &str = "xi = [0.356, 0.143, 0.147]\nstiffness = [[37.95, 9.31], [9.31, 10.14]]\ndamping = [[1.854, 0.590], [0.590, 1.435]]\nposture_rad = [0.08, 1.0]\ntau0 = [0.37, 0.41]\n";

fn planar_request(
    prior: &str,
    limits: &str,
    runs: usize,
    verify: usize,
) -> limpid_core::Result<limpid_app::design::planar::PlanarDesignRequest> {
    let seed = limpid_lab::design::Design::preset("lakatos-planar")
        .unwrap()
        .to_toml();
    limpid_app::design::planar::planar_request_from_texts(&limpid_app::design::DesignInputs {
        prior: (prior, std::path::Path::new("arm.toml")),
        limits_from: Some((limits, std::path::Path::new("limits.toml"))),
        baseline: Some((&seed, std::path::Path::new("lakatos.toml"))),
        budget_s: 72.0,
        objective: "stiffness,damping",
        robust: "worst",
        runs,
        verify,
        seed: 3,
    })
}

/// Seed 003's protocol (0.05 rad over 200 ms, 450 ms windows) on an arm
/// whose torque fluctuates slowly: the design moves faster and records
/// shorter windows, beats it on K and D, and predicts its own spread.
#[test]
fn a_planar_design_beats_the_seed_protocol_and_predicts_its_own_spread() {
    let seed = limpid_lab::design::Design::preset("lakatos-planar")
        .unwrap()
        .to_toml();
    let req = planar_request(PLANAR_ARM, &seed, 16, 16).unwrap();
    let d = limpid_app::design::planar::design_planar(&req).unwrap();
    let r = &d.result;
    let report =
        limpid_lab::design::check(&limpid_lab::design::Design::Planar(d.protocol.clone())).unwrap();
    let limpid_lab::design::DesignReport::Planar(p) = report else {
        panic!("not a planar report")
    };
    assert!(p.session_s <= 72.0, "{}", p.session_s);
    assert!((r.chosen.duration_s - p.session_s).abs() < 1e-9);
    assert!(
        r.limits.iter().all(|m| m.margin_percent >= 0.0),
        "{:?}",
        r.limits
    );
    let base = r.baseline.as_ref().unwrap();
    // K a little, D by more than half (seed 3: 0.81 and 0.32 of the seed's)
    for (m, share) in [(0, 0.95), (1, 0.5)] {
        assert!(
            r.predicted.pooled.se[m] < share * base.pooled.se[m],
            "{m}: {:?} vs {:?}",
            r.predicted.pooled,
            base.pooled
        );
    }
    assert!(r.chosen.window_ms < 400.0, "{:?}", r.chosen);
    let v = r.verify.as_ref().unwrap();
    for m in 0..3 {
        assert!(
            (0.65..1.5).contains(&v.ratio[m]),
            "ratio {m}: {:?}",
            v.ratio
        );
    }
    assert_eq!(v.within_tolerance_share, 1.0, "{v:?}");
}

/// With a reflex 90 ms after the onset (`demo:planar`) every window past it
/// biases K; under limits that allow fast motions the design ends its window
/// near the latency and K's error drops to a fraction of the seed protocol's.
#[test]
fn a_reflex_in_the_prior_keeps_the_planar_window_near_its_latency() {
    let fast = limpid_lab::design::Design::preset("lakatos-planar")
        .unwrap()
        .to_toml()
        .replace(
            "max_joint_acceleration_rad_s2 = 15.0",
            "max_joint_acceleration_rad_s2 = 60.0",
        )
        .replace(
            "max_joint_velocity_rad_s = 1.0",
            "max_joint_velocity_rad_s = 2.0",
        );
    let req = planar_request("demo:planar", &fast, 12, 0).unwrap();
    let r = limpid_app::design::planar::design_planar(&req)
        .unwrap()
        .result;
    assert!(r.chosen.window_ms < 130.0, "{:?}", r.chosen);
    let base = r.baseline.as_ref().unwrap();
    assert!(base.pooled.error_percent[0] > 20.0, "{:?}", base.pooled);
    assert!(
        r.predicted.pooled.error_percent[0] < 0.5 * base.pooled.error_percent[0],
        "{:?} vs {:?}",
        r.predicted.pooled,
        base.pooled
    );
}

#[test]
fn a_planar_prior_and_its_limits_are_checked_with_the_file_named() {
    let seed = limpid_lab::design::Design::preset("lakatos-planar")
        .unwrap()
        .to_toml();
    let e = |prior: &str, limits: &str| {
        planar_request(prior, limits, 4, 0)
            .and_then(|r| limpid_app::design::planar::design_planar(&r).map(|_| ()))
            .err()
            .unwrap()
            .to_string()
    };
    let negative = PLANAR_ARM.replace("damping = [[1.854", "damping = [[-1.854");
    let msg = e(&negative, &seed);
    assert!(
        msg.contains("arm.toml") && msg.contains("damping[0][0]"),
        "{msg}"
    );
    let msg = e(&PLANAR_ARM.replace("xi = [0.356", "xi = [1e308"), &seed);
    assert!(msg.contains("arm.toml") && msg.contains("xi"), "{msg}");
    let msg = e(
        &format!(
            "{PLANAR_ARM}[reflex]\nlatency_s = 5.0\nstiffness_gain = 0.3\ndamping_gain = 0.3\n"
        ),
        &seed,
    );
    assert!(
        msg.contains("arm.toml") && msg.contains("latency_s = 5"),
        "{msg}"
    );
    let msg = e(
        &format!("{PLANAR_ARM}[noise]\nfluctuation_below_hz = 900\n"),
        &seed,
    );
    assert!(
        msg.contains("arm.toml") && msg.contains("fluctuation_below_hz"),
        "{msg}"
    );
    let msg = e(
        &PLANAR_ARM.replace("posture_rad = [0.08", "posture_rad = [1e300"),
        &seed,
    );
    assert!(
        msg.contains("arm.toml") && msg.contains("posture_rad"),
        "{msg}"
    );
    let msg = e(&PLANAR_ARM.replace("tau0 = [0.37", "tau0 = [1e300"), &seed);
    assert!(msg.contains("arm.toml") && msg.contains("tau0[0]"), "{msg}");
    let msg = e(
        &format!("{PLANAR_ARM}[noise]\nfluctuation_below_hz = 1e-9\ntorque_fluctuation_nm = 0.1\n"),
        &seed,
    );
    assert!(
        msg.contains("arm.toml") && msg.contains("fluctuation_below_hz"),
        "{msg}"
    );
    let msg = e(
        "demo:planar",
        &seed.replace(
            "link_lengths_m = [0.3, 0.33]",
            "link_lengths_m = [1e-9, 0.33]",
        ),
    );
    assert!(
        msg.contains("limits.toml") && msg.contains("link_lengths_m"),
        "{msg}"
    );
    let msg = e("demo:S1", &seed);
    assert!(msg.contains("demo:planar"), "{msg}");
    let centre_out = limpid_lab::design::Design::preset("artemiadis-3d")
        .unwrap()
        .to_toml();
    let msg = e(PLANAR_ARM, &centre_out);
    assert!(
        msg.contains("limits.toml") && msg.contains("planar protocol"),
        "{msg}"
    );
    let msg = e(
        PLANAR_ARM,
        &seed.replace("max_torque_nm = 20.0", "max_torque_nm = 1e-9"),
    );
    assert!(msg.contains("nothing below"), "{msg}");
}

/// `Robustness::Expected`: a prior range is ranked and predicted on its ends
/// and midpoint, the result says so, and the prediction holds on subjects
/// drawn from the range.
#[test]
fn an_expected_design_predicts_the_range_it_is_run_on() {
    use limpid_app::design::{Impedance, Robustness};
    assert_eq!(Robustness::parse("expected"), Ok(Robustness::Expected));
    assert!(Robustness::parse("best").is_err());
    let mut req = request(147.2, 12, 12, false);
    let nominal = req.prior.nominal;
    req.prior.other_end = Some(Impedance {
        stiffness: nominal.stiffness * 1.4,
        damping: nominal.damping * 0.7,
        ..nominal
    });
    req.objective.robust = Robustness::Expected;
    let r = design(&req).unwrap().result;
    assert_eq!(r.objective.robust, "expected");
    let v = r.verify.as_ref().unwrap();
    for m in 0..2 {
        assert!(
            (0.65..1.5).contains(&v.ratio[m]),
            "ratio {m}: {:?}",
            v.ratio
        );
    }
}
