//! The section of `limpid calibrate`: coverage and verdict rates per method.

#[allow(unused_imports)]
use crate::*;

pub(crate) fn calibration_section(
    name: &str,
    v: &limpid_analysis::calibrate::Calibration,
) -> Section {
    let (header, rows) = v.table();
    let w = &v.window_sweep;
    Section {
        heading: format!("Calibration of standard errors and verdicts: {name}"),
        verdict: format!(
            "{} virtual recordings per method (seed {}); window sweep: {} of {} trusted windows beyond K 10 % / D 25 % of the truth",
            v.recordings_per_method, v.seed, w.trusted_but_wrong, w.trusted_windows
        ),
        warnings: vec![],
        tables: vec![Table {
            caption: "Per method and matrix: truth within ±2 reported SE, and how often a verdict is wrong".into(),
            header,
            rows,
        }],
        figures: vec![],
        ellipsoids: vec![],
        drawings: vec![],
    }
}
