//! Units from what a column *is*, never from its name (issue 63, item 2).
//!
//! A request names its position column; the recording format (FORMAT.md)
//! gives its canonical names a quantity (`theta`, `q1`..: joint angles in
//! rad; `x`, `y`, `z`: end-point displacements in m). A column renamed by a
//! lab (`angle`, `ankle_pos`) has no such meaning, so the request says what
//! it is ([`Coordinate`]), and the result carries the [`Units`] that follow,
//! which every display (CLI, report, Python) prints.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// What a position column is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "snake_case")]
pub enum Coordinate {
    /// A joint angle (rad); its force is a torque (N m).
    Angle,
    /// An end-point displacement (m); its force is a force (N).
    Displacement,
}

impl Coordinate {
    /// The quantity FORMAT.md gives a canonical column name, if any.
    pub fn of_name(name: &str) -> Option<Coordinate> {
        let joint = |rest: &str| !rest.is_empty() && rest.bytes().all(|b| b.is_ascii_digit());
        match name {
            "theta" => Some(Coordinate::Angle),
            "x" | "y" | "z" => Some(Coordinate::Displacement),
            _ if name.strip_prefix('q').is_some_and(joint) => Some(Coordinate::Angle),
            _ => None,
        }
    }

    /// The units of an impedance on this coordinate.
    pub fn units(self) -> Units {
        let s = |v: &str| v.to_string();
        match self {
            Coordinate::Angle => Units {
                coordinate: self,
                position: s("rad"),
                force: s("N m"),
                stiffness: s("N m/rad"),
                damping: s("N m s/rad"),
                inertia: s("kg m²"),
            },
            Coordinate::Displacement => Units {
                coordinate: self,
                position: s("m"),
                force: s("N"),
                stiffness: s("N/m"),
                damping: s("N s/m"),
                inertia: s("kg"),
            },
        }
    }
}

/// The units an estimate is in, from what its position column is.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct Units {
    /// What the position column is.
    pub coordinate: Coordinate,
    /// Position (rad or m).
    pub position: String,
    /// Force or torque (N or N m).
    pub force: String,
    /// Stiffness (N m/rad or N/m).
    pub stiffness: String,
    /// Damping, and a reflex gain on velocity (N m s/rad or N s/m).
    pub damping: String,
    /// Inertia (kg m² or kg).
    pub inertia: String,
}

impl Default for Units {
    /// A joint angle's: results written before units were carried were all angular.
    fn default() -> Self {
        Coordinate::Angle.units()
    }
}

/// Largest plausible excursion of an end-point position column (m): a hand
/// perturbed or reaching moves centimetres to tens of centimetres.
pub const PLAUSIBLE_DISPLACEMENT_M: f64 = 1.0;
/// Largest plausible distance of a hand from a frame's origin (m).
pub const PLAUSIBLE_REACH_M: f64 = 3.0;
/// Largest plausible excursion or value of a joint angle column (rad): one turn.
pub const PLAUSIBLE_ANGLE_RAD: f64 = std::f64::consts::TAU;

/// A warning when position column `name`, whose values lie in `range`
/// (min, max in the column's own numbers), moves further or lies further
/// from the origin than a limb can, naming the unit it likely is in. Every
/// stiffness, damping and inertia is then off by that unit's factor (a
/// centimetre column gives K 100 times too small), which no criterion of
/// the fit can see.
pub fn implausible_motion(
    name: &str,
    coordinate: Coordinate,
    range: (f64, f64),
) -> Option<limpid_core::Warning> {
    let n = |v: f64| limpid_core::short_number(v);
    let (lo, hi) = range;
    if !(lo.is_finite() && hi.is_finite() && hi >= lo) {
        return None;
    }
    let (excursion, peak) = (hi - lo, lo.abs().max(hi.abs()));
    let tail = "recordings are in SI units, so every stiffness, damping and inertia here is off by";
    let fix = "(convert the column, or scale it in a channel map)";
    let message = match coordinate {
        Coordinate::Displacement
            if excursion > PLAUSIBLE_DISPLACEMENT_M || peak > PLAUSIBLE_REACH_M =>
        {
            let (what, amount, limit) = if excursion > PLAUSIBLE_DISPLACEMENT_M {
                ("moves", excursion, PLAUSIBLE_DISPLACEMENT_M)
            } else {
                ("reaches", peak, PLAUSIBLE_REACH_M)
            };
            let (unit, factor) = if amount / 100.0 <= limit {
                ("centimetres", 100.0)
            } else {
                ("millimetres", 1000.0)
            };
            let said = if what == "moves" {
                "over the recording"
            } else {
                "from the frame's origin"
            };
            format!(
                "position {name} {what} {} m {said}, more than a limb can; it looks like {unit} ({} m): {tail} a factor {} {fix}",
                n(amount),
                n(amount / factor),
                n(factor)
            )
        }
        Coordinate::Angle if excursion > PLAUSIBLE_ANGLE_RAD || peak > PLAUSIBLE_ANGLE_RAD => {
            let amount = excursion.max(peak);
            format!(
                "joint angle {name} spans {} rad, more than a turn; it looks like degrees ({} rad): {tail} a factor 57.3 {fix}",
                n(amount),
                n(amount.to_radians())
            )
        }
        _ => return None,
    };
    Some(limpid_core::Warning::new(
        limpid_core::WarningCode::ImplausibleUnits,
        message,
    ))
}

