//! Issue 59: `limpid spectra --period` on periodic recordings: the response
//! at the excited lines against the analytic one, within its standard
//! errors; the distortion verdict of linear, quadratic and cubic systems;
//! each input's response from zippered multi-input multisines.

use crate::common::*;

use limpid_dsp::excitation::{multisine, multisine_lines, optimise_phases, LineSet};
use std::f64::consts::PI;
use std::path::Path;

/// A Gaussian-like deviate (sum of 12 uniforms), reproducible.
fn noise(seed: &mut u64) -> f64 {
    (0..12)
        .map(|_| {
            *seed ^= *seed << 13;
            *seed ^= *seed >> 7;
            *seed ^= *seed << 17;
            (*seed >> 11) as f64 / (1u64 << 53) as f64
        })
        .sum::<f64>()
        - 6.0
}

const FS: f64 = 500.0;
const PERIOD_S: f64 = 4.0;

/// A joint (I, B, K) driven through a torque multisine, integrated exactly
/// enough at 50 x the sample rate; the angle has `c` x angle² (quadratic)
/// or `d` x angle³ (cubic) stiffness added, and noise of `sigma` rad.
fn joint_recording(
    path: &Path,
    periods: usize,
    (c, d): (f64, f64),
    sigma: f64,
    with_period_column: bool,
) -> (f64, f64, f64) {
    let (inertia, damping, stiffness) = (0.02, 0.5, 40.0);
    let n = (FS * PERIOD_S) as usize;
    let lines = multisine_lines(PERIOD_S, [0.5, 20.0], LineSet::RandomOdd, 5).unwrap();
    let amplitudes = vec![1.0; lines.len()];
    let phases = optimise_phases(n, &lines, &amplitudes);
    let one = multisine(n, &lines, &amplitudes, &phases);
    let rms = (one.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    let total = n * (periods + 1);
    let (mut q, mut v) = (0.0f64, 0.0f64);
    let sub = 50;
    let h = 1.0 / (FS * sub as f64);
    let mut seed = 11u64;
    let mut text = String::from(if with_period_column {
        "t,tau1,q1,period\n"
    } else {
        "t,tau1,q1\n"
    });
    for i in 0..total {
        let torque = 2.0 * one[i % n] / rms;
        let next = 2.0 * one[(i + 1) % n] / rms;
        // the angle at this sample's time, then the torque interpolated to the next
        let period = if i < n { -1 } else { (i / n - 1) as i64 };
        let measured = q + sigma * noise(&mut seed);
        for s in 0..sub {
            let f = (s as f64 + 0.5) / sub as f64;
            let applied = torque * (1.0 - f) + next * f;
            let spring = stiffness * q + c * q * q + d * q * q * q;
            let a = (applied - damping * v - spring) / inertia;
            v += h * a;
            q += h * v;
        }
        if with_period_column {
            text.push_str(&format!(
                "{},{torque:e},{measured:e},{period}\n",
                i as f64 / FS
            ));
        } else {
            text.push_str(&format!("{},{torque:e},{measured:e}\n", i as f64 / FS));
        }
    }
    std::fs::write(path, text).unwrap();
    (inertia, damping, stiffness)
}

fn spectra(path: &Path, inputs: &str, outputs: &str) -> serde_json::Value {
    json(&[
        "spectra",
        path.to_str().unwrap(),
        "--inputs",
        inputs,
        "--outputs",
        outputs,
        "--period",
        &PERIOD_S.to_string(),
        "--json",
    ])
}

#[test]
fn the_response_of_a_linear_joint_is_found_at_its_excited_lines() {
    let d = tempfile::tempdir().unwrap();
    let path = d.path().join("joint.csv");
    // noise well above the simulation's own error, so that the SEs are tested
    let (i, b, k) = joint_recording(&path, 8, (0.0, 0.0), 2e-3, true);
    let v = spectra(&path, "tau1", "q1");
    validate(&v);
    let p = &v["periodic"];
    assert_eq!(p["periods"], 8);
    assert!(
        p["transient"].as_str().unwrap().contains("numbered -1"),
        "{}",
        p["transient"]
    );
    let frf = &p["frf"][0];
    let f: Vec<f64> = serde_json::from_value(frf["frequency_hz"].clone()).unwrap();
    let mag: Vec<f64> = serde_json::from_value(frf["magnitude"].clone()).unwrap();
    let se: Vec<f64> = serde_json::from_value(frf["magnitude_se"].clone()).unwrap();
    let phase: Vec<f64> = serde_json::from_value(frf["phase_deg"].clone()).unwrap();
    assert!(f.len() > 20, "{} excited lines", f.len());
    let mut covered = 0;
    for j in 0..f.len() {
        let w = 2.0 * PI * f[j];
        // angle over torque: 1 / (K - I w² + j B w)
        let (re, im) = (k - i * w * w, b * w);
        let truth = 1.0 / (re * re + im * im).sqrt();
        let truth_phase = -im.atan2(re).to_degrees();
        let err = (mag[j] - truth).abs();
        // the criterion: 3 %, or 4 SE where the noise rules 3 % out
        let allowed = (0.03 * truth).max(4.0 * se[j]);
        assert!(
            err < allowed,
            "{} Hz: |G| {} ± {} vs {truth}",
            f[j],
            mag[j],
            se[j]
        );
        assert!(
            (phase[j] - truth_phase).abs() < 3.0f64.max((allowed / truth).to_degrees()),
            "{} Hz: phase {} vs {truth_phase}",
            f[j],
            phase[j]
        );
        covered += usize::from(err < 2.0 * se[j]);
    }
    assert!(
        covered * 10 >= 8 * f.len(),
        "±2 SE covered {covered} of {}",
        f.len()
    );
    let distortion = &p["distortion"];
    assert_eq!(distortion["verdict"], "linear", "{distortion}");
    // lines and kinds as the contract names them
    let kinds: std::collections::BTreeSet<&str> = p["lines"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["kind"].as_str().unwrap())
        .collect();
    assert_eq!(
        kinds.into_iter().collect::<Vec<_>>(),
        ["even_detection", "excited", "odd_detection"]
    );
}

#[test]
fn quadratic_and_cubic_stiffness_show_at_their_detection_lines() {
    let d = tempfile::tempdir().unwrap();
    let quadratic = d.path().join("quadratic.csv");
    joint_recording(&quadratic, 8, (100.0, 0.0), 2e-5, false);
    let v = spectra(&quadratic, "tau1", "q1");
    let dist = &v["periodic"]["distortion"];
    assert_eq!(dist["verdict"], "nonlinear", "{dist}");
    let (even, noise) = (
        dist["even_db"].as_f64().unwrap(),
        dist["noise_db"].as_f64().unwrap(),
    );
    assert!(even > noise + 6.0, "{dist}");
    assert!(v["periodic"]["transient"]
        .as_str()
        .unwrap()
        .contains("first period"));
    let cubic = d.path().join("cubic.csv");
    joint_recording(&cubic, 8, (0.0, 40.0 * 400.0), 2e-5, false);
    let v = spectra(&cubic, "tau1", "q1");
    let dist = &v["periodic"]["distortion"];
    assert_eq!(dist["verdict"], "nonlinear", "{dist}");
    assert!(
        dist["odd_db"].as_f64().unwrap() > dist["even_db"].as_f64().unwrap() + 6.0,
        "{dist}"
    );
    // the text: CSV on stdout, the verdict on stderr
    let out = limpid(&[
        "spectra",
        cubic.to_str().unwrap(),
        "--inputs",
        "tau1",
        "--outputs",
        "q1",
        "--period",
        "4",
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out
        .stdout
        .starts_with("frequency_hz,kind,output_level_db,noise_level_db,magnitude_tau1_q1"));
    assert!(out.stderr.contains(": nonlinear"), "{}", out.stderr);
}

#[test]
fn a_period_that_is_not_whole_samples_or_given_with_segments_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let path = d.path().join("joint.csv");
    joint_recording(&path, 4, (0.0, 0.0), 0.0, false);
    let p = path.to_str().unwrap();
    for (extra, says) in [
        (vec!["--period", "4.0007"], "whole number of samples"),
        (vec!["--period", "4", "--nfft", "512"], "whole periods"),
        (vec!["--period", "-4"], "--period"),
    ] {
        let mut args = vec!["spectra", p, "--inputs", "tau1", "--outputs", "q1"];
        args.extend(extra);
        let out = limpid(&args);
        assert_eq!(out.code, 2, "{args:?}: {}", out.stdout);
        assert!(out.stderr.contains(says), "{args:?}: {}", out.stderr);
    }
}

#[test]
fn zippered_multisines_give_each_inputs_response() {
    let d = tempfile::tempdir().unwrap();
    let path = d.path().join("mimo.csv");
    let n = (FS * PERIOD_S) as usize;
    let lines = multisine_lines(PERIOD_S, [0.5, 20.0], LineSet::Full, 1).unwrap();
    // input j takes every third line from the j-th
    let inputs: Vec<Vec<f64>> = (0..3)
        .map(|j| {
            let own: Vec<usize> = lines.iter().copied().skip(j).step_by(3).collect();
            let amplitudes = vec![1.0; own.len()];
            let phases = optimise_phases(n, &own, &amplitudes);
            multisine(n, &own, &amplitudes, &phases)
        })
        .collect();
    // outputs: y_o = gain_oj * u_j (static mixing), plus noise
    let gains = [[1.0, 0.5, 0.0], [0.0, 2.0, -1.0], [0.3, 0.0, 1.5]];
    let mut seed = 3u64;
    let mut text = String::from("t,u1,u2,u3,y1,y2,y3\n");
    for i in 0..n * 9 {
        let u: Vec<f64> = inputs.iter().map(|s| s[i % n]).collect();
        let y: Vec<f64> = gains
            .iter()
            .map(|g| g.iter().zip(&u).map(|(g, u)| g * u).sum::<f64>() + 0.01 * noise(&mut seed))
            .collect();
        text.push_str(&format!(
            "{},{},{},{},{},{},{}\n",
            i as f64 / FS,
            u[0],
            u[1],
            u[2],
            y[0],
            y[1],
            y[2]
        ));
    }
    std::fs::write(&path, text).unwrap();
    let v = spectra(&path, "u1,u2,u3", "y1,y2,y3");
    let frf = v["periodic"]["frf"].as_array().unwrap();
    assert_eq!(frf.len(), 9);
    for pair in frf {
        let (i, o) = (
            pair["input"].as_str().unwrap()[1..]
                .parse::<usize>()
                .unwrap()
                - 1,
            pair["output"].as_str().unwrap()[1..]
                .parse::<usize>()
                .unwrap()
                - 1,
        );
        let mag: Vec<f64> = serde_json::from_value(pair["magnitude"].clone()).unwrap();
        let truth: f64 = gains[o][i].abs();
        for m in &mag {
            assert!(
                (m - truth).abs() < 0.03 * truth.max(0.05),
                "G{o}{i}: {m} vs {truth}"
            );
        }
    }
}

#[test]
fn multisine_and_prbs_protocols_check_export_and_simulate() {
    let d = tempfile::tempdir().unwrap();
    let multisine = preset(d.path(), "ankle-multisine");
    let v = json(&["protocol", "check", multisine.to_str().unwrap(), "--json"]);
    let cf = v["crest_factor"][0].as_f64().unwrap();
    assert!(cf < 1.6, "crest factor {cf}");
    assert!(v["detection_lines"].as_u64().unwrap() > 50);
    // the command in its own coordinates, faded in and out, period-numbered
    let command = d.path().join("cmd.csv");
    let out = limpid(&[
        "protocol",
        "export",
        multisine.to_str().unwrap(),
        "-o",
        command.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let text = std::fs::read_to_string(&command).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), "t,q1,period");
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 80_000);
    assert_eq!((rows[0][1], rows[0][2]), (0.0, -1.0));
    assert_eq!(rows[10_000][2], 0.0);
    assert!(rows.last().unwrap()[1].abs() < 1e-6);
    let peak = rows.iter().map(|r| r[1].abs()).fold(0.0, f64::max);
    assert!(peak <= 0.1, "{peak}");
    // a robot is refused: the command is in its own coordinates
    let out = limpid(&[
        "protocol",
        "export",
        multisine.to_str().unwrap(),
        "--robot",
        "puma3",
        "-o",
        command.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("leave out --robot"), "{}", out.stderr);
    // simulated on the reflex-free ankle: linear, K within 3 % at low frequency
    let subject = d.path().join("ankle.toml");
    std::fs::write(
        &subject,
        "inertia = 0.015\ndamping = 0.8\nstiffness = 80.0\n",
    )
    .unwrap();
    let rec = d.path().join("rec.csv");
    let out = limpid(&[
        "simulate",
        multisine.to_str().unwrap(),
        "--subject",
        subject.to_str().unwrap(),
        "-o",
        rec.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let v = json(&[
        "spectra",
        rec.to_str().unwrap(),
        "--inputs",
        "q1",
        "--outputs",
        "tau1",
        "--period",
        "10",
        "--json",
    ]);
    let p = &v["periodic"];
    assert_eq!(p["periods"], 6);
    assert_eq!(p["distortion"]["verdict"], "linear", "{}", p["distortion"]);
    let f: Vec<f64> = serde_json::from_value(p["frf"][0]["frequency_hz"].clone()).unwrap();
    let mag: Vec<f64> = serde_json::from_value(p["frf"][0]["magnitude"].clone()).unwrap();
    for (f, m) in f.iter().zip(&mag) {
        let w = 2.0 * PI * f;
        let truth = ((80.0 - 0.015 * w * w).powi(2) + (0.8 * w).powi(2)).sqrt();
        assert!((m - truth).abs() < 0.03 * truth, "{f} Hz: {m} vs {truth}");
    }
    // the report draws the lines, the noise and |G| with its units
    let html = d.path().join("periodic.html");
    let out = limpid(&[
        "spectra",
        rec.to_str().unwrap(),
        "--inputs",
        "q1",
        "--outputs",
        "tau1",
        "--period",
        "10",
        "--report",
        html.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let page = std::fs::read_to_string(&html).unwrap();
    for text in [
        "Output at excited and detection lines",
        "odd detection",
        "Periodic analysis",
        "|G| (N m/rad)",
        "linear",
    ] {
        assert!(page.contains(text), "the report lacks {text:?}");
    }
    // with the default ankle's half-wave rectified reflex: nonlinear, at the even lines
    let out = limpid(&[
        "simulate",
        multisine.to_str().unwrap(),
        "-o",
        rec.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let v = json(&[
        "spectra",
        rec.to_str().unwrap(),
        "--inputs",
        "q1",
        "--outputs",
        "tau1",
        "--period",
        "10",
        "--json",
    ]);
    let dist = &v["periodic"]["distortion"];
    assert_eq!(dist["verdict"], "nonlinear", "{dist}");
    assert!(
        dist["even_db"].as_f64().unwrap() > dist["noise_db"].as_f64().unwrap() + 20.0,
        "{dist}"
    );
    // the PRBS preset: a maximum-length sequence of order 7 at 150 ms
    let prbs = preset(d.path(), "ankle-prbs");
    let out = limpid(&[
        "protocol",
        "export",
        prbs.to_str().unwrap(),
        "-o",
        command.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let text = std::fs::read_to_string(&command).unwrap();
    let q: Vec<f64> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    let n = 127 * 150;
    let levels: Vec<f64> = (0..127).map(|j| q[n + j * 150 + 75].signum()).collect();
    assert_eq!(levels, limpid_dsp::excitation::mls(7).unwrap());
    assert!(q[n..2 * n].iter().all(|v| v.abs() <= 0.03 + 1e-12));
}

#[test]
fn inertia_damping_and_stiffness_come_from_the_excited_lines_with_honest_errors() {
    let d = tempfile::tempdir().unwrap();
    let linear = d.path().join("linear.csv");
    // noise well above the simulation's own error, so that the SEs are tested
    let (inertia, damping, stiffness) = joint_recording(&linear, 8, (0.0, 0.0), 2e-3, true);
    // the impedance: displacement in, torque out
    let v = spectra(&linear, "q1", "tau1");
    let z = &v["periodic"]["impedance"];
    let se = &z["standard_errors"];
    for (key, truth) in [
        ("inertia", inertia),
        ("damping", damping),
        ("stiffness", stiffness),
    ] {
        let (est, err) = (
            z[key][0][0].as_f64().unwrap(),
            se[key][0][0].as_f64().unwrap(),
        );
        assert!(err > 0.0, "{key}: {z}");
        assert!(
            (est - truth).abs() < 3.0 * err,
            "{key}: {est} ± {err} vs {truth}"
        );
        assert!(
            (est - truth).abs() < 0.02 * truth,
            "{key}: {est} vs {truth}"
        );
    }
    assert_eq!(z["verdicts"]["stiffness"], "trusted", "{z}");
    let ratio = z["residual_ratio"].as_f64().unwrap();
    assert!(
        ratio < 2.0,
        "a linear joint's fit is within its noise: {ratio}"
    );
    // a cubic spring: the best linear approximation, not trusted, and errors
    // scaled by how far the model misses
    let cubic = d.path().join("cubic.csv");
    joint_recording(&cubic, 8, (0.0, 40.0 * 400.0), 2e-5, true);
    let v = spectra(&cubic, "q1", "tau1");
    let z = &v["periodic"]["impedance"];
    assert_ne!(z["verdicts"]["stiffness"], "trusted", "{z}");
    assert!(z["residual_ratio"].as_f64().unwrap() > 5.0, "{z}");
    let out = limpid(&[
        "spectra",
        cubic.to_str().unwrap(),
        "--inputs",
        "q1",
        "--outputs",
        "tau1",
        "--period",
        "4",
    ]);
    assert!(
        out.stderr.contains("best linear approximation"),
        "{}",
        out.stderr
    );
    // torque in, angle out is not an impedance: no fit
    let v = spectra(&linear, "tau1", "q1");
    assert!(
        v["periodic"].get("impedance").is_none(),
        "{}",
        v["periodic"]
    );
}

#[test]
fn time_domain_methods_accept_a_periodic_recording_and_say_so() {
    let d = tempfile::tempdir().unwrap();
    let path = d.path().join("joint.csv");
    let (inertia, damping, stiffness) = joint_recording(&path, 6, (0.0, 0.0), 2e-5, true);
    let out = limpid(&["estimate", "reflex", path.to_str().unwrap(), "--json"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(
        out.stderr.contains("a periodic recording"),
        "{}",
        out.stderr
    );
    let v: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
    let i = &v["intrinsic"];
    // the torque-driven joint through the reflex-free cascade
    for (key, truth) in [
        ("inertia", inertia),
        ("damping", damping),
        ("stiffness", stiffness),
    ] {
        let est = i[key].as_f64().unwrap();
        assert!(
            (est - truth).abs() < 0.05 * truth,
            "{key}: {est} vs {truth}"
        );
    }
}

#[test]
fn a_periodic_result_whose_arrays_disagree_is_refused_by_the_report() {
    let d = tempfile::tempdir().unwrap();
    let path = d.path().join("joint.csv");
    joint_recording(&path, 4, (0.0, 0.0), 2e-3, true);
    let good = spectra(&path, "q1", "tau1");
    let html = d.path().join("r.html");
    for (edit, says) in [
        (
            "/periodic/impedance/stiffness",
            "periodic.impedance.stiffness",
        ),
        ("/periodic/frf/0/magnitude", "periodic.frf[0].magnitude"),
    ] {
        let mut bad = good.clone();
        let target = bad.pointer_mut(edit).unwrap();
        *target = if edit.ends_with("stiffness") {
            serde_json::json!([[1.0, 2.0]])
        } else {
            serde_json::json!([1.0])
        };
        let file = d.path().join("bad.json");
        std::fs::write(&file, bad.to_string()).unwrap();
        let out = limpid(&[
            "report",
            file.to_str().unwrap(),
            "-o",
            html.to_str().unwrap(),
        ]);
        assert_eq!(out.code, 2, "{edit}: {}", out.stderr);
        assert!(out.stderr.contains(says), "{edit}: {}", out.stderr);
        assert_eq!(out.stderr.trim_end().lines().count(), 1, "{}", out.stderr);
        assert!(!out.stderr.contains("internal error"), "{}", out.stderr);
    }
}

/// `simulate` of a periodic protocol and `spectra --period` of what it wrote:
/// each element of M, B and K against the truth written beside it.
fn simulated_impedance(
    dir: &Path,
    protocol: &Path,
    subject: Option<&str>,
    name: &str,
) -> (serde_json::Value, serde_json::Value) {
    let rec = dir.join(format!("{name}.csv"));
    let mut args = vec![
        "simulate",
        protocol.to_str().unwrap(),
        "-o",
        rec.to_str().unwrap(),
        "--seed",
        "5",
    ];
    let subject_path = dir.join(format!("{name}.toml"));
    if let Some(text) = subject {
        std::fs::write(&subject_path, text).unwrap();
        args.extend(["--subject", subject_path.to_str().unwrap()]);
    }
    let out = limpid(&args);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let truth: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(format!("{name}.truth.json"))).unwrap(),
    )
    .unwrap();
    let coordinates: Vec<String> = serde_json::from_value(truth["coordinates"].clone()).unwrap();
    let forces: Vec<String> = coordinates
        .iter()
        .map(|c| match c.as_str() {
            "x" | "y" | "z" => format!("f{c}"),
            q => format!("tau{}", &q[1..]),
        })
        .collect();
    let period = protocol_period(protocol);
    let v = json(&[
        "spectra",
        rec.to_str().unwrap(),
        "--inputs",
        &coordinates.join(","),
        "--outputs",
        &forces.join(","),
        "--period",
        &period.to_string(),
        "--json",
    ]);
    (v["periodic"].clone(), truth)
}

fn protocol_period(protocol: &Path) -> f64 {
    let text = std::fs::read_to_string(protocol).unwrap();
    let table: toml::Value = toml::from_str(&text).unwrap();
    table["period_s"].as_float().unwrap()
}

/// The largest |estimate - truth| / SE over the elements of M, B and K.
fn worst_z(periodic: &serde_json::Value, truth: &serde_json::Value) -> f64 {
    let z = &periodic["impedance"];
    let mut worst = 0.0f64;
    for m in ["inertia", "damping", "stiffness"] {
        let est: Vec<Vec<f64>> = serde_json::from_value(z[m].clone()).unwrap();
        let se: Vec<Vec<f64>> = serde_json::from_value(z["standard_errors"][m].clone()).unwrap();
        let want: Vec<Vec<f64>> = serde_json::from_value(truth[m].clone()).unwrap();
        for i in 0..est.len() {
            for j in 0..est.len() {
                worst = worst.max((est[i][j] - want[i][j]).abs() / se[i][j]);
            }
        }
    }
    worst
}

#[test]
fn end_point_and_planar_multisines_play_on_their_virtual_subjects() {
    let d = tempfile::tempdir().unwrap();
    // the 3-D end point (seed 000, S1) under a zippered random-odd multisine
    let endpoint = preset(d.path(), "endpoint-multisine");
    let (p, truth) = simulated_impedance(d.path(), &endpoint, None, "linear");
    assert_eq!(truth["method"], "periodic");
    assert_eq!(p["distortion"]["verdict"], "linear", "{}", p["distortion"]);
    assert_eq!(p["impedance"]["verdicts"]["stiffness"], "trusted");
    let z = worst_z(&p, &truth);
    assert!(z < 4.0, "worst element {z} SE from the truth");
    // a stiffening spring along x: odd distortion, and the best linear
    // approximation stiffer than the linear part, not trusted
    let matrices = "inertia = [[0.4, 0.03, 0.02], [0.03, 0.35, 0.01], [0.02, 0.01, 0.19]]\n\
                    damping = [[80.0, 22.0, 25.0], [22.0, 50.0, 47.0], [25.0, 47.0, 86.0]]\n\
                    stiffness = [[1002.0, 12.0, 26.0], [12.0, 250.0, 94.0], [26.0, 94.0, 320.0]]\n";
    let (p, truth) = simulated_impedance(
        d.path(),
        &endpoint,
        Some(&format!("{matrices}cubic = [3e7, 0.0, 0.0]\n")),
        "cubic",
    );
    assert_eq!(truth["cubic"][0], 3e7);
    let dist = &p["distortion"];
    assert_eq!(dist["verdict"], "nonlinear", "{dist}");
    assert_eq!(dist["odd_above_noise"], true, "{dist}");
    assert_ne!(p["impedance"]["verdicts"]["stiffness"], "trusted");
    let kxx = p["impedance"]["stiffness"][0][0].as_f64().unwrap();
    assert!(kxx > 1.1 * 1002.0, "best linear K_xx {kxx}");
    // a quadratic term: even distortion, which an odd multisine keeps off
    // its excited lines, so M, B, K stay the linear part's
    let (p, truth) = simulated_impedance(
        d.path(),
        &endpoint,
        Some(&format!("{matrices}quadratic = [3e5, 0.0, 0.0]\n")),
        "quadratic",
    );
    let dist = &p["distortion"];
    assert_eq!(dist["verdict"], "nonlinear", "{dist}");
    assert_eq!(
        (
            dist["even_above_noise"].clone(),
            dist["odd_above_noise"].clone()
        ),
        (true.into(), false.into()),
        "{dist}"
    );
    assert_eq!(p["impedance"]["verdicts"]["stiffness"], "trusted");
    let z = worst_z(&p, &truth);
    assert!(z < 4.0, "worst element {z} SE from the truth");
    // the planar arm: its Coriolis term is an even distortion; the joint
    // impedance about the posture (inertia M(q0)) is found within its SEs
    let planar = preset(d.path(), "planar-multisine");
    let (p, truth) = simulated_impedance(d.path(), &planar, None, "planar");
    assert_eq!(
        p["distortion"]["even_above_noise"], true,
        "{}",
        p["distortion"]
    );
    assert_eq!(p["impedance"]["verdicts"]["stiffness"], "trusted");
    let z = worst_z(&p, &truth);
    assert!(z < 4.0, "worst element {z} SE from the truth");
    // a joint protocol with channels the arm does not have is refused
    let text = std::fs::read_to_string(&planar)
        .unwrap()
        .replace("\"q2\"", "\"q3\"");
    let renamed = d.path().join("q3.toml");
    std::fs::write(&renamed, text).unwrap();
    let out = limpid(&[
        "simulate",
        renamed.to_str().unwrap(),
        "-o",
        d.path().join("q3.csv").to_str().unwrap(),
    ]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("channel \"q3\""), "{}", out.stderr);
}

#[test]
fn the_stochastic_estimate_of_a_periodic_recording_averages_whole_periods() {
    let d = tempfile::tempdir().unwrap();
    let endpoint = preset(d.path(), "endpoint-multisine");
    let rec = d.path().join("rec.csv");
    let out = limpid(&[
        "simulate",
        endpoint.to_str().unwrap(),
        "-o",
        rec.to_str().unwrap(),
        "--seed",
        "6",
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.path().join("rec.truth.json")).unwrap())
            .unwrap();
    let estimate = |extra: &[&str]| {
        let mut args = vec![
            "estimate",
            "stochastic",
            rec.to_str().unwrap(),
            "--period",
            "20",
            "--band",
            "0.2,6",
            "--json",
        ];
        args.extend(extra);
        json(&args)
    };
    let r = estimate(&[]);
    // a position-controlled rig's recording: the displacements classify
    // the lines; the fit is the periodic one
    assert_eq!(r["inputs"], serde_json::json!(["x", "y", "z"]));
    assert_eq!(r["criteria"]["segments"], 6);
    assert_eq!(r["periodic"]["distortion"]["verdict"], "linear");
    assert_eq!(r["criteria"]["verdicts"]["stiffness"], "trusted");
    // zippered: another coordinate at a coordinate's line is noise only
    assert!(r["criteria"]["max_input_coherence"].as_f64().unwrap() < 1e-3);
    let mut worst = 0.0f64;
    for m in ["inertia", "damping", "stiffness"] {
        for i in 0..3 {
            for j in 0..3 {
                let est = r[m][i][j].as_f64().unwrap();
                let se = r["standard_errors"][m][i][j].as_f64().unwrap();
                let want = truth[m][i][j].as_f64().unwrap();
                worst = worst.max((est - want).abs() / se);
            }
        }
    }
    assert!(worst < 4.0, "worst element {worst} SE from the truth");
    // Z on groups of lines: within 3 % of the truth's K - w^2 M + j w B on the diagonal
    let freqs: Vec<f64> = serde_json::from_value(r["frequencies"].clone()).unwrap();
    assert!(freqs.len() >= 10, "{} groups", freqs.len());
    let mat = |name: &str, i: usize, j: usize| truth[name][i][j].as_f64().unwrap();
    for (k, f) in freqs.iter().enumerate() {
        let w = 2.0 * PI * f;
        for i in 0..3 {
            let re = mat("stiffness", i, i) - w * w * mat("inertia", i, i);
            let im = w * mat("damping", i, i);
            let z = &r["impedance"][k][i][i];
            let (zr, zi) = (z[0].as_f64().unwrap(), z[1].as_f64().unwrap());
            let err = ((zr - re).powi(2) + (zi - im).powi(2)).sqrt() / (re * re + im * im).sqrt();
            assert!(err < 0.03, "{f} Hz, Z[{i}][{i}] off by {err}");
        }
    }
    let coherence: Vec<f64> =
        serde_json::from_value(r["coherence"]["multiple"][3].clone()).unwrap();
    assert!(coherence.iter().all(|c| *c > 0.9), "{coherence:?}");
    // with commanded forces u* (the format's inputs; here 1000 N/m times the
    // exported command) the commands classify the same lines: the same fit
    let command = d.path().join("command.csv");
    let out = limpid(&[
        "protocol",
        "export",
        endpoint.to_str().unwrap(),
        "-o",
        command.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let commands = std::fs::read_to_string(&command).unwrap();
    let recorded = std::fs::read_to_string(&rec).unwrap();
    let merged: String = recorded
        .lines()
        .zip(commands.lines())
        .enumerate()
        .map(|(row, (r, c))| {
            let cells: Vec<&str> = c.split(',').collect();
            let forces = if row == 0 {
                "ux,uy,uz".to_string()
            } else {
                cells[1..4]
                    .iter()
                    .map(|v| (1000.0 * v.parse::<f64>().unwrap()).to_string())
                    .collect::<Vec<_>>()
                    .join(",")
            };
            format!("{r},{forces}\n")
        })
        .collect();
    let with_u = d.path().join("with_u.csv");
    std::fs::write(&with_u, merged).unwrap();
    let u = json(&[
        "estimate",
        "stochastic",
        with_u.to_str().unwrap(),
        "--period",
        "20",
        "--band",
        "0.2,6",
        "--json",
    ]);
    assert_eq!(u["inputs"], serde_json::json!(["ux", "uy", "uz"]));
    assert!(u["criteria"]["max_input_coherence"].as_f64().unwrap() < 1e-12);
    let (k, ku) = (
        r["stiffness"][0][0].as_f64().unwrap(),
        u["stiffness"][0][0].as_f64().unwrap(),
    );
    assert!((k - ku).abs() < 1e-9 * k, "{k} vs {ku}");
    // a period with Welch segments, pooled trials or too narrow a band is refused by name
    let path = rec.to_str().unwrap();
    for (extra, want) in [
        (vec![path, "--nfft", "1024"], "--period"),
        (vec![path, path], "one recording"),
        (vec![path, "--band", "5.9,6"], "widen --band"),
    ] {
        let args: Vec<&str> = ["estimate", "stochastic"]
            .into_iter()
            .chain(extra)
            .chain(["--period", "20"])
            .collect();
        let out = limpid(&args);
        assert_eq!(out.code, 2, "{args:?}: {}", out.stderr);
        assert!(out.stderr.contains(want), "{args:?}: {}", out.stderr);
    }
    // the text names the periods and the report draws the lines
    let html = d.path().join("r.html");
    let out = limpid(&[
        "estimate",
        "stochastic",
        rec.to_str().unwrap(),
        "--period",
        "20",
        "--band",
        "0.2,6",
        "--report",
        html.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains("periodic: 6 periods"), "{}", out.stdout);
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("Output at excited and detection lines"));
}
