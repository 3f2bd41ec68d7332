//! Every estimator, through its typed request (`Request::check`, then
//! `limpid_app::estimate::run`), on virtual data without sensor noise whose
//! truth is known: the error of each estimate against the truth, printed as
//! one table (`cargo test -p limpid-app accuracy -- --nocapture`) and held
//! under a bound per method (after RustFFT's `tests/accuracy.rs`).
//!
//! What remains without noise is each method's own error: filtering and
//! numerical derivatives (linear, planar, varying), the Welch estimate of a
//! spectrum (stochastic, whose design keeps its sensors' noise), the finite
//! IRF and the decimation (reflex). The bounds are 4-10 times the errors
//! measured when this test was written (relative: linear K 6e-7, B 8e-6;
//! planar K 5e-5, D 2e-5, xi 8e-5; stochastic K 5e-3; 1 - multiple
//! coherence 0.012; reflex K 6e-4, B 2e-3, gain 3e-3; varying K(t) 3e-3),
//! so a change that makes any method markedly worse fails here.

use limpid_analysis::result::Estimate;
use limpid_app::estimate::run;
use limpid_core::truth::Truth;
use limpid_core::{Matrix, Recording};
use limpid_ident::request::{
    ArmRequest, LinearRequest, PlanarRequest, ReflexRequest, Request, SpectraRequest,
    StochasticRequest, VaryingRequest,
};
use limpid_lab::ankle::{simulate_ankle, AnkleExperiment, AnkleSubject};
use limpid_lab::planar::{simulate_planar, PlanarProtocol, PlanarSubject};
use limpid_lab::varying::{simulate_ensemble, EnsembleExperiment, EnsembleSubject};
use limpid_lab::{seed000_subject1, simulate_centre_out, CentreOut, NoiseModel, Profile};
use nalgebra::DMatrix;

/// Relative error (Frobenius) of an estimate against the truth.
fn rel(est: &Matrix, truth: &DMatrix<f64>) -> f64 {
    (&est.0 - truth).norm() / truth.norm()
}

fn estimate(request: Request, recordings: Vec<Recording>) -> Estimate {
    let checked = request.check().expect("a valid request");
    run(&checked, recordings)
        .expect("the estimate runs")
        .document
        .estimate
}

/// One row of the table: method, quantity, relative error, bound.
type Row = (&'static str, &'static str, f64, f64);

fn linear() -> Vec<Row> {
    let posture = seed000_subject1()[1].clone();
    let rec = simulate_centre_out(
        &posture,
        &CentreOut::seed000(Profile::Cubic),
        &NoiseModel::none(),
        7,
    )
    .unwrap();
    let Estimate::Linear(e) = estimate(Request::Linear(LinearRequest::default()), vec![rec]) else {
        panic!("a linear result")
    };
    let k = DMatrix::from_iterator(3, 3, posture.stiffness.iter().copied());
    let b = DMatrix::from_iterator(3, 3, posture.damping.iter().copied());
    vec![
        ("linear (cubic)", "K", rel(&e.stiffness, &k), 5e-6),
        ("linear (cubic)", "B", rel(&e.damping, &b), 5e-5),
    ]
}

fn planar() -> Vec<Row> {
    let subject = PlanarSubject::seed003();
    let rec = simulate_planar(&subject, &PlanarProtocol::seed003(), 0.0, 0.0, 8).unwrap();
    let request = Request::Planar(PlanarRequest {
        arm: ArmRequest::new([0.32, 0.31]),
        window_ms: None,
    });
    let Estimate::Planar(e) = estimate(request, vec![rec]) else {
        panic!("a planar result")
    };
    let k = DMatrix::from_iterator(2, 2, subject.stiffness.iter().copied());
    let d = DMatrix::from_iterator(2, 2, subject.damping.iter().copied());
    let xi = |v: [f64; 3]| DMatrix::from_row_slice(1, 3, &v);
    vec![
        ("planar (joint)", "K", rel(&e.stiffness, &k), 3e-4),
        ("planar (joint)", "D", rel(&e.damping, &d), 2e-4),
        (
            "planar (joint)",
            "xi",
            rel(&Matrix(xi(e.inertial_parameters)), &xi(subject.xi)),
            5e-4,
        ),
    ]
}

