//! The settings of the parallel-cascade estimator, written once:
//! [`ReflexRequest`] is what every front-end fills (the CLI's flags are
//! derived from it, Python's keywords and a rerun's JSON are read into it),
//! [`ReflexRequest::check`] refuses what cannot give an honest result and
//! returns [`ReflexParams`], the only settings [`super::estimate_reflex`]
//! accepts. Errors name the field; each front-end spells it its own way.

use std::ops::Deref;

use limpid_core::{Error, Result};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::estimator::positive;
use crate::request::{boolean_names, Method};

/// Stop alternating when the total VAF rises by less than this (percentage points).
pub const TOLERANCE_VAF: f64 = 0.05;
/// At most this many alternations of the two pathways.
pub const MAX_ITERATIONS: usize = 10;

/// Intrinsic and reflex stiffness by the parallel cascade (Kearney et al. 1997).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(default, deny_unknown_fields)]
pub struct ReflexRequest {
    /// Position column (rad, or m for end-point data), e.g. `q1`.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = ReflexRequest::default().position))]
    pub position: String,
    /// Torque column applied to the limb (N m, or N), e.g. `tau1`.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = ReflexRequest::default().torque))]
    pub torque: String,
    /// What the position column is, `angle` (rad, torque in N m) or `displacement` (m, force in N) [default: from a recording-format name (`theta`, `q1`.. angle; `x`, `y`, `z` displacement), else angle]; the result's units follow it, never the column's name.
    #[cfg_attr(feature = "clap", arg(long, value_enum, value_name = "KIND"))]
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coordinate: Option<crate::units::Coordinate>,
    /// Decimate to this rate (Hz) before identification.
    #[cfg_attr(feature = "clap", arg(long = "rate", default_value_t = ReflexRequest::default().rate_hz, value_name = "HZ"))]
    pub rate_hz: f64,
    /// Intrinsic IRF half-width (s): it spans ± this.
    #[cfg_attr(feature = "clap", arg(long = "intrinsic-lags", default_value_t = ReflexRequest::default().intrinsic_lags_s, value_name = "S"))]
    pub intrinsic_lags_s: f64,
    /// Reflex IRF length (s); also left out of every VAF.
    #[cfg_attr(feature = "clap", arg(long = "reflex-lags", default_value_t = ReflexRequest::default().reflex_lags_s, value_name = "S"))]
    pub reflex_lags_s: f64,
    /// Largest reflex delay scanned (s).
    #[cfg_attr(feature = "clap", arg(long = "max-delay", default_value_t = ReflexRequest::default().max_delay_s, value_name = "S"))]
    pub max_delay_s: f64,
    /// Rectify the velocity before anti-aliasing (the physical order, default) instead of after (Kearney et al.'s order).
    #[cfg_attr(
        feature = "clap",
        arg(
            long = "rectify-after",
            action = clap::ArgAction::SetFalse,
            help = "Rectify the velocity after anti-aliasing (Kearney et al.'s order) instead of before it (the physical order, default); the difference goes into the standard errors"
        )
    )]
    pub rectify_first: bool,
    /// Regress on the measured motion even when a commanded reference column (`r1` for `q1`) is recorded: right only when the robot imposed the motion (a stiff servo); by default a reference makes the estimate closed-loop (the reference as instrument).
    #[cfg_attr(feature = "clap", arg(long = "open-loop"))]
    pub open_loop: bool,
    /// The reflex's static curve: `auto` (chosen by cross-validation among the rectifier and piecewise-linear curves), `rectifier` (Kearney et al.'s) or `piecewise-linear`.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value_t = Nonlinearity::Auto, value_name = "CURVE"))]
    pub nonlinearity: Nonlinearity,
}

/// Which static curves the reflex pathway may take (issue 78).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "snake_case")]
pub enum Nonlinearity {
    /// Chosen by 10-fold cross-validated VAF (one-standard-error rule).
    #[default]
    Auto,
    /// The half-wave rectifier only.
    Rectifier,
    /// A piecewise-linear curve, its knots chosen by cross-validation.
    #[cfg_attr(feature = "clap", value(alias = "piecewise_linear"))]
    PiecewiseLinear,
}

impl Default for ReflexRequest {
    fn default() -> Self {
        ReflexRequest {
            position: "q1".into(),
            torque: "tau1".into(),
            coordinate: None,
            rate_hz: 100.0,
            intrinsic_lags_s: 0.04,
            reflex_lags_s: 1.0,
            max_delay_s: 0.15,
            rectify_first: true,
            open_loop: false,
            nonlinearity: Nonlinearity::Auto,
        }
    }
}

