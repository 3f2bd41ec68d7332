//! `limpid._limpid`: the Rust side of the Python package, thin over the
//! library. Arrays come in as numpy arrays and go out as numpy arrays;
//! results go out as JSON text with the keys of the CLI's `--json`, which the
//! Python side turns into result objects. Errors raise `ValueError` (bad
//! input, with the library's one-line message) or `OSError` (files). Long
//! computations release the GIL.

use std::path::Path;

use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use limpid_analysis::result::{Document, Estimate};
use limpid_core::{Error, Recording};

mod spectral;
use spectral::{cross_spectra, frequency_response, lowpass_filtfilt};

fn err(e: Error) -> PyErr {
    let text = limpid_core::error::tidy_numbers(&e.to_string());
    match e {
        Error::Io { .. } => PyOSError::new_err(text),
        _ => PyValueError::new_err(text),
    }
}

/// This process's thread pool. Rayon's global pool does not survive `fork`:
/// a child inherits the pool's state but not its threads, and its first
/// parallel call waits for ever (Python's default start method on Linux
/// before 3.14). So the package keeps its own pool, tagged with the process
/// id; a forked child finds a foreign tag and builds a fresh pool.
/// The pool's size is the caller's ([`set_threads`]); 0: one thread a core.
fn pool() -> Result<std::sync::Arc<rayon::ThreadPool>, rayon::ThreadPoolBuildError> {
    use std::sync::Arc;
    let pid = std::process::id();
    let threads = match THREADS.load(std::sync::atomic::Ordering::Relaxed) {
        // rayon would read RAYON_NUM_THREADS: beyond the cap, one a core
        0 => match limpid_core::threads::environment_thread_count() {
            Ok(Some(n)) => n,
            Ok(None) => 0,
            Err(_) => std::thread::available_parallelism().map_or(1, |n| n.get()),
        },
        n => n,
    };
    let mut slot = POOL.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((owner, size, pool)) = slot.as_ref() {
        if *owner == pid && *size == threads {
            return Ok(pool.clone());
        }
    }
    match slot.take() {
        // this process's pool of another size: its threads end when it is dropped
        Some((owner, _, ours)) if owner == pid => drop(ours),
        // its threads exist only in the parent: never signal or wait for them
        Some((_, _, inherited)) => std::mem::forget(inherited),
        None => {}
    }
    let fresh = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("limpid-{i}"))
            .build()?,
    );
    *slot = Some((pid, threads, fresh.clone()));
    Ok(fresh)
}

/// The pool, the process that made it and the size it was asked for.
type Pool = Option<(u32, usize, std::sync::Arc<rayon::ThreadPool>)>;
static POOL: std::sync::Mutex<Pool> = std::sync::Mutex::new(None);
static THREADS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// How many threads limpid's estimators use (None: one a core).
#[pyfunction]
#[pyo3(signature = (threads=None))]
fn set_threads(threads: Option<u128>) -> PyResult<()> {
    if threads == Some(0) {
        return Err(PyValueError::new_err(
            "invalid threads: expected at least 1, or None for one a core",
        ));
    }
    let threads = match threads {
        Some(n) => limpid_core::threads::check_thread_count(n, "invalid threads")
            .map_err(PyValueError::new_err)?,
        None => 0,
    };
    THREADS.store(threads, std::sync::atomic::Ordering::Relaxed);
    Ok(())
}

/// Run `work` without the GIL on this process's thread pool (on the calling
/// thread alone if no pool can be started).
fn detached<T: Send>(py: Python<'_>, work: impl FnOnce() -> T + Send) -> T {
    match pool() {
        Ok(pool) => py.detach(|| pool.install(work)),
        Err(_) => py.detach(work),
    }
}

fn value_err(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(limpid_core::error::tidy_numbers(&e.to_string()))
}

/// A recording from a path (CSV or Parquet) or a dict of 1-D arrays.
fn recording(source: &Bound<'_, PyAny>) -> PyResult<Recording> {
    let rec = recording_unwarned(source)?;
    warn_about(source.py(), &rec)?;
    Ok(rec)
}

