//! `limpid live` end to end (issue 9): a replayed co-contraction recording,
//! the page in headless Chromium at each phase, and garbage on the UDP port.

use crate::common::*;
use crate::live_common::*;
use std::net::UdpSocket;
use std::path::Path;
use std::time::{Duration, Instant};

/// The limpid-made ex_config4 co-contraction example, with `suffix`.
fn example(suffix: &str) -> String {
    examples("cocontraction")
        .join(format!("ex_config4{suffix}"))
        .to_str()
        .unwrap()
        .to_string()
}

fn chromium_dom(url: &str, shot: Option<&Path>) -> (String, String) {
    // long enough for the WebSocket's first messages, shorter than the page's 0.5 s stall alarm
    let mut extra = vec!["--virtual-time-budget=400".to_string()];
    match shot {
        Some(p) => extra.extend([
            format!("--screenshot={}", p.display()),
            "--window-size=900,700".into(),
        ]),
        None => extra.push("--dump-dom".into()),
    }
    chromium(url, &extra)
}

/// The co-contraction index the page shows; none while it shows "n/a"
/// (before its first update).
fn shown_level(dom: &str) -> Option<f64> {
    let after = dom
        .split("id=\"level\">")
        .nth(1)
        .expect("the level element");
    let text = after.split('<').next().unwrap();
    (text != "n/a").then(|| {
        text.parse()
            .unwrap_or_else(|_| panic!("the page shows the index as {text:?}"))
    })
}

#[test]
fn replay_shows_each_phase_level_in_the_browser() {
    // the offline index per level (zero-phase envelope) is what the page's
    // causal one must come near
    let offline = json(&[
        "estimate",
        "cocontraction",
        &example(".csv"),
        "--mvc",
        &example(".mvc.csv"),
        "--json",
    ]);
    let levels: Vec<(f64, f64)> = offline["levels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| {
            (
                l["level"].as_f64().unwrap(),
                l["cocontraction_index"].as_f64().unwrap(),
            )
        })
        .collect();
    // real time: a browser that takes seconds to start on a loaded machine
    // (the tests run on twice as many threads as cores) still reads each
    // 13.5 s phase in its middle
    let speed = 1.0;
    let live = start(&[
        "--mvc",
        &example(".mvc.csv"),
        "--replay",
        &example(".csv"),
        "--speed",
        "1",
        "--target",
        "0.5",
    ]);
    // the recording holds 4 phases of 13.5 s (levels 0, 0.5, 0.75, 1); look at
    // each one's middle part, timed by the replay's own clock (the last sample time)
    let phase_s = 13.5;
    let started = Instant::now();
    for (k, (level, expected)) in levels.iter().enumerate() {
        let mut readings = Vec::new();
        let last_t = || {
            get_json(&live.http, "/state")["last_t"]
                .as_f64()
                .unwrap_or(0.0)
        };
        for q in [0.3, 0.4, 0.5, 0.6] {
            let due = (k as f64 + q) * phase_s;
            while last_t() < due {
                std::thread::sleep(Duration::from_millis(20));
            }
            let (dom, log) = chromium_dom(&live.page, None);
            // a browser slow to start on a loaded machine reads the page after
            // the replay has entered the next phase: that reading is not this level's
            let read_at = last_t();
            if read_at > (k as f64 + 0.9) * phase_s {
                eprintln!("level {level}: page read at {read_at:.1} s, past the phase; skipped");
                continue;
            }
            for line in log.lines() {
                assert!(
                    !line.contains("CONSOLE") && !line.contains("Uncaught"),
                    "console: {line}"
                );
            }
            assert!(
                dom.contains("streaming"),
                "stream health shown: {}",
                dom.split("id=\"health\"")
                    .nth(1)
                    .unwrap_or("")
                    .chars()
                    .take(80)
                    .collect::<String>()
            );
            // a browser that reads the page before its first update (a
            // loaded machine) finds "n/a": not a reading of this level
            let Some(shown) = shown_level(&dom) else {
                eprintln!("level {level}: page not updated yet at {read_at:.1} s; skipped");
                continue;
            };
            readings.push(shown);
        }
        assert!(
            readings.len() >= 2,
            "level {level}: the page could be read within the phase only {} times (machine too loaded?)",
            readings.len()
        );
        readings.sort_by(f64::total_cmp);
        let median = readings[readings.len() / 2];
        eprintln!("level {level}: page shows {readings:?}, offline index {expected:.3}");
        assert!(
            (median - expected).abs() < 0.05,
            "level {level}: page {median}, offline {expected}"
        );
    }
    let shot = std::env::temp_dir().join("limpid-live.png");
    chromium_dom(&live.page, Some(&shot));
    let png = std::fs::read(&shot).expect("screenshot");
    assert!(png.starts_with(b"\x89PNG") && png.len() > 5_000);
    // after the replay ends the stream stalls, and the page says so within 0.5 s
    // (wait for the last sample rather than for the clock: a busy machine may
    // replay late)
    let deadline = started + Duration::from_secs_f64(4.0 * phase_s / speed + 60.0);
    while get_json(&live.http, "/state")["received"] != 54_000 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(700));
    let s = get_json(&live.http, "/state");
    assert_eq!(s["stalled"], true, "{s}");
    assert_eq!(s["lost"], 0);
    assert_eq!(s["received"], 54_000);
}

