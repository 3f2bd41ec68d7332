//! Whole studies (seed 001 Tables 1-5), run: the manifest read, every
//! recording processed in parallel, the tables written, virtual studies
//! simulated. The manifest, the outcomes and the tables are
//! [`limpid_analysis::result::study`]'s.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::Serialize;

use limpid_analysis::cocontraction::CocontractionResult;
use limpid_analysis::result::study::{summarise, Entry, Failure, Manifest, Processed, StudyResult};
use limpid_analysis::result::Estimate;
use limpid_core::truth::{About, CocontractionTruth, LevelTruth, Truth};
use limpid_core::{Error, Result};
use limpid_ident::request::{CocontractionRequest, Request};

/// Read and check a manifest; relative paths are resolved against its folder.
pub fn load_manifest(path: &Path) -> Result<Manifest> {
    let text = limpid_core::files::read_text(path)?;
    let mut m: Manifest =
        toml::from_str(&text).map_err(|e| Error::settings(path, &text, e.span(), e.message()))?;
    if m.recording.is_empty() {
        return Err(Error::Format {
            path: path.to_path_buf(),
            message: "no [[recording]] entry: nothing to process".into(),
        });
    }
    if m.recording.len() > MAX_STUDY_RECORDINGS {
        return Err(Error::Format {
            path: path.to_path_buf(),
            message: format!(
                "{} [[recording]] entries; limpid runs at most {MAX_STUDY_RECORDINGS} per study: split it",
                m.recording.len()
            ),
        });
    }
    // the request is checked here, at the boundary, not once per recording
    Request::Cocontraction(m.study.request()?)
        .check()
        .map_err(|e| Error::Format {
            path: path.to_path_buf(),
            message: format!("[study.request]: {e}"),
        })?;
    let base = path.parent().unwrap_or(Path::new("."));
    for e in &mut m.recording {
        e.file = base.join(&e.file);
        e.mvc = base.join(&e.mvc);
        e.map = e
            .map
            .take()
            .or_else(|| m.study.map.clone())
            .map(|p| base.join(p));
    }
    // every map is read once here, so a mistake in one is found before any recording
    let mut maps: Vec<&Path> = m
        .recording
        .iter()
        .filter_map(|e| e.map.as_deref())
        .collect();
    maps.sort();
    maps.dedup();
    for map in maps {
        limpid_io::map::ChannelMap::read(map)?;
    }
    refuse_repeats(path, &m.recording)?;
    Ok(m)
}

/// A study counts each recording once: a file listed twice (under any
/// subject) would be averaged as independent data (issue 36). Repeated
/// recordings of one subject and configuration are separate files.
fn refuse_repeats(path: &Path, entries: &[Entry]) -> Result<()> {
    let mut files = std::collections::HashMap::new();
    for (i, e) in entries.iter().enumerate() {
        let key = std::fs::canonicalize(&e.file).unwrap_or_else(|_| e.file.clone());
        if let Some(j) = files.insert(key, i) {
            return Err(Error::Format {
                path: path.to_path_buf(),
                message: format!(
                    "[[recording]] entries {} and {} name the same file {} (subjects {:?} and {:?}): a study counts each recording once",
                    j + 1,
                    i + 1,
                    e.file.display(),
                    entries[j].subject,
                    e.subject
                ),
            });
        }
    }
    Ok(())
}

