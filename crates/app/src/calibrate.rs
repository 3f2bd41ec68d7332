//! `limpid calibrate`: do the standard errors and the verdicts mean what they
//! say? (issue 15). A Monte Carlo study over virtual subjects of every method
//! with the sensor models of `limpid_lab`: centre-out cubic, trapezoid and
//! sinusoid perturbations (seed 000), co-contraction sessions (seed 001),
//! planar-arm perturbations and their observation-window sweep (seed 003),
//! and the stochastic spring-array experiment (seed 004).
//!
//! For each method and matrix it reports the share of elements whose truth
//! lies within ±2 reported standard errors (target 90-98 %), the share of
//! "trusted" matrices further from the truth than the documented tolerance
//! (K 10 %, B 25 %, relative Frobenius norm; target at most 5 %), and the
//! share of matrices within the tolerance that were nevertheless not trusted.
//!
//! Subjects are drawn from realistic ranges: end-point stiffness eigenvalues
//! 100-1000 N/m, damping 5-50 N s/m, inertia 0.2-2 kg (seed 000 Table I,
//! seed 001 Tables 1-4), each with a random orientation and an antisymmetric
//! part of 1-3 %; joint stiffness 5-50 N m/rad and damping 0.5-3 N m s/rad
//! around seed 003's subject, a third of them with a stretch reflex (latency
//! 40-80 ms, K and D +30-60 %); spring arrays of 20-70 N/m springs (seed 004).
//! Half the centre-out recordings use an ideal position servo (velocity steps
//! at the onset, as in the outside examples), half a 30 Hz servo.

use nalgebra::{Matrix2, Matrix3, Rotation3, Unit, Vector3};
use rand::{rngs::StdRng, Rng, SeedableRng};
use rayon::prelude::*;

use limpid_analysis::cocontraction::estimate_cocontraction;
use limpid_analysis::emg::EmgParams;
use limpid_analysis::linear::{linear_result, tolerance, LinearResult, MatrixKind};
use limpid_core::{Matrix, Result};
use limpid_ident::planar::{prepare_planar, window_sweep, PlanarPrepare};
use limpid_ident::stochastic::{estimate_stochastic, StochasticParams};
use limpid_ident::{fit_linear, prepare, LinearParams, PrepareParams};
use limpid_lab::cocontraction::{
    seed001_population, simulate_cocontraction, CocontractionProtocol, CocontractionSubject,
};
use limpid_lab::planar::{simulate_planar, Cuff, PlanarProtocol, PlanarSubject, Reflex};
use limpid_lab::rig::{simulate_rig, RigExperiment};
use limpid_lab::{simulate_centre_out, CentreOut, NoiseModel, Posture, Profile};

pub use limpid_analysis::calibrate::*;

/// What one recording contributes: per matrix kind (stiffness, damping), the
/// |z| of every element, the relative error and the verdict.
#[derive(Default)]
struct Outcome {
    z: [Vec<f64>; 2],
    matrices: [Vec<(f64, bool)>; 2],
}

impl Outcome {
    fn add(&mut self, kind: usize, est: &Matrix, se: &Matrix, truth: &Matrix, trusted: bool) {
        for ((e, s), t) in est.iter().zip(se.iter()).zip(truth.iter()) {
            let z = (e - t).abs() / s;
            self.z[kind].push(if z.is_nan() { f64::INFINITY } else { z });
        }
        let err = (&est.0 - &truth.0).norm() / truth.norm();
        self.matrices[kind].push((err, trusted));
    }

    fn add_linear(&mut self, r: &LinearResult, k: &Matrix, b: &Matrix) {
        let v = &r.criteria;
        self.add(
            0,
            &r.stiffness,
            &r.standard_errors.stiffness,
            k,
            v.verdict_of(MatrixKind::Stiffness).trusted(),
        );
        self.add(
            1,
            &r.damping,
            &r.standard_errors.damping,
            b,
            v.verdict_of(MatrixKind::Damping).trusted(),
        );
    }
}

