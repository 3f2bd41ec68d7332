//! `limpid protocol` and `limpid simulate` (issue 3, first part).

use crate::common::*;

#[test]
fn preset_checks_simulates_and_estimates_back_to_its_truth() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("p.toml");
    let out = limpid(&[
        "protocol",
        "new",
        "--preset",
        "artemiadis-3d",
        "-o",
        p.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let check = limpid(&["protocol", "check", p.to_str().unwrap()]);
    assert_eq!(check.code, 0, "{}", check.stderr);
    assert!(
        check.stdout.contains("96 trials") && check.stdout.contains("minimum angular separation"),
        "{}",
        check.stdout
    );
    let rec = dir.path().join("rec.parquet");
    let sim = limpid(&[
        "simulate",
        p.to_str().unwrap(),
        "-o",
        rec.to_str().unwrap(),
        "--seed",
        "5",
    ]);
    assert_eq!(sim.code, 0, "{}", sim.stderr);
    for s in 1..=6 {
        let r = dir.path().join(format!("rec_S{s}.parquet"));
        let truth = read_json(&dir.path().join(format!("rec_S{s}.truth.json")));
        let est = json(&["estimate", "linear", r.to_str().unwrap(), "--json"]);
        let ek = rel_err(&mat(&est["stiffness"]), &mat(&truth["stiffness"]));
        assert!(ek < 0.03, "S{s}: stiffness error {ek}");
    }
}

#[test]
fn over_fast_protocol_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("fast.toml");
    let text = limpid(&["protocol", "new", "--preset", "patel-cocontraction"])
        .stdout
        .replace("centre_out_s = 0.1", "centre_out_s = 0.02");
    std::fs::write(&p, text).unwrap();
    let out = limpid(&["protocol", "check", p.to_str().unwrap()]);
    assert_eq!(out.code, 2);
    let line = out.stderr.trim_end();
    assert!(
        line.starts_with(&format!(
            "limpid: {}: invalid protocol: acceleration (m/s^2) ",
            p.display()
        )),
        "{line}"
    );
    assert!(
        line.contains("exceeds the limit 8 at start point 1, target 1"),
        "{line}"
    );
    let unknown = limpid(&["protocol", "new", "--preset", "nope"]);
    assert_eq!(unknown.code, 2);
    // every preset is named (issue 81: --help listed 6 of the 12)
    for name in limpid_lab::design::PRESET_NAMES {
        assert!(unknown.stderr.contains(name), "{name}: {}", unknown.stderr);
    }
    let help = limpid(&["protocol", "new", "--help"]);
    for name in limpid_lab::design::PRESET_NAMES {
        assert!(help.stdout.contains(name), "{name}: {}", help.stdout);
    }
}

