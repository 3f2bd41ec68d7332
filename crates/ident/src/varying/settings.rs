//! The settings of `limpid estimate varying`, written once:
//! [`VaryingRequest`] is what every front-end fills (the CLI's flags are
//! derived from it, Python's keywords and a rerun's JSON are read into it),
//! [`VaryingRequest::check`] refuses what cannot give an honest result and
//! returns [`VaryingParams`], the only settings [`super::estimate_varying`]
//! accepts, with the durations in seconds computed once.

use std::ops::Deref;

use limpid_core::{Error, Result};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::{MAX_BASIS_ORDER, TIME};
use crate::estimator::positive;
use crate::request::{boolean_names, Method};

/// What a parameter-varying schedule is to the coordinate's angle (issue
/// 58): where the stiffness varies with the angle itself, a perturbation of
/// half-swing `a` sees the mean slope over `[σ - a, σ + a]`, which differs
/// from the local slope K(σ) by about `K''(σ) E[x⁴] / (6 E[x²])` (+0.25 % on
/// an exponential K with a ±0.038 rad perturbation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "snake_case")]
pub enum ScheduleAngle {
    /// `total` when the schedule is the coordinate or its slow part follows
    /// the schedule; otherwise unknown: K is the mean slope over the
    /// perturbation and its standard error allows for the `offset` reading.
    #[default]
    Auto,
    /// The coordinate is the joint's whole angle; the schedule its operating angle.
    Total,
    /// The coordinate is the angle's offset from the schedule (the whole
    /// angle is schedule + coordinate, as in REKLAB's parameter-varying recordings).
    Offset,
    /// The schedule is not the coordinate's angle: K multiplies the displacement.
    None,
}

