//! How often the live display's ±2 SE covers the true stiffness: simulated
//! co-contraction sessions (seed 001) streamed sample by sample through the
//! online estimator, restarted per level; every estimate after a completed
//! perturbation is compared with the level's true K (issue 37):
//! `cargo run --profile ci -p limpid-app --example live_coverage -- 20 1`
use limpid_app::live_check::live_stiffness_checks;
use limpid_lab::NoiseModel;

fn main() {
    let mut args = std::env::args().skip(1);
    let n: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(20);
    let seed: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1);
    for (name, noise) in noises() {
        let (mut within, mut total, mut zmax) = (0usize, 0usize, 0.0f64);
        let (mut se_rel, mut err_rel, mut signed) = (Vec::new(), Vec::new(), 0.0f64);
        for s in 0..n {
            for c in live_stiffness_checks(&noise, seed * 1000 + s).expect("simulated") {
                within += usize::from(c.z.abs() <= 2.0);
                total += 1;
                zmax = zmax.max(c.z.abs());
                se_rel.push(c.se_rel);
                signed += c.error_rel;
                err_rel.push(c.error_rel.abs());
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
