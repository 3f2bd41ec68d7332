//! The shapes a result document must have before anything indexes it.
//!
//! serde checks each field's type; it cannot check that fields agree with
//! each other (an impedance row one entry short, a coherence list for fewer
//! outputs than the result has, a 1000-row inertia beside 3 coordinates).
//! The report indexed such documents and crashed (issue 36); a document read
//! back is now checked here first, and a disagreement is one line naming the
//! field. Every kind the report draws from arrays is checked; kinds without
//! such arrays pass.

use limpid_core::Matrix;

use crate::cocontraction::CocontractionResult;
use crate::linear::LinearResult;
use crate::result::Estimate;
use limpid_ident::planar::PlanarEstimate;

/// `Err(field: what is wrong)` for the first disagreement in `e`.
pub fn check(e: &Estimate) -> Result<(), String> {
    match e {
        Estimate::Linear(r) => linear("", r),
        Estimate::Cocontraction(c) => cocontraction("", c),
        Estimate::Stochastic(s) => stochastic(s),
        Estimate::Spectra(s) => spectra(s),
        Estimate::Planar(p) => planar("", p),
        Estimate::WindowSweep(w) => window_sweep(w),
        Estimate::Study(st) => study(st),
        Estimate::Demo(d) => demo(d),
        Estimate::Reflex(r) => reflex(r),
        Estimate::Varying(v) => varying(v),
        Estimate::Calibration(c) => calibration(c),
        Estimate::Design(d) => design(d),
        // scalars and a protocol: nothing to fit together
        Estimate::ReflexDesign(_) => Ok(()),
        Estimate::PlanarDesign(d) => planar_design(d),
    }
}

/// A prediction's and its baseline's matrices have the method's `shapes`
/// (rows, columns) of K, B (D), M (ξ).
fn predictions(
    predicted: &crate::result::design::Prediction,
    baseline: Option<&crate::result::design::Prediction>,
    shapes: [(usize, usize); 3],
) -> Result<(), String> {
    for (name, p) in
        std::iter::once(("predicted", predicted)).chain(baseline.map(|b| ("baseline", b)))
    {
        for ((field, m), (rows, columns)) in [
            ("stiffness_se", &p.stiffness_se),
            ("damping_se", &p.damping_se),
            ("inertia_se", &p.inertia_se),
        ]
        .into_iter()
        .zip(shapes)
        {
            same(
                &format!("{name}.{field} rows"),
                m.0.nrows(),
                rows,
                "the method's rows",
            )?;
            same(
                &format!("{name}.{field} columns"),
                m.0.ncols(),
                columns,
                "the method's columns",
            )?;
        }
    }
    Ok(())
}

/// Every trace spans its `times` (`what`), every spectrum its frequencies.
fn spanning<'a>(
    times: (&str, usize),
    series: impl IntoIterator<Item = (&'a str, &'a Vec<f64>)>,
) -> Result<(), String> {
    for (field, v) in series {
        same(field, v.len(), times.1, times.0)?;
    }
    Ok(())
}

/// A design's matrices are 3 x 3 (the prediction, the baseline's).
fn design(d: &crate::result::design::DesignResult) -> Result<(), String> {
    predictions(&d.predicted, d.baseline.as_ref(), [(3, 3); 3])?;
    let c = &d.command;
    spanning(
        ("command.t_s", c.t_s.len()),
        [
            ("command.displacement_m", &c.displacement_m),
            ("command.velocity_m_s", &c.velocity_m_s),
            ("command.acceleration_m_s2", &c.acceleration_m_s2),
        ],
    )?;
    let s = &d.spectrum;
    spanning(
        ("spectrum.frequency_hz", s.frequency_hz.len()),
        [
            ("spectrum.designed_m", &s.designed_m),
            ("spectrum.limit_m", &s.limit_m),
        ]
        .into_iter()
        .chain(s.baseline_m.iter().map(|v| ("spectrum.baseline_m", v))),
    )
}

