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

use rayon::prelude::*;

use limpid_analysis::linear::{tolerance, LinearResult, MatrixKind};
use limpid_core::{Matrix, Result};
use limpid_lab::cocontraction::{seed001_population, CocontractionSubject};
use limpid_lab::Profile;

mod methods;
mod subjects;
mod sweeps;
use methods::{
    centre_out, cocontraction, ensemble, planar, planar_session, reflex, reflex_segments,
    reflex_servo, scheduled, scheduled_segments, stochastic, walking,
};
use subjects::{planar_subject, random_matrix2, random_matrix3, sensors, uniform, PLANAR_NOISE};
use sweeps::{sweep, sweep_session, SweepOutcome};

use limpid_analysis::result::calibration::{
    Calibration, DesignCalibration, MatrixCalibration, MethodCalibration, ReflexClaims,
    SweepCalibration,
};

/// What one recording contributes: per matrix kind (stiffness, damping), the
/// |z| of every element (against the reported SE, and against the SE
/// without the method's fixed floor), the relative error and the verdict.
#[derive(Default)]
struct Outcome {
    z: [Vec<f64>; 2],
    z_without_floor: [Vec<f64>; 2],
    /// The share of each value the estimator added in quadrature to its SE
    /// (a fixed model-error floor) for this recording, per matrix kind.
    floors: [f64; 2],
    matrices: [Vec<(f64, bool)>; 2],
}

/// |estimate - truth| / se, infinite where undefined.
fn abs_z(e: f64, t: f64, se: f64) -> f64 {
    let z = (e - t).abs() / se;
    if z.is_nan() {
        f64::INFINITY
    } else {
        z
    }
}

impl Outcome {
    /// An outcome whose estimator floors its K and B standard errors at these shares.
    fn floored(floors: [f64; 2]) -> Self {
        Outcome {
            floors,
            ..Outcome::default()
        }
    }

    fn add(&mut self, kind: usize, est: &Matrix, se: &Matrix, truth: &Matrix, trusted: bool) {
        let floor = self.floors[kind];
        for ((e, s), t) in est.iter().zip(se.iter()).zip(truth.iter()) {
            self.z[kind].push(abs_z(*e, *t, *s));
            // every floor is added in quadrature, se = hypot(se0, floor |e|): undone exactly
            let unfloored = (s * s - (floor * e).powi(2)).max(0.0).sqrt();
            self.z_without_floor[kind].push(abs_z(*e, *t, unfloored));
        }
        let err = (&est.0 - &truth.0).norm() / truth.norm();
        self.matrices[kind].push((err, trusted));
    }

