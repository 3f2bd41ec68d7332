//! Recovery of the examples' truths by the linear estimator (issue 2
//! acceptance): limpid-made examples always, the outside generator's with
//! `LIMPID_EXAMPLES`.

use limpid_ident::{fit_linear, prepare, LinearParams, PrepareParams};

use limpid_testkit::cartesian_truth;

use crate::common::{example_sets, examples, rel_err};

#[test]
fn cartesian_slow_examples_recover_stiffness_and_damping() {
    for (set, dir) in example_sets("cartesian_slow") {
        for case in ["ex_cubic", "ex_sinusoid"] {
            let case = &format!("{set}/{case}");
            let name = case.rsplit('/').next().unwrap();
            let rec = limpid_io::read_recording(dir.join(format!("{name}.csv"))).unwrap();
            let t = cartesian_truth(&dir.join(format!("{name}.truth.json")));
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
                let ek = rel_err(&est.stiffness, &t.stiffness);
                let eb = rel_err(&est.damping, &t.damping);
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
}

/// Issue 16: the window-by-window fit (`fit_linear_plan`, the CLI's path)
/// gives the estimate of the materialised signals, and its r, VAF and RMSE
/// (quadratic forms of the QR triangle) equal the ones computed sample by
/// sample from the prepared columns.
#[test]
fn fitting_window_by_window_equals_fitting_the_prepared_columns() {
    use limpid_ident::{fit_linear_plan, plan, Offsets};
    let close = |a: f64, b: f64, what: &str| {
        assert!(
            (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-12),
            "{what}: {a} vs {b}"
        );
    };
    for (family, case, offsets) in [
        ("cocontraction", "ex_config7.csv", Offsets::Rest),
        ("cocontraction", "ex_config4.csv", Offsets::Fit),
        ("cartesian_slow", "ex_cubic.csv", Offsets::Auto),
        ("cartesian_slow", "ex_sinusoid.csv", Offsets::Auto),
    ] {
        let path = examples(family).join(case);
        let file = &path.display().to_string();
        let rec = limpid_io::read_recording(&path).unwrap();
        let params = PrepareParams {
            offsets,
            ..Default::default()
        };
        let the_plan = plan(&rec, &params).unwrap();
        let prepared = prepare(&rec, &params).unwrap();
        assert_eq!(the_plan.len(), prepared.len(), "{file}");
        for equilibrium in [true, false] {
            let lp = LinearParams {
                equilibrium,
                ..Default::default()
            };
            let streamed = fit_linear_plan(&the_plan, &lp).unwrap();
            let whole = fit_linear(&prepared, &lp).unwrap();
            let pairs = [
                (&streamed.inertia, &whole.inertia),
                (&streamed.damping, &whole.damping),
                (&streamed.stiffness, &whole.stiffness),
                (
                    &streamed.standard_errors.stiffness,
                    &whole.standard_errors.stiffness,
                ),
                (
                    &streamed.standard_errors.damping,
                    &whole.standard_errors.damping,
                ),
            ];
            for (a, b) in pairs {
                for (x, y) in a.iter().zip(b.iter()) {
                    close(*x, *y, file);
                }
            }
            for (x, y) in streamed.fit.vaf.iter().zip(&whole.fit.vaf) {
                close(*x, *y, file);
            }
            assert_eq!(streamed.fit.traces.measured, whole.fit.traces.measured);
            assert_eq!(streamed.standard_error_method, whole.standard_error_method);
            // r, VAF, RMSE sample by sample, when no prior inertia moved B and K after the fit
            if equilibrium || !whole.identifiable.inertia || prepared.continuous {
                continue;
            }
            let n = prepared.dims();
            for a in 0..n {
                let f = &prepared.force[a];
                let fhat: Vec<f64> = (0..prepared.len())
                    .map(|i| {
                        (0..n)
                            .map(|k| {
                                whole.inertia[(a, k)] * prepared.acc[k][i]
                                    + whole.damping[(a, k)] * prepared.vel[k][i]
                                    + whole.stiffness[(a, k)] * prepared.disp[k][i]
                            })
                            .sum()
                    })
                    .collect();
                let m = f.len() as f64;
                let (mf, mh) = (f.iter().sum::<f64>() / m, fhat.iter().sum::<f64>() / m);
                let e: Vec<f64> = f.iter().zip(&fhat).map(|(y, h)| y - h).collect();
                let me = e.iter().sum::<f64>() / m;
                let var_f = f.iter().map(|y| (y - mf).powi(2)).sum::<f64>() / m;
                let var_e = e.iter().map(|v| (v - me).powi(2)).sum::<f64>() / m;
                let cov = f
                    .iter()
                    .zip(&fhat)
                    .map(|(y, h)| (y - mf) * (h - mh))
                    .sum::<f64>()
                    / m;
                let var_h = fhat.iter().map(|h| (h - mh).powi(2)).sum::<f64>() / m;
                let rmse = (e.iter().map(|v| v * v).sum::<f64>() / m).sqrt();
                eprintln!("{file} {a}: vaf {} r {}", whole.fit.vaf[a], whole.fit.r[a]);
                close(whole.fit.vaf[a], 100.0 * (1.0 - var_e / var_f), "VAF");
                close(whole.fit.r[a], cov / (var_f * var_h).sqrt(), "r");
                close(whole.fit.rmse[a], rmse, "RMSE");
            }
        }
    }
}
