//! `limpid reproduce`: each seed's experiment on the virtual lab with the
//! realistic subjects of [`limpid_lab::realistic`], its tables and headline
//! numbers printed beside the paper's.
//!
//! - 000: seed 000 §III on subject 1 of Table I (plus Table II's antisymmetric
//!   part), cubic perturbations, [`NoiseModel::realistic`]: Table II per start
//!   point and the fit correlation per axis.
//! - 001: seed 001's 7 configurations x 4 levels on 4 subjects built from its
//!   Tables 1-5, one MVC from configuration 5: Tables 1-4 (diagonal, K_maxA,
//!   principal stiffnesses), Table 5 (axis rotations), the index per level.
//! - 003: seed 003's planar experiment with a spinal reflex: the shortest
//!   windows at which K is positive definite, K and D quasi-symmetric, all
//!   parameters quasi-constant, with known and unknown inertia; Table I's
//!   conditioning ratios, quintic against a sixth-order polynomial.
//! - 004: seed 004's spring arrays sa1 and sa2 held by the robot under IMBIC
//!   and under PD, Table III's Welch settings: K_sa, phi_T and the multiple
//!   coherence.
//!
//! Every paper number the experiment addresses is one [`Row`]; `paper` is
//! `None` where the text does not give the number (figures only, garbled
//! tables). [`Finding`]s state the papers' qualitative findings and whether
//! the virtual experiment shows them.

// the paper's tables and limpid's are indexed in step ([configuration][level][value])
#![allow(clippy::needless_range_loop)]

use nalgebra::{Matrix3, Matrix4, Vector4};
use rayon::prelude::*;

use limpid_core::criteria::MatrixVerdict;
use limpid_core::{Error, Matrix, Result};
use limpid_ident::{fit_linear, prepare, LinearParams, PrepareParams};
use limpid_lab::realistic::{
    antisymmetric_part, SEED000_K_MAX_A, SEED001_LEVELS, SEED001_ROTATION_DEG, SEED001_TABLES,
};
use limpid_lab::{seed000_subject1, simulate_centre_out, CentreOut, NoiseModel, Profile};

use limpid_analysis::cocontraction::estimate_cocontraction;
use limpid_analysis::emg::EmgParams;
use limpid_analysis::linear::{linear_result, MatrixKind};
pub use limpid_analysis::reproduce::*;
use limpid_analysis::{antisymmetric, symmetric, table_ii};

/// Run the experiments of `seeds` with random seed `seed`.
pub fn reproduce(seeds: &[Seed], seed: u64) -> Result<Reproduction> {
    let mut out = Reproduction::default();
    for s in seeds {
        let part = match s {
            Seed::S000 => seed000(seed)?,
            Seed::S001 => seed001(seed)?,
            Seed::S003 => seed003(seed)?,
            Seed::S004 => seed004(seed)?,
        };
        out.rows.extend(part.rows);
        out.findings.extend(part.findings);
    }
    Ok(out)
}

fn verdict_words(v: MatrixVerdict) -> &'static str {
    match v {
        MatrixVerdict::Trusted => "trusted",
        MatrixVerdict::PoorFit => "poor fit",
        MatrixVerdict::NotIdentifiable => "not identifiable",
        MatrixVerdict::NotPassive => "not passive",
        MatrixVerdict::Imprecise => "imprecise (2 SE beyond the tolerance)",
    }
}

fn row(seed: &str, item: String, paper: Option<f64>, limpid: Option<f64>, unit: &str) -> Row {
    Row {
        seed: seed.into(),
        item,
        paper,
        limpid: limpid.filter(|v| v.is_finite()),
        unit: unit.into(),
        note: String::new(),
    }
}

fn mean(v: impl IntoIterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for x in v {
        s += x;
        n += 1;
    }
    if n == 0 {
        f64::NAN
    } else {
        s / n as f64
    }
}

/// Seed 000 Table II, subject 1: K_max, K_min, K_maxA, B_max, B_min, B_maxA,
/// M_max, M_min, M_maxA per start point S1-S6.
const SEED000_TABLE_II: [[f64; 9]; 6] = [
    [1002.0, 12.0, 2.0, 86.0, 9.0, 1.0, 0.40, 0.01, 1.3e-3],
    [620.0, 83.0, 13.0, 139.0, 11.0, 2.0, 0.18, 0.01, 2.3e-4],
    [429.0, 42.0, 8.0, 61.0, 16.0, 2.0, 0.36, 0.02, 3.4e-3],
    [224.0, 9.0, 2.0, 35.0, 4.0, 0.7, 0.60, 0.01, 1.5e-3],
    [431.0, 23.0, 2.3, 96.0, 1.5, 0.09, 0.63, 0.07, 8.9e-3],
    [690.0, 21.0, 1.2, 55.0, 5.58, 0.17, 0.31, 0.05, 0.01],
];

