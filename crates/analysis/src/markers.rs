//! The arm's configuration from tracked markers (seed 000 §II-A: magnetic
//! trackers at the elbow and the wrist with the reference frame on the
//! shoulder; seed 001: motion capture). Columns `elbow_x/y/z`, `wrist_x/y/z`
//! and optionally `shoulder_x/y/z` (FORMAT.md); without shoulder markers the
//! shoulder is the frame's origin, as in seed 000.

use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use limpid_core::arm::arm_configuration;
use limpid_core::{Error, Recording, Result, Warning, WarningCode};

/// Mean configuration over the recording, angles in degrees.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct MarkerConfiguration {
    /// Samples with every marker present.
    pub samples: usize,
    /// Shoulder elevation (deg).
    pub shoulder_elevation_deg: f64,
    /// Shoulder azimuth (deg).
    pub shoulder_azimuth_deg: f64,
    /// Absent when the elbow is straight or the upper arm vertical in any sample.
    pub humeral_rotation_deg: Option<f64>,
    /// Elbow flexion (deg).
    pub elbow_flexion_deg: f64,
    /// Mean upper-arm length (m).
    pub upper_arm_length_m: f64,
    /// Mean forearm length (m).
    pub forearm_length_m: f64,
    /// Largest deviation of a segment length from its mean (m): markers on a
    /// rigid segment keep it near 0; centimetres mean slipping markers.
    pub segment_length_spread_m: f64,
    /// What the reader should know (slipping markers).
    pub warnings: Vec<Warning>,
}

/// None when the recording has no elbow and wrist markers.
pub fn from_markers(rec: &Recording, up: Vector3<f64>) -> Result<Option<MarkerConfiguration>> {
    let xyz = |m: &str| -> Option<[&[f64]; 3]> {
        Some([
            rec.column(&format!("{m}_x"))?,
            rec.column(&format!("{m}_y"))?,
            rec.column(&format!("{m}_z"))?,
        ])
    };
    let (Some(elbow), Some(wrist)) = (xyz("elbow"), xyz("wrist")) else {
        return Ok(None);
    };
    let shoulder = xyz("shoulder");
    let at = |c: &[&[f64]; 3], k: usize| Vector3::new(c[0][k], c[1][k], c[2][k]);
    let n = rec.len();
    // azimuth and rotation wrap at ±180 deg: averaged as unit vectors
    let mut sums = [0.0; 6];
    let mut circular = [(0.0, 0.0); 2];
    let mut rotation_defined = true;
    let mut lengths = Vec::with_capacity(n);
    for k in 0..n {
        let s = shoulder.as_ref().map_or(Vector3::zeros(), |c| at(c, k));
        let c = arm_configuration(s, at(&elbow, k), at(&wrist, k), up).ok_or_else(|| {
            Error::invalid(
                "markers",
                format!(
                    "{}: row {}: two of the shoulder, elbow and wrist markers coincide",
                    rec.path().display(),
                    k + 2
                ),
            )
        })?;
        sums[0] += c.shoulder_elevation;
        circular[0].0 += c.shoulder_azimuth.sin();
        circular[0].1 += c.shoulder_azimuth.cos();
        match c.humeral_rotation {
            Some(r) => {
                circular[1].0 += r.sin();
                circular[1].1 += r.cos();
            }
            None => rotation_defined = false,
        }
        sums[3] += c.elbow_flexion;
        sums[4] += c.upper_arm_length;
        sums[5] += c.forearm_length;
        lengths.push((c.upper_arm_length, c.forearm_length));
    }
    let mean = |v: f64| v / n as f64;
    let (lu, lf) = (mean(sums[4]), mean(sums[5]));
    let spread = lengths
        .iter()
        .map(|(u, f)| (u - lu).abs().max((f - lf).abs()))
        .fold(0.0, f64::max);
    let mut warnings = Vec::new();
    if spread > 0.01 {
        warnings.push(Warning::new(
            WarningCode::MarkersSlipped,
            format!(
                "a segment length varies by {:.1} cm: the markers may have slipped",
                spread * 100.0
            ),
        ));
    }
    Ok(Some(MarkerConfiguration {
        samples: n,
        shoulder_elevation_deg: mean(sums[0]).to_degrees(),
        shoulder_azimuth_deg: circular[0].0.atan2(circular[0].1).to_degrees(),
        humeral_rotation_deg: rotation_defined
            .then(|| circular[1].0.atan2(circular[1].1).to_degrees()),
        elbow_flexion_deg: mean(sums[3]).to_degrees(),
        upper_arm_length_m: lu,
        forearm_length_m: lf,
        segment_length_spread_m: spread,
        warnings,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn recording(elbow: [f64; 3], wrist: Vec<[f64; 3]>) -> Recording {
        let n = wrist.len();
        let mut names = vec!["t".to_string()];
        let mut cols = vec![(0..n).map(|k| k as f64 * 0.002).collect::<Vec<_>>()];
        for (m, rows) in [("elbow", vec![elbow; n]), ("wrist", wrist)] {
            for (a, axis) in ["x", "y", "z"].iter().enumerate() {
                names.push(format!("{m}_{axis}"));
                cols.push(rows.iter().map(|r| r[a]).collect());
            }
        }
        Recording::new("markers.csv", names, cols, 2).unwrap()
    }

    #[test]
    fn configuration_of_a_horizontal_upper_arm_with_the_forearm_forward() {
        // shoulder at the origin (seed 000), upper arm 0.3 m along -y, horizontal;
        // forearm 0.25 m forward along +x: elbow 90 deg, rotation 90 deg, azimuth -90 deg
        let rec = recording([0.0, -0.3, 0.0], vec![[0.25, -0.3, 0.0]; 50]);
        let c = from_markers(&rec, Vector3::z()).unwrap().unwrap();
        assert!((c.shoulder_elevation_deg - 90.0).abs() < 1e-9);
        assert!((c.shoulder_azimuth_deg + 90.0).abs() < 1e-9);
        assert!((c.elbow_flexion_deg - 90.0).abs() < 1e-9);
        assert!((c.humeral_rotation_deg.unwrap().abs() - 90.0).abs() < 1e-9);
        assert!(c.segment_length_spread_m < 1e-12 && c.warnings.is_empty());
        // a wrist marker that slides 3 cm along the forearm is flagged
        let mut wrist = vec![[0.25, -0.3, 0.0]; 50];
        wrist[10][0] = 0.28;
        let c = from_markers(&recording([0.0, -0.3, 0.0], wrist), Vector3::z())
            .unwrap()
            .unwrap();
        assert!(
            c.warnings[0].message.contains("may have slipped"),
            "{:?}",
            c.warnings
        );
    }

    #[test]
    fn coincident_markers_name_the_row_and_no_markers_is_none() {
        let mut wrist = vec![[0.25, -0.3, 0.0]; 5];
        wrist[3] = [0.0, -0.3, 0.0];
        let e = from_markers(&recording([0.0, -0.3, 0.0], wrist), Vector3::z())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("markers.csv: row 5: two of the shoulder, elbow and wrist markers coincide"),
            "{e}"
        );
        let plain = Recording::new("p.csv", vec!["t".into()], vec![vec![0.0, 1.0]], 2).unwrap();
        assert!(from_markers(&plain, Vector3::z()).unwrap().is_none());
    }
}
