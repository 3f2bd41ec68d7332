//! The committed JSON Schema of the result contract is the one the types
//! generate (regenerate with `LIMPID_UPDATE_SCHEMA=1 cargo test -p
//! limpid-analysis --test schema`), and documents round-trip through it.

use limpid_analysis::result::{json_schema, Document};

const SCHEMA_FILE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../schema/limpid-result.v1.schema.json"
);

#[test]
fn committed_schema_matches_the_types() {
    let generated = serde_json::to_string_pretty(&json_schema()).unwrap() + "\n";
    if std::env::var_os("LIMPID_UPDATE_SCHEMA").is_some() {
        std::fs::write(SCHEMA_FILE, &generated).unwrap();
    }
    let committed = std::fs::read_to_string(SCHEMA_FILE).expect("schema file committed");
    assert!(
        committed == generated,
        "{SCHEMA_FILE} is out of date: the result types changed. Regenerate it with \
         LIMPID_UPDATE_SCHEMA=1 cargo test -p limpid-analysis --test schema, and raise \
         SCHEMA_VERSION if a field changed meaning or was removed"
    );
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
