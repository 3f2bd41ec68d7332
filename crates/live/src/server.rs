//! The live server: a UDP receiver thread (blocking socket with a large
//! receive buffer, one datagram per sample, processing inline), optionally a
//! Lab Streaming Layer inlet thread (cargo feature `lsl`), an optional
//! replay thread that streams a recording to that socket at real time or
//! faster, and an HTTP server (axum) with the page, `/state` (JSON),
//! `/ws` (the same JSON pushed every 33 ms), and `POST /mvc/start|stop`.

use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::State as AxState;
use axum::response::{Html, IntoResponse};
use axum::routing::{get, post};
use axum::{Json, Router};
use serde::Serialize;

use crate::process::Processor;
use crate::wire::{decode, encode, Sample};
use limpid_core::{Error, Recording, Result};

/// How the session is set up.
pub struct Config {
    /// UDP address the samples arrive at.
    pub udp: SocketAddr,
    /// Channel names, in the order of the datagram's values.
    pub channels: Vec<String>,
    /// Sample rate of the stream (Hz).
    pub sample_rate: f64,
    /// MVC maxima per channel (None: capture live with the page's button).
    pub maxima: Option<Vec<f64>>,
    /// Target co-contraction level shown as a band (fraction of MVC).
    pub target: Option<f64>,
    /// Half-width of the target band (fraction of MVC).
    pub tolerance: f64,
    /// A recording to stream to the UDP address, and the speed-up.
    pub replay: Option<(Recording, f64)>,
    /// The name of a Lab Streaming Layer stream to read as well (EMG channels
    /// in order, optionally followed by x, y, z, fx, fy, fz).
    pub lsl: Option<String>,
}

/// Fastest stream the live page takes (Hz); EMG amplifiers sample at a few kHz.
pub const MAX_LIVE_RATE_HZ: f64 = 1e6;
/// Fastest replay (times real time).
pub const MAX_REPLAY_SPEED: f64 = 1000.0;