/// A planar design's K and D are 2 x 2, its ξ one row of 3.
fn planar_design(d: &crate::result::design::PlanarDesignResult) -> Result<(), String> {
    predictions(&d.predicted, d.baseline.as_ref(), [(2, 2), (2, 2), (1, 3)])?;
    let c = &d.command;
    spanning(
        ("command.t_s", c.t_s.len()),
        [
            ("command.displacement_rad", &c.displacement_rad),
            ("command.velocity_rad_s", &c.velocity_rad_s),
            ("command.acceleration_rad_s2", &c.acceleration_rad_s2),
        ],
    )?;
    let s = &d.spectrum;
    spanning(
        ("spectrum.frequency_hz", s.frequency_hz.len()),
        [
            ("spectrum.designed_rad", &s.designed_rad),
            ("spectrum.limit_rad", &s.limit_rad),
        ]
        .into_iter()
        .chain(s.baseline_rad.iter().map(|v| ("spectrum.baseline_rad", v))),
    )
}

/// Every spectrum, coherence and matrix agrees with the frequencies, coordinates and inputs.
fn stochastic(s: &limpid_ident::stochastic::StochasticEstimate) -> Result<(), String> {
    let (nf, no, ni) = (s.frequencies.len(), s.coordinates.len(), s.inputs.len());
    same("impedance", s.impedance.len(), nf, "frequencies")?;
    for (f, rows) in s.impedance.iter().enumerate() {
        same(&format!("impedance[{f}]"), rows.len(), no, "coordinates")?;
        for (o, row) in rows.iter().enumerate() {
            same(&format!("impedance[{f}][{o}]"), row.len(), ni, "inputs")?;
        }
    }
    let c = &s.coherence;
    same(
        "coherence.multiple",
        c.multiple.len(),
        c.outputs.len(),
        "coherence.outputs",
    )?;
    same(
        "coherence.partial",
        c.partial.len(),
        c.outputs.len(),
        "coherence.outputs",
    )?;
    for (o, m) in c.multiple.iter().enumerate() {
        same(
            &format!("coherence.multiple[{o}]"),
            m.len(),
            nf,
            "frequencies",
        )?;
    }
    for (o, p) in c.partial.iter().enumerate() {
        same(&format!("coherence.partial[{o}]"), p.len(), ni, "inputs")?;
        for (i, q) in p.iter().enumerate() {
            same(
                &format!("coherence.partial[{o}][{i}]"),
                q.len(),
                nf,
                "frequencies",
            )?;
        }
    }
    for (name, m) in [
        ("inertia", &s.inertia),
        ("damping", &s.damping),
        ("stiffness", &s.stiffness),
        ("standard_errors.inertia", &s.standard_errors.inertia),
        ("standard_errors.damping", &s.standard_errors.damping),
        ("standard_errors.stiffness", &s.standard_errors.stiffness),
    ] {
        square(name, m, no)?;
    }
    if let Some(p) = &s.periodic {
        periodic(p, no)?;
    }
    Ok(())
}

/// The findings, and every window's and interval's planar estimate.
fn window_sweep(w: &limpid_ident::planar::Sweep) -> Result<(), String> {
    sweep_findings(w)?;
    for (i, row) in w.rows.iter().enumerate() {
        planar(&format!("rows[{i}].estimate."), &row.estimate)?;
    }
    for (i, row) in w.intervals.iter().enumerate() {
        planar(&format!("intervals[{i}].estimate."), &row.estimate)?;
    }
    Ok(())
}

/// Every level's stiffness and ellipsoid, and every recording's result.
fn study(st: &crate::result::study::StudyResult) -> Result<(), String> {
    for (i, l) in st.levels.iter().enumerate() {
        let d = l.stiffness.0.nrows();
        square(&format!("levels[{i}].stiffness"), &l.stiffness, d)?;
        if let Some(e) = &l.ellipsoid {
            ellipsoid(&format!("levels[{i}].ellipsoid"), e, d)?;
        }
    }
    for (i, r) in st.recordings.iter().enumerate() {
        cocontraction(&format!("recordings[{i}].result."), &r.result)?;
    }
    Ok(())
}

