//! Lab Streaming Layer inlet on loopback (issue 9; cargo feature `lsl`): an
//! outlet in this process publishes EMG and kinematics, `Session` reads it.

#![cfg(feature = "lsl")]

use std::time::{Duration, Instant};

use limpid_live::server::{Config, Session};
use lsl::Pushable;

fn config(name: &str) -> Config {
    Config {
        udp: "127.0.0.1:0".parse().unwrap(),
        channels: vec!["emg_1".into(), "emg_2".into()],
        sample_rate: 1000.0,
        maxima: Some(vec![1.0, 1.0]),
        target: None,
        tolerance: 0.1,
        replay: None,
        lsl: Some(name.into()),
    }
}

#[test]
fn samples_from_an_lsl_outlet_reach_the_index() {
    let name = format!("limpid-test-{}", std::process::id());
    let info =
        lsl::StreamInfo::new(&name, "EMG", 8, 1000.0, lsl::ChannelFormat::Double64, &name).unwrap();
    let outlet = lsl::StreamOutlet::new(&info, 0, 360).unwrap();
    let session = Session::start(&config(&name)).expect("inlet opens");
    assert!(outlet.wait_for_consumers(5.0), "the inlet connected");
    let n = 2000;
    let start = Instant::now();
    for k in 0..n {
        // both channels at half their MVC maximum (rectified envelope 0.5)
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        let t = k as f64 / 1000.0;
        outlet
            .push_sample(&vec![
                0.5 * sign,
                0.5 * sign,
                0.3,
                -0.2,
                0.05 + 1e-3 * t.sin(),
                1.0,
                0.0,
                0.0,
            ])
            .unwrap();
        if k % 100 == 99 {
            std::thread::sleep(Duration::from_millis(5));
        }
    }
    let deadline = start + Duration::from_secs(10);
    while session.snapshot().received < n && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
    }
    let s = session.snapshot();
    session.stop();
    assert_eq!(s.received, n, "{s:?}");
    assert_eq!(s.malformed, 0);
    let index = s.index.expect("an index with MVC maxima");
    assert!((index - 0.5).abs() < 0.05, "index {index}");
    assert!(s.latency_p99_us.is_some());
}

#[test]
fn a_missing_stream_or_a_wrong_channel_count_is_refused() {
    let e = Session::start(&config("limpid-no-such-stream"))
        .err()
        .expect("no stream")
        .to_string();
    assert!(e.contains("no stream named"), "{e}");
    let name = format!("limpid-test-three-{}", std::process::id());
    let info =
        lsl::StreamInfo::new(&name, "EMG", 3, 1000.0, lsl::ChannelFormat::Double64, &name).unwrap();
    let _outlet = lsl::StreamOutlet::new(&info, 0, 360).unwrap();
    let e = Session::start(&config(&name))
        .err()
        .expect("3 channels")
        .to_string();
    assert!(
        e.contains("has 3 channels") && e.contains("expected 2"),
        "{e}"
    );
}