/// What the reader accepted but found suspicious: Python warnings, as the CLI's stderr lines.
fn warn_about(py: Python<'_>, rec: &Recording) -> PyResult<()> {
    for w in rec.warnings() {
        let message =
            std::ffi::CString::new(format!("{}: {w}", rec.path().display())).unwrap_or_default();
        PyErr::warn(
            py,
            &py.get_type::<pyo3::exceptions::PyUserWarning>(),
            &message,
            1,
        )?;
    }
    Ok(())
}

fn recording_unwarned(source: &Bound<'_, PyAny>) -> PyResult<Recording> {
    recording_through(source, &Reading::default())
}

/// How the files of a call are read: `map=` and `columns=` (issue 81: every
/// estimator takes them, as every CLI command takes --map and --column).
#[derive(Default)]
struct Reading {
    map: Option<limpid_io::map::ChannelMap>,
    columns: Vec<(String, String)>,
}

impl Reading {
    fn new(
        map: Option<&Bound<'_, PyAny>>,
        columns: Option<std::collections::BTreeMap<String, String>>,
    ) -> PyResult<Reading> {
        Ok(Reading {
            map: map.map(channel_map).transpose()?,
            columns: columns.unwrap_or_default().into_iter().collect(),
        })
    }
}

/// A recording from a path (through `reading`'s map and columns) or a dict of arrays.
fn recording_through(source: &Bound<'_, PyAny>, reading: &Reading) -> PyResult<Recording> {
    if let Ok(path) = source.extract::<std::path::PathBuf>() {
        // on the package's pool: the Parquet reader decodes columns in
        // parallel, and rayon's global pool hangs a forked child
        return detached(source.py(), || {
            limpid_io::convert_with_columns(&path, reading.map.as_ref(), &reading.columns)
                .map(|c| c.recording)
        })
        .map_err(err);
    }
    let dict = source.cast::<PyDict>().map_err(|_| {
        PyValueError::new_err("a recording is a path or a dict of 1-D float arrays")
    })?;
    let mut names = Vec::with_capacity(dict.len());
    let mut cols = Vec::with_capacity(dict.len());
    for (k, v) in dict.iter() {
        let name: String = k
            .extract()
            .map_err(|_| PyValueError::new_err("column names must be strings"))?;
        let arr: PyReadonlyArray1<f64> = v.extract().map_err(|_| {
            PyValueError::new_err(format!("column {name}: expected a 1-D float array"))
        })?;
        cols.push(arr.as_array().to_vec());
        names.push(name);
    }
    Recording::new("<arrays>", names, cols, 1).map_err(err)
}

/// A recording as a dict of numpy arrays (column order kept).
fn columns_dict<'py>(py: Python<'py>, rec: &Recording) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (name, col) in rec.columns() {
        d.set_item(name, col.to_vec().into_pyarray(py))?;
    }
    Ok(d)
}

/// Deepest nesting of dicts and lists taken from Python (a channel map is
/// four levels deep, a request three).
const MAX_PYTHON_NESTING: usize = 16;

/// Refuse a Python value nested deeper than [`MAX_PYTHON_NESTING`] or
/// containing itself, before serde walks it: the walk recurses on the
/// native stack and a dict that contains itself crashed the interpreter
/// (issue 56). `what` names the value in the error.
fn check_nesting(value: &Bound<'_, PyAny>, what: &str) -> PyResult<()> {
    fn walk(value: &Bound<'_, PyAny>, depth: usize, what: &str) -> PyResult<()> {
        let children: Vec<Bound<'_, PyAny>> = if let Ok(d) = value.cast::<PyDict>() {
            d.values().iter().collect()
        } else if let Ok(l) = value.cast::<pyo3::types::PyList>() {
            l.iter().collect()
        } else if let Ok(t) = value.cast::<pyo3::types::PyTuple>() {
            t.iter().collect()
        } else {
            return Ok(());
        };
        if depth >= MAX_PYTHON_NESTING {
            return Err(value_err(format!(
                "{what}: nested deeper than {MAX_PYTHON_NESTING} levels (or it contains itself)"
            )));
        }
        children.iter().try_for_each(|c| walk(c, depth + 1, what))
    }
    walk(value, 0, what)
}

