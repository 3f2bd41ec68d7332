//! Plain-text tables in the layout of seed 000 Table I-II.

use std::fmt::Write;

use limpid_analysis::cocontraction::CocontractionResult;
use limpid_analysis::linear::{LinearResult, MatrixKind, MatrixVerdict};
use limpid_analysis::Matrix;

/// A number with 4 significant digits, without exponent for the usual range.
pub fn num(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.3e}")
    } else {
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    }
}

fn matrix_block(out: &mut String, title: &str, m: &Matrix, se: &Matrix, coords: &[String]) {
    let _ = writeln!(out, "{title}");
    let _ = write!(out, "      ");
    for c in coords {
        let _ = write!(out, "{c:>22}");
    }
    out.push('\n');
    for i in 0..m.nrows() {
        let _ = write!(out, "  {:<4}", coords[i]);
        for j in 0..m.ncols() {
            // rounded to the standard error, as the report and Python print it
            let cell = limpid_core::with_standard_error(m[(i, j)], se[(i, j)]);
            let _ = write!(out, "{cell:>22}");
        }
        out.push('\n');
    }
}

/// The readable report of `estimate linear`.
pub fn linear_text(r: &LinearResult) -> String {
    let mut out = String::new();
    let p = &r.provenance;
    let coords = &p.coordinates;
    let _ = writeln!(out, "limpid estimate linear: {}", p.recording);
    let windows = if p.continuous {
        "one continuous window".to_string()
    } else {
        format!("{} trials", p.windows)
    };
    let _ = writeln!(
        out,
        "coordinates {} | {} Hz | {} | {} samples used | low-pass {} Hz (Butterworth order {}, zero-phase), derivatives: {}, force offsets: {}",
        coords.join(", "),
        num(p.sample_rate_hz),
        windows,
        r.criteria.samples,
        num(p.cutoff_hz),
        p.filter_order,
        p.derivative,
        p.offsets
    );
    out.push('\n');
    let flag = |kind: MatrixKind| verdict_flag(r.criteria.verdict_of(kind));
    let [mu, bu, ku] = &p.units;
    matrix_block(
        &mut out,
        &format!("Stiffness K ({ku}){}", flag(MatrixKind::Stiffness)),
        &r.stiffness,
        &r.standard_errors.stiffness,
        coords,
    );
    matrix_block(
        &mut out,
        &format!("Damping B ({bu}){}", flag(MatrixKind::Damping)),
        &r.damping,
        &r.standard_errors.damping,
        coords,
    );
    matrix_block(
        &mut out,
        &format!("Inertia M ({mu}){}", flag(MatrixKind::Inertia)),
        &r.inertia,
        &r.standard_errors.inertia,
        coords,
    );
    match &r.equilibrium {
        Some(eq) => {
            let _ = writeln!(
                out,
                "Equilibrium x_eq: {}",
                eq.iter().map(|v| num(*v)).collect::<Vec<_>>().join(", ")
            );
        }
        None => {
            let _ = writeln!(out, "Equilibrium x_eq: not estimated (see warnings)");
        }
    }
    out.push('\n');
    if coords.len() >= 2 {
        symmetric_parts(&mut out, r);
    }
    quality(&mut out, r);
    out
}

