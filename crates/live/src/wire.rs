//! The live stream's datagram (one sample per UDP datagram, little-endian):
//!
//! | bytes | field | meaning |
//! |---|---|---|
//! | 0-3 | `LMPD` | magic |
//! | 4 | u8 | version, 1 |
//! | 5 | u8 | flags: bit 0 = kinematics follow the EMG |
//! | 6-7 | u16 | number of EMG channels n |
//! | 8-15 | u64 | sequence number (gaps count as lost samples) |
//! | 16-23 | f64 | sample time (s) |
//! | 24-31 | u64 | sender's wall clock at sending (ns since the Unix epoch; 0: unknown) |
//! | 32- | n x f64 | raw EMG (V), in the order of `--channels` / the MVC file |
//! | then | 6 x f64 | if flag bit 0: x, y, z (m), fx, fy, fz (N, on the limb) |
//!
//! Anything else (other magic, version, length, channel count) is malformed:
//! counted and dropped. So is a sample with a value no sensor gives (issue
//! 13: one 1e308 would poison the envelope and the online estimate for the rest of the
//! session): beyond the recording limits of `limpid_core::recording::magnitude_limit`
//! (t 1e10 s, EMG 1e6 V, positions 100 m, forces 1e6 N).

/// One decoded sample.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// Sequence number (gaps count as lost datagrams).
    pub seq: u64,
    /// Sample time (s).
    pub t: f64,
    /// Sender's clock at sending (ns since the Unix epoch), for latency.
    pub sent_unix_ns: u64,
    /// EMG value per channel (V).
    pub emg: Vec<f64>,
    /// x, y, z, fx, fy, fz when present.
    pub kinematics: Option<[f64; 6]>,
}

/// The first four bytes of every datagram.
pub const MAGIC: &[u8; 4] = b"LMPD";
/// Bytes before the values.
pub const HEADER: usize = 32;

/// Encode a sample.
pub fn encode(s: &Sample) -> Vec<u8> {
    let mut b = Vec::with_capacity(HEADER + 8 * (s.emg.len() + 6));
    b.extend_from_slice(MAGIC);
    b.push(1);
    b.push(u8::from(s.kinematics.is_some()));
    b.extend_from_slice(&(s.emg.len() as u16).to_le_bytes());
    b.extend_from_slice(&s.seq.to_le_bytes());
    b.extend_from_slice(&s.t.to_le_bytes());
    b.extend_from_slice(&s.sent_unix_ns.to_le_bytes());
    for v in s.emg.iter().chain(s.kinematics.iter().flatten()) {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b
}

/// Why a datagram was dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Malformed {
    /// Shorter than the header.
    Short,
    /// Wrong magic bytes.
    Magic,
    /// Unknown format version.
    Version,
    /// Channel count differs from the session's.
    Channels,
    /// Length differs from what the header announces.
    Length,
    /// A value is NaN or infinite.
    NotFinite,
    /// Finite but beyond what any sensor gives (see the module docs).
    Implausible,
}

fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

/// Decode a datagram for a stream of `channels` EMG channels.
pub fn decode(b: &[u8], channels: usize) -> Result<Sample, Malformed> {
    if b.len() < HEADER {
        return Err(Malformed::Short);
    }
    if &b[0..4] != MAGIC {
        return Err(Malformed::Magic);
    }
    if b[4] != 1 {
        return Err(Malformed::Version);
    }
    let kin = b[5] & 1 == 1;
    let n = u16::from_le_bytes([b[6], b[7]]) as usize;
    if n != channels {
        return Err(Malformed::Channels);
    }
    let values = n + if kin { 6 } else { 0 };
    if b.len() != HEADER + 8 * values {
        return Err(Malformed::Length);
    }
    let seq = u64::from_le_bytes(b[8..16].try_into().expect("8 bytes"));
    let t = f64_at(b, 16);
    let sent_unix_ns = u64::from_le_bytes(b[24..32].try_into().expect("8 bytes"));
    let emg: Vec<f64> = (0..n).map(|i| f64_at(b, HEADER + 8 * i)).collect();
    let kinematics = kin.then(|| {
        let mut k = [0.0; 6];
        for (i, v) in k.iter_mut().enumerate() {
            *v = f64_at(b, HEADER + 8 * (n + i));
        }
        k
    });
    let sample = Sample {
        seq,
        t,
        sent_unix_ns,
        emg,
        kinematics,
    };
    check_values(&sample)?;
    Ok(sample)
}