/// A channel map from a TOML file's path or from a dict of the same shape
/// (through serde, as requests are).
fn channel_map(map: &Bound<'_, PyAny>) -> PyResult<limpid_io::map::ChannelMap> {
    if let Ok(path) = map.extract::<std::path::PathBuf>() {
        return limpid_io::map::ChannelMap::read(&path).map_err(err);
    }
    if map.cast::<PyDict>().is_err() {
        return Err(PyValueError::new_err(
            "map is the path of a channel map (TOML) or a dict like {'time': {...}, 'columns': {...}}",
        ));
    }
    check_nesting(map, "channel map")?;
    let mut de = pythonize::Depythonizer::from_object(map);
    let parsed: limpid_io::map::ChannelMap = serde::Deserialize::deserialize(&mut de)
        .map_err(|e| PyValueError::new_err(format!("channel map: {e}")))?;
    parsed
        .checked()
        .map_err(|m| PyValueError::new_err(format!("channel map: {m}")))
}

/// A recording file as a dict of numpy arrays (column order kept); lab
/// files (XDF, C3D, TDMS, MAT structs, ROS 2 bags) through a channel map.
#[pyfunction]
#[pyo3(signature = (path, map=None, partial=false, columns=None))]
fn read_recording<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    map: Option<Bound<'py, PyAny>>,
    partial: bool,
    columns: Option<std::collections::BTreeMap<String, String>>,
) -> PyResult<Bound<'py, PyDict>> {
    let reading = Reading::new(map.as_ref(), columns)?;
    let rec = detached(py, || {
        if partial {
            limpid_io::read_supporting_recording(&path, reading.map.as_ref())
        } else {
            limpid_io::convert_with_columns(&path, reading.map.as_ref(), &reading.columns)
                .map(|c| c.recording)
        }
    })
    .map_err(err)?;
    warn_about(py, &rec)?;
    columns_dict(py, &rec)
}

/// What a lab file holds (streams, channels, rates, units, gaps, markers,
/// a proposed map), as JSON text.
#[pyfunction]
fn inspect(py: Python<'_>, path: std::path::PathBuf) -> PyResult<String> {
    let found = detached(py, || {
        limpid_io::sources::read_source(&path).map(|s| limpid_io::inspect::inspect(&s))
    })
    .map_err(err)?;
    serde_json::to_string(&found).map_err(value_err)
}

/// A method's request from flat keyword options (`limpid_ident::request`):
/// the fields of its `prepare` or `arm` part are nested, `None` keeps a
/// default, and the request is made by serde from the Python objects.
fn build_request(
    method: &str,
    options: &Bound<'_, PyDict>,
) -> PyResult<limpid_ident::request::Request> {
    use limpid_ident::request::{deserialize_request, nesting};
    let py = options.py();
    let nested = nesting(method).map_err(err)?;
    let booleans = limpid_ident::request::boolean_options(method).map_err(err)?;
    let top = PyDict::new(py);
    let inner = PyDict::new(py);
    for (key, value) in options.iter() {
        if value.is_none() {
            continue;
        }
        let name: String = key
            .extract()
            .map_err(|_| value_err("option names must be strings"))?;
        // Python's True is also 1: keep numbers and truth values apart
        let is_bool = value.is_instance_of::<pyo3::types::PyBool>();
        if is_bool != booleans.contains(&name) {
            return Err(value_err(format!(
                "invalid {name}: expected {}, found {value}",
                if is_bool {
                    "a value other than True/False"
                } else {
                    "True or False"
                }
            )));
        }
        match &nested {
            Some((_, names)) if names.contains(&name) => inner.set_item(name, value)?,
            // the nested part itself, as a request's dict holds it
            Some((part, _)) if name == *part => {
                let given = value
                    .cast::<PyDict>()
                    .map_err(|_| value_err(format!("invalid {part}: expected a dict")))?;
                for (k, v) in given.iter() {
                    inner.set_item(k, v)?;
                }
            }
            _ => top.set_item(name, value)?,
        }
    }
    if let Some((name, _)) = nested {
        top.set_item(name, inner)?;
    }
    check_nesting(top.as_any(), "options")?;
    let mut de = pythonize::Depythonizer::from_object(top.as_any());
    deserialize_request(method, &mut de).map_err(|e| {
        let text = e.to_string();
        if text.contains("unknown field") {
            // as Python says of a keyword a function does not take
            pyo3::exceptions::PyTypeError::new_err(text)
        } else {
            err(e)
        }
    })
}