impl Config {
    /// The numbers a session runs on, each in its range; errors name the flag.
    pub fn check(&self) -> Result<()> {
        let number = |v: f64| limpid_core::short_number(v);
        if !(self.sample_rate > 0.0 && self.sample_rate <= MAX_LIVE_RATE_HZ) {
            return Err(Error::invalid(
                "sample rate",
                format!(
                    "expected a sample rate above 0 and up to {MAX_LIVE_RATE_HZ:e} Hz, found {}",
                    number(self.sample_rate)
                ),
            ));
        }
        if let Some(t) = self.target {
            if !(0.0..=2.0).contains(&t) {
                return Err(Error::invalid(
                    "target level",
                    format!(
                        "expected a co-contraction level from 0 to 2 (fraction of MVC), found {}",
                        number(t)
                    ),
                ));
            }
        }
        if !(self.tolerance > 0.0 && self.tolerance <= 1.0) {
            return Err(Error::invalid(
                "target tolerance",
                format!(
                    "expected a half-width above 0 and up to 1 (fraction of MVC), found {}",
                    number(self.tolerance)
                ),
            ));
        }
        if let Some((_, speed)) = &self.replay {
            if !(*speed > 0.0 && *speed <= MAX_REPLAY_SPEED) {
                return Err(Error::invalid(
                    "replay speed",
                    format!(
                        "expected a replay speed above 0 and up to {} (times real time), found {}",
                        number(MAX_REPLAY_SPEED),
                        number(*speed)
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// Latency histogram: 10 µs buckets up to 100 ms.
struct Histogram {
    buckets: Vec<u64>,
    overflow: u64,
    max_us: f64,
    count: u64,
}

impl Histogram {
    fn new() -> Self {
        Histogram {
            buckets: vec![0; 10_000],
            overflow: 0,
            max_us: 0.0,
            count: 0,
        }
    }
    fn add(&mut self, us: f64) {
        let i = (us / 10.0) as usize;
        match self.buckets.get_mut(i) {
            Some(b) => *b += 1,
            None => self.overflow += 1,
        }
        self.max_us = self.max_us.max(us);
        self.count += 1;
    }
    fn quantile(&self, q: f64) -> Option<f64> {
        if self.count == 0 {
            return None;
        }
        let target = (q * self.count as f64).ceil() as u64;
        let mut seen = 0;
        for (i, b) in self.buckets.iter().enumerate() {
            seen += b;
            if seen >= target {
                return Some((i + 1) as f64 * 10.0);
            }
        }
        Some(self.max_us)
    }
}

struct State {
    processor: Processor,
    received: u64,
    malformed: u64,
    lost: u64,
    last_seq: Option<u64>,
    last_arrival: Option<Instant>,
    last_t: Option<f64>,
    latency: Histogram,
    rate_mark: (Instant, u64),
    rate_hz: f64,
}

/// What the page and `/state` show.
#[derive(Debug, Clone, Serialize)]
pub struct Snapshot {
    /// Channel names.
    pub channels: Vec<String>,
    /// Co-contraction index (fraction of MVC); absent until an MVC is known.
    pub index: Option<f64>,
    /// The index averaged over about 1 s, as the bar shows it.
    pub index_display: Option<f64>,
    /// Normalised activation per muscle (fraction of MVC).
    pub activations: Vec<f64>,
    /// Target level (fraction of MVC).
    pub target: Option<f64>,
    /// Half-width of the target band.
    pub tolerance: f64,
    /// MVC maxima are known.
    pub mvc: bool,
    /// MVC capture running.
    pub capturing: bool,
    /// Datagrams received.
    pub received: u64,
    /// Datagrams dropped as malformed.
    pub malformed: u64,
    /// Datagrams lost (gaps in the sequence numbers).
    pub lost: u64,
    /// Sample rate measured over the last second (Hz).
    pub rate_hz: f64,
    /// No sample for more than 0.5 s (or none yet).
    pub stalled: bool,
    /// Time since the last sample (ms).
    pub since_last_ms: Option<f64>,
    /// Sample time of the last sample (s).
    pub last_t: Option<f64>,
    /// Datagram-to-index-update latency (µs), from the sender's clock stamp.
    pub latency_p50_us: Option<f64>,
    /// 99th percentile of the latency (µs).
    pub latency_p99_us: Option<f64>,
    /// Largest latency (µs).
    pub latency_max_us: Option<f64>,
    /// The online impedance of the current co-contraction level.
    pub online: OnlineView,
}

/// The online impedance as the page shows it: a number only with its
/// standard error, and otherwise the reason there is none.
#[derive(Debug, Clone, Serialize)]
pub struct OnlineView {
    /// "estimating", or why no number is shown ("no kinematics in the
    /// stream", "waiting for perturbations: 1 of 3", ...).
    pub status: String,
    /// Stiffness (N/m), row = force axis; only while estimating.
    pub stiffness: Option<[[f64; 3]; 3]>,
    /// Its standard errors (N/m).
    pub stiffness_se: Option<[[f64; 3]; 3]>,
    /// Damping (N s/m).
    pub damping: Option<[[f64; 3]; 3]>,
    /// Inertia (kg).
    pub inertia: Option<[[f64; 3]; 3]>,
    /// VAF per force axis (%); null where it is not in [0, 100].
    pub vaf: Option<[Option<f64>; 3]>,
    /// Perturbations in the estimate (the most recent of this level).
    pub trials: usize,
    /// Perturbations seen since the start.
    pub perturbations: u64,
    /// Mean co-contraction index of the current level (fraction of MVC).
    pub level_index: Option<f64>,
    /// Level changes detected (each restarts the estimate).
    pub level_changes: u64,
    /// Earlier levels: mean index and last stiffness with standard errors.
    pub history: Vec<LevelView>,
    /// Kinematic samples refused as implausible.
    pub rejected: u64,
}

/// One earlier level of [`OnlineView::history`].
#[derive(Debug, Clone, Serialize)]
pub struct LevelView {
    /// Mean co-contraction index (fraction of MVC).
    pub index: f64,
    /// Stiffness (N/m).
    pub stiffness: [[f64; 3]; 3],
    /// Its standard errors (N/m).
    pub stiffness_se: [[f64; 3]; 3],
    /// Perturbations in it.
    pub trials: usize,
}

impl OnlineView {
    /// The view of a processor's online state.
    pub fn of(p: &Processor) -> Self {
        use crate::process::OnlineState;
        let o = &p.online;
        let e = o.estimate();
        let status = if o.samples == 0 {
            "no kinematics in the stream".to_string()
        } else {
            match o.state() {
                OnlineState::Estimating => "estimating".to_string(),
                OnlineState::Waiting(why) => why.clone(),
            }
        };
        OnlineView {
            status,
            stiffness: e.map(|e| e.stiffness),
            stiffness_se: e.map(|e| e.stiffness_se),
            damping: e.map(|e| e.damping),
            inertia: e.map(|e| e.inertia),
            vaf: e.map(|e| e.vaf),
            trials: o.window_trials(),
            perturbations: o.perturbations,
            level_index: p.level_index(),
            level_changes: p.level_changes,
            history: p
                .history
                .iter()
                .map(|h| LevelView {
                    index: h.index,
                    stiffness: h.estimate.stiffness,
                    stiffness_se: h.estimate.stiffness_se,
                    trials: h.estimate.trials,
                })
                .collect(),
            rejected: o.rejected,
        }
    }
}

/// A running session.
pub struct Session {
    shared: Arc<Mutex<State>>,
    stop: Arc<AtomicBool>,
    channels: Vec<String>,
    target: Option<f64>,
    tolerance: f64,
    /// The UDP address the session listens on.
    pub udp: SocketAddr,
}

fn now_unix_ns() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0)
}

impl Session {
    /// Bind the UDP socket and start the receiver (and the replay, if any).
    pub fn start(config: &Config) -> Result<Session> {
        config.check()?;
        let processor = Processor::new(
            config.channels.len(),
            config.sample_rate,
            config.maxima.clone(),
        )?;
        let shared = Arc::new(Mutex::new(State {
            processor,
            received: 0,
            malformed: 0,
            lost: 0,
            last_seq: None,
            last_arrival: None,
            last_t: None,
            latency: Histogram::new(),
            rate_mark: (Instant::now(), 0),
            rate_hz: 0.0,
        }));
        let io = |e: std::io::Error| Error::invalid("UDP", format!("{}: {e}", config.udp));
        let socket = socket2::Socket::new(
            socket2::Domain::for_address(config.udp),
            socket2::Type::DGRAM,
            Some(socket2::Protocol::UDP),
        )
        .map_err(io)?;
        // room for bursts: 8 MB (the kernel may cap it at net.core.rmem_max)
        let _ = socket.set_recv_buffer_size(8 << 20);
        socket.bind(&config.udp.into()).map_err(io)?;
        let socket: UdpSocket = socket.into();
        socket
            .set_read_timeout(Some(Duration::from_millis(100)))
            .map_err(io)?;
        let udp = socket.local_addr().map_err(io)?;
        let stop = Arc::new(AtomicBool::new(false));
        let channels = config.channels.len();
        {
            let (shared, stop) = (shared.clone(), stop.clone());
            std::thread::spawn(move || receive(socket, channels, &shared, &stop));
        }
        if let Some(name) = &config.lsl {
            if let Err(e) = start_lsl(name, channels, &shared, &stop) {
                stop.store(true, Ordering::Relaxed);
                return Err(e);
            }
        }
        if let Some((rec, speed)) = &config.replay {
            let (rec, speed, stop) = (rec.clone(), *speed, stop.clone());
            let names = config.channels.clone();
            std::thread::spawn(move || replay(&rec, &names, speed, udp, &stop));
        }
        Ok(Session {
            shared,
            stop,
            channels: config.channels.clone(),
            target: config.target,
            tolerance: config.tolerance,
            udp,
        })
    }

    /// The current state.
    pub fn snapshot(&self) -> Snapshot {
        let mut s = self.shared.lock().expect("state lock");
        let now = Instant::now();
        let dt = now.duration_since(s.rate_mark.0).as_secs_f64();
        if dt >= 0.5 {
            s.rate_hz = (s.received - s.rate_mark.1) as f64 / dt;
            s.rate_mark = (now, s.received);
        }
        let since = s
            .last_arrival
            .map(|a| now.duration_since(a).as_secs_f64() * 1e3);
        let p = &s.processor;
        Snapshot {
            channels: self.channels.clone(),
            index: p.index.is_finite().then_some(p.index),
            index_display: p.index_display.is_finite().then_some(p.index_display),
            activations: p.activations.clone(),
            target: self.target,
            tolerance: self.tolerance,
            mvc: p.has_mvc(),
            capturing: p.capturing(),
            received: s.received,
            malformed: s.malformed,
            lost: s.lost,
            rate_hz: if since.is_none_or(|ms| ms > 500.0) {
                0.0
            } else {
                s.rate_hz
            },
            stalled: since.is_none_or(|ms| ms > 500.0),
            since_last_ms: since,
            last_t: s.last_t,
            latency_p50_us: s.latency.quantile(0.5),
            latency_p99_us: s.latency.quantile(0.99),
            latency_max_us: (s.latency.count > 0).then_some(s.latency.max_us),
            online: OnlineView::of(p),
        }
    }

    fn mvc(&self, start: bool) -> Result<()> {
        let mut s = self.shared.lock().expect("state lock");
        if start {
            s.processor.start_capture();
            Ok(())
        } else {
            s.processor.stop_capture()
        }
    }

    /// Serve the page on a bound listener until the process ends.
    pub async fn serve(self: Arc<Self>, listener: tokio::net::TcpListener) -> Result<()> {
        let app = Router::new()
            .route("/", get(|| async { Html(PAGE) }))
            .route(
                "/state",
                get(|AxState(s): AxState<Arc<Session>>| async move { Json(s.snapshot()) }),
            )
            .route("/ws", get(ws_handler))
            .route(
                "/mvc/start",
                post(|AxState(s): AxState<Arc<Session>>| async move { mvc_reply(s.mvc(true)) }),
            )
            .route(
                "/mvc/stop",
                post(|AxState(s): AxState<Arc<Session>>| async move { mvc_reply(s.mvc(false)) }),
            )
            .with_state(self.clone());
        axum::serve(listener, app)
            .await
            .map_err(|e| Error::invalid("server", e.to_string()))
    }

    /// Stop the receiver and the replay.
    pub fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

fn mvc_reply(r: Result<()>) -> impl IntoResponse {
    match r {
        Ok(()) => (axum::http::StatusCode::OK, "ok".to_string()),
        Err(e) => (axum::http::StatusCode::BAD_REQUEST, e.to_string()),
    }
}

async fn ws_handler(
    headers: axum::http::HeaderMap,
    ws: WebSocketUpgrade,
    AxState(s): AxState<Arc<Session>>,
) -> axum::response::Response {
    let key = headers
        .get("sec-websocket-key")
        .map(|v| v.as_bytes())
        .unwrap_or_default();
    if !is_websocket_key(key) {
        return (
            axum::http::StatusCode::BAD_REQUEST,
            "Sec-WebSocket-Key must be 16 bytes in base64 (RFC 6455, section 4.1)",
        )
            .into_response();
    }
    ws.on_upgrade(move |socket| push(socket, s)).into_response()
}

/// RFC 6455 section 4.1: the key is a random 16-byte value in base64, that
/// is 22 base64 digits and "==", the last digit carrying 2 bits (its low 4
/// bits zero: A, Q, g or w).
pub fn is_websocket_key(key: &[u8]) -> bool {
    let digit = |b: &u8| b.is_ascii_alphanumeric() || *b == b'+' || *b == b'/';
    key.len() == 24
        && key[..22].iter().all(digit)
        && matches!(key[21], b'A' | b'Q' | b'g' | b'w')
        && &key[22..] == b"=="
}

async fn push(mut socket: WebSocket, s: Arc<Session>) {
    let mut tick = tokio::time::interval(Duration::from_millis(33));
    loop {
        tick.tick().await;
        let text = serde_json::to_string(&s.snapshot()).unwrap_or_default();
        if socket.send(Message::Text(text.into())).await.is_err() {
            return;
        }
    }
}

fn receive(socket: UdpSocket, channels: usize, shared: &Mutex<State>, stop: &AtomicBool) {
    let mut buf = vec![0u8; 65_536];
    while !stop.load(Ordering::Relaxed) {
        let n = match socket.recv_from(&mut buf) {
            Ok((n, _)) => n,
            Err(_) => continue, // timeout: look at the stop flag
        };
        let arrival = Instant::now();
        match decode(&buf[..n], channels) {
            Err(_) => shared.lock().expect("state lock").malformed += 1,
            Ok(sample) => {
                let now = now_unix_ns();
                // a sender clock more than a minute off (e.g. 1 ns) is unknown, not a latency
                let latency_us = (sample.sent_unix_ns > 0
                    && now >= sample.sent_unix_ns
                    && now - sample.sent_unix_ns < 60_000_000_000)
                    .then(|| (now - sample.sent_unix_ns) as f64 / 1e3);
                ingest(shared, &sample, arrival, latency_us);
            }
        }
    }
}

/// Largest gap in the sequence numbers counted as lost datagrams (about
/// 17 minutes at 1 kHz). A larger jump is the sender restarting or
/// renumbering, not loss: one datagram jumping by 2^32 made `lost` read
/// 4,294,967,292 for the rest of the session (issue 36).
pub const MAX_COUNTED_GAP: u64 = 1 << 20;

/// Datagrams lost between sequence numbers `last` and `seq`.
pub fn lost_between(last: u64, seq: u64) -> u64 {
    match seq.checked_sub(last) {
        Some(step) if step > 1 && step - 1 <= MAX_COUNTED_GAP => step - 1,
        _ => 0,
    }
}

/// One sample into the processor and the stream statistics.
fn ingest(shared: &Mutex<State>, sample: &Sample, arrival: Instant, latency_us: Option<f64>) {
    let mut s = shared.lock().expect("state lock");
    if let Some(last) = s.last_seq {
        s.lost += lost_between(last, sample.seq);
    }
    s.last_seq = Some(sample.seq);
    s.processor.update(&sample.emg, sample.kinematics.as_ref());
    s.received += 1;
    s.last_arrival = Some(arrival);
    s.last_t = Some(sample.t);
    if let Some(us) = latency_us {
        s.latency.add(us);
    }
}

/// Resolve the LSL stream `name` (up to 5 s), then pull its samples until
/// `stop`. The first message on `ready` says whether the inlet is open.
/// LSL has no sequence numbers: `lost` counts UDP gaps only; the latency is
/// the LSL clock now minus the sample's time stamp (same machine).
#[cfg(feature = "lsl")]
fn receive_lsl(
    name: &str,
    channels: usize,
    shared: &Mutex<State>,
    stop: &AtomicBool,
    ready: std::sync::mpsc::Sender<Result<()>>,
) {
    use lsl::Pullable;
    let fail = |message: String| Error::invalid("lsl", message);
    let open = || -> Result<lsl::StreamInlet> {
        let found = lsl::resolve_byprop("name", name, 1, 5.0)
            .map_err(|e| fail(format!("resolving {name:?}: {e:?}")))?;
        let info = found.first().ok_or_else(|| {
            fail(format!(
                "no stream named {name:?} on the network within 5 s"
            ))
        })?;
        let count = info.channel_count() as usize;
        if count != channels && count != channels + 6 {
            return Err(fail(format!(
                "stream {name:?} has {count} channels; expected {channels} EMG channels, optionally followed by x, y, z, fx, fy, fz ({})",
                channels + 6
            )));
        }
        let inlet = lsl::StreamInlet::new(info, 360, 0, true)
            .map_err(|e| fail(format!("opening {name:?}: {e:?}")))?;
        inlet
            .open_stream(5.0)
            .map_err(|e| fail(format!("opening {name:?}: {e:?}")))?;
        Ok(inlet)
    };
    let inlet = match open() {
        Ok(inlet) => {
            let _ = ready.send(Ok(()));
            inlet
        }
        Err(e) => {
            let _ = ready.send(Err(e));
            return;
        }
    };
    let mut seq = 0u64;
    while !stop.load(Ordering::Relaxed) {
        let (values, stamp): (Vec<f64>, f64) = match inlet.pull_sample(0.1) {
            Ok(pulled) => pulled,
            Err(_) => continue, // the stream is being recovered
        };
        if values.is_empty() {
            continue; // timeout: look at the stop flag
        }
        let arrival = Instant::now();
        let kinematics = (values.len() == channels + 6).then(|| {
            let k = &values[channels..];
            [k[0], k[1], k[2], k[3], k[4], k[5]]
        });
        let sample = Sample {
            seq,
            t: stamp,
            sent_unix_ns: 0,
            emg: values[..channels.min(values.len())].to_vec(),
            kinematics,
        };
        seq += 1;
        if sample.emg.len() != channels
            || values.len() > channels + 6
            || crate::wire::check_values(&sample).is_err()
        {
            shared.lock().expect("state lock").malformed += 1;
            continue;
        }
        let latency_us = Some(((lsl::local_clock() - stamp) * 1e6).max(0.0));
        ingest(shared, &sample, arrival, latency_us);
    }
}

/// Start the LSL inlet thread and wait until it is open (or failed).
fn start_lsl(
    name: &str,
    channels: usize,
    shared: &Arc<Mutex<State>>,
    stop: &Arc<AtomicBool>,
) -> Result<()> {
    #[cfg(feature = "lsl")]
    {
        let (tx, rx) = std::sync::mpsc::channel();
        let (name, shared, stop) = (name.to_string(), shared.clone(), stop.clone());
        std::thread::spawn(move || receive_lsl(&name, channels, &shared, &stop, tx));
        rx.recv()
            .unwrap_or_else(|_| Err(Error::invalid("lsl", "the inlet thread ended")))
    }
    #[cfg(not(feature = "lsl"))]
    {
        let _ = (name, channels, shared, stop);
        Err(Error::invalid(
            "lsl",
            "this limpid was built without Lab Streaming Layer support; rebuild with `--features lsl` (needs cmake, a C++ compiler and, with glibc >= 2.34, CXXFLAGS=-DPTHREAD_STACK_MIN=16384)",
        ))
    }
}

/// Stream a recording's EMG (and x, y, z, fx, fy, fz when present) to `udp` at `speed` x real time.
fn replay(rec: &Recording, channels: &[String], speed: f64, udp: SocketAddr, stop: &AtomicBool) {
    let Ok(socket) = UdpSocket::bind(if udp.is_ipv4() {
        "127.0.0.1:0"
    } else {
        "[::1]:0"
    }) else {
        return;
    };
    let emg: Vec<&[f64]> = channels.iter().filter_map(|c| rec.column(c)).collect();
    if emg.len() != channels.len() {
        return;
    }
    let kin: Option<Vec<&[f64]>> = ["x", "y", "z", "fx", "fy", "fz"]
        .iter()
        .map(|c| rec.column(c))
        .collect();
    let t = rec.column("t").unwrap_or(&[]);
    let start = Instant::now();
    let t0 = t.first().copied().unwrap_or(0.0);
    let mut values = vec![0.0; channels.len()];
    for k in 0..rec.len() {
        if stop.load(Ordering::Relaxed) {
            return;
        }
        let due = Duration::from_secs_f64(((t[k] - t0) / speed).max(0.0));
        let elapsed = start.elapsed();
        if due > elapsed + Duration::from_micros(500) {
            std::thread::sleep(due - elapsed);
        }
        for (v, c) in values.iter_mut().zip(&emg) {
            *v = c[k];
        }
        let sample = Sample {
            seq: k as u64,
            t: t[k],
            sent_unix_ns: now_unix_ns(),
            emg: values.clone(),
            kinematics: kin
                .as_ref()
                .map(|c| [c[0][k], c[1][k], c[2][k], c[3][k], c[4][k], c[5][k]]),
        };
        let _ = socket.send_to(&encode(&sample), udp);
    }
}

/// The page: no external resource; reconnects by itself.
pub const PAGE: &str = include_str!("page.html");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn websocket_keys_are_16_bytes_of_base64() {
        // RFC 6455's example key, and 16 bytes of 0xff
        assert!(is_websocket_key(b"dGhlIHNhbXBsZSBub25jZQ=="));
        assert!(is_websocket_key(b"/////////////////////w=="));
        for bad in [
            &b""[..],
            b"not-a-key",
            b"dGhlIHNhbXBsZSBub25jZQ=",
            b"dGhlIHNhbXBsZSBub25jZR==", // 'R' leaves bits beyond 16 bytes
            b"dGhlIHNhbXBsZSBub25j!Q==",
            b"dGhlIHNhbXBsZSBub25jZQ==x",
        ] {
            assert!(!is_websocket_key(bad), "{}", String::from_utf8_lossy(bad));
        }
    }

    #[test]
    fn gaps_count_as_lost_and_jumps_do_not() {
        assert_eq!(lost_between(10, 11), 0);
        assert_eq!(lost_between(10, 14), 3);
        assert_eq!(lost_between(10, 10), 0, "a repeated datagram");
        assert_eq!(lost_between(10, 3), 0, "numbering went back");
        assert_eq!(lost_between(0, MAX_COUNTED_GAP + 1), MAX_COUNTED_GAP);
        // one datagram whose number jumps by 2^32: a renumbering, not 4e9 losses
        assert_eq!(lost_between(7, 7 + (1 << 32)), 0);
        assert_eq!(lost_between(u64::MAX - 1, u64::MAX), 0);
        assert_eq!(lost_between(0, u64::MAX), 0);
    }
}
