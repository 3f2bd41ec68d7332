//! Co-contraction studies (seed 001): per-level impedance, co-contraction
//! index per level, and the comparisons of Fig. 6 and Table 5.
//!
//! Each level is estimated on its own trials with the foundation estimator in
//! seed 001's 9-column form (`P = F Y^+`, no equilibrium term, eq. (3)-(10)).
//! Comparisons are against the lowest level:
//! - percent change of each principal stiffness (eigenvalues of the symmetric
//!   part, sorted: primary > secondary > tertiary);
//! - rotation of each principal axis, `acos(|e_i . e_i'|)` in [0, 90] degrees
//!   (the sign of an eigenvector is arbitrary).
//!
//! Axes are matched by direction, not by the order of their eigenvalues: the
//! permutation that maximises the sum of `|cos|` between reference and
//! compared axes. Co-contraction can raise the tertiary stiffness past the
//! secondary (ex_config4: 471 -> 905 N/m past 663 -> 683 N/m); matching by
//! order would then report an 84-degree "rotation" and a +39 % secondary
//! change instead of the true +92 % along the tertiary axis. `order_changed`
//! says when the matched axes changed rank. A rotation beyond 45 degrees in
//! a principal plane is read as an exchange of the two axes. Where two eigenvalues of either
//! level are within 5 % of each other, the axes between them are not defined
//! by the matrix, and their angles are flagged `ambiguous`.

use nalgebra::{Matrix3, Vector3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::emg::{emg_columns, mvc_maxima, per_level, EmgParams};
use crate::linear::{linear_result, LinearResult};
use crate::{ellipsoid, Ellipsoid, Matrix};
use limpid_core::{Error, Recording, Result, Warning, WarningCode};
use limpid_ident::{fit_linear, prepare, LinearParams, PrepareParams};

/// Relative eigenvalue gap below which principal axes count as tied.
pub const TIE_GAP: f64 = 0.05;

/// One condition level.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct LevelResult {
    /// The condition level (the recording's `level` value).
    pub level: f64,
    /// Mean co-contraction index over the samples of this level (fraction of MVC).
    pub cocontraction_index: f64,
    /// Standard deviation of the index over the level's samples.
    pub cocontraction_sd: f64,
    /// Share of samples within the tolerance band of the target level.
    pub cocontraction_within_band: f64,
    /// K (N/m), seed 001's 9-column form.
    pub stiffness: Matrix,
    /// B (N s/m).
    pub damping: Matrix,
    /// M (kg).
    pub inertia: Matrix,
    /// Stiffness ellipsoid (symmetric part).
    pub ellipsoid: Option<Ellipsoid>,
    /// The full linear result (standard errors, fit, criteria, warnings).
    pub estimate: LinearResult,
}

/// One level compared with the reference (lowest) level.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Comparison {
    /// The compared level.
    pub level: f64,
    /// The reference (lowest) level.
    pub reference_level: f64,
    /// Percent change of the primary, secondary, tertiary principal stiffness.
    pub principal_change_percent: Vec<f64>,
    /// Rotation of the primary, secondary, tertiary axis (degrees, 0-90).
    pub rotation_deg: Vec<f64>,
    /// Axes whose direction is undefined (tied eigenvalues).
    pub ambiguous: Vec<bool>,
    /// The reference axes' partners at this level changed rank order.
    pub order_changed: bool,
}

/// Everything `estimate cocontraction` reports.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct CocontractionResult {
    /// The recording's path.
    pub recording: String,
    /// The MVC recording's path.
    pub mvc: String,
    /// EMG columns used.
    pub muscles: Vec<String>,
    /// One result per level, lowest first.
    pub levels: Vec<LevelResult>,
    /// Every level against the lowest.
    pub comparisons: Vec<Comparison>,
    /// What the reader should know about this analysis.
    pub warnings: Vec<Warning>,
}

/// Change of one stiffness ellipsoid against a reference (3 x 3 or 2 x 2).
#[derive(Debug, Clone, PartialEq)]
pub struct EllipsoidChange {
    /// Percent change along the reference's primary, secondary, tertiary axes.
    pub change_percent: Vec<f64>,
    /// Angle (deg, 0-90) between each reference axis and its matched axis.
    pub rotation_deg: Vec<f64>,
    /// Reference axes whose direction is undefined (tied eigenvalues).
    pub ambiguous: Vec<bool>,
    /// `partner[i]`: rank of the axis matched to reference axis i.
    pub partner: Vec<usize>,
}

fn permutations(n: usize) -> Vec<Vec<usize>> {
    if n == 1 {
        return vec![vec![0]];
    }
    let mut out = Vec::new();
    for p in permutations(n - 1) {
        for pos in 0..n {
            let mut q = p.clone();
            q.insert(pos, n - 1);
            out.push(q);
        }
    }
    out
}

