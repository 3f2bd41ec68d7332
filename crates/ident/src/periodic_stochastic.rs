//! The stochastic estimate of a periodic excitation (issue 59: `estimate
//! stochastic --period S`): seed 004's layout (commanded inputs `u*`,
//! displacements, forces) with a multisine or PRBS command repeated for
//! whole periods.
//!
//! Averaged over whole periods, the spectra have no leakage and their
//! period-to-period scatter is the noise (`limpid_dsp::periodic`), so the
//! analytical compensation through the commands (Z = T R^-1, which needs
//! random, mutually incoherent inputs at every frequency) is not needed:
//! the period-averaged displacements carry little noise, and
//!
//! - M, B, K are fitted to the forces and displacements at the excited
//!   lines in the band ([`crate::periodic_fit`]), with standard errors from
//!   the period-to-period scatter and the verdicts of the periodic fit;
//! - the non-parametric Z is solved on groups of consecutive excited lines
//!   that hold a line of every input (zippered or randomly assigned
//!   multisines excite each line from one input): `Z = F X^+` over the
//!   group, at the group's mean frequency, each line's forces first moved
//!   to that frequency by the fitted model's change between the two (a
//!   group spans n lines or more; only that change across it is the
//!   model's, the rest is measured);
//! - coherences are the share of an output's per-period power that repeats
//!   from period to period: `Σ S / Σ (S + N)` over lines, S a line's
//!   unbiased mean power `|Ȳ|² - σ²_Ȳ`, N its per-period noise `m σ²_Ȳ`
//!   (what ordinary coherence measures for a periodic input); multiple:
//!   over the group's lines, partial on input i: over its lines excited by i;
//! - `max_input_coherence` is the largest power of another command at a
//!   command's excited line relative to that command's (0 for zippered
//!   lines; the analysis refuses a line two commands excite);
//! - the lines are classified by the commands, and the `periodic` block
//!   (excited and detection lines, distortion, the FRF force per command)
//!   is the one `spectra --period` gives with the commands as inputs. A
//!   recording without command columns (a position-controlled rig's, whose
//!   command is the displacement itself; `u*` are commanded forces in the
//!   format) has its displacements classify the lines (`inputs` then names
//!   them, and the FRF is force per displacement): each line must still be
//!   excited along one coordinate.

use limpid_core::{Error, Recording, Result, Warning, WarningCode};
use limpid_dsp::periodic::{analyse, PeriodSpectra, PeriodicAnalysis};
use nalgebra::DMatrix;
use num_complex::Complex64;

use crate::prepare::choose_coordinates;
use crate::spectra::{periodic_result, whole_periods, Periods};
use crate::stochastic::{
    band_below_nyquist, distance_to_fit, input_name, quality_warnings, re_im, Coherences,
    StochasticCriteria, StochasticEstimate,
};

