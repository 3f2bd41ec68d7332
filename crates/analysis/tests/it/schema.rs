//! The committed JSON Schemas of the result contract and of the truth files
//! are the ones the types generate (regenerate with `LIMPID_UPDATE_SCHEMA=1
//! cargo test -p limpid-analysis --test it schema`), documents round-trip
//! through them, and every example's truth (limpid's and the outside
//! generator's) reads through its type.

use limpid_analysis::result::{json_schema, Document};
use limpid_core::Truth;

const TRUTH_SCHEMA_FILE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../schema/limpid-truth.v1.schema.json"
);

/// The committed `file` is the `schema` the types generate (rewritten first
/// with `LIMPID_UPDATE_SCHEMA`); `what` says which types changed.
fn assert_committed(file: &str, schema: &serde_json::Value, what: &str) {
    let generated = serde_json::to_string_pretty(schema).unwrap() + "\n";
    if std::env::var_os("LIMPID_UPDATE_SCHEMA").is_some() {
        std::fs::write(file, &generated).unwrap();
    }
    let committed = std::fs::read_to_string(file).expect("schema file committed");
    assert!(
        committed == generated,
        "{file} is out of date: the {what} types changed. Regenerate it with \
         LIMPID_UPDATE_SCHEMA=1 cargo test -p limpid-analysis --test it schema, and raise \
         its version if a field changed meaning or was removed"
    );
}

#[test]
fn committed_truth_schema_matches_the_types() {
    assert_committed(TRUTH_SCHEMA_FILE, &Truth::json_schema(), "truth");
}

/// Every number as a float, so that 220 and 220.0 compare equal.
fn as_floats(v: serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    match v {
        Value::Number(n) => serde_json::json!(n.as_f64().expect("finite")),
        Value::Array(a) => Value::Array(a.into_iter().map(as_floats).collect()),
        Value::Object(o) => Value::Object(o.into_iter().map(|(k, v)| (k, as_floats(v))).collect()),
        other => other,
    }
}

#[test]
fn every_example_truth_reads_through_its_type_and_keeps_its_keys() {
    for family in limpid_testkit::examples::FAMILIES {
        let mut sets = vec![limpid_testkit::limpid_examples(family)];
        // the outside set has no ankle family
        if family != "ankle" {
            sets.extend(limpid_testkit::outside_examples(family));
        }
        for dir in sets {
            let mut read = 0;
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                if !path.to_string_lossy().ends_with(".truth.json") {
                    continue;
                }
                let truth = limpid_testkit::read_truth(&path);
                let kind = matches!(
                    (&truth, family),
                    (Truth::Cartesian(_), "cartesian_slow")
                        | (Truth::Cocontraction(_), "cocontraction")
                        | (Truth::Planar(_), "planar")
                        | (Truth::Stochastic(_), "stochastic")
                        | (Truth::Reflex(_), "ankle")
                );
                assert!(
                    kind,
                    "{}: a {family} example read as {truth:?}",
                    path.display()
                );
                // nothing is lost: written back, the file says the same (220 and 220.0 alike)
                let original = limpid_testkit::read_json(&path);
                assert_eq!(
                    as_floats(serde_json::to_value(&truth).unwrap()),
                    as_floats(original),
                    "{}",
                    path.display()
                );
                read += 1;
            }
            assert!(read >= 1, "{}: no truth files", dir.display());
        }
    }
}

const SCHEMA_FILE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../schema/limpid-result.v1.schema.json"
);

#[test]
fn committed_schema_matches_the_types() {
    assert_committed(SCHEMA_FILE, &json_schema(), "result");
}

#[test]
fn documents_of_another_schema_or_none_are_refused_in_one_line() {
    let e = Document::from_json("old.json", "[{\"start_point\": \"S1\"}]").unwrap_err();
    assert!(e.starts_with("old.json: not a limpid result"), "{e}");
    let e = Document::from_json("new.json", "{\"schema\": 99, \"kind\": \"linear\"}").unwrap_err();
    assert!(e.contains("schema 99"), "{e}");
    let e = Document::from_json("odd.json", "{\"schema\": 1, \"kind\": \"banana\"}").unwrap_err();
    assert!(e.contains("banana"), "{e}");
    assert!(!e.contains('\n'));
    // a schema key that is not a whole number is named as such, not as missing
    for odd in ["1.0", "\"1\"", "-1", "null"] {
        let text = format!("{{\"schema\": {odd}, \"kind\": \"linear\"}}");
        let e = Document::from_json("odd.json", &text).unwrap_err();
        assert!(e.contains("expected the whole number 1"), "{odd}: {e}");
    }
}
