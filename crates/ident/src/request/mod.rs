//! What a user asks of each estimator: one typed request per method, shared
//! by every front-end (the CLI builds it from flags, Python from keyword
//! arguments, a study from its manifest, `limpid rerun` from a result's run
//! block). Defaults are defined here once; [`Request::check`] turns a request
//! into the validated settings the estimators run on ([`Checked`]), the only
//! way `limpid-app` runs one.
//!
//! Requests are plain data: file paths are named, not read (reading,
//! robot kinematics and the shoulder's joint space happen in `limpid-app`).
//! Field names carry their units (`_hz`, `_ms`, `_s`, `_m`, `_deg`).

use limpid_core::{Error, Result};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::estimator::positive;
use crate::reflex::ReflexParams;
pub use crate::reflex::ReflexRequest;
use crate::stochastic::StochasticParams;
use crate::varying::VaryingParams;
pub use crate::varying::VaryingRequest;

mod methods;
mod options;

pub use methods::{
    ArmRequest, Axis, CocontractionRequest, Frame, LinearRequest, PlanarRequest, PrepareRequest,
    SegmentWindow, SpectraRequest, StochasticRequest, SweepRequest,
};
pub use options::{boolean_options, deserialize_request, field_names, from_options, nesting};

/// Band of the stochastic parametric fit and accuracy measures (Hz).
pub const DEFAULT_BAND_HZ: [f64; 2] = [0.5, 10.0];
/// The window sweep's shortest, longest observation window and step (ms).
pub const DEFAULT_SWEEP_MS: [f64; 3] = [50.0, 400.0, 10.0];
/// Half-width of the band around a co-contraction target counted as "on target".
pub const DEFAULT_TOLERANCE: f64 = 0.1;

/// One estimate, as any front-end asks for it; `method` names the estimator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "method", rename_all = "snake_case")]
pub enum Request {
    /// `limpid estimate linear`.
    Linear(LinearRequest),
    /// `limpid estimate cocontraction` (inputs: the recording, then the MVC recording).
    Cocontraction(CocontractionRequest),
    /// `limpid estimate planar`.
    Planar(PlanarRequest),
    /// `limpid window-sweep`.
    WindowSweep(SweepRequest),
    /// `limpid estimate stochastic` (inputs: one or more recordings, pooled).
    Stochastic(StochasticRequest),
    /// `limpid estimate reflex`.
    Reflex(ReflexRequest),
    /// `limpid estimate varying`.
    Varying(VaryingRequest),
    /// `limpid spectra`.
    Spectra(SpectraRequest),
}

/// A request whose settings were checked; only [`Request::check`] makes one.
#[derive(Debug, Clone)]
pub struct Checked {
    request: Request,
    settings: Settings,
}

/// The settings a checked request runs with: the estimator's checked
/// settings where the method has them (the request is not checked again),
/// else the request itself.
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)]
pub enum Settings {
    /// `limpid estimate linear`.
    Linear(LinearRequest),
    /// `limpid estimate cocontraction`.
    Cocontraction(CocontractionRequest),
    /// `limpid estimate planar`.
    Planar(PlanarRequest),
    /// `limpid window-sweep`.
    WindowSweep(SweepRequest),
    /// `limpid estimate stochastic`.
    Stochastic(StochasticRequest),
    /// `limpid estimate reflex`.
    Reflex(ReflexParams),
    /// `limpid estimate varying`.
    Varying(VaryingParams),
    /// `limpid spectra`.
    Spectra(SpectraRequest),
}

impl Checked {
    /// The request as it was checked.
    pub fn request(&self) -> &Request {
        &self.request
    }

    /// The settings it runs with.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }
}

fn finite(name: &str, v: f64) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(Error::invalid(
            name,
            format!(
                "expected a finite number, found {}",
                limpid_core::error::Num(v)
            ),
        ))
    }
}

fn check_prepare(p: &PrepareRequest) -> Result<()> {
    if !(1..=20).contains(&p.order) {
        return Err(Error::invalid(
            "order",
            format!(
                "expected a Butterworth order from 1 to 20, found {}",
                p.order
            ),
        ));
    }
    if let Some(c) = p.cutoff_hz {
        positive("cutoff_hz", c)?;
    }
    if let Some(l) = p.level {
        finite("level", l)?;
    }
    p.params().map(|_| ())
}

fn check_arm(a: &ArmRequest) -> Result<()> {
    for v in a.link_lengths {
        positive("link_lengths", v)?;
    }
    for v in a.shoulder {
        finite("shoulder", v)?;
    }
    if let Some(c) = a.cutoff_hz {
        positive("cutoff_hz", c)?;
    }
    if let Some(xi) = a.inertial_parameters {
        crate::planar::check_inertial_parameters(&xi)?;
    }
    Ok(())
}