/// One recording of a study: its co-contraction analysis, or why it failed
/// (in one line; a panic in one recording, a bug, is caught as a failure too,
/// so it cannot abort the study). Runs anywhere: a study may be spread over
/// processes or machines and its outcomes joined by [`summarise`].
pub fn process_entry(
    e: &Entry,
    request: &CocontractionRequest,
) -> std::result::Result<Processed, Failure> {
    let run = || -> Result<CocontractionResult> {
        let checked = Request::Cocontraction(request.clone()).check()?;
        let map = e
            .map
            .as_deref()
            .map(limpid_io::map::ChannelMap::read)
            .transpose()?;
        let rec = limpid_io::read_recording_mapped(&e.file, map.as_ref())?;
        // the MVC recording may record less than the session (EMG only)
        let mvc = limpid_io::read_supporting_recording(&e.mvc, map.as_ref())?;
        if !["x", "y", "z"].iter().all(|c| rec.has(c)) {
            return Err(Error::Format {
                path: e.file.clone(),
                message: "study tables need 3-D recordings (x, y, z)".into(),
            });
        }
        match crate::estimate::run(&checked, vec![rec, mvc])?
            .document
            .estimate
        {
            Estimate::Cocontraction(result) => Ok(result),
            _ => unreachable!("a co-contraction request gives a co-contraction result"),
        }
    };
    limpid_core::error::catch_panic(&e.file, "estimation", run)
        .map(|result| Processed {
            subject: e.subject.clone(),
            configuration: e.configuration.clone(),
            result,
        })
        .map_err(|err| Failure {
            subject: e.subject.clone(),
            configuration: e.configuration.clone(),
            file: e.file.display().to_string(),
            error: err.to_string(),
        })
}

/// Process every recording (in parallel) with the manifest's request;
/// `progress` is called once per recording.
pub fn run_study(m: &Manifest, progress: &(dyn Fn() + Sync)) -> Result<StudyResult> {
    let request = m.study.request()?;
    let outcomes: Vec<std::result::Result<Processed, Failure>> = m
        .recording
        .par_iter()
        .map(|e| {
            let out = process_entry(e, &request);
            progress();
            out
        })
        .collect();
    Ok(summarise(
        m.study.name.clone().unwrap_or_else(|| "study".into()),
        outcomes,
    ))
}

/// Largest number of `[[recording]]` entries a manifest may list.
pub const MAX_STUDY_RECORDINGS: usize = 100_000;

/// [`run_study`] for a study written to `dir`: each recording's full result
/// (with its fit traces) is staged as `recordings/<name>.json` in `outputs`
/// as soon as it is processed, and only the slim result (no traces) is kept,
/// so memory does not grow with the traces of every recording (issue 36:
/// 0.6 MB per entry). Commit `outputs` after [`stage_tables`].
pub fn run_study_staged(
    m: &Manifest,
    dir: &Path,
    outputs: &mut limpid_core::files::OutputSet,
    progress: &(dyn Fn() + Sync),
) -> Result<StudyResult> {
    let request = m.study.request()?;
    outputs.create_dir(&dir.join("recordings"))?;
    let names = recording_names(
        m.recording
            .iter()
            .map(|e| (e.subject.as_str(), e.configuration.as_str())),
    );
    // the first staging error (a full disk) is the study's
    let staging = std::sync::Mutex::new((outputs, None::<Error>));
    let outcomes: Vec<std::result::Result<Processed, Failure>> = m
        .recording
        .par_iter()
        .zip(&names)
        .map(|(e, name)| {
            let mut out = process_entry(e, &request);
            if let Ok(p) = &mut out {
                let text = recording_json(&p.result);
                let mut guard = staging.lock().unwrap_or_else(|e| e.into_inner());
                if let Err(err) = guard.0.add(&dir.join(name), text.as_bytes()) {
                    guard.1.get_or_insert(err);
                }
                drop(guard);
                slim(&mut p.result);
            }
            progress();
            out
        })
        .collect();
    let (_, error) = staging.into_inner().unwrap_or_else(|e| e.into_inner());
    if let Some(e) = error {
        return Err(e);
    }
    Ok(summarise(
        m.study.name.clone().unwrap_or_else(|| "study".into()),
        outcomes,
    ))
}

/// A recording's full result document, as `recordings/<name>.json` holds it.
fn recording_json(r: &CocontractionResult) -> String {
    limpid_analysis::result::Document::new(Estimate::Cocontraction(r.clone())).to_json()
}

/// A co-contraction result without its fit traces (kept in the per-recording files).
fn slim(r: &mut CocontractionResult) {
    for l in &mut r.levels {
        let t = &mut l.estimate.fit.traces;
        t.time = Vec::new();
        t.measured.iter_mut().for_each(|v| *v = Vec::new());
        t.predicted.iter_mut().for_each(|v| *v = Vec::new());
    }
}