/// Seed 000's fit correlations per Cartesian axis (§III).
const SEED000_R: [f64; 3] = [0.94, 0.88, 0.87];

fn seed000(seed: u64) -> Result<Reproduction> {
    let protocol = CentreOut::seed000(Profile::Cubic);
    let noise = NoiseModel::realistic();
    let results = seed000_subject1()
        .into_par_iter()
        .enumerate()
        .map(|(i, mut p)| {
            p.stiffness += antisymmetric_part(SEED000_K_MAX_A[i]);
            let rec =
                simulate_centre_out(&p, &protocol, &noise, seed.wrapping_mul(1000) + i as u64)?;
            let data = prepare(&rec, &PrepareParams::default())?;
            let est = fit_linear(&data, &LinearParams::default())?;
            Ok(linear_result(&est, &data))
        })
        .collect::<Result<Vec<_>>>()?;
    let mut out = Reproduction::default();
    let kinds = [
        (MatrixKind::Stiffness, "K", "N/m"),
        (MatrixKind::Damping, "B", "N s/m"),
        (MatrixKind::Inertia, "M", "kg"),
    ];
    // Table I: the subject's diagonal (as read from the garbled table, see
    // limpid_lab::seed000_subject1) against limpid's estimate
    let table_i = seed000_subject1();
    for (i, r) in results.iter().enumerate() {
        for (kind, letter, unit) in kinds.iter().take(2) {
            let truth = match kind {
                MatrixKind::Stiffness => table_i[i].stiffness,
                _ => table_i[i].damping,
            };
            for (a, axis) in ["xx", "yy", "zz"].iter().enumerate() {
                let mut x = row(
                    "000",
                    format!("Table I, subject 1, S{}, {letter}_{axis}", i + 1),
                    Some(truth[(a, a)]),
                    Some(r.matrix(*kind)[(a, a)]),
                    unit,
                );
                let verdict = r.criteria.verdicts.get(*kind);
                if *verdict != MatrixVerdict::Trusted {
                    x.note = format!("limpid's verdict on {letter}: {}", verdict_words(*verdict));
                }
                out.rows.push(x);
            }
        }
    }
    let mut ratio_max = 0.0f64;
    for (i, r) in results.iter().enumerate() {
        for (k, (kind, letter, unit)) in kinds.iter().enumerate() {
            let t = table_ii(r.matrix(*kind));
            let verdict = r.criteria.verdicts.get(*kind);
            let note = match verdict {
                MatrixVerdict::Trusted => String::new(),
                v => format!("limpid's verdict on {letter}: {}", verdict_words(*v)),
            };
            let paper = &SEED000_TABLE_II[i];
            for (j, (name, value)) in [
                ("max", t.max_symmetric),
                ("min", t.min_symmetric),
                ("maxA", t.max_antisymmetric),
            ]
            .into_iter()
            .enumerate()
            {
                out.rows.push(
                    row(
                        "000",
                        format!("Table II, subject 1, S{}, {letter}_{name}", i + 1),
                        Some(paper[3 * k + j]),
                        Some(value),
                        unit,
                    )
                    .with_note(note.clone()),
                );
            }
            if *letter == "K" {
                ratio_max = ratio_max.max(t.max_antisymmetric / t.max_symmetric);
            }
        }
    }
    let r_axis: Vec<f64> = (0..3)
        .map(|a| mean(results.iter().map(|r| r.fit.r[a])))
        .collect();
    for (a, axis) in ["x", "y", "z"].iter().enumerate() {
        out.rows.push(row(
            "000",
            format!("fit correlation r, {axis} axis (mean of S1-S6)"),
            Some(SEED000_R[a]),
            Some(r_axis[a]),
            "",
        ).with_note("signal-dependent force noise (25 % of the subject's force, < 2 Hz) and posture drift of the realistic subject"));
    }
    out.findings.push(Finding {
        seed: "000".into(),
        claim: "the antisymmetric (curl) stiffness is much lower than the symmetric".into(),
        holds: ratio_max < 0.1,
        evidence: format!("largest K_maxA / K_max over S1-S6: {:.3}", ratio_max),
    });
    let (lo, hi) = r_axis
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, h), v| (l.min(*v), h.max(*v)));
    out.findings.push(Finding {
        seed: "000".into(),
        claim: "the linear model fits the force with r of about 0.87-0.94 per axis".into(),
        holds: lo > 0.8 && hi < 0.98,
        evidence: format!("limpid: r = {lo:.3}-{hi:.3}"),
    });
    Ok(out)
}

/// Principal values (largest first) of the symmetric part and the largest
/// antisymmetric element.
fn principal_and_max_a(k: &Matrix) -> ([f64; 3], f64) {
    let s = symmetric(k);
    let m3 = Matrix3::from_fn(|i, j| s[(i, j)]);
    let mut e: Vec<f64> = m3.symmetric_eigenvalues().iter().copied().collect();
    e.sort_by(|a, b| b.total_cmp(a));
    let a = antisymmetric(k);
    (
        [e[0], e[1], e[2]],
        a.iter().fold(0.0, |m, v| m.max(v.abs())),
    )
}