impl Request {
    /// The command a user types for this method.
    pub fn command(&self) -> &'static str {
        match self {
            Request::Linear(_) => "estimate linear",
            Request::Cocontraction(_) => "estimate cocontraction",
            Request::Planar(_) => "estimate planar",
            Request::WindowSweep(_) => "window-sweep",
            Request::Stochastic(_) => "estimate stochastic",
            Request::Reflex(_) => "estimate reflex",
            Request::Varying(_) => "estimate varying",
            Request::Spectra(_) => "spectra",
        }
    }

    /// Refuse settings that cannot give an honest result, before any data is read.
    pub fn check(self) -> Result<Checked> {
        let settings = match &self {
            Request::Linear(r) => {
                // the posture itself is checked where it is used, with reasons
                check_prepare(&r.prepare)?;
                Settings::Linear(r.clone())
            }
            Request::Cocontraction(r) => {
                check_prepare(&r.prepare)?;
                // finite too: an infinite band counts every sample "on target" (issue 56)
                if !(r.tolerance.is_finite() && r.tolerance > 0.0) {
                    return Err(Error::invalid(
                        "tolerance",
                        format!(
                            "expected a positive, finite band half-width, found {}",
                            limpid_core::error::Num(r.tolerance)
                        ),
                    ));
                }
                Settings::Cocontraction(r.clone())
            }
            Request::Planar(r) => {
                check_arm(&r.arm)?;
                if let Some(ms) = r.window_ms {
                    // finite too: an infinite window was stored as null and
                    // refused by `rerun` (issue 56)
                    if !(ms.is_finite() && ms > 0.0) {
                        return Err(Error::invalid(
                            "window_ms",
                            format!(
                                "expected a positive, finite duration in ms, found {}",
                                limpid_core::error::Num(ms)
                            ),
                        ));
                    }
                }
                Settings::Planar(r.clone())
            }
            Request::WindowSweep(r) => {
                check_arm(&r.arm)?;
                positive("from_ms", r.from_ms)?;
                positive("to_ms", r.to_ms)?;
                positive("step_ms", r.step_ms)?;
                Settings::WindowSweep(r.clone())
            }
            Request::Stochastic(r) => {
                crate::Estimator::check(&StochasticParams {
                    welch: None,
                    band_hz: (r.band_hz[0], r.band_hz[1]),
                })?;
                Settings::Stochastic(r.clone())
            }
            Request::Reflex(r) => Settings::Reflex(r.check()?),
            Request::Varying(r) => Settings::Varying(r.check()?),
            // the segments are checked against the recording's length when it is read
            Request::Spectra(r) => {
                crate::spectra::check_columns(&r.inputs, &r.outputs)?;
                if let Some(p) = r.period_s {
                    positive("period_s", p)?;
                    if r.nperseg.is_some() || r.noverlap.is_some() {
                        return Err(Error::invalid(
                            "period_s",
                            "a periodic analysis takes whole periods as its segments: leave out the segment length and overlap",
                        ));
                    }
                }
                Settings::Spectra(r.clone())
            }
        };
        Ok(Checked {
            request: self,
            settings,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prepare::PrepareParams;

    #[test]
    fn defaults_are_the_estimators_defaults() {
        let p = PrepareRequest::default().params().unwrap();
        assert_eq!(p.filter_order, PrepareParams::default().filter_order);
        assert_eq!(
            StochasticRequest::default().params(10_000, 1000.0).band_hz,
            StochasticParams::default().band_hz
        );
    }

    #[test]
    fn flat_options_become_the_nested_request() {
        let mut o = serde_json::Map::new();
        o.insert("cutoff_hz".into(), 20.0.into());
        o.insert("equilibrium".into(), false.into());
        o.insert("level".into(), serde_json::Value::Null);
        let r = from_options("linear", o).unwrap();
        let Request::Linear(l) = r else { panic!() };
        assert_eq!(l.prepare.cutoff_hz, Some(20.0));
        assert!(!l.equilibrium);
        let mut o = serde_json::Map::new();
        o.insert("link_lengths".into(), serde_json::json!([0.3, 0.35]));
        o.insert("from_ms".into(), 60.0.into());
        let Request::WindowSweep(s) = from_options("window_sweep", o).unwrap() else {
            panic!()
        };
        assert_eq!(s.arm.link_lengths, [0.3, 0.35]);
        assert_eq!(
            boolean_options("linear").unwrap(),
            ["equilibrium", "negate_force"]
        );
        assert_eq!((s.from_ms, s.to_ms), (60.0, DEFAULT_SWEEP_MS[1]));
    }

    #[test]
    fn unknown_or_mistyped_options_are_named() {
        let mut o = serde_json::Map::new();
        o.insert("cutof_hz".into(), 20.0.into());
        let e = from_options("linear", o).unwrap_err().to_string();
        assert!(e.contains("cutof_hz"), "{e}");
        let mut o = serde_json::Map::new();
        o.insert("band_hz".into(), serde_json::json!([1.0]));
        let e = from_options("stochastic", o).unwrap_err().to_string();
        assert!(e.contains("band_hz"), "{e}");
        let e = from_options("fourier", serde_json::Map::new())
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a method"), "{e}");
    }

    #[test]
    fn checks_refuse_before_any_data() {
        let mut r = LinearRequest::default();
        r.prepare.cutoff_hz = Some(f64::NAN);
        assert!(Request::Linear(r).check().is_err());
        let r = CocontractionRequest {
            tolerance: 0.0,
            ..Default::default()
        };
        assert!(Request::Cocontraction(r).check().is_err());
        let r = PlanarRequest {
            arm: ArmRequest::new([0.3, 0.0]),
            window_ms: None,
        };
        assert!(Request::Planar(r).check().is_err());
    }

    #[test]
    fn a_request_round_trips_through_json() {
        let r = Request::Stochastic(StochasticRequest {
            nperseg: Some(1024),
            ..Default::default()
        });
        let text = serde_json::to_string(&r).unwrap();
        assert!(text.contains("\"method\":\"stochastic\""), "{text}");
        let back: Request = serde_json::from_str(&text).unwrap();
        assert_eq!(back, r);
    }
}
