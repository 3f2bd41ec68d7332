use limpid_ident::{fit_linear, prepare, LinearParams, PrepareParams};
use limpid_lab::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let noisy = args.get(1).map(|s| s == "noisy").unwrap_or(false);
    let cutoff: Option<f64> = args.get(2).map(|s| s.parse().unwrap());
    for prof in [Profile::Cubic, Profile::Trapezoid, Profile::Sinusoid] {
        let p = &seed000_subject1()[3];
        let proto = CentreOut::seed000(prof);
        let mut noise = if noisy {
            NoiseModel::default()
        } else {
            NoiseModel::none()
        };
        if let Some(which) = args.get(3) {
            let mut n = NoiseModel::none();
            match which.as_str() {
                "pos" => n.position_std_m = 2e-5,
                "off" => n.offset_per_trial_std_n = 3.0,
                "white" => n.white_std_n = 0.1,
                "drift" => n.drift_std_n = 0.05,
                _ => {}
            }
            noise = n;
        }
        let rec = simulate_centre_out(p, &proto, &noise, 7).unwrap();
        let prepared = prepare(
            &rec,
            &PrepareParams {
                cutoff_hz: cutoff,
                ..Default::default()
            },
        )
        .unwrap();
        let e = fit_linear(&prepared, &LinearParams::default()).unwrap();
        let err = |est: &Vec<Vec<f64>>, t: &nalgebra::Matrix3<f64>| {
            let mut n = 0.0;
            let mut d = 0.0;
            for i in 0..3 {
                for j in 0..3 {
                    n += (est[i][j] - t[(i, j)]).powi(2);
                    d += t[(i, j)].powi(2);
                }
            }
            (n / d).sqrt()
        };
        println!(
            "{prof:?}: K {:.5} B {:.5} M {:.5} rest {:?}",
            err(&e.stiffness, &p.stiffness),
            err(&e.damping, &p.damping),
            err(&e.inertia, &p.inertia),
            prepared
                .windows
                .iter()
                .take(4)
                .map(|w| w.rest_samples)
                .collect::<Vec<_>>()
        );
    }
}