fn seed001(seed: u64) -> Result<Reproduction> {
    use limpid_lab::cocontraction::{
        seed001_realistic_population, simulate_cocontraction, CocontractionProtocol,
    };
    const SUBJECTS: usize = 4;
    let population = seed001_realistic_population(SUBJECTS, seed);
    let protocol = CocontractionProtocol::seed001();
    let noise = NoiseModel::realistic();
    let simulated = population
        .par_iter()
        .map(|(s, c, subject)| {
            let sim_seed = seed.wrapping_mul(10_000) + (*s as u64) * 100 + *c as u64;
            simulate_cocontraction(subject, &protocol, &noise, sim_seed).map(|r| (*s, *c, r))
        })
        .collect::<Result<Vec<_>>>()?;
    // seed 001: one MVC, recorded in configuration 5, for every configuration
    let mvc_of = |s: usize| {
        simulated
            .iter()
            .find(|(si, c, _)| *si == s && *c == 5)
            .map(|(_, _, (_, mvc))| mvc)
            .ok_or_else(|| Error::invalid("reproduce", "configuration 5 missing"))
    };
    let results = simulated
        .par_iter()
        .map(|(s, c, (rec, _))| {
            let r = estimate_cocontraction(
                rec,
                mvc_of(*s)?,
                &PrepareParams::default(),
                &EmgParams::default(),
            )?;
            Ok((*c, r))
        })
        .collect::<Result<Vec<_>>>()?;
    let mut out = Reproduction::default();
    let names = ["K_xx", "K_yy", "K_zz", "K_maxA", "K_1", "K_2", "K_3"];
    // [config][level] -> the 7 table values, mean over subjects
    let mut measured = [[[0.0f64; 7]; 4]; 7];
    let mut index = [[0.0f64; 4]; 7];
    let mut rotation = [[0.0f64; 3]; 7];
    for c in 1..=7 {
        let of_config: Vec<_> = results
            .iter()
            .filter(|(ci, _)| *ci == c)
            .map(|(_, r)| r)
            .collect();
        for (l, level) in SEED001_LEVELS.iter().enumerate() {
            let values: Vec<[f64; 7]> = of_config
                .iter()
                .filter_map(|r| r.levels.iter().find(|x| (x.level - level).abs() < 1e-9))
                .map(|x| {
                    let k = &x.stiffness;
                    let (p, max_a) = principal_and_max_a(k);
                    [k[(0, 0)], k[(1, 1)], k[(2, 2)], max_a, p[0], p[1], p[2]]
                })
                .collect();
            for v in 0..7 {
                measured[c - 1][l][v] = mean(values.iter().map(|x| x[v]));
            }
            index[c - 1][l] = mean(
                of_config
                    .iter()
                    .filter_map(|r| r.levels.iter().find(|x| (x.level - level).abs() < 1e-9))
                    .map(|x| x.cocontraction_index),
            );
        }
        for axis in 0..3 {
            rotation[c - 1][axis] = mean(of_config.iter().filter_map(|r| {
                r.comparisons
                    .iter()
                    .find(|x| (x.level - 1.0).abs() < 1e-9)
                    .map(|x| x.rotation_deg[axis])
            }));
        }
    }
    for (l, level) in SEED001_LEVELS.iter().enumerate() {
        for c in 0..7 {
            for v in 0..7 {
                out.rows.push(row(
                    "001",
                    format!(
                        "Table {}, {} %, configuration {}, {}",
                        l + 1,
                        level * 100.0,
                        c + 1,
                        names[v]
                    ),
                    Some(SEED001_TABLES[l][c][v]),
                    Some(measured[c][l][v]),
                    "N/m",
                ));
            }
        }
    }
    for c in 0..7 {
        for axis in 0..3 {
            out.rows.push(row(
                "001",
                format!(
                    "Table 5, configuration {}, rotation of axis {}",
                    c + 1,
                    axis + 1
                ),
                Some(SEED001_ROTATION_DEG[c][axis]),
                Some(rotation[c][axis]),
                "deg",
            ));
        }
    }
    for (l, level) in SEED001_LEVELS.iter().enumerate() {
        out.rows.push(
            row(
                "001",
                format!(
                    "co-contraction index C at the {} % level (mean of configurations)",
                    level * 100.0
                ),
                None,
                Some(mean((0..7).map(|c| index[c][l]))),
                "",
            )
            .with_note("Fig. 4 only: the subjects held each level; MVC from configuration 5"),
        );
    }
    // findings
    let ratio = |v: usize| {
        mean(
            (0..7)
                .flat_map(|c| (0..4).map(move |l| (c, l)))
                .map(|(c, l)| measured[c][l][v] / SEED001_TABLES[l][c][v]),
        )
    };
    let max_a_ratio = ratio(3);
    out.findings.push(Finding {
        seed: "001".into(),
        claim: "the antisymmetric stiffness K_maxA is of the size Tables 1-4 report (114-507 N/m)"
            .into(),
        holds: (0.67..1.5).contains(&max_a_ratio),
        evidence: format!("mean limpid / paper K_maxA: {max_a_ratio:.2}"),
    });
    let increase =
        |v: usize| mean((0..7).map(|c| 100.0 * (measured[c][3][v] / measured[c][0][v] - 1.0)));
    let (i1, i2, i3) = (increase(4), increase(5), increase(6));
    out.findings.push(Finding {
        seed: "001".into(),
        claim: "co-contraction enlarges the ellipsoid mainly along the tertiary axis".into(),
        holds: i3 > i1 && i3 > i2,
        evidence: format!(
            "0 -> 100 %: K_1 +{i1:.0} %, K_2 +{i2:.0} %, K_3 +{i3:.0} % (mean of configurations)"
        ),
    });
    let primary = mean((0..7).map(|c| rotation[c][0]));
    let others = mean((0..7).flat_map(|c| [rotation[c][1], rotation[c][2]]));
    out.findings.push(Finding {
        seed: "001".into(),
        claim: "100 % co-contraction turns the secondary and tertiary axes by 24.2 deg on average, the primary by 8.5".into(),
        holds: others > 2.0 * primary && (12.0..36.0).contains(&others),
        evidence: format!("limpid: secondary/tertiary {others:.1} deg, primary {primary:.1} deg"),
    });
    // departure of the 50 % and 75 % levels from the line through 0 and 100 %
    let departure = |table: &dyn Fn(usize, usize, usize) -> f64| {
        mean((0..7).flat_map(|c| {
            (4..7).flat_map(move |v| {
                [(1usize, 0.5), (2, 0.75)].map(|(l, level)| {
                    let line = table(c, 0, v) + level * (table(c, 3, v) - table(c, 0, v));
                    100.0 * (table(c, l, v) - line).abs() / table(c, 3, v)
                })
            })
        }))
    };
    let paper_departure = departure(&|c, l, v| SEED001_TABLES[l][c][v]);
    let limpid_departure = departure(&|c, l, v| measured[c][l][v]);
    out.rows.push(row(
        "001",
        "mean departure of K_1-K_3 at 50 % and 75 % from the line through 0 and 100 % (of K at 100 %)".into(),
        Some(paper_departure),
        Some(limpid_departure),
        "%",
    ).with_note("Tables 1-4; the subject carries each table's own values"));
    out.findings.push(Finding {
        seed: "001".into(),
        claim: "stiffness is not linear in the level (Tables 2-3)".into(),
        holds: (0.5..2.0).contains(&(limpid_departure / paper_departure)),
        evidence: format!(
            "mean departure from linear: paper {paper_departure:.1} %, limpid {limpid_departure:.1} %"
        ),
    });
    Ok(out)
}

