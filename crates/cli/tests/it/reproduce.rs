//! `limpid reproduce`: each seed's experiment on the realistic virtual
//! subjects, compared with the paper's numbers (issue 18).

use crate::common::*;
use serde_json::Value;

fn rows<'a>(r: &'a Value, seed: &str, item_start: &str) -> Vec<&'a Value> {
    r["rows"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|x| x["seed"] == seed && x["item"].as_str().unwrap().starts_with(item_start))
        .collect()
}

fn finding<'a>(r: &'a Value, seed: &str, claim_part: &str) -> &'a Value {
    r["findings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["seed"] == seed && f["claim"].as_str().unwrap().contains(claim_part))
        .unwrap_or_else(|| panic!("no finding of seed {seed} about {claim_part:?}"))
}

#[test]
fn reproduce_all_prints_every_seeds_tables_and_the_findings_hold_where_the_subject_allows() {
    let out = limpid(&["reproduce", "all", "--json"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let r: Value = serde_json::from_str(&out.stdout).unwrap();
    for seed in ["000", "001", "003", "004"] {
        assert!(!rows(&r, seed, "").is_empty(), "no rows for seed {seed}");
    }
    // every row has the contract's keys; no NaN passes as a number
    for x in r["rows"].as_array().unwrap() {
        for key in ["seed", "item", "paper", "limpid", "unit", "note"] {
            assert!(x.get(key).is_some(), "{x} lacks {key}");
        }
    }

    // seed 001 Tables 1-4: 7 configurations x 4 levels x 7 values; the
    // principal stiffnesses within 15 % of the tables (4 subjects, realistic noise)
    assert_eq!(rows(&r, "001", "Table ").len(), 4 * 7 * 7 + 7 * 3);
    for l in ["Table 1", "Table 2", "Table 3", "Table 4"] {
        for x in rows(&r, "001", l) {
            let item = x["item"].as_str().unwrap();
            let (p, v) = (x["paper"].as_f64().unwrap(), x["limpid"].as_f64().unwrap());
            if item.ends_with("K_1") || item.ends_with("K_2") || item.ends_with("K_3") {
                assert!((v / p - 1.0).abs() < 0.15, "{item}: {v} vs {p}");
            }
            // the largest |element| of a noisy antisymmetric part is biased
            // upwards where the true one is small (configuration 6: 164 N/m)
            if item.ends_with("K_maxA") {
                assert!((0.6..1.8).contains(&(v / p)), "{item}: {v} vs {p}");
            }
        }
    }
    // Table 5: the secondary and tertiary axes turn within 12 degrees of the paper
    for x in rows(&r, "001", "Table 5") {
        let item = x["item"].as_str().unwrap();
        let (p, v) = (x["paper"].as_f64().unwrap(), x["limpid"].as_f64().unwrap());
        assert!((v - p).abs() < 12.0, "{item}: {v} vs {p}");
    }
    for claim in [
        "K_maxA",
        "tertiary axis",
        "turns the secondary",
        "not linear",
    ] {
        let f = finding(&r, "001", claim);
        assert_eq!(f["holds"], true, "{f}");
    }

    // seed 000: fit correlations of the realistic subject near the paper's
    let r000 = rows(&r, "000", "fit correlation");
    assert_eq!(r000.len(), 3);
    for x in r000 {
        let v = x["limpid"].as_f64().unwrap();
        assert!((0.8..0.98).contains(&v), "{x}");
    }
    assert_eq!(rows(&r, "000", "Table II").len(), 6 * 9);
    // Table I's stiffness diagonal recovered within 20 % under realistic noise
    let table_i = rows(&r, "000", "Table I,");
    assert_eq!(table_i.len(), 6 * 6);
    for x in table_i
        .iter()
        .filter(|x| x["item"].as_str().unwrap().contains("K_"))
    {
        let (p, v) = (x["paper"].as_f64().unwrap(), x["limpid"].as_f64().unwrap());
        assert!((v / p - 1.0).abs() < 0.2, "{x}");
    }
    assert_eq!(finding(&r, "000", "antisymmetric")["holds"], true);

    // seed 003: Table I's comparison holds; thresholds are reported
    assert_eq!(finding(&r, "003", "fifth-order")["holds"], true);
    assert_eq!(rows(&r, "003", "Table I").len(), 6);
    assert!(rows(&r, "003", "shortest T_obs with K positive definite")[0]["limpid"].is_number());

    // seed 004: IMBIC's multiple coherence above PD's; f_r of Table III
    assert_eq!(
        finding(&r, "004", "higher multiple coherence")["holds"],
        true
    );
    let fr = rows(&r, "004", "Table III")[0]["limpid"].as_f64().unwrap();
    assert!((fr - 1000.0 / 24576.0).abs() < 1e-12);
    for x in rows(&r, "004", "K error") {
        assert!(x["limpid"].as_f64().unwrap() < 10.0, "{x}");
    }
}

#[test]
fn reproduce_prints_a_table_per_paper_and_refuses_unknown_papers() {
    let out = limpid(&["reproduce", "003"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains("Lakatos, Petit & van der Smagt (2011)"));
    assert!(!out.stdout.contains("seed 003"), "{}", out.stdout);
    // the id a reader understands gives the same tables as the numeric alias
    let by_id = limpid(&["reproduce", "lakatos2011"]);
    assert_eq!(by_id.code, 0, "{}", by_id.stderr);
    assert_eq!(by_id.stdout, out.stdout);
    assert!(out.stdout.contains("paper"));
    assert!(out.stdout.contains("findings"));
    assert!(!out.stdout.contains("NaN"));
    for name in ["002", "", "artemiadis"] {
        let bad = limpid(&["reproduce", name]);
        assert_ne!(bad.code, 0, "{name:?}");
        assert!(bad.stderr.contains("unknown paper"), "{}", bad.stderr);
        assert!(bad.stderr.contains("artemiadis2010"), "{}", bad.stderr);
        assert_eq!(bad.stderr.trim().lines().count(), 1, "{}", bad.stderr);
    }
}

#[test]
fn reproduce_out_writes_json_and_text() {
    let dir = tempfile::tempdir().unwrap();
    let page = dir.path().join("page.html");
    let out = limpid(&[
        "reproduce",
        "004",
        "--out",
        dir.path().to_str().unwrap(),
        "--report",
        page.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let json: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("reproduce.json")).unwrap())
            .unwrap();
    assert!(!json["rows"].as_array().unwrap().is_empty());
    assert!(std::fs::read_to_string(dir.path().join("reproduce.txt"))
        .unwrap()
        .contains("Park & Chang (2011)"));
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains("<h2>Park &amp; Chang (2011)</h2>"), "{html}");
    assert!(html.contains("higher multiple coherence"));
    assert!(!html.contains("http://") && !html.contains("https://"));
    assert!(!html.contains("NaN"));
}
