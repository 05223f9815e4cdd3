//! Planes: the model, the 3-point estimator, and a least-squares refit on the inliers.
//!
//! A plane is a unit normal `n` and an offset `d` with `n·p + d = 0` for points `p` on it; the
//! residual is the unsigned point-to-plane distance `|n·p + d|`. Three points determine one (the
//! normal is the cross product of two edges); collinear or repeated points do not and are
//! rejected. The refit is the total-least-squares plane of the inliers: through their centroid,
//! normal the direction of least variance ([`crate::normals::pca_normal`], the same PCA as the
//! normals). The plane is the ground or a leaf wall to remove before fruit search, and the
//! building block the Open3D comparison (`scripts/open3d_blocks.sh`) times against
//! `segment_plane`.

use nalgebra::{Point3, Unit, Vector3};
use serde::{Deserialize, Serialize};

use crate::normals::pca_normal;
use crate::{Estimator, Model, Positioned};

/// Relative area below which three points count as collinear: `‖q₁ × q₂‖ / (‖q₁‖‖q₂‖)`, the sine
/// of the angle between the two edges.
const COLLINEAR_TOLERANCE: f64 = 1e-6;

/// A plane `normal · p + offset_m = 0`, metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Plane {
    /// Unit normal (its sign is that of the constructing points' orientation).
    pub normal: Unit<Vector3<f64>>,
    /// Signed offset: minus the distance of the plane from the origin along `normal`, metres.
    pub offset_m: f64,
}

impl Plane {
    /// The plane through `point` with `normal`.
    pub fn through(point: &Point3<f64>, normal: Unit<Vector3<f64>>) -> Self {
        Self {
            normal,
            offset_m: -normal.dot(&point.coords),
        }
    }

    /// The plane through three points, or `None` when they are collinear, repeated or not finite.
    pub fn from_three_points(p: [&Point3<f64>; 3]) -> Option<Self> {
        let q1 = p[1] - p[0];
        let q2 = p[2] - p[0];
        let n = q1.cross(&q2);
        let scale = q1.norm() * q2.norm();
        if !(scale > 0.0 && scale.is_finite() && n.norm() > COLLINEAR_TOLERANCE * scale) {
            return None;
        }
        Some(Self::through(p[0], Unit::new_normalize(n)))
    }

    /// The total-least-squares plane of `points` (non-finite ones skipped): through the centroid,
    /// normal along the least variance. `None` with fewer than three usable points or when they
    /// are collinear.
    pub fn fit_least_squares(points: &[Point3<f64>]) -> Option<Self> {
        let pts: Vec<Point3<f64>> = points
            .iter()
            .filter(|p| p.has_finite_position())
            .copied()
            .collect();
        let normal = pca_normal(&pts)?;
        let centroid = pts.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / pts.len() as f64;
        Some(Self::through(&Point3::from(centroid), normal))
    }

    /// Signed distance of `p`, positive on the side `normal` points to, metres.
    pub fn signed_distance(&self, p: &Point3<f64>) -> f64 {
        self.normal.dot(&p.coords) + self.offset_m
    }
}

impl<D: Positioned> Model<D> for Plane {
    /// `|n·p + d|`, metres.
    fn distance(&self, datum: &D) -> f64 {
        self.signed_distance(&datum.position()).abs()
    }
}

/// Plane hypotheses from three points, refitted by least squares on the inliers.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PlaneEstimator;

impl<D: Positioned> Estimator<D> for PlaneEstimator {
    type Model = Plane;

    fn min_samples(&self) -> usize {
        3
    }

    fn estimate(&self, sample: &[&D]) -> Option<Plane> {
        let [a, b, c] = sample else {
            return None;
        };
        let (pa, pb, pc) = (a.position(), b.position(), c.position());
        Plane::from_three_points([&pa, &pb, &pc])
    }

    fn is_datum_valid(&self, datum: &D) -> bool {
        datum.has_finite_position()
    }

    fn refine(&self, _model: &Plane, data: &[D], inliers: &[usize]) -> Option<Plane> {
        let pts: Vec<Point3<f64>> = inliers.iter().map(|&i| data[i].position()).collect();
        Plane::fit_least_squares(&pts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Consensus, RansacParams, UniformSampler};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn three_points_give_the_plane_and_degenerate_ones_none() {
        let a = Point3::new(0.0, 0.0, 1.0);
        let b = Point3::new(1.0, 0.0, 1.0);
        let c = Point3::new(0.0, 1.0, 1.0);
        let p = Plane::from_three_points([&a, &b, &c]).unwrap();
        assert!((p.normal.into_inner() - Vector3::z()).norm() < 1e-12);
        assert!((p.offset_m + 1.0).abs() < 1e-12);
        assert!((p.signed_distance(&Point3::new(5.0, -3.0, 1.25)) - 0.25).abs() < 1e-12);
        let on_line = Point3::new(2.0, 0.0, 1.0);
        assert!(Plane::from_three_points([&a, &b, &on_line]).is_none());
        assert!(Plane::from_three_points([&a, &a, &c]).is_none());
        let nan = Point3::new(f64::NAN, 0.0, 0.0);
        assert!(Plane::from_three_points([&a, &b, &nan]).is_none());
        assert!(Plane::fit_least_squares(&[a, b, on_line]).is_none());
    }

    #[test]
    fn ransac_finds_a_noisy_plane_among_outliers() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let normal = Unit::new_normalize(Vector3::new(0.1, -0.8, -0.3));
        let truth = Plane::through(&Point3::new(0.0, 0.2, 1.0), normal);
        let (u, v) = {
            let u = normal.cross(&Vector3::x()).normalize();
            (u, normal.cross(&u))
        };
        let mut pts: Vec<Point3<f64>> = (0..3000)
            .map(|_| {
                Point3::new(0.0, 0.2, 1.0)
                    + u * rng.gen_range(-0.5..0.5)
                    + v * rng.gen_range(-0.5..0.5)
                    + normal.into_inner() * rng.gen_range(-0.002..0.002)
            })
            .collect();
        // 40 % clutter in a box around the plane, and an invalid point.
        pts.extend((0..2000).map(|_| {
            Point3::new(
                rng.gen_range(-0.5..0.5),
                rng.gen_range(-0.3..0.7),
                rng.gen_range(0.5..1.5),
            )
        }));
        pts.push(Point3::new(f64::NAN, 0.0, 0.0));
        let ransac = RansacParams {
            inlier_threshold_m: 0.01,
            iterations: 200,
            ..Default::default()
        }
        .check()
        .unwrap();
        let fit = ransac
            .fit(&PlaneEstimator, &pts, &mut UniformSampler::new(1))
            .unwrap()
            .unwrap();
        let angle = fit.model.normal.dot(&truth.normal).abs().min(1.0).acos();
        assert!(angle < 0.01, "{angle} rad");
        let at = Point3::new(0.0, 0.2, 1.0);
        assert!(fit.model.signed_distance(&at).abs() < 1e-3);
        // Every plane point is an inlier; clutter within 10 mm of the plane is too (about 2 %).
        assert!(
            fit.inliers.len() >= 3000 && fit.inliers.len() < 3100,
            "{}",
            fit.inliers.len()
        );
        assert_eq!(fit.valid_points, 5000);
    }
}
