//! Static drawings of impedance ellipsoids and ellipses as SVG, for papers:
//! a grid of small multiples (configuration x co-contraction level, as seed
//! 001 Fig. 5) and the planar arm's end-point stiffness ellipse (seed 003).
//!
//! An ellipsoid with principal axes `R` and radii `r` (|eigenvalues| of the
//! symmetric part, seed 001's convention) is the image of the unit sphere
//! under `A = R diag(r) Rᵀ`. Seen along a direction with the orthographic
//! projection `P` (2x3), its outline is the ellipse `P A u`, whose shape
//! matrix is `S = P A² Pᵀ`; the outline is drawn from the eigen-decomposition
//! of `S`, with the three principal sections `c ± cos t Aeᵢ + sin t Aeⱼ`
//! inside it. One scale for the whole grid, shown by a scale bar.

use std::fmt::Write as _;

use crate::svg::escape;
use crate::EllipsoidView;

/// How the ellipsoids are seen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum View {
    /// From above: x right, y up (for planar, 2-D ellipses).
    Top,
    /// Orthographic from azimuth `yaw` and elevation `pitch` (rad), z up.
    Oblique {
        /// Rotation about z (rad).
        yaw: f64,
        /// Elevation above the x-y plane (rad).
        pitch: f64,
    },
}

impl View {
    /// The default 3-D view of limpid's figures (that of the interactive viewer).
    pub const DEFAULT: View = View::Oblique {
        yaw: -0.6,
        pitch: 0.35,
    };

    /// Screen coordinates (right, up) of a lab vector.
    fn project(self, p: [f64; 3]) -> [f64; 2] {
        match self {
            View::Top => [p[0], p[1]],
            View::Oblique { yaw, pitch } => {
                let (cy, sy, cp, sp) = (yaw.cos(), yaw.sin(), pitch.cos(), pitch.sin());
                let x1 = cy * p[0] - sy * p[1];
                let y1 = sy * p[0] + cy * p[1];
                [y1, cp * p[2] - sp * x1]
            }
        }
    }
}

/// `A e_k` for the ellipsoid: the k-th principal semi-axis as a lab vector.
fn semi_axis(e: &EllipsoidView, k: usize) -> [f64; 3] {
    let r = e.eigenvalues[k].abs();
    [e.axes[0][k] * r, e.axes[1][k] * r, e.axes[2][k] * r]
}

/// Outline of the projected ellipsoid as screen points (unscaled, centred).
fn outline(e: &EllipsoidView, view: View, n: usize) -> Vec<[f64; 2]> {
    // S = Σ_k (P A e_k)(P A e_k)ᵀ, formed in units of the largest radius so
    // that squaring cannot overflow (radii up to 1e307)
    let unit = e.eigenvalues.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let unit = if unit > 0.0 && unit.is_finite() {
        unit
    } else {
        1.0
    };
    let mut s = [[0.0; 2]; 2];
    for k in 0..3 {
        let p = view.project(semi_axis(e, k)).map(|v| v / unit);
        for (i, row) in s.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v += p[i] * p[j];
            }
        }
    }
    // eigen-decomposition of the symmetric 2x2 S
    let (a, b, d) = (s[0][0], s[0][1], s[1][1]);
    let mean = 0.5 * (a + d);
    let dev = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let (l1, l2) = ((mean + dev).max(0.0), (mean - dev).max(0.0));
    let angle = 0.5 * (2.0 * b).atan2(a - d);
    let (c, sn) = (angle.cos(), angle.sin());
    (0..=n)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / n as f64;
            let (u, v) = (l1.sqrt() * t.cos(), l2.sqrt() * t.sin());
            [unit * (c * u - sn * v), unit * (sn * u + c * v)]
        })
        .collect()
}

/// Principal section through semi-axes i and j (unscaled, centred).
fn section(e: &EllipsoidView, view: View, i: usize, j: usize, n: usize) -> Vec<[f64; 2]> {
    let (a, b) = (semi_axis(e, i), semi_axis(e, j));
    (0..=n)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / n as f64;
            let (c, s) = (t.cos(), t.sin());
            view.project([
                c * a[0] + s * b[0],
                c * a[1] + s * b[1],
                c * a[2] + s * b[2],
            ])
        })
        .collect()
}

fn path(points: &[[f64; 2]], cx: f64, cy: f64, scale: f64) -> String {
    let mut d = String::new();
    for (k, p) in points.iter().enumerate() {
        let _ = write!(
            d,
            "{}{:.1},{:.1}",
            if k == 0 { "M" } else { " L" },
            cx + scale * p[0],
            cy - scale * p[1]
        );
    }
    d
}

/// A round number (1, 2 or 5 x 10^k) not above `v`.
pub fn round_down(v: f64) -> f64 {
    if !(v.is_finite() && v > 0.0) {
        return 1.0;
    }
    let mag = 10f64.powf(v.log10().floor());
    [5.0, 2.0, 1.0]
        .iter()
        .map(|m| m * mag)
        .find(|x| *x <= v * (1.0 + 1e-12))
        .unwrap_or(mag)
}

