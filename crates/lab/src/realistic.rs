//! Virtual subjects grounded in what the seeds measured on people (issue 18).
//!
//! The clean subjects of [`crate::subject`] and [`crate::cocontraction`]
//! return exactly what was typed in. The subjects here carry what the seeds'
//! humans showed, each part with its source:
//!
//! - **Seed 001 stiffness per configuration and level** ([`seed001_stiffness`]):
//!   Tables 1-4 give, per arm configuration and co-contraction level, the
//!   diagonal K_xx, K_yy, K_zz, the principal stiffnesses K_1 > K_2 > K_3 and
//!   the largest antisymmetric element K_maxA; Table 5 the rotation of each
//!   principal axis from 0 % to 100 %. The symmetric part is R diag(K_1, K_2,
//!   K_3) R^T with R chosen so that its diagonal matches the table's (least
//!   squares, [`fit_orientation`]) and so that the axes turn from 0 % to 100 %
//!   by Table 5's angles; the 50 % and 75 % levels carry their own tables'
//!   values (not interpolated: Tables 2-3 are not linear in the level) with
//!   the rotation fraction fitted to their diagonal. The antisymmetric part
//!   has K_maxA in the xy element and K_maxA / 2 in xz and yz (the tables give
//!   only the largest element; xy is the shoulder-elbow plane where planar
//!   studies report the curl, Mussa-Ivaldi et al. 1985).
//! - **Seed 000 antisymmetric stiffness**: Table II's K_maxA per start point of
//!   subject 1 ([`SEED000_K_MAX_A`]), placed like seed 001's.
//! - **Stretch reflex** ([`StretchReflex`]): a force opposing the hand's
//!   velocity 40 ms earlier (seed 003 §I: the stretch reflex acts after 25-50 ms),
//!   with a gain that rises with co-contraction.
//! - **Signal-dependent force noise and drift**: set in [`crate::NoiseModel`]
//!   ([`NoiseModel::realistic`](crate::NoiseModel::realistic)).

use argmin::core::{CostFunction, Executor};
use argmin::solver::neldermead::NelderMead;
use nalgebra::{Matrix3, Rotation3, Unit, Vector3};
use serde::{Deserialize, Serialize};

/// Seed 001 co-contraction levels of Tables 1-4.
pub const SEED001_LEVELS: [f64; 4] = [0.0, 0.5, 0.75, 1.0];

/// Seed 001 Tables 1-4 (levels 0, 50, 75, 100 %), configurations 1-7:
/// K_xx, K_yy, K_zz, K_maxA, K_1, K_2, K_3 in N/m, averaged over 4 subjects.
pub const SEED001_TABLES: [[[f64; 7]; 7]; 4] = [
    [
        [580.7, 1082.0, 1439.5, 348.7, 2202.1, 711.5, 188.7],
        [269.6, 2405.1, 873.4, 507.2, 2740.1, 661.3, 146.6],
        [455.8, 2357.3, 739.1, 370.3, 2807.6, 476.6, 268.1],
        [862.8, 1735.2, 583.1, 136.8, 2046.6, 663.4, 471.1],
        [667.3, 2158.9, 509.2, 344.5, 2550.1, 484.3, 301.1],
        [458.7, 2904.9, 654.1, 163.5, 3264.9, 505.1, 247.7],
        [684.9, 2314.8, 764.3, 401.4, 2549.9, 845.9, 368.3],
    ],
    [
        [651.1, 1177.1, 1674.6, 290.5, 2421.0, 799.6, 282.2],
        [559.9, 2435.1, 1021.5, 492.4, 2841.2, 910.3, 265.0],
        [524.1, 2406.1, 829.1, 378.8, 2887.5, 541.6, 330.2],
        [973.4, 1766.3, 654.6, 113.3, 2108.3, 747.3, 538.7],
        [799.4, 2243.3, 613.4, 356.6, 2725.4, 574.0, 356.7],
        [630.2, 2927.0, 775.6, 213.1, 3438.4, 570.0, 324.2],
        [944.5, 2432.1, 900.8, 375.1, 2721.6, 955.0, 600.4],
    ],
    [
        [451.8, 1078.3, 2144.3, 293.3, 2499.6, 921.8, 253.0],
        [620.5, 2516.1, 1004.6, 475.6, 2928.7, 894.3, 318.1],
        [602.7, 2424.6, 877.3, 337.3, 2949.5, 585.7, 369.4],
        [987.5, 1773.2, 709.7, 122.9, 2132.0, 755.6, 582.6],
        [790.2, 2278.1, 608.3, 354.4, 2731.3, 582.1, 363.5],
        [676.8, 2968.0, 826.7, 219.1, 3518.9, 590.9, 361.0],
        [1026.1, 2441.9, 943.2, 350.8, 2701.0, 1022.4, 686.9],
    ],
    [
        [595.9, 1149.8, 1985.1, 318.1, 2406.5, 910.1, 414.2],
        [718.9, 2502.8, 1148.4, 470.7, 2924.1, 1090.4, 355.2],
        [641.9, 2423.5, 844.2, 334.4, 2955.3, 579.3, 374.0],
        [1076.9, 1830.9, 728.3, 114.2, 2182.5, 845.5, 608.0],
        [831.3, 2371.6, 660.6, 379.3, 2827.8, 642.2, 393.4],
        [725.3, 3002.6, 788.4, 232.1, 3471.0, 627.6, 417.7],
        [1167.8, 2476.4, 915.5, 339.6, 2701.0, 1191.2, 667.5],
    ],
];