#[test]
fn garbage_is_counted_and_dropped_and_the_stream_goes_on() {
    let live = start(&["--channels", "emg_a,emg_b", "--rate", "1000"]);
    let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
    let good = |seq: u64| {
        limpid_live::wire::encode(&limpid_live::wire::Sample {
            seq,
            t: seq as f64 * 1e-3,
            sent_unix_ns: 0,
            emg: vec![1e-4, -2e-4],
            kinematics: None,
        })
    };
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut garbage = 0;
    for seq in 0..2000u64 {
        sock.send_to(&good(seq), &live.udp).unwrap();
        if seq % 10 == 0 {
            // random bytes of random length, and truncated good datagrams
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let len = (state % 120) as usize;
            let bytes: Vec<u8> = (0..len).map(|i| (state >> (i % 56)) as u8).collect();
            sock.send_to(&bytes, &live.udp).unwrap();
            let g = good(seq);
            sock.send_to(&g[..g.len() - 1 - (seq as usize % 20)], &live.udp)
                .unwrap();
            garbage += 2;
        }
        if seq % 200 == 0 {
            std::thread::sleep(Duration::from_millis(5));
        }
    }
    std::thread::sleep(Duration::from_millis(300));
    let s = get_json(&live.http, "/state");
    assert_eq!(s["received"], 2000, "{s}");
    assert_eq!(s["malformed"], garbage, "{s}");
    assert_eq!(s["lost"], 0, "{s}");
    assert_eq!(s["stalled"], false);
    // no MVC was given: the index waits for a capture, which the page's buttons drive
    assert!(s["index"].is_null());
}

#[test]
fn an_lsl_stream_that_cannot_be_read_is_a_one_line_error() {
    // without the `lsl` feature: how to get it; with it: no such stream
    let out = limpid(&[
        "live",
        "--listen",
        "127.0.0.1:0",
        "--udp",
        "127.0.0.1:0",
        "--channels",
        "emg_a",
        "--rate",
        "1000",
        "--lsl",
        "limpid-no-such-stream",
    ]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("--lsl")
            && (out.stderr.contains("--features lsl") || out.stderr.contains("no stream named")),
        "{}",
        out.stderr
    );
    assert_eq!(out.stderr.trim().lines().count(), 1, "{}", out.stderr);
}

