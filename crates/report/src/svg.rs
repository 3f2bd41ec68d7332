//! Static line charts as SVG. Each trace is one `<path class="trace">` with
//! its name in `data-name`, so that tests (and readers of the file) can find
//! it; axes are linear or logarithmic with 1-2-5 or decade ticks.

use serde::Serialize;
use std::fmt::Write as _;

/// How a trace is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Stroke {
    /// A solid line.
    Solid,
    /// A dashed line.
    Dashed,
    /// A dotted line.
    Dotted,
    /// A mark at each point, no line (spectral lines of a periodic analysis).
    Points,
}

/// One trace.
#[derive(Debug, Clone, Serialize)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates.
    pub y: Vec<f64>,
    /// Line style.
    pub stroke: Stroke,
    /// CSS colour.
    pub color: String,
}

/// One chart: axes and traces.
#[derive(Debug, Clone, Serialize)]
pub struct Chart {
    /// Title above the chart.
    pub title: String,
    /// Label of the x axis (with unit).
    pub x_label: String,
    /// Label of the y axis (with unit).
    pub y_label: String,
    /// Logarithmic x axis.
    pub x_log: bool,
    /// Logarithmic y axis.
    pub y_log: bool,
    /// Fixed y range; None: from the data.
    pub y_range: Option<(f64, f64)>,
    /// The traces.
    pub series: Vec<Series>,
}

/// Colours for up to 9 traces (colour-blind-safe Okabe-Ito, then greys).
pub const PALETTE: [&str; 9] = [
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#999999",
    "#F0E442",
];

/// Text for HTML/SVG content and attribute values.
pub(crate) fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Tick positions for [lo, hi]: decades on a log axis, 1-2-5 steps otherwise.
fn ticks(lo: f64, hi: f64, log: bool) -> Vec<f64> {
    if log {
        let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        // three decades or fewer: 1-2-5 in each
        let steps: &[f64] = if b - a <= 3 { &[1.0, 2.0, 5.0] } else { &[1.0] };
        return (a..=b)
            .flat_map(|e| steps.iter().map(move |m| m * 10f64.powi(e)))
            .filter(|t| *t >= lo * 0.999 && *t <= hi * 1.001)
            .collect();
    }
    let span = (hi - lo).abs().max(1e-300);
    let raw = span / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| span / s <= 6.0)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

