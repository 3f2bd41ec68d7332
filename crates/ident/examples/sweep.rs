use limpid_ident::{fit_linear, prepare, Derivative, LinearParams, PrepareParams};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rec = limpid_io::read_recording(&args[1]).unwrap();
    for deriv in [Derivative::Central, Derivative::Savgol] {
        for cutoff in [5.0, 10.0, 20.0, 30.0, 50.0] {
            let p = PrepareParams {
                cutoff_hz: Some(cutoff),
                derivative: deriv,
                level: args.get(2).map(|l| l.parse().unwrap()),
                ..Default::default()
            };
            let prepared = prepare(&rec, &p).unwrap();
            let e = fit_linear(&prepared, &LinearParams::default()).unwrap();
            let d = |m: &Vec<Vec<f64>>| {
                (0..m.len())
                    .map(|i| format!("{:.4}", m[i][i]))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            println!("{deriv:?} fc={cutoff}: M [{}] ±[{}] B [{}] K [{}] vaf {:?} infl {:?} windows {} cont {}", d(&e.inertia), d(&e.standard_errors.inertia), d(&e.damping), d(&e.stiffness), e.fit.vaf.iter().map(|v| format!("{v:.1}")).collect::<Vec<_>>(), e.variance_inflation.iter().map(|v| format!("{v:.1}")).collect::<Vec<_>>(), prepared.windows.len(), prepared.continuous);
        }
    }
}
