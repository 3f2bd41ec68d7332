//! Standard errors earn their name (issue 15): over every example recording
//! of every method, the truth lies within ±2 reported standard errors for
//! 90-99 % of the stiffness and damping elements, and no element is further
//! than 4 standard errors from it.

mod common;
use common::*;
use serde_json::Value;

/// (|z|, label) for every element of `key` in `est` against `truth`.
fn z_scores(label: &str, est: &Value, se: &Value, truth: &Value) -> Vec<(f64, String)> {
    let (e, s, t) = (mat(est), mat(se), mat(truth));
    let mut out = Vec::new();
    for i in 0..t.nrows() {
        for j in 0..t.ncols() {
            let z = (e[(i, j)] - t[(i, j)]).abs() / s[(i, j)];
            assert!(
                z.is_finite(),
                "{label}[{i}{j}]: SE {} is not positive",
                s[(i, j)]
            );
            out.push((
                z,
                format!(
                    "{label}[{i}{j}] est {} truth {} se {}",
                    e[(i, j)],
                    t[(i, j)],
                    s[(i, j)]
                ),
            ));
        }
    }
    out
}

fn linear_elements(label: &str, r: &Value, truth_k: &Value, truth_b: &Value) -> Vec<(f64, String)> {
    let se = &r["standard_errors"];
    let mut z = z_scores(
        &format!("{label} K"),
        &r["stiffness"],
        &se["stiffness"],
        truth_k,
    );
    z.extend(z_scores(
        &format!("{label} B"),
        &r["damping"],
        &se["damping"],
        truth_b,
    ));
    z
}

#[test]
fn the_truth_lies_within_two_standard_errors_of_nine_elements_in_ten() {
    let ex = shared().join("examples");
    let mut z = Vec::new();
    for case in ["ex_cubic", "ex_sinusoid"] {
        let dir = ex.join("cartesian_slow");
        let t = read_json(&dir.join(format!("{case}.truth.json")));
        let rec = dir.join(format!("{case}.csv"));
        let r = json(&["estimate", "linear", rec.to_str().unwrap(), "--json"]);
        z.extend(linear_elements(case, &r, &t["stiffness"], &t["damping"]));
    }
    for case in ["ex_config4", "ex_config7"] {
        let dir = ex.join("cocontraction");
        let t = read_json(&dir.join(format!("{case}.truth.json")));
        let rec = dir.join(format!("{case}.csv"));
        let mvc = dir.join(format!("{case}.mvc.csv"));
        let r = json(&[
            "estimate",
            "cocontraction",
            rec.to_str().unwrap(),
            "--mvc",
            mvc.to_str().unwrap(),
            "--json",
        ]);
        let levels = r["levels"].as_array().unwrap();
        let truths = t["levels"].as_array().unwrap();
        assert_eq!(levels.len(), truths.len(), "{case}");
        for (l, tl) in levels.iter().zip(truths) {
            let label = format!("{case}@{}", l["level"]);
            z.extend(linear_elements(
                &label,
                &l["estimate"],
                &tl["stiffness"],
                &t["damping"],
            ));
        }
    }
    for case in ["ex_endpoint_220", "ex_joint_180"] {
        let dir = ex.join("planar");
        let t = read_json(&dir.join(format!("{case}.truth.json")));
        let rec = dir.join(format!("{case}.csv"));
        let l: Vec<String> = t["link_lengths"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.to_string())
            .collect();
        let r = json(&[
            "estimate",
            "planar",
            rec.to_str().unwrap(),
            "--link-lengths",
            &l.join(","),
            "--json",
        ]);
        z.extend(linear_elements(case, &r, &t["stiffness"], &t["damping"]));
    }
    for case in ["ex_sa3", "ex_sa4"] {
        let dir = ex.join("stochastic");
        let t = read_json(&dir.join(format!("{case}.truth.json")));
        let rec = dir.join(format!("{case}.csv"));
        let r = json(&["estimate", "stochastic", rec.to_str().unwrap(), "--json"]);
        z.extend(linear_elements(case, &r, &t["stiffness"], &t["damping"]));
    }
    z.sort_by(|a, b| b.0.total_cmp(&a.0));
    let covered = z.iter().filter(|(v, _)| *v <= 2.0).count() as f64 / z.len() as f64;
    eprintln!(
        "{} elements, {:.1} % within 2 SE; worst:",
        z.len(),
        100.0 * covered
    );
    for (v, label) in z.iter().take(8) {
        eprintln!("  |z| {v:.2} {label}");
    }
    assert!(z.len() >= 200, "{} elements", z.len());
    assert!((0.90..=0.99).contains(&covered), "coverage {covered}");
    assert!(z[0].0 < 4.0, "worst |z| {:.2}: {}", z[0].0, z[0].1);
}
