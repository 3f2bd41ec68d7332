//! The reflex in flight at a cut (issue 80): in a recording of short
//! segments the reflex answers motion from before each segment's start, so
//! its low-pass starts in an unknown state. Its two free responses from
//! the segment's start are nuisance regressors of that segment (the
//! transient terms of Ludvig & Perreault 2012, IEEE TBME 59(12)), projected
//! out with each segment's constant: row by row for the final fit, from
//! each segment's cross products (Frisch-Waugh on the sums) for the many
//! fits of the delay scan.

use std::ops::Range;

use super::parametric::{delayed, dot, fixed_from, low_pass_coefficients, phases, Fixed};
use super::segments::{gather, groups};
use super::Decimated;

/// The low-pass's two free responses (no input, unit output one and two
/// samples before) in each segment from its start: the reflex in flight at
/// a cut, answering motion before it, adds a combination of them.
pub(crate) fn free_responses(
    (natural_hz, zeta, fs): (f64, f64, f64),
    segments: &[Range<usize>],
    len: usize,
) -> [Vec<f64>; 2] {
    let (_, a1, a2) = low_pass_coefficients(natural_hz, zeta, fs);
    let mut out = [vec![0.0; len], vec![0.0; len]];
    for (h, before) in out.iter_mut().zip([(1.0, 0.0), (0.0, 1.0)]) {
        for s in segments {
            let (mut p1, mut p2) = before;
            for v in &mut h[s.clone()] {
                let y = -a1 * p1 - a2 * p2;
                p2 = p1;
                p1 = y;
                *v = y;
            }
        }
    }
    out
}

/// The I-B-K columns and the torque at each segment's rows past its first
/// `skip`, gathered once for the many fits of a scan.
pub(crate) struct SegmentRows {
    columns: [Vec<f64>; 4],
    groups: Vec<Range<usize>>,
    skip: usize,
}

/// The low-pass's free responses (see [`free_responses`]) in decimation phases.
pub(crate) type FreePhases = [Vec<Vec<f64>>; 2];

impl SegmentRows {
    pub(crate) fn new(d: &Decimated, skip: usize) -> Self {
        SegmentRows {
            columns: [&d.acceleration, &d.velocity, &d.position, &d.torque]
                .map(|c| gather(c, &d.segments, skip).into_owned()),
            groups: groups(&d.segments, skip),
            skip,
        }
    }

    /// The free responses of the low-pass `(natural Hz, damping ratio, fs)`
    /// from each segment's start, in decimation phases.
    pub(crate) fn free_phases(
        d: &Decimated,
        low_pass: (f64, f64, f64),
        full_segments: &[Range<usize>],
    ) -> FreePhases {
        let full_len = full_segments.last().map_or(0, |s| s.end);
        free_responses(low_pass, full_segments, full_len)
            .map(|h| phases(&h, d.ratio, d.torque.len()))
    }

    /// The joint model for the reflex regressor in phases `ph` at `delay`,
    /// with each segment's constant and the low-pass's two free responses
    /// (the reflex in flight at its cut) projected out inside the segment:
    /// the fit of the projected columns and the projected regressor.
    pub(crate) fn fit(
        &self,
        d: &Decimated,
        (ph, free): (&[Vec<f64>], &FreePhases),
        delay: usize,
    ) -> Option<(Fixed, Vec<f64>)> {
        let nuisance = free
            .each_ref()
            .map(|h| delayed(h, d.ratio, delay, self.skip, &d.segments));
        let mut columns = self.columns.clone();
        let mut x = delayed(ph, d.ratio, delay, self.skip, &d.segments).into_owned();
        for g in &self.groups {
            let basis = orthonormal(&[
                vec![1.0; g.len()],
                nuisance[0][g.clone()].to_vec(),
                nuisance[1][g.clone()].to_vec(),
            ]);
            for c in columns.iter_mut().chain(std::iter::once(&mut x)) {
                let c = &mut c[g.clone()];
                for b in &basis {
                    let k = dot(c, b);
                    c.iter_mut().zip(b).for_each(|(v, bv)| *v -= k * bv);
                }
            }
        }
        let [a, v, q, y] = columns;
        Some((fixed_from([a, v, q], y, self.groups.clone())?, x))
    }
}