/// `recordings/s<subject>_c<configuration>.json` per manifest entry, in
/// manifest order; a subject's second recording of one configuration is `_2`.
fn recording_names<'a>(ids: impl Iterator<Item = (&'a str, &'a str)>) -> Vec<String> {
    let mut used = std::collections::HashSet::new();
    ids.map(|(subject, configuration)| {
        let stem = format!(
            "recordings/s{}_c{}",
            file_safe(subject),
            file_safe(configuration)
        );
        let mut name = format!("{stem}.json");
        let mut k = 2;
        while !used.insert(name.clone()) {
            name = format!("{stem}_{k}.json");
            k += 1;
        }
        name
    })
    .collect()
}

/// A virtual seed 001 study: `subjects` drawn from the seed 001 population,
/// each in the 7 arm configurations, simulated (`limpid_lab`) and written to
/// `dir` as `s<subject>_c<config>.parquet`, its MVC recording and a
/// `.truth.json` with the stiffness per level, with the manifest
/// `study.toml` that `run_study` reads. Returns the number of recordings and
/// the manifest's path; `progress` is called once per recording.
///
/// `realistic`: the subjects of [`limpid_lab::cocontraction::seed001_realistic_population`]
/// (seed 001 Tables 1-5, reflex, [`limpid_lab::NoiseModel::realistic`]) and,
/// as seed 001 does, one MVC — configuration 5's — for all configurations;
/// otherwise the clean population with an MVC per recording.
pub fn simulate_study(
    dir: &Path,
    subjects: usize,
    realistic: bool,
    seed: u64,
    progress: &(dyn Fn() + Sync),
) -> Result<(usize, PathBuf)> {
    use limpid_lab::cocontraction::{
        seed001_population, seed001_realistic_population, simulate_cocontraction,
        CocontractionProtocol,
    };
    limpid_core::files::create_dir(dir)?;
    let (population, noise) = if realistic {
        (
            seed001_realistic_population(subjects, seed),
            limpid_lab::NoiseModel::realistic(),
        )
    } else {
        (
            seed001_population(subjects, seed),
            limpid_lab::NoiseModel::default(),
        )
    };
    let protocol = CocontractionProtocol::seed001();
    let entries: Vec<String> = population
        .par_iter()
        .map(|(s, c, subject)| -> Result<String> {
            let seed = seed.wrapping_mul(10_000) + (*s as u64) * 100 + *c as u64;
            let (rec, mvc) = simulate_cocontraction(subject, &protocol, &noise, seed)?;
            let file = format!("s{s}_c{c}.parquet");
            let mvc_file = if realistic {
                format!("s{s}_c5.mvc.parquet")
            } else {
                format!("s{s}_c{c}.mvc.parquet")
            };
            limpid_io::write_recording(&rec, dir.join(&file))?;
            if !realistic || *c == 5 {
                limpid_io::write_recording(&mvc, dir.join(&mvc_file))?;
            }
            let truth = Truth::Cocontraction(CocontractionTruth {
                about: About {
                    sample_rate: Some(protocol.sample_rate),
                    notes: vec!["made by limpid study --simulate: K per level of a Patel, O'Neill & Artemiadis virtual subject".into()],
                    ..About::default()
                },
                inertia: Some(limpid_core::Matrix::from(subject.inertia)),
                damping: Some(limpid_core::Matrix::from(subject.damping)),
                equilibrium: None,
                levels: protocol
                    .levels
                    .iter()
                    .map(|l| LevelTruth {
                        level: *l,
                        stiffness: limpid_core::Matrix::from(subject.stiffness(*l)),
                        cocontraction_index: None,
                        muscle_activation: None,
                    })
                    .collect(),
                stiffness_level0: None,
                stiffness_increment_per_unit_level: None,
                other: Default::default(),
            });
            let text = serde_json::to_string_pretty(&truth).expect("truth serialises");
            limpid_core::files::write_file(&dir.join(format!("s{s}_c{c}.truth.json")), text.as_bytes())?;
            progress();
            Ok(format!(
                "[[recording]]\nsubject = \"{s}\"\nconfiguration = \"{c}\"\nfile = \"{file}\"\nmvc = \"{mvc_file}\"\n"
            ))
        })
        .collect::<Result<_>>()?;
    let manifest = format!(
        "# virtual Patel, O'Neill & Artemiadis (2013) study: {subjects} {} subjects x 7 configurations x 4 levels x 18 perturbations\n[study]\nname = \"virtual Patel, O'Neill & Artemiadis (2013) study\"\n\n{}",
        if realistic { "realistic" } else { "ideal" },
        entries.join("\n")
    );
    let path = dir.join("study.toml");
    limpid_core::files::write_file(&path, manifest.as_bytes())?;
    Ok((population.len(), path))
}

