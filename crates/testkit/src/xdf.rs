//! A small XDF writer for tests, from the specification
//! (github.com/sccn/xdf/wiki/Specifications): lab files of any size made from
//! a lab recording, to check that a split recording reads back as the whole.
//! Every sample carries its stamp; chunks hold up to 1000 samples.

use std::io::Write;
use std::path::Path;

/// One stream to write.
pub struct XdfStream {
    /// `<name>`.
    pub name: String,
    /// `<type>`.
    pub kind: String,
    /// `<nominal_srate>` (0 for irregular).
    pub rate: f64,
    /// Channel labels and units; empty for a marker stream.
    pub channels: Vec<(String, String)>,
    /// Stamps, on the stream's own clock.
    pub stamps: Vec<f64>,
    /// Values per channel (double64); unused for markers.
    pub values: Vec<Vec<f64>>,
    /// Marker texts (a string stream when not empty).
    pub texts: Vec<String>,
    /// ClockOffset records: (collection time, offset).
    pub clock_offsets: Vec<(f64, f64)>,
}

fn chunk(out: &mut Vec<u8>, tag: u16, content: &[u8]) {
    out.push(8);
    out.extend_from_slice(&((content.len() + 2) as u64).to_le_bytes());
    out.extend_from_slice(&tag.to_le_bytes());
    out.extend_from_slice(content);
}

/// Write `streams` as an XDF file.
pub fn write(path: &Path, streams: &[XdfStream]) -> std::io::Result<()> {
    let mut out = b"XDF:".to_vec();
    chunk(
        &mut out,
        1,
        b"<?xml version=\"1.0\"?><info><version>1.0</version></info>",
    );
    for (i, s) in streams.iter().enumerate() {
        let id = (i + 1) as u32;
        let text = !s.texts.is_empty();
        let labels: Vec<(String, String)> = if text {
            vec![("marker".into(), String::new())]
        } else {
            s.channels.clone()
        };
        let chans: String = labels
            .iter()
            .map(|(l, u)| format!("<channel><label>{l}</label><unit>{u}</unit></channel>"))
            .collect();
        let xml = format!(
            "<?xml version=\"1.0\"?><info><name>{}</name><type>{}</type><channel_count>{}</channel_count><nominal_srate>{}</nominal_srate><channel_format>{}</channel_format><desc><channels>{chans}</channels></desc></info>",
            s.name,
            s.kind,
            labels.len(),
            s.rate,
            if text { "string" } else { "double64" }
        );
        let mut content = id.to_le_bytes().to_vec();
        content.extend_from_slice(xml.as_bytes());
        chunk(&mut out, 2, &content);
    }
    for (i, s) in streams.iter().enumerate() {
        let id = (i + 1) as u32;
        for start in (0..s.stamps.len()).step_by(1000) {
            let end = (start + 1000).min(s.stamps.len());
            let mut content = id.to_le_bytes().to_vec();
            content.push(4);
            content.extend_from_slice(&((end - start) as u32).to_le_bytes());
            for k in start..end {
                content.push(8);
                content.extend_from_slice(&s.stamps[k].to_le_bytes());
                if s.texts.is_empty() {
                    for ch in &s.values {
                        content.extend_from_slice(&ch[k].to_le_bytes());
                    }
                } else {
                    let b = s.texts[k].as_bytes();
                    content.push(4);
                    content.extend_from_slice(&(b.len() as u32).to_le_bytes());
                    content.extend_from_slice(b);
                }
            }
            chunk(&mut out, 3, &content);
        }
        for (t, o) in &s.clock_offsets {
            let mut content = id.to_le_bytes().to_vec();
            content.extend_from_slice(&t.to_le_bytes());
            content.extend_from_slice(&o.to_le_bytes());
            chunk(&mut out, 4, &content);
        }
    }
    std::fs::File::create(path)?.write_all(&out)
}