/// Compare two stiffness matrices' ellipsoids, axes matched by direction.
pub fn compare(reference: &Matrix, other: &Matrix) -> Option<EllipsoidChange> {
    let (a, b) = (ellipsoid(reference)?, ellipsoid(other)?);
    let n = a.eigenvalues.len();
    let cos = |i: usize, j: usize| {
        (0..n)
            .map(|r| a.axes[(r, i)] * b.axes[(r, j)])
            .sum::<f64>()
            .abs()
            .min(1.0)
    };
    let partner = permutations(n).into_iter().max_by(|p, q| {
        let sp: f64 = (0..n).map(|i| cos(i, p[i])).sum();
        let sq: f64 = (0..n).map(|i| cos(i, q[i])).sum();
        sp.total_cmp(&sq)
    })?;
    let tied = |e: &Ellipsoid, i: usize| {
        let near = |j: usize| {
            let (x, y) = (e.eigenvalues[i], e.eigenvalues[j]);
            (x - y).abs() <= TIE_GAP * x.abs().max(y.abs())
        };
        (i > 0 && near(i - 1)) || (i + 1 < n && near(i + 1))
    };
    Some(EllipsoidChange {
        change_percent: (0..n)
            .map(|i| 100.0 * (b.eigenvalues[partner[i]] / a.eigenvalues[i] - 1.0))
            .collect(),
        rotation_deg: (0..n)
            .map(|i| cos(i, partner[i]).acos().to_degrees())
            .collect(),
        ambiguous: (0..n)
            .map(|i| tied(&a, i) || tied(&b, partner[i]))
            .collect(),
        partner,
    })
}

/// Estimate impedance and co-contraction index per level of a recording.
pub fn estimate_cocontraction(
    rec: &Recording,
    mvc: &Recording,
    prepare_params: &PrepareParams,
    emg: &EmgParams,
) -> Result<CocontractionResult> {
    let levels_col = rec.require(
        "level",
        "the condition level of each sample (Patel et al. 2013)",
    )?;
    refuse_swapped_files(rec, mvc)?;
    let muscles = emg_columns(rec);
    let maxima = mvc_maxima(mvc, &muscles, emg)?;
    let (index, peaks) = crate::emg::cocontraction_index_and_peaks(rec, &muscles, &maxima, emg)?;
    let stats = per_level(&index, levels_col, emg.tolerance);
    let mut levels = Vec::with_capacity(stats.len());
    let mut warnings = Vec::new();
    above_mvc_warning(&muscles, &peaks, &mut warnings);
    if muscles.iter().any(|m| crate::emg::is_envelope_column(m)) {
        warnings.push(Warning::new(
            WarningCode::EnvelopesGiven,
            format!(
                "the EMG envelopes are the recording's env_ columns ({}), made at the EMG's native rate by a channel map; the {} Hz envelope low-pass is not applied again",
                muscles.join(", "),
                emg.cutoff_hz
            ),
        ));
    }
    for s in &stats {
        let params = PrepareParams {
            level: Some(s.level),
            ..prepare_params.clone()
        };
        let data = match prepare(rec, &params) {
            Ok(d) => d,
            Err(Error::InvalidParameter { .. }) => {
                warnings.push(Warning::new(
                    WarningCode::LevelSkipped,
                    format!(
                        "level {}: no complete trial at this level; skipped",
                        s.level
                    ),
                ));
                continue;
            }
            Err(e) => return Err(e),
        };
        let est = fit_linear(
            &data,
            &LinearParams {
                equilibrium: false,
                ..LinearParams::default()
            },
        )?;
        let result = linear_result(&est, &data);
        levels.push(LevelResult {
            level: s.level,
            cocontraction_index: s.mean,
            cocontraction_sd: s.sd,
            cocontraction_within_band: s.within_band,
            stiffness: result.stiffness.clone(),
            damping: result.damping.clone(),
            inertia: result.inertia.clone(),
            ellipsoid: result.ellipsoids.stiffness.clone(),
            estimate: result,
        });
    }
    let comparisons = match levels.first() {
        Some(base) => levels
            .iter()
            .skip(1)
            .filter_map(|l| {
                compare(&base.stiffness, &l.stiffness).map(|c| Comparison {
                    level: l.level,
                    reference_level: base.level,
                    order_changed: c.partner.iter().enumerate().any(|(i, p)| i != *p),
                    principal_change_percent: c.change_percent,
                    rotation_deg: c.rotation_deg,
                    ambiguous: c.ambiguous,
                })
            })
            .collect(),
        None => Vec::new(),
    };
    Ok(CocontractionResult {
        recording: rec.path().display().to_string(),
        mvc: mvc.path().display().to_string(),
        muscles,
        levels,
        comparisons,
        warnings,
    })
}

/// Rotation about a unit axis by `angle` (rad), for tests and simulations.
pub fn axis_rotation(axis: Vector3<f64>, angle: f64) -> Matrix3<f64> {
    nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle).into_inner()
}

