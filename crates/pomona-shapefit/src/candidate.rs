//! A fruit candidate: one shape found by MSAC in one cluster, with the pixels that support it.

use pomona_consensus::nalgebra::{Point3, Unit, Vector3};
use pomona_consensus::Shape;

/// A shape and its inliers.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// The fitted sphere or cylinder (camera frame, metres).
    pub shape: Shape,
    /// Row-major pixel indices of the inliers.
    pub pixels: Vec<usize>,
    /// Inlier positions, camera frame.
    pub points: Vec<Point3<f64>>,
    /// Inlier normals (towards the camera), where defined, when the shape stage estimated them
    /// (its estimators read normals: cylinders, or a sphere normal-angle test); `None`
    /// otherwise, and the descriptor estimates only the normals it samples.
    pub normals: Option<Vec<Option<Unit<Vector3<f64>>>>>,
}

/// The point of `shape`'s core nearest `p`: the sphere's centre, or the point of the
/// cylinder's axis segment (its extent; the axis point without one).
fn nearest_core_point(shape: &Shape, p: &Point3<f64>) -> Point3<f64> {
    match shape {
        Shape::Sphere(s) => s.center,
        Shape::Cylinder(c) => {
            let (lo, hi) = c.extent_m.unwrap_or((0.0, 0.0));
            // max-then-min, not `clamp`, which panics on an empty or NaN extent.
            let t = (p - c.axis_point).dot(&c.axis).max(lo).min(hi);
            c.axis_point + c.axis.into_inner() * t
        }
    }
}

/// Whether one shape's core lies within the other's radius: the distance between their cores
/// (each centre to the other's core, the nearer) is at most the larger radius. Two fruit
/// touching side by side are about the sum of their radii apart; a shape fitted to a piece of
/// a fruit lies inside it.
pub(crate) fn cores_within_larger_radius(a: &Shape, b: &Shape) -> bool {
    let core_distance = (b.center() - nearest_core_point(a, &b.center()))
        .norm()
        .min((a.center() - nearest_core_point(b, &a.center())).norm());
    core_distance <= a.radius_m().max(b.radius_m())
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_consensus::{Cylinder, Sphere};

    fn ball(x: f64, radius_m: f64) -> Shape {
        Shape::Sphere(Sphere {
            center: Point3::new(x, 0.0, 1.0),
            radius_m,
        })
    }

    #[test]
    fn a_piece_lies_within_its_fruit_and_a_neighbour_beside_it() {
        // Two 30 mm fruit touching side by side, their fits 10 % too large: apart.
        assert!(!cores_within_larger_radius(
            &ball(0.0, 0.033),
            &ball(0.06, 0.033)
        ));
        // A 25 mm piece fitted 40 mm from a 45 mm fruit's centre: on it, either way round.
        assert!(cores_within_larger_radius(
            &ball(0.0, 0.045),
            &ball(0.04, 0.025)
        ));
        assert!(cores_within_larger_radius(
            &ball(0.04, 0.025),
            &ball(0.0, 0.045)
        ));
        // An eggplant along x from 0 to 0.15 m, radius 35 mm: a ball 20 mm past its end and
        // 25 mm off the axis is a piece of it (32 mm from the axis segment's end); one 70 mm
        // past the end is not, though both lie level with the axis line.
        let eggplant = Shape::Cylinder(Cylinder {
            axis_point: Point3::new(0.0, 0.0, 1.0),
            axis: Unit::new_normalize(Vector3::x()),
            radius_m: 0.035,
            extent_m: Some((0.0, 0.15)),
        });
        let at = |x: f64, y: f64| {
            Shape::Sphere(Sphere {
                center: Point3::new(x, y, 1.0),
                radius_m: 0.03,
            })
        };
        assert!(cores_within_larger_radius(&eggplant, &at(0.17, 0.025)));
        assert!(cores_within_larger_radius(&at(0.17, 0.025), &eggplant));
        assert!(!cores_within_larger_radius(&eggplant, &at(0.22, 0.0)));
        // Beside the middle of the fruit, touching it: apart.
        assert!(!cores_within_larger_radius(&eggplant, &at(0.075, 0.066)));
    }
}