/// The cross products of `[a, v, q, y]` over one segment's fitted rows.
pub(crate) struct GroupSums {
    ww: [[f64; 4]; 4],
    sums: [f64; 4],
}

impl SegmentRows {
    /// Each segment's fixed cross products, once per scan.
    #[allow(clippy::needless_range_loop)] // small matrices read best by index
    pub(crate) fn sums(&self) -> Vec<GroupSums> {
        self.groups
            .iter()
            .map(|g| {
                let mut ww = [[0.0; 4]; 4];
                let mut sums = [0.0; 4];
                for t in g.clone() {
                    let w = self.columns.each_ref().map(|c| c[t]);
                    for i in 0..4 {
                        sums[i] += w[i];
                        for j in 0..4 {
                            ww[i][j] += w[i] * w[j];
                        }
                    }
                }
                GroupSums { ww, sums }
            })
            .collect()
    }

    /// [`SegmentRows::fit`]'s RSS and `[I, B, K, G]` from cross products
    /// (Frisch-Waugh per segment on the sums): what the scan needs, without
    /// copying a column.
    #[allow(clippy::needless_range_loop)] // small matrices read best by index
    pub(crate) fn scan_fit(
        &self,
        sums: &[GroupSums],
        d: &Decimated,
        (ph, free): (&[Vec<f64>], &FreePhases),
        delay: usize,
    ) -> (f64, [f64; 4]) {
        let (m, r) = (delay / d.ratio, delay % d.ratio);
        let (x, n1, n2) = (&ph[r], &free[0][r], &free[1][r]);
        // W = [a, v, q, y, x]; N = [1, n1, n2]
        let mut total = [[0.0f64; 5]; 5];
        let fitted = d.segments.iter().filter(|s| s.len() > self.skip);
        for ((seg, g), gs) in fitted.zip(&self.groups).zip(sums) {
            let mut ww = [[0.0f64; 5]; 5];
            let mut nw = [[0.0f64; 5]; 3];
            let mut nn = [[0.0f64; 3]; 3];
            for i in 0..4 {
                ww[i][..4].copy_from_slice(&gs.ww[i]);
                nw[0][i] = gs.sums[i];
            }
            nn[0][0] = g.len() as f64;
            let first = seg.start + self.skip - m;
            for (k, t) in (first..seg.end - m).zip(g.clone()) {
                let (xv, a, b) = (x[k], n1[k], n2[k]);
                for (i, c) in self.columns.iter().enumerate() {
                    let w = c[t];
                    ww[4][i] += xv * w;
                    nw[1][i] += a * w;
                    nw[2][i] += b * w;
                }
                ww[4][4] += xv * xv;
                nw[0][4] += xv;
                nw[1][4] += a * xv;
                nw[2][4] += b * xv;
                nn[0][1] += a;
                nn[0][2] += b;
                nn[1][1] += a * a;
                nn[1][2] += a * b;
                nn[2][2] += b * b;
            }
            for i in 0..4 {
                ww[i][4] = ww[4][i];
            }
            nn[1][0] = nn[0][1];
            nn[2][0] = nn[0][2];
            nn[2][1] = nn[1][2];
            // W'W - (N'W)' (N'N)^+ (N'W), by Cholesky of N'N dropping a
            // pivot the earlier columns nearly span
            let mut l = [[0.0f64; 3]; 3];
            let mut kept = [false; 3];
            for j in 0..3 {
                let mut dj = nn[j][j];
                for p in 0..j {
                    dj -= l[j][p] * l[j][p];
                }
                if dj > 1e-10 * nn[j][j] && dj > 0.0 {
                    kept[j] = true;
                    let s = dj.sqrt();
                    l[j][j] = s;
                    for i in j + 1..3 {
                        let mut v = nn[i][j];
                        for p in 0..j {
                            v -= l[i][p] * l[j][p];
                        }
                        l[i][j] = v / s;
                    }
                }
            }
            // C = L^-1 N'W, rows of dropped pivots left out
            let mut c = [[0.0f64; 5]; 3];
            for j in 0..3 {
                if !kept[j] {
                    continue;
                }
                for col in 0..5 {
                    let mut v = nw[j][col];
                    for p in 0..j {
                        v -= l[j][p] * c[p][col];
                    }
                    c[j][col] = v / l[j][j];
                }
            }
            for i in 0..5 {
                for j in 0..5 {
                    total[i][j] += ww[i][j] - (0..3).map(|p| c[p][i] * c[p][j]).sum::<f64>();
                }
            }
        }
        solve_joint(&total)
    }
}