/// Every point's estimate and its truths.
fn demo(d: &crate::result::demo::DemoResult) -> Result<(), String> {
    let points = d
        .points
        .iter()
        .enumerate()
        .map(|(i, p)| (format!("points[{i}]"), p));
    let designed = d
        .designed
        .iter()
        .map(|x| ("designed.point".to_string(), &x.point));
    for (at, p) in points.chain(designed) {
        linear(&format!("{at}.estimate."), &p.estimate)?;
        let n = p.estimate.stiffness.0.nrows();
        for (name, m) in [
            ("true_stiffness", &p.true_stiffness),
            ("true_damping", &p.true_damping),
            ("true_inertia", &p.true_inertia),
        ] {
            square(&format!("{at}.{name}"), m, n)?;
        }
    }
    Ok(())
}

/// Each IRF's values span its lags.
fn reflex(r: &limpid_ident::reflex::ReflexEstimate) -> Result<(), String> {
    for (name, irf) in [
        ("intrinsic.irf", &r.intrinsic.irf),
        ("reflex.irf", &r.reflex.irf),
    ] {
        same(
            &format!("{name}.values"),
            irf.values.len(),
            irf.lags_s.len(),
            &format!("{name}.lags_s"),
        )?;
    }
    Ok(())
}

/// A point per schedule value, and every point's matrices square in the coordinates.
fn varying(v: &limpid_ident::varying::VaryingEstimate) -> Result<(), String> {
    same(
        "schedule.values",
        v.schedule.values.len(),
        v.points.len(),
        "points",
    )?;
    let d = v.coordinates.len();
    for (i, p) in v.points.iter().enumerate() {
        for (name, m) in [
            ("stiffness", &p.stiffness),
            ("stiffness_se", &p.stiffness_se),
            ("damping", &p.damping),
            ("damping_se", &p.damping_se),
            ("inertia", &p.inertia),
            ("inertia_se", &p.inertia_se),
        ] {
            if let Some(m) = m {
                square(&format!("points[{i}].{name}"), m, d)?;
            }
        }
    }
    Ok(())
}

/// The window-sweep counts agree.
fn calibration(c: &crate::result::calibration::Calibration) -> Result<(), String> {
    sweep_counts("window_sweep", &c.window_sweep)?;
    match &c.window_sweep_varied {
        Some(w) => sweep_counts("window_sweep_varied", w),
        None => Ok(()),
    }
}

/// Every spectrum and coherence spans the frequencies, per signal, output and input.
fn spectra(s: &limpid_ident::spectra::SpectraResult) -> Result<(), String> {
    let (nf, ni, no) = (s.frequencies.len(), s.inputs.len(), s.outputs.len());
    same("signals", s.signals.len(), ni + no, "inputs and outputs")?;
    same("psd", s.psd.len(), ni + no, "signals")?;
    for (i, p) in s.psd.iter().enumerate() {
        same(&format!("psd[{i}]"), p.len(), nf, "frequencies")?;
    }
    same(
        "multiple_coherence",
        s.multiple_coherence.len(),
        no,
        "outputs",
    )?;
    for (o, m) in s.multiple_coherence.iter().enumerate() {
        same(
            &format!("multiple_coherence[{o}]"),
            m.len(),
            nf,
            "frequencies",
        )?;
    }
    for (name, c) in [
        (
            "coherence",
            s.coherence
                .iter()
                .map(|o| o.iter().map(Vec::len).collect())
                .collect::<Vec<Vec<usize>>>(),
        ),
        (
            "partial_coherence",
            s.partial_coherence
                .iter()
                .map(|o| o.iter().map(Vec::len).collect())
                .collect(),
        ),
    ] {
        same(name, c.len(), no, "outputs")?;
        for (o, inputs) in c.iter().enumerate() {
            same(&format!("{name}[{o}]"), inputs.len(), ni, "inputs")?;
            for (i, len) in inputs.iter().enumerate() {
                same(&format!("{name}[{o}][{i}]"), *len, nf, "frequencies")?;
            }
        }
    }
    if let Some(p) = &s.periodic {
        periodic(p, ni)?;
    }
    Ok(())
}