/// Seed 001 Table 5: rotation (degrees) of the primary, secondary and tertiary
/// axes from 0 % to 100 % co-contraction, configurations 1-7.
pub const SEED001_ROTATION_DEG: [[f64; 3]; 7] = [
    [26.0, 32.2, 27.7],
    [6.6, 12.4, 14.8],
    [5.7, 25.8, 27.3],
    [6.7, 35.2, 35.1],
    [4.9, 16.5, 16.2],
    [3.7, 23.6, 23.8],
    [6.5, 23.7, 24.5],
];

/// Seed 000 Table II, subject 1: largest antisymmetric stiffness element per
/// start point S1-S6 (N/m).
pub const SEED000_K_MAX_A: [f64; 6] = [2.0, 13.0, 8.0, 2.0, 2.3, 1.2];

/// An antisymmetric matrix with `max` in xy and `max / 2` in xz and yz.
pub fn antisymmetric_part(max: f64) -> Matrix3<f64> {
    let (a, b) = (max, 0.5 * max);
    Matrix3::new(0.0, a, b, -a, 0.0, b, -b, -b, 0.0)
}

/// A velocity-driven stretch reflex: force `-(gain_rest + gain_per_level
/// level) B v(t - delay)`, B the subject's intrinsic damping.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StretchReflex {
    /// Delay (s); seed 003 §I: 25-50 ms for the stretch reflex.
    pub delay_s: f64,
    /// Gain relative to the intrinsic damping at rest.
    pub gain_rest: f64,
    /// Gain added per unit co-contraction level.
    pub gain_per_level: f64,
}

impl StretchReflex {
    /// Delay 40 ms; gain 0.3 at rest rising to 0.8 at full co-contraction
    /// (reflex gain grows with background activation: "automatic gain
    /// scaling", Matthews 1986; seed 003 gives only the latency).
    pub fn typical() -> Self {
        StretchReflex {
            delay_s: 0.040,
            gain_rest: 0.3,
            gain_per_level: 0.5,
        }
    }

    /// Gain at a co-contraction level.
    pub fn gain(&self, level: f64) -> f64 {
        self.gain_rest + self.gain_per_level * level
    }
}