#[test]
fn export_for_the_kuka_and_estimate_from_robot_joint_angles() {
    use limpid_robot::Robot;
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("p.toml");
    assert_eq!(
        limpid(&[
            "protocol",
            "new",
            "--preset",
            "patel-cocontraction",
            "-o",
            p.to_str().unwrap()
        ])
        .code,
        0
    );
    let traj = dir.path().join("traj.parquet");
    let out = limpid(&[
        "protocol",
        "export",
        p.to_str().unwrap(),
        "--robot",
        "kuka-lwr4",
        "-o",
        traj.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    // the exported joints reproduce the exported end-effector path with the orientation held
    let rec = limpid_io::read_recording(&traj).unwrap();
    // the preset places the robot's base below and behind the workspace, facing it
    let base = [-0.05, 0.0, -0.6, 0.0, 0.0, std::f64::consts::PI];
    let robot = Robot::kuka_lwr4().placed([base[0], base[1], base[2]], [base[3], base[4], base[5]]);
    let q: Vec<&[f64]> = (1..=7)
        .map(|i| rec.column(&format!("robot_q{i}")).unwrap())
        .collect();
    let first = robot.fk(&(0..7).map(|j| q[j][0]).collect::<Vec<_>>());
    for k in (0..rec.len()).step_by(97) {
        let t = robot.fk(&(0..7).map(|j| q[j][k]).collect::<Vec<_>>());
        for (a, name) in ["x", "y", "z"].iter().enumerate() {
            assert!((t[(a, 3)] - rec.column(name).unwrap()[k]).abs() < 1e-9);
        }
        assert!((t.fixed_view::<3, 3>(0, 0) - first.fixed_view::<3, 3>(0, 0)).norm() < 1e-9);
    }

    // a simulated recording whose end point is known only through the robot's joint angles
    let sim = dir.path().join("rec.parquet");
    assert_eq!(
        limpid(&["simulate", p.to_str().unwrap(), "-o", sim.to_str().unwrap()]).code,
        0
    );
    let truth = read_json(&dir.path().join("rec.truth.json"));
    let rec = limpid_io::read_recording(&sim).unwrap();
    let orientation: nalgebra::Matrix3<f64> =
        robot.fk(&robot.home()).fixed_view::<3, 3>(0, 0).into();
    let positions: Vec<nalgebra::Vector3<f64>> = (0..rec.len())
        .map(|k| {
            nalgebra::Vector3::new(
                rec.column("x").unwrap()[k],
                rec.column("y").unwrap()[k],
                rec.column("z").unwrap()[k],
            )
        })
        .collect();
    let start = robot
        .reach(&positions[0], &orientation, &robot.home())
        .unwrap();
    let joints = robot.track(&positions, &orientation, &start).unwrap();
    let mut names: Vec<String> = vec![
        "t".into(),
        "fx".into(),
        "fy".into(),
        "fz".into(),
        "trial".into(),
    ];
    let mut cols: Vec<Vec<f64>> = names
        .iter()
        .map(|n| rec.column(n).unwrap().to_vec())
        .collect();
    // x, y, z must be present for the coordinates; --robot overwrites them from the joint angles
    for n in ["x", "y", "z"] {
        names.push(n.into());
        cols.push(vec![0.0; rec.len()]);
    }
    for j in 0..7 {
        names.push(format!("robot_q{}", j + 1));
        cols.push(joints.iter().map(|q| q[j]).collect());
    }
    let robot_rec = dir.path().join("robot.parquet");
    limpid_io::write_recording(
        &limpid_core::Recording::new(&robot_rec, names, cols, 1).unwrap(),
        &robot_rec,
    )
    .unwrap();
    let est = json(&[
        "estimate",
        "linear",
        robot_rec.to_str().unwrap(),
        "--robot",
        "kuka-lwr4",
        "--robot-base",
        &base.map(|v| v.to_string()).join(","),
        "--json",
    ]);
    let ek = rel_err(&mat(&est["stiffness"]), &mat(&truth["stiffness"]));
    assert!(ek < 0.03, "stiffness from robot joint angles: error {ek}");
}

#[test]
fn urdf_robot_exports_the_same_joint_trajectory_as_its_dh_model() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("p.toml");
    limpid(&[
        "protocol",
        "new",
        "--preset",
        "patel-cocontraction",
        "-o",
        p.to_str().unwrap(),
    ]);
    let urdf = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../robot/tests/fixtures/kuka_lwr4.urdf");
    let mut recs = Vec::new();
    for (name, robot) in [
        ("dh.parquet", "kuka-lwr4"),
        ("urdf.parquet", urdf.to_str().unwrap()),
    ] {
        let out_path = dir.path().join(name);
        let out = limpid(&[
            "protocol",
            "export",
            p.to_str().unwrap(),
            "--robot",
            robot,
            "-o",
            out_path.to_str().unwrap(),
        ]);
        assert_eq!(out.code, 0, "{}", out.stderr);
        recs.push(limpid_io::read_recording(&out_path).unwrap());
    }
    assert_eq!(recs[0].len(), recs[1].len());
    for j in 1..=7 {
        let c = format!("robot_q{j}");
        let worst = recs[0]
            .column(&c)
            .unwrap()
            .iter()
            .zip(recs[1].column(&c).unwrap())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-8, "{c}: {worst:e}");
    }
    // seed 001's sets of 6 with a 10 s rest between sets: 2 set rests of 10 s at 1 kHz
    let per_trial = ((0.05 + 0.1 + 0.5 + 0.1 + 1.0) * 1000.0f64).round() as usize;
    assert_eq!(recs[0].len(), 18 * per_trial + 2 * 10_000);
    // a robot that cannot reach the start points is the URDF's fault, and
    // the error names the URDF, not the output file
    let text = std::fs::read_to_string(&urdf).unwrap();
    assert!(text.contains("xyz=\"0 0 0.3105\""));
    let tiny = dir.path().join("tiny.urdf");
    std::fs::write(
        &tiny,
        text.replacen("xyz=\"0 0 0.3105\"", "xyz=\"0 0 1e-9\"", 1),
    )
    .unwrap();
    let out_path = dir.path().join("never.csv");
    let out = limpid(&[
        "protocol",
        "export",
        p.to_str().unwrap(),
        "--robot",
        tiny.to_str().unwrap(),
        "-o",
        out_path.to_str().unwrap(),
    ]);
    assert_eq!(out.code, 2, "{}", out.stdout);
    assert!(
        out.stderr
            .starts_with(&format!("limpid: {}: ", tiny.display())),
        "{}",
        out.stderr
    );
    assert!(out.stderr.contains("start point 1"), "{}", out.stderr);
    assert!(
        !out.stderr.contains("never.csv") && !out_path.exists(),
        "{}",
        out.stderr
    );
}