/// The package function of a method.
fn python_name(method: &str) -> String {
    match method {
        "window_sweep" | "spectra" => method.into(),
        other => format!("estimate_{other}"),
    }
}

/// The request flat keyword options make, as a dict (what a result's run
/// block records; `request(method, {})` shows every default).
#[pyfunction]
fn request<'py>(
    py: Python<'py>,
    method: &str,
    options: &Bound<'py, PyDict>,
) -> PyResult<Bound<'py, PyAny>> {
    // checked as an estimate checks it: `window_ms=inf` made a request that
    // serialised the value as null (issue 56)
    let checked = build_request(method, options)?.check().map_err(err)?;
    let r = checked.request();
    // through JSON's data model: lists, not tuples, as a result's run block reads back
    let value = serde_json::to_value(r).map_err(value_err)?;
    pythonize::pythonize(py, &value).map_err(value_err)
}

/// The JSON Schema of a method's request (its options' types, descriptions
/// and choices), from the same types the CLI's flags are derived from: the
/// Python signatures are generated from it (scripts/python-signatures.py).
#[pyfunction]
fn request_schema(method: &str) -> PyResult<String> {
    let schema = limpid_ident::request::method_schema(method).map_err(err)?;
    serde_json::to_string(&schema).map_err(value_err)
}

/// Any estimator (`method`: linear, cocontraction, planar, window_sweep,
/// stochastic, reflex, varying, spectra) on its recordings, with keyword options as
/// `limpid estimate METHOD`'s (or `limpid spectra`'s) flags; JSON text of the result.
#[pyfunction]
#[pyo3(signature = (method, recordings, options, map=None, columns=None))]
fn estimate(
    py: Python<'_>,
    method: &str,
    recordings: Vec<Bound<'_, PyAny>>,
    options: &Bound<'_, PyDict>,
    map: Option<Bound<'_, PyAny>>,
    columns: Option<std::collections::BTreeMap<String, String>>,
) -> PyResult<String> {
    let checked = build_request(method, options)?.check().map_err(err)?;
    let reading = Reading::new(map.as_ref(), columns)?;
    // files by their path, arrays as "<arrays>": the run block says which
    let names: Vec<std::path::PathBuf> = recordings
        .iter()
        .map(|r| {
            r.extract::<std::path::PathBuf>()
                .unwrap_or_else(|_| "<arrays>".into())
        })
        .collect();
    let recordings = recordings
        .iter()
        .map(|r| {
            let rec = recording_through(r, &reading)?;
            warn_about(py, &rec)?;
            Ok(rec)
        })
        .collect::<PyResult<Vec<_>>>()?;
    let inputs: Vec<&Path> = names.iter().map(|p| p.as_path()).collect();
    // what was read, before the recordings go to the estimator
    let run = limpid_analysis::result::Run::of_call(
        format!("Python: limpid.{}", python_name(method)),
        &inputs,
    )
    .with_request(checked.request())
    .with_channel_map(reading.map.as_ref().and_then(|m| m.path.as_deref()))
    .with_columns(&reading.columns)
    .with_recordings(&recordings);
    let mut document = detached(py, || limpid_app::estimate::run(&checked, recordings))
        .map_err(err)?
        .document;
    document.run = Some(run);
    Ok(document.to_json())
}