/// The rotation about unit axis `n` by φ that turns axis i by `angles_deg[i]`:
/// cos θ_i = cos φ + (1 - cos φ) n_i². For angles of one rotation this gives
/// cos φ = (Σ cos θ_i - 1) / 2 and n_i² = (cos θ_i - cos φ) / (1 - cos φ).
/// Averaged angles need not be those of one rotation (no angle can exceed φ;
/// Table 5's configurations 2 and 3 break this): then n and φ minimise the
/// squared angle differences (Nelder-Mead from the closed form with negative
/// n_i² set to 0). `signs` chooses the signs of n_2, n_3 (n_1 >= 0); None when
/// the angles are out of range.
pub fn rotation_turning_axes(angles_deg: [f64; 3], signs: [f64; 2]) -> Option<(Vector3<f64>, f64)> {
    let c: Vec<f64> = angles_deg.iter().map(|a| a.to_radians().cos()).collect();
    let cos_phi = (c.iter().sum::<f64>() - 1.0) / 2.0;
    if !(-1.0..1.0).contains(&cos_phi) {
        return None;
    }
    let n2: Vec<f64> = c
        .iter()
        .map(|ci| ((ci - cos_phi) / (1.0 - cos_phi)).max(0.0))
        .collect();
    let total: f64 = n2.iter().sum();
    let mut squares = [n2[0] / total, n2[1] / total, n2[2] / total];
    let mut phi = cos_phi.acos();
    let angles_of = |sq: &[f64; 3], phi: f64| -> [f64; 3] {
        sq.map(|s| {
            (phi.cos() + (1.0 - phi.cos()) * s)
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees()
        })
    };
    let misfit = |sq: &[f64; 3], phi: f64| -> f64 {
        let got = angles_of(sq, phi);
        (0..3).map(|i| (got[i] - angles_deg[i]).powi(2)).sum()
    };
    if misfit(&squares, phi) > 1e-12 {
        // parameters (u1, u2, φ): n² ∝ (u1², u2², 1) — the third axis has the
        // largest share in Table 5, so it is never 0
        struct AngleProblem<F: Fn(&[f64; 3], f64) -> f64>(F);
        impl<F: Fn(&[f64; 3], f64) -> f64> CostFunction for AngleProblem<F> {
            type Param = Vec<f64>;
            type Output = f64;
            fn cost(&self, p: &Vec<f64>) -> Result<f64, argmin::core::Error> {
                Ok((self.0)(&unpack(p), p[2]))
            }
        }
        fn unpack(p: &[f64]) -> [f64; 3] {
            let t = p[0] * p[0] + p[1] * p[1] + 1.0;
            [p[0] * p[0] / t, p[1] * p[1] / t, 1.0 / t]
        }
        let s3 = squares[2].max(1e-6);
        let start = vec![(squares[0] / s3).sqrt(), (squares[1] / s3).sqrt(), phi];
        let simplex: Vec<Vec<f64>> = (0..4)
            .map(|k| {
                let mut v = start.clone();
                if k > 0 {
                    v[k - 1] += if k == 3 { 0.02 } else { 0.1 };
                }
                v
            })
            .collect();
        let solver = NelderMead::new(simplex).with_sd_tolerance(1e-14).ok()?;
        let res = Executor::new(AngleProblem(misfit), solver)
            .configure(|s| s.max_iters(2000))
            .run()
            .ok()?;
        let p = res.state().best_param.clone()?;
        squares = unpack(&p);
        phi = p[2];
    }
    let n = Vector3::new(
        squares[0].sqrt(),
        signs[0] * squares[1].sqrt(),
        signs[1] * squares[2].sqrt(),
    );
    Some((n.normalize(), phi))
}

fn rotation(w: &[f64]) -> Matrix3<f64> {
    Rotation3::new(Vector3::new(w[0], w[1], w[2])).into_inner()
}

fn diagonal_misfit(r: &Matrix3<f64>, principal: &[f64], diag: &[f64]) -> f64 {
    let k = r
        * Matrix3::from_diagonal(&Vector3::new(principal[0], principal[1], principal[2]))
        * r.transpose();
    (0..3).map(|i| (k[(i, i)] - diag[i]).powi(2)).sum()
}