/// Artemiadis et al. (2010)'s Table I layout (symmetric parts), Table II and the stiffness ellipsoid.
fn symmetric_parts(out: &mut String, r: &LinearResult) {
    let coords = &r.provenance.coordinates;
    let ku = &r.provenance.units[2];
    let _ = writeln!(
        out,
        "Symmetric parts (Artemiadis et al. 2010, Table I layout): K(s) | B(s) | M(s)"
    );
    for i in 0..coords.len() {
        let row = |m: &Matrix| {
            (0..m.ncols())
                .map(|j| format!("{:>9}", num(m[(i, j)])))
                .collect::<String>()
        };
        let _ = writeln!(
            out,
            "  {:<4}{}  |{}  |{}",
            coords[i],
            row(&r.symmetric.stiffness),
            row(&r.symmetric.damping),
            row(&r.symmetric.inertia)
        );
    }
    let t = &r.table_ii;
    let _ = writeln!(
        out,
        "Table II: K max/min/maxA {} / {} / {} | B {} / {} / {} | M {} / {} / {}",
        num(t.stiffness.max_symmetric),
        num(t.stiffness.min_symmetric),
        num(t.stiffness.max_antisymmetric),
        num(t.damping.max_symmetric),
        num(t.damping.min_symmetric),
        num(t.damping.max_antisymmetric),
        num(t.inertia.max_symmetric),
        num(t.inertia.min_symmetric),
        num(t.inertia.max_antisymmetric),
    );
    if let Some(e) = &r.ellipsoids.stiffness {
        let _ = writeln!(
            out,
            "Stiffness ellipsoid: principal stiffnesses {} {ku}; orientation {} deg ({})",
            e.eigenvalues
                .iter()
                .map(|v| num(*v))
                .collect::<Vec<_>>()
                .join(", "),
            e.angles_deg
                .iter()
                .map(|v| format!("{v:.1}"))
                .collect::<Vec<_>>()
                .join(", "),
            if e.angles_deg.len() == 3 {
                "yaw, pitch, roll"
            } else {
                "major axis from the first coordinate"
            }
        );
    }
    out.push('\n');
}

/// The fit, the criteria, the standard errors' method and the warnings.
fn quality(out: &mut String, r: &LinearResult) {
    let coords = &r.provenance.coordinates;
    let _ = writeln!(out, "Quality");
    let per_axis = |v: &[f64], digits: usize| {
        coords
            .iter()
            .zip(v)
            .map(|(c, x)| format!("{c} {x:.digits$}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let _ = writeln!(
        out,
        "  fit: r {}; VAF % {}",
        per_axis(&r.fit.r, 3),
        per_axis(&r.fit.vaf, 1)
    );
    let m = &r.criteria.matrices;
    let _ = writeln!(
        out,
        "  condition number (scaled regressor) {:.3}; K positive definite: {} (min eigenvalue {}), symmetry ratio {:.3}; B positive definite: {}",
        r.criteria.condition_number,
        yes(m.stiffness.positive_definite),
        num(m.stiffness.min_eigenvalue),
        m.stiffness.symmetry_ratio,
        yes(m.damping.positive_definite)
    );
    let _ = writeln!(
        out,
        "  standard errors: {}",
        r.criteria.standard_error_method
    );
    if r.warnings.is_empty() {
        let _ = writeln!(
            out,
            "  no warnings: every matrix is identified from this data"
        );
    }
    for w in &r.warnings {
        let _ = writeln!(out, "warning: {w}");
    }
}

fn yes(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}

/// The readable report of `estimate cocontraction` (Patel et al. 2013, Tables 1-5 for one recording).
pub fn cocontraction_text(r: &CocontractionResult) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "limpid estimate cocontraction: {} (MVC {})",
        r.recording, r.mvc
    );
    let _ = writeln!(out, "muscles: {}", r.muscles.join(", "));
    out.push('\n');
    let _ = writeln!(
        out,
        "{:>6} {:>16} {:>8} {:>13} {:>13} {:>13} {:>9} {:>9} {:>9} {:>9}  quality",
        "level",
        "C (mean ± sd)",
        "on band",
        "Kxx ± SE",
        "Kyy ± SE",
        "Kzz ± SE",
        "K_maxA",
        "K1",
        "K2",
        "K3",
    );
    for l in &r.levels {
        let k = &l.stiffness;
        let se = &l.estimate.standard_errors.stiffness;
        let n = k.nrows();
        let get = |i: usize, j: usize| {
            if i < n && j < n {
                limpid_core::with_standard_error(k[(i, j)], se[(i, j)])
            } else {
                "-".into()
            }
        };
        let principal: Vec<String> = match &l.ellipsoid {
            Some(e) => e.eigenvalues.iter().map(|v| num(*v)).collect(),
            None => vec![],
        };
        let p = |i: usize| principal.get(i).cloned().unwrap_or_else(|| "-".into());
        let e = &l.estimate;
        let quality = format!(
            "K {}, VAF {}%",
            e.criteria.verdicts.stiffness.words(),
            e.fit
                .vaf
                .iter()
                .map(|v| format!("{v:.1}"))
                .collect::<Vec<_>>()
                .join("/")
        );
        let _ = writeln!(
            out,
            "{:>6} {:>16} {:>7.0}% {:>13} {:>13} {:>13} {:>9} {:>9} {:>9} {:>9}  {}",
            num(l.level),
            format!("{:.3} ± {:.3}", l.cocontraction_index, l.cocontraction_sd),
            100.0 * l.cocontraction_within_band,
            get(0, 0),
            get(1, 1),
            get(2, 2),
            num(e.table_ii.stiffness.max_antisymmetric),
            p(0),
            p(1),
            p(2),
            quality
        );
    }
    if !r.comparisons.is_empty() {
        out.push('\n');
        let _ = writeln!(
            out,
            "Change against level {} (Fig. 6, Table 5): principal stiffness % | axis rotation deg",
            num(r.comparisons[0].reference_level)
        );
        for c in &r.comparisons {
            let fmt = |v: &[f64], amb: &[bool]| {
                v.iter()
                    .zip(amb)
                    .map(|(x, a)| format!("{x:+.1}{}", if *a { "?" } else { "" }))
                    .collect::<Vec<_>>()
                    .join(" / ")
            };
            let _ = writeln!(
                out,
                "  level {:>5}: primary/secondary/tertiary {} % | {} deg",
                num(c.level),
                fmt(&c.principal_change_percent, &c.ambiguous),
                fmt(&c.rotation_deg, &c.ambiguous)
            );
        }
        if r.comparisons.iter().any(|c| c.ambiguous.iter().any(|a| *a)) {
            let _ = writeln!(out, "  ? = tied principal stiffnesses (within 5 %): that axis is not defined by the matrix");
        }
    }
    for l in &r.levels {
        for w in &l.estimate.warnings {
            let _ = writeln!(out, "warning: level {}: {w}", num(l.level));
        }
    }
    for w in &r.warnings {
        let _ = writeln!(out, "warning: {w}");
    }
    out
}

