//! The example recordings the tests read, made by limpid's own lab with fixed
//! random seeds: one folder per family, each case a CSV with its
//! `<case>.truth.json`, laid out like the outside examples (`LIMPID_EXAMPLES`)
//! so a test can run on both sets.
//!
//! | family | cases | made by |
//! |---|---|---|
//! | `cartesian_slow` | `ex_cubic`, `ex_sinusoid` | [`simulate_centre_out`] on a Table I posture of Artemiadis et al. (2010) with an antisymmetric part, 16 trials, sensor noise of [`NoiseModel::default`] |
//! | `cocontraction` | `ex_config4`, `ex_config7` (+ `.mvc.csv`) | [`simulate_cocontraction`]: K(level) = K0 + level dK, the tertiary principal stiffness +90 % at level 1 and the axes turned 8.6 deg (Patel, O'Neill & Artemiadis) |
//! | `planar` | `ex_joint_180`, `ex_endpoint_220` | [`simulate_planar`] (Lakatos, Petit & van der Smagt eq. 9); the end-point case mapped through the arm's kinematics, force f = J^-T tau, with position and force noise |
//! | `stochastic` | `ex_sa3`, `ex_sa4` | the spring array on the ideal impedance-controlled rig (Park & Chang eq. 10) |
//! | `ankle` | `ex_ankle` | [`simulate_ankle`]: a 1-DoF ankle with a stretch reflex under a PRBS position perturbation, 60 s at 1 kHz (Kearney, Stein & Parameswaran 1997) |
//!
//! The truth files hold the keys the outside examples hold (`stiffness`,
//! `damping`, `inertia`, `equilibrium`, `levels`, `inertial_parameters`, ...),
//! except the co-contraction index per level: the outside generator gives the
//! index its reference processing computes from the data; limpid's lab knows
//! only the activations, and the index of eq. (1) (normalised by the MVC's
//! maximum envelope) is not the activation. Tests check the index where the
//! truth has it.
//!
//! Generation takes a few seconds per family and happens once per test
//! binary build: the files are kept under the target folder, keyed by the
//! test executable's name and modification time.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use limpid_core::arm::Arm;
use limpid_core::truth::{
    other_keys, About, CartesianTruth, CocontractionTruth, LevelTruth, PlanarTruth, PlanarVariant,
    ReflexTruth, Truth,
};
use limpid_core::{Matrix, Recording};
use limpid_lab::ankle::{simulate_ankle, AnkleExperiment, AnkleSubject};
use limpid_lab::cocontraction::{
    simulate_cocontraction, CocontractionProtocol, CocontractionSubject,
};
use limpid_lab::planar::{simulate_planar, PlanarProtocol, PlanarSubject};
use limpid_lab::session::{simulate_design, RigController, SubjectText};
use limpid_lab::{seed000_subject1, simulate_centre_out, CentreOut, NoiseModel, Profile};
use nalgebra::{Matrix2, Matrix3, Rotation3, Vector3};
use serde_json::{json, Value};

/// The example families.
pub const FAMILIES: [&str; 5] = [
    "cartesian_slow",
    "cocontraction",
    "planar",
    "stochastic",
    "ankle",
];

/// Folder of limpid-made examples of `family` (made on first use).
pub fn limpid_examples(family: &str) -> PathBuf {
    static DIRS: [OnceLock<PathBuf>; FAMILIES.len()] = [const { OnceLock::new() }; FAMILIES.len()];
    let index = FAMILIES
        .iter()
        .position(|f| *f == family)
        .unwrap_or_else(|| panic!("no example family {family:?}; families: {FAMILIES:?}"));
    DIRS[index].get_or_init(|| make_family(family)).clone()
}

/// Write every family into `dir/<family>/` (made here, then copied).
pub fn write_all(dir: &Path) -> std::io::Result<()> {
    for family in FAMILIES {
        let from = limpid_examples(family);
        let to = dir.join(family);
        std::fs::create_dir_all(&to)?;
        for entry in std::fs::read_dir(&from)? {
            let entry = entry?;
            if entry.file_name() != "complete" {
                std::fs::copy(entry.path(), to.join(entry.file_name()))?;
            }
        }
    }
    Ok(())
}

