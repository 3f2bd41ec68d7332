//! The section of `limpid calibrate`: coverage and verdict rates per method.

use crate::{Section, Table};

pub(crate) fn calibration_section(
    name: &str,
    v: &limpid_analysis::result::calibration::Calibration,
) -> Section {
    let (header, rows) = v.table();
    let sweep = |title: &str, w: &limpid_analysis::result::calibration::SweepCalibration| {
        format!(
            "; window sweep, {title}: {} of {} trusted windows beyond K 10 % / D 25 % of the truth, a change (reflex?) claimed in {} of {} sweeps without a reflex and {} of {} with one ({} and {} of them on cuffed arms, {} and {} put down to soft tissue in series)",
            w.trusted_but_wrong,
            w.trusted_windows,
            w.changes_claimed[0],
            w.without_reflex(),
            w.changes_claimed[1],
            w.with_reflex,
            w.cuff_changes_claimed[0],
            w.cuff_changes_claimed[1],
            w.tissue_named[0],
            w.tissue_named[1]
        )
    };
    let mut verdict = format!(
        "{} virtual recordings per method (seed {})",
        v.recordings_per_method, v.seed
    );
    verdict += &sweep("Lakatos et al. (2011) session", &v.window_sweep);
    if let Some(w) = &v.window_sweep_varied {
        verdict += &sweep("varied subjects", w);
    }
    let designs = [
        ("linear", &v.design, "B"),
        ("stochastic", &v.stochastic_design, "B"),
        ("planar", &v.planar_design, "D"),
    ];
    for (method, d, b) in designs
        .iter()
        .filter_map(|(m, d, b)| d.as_ref().map(|d| (m, d, b)))
    {
        verdict += &format!(
            "; protocol design ({method}) for {}: predicted/achieved spread K {:.2}, {b} {:.2} over {} subjects, {:.0} % within K 5 % and {b} 20 %",
            d.prior,
            d.ratio[0],
            d.ratio[1],
            d.recordings,
            100.0 * d.within_tolerance_share
        );
    }
    Section {
        heading: format!("Calibration of standard errors and verdicts: {name}"),
        verdict,
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