#[test]
fn planar_preset_checks_exports_simulates_and_estimates_back_to_its_truth() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("planar.toml");
    limpid(&[
        "protocol",
        "new",
        "--preset",
        "lakatos-planar",
        "-o",
        p.to_str().unwrap(),
    ]);
    let check = limpid(&["protocol", "check", p.to_str().unwrap(), "--json"]);
    assert_eq!(check.code, 0, "{}", check.stderr);
    let report: serde_json::Value = serde_json::from_str(&check.stdout).unwrap();
    assert_eq!(report["kind"], "planar");
    let cond = report["predicted_condition_number"].as_f64().unwrap();
    assert!(cond > 1.0 && cond < 100.0, "condition number {cond}");

    // the schedule: 30 perturbations, each after a wait of 1-3 s
    let traj = dir.path().join("schedule.csv");
    assert_eq!(
        limpid(&[
            "protocol",
            "export",
            p.to_str().unwrap(),
            "-o",
            traj.to_str().unwrap()
        ])
        .code,
        0
    );
    let rec = limpid_io::read_recording(&traj).unwrap();
    let (t, trial) = (rec.column("t").unwrap(), rec.column("trial").unwrap());
    let mut last_end = 0.0;
    let mut onsets = 0;
    for k in 1..rec.len() {
        if trial[k] > 0.0 && trial[k - 1] == 0.0 {
            let wait = t[k] - last_end;
            assert!(
                (0.999..=3.001).contains(&wait),
                "wait {wait} before trial {}",
                trial[k]
            );
            onsets += 1;
        }
        if trial[k] == 0.0 && trial[k - 1] > 0.0 {
            last_end = t[k];
        }
    }
    assert_eq!(onsets, 30);
    // every step of the command within the velocity limit (1 rad/s), the
    // returns included, and the session ends at rest at the posture
    for (name, q0) in [("q1", 0.08), ("q2", 1.0)] {
        let q = rec.column(name).unwrap();
        let fastest = q
            .windows(2)
            .zip(t.windows(2))
            .map(|(q, t)| (q[1] - q[0]).abs() / (t[1] - t[0]))
            .fold(0.0f64, f64::max);
        assert!(fastest <= 1.0, "{name}: {fastest} rad/s");
        assert!(
            (q[q.len() - 1] - q0).abs() < 1e-12,
            "{name} ends at {}",
            q[q.len() - 1]
        );
    }

    let sim = dir.path().join("planar.csv");
    let out = limpid(&[
        "simulate",
        p.to_str().unwrap(),
        "-o",
        sim.to_str().unwrap(),
        "--seed",
        "3",
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let truth = read_json(&dir.path().join("planar.truth.json"));
    let est = json(&[
        "estimate",
        "planar",
        sim.to_str().unwrap(),
        "--link-lengths",
        "0.3,0.33",
        "--json",
    ]);
    let ek = rel_err(&mat(&est["stiffness"]), &mat(&truth["stiffness"]));
    let ed = rel_err(&mat(&est["damping"]), &mat(&truth["damping"]));
    assert!(ek < 0.03 && ed < 0.05, "planar K error {ek}, D error {ed}");
}

#[test]
fn stochastic_preset_simulates_and_estimates_back_to_its_truth() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("st.toml");
    limpid(&[
        "protocol",
        "new",
        "--preset",
        "park-stochastic",
        "-o",
        p.to_str().unwrap(),
    ]);
    let check = limpid(&["protocol", "check", p.to_str().unwrap()]);
    assert_eq!(check.code, 0, "{}", check.stderr);
    assert!(
        check.stdout.contains("largest input coherence below 15 Hz"),
        "{}",
        check.stdout
    );
    let sim = dir.path().join("st.parquet");
    let out = limpid(&["simulate", p.to_str().unwrap(), "-o", sim.to_str().unwrap()]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let truth = read_json(&dir.path().join("st.truth.json"));
    let est = json(&["estimate", "stochastic", sim.to_str().unwrap(), "--json"]);
    let ek = rel_err(&mat(&est["stiffness"]), &mat(&truth["stiffness"]));
    assert!(ek < 0.05, "stochastic stiffness error {ek}");
}

#[test]
fn protocol_files_of_unknown_kind_are_refused_and_without_a_robot_export_the_command() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("odd.toml");
    std::fs::write(&p, "kind = \"spiral\"\n").unwrap();
    let out = limpid(&["protocol", "check", p.to_str().unwrap()]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("odd.toml") && out.stderr.contains("unknown kind \"spiral\""),
        "{}",
        out.stderr
    );
    // a misspelt key in a planar protocol: its line in the file, and the key
    let planar = limpid(&["protocol", "new", "--preset", "lakatos-planar"]).stdout;
    let key_line = planar
        .lines()
        .position(|l| l.starts_with("trials"))
        .expect("a trials key")
        + 1;
    let typo = dir.path().join("typo.toml");
    std::fs::write(&typo, planar.replacen("trials", "trails", 1)).unwrap();
    let out = limpid(&["protocol", "check", typo.to_str().unwrap()]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr
            .contains(&format!("typo.toml: line {key_line}, column 1"))
            && out.stderr.contains("unknown field `trails`"),
        "{}",
        out.stderr
    );
    assert_eq!(out.stderr.trim().lines().count(), 1, "{}", out.stderr);
    let c = dir.path().join("c.toml");
    limpid(&[
        "protocol",
        "new",
        "--preset",
        "artemiadis-3d",
        "-o",
        c.to_str().unwrap(),
    ]);
    let out = limpid(&[
        "protocol",
        "export",
        c.to_str().unwrap(),
        "-o",
        dir.path().join("x.csv").to_str().unwrap(),
    ]);
    // without a robot: the end-point command (issue 60), at rest at each start point
    assert_eq!(out.code, 0, "{}", out.stderr);
    let csv = std::fs::read_to_string(dir.path().join("x.csv")).unwrap();
    assert_eq!(csv.lines().next(), Some("t,start_point,trial,x,y,z"));
    let last: Vec<f64> = csv
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    // the last sample: start point 6, trial 16, back at the start point (the octahedron's -z vertex)
    assert_eq!((last[1], last[2]), (6.0, 16.0));
    assert!((last[5] + 0.2).abs() < 1e-9, "{last:?}");
}

