//! The result contract: every result limpid hands out, as one typed family.
//!
//! [`Document`] is what the CLI prints with `--json`, what the Python
//! functions return as text and what the report reads: a `schema` version,
//! a `kind` tag naming the [`Estimate`] variant, and that variant's fields.
//! The JSON is exactly the serialisation of these types; JSON Schema files
//! generated from them (`schemars`) are committed under `schema/` and the
//! tests validate the CLI's output against them.
//!
//! A renamed or removed field is a compile error in every consumer (report,
//! CLI tables, Python), not a blank table; a consumer of the JSON checks
//! `schema` and gets a one-line error for a result it does not know.

pub mod calibration;
pub mod demo;
pub mod design;
pub mod reproduction;
pub mod study;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::cocontraction::CocontractionResult;
use crate::linear::LinearResult;
use crate::result::demo::DemoResult;
use crate::result::study::StudyResult;
use limpid_ident::planar::{PlanarEstimate, Sweep};
use limpid_ident::reflex::ReflexEstimate;
use limpid_ident::spectra::SpectraResult;
use limpid_ident::stochastic::StochasticEstimate;
use limpid_ident::varying::VaryingEstimate;

/// Version of the result schema; raised when a field changes meaning or is removed.
pub const SCHEMA_VERSION: u32 = 1;

/// One result of any method.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
#[allow(clippy::large_enum_variant)]
pub enum Estimate {
    /// `M x'' + B x' + K (x - x_eq) = f` by least squares (seeds 000, 001).
    Linear(LinearResult),
    /// Planar 2-link arm, joint space (seed 003).
    Planar(PlanarEstimate),
    /// Criteria against the observation window (seed 003 §IV).
    WindowSweep(Sweep),
    /// Stochastic MIMO impedance Z(f) (seed 004).
    Stochastic(StochasticEstimate),
    /// Welch spectra and coherences of named columns (`limpid spectra`, seed 004 eq. 3-6).
    Spectra(SpectraResult),
    /// Intrinsic and reflex joint stiffness, parallel cascade (Kearney et al. 1997).
    Reflex(ReflexEstimate),
    /// Impedance against time (ensemble) or an operating point (parameter-varying).
    Varying(VaryingEstimate),
    /// Impedance per co-contraction level (seed 001).
    Cocontraction(CocontractionResult),
    /// A whole co-contraction study (seed 001 Tables 1-5).
    Study(StudyResult),
    /// The virtual seed 000 study of `limpid demo`, with its truth.
    Demo(DemoResult),
    /// Coverage and verdict calibration over virtual subjects (`limpid calibrate`).
    Calibration(crate::result::calibration::Calibration),
    /// A protocol designed for an estimate (`limpid protocol design`), with its predicted precision.
    Design(crate::result::design::DesignResult),
    /// A PRBS designed for the reflex method (`limpid protocol design --method reflex`).
    ReflexDesign(crate::result::design::ReflexDesignResult),
    /// Quintic joint perturbations designed for the planar method (`limpid protocol design --method planar`).
    PlanarDesign(crate::result::design::PlanarDesignResult),
}

impl Estimate {
    /// The `kind` tag.
    pub fn kind(&self) -> &'static str {
        match self {
            Estimate::Linear(_) => "linear",
            Estimate::Planar(_) => "planar",
            Estimate::WindowSweep(_) => "window_sweep",
            Estimate::Stochastic(_) => "stochastic",
            Estimate::Spectra(_) => "spectra",
            Estimate::Reflex(_) => "reflex",
            Estimate::Varying(_) => "varying",
            Estimate::Cocontraction(_) => "cocontraction",
            Estimate::Study(_) => "study",
            Estimate::Demo(_) => "demo",
            Estimate::Calibration(_) => "calibration",
            Estimate::Design(_) => "design",
            Estimate::ReflexDesign(_) => "reflex_design",
            Estimate::PlanarDesign(_) => "planar_design",
        }
    }

    /// The recording it was estimated from, where the result names one.
    pub fn recording(&self) -> Option<&str> {
        match self {
            Estimate::Linear(r) => Some(r.provenance.recording.as_str()),
            Estimate::Cocontraction(r) => Some(r.recording.as_str()),
            Estimate::Spectra(r) => Some(r.recording.as_str()),
            _ => None,
        }
    }
}

