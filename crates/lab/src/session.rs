//! A protocol run on a virtual subject: the one path behind `limpid simulate`
//! and Python's `limpid.simulate`. Each recording comes with its truth, in the
//! layout of the outside examples (`*/*.truth.json`).
//!
//! Subjects (TOML, all optional — the defaults are the built-in subjects):
//! - centre-out (seed 000): 3 x 3 `inertia`, `damping`, `stiffness` (SI) and an
//!   optional `[noise]` table ([`NoiseModel`]); default seed 000 Table I
//!   subject 1, posture i at start point i;
//! - planar (seed 003 eq. 9): `xi` (3 inertial parameters), 2 x 2 `stiffness`,
//!   `damping`, `tau0` (2), optional `[reflex]` (`latency_s`, `stiffness_gain`,
//!   `damping_gain`); default [`PlanarDesign::nominal_subject`];
//! - stochastic (seed 004 eq. 10): `springs` (8 values, N/m, k1a..k4b); default
//!   spring set SA3;
//! - periodic (issue 59), by the protocol's coordinates: one joint channel
//!   plays on the virtual ankle (`inertia`, `damping`, `stiffness`, optional
//!   `[reflex]`, `quadratic`, `cubic`; [`crate::ankle::AnkleSubject`]), two
//!   (`q1, q2`) on the planar arm ([`crate::follow::PlanarFollower`]), end-point
//!   channels (`x`, `y`, `z`) on the 3-D end point
//!   ([`crate::follow::EndpointFollower`]); the quadratic and cubic terms make
//!   the elastic force nonlinear.

use std::path::Path;

use limpid_core::truth::{
    other_keys, About, CartesianTruth, PeriodicTruth, PlanarTruth, PlanarVariant, StochasticTruth,
    Truth,
};
use limpid_core::Matrix;
use limpid_core::{Error, Recording, Result};
use nalgebra::{Matrix2, Matrix3};
use serde::Deserialize;
use serde_json::{json, Value};

use crate::design::{Design, PlanarDesign, StochasticDesign};
use crate::imbic::{simulate_robot_rig, Controller, RobotDynamics};
use crate::planar::{simulate_planar, Reflex};
use crate::protocol::Protocol;
use crate::rig::{simulate_rig, Springs, SPRING_SET_SA3};
use crate::{seed000_subject1, simulate_centre_out, NoiseModel, Posture};

/// Who holds the spring array of a stochastic protocol.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RigController {
    /// A linear robot with the desired impedance.
    Ideal,
    /// The PUMA-type robot with joint friction under IMBIC (seed 004 eq. 11-14).
    Imbic,
    /// The same robot under a plain PD law.
    Pd,
}

impl std::str::FromStr for RigController {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "ideal" => Ok(Self::Ideal),
            "imbic" => Ok(Self::Imbic),
            "pd" => Ok(Self::Pd),
            other => Err(format!(
                "unknown controller {other:?}; expected ideal, imbic or pd"
            )),
        }
    }
}

/// A subject given as TOML text, with the name errors should carry.
pub struct SubjectText<'a> {
    /// The subject file's text.
    pub text: &'a str,
    /// Its path, for error messages.
    pub path: &'a Path,
}

