//! A co-contraction experiment split across an XDF file as a rig records it
//! (robot pose and force at 500 Hz, EMG at 2 kHz on a clock 12.3 ms behind,
//! with ClockOffset records, perturbation and level markers) gives the same
//! co-contraction index and per-level stiffness as the single-rate
//! recording of the same experiment (issue 40).

use limpid_analysis::cocontraction::estimate_cocontraction;
use limpid_analysis::emg::EmgParams;
use limpid_core::Recording;
use limpid_ident::prepare::PrepareParams;
use limpid_io::map::ChannelMap;
use limpid_lab::cocontraction::{
    seed001_population, simulate_cocontraction, CocontractionProtocol,
};
use limpid_lab::NoiseModel;
use limpid_testkit::xdf::{write, XdfStream};

const LSL_START: f64 = 4321.0;
const EMG_CLOCK_BEHIND: f64 = 0.0123;

/// The recording as three XDF streams; the robot keeps every 4th sample.
fn split(rec: &Recording) -> Vec<XdfStream> {
    let t = rec.t();
    let mut streams = Vec::new();
    let robot: Vec<&str> = ["x", "y", "z", "fx", "fy", "fz"]
        .into_iter()
        .filter(|c| rec.has(c))
        .collect();
    if !robot.is_empty() {
        let keep: Vec<usize> = (0..t.len()).step_by(4).collect();
        streams.push(XdfStream {
            name: "robot".into(),
            kind: "Position".into(),
            rate: rec.sample_rate() / 4.0,
            channels: robot
                .iter()
                .map(|c| {
                    let unit = if c.starts_with('f') { "N" } else { "mm" };
                    (format!("Robot.{}", c.to_uppercase()), unit.to_string())
                })
                .collect(),
            stamps: keep.iter().map(|&i| LSL_START + t[i]).collect(),
            values: robot
                .iter()
                .map(|c| {
                    let v = rec.column(c).unwrap();
                    let k = if c.starts_with('f') { 1.0 } else { 1e3 };
                    keep.iter().map(|&i| v[i] * k).collect()
                })
                .collect(),
            texts: Vec::new(),
            clock_offsets: Vec::new(),
        });
    }
    let emg: Vec<&String> = rec
        .names()
        .iter()
        .filter(|n| n.starts_with("emg_"))
        .collect();
    streams.push(XdfStream {
        name: "emg".into(),
        kind: "EMG".into(),
        rate: rec.sample_rate(),
        channels: emg
            .iter()
            .map(|n| (format!("EMG {}", &n[4..]), "uV".into()))
            .collect(),
        stamps: t.iter().map(|t| LSL_START + t - EMG_CLOCK_BEHIND).collect(),
        values: emg
            .iter()
            .map(|n| rec.column(n).unwrap().iter().map(|v| v * 1e6).collect())
            .collect(),
        texts: Vec::new(),
        clock_offsets: vec![
            (LSL_START - 5.0, EMG_CLOCK_BEHIND),
            (LSL_START + 500.0, EMG_CLOCK_BEHIND),
        ],
    });
    if let (Some(trial), Some(level)) = (rec.column("trial"), rec.column("level")) {
        let (mut stamps, mut texts) = (Vec::new(), Vec::new());
        for i in 0..t.len() {
            if i == 0 || trial[i] != trial[i - 1] {
                stamps.push(LSL_START + t[i]);
                texts.push(format!("level {}", level[i]));
                stamps.push(LSL_START + t[i]);
                texts.push("perturbation_start".into());
            }
        }
        streams.push(XdfStream {
            name: "events".into(),
            kind: "Markers".into(),
            rate: 0.0,
            channels: Vec::new(),
            stamps,
            values: Vec::new(),
            texts,
            clock_offsets: Vec::new(),
        });
    }
    streams
}

fn map(rec: &Recording, time_stream: &str) -> ChannelMap {
    let mut text = format!("[time]\nstream = \"{time_stream}\"\n[columns]\n");
    for c in ["x", "y", "z", "fx", "fy", "fz"] {
        if rec.has(c) {
            let unit = if c.starts_with('f') { "N" } else { "mm" };
            text += &format!(
                "{c} = {{ channel = \"Robot.{}\", unit = \"{unit}\" }}\n",
                c.to_uppercase()
            );
        }
    }
    for n in rec.names().iter().filter(|n| n.starts_with("emg_")) {
        // envelopes made at the EMG's 2 kHz, then sampled by the robot's clock
        text += &format!(
            "env_{} = {{ channel = \"EMG {}\", stream = \"emg\", unit = \"uV\" }}\n",
            &n[4..],
            &n[4..]
        );
    }
    if rec.has("trial") {
        text +=
            "trial = { marker = \"perturbation_start\" }\nlevel = { marker_prefix = \"level \" }\n";
    }
    ChannelMap::parse(&text).unwrap()
}

#[test]
fn a_cocontraction_experiment_split_across_xdf_streams_estimates_as_the_single_rate_file() {
    let population = seed001_population(1, 11);
    let subject = &population[0].2;
    let protocol = CocontractionProtocol {
        sample_rate: 2000.0,
        ..CocontractionProtocol::seed001()
    };
    let (rec, mvc) =
        simulate_cocontraction(subject, &protocol, &NoiseModel::default(), 11).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (rec_xdf, mvc_xdf) = (dir.path().join("session.xdf"), dir.path().join("mvc.xdf"));
    write(&rec_xdf, &split(&rec)).unwrap();
    write(&mvc_xdf, &split(&mvc)).unwrap();
    let (prep, emg) = (PrepareParams::default(), EmgParams::default());
    let whole = estimate_cocontraction(&rec, &mvc, &prep, &emg).unwrap();
    // the robot (500 Hz) sets the time base; the MVC recording has only EMG
    let from_xdf = limpid_io::read_recording_mapped(&rec_xdf, Some(&map(&rec, "robot"))).unwrap();
    let mvc_time = if mvc.has("x") { "robot" } else { "emg" };
    let mvc_from_xdf =
        limpid_io::read_recording_mapped(&mvc_xdf, Some(&map(&mvc, mvc_time))).unwrap();
    assert_eq!(from_xdf.sample_rate().round(), 500.0);
    let split_estimate = estimate_cocontraction(&from_xdf, &mvc_from_xdf, &prep, &emg).unwrap();
    assert_eq!(whole.levels.len(), split_estimate.levels.len());
    let given = split_estimate
        .warnings
        .iter()
        .any(|w| w.code == limpid_core::WarningCode::EnvelopesGiven);
    assert!(
        given,
        "the result says the envelopes came with the recording"
    );
    for (a, b) in whole.levels.iter().zip(&split_estimate.levels) {
        assert_eq!(a.level, b.level);
        let di =
            (a.cocontraction_index - b.cocontraction_index).abs() / a.cocontraction_index.max(0.05);
        assert!(
            di < 0.01,
            "level {}: index {} vs {}",
            a.level,
            a.cocontraction_index,
            b.cocontraction_index
        );
        let (ka, kb): (&nalgebra::DMatrix<f64>, &nalgebra::DMatrix<f64>) =
            (&a.stiffness, &b.stiffness);
        let dk = (ka - kb).norm() / ka.norm();
        eprintln!(
            "level {}: index {:.4} vs {:.4}, stiffness differs by {:.2} %",
            a.level,
            a.cocontraction_index,
            b.cocontraction_index,
            100.0 * dk
        );
        assert!(
            dk < 0.01,
            "level {}: stiffness differs by {:.2} %",
            a.level,
            100.0 * dk
        );
    }
}