/// How a result was made: limpid's version, the command, when, and the
/// files it read (size and modification time, to tell one file from another).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema, PartialEq)]
pub struct Run {
    /// limpid's version.
    pub limpid_version: String,
    /// The command line, arguments separated by spaces.
    pub command_line: String,
    /// When the result was made (UTC, RFC 3339).
    pub created_utc: String,
    /// The files the command read.
    pub inputs: Vec<InputFile>,
    /// The estimator's request, as it ran (`limpid rerun` runs it again on
    /// the same inputs); absent for workflows that are not one estimate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub request: Option<limpid_ident::request::Request>,
    /// The channel map (`--map`) the input files were read through, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub channel_map: Option<InputFile>,
    /// Columns named on the command line (`--column NAME=CHANNEL`, Python
    /// `columns=`): column -> the file's channel.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub columns: std::collections::BTreeMap<String, String>,
}

/// One file a result was made from.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema, PartialEq)]
pub struct InputFile {
    /// The path as given.
    pub path: String,
    /// Size in bytes (absent when the file could not be read).
    pub bytes: Option<u64>,
    /// Last modification (UTC, RFC 3339), where the file system keeps it.
    pub modified_utc: Option<String>,
    /// Samples read (recordings; absent for other files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<usize>,
    /// Sample rate (Hz) of the recording read.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sample_rate_hz: Option<f64>,
    /// Duration (s) of the recording read.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration_s: Option<f64>,
}

fn rfc3339(t: std::time::SystemTime) -> String {
    chrono::DateTime::<chrono::Utc>::from(t).to_rfc3339_opts(chrono::SecondsFormat::Secs, true)
}

impl Run {
    /// This process: its arguments, now, and the given input files.
    pub fn of_this_process(inputs: &[&std::path::Path]) -> Run {
        // args_os: a path need not be UTF-8 (std::env::args would panic)
        let command_line = std::env::args_os()
            .map(|a| a.to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join(" ");
        Run::of_call(command_line, inputs)
    }

    /// A call described by `command_line` (e.g. a Python function), now, and
    /// the given input files (size and date where each is a file).
    pub fn of_call(command_line: String, inputs: &[&std::path::Path]) -> Run {
        Run {
            limpid_version: env!("CARGO_PKG_VERSION").into(),
            command_line,
            created_utc: rfc3339(std::time::SystemTime::now()),
            inputs: inputs.iter().map(|p| InputFile::of(p)).collect(),
            request: None,
            channel_map: None,
            columns: Default::default(),
        }
    }

    /// The same run, recording the request it ran.
    pub fn with_request(self, request: &limpid_ident::request::Request) -> Run {
        Run {
            request: Some(request.clone()),
            ..self
        }
    }

    /// The run with what was read from each input (samples, rate, duration),
    /// in the order of the inputs.
    pub fn with_recordings(mut self, recordings: &[limpid_core::Recording]) -> Run {
        let inputs = std::mem::take(&mut self.inputs);
        self.inputs = inputs
            .into_iter()
            .enumerate()
            .map(|(i, f)| match recordings.get(i) {
                Some(rec) => f.with_recording(rec),
                None => f,
            })
            .collect();
        self
    }

    /// The run with the columns named on the command line.
    pub fn with_columns(self, columns: &[(String, String)]) -> Run {
        Run {
            columns: columns.iter().cloned().collect(),
            ..self
        }
    }

    /// The run with the channel map its inputs were read through.
    pub fn with_channel_map(self, map: Option<&std::path::Path>) -> Run {
        Run {
            channel_map: map.map(InputFile::of),
            ..self
        }
    }
}

impl InputFile {
    /// A file as found now: path, size and date where it is a file.
    pub fn of(p: &std::path::Path) -> InputFile {
        let meta = std::fs::metadata(p).ok();
        InputFile {
            path: p.to_string_lossy().into_owned(),
            bytes: meta.as_ref().map(|m| m.len()),
            modified_utc: meta.and_then(|m| m.modified().ok()).map(rfc3339),
            samples: None,
            sample_rate_hz: None,
            duration_s: None,
        }
    }

    /// The file with what was read from it: samples, rate and duration.
    pub fn with_recording(self, rec: &limpid_core::Recording) -> InputFile {
        let fs = rec.sample_rate();
        InputFile {
            samples: Some(rec.len()),
            sample_rate_hz: Some(fs),
            duration_s: Some(rec.len() as f64 / fs),
            ..self
        }
    }
}

/// A result with its schema version: the JSON document.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Document {
    /// [`SCHEMA_VERSION`] of the writer.
    pub schema: u32,
    /// How the result was made (absent in documents written by the library).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub run: Option<Run>,
    #[serde(flatten)]
    /// The result.
    pub estimate: Estimate,
}

