//! A demo's result document round-trips through the result contract.

use limpid_analysis::result::{Document, Estimate, SCHEMA_VERSION};

#[test]
fn a_demo_document_round_trips_and_names_its_kind_and_schema() {
    let demo = limpid_app::demo::run_demo(
        limpid_lab::Profile::Cubic,
        limpid_analysis::result::demo::DemoSubject::Realistic,
        3,
        true,
        &|| (),
    )
    .unwrap();
    let doc = Document::new(Estimate::Demo(demo));
    let text = doc.to_json();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["schema"], SCHEMA_VERSION);
    assert_eq!(v["kind"], "demo");
    let back = Document::from_json("demo", &text).unwrap();
    let Estimate::Demo(d) = back.estimate else {
        panic!("kind lost")
    };
    // the stiffness of every start point comes back to the last bit
    let Estimate::Demo(orig) = &doc.estimate else {
        unreachable!()
    };
    for (a, b) in d.points.iter().zip(&orig.points) {
        assert_eq!(a.estimate.stiffness, b.estimate.stiffness);
    }
    // a text serialised again is the same text
    assert_eq!(Document::from_json("demo", &text).unwrap().to_json(), text);
}