fn stochastic() -> Vec<Row> {
    let design = limpid_lab::design::Design::preset("park-stochastic").unwrap();
    let mut runs = limpid_lab::session::simulate_design(
        &design,
        None,
        limpid_lab::session::RigController::Ideal,
        9,
    )
    .unwrap();
    let run0 = runs.pop().unwrap();
    let Truth::Stochastic(truth) = &run0.truth else {
        panic!("a stochastic truth")
    };
    let k = truth.stiffness.0.clone();
    let Estimate::Stochastic(e) = estimate(
        Request::Stochastic(StochasticRequest::default()),
        vec![run0.recording.clone()],
    ) else {
        panic!("a stochastic result")
    };
    // the spectra of the same recording: the spring array's outputs are
    // explained by its inputs over the band (noise-free but for the sensors)
    let Estimate::Spectra(s) = estimate(
        Request::Spectra(SpectraRequest::new(
            vec!["ux".into(), "uz".into()],
            vec!["x".into(), "z".into()],
        )),
        vec![run0.recording],
    ) else {
        panic!("a spectra result")
    };
    let in_band: Vec<f64> = s
        .frequencies
        .iter()
        .zip(&s.multiple_coherence[0])
        .filter(|(f, _)| (1.0..=10.0).contains(*f))
        .map(|(_, c)| 1.0 - c.expect("the inputs have power in the band"))
        .collect();
    let worst = in_band.iter().copied().fold(0.0, f64::max);
    vec![
        (
            "stochastic (spring array)",
            "K",
            rel(&e.stiffness, &k),
            0.02,
        ),
        (
            "spectra (spring array)",
            "1 - multiple coherence",
            worst,
            0.05,
        ),
    ]
}

fn reflex() -> Vec<Row> {
    let subject = AnkleSubject::default();
    let experiment = AnkleExperiment {
        torque_noise_nm: 0.0,
        ..AnkleExperiment::default()
    };
    let rec = simulate_ankle(&subject, &experiment, 10).unwrap();
    let Estimate::Reflex(e) = estimate(Request::Reflex(ReflexRequest::default()), vec![rec]) else {
        panic!("a reflex result")
    };
    let gain = subject
        .reflex
        .as_ref()
        .expect("the default ankle has a reflex")
        .gain;
    let r = |est: f64, truth: f64| (est - truth).abs() / truth.abs();
    vec![
        (
            "reflex (ankle)",
            "intrinsic K",
            r(e.intrinsic.stiffness, subject.stiffness),
            0.005,
        ),
        (
            "reflex (ankle)",
            "intrinsic B",
            r(e.intrinsic.damping, subject.damping),
            0.01,
        ),
        (
            "reflex (ankle)",
            "reflex gain",
            r(e.reflex.gain, gain),
            0.015,
        ),
    ]
}

fn varying() -> Vec<Row> {
    let subject = EnsembleSubject::joint();
    let experiment = EnsembleExperiment {
        torque_noise_nm: 0.0,
        ..EnsembleExperiment::default()
    };
    let rec = simulate_ensemble(&subject, &experiment, 11).unwrap();
    let Estimate::Varying(e) = estimate(Request::Varying(VaryingRequest::default()), vec![rec])
    else {
        panic!("a varying result")
    };
    // the median over the identifiable instants of |K(t) - K_true(t)| / K_true(t)
    let mut errors: Vec<f64> = e
        .points
        .iter()
        .filter_map(|p| {
            let k = p.stiffness.as_ref()?;
            let truth = subject.truth_at(p.sigma)[2][0][0];
            Some((k[(0, 0)] - truth).abs() / truth)
        })
        .collect();
    assert!(errors.len() > 10, "{} identifiable instants", errors.len());
    errors.sort_by(f64::total_cmp);
    vec![(
        "varying (ensemble)",
        "K(t), median",
        errors[errors.len() / 2],
        0.015,
    )]
}

#[test]
fn every_estimator_recovers_a_noiseless_truth() {
    let rows: Vec<Row> = [linear(), planar(), stochastic(), reflex(), varying()].concat();
    eprintln!(
        "{:<28} {:<24} {:>10} {:>8}",
        "method", "quantity", "error %", "bound %"
    );
    for (method, quantity, error, bound) in &rows {
        eprintln!(
            "{method:<28} {quantity:<24} {:>10.2e} {:>8.1e}",
            100.0 * error,
            100.0 * bound
        );
    }
    for (method, quantity, error, bound) in &rows {
        assert!(
            error.is_finite() && error <= bound,
            "{method}: {quantity} off by {:.3} % (bound {:.1} %)",
            100.0 * error,
            100.0 * bound
        );
    }
}