/// Write `tables.csv`, `rotation.csv`, `study.json`, `tables.md` and each
/// recording's full result (`recordings/`) into `dir`, as one set: all or
/// none (issue 36).
pub fn write_tables(r: &StudyResult, dir: &Path) -> Result<Vec<PathBuf>> {
    let mut outputs = limpid_core::files::OutputSet::new();
    outputs.create_dir(&dir.join("recordings"))?;
    let mut written = stage_tables(r, dir, &mut outputs)?;
    let names = recording_names(
        r.recordings
            .iter()
            .map(|p| (p.subject.as_str(), p.configuration.as_str())),
    );
    for (p, name) in r.recordings.iter().zip(names) {
        written.push(outputs.add(&dir.join(&name), recording_json(&p.result).as_bytes())?);
    }
    outputs.commit()?;
    Ok(written)
}

/// Stage `tables.csv`, `rotation.csv`, `study.json`, `tables.md` of `dir`
/// in `outputs`; returns their paths.
pub fn stage_tables(
    r: &StudyResult,
    dir: &Path,
    outputs: &mut limpid_core::files::OutputSet,
) -> Result<Vec<PathBuf>> {
    outputs.create_dir(dir)?;
    let mut write = |name: &str, text: String| -> Result<PathBuf> {
        outputs.add(&dir.join(name), text.as_bytes())
    };
    // study.json keeps every number but not the fit traces (150 kB per level
    // and recording); each recording's full result is in recordings/
    let mut slimmed = r.clone();
    for p in &mut slimmed.recordings {
        slim(&mut p.result);
    }
    let json = study_json(&slimmed).map_err(|e| Error::Format {
        path: dir.join("study.json"),
        message: e.to_string(),
    })?;
    Ok(vec![
        write("tables.csv", limpid_report::text::study_levels_csv(r))?,
        write("rotation.csv", limpid_report::text::study_rotation_csv(r))?,
        write("study.json", json)?,
        write("tables.md", limpid_report::text::study_markdown(r))?,
    ])
}

/// An id as part of a file name: letters, digits, '-' and '_' kept, others '_'.
fn file_safe(id: &str) -> String {
    id.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The study's result document (`limpid_analysis::result`, kind "study"), serialised
/// without copying the study.
fn study_json(r: &StudyResult) -> serde_json::Result<String> {
    #[derive(Serialize)]
    struct StudyDocument<'a> {
        schema: u32,
        kind: &'static str,
        #[serde(flatten)]
        study: &'a StudyResult,
    }
    serde_json::to_string_pretty(&StudyDocument {
        schema: limpid_analysis::result::SCHEMA_VERSION,
        kind: "study",
        study: r,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use limpid_analysis::result::{Document, Estimate};

    #[test]
    fn the_borrowed_study_document_is_the_result_contract() {
        let study = StudyResult {
            name: "t".into(),
            levels: vec![],
            rotation: vec![],
            failures: vec![Failure {
                subject: "s1".into(),
                configuration: "c1".into(),
                file: "a.csv".into(),
                error: "bad".into(),
            }],
            recordings: vec![],
        };
        let borrowed = study_json(&study).unwrap();
        let owned = serde_json::to_string_pretty(&Document::new(Estimate::Study(study))).unwrap();
        assert_eq!(borrowed, owned);
        assert!(Document::from_json("study.json", &borrowed).is_ok());
    }
}
