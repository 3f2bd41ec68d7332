//! Cutting a recording into windows: trial columns, onsets found from the
//! motion, or continuous holds; condition levels; fitted or rest offsets.

use super::{Offsets, PrepareParams, Windowing, AUTO_FIT_ABOVE_S};
use limpid_core::trial::{
    change_floors, detect_windows, perturbation_onset, windows_from_trial_column,
};
use limpid_core::{Error, Recording, Result, Window};
use rayon::prelude::*;
/// Keep only the windows whose samples all carry `level` (seed 001's
/// condition label); an error listing the levels present when none does.
pub(super) fn keep_level(rec: &Recording, windows: &mut Vec<Window>, level: f64) -> Result<()> {
    let levels = rec.require("level", "selecting windows by --level")?;
    windows.retain(|w| {
        levels[w.range.clone()]
            .iter()
            .all(|l| (l - level).abs() < 1e-9)
    });
    if windows.is_empty() {
        let mut found: Vec<f64> = levels.to_vec();
        found.sort_by(f64::total_cmp);
        found.dedup();
        return Err(Error::invalid(
            "level",
            format!("no window has level {level} throughout; levels present: {found:?}"),
        ));
    }
    Ok(())
}

/// Whether each window's force offset is fitted (demeaned) rather than
/// taken from its rest: `auto` fits when the median window lasts over
/// [`AUTO_FIT_ABOVE_S`] (slow drift then dominates the rest mean).
pub(super) fn fits_offsets(offsets: Offsets, windows: &[Window], fs: f64) -> bool {
    match offsets {
        Offsets::Fit => true,
        Offsets::Rest => false,
        Offsets::Auto => {
            let mut lengths: Vec<usize> = windows.iter().map(|w| w.range.len()).collect();
            lengths.sort_unstable();
            lengths[lengths.len() / 2] as f64 / fs > AUTO_FIT_ABOVE_S
        }
    }
}

/// `params.windowing` with `Auto` decided: trial windows when the recording
/// has the trial column, else one continuous window.
pub(super) fn resolved_windowing(rec: &Recording, params: &PrepareParams) -> Windowing {
    match params.windowing {
        Windowing::Auto if rec.has(&params.trial_column) => Windowing::Trials,
        Windowing::Auto => Windowing::Continuous,
        other => other,
    }
}

/// The longest a force may lead the motion and still mark a trial's onset
/// (s): slow ramps (Artemiadis et al.'s cubic) move the force well before the
/// displacement leaves its noise band; a force that leaves rest earlier than
/// this is a drifting or coarse sensor (issue 37: 1-2 of 200 calibration
/// recordings refused, "no rest before its perturbation onset").
pub const FORCE_LEAD_S: f64 = 0.2;

/// Windows of a [`resolved_windowing`] `mode`; `force_noise` is needed (and
/// given) only for trial windows.
pub(super) fn make_windows(
    rec: &Recording,
    mode: Windowing,
    trial_column: &str,
    (pos, frc): (&[&[f64]], &[&[f64]]),
    (position_noise, force_noise): (&[f64], &[f64]),
    min_rest: usize,
) -> Result<Vec<Window>> {
    let continuous = || {
        vec![Window {
            id: 1,
            range: 0..rec.len(),
            onset: None,
        }]
    };
    match mode {
        Windowing::Continuous => Ok(continuous()),
        Windowing::ContinuousTrials => windows_from_trial_column(rec, trial_column),
        Windowing::Trials => {
            // onset: the earlier of motion and force change (a step in acceleration
            // moves the force before the displacement rises above the noise),
            // unless the force leads by more than FORCE_LEAD_S (a drifting or
            // coarse force sensor at rest: the motion decides)
            let lead_max = (FORCE_LEAD_S * rec.sample_rate()).round() as usize;
            let signals: Vec<&[f64]> = pos.iter().chain(frc).copied().collect();
            let floors: Vec<f64> = signals.par_iter().map(|c| change_floors(&[c])[0]).collect();
            let mut windows = windows_from_trial_column(rec, trial_column)?;
            let force_rest =
                force_rest_spread(&windows, pos, frc, position_noise, &floors, min_rest);
            let sigmas: Vec<f64> = position_noise
                .iter()
                .copied()
                .chain(force_noise.iter().zip(&force_rest).map(|(a, b)| a.max(*b)))
                .collect();
            // trials in parallel; the first trial without rest (in order) is the error
            let onsets: Vec<usize> = windows
                .par_iter()
                .map(|w| {
                    perturbation_onset(
                        &signals,
                        pos.len(),
                        w.range.clone(),
                        &sigmas,
                        &floors,
                        (lead_max, min_rest),
                    )
                    .unwrap_or(w.range.end)
                })
                .collect();
            for (w, onset) in windows.iter_mut().zip(onsets) {
                let rest = onset - w.range.start;
                if rest < min_rest {
                    return Err(Error::NoRestBeforeOnset {
                        path: rec.path().to_path_buf(),
                        row: rec.row_of(w.range.start),
                        column: trial_column.to_string(),
                        trial: w.id,
                        rest_samples: rest,
                        needed: min_rest,
                    });
                }
                // leave a guard of 2 samples between rest and detected motion
                w.onset = Some(onset.saturating_sub(2).max(w.range.start + 1));
            }
            Ok(windows)
        }
        // Auto is resolved before; it cannot reach here
        Windowing::Onsets | Windowing::Auto => {
            let found = detect_windows(pos, min_rest);
            if found.is_empty() {
                return Err(Error::Format {
                    path: rec.path().to_path_buf(),
                    message: "no perturbation onsets found (need at least two rests at the start position followed by motion); use continuous windowing".into(),
                });
            }
            Ok(found)
        }
    }
}

/// Per force, the median over the trials of its standard deviation before
/// the motion leaves rest (issue 58): a force at rest moves by more than its
/// sensor's white noise — physiological tremor at 8-12 Hz, slow
/// fluctuation — and second differences barely see an oscillation that slow
/// (0.3 N of tremor put the onset 7 samples into a 25-sample rest). The
/// first half of the samples before the motion is detected (the
/// perturbation's force leads the displacement's detection); trials with
/// fewer than `min_rest` samples there add nothing.
fn force_rest_spread(
    windows: &[Window],
    pos: &[&[f64]],
    frc: &[&[f64]],
    position_noise: &[f64],
    floors: &[f64],
    min_rest: usize,
) -> Vec<f64> {
    let motion_onsets: Vec<Option<usize>> = windows
        .par_iter()
        .map(|w| {
            limpid_core::trial::detect_onset(
                pos,
                w.range.clone(),
                position_noise,
                &floors[..pos.len()],
            )
        })
        .collect();
    frc.iter()
        .map(|f| {
            let mut spreads: Vec<f64> = windows
                .iter()
                .zip(&motion_onsets)
                .filter_map(|(w, m)| {
                    // the first half before the motion: the perturbation's
                    // force leads the displacement's detection
                    let end = w.range.start + ((*m)? - w.range.start) / 2;
                    (end >= w.range.start + min_rest.max(4)).then(|| {
                        let rest = &f[w.range.start..end];
                        let mean = rest.iter().sum::<f64>() / rest.len() as f64;
                        (rest.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / rest.len() as f64)
                            .sqrt()
                    })
                })
                .collect();
            if spreads.is_empty() {
                return 0.0;
            }
            spreads.sort_by(f64::total_cmp);
            spreads[spreads.len() / 2]
        })
        .collect()
}