/// A study manifest with its paths resolved: JSON text of
/// `{"study": {"name", "tolerance"}, "recording": [{subject, configuration, file, mvc}]}`.
#[pyfunction]
fn study_entries(manifest: std::path::PathBuf) -> PyResult<String> {
    let m = limpid_app::study::load_manifest(&manifest).map_err(err)?;
    serde_json::to_string(&m).map_err(value_err)
}

/// One study recording (JSON text of a manifest entry) processed with the
/// study's request (co-contraction options, as `estimate_cocontraction`'s):
/// JSON text of `{"Ok": processed}` or `{"Err": failure}`.
#[pyfunction]
fn study_process(py: Python<'_>, entry: &str, request: &Bound<'_, PyDict>) -> PyResult<String> {
    use limpid_analysis::result::study::Entry;
    use limpid_app::study::process_entry;
    use limpid_ident::request::Request;
    let e: Entry = serde_json::from_str(entry).map_err(value_err)?;
    let Request::Cocontraction(request) = build_request("cocontraction", request)? else {
        unreachable!("a co-contraction request")
    };
    let out = detached(py, || process_entry(&e, &request));
    serde_json::to_string(&out).map_err(value_err)
}

/// Study tables from outcomes of `study_process` (JSON texts), written to
/// `out` when given; JSON text of the study document.
#[pyfunction]
#[pyo3(signature = (name, outcomes, out=None))]
fn study_combine(
    py: Python<'_>,
    name: String,
    outcomes: Vec<String>,
    out: Option<std::path::PathBuf>,
) -> PyResult<String> {
    use limpid_analysis::result::study::{Failure, Processed};
    let parsed = outcomes
        .iter()
        .enumerate()
        .map(|(i, text)| {
            serde_json::from_str::<std::result::Result<Processed, Failure>>(text).map_err(|e| {
                value_err(format!(
                    "outcome {}: not a study_process outcome ({e})",
                    i + 1
                ))
            })
        })
        .collect::<PyResult<Vec<_>>>()?;
    let result = detached(py, || {
        limpid_analysis::result::study::summarise(name, parsed)
    });
    finish_study(result, out)
}

/// `limpid study run`: every recording of the manifest (in parallel), the
/// tables written to `out` when given; JSON text of the study document.
#[pyfunction]
#[pyo3(signature = (manifest, out=None))]
fn study_run(
    py: Python<'_>,
    manifest: std::path::PathBuf,
    out: Option<std::path::PathBuf>,
) -> PyResult<String> {
    let m = limpid_app::study::load_manifest(&manifest).map_err(err)?;
    let result = detached(py, || limpid_app::study::run_study(&m, &|| {})).map_err(err)?;
    finish_study(result, out)
}

fn finish_study(
    result: limpid_analysis::result::study::StudyResult,
    out: Option<std::path::PathBuf>,
) -> PyResult<String> {
    if result.recordings.is_empty() {
        let first = result
            .failures
            .first()
            .map_or(String::new(), |f| format!(": {}", f.error));
        return Err(value_err(format!(
            "no recording could be processed (nothing written){first}"
        )));
    }
    if let Some(dir) = out {
        limpid_app::study::write_tables(&result, &dir).map_err(err)?;
    }
    Ok(document(Estimate::Study(result)))
}

/// The parameter rows of a result document (JSON text) as JSON text: the
/// rows the report's table shows (issue 77), for `to_pandas()`. Reflex
/// results only, for now.
#[pyfunction]
fn parameter_rows(document: &str) -> PyResult<String> {
    let d = limpid_analysis::result::Document::from_json("result", document).map_err(value_err)?;
    let rows = match &d.estimate {
        limpid_analysis::result::Estimate::Reflex(e) => e.parameters(),
        _ => return Err(value_err("parameter rows are made for reflex results")),
    };
    serde_json::to_string(&rows).map_err(value_err)
}

/// `value ± se` rounded to the standard error, as the report and the CLI
/// print it (limpid_core::with_standard_error).
#[pyfunction]
fn with_standard_error(value: f64, se: f64) -> String {
    limpid_core::with_standard_error(value, se)
}

