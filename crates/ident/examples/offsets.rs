use limpid_ident::{fit_linear, prepare, LinearParams, Offsets, PrepareParams};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rec = limpid_io::read_recording(&args[1]).unwrap();
    let level: Option<f64> = args.get(2).map(|s| s.parse().unwrap());
    for off in [Offsets::Rest, Offsets::Fit] {
        for cutoff in [10.0, 20.0, 30.0, 45.0] {
            let p = PrepareParams {
                cutoff_hz: Some(cutoff),
                offsets: off,
                level,
                ..Default::default()
            };
            let prepared = prepare(&rec, &p).unwrap();
            let e = fit_linear(&prepared, &LinearParams::default()).unwrap();
            let d = |m: &Vec<Vec<f64>>| {
                (0..m.len())
                    .map(|i| format!("{:.3}", m[i][i]))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            println!(
                "{off:?} fc={cutoff}: M [{}] B [{}] K [{}] Kse [{}]",
                d(&e.inertia),
                d(&e.damping),
                d(&e.stiffness),
                d(&e.standard_errors.stiffness)
            );
        }
    }
}
