//! Points on spheres: start points (seed 000: six on a 20 cm sphere) and target
//! directions spread evenly (16 at 3 cm in seed 000, 18 at 8 mm in seed 001).
//!
//! Construction: a Fibonacci (golden-angle) spiral, then 2000 steps of
//! repulsion with a steep 1/r^12 potential projected back to the sphere, which
//! approaches the Tammes optimum (largest minimum separation). Deterministic.

use nalgebra::Vector3;

/// `n` unit vectors spread evenly over the sphere.
pub fn even_directions(n: usize) -> Vec<Vector3<f64>> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let mut pts: Vec<Vector3<f64>> = (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            Vector3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect();
    if n < 2 {
        return pts;
    }
    let mut step = 0.01;
    for _ in 0..2000 {
        let forces: Vec<Vector3<f64>> = (0..n)
            .map(|i| {
                let mut f = Vector3::zeros();
                for j in 0..n {
                    if i != j {
                        let d = pts[i] - pts[j];
                        let r = d.norm().max(1e-9);
                        f += d / r.powi(14);
                    }
                }
                f
            })
            .collect();
        for (p, f) in pts.iter_mut().zip(&forces) {
            let tangential = f - *p * p.dot(f);
            let norm = tangential.norm();
            if norm > 0.0 {
                *p = (*p + tangential / norm * step).normalize();
            }
        }
        step *= 0.998;
    }
    pts
}

/// Smallest angle (degrees) between any two of the unit vectors.
/// With fewer than two points there is no pair: 180 (never infinite in a report).
pub fn min_separation_deg(pts: &[Vector3<f64>]) -> f64 {
    let mut best: f64 = 180.0;
    for i in 0..pts.len() {
        for j in i + 1..pts.len() {
            let c = pts[i].dot(&pts[j]).clamp(-1.0, 1.0);
            best = best.min(c.acos().to_degrees());
        }
    }
    best
}

/// The six start points of seed 000: octahedron vertices on a sphere of `radius` around `centre`.
pub fn octahedron_points(centre: Vector3<f64>, radius: f64) -> Vec<Vector3<f64>> {
    [
        Vector3::x(),
        -Vector3::x(),
        Vector3::y(),
        -Vector3::y(),
        Vector3::z(),
        -Vector3::z(),
    ]
    .iter()
    .map(|d| centre + d * radius)
    .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placed_robot_reaches_the_seed000_start_points() {
        // seed 000's six start points on a 20 cm sphere, reached with the home
        // orientation held, once the base is placed behind the workspace facing it
        // (the artemiadis-3d preset's placement); unplaced, the far points are out of reach
        let robot = limpid_robot::Robot::kuka_lwr4()
            .placed([-0.05, 0.0, -0.6], [0.0, 0.0, std::f64::consts::PI]);
        let orientation: nalgebra::Matrix3<f64> =
            robot.fk(&robot.home()).fixed_view::<3, 3>(0, 0).into();
        // start points and the farthest and nearest targets 3 cm around them
        let centre = Vector3::new(0.40, 0.0, 0.0);
        let mut points = octahedron_points(centre, 0.20);
        points.extend(octahedron_points(centre, 0.23));
        points.extend(octahedron_points(centre, 0.17));
        for p in points {
            let q = robot.reach(&p, &orientation, &robot.home()).unwrap();
            let got = robot.fk(&q);
            assert!((got.fixed_view::<3, 1>(0, 3) - p).norm() < 1e-9);
            assert!(robot.check_joint_trajectory(&[q], 1.0).is_ok());
        }
    }

    #[test]
    fn directions_are_unit_and_near_tammes_optimum() {
        // best known minimum separations (Tammes problem): N = 16: 52.24 deg, N = 18: 49.56 deg
        for (n, best) in [(16, 52.24), (18, 49.56)] {
            let d = even_directions(n);
            assert_eq!(d.len(), n);
            assert!(d.iter().all(|p| (p.norm() - 1.0).abs() < 1e-12));
            let sep = min_separation_deg(&d);
            assert!(sep > 0.9 * best && sep <= best + 1e-6, "n = {n}: {sep} deg");
        }
    }
}
