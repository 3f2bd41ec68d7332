use limpid_ident::planar::{prepare_planar, window_sweep, PlanarPrepare};
use limpid_lab::planar::{simulate_planar, PlanarProtocol, PlanarSubject};
fn main() {
    let mut a = std::env::args().skip(1);
    let tn: f64 = a.next().and_then(|x| x.parse().ok()).unwrap_or(0.0);
    let an: f64 = a.next().and_then(|x| x.parse().ok()).unwrap_or(0.0);
    let (mut subject, protocol) = (PlanarSubject::seed003(), PlanarProtocol::seed003());
    if std::env::var("XI2").is_ok() {
        subject.xi[1] = 0.0;
    }
    if let Some(lat) = std::env::var("REFLEX")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
    {
        subject.reflex = Some(limpid_lab::planar::Reflex {
            latency_s: lat,
            stiffness_gain: 0.3,
            damping_gain: 0.3,
        });
    }
    println!("xi {:?}", subject.xi);
    let rec = simulate_planar(&subject, &protocol, tn, an, 1).unwrap();
    let mut pp = PlanarPrepare::new(0.32, 0.31);
    pp.cutoff_hz = a.next().and_then(|x| x.parse().ok());
    println!("fs {}", rec.sample_rate());
    let mut data = prepare_planar(&rec, &pp).unwrap();
    println!("noise {:?}", data.angle_noise);
    if std::env::var("NONOISE").is_ok() {
        data.angle_noise = Default::default();
    }
    let s = window_sweep(&data, 50.0, 400.0, 10.0, None).unwrap();
    println!("truth K {:?}", subject.stiffness);
    for r in &s.rows {
        println!(
            "{} K {:?} trusted {} {:?}",
            r.observation_window_ms,
            r.estimate.stiffness.0.as_slice(),
            r.trusted,
            r.reasons
        );
    }
    println!("{:?}", s.impedance_change);
}