/// s(τ) = a3 τ³ + a4 τ⁴ + a5 τ⁵ + a6 τ⁶ with s(0) = s'(0) = s''(0) = 0,
/// s(1) = 1, s'(1) = s''(1) = s'''(1) = 0 (seed 003 §III-B's sixth-order
/// comparison polynomial).
fn sextic_coefficients() -> [f64; 4] {
    let a = Matrix4::new(
        1.0, 1.0, 1.0, 1.0, //
        3.0, 4.0, 5.0, 6.0, //
        6.0, 12.0, 20.0, 30.0, //
        6.0, 24.0, 60.0, 120.0,
    );
    let x = a
        .lu()
        .solve(&Vector4::new(1.0, 0.0, 0.0, 0.0))
        .expect("the boundary conditions are independent");
    [x[0], x[1], x[2], x[3]]
}

/// Seed 003 eq. (17) for a polynomial s(τ) = Σ c_k τ^k over `duration`.
fn polynomial_ratios(coef: &[(i32, f64)], duration: f64) -> [f64; 3] {
    let derivative = |tau: f64, order: i32| -> f64 {
        coef.iter()
            .map(|(k, c)| {
                if *k < order {
                    return 0.0;
                }
                let falling: f64 = (0..order).map(|j| (k - j) as f64).product();
                c * falling * tau.powi(k - order) / duration.powi(order)
            })
            .sum()
    };
    let n = 4000;
    let (mut m1, mut m2, mut m3) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let tau = (i as f64 + 0.5) / n as f64;
        m1 += derivative(tau, 1).powi(2);
        m2 += derivative(tau, 2).powi(2);
        m3 += derivative(tau, 3).powi(2);
    }
    [m1 / m2, m1 / m3, m2 / m3]
}

/// Torque noise of the seed 003 subject (N m, s.d.).
const PLANAR_TORQUE_NOISE_NM: f64 = 0.15;

