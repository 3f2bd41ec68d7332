use limpid_ident::{fit_linear, prepare, LinearParams, PrepareParams};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rec = limpid_io::read_recording(&args[1]).unwrap();
    let cutoff: Option<f64> = args.get(2).map(|s| s.parse().unwrap());
    let p = PrepareParams {
        cutoff_hz: cutoff,
        ..Default::default()
    };
    let prepared = prepare(&rec, &p).unwrap();
    let e = fit_linear(&prepared, &LinearParams::default()).unwrap();
    for (name, m, s) in [
        ("M", &e.inertia, &e.standard_errors.inertia),
        ("B", &e.damping, &e.standard_errors.damping),
        ("K", &e.stiffness, &e.standard_errors.stiffness),
    ] {
        println!("{name}:");
        for i in 0..m.len() {
            println!(
                "  {}",
                (0..m.len())
                    .map(|j| format!("{:9.4} ±{:7.4}", m[i][j], s[i][j]))
                    .collect::<Vec<_>>()
                    .join("  ")
            );
        }
    }
    println!(
        "eq {:?} vaf {:?} cond {:.1} windows {} rest {:?}",
        e.equilibrium,
        e.fit.vaf,
        e.condition_number,
        prepared.windows.len(),
        prepared
            .windows
            .iter()
            .take(5)
            .map(|w| w.rest_samples)
            .collect::<Vec<_>>()
    );
}