/// The unit of element (row, column) of a stiffness, damping or inertia
/// matrix for these coordinate names (as the report writes it).
#[pyfunction]
fn matrix_element_unit(kind: &str, row: &str, column: &str) -> PyResult<String> {
    use limpid_core::criteria::MatrixKind;
    let kind = match kind {
        "stiffness" => MatrixKind::Stiffness,
        "damping" => MatrixKind::Damping,
        "inertia" => MatrixKind::Inertia,
        other => {
            return Err(value_err(format!(
                "expected stiffness, damping or inertia, found {other:?}"
            )))
        }
    };
    Ok(limpid_report::matrix_element_unit(kind, row, column))
}

/// The ellipsoid of the symmetric part of a 2 x 2 or 3 x 3 matrix; JSON text.
#[pyfunction]
fn ellipsoid(matrix: Vec<Vec<f64>>) -> PyResult<String> {
    let matrix = limpid_core::Matrix::from_rows(&matrix)
        .ok_or_else(|| value_err("the matrix's rows differ in length"))?;
    let n = matrix.0.nrows();
    if !(matrix.0.is_square() && (n == 2 || n == 3)) {
        return Err(value_err(format!(
            "ellipsoids are for 2 x 2 and 3 x 3 matrices, found {} x {}",
            n,
            matrix.0.ncols()
        )));
    }
    // issue 56: a NaN matrix was told it was not 2 x 2 or 3 x 3
    if matrix.0.iter().any(|v| !v.is_finite()) {
        return Err(value_err(
            "the matrix holds NaN or infinite values: no ellipsoid",
        ));
    }
    let e = limpid_analysis::ellipsoid(&matrix).ok_or_else(|| {
        value_err("no ellipsoid: the matrix's symmetric part has no real eigen-decomposition")
    })?;
    serde_json::to_string(&e).map_err(value_err)
}

/// A preset protocol as TOML text.
#[pyfunction]
fn protocol_preset(name: &str) -> PyResult<String> {
    Ok(limpid_lab::design::Design::preset(name)
        .map_err(err)?
        .to_toml())
}

/// Check a protocol (TOML text); JSON text of the report.
#[pyfunction]
fn protocol_check(py: Python<'_>, toml_text: &str) -> PyResult<String> {
    let d =
        limpid_lab::design::Design::from_toml(toml_text, Path::new("<protocol>")).map_err(err)?;
    let r = detached(py, || limpid_lab::design::check(&d)).map_err(err)?;
    serde_json::to_string(&r).map_err(value_err)
}

/// Design a protocol for `method` (linear, stochastic, reflex or planar), as
/// `limpid protocol design`: the prior (`demo:...` or a prior file's text,
/// named `prior_name` in errors), the limits from the method's protocol text
/// (else the prior's `[limits]`), the baseline's text. Returns (the designed
/// protocol as TOML, the result document as JSON).
#[pyfunction]
#[pyo3(signature = (prior, duration_s, limits_from=None, objective="stiffness,damping", baseline=None, verify=0, runs=40, seed=1, prior_name="<prior>", method="linear", robust="worst"))]
#[allow(clippy::too_many_arguments)]
fn design(
    py: Python<'_>,
    prior: &str,
    duration_s: f64,
    limits_from: Option<&str>,
    objective: &str,
    baseline: Option<&str>,
    verify: usize,
    runs: usize,
    seed: u64,
    prior_name: &str,
    method: &str,
    robust: &str,
) -> PyResult<(String, String)> {
    use limpid_analysis::result::{Document, Estimate};
    if method == "reflex" {
        if verify > 0 {
            return Err(value_err("verify is for the linear, stochastic and planar methods: the reflex design's prediction is already the spread over `runs` simulated recordings".to_string()));
        }
        if robust != "worst" {
            return Err(value_err(
                "robust is for the linear, stochastic and planar methods: a reflex prior has no range",
            ));
        }
        let request = limpid_app::design::reflex::reflex_request_from_texts(
            (prior, Path::new(prior_name)),
            limits_from.map(|t| (t, Path::new("<limits_from>"))),
            baseline.map(|t| (t, Path::new("<baseline>"))),
            duration_s,
            runs,
            seed,
        )
        .map_err(err)?;
        let designed =
            detached(py, || limpid_app::design::reflex::design_reflex(&request)).map_err(err)?;
        let toml = limpid_lab::design::Design::Periodic(designed.protocol).to_toml();
        let doc = Document::new(Estimate::ReflexDesign(designed.result));
        return Ok((toml, doc.to_json()));
    }
    if !matches!(method, "linear" | "stochastic" | "planar") {
        return Err(value_err(format!(
            "method: expected linear, stochastic, reflex or planar, found {method:?}"
        )));
    }
    let inputs = limpid_app::design::DesignInputs {
        prior: (prior, Path::new(prior_name)),
        limits_from: limits_from.map(|t| (t, Path::new("<limits_from>"))),
        baseline: baseline.map(|t| (t, Path::new("<baseline>"))),
        budget_s: duration_s,
        objective,
        robust,
        runs,
        verify,
        seed,
    };
    let (toml, result) = detached(py, || {
        limpid_app::design::design_from_texts(method, &inputs)
    })
    .map_err(err)?;
    Ok((toml, Document::new(result).to_json()))
}