/// Each pair's response arrays along its lines; M, B, K square in the inputs.
fn periodic(p: &limpid_ident::spectra::PeriodicResult, ni: usize) -> Result<(), String> {
    for (k, f) in p.frf.iter().enumerate() {
        let n = f.frequency_hz.len();
        for (name, len) in [
            ("magnitude", f.magnitude.len()),
            ("magnitude_se", f.magnitude_se.len()),
            ("phase_deg", f.phase_deg.len()),
            ("phase_se_deg", f.phase_se_deg.len()),
        ] {
            same(&format!("periodic.frf[{k}].{name}"), len, n, "frequency_hz")?;
        }
    }
    if let Some(z) = &p.impedance {
        let e = &z.standard_errors;
        for (name, m) in [
            ("inertia", &z.inertia),
            ("damping", &z.damping),
            ("stiffness", &z.stiffness),
            ("standard_errors.inertia", &e.inertia),
            ("standard_errors.damping", &e.damping),
            ("standard_errors.stiffness", &e.stiffness),
        ] {
            square(&format!("periodic.impedance.{name}"), m, ni)?;
        }
    }
    Ok(())
}

/// The counts of a set of window sweeps are parts of their wholes.
fn sweep_counts(at: &str, w: &crate::result::calibration::SweepCalibration) -> Result<(), String> {
    let without = w.without_reflex();
    for (name, part, whole, of) in [
        ("with_reflex", w.with_reflex, w.sweeps, "sweeps"),
        ("endpoint_sweeps", w.endpoint_sweeps, w.sweeps, "sweeps"),
        ("cuff_sweeps", w.cuff_sweeps, w.sweeps, "sweeps"),
        (
            "changes_claimed[0]",
            w.changes_claimed[0],
            without,
            "sweeps without a reflex",
        ),
        (
            "changes_claimed[1]",
            w.changes_claimed[1],
            w.with_reflex,
            "with_reflex",
        ),
        (
            "cuff_with_reflex",
            w.cuff_with_reflex,
            w.cuff_sweeps,
            "cuff_sweeps",
        ),
        (
            "cuff_with_reflex",
            w.cuff_with_reflex,
            w.with_reflex,
            "with_reflex",
        ),
        (
            "cuff_changes_claimed[0]",
            w.cuff_changes_claimed[0],
            w.changes_claimed[0],
            "changes_claimed[0]",
        ),
        (
            "cuff_changes_claimed[1]",
            w.cuff_changes_claimed[1],
            w.changes_claimed[1],
            "changes_claimed[1]",
        ),
        (
            "tissue_named[0]",
            w.tissue_named[0],
            w.changes_claimed[0],
            "changes_claimed[0]",
        ),
        (
            "tissue_named[1]",
            w.tissue_named[1],
            w.changes_claimed[1],
            "changes_claimed[1]",
        ),
        (
            "sweeps_with_a_trusted_window[0]",
            w.sweeps_with_a_trusted_window[0],
            without,
            "sweeps without a reflex",
        ),
        (
            "sweeps_with_a_trusted_window[1]",
            w.sweeps_with_a_trusted_window[1],
            w.with_reflex,
            "with_reflex",
        ),
        (
            "trusted_but_wrong",
            w.trusted_but_wrong,
            w.trusted_windows,
            "trusted_windows",
        ),
    ] {
        if part > whole {
            return Err(format!("{at}.{name}: {part}, more than the {whole} {of}"));
        }
    }
    Ok(())
}

fn cocontraction(at0: &str, c: &CocontractionResult) -> Result<(), String> {
    for (i, l) in c.levels.iter().enumerate() {
        let at = format!("{at0}levels[{i}].");
        linear(&format!("{at}estimate."), &l.estimate)?;
        let d = l.estimate.stiffness.0.nrows();
        for (name, m) in [
            ("stiffness", &l.stiffness),
            ("damping", &l.damping),
            ("inertia", &l.inertia),
        ] {
            square(&format!("{at}{name}"), m, d)?;
        }
        if let Some(e) = &l.ellipsoid {
            ellipsoid(&format!("{at}ellipsoid"), e, d)?;
        }
    }
    for (i, c) in c.comparisons.iter().enumerate() {
        let n = c.principal_change_percent.len();
        for (name, len) in [
            ("rotation_deg", c.rotation_deg.len()),
            ("ambiguous", c.ambiguous.len()),
        ] {
            same(
                &format!("{at0}comparisons[{i}].{name}"),
                len,
                n,
                "principal_change_percent",
            )?;
        }
    }
    Ok(())
}

