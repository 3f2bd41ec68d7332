//! Whole studies (seed 001 Tables 1-5): subjects x configurations x
//! recordings listed in a TOML manifest, processed in parallel (in
//! `limpid-app`), averaged across subjects per configuration and level (here).
//!
//! Manifest (paths relative to the manifest's folder):
//!
//! ```toml
//! [study]
//! name = "virtual Patel, O'Neill & Artemiadis (2013)"   # optional
//! tolerance = 0.1             # optional, band around the target level
//!
//! [study.request.prepare]     # optional: `limpid estimate cocontraction`'s request
//! cutoff_hz = 20
//!
//! [[recording]]
//! subject = "1"
//! configuration = "4"
//! file = "s1_c4.parquet"
//! mvc = "s1_mvc.parquet"
//! ```
//!
//! Tables 1-4: per configuration and level, the across-subject means of Kxx,
//! Kyy, Kzz, K_maxA (largest antisymmetric element), K1, K2, K3 (principal
//! stiffnesses). Table 5: per configuration, the mean rotation of the
//! primary, secondary and tertiary axes from the lowest to the highest level
//! (axes matched by direction, see [`crate::cocontraction`]), with the mean
//! percent change of each principal stiffness (Fig. 6). A recording that fails
//! is listed with its error and left out of the means.

use std::path::PathBuf;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::cocontraction::{compare, CocontractionResult};
use limpid_ident::request::CocontractionRequest;

/// The manifest file.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    #[serde(default)]
    /// Study-wide settings.
    pub study: StudyMeta,
    #[serde(default)]
    /// The recordings.
    pub recording: Vec<Entry>,
}

/// Study-wide settings.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct StudyMeta {
    /// Study name for the tables.
    pub name: Option<String>,
    /// Half-width of the band around each target level (the request's
    /// default when absent); the same as `request.tolerance`, give one.
    pub tolerance: Option<f64>,
    /// How every recording is analysed: `limpid estimate cocontraction`'s
    /// request (`[study.request]` with `tolerance`, `[study.request.prepare]`
    /// with the preparation options); absent: the defaults.
    pub request: Option<CocontractionRequest>,
    /// The channel map every recording is read through (a rig's lab files:
    /// docs/src/reference/lab-files.md), relative to the manifest.
    pub map: Option<PathBuf>,
}

impl StudyMeta {
    /// The request every recording of the study is run with.
    pub fn request(&self) -> limpid_core::Result<CocontractionRequest> {
        match (&self.request, self.tolerance) {
            (Some(_), Some(_)) => Err(limpid_core::Error::invalid(
                "study.tolerance",
                "give the tolerance once: as study.tolerance or as study.request.tolerance",
            )),
            (Some(r), None) => Ok(r.clone()),
            (None, Some(tolerance)) => Ok(CocontractionRequest {
                tolerance,
                ..CocontractionRequest::default()
            }),
            (None, None) => Ok(CocontractionRequest::default()),
        }
    }
}

/// One recording of one subject in one configuration.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Entry {
    /// Subject id.
    pub subject: String,
    /// Arm configuration id.
    pub configuration: String,
    /// The recording.
    pub file: PathBuf,
    /// Its MVC recording.
    pub mvc: PathBuf,
    /// The channel map both are read through (lab files; `[study] map` when
    /// the entry gives none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map: Option<PathBuf>,
}

/// Tables 1-4 row: one configuration at one level.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct LevelRow {
    /// Arm configuration.
    pub configuration: String,
    /// Co-contraction level.
    pub level: f64,
    /// Subjects averaged.
    pub subjects: usize,
    /// Means over the subjects that have the value; null when none has it.
    pub cocontraction_index: Option<f64>,
    /// Mean Kxx (N/m).
    pub kxx: Option<f64>,
    /// Mean Kyy (N/m).
    pub kyy: Option<f64>,
    /// Mean Kzz (N/m).
    pub kzz: Option<f64>,
    /// Mean largest antisymmetric element (N/m).
    pub k_max_a: Option<f64>,
    /// Mean primary principal stiffness (N/m).
    pub k1: Option<f64>,
    /// Mean secondary principal stiffness (N/m).
    pub k2: Option<f64>,
    /// Mean tertiary principal stiffness (N/m).
    pub k3: Option<f64>,
    /// Sample standard deviation over the subjects of each mean above (as
    /// seed 001's tables give mean ± sd); a field is absent with fewer than two values.
    #[serde(default)]
    pub sd: LevelSpread,
    /// Mean stiffness matrix over subjects (N/m) and its ellipsoid (seed 001 Fig. 5).
    pub stiffness: crate::Matrix,
    /// Ellipsoid of the mean matrix; absent when it is not 2 x 2 or 3 x 3.
    pub ellipsoid: Option<crate::Ellipsoid>,
}