/// `(min, max)` of the finite values (`(0, 0)` when there are none).
pub fn range(values: &[f64]) -> (f64, f64) {
    // the vectorised pass (NaN left out); an infinity found: again, finite values only
    let (lo, hi) = match limpid_core::trial::extremes(values) {
        (lo, hi) if lo == f64::NEG_INFINITY || hi == f64::INFINITY => values
            .iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            }),
        found => found,
    };
    if hi >= lo {
        (lo, hi)
    } else {
        (0.0, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_leaves_out_what_is_not_finite() {
        assert_eq!(range(&[1.0, f64::NAN, -2.0, 3.0]), (-2.0, 3.0));
        assert_eq!(range(&[1.0, f64::INFINITY, -2.0]), (-2.0, 1.0));
        assert_eq!(range(&[f64::NEG_INFINITY, 5.0, 4.0]), (4.0, 5.0));
        assert_eq!(range(&[f64::NAN, f64::INFINITY]), (0.0, 0.0));
        assert_eq!(range(&[]), (0.0, 0.0));
        let long: Vec<f64> = (0..1001).map(|i| (i as f64 * 0.37).sin()).collect();
        let lo = long.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = long.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(range(&long), (lo, hi));
    }

    #[test]
    fn canonical_names_have_a_quantity_and_others_none() {
        assert_eq!(Coordinate::of_name("q12"), Some(Coordinate::Angle));
        assert_eq!(Coordinate::of_name("theta"), Some(Coordinate::Angle));
        assert_eq!(Coordinate::of_name("y"), Some(Coordinate::Displacement));
        for other in ["q", "qa", "angle", "torque", "xx"] {
            assert_eq!(Coordinate::of_name(other), None, "{other}");
        }
        assert_eq!(Coordinate::Displacement.units().stiffness, "N/m");
        assert_eq!(Units::default().inertia, "kg m²");
    }

    #[test]
    fn a_limb_moving_metres_or_turns_is_said_to_be_in_other_units() {
        use Coordinate::*;
        assert!(implausible_motion("x", Displacement, (0.2, 0.5)).is_none());
        let cm = implausible_motion("x", Displacement, (17.0, 21.0)).unwrap();
        assert!(cm.message.contains("moves 4 m"), "{}", cm.message);
        assert!(
            cm.message.contains("centimetres (0.04 m)"),
            "{}",
            cm.message
        );
        let far = implausible_motion("x", Displacement, (28.0, 28.5)).unwrap();
        assert!(far.message.contains("reaches 28.5 m"), "{}", far.message);
        assert!(
            far.message.contains("centimetres (0.285 m)"),
            "{}",
            far.message
        );
        let mm = implausible_motion("x", Displacement, (0.0, 250.0)).unwrap();
        assert!(
            mm.message.contains("millimetres (0.25 m)"),
            "{}",
            mm.message
        );
        assert!(implausible_motion("q1", Angle, (-1.0, 1.5)).is_none());
        let deg = implausible_motion("q1", Angle, (0.0, 30.0)).unwrap();
        assert!(
            deg.message.contains("degrees (0.5236 rad)"),
            "{}",
            deg.message
        );
        assert!(implausible_motion("x", Displacement, (f64::NAN, 1e9)).is_none());
        assert_eq!(range(&[1.0, f64::NAN, -2.0]), (-2.0, 1.0));
        assert_eq!(range(&[]), (0.0, 0.0));
    }
}
