//! Writes the fuzzer's seed corpus (`corpus/seeds`): small valid inputs of
//! every kind, so that mutations reach past the readers into the estimators.
//! `cargo run --release -p limpid-fuzz --example make_seeds`

use std::path::Path;

use limpid_core::Recording;

/// A deterministic pseudo-random stream in [-1, 1).
struct Noise(u64);
impl Noise {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// Trials of a cubic step from rest in `dims` coordinates through M x'' + B x' + K x = f.
fn trials(
    names: &[&str],
    forces: &[&str],
    extra: &[(&str, f64)],
    fs: f64,
    n_trials: usize,
    emg: usize,
) -> Recording {
    let d = names.len();
    let (rest, motion, hold) = (10usize, 30usize, 20usize);
    let per = rest + motion + hold;
    let mut noise = Noise(0x9e37_79b9_7f4a_7c15);
    let k = [800.0, 500.0, 300.0];
    let b = [12.0, 9.0, 6.0];
    let m = [1.5, 1.2, 1.0];
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); 1 + 2 * d + 1 + extra.len() + emg];
    for trial in 0..n_trials {
        let dir: Vec<f64> = (0..d)
            .map(|a| if (trial + a) % 2 == 0 { 1.0 } else { -0.6 })
            .collect();
        let offset: Vec<f64> = (0..d).map(|_| 2.0 * noise.next()).collect();
        for i in 0..per {
            let t = (trial * per + i) as f64 / fs;
            let tau = ((i as f64 - rest as f64) / motion as f64).clamp(0.0, 1.0);
            let dur = motion as f64 / fs;
            let inside = i >= rest && i < rest + motion;
            let s = 3.0 * tau * tau - 2.0 * tau.powi(3);
            let v = if inside {
                (6.0 * tau - 6.0 * tau * tau) / dur
            } else {
                0.0
            };
            let a = if inside {
                (6.0 - 12.0 * tau) / (dur * dur)
            } else {
                0.0
            };
            cols[0].push(t);
            for c in 0..d {
                let amp = 0.004 * dir[c];
                let x = 0.3 * f64::from(u8::from(c == 0)) + amp * s + 2e-6 * noise.next();
                cols[1 + c].push(x);
                let f = m[c % 3] * amp * a
                    + b[c % 3] * amp * v
                    + k[c % 3] * amp * s
                    + offset[c]
                    + 0.05 * noise.next();
                cols[1 + d + c].push(f);
            }
            cols[1 + 2 * d].push(trial as f64 + 1.0);
            for (j, (_, level_every)) in extra.iter().enumerate() {
                cols[2 + 2 * d + j].push(((trial as f64 / level_every).floor() * 0.5).min(1.0));
            }
            for e in 0..emg {
                let level = ((trial as f64 / 2.0).floor() * 0.5).min(1.0);
                cols[2 + 2 * d + extra.len() + e]
                    .push((0.05 + level) * noise.next() * (1.0 + e as f64));
            }
        }
    }
    let mut header: Vec<String> = vec!["t".into()];
    header.extend(names.iter().map(|s| s.to_string()));
    header.extend(forces.iter().map(|s| s.to_string()));
    header.push("trial".into());
    header.extend(extra.iter().map(|(n, _)| n.to_string()));
    header.extend((0..emg).map(|e| format!("emg_m{e}")));
    Recording::new("seed", header, cols, 2).expect("a valid seed")
}

fn stochastic() -> Recording {
    let fs = 200.0;
    let n = 1024;
    let mut noise = Noise(7);
    let names = [
        "t", "x", "z", "theta", "fx", "fz", "tauy", "ux", "uz", "utheta",
    ];
    let mut cols: Vec<Vec<f64>> = (0..names.len()).map(|_| Vec::with_capacity(n)).collect();
    let (mut u, mut x) = ([0.0f64; 3], [0.0f64; 3]);
    for i in 0..n {
        for c in 0..3 {
            u[c] = 0.8 * u[c] + 0.2 * noise.next() * [20.0, 20.0, 2.0][c];
            // a spring with a little lag: x follows u / k
            x[c] += 0.3 * (u[c] / [1000.0, 800.0, 50.0][c] - x[c]);
        }
        cols[0].push(i as f64 / fs);
        for c in 0..3 {
            cols[1 + c].push(x[c]);
            cols[4 + c].push(u[c] + 0.01 * noise.next());
            cols[7 + c].push(u[c]);
        }
    }
    Recording::new(
        "seed",
        names.iter().map(|s| s.to_string()).collect(),
        cols,
        2,
    )
    .expect("valid")
}

