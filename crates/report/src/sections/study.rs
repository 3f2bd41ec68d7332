//! The section of a co-contraction study (seed 001 Tables 1-5): means and SDs over subjects, stiffness and index against level.

use super::linear::ellipsoid_view;
use crate::{
    ellipse, fmt, mean_sd, Chart, Drawing, EllipsoidView, Figure, Section, Series, Stroke, Table,
    PALETTE,
};
use limpid_analysis::result::study::StudyResult;

/// A whole seed 001 study: means over subjects per configuration and level,
/// ellipsoid rotation from level 0 to 1, and the stiffness against the index.
pub(crate) fn study_section(name: &str, v: &StudyResult) -> Section {
    let mut configs: Vec<&String> = v.levels.iter().map(|r| &r.configuration).collect();
    configs.dedup();
    let (ellipsoids, drawings) = ellipsoid_views(v, &configs);
    let figures = vec![k1_against_index(v, &configs)];
    let failures: Vec<String> = v
        .failures
        .iter()
        .map(|f| {
            format!(
                "subject {}, configuration {}: {}",
                f.subject, f.configuration, f.error
            )
        })
        .collect();
    Section {
        heading: format!("Study {}: {name}", v.name),
        verdict: format!(
            "{} recordings analysed, {} failed; {} configurations",
            v.recordings.len(),
            failures.len(),
            configs.len()
        ),
        warnings: failures,
        tables: tables(v).into(),
        figures,
        ellipsoids,
        drawings,
    }
}

/// The means ± sd per configuration and level, and the ellipsoid rotations.
fn tables(v: &StudyResult) -> [Table; 2] {
    let levels = Table {
        caption: "Mean ± sd over subjects per configuration and level (Patel et al. 2013, Tables 1-5): co-contraction index (fraction of MVC), diagonal stiffness, largest antisymmetric element, principal stiffnesses (N/m)".into(),
        header: [
            "configuration",
            "level",
            "subjects (n)",
            "index C",
            "Kxx",
            "Kyy",
            "Kzz",
            "K_maxA",
            "K1",
            "K2",
            "K3",
        ]
        .map(String::from)
        .to_vec(),
        rows: v
            .levels
            .iter()
            .map(|r| {
                let sd = &r.sd;
                vec![
                    r.configuration.clone(),
                    fmt(r.level),
                    r.subjects.to_string(),
                    mean_sd(r.cocontraction_index, sd.cocontraction_index),
                    mean_sd(r.kxx, sd.kxx),
                    mean_sd(r.kyy, sd.kyy),
                    mean_sd(r.kzz, sd.kzz),
                    mean_sd(r.k_max_a, sd.k_max_a),
                    mean_sd(r.k1, sd.k1),
                    mean_sd(r.k2, sd.k2),
                    mean_sd(r.k3, sd.k3),
                ]
            })
            .collect(),
    };
    let list = |x: &[f64]| x.iter().map(|v| fmt(*v)).collect::<Vec<_>>().join(" / ");
    let rotation = Table {
        caption: "Stiffness ellipsoid from the lowest to the highest level: axis rotations and principal changes".into(),
        header: ["configuration", "from", "to", "subjects", "rotation (deg)", "principal change %"].map(String::from).to_vec(),
        rows: v
            .rotation
            .iter()
            .map(|r| {
                vec![
                    r.configuration.clone(),
                    fmt(r.from_level),
                    fmt(r.to_level),
                    r.subjects.to_string(),
                    list(&r.rotation_deg),
                    list(&r.principal_change_percent),
                ]
            })
            .collect(),
    };
    [levels, rotation]
}

/// The mean stiffness ellipsoids (3-D views: levels side by side along x,
/// configurations down z) and the small multiples (configurations down,
/// levels across), as seed 001 Fig. 5.
fn ellipsoid_views(v: &StudyResult, configs: &[&String]) -> (Vec<EllipsoidView>, Vec<Drawing>) {
    let mut ellipsoids = Vec::new();
    for (i, c) in configs.iter().enumerate() {
        let at = v.levels.iter().filter(|r| &r.configuration == *c);
        for (j, r) in at.enumerate() {
            let point = format!("configuration {c}, level {}", fmt(r.level));
            let centre = [0.15 * j as f64, 0.0, -0.15 * i as f64];
            if let Some(e) = &r.ellipsoid {
                ellipsoids.extend(ellipsoid_view(&point, "stiffness", centre, e));
            }
        }
    }
    let mut level_values: Vec<f64> = v.levels.iter().map(|r| r.level).collect();
    level_values.sort_by(f64::total_cmp);
    level_values.dedup();
    let cells: Vec<Vec<Option<EllipsoidView>>> = configs
        .iter()
        .map(|c| {
            level_values
                .iter()
                .map(|level| {
                    let r = v
                        .levels
                        .iter()
                        .find(|r| &r.configuration == *c && r.level == *level)?;
                    let point = format!("configuration {c}, level {}", fmt(*level));
                    ellipsoid_view(&point, "stiffness", [0.0; 3], r.ellipsoid.as_ref()?)
                })
                .collect()
        })
        .collect();
    let drawings =
        vec![Drawing {
        id: "study-stiffness-ellipsoids".into(),
        svg: ellipse::grid(
            "Mean stiffness ellipsoid per configuration and co-contraction level (Patel et al. 2013, Fig. 5)",
            &configs.iter().map(|c| format!("configuration {c}")).collect::<Vec<_>>(),
            &level_values.iter().map(|l| format!("level {}", fmt(*l))).collect::<Vec<_>>(),
            &cells,
            "N/m",
            ellipse::View::DEFAULT,
        ),
    }];
    (ellipsoids, drawings)
}

/// The largest principal stiffness against the co-contraction index, one line per configuration.
fn k1_against_index(v: &StudyResult, configs: &[&String]) -> Figure {
    let series: Vec<Series> = configs
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let pts: Vec<_> = v.levels.iter().filter(|r| &r.configuration == *c).collect();
            Series {
                name: format!("configuration {c}"),
                x: pts
                    .iter()
                    .map(|r| r.cocontraction_index.unwrap_or(f64::NAN))
                    .collect(),
                y: pts.iter().map(|r| r.k1.unwrap_or(f64::NAN)).collect(),
                stroke: Stroke::Solid,
                color: PALETTE[k % PALETTE.len()].into(),
            }
        })
        .collect();
    Figure {
        id: "study-k1".into(),
        chart: Chart {
            title: "Largest principal stiffness against the co-contraction index".into(),
            x_label: "co-contraction index (fraction of MVC)".into(),
            y_label: "k1 (N/m)".into(),
            x_log: false,
            y_log: false,
            y_range: None,
            series,
        },
    }
}