/// Standard deviations over subjects of one [`LevelRow`]'s means (same
/// units); a field is absent with fewer than two values (never null).
#[derive(Debug, Clone, Default, Serialize, Deserialize, JsonSchema)]
pub struct LevelSpread {
    /// Of the co-contraction index.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cocontraction_index: Option<f64>,
    /// Of Kxx (N/m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kxx: Option<f64>,
    /// Of Kyy (N/m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kyy: Option<f64>,
    /// Of Kzz (N/m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kzz: Option<f64>,
    /// Of the largest antisymmetric element (N/m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k_max_a: Option<f64>,
    /// Of the primary principal stiffness (N/m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k1: Option<f64>,
    /// Of the secondary principal stiffness (N/m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k2: Option<f64>,
    /// Of the tertiary principal stiffness (N/m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k3: Option<f64>,
}

/// Table 5 row (and Fig. 6): highest vs lowest level for one configuration.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct RotationRow {
    /// Arm configuration.
    pub configuration: String,
    /// Lowest level.
    pub from_level: f64,
    /// Highest level.
    pub to_level: f64,
    /// Subjects with both levels.
    pub subjects: usize,
    /// Mean rotation of primary, secondary, tertiary axes (deg).
    pub rotation_deg: Vec<f64>,
    /// Mean percent change of primary, secondary, tertiary stiffness.
    pub principal_change_percent: Vec<f64>,
}

/// A recording that could not be processed.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Failure {
    /// Subject id.
    pub subject: String,
    /// Arm configuration id.
    pub configuration: String,
    /// The recording.
    pub file: String,
    /// The error, in one line.
    pub error: String,
}

/// One processed recording.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Processed {
    /// Subject id.
    pub subject: String,
    /// Arm configuration id.
    pub configuration: String,
    /// Its co-contraction analysis.
    pub result: CocontractionResult,
}

/// The whole study.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct StudyResult {
    /// Study name.
    pub name: String,
    /// Tables 1-4 rows.
    pub levels: Vec<LevelRow>,
    /// Table 5 rows.
    pub rotation: Vec<RotationRow>,
    /// Recordings left out, with their errors.
    pub failures: Vec<Failure>,
    /// Every processed recording.
    pub recordings: Vec<Processed>,
}

/// Tables 1-5 from the outcomes of a study's recordings (in the manifest's
/// order): per configuration and level the means and spreads over subjects,
/// per configuration the rotation from the lowest to the highest level.
pub fn summarise(
    name: String,
    outcomes: Vec<std::result::Result<Processed, Failure>>,
) -> StudyResult {
    let mut recordings = Vec::new();
    let mut failures = Vec::new();
    for o in outcomes {
        match o {
            Ok(p) => recordings.push(p),
            Err(f) => failures.push(f),
        }
    }
    let mut configurations: Vec<String> =
        recordings.iter().map(|p| p.configuration.clone()).collect();
    configurations.sort_by(|a, b| natural(a, b));
    configurations.dedup();
    let mut levels_out = Vec::new();
    let mut rotation = Vec::new();
    for c in &configurations {
        let group: Vec<&Processed> = recordings
            .iter()
            .filter(|p| &p.configuration == c)
            .collect();
        let mut levels: Vec<f64> = group
            .iter()
            .flat_map(|p| p.result.levels.iter().map(|l| l.level))
            .collect();
        levels.sort_by(f64::total_cmp);
        levels.dedup();
        for level in &levels {
            levels_out.push(level_row(c, *level, &group));
        }
        rotation.extend(rotation_row(c, &levels, &group));
    }
    StudyResult {
        name,
        levels: levels_out,
        rotation,
        failures,
        recordings,
    }
}