/// Simulate a protocol (TOML text), as `limpid simulate`: on `subject` (TOML
/// text, named `subject_name` in errors) or the built-in subjects, stochastic
/// protocols held by `controller` (ideal, imbic, pd). One (columns, truth
/// JSON) per recording.
#[pyfunction]
#[pyo3(signature = (toml_text, seed=1, subject=None, subject_name="<subject>", controller="ideal"))]
fn simulate<'py>(
    py: Python<'py>,
    toml_text: &str,
    seed: u64,
    subject: Option<&str>,
    subject_name: &str,
    controller: &str,
) -> PyResult<Vec<(Bound<'py, PyDict>, String)>> {
    use limpid_lab::session::{simulate_design, RigController, SubjectText};
    let d =
        limpid_lab::design::Design::from_toml(toml_text, Path::new("<protocol>")).map_err(err)?;
    limpid_lab::design::check(&d).map_err(err)?;
    let controller: RigController = controller.parse().map_err(value_err)?;
    let name = Path::new(subject_name);
    let subject = subject.map(|text| SubjectText { text, path: name });
    let runs = detached(py, || {
        simulate_design(&d, subject.as_ref(), controller, seed)
    })
    .map_err(err)?;
    runs.into_iter()
        .map(|run| {
            let truth = serde_json::to_string(&run.truth).map_err(|e| value_err(e.to_string()))?;
            Ok((columns_dict(py, &run.recording)?, truth))
        })
        .collect()
}

/// Gravity compensation of F/T readings, as `limpid gravity-compensate`:
/// seed 004's two steps (`bias`, `initial_s`) or a calibration from still
/// poses (`calibration`); the orientation from `robot` (placed at
/// `robot_base`), else `theta`. Returns (columns, summary lines).
#[pyfunction]
#[pyo3(signature = (recording, bias=None, calibration=None, initial_s=1.0, robot=None, robot_base=None))]
fn gravity_compensate<'py>(
    py: Python<'py>,
    recording: &Bound<'py, PyAny>,
    bias: Option<&Bound<'py, PyAny>>,
    calibration: Option<&Bound<'py, PyAny>>,
    initial_s: f64,
    robot: Option<&str>,
    robot_base: Option<Vec<f64>>,
) -> PyResult<(Bound<'py, PyDict>, Vec<String>)> {
    use limpid_lab::gravity::{compensate, LoadSource};
    let mut rec = self::recording(recording)?;
    let robot = robot
        .map(|name| limpid_app::estimate::placed_robot(name, robot_base.as_deref()))
        .transpose()
        .map_err(err)?;
    let bias = bias.map(self::recording).transpose()?;
    let calibration = calibration.map(self::recording).transpose()?;
    let source = match (&bias, &calibration) {
        (Some(bias), None) => LoadSource::TwoSteps { bias, initial_s },
        (None, Some(cal)) => LoadSource::Calibration(cal),
        _ => {
            return Err(value_err(
                "give exactly one of bias (two steps) and calibration",
            ))
        }
    };
    let summary = detached(py, || compensate(&mut rec, source, robot.as_ref())).map_err(err)?;
    Ok((columns_dict(py, &rec)?, summary))
}