#[test]
fn subject_files_of_every_kind_are_simulated_and_estimated_back() {
    let dir = tempfile::tempdir().unwrap();
    let preset = |name: &str| {
        let p = dir.path().join(format!("{name}.toml"));
        limpid(&[
            "protocol",
            "new",
            "--preset",
            name,
            "-o",
            p.to_str().unwrap(),
        ]);
        p
    };
    let simulate = |protocol: &std::path::Path, subject: &str, out: &str| {
        let s = dir.path().join(format!("{out}.subject.toml"));
        std::fs::write(&s, subject).unwrap();
        let rec = dir.path().join(format!("{out}.csv"));
        let run = limpid(&[
            "simulate",
            protocol.to_str().unwrap(),
            "--subject",
            s.to_str().unwrap(),
            "-o",
            rec.to_str().unwrap(),
        ]);
        assert_eq!(run.code, 0, "{}", run.stderr);
        rec
    };

    // centre-out: a stiffer, anisotropic subject (not Table I) at every start point
    let centre = preset("artemiadis-3d");
    let k_given = [
        [900.0, 120.0, -60.0],
        [120.0, 500.0, 40.0],
        [-60.0, 40.0, 350.0],
    ];
    simulate(
        &centre,
        "inertia = [[1.5, 0.0, 0.0], [0.0, 1.8, 0.0], [0.0, 0.0, 2.0]]\n\
         damping = [[12.0, 1.0, 0.0], [1.0, 9.0, 0.0], [0.0, 0.0, 7.0]]\n\
         stiffness = [[900.0, 120.0, -60.0], [120.0, 500.0, 40.0], [-60.0, 40.0, 350.0]]\n",
        "centre",
    );
    let truth = read_json(&dir.path().join("centre_S4.truth.json"));
    assert_eq!(
        mat(&truth["stiffness"]),
        limpid_core::Matrix::from_rows(&k_given.map(|r| r.to_vec())).unwrap()
    );
    let est = json(&[
        "estimate",
        "linear",
        dir.path().join("centre_S4.csv").to_str().unwrap(),
        "--json",
    ]);
    let ek = rel_err(&mat(&est["stiffness"]), &mat(&truth["stiffness"]));
    assert!(ek < 0.03, "centre-out K error {ek}");

    // planar: a softer arm than seed 003's, with a reflex recorded in the truth
    let planar = preset("lakatos-planar");
    let rec = simulate(
        &planar,
        "xi = [0.30, 0.09, 0.10]\nstiffness = [[20.0, 5.0], [5.0, 8.0]]\n\
         damping = [[1.2, 0.3], [0.3, 0.9]]\ntau0 = [0.2, 0.1]\n",
        "planar",
    );
    let truth = read_json(&dir.path().join("planar.truth.json"));
    assert_eq!(truth["stiffness"][0][0], 20.0);
    let est = json(&[
        "estimate",
        "planar",
        rec.to_str().unwrap(),
        "--link-lengths",
        "0.3,0.33",
        "--json",
    ]);
    let ek = rel_err(&mat(&est["stiffness"]), &mat(&truth["stiffness"]));
    assert!(ek < 0.03, "planar K error {ek}");

    // stochastic: spring set SA3 with every spring 1.5 times stiffer
    let stochastic = preset("park-stochastic");
    let rec = simulate(
        &stochastic,
        "springs = [75.0, 75.0, 45.0, 45.0, 0.0, 99.556, 0.0, 0.0]\n",
        "stochastic",
    );
    let truth = read_json(&dir.path().join("stochastic.truth.json"));
    let est = json(&["estimate", "stochastic", rec.to_str().unwrap(), "--json"]);
    let ek = rel_err(&mat(&est["stiffness"]), &mat(&truth["stiffness"]));
    assert!(ek < 0.05, "stochastic K error {ek}");

    // a subject of the wrong kind: one line naming the file and the field
    let wrong = dir.path().join("wrong.toml");
    std::fs::write(&wrong, "springs = [1.0, 2.0]\n").unwrap();
    let out = limpid(&[
        "simulate",
        centre.to_str().unwrap(),
        "--subject",
        wrong.to_str().unwrap(),
        "-o",
        dir.path().join("x.csv").to_str().unwrap(),
    ]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("wrong.toml") && out.stderr.contains("springs"),
        "{}",
        out.stderr
    );
    assert_eq!(out.stderr.trim().lines().count(), 1, "{}", out.stderr);
}