/// Most muscles' envelopes peak well above their MVC maximum: the MVC was
/// not maximal, or the recording and the MVC file were given the wrong way
/// round (issue 56: swapped, the estimate ran without a word about it).
fn above_mvc_warning(muscles: &[String], peaks: &[f64], warnings: &mut Vec<Warning>) {
    let above: Vec<String> = muscles
        .iter()
        .zip(peaks)
        .filter(|(_, p)| **p > 1.5)
        .map(|(m, p)| format!("{m} {:.1}x", p))
        .collect();
    if 2 * above.len() >= muscles.len() && !above.is_empty() {
        warnings.push(Warning::new(
            WarningCode::EmgAboveMvc,
            format!(
                "the recording's EMG peaks well above its MVC maximum ({}): the MVC was not maximal, or the recording and the MVC file are swapped (the MVC recording is the one given with --mvc); the co-contraction index is not a fraction of MVC",
                above.join(", ")
            ),
        ));
    }
}

/// The recording and the MVC file given the wrong way round (issue 56): the
/// perturbed recording moves, the MVC's still contraction does not. Refused
/// when the MVC file's positions span more than ten times the recording's.
fn refuse_swapped_files(rec: &Recording, mvc: &Recording) -> Result<()> {
    let span = |r: &Recording| -> Option<f64> {
        ["x", "y", "z"]
            .iter()
            .filter_map(|c| r.column(c))
            .map(|v| {
                let (lo, hi) = v
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                        (a.min(*x), b.max(*x))
                    });
                hi - lo
            })
            .reduce(f64::max)
    };
    if let (Some(moving), Some(still)) = (span(mvc), span(rec)) {
        if moving > 10.0 * still && moving > 1e-3 {
            return Err(Error::Format {
                path: rec.path().to_path_buf(),
                message: format!(
                    "its positions span {} mm but those of the MVC file {} span {} mm: are the two swapped? The perturbed recording comes first, the MVC recording after --mvc",
                    limpid_core::error::significant(1e3 * still, 3),
                    mvc.path().display(),
                    limpid_core::error::significant(1e3 * moving, 3)
                ),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(m: &Matrix3<f64>) -> Matrix {
        Matrix::from(*m)
    }

    #[test]
    fn rotation_angle_of_a_rotated_matrix() {
        let k0 = Matrix3::from_diagonal(&Vector3::new(2000.0, 800.0, 400.0));
        // below 45 degrees; beyond it, matching by direction reads the rotation as a swap of axes
        for deg in [0.0f64, 8.6, 13.5, 30.0, 40.0] {
            // rotate about the tertiary (z) axis: primary and secondary turn by `deg`, tertiary stays
            let r = axis_rotation(Vector3::z(), deg.to_radians());
            let k1 = r * k0 * r.transpose();
            let c = compare(&rows(&k0), &rows(&k1)).unwrap();
            assert!(c.change_percent.iter().all(|c| c.abs() < 1e-9));
            let angle = &c.rotation_deg;
            assert!((angle[0] - deg).abs() < 1e-6, "{deg}: {angle:?}");
            assert!((angle[1] - deg).abs() < 1e-6);
            assert!(angle[2].abs() < 1e-6);
            assert!(c.ambiguous.iter().all(|a| !a));
        }
    }

    #[test]
    fn swapped_eigenvector_signs_do_not_change_the_angle() {
        let k0 = Matrix3::from_diagonal(&Vector3::new(2000.0, 800.0, 400.0));
        let r = axis_rotation(Vector3::new(1.0, 1.0, 0.0), 10f64.to_radians());
        let k1 = r * k0 * r.transpose();
        // flip signs by conjugating with a reflection: the same matrix family, other eigenvector signs
        let s = Matrix3::from_diagonal(&Vector3::new(-1.0, 1.0, -1.0));
        let a = compare(&rows(&k0), &rows(&k1)).unwrap().rotation_deg;
        let b = compare(&rows(&(s * k0 * s)), &rows(&(s * k1 * s)))
            .unwrap()
            .rotation_deg;
        for i in 0..3 {
            assert!(a[i] <= 90.0 && (a[i] - b[i]).abs() < 1e-9);
        }
    }

    #[test]
    fn tied_eigenvalues_are_flagged() {
        let k0 = Matrix3::from_diagonal(&Vector3::new(1000.0, 990.0, 300.0));
        let amb = compare(&rows(&k0), &rows(&k0)).unwrap().ambiguous;
        assert_eq!(amb, vec![true, true, false]);
    }

    #[test]
    fn axes_matched_by_direction_when_the_order_changes() {
        // the tertiary stiffness grows past the secondary: +100 % along z
        let k0 = Matrix3::from_diagonal(&Vector3::new(2000.0, 700.0, 450.0));
        let r = axis_rotation(Vector3::new(0.3, -0.2, 1.0), 5f64.to_radians());
        let k1 = r * Matrix3::from_diagonal(&Vector3::new(2050.0, 720.0, 900.0)) * r.transpose();
        let c = compare(&rows(&k0), &rows(&k1)).unwrap();
        assert_eq!(c.partner, vec![0, 2, 1]);
        assert!(
            (c.change_percent[2] - 100.0).abs() < 1e-9,
            "{:?}",
            c.change_percent
        );
        assert!((c.change_percent[1] - 100.0 * (720.0 / 700.0 - 1.0)).abs() < 1e-9);
        assert!(c.rotation_deg.iter().all(|a| (a - 5.0).abs() < 5.0 + 1e-9));
    }
}