fn seed003(seed: u64) -> Result<Reproduction> {
    use limpid_ident::planar::{prepare_planar, window_sweep, PlanarPrepare};
    use limpid_lab::design::PlanarDesign;
    use limpid_lab::planar::{simulate_planar, Cuff, Reflex};
    let design = PlanarDesign::seed003();
    let mut arm = design.nominal_subject();
    // seed 003 §IV-A: the robot holds the forearm in a plastic cuff; the soft
    // tissue in between is a spring and damper in series (values: ours)
    let links = limpid_core::arm::Arm {
        l1: design.link_lengths_m[0],
        l2: design.link_lengths_m[1],
        shoulder: [0.0, 0.0],
    };
    arm.cuff = Some(Cuff::seed003(&links, arm.q0));
    // the spinal reflex of seed 003 §I (latency 70-110 ms): K and D rise after it
    arm.reflex = Some(Reflex {
        latency_s: 0.09,
        stiffness_gain: 0.3,
        damping_gain: 0.3,
    });
    // the subject holds 5 N distal (seed 003 §IV): force fluctuation of about
    // 0.5 N at the hand, 0.15 N m at the joints, white (sensor and fast
    // fluctuation) ...
    let mut rec = simulate_planar(
        &arm,
        &design.simulation(),
        PLANAR_TORQUE_NOISE_NM,
        2e-5,
        seed,
    )?;
    // ... which is slow (below 3 Hz, the physiological tremor-free band of
    // force fluctuation): within a window it acts as a drifting offset
    limpid_lab::planar::add_torque_fluctuation(
        &mut rec,
        PLANAR_TORQUE_NOISE_NM,
        3.0,
        seed ^ 0x5eed,
    )?;
    let data = prepare_planar(
        &rec,
        &PlanarPrepare::new(design.link_lengths_m[0], design.link_lengths_m[1]),
    )?;
    let longest = (data.max_window_s() * 1e3).floor().min(450.0);
    const SHORTEST_MS: f64 = 50.0;
    let full = window_sweep(&data, SHORTEST_MS, longest, 10.0, None)?;
    let known = window_sweep(&data, SHORTEST_MS, longest, 10.0, Some(arm.xi))?;
    let mut out = Reproduction::default();
    let ms = "ms";
    // seed 003 §V's "required" window: K positive definite and K, D quasi-symmetric from here on
    let both = |s: &limpid_ident::planar::Sweep| match (
        s.min_positive_definite_ms,
        s.min_quasi_symmetric_ms,
    ) {
        (Some(a), Some(b)) => Some(a.max(b)),
        _ => None,
    };
    for (item, paper, value) in [
        (
            "shortest T_obs with K positive definite",
            Some(320.0),
            full.min_positive_definite_ms,
        ),
        (
            "shortest T_obs with K and D quasi-symmetric",
            Some(370.0),
            full.min_quasi_symmetric_ms,
        ),
        (
            "shortest T_obs with every parameter quasi-constant",
            Some(400.0),
            full.min_quasi_constant_ms,
        ),
        (
            "shortest T_obs with K positive definite and K, D quasi-symmetric, full model",
            Some(370.0),
            both(&full),
        ),
        (
            "shortest T_obs with K positive definite and K, D quasi-symmetric, inertia known (reduced model eq. 23)",
            Some(300.0),
            both(&known),
        ),
        (
            "shortest trusted T_obs (limpid's criterion), full model",
            None,
            full.shortest_trusted_ms,
        ),
        (
            "shortest trusted T_obs (limpid's criterion), inertia known",
            None,
            known.shortest_trusted_ms,
        ),
    ] {
        out.rows.push(row("003", item.into(), paper, value, ms).with_note(match value {
            None => format!("no window up to {longest} ms meets it"),
            Some(_) if item.starts_with("shortest trusted") => {
                "not the paper's criterion: 2 SE of K within 10 %, of D within 25 %, and no change of K or D within the window".into()
            }
            Some(v) if item == "shortest T_obs with K and D quasi-symmetric" && v <= SHORTEST_MS => {
                "from the shortest window scanned: the virtual cuff is symmetric (J^T k J); the paper's asymmetry at short windows has another source".into()
            }
            Some(_) if item.contains("quasi-symmetric, ") => {
                "the paper's 'required' window (§V: 370 ms, about 300 ms with the inertia known); both of its criteria hold from here on".into()
            }
            Some(_) => String::new(),
        }));
    }
    out.rows.push(row(
        "003",
        "change of K or D within the trials detected after onset".into(),
        None,
        full.impedance_change.as_ref().map(|c| c.onset_ms),
        ms,
    ).with_note("the cuff's fast dynamics in the first tens of ms and the virtual subject's reflex (K and D +30 % after 90 ms) are changes the rigid model does not hold through; Lakatos, Petit & van der Smagt (2011) §I: reflexes act after 25-110 ms, the paper's windows include them"));
    // Table I: quintic against the sixth-order polynomial
    let q = polynomial_ratios(&[(3, 10.0), (4, -15.0), (5, 6.0)], design.interpolation_s);
    let c6 = sextic_coefficients();
    let s = polynomial_ratios(
        &[(3, c6[0]), (4, c6[1]), (5, c6[2]), (6, c6[3])],
        design.interpolation_s,
    );
    let labels = ["C_12", "C_13", "C_23"];
    let mut closer = 0;
    for i in 0..3 {
        for (name, v) in [("fifth-order", q[i]), ("sixth-order", s[i])] {
            out.rows.push(
                row(
                    "003",
                    format!(
                        "Table I, {} of the {name} polynomial (T_k = {} ms)",
                        labels[i],
                        design.interpolation_s * 1e3
                    ),
                    None,
                    Some(v),
                    if i == 1 { "s^4" } else { "s^2" },
                )
                .with_note("Table I's cells are garbled in the text"),
            );
        }
        if q[i].ln().abs() < s[i].ln().abs() {
            closer += 1;
        }
    }
    out.findings.push(Finding {
        seed: "003".into(),
        claim: "every C_ij of the fifth-order polynomial is closer to 1 than the sixth-order one's"
            .into(),
        holds: closer == 3,
        evidence: format!(
            "closer (in log) in {closer} of 3: quintic {}, sextic {}",
            q.map(sig).join(" / "),
            s.map(sig).join(" / ")
        ),
    });
    let order = |v: Option<f64>| v.unwrap_or(f64::INFINITY);
    let shown = |v: Option<f64>| v.map_or("none".into(), |v| format!("{v} ms"));
    out.findings.push(Finding {
        seed: "003".into(),
        claim: "the full model needs an observation window of a few hundred ms (~370 ms) to meet the paper's criteria (K positive definite, K and D quasi-symmetric); known inertia shortens it".into(),
        holds: both(&full).is_some_and(|v| v >= 150.0)
            && order(both(&known)) <= order(both(&full)),
        evidence: format!(
            "from {} (full model), {} (inertia known), with a cuff of {} N/m, {} N s/m between robot and arm; limpid's stricter trust (precision, no change of K or D within the window): full model {}, inertia known {}",
            shown(both(&full)),
            shown(both(&known)),
            limpid_lab::planar::SEED003_CUFF.0,
            limpid_lab::planar::SEED003_CUFF.1,
            shown(full.shortest_trusted_ms),
            shown(known.shortest_trusted_ms)
        ),
    });
    Ok(out)
}

