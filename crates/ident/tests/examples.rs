//! Recovery of ../shared/examples truths by the linear estimator (issue 2 acceptance).

use limpid_ident::{fit_linear, prepare, LinearParams, PrepareParams};

mod common;
use common::{mat, rel_err, truth};

const EXAMPLES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/examples");

#[test]
fn cartesian_slow_examples_recover_stiffness_and_damping() {
    for case in ["ex_cubic", "ex_sinusoid"] {
        let rec =
            limpid_io::read_recording(format!("{EXAMPLES}/cartesian_slow/{case}.csv")).unwrap();
        let t = truth(&format!("{EXAMPLES}/cartesian_slow/{case}.truth.json"));
        for equilibrium in [true, false] {
            let prepared = prepare(&rec, &PrepareParams::default()).unwrap();
            let est = fit_linear(
                &prepared,
                &LinearParams {
                    equilibrium,
                    ..Default::default()
                },
            )
            .unwrap();
            let ek = rel_err(&est.stiffness, &mat(&t["stiffness"]));
            let eb = rel_err(&est.damping, &mat(&t["damping"]));
            eprintln!("{case} eq={equilibrium}: K err {:.4}, B err {:.4}, M {:?}, vaf {:?}, warnings {:?}", ek, eb, est.inertia, est.fit.vaf, est.warnings);
            assert!(ek < 0.03, "{case}: stiffness error {ek}");
            assert!(eb < 0.15, "{case}: damping error {eb}");
            assert!(
                !est.identifiable.inertia,
                "{case}: slow perturbations must flag inertia"
            );
        }
    }
}