    fn add_linear(&mut self, r: &LinearResult, k: &Matrix, b: &Matrix) {
        // the linear SEs of B (and M) carry the derivative-bias floor
        self.floors = [0.0, limpid_ident::linear::DERIVATIVE_ERROR_FLOOR];
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
    summarise_within(method, outcomes, seconds, None)
}

/// [`summarise`] judging "trusted beyond tolerance" against the method's own
/// tolerances (K, B), when it has them (walking).
fn summarise_within(
    method: &str,
    outcomes: Vec<std::result::Result<Outcome, String>>,
    seconds: f64,
    tolerances: Option<[f64; 2]>,
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
                    all.z_without_floor[k].extend(&o.z_without_floor[k]);
                    all.matrices[k].extend(&o.matrices[k]);
                    all.floors[k] = all.floors[k].max(o.floors[k]);
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
            let tol = tolerances.map_or_else(|| tolerance(*kind), |t| t[k]);
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
                coverage_without_floor_percent: (all.floors[k] > 0.0)
                    .then(|| {
                        let z = &all.z_without_floor[k];
                        share(z.iter().filter(|v| **v <= 2.0).count(), z.len())
                    })
                    .flatten(),
                floor_percent: (all.floors[k] > 0.0).then(|| 100.0 * all.floors[k]),
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

/// Methods of the study (each `recordings` virtual recordings).
pub const METHODS: usize = 13;

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
    let run_within = |name: &str,
                      f: &(dyn Fn(u64) -> std::result::Result<Outcome, String> + Sync),
                      salt: u64,
                      tolerances: Option<[f64; 2]>| {
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
        summarise_within(name, outcomes, started.elapsed().as_secs_f64(), tolerances)
    };
    let run = |name: &str,
               f: &(dyn Fn(u64) -> std::result::Result<Outcome, String> + Sync),
               salt: u64| run_within(name, f, salt, None);
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
        run(
            "planar arm, whole window (Lakatos et al. 2011; half end-point, varied sensors)",
            &planar,
            5,
        ),
        run(
            "stochastic spring array (Park & Chang 2011)",
            &stochastic,
            6,
        ),
        run("ankle with reflex, parallel cascade", &reflex, 8),
        run(
            "ankle with reflex, short segments of 0.3-1.5 s (Ludvig & Perreault 2012)",
            &reflex_segments,
            11,
        ),
        run(
            "ankle with reflex on a compliant servo, closed loop (K_e/K 0.5-10; the reference as instrument)",
            &reflex_servo,
            13,
        ),
        run(
            "parameter-varying ankle with --reflex, short segments of 0.3-1.5 s (per operating angle)",
            &scheduled_segments,
            12,
        ),
        run(
            "time-varying ensemble, joint and planar (per instant)",
            &ensemble,
            9,
        ),
        run_within(
            "walking ankle, pulses or continuous perturbation (per stance gait-phase point)",
            &walking,
            10,
            {
                let t = limpid_ident::varying::gait::WALKING_TOLERANCES;
                Some([t[0], t[1]])
            },
        ),
    ];
    let mut methods = methods;
    let (scheduled_method, varying_reflex) = calibrate_scheduled(recordings, seed, progress);
    methods.push(scheduled_method);
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
        design: Some(calibrate_design(recordings, seed)?),
        stochastic_design: Some(calibrate_stochastic_design(recordings, seed)?),
        planar_design: Some(calibrate_planar_design(recordings, seed)?),
    })
}

/// The parameter-varying ankle's part of the study (it also counts reflex
/// claims): `recordings` scheduled ankles drawn at random.
pub fn calibrate_scheduled(
    recordings: usize,
    seed: u64,
    progress: &(dyn Fn() + Sync),
) -> (MethodCalibration, ReflexClaims) {
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
    let method = summarise(
        "parameter-varying ankle with --reflex (per operating angle)",
        outcomes,
        started.elapsed().as_secs_f64(),
    );
    (method, varying_reflex)
}

/// Stiffness and damping of the prior range's other end, relative to the
/// demo's S1: subjects unlike the nominal one (a stiffer, less damped arm).
const DESIGN_RANGE: (f64, f64) = (1.4, 0.7);

/// The demo's S1 with a prior range (K x1.4, B x0.7 at its other end).
fn design_prior() -> crate::design::Prior {
    let mut prior = crate::design::Prior::demo(0);
    prior.other_end = Some(crate::design::Impedance {
        stiffness: prior.nominal.stiffness * DESIGN_RANGE.0,
        damping: prior.nominal.damping * DESIGN_RANGE.1,
        ..prior.nominal
    });
    prior
}

/// A design's figures for calibrate, from its verification; `prior` in words.
fn design_calibration(
    prior: String,
    predicted: &limpid_analysis::result::design::Prediction,
    verify: Option<&limpid_analysis::result::design::Verification>,
    recordings: usize,
    started: std::time::Instant,
) -> DesignCalibration {
    let v = verify.expect("a design asked to verify carries its verification");
    DesignCalibration {
        prior,
        recordings,
        predicted_se: predicted.pooled.se,
        achieved_se: v.achieved_se,
        ratio: v.ratio,
        within_tolerance_share: v.within_tolerance_share,
        seconds: started.elapsed().as_secs_f64(),
    }
}

/// The demo's S1 prior range in words.
fn design_prior_words() -> String {
    format!(
        "the demo's S1 to K x{}, B x{} (predicted at the worse end, subjects drawn uniformly between)",
        DESIGN_RANGE.0, DESIGN_RANGE.1
    )
}