/// Where generated examples are kept: beside the test executable's target
/// profile folder, one folder per executable and build.
fn cache_root() -> PathBuf {
    let exe = std::env::current_exe().expect("the test executable's path");
    let stamp = std::fs::metadata(&exe)
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    let name = exe
        .file_name()
        .map_or("tests".into(), |n| n.to_string_lossy().into_owned());
    // target/<profile>/deps/<exe> -> target/<profile>/limpid-examples
    let profile_dir = exe
        .parent()
        .and_then(Path::parent)
        .map_or_else(std::env::temp_dir, Path::to_path_buf);
    let root = profile_dir.join("limpid-examples");
    let current = format!("{name}-{stamp}");
    // earlier builds of this executable leave their copies: remove them
    if let Ok(entries) = std::fs::read_dir(&root) {
        for entry in entries.flatten() {
            let other = entry.file_name().to_string_lossy().into_owned();
            if other != current && other.starts_with(&format!("{name}-")) {
                let _ = std::fs::remove_dir_all(entry.path());
            }
        }
    }
    root.join(current)
}

fn make_family(family: &str) -> PathBuf {
    let dir = cache_root().join(family);
    if dir.join("complete").exists() {
        return dir;
    }
    let tmp = dir.with_extension(format!("tmp-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap_or_else(|e| panic!("{}: {e}", tmp.display()));
    match family {
        "cartesian_slow" => cartesian_slow(&tmp),
        "cocontraction" => cocontraction(&tmp),
        "planar" => planar(&tmp),
        "stochastic" => stochastic(&tmp),
        "ankle" => ankle(&tmp),
        _ => unreachable!("families are checked above"),
    }
    std::fs::write(tmp.join("complete"), b"").expect("stamp");
    let _ = std::fs::remove_dir_all(&dir);
    if std::fs::rename(&tmp, &dir).is_err() {
        // another thread or process won the race: its copy is identical
        let _ = std::fs::remove_dir_all(&tmp);
    }
    dir
}

fn write(dir: &Path, case: &str, rec: &Recording, truth: Truth) {
    limpid_io::write_recording(rec, dir.join(format!("{case}.csv")))
        .unwrap_or_else(|e| panic!("{case}: {e}"));
    let text = serde_json::to_string_pretty(&truth).expect("truth serialises");
    std::fs::write(dir.join(format!("{case}.truth.json")), text).expect("truth written");
}

/// Family, case, seed, rate, checked quantities and notes of a truth.
fn about(
    family: &str,
    case: &str,
    seed: u64,
    rate: f64,
    checked: &[&str],
    notes: &[&str],
) -> About {
    About {
        family: Some(family.into()),
        case: Some(case.into()),
        seed: Some(seed),
        sample_rate: Some(rate),
        source: None,
        checked: checked.iter().map(|c| c.to_string()).collect(),
        notes: notes.iter().map(|n| n.to_string()).collect(),
    }
}

fn to_value<T: serde::Serialize>(value: &T) -> Value {
    serde_json::to_value(value).expect("lab types serialise")
}

/// A skew-symmetric matrix whose largest entry is `max`.
fn skew(max: f64) -> Matrix3<f64> {
    let a = Matrix3::new(0.0, 1.0, -0.6, -1.0, 0.0, 0.8, 0.6, -0.8, 0.0);
    a * max
}

fn cartesian_slow(dir: &Path) {
    let table = seed000_subject1();
    for (case, profile, posture_index, seed) in [
        ("ex_cubic", Profile::Cubic, 1usize, 2101u64),
        ("ex_sinusoid", Profile::Sinusoid, 3, 2102),
    ] {
        let mut posture = table[posture_index].clone();
        // an antisymmetric part of 1.5 % of the largest entry, as real arms show
        let kmax = posture.stiffness.amax();
        posture.stiffness += skew(0.015 * kmax);
        posture.damping += skew(0.015 * posture.damping.amax());
        let protocol = CentreOut::seed000(profile);
        let noise = NoiseModel::default();
        let rec = simulate_centre_out(&posture, &protocol, &noise, seed)
            .unwrap_or_else(|e| panic!("{case}: {e}"));
        let s = posture.start;
        let truth = Truth::Cartesian(CartesianTruth {
            about: about(
                "cartesian_slow",
                case,
                seed,
                protocol.sample_rate,
                &["stiffness", "damping"],
                &[
                    "made by limpid's lab (limpid-testkit): Artemiadis et al. (2010) Table I posture with a 1.5 % antisymmetric part",
                    "inertia is not identifiable with 3 s motions",
                ],
            ),
            inertia: Matrix::from(posture.inertia),
            damping: Matrix::from(posture.damping),
            stiffness: Matrix::from(posture.stiffness),
            equilibrium: vec![s.x, s.y, s.z],
            profile: to_value(&profile).as_str().map(String::from),
            other: other_keys([
                (
                    "protocol",
                    json!({"trials": protocol.directions.len(), "rest_s": protocol.rest_s,
                           "motion_s": protocol.motion_s, "radius_m": protocol.radius_m}),
                ),
                ("noise", to_value(&noise)),
            ]),
        });
        write(dir, case, &rec, truth);
    }
}

/// K0 from principal stiffnesses and a rotation; at level 1 the principal
/// values grow by `growth` along axes turned by `turn_deg` about the first.
fn cocontraction_subject(
    name: &str,
    principal: [f64; 3],
    euler: [f64; 3],
    start: [f64; 3],
) -> (CocontractionSubject, Matrix3<f64>, Matrix3<f64>) {
    let r0 = Rotation3::from_euler_angles(euler[0], euler[1], euler[2]);
    let k0 = r0 * Matrix3::from_diagonal(&Vector3::from(principal)) * r0.transpose();
    let grown = Vector3::new(principal[0] * 1.05, principal[1] * 1.03, principal[2] * 1.9);
    let r1 = r0 * Rotation3::from_axis_angle(&Vector3::x_axis(), 8.6f64.to_radians());
    let k1 = r1 * Matrix3::from_diagonal(&grown) * r1.transpose();
    let k1 = (k1 + k1.transpose()) * 0.5;
    let subject = CocontractionSubject {
        name: name.into(),
        start: Vector3::from(start),
        inertia: Matrix3::new(1.64, -0.03, -0.04, -0.03, 1.68, 0.03, -0.04, 0.03, 1.41),
        damping: Matrix3::new(16.5, 0.9, 2.8, 0.9, 19.4, 1.9, 2.8, 1.9, 18.0),
        stiffness_knots: vec![(0.0, k0), (1.0, k1)],
        emg_amplitude: [6.9e-4, 5.0e-4, 3.7e-4, 6.7e-4, 2.4e-4, 8.2e-4],
        activation_gain: [1.0; 6],
        reflex: None,
        activation_wobble: 0.0,
    };
    (subject, k0, k1 - k0)
}

fn cocontraction(dir: &Path) {
    for (case, principal, euler, start, seed) in [
        (
            "ex_config4",
            [2046.6, 663.4, 471.1],
            [0.4, -0.3, 0.9],
            [0.2856, -0.2209, 0.0689],
            2201u64,
        ),
        (
            "ex_config7",
            [2432.1, 944.5, 600.4],
            [-0.2, 0.5, -0.7],
            [0.3132, -0.1934, 0.0591],
            2202,
        ),
    ] {
        let (subject, k0, dk) = cocontraction_subject(case, principal, euler, start);
        let protocol = CocontractionProtocol::seed001();
        let noise = NoiseModel::default();
        let (rec, mvc) = simulate_cocontraction(&subject, &protocol, &noise, seed)
            .unwrap_or_else(|e| panic!("{case}: {e}"));
        limpid_io::write_recording(&mvc, dir.join(format!("{case}.mvc.csv")))
            .unwrap_or_else(|e| panic!("{case}: {e}"));
        let levels = protocol
            .levels
            .iter()
            .map(|l| LevelTruth {
                level: *l,
                stiffness: Matrix::from(subject.stiffness(*l)),
                cocontraction_index: None,
                muscle_activation: Some(subject.activation_gain.map(|g| g * l).to_vec()),
            })
            .collect();
        let truth = Truth::Cocontraction(CocontractionTruth {
            about: about(
                "cocontraction",
                case,
                seed,
                protocol.sample_rate,
                &["levels[].stiffness"],
                &[
                    "made by limpid's lab (limpid-testkit): K(level) = K0 + level dK; at level 1 the tertiary principal stiffness +90 %, the others +5 % / +3 %, axes turned 8.6 deg about the primary",
                    "no cocontraction_index: the index of eq. (1) is normalised by the MVC's maximum envelope, which the lab does not know in advance",
                ],
            ),
            inertia: Some(Matrix::from(subject.inertia)),
            damping: Some(Matrix::from(subject.damping)),
            equilibrium: Some(start.to_vec()),
            levels,
            stiffness_level0: Some(Matrix::from(k0)),
            stiffness_increment_per_unit_level: Some(Matrix::from(dk)),
            other: other_keys([("noise", to_value(&noise))]),
        });
        write(dir, case, &rec, truth);
    }
}

fn planar(dir: &Path) {
    let joint = PlanarSubject::seed003();
    let endpoint = PlanarSubject {
        xi: [0.3397, 0.1230, 0.0977],
        stiffness: Matrix2::new(17.16, 6.17, 6.17, 13.85),
        damping: Matrix2::new(1.878, 0.300, 0.300, 1.129),
        q0: [0.08, 1.0],
        tau0: [-0.46, 0.08],
        reflex: None,
        cuff: None,
    };
    let links = [0.32, 0.31];
    for (case, subject, interval_s, seed, end_point) in [
        ("ex_joint_180", &joint, 0.18, 2301u64, false),
        ("ex_endpoint_220", &endpoint, 0.22, 2302, true),
    ] {
        // observed from 0.3 s before the onset to T_k + 70 ms after it (§IV)
        let protocol = PlanarProtocol {
            interpolation_s: interval_s,
            after_s: interval_s + 0.07,
            ..PlanarProtocol::seed003()
        };
        let (torque_std, angle_std) = (0.02, 1e-5);
        let joint_rec = simulate_planar(subject, &protocol, torque_std, angle_std, seed)
            .unwrap_or_else(|e| panic!("{case}: {e}"));
        let rec = if end_point {
            to_end_point(&joint_rec, links, seed)
        } else {
            joint_rec
        };
        let truth = Truth::Planar(PlanarTruth {
            about: about(
                "planar",
                case,
                seed,
                protocol.sample_rate,
                &["stiffness", "damping", "inertial_parameters"],
                &[
                    "made by limpid's lab (limpid-testkit): Lakatos, Petit & van der Smagt (2011) eq. (9)",
                    "end-point variant: x = FK(q) (shoulder at the origin, q2 relative), f = J(q)^-T tau on the hand, then position and force noise",
                ],
            ),
            variant: if end_point {
                PlanarVariant::Endpoint
            } else {
                PlanarVariant::Joint
            },
            inertial_parameters: subject.xi,
            stiffness: Matrix::from(subject.stiffness),
            damping: Matrix::from(subject.damping),
            link_lengths: links,
            q0: subject.q0,
            equilibrium: Some(subject.q0),
            shoulder: Some([0.0, 0.0]),
            interpolation_interval_ms: (interval_s * 1e3).round(),
            observation_window_ms: Some((protocol.after_s * 1e3).round()),
            other: other_keys([(
                "noise",
                json!({"torque_white_std_Nm": torque_std, "baseline_torque_Nm": subject.tau0,
                       "joint_angle_std_rad": angle_std,
                       "position_std_m": if end_point { 2e-5 } else { 0.0 },
                       "force_white_std_N": if end_point { 0.1 } else { 0.0 }}),
            )]),
        });
        write(dir, case, &rec, truth);
    }
}

/// Joint angles and torques as a hand position and force, with the end-point
/// sensors' noise (20 µm, 0.1 N).
fn to_end_point(rec: &Recording, links: [f64; 2], seed: u64) -> Recording {
    use rand::{rngs::StdRng, SeedableRng};
    use rand_distr::{Distribution, Normal};
    let arm = Arm {
        l1: links[0],
        l2: links[1],
        shoulder: [0.0, 0.0],
    };
    let col = |n: &str| rec.column(n).unwrap_or_else(|| panic!("no {n}"));
    let (q1, q2, tau1, tau2) = (col("q1"), col("q2"), col("tau1"), col("tau2"));
    let mut rng = StdRng::seed_from_u64(seed ^ 0x5eed);
    let position = Normal::new(0.0, 2e-5).expect("valid");
    let force = Normal::new(0.0, 0.1).expect("valid");
    let n = rec.len();
    let mut cols: Vec<Vec<f64>> = (0..6).map(|_| Vec::with_capacity(n)).collect();
    for i in 0..n {
        let q = [q1[i], q2[i]];
        let x = arm.fk(q);
        let j = arm.jacobian(q);
        let f = j
            .transpose()
            .try_inverse()
            .expect("the arm is away from its singularity")
            * nalgebra::Vector2::new(tau1[i], tau2[i]);
        cols[0].push(rec.t()[i]);
        cols[1].push(x[0] + position.sample(&mut rng));
        cols[2].push(x[1] + position.sample(&mut rng));
        cols[3].push(f[0] + force.sample(&mut rng));
        cols[4].push(f[1] + force.sample(&mut rng));
        cols[5].push(col("trial")[i]);
    }
    let names = ["t", "x", "y", "fx", "fy", "trial"]
        .map(String::from)
        .to_vec();
    Recording::new("virtual:end-point", names, cols, 2).expect("a valid recording")
}

fn stochastic(dir: &Path) {
    let design = limpid_lab::design::Design::preset("park-stochastic").expect("preset");
    for (case, springs, seed) in [
        (
            "ex_sa3",
            "springs = [50.0, 50.0, 30.0, 30.0, 0.0, 66.3707, 0.0, 0.0]",
            2401u64,
        ),
        (
            "ex_sa4",
            "springs = [38.0615, 38.0615, 45.0, 45.0, 45.0, 0.0, 0.0, 25.0]",
            2402,
        ),
    ] {
        let path = Path::new("testkit-springs.toml");
        let subject = SubjectText {
            text: springs,
            path,
        };
        let mut runs = simulate_design(&design, Some(&subject), RigController::Ideal, seed)
            .unwrap_or_else(|e| panic!("{case}: {e}"));
        let run = runs.pop().expect("one recording");
        let Truth::Stochastic(mut truth) = run.truth else {
            panic!("{case}: a stochastic design simulates a stochastic truth")
        };
        truth.about.family = Some("stochastic".into());
        truth.about.case = Some(case.into());
        truth.about.seed = Some(seed);
        truth.band_hz = Some([0.5, 10.0]);
        truth.about.checked = vec!["stiffness".into(), "impedance over 0.5-10 Hz".into()];
        write(dir, case, &run.recording, Truth::Stochastic(truth));
    }
}

fn ankle(dir: &Path) {
    let (subject, experiment, seed) =
        (AnkleSubject::default(), AnkleExperiment::default(), 2501u64);
    let rec =
        simulate_ankle(&subject, &experiment, seed).unwrap_or_else(|e| panic!("ex_ankle: {e}"));
    let one = |v: f64| Matrix::from_rows(&[vec![v]]).expect("1 x 1");
    let truth = Truth::Reflex(ReflexTruth {
        about: about(
            "ankle",
            "ex_ankle",
            seed,
            experiment.rate_hz,
            &[],
            &["made by limpid's lab (limpid-testkit): intrinsic I, B, K plus a reflex on half-wave rectified velocity, delayed and low-passed"],
        ),
        inertia: one(subject.inertia),
        damping: one(subject.damping),
        stiffness: one(subject.stiffness),
        other: other_keys([
            ("reflex", to_value(&subject.reflex)),
            ("noise", json!({"torque_white_std_Nm": experiment.torque_noise_nm})),
        ]),
    });
    write(dir, "ex_ankle", &rec, truth);
}
