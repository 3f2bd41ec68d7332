//! `limpid live`: the live co-contraction display of seed 001 Fig. 3 (limpid-live).

use std::io::Write as _;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use limpid_analysis::emg::{emg_columns, mvc_maxima, EmgParams};
use limpid_live::server::{Config, Session};

use crate::context::{CliResult, Context};

#[derive(Args)]
pub struct LiveArgs {
    /// Address of the web page (port 0: any free port; the URL is printed).
    #[arg(long, default_value = "127.0.0.1:8080")]
    pub listen: SocketAddr,
    /// UDP address the samples arrive at (wire format: docs/src/reference/live.md).
    #[arg(long, default_value = "127.0.0.1:9000")]
    pub udp: SocketAddr,
    /// MVC recording (`emg_*` columns): normalisation maxima; without it, capture one live from the page.
    #[arg(long)]
    pub mvc: Option<PathBuf>,
    /// EMG channel names in stream order (default: the `emg_*` columns of --mvc or --replay).
    #[arg(long, value_delimiter = ',')]
    pub channels: Option<Vec<String>>,
    /// Sample rate of the stream (Hz; default: that of --replay or --mvc).
    #[arg(long)]
    pub rate: Option<f64>,
    /// Target co-contraction level shown as a band (fraction of MVC).
    #[arg(long)]
    pub target: Option<f64>,
    /// Half-width of the target band.
    #[arg(long, default_value_t = 0.1)]
    pub tolerance: f64,
    /// Stream this recording to the UDP address (demos and tests).
    #[arg(long)]
    pub replay: Option<PathBuf>,
    /// Replay speed (1: real time).
    #[arg(long, default_value_t = 1.0)]
    pub speed: f64,
    /// Also read the Lab Streaming Layer stream of this name (EMG channels in
    /// order, optionally followed by x, y, z, fx, fy, fz); needs a limpid
    /// built with `--features lsl`.
    #[arg(long, value_name = "STREAM")]
    pub lsl: Option<String>,
}

pub fn run(args: LiveArgs, cx: &Context) -> CliResult {
    let mvc = args
        .mvc
        .as_ref()
        .map(|p| cx.read_supporting_recording(p))
        .transpose()?;
    let replay = args
        .replay
        .as_ref()
        .map(|p| cx.read_recording(p))
        .transpose()?;
    let channels =
        match (&args.channels, &mvc, &replay) {
            (Some(c), _, _) => c.clone(),
            (None, Some(m), _) => emg_columns(m),
            (None, None, Some(r)) => emg_columns(r),
            _ => return Err(
                "name the EMG channels: --channels, or give --mvc or --replay with emg_* columns"
                    .into(),
            ),
        };
    if channels.is_empty() {
        return Err("no EMG channels (emg_* columns) to show".into());
    }
    // `--channels ""` or `a,,b`, and one name twice (issue 56)
    if let Some(i) = channels.iter().position(|c| c.trim().is_empty()) {
        return Err(format!("invalid --channels: channel {} has no name", i + 1).into());
    }
    if let Some((i, c)) = channels
        .iter()
        .enumerate()
        .find(|(i, c)| channels[..*i].contains(c))
    {
        return Err(format!("invalid --channels: {c} is named twice (channel {})", i + 1).into());
    }
    let rate = args
        .rate
        .or(replay.as_ref().map(|r| r.sample_rate()))
        .or(mvc.as_ref().map(|r| r.sample_rate()))
        .ok_or("give --rate (Hz) for a stream without --replay or --mvc")?;
    // the MVC file is offline: its maxima come from the zero-phase envelope, as in
    // `estimate cocontraction`; only the live stream is filtered causally (the
    // causal and zero-phase envelopes have the same mean, not the same peaks)
    let maxima = mvc
        .as_ref()
        .map(|m| mvc_maxima(m, &channels, &EmgParams::default()))
        .transpose()?;
    let config = Config {
        udp: args.udp,
        channels,
        sample_rate: rate,
        maxima,
        target: args.target,
        tolerance: args.tolerance,
        replay: replay.map(|r| (r, args.speed)),
        lsl: args.lsl.clone(),
    };
    let session = Arc::new(Session::start(&config).map_err(|e| cx.with_flag_names("live", e))?);
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()?;
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::bind(args.listen)
            .await
            .map_err(|e| format!("{}: {e}", args.listen))?;
        let addr = listener.local_addr()?;
        println!(
            "limpid live: page http://{addr}/  (UDP samples on {})",
            session.udp
        );
        std::io::stdout().flush()?;
        session.serve(listener).await?;
        Ok(())
    })
}