/// `limpid protocol design --method planar` for seed 003's arm holding a
/// load (no reflex) to K x1.4, D x0.7, with lakatos-planar's limits and a
/// 72 s budget (the seed protocol's session).
fn calibrate_planar_design(recordings: usize, seed: u64) -> Result<DesignCalibration> {
    use crate::design::planar::{design_planar, ArmImpedance, PlanarDesignRequest, PlanarFrame};
    let started = std::time::Instant::now();
    let mut prior = crate::design::planar::PlanarPrior::demo();
    prior.reflex = None;
    prior.other_end = Some(ArmImpedance {
        stiffness: prior.nominal.stiffness * DESIGN_RANGE.0,
        damping: prior.nominal.damping * DESIGN_RANGE.1,
        ..prior.nominal
    });
    let seed003 = limpid_lab::design::PlanarDesign::seed003();
    let request = PlanarDesignRequest {
        limits: PlanarFrame {
            limits: seed003.limits.clone(),
            link_lengths_m: seed003.link_lengths_m,
            posture_rad: seed003.posture_rad,
            wait_s: seed003.wait_s,
        },
        prior,
        sample_rate_hz: seed003.sample_rate_hz,
        budget_s: 72.0,
        objective: crate::design::Objective::default(),
        runs: recordings,
        baseline: None,
        verify: recordings,
        seed: seed ^ 0x6062,
    };
    let d = design_planar(&request)?;
    Ok(design_calibration(
        format!(
            "seed 003's arm holding a load, no reflex, to K x{}, D x{} (predicted at the worse end, arms drawn uniformly between)",
            DESIGN_RANGE.0, DESIGN_RANGE.1
        ),
        &d.result.predicted,
        d.result.verify.as_ref(),
        recordings,
        started,
    ))
}

/// `limpid protocol design --method stochastic` for the same prior range,
/// with the endpoint-multisine preset's limits and the seed's time.
fn calibrate_stochastic_design(recordings: usize, seed: u64) -> Result<DesignCalibration> {
    use crate::design::stochastic::{design_stochastic, StochasticDesignRequest};
    let started = std::time::Instant::now();
    let preset = limpid_lab::periodic::PeriodicDesign::multisine_endpoint();
    let request = StochasticDesignRequest {
        prior: design_prior(),
        limits: preset.limits.clone(),
        sample_rate_hz: preset.sample_rate_hz,
        budget_s: crate::design::protocol_duration(&limpid_lab::protocol::preset("artemiadis-3d")?),
        objective: crate::design::Objective::default(),
        runs: recordings,
        baseline: None,
        verify: recordings,
        seed: seed ^ 0x6061,
    };
    let d = design_stochastic(&request)?;
    Ok(design_calibration(
        design_prior_words(),
        &d.result.predicted,
        d.result.verify.as_ref(),
        recordings,
        started,
    ))
}

/// `limpid protocol design` for the demo's S1 with a prior range (K x1.4,
/// B x0.7 at its other end), predicted on `recordings` simulated recordings
/// and verified on as many subjects drawn from the range.
fn calibrate_design(recordings: usize, seed: u64) -> Result<DesignCalibration> {
    use crate::design::{design, DesignRequest, Objective};
    let started = std::time::Instant::now();
    let prior = design_prior();
    let limits = limpid_lab::protocol::preset("artemiadis-3d")?;
    let request = DesignRequest {
        prior,
        limits: limits.limits.clone(),
        sample_rate_hz: limits.sample_rate_hz,
        budget_s: crate::design::protocol_duration(&limits),
        objective: Objective::default(),
        runs: recordings,
        baseline: None,
        verify: recordings,
        seed: seed ^ 0x6060,
    };
    let d = design(&request)?;
    Ok(design_calibration(
        design_prior_words(),
        &d.result.predicted,
        d.result.verify.as_ref(),
        recordings,
        started,
    ))
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