/// The stochastic estimate of a periodic recording (module docs).
pub fn estimate_stochastic_periodic(
    rec: &Recording,
    period_s: f64,
    band_hz: (f64, f64),
) -> Result<StochasticEstimate> {
    let (coords, force_cols) = choose_coordinates(rec)?;
    let n = coords.len();
    // the commands classify the lines; a recording without any (a periodic
    // recording in the format's own columns) has its displacements do it
    let commands: Vec<String> = coords.iter().map(|c| input_name(c)).collect();
    let inputs = if commands.iter().any(|u| rec.has(u)) {
        for u in &commands {
            rec.require(
                u,
                "commanded perturbation (stochastic input) of each coordinate",
            )?;
        }
        commands
    } else {
        coords.clone()
    };
    let (lo, hi) = band_below_nyquist(band_hz, rec.sample_rate())?;
    let names: Vec<String> = inputs
        .iter()
        .chain(&coords)
        .chain(&force_cols)
        .cloned()
        .collect();
    let Periods {
        period,
        periods,
        transient,
        spectra,
        ..
    } = whole_periods(rec, &names, period_s)?;
    let signals = |from: std::ops::Range<usize>, to: std::ops::Range<usize>| -> Vec<usize> {
        from.chain(to).collect()
    };
    // lines classified by the commands; distortion of the forces and of the displacements
    let forces = spectra.select(&signals(0..n, 2 * n..3 * n));
    let analysis = analyse(&forces, n).map_err(|e| located(rec, e))?;
    let mut periodic = periodic_result(
        &analysis,
        &inputs,
        &force_cols,
        period_s,
        periods,
        transient,
    );
    let displacements = spectra.select(&signals(0..n, n..2 * n));
    periodic.input_distortion = analyse(&displacements, n)
        .ok()
        .and_then(|a| a.distortion)
        .as_ref()
        .map(crate::spectra::distortion_of);
    // the fit on the band's excited lines, displacements then forces
    let in_band = PeriodicAnalysis {
        responses: analysis
            .responses
            .iter()
            .filter(|r| (lo..=hi).contains(&(r.line as f64 / period_s)))
            .cloned()
            .collect(),
        ..analysis.clone()
    };
    let motion_and_force = spectra.select(&signals(n..2 * n, 2 * n..3 * n));
    let fitted = crate::periodic_fit::fit(
        &motion_and_force,
        &in_band,
        n,
        period_s,
        periodic.distorts_excited_lines(),
    )
    .ok_or_else(|| Error::Format {
        path: rec.path().to_path_buf(),
        message: format!(
            "{} excited line(s) in the {lo}-{hi} Hz band: the fit of M, B and K needs at least {} (3 per coordinate); widen --band",
            in_band.responses.len(),
            3 * n
        ),
    })?;
    // the non-parametric Z on groups of lines up to the band's upper edge
    let up_to_band: Vec<(usize, usize)> = analysis
        .responses
        .iter()
        .filter(|r| r.line as f64 / period_s <= hi)
        .map(|r| (r.line, r.input))
        .collect();
    let groups = line_groups(&up_to_band, n);
    let mut frequencies = Vec::with_capacity(groups.len());
    let mut impedance = Vec::with_capacity(groups.len());
    let mut multiple: Vec<Vec<f64>> = vec![Vec::new(); 2 * n];
    let mut partial: Vec<Vec<Vec<f64>>> = vec![vec![Vec::new(); n]; 2 * n];
    let mut singular_in_band = 0;
    let model = |hz: f64| -> DMatrix<Complex64> {
        let w = 2.0 * std::f64::consts::PI * hz;
        DMatrix::from_fn(n, n, |i, j| {
            Complex64::new(
                fitted.stiffness[(i, j)] - w * w * fitted.inertia[(i, j)],
                w * fitted.damping[(i, j)],
            )
        })
    };
    for group in &groups {
        let f = group.iter().map(|(l, _)| *l as f64).sum::<f64>() / group.len() as f64 / period_s;
        let Some(z) = group_impedance(&spectra, n, group, |line| {
            model(f) - model(line as f64 / period_s)
        }) else {
            if f >= lo {
                singular_in_band += 1;
            }
            continue;
        };
        frequencies.push(f);
        impedance.push(z);
        for (o, m) in multiple.iter_mut().enumerate() {
            let s = n + o;
            m.push(repeatable_share(&spectra, s, group.iter().map(|(l, _)| *l)));
            for (i, p) in partial[o].iter_mut().enumerate() {
                let own = group.iter().filter(|(_, g)| *g == i).map(|(l, _)| *l);
                p.push(repeatable_share(&spectra, s, own));
            }
        }
    }
    let band: Vec<usize> = (0..frequencies.len())
        .filter(|&k| frequencies[k] >= lo && frequencies[k] <= hi)
        .collect();
    let lowest: Vec<f64> = (0..frequencies.len())
        .map(|k| multiple.iter().map(|m| m[k]).fold(1.0, f64::min))
        .collect();
    let (mean_coh, min_coh) = if band.is_empty() {
        (0.0, 0.0)
    } else {
        (
            band.iter().map(|&k| lowest[k]).sum::<f64>() / band.len() as f64,
            band.iter().map(|&k| lowest[k]).fold(1.0, f64::min),
        )
    };
    let max_input_coherence = input_coherence(&spectra, n, &analysis);
    let phi_t_vs_fit = if band.is_empty() {
        0.0
    } else {
        distance_to_fit(
            &impedance,
            &frequencies,
            &band,
            [&fitted.inertia, &fitted.damping, &fitted.stiffness],
        )
    };
    let mut warnings = quality_warnings(min_coh, singular_in_band, max_input_coherence);
    if periodic.distorts_excited_lines() {
        warnings.push(Warning::new(
            WarningCode::PoorFit,
            "the detection lines show distortion that reaches the excited lines: M, B, K are the best linear approximation at this amplitude, not the limb's linear impedance",
        ));
    }
    for c in &coords {
        if let (Some(kind), Some(values)) = (crate::units::Coordinate::of_name(c), rec.column(c)) {
            warnings.extend(crate::units::implausible_motion(
                c,
                kind,
                crate::units::range(values),
            ));
        }
    }
    let outputs: Vec<String> = coords.iter().chain(&force_cols).cloned().collect();
    let criteria = StochasticCriteria {
        band_hz: [lo, hi],
        frequency_resolution_hz: 1.0 / period_s,
        segments: periods,
        nperseg: period,
        mean_multiple_coherence: mean_coh,
        min_multiple_coherence: min_coh,
        max_input_coherence,
        phi_t_vs_fit,
        fit_vaf: fitted.fit_vaf,
        verdicts: fitted.verdicts,
    };
    let estimate = StochasticEstimate {
        coordinates: coords,
        inputs,
        frequencies,
        impedance: impedance.iter().map(re_im).collect(),
        coherence: Coherences {
            outputs,
            multiple,
            partial,
        },
        inertia: fitted.inertia.clone(),
        damping: fitted.damping.clone(),
        stiffness: fitted.stiffness.clone(),
        standard_errors: fitted.standard_errors.clone(),
        criteria,
        accuracy: None,
        warnings,
        periodic: None,
    };
    periodic.impedance = Some(fitted);
    Ok(StochasticEstimate {
        periodic: Some(periodic),
        ..estimate
    })
}