fn summarise(
    method: &str,
    outcomes: Vec<std::result::Result<Outcome, String>>,
    seconds: f64,
) -> MethodCalibration {
    let recordings = outcomes.len();
    let mut refused = 0;
    let mut first_refusal = None;
    let mut all = Outcome::default();
    for o in outcomes {
        match o {
            Ok(o) => {
                for k in 0..2 {
                    all.z[k].extend(&o.z[k]);
                    all.matrices[k].extend(&o.matrices[k]);
                }
            }
            Err(e) => {
                refused += 1;
                first_refusal.get_or_insert(e);
            }
        }
    }
    let matrices = [MatrixKind::Stiffness, MatrixKind::Damping]
        .iter()
        .enumerate()
        .map(|(k, kind)| {
            let z = &all.z[k];
            let m = &all.matrices[k];
            let tol = tolerance(*kind);
            let share = |num: usize, den: usize| (den > 0).then(|| 100.0 * num as f64 / den as f64);
            let trusted = m.iter().filter(|(_, t)| *t).count();
            let within = m.iter().filter(|(e, _)| *e <= tol).count();
            let mut errors: Vec<f64> = m.iter().map(|(e, _)| *e).collect();
            errors.sort_by(f64::total_cmp);
            MatrixCalibration {
                matrix: kind.name().into(),
                elements: z.len(),
                coverage_percent: share(z.iter().filter(|v| **v <= 2.0).count(), z.len())
                    .unwrap_or(0.0),
                worst_abs_z: z.iter().copied().fold(0.0, f64::max),
                median_error_percent: errors.get(errors.len() / 2).map_or(0.0, |e| 100.0 * e),
                tolerance_percent: 100.0 * tol,
                judged: m.len(),
                trusted,
                trusted_beyond_tolerance_percent: share(
                    m.iter().filter(|(e, t)| *t && *e > tol).count(),
                    trusted,
                ),
                within_tolerance: within,
                correct_but_untrusted_percent: share(
                    m.iter().filter(|(e, t)| !*t && *e <= tol).count(),
                    within,
                ),
            }
        })
        .collect();
    MethodCalibration {
        method: method.into(),
        recordings,
        refused,
        first_refusal,
        matrices,
        seconds,
    }
}