fn ankle() -> Recording {
    let fs = 100.0;
    let mut noise = Noise(11);
    let (mut q, mut v) = (0.0f64, 0.0f64);
    let mut cols = vec![Vec::new(); 3];
    for i in 0..600 {
        let tau = if (i / 15) % 2 == 0 { 2.0 } else { -2.0 };
        let a = (tau - 0.5 * v - 40.0 * q) / 0.02;
        v += a / fs;
        q += v / fs;
        cols[0].push(i as f64 / fs);
        cols[1].push(q + 1e-5 * noise.next());
        cols[2].push(tau + 0.01 * noise.next());
    }
    Recording::new(
        "seed",
        vec!["t".into(), "q1".into(), "tau1".into()],
        cols,
        2,
    )
    .expect("valid")
}

fn main() {
    let dir = limpid_fuzz::corpus_dir().join("seeds");
    std::fs::create_dir_all(&dir).unwrap();
    let recordings = [
        (
            "linear3d",
            trials(&["x", "y", "z"], &["fx", "fy", "fz"], &[], 200.0, 6, 0),
        ),
        (
            "endpoint2d",
            trials(&["x", "y"], &["fx", "fy"], &[], 200.0, 6, 0),
        ),
        (
            "joint2",
            trials(&["q1", "q2"], &["tau1", "tau2"], &[], 200.0, 6, 0),
        ),
        (
            "cocontraction",
            trials(
                &["x", "y", "z"],
                &["fx", "fy", "fz"],
                &[("level", 2.0)],
                200.0,
                8,
                2,
            ),
        ),
        ("stochastic", stochastic()),
        ("ankle", ankle()),
    ];
    for (name, rec) in &recordings {
        limpid_io::write_recording(rec, dir.join(format!("{name}.csv"))).unwrap();
    }
    for (name, rec) in recordings
        .iter()
        .filter(|(n, _)| ["linear3d", "stochastic", "joint2"].contains(n))
    {
        limpid_io::write_recording(rec, dir.join(format!("{name}.parquet"))).unwrap();
    }
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../io/tests/fixtures");
    for f in ["small_v5.mat", "small_v7.mat"] {
        std::fs::copy(fixtures.join(f), dir.join(f)).unwrap();
    }
    for preset in [
        "artemiadis-3d",
        "patel-cocontraction",
        "lakatos-planar",
        "park-stochastic",
    ] {
        let d = limpid_lab::design::Design::preset(preset).unwrap();
        std::fs::write(dir.join(format!("{preset}.toml")), d.to_toml()).unwrap();
    }
    // live datagrams (2 EMG channels), each prefixed by its u16 length
    let mut wire = Vec::new();
    for i in 0..50u64 {
        let s = limpid_live::wire::Sample {
            seq: i,
            t: i as f64 * 1e-3,
            sent_unix_ns: 1_700_000_000_000_000_000 + i,
            emg: vec![0.1 * (i as f64).sin(), 0.05],
            kinematics: (i % 2 == 0).then_some([0.3, 0.0, 0.01 * i as f64, 1.0, 2.0, 3.0]),
        };
        let b = limpid_live::wire::encode(&s);
        wire.extend_from_slice(&(b.len() as u16).to_le_bytes());
        wire.extend_from_slice(&b);
    }
    std::fs::write(dir.join("stream.wire"), wire).unwrap();
    println!("wrote the seeds to {}", dir.display());
}
