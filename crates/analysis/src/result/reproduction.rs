//! What `limpid reproduce` reports (the experiments run in `limpid-app`):
//! each seed's experiment on the virtual lab with the realistic subjects of
//! the lab, its tables and headline numbers printed beside the paper's.
//!
//! - 000: seed 000 §III on subject 1 of Table I (plus Table II's antisymmetric
//!   part), cubic perturbations, the lab's realistic noise model: Table II per start
//!   point and the fit correlation per axis.
//! - 001: seed 001's 7 configurations x 4 levels on 4 subjects built from its
//!   Tables 1-5, one MVC from configuration 5: Tables 1-4 (diagonal, K_maxA,
//!   principal stiffnesses), Table 5 (axis rotations), the index per level.
//! - 003: seed 003's planar experiment with a spinal reflex: the shortest
//!   windows at which K is positive definite, K and D quasi-symmetric, all
//!   parameters quasi-constant, with known and unknown inertia; Table I's
//!   conditioning ratios, quintic against a sixth-order polynomial.
//! - 004: seed 004's spring arrays sa1 and sa2 held by the robot under IMBIC
//!   and under PD, Table III's Welch settings: K_sa, phi_T and the multiple
//!   coherence.
//!
//! Every paper number the experiment addresses is one [`Row`]; `paper` is
//! `None` where the text does not give the number (figures only, garbled
//! tables). [`Finding`]s state the papers' qualitative findings and whether
//! the virtual experiment shows them.

use serde::Serialize;

/// One number of a paper beside limpid's.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// "000", "001", "003" or "004".
    pub seed: String,
    /// What the number is, e.g. "Table 5, configuration 1, rotation of axis 2".
    pub item: String,
    /// The paper's value; `None` where the text does not give it.
    pub paper: Option<f64>,
    /// limpid's value on the virtual experiment; `None` where it has none.
    pub limpid: Option<f64>,
    /// Unit.
    pub unit: String,
    /// Why a value is missing or differs, or how it was obtained.
    pub note: String,
}

/// A qualitative finding of a paper and whether the virtual experiment shows it.
#[derive(Debug, Clone, Serialize)]
pub struct Finding {
    /// The seed.
    pub seed: String,
    /// The paper's claim.
    pub claim: String,
    /// Whether limpid's numbers show it.
    pub holds: bool,
    /// The numbers behind the verdict.
    pub evidence: String,
}

/// What `limpid reproduce` prints.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Reproduction {
    /// One row per paper number.
    pub rows: Vec<Row>,
    /// The qualitative findings.
    pub findings: Vec<Finding>,
}

/// The seeds `limpid reproduce` knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Seed {
    /// 3-D end-point impedance (seed 000).
    S000,
    /// Co-contraction (seed 001).
    S001,
    /// Planar arm, observation windows (seed 003).
    S003,
    /// Stochastic MIMO, IMBIC (seed 004).
    S004,
}

impl Seed {
    /// All four.
    pub const ALL: [Seed; 4] = [Seed::S000, Seed::S001, Seed::S003, Seed::S004];

    /// "000", ...
    pub fn code(self) -> &'static str {
        match self {
            Seed::S000 => "000",
            Seed::S001 => "001",
            Seed::S003 => "003",
            Seed::S004 => "004",
        }
    }

    /// The id a reader understands: the first author and the year.
    pub fn id(self) -> &'static str {
        match self {
            Seed::S000 => "artemiadis2010",
            Seed::S001 => "patel2013",
            Seed::S003 => "lakatos2011",
            Seed::S004 => "park2011",
        }
    }

    /// The paper as a reader cites it.
    pub fn citation(self) -> &'static str {
        citation(self.code())
    }

    /// The paper named by `text`: its id (`artemiadis2010`, `patel2013`,
    /// `lakatos2011`, `park2011`, case-insensitive) or the short number
    /// (`000`, `0`, `001`, ...) kept as an alias.
    pub fn parse(text: &str) -> Option<Seed> {
        let lower = text.trim().to_ascii_lowercase();
        if let Some(s) = Seed::ALL.into_iter().find(|s| s.id() == lower) {
            return Some(s);
        }
        if lower.is_empty() || !lower.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        match lower.trim_start_matches('0') {
            "" => Some(Seed::S000),
            "1" => Some(Seed::S001),
            "3" => Some(Seed::S003),
            "4" => Some(Seed::S004),
            _ => None,
        }
    }
}

/// The citation of the paper whose short number is `code` ("000", ...);
/// the code itself for an unknown one.
pub fn citation(code: &str) -> &str {
    match code {
        "000" => "Artemiadis, Katsiaris, Liarokapis & Kyriakopoulos (2010)",
        "001" => "Patel, O'Neill & Artemiadis (2013)",
        "003" => "Lakatos, Petit & van der Smagt (2011)",
        "004" => "Park & Chang (2011)",
        other => other,
    }
}

impl Row {
    /// limpid's value relative to the paper's ("+6 %"); empty when either
    /// is missing or the paper's is 0.
    pub fn difference(&self) -> String {
        match (self.paper, self.limpid) {
            (Some(p), Some(l)) if p != 0.0 => format!("{:+.0} %", 100.0 * (l / p - 1.0)),
            _ => String::new(),
        }
    }

    /// The row with a note.
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.note = note.into();
        self
    }
}

/// Four significant digits, exponent for very small or large values.
pub fn sig(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e6).contains(&a) {
        return format!("{v:.3e}");
    }
    let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}