fn tick_label(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        format!("{v:.0e}")
    } else if a >= 1.0 && (v - v.round()).abs() < 1e-9 {
        format!("{}", v.round())
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// Largest magnitude a chart draws.
const DRAWABLE: f64 = 1e300;

impl Chart {
    fn finite_points<'a>(&'a self, s: &'a Series) -> impl Iterator<Item = (f64, f64)> + 'a {
        s.x.iter()
            .zip(&s.y)
            .map(|(x, y)| (*x, *y))
            // beyond 1e300 the axis span (hi - lo) would overflow into NaN
            // coordinates; such a value cannot be drawn beside others anyway
            .filter(move |(x, y)| {
                x.abs() <= DRAWABLE
                    && y.abs() <= DRAWABLE
                    && (!self.x_log || *x > 0.0)
                    && (!self.y_log || *y > 0.0)
            })
    }

    fn range(&self, pick: impl Fn((f64, f64)) -> f64, log: bool) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for s in &self.series {
            for p in self.finite_points(s) {
                lo = lo.min(pick(p));
                hi = hi.max(pick(p));
            }
        }
        if !lo.is_finite() {
            return if log { (1.0, 10.0) } else { (0.0, 1.0) };
        }
        if log {
            if hi / lo < 10.0 {
                // sqrt(lo) sqrt(hi): lo * hi underflows to 0 below about 1e-154
                let mid = lo.sqrt() * hi.sqrt();
                return (mid / 3.2, mid * 3.2);
            }
            return (lo, hi);
        }
        if (hi - lo).abs() < 1e-12 * hi.abs().max(1.0) {
            return (lo - 1.0, hi + 1.0);
        }
        let pad = 0.05 * (hi - lo);
        (lo - pad, hi + pad)
    }

    /// The chart as a standalone `<svg>` element of `width` x `height` px
    /// (11 px text, for the page).
    pub fn to_svg(&self, width: f64, height: f64) -> String {
        // one legend width for every chart of the page, so their plots align
        self.render(width, height, 11.0, Some(200.0))
    }

    /// The chart alone (for a file) with `font` px text; margins grow with
    /// the text, the legend is as wide as its longest name.
    pub fn to_svg_styled(&self, width: f64, height: f64, font: f64) -> String {
        self.render(width, height, font, None)
    }

    fn render(&self, width: f64, height: f64, font: f64, legend: Option<f64>) -> String {
        let k = font / 11.0;
        // the legend sits right of the plot, outside the data
        let longest = self
            .series
            .iter()
            .map(|s| s.name.chars().count())
            .max()
            .unwrap_or(0) as f64;
        let mr = legend.unwrap_or((34.0 * k + 0.6 * font * longest).max(40.0 * k));
        let (ml, mt, mb) = (64.0 * k, 28.0 * k, 44.0 * k);
        let (pw, ph) = (width - ml - mr, height - mt - mb);
        let (x0, x1) = self.range(|p| p.0, self.x_log);
        let (y0, y1) = self
            .y_range
            .unwrap_or_else(|| self.range(|p| p.1, self.y_log));
        let map = |v: f64, lo: f64, hi: f64, log: bool| {
            if log {
                (v.log10() - lo.log10()) / (hi.log10() - lo.log10())
            } else {
                (v - lo) / (hi - lo)
            }
        };
        let px = |x: f64| ml + pw * map(x, x0, x1, self.x_log);
        let py = |y: f64| mt + ph * (1.0 - map(y, y0, y1, self.y_log));
        let mut s = String::new();
        let _ = write!(
            s,
            r##"<svg xmlns="http://www.w3.org/2000/svg" class="chart" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="{font}"><rect width="{width}" height="{height}" fill="#fff"/>"##
        );
        let _ = write!(s, r#"<title>{}</title>"#, escape(&self.title));
        let _ = write!(
            s,
            r##"<text x="{}" y="{:.1}" text-anchor="middle" font-size="{}" font-weight="bold">{}</text>"##,
            ml + pw / 2.0,
            16.0 * k,
            font + 1.0,
            escape(&self.title)
        );
        let _ = write!(
            s,
            r##"<rect x="{ml}" y="{mt}" width="{pw}" height="{ph}" fill="none" stroke="#444"/>"##
        );
        for t in ticks(x0, x1, self.x_log) {
            let x = px(t);
            let _ = write!(
                s,
                r##"<line x1="{x:.1}" y1="{mt}" x2="{x:.1}" y2="{:.1}" stroke="#ddd"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
                mt + ph,
                mt + ph + 14.0 * k,
                tick_label(t)
            );
        }
        for t in ticks(y0, y1, self.y_log) {
            let y = py(t);
            let _ = write!(
                s,
                r##"<line x1="{ml}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
                ml + pw,
                ml - 4.0 * k,
                y + 4.0 * k,
                tick_label(t)
            );
        }
        let _ = write!(
            s,
            r##"<text x="{}" y="{}" text-anchor="middle">{}</text>"##,
            ml + pw / 2.0,
            height - 8.0 * k,
            escape(&self.x_label)
        );
        let _ = write!(
            s,
            r##"<text transform="translate({:.1} {}) rotate(-90)" text-anchor="middle">{}</text>"##,
            14.0 * k,
            mt + ph / 2.0,
            escape(&self.y_label)
        );
        let mut legend_rows = 0;
        for (index, series) in self.series.iter().enumerate() {
            let mut d = String::new();
            let mut pen_down = false;
            for (x, y) in self.finite_points(series) {
                let (cx, cy) = (px(x), py(y.clamp(y0.min(y1), y0.max(y1))));
                let _ = write!(d, "{}{cx:.1},{cy:.1}", if pen_down { " L" } else { "M" });
                pen_down = true;
            }
            let dash = match series.stroke {
                Stroke::Solid | Stroke::Points => "",
                Stroke::Dashed => r#" stroke-dasharray="6 3""#,
                Stroke::Dotted => r#" stroke-dasharray="1.5 2.5""#,
            };
            if series.stroke == Stroke::Points {
                let _ = write!(
                    s,
                    r#"<g class="trace" data-name="{}" fill="{}">"#,
                    escape(&series.name),
                    series.color
                );
                for (x, y) in self.finite_points(series) {
                    let (cx, cy) = (px(x), py(y.clamp(y0.min(y1), y0.max(y1))));
                    let _ = write!(
                        s,
                        r#"<circle cx="{cx:.1}" cy="{cy:.1}" r="{:.1}"/>"#,
                        2.2 * k
                    );
                }
                s.push_str("</g>");
            } else {
                let _ = write!(
                    s,
                    r#"<path class="trace" data-name="{}" d="{d}" fill="none" stroke="{}" stroke-width="{:.2}"{dash}/>"#,
                    escape(&series.name),
                    series.color,
                    1.4 * k
                );
            }
            // legend: one entry per name (series drawn in pieces share one)
            if self.series[..index].iter().any(|o| o.name == series.name) {
                continue;
            }
            let ly = mt + 8.0 * k + 14.0 * k * legend_rows as f64;
            legend_rows += 1;
            let lx = ml + pw + 10.0 * k;
            if series.stroke == Stroke::Points {
                let _ = write!(
                    s,
                    r#"<circle cx="{:.1}" cy="{ly:.1}" r="{:.1}" fill="{}"/><text x="{:.1}" y="{:.1}">{}</text>"#,
                    lx + 10.0 * k,
                    2.6 * k,
                    series.color,
                    lx + 24.0 * k,
                    ly + 4.0 * k,
                    escape(&series.name)
                );
                continue;
            }
            let _ = write!(
                s,
                r#"<line x1="{lx:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="{}" stroke-width="1.6"{dash}/><text x="{:.1}" y="{:.1}">{}</text>"#,
                lx + 20.0 * k,
                series.color,
                lx + 24.0 * k,
                ly + 4.0 * k,
                escape(&series.name)
            );
        }
        s.push_str("</svg>");
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_numbers_inside_the_range() {
        assert_eq!(
            ticks(0.0, 1.0, false),
            vec![0.0, 0.2, 0.4, 0.6000000000000001, 0.8, 1.0]
        );
        assert_eq!(ticks(0.3, 30.0, true), vec![0.5, 1.0, 2.0, 5.0, 10.0, 20.0]);
        assert_eq!(
            ticks(0.01, 1000.0, true),
            vec![0.01, 0.1, 1.0, 10.0, 100.0, 1000.0]
        );
        assert_eq!(tick_label(1000.0), "1000");
        assert_eq!(tick_label(0.25), "0.25");
    }

    /// A log axis over one tiny (or huge) value: its geometric mean had
    /// underflowed to 0, and the page drew "0" ticks at NaN positions.
    #[test]
    fn a_log_axis_over_one_extreme_value_has_finite_ticks() {
        for v in [1e-300, 1e-160, 1e150, 1e299] {
            let chart = Chart {
                title: "psd".into(),
                x_label: "f".into(),
                y_label: "y".into(),
                x_log: true,
                y_log: true,
                y_range: None,
                series: vec![Series {
                    name: "x".into(),
                    x: vec![1.0, 2.0],
                    y: vec![f64::NAN, v],
                    stroke: Stroke::Solid,
                    color: PALETTE[0].into(),
                }],
            };
            let (lo, hi) = chart.range(|p| p.1, true);
            assert!(
                lo > 0.0 && lo < v && v < hi && hi.is_finite(),
                "{v}: {lo} {hi}"
            );
            assert!(!ticks(lo, hi, true).is_empty(), "{v}");
            assert!(!chart.to_svg(400.0, 300.0).contains("NaN"), "{v}");
        }
    }

    #[test]
    fn every_series_is_one_named_path_and_log_axes_drop_non_positive_points() {
        let chart = Chart {
            title: "a <b>".into(),
            x_label: "f (Hz)".into(),
            y_label: "|Z|".into(),
            x_log: true,
            y_log: true,
            y_range: None,
            series: vec![
                Series {
                    name: "one".into(),
                    x: vec![0.0, 1.0, 10.0],
                    y: vec![1.0, 2.0, 3.0],
                    stroke: Stroke::Solid,
                    color: PALETTE[0].into(),
                },
                Series {
                    name: "two".into(),
                    x: vec![1.0, 10.0],
                    y: vec![f64::NAN, 5.0],
                    stroke: Stroke::Dashed,
                    color: PALETTE[1].into(),
                },
            ],
        };
        let svg = chart.to_svg(400.0, 300.0);
        assert_eq!(svg.matches(r#"class="trace""#).count(), 2);
        assert!(svg.contains("a &lt;b&gt;"));
        // the x = 0 point of "one" and the NaN of "two" are left out
        let one = svg.split(r#"data-name="one" d=""#).nth(1).unwrap();
        assert_eq!(one.split('"').next().unwrap().matches('L').count(), 1);
        let two = svg.split(r#"data-name="two" d=""#).nth(1).unwrap();
        assert_eq!(two.split('"').next().unwrap().matches('L').count(), 0);
    }

    #[test]
    fn values_beside_1e308_are_left_out_not_drawn_as_nan() {
        // a span of +-1e308 overflowed the axis into NaN coordinates (fuzzer)
        let chart = Chart {
            title: "K".into(),
            x_label: "T (ms)".into(),
            y_label: "K".into(),
            x_log: false,
            y_log: false,
            y_range: None,
            series: vec![Series {
                name: "one".into(),
                x: vec![50.0, 100.0, 150.0],
                y: vec![-1e308, 20.0, 1e308],
                stroke: Stroke::Solid,
                color: PALETTE[0].into(),
            }],
        };
        let svg = chart.to_svg(400.0, 300.0);
        assert!(!svg.contains("NaN") && !svg.contains("inf"), "{svg}");
    }
}