/// One simulated recording and its truth.
pub struct Simulated {
    /// `S1`, `S2`, ... for the start points of a centre-out protocol; `None` for a single recording.
    pub label: Option<String>,
    /// The recording.
    pub recording: Recording,
    /// Its truth (the `*.truth.json` content).
    pub truth: Truth,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CentreOutSubjectFile {
    inertia: [[f64; 3]; 3],
    damping: [[f64; 3]; 3],
    stiffness: [[f64; 3]; 3],
    #[serde(default)]
    noise: Option<NoiseModel>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlanarSubjectFile {
    xi: [f64; 3],
    stiffness: [[f64; 2]; 2],
    damping: [[f64; 2]; 2],
    #[serde(default)]
    tau0: [f64; 2],
    #[serde(default)]
    reflex: Option<Reflex>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RigSubjectFile {
    springs: Springs,
}

fn parse<T: for<'de> Deserialize<'de>>(subject: &SubjectText) -> Result<T> {
    // finite numbers only (a nan stiffness would simulate a recording of NaN)
    crate::validate::check_numbers(subject.text, subject.path)?;
    crate::validate::parse_settings(subject.text, subject.path)
}

/// A value as JSON (the lab's types always serialise).
fn to_value<T: serde::Serialize>(value: &T) -> Value {
    serde_json::to_value(value).expect("lab types serialise")
}

/// A matrix as its rows, the layout of the truth files.
pub fn rows<R: nalgebra::Dim, C: nalgebra::Dim, S: nalgebra::RawStorage<f64, R, C>>(
    m: &nalgebra::Matrix<f64, R, C, S>,
) -> Vec<Vec<f64>> {
    m.row_iter().map(|r| r.iter().copied().collect()).collect()
}

/// Simulate a (checked) protocol on a subject. `seed` drives the sensor noise.
pub fn simulate_design(
    design: &Design,
    subject: Option<&SubjectText>,
    controller: RigController,
    seed: u64,
) -> Result<Vec<Simulated>> {
    simulate_on(design, subject, controller, seed).map_err(|e| blame_the_subject(e, subject))
}

/// An error from inside the simulation (a recording of implausible values,
/// a filter its noise cannot have) is the subject file's when one was given:
/// "virtual ankle: row 2, column tau1: implausible value 3.65e286" named
/// no file a user wrote (subject stiffness 1e12; issue 76).
fn blame_the_subject(e: Error, subject: Option<&SubjectText>) -> Error {
    let Some(s) = subject else {
        return e;
    };
    let text = e.to_string();
    let inside = text.starts_with("virtual")
        || matches!(&e, Error::InvalidParameter { name, .. } if name == "cutoff_hz");
    if !inside {
        return e;
    }
    Error::Format {
        path: s.path.to_path_buf(),
        message: format!(
            "simulating this subject gives what no limb and rig can ({}): check its values (stiffness, inertia, noise)",
            limpid_core::error::tidy_numbers(&text)
        ),
    }
}

fn simulate_on(
    design: &Design,
    subject: Option<&SubjectText>,
    controller: RigController,
    seed: u64,
) -> Result<Vec<Simulated>> {
    match design {
        Design::CentreOut(p) => centre_out(p, subject, seed),
        Design::Planar(p) => planar(p, subject, seed).map(|s| vec![s]),
        Design::Stochastic(p) => stochastic(p, subject, controller, seed).map(|s| vec![s]),
        Design::Ensemble(p) => {
            let s: crate::varying::EnsembleSubject = match subject {
                Some(text) => parse(text)?,
                None => crate::varying::EnsembleSubject::joint(),
            };
            let recording = crate::varying::simulate_ensemble(&s, p, seed)?;
            let truth = crate::varying::ensemble_truth(&s, p, 0.01);
            Ok(vec![Simulated {
                label: None,
                recording,
                truth: Truth::Varying(truth),
            }])
        }
        Design::Periodic(p) => periodic(p, subject, seed).map(|s| vec![s]),
        Design::Walking(p) => {
            let s: crate::varying::WalkingAnkle = match subject {
                Some(text) => parse(text)?,
                None => crate::varying::WalkingAnkle::default(),
            };
            let recording = crate::varying::simulate_walking(&s, p, seed)?;
            let truth = crate::varying::walking_truth(&s, p);
            Ok(vec![Simulated {
                label: None,
                recording,
                truth: Truth::Varying(truth),
            }])
        }
        Design::RampAndHold(p) => {
            let s: crate::varying::ScheduledAnkle = match subject {
                Some(text) => parse(text)?,
                None => crate::varying::ScheduledAnkle::default(),
            };
            // the subject's values are the subject file's, not the protocol's
            if let (Err(e), Some(text)) = (s.validate(), subject) {
                return Err(Error::Format {
                    path: text.path.to_path_buf(),
                    message: e.to_string(),
                });
            }
            let recording = crate::varying::simulate_scheduled_ankle(&s, p, seed)?;
            let truth = crate::varying::scheduled_truth(&s, p, 25);
            Ok(vec![Simulated {
                label: None,
                recording,
                truth: Truth::Varying(truth),
            }])
        }
    }
}

/// A periodic protocol (issue 59) on the virtual ankle ([`crate::ankle`]):
/// the command played through its actuator, the `period` column kept. Its
/// subject (TOML) is an [`AnkleSubject`](crate::ankle::AnkleSubject)
/// (`inertia`, `damping`, `stiffness`, optional `[reflex]`; default the
/// ankle with a reflex); joint protocols of one channel only so far.
fn periodic(
    p: &crate::periodic::PeriodicDesign,
    subject: Option<&SubjectText>,
    seed: u64,
) -> Result<Simulated> {
    use crate::periodic::Coordinates;
    let channels = p.channel_names();
    match (p.coordinates, channels.len()) {
        (Coordinates::Joint, 1) => periodic_ankle(p, subject, seed),
        (Coordinates::Joint, 2) => periodic_planar(p, &channels, subject, seed),
        (Coordinates::Endpoint, _) => periodic_endpoint(p, &channels, subject, seed),
        _ => Err(Error::invalid(
            "protocol",
            format!(
                "periodic joint protocols are simulated on the virtual ankle (one channel) or the planar arm (q1, q2); this one commands {}: export it with `limpid protocol export` and play it on your rig or simulator",
                channels.join(", ")
            ),
        )),
    }
}

/// Each channel's place among `names` (`q1, q2` or `x, y, z`), each at most once.
fn channel_places<const N: usize>(channels: &[String], names: [&str; N]) -> Result<Vec<usize>> {
    let mut places = Vec::with_capacity(channels.len());
    for c in channels {
        let Some(i) = names.iter().position(|n| n == c) else {
            return Err(Error::invalid(
                "protocol",
                format!(
                    "channel {c:?}: the virtual subject's coordinates are {}",
                    names.join(", ")
                ),
            ));
        };
        if places.contains(&i) {
            return Err(Error::invalid(
                "protocol",
                format!("channel {c:?} is given twice"),
            ));
        }
        places.push(i);
    }
    Ok(places)
}

/// The command per coordinate of the subject (0 for one the protocol does not command).
fn command_by_place<const N: usize>(
    command: &crate::periodic::Command,
    places: &[usize],
) -> [Vec<f64>; N] {
    std::array::from_fn(|i| match places.iter().position(|&p| p == i) {
        Some(c) => command.values[c].clone(),
        None => vec![0.0; command.t.len()],
    })
}

/// A periodic recording: `t`, positions, forces, `period`. (The command is
/// a displacement; the format's `u*` columns are commanded forces, so it is
/// not written: `protocol export` gives it.)
fn periodic_recording(
    source: &str,
    command: &crate::periodic::Command,
    positions: &[&str],
    forces: &[&str],
    followed: crate::follow::Followed,
) -> Result<Recording> {
    let names: Vec<String> = std::iter::once("t")
        .chain(positions.iter().copied())
        .chain(forces.iter().copied())
        .chain(std::iter::once("period"))
        .map(String::from)
        .collect();
    let columns: Vec<Vec<f64>> = std::iter::once(command.t.clone())
        .chain(followed.position)
        .chain(followed.force)
        .chain(std::iter::once(
            command.period.iter().map(|&i| i as f64).collect(),
        ))
        .collect();
    Recording::new(source, names, columns, 2)
}

fn periodic_truth_notes(p: &crate::periodic::PeriodicDesign, model: &str) -> Vec<String> {
    vec![
        model.to_string(),
        format!(
            "following {} through a second-order position servo (damping ratio 0.7); samples are means over their sample period; period -1 marks the fade-in and fade-out",
            p.name
        ),
        "made by limpid simulate".into(),
    ]
}

fn periodic_planar(
    p: &crate::periodic::PeriodicDesign,
    channels: &[String],
    subject: Option<&SubjectText>,
    seed: u64,
) -> Result<Simulated> {
    use crate::follow::{follow_planar, PlanarFollower};
    let places = channel_places(channels, ["q1", "q2"])?;
    let s: PlanarFollower = match subject {
        Some(text) => parse(text)?,
        None => PlanarFollower::default(),
    };
    let command = p.command()?;
    let commands = command_by_place(&command, &places);
    let followed = follow_planar(&s, &commands, p.sample_rate_hz, seed)?;
    let recording = periodic_recording(
        "virtual planar arm",
        &command,
        &["q1", "q2"],
        &["tau1", "tau2"],
        followed,
    )?;
    let m = |a: &[[f64; 2]; 2]| Matrix::from_rows(&[a[0].to_vec(), a[1].to_vec()]).expect("2 x 2");
    let truth = Truth::Periodic(PeriodicTruth {
        about: About {
            sample_rate: Some(p.sample_rate_hz),
            seed: Some(seed),
            notes: periodic_truth_notes(
                p,
                "tau = M(q) q'' + C(q,q') q' + D dq + K dq + k2 dq^2 + k3 dq^3 + tau0 + noise (Lakatos, Petit & van der Smagt 2011 eq. (9)); inertia is M(q0), the linearisation at the posture",
            ),
            ..About::default()
        },
        coordinates: vec!["q1".into(), "q2".into()],
        inertia: Matrix::from(s.inertia_at_posture()),
        damping: m(&s.damping),
        stiffness: m(&s.stiffness),
        equilibrium: s.q0.to_vec(),
        quadratic: s.quadratic.map(|v| v.to_vec()),
        cubic: s.cubic.map(|v| v.to_vec()),
        other: other_keys([
            ("inertial_parameters", json!(s.xi)),
            ("tau0", json!(s.tau0)),
            ("rig", to_value(&s.rig)),
        ]),
    });
    Ok(Simulated {
        label: None,
        recording,
        truth,
    })
}

fn periodic_endpoint(
    p: &crate::periodic::PeriodicDesign,
    channels: &[String],
    subject: Option<&SubjectText>,
    seed: u64,
) -> Result<Simulated> {
    use crate::follow::{follow_endpoint, EndpointFollower};
    let places = channel_places(channels, ["x", "y", "z"])?;
    let s: EndpointFollower = match subject {
        Some(text) => parse(text)?,
        None => EndpointFollower::default(),
    };
    let command = p.command()?;
    let commands = command_by_place(&command, &places);
    let followed = follow_endpoint(&s, &commands, p.sample_rate_hz, seed)?;
    let recording = periodic_recording(
        "virtual end point",
        &command,
        &["x", "y", "z"],
        &["fx", "fy", "fz"],
        followed,
    )?;
    let m = |a: &[[f64; 3]; 3]| {
        Matrix::from_rows(&a.iter().map(|r| r.to_vec()).collect::<Vec<_>>()).expect("3 x 3")
    };
    let truth = Truth::Periodic(PeriodicTruth {
        about: About {
            sample_rate: Some(p.sample_rate_hz),
            seed: Some(seed),
            notes: periodic_truth_notes(
                p,
                "f = M a + B v + K dx + k2 dx^2 + k3 dx^3 + noise, force applied to the limb",
            ),
            ..About::default()
        },
        coordinates: vec!["x".into(), "y".into(), "z".into()],
        inertia: m(&s.inertia),
        damping: m(&s.damping),
        stiffness: m(&s.stiffness),
        equilibrium: s.equilibrium.to_vec(),
        quadratic: s.quadratic.map(|v| v.to_vec()),
        cubic: s.cubic.map(|v| v.to_vec()),
        other: other_keys([("rig", to_value(&s.rig))]),
    });
    Ok(Simulated {
        label: None,
        recording,
        truth,
    })
}

/// A periodic end-point command played on a subject with M, B, K at its
/// posture, with a human subject's noise ([`NoiseModel`]) instead of the
/// follower's white noise: the prediction behind `limpid protocol design
/// --method stochastic` (issue 60). The servo is the noise model's (`fs / 10`
/// when it tracks ideally); the forces carry, as the centre-out simulation's
/// do, one offset for the recording, slow drift, the subject's
/// signal-dependent force fluctuation, posture drift and tremor, the force
/// sensor's low-pass, white noise and the sensor's resolution (trial-to-trial
/// change has no trials to act on here). `command` is `p.command()`, made
/// once by the caller for many recordings.
pub fn periodic_endpoint_noisy(
    p: &crate::periodic::PeriodicDesign,
    command: &crate::periodic::Command,
    subject: &crate::follow::EndpointFollower,
    noise: &NoiseModel,
    seed: u64,
) -> Result<Recording> {
    use crate::follow::{follow_endpoint, EndpointFollower, Rig};
    use nalgebra::Vector3;
    use rand::{rngs::StdRng, SeedableRng};
    use rand_distr::{Distribution, Normal};
    let fs = p.sample_rate_hz;
    noise.check_at(fs).map_err(|m| Error::invalid("noise", m))?;
    let places = channel_places(&command.channels, ["x", "y", "z"])?;
    let commands = command_by_place::<3>(command, &places);
    let quiet = EndpointFollower {
        rig: Rig {
            servo_hz: if noise.servo_bandwidth_hz > 0.0 {
                noise.servo_bandwidth_hz
            } else {
                fs / 10.0
            },
            force_noise_std: 0.0,
            position_noise_std: 0.0,
        },
        ..subject.clone()
    };
    let whole = follow_endpoint(&quiet, &commands, fs, seed)?;
    // the same motion without inertia: the subject's own force B v + K dx,
    // which the signal-dependent fluctuation scales
    let own = follow_endpoint(
        &EndpointFollower {
            inertia: [[0.0; 3]; 3],
            ..quiet.clone()
        },
        &commands,
        fs,
        seed,
    )?;
    let n = command.t.len();
    let mut rng = StdRng::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).expect("the unit normal is valid");
    let drift =
        crate::simulate::slow_noise(n, fs, noise.drift_lowpass_hz, noise.drift_std_n, &mut rng)?;
    let subject_noise = noise.disturbances(n, fs, &mut rng)?;
    let offset = Vector3::from_fn(|_, _| noise.offset_per_trial_std_n * unit.sample(&mut rng));
    let k = Matrix3::from_fn(|r, c| subject.stiffness[r][c]);
    let mut sensor = noise.force_sensor(fs);
    let mut position: Vec<Vec<f64>> = (0..3).map(|_| Vec::with_capacity(n)).collect();
    let mut force: Vec<Vec<f64>> = (0..3).map(|_| Vec::with_capacity(n)).collect();
    for i in 0..n {
        let at = |v: &[Vec<f64>]| Vector3::from_fn(|a, _| v[a][i]);
        let f = at(&whole.force) + offset + subject_noise.force(i, &at(&own.force), &k);
        let f = sensor.as_mut().map_or(f, |s| s.read(f));
        for a in 0..3 {
            position[a].push(whole.position[a][i] + noise.position_std_m * unit.sample(&mut rng));
            force[a]
                .push(noise.quantise_force(
                    f[a] + drift[a][i] + noise.white_std_n * unit.sample(&mut rng),
                ));
        }
    }
    periodic_recording(
        "virtual end point (design)",
        command,
        &["x", "y", "z"],
        &["fx", "fy", "fz"],
        crate::follow::Followed { position, force },
    )
}

fn periodic_ankle(
    p: &crate::periodic::PeriodicDesign,
    subject: Option<&SubjectText>,
    seed: u64,
) -> Result<Simulated> {
    use crate::ankle::{simulate_ankle_following, AnkleExperiment, AnkleSubject};
    let s: AnkleSubject = match subject {
        Some(text) => parse(text)?,
        None => AnkleSubject::default(),
    };
    let command = p.command()?;
    let experiment = AnkleExperiment {
        rate_hz: p.sample_rate_hz,
        duration_s: command.t.len() as f64 / p.sample_rate_hz,
        ..AnkleExperiment::default()
    };
    let ankle = match &s.servo {
        Some(servo) => crate::ankle::simulate_ankle_servo_following(
            &s,
            &experiment,
            servo,
            &command.values[0],
            seed,
        )?,
        None => simulate_ankle_following(&s, &experiment, &command.values[0], seed)?,
    };
    // the servo's reference too, when the rig is one (issue 79)
    let recorded: Vec<&str> = ["q1", "tau1", "r1"]
        .into_iter()
        .filter(|c| ankle.has(c))
        .collect();
    let period: Vec<f64> = command.period.iter().map(|&i| i as f64).collect();
    let mut names = vec!["t".to_string()];
    let mut columns = vec![command.t.clone()];
    for c in recorded {
        names.push(c.to_string());
        columns.push(ankle.column(c).unwrap_or_default().to_vec());
    }
    names.push("period".into());
    columns.push(period);
    let recording = Recording::new("virtual ankle", names, columns, 2)?;
    let one = |v: f64| Matrix::from_rows(&[vec![v]]).expect("1 x 1");
    let truth = Truth::Reflex(limpid_core::truth::ReflexTruth {
        about: About {
            sample_rate: Some(p.sample_rate_hz),
            seed: Some(seed),
            notes: vec![format!(
                "the virtual ankle (intrinsic I, B, K{}) following {}{}",
                if s.reflex.is_some() {
                    " and a stretch reflex"
                } else {
                    ""
                },
                p.name,
                s.servo.map_or(String::new(), |v| format!(
                    " on a position servo of finite stiffness (K_e {} N m/rad, B_e {} N m s/rad; the subject's own torque {} N m in {}-{} Hz moves the joint too); r1 is the servo's reference",
                    v.stiffness, v.damping, v.subject_torque_nm, v.subject_band_hz.0, v.subject_band_hz.1
                ))
            )],
            ..About::default()
        },
        inertia: one(s.inertia),
        damping: one(s.damping),
        stiffness: one(s.stiffness),
        other: other_keys([
            ("reflex", to_value(&s.reflex)),
            (
                "noise",
                json!({"torque_white_std_Nm": experiment.torque_noise_nm}),
            ),
            ("actuator_hz", json!(experiment.actuator_hz)),
            ("quadratic", json!([s.quadratic])),
            ("cubic", json!([s.cubic])),
        ]),
    });
    let mut truth = truth;
    if let (Some(servo), Truth::Reflex(t)) = (&s.servo, &mut truth) {
        t.other.insert("robot".into(), to_value(servo));
    }
    Ok(Simulated {
        label: None,
        recording,
        truth,
    })
}

fn centre_out(p: &Protocol, subject: Option<&SubjectText>, seed: u64) -> Result<Vec<Simulated>> {
    let given: Option<CentreOutSubjectFile> = subject.map(parse).transpose()?;
    let table = seed000_subject1();
    let starts = p.start_points();
    let protocol = p.centre_out();
    let noise = given
        .as_ref()
        .and_then(|s| s.noise.clone())
        .unwrap_or_default();
    if let Err(message) = noise.check_at(protocol.sample_rate) {
        return Err(Error::Format {
            path: subject.map_or_else(Default::default, |s| s.path.to_path_buf()),
            message: format!("[noise] {message}"),
        });
    }
    let m3 = |a: &[[f64; 3]; 3]| Matrix3::from_fn(|r, c| a[r][c]);
    let mut out = Vec::with_capacity(starts.len());
    for (i, start) in starts.iter().enumerate() {
        let mut posture: Posture = table[i % table.len()].clone();
        if let Some(s) = &given {
            posture.inertia = m3(&s.inertia);
            posture.damping = m3(&s.damping);
            posture.stiffness = m3(&s.stiffness);
        }
        posture.start = *start;
        posture.name = format!("S{}", i + 1);
        let recording = simulate_centre_out(
            &posture,
            &protocol,
            &noise,
            seed.wrapping_mul(1000) + i as u64,
        )?;
        let truth = Truth::Cartesian(CartesianTruth {
            about: About {
                sample_rate: Some(p.sample_rate_hz),
                notes: vec![
                    "f = M a + B v + K (x - S) + offset_trial + drift + white; force applied to the limb".into(),
                    "made by limpid simulate".into(),
                ],
                ..About::default()
            },
            inertia: Matrix::from(posture.inertia),
            damping: Matrix::from(posture.damping),
            stiffness: Matrix::from(posture.stiffness),
            equilibrium: vec![start.x, start.y, start.z],
            profile: to_value(&p.phases.profile).as_str().map(String::from),
            other: other_keys([
                ("noise", to_value(&noise)),
                (
                    "protocol",
                    json!({"trials": protocol.directions.len(), "rest_s": protocol.rest_s, "motion_s": protocol.motion_s, "radius_m": protocol.radius_m}),
                ),
            ]),
        });
        out.push(Simulated {
            label: (starts.len() > 1).then(|| posture.name.clone()),
            recording,
            truth,
        });
    }
    Ok(out)
}

fn planar(p: &PlanarDesign, subject: Option<&SubjectText>, seed: u64) -> Result<Simulated> {
    let mut arm = p.nominal_subject();
    if let Some(text) = subject {
        let s: PlanarSubjectFile = parse(text)?;
        let m2 = |a: &[[f64; 2]; 2]| Matrix2::new(a[0][0], a[0][1], a[1][0], a[1][1]);
        arm.xi = s.xi;
        arm.stiffness = m2(&s.stiffness);
        arm.damping = m2(&s.damping);
        arm.tau0 = s.tau0;
        arm.reflex = s.reflex;
    }
    let (torque_std, angle_std) = (0.02, 1e-5);
    let recording = simulate_planar(&arm, &p.simulation(), torque_std, angle_std, seed)?;
    let truth = Truth::Planar(PlanarTruth {
        about: About {
            sample_rate: Some(p.sample_rate_hz),
            notes: vec![
                "tau = M(q) q'' + C(q,q') q' + D q' + K (q - q0) + tau0 + noise, Lakatos, Petit & van der Smagt (2011) eq. (9)".into(),
                "made by limpid simulate".into(),
            ],
            ..About::default()
        },
        variant: PlanarVariant::Joint,
        inertial_parameters: arm.xi,
        stiffness: Matrix::from(arm.stiffness),
        damping: Matrix::from(arm.damping),
        link_lengths: p.link_lengths_m,
        q0: arm.q0,
        equilibrium: None,
        shoulder: None,
        interpolation_interval_ms: p.interpolation_s * 1e3,
        observation_window_ms: None,
        other: other_keys([
            ("reflex", to_value(&arm.reflex)),
            (
                "noise",
                json!({"torque_white_std_Nm": torque_std, "baseline_torque_Nm": arm.tau0, "joint_angle_std_rad": angle_std}),
            ),
        ]),
    });
    Ok(Simulated {
        label: None,
        recording,
        truth,
    })
}

fn stochastic(
    p: &StochasticDesign,
    subject: Option<&SubjectText>,
    controller: RigController,
    seed: u64,
) -> Result<Simulated> {
    let springs: Springs = match subject {
        Some(text) => {
            let springs = parse::<RigSubjectFile>(text)?.springs;
            // a spring array of real springs: none negative (not passive)
            // or beyond a rig's (issue 76: negative springs simulated)
            if let Some((i, k)) = springs
                .iter()
                .enumerate()
                .find(|(_, k)| !(0.0..=1e6).contains(*k))
            {
                return Err(Error::Format {
                    path: text.path.to_path_buf(),
                    message: format!(
                        "springs[{i}] = {}: a spring's stiffness is 0 (absent) to 1e6 N/m",
                        limpid_core::error::Num(*k)
                    ),
                });
            }
            if springs.iter().all(|k| *k == 0.0) {
                return Err(Error::Format {
                    path: text.path.to_path_buf(),
                    message: "springs: every spring is 0: nothing holds the end point".into(),
                });
            }
            springs
        }
        None => SPRING_SET_SA3,
    };
    let e = p.rig_experiment(&springs)?;
    let noise = [1e-6, 1e-5];
    let seed = seed.wrapping_add(p.seed);
    let dynamics = RobotDynamics::seed004();
    let recording = match controller {
        RigController::Ideal => simulate_rig(&e, noise, seed)?,
        RigController::Imbic => {
            simulate_robot_rig(&e, &dynamics, &Controller::imbic_seed004(), noise, seed)?
        }
        RigController::Pd => {
            simulate_robot_rig(&e, &dynamics, &Controller::pd_seed004(), noise, seed)?
        }
    };
    let robot = match controller {
        RigController::Ideal => {
            json!({"model": "linear, desired impedance", "M_rd": rows(&e.robot_inertia), "B_rd": rows(&e.robot_damping), "K_rd": rows(&e.robot_stiffness)})
        }
        RigController::Imbic => {
            json!({"model": "PUMA-type vertical-plane chain with joint friction under IMBIC (Park & Chang 2011, eq. 11-14, the paper's gains)", "coulomb_Nm": dynamics.coulomb, "viscous_Nms": dynamics.viscous})
        }
        RigController::Pd => {
            json!({"model": "PUMA-type vertical-plane chain with joint friction under a plain PD law", "coulomb_Nm": dynamics.coulomb, "viscous_Nms": dynamics.viscous})
        }
    };
    let truth = Truth::Stochastic(StochasticTruth {
        about: About {
            sample_rate: Some(p.sample_rate_hz),
            notes: vec![
                "spring array of Park & Chang (2011) eq. (10) on the impedance-controlled robot; force on the rig".into(),
                "made by limpid simulate".into(),
            ],
            ..About::default()
        },
        coordinates: ["x (m)", "z (m)", "theta (rad, about y)"].map(String::from).to_vec(),
        inertia: Matrix::from(e.inertia),
        damping: Matrix::from(e.damping),
        stiffness: Matrix::from(e.stiffness),
        equilibrium: vec![0.0, 0.0, 0.0],
        springs_n_per_m: Some(
            ["k1a", "k1b", "k2a", "k2b", "k3a", "k3b", "k4a", "k4b"]
                .into_iter()
                .map(String::from)
                .zip(springs)
                .collect(),
        ),
        band_hz: None,
        other: other_keys([
            ("robot", robot),
            ("noise", json!({"position_std_m": noise[0], "angle_std_rad": noise[1]})),
        ]),
    });
    Ok(Simulated {
        label: None,
        recording,
        truth,
    })
}