/// Checked settings of the parallel-cascade estimator; only
/// [`ReflexRequest::check`] makes them. They read as the request they were
/// checked from.
#[derive(Debug, Clone)]
pub struct ReflexParams {
    request: ReflexRequest,
}

impl Deref for ReflexParams {
    type Target = ReflexRequest;

    fn deref(&self) -> &ReflexRequest {
        &self.request
    }
}

impl Default for ReflexParams {
    /// The defaults, which pass the check (tested).
    fn default() -> Self {
        ReflexParams {
            request: ReflexRequest::default(),
        }
    }
}

impl ReflexParams {
    /// These settings with the delay scan ending at `max_delay_s` (never
    /// beyond the one checked): what segments too short for it allow.
    pub(crate) fn with_max_delay(&self, max_delay_s: f64) -> ReflexParams {
        let mut request = self.request.clone();
        request.max_delay_s = max_delay_s.min(self.request.max_delay_s);
        ReflexParams { request }
    }
}

impl ReflexRequest {
    /// What the position column is: as the request says, else as its
    /// recording-format name says, else (the method is a joint's) an angle;
    /// the flag says whether it was taken without being said.
    pub fn coordinate(&self) -> (crate::units::Coordinate, bool) {
        match self
            .coordinate
            .or_else(|| crate::units::Coordinate::of_name(&self.position))
        {
            Some(c) => (c, false),
            None => (crate::units::Coordinate::Angle, true),
        }
    }

    /// Refuse settings that cannot give an honest result, before any data is read.
    pub fn check(&self) -> Result<ReflexParams> {
        let described = |name: &str, what: &str, v: f64| {
            positive(name, v).map_err(|_| {
                Error::invalid(
                    name,
                    format!(
                        "the {what} must be a positive number, found {}",
                        limpid_core::error::Num(v)
                    ),
                )
            })
        };
        described("rate_hz", "decimated rate (Hz)", self.rate_hz)?;
        described(
            "intrinsic_lags_s",
            "intrinsic IRF half-width (s)",
            self.intrinsic_lags_s,
        )?;
        described("reflex_lags_s", "reflex IRF length (s)", self.reflex_lags_s)?;
        described("max_delay_s", "largest reflex delay (s)", self.max_delay_s)?;
        // the intrinsic IRF needs lags on each side of zero: below two per
        // side its ±half-width would silently become ±1 sample of a slower rate
        if self.rate_hz * self.intrinsic_lags_s < 2.0 {
            return Err(Error::invalid(
                "rate_hz",
                format!(
                    "at a decimated rate of {} Hz the intrinsic IRF (±{} ms) holds fewer than 2 lags each side; use at least {} Hz",
                    limpid_core::short_number(self.rate_hz),
                    limpid_core::short_number(self.intrinsic_lags_s * 1e3),
                    limpid_core::short_number((2.0 / self.intrinsic_lags_s).ceil())
                ),
            ));
        }
        if self.max_delay_s >= self.reflex_lags_s {
            return Err(Error::invalid(
                "max_delay_s",
                format!(
                    "the largest reflex delay scanned ({} s) must be shorter than the reflex IRF ({} s), which is left out of every VAF",
                    self.max_delay_s, self.reflex_lags_s
                ),
            ));
        }
        Ok(ReflexParams {
            request: self.clone(),
        })
    }
}

impl Method for ReflexRequest {
    const COMMAND: &'static str = "estimate reflex";
    const LONG_ARRAYS: bool = true;
    type Valid = ReflexParams;

    fn check_settings(&self) -> Result<ReflexParams> {
        self.check()
    }

    fn booleans() -> Vec<String> {
        boolean_names::<ReflexRequest>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_pass_the_check() {
        let p = ReflexRequest::default().check().unwrap();
        assert_eq!(p.rate_hz, 100.0);
        assert_eq!(*p, *ReflexParams::default());
    }

    #[test]
    fn the_check_names_the_field() {
        let r = ReflexRequest {
            rate_hz: 10.0,
            ..ReflexRequest::default()
        };
        let e = r.check().unwrap_err().to_string();
        assert!(e.starts_with("invalid rate_hz:"), "{e}");
        assert!(e.contains("use at least 50 Hz"), "{e}");
        let r = ReflexRequest {
            max_delay_s: 2.0,
            ..ReflexRequest::default()
        };
        assert!(r.check().unwrap_err().to_string().contains("max_delay_s"));
    }
}