fn uniform(rng: &mut StdRng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

fn random_rotation(rng: &mut StdRng) -> Matrix3<f64> {
    let axis = Vector3::new(
        uniform(rng, -1.0, 1.0),
        uniform(rng, -1.0, 1.0),
        uniform(rng, -1.0, 1.0),
    );
    let axis = if axis.norm() > 1e-6 {
        axis
    } else {
        Vector3::x()
    };
    Rotation3::from_axis_angle(
        &Unit::new_normalize(axis),
        uniform(rng, 0.0, std::f64::consts::PI),
    )
    .into_inner()
}

/// A 3 x 3 matrix with eigenvalues in lo..hi, a random orientation and an
/// antisymmetric part of 1-3 % of its norm.
fn random_matrix3(rng: &mut StdRng, lo: f64, hi: f64) -> Matrix3<f64> {
    let r = random_rotation(rng);
    let d = Matrix3::from_diagonal(&Vector3::from_fn(|_, _| uniform(rng, lo, hi)));
    let s = r * d * r.transpose();
    let w = Vector3::from_fn(|_, _| uniform(rng, -1.0, 1.0));
    let a = w.cross_matrix();
    let share = uniform(rng, 0.01, 0.03);
    s + a * (share * s.norm() / a.norm().max(1e-12))
}

/// Sensors of the end-point subjects (issue 37: coverage on subjects unlike
/// the calibration generator's): half the outside examples' noise, half
/// drawn from wider ranges: white force noise 0.05-0.5 N, a force offset
/// drifting within the trials (0-0.5 N below 0.2-2 Hz), force noise
/// proportional to the force (0-5 %, coloured below 2 Hz), a coarser force
/// resolution (1/160-1/20 N), position noise 5-50 µm and a posture drifting
/// by 0-0.5 mm.
fn sensors(rng: &mut StdRng) -> NoiseModel {
    let base = NoiseModel::default();
    if rng.random::<bool>() {
        return base;
    }
    NoiseModel {
        white_std_n: uniform(rng, 0.05, 0.5),
        drift_std_n: uniform(rng, 0.0, 0.5),
        drift_lowpass_hz: uniform(rng, 0.2, 2.0),
        force_noise_fraction: uniform(rng, 0.0, 0.05),
        force_quantum_n: 1.0 / uniform(rng, 20.0, 160.0),
        position_std_m: uniform(rng, 5e-6, 5e-5),
        posture_drift_std_m: uniform(rng, 0.0, 5e-4),
        ..base
    }
}

fn centre_out(profile: Profile, seed: u64) -> std::result::Result<Outcome, String> {
    let mut rng = StdRng::seed_from_u64(seed);
    let inertia = Matrix3::from_diagonal(&Vector3::from_fn(|_, _| uniform(&mut rng, 0.2, 2.0)));
    let posture = Posture {
        name: "S".into(),
        start: Vector3::new(0.4, 0.0, 0.0),
        inertia,
        damping: random_matrix3(&mut rng, 5.0, 50.0),
        stiffness: random_matrix3(&mut rng, 100.0, 1000.0),
    };
    let noise = NoiseModel {
        servo_bandwidth_hz: if rng.random::<bool>() { 30.0 } else { 0.0 },
        ..sensors(&mut rng)
    };
    let rec = simulate_centre_out(&posture, &CentreOut::seed000(profile), &noise, seed)
        .map_err(|e| e.to_string())?;
    let data = prepare(&rec, &PrepareParams::default()).map_err(|e| e.to_string())?;
    let est = fit_linear(&data, &LinearParams::default()).map_err(|e| e.to_string())?;
    let mut o = Outcome::default();
    o.add_linear(
        &linear_result(&est, &data),
        &Matrix::from(posture.stiffness),
        &Matrix::from(posture.damping),
    );
    Ok(o)
}

/// One of seed 001's configurations for a virtual co-contraction session,
/// chosen by `seed`.
pub(crate) fn cocontraction_subject(seed: u64) -> CocontractionSubject {
    let population = seed001_population(1, seed);
    let index = (seed % population.len() as u64) as usize;
    population
        .into_iter()
        .nth(index)
        .expect("index within the population")
        .2
}

fn cocontraction(seed: u64) -> std::result::Result<Outcome, String> {
    let subject = &cocontraction_subject(seed);
    let mut rng = StdRng::seed_from_u64(seed ^ 0x5e45);
    let (rec, mvc) = simulate_cocontraction(
        subject,
        &CocontractionProtocol::seed001(),
        &sensors(&mut rng),
        seed,
    )
    .map_err(|e| e.to_string())?;
    let r = estimate_cocontraction(&rec, &mvc, &PrepareParams::default(), &EmgParams::default())
        .map_err(|e| e.to_string())?;
    let mut o = Outcome::default();
    for l in &r.levels {
        o.add_linear(
            &l.estimate,
            &Matrix::from(subject.stiffness(l.level)),
            &Matrix::from(subject.damping),
        );
    }
    Ok(o)
}

/// A symmetric 2 x 2 matrix with eigenvalues in lo..hi and a random orientation.
fn random_matrix2(rng: &mut StdRng, lo: f64, hi: f64) -> Matrix2<f64> {
    let a = uniform(rng, 0.0, std::f64::consts::PI);
    let r = Matrix2::new(a.cos(), -a.sin(), a.sin(), a.cos());
    let d = Matrix2::new(uniform(rng, lo, hi), 0.0, 0.0, uniform(rng, lo, hi));
    r * d * r.transpose()
}

fn planar_subject(rng: &mut StdRng, reflex: bool) -> PlanarSubject {
    let base = PlanarSubject::seed003();
    PlanarSubject {
        xi: base.xi.map(|v| v * uniform(rng, 0.8, 1.2)),
        stiffness: random_matrix2(rng, 5.0, 50.0),
        damping: random_matrix2(rng, 0.5, 3.0),
        reflex: reflex.then(|| Reflex {
            latency_s: uniform(rng, 0.04, 0.08),
            stiffness_gain: uniform(rng, 0.3, 0.6),
            damping_gain: uniform(rng, 0.3, 0.6),
        }),
        ..base
    }
}

/// Seed 003's torque and angle noise (the outside examples (`planar`)).
const PLANAR_NOISE: (f64, f64) = (0.02, 1e-5);

/// A random planar subject, its seed 003 session, prepared.
fn planar_session(
    seed: u64,
    reflex: bool,
) -> std::result::Result<(PlanarSubject, limpid_ident::planar::PlanarData), String> {
    let mut rng = StdRng::seed_from_u64(seed);
    let subject = planar_subject(&mut rng, reflex);
    let rec = simulate_planar(
        &subject,
        &PlanarProtocol::seed003(),
        PLANAR_NOISE.0,
        PLANAR_NOISE.1,
        seed,
    )
    .map_err(|e| e.to_string())?;
    let data = prepare_planar(&rec, &PlanarPrepare::new(0.3, 0.33)).map_err(|e| e.to_string())?;
    Ok((subject, data))
}

fn planar(seed: u64) -> std::result::Result<Outcome, String> {
    let (subject, data) = planar_session(seed, false)?;
    let all: Vec<usize> = (0..data.trials.len()).collect();
    // the whole window; the leave-one-trial-out VAF of `estimate_planar` is not needed here
    let est = limpid_ident::planar::fit_planar(&data, usize::MAX, None, &all)
        .map_err(|e| e.to_string())?;
    let mut o = Outcome::default();
    let trusted = est.criteria.trusted;
    o.add(
        0,
        &est.stiffness,
        &est.standard_errors.stiffness,
        &Matrix::from(subject.stiffness),
        trusted,
    );
    o.add(
        1,
        &est.damping,
        &est.standard_errors.damping,
        &Matrix::from(subject.damping),
        trusted,
    );
    Ok(o)
}

/// What one sweep contributes.
#[derive(Debug, Clone, Copy)]
struct SweepOutcome {
    trusted: usize,
    trusted_but_wrong: usize,
    correct: usize,
    /// The sweep claimed a change of the impedance within the trials.
    change_claimed: bool,
    /// ... and put it down to soft tissue in series.
    tissue_named: bool,
    endpoint: bool,
    cuff: bool,
}

/// A window-sweep subject unlike seed 003's lab alone (issue 37: the change
/// scan cried "reflex" on another generator's reflex-free arms): joint or
/// end-point data (positions through inverse kinematics, white position and
/// force noise), 20-60 trials, T_k 150-250 ms observed for T_k + 70 ms (the
/// held-out generator) or 450 ms (limpid's), a cuff in a quarter, random
/// link lengths, rest torques and sensor noise.
fn sweep_session(
    seed: u64,
    reflex: bool,
) -> std::result::Result<(PlanarSubject, limpid_ident::planar::PlanarData, bool), String> {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut subject = planar_subject(&mut rng, reflex);
    let arm = limpid_core::arm::Arm {
        l1: uniform(&mut rng, 0.26, 0.34),
        l2: uniform(&mut rng, 0.28, 0.36),
        shoulder: [0.0, 0.0],
    };
    subject.tau0 = [uniform(&mut rng, -0.5, 0.5), uniform(&mut rng, -0.5, 0.5)];
    if rng.random::<f64>() < 0.25 {
        subject.cuff = Some(Cuff::seed003(&arm, subject.q0));
    }
    let mut protocol = PlanarProtocol::seed003();
    protocol.trials = rng.random_range(20..=60);
    protocol.interpolation_s = uniform(&mut rng, 0.15, 0.25);
    protocol.after_s = if rng.random::<bool>() {
        protocol.interpolation_s + 0.07
    } else {
        0.45
    };
    let endpoint = rng.random::<bool>();
    let rec = if endpoint {
        let joint =
            simulate_planar(&subject, &protocol, 0.0, 0.0, seed).map_err(|e| e.to_string())?;
        let (position_std, force_std) =
            (uniform(&mut rng, 1e-5, 5e-5), uniform(&mut rng, 0.05, 0.2));
        limpid_lab::planar::to_endpoint(&joint, &arm, position_std, force_std, seed ^ 0x5eed)
            .map_err(|e| e.to_string())?
    } else {
        let (torque_std, angle_std) =
            (uniform(&mut rng, 0.01, 0.05), uniform(&mut rng, 5e-6, 5e-5));
        simulate_planar(&subject, &protocol, torque_std, angle_std, seed)
            .map_err(|e| e.to_string())?
    };
    let data =
        prepare_planar(&rec, &PlanarPrepare::new(arm.l1, arm.l2)).map_err(|e| e.to_string())?;
    Ok((subject, data, endpoint))
}

fn sweep(seed: u64, reflex: bool, varied: bool) -> Option<SweepOutcome> {
    let (subject, data, endpoint) = if varied {
        sweep_session(seed, reflex).ok()?
    } else {
        let (subject, data) = planar_session(seed, reflex).ok()?;
        (subject, data, false)
    };
    let [from, to, step] = limpid_ident::request::DEFAULT_SWEEP_MS;
    let s = window_sweep(&data, from, to, step, None).ok()?;
    let (k, d) = (
        Matrix::from(subject.stiffness),
        Matrix::from(subject.damping),
    );
    let rel = |e: &Matrix, t: &Matrix| (&e.0 - &t.0).norm() / t.norm();
    let mut o = SweepOutcome {
        trusted: 0,
        trusted_but_wrong: 0,
        correct: 0,
        change_claimed: s.impedance_change.is_some(),
        tissue_named: s.series_compliance.is_some(),
        endpoint,
        cuff: subject.cuff.is_some(),
    };
    for r in &s.rows {
        let ok = rel(&r.estimate.stiffness, &k) <= 0.10 && rel(&r.estimate.damping, &d) <= 0.25;
        o.correct += usize::from(ok);
        if r.trusted {
            o.trusted += 1;
            o.trusted_but_wrong += usize::from(!ok);
        }
    }
    Some(o)
}

fn stochastic(seed: u64) -> std::result::Result<Outcome, String> {
    let mut rng = StdRng::seed_from_u64(seed);
    let springs: [f64; 8] = std::array::from_fn(|_| uniform(&mut rng, 20.0, 70.0));
    let e = RigExperiment::spring_array(&springs);
    let rec = simulate_rig(&e, [1e-6, 1e-5], seed).map_err(|e| e.to_string())?;
    let est = estimate_stochastic(&rec, &StochasticParams::default()).map_err(|e| e.to_string())?;
    let mut o = Outcome::default();
    let (v, se) = (&est.criteria.verdicts, &est.standard_errors);
    let (k, b) = (&est.stiffness, &est.damping);
    o.add(
        0,
        k,
        &se.stiffness,
        &Matrix::from(e.stiffness),
        v.stiffness.trusted(),
    );
    o.add(
        1,
        b,
        &se.damping,
        &Matrix::from(e.damping),
        v.damping.trusted(),
    );
    Ok(o)
}

/// A virtual ankle with a stretch reflex (Kearney et al. 1997): random
/// intrinsic I-B-K, reflex delay, gain, low-pass and polarity; 30 s at 1 kHz.
fn reflex(seed: u64) -> std::result::Result<Outcome, String> {
    use limpid_ident::reflex::{estimate_reflex, ReflexParams};
    use limpid_lab::ankle::{simulate_ankle, AnkleExperiment, AnkleReflex, AnkleSubject};
    let mut rng = StdRng::seed_from_u64(seed);
    let subject = AnkleSubject {
        inertia: uniform(&mut rng, 0.01, 0.025),
        damping: uniform(&mut rng, 0.4, 1.5),
        stiffness: uniform(&mut rng, 40.0, 180.0),
        reflex: Some(AnkleReflex {
            gain: uniform(&mut rng, 5.0, 45.0),
            delay_s: uniform(&mut rng, 0.03, 0.07),
            natural_hz: uniform(&mut rng, 1.5, 4.0),
            damping_ratio: uniform(&mut rng, 0.5, 1.0),
            positive: rng.random::<bool>(),
        }),
    };
    let experiment = AnkleExperiment {
        duration_s: 30.0,
        torque_noise_nm: uniform(&mut rng, 0.05, 0.4),
        ..AnkleExperiment::default()
    };
    let rec = simulate_ankle(&subject, &experiment, seed).map_err(|e| e.to_string())?;
    let est = estimate_reflex(&rec, &ReflexParams::default()).map_err(|e| e.to_string())?;
    let i = &est.intrinsic;
    let one = |v: f64| Matrix::from(nalgebra::DMatrix::from_element(1, 1, v));
    let fit_ok = est.fit.vaf_parametric >= limpid_analysis::linear::VAF_FLOOR_PERCENT;
    let mut o = Outcome::default();
    for (kind, k, v, se, truth) in [
        (
            0,
            MatrixKind::Stiffness,
            i.stiffness,
            i.standard_errors.stiffness,
            subject.stiffness,
        ),
        (
            1,
            MatrixKind::Damping,
            i.damping,
            i.standard_errors.damping,
            subject.damping,
        ),
    ] {
        let trusted = limpid_analysis::linear::matrix_verdict(
            k,
            &one(v),
            &one(se),
            fit_ok,
            v.abs() >= 2.0 * se,
            v > 0.0,
        )
        .trusted();
        o.add(kind, &one(v), &one(se), &one(truth), trusted);
    }
    Ok(o)
}

/// The identifiable points of a varying estimate against the truth at their
/// schedule value: K and B with their per-point verdicts.
fn add_varying(
    o: &mut Outcome,
    est: &limpid_ident::varying::VaryingEstimate,
    truth: impl Fn(f64) -> (Matrix, Matrix),
) {
    for p in est.points.iter().filter(|p| p.identifiable) {
        let (Some(k), Some(ks), Some(b), Some(bs), Some(v)) = (
            &p.stiffness,
            &p.stiffness_se,
            &p.damping,
            &p.damping_se,
            &p.verdicts,
        ) else {
            continue;
        };
        let (tk, tb) = truth(p.sigma);
        o.add(0, k, ks, &tk, v.stiffness.trusted());
        o.add(1, b, bs, &tb, v.damping.trusted());
    }
}

/// An ensemble subject drawn at random: one joint (half), or a planar arm in
/// joint (a quarter) or end-point coordinates (a quarter); 15-120
/// repetitions, torque and position noise.
fn ensemble(seed: u64) -> std::result::Result<Outcome, String> {
    use limpid_ident::varying::{estimate_varying, VaryingParams};
    use limpid_lab::varying::{
        simulate_ensemble, EnsembleBody, EnsembleExperiment, EnsembleSubject, TimeChange,
    };
    let mut rng = StdRng::seed_from_u64(seed);
    let change = TimeChange {
        centre_s: uniform(&mut rng, 0.45, 0.75),
        width_s: uniform(&mut rng, 0.12, 0.3),
        stiffness_gain: uniform(&mut rng, 0.0, 1.2),
        damping_gain: uniform(&mut rng, 0.0, 0.6),
    };
    let kind = rng.random_range(0..4);
    let (subject, experiment) = if kind < 2 {
        (
            EnsembleSubject {
                body: EnsembleBody::Joint {
                    inertia: uniform(&mut rng, 0.008, 0.03),
                    movement_rad: uniform(&mut rng, 0.0, 0.5),
                },
                stiffness: vec![vec![uniform(&mut rng, 20.0, 150.0)]],
                damping: vec![vec![uniform(&mut rng, 0.3, 2.0)]],
                change,
            },
            EnsembleExperiment {
                repetitions: rng.random_range(15..=120),
                torque_noise_nm: uniform(&mut rng, 0.02, 0.3),
                position_noise: uniform(&mut rng, 0.0, 2e-5),
                ..EnsembleExperiment::default()
            },
        )
    } else {
        let mut s = EnsembleSubject::planar(kind == 3);
        let k = random_matrix2(&mut rng, 8.0, 40.0);
        let b = random_matrix2(&mut rng, 0.4, 2.0);
        s.stiffness = vec![vec![k[(0, 0)], k[(0, 1)]], vec![k[(1, 0)], k[(1, 1)]]];
        s.damping = vec![vec![b[(0, 0)], b[(0, 1)]], vec![b[(1, 0)], b[(1, 1)]]];
        s.change = change;
        (
            s,
            EnsembleExperiment {
                repetitions: rng.random_range(20..=120),
                amplitude_rad: uniform(&mut rng, 0.02, 0.04),
                switch_s: uniform(&mut rng, 0.1, 0.2),
                actuator_hz: uniform(&mut rng, 4.0, 8.0),
                torque_noise_nm: uniform(&mut rng, 0.01, 0.05),
                position_noise: uniform(&mut rng, 0.0, 1e-5),
                ..EnsembleExperiment::default()
            },
        )
    };
    let rec = simulate_ensemble(&subject, &experiment, seed).map_err(|e| e.to_string())?;
    let est = estimate_varying(&rec, &VaryingParams::default()).map_err(|e| e.to_string())?;
    let mut o = Outcome::default();
    let to = |m: &Vec<Vec<f64>>| Matrix::from_rows(m).expect("square truth");
    add_varying(&mut o, &est, |t| {
        let [_, b, k] = subject.truth_at(t);
        (to(&k), to(&b))
    });
    Ok(o)
}

/// A scheduled ankle drawn at random (K, B quadratic in the operating angle;
/// a reflex whose gain rises with it in half of them), on a ramp-and-hold
/// schedule with or without the ramps recorded. Returns the outcome and,
/// for the reflex claims, (had a reflex, a reflex was detected).
fn scheduled(seed: u64) -> std::result::Result<(Outcome, bool, bool), String> {
    use limpid_ident::varying::{estimate_varying, VaryingParams};
    use limpid_lab::varying::{
        simulate_scheduled_ankle, RampAndHold, ScheduledAnkle, ScheduledReflex,
    };
    let mut rng = StdRng::seed_from_u64(seed);
    let with_reflex = rng.random::<bool>();
    let subject = ScheduledAnkle {
        inertia: uniform(&mut rng, 0.01, 0.025),
        stiffness: [
            uniform(&mut rng, 40.0, 120.0),
            uniform(&mut rng, 0.0, 120.0),
            uniform(&mut rng, 0.0, 150.0),
        ],
        damping: [
            uniform(&mut rng, 0.5, 1.5),
            uniform(&mut rng, -0.5, 1.0),
            0.0,
        ],
        background: [
            uniform(&mut rng, -2.0, 2.0),
            uniform(&mut rng, 0.0, 20.0),
            0.0,
        ],
        reflex: with_reflex.then(|| {
            let low = uniform(&mut rng, 2.0, 10.0);
            let slope = uniform(&mut rng, 0.0, 40.0);
            ScheduledReflex {
                gain: [low + 0.4 * slope, slope, 0.0],
                delay_s: uniform(&mut rng, 0.03, 0.07),
                natural_hz: uniform(&mut rng, 1.5, 4.0),
                damping_ratio: uniform(&mut rng, 0.6, 0.9),
            }
        }),
    };
    let protocol = RampAndHold {
        torque_noise_nm: uniform(&mut rng, 0.05, 0.3),
        keep_ramps: rng.random::<bool>(),
        ..RampAndHold::default()
    };
    let rec = simulate_scheduled_ankle(&subject, &protocol, seed).map_err(|e| e.to_string())?;
    let params = VaryingParams {
        schedule: "sv".into(),
        reflex: true,
        ..VaryingParams::default()
    };
    let est = estimate_varying(&rec, &params).map_err(|e| e.to_string())?;
    let mut o = Outcome::default();
    let one = |v: f64| Matrix::from(nalgebra::DMatrix::from_element(1, 1, v));
    add_varying(&mut o, &est, |s| {
        let [k, b, _] = subject.at(s);
        (one(k), one(b))
    });
    let detected = est.reflex.as_ref().is_some_and(|r| r.detected);
    Ok((o, with_reflex, detected))
}

/// Methods of the study (each `recordings` virtual recordings).
pub const METHODS: usize = 9;

/// Sets of window sweeps: seed 003's session, and the varied subjects.
pub const SWEEP_SETS: usize = 2;

/// Window sweeps per set run beside `recordings` per method: half as many
/// (each fits some 70 windows and split models), at least 10.
pub fn sweeps_for(recordings: usize) -> usize {
    (recordings / 2).max(10)
}

/// Run the whole study: `recordings` virtual recordings per method, in
/// parallel; `progress` is called once per recording and sweep.
pub fn calibrate(
    recordings: usize,
    seed: u64,
    progress: &(dyn Fn() + Sync),
) -> Result<Calibration> {
    let run = |name: &str,
               f: &(dyn Fn(u64) -> std::result::Result<Outcome, String> + Sync),
               salt: u64| {
        let started = std::time::Instant::now();
        let outcomes: Vec<_> = (0..recordings as u64)
            .into_par_iter()
            .map(|i| {
                let o = f(seed
                    .wrapping_mul(1_000_003)
                    .wrapping_add(salt * 100_000 + i));
                progress();
                o
            })
            .collect();
        summarise(name, outcomes, started.elapsed().as_secs_f64())
    };
    let methods = vec![
        run(
            "centre-out cubic (Artemiadis et al. 2010)",
            &|s| centre_out(Profile::Cubic, s),
            1,
        ),
        run(
            "centre-out trapezoid (Artemiadis et al. 2010)",
            &|s| centre_out(Profile::Trapezoid, s),
            2,
        ),
        run(
            "centre-out sinusoid (Artemiadis et al. 2010)",
            &|s| centre_out(Profile::Sinusoid, s),
            3,
        ),
        run(
            "co-contraction, 4 levels (Patel et al. 2013)",
            &cocontraction,
            4,
        ),
        run("planar arm, whole window (Lakatos et al. 2011)", &planar, 5),
        run(
            "stochastic spring array (Park & Chang 2011)",
            &stochastic,
            6,
        ),
        run("ankle with reflex, parallel cascade", &reflex, 8),
        run(
            "time-varying ensemble, joint and planar (per instant)",
            &ensemble,
            9,
        ),
    ];
    let mut methods = methods;
    // the parameter-varying ankle also counts reflex claims
    let started = std::time::Instant::now();
    let scheduled_runs: Vec<_> = (0..recordings as u64)
        .into_par_iter()
        .map(|i| {
            let o = scheduled(seed.wrapping_mul(1_000_003).wrapping_add(1_000_000 + i));
            progress();
            o
        })
        .collect();
    let mut varying_reflex = ReflexClaims::default();
    let outcomes = scheduled_runs
        .into_iter()
        .map(|r| {
            r.map(|(o, had, detected)| {
                if had {
                    varying_reflex.with_reflex += 1;
                    varying_reflex.detected += usize::from(detected);
                } else {
                    varying_reflex.without_reflex += 1;
                    varying_reflex.claimed_without += usize::from(detected);
                }
                o
            })
        })
        .collect();
    methods.push(summarise(
        "parameter-varying ankle with --reflex (per operating angle)",
        outcomes,
        started.elapsed().as_secs_f64(),
    ));
    debug_assert_eq!(methods.len(), METHODS);
    let window_sweep = calibrate_sweeps(sweeps_for(recordings), seed, false, progress);
    let window_sweep_varied = Some(calibrate_sweeps(
        sweeps_for(recordings),
        seed ^ 0x3737,
        true,
        progress,
    ));
    Ok(Calibration {
        seed,
        recordings_per_method: recordings,
        methods,
        window_sweep,
        window_sweep_varied,
        varying_reflex,
    })
}

/// The window sweep's part of [`calibrate`]: `sweeps` subjects, a third
/// with a stretch reflex; seed 003's session around its subject, or (`varied`)
/// the subjects of [`sweep_session`].
pub fn calibrate_sweeps(
    sweeps: usize,
    seed: u64,
    varied: bool,
    progress: &(dyn Fn() + Sync),
) -> SweepCalibration {
    let started = std::time::Instant::now();
    let outcomes: Vec<(bool, Option<SweepOutcome>)> = (0..sweeps as u64)
        .into_par_iter()
        .map(|i| {
            let reflex = i % 3 == 0;
            let r = sweep(
                seed.wrapping_mul(1_000_003).wrapping_add(700_000 + i),
                reflex,
                varied,
            );
            progress();
            (reflex, r)
        })
        .collect();
    let mut window_sweep = SweepCalibration {
        seconds: started.elapsed().as_secs_f64(),
        ..SweepCalibration::default()
    };
    for (reflex, r) in outcomes {
        window_sweep.refused += usize::from(r.is_none());
        if let Some(o) = r {
            let w = &mut window_sweep;
            w.sweeps += 1;
            w.with_reflex += usize::from(reflex);
            w.endpoint_sweeps += usize::from(o.endpoint);
            w.cuff_sweeps += usize::from(o.cuff);
            w.trusted_windows += o.trusted;
            w.trusted_but_wrong += o.trusted_but_wrong;
            w.correct_windows += o.correct;
            w.sweeps_with_a_trusted_window[usize::from(reflex)] += usize::from(o.trusted > 0);
            w.changes_claimed[usize::from(reflex)] += usize::from(o.change_claimed);
            w.cuff_with_reflex += usize::from(o.cuff && reflex);
            w.cuff_changes_claimed[usize::from(reflex)] += usize::from(o.cuff && o.change_claimed);
            w.tissue_named[usize::from(reflex)] += usize::from(o.tissue_named);
        }
    }
    window_sweep
}