/// The means and spreads over subjects of one configuration at one level.
fn level_row(c: &str, level: f64, group: &[&Processed]) -> LevelRow {
    let at: Vec<&crate::cocontraction::LevelResult> = group
        .iter()
        .filter_map(|p| p.result.levels.iter().find(|l| l.level == level))
        .collect();
    // mean over the recordings that have the value (a matrix without an
    // ellipsoid has no eigenvalues); NaN only when none has it, which
    // the tables write as an empty cell
    let mean = |f: &dyn Fn(&crate::cocontraction::LevelResult) -> f64| {
        let v: Vec<f64> = at.iter().map(|l| f(l)).filter(|v| v.is_finite()).collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    let sd = |f: &dyn Fn(&crate::cocontraction::LevelResult) -> f64| {
        let v: Vec<f64> = at.iter().map(|l| f(l)).filter(|v| v.is_finite()).collect();
        (v.len() >= 2).then(|| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
        })
    };
    let eig = |l: &crate::cocontraction::LevelResult, i: usize| {
        l.ellipsoid
            .as_ref()
            .and_then(|e| e.eigenvalues.get(i).copied())
            .unwrap_or(f64::NAN)
    };
    let k = |l: &crate::cocontraction::LevelResult, i: usize| {
        l.stiffness.get((i, i)).copied().unwrap_or(f64::NAN)
    };
    // every recording has x, y, z (checked above): 3 x 3 matrices
    let n = at.first().map_or(0, |l| l.stiffness.nrows());
    let same_shape = at.iter().all(|l| l.stiffness.shape() == (n, n));
    let n = if same_shape { n } else { 0 };
    let mean_k = crate::Matrix(nalgebra::DMatrix::from_fn(n, n, |r, c| {
        mean(&|l| l.stiffness[(r, c)]).unwrap_or(f64::NAN)
    }));
    LevelRow {
        configuration: c.to_string(),
        level,
        subjects: at.len(),
        cocontraction_index: mean(&|l| l.cocontraction_index),
        kxx: mean(&|l| k(l, 0)),
        kyy: mean(&|l| k(l, 1)),
        kzz: mean(&|l| k(l, 2)),
        k_max_a: mean(&|l| l.estimate.table_ii.stiffness.max_antisymmetric),
        k1: mean(&|l| eig(l, 0)),
        k2: mean(&|l| eig(l, 1)),
        k3: mean(&|l| eig(l, 2)),
        sd: LevelSpread {
            cocontraction_index: sd(&|l| l.cocontraction_index),
            kxx: sd(&|l| k(l, 0)),
            kyy: sd(&|l| k(l, 1)),
            kzz: sd(&|l| k(l, 2)),
            k_max_a: sd(&|l| l.estimate.table_ii.stiffness.max_antisymmetric),
            k1: sd(&|l| eig(l, 0)),
            k2: sd(&|l| eig(l, 1)),
            k3: sd(&|l| eig(l, 2)),
        },
        ellipsoid: crate::ellipsoid(&mean_k),
        stiffness: mean_k,
    }
}

/// The ellipsoid's mean rotation and principal changes from the lowest to
/// the highest level of one configuration, over the subjects that have both.
fn rotation_row(c: &str, levels: &[f64], group: &[&Processed]) -> Option<RotationRow> {
    let (lo, hi) = (levels.first()?, levels.last()?);
    let changes: Vec<_> = group
        .iter()
        .filter_map(|p| {
            let a = p.result.levels.iter().find(|l| l.level == *lo)?;
            let b = p.result.levels.iter().find(|l| l.level == *hi)?;
            compare(&a.stiffness, &b.stiffness)
        })
        .collect();
    if lo == hi || changes.is_empty() {
        return None;
    }
    let n = changes[0].rotation_deg.len();
    let avg = |f: &dyn Fn(&crate::cocontraction::EllipsoidChange) -> &Vec<f64>| {
        (0..n)
            .map(|i| changes.iter().map(|c| f(c)[i]).sum::<f64>() / changes.len() as f64)
            .collect()
    };
    Some(RotationRow {
        configuration: c.to_string(),
        from_level: *lo,
        to_level: *hi,
        subjects: changes.len(),
        rotation_deg: avg(&|c| &c.rotation_deg),
        principal_change_percent: avg(&|c| &c.change_percent),
    })
}

/// Numbers in numeric order, then text.
fn natural(a: &str, b: &str) -> std::cmp::Ordering {
    match (a.parse::<f64>(), b.parse::<f64>()) {
        (Ok(x), Ok(y)) => x.total_cmp(&y),
        _ => a.cmp(b),
    }
}

/// A table cell: the value with `decimals`, or `missing` when no recording had it.
pub fn cell(v: Option<f64>, decimals: usize, missing: &str) -> String {
    v.filter(|v| v.is_finite())
        .map_or(missing.to_string(), |v| format!("{v:.decimals$}"))
}