fn planar(at: &str, p: &PlanarEstimate) -> Result<(), String> {
    for (name, m) in [
        ("stiffness", &p.stiffness),
        ("damping", &p.damping),
        ("endpoint_stiffness", &p.endpoint_stiffness),
        ("standard_errors.stiffness", &p.standard_errors.stiffness),
        ("standard_errors.damping", &p.standard_errors.damping),
    ] {
        square(&format!("{at}{name}"), m, 2)?;
    }
    if let Some(t) = &p.traces {
        traces(&format!("{at}traces"), t, 2)?;
    }
    Ok(())
}

fn linear(at: &str, r: &LinearResult) -> Result<(), String> {
    let d = r.stiffness.0.nrows();
    for (name, m) in [
        ("stiffness", &r.stiffness),
        ("damping", &r.damping),
        ("inertia", &r.inertia),
        ("standard_errors.stiffness", &r.standard_errors.stiffness),
        ("standard_errors.damping", &r.standard_errors.damping),
        ("standard_errors.inertia", &r.standard_errors.inertia),
        ("symmetric.stiffness", &r.symmetric.stiffness),
        ("symmetric.damping", &r.symmetric.damping),
        ("symmetric.inertia", &r.symmetric.inertia),
        ("antisymmetric.stiffness", &r.antisymmetric.stiffness),
        ("antisymmetric.damping", &r.antisymmetric.damping),
        ("antisymmetric.inertia", &r.antisymmetric.inertia),
    ] {
        square(&format!("{at}{name}"), m, d)?;
    }
    // the tables label rows and columns from the provenance (issue 56: a
    // 3x3 result naming 1 coordinate crashed the report)
    for (name, len) in [
        ("provenance.coordinates", r.provenance.coordinates.len()),
        ("provenance.force_columns", r.provenance.force_columns.len()),
        (
            "criteria.regressor_reliability",
            r.criteria.regressor_reliability.len(),
        ),
    ] {
        same(&format!("{at}{name}"), len, d, "the matrices' rows")?;
    }
    if let Some(eq) = &r.equilibrium {
        same(&format!("{at}equilibrium"), eq.len(), d, "coordinates")?;
    }
    for (name, len) in [
        ("fit.r", r.fit.r.len()),
        ("fit.vaf", r.fit.vaf.len()),
        ("fit.rmse", r.fit.rmse.len()),
    ] {
        same(&format!("{at}{name}"), len, d, "coordinates")?;
    }
    for (name, e) in [
        ("stiffness", &r.ellipsoids.stiffness),
        ("damping", &r.ellipsoids.damping),
        ("inertia", &r.ellipsoids.inertia),
    ] {
        if let Some(e) = e {
            ellipsoid(&format!("{at}ellipsoids.{name}"), e, d)?;
        }
    }
    traces(&format!("{at}fit.traces"), &r.fit.traces, d)
}

/// An ellipsoid's lists have one entry per axis, and its axes are a
/// rotation: unit columns at right angles (the report draws with them; a
/// hand-edited axis of 1e307 drew NaN coordinates).
fn ellipsoid(name: &str, e: &crate::Ellipsoid, d: usize) -> Result<(), String> {
    square(&format!("{name}.axes"), &e.axes, d)?;
    same(
        &format!("{name}.eigenvalues"),
        e.eigenvalues.len(),
        d,
        "axes",
    )?;
    same(
        &format!("{name}.radii_proportional"),
        e.radii_proportional.len(),
        d,
        "axes",
    )?;
    if let Some(r) = &e.radii_inverse_sqrt {
        same(&format!("{name}.radii_inverse_sqrt"), r.len(), d, "axes")?;
    }
    let a = &e.axes.0;
    let gram = a.transpose() * a;
    let off = (0..d)
        .flat_map(|i| (0..d).map(move |j| (i, j)))
        .map(|(i, j)| (gram[(i, j)] - if i == j { 1.0 } else { 0.0 }).abs())
        .fold(0.0, f64::max);
    if off.is_nan() || off > 1e-6 {
        return Err(format!(
            "{name}.axes: not a rotation (its columns must be unit vectors at right angles)"
        ));
    }
    Ok(())
}