/// The arm configuration from markers, one paragraph.
pub fn arm_configuration_text(a: &limpid_analysis::markers::MarkerConfiguration) -> String {
    let rotation = a.humeral_rotation_deg.map_or(
        "undefined (elbow straight or arm vertical)".to_string(),
        |r| format!("{r:.1} deg"),
    );
    let mut s = format!(
        "arm configuration from markers ({} samples): shoulder elevation {:.1} deg, azimuth {:.1} deg, humeral rotation {rotation}, elbow flexion {:.1} deg; upper arm {:.3} m, forearm {:.3} m (spread {:.1} mm)\n",
        a.samples, a.shoulder_elevation_deg, a.shoulder_azimuth_deg, a.elbow_flexion_deg, a.upper_arm_length_m, a.forearm_length_m, a.segment_length_spread_m * 1e3
    );
    for w in &a.warnings {
        s.push_str(&format!("warning: {w}\n"));
    }
    s
}

/// The tag printed after a matrix's heading.
pub(crate) fn verdict_flag(v: MatrixVerdict) -> &'static str {
    match v {
        MatrixVerdict::Trusted => "   [trusted]",
        MatrixVerdict::PoorFit => "   [NOT TRUSTED: the model misses most of the force]",
        MatrixVerdict::NotIdentifiable => "   [NOT IDENTIFIABLE: see warnings]",
        MatrixVerdict::NotPassive => "   [NOT PASSIVE: not positive definite]",
        MatrixVerdict::Imprecise => "   [IMPRECISE: 2 SE above the tolerance]",
    }
}
