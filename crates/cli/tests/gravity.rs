//! `limpid gravity-compensate` (seed 004 eq. 4-9) on a synthetic rig whose
//! sensor tilts with theta: bias in the sensor frame, weight in the reference frame.

mod common;
use common::*;
use nalgebra::{Matrix3, Vector3};

fn ry(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

#[test]
fn bias_and_weight_are_removed_and_the_force_on_the_limb_recovered() {
    let dir = tempfile::tempdir().unwrap();
    let fs = 1000.0;
    let n = 5000;
    let bias = Vector3::new(0.7, -1.3, 2.1);
    let weight_ref = Vector3::new(0.0, 0.0, -9.81 * 0.45); // handle + forearm, gravity along -z
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); 5];
    let mut truth = Vec::new();
    for k in 0..n {
        let t = k as f64 / fs;
        // still for the first second, then tilting and pushed
        let moving = t >= 1.0;
        let theta = if moving {
            0.3 * (2.0 * (t - 1.0)).sin()
        } else {
            0.0
        };
        let f_limb = if moving {
            Vector3::new(
                3.0 * (5.0 * t).sin(),
                1.0 * (3.0 * t).cos() - 1.0,
                2.0 * (7.0 * t).sin(),
            )
        } else {
            Vector3::zeros()
        };
        // the sensor reads the hand's force (-f) plus the weight it carries, in its own frame, plus its bias
        let reading = ry(theta).transpose() * (weight_ref - f_limb) + bias;
        cols[0].push(t);
        cols[1].push(theta);
        for a in 0..3 {
            cols[2 + a].push(reading[a]);
        }
        truth.push(f_limb);
    }
    let names = ["t", "theta", "sensor_fx", "sensor_fy", "sensor_fz"]
        .map(String::from)
        .to_vec();
    let rec_path = dir.path().join("test.csv");
    limpid_io::write_recording(
        &limpid_core::Recording::new(&rec_path, names.clone(), cols, 2).unwrap(),
        &rec_path,
    )
    .unwrap();
    // step 1: sensor turned so that gravity does not load it: it reads its bias
    let bias_cols = vec![
        (0..200).map(|k| k as f64 / fs).collect(),
        vec![0.0; 200],
        vec![bias[0]; 200],
        vec![bias[1]; 200],
        vec![bias[2]; 200],
    ];
    let bias_path = dir.path().join("bias.csv");
    limpid_io::write_recording(
        &limpid_core::Recording::new(&bias_path, names, bias_cols, 2).unwrap(),
        &bias_path,
    )
    .unwrap();
    let out_path = dir.path().join("out.csv");
    let out = limpid(&[
        "gravity-compensate",
        rec_path.to_str().unwrap(),
        "--bias",
        bias_path.to_str().unwrap(),
        "--initial-s",
        "0.5",
        "-o",
        out_path.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let got = limpid_io::read_recording(&out_path).unwrap();
    let mut worst = 0.0f64;
    for (a, c) in ["fx", "fy", "fz"].iter().enumerate() {
        for (k, v) in got.column(c).unwrap().iter().enumerate() {
            worst = worst.max((v - truth[k][a]).abs());
        }
    }
    assert!(worst < 1e-9, "force error {worst:e} N");

    // without sensor columns: a one-line error naming the file and the column
    let plain = dir.path().join("plain.csv");
    std::fs::write(&plain, "t,x\n0,0\n0.001,0\n").unwrap();
    let out = limpid(&[
        "gravity-compensate",
        plain.to_str().unwrap(),
        "--bias",
        bias_path.to_str().unwrap(),
        "-o",
        out_path.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("plain.csv") && out.stderr.contains("sensor_fx"),
        "{}",
        out.stderr
    );
}