/// Impedance that varies with time (`schedule = "time"`, an ensemble of
/// repetitions) or with a measured operating point (a column: parameter-varying).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(default, deny_unknown_fields)]
pub struct VaryingRequest {
    /// `time` (ensemble over the `trial` repetitions) or the column the impedance varies with (e.g. sv, level, q1); with --event, `gait-phase` (the default then) or `time-since-event`.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = VaryingRequest::default().schedule, value_name = "time|COLUMN|gait-phase|time-since-event"))]
    pub schedule: String,
    /// Walking: the stride event, a 0/1 column (e.g. heel_strike) or a threshold crossing COLUMN>LEVEL / COLUMN<LEVEL.
    #[cfg_attr(feature = "clap", arg(long, value_name = "COLUMN|COLUMN>LEVEL"))]
    pub event: Option<String>,
    /// Walking: hysteresis of a threshold event, in the column's unit [default: 5 % of the level].
    #[cfg_attr(feature = "clap", arg(long, value_name = "X"))]
    pub hysteresis: Option<f64>,
    /// Walking: an event sooner than this after the one before is ignored (ms), and reported.
    #[cfg_attr(feature = "clap", arg(long = "refractory", default_value_t = VaryingRequest::default().refractory_ms, value_name = "MS"))]
    pub refractory_ms: f64,
    /// Walking: the 0/1 column that is 1 while a perturbation is active [default: `perturbation` when present].
    #[cfg_attr(feature = "clap", arg(long, value_name = "COLUMN"))]
    pub trigger: Option<String>,
    /// Walking: `pulses` (perturbed minus unperturbed strides) or `ensemble` (a perturbation on every stride) [default: pulses when the trigger marks some strides].
    #[cfg_attr(
        feature = "clap",
        arg(long = "method", value_enum, value_name = "METHOD")
    )]
    pub gait_method: Option<super::gait::GaitMethod>,
    /// Walking: strides in each baseline [default: 10 unperturbed strides (pulses), 20 strides (ensemble)].
    #[cfg_attr(feature = "clap", arg(long, value_name = "N"))]
    pub neighbours: Option<usize>,
    /// Walking, pulses: width of the onset bins (fraction of the stride, or s with time-since-event) [default: 0.05].
    #[cfg_attr(feature = "clap", arg(long, value_name = "WIDTH"))]
    pub bin: Option<f64>,
    /// Walking, pulses: fewest perturbations in an identifiable bin.
    #[cfg_attr(feature = "clap", arg(long = "min-pulses", default_value_t = VaryingRequest::default().min_pulses, value_name = "N"))]
    pub min_pulses: usize,
    /// Walking, pulses: longest fit window after an onset (ms) [default: until 50 ms after the trigger falls, at most 400].
    #[cfg_attr(feature = "clap", arg(long = "pulse-window", value_name = "MS"))]
    pub pulse_window_ms: Option<f64>,
    /// Walking: the gait phase where stance ends, drawn in figures (typical walking: 0.6).
    #[cfg_attr(feature = "clap", arg(long = "stance-end", default_value_t = VaryingRequest::default().stance_end, value_name = "PHASE"))]
    pub stance_end: f64,
    /// Zero-phase low-pass before differentiation (Hz) [default: 30, or 0.4 x the rate].
    #[cfg_attr(feature = "clap", arg(long = "cutoff", value_name = "HZ"))]
    pub cutoff_hz: Option<f64>,
    /// Ensemble: the window pooled around each instant (ms), the time resolution.
    #[cfg_attr(feature = "clap", arg(long = "window-ms", default_value_t = VaryingRequest::default().window_ms, value_name = "MS"))]
    pub window_ms: f64,
    /// Ensemble: grid step (ms) [default: half the window].
    #[cfg_attr(feature = "clap", arg(long = "step", value_name = "MS"))]
    pub step_ms: Option<f64>,
    /// Ensemble: fewest repetitions for an identifiable instant.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = VaryingRequest::default().min_repetitions, value_name = "N"))]
    pub min_repetitions: usize,
    /// Parameter-varying: points on the schedule's grid.
    #[cfg_attr(feature = "clap", arg(long = "grid", default_value_t = VaryingRequest::default().grid_points, value_name = "N"))]
    pub grid_points: usize,
    /// Parameter-varying: Chebyshev order of every parameter [default: chosen by 10-fold blocked cross-validation, 0-6].
    #[cfg_attr(feature = "clap", arg(long = "order", value_name = "P"))]
    pub basis_order: Option<usize>,
    /// Parameter-varying: the operating point is what varies slower than this (Hz); regression is on the deviations from it.
    #[cfg_attr(feature = "clap", arg(long = "slow", default_value_t = VaryingRequest::default().slow_hz, value_name = "HZ"))]
    pub slow_hz: f64,
    /// Parameter-varying: decimate to about this rate (Hz) after filtering.
    #[cfg_attr(feature = "clap", arg(long = "rate", default_value_t = VaryingRequest::default().rate_hz, value_name = "HZ"))]
    pub rate_hz: f64,
    /// Parameter-varying: add a stretch-reflex pathway (rectified velocity, delay, low-pass) whose gain varies with the schedule.
    #[cfg_attr(feature = "clap", arg(long))]
    pub reflex: bool,
    /// Parameter-varying: what the schedule is to the coordinate's angle: `total` (the coordinate is the whole angle, the schedule its operating angle) or `offset` (the coordinate is the angle's offset from the schedule) give K as the local slope at each operating angle; `none` (not an angle): K multiplies the displacement; `auto`: `total` when the coordinate's slow part follows the schedule, else unknown, K's SE allowing for either.
    #[cfg_attr(feature = "clap", arg(long = "schedule-angle", value_enum, default_value_t = ScheduleAngle::Auto, value_name = "READING"))]
    pub schedule_angle: ScheduleAngle,
    /// Largest reflex delay scanned (s).
    #[cfg_attr(feature = "clap", arg(long = "max-delay", default_value_t = VaryingRequest::default().max_delay_s, value_name = "S"))]
    pub max_delay_s: f64,
    /// Regress on the measured motion even when commanded reference columns (`r1` for `q1`; `rx, ry, rz`) are recorded: right only when the robot imposed the motion; by default a reference makes the fit closed-loop (on the motion the reference predicts).
    #[cfg_attr(feature = "clap", arg(long = "open-loop"))]
    pub open_loop: bool,
}

