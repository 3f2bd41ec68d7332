//! Units per physical quantity of a FORMAT.md column (time, length, angle, force, torque, voltage): the factor to SI of a unit a lab file declares, and the nearest names for a mistyped one.

use limpid_core::recording::magnitude_limit;

/// The physical quantity of a FORMAT.md column, from its unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Quantity {
    Time,
    Length,
    Angle,
    Force,
    Torque,
    Voltage,
    Number,
}

impl Quantity {
    pub(crate) fn of(column: &str) -> Quantity {
        match magnitude_limit(column).1 {
            "s" => Quantity::Time,
            "m" => Quantity::Length,
            "rad" => Quantity::Angle,
            "N" => Quantity::Force,
            "N m" => Quantity::Torque,
            "V" => Quantity::Voltage,
            _ => Quantity::Number,
        }
    }

    pub(crate) fn name(self) -> &'static str {
        match self {
            Quantity::Time => "a time (s)",
            Quantity::Length => "a length (m)",
            Quantity::Angle => "an angle (rad)",
            Quantity::Force => "a force (N)",
            Quantity::Torque => "a torque (N m)",
            Quantity::Voltage => "a voltage (V)",
            Quantity::Number => "a number without unit",
        }
    }

    /// Units limpid converts, with their factor to SI.
    pub(crate) fn units(self) -> &'static [(&'static str, f64)] {
        const DEG: f64 = std::f64::consts::PI / 180.0;
        const LBF: f64 = 4.448_221_615_260_5;
        match self {
            Quantity::Time => &[
                ("s", 1.0),
                ("ms", 1e-3),
                ("us", 1e-6),
                ("µs", 1e-6),
                ("min", 60.0),
            ],
            Quantity::Length => &[
                ("m", 1.0),
                ("cm", 1e-2),
                ("mm", 1e-3),
                ("um", 1e-6),
                ("µm", 1e-6),
                ("in", 0.0254),
                ("ft", 0.3048),
            ],
            Quantity::Angle => &[
                ("rad", 1.0),
                ("mrad", 1e-3),
                ("deg", DEG),
                ("degree", DEG),
                ("degrees", DEG),
                ("°", DEG),
            ],
            Quantity::Force => &[
                ("N", 1.0),
                ("kN", 1e3),
                ("mN", 1e-3),
                ("lbf", LBF),
                ("kgf", 9.806_65),
            ],
            Quantity::Torque => &[
                ("N m", 1.0),
                ("N*m", 1.0),
                ("N.m", 1.0),
                ("N·m", 1.0),
                ("Nm", 1.0),
                ("N mm", 1e-3),
                ("N*mm", 1e-3),
                ("N.mm", 1e-3),
                ("Nmm", 1e-3),
                ("mN m", 1e-3),
                ("mN*m", 1e-3),
                ("mNm", 1e-3),
                ("kN m", 1e3),
                ("lbf in", LBF * 0.0254),
                ("lbf*in", LBF * 0.0254),
            ],
            Quantity::Voltage => &[
                ("V", 1.0),
                ("mV", 1e-3),
                ("uV", 1e-6),
                ("µV", 1e-6),
                ("kV", 1e3),
            ],
            Quantity::Number => &[("1", 1.0), ("", 1.0), ("count", 1.0)],
        }
    }

    /// The factor to SI of `unit`, or why it cannot be converted.
    pub(crate) fn factor(self, unit: &str) -> std::result::Result<f64, String> {
        let unit = unit.trim();
        if let Some((_, f)) = self.units().iter().find(|(u, _)| *u == unit) {
            return Ok(*f);
        }
        // a unit of another quantity is a different mistake than a typo
        for other in [
            Quantity::Time,
            Quantity::Length,
            Quantity::Angle,
            Quantity::Force,
            Quantity::Torque,
            Quantity::Voltage,
        ] {
            if other != self && other.units().iter().any(|(u, _)| *u == unit) {
                return Err(format!(
                    "unit {unit:?} is {}, but the column is {}",
                    other.name(),
                    self.name()
                ));
            }
        }
        let names: Vec<&str> = self
            .units()
            .iter()
            .map(|(u, _)| *u)
            .filter(|u| !u.is_empty())
            .collect();
        Err(format!(
            "unknown unit {unit:?} for {}{}",
            self.name(),
            nearest_hint(unit, &names)
        ))
    }
}

/// The factor that converts `unit` to the SI unit of FORMAT.md column
/// `column`, or why it cannot.
pub fn unit_factor(column: &str, unit: &str) -> std::result::Result<f64, String> {
    Quantity::of(column).factor(unit)
}

/// ", nearest: a, b" (the closest names by edit distance), or the list of all when few.
pub fn nearest_hint(wanted: &str, names: &[&str]) -> String {
    if names.is_empty() {
        return String::new();
    }
    let mut scored: Vec<(usize, &str)> = names
        .iter()
        .map(|n| {
            let d = strsim::levenshtein(&wanted.to_lowercase(), &n.to_lowercase());
            (d, *n)
        })
        .collect();
    scored.sort();
    let close: Vec<&str> = scored.iter().take(3).map(|(_, n)| *n).collect();
    format!("; nearest: {}", close.join(", "))
}