impl Document {
    /// A document of the current schema.
    pub fn new(estimate: Estimate) -> Self {
        Document {
            schema: SCHEMA_VERSION,
            run: None,
            estimate,
        }
    }

    /// The document with how it was made.
    pub fn with_run(mut self, run: Run) -> Self {
        self.run = Some(run);
        self
    }

    /// The document as pretty JSON.
    pub fn to_json_pretty(&self) -> String {
        serde_json::to_string_pretty(self).expect("results serialise (no map has non-string keys)")
    }

    /// The document as pretty JSON, read back before it is given out: a
    /// number that serialises as `null` (a design's SE of a prior at 1e-300
    /// printed "inf %" and wrote a result `report` refused; issue 76) is an
    /// error naming the field, not a file limpid cannot read.
    pub fn to_readable_json_pretty(&self) -> Result<String, String> {
        let text = self.to_json_pretty();
        Document::from_json("the result", &text)?;
        Ok(text)
    }

    /// The document as compact JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("results serialise (no map has non-string keys)")
    }

    /// Read a document; `name` names the source in the error.
    pub fn from_json(name: &str, text: &str) -> Result<Self, String> {
        let v: serde_json::Value =
            serde_json::from_str(text).map_err(|e| format!("{name}: not JSON: {e}"))?;
        let schema = v.get("schema");
        match schema.and_then(|s| s.as_u64()) {
            Some(s) if s == SCHEMA_VERSION as u64 => {}
            Some(s) => {
                return Err(format!(
                    "{name}: result schema {s}, this limpid reads schema {SCHEMA_VERSION}"
                ))
            }
            None if schema.is_some() => {
                return Err(format!(
                    "{name}: \"schema\" is {}, expected the whole number {SCHEMA_VERSION}",
                    schema.map(|s| s.to_string()).unwrap_or_default()
                ))
            }
            None => {
                return Err(format!(
                    "{name}: not a limpid result (no \"schema\" key; results of limpid before schema 1 must be made again)"
                ))
            }
        }
        let doc: Document =
            serde_json::from_value(v.clone()).map_err(|e| {
                match offending_field(&v, &e.to_string()) {
                    Some(path) => format!("{name}: not a limpid result: field {path}: {e}"),
                    None => format!("{name}: not a limpid result: {e}"),
                }
            })?;
        // fields that must agree with each other, before anything indexes them
        crate::shapes::check(&doc.estimate)
            .map_err(|e| format!("{name}: not a consistent limpid result: {e}"))?;
        Ok(doc)
    }
}

/// Where a hand-edited document holds the value serde could not take
/// (`invalid type: string "high", expected f64`): the result kinds are
/// read through a tagged, flattened enum, whose errors carry no path, so
/// the value the error names is looked for in the document
/// (`fit.vaf[1]`); the first of several is named. None when the error
/// names no value (a missing field names itself).
pub fn offending_field(v: &serde_json::Value, error: &str) -> Option<String> {
    use serde_json::Value;
    let found = error.strip_prefix("invalid type: ")?;
    let found = found.split(", expected").next()?;
    let matches = |x: &Value| -> bool {
        match x {
            Value::Null => found == "null",
            Value::Bool(b) => found == format!("boolean `{b}`"),
            Value::String(t) => found == format!("string {t:?}"),
            Value::Number(n) => {
                found == format!("integer `{n}`") || found == format!("floating point `{n}`")
            }
            Value::Array(_) => found == "sequence",
            Value::Object(_) => found == "map",
        }
    };
    fn walk(
        x: &serde_json::Value,
        path: &mut String,
        matches: &dyn Fn(&serde_json::Value) -> bool,
    ) -> Option<String> {
        if matches(x) && !path.is_empty() {
            return Some(path.clone());
        }
        let len = path.len();
        match x {
            serde_json::Value::Object(map) => map.iter().find_map(|(k, child)| {
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(k);
                let r = walk(child, path, matches);
                path.truncate(len);
                r
            }),
            serde_json::Value::Array(items) => items.iter().enumerate().find_map(|(i, child)| {
                path.push_str(&format!("[{i}]"));
                let r = walk(child, path, matches);
                path.truncate(len);
                r
            }),
            _ => None,
        }
    }
    walk(v, &mut String::new(), &matches)
}

impl From<Estimate> for Document {
    fn from(e: Estimate) -> Self {
        Document::new(e)
    }
}

/// The JSON Schema of [`Document`].
pub fn json_schema() -> serde_json::Value {
    serde_json::to_value(schemars::schema_for!(Document)).expect("a schema is JSON")
}