/// A subject file with a negative noise deviation or servo bandwidth was
/// simulated (issue 36): refused in one line naming the file and the field.
#[test]
fn a_subject_whose_noise_cannot_exist_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let protocol = dir.path().join("p.toml");
    let made = limpid(&[
        "protocol",
        "new",
        "--preset",
        "artemiadis-3d",
        "-o",
        protocol.to_str().unwrap(),
    ]);
    assert_eq!(made.code, 0, "{}", made.stderr);
    let matrices = "inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]\n\
                    damping = [[20.0, 0.0, 0.0], [0.0, 20.0, 0.0], [0.0, 0.0, 20.0]]\n\
                    stiffness = [[500.0, 0.0, 0.0], [0.0, 500.0, 0.0], [0.0, 0.0, 500.0]]\n";
    for (noise, says) in [
        (
            "white_std_n = -0.1",
            "[noise] white_std_n = -0.1: expected zero or a positive number",
        ),
        (
            "servo_bandwidth_hz = -30.0",
            "[noise] servo_bandwidth_hz = -30",
        ),
        (
            "drift_lowpass_hz = 0.0",
            "[noise] drift_lowpass_hz = 0: expected a bandwidth of 0.001 to 1e5 Hz",
        ),
    ] {
        let subject = dir.path().join("bad.subject.toml");
        std::fs::write(&subject, format!("{matrices}[noise]\n{noise}\n")).unwrap();
        let out = limpid(&[
            "simulate",
            protocol.to_str().unwrap(),
            "--subject",
            subject.to_str().unwrap(),
            "-o",
            dir.path().join("r.csv").to_str().unwrap(),
        ]);
        assert_eq!(out.code, 2, "{noise}: {}", out.stderr);
        assert!(
            out.stderr.contains("bad.subject.toml") && out.stderr.contains(says),
            "{noise}: {}",
            out.stderr
        );
        assert_eq!(out.stderr.trim().lines().count(), 1, "{}", out.stderr);
    }
}