/// Issue 19 end to end: a 4x replay of ex_config4; `/state` shows each
/// level's stiffness within 10 % (relative Frobenius) of the offline estimate
/// of that level 3 s of data after the level starts, a reason instead of a
/// number before, and the earlier levels in its history.
#[test]
fn replay_at_4x_shows_each_levels_stiffness_within_10_percent_of_offline() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_limpid"))
        .args([
            "estimate",
            "cocontraction",
            &example(".csv"),
            "--mvc",
            &example(".mvc.csv"),
            "--json",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let offline: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let k_of = |v: &serde_json::Value| -> Vec<f64> {
        v.as_array()
            .unwrap()
            .iter()
            .flat_map(|r| r.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()))
            .collect()
    };
    let rel = |a: &[f64], b: &[f64]| {
        let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
        (d / b.iter().map(|y| y * y).sum::<f64>()).sqrt()
    };
    let levels: Vec<Vec<f64>> = offline["levels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| k_of(&l["stiffness"]))
        .collect();
    assert_eq!(levels.len(), 4);
    let live = start(&[
        "--mvc",
        &example(".mvc.csv"),
        "--replay",
        &example(".csv"),
        "--speed",
        "4",
    ]);
    let phase_s = 13.5;
    let mut saw_waiting = false;
    for (k, offline_k) in levels.iter().enumerate() {
        let due = k as f64 * phase_s + 3.0;
        let state = loop {
            let s = get_json(&live.http, "/state");
            let t = s["last_t"].as_f64().unwrap_or(0.0);
            let o = &s["online"];
            if t > k as f64 * phase_s + 0.5 && t < due && o["stiffness"].is_null() {
                assert!(o["status"].as_str().unwrap().starts_with("waiting"), "{o}");
                saw_waiting = true;
            }
            if t >= due {
                break s;
            }
            std::thread::sleep(Duration::from_millis(10));
        };
        let o = &state["online"];
        assert_eq!(o["status"], "estimating", "level {k}: {o}");
        let err = rel(&k_of(&o["stiffness"]), offline_k);
        eprintln!(
            "level {k}: 3 s in (t = {}), online K within {:.1} % of offline",
            state["last_t"],
            100.0 * err
        );
        assert!(err < 0.10, "level {k}: {:.1} %", 100.0 * err);
        assert_eq!(o["history"].as_array().unwrap().len(), k, "{o}");
        assert!(o["vaf"]
            .as_array()
            .unwrap()
            .iter()
            .all(|v| v.is_null() || (0.0..=100.0).contains(&v.as_f64().unwrap())));
    }
    assert!(saw_waiting, "the page said why before it had a number");
    let (dom, log) = chromium_dom(&live.page, None);
    assert!(!log.contains("Uncaught"), "{log}");
    assert!(
        dom.contains("K (N/m)") && dom.contains("earlier level"),
        "table and history on the page"
    );
}

/// Issue 36: an upgrade to the page's WebSocket with a key that is not 16
/// bytes of base64 (RFC 6455 section 4.1) is refused; a valid one is served.
#[test]
fn websocket_upgrades_need_a_valid_key() {
    use std::io::{Read, Write};
    let live = start(&["--channels", "emg_a", "--rate", "1000"]);
    let status = |key: &str| {
        let mut s = std::net::TcpStream::connect(&live.http).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        write!(
            s,
            "GET /ws HTTP/1.1\r\nHost: {}\r\nConnection: Upgrade\r\nUpgrade: websocket\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Key: {key}\r\n\r\n",
            live.http
        )
        .unwrap();
        let mut head = [0u8; 12];
        s.read_exact(&mut head).unwrap();
        String::from_utf8_lossy(&head[9..12]).to_string()
    };
    assert_eq!(status("dGhlIHNhbXBsZSBub25jZQ=="), "101");
    for bad in ["x", "dGhlIHNhbXBsZSBub25jZR==", "!!!!!!!!!!!!!!!!!!!!!!=="] {
        assert_eq!(status(bad), "400", "{bad}");
    }
}

/// Issue 36: the live page's numbers are checked before it starts (a NaN
/// target or a negative tolerance used to start a page that drew nothing).
#[test]
fn live_settings_out_of_range_are_one_line_errors() {
    let replay = examples("cocontraction").join("ex_config4.csv");
    let replay = replay.to_str().unwrap();
    for (extra, says) in [
        (
            vec!["--rate", "1e308"],
            "invalid sample rate: expected a sample rate above 0 and up to 1e6 Hz",
        ),
        (
            vec!["--rate", "1000", "--target", "nan"],
            "invalid target level",
        ),
        (
            vec!["--rate", "1000", "--target", "5"],
            "invalid target level",
        ),
        (
            vec!["--rate", "1000", "--tolerance", "-1"],
            "invalid target tolerance",
        ),
        (
            vec!["--replay", replay, "--speed", "1e308"],
            "invalid replay speed",
        ),
        (
            vec!["--replay", replay, "--speed", "0"],
            "invalid replay speed",
        ),
    ] {
        let mut args = vec![
            "live",
            "--listen",
            "127.0.0.1:0",
            "--udp",
            "127.0.0.1:0",
            "--channels",
            "emg_a",
        ];
        args.extend(extra.iter().copied());
        let out = limpid(&args);
        assert_eq!(out.code, 2, "{extra:?}: {}", out.stdout);
        assert!(
            out.stderr.starts_with(&format!("limpid: {says}")),
            "{extra:?}: {}",
            out.stderr
        );
        assert_eq!(out.stderr.lines().count(), 1, "{}", out.stderr);
    }
}