impl Default for VaryingRequest {
    fn default() -> Self {
        VaryingRequest {
            schedule: TIME.into(),
            event: None,
            hysteresis: None,
            refractory_ms: 250.0,
            trigger: None,
            gait_method: None,
            neighbours: None,
            bin: None,
            min_pulses: 5,
            pulse_window_ms: None,
            stance_end: 0.6,
            cutoff_hz: None,
            window_ms: 30.0,
            step_ms: None,
            min_repetitions: 10,
            grid_points: 21,
            basis_order: None,
            slow_hz: 0.5,
            rate_hz: 200.0,
            reflex: false,
            schedule_angle: ScheduleAngle::Auto,
            max_delay_s: 0.1,
            open_loop: false,
        }
    }
}

/// Checked settings of [`super::estimate_varying`]; only
/// [`VaryingRequest::check`] makes them. They read as the request they were
/// checked from, plus its durations in seconds.
#[derive(Debug, Clone, PartialEq)]
pub struct VaryingParams {
    request: VaryingRequest,
    /// Ensemble: the window pooled around each instant (s).
    pub(crate) window_s: f64,
    /// Ensemble: grid step (s); `None`: half the window.
    pub(crate) step_s: Option<f64>,
}

impl Deref for VaryingParams {
    type Target = VaryingRequest;

    fn deref(&self) -> &VaryingRequest {
        &self.request
    }
}

impl Default for VaryingParams {
    /// The defaults, which pass the check (tested).
    fn default() -> Self {
        VaryingRequest::default().valid()
    }
}

impl VaryingRequest {
    /// Refuse settings that cannot give an honest result, before any data is read.
    pub fn check(&self) -> Result<VaryingParams> {
        if self.schedule.trim().is_empty() {
            return Err(Error::invalid(
                "schedule",
                "expected `time` or a column name",
            ));
        }
        if let Some(c) = self.cutoff_hz {
            positive("cutoff_hz", c)?;
        }
        positive("window_ms", self.window_ms)?;
        if let Some(s) = self.step_ms {
            positive("step_ms", s)?;
        }
        positive("slow_hz", self.slow_hz)?;
        positive("rate_hz", self.rate_hz)?;
        positive("max_delay_s", self.max_delay_s)?;
        if self.max_delay_s > 1.0 {
            return Err(Error::invalid(
                "max_delay_s",
                format!(
                    "a reflex delay is well under 1 s, found {} s",
                    limpid_core::significant(self.max_delay_s, 4)
                ),
            ));
        }
        if self.min_repetitions < 3 {
            return Err(Error::invalid(
                "min_repetitions",
                format!(
                    "the jackknife needs at least 3, found {}",
                    self.min_repetitions
                ),
            ));
        }
        if !(2..=1000).contains(&self.grid_points) {
            return Err(Error::invalid(
                "grid_points",
                format!("expected 2 to 1000, found {}", self.grid_points),
            ));
        }
        if let Some(p) = self.basis_order {
            if p > MAX_BASIS_ORDER {
                return Err(Error::invalid(
                    "basis_order",
                    format!("expected 0 to {MAX_BASIS_ORDER}, found {p}"),
                ));
            }
        }
        self.check_walking()?;
        if self.reflex && self.schedule == TIME {
            return Err(Error::invalid(
                "reflex",
                "the reflex pathway is estimated against a measured schedule (a column), not with --schedule time",
            ));
        }
        Ok(self.valid())
    }