/// Issue 58's subject fields beyond what can be simulated are refused
/// naming the subject file, not the protocol: a scheduled ankle whose
/// stiffness would overflow, a tremor above what the sample rate holds.
#[test]
fn subject_values_that_cannot_be_simulated_are_refused_naming_the_subject_file() {
    let dir = tempfile::tempdir().unwrap();
    for (preset_name, subject, field) in [
        (
            "ankle-ramp-and-hold",
            "inertia = 0.015\nstiffness = [70.0, 80.0, 100.0]\nstiffness_growth = 1e307\n\
             damping = [0.8, 0.5, 0.0]\nbackground = [2.0, 10.0, 0.0]\n",
            "stiffness_growth",
        ),
        (
            "artemiadis-3d",
            "inertia = [[1.5, 0.0, 0.0], [0.0, 1.8, 0.0], [0.0, 0.0, 2.0]]\n\
             damping = [[12.0, 1.0, 0.0], [1.0, 9.0, 0.0], [0.0, 0.0, 7.0]]\n\
             stiffness = [[900.0, 0.0, 0.0], [0.0, 500.0, 0.0], [0.0, 0.0, 350.0]]\n\
             [noise]\ntremor_std_n = 0.3\ntremor_hz = 1000\n",
            "tremor_hz",
        ),
    ] {
        let protocol = preset(dir.path(), preset_name);
        let file = dir.path().join(format!("{preset_name}.subject.toml"));
        std::fs::write(&file, subject).unwrap();
        let out = limpid(&[
            "simulate",
            protocol.to_str().unwrap(),
            "--subject",
            file.to_str().unwrap(),
            "-o",
            dir.path().join("r.csv").to_str().unwrap(),
        ]);
        assert_eq!(out.code, 2, "{}", out.stderr);
        assert!(
            out.stderr.contains(".subject.toml")
                && out.stderr.contains(field)
                && out.stderr.lines().count() == 1,
            "{}",
            out.stderr
        );
    }
}
