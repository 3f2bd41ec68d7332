//! Virtual subjects with known impedance (seed 000 Table I).

use nalgebra::{Matrix3, Vector3};

/// One posture: start point and the impedance there (SI, force applied to the limb).
#[derive(Debug, Clone)]
pub struct Posture {
    /// Start point name.
    pub name: String,
    /// Start point (m).
    pub start: Vector3<f64>,
    /// M (kg).
    pub inertia: Matrix3<f64>,
    /// B (N s/m).
    pub damping: Matrix3<f64>,
    /// K (N/m).
    pub stiffness: Matrix3<f64>,
}

/// One start point of Table I: K diagonal, K off-diagonal (xy, xz, yz), then B and M likewise.
type TableRow = ([f64; 3], [f64; 3], [f64; 3], [f64; 3], [f64; 3], [f64; 3]);

fn sym(d: [f64; 3], off: [f64; 3]) -> Matrix3<f64> {
    // off = [xy, xz, yz]
    Matrix3::new(
        d[0], off[0], off[1], off[0], d[1], off[2], off[1], off[2], d[2],
    )
}

/// Subject 1 of seed 000 Table I at six start points (symmetric parts; N/m, N s/m, kg).
///
/// The table as extracted from the paper is partly garbled; entries that could
/// not be read were filled so that Table II's max/min of the same point hold:
/// S1 B_zz = 86 (Table II B_max), S6 K_zz = 180 and B_zz = 55 (Table II B_max),
/// S2 and S6 inertia rows. Inertia is not identifiable with seed 000's slow
/// perturbations anyway. Start points: octahedron vertices on a 20 cm sphere
/// around (0.40, 0.0, 0.0) m — seed 000 does not give their coordinates.
pub fn seed000_subject1() -> Vec<Posture> {
    let centre = Vector3::new(0.40, 0.0, 0.0);
    let starts = crate::sphere::octahedron_points(centre, 0.20);
    let table: [TableRow; 6] = [
        (
            [1002.0, 250.0, 320.0],
            [12.0, 26.0, 94.0],
            [80.0, 50.0, 86.0],
            [22.0, 25.0, 47.0],
            [0.40, 0.35, 0.19],
            [0.03, 0.02, 0.01],
        ),
        (
            [620.0, 360.0, 449.0],
            [208.0, 86.0, 83.0],
            [139.0, 18.0, 17.0],
            [16.0, 15.0, 11.0],
            [0.18, 0.17, 0.18],
            [0.02, 0.02, 0.01],
        ),
        (
            [429.0, 181.0, 221.0],
            [155.0, 42.0, 44.0],
            [32.0, 25.0, 61.0],
            [17.0, 21.0, 16.0],
            [0.22, 0.36, 0.11],
            [0.02, 0.07, 0.12],
        ),
        (
            [224.0, 67.0, 167.0],
            [55.0, 9.0, 16.0],
            [21.0, 18.0, 35.0],
            [14.0, 12.0, 4.0],
            [0.60, 0.14, 0.18],
            [0.03, 0.08, 0.01],
        ),
        (
            [431.0, 72.0, 68.0],
            [52.0, 23.0, 41.0],
            [96.0, 12.0, 41.0],
            [2.2, 8.1, 1.5],
            [0.24, 0.63, 0.47],
            [0.11, 0.07, 0.32],
        ),
        (
            [690.0, 282.0, 180.0],
            [75.0, 21.0, 60.0],
            [22.0, 18.0, 55.0],
            [8.2, 5.58, 6.68],
            [0.31, 0.22, 0.20],
            [0.08, 0.05, 0.06],
        ),
    ];
    table
        .iter()
        .zip(starts)
        .enumerate()
        .map(|(i, (t, start))| Posture {
            name: format!("S{}", i + 1),
            start,
            stiffness: sym(t.0, t.1),
            damping: sym(t.2, t.3),
            inertia: sym(t.4, t.5),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_matrices_are_positive_definite() {
        for p in seed000_subject1() {
            for m in [p.stiffness, p.damping, p.inertia] {
                let eig = m.symmetric_eigenvalues();
                assert!(eig.iter().all(|v| *v > 0.0), "{}: {eig}", p.name);
            }
        }
    }
}
