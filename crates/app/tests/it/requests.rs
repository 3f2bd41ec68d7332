//! Requests run by `limpid_app::estimate::run`: the settings reach the
//! estimators as documented, and wrong inputs are refused by name.

use limpid_analysis::result::Estimate;
use limpid_app::estimate::run;
use limpid_ident::request::{from_options, ArmRequest, PlanarRequest, Request, StochasticRequest};
use limpid_testkit::examples;

fn read(family: &str, file: &str) -> limpid_core::Recording {
    limpid_io::read_recording(examples(family).join(file)).unwrap()
}

#[test]
fn a_method_refuses_the_wrong_number_of_recordings() {
    let rec = read("ankle", "ex_ankle.csv");
    let checked = from_options("cocontraction", Default::default())
        .unwrap()
        .check()
        .unwrap();
    let e = run(&checked, vec![rec]).unwrap_err().to_string();
    assert!(e.contains("estimate cocontraction reads 2, found 1"), "{e}");
    let checked = from_options("reflex", Default::default())
        .unwrap()
        .check()
        .unwrap();
    let e = run(&checked, vec![]).unwrap_err().to_string();
    assert!(e.contains("reads 1, found 0"), "{e}");
}

#[test]
fn the_planar_window_in_ms_is_the_estimators_window_in_samples() {
    let rec = read("planar", "ex_joint_180.csv");
    let l = limpid_testkit::planar_truth(&examples("planar").join("ex_joint_180.truth.json"))
        .link_lengths;
    let request = Request::Planar(PlanarRequest {
        arm: ArmRequest::new(l),
        window_ms: Some(200.0),
    });
    let via_request = run(&request.check().unwrap(), vec![rec.clone()]).unwrap();
    let Estimate::Planar(a) = via_request.document.estimate else {
        panic!("a planar request gives a planar result")
    };
    let data = limpid_ident::planar::prepare_planar(&rec, &ArmRequest::new(l).prepare()).unwrap();
    let samples = (0.2 * data.fs).round() as usize;
    let b = limpid_ident::planar::estimate_planar(&data, samples, None).unwrap();
    assert_eq!(a.stiffness, b.stiffness);
    assert_eq!(a.observation_window_ms, b.observation_window_ms);
    assert_eq!(via_request.from_endpoint, Some(false));
}

#[test]
fn welch_settings_of_a_stochastic_request_are_used() {
    let rec = read("stochastic", "ex_sa3.csv");
    let request = Request::Stochastic(StochasticRequest {
        nperseg: Some(2048),
        band_hz: [1.0, 8.0],
        ..StochasticRequest::default()
    });
    let out = run(&request.check().unwrap(), vec![rec]).unwrap();
    let Estimate::Stochastic(e) = out.document.estimate else {
        panic!("a stochastic request gives a stochastic result")
    };
    assert_eq!(e.criteria.nperseg, 2048);
}