fn traces(at: &str, t: &limpid_ident::linear::FitTraces, d: usize) -> Result<(), String> {
    for (name, series) in [("measured", &t.measured), ("predicted", &t.predicted)] {
        // absent traces (a study's compact results) are an empty list
        if series.is_empty() {
            continue;
        }
        same(&format!("{at}.{name}"), series.len(), d, "coordinates")?;
        for (k, s) in series.iter().enumerate() {
            same(&format!("{at}.{name}[{k}]"), s.len(), t.time.len(), "time")?;
        }
    }
    Ok(())
}

fn square(name: &str, m: &Matrix, d: usize) -> Result<(), String> {
    let (r, c) = m.0.shape();
    if r == d && c == d {
        Ok(())
    } else {
        Err(format!(
            "{name}: {r} x {c}, expected {d} x {d} (one row and column per coordinate)"
        ))
    }
}

/// The change scan's and the tissue fit's numbers where a reader takes them
/// as they are: a probability outside [0, 1] or a negative time would be
/// printed unquestioned.
fn sweep_findings(w: &limpid_ident::planar::Sweep) -> Result<(), String> {
    if let Some(c) = &w.impedance_change {
        for (name, v) in [
            ("onset_ms", c.onset_ms),
            ("significant_from_ms", c.significant_from_ms),
            ("stiffness_change", c.stiffness_change),
            ("damping_change", c.damping_change),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!(
                    "impedance_change.{name}: {v}, expected a finite value >= 0"
                ));
            }
        }
        if !(0.0..=1.0).contains(&c.p_value) {
            return Err(format!(
                "impedance_change.p_value: {}, expected a probability in [0, 1]",
                c.p_value
            ));
        }
        if c.z.is_nan() {
            return Err("impedance_change.z: NaN, expected a number".into());
        }
    }
    if let Some(t) = &w.series_compliance {
        for (name, v) in [
            ("time_constant_s", t.time_constant_s),
            ("residual_ratio", t.residual_ratio),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!(
                    "series_compliance.{name}: {v}, expected a finite value >= 0"
                ));
            }
        }
        if t.compliance.iter().flatten().any(|v| !v.is_finite()) {
            return Err("series_compliance.compliance: a value is not finite".into());
        }
    }
    Ok(())
}

fn same(name: &str, len: usize, want: usize, of: &str) -> Result<(), String> {
    if len == want {
        Ok(())
    } else {
        Err(format!(
            "{name}: {len} entries, expected {want} (one per entry of {of})"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::result::calibration::SweepCalibration;

    fn sweeps() -> SweepCalibration {
        SweepCalibration {
            sweeps: 10,
            with_reflex: 4,
            trusted_windows: 50,
            trusted_but_wrong: 1,
            correct_windows: 60,
            sweeps_with_a_trusted_window: [5, 0],
            endpoint_sweeps: 5,
            cuff_sweeps: 2,
            changes_claimed: [6, 4],
            cuff_with_reflex: 1,
            cuff_changes_claimed: [1, 1],
            tissue_named: [1, 0],
            refused: 0,
            seconds: 1.0,
        }
    }

    #[test]
    fn sweep_counts_larger_than_their_wholes_are_named() {
        assert_eq!(sweep_counts("w", &sweeps()), Ok(()));
        let mut w = sweeps();
        w.with_reflex = 11;
        assert_eq!(
            sweep_counts("w", &w).unwrap_err(),
            "w.with_reflex: 11, more than the 10 sweeps"
        );
        let mut w = sweeps();
        w.changes_claimed[0] = 7;
        assert_eq!(
            sweep_counts("w", &w).unwrap_err(),
            "w.changes_claimed[0]: 7, more than the 6 sweeps without a reflex"
        );
        let mut w = sweeps();
        w.tissue_named[1] = 5;
        assert_eq!(
            sweep_counts("w", &w).unwrap_err(),
            "w.tissue_named[1]: 5, more than the 4 changes_claimed[1]"
        );
        let mut w = sweeps();
        w.trusted_but_wrong = 51;
        assert!(sweep_counts("w", &w)
            .unwrap_err()
            .contains("trusted_windows"));
    }
}