    /// The walking settings (issue 61): refused unless they go with `event`.
    fn check_walking(&self) -> Result<()> {
        use super::gait::{EventRule, GAIT_PHASE, TIME_SINCE_EVENT};
        let walking_schedule = [GAIT_PHASE, TIME_SINCE_EVENT].contains(&self.schedule.as_str());
        let Some(event) = &self.event else {
            let stray = [
                ("schedule", walking_schedule),
                ("trigger", self.trigger.is_some()),
                ("gait_method", self.gait_method.is_some()),
                ("neighbours", self.neighbours.is_some()),
                ("bin", self.bin.is_some()),
                ("pulse_window_ms", self.pulse_window_ms.is_some()),
                ("hysteresis", self.hysteresis.is_some()),
            ];
            if let Some((name, _)) = stray.iter().find(|s| s.1) {
                return Err(Error::invalid(
                    *name,
                    "is a walking setting: give the stride event too (--event heel_strike, or --event 'fz>50')",
                ));
            }
            return Ok(());
        };
        EventRule::parse(event)?;
        if !walking_schedule && self.schedule != TIME {
            return Err(Error::invalid(
                "schedule",
                format!(
                    "with --event the schedule is {GAIT_PHASE} or {TIME_SINCE_EVENT}, found {}",
                    self.schedule
                ),
            ));
        }
        if self.reflex {
            return Err(Error::invalid(
                "reflex",
                "the reflex pathway is not estimated during walking",
            ));
        }
        if let Some(h) = self.hysteresis {
            if !h.is_finite() || h < 0.0 {
                return Err(Error::invalid(
                    "hysteresis",
                    format!(
                        "expected a finite number >= 0, found {}",
                        limpid_core::error::Num(h)
                    ),
                ));
            }
        }
        positive("refractory_ms", self.refractory_ms)?;
        if self.refractory_ms > 5000.0 {
            return Err(Error::invalid(
                "refractory_ms",
                format!(
                    "a stride event cannot be refractory for {} ms (more than 5 s)",
                    limpid_core::significant(self.refractory_ms, 4)
                ),
            ));
        }
        if let Some(n) = self.neighbours {
            // pulses compare a perturbed stride with the mean of at least 3
            // unperturbed ones (fewer failed every pulse, blaming the trigger)
            if !(3..=1000).contains(&n) {
                return Err(Error::invalid(
                    "neighbours",
                    format!("expected 3 to 1000 strides (a baseline of fewer is as noisy as the stride it is subtracted from), found {n}"),
                ));
            }
        }
        if let Some(b) = self.bin {
            positive("bin", b)?;
            if self.schedule != TIME_SINCE_EVENT && b > 0.5 {
                return Err(Error::invalid(
                    "bin",
                    format!(
                        "a bin of gait phase is a fraction of the stride, at most 0.5, found {}",
                        limpid_core::significant(b, 4)
                    ),
                ));
            }
            if b > 10.0 {
                return Err(Error::invalid(
                    "bin",
                    format!(
                        "expected at most 10 s, found {}",
                        limpid_core::significant(b, 4)
                    ),
                ));
            }
        }
        if self.min_pulses < 3 {
            return Err(Error::invalid(
                "min_pulses",
                format!("the jackknife needs at least 3, found {}", self.min_pulses),
            ));
        }
        if let Some(w) = self.pulse_window_ms {
            positive("pulse_window_ms", w)?;
            if w > 5000.0 {
                return Err(Error::invalid(
                    "pulse_window_ms",
                    format!(
                        "expected at most 5000 ms, found {}",
                        limpid_core::significant(w, 4)
                    ),
                ));
            }
        }
        if !(self.stance_end > 0.0 && self.stance_end < 1.0) {
            return Err(Error::invalid(
                "stance_end",
                format!(
                    "expected a fraction of the stride between 0 and 1, found {}",
                    limpid_core::error::Num(self.stance_end)
                ),
            ));
        }
        Ok(())
    }

    fn valid(&self) -> VaryingParams {
        let mut request = self.clone();
        if request.event.is_some() && request.schedule == TIME {
            request.schedule = super::gait::GAIT_PHASE.into();
        }
        VaryingParams {
            request,
            window_s: self.window_ms / 1e3,
            step_s: self.step_ms.map(|ms| ms / 1e3),
        }
    }
}

impl Method for VaryingRequest {
    const COMMAND: &'static str = "estimate varying";
    const LONG_ARRAYS: bool = true;
    type Valid = VaryingParams;

    fn check_settings(&self) -> Result<VaryingParams> {
        self.check()
    }

    fn booleans() -> Vec<String> {
        boolean_names::<VaryingRequest>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_pass_the_check() {
        let p = VaryingRequest::default().check().unwrap();
        assert_eq!(p, VaryingParams::default());
        assert_eq!(p.window_s, 0.03);
    }

    #[test]
    fn the_check_names_the_field() {
        let r = VaryingRequest {
            step_ms: Some(-1.0),
            ..VaryingRequest::default()
        };
        assert!(r.check().unwrap_err().to_string().contains("step_ms"));
        let r = VaryingRequest {
            reflex: true,
            ..VaryingRequest::default()
        };
        assert!(r.check().unwrap_err().to_string().contains("reflex"));
    }
}