/// Small multiples: `cells[row][column]` (None: no estimate there), row and
/// column labels, one scale for all. Returns a standalone `<svg>`; every
/// drawn ellipsoid is a `<g class="ellipsoid" data-point=...>` whose
/// `<title>` gives its principal values.
pub fn grid(
    title: &str,
    rows: &[String],
    columns: &[String],
    cells: &[Vec<Option<EllipsoidView>>],
    unit: &str,
    view: View,
) -> String {
    let cell = 150.0;
    let (left, top, bottom) = (120.0, 52.0, 56.0);
    // wide enough for the title (about 7 px per character at 13 px)
    let width = (left + cell * columns.len().max(1) as f64 + 20.0)
        .max(7.0 * title.chars().count() as f64 + 40.0);
    let height = top + cell * rows.len().max(1) as f64 + bottom;
    // the largest outline radius fills 45 % of a cell
    let largest = cells
        .iter()
        .flatten()
        .flatten()
        .flat_map(|e| e.eigenvalues.iter().map(|v| v.abs()))
        .fold(0.0, f64::max);
    let scale = if largest > 0.0 {
        0.45 * cell / largest
    } else {
        1.0
    };
    let mut s = String::new();
    let _ = write!(
        s,
        r##"<svg xmlns="http://www.w3.org/2000/svg" class="ellipse-grid" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="12"><title>{}</title><rect width="{width}" height="{height}" fill="#fff"/>"##,
        escape(title)
    );
    let _ = write!(
        s,
        r#"<text x="{}" y="20" text-anchor="middle" font-size="13" font-weight="bold">{}</text>"#,
        width / 2.0,
        escape(title)
    );
    for (j, c) in columns.iter().enumerate() {
        let _ = write!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            left + cell * (j as f64 + 0.5),
            top - 8.0,
            escape(c)
        );
    }
    for (i, r) in rows.iter().enumerate() {
        let cy = top + cell * (i as f64 + 0.5);
        let _ = write!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"#,
            left - 10.0,
            cy + 4.0,
            escape(r)
        );
        for (j, e) in cells.get(i).into_iter().flatten().enumerate() {
            let cx = left + cell * (j as f64 + 0.5);
            let _ = write!(
                s,
                r##"<rect x="{:.1}" y="{:.1}" width="{cell}" height="{cell}" fill="none" stroke="#e4e4e4"/>"##,
                cx - cell / 2.0,
                cy - cell / 2.0
            );
            let Some(e) = e else {
                let _ = write!(
                    s,
                    r##"<text x="{cx:.1}" y="{cy:.1}" text-anchor="middle" fill="#888">no estimate</text>"##
                );
                continue;
            };
            draw_ellipsoid(&mut s, e, (cx, cy, scale), unit, view);
        }
    }
    scale_and_axes(&mut s, (width, height, left), (largest, scale), unit, view);
    s.push_str("</svg>");
    s
}

/// One ellipsoid at the centre `(cx, cy)` of its cell, `scale` pixels per
/// unit: its outline and, in the oblique views, its three principal sections.
fn draw_ellipsoid(
    s: &mut String,
    e: &EllipsoidView,
    (cx, cy, scale): (f64, f64, f64),
    unit: &str,
    view: View,
) {
    let palette = crate::svg::PALETTE;
    let values = e
        .eigenvalues
        .iter()
        .filter(|v| **v != 0.0)
        .map(|v| crate::fmt(*v))
        .collect::<Vec<_>>()
        .join(", ");
    let _ = write!(
        s,
        r#"<g class="ellipsoid" data-point="{}"><title>{}: principal values {values} {unit}</title>"#,
        escape(&e.point),
        escape(&e.point)
    );
    let _ = write!(
        s,
        r#"<path class="outline" d="{}" fill="{}" fill-opacity="0.12" stroke="{}" stroke-width="1.6"/>"#,
        path(&outline(e, view, 72), cx, cy, scale),
        palette[0],
        palette[0]
    );
    if view != View::Top {
        for (a, b, w) in [(0, 1, 1.1), (1, 2, 0.8), (0, 2, 0.8)] {
            let _ = write!(
                s,
                r#"<path class="section" d="{}" fill="none" stroke="{}" stroke-width="{w}" stroke-opacity="0.7"/>"#,
                path(&section(e, view, a, b, 60), cx, cy, scale),
                palette[0]
            );
        }
    }
    s.push_str("</g>");
}