/// Refuse a sample with a non-finite value or one no sensor gives (module docs).
pub fn check_values(s: &Sample) -> Result<(), Malformed> {
    let values = || s.emg.iter().chain(s.kinematics.iter().flatten());
    if !s.t.is_finite() || values().any(|v| !v.is_finite()) {
        return Err(Malformed::NotFinite);
    }
    use limpid_core::recording::magnitude_limit;
    let emg_limit = magnitude_limit("emg_").0;
    let kin_names = ["x", "y", "z", "fx", "fy", "fz"];
    if s.t.abs() > magnitude_limit("t").0
        || s.emg.iter().any(|v| v.abs() > emg_limit)
        || s.kinematics.is_some_and(|k| {
            k.iter()
                .zip(kin_names)
                .any(|(v, name)| v.abs() > magnitude_limit(name).0)
        })
    {
        return Err(Malformed::Implausible);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_every_kind_of_malformed_datagram() {
        let s = Sample {
            seq: 42,
            t: 1.25,
            sent_unix_ns: 7,
            emg: vec![0.1, -0.2, 0.3],
            kinematics: Some([1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
        };
        let b = encode(&s);
        assert_eq!(decode(&b, 3).unwrap(), s);
        let plain = Sample {
            kinematics: None,
            ..s.clone()
        };
        assert_eq!(decode(&encode(&plain), 3).unwrap(), plain);
        assert_eq!(decode(&b[..20], 3), Err(Malformed::Short));
        assert_eq!(decode(&b[..b.len() - 3], 3), Err(Malformed::Length));
        assert_eq!(decode(&b, 4), Err(Malformed::Channels));
        let mut bad = b.clone();
        bad[0] = b'X';
        assert_eq!(decode(&bad, 3), Err(Malformed::Magic));
        let mut bad = b.clone();
        bad[4] = 9;
        assert_eq!(decode(&bad, 3), Err(Malformed::Version));
        let nan = Sample {
            emg: vec![f64::NAN, 0.0, 0.0],
            ..s
        };
        assert_eq!(decode(&encode(&nan), 3), Err(Malformed::NotFinite));
    }

    #[test]
    fn finite_extreme_samples_are_malformed_not_processed() {
        let s = Sample {
            seq: 1,
            t: 1.0,
            sent_unix_ns: 1,
            emg: vec![0.1, 0.2],
            kinematics: Some([0.3, 0.0, 0.0, 1.0, 2.0, 3.0]),
        };
        assert!(decode(&encode(&s), 2).is_ok());
        let huge_emg = Sample {
            emg: vec![1e308, 0.2],
            ..s.clone()
        };
        assert_eq!(decode(&encode(&huge_emg), 2), Err(Malformed::Implausible));
        let huge_x = Sample {
            kinematics: Some([1e308, 0.0, 0.0, 1.0, 2.0, 3.0]),
            ..s.clone()
        };
        assert_eq!(decode(&encode(&huge_x), 2), Err(Malformed::Implausible));
        let huge_force = Sample {
            kinematics: Some([0.3, 0.0, 0.0, 1e9, 2.0, 3.0]),
            ..s.clone()
        };
        assert_eq!(decode(&encode(&huge_force), 2), Err(Malformed::Implausible));
        let huge_t = Sample { t: 1e300, ..s };
        assert_eq!(decode(&encode(&huge_t), 2), Err(Malformed::Implausible));
    }
}
