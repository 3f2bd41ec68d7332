//! The joint parametric model by instrumental variables (issue 79): in
//! closed loop the measured motion is correlated with the subject's own
//! torque, so the regressors `[q'', q', q, LP2(rect q')(t - d)]` are built
//! from the measured motion and instrumented by the same columns built from
//! the motion the commanded reference predicts
//! ([`crate::closed_loop`]). The model is exact in the measured motion, so
//! the estimate is consistent however well the reference predicts it (only
//! its precision depends on that); a plug-in fit on the predicted motion is
//! not, because the rectifier is nonlinear (on the virtual ankle with a
//! reflex on a servo of 0.5 K: B 0.36 vs 0.8, G 6 vs 30).
//!
//! For a delay and low-pass the IV solution is found from the
//! intrinsic-only IV fit by partitioning (as [`super::parametric::joint_fit`]
//! does for least squares):
//! `G = z'e0 / (z'x - c'A^-1 b)`, `theta = theta0 - A^-1 b G`, with
//! `A = Zi'Xi`, `b = Zi'x`, `c = Xi'z`, `e0` the intrinsic-only IV residual.
//! Delay and low-pass are chosen by the residual sum of squares of the
//! measured torque (the IV residual is the subject's torque and the sensor
//! noise at the true structure; tested on the virtual ankles on servos of
//! 0.5-10 K, where the plug-in fit's RSS picked 50-70 ms for a 45 ms
//! delay); standard errors by the 10-block jackknife of the IV estimate.

use super::cascade::centre;
use super::parametric::{delete_one_jackknife, dot, Fixed};
use super::Decimated;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

/// The intrinsic columns, measured (the least-squares fit's) and
/// instrumented, centred over the fitted rows (one continuous record), with
/// the intrinsic-only IV fit.
pub(crate) struct FixedIv<'a> {
    pub(crate) measured: &'a [Vec<f64>; 3],
    pub(crate) instruments: [Vec<f64>; 3],
    pub(crate) torque: Vec<f64>,
    /// `(Zi' Xi)^-1`.
    a_inv: Matrix3<f64>,
    /// `Xi' Xi`.
    xtx: Matrix3<f64>,
    /// The intrinsic-only IV estimate and its residual.
    pub(crate) theta: Vector3<f64>,
    residual: Vec<f64>,
    /// `Xi' e0`.
    xte: Vector3<f64>,
    pub(crate) rss: f64,
}

/// [`FixedIv`] of the least-squares fit `ls` of `d` (its centred columns
/// are the measured ones) instrumented by `di`.
pub(crate) fn fixed_iv<'a>(
    ls: &'a Fixed,
    (d, di): (&Decimated, &Decimated),
    skip: usize,
) -> Option<FixedIv<'a>> {
    let centred = |x: &[f64]| {
        let mut c = x[skip.min(x.len())..].to_vec();
        centre(&mut c);
        c
    };
    let measured = &ls.columns;
    let instruments = [
        centred(&di.acceleration),
        centred(&di.velocity),
        centred(&di.position),
    ];
    let torque = centred(&d.torque);
    let a = Matrix3::from_fn(|i, j| dot(&instruments[i], &measured[j]));
    let xtx = Matrix3::from_fn(|i, j| dot(&measured[i], &measured[j]));
    let zty = Vector3::from_fn(|i, _| dot(&instruments[i], &torque));
    let a_inv = a.try_inverse()?;
    let theta = a_inv * zty;
    let residual: Vec<f64> = (0..torque.len())
        .map(|t| {
            torque[t]
                - theta[0] * measured[0][t]
                - theta[1] * measured[1][t]
                - theta[2] * measured[2][t]
        })
        .collect();
    let xte = Vector3::from_fn(|i, _| dot(&measured[i], &residual));
    Some(FixedIv {
        rss: dot(&residual, &residual),
        measured,
        instruments,
        torque,
        a_inv,
        xtx,
        theta,
        residual,
        xte,
    })
}