/// Write the HTML report of JSON results (texts) to `path`.
#[pyfunction]
fn report(py: Python<'_>, results: Vec<String>, path: std::path::PathBuf) -> PyResult<()> {
    let docs: Vec<Document> = results
        .iter()
        .enumerate()
        .map(|(i, t)| Document::from_json(&format!("result {}", i + 1), t).map_err(value_err))
        .collect::<PyResult<_>>()?;
    // the recordings the results were made from are inputs: never replaced (issue 56)
    let recordings: Vec<std::path::PathBuf> = docs
        .iter()
        .filter_map(|d| d.estimate.recording().map(std::path::PathBuf::from))
        .collect();
    let named: Vec<(&Path, &str)> = recordings
        .iter()
        .map(|p| (p.as_path(), "the recording of a result"))
        .collect();
    limpid_core::files::refuse_overwriting_inputs(&[(&path, "the report path")], &named)
        .map_err(value_err)?;
    let named: Vec<(String, &Document)> = docs
        .iter()
        .enumerate()
        .map(|(i, d)| (limpid_report::section_name(d, i), d))
        .collect();
    let r = detached(py, || limpid_report::build_documents(&named));
    limpid_core::files::write_file(&path, limpid_report::to_html(&r).as_bytes())
        .map_err(|e| PyOSError::new_err(e.to_string()))
}

/// Check a result document (JSON text) as `limpid report` reads one: its
/// kind's fields, types and shapes; the error names the field.
#[pyfunction]
fn check_result(text: &str) -> PyResult<()> {
    Document::from_json("result", text)
        .map(|_| ())
        .map_err(value_err)
}

/// A result as the JSON document of `limpid_analysis::result`.
fn document(e: Estimate) -> String {
    Document::new(e).to_json()
}

#[pymodule]
fn _limpid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(cross_spectra, m)?)?;
    m.add_function(wrap_pyfunction!(lowpass_filtfilt, m)?)?;
    m.add_function(wrap_pyfunction!(frequency_response, m)?)?;
    m.add_function(wrap_pyfunction!(read_recording, m)?)?;
    m.add_function(wrap_pyfunction!(inspect, m)?)?;
    m.add_function(wrap_pyfunction!(request, m)?)?;
    m.add_function(wrap_pyfunction!(request_schema, m)?)?;
    m.add_function(wrap_pyfunction!(estimate, m)?)?;
    m.add_function(wrap_pyfunction!(gravity_compensate, m)?)?;
    m.add_function(wrap_pyfunction!(ellipsoid, m)?)?;
    m.add_function(wrap_pyfunction!(study_entries, m)?)?;
    m.add_function(wrap_pyfunction!(study_process, m)?)?;
    m.add_function(wrap_pyfunction!(study_combine, m)?)?;
    m.add_function(wrap_pyfunction!(study_run, m)?)?;
    m.add_function(wrap_pyfunction!(protocol_preset, m)?)?;
    m.add_function(wrap_pyfunction!(protocol_check, m)?)?;
    m.add_function(wrap_pyfunction!(design, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(report, m)?)?;
    m.add_function(wrap_pyfunction!(check_result, m)?)?;
    m.add_function(wrap_pyfunction!(with_standard_error, m)?)?;
    m.add_function(wrap_pyfunction!(parameter_rows, m)?)?;
    m.add_function(wrap_pyfunction!(matrix_element_unit, m)?)?;
    m.add_function(wrap_pyfunction!(set_threads, m)?)?;
    Ok(())
}
