//! Shared by the live tests: start `limpid live`, read its state over HTTP.
#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};

pub struct Live {
    pub child: Child,
    pub page: String,
    pub http: String,
    pub udp: String,
}

impl Drop for Live {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Start `limpid live` with free ports and these extra arguments.
pub fn start(extra: &[&str]) -> Live {
    let mut child = Command::new(env!("CARGO_BIN_EXE_limpid"))
        .args(["live", "--listen", "127.0.0.1:0", "--udp", "127.0.0.1:0"])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("limpid live starts");
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    // "limpid live: page http://127.0.0.1:PORT/  (UDP samples on 127.0.0.1:PORT)"
    let page = line
        .split_whitespace()
        .find(|w| w.starts_with("http://"))
        .expect("URL printed")
        .to_string();
    let http = page
        .trim_start_matches("http://")
        .trim_end_matches('/')
        .to_string();
    let udp = line
        .rsplit(' ')
        .next()
        .unwrap()
        .trim()
        .trim_end_matches(')')
        .to_string();
    Live {
        child,
        page,
        http,
        udp,
    }
}

/// GET a path and parse the JSON body.
pub fn get_json(http: &str, path: &str) -> serde_json::Value {
    let mut s = TcpStream::connect(http).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {http}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut text = String::new();
    s.read_to_string(&mut text).unwrap();
    let body = text.split("\r\n\r\n").nth(1).expect("a body");
    serde_json::from_str(body).unwrap_or_else(|e| panic!("{e}: {body}"))
}

/// Resident memory of a process (kB), from /proc.
pub fn rss_kb(pid: u32) -> u64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .unwrap()
        .lines()
        .find(|l| l.starts_with("VmRSS:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}