/// Trials per spring array and controller (seed 004 §III-F).
const SEED004_TRIALS: usize = 6;

/// Half-width (Hz) of the band about the spring array's antiresonance that
/// [`CoherenceProfile::min_outside`] leaves out: a few Welch bins of Table III
/// (0.041 Hz) beyond the Hann main lobe (±0.08 Hz).
const ANTIRESONANCE_HALF_WIDTH_HZ: f64 = 0.2;

/// Where in the band the smallest multiple coherence (over all outputs) lies.
struct CoherenceProfile {
    /// Share of the band's frequencies with every multiple coherence ≥ 0.95.
    share_above: f64,
    /// Frequency (Hz) of the smallest.
    at_hz: f64,
    /// Smallest outside ±[`ANTIRESONANCE_HALF_WIDTH_HZ`] of `antiresonance_hz`.
    min_outside: f64,
}

fn coherence_profile(
    est: &limpid_ident::stochastic::StochasticEstimate,
    band: (f64, f64),
    antiresonance_hz: f64,
) -> CoherenceProfile {
    let (mut inside, mut above, mut min, mut at_hz, mut min_outside) =
        (0usize, 0usize, f64::INFINITY, f64::NAN, f64::INFINITY);
    for (k, &f) in est.frequencies.iter().enumerate() {
        if f < band.0 || f > band.1 {
            continue;
        }
        let c = est
            .coherence
            .multiple
            .iter()
            .map(|m| m[k])
            .fold(f64::INFINITY, f64::min);
        inside += 1;
        if c >= 0.95 {
            above += 1;
        }
        if c < min {
            (min, at_hz) = (c, f);
        }
        if (f - antiresonance_hz).abs() > ANTIRESONANCE_HALF_WIDTH_HZ {
            min_outside = min_outside.min(c);
        }
    }
    CoherenceProfile {
        share_above: above as f64 / inside.max(1) as f64,
        at_hz,
        min_outside,
    }
}