/// Residual sum of squares (measured torque) and `[I, B, K, G]` of the IV
/// fit with the reflex column `x` (measured) instrumented by `z`.
pub(crate) fn joint_fit_iv(f: &FixedIv<'_>, x: &[f64], z: &[f64]) -> (f64, [f64; 4]) {
    let m = x.len() as f64;
    let [x0, x1, x2] = &f.measured;
    let [z0, z1, z2] = &f.instruments;
    // fifteen sums in one pass over nine columns, in plain accumulators
    // (the scan calls this ~13,000 times: it is most of a closed-loop estimate)
    let mut acc = [0.0f64; 15];
    let rows = x
        .iter()
        .zip(z)
        .zip(&f.residual)
        .zip(x0.iter().zip(x1).zip(x2))
        .zip(z0.iter().zip(z1).zip(z2));
    for ((((&xv, &zv), &e), ((&a0, &a1), &a2)), ((&i0, &i1), &i2)) in rows {
        acc[0] += xv;
        acc[1] += zv;
        acc[2] += zv * xv;
        acc[3] += xv * xv;
        acc[4] += zv * e;
        acc[5] += xv * e;
        acc[6] += i0 * xv;
        acc[7] += i1 * xv;
        acc[8] += i2 * xv;
        acc[9] += a0 * zv;
        acc[10] += a1 * zv;
        acc[11] += a2 * zv;
        acc[12] += a0 * xv;
        acc[13] += a1 * xv;
        acc[14] += a2 * xv;
    }
    let [sx, sz, mut zx, mut xx, ze, xe, b0, b1, b2, c0, c1, c2, xa0, xa1, xa2] = acc;
    let (b, c, xa) = (
        Vector3::new(b0, b1, b2),
        Vector3::new(c0, c1, c2),
        Vector3::new(xa0, xa1, xa2),
    );
    // the constant: the other columns are centred, x and z are not
    zx -= sx * sz / m;
    xx -= sx * sx / m;
    let u = f.a_inv * b;
    let denominator = zx - c.dot(&u);
    if denominator.abs() <= 1e-12 * (zx.abs() + c.dot(&u).abs()).max(f64::MIN_POSITIVE) {
        return (f64::INFINITY, [f.theta[0], f.theta[1], f.theta[2], 0.0]);
    }
    let gain = ze / denominator;
    let theta = f.theta - u * gain;
    // e = e0 - (x - Xi u) G
    let w_norm = xx - 2.0 * u.dot(&xa) + (u.transpose() * f.xtx * u)[0];
    let w_e = xe - u.dot(&f.xte);
    let rss = (f.rss - 2.0 * gain * w_e + gain * gain * w_norm).max(0.0);
    (rss, [theta[0], theta[1], theta[2], gain])
}

/// The measured torque's residual at `[I, B, K, G]` (the constant refitted).
pub(crate) fn residual_iv(f: &FixedIv<'_>, x: &[f64], [i, b, k, gain]: [f64; 4]) -> Vec<f64> {
    let xm = x.iter().sum::<f64>() / x.len().max(1) as f64;
    (0..x.len())
        .map(|t| {
            f.torque[t]
                - i * f.measured[0][t]
                - b * f.measured[1][t]
                - k * f.measured[2][t]
                - gain * (x[t] - xm)
        })
        .collect()
}

/// 10-block delete-one jackknife standard errors of the IV estimate of (I, B, K, G).
pub(crate) fn joint_jackknife_iv(f: &FixedIv<'_>, x: &[f64], z: &[f64]) -> [f64; 4] {
    let blocks = 10;
    let m = x.len();
    let scale = |c: &[f64]| (dot(c, c) / m as f64).sqrt().max(f64::MIN_POSITIVE);
    let sx: Vec<f64> = f
        .measured
        .iter()
        .map(|c| scale(c))
        .chain([scale(x)])
        .collect();
    let sz: Vec<f64> = f
        .instruments
        .iter()
        .map(|c| scale(c))
        .chain([scale(z)])
        .collect();
    type Pair = (SMatrix<f64, 5, 5>, SVector<f64, 5>);
    let mut sums: Vec<Pair> = vec![(SMatrix::zeros(), SVector::zeros()); blocks];
    for (bk, (g, r)) in sums.iter_mut().enumerate() {
        for t in bk * m / blocks..(bk + 1) * m / blocks {
            let xr = SVector::<f64, 5>::from([
                f.measured[0][t] / sx[0],
                f.measured[1][t] / sx[1],
                f.measured[2][t] / sx[2],
                x[t] / sx[3],
                1.0,
            ]);
            let zr = SVector::<f64, 5>::from([
                f.instruments[0][t] / sz[0],
                f.instruments[1][t] / sz[1],
                f.instruments[2][t] / sz[2],
                z[t] / sz[3],
                1.0,
            ]);
            *g += zr * xr.transpose();
            *r += zr * f.torque[t];
        }
    }
    delete_one_jackknife(&sums, &sx)
}
