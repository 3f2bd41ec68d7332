//! How often the live display's ±2 SE covers the true stiffness: simulated
//! co-contraction sessions (seed 001) streamed sample by sample through the
//! online estimator, restarted per level; every estimate after a completed
//! perturbation is compared with the level's true K (issue 37):
//! `cargo run --profile ci -p limpid-app --example live_coverage -- 20 1`
use limpid_ident::online::{OnlineImpedance, OnlineSettings};
use limpid_lab::cocontraction::{
    seed001_population, simulate_cocontraction, CocontractionProtocol,
};
use limpid_lab::NoiseModel;

fn main() {
    let mut args = std::env::args().skip(1);
    let n: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(20);
    let seed: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1);
    for (name, noise) in noises() {
        let (mut within, mut total, mut zmax) = (0usize, 0usize, 0.0f64);
        let (mut se_rel, mut err_rel, mut signed) = (Vec::new(), Vec::new(), 0.0f64);
        for s in 0..n {
            let seed = seed * 1000 + s;
            let population = seed001_population(1, seed);
            let (_, _, subject) = &population[(seed % population.len() as u64) as usize];
            let (rec, _) =
                simulate_cocontraction(subject, &CocontractionProtocol::seed001(), &noise, seed)
                    .expect("simulated");
            let col = |c: &str| rec.column(c).expect("column");
            let (x, y, z) = (col("x"), col("y"), col("z"));
            let (fx, fy, fz) = (col("fx"), col("fy"), col("fz"));
            let level = col("level");
            let mut est = OnlineImpedance::new(OnlineSettings::new(rec.sample_rate())).unwrap();
            let mut seen = 0usize;
            for i in 0..x.len() {
                if i > 0 && level[i] != level[i - 1] {
                    est.reset();
                    seen = 0;
                }
                est.update([x[i], y[i], z[i]], [fx[i], fy[i], fz[i]]);
                let Some(e) = est.estimate() else { continue };
                if est.perturbations as usize == seen {
                    continue;
                }
                seen = est.perturbations as usize;
                let k = subject.stiffness(level[i]);
                for o in 0..3 {
                    let zv = (e.stiffness[o][o] - k[(o, o)]) / e.stiffness_se[o][o];
                    within += usize::from(zv.abs() <= 2.0);
                    total += 1;
                    zmax = zmax.max(zv.abs());
                    se_rel.push(e.stiffness_se[o][o] / k[(o, o)].abs());
                    signed += (e.stiffness[o][o] - k[(o, o)]) / k[(o, o)].abs();
                    err_rel.push((e.stiffness[o][o] - k[(o, o)]).abs() / k[(o, o)].abs());
                }
            }
        }
        let median = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
        };
        println!(
            "{name}: {} diagonal K estimates, within ±2 SE {:.1} %, largest |z| {:.1}, median SE/K {:.2} %, median |error|/K {:.2} %, mean error/K {:+.2} %",
            total,
            100.0 * within as f64 / total.max(1) as f64,
            zmax,
            100.0 * median(&mut se_rel),
            100.0 * median(&mut err_rel),
            100.0 * signed / total.max(1) as f64
        );
    }
}

fn noises() -> Vec<(&'static str, NoiseModel)> {
    let base = NoiseModel::default();
    vec![
        ("default", base.clone()),
        (
            "noise-free",
            NoiseModel {
                position_std_m: 0.0,
                offset_per_trial_std_n: 0.0,
                white_std_n: 0.0,
                drift_std_n: 0.0,
                force_quantum_n: 0.0,
                force_noise_fraction: 0.0,
                posture_drift_std_m: 0.0,
                ..base.clone()
            },
        ),
        (
            "signal-dependent 5 %",
            NoiseModel {
                force_noise_fraction: 0.05,
                ..base.clone()
            },
        ),
        (
            "drift 0.5 N, white 0.5 N",
            NoiseModel {
                drift_std_n: 0.5,
                white_std_n: 0.5,
                ..base.clone()
            },
        ),
        (
            "posture drift 0.5 mm",
            NoiseModel {
                posture_drift_std_m: 5e-4,
                ..base.clone()
            },
        ),
        (
            "ideal servo, position noise 1e-4 m",
            NoiseModel {
                servo_bandwidth_hz: 0.0,
                position_std_m: 1e-4,
                ..base
            },
        ),
    ]
}