struct OrientationProblem<'a, 'b> {
    /// (principal, diagonal, relative rotation after R) per level fitted jointly.
    levels: &'b [(&'a [f64], &'a [f64], Matrix3<f64>)],
}

impl CostFunction for OrientationProblem<'_, '_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, w: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        let r = rotation(w);
        Ok(self
            .levels
            .iter()
            .map(|(p, d, q)| diagonal_misfit(&(r * q), p, d))
            .sum())
    }
}

/// The orientation R (principal axes as columns) minimising the squared
/// difference between diag(R Q_l Λ_l Q_l^T R^T) and each level's diagonal:
/// Nelder-Mead from 27 starting rotations. Returns R and the rms misfit (N/m).
pub fn fit_orientation(levels: &[(&[f64], &[f64], Matrix3<f64>)]) -> (Matrix3<f64>, f64) {
    let mut best = (Matrix3::identity(), f64::INFINITY);
    let steps = [-2.0, 0.0, 2.0];
    for a in steps {
        for b in steps {
            for c in steps {
                let start = vec![a, b, c];
                let simplex = (0..4)
                    .map(|k| {
                        let mut v = start.clone();
                        if k > 0 {
                            v[k - 1] += 0.5;
                        }
                        v
                    })
                    .collect();
                let Ok(solver) = NelderMead::new(simplex).with_sd_tolerance(1e-9) else {
                    continue;
                };
                let problem = OrientationProblem { levels };
                let Ok(res) = Executor::new(problem, solver)
                    .configure(|s| s.max_iters(800))
                    .run()
                else {
                    continue;
                };
                let state = res.state();
                if let Some(w) = state.best_param.as_ref() {
                    if state.best_cost < best.1 {
                        best = (rotation(w), state.best_cost);
                    }
                }
            }
        }
    }
    let n = (3 * levels.len()) as f64;
    (best.0, (best.1 / n).sqrt())
}

/// One configuration's stiffness at seed 001's four levels.
#[derive(Debug, Clone)]
pub struct Seed001Stiffness {
    /// (level, full K with its antisymmetric part), levels 0, 0.5, 0.75, 1.
    pub knots: Vec<(f64, Matrix3<f64>)>,
    /// rms difference between the symmetric parts' diagonal and the tables' (N/m).
    pub diagonal_misfit: f64,
}