/// RSS and `[I, B, K, G]` of `y` (index 3) on `a, v, q, x` (0, 1, 2, 4)
/// from their projected cross products (Jacobi-scaled Cholesky).
fn solve_joint(total: &[[f64; 5]; 5]) -> (f64, [f64; 4]) {
    let idx = [0, 1, 2, 4];
    let scale = idx.map(|i| 1.0 / total[i][i].max(f64::MIN_POSITIVE).sqrt());
    let g = nalgebra::Matrix4::from_fn(|i, j| total[idx[i]][idx[j]] * scale[i] * scale[j]);
    let h = nalgebra::Vector4::from_fn(|i, _| total[idx[i]][3] * scale[i]);
    let Some(chol) = g.cholesky() else {
        return (f64::INFINITY, [0.0; 4]);
    };
    let th = chol.solve(&h);
    let rss = (total[3][3] - th.dot(&h)).max(0.0);
    (rss, [0, 1, 2, 3].map(|i| th[i] * scale[i]))
}

/// An orthonormal basis of the vectors' span (Gram-Schmidt, twice, leaving
/// out a vector the others nearly span).
pub(crate) fn orthonormal(vectors: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut basis: Vec<Vec<f64>> = Vec::new();
    for v in vectors {
        let norm0 = dot(v, v).sqrt();
        let mut u = v.clone();
        for _ in 0..2 {
            for b in &basis {
                let k = dot(&u, b);
                u.iter_mut().zip(b).for_each(|(x, bx)| *x -= k * bx);
            }
        }
        let norm = dot(&u, &u).sqrt();
        if norm > 1e-8 * norm0 && norm > 0.0 {
            u.iter_mut().for_each(|x| *x /= norm);
            basis.push(u);
        }
    }
    basis
}

#[cfg(test)]
mod tests {
    use super::super::parametric::{joint_fit, low_pass_in};
    use super::*;

    /// The scan's fit from cross products is the row-wise fit with each
    /// segment's constant and free responses projected out.
    #[test]
    fn scan_fit_from_sums_equals_the_projected_row_fit() {
        let mut seed = 7u64;
        let mut noise = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let (ratio, n) = (4, 90);
        let segments = vec![0..30, 30..55, 55..90];
        let full: Vec<f64> = (0..n * ratio).map(|_| noise().max(0.0)).collect();
        let column = |noise: &mut dyn FnMut() -> f64| (0..n).map(|_| noise()).collect::<Vec<f64>>();
        let d = Decimated {
            fs: 250.0,
            ratio,
            segments: segments.clone(),
            position: column(&mut noise),
            velocity: column(&mut noise),
            acceleration: column(&mut noise),
            torque: column(&mut noise),
            rectified: [column(&mut noise), column(&mut noise)],
            rectified_full: [full.clone(), full.clone()],
        };
        let fs = 1000.0;
        let full_segments = super::super::segments::full_rate(&segments, ratio);
        let ph = phases(
            &low_pass_in(&full, (3.0, 0.8, fs), &full_segments),
            ratio,
            n,
        );
        let free = SegmentRows::free_phases(&d, (3.0, 0.8, fs), &full_segments);
        let rows = SegmentRows::new(&d, 6);
        let sums = rows.sums();
        for delay in [0, 5, 13, 22] {
            let (g, x) = rows.fit(&d, (&ph, &free), delay).expect("fit");
            let (rss, params) = joint_fit(&g, &x);
            let (rss2, params2) = rows.scan_fit(&sums, &d, (&ph, &free), delay);
            assert!((rss - rss2).abs() < 1e-9 * rss, "{rss} vs {rss2}");
            for (a, b) in params.iter().zip(params2) {
                assert!(
                    (a - b).abs() < 1e-8 * a.abs().max(1.0),
                    "{params:?} vs {params2:?}"
                );
            }
        }
    }
}
