//! limpid-dsp against scipy 1.17 values (fixture made by fixtures/make_scipy_fixtures.py).

use limpid_dsp::{savgol, LowPass};
use serde_json::Value;

use crate::common::{max_rel, vec_of};

fn fixture() -> Value {
    let text = include_str!("../fixtures/scipy_dsp.json");
    serde_json::from_str(text).expect("fixture is valid JSON")
}

#[test]
fn butterworth_sosfiltfilt_matches_scipy() {
    let f = fixture();
    let x = vec_of(&f["x"]);
    for case in f["butter"].as_array().unwrap() {
        let order = case["order"].as_u64().unwrap() as usize;
        let lp = LowPass::butterworth(
            order,
            case["cutoff"].as_f64().unwrap(),
            case["fs"].as_f64().unwrap(),
        )
        .unwrap();
        let y = lp.filtfilt(&x).unwrap();
        let err = max_rel(&y, &vec_of(&case["filtfilt"]));
        assert!(err < 1e-10, "order {order}: max relative error {err:e}");
    }
}

#[test]
fn savitzky_golay_matches_scipy_nearest_mode() {
    let f = fixture();
    let x = vec_of(&f["x"]);
    for case in f["savgol"].as_array().unwrap() {
        let w = case["window"].as_u64().unwrap() as usize;
        let p = case["polyorder"].as_u64().unwrap() as usize;
        let d = case["deriv"].as_u64().unwrap() as usize;
        let y = savgol(&x, w, p, d, case["delta"].as_f64().unwrap()).unwrap();
        let err = max_rel(&y, &vec_of(&case["y"]));
        assert!(
            err < 1e-9,
            "window {w} poly {p} deriv {d}: max relative error {err:e}"
        );
    }
}