/// The scale bar (the largest semi-axis rounded down) and the lab axes' directions.
fn scale_and_axes(
    s: &mut String,
    (width, height, left): (f64, f64, f64),
    (largest, scale): (f64, f64),
    unit: &str,
    view: View,
) {
    let bar_value = round_down(largest);
    let bar = bar_value * scale;
    let by = height - 22.0;
    let _ = write!(
        s,
        r##"<g class="scale-bar"><line x1="{left}" y1="{by}" x2="{:.1}" y2="{by}" stroke="#222" stroke-width="2"/><line x1="{left}" y1="{:.1}" x2="{left}" y2="{:.1}" stroke="#222"/><line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#222"/><text x="{:.1}" y="{:.1}">{} {} (semi-axis)</text></g>"##,
        left + bar,
        by - 4.0,
        by + 4.0,
        left + bar,
        by - 4.0,
        left + bar,
        by + 4.0,
        left + bar + 8.0,
        by + 4.0,
        crate::fmt(bar_value),
        escape(unit)
    );
    let (ax, ay) = (width - 60.0, height - 30.0);
    let names: &[&str] = if view == View::Top {
        &["x", "y"]
    } else {
        &["x", "y", "z"]
    };
    for (k, name) in names.iter().enumerate() {
        let mut v = [0.0; 3];
        v[k] = 1.0;
        let p = view.project(v);
        let (ex, ey) = (ax + 22.0 * p[0], ay - 22.0 * p[1]);
        let _ = write!(
            s,
            r##"<line x1="{ax}" y1="{ay}" x2="{ex:.1}" y2="{ey:.1}" stroke="#666"/><text x="{:.1}" y="{:.1}" font-size="11" fill="#444">{name}</text>"##,
            ex + 3.0 * p[0].signum(),
            ey - 3.0 * p[1].signum() + 4.0
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere_like(r: [f64; 3]) -> EllipsoidView {
        EllipsoidView {
            point: "p".into(),
            kind: "stiffness".into(),
            centre: [0.0; 3],
            eigenvalues: r,
            axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        }
    }

    #[test]
    fn outline_of_an_axis_aligned_ellipsoid_seen_from_above_has_its_x_and_y_radii() {
        let e = sphere_like([3.0, 2.0, 1.0]);
        let pts = outline(&e, View::Top, 360);
        let max_x = pts.iter().map(|p| p[0].abs()).fold(0.0, f64::max);
        let max_y = pts.iter().map(|p| p[1].abs()).fold(0.0, f64::max);
        assert!((max_x - 3.0).abs() < 1e-9 && (max_y - 2.0).abs() < 1e-3);
    }

    #[test]
    fn outline_of_a_huge_ellipsoid_stays_finite() {
        let e = sphere_like([1e307, 415.0, 0.0]);
        let pts = outline(&e, View::Top, 360);
        assert!(pts.iter().all(|p| p[0].is_finite() && p[1].is_finite()));
        let max_x = pts.iter().map(|p| p[0].abs()).fold(0.0, f64::max);
        assert!((max_x / 1e307 - 1.0).abs() < 1e-12, "{max_x}");
    }

    #[test]
    fn outline_of_a_sphere_is_a_circle_from_any_view() {
        let e = sphere_like([2.0, 2.0, 2.0]);
        for p in outline(&e, View::DEFAULT, 90) {
            assert!((p[0].hypot(p[1]) - 2.0).abs() < 1e-9);
        }
    }

    #[test]
    fn outline_encloses_every_principal_section() {
        // a rotated, elongated ellipsoid: no section point outside the outline
        let (c, s) = (0.6f64.cos(), 0.6f64.sin());
        let e = EllipsoidView {
            point: "p".into(),
            kind: "stiffness".into(),
            centre: [0.0; 3],
            eigenvalues: [5.0, 2.0, 0.5],
            axes: [
                [c, -s, 0.0],
                [s * 0.8, c * 0.8, -0.6],
                [s * 0.6, c * 0.6, 0.8],
            ],
        };
        let o = outline(&e, View::DEFAULT, 720);
        let reach = |angle: f64| {
            o.iter()
                .filter(|p| (p[1].atan2(p[0]) - angle).abs() < 0.02)
                .map(|p| p[0].hypot(p[1]))
                .fold(0.0, f64::max)
        };
        for (a, b) in [(0, 1), (1, 2), (0, 2)] {
            for p in section(&e, View::DEFAULT, a, b, 90) {
                let r = p[0].hypot(p[1]);
                assert!(r <= reach(p[1].atan2(p[0])) * 1.02 + 1e-6, "{p:?}");
            }
        }
    }

    #[test]
    fn grid_draws_one_group_per_estimate_and_says_where_there_is_none() {
        let svg = grid(
            "K",
            &["configuration 1".into(), "configuration 2".into()],
            &["level 0".into(), "level 1".into()],
            &[
                vec![Some(sphere_like([300.0, 200.0, 100.0])), None],
                vec![
                    Some(sphere_like([600.0, 200.0, 100.0])),
                    Some(sphere_like([900.0, 200.0, 100.0])),
                ],
            ],
            "N/m",
            View::DEFAULT,
        );
        assert_eq!(svg.matches("class=\"ellipsoid\"").count(), 3);
        assert!(svg.contains("no estimate"));
        // scale bar: a round number not above the largest principal value
        assert!(svg.contains(">500 N/m (semi-axis)</text>"), "{svg}");
        assert_eq!(round_down(449.0), 200.0);
        assert_eq!(round_down(450.0), 200.0);
        assert_eq!(round_down(500.0), 500.0);
    }
}
