//! What a user asks of each estimator: one typed request per method, shared
//! by every front-end (the CLI builds it from flags, Python from keyword
//! arguments, a study from its manifest, `limpid rerun` from a result's run
//! block). Defaults are defined here once; [`Request::check`] turns a request
//! into the validated settings the estimators run on ([`Checked`]), the only
//! way `limpid-app` runs one.
//!
//! The methods are listed once, in the `methods!` invocation below: the
//! `Request` and `Settings` enums, the names, the commands and the option
//! parsing are made from that list, and each method says the rest of itself
//! by implementing [`Method`] beside its request type.
//!
//! Requests are plain data: file paths are named, not read (reading,
//! robot kinematics and the shoulder's joint space happen in `limpid-app`).
//! Field names carry their units (`_hz`, `_ms`, `_s`, `_m`, `_deg`).

use limpid_core::{Error, Result};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

pub use crate::reflex::ReflexRequest;
pub use crate::varying::VaryingRequest;

mod methods;
mod options;

pub use methods::{
    ArmRequest, Axis, CocontractionRequest, Frame, LinearRequest, PlanarRequest, PrepareRequest,
    SegmentWindow, SpectraRequest, StochasticRequest, SweepRequest, Valid, ValidArm, ValidPrepared,
    DEFAULT_BAND_TEXT,
};
pub use options::{boolean_names, boolean_options, field_names, from_options, nesting};

/// Band of the stochastic parametric fit and accuracy measures (Hz).
pub const DEFAULT_BAND_HZ: [f64; 2] = [0.5, 10.0];
/// The window sweep's shortest, longest observation window and step (ms).
pub const DEFAULT_SWEEP_MS: [f64; 3] = [50.0, 400.0, 10.0];
/// Half-width of the band around a co-contraction target counted as "on target".
pub const DEFAULT_TOLERANCE: f64 = 0.1;

/// What a method's request says of itself. Each method implements it beside
/// its request type; `methods!` below is the one list of methods, and the
/// enums, names, commands, option parsing and checks are made from it.
pub trait Method: Clone + std::fmt::Debug {
    /// The command a user types.
    const COMMAND: &'static str;
    /// How many recordings it reads: (fewest, most).
    const INPUTS: (usize, usize) = (1, 1);
    /// Its result holds long frequency or lag arrays: written as one JSON
    /// line, not indented.
    const LONG_ARRAYS: bool = false;
    /// The settings it runs with once checked.
    type Valid: Clone + std::fmt::Debug;
    /// Refuse settings that cannot give an honest result, before any data is
    /// read; the estimator takes what this returns and checks nothing again.
    fn check_settings(&self) -> Result<Self::Valid>;
    /// Where its flat options nest (`prepare`, `arm`) and that part's field names.
    fn nesting() -> Option<(&'static str, Vec<String>)> {
        None
    }
    /// Its yes/no options, top level and nested.
    fn booleans() -> Vec<String>;
}

/// The one list of methods: each entry is a variant, its request type and
/// its name (`method` in JSON).
macro_rules! methods {
    ($($(#[$doc:meta])* $variant:ident($request:ty) = $name:literal,)*) => {
        /// One estimate, as any front-end asks for it; `method` names the estimator.
        #[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
        #[serde(tag = "method")]
        pub enum Request {
            $($(#[$doc])* #[serde(rename = $name)] $variant($request),)*
        }

        /// The settings a checked request runs with (its method's
        /// [`Method::Valid`]): the request is not checked again.
        #[derive(Debug, Clone)]
        #[allow(clippy::large_enum_variant)]
        pub enum Settings {
            $($(#[$doc])* $variant(<$request as Method>::Valid),)*
        }

        /// Every method's name, in the list's order.
        pub const METHODS: &[&str] = &[$($name),*];

        impl Request {
            /// The method's name (`method` in JSON).
            pub fn method(&self) -> &'static str {
                match self {
                    $(Request::$variant(_) => $name,)*
                }
            }

            /// The command a user types for this method.
            pub fn command(&self) -> &'static str {
                match self {
                    $(Request::$variant(_) => <$request as Method>::COMMAND,)*
                }
            }

            /// How many recordings the method reads: (fewest, most).
            pub fn inputs_expected(&self) -> (usize, usize) {
                match self {
                    $(Request::$variant(_) => <$request as Method>::INPUTS,)*
                }
            }

            /// The result holds long arrays (one JSON line, not indented).
            pub fn long_arrays(&self) -> bool {
                match self {
                    $(Request::$variant(_) => <$request as Method>::LONG_ARRAYS,)*
                }
            }

            /// Refuse settings that cannot give an honest result, before any data is read.
            pub fn check(self) -> Result<Checked> {
                let settings = match &self {
                    $(Request::$variant(r) => Settings::$variant(r.check_settings()?),)*
                };
                Ok(Checked {
                    request: self,
                    settings,
                })
            }
        }

        /// The JSON Schema of a method's request type, by its name: every
        /// option with its type, description (unit and default in words) and
        /// choices, the nested part (`prepare`, `arm`) under `$defs`.
        pub fn method_schema(method: &str) -> Result<serde_json::Value> {
            $(if method == $name {
                return Ok(schemars::schema_for!($request).to_value());
            })*
            Err(not_a_method(method))
        }

        /// A method's nesting and yes/no options by its name.
        fn method_options(method: &str) -> Result<(Option<(&'static str, Vec<String>)>, Vec<String>)> {
            $(if method == $name {
                return Ok((<$request as Method>::nesting(), <$request as Method>::booleans()));
            })*
            Err(not_a_method(method))
        }

        /// A method's request from any serde deserializer of its (nested)
        /// options: each method's own type (not the tagged enum, which would
        /// buffer the value and lose the path of an error); an error names
        /// the option (`band_hz`, `order`, ...).
        pub fn deserialize_request<'de, D: serde::Deserializer<'de>>(
            method: &str,
            options: D,
        ) -> Result<Request> {
            $(if method == $name {
                return Ok(Request::$variant(options::typed(options)?));
            })*
            Err(not_a_method(method))
        }
    };
}

fn not_a_method(method: &str) -> Error {
    Error::invalid(
        "method",
        format!(
            "{method:?} is not a method: {}",
            match METHODS.split_last() {
                Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
                None => String::new(),
            }
        ),
    )
}

methods! {
    /// `limpid estimate linear`.
    Linear(LinearRequest) = "linear",
    /// `limpid estimate cocontraction` (inputs: the recording, then the MVC recording).
    Cocontraction(CocontractionRequest) = "cocontraction",
    /// `limpid estimate planar`.
    Planar(PlanarRequest) = "planar",
    /// `limpid window-sweep`.
    WindowSweep(SweepRequest) = "window_sweep",
    /// `limpid estimate stochastic` (inputs: one or more recordings, pooled).
    Stochastic(StochasticRequest) = "stochastic",
    /// `limpid estimate reflex`.
    Reflex(ReflexRequest) = "reflex",
    /// `limpid estimate varying`.
    Varying(VaryingRequest) = "varying",
    /// `limpid spectra`.
    Spectra(SpectraRequest) = "spectra",
}

/// A request whose settings were checked; only [`Request::check`] makes one.
#[derive(Debug, Clone)]
pub struct Checked {
    request: Request,
    settings: Settings,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prepare::PrepareParams;
    use crate::stochastic::StochasticParams;

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
            ["equilibrium", "negate_force", "open_loop"]
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