fn located(rec: &Recording, e: Error) -> Error {
    Error::Format {
        path: rec.path().to_path_buf(),
        message: e.to_string(),
    }
}

/// Consecutive excited lines `(line, input)` in groups that hold a line of
/// every one of `inputs` inputs (a trailing group without one is dropped).
fn line_groups(lines: &[(usize, usize)], inputs: usize) -> Vec<Vec<(usize, usize)>> {
    let mut groups = Vec::new();
    let mut group: Vec<(usize, usize)> = Vec::new();
    for &(line, input) in lines {
        group.push((line, input));
        if (0..inputs).all(|i| group.iter().any(|(_, g)| *g == i)) {
            groups.push(std::mem::take(&mut group));
        }
    }
    groups
}

/// `Z = F X^+` over a group's lines (the period-averaged displacements and
/// forces, signals `n..2n` and `2n..3n`), each line's forces first moved
/// to the group's frequency by `shift(line) X` (the fitted model's change
/// from the line to the group: without it each column of Z would be read at
/// its own input's line, up to a group's span away); `None` where `X X^H`
/// is singular.
fn group_impedance(
    spectra: &PeriodSpectra,
    n: usize,
    group: &[(usize, usize)],
    shift: impl Fn(usize) -> DMatrix<Complex64>,
) -> Option<DMatrix<Complex64>> {
    let columns = group.len();
    let x = DMatrix::from_fn(n, columns, |i, c| spectra.mean[n + i][group[c].0]);
    let mut f = DMatrix::from_fn(n, columns, |i, c| spectra.mean[2 * n + i][group[c].0]);
    for (c, (line, _)) in group.iter().enumerate() {
        let moved = shift(*line) * x.column(c);
        let mut column = f.column_mut(c);
        column += moved;
    }
    let xh = x.adjoint();
    let gram = &x * &xh;
    // a displacement matrix whose smallest direction is lost in rounding carries no Z
    let singular = gram.clone().singular_values();
    let (largest, smallest) = (singular.max(), singular.min());
    if !(largest > 0.0 && smallest > 1e-12 * largest) {
        return None;
    }
    let inverse = gram.try_inverse()?;
    Some(f * xh * inverse)
}

/// The share of signal `s`'s per-period power at `lines` that repeats from
/// period to period, `Σ S / Σ (S + N)` over the lines (module docs): the
/// power-weighted coherence, so a line where the signal is only noise
/// counts for its little power.
fn repeatable_share(spectra: &PeriodSpectra, s: usize, lines: impl Iterator<Item = usize>) -> f64 {
    let m = spectra.periods as f64;
    let (mut signal, mut total) = (0.0, 0.0);
    for line in lines {
        let variance = spectra.variance_of_mean(s, line);
        let power = (spectra.mean[s][line].norm_sqr() - variance).max(0.0);
        signal += power;
        total += power + m * variance;
    }
    if total > 0.0 {
        signal / total
    } else {
        0.0
    }
}

/// The largest power of another command at a command's excited line,
/// relative to that command's: the periodic analysis refuses lines that two
/// commands excite (within 30 dB), so this is at most 0.001, and 0 for
/// zippered commands. (The ordinary coherence of two deterministic periodic
/// signals is 1 at any line both carry, however little: it says nothing here.)
fn input_coherence(spectra: &PeriodSpectra, n: usize, analysis: &PeriodicAnalysis) -> f64 {
    let mut largest = 0.0f64;
    for r in &analysis.responses {
        let own = spectra.mean[r.input][r.line].norm_sqr();
        for other in (0..n).filter(|&j| j != r.input) {
            if own > 0.0 {
                largest = largest.max(spectra.mean[other][r.line].norm_sqr() / own);
            }
        }
    }
    largest
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_close_once_every_input_has_a_line() {
        let lines = [
            (3, 0),
            (5, 0),
            (7, 1),
            (9, 2),
            (11, 1),
            (13, 0),
            (15, 2),
            (17, 0),
        ];
        let groups = line_groups(&lines, 3);
        assert_eq!(
            groups,
            vec![
                vec![(3, 0), (5, 0), (7, 1), (9, 2)],
                vec![(11, 1), (13, 0), (15, 2)],
            ]
        );
        assert!(line_groups(&lines, 4).is_empty());
    }
}