/// Seed 001's stiffness of configuration `config` (0-based) at its four levels.
pub fn seed001_stiffness(config: usize) -> Seed001Stiffness {
    let row = |l: usize| &SEED001_TABLES[l][config];
    let mut best: Option<(Matrix3<f64>, f64, Vector3<f64>, f64)> = None;
    for signs in [[1.0, 1.0], [1.0, -1.0], [-1.0, 1.0], [-1.0, -1.0]] {
        let Some((axis, phi)) = rotation_turning_axes(SEED001_ROTATION_DEG[config], signs) else {
            continue;
        };
        let q = Rotation3::from_axis_angle(&Unit::new_normalize(axis), phi).into_inner();
        let (r, misfit) = fit_orientation(&[
            (&row(0)[4..7], &row(0)[0..3], Matrix3::identity()),
            (&row(3)[4..7], &row(3)[0..3], q),
        ]);
        if best.as_ref().is_none_or(|b| misfit < b.1) {
            best = Some((r, misfit, axis, phi));
        }
    }
    let (r0, _, axis, phi) = best.expect("Table 5's angles are those of a rotation");
    let turn = |fraction: f64| {
        Rotation3::from_axis_angle(&Unit::new_normalize(axis), fraction * phi).into_inner()
    };
    let symmetric = |l: usize, q: &Matrix3<f64>| {
        let p = &row(l)[4..7];
        let r = r0 * q;
        r * Matrix3::from_diagonal(&Vector3::new(p[0], p[1], p[2])) * r.transpose()
    };
    let mut knots = Vec::with_capacity(4);
    let mut squared = 0.0;
    for (l, level) in SEED001_LEVELS.iter().enumerate() {
        // rotation fraction: 0 and 1 at the ends, fitted to the diagonal between
        let fraction = match l {
            0 => 0.0,
            3 => 1.0,
            _ => (0..=120)
                .map(|i| i as f64 / 100.0)
                .min_by(|a, b| {
                    let m = |f: f64| diagonal_misfit(&(r0 * turn(f)), &row(l)[4..7], &row(l)[0..3]);
                    m(*a).total_cmp(&m(*b))
                })
                .unwrap_or(*level),
        };
        let k = symmetric(l, &turn(fraction));
        squared += (0..3).map(|i| (k[(i, i)] - row(l)[i]).powi(2)).sum::<f64>();
        knots.push((*level, k + antisymmetric_part(row(l)[3])));
    }
    Seed001Stiffness {
        knots,
        diagonal_misfit: (squared / 12.0).sqrt(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axis_angles(a: &Matrix3<f64>, b: &Matrix3<f64>) -> Vec<f64> {
        let ea = a.symmetric_eigen();
        let eb = b.symmetric_eigen();
        let order = |e: &nalgebra::SymmetricEigen<f64, nalgebra::U3>| {
            let mut idx = [0, 1, 2];
            idx.sort_by(|i, j| e.eigenvalues[*j].total_cmp(&e.eigenvalues[*i]));
            idx
        };
        let (oa, ob) = (order(&ea), order(&eb));
        (0..3)
            .map(|i| {
                let c = ea
                    .eigenvectors
                    .column(oa[i])
                    .dot(&eb.eigenvectors.column(ob[i]));
                c.abs().min(1.0).acos().to_degrees()
            })
            .collect()
    }

    #[test]
    fn rotation_turning_axes_turns_each_axis_by_its_angle() {
        for angles in SEED001_ROTATION_DEG {
            let (n, phi) = rotation_turning_axes(angles, [1.0, -1.0]).unwrap();
            let q = Rotation3::from_axis_angle(&Unit::new_normalize(n), phi).into_inner();
            for i in 0..3 {
                let e = Vector3::ith(i, 1.0);
                let got = (q * e).dot(&e).clamp(-1.0, 1.0).acos().to_degrees();
                assert!((got - angles[i]).abs() < 1.0, "{angles:?}: axis {i} {got}");
            }
        }
    }

    #[test]
    fn seed001_subject_has_the_tables_principal_values_kmaxa_and_table5_rotation() {
        for c in 0..7 {
            let s = seed001_stiffness(c);
            for (l, (level, k)) in s.knots.iter().enumerate() {
                let row = SEED001_TABLES[l][c];
                assert_eq!(*level, SEED001_LEVELS[l]);
                let sym = (k + k.transpose()) * 0.5;
                let anti = (k - k.transpose()) * 0.5;
                let mut eig: Vec<f64> = sym.symmetric_eigenvalues().iter().copied().collect();
                eig.sort_by(|a, b| b.total_cmp(a));
                for i in 0..3 {
                    assert!((eig[i] - row[4 + i]).abs() < 1e-6, "c{c} l{l}: {eig:?}");
                }
                let max_a = anti.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                assert!((max_a - row[3]).abs() < 1e-9);
            }
            let sym = |k: &Matrix3<f64>| (k + k.transpose()) * 0.5;
            let got = axis_angles(&sym(&s.knots[0].1), &sym(&s.knots[3].1));
            for i in 0..3 {
                let want = SEED001_ROTATION_DEG[c][i];
                assert!((got[i] - want).abs() < 1.0, "c{c}: {got:?} vs {want}");
            }
            // the diagonal is matched as far as one orientation and Table 5 allow
            eprintln!(
                "c{c}: diagonal misfit {:.1} N/m, rotation {got:.1?}",
                s.diagonal_misfit
            );
            assert!(
                s.diagonal_misfit < 150.0,
                "c{c}: misfit {}",
                s.diagonal_misfit
            );
        }
    }
}