fn seed004(seed: u64) -> Result<Reproduction> {
    use limpid_dsp::spectral::{Welch, Window};
    use limpid_ident::stochastic::{
        accuracy, estimate_stochastic_pooled, ExpectedModel, StochasticParams,
    };
    use limpid_lab::imbic::{simulate_robot_rig, Controller, RobotDynamics};
    use limpid_lab::rig::{RigExperiment, Springs, SA1, SA2};
    use std::f64::consts::TAU;
    let (sa1, sa2): (Springs, Springs) = (SA1, SA2);
    let welch = Welch {
        nperseg: 24576,
        noverlap: Some(18432),
        window: Window::Hann,
        ..Welch::new(1000.0)
    };
    let band = (
        limpid_ident::request::DEFAULT_BAND_HZ[0],
        limpid_ident::request::DEFAULT_BAND_HZ[1],
    );
    let cases: Vec<(&str, &Springs, &str, Controller)> = vec![
        ("sa1", &sa1, "IMBIC", Controller::imbic_seed004()),
        ("sa1", &sa1, "PD", Controller::pd_seed004()),
        ("sa2", &sa2, "IMBIC", Controller::imbic_seed004()),
        ("sa2", &sa2, "PD", Controller::pd_seed004()),
    ];
    // seed 004 §III-F: six trials per configuration, their estimates averaged
    // (limpid pools the trials' Welch segments: the spectra are averaged)
    let recordings = cases
        .par_iter()
        .flat_map(|case| (0..SEED004_TRIALS).into_par_iter().map(move |t| (case, t)))
        .map(|((_, springs, _, ctrl), t)| {
            let rig = RigExperiment::spring_array(springs);
            simulate_robot_rig(
                &rig,
                &RobotDynamics::seed004(),
                ctrl,
                [1e-5, 1e-4],
                seed.wrapping_mul(100) + t as u64,
            )
        })
        .collect::<Result<Vec<_>>>()?;
    let results = cases
        .par_iter()
        .zip(recordings.par_chunks(SEED004_TRIALS))
        .map(|((name, springs, ctrl_name, _), recs)| {
            let rig = RigExperiment::spring_array(springs);
            let est = estimate_stochastic_pooled(
                recs,
                &StochasticParams {
                    welch: Some(welch.clone()),
                    band_hz: band,
                },
            )?;
            let expected = ExpectedModel {
                inertia: Matrix::from(rig.inertia),
                damping: Matrix::from(rig.damping),
                stiffness: Matrix::from(rig.stiffness),
            };
            let acc = accuracy(&est, &expected, band)?;
            Ok((*name, *ctrl_name, rig, est, acc))
        })
        .collect::<Result<Vec<_>>>()?;
    let mut out = Reproduction::default();
    out.rows.push(
        row(
            "004",
            "Table III, minimum resolvable frequency f_r = fs / N_FFT".into(),
            Some(0.041),
            Some(1000.0 / welch.nperseg as f64),
            "Hz",
        )
        .with_note("N_FFT = N_WND = 24576, N_OVL = 18432, Hann, 50 s at 1 kHz"),
    );
    for link in ["a_1", "a_2", "d_3"] {
        out.rows.push(
            row(
                "004",
                format!("Table I (D-H, Craig's notation), {link} of the PUMA-type robot"),
                None,
                None,
                "m",
            )
            .with_note("the table names the length but gives no value, and its third row reads alpha_2 = 90 deg + theta_3 with theta_3 = 0: the geometry cannot be rebuilt; the virtual robot is a 3-joint vertical-plane chain (0.35, 0.35, 0.10 m) with the paper's M-bar_phi"),
        );
    }
    let coords = ["x", "z", "theta"];
    let mut profiles = Vec::new();
    for (name, ctrl, rig, est, acc) in &results {
        if *ctrl == "IMBIC" {
            for (i, ci) in coords.iter().enumerate() {
                out.rows.push(
                    row(
                        "004",
                        format!("K_{name}, {ci}{ci} (spring array, Table II springs)"),
                        None,
                        Some(est.stiffness[(i, i)]),
                        if i == 2 { "N m/rad" } else { "N/m" },
                    )
                    .with_note(format!(
                        "true {:.4}; the paper prints K_sa only through its springs",
                        rig.stiffness[(i, i)]
                    )),
                );
            }
        }
        out.rows.push(
            row(
                "004",
                format!("phi_T, {name}, {ctrl}"),
                None,
                Some(acc.phi_t),
                "SI",
            )
            .with_note("Fig. 11 only"),
        );
        out.rows.push(
            row(
                "004",
                format!("smallest multiple coherence 0.5-10 Hz, {name}, {ctrl}"),
                if *ctrl == "IMBIC" { Some(0.95) } else { None },
                Some(est.criteria.min_multiple_coherence),
                "",
            )
            .with_note("paper: 'exceed 0.95 throughout the frequency range of interest' (IMBIC)"),
        );
        let antiresonance = (rig.stiffness[(0, 0)] / rig.inertia[(0, 0)]).sqrt() / TAU;
        let profile = coherence_profile(est, band, antiresonance);
        out.rows.push(
            row(
                "004",
                format!("share of 0.5-10 Hz with multiple coherence >= 0.95, {name}, {ctrl}"),
                None,
                Some(100.0 * profile.share_above),
                "%",
            )
            .with_note(format!("smallest at {:.2} Hz; the spring array's antiresonance sqrt(K_xx/M)/2pi = {antiresonance:.2} Hz", profile.at_hz)),
        );
        out.rows.push(
            row(
                "004",
                format!("smallest multiple coherence 0.5-10 Hz outside {antiresonance:.2} ± {ANTIRESONANCE_HALF_WIDTH_HZ} Hz, {name}, {ctrl}"),
                None,
                Some(profile.min_outside),
                "",
            )
            .with_note("at the antiresonance the force on the handle nearly vanishes (damping ratio 0.01) and the notch is narrower than Table III's Welch resolution"),
        );
        profiles.push((*name, *ctrl, profile, antiresonance));
        out.rows.push(row(
            "004",
            format!("input coherence (largest) 0.5-10 Hz, {name}, {ctrl}"),
            None,
            Some(est.criteria.max_input_coherence),
            "",
        ).with_note("Park & Chang (2011) asks < 0.6; with Table III's long segments (30 in six trials) independent inputs show high coherence at some of the 400 frequencies"));
    }
    let get = |n: &str, c: &str| results.iter().find(|r| r.0 == n && r.1 == c);
    let k_error = |r: &(
        &str,
        &str,
        RigExperiment,
        limpid_ident::stochastic::StochasticEstimate,
        limpid_ident::stochastic::Accuracy,
    )| {
        limpid_analysis::demo::relative_error_percent(&r.3.stiffness, &Matrix::from(r.2.stiffness))
    };
    for (name, ctrl) in [
        ("sa1", "IMBIC"),
        ("sa1", "PD"),
        ("sa2", "IMBIC"),
        ("sa2", "PD"),
    ] {
        if let Some(r) = get(name, ctrl) {
            out.rows.push(
                row(
                    "004",
                    format!("K error vs the spring array (relative Frobenius), {name}, {ctrl}"),
                    None,
                    Some(k_error(r)),
                    "%",
                )
                .with_note("not in the paper"),
            );
        }
    }
    let mut higher = Vec::new();
    let mut above = Vec::new();
    for name in ["sa1", "sa2"] {
        if let (Some(i), Some(p)) = (get(name, "IMBIC"), get(name, "PD")) {
            let (ci, cp) = (
                i.3.criteria.min_multiple_coherence,
                p.3.criteria.min_multiple_coherence,
            );
            higher.push((name, ci, cp));
            above.push((name, ci));
        }
    }
    out.findings.push(Finding {
        seed: "004".into(),
        claim: "IMBIC gives a higher multiple coherence than a PD-controlled robot (the reason Park & Chang (2011) uses it)".into(),
        holds: !higher.is_empty() && higher.iter().all(|(_, i, p)| i > p),
        evidence: higher
            .iter()
            .map(|(n, i, p)| format!("{n}: smallest multiple coherence IMBIC {i:.3}, PD {p:.3}"))
            .collect::<Vec<_>>()
            .join("; "),
    });
    out.findings.push(Finding {
        seed: "004".into(),
        claim: "under IMBIC the multiple coherence exceeds 0.95 throughout 0-10 Hz".into(),
        holds: !above.is_empty() && above.iter().all(|(_, c)| *c > 0.95),
        evidence: format!(
            "{}; six 50 s trials pooled: 30 segments of Table III's settings",
            above
                .iter()
                .map(|(n, c)| {
                    let p = profiles.iter().find(|p| p.0 == *n && p.1 == "IMBIC");
                    match p {
                        Some((_, _, p, fa)) => format!(
                            "{n}: {c:.3} at {:.2} Hz (the rig's antiresonance {fa:.2} Hz), >= 0.95 at {:.0} % of the band, smallest {:.3} outside ±{ANTIRESONANCE_HALF_WIDTH_HZ} Hz of it",
                            p.at_hz,
                            100.0 * p.share_above,
                            p.min_outside
                        ),
                        None => format!("{n}: {c:.3}"),
                    }
                })
                .collect::<Vec<_>>()
                .join(", ")
        ),
    });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sextic_meets_its_boundary_conditions() {
        let c = sextic_coefficients();
        let at1: f64 = c.iter().sum();
        assert!((at1 - 1.0).abs() < 1e-12);
        let d3: f64 = 6.0 * c[0] + 24.0 * c[1] + 60.0 * c[2] + 120.0 * c[3];
        assert!(d3.abs() < 1e-9);
    }

    #[test]
    fn polynomial_ratios_match_the_profile_module_for_the_quintic() {
        let ours = polynomial_ratios(&[(3, 10.0), (4, -15.0), (5, 6.0)], 0.2);
        let lab = limpid_lab::protocol::conditioning_ratios(Profile::Quintic, 0.2, 1.0);
        for i in 0..3 {
            assert!((ours[i] / lab[i] - 1.0).abs() < 1e-3, "{ours:?} vs {lab:?}");
        }
    }
}
