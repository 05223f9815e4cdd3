//! The curvature check (not in seed 002): a fruit's surface is curved, so the plane that best
//! fits a candidate's inliers must lie clearly farther from them than its sphere or cylinder
//! does. A patch of soil, a wall or a flat leaf seen through depth noise lets MSAC fit a sphere
//! of fruit size — a cap whose sagitta is within the inlier threshold — that a plane explains
//! just as well.
//!
//! The test compares two root-mean-square distances over the same inliers: to the least-squares
//! plane, and to the fitted shape. A candidate passes when the plane's is at least
//! `min_plane_to_shape_rms` times the shape's. Like the free-space check it is geometry, not
//! learnt, and runs in detection only (training sees every shape, as in the paper).
//!
//! Why a ratio and not an absolute flatness: depth noise sets both distances, and it differs by
//! camera and distance; the ratio asks only whether the curvature explains the points better
//! than a plane does. Measured on the depth pixels within 12 mm of each detected sphere's surface
//! (docs/results.md, "The learnt depth limit widens the arm's reach … a curvature check"): the
//! built-in model's matched real `ak-apples` apples have ratios of 1.2 and above (median about
//! 2.7); the soil patches a model trained on crop-row scenes took for fruit in `wide` scenes
//! (at 1.2–1.5 m) have a median of 1.05.
//!
//! Checked at every depth it costs fruit (a pepper's flat face or a piece of an eggplant is at
//! times the best candidate of its fruit), so training switches it on only beyond the depth its
//! fruit reached ([`crate::SizePrior::apply`]).

use pomona_consensus::nalgebra::Point3;
use pomona_consensus::{Plane, Shape};
use serde::{Deserialize, Serialize};

/// The least ratio of the inliers' RMS distance to their best plane over their RMS distance to
/// the fitted shape.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CurvatureCheck {
    /// A candidate passes when `plane RMS ≥ min_plane_to_shape_rms × shape RMS` (default 1.1;
    /// 1 would drop only shapes no better than a plane).
    pub min_plane_to_shape_rms: f64,
    /// Only shapes centred deeper than this (camera z, metres) are checked (default 0: every
    /// shape). Training sets it to the depth its fruit reached when the arm's reach extends
    /// beyond them ([`crate::SizePrior::apply`]): where the classifier saw fruit it is trusted
    /// alone.
    pub from_depth_m: f64,
}

impl Default for CurvatureCheck {
    fn default() -> Self {
        Self {
            min_plane_to_shape_rms: 1.1,
            from_depth_m: 0.0,
        }
    }
}

impl CurvatureCheck {
    /// Why the setting is unusable, if it is: `(name, value, reason)`.
    pub fn invalid_reason(&self) -> Option<(&'static str, f64, &'static str)> {
        let v = self.min_plane_to_shape_rms;
        if !(v.is_finite() && v >= 0.0) {
            return Some((
                "curvature.min_plane_to_shape_rms",
                v,
                "must be finite and non-negative",
            ));
        }
        let d = self.from_depth_m;
        (!(d.is_finite() && d >= 0.0)).then_some((
            "curvature.from_depth_m",
            d,
            "must be finite and non-negative",
        ))
    }

    /// Whether `shape` fitted to `inliers` is curved enough to be a fruit. Fewer than four
    /// inliers, or inliers exactly on the shape, pass (nothing to compare).
    ///
    /// ```
    /// use pomona_shapefit::CurvatureCheck;
    /// use pomona_consensus::nalgebra::Point3;
    /// use pomona_consensus::{Shape, Sphere};
    ///
    /// // A cap of a 4 cm ball, and a flat patch with 3 mm bumps under a 4 cm sphere.
    /// let ball = Sphere { center: Point3::new(0.0, 0.0, 1.0), radius_m: 0.04 };
    /// let mut cap = Vec::new();
    /// let mut flat = Vec::new();
    /// for i in 0..15 {
    ///     for j in 0..15 {
    ///         let (x, y) = (f64::from(i - 7) * 0.004, f64::from(j - 7) * 0.004);
    ///         cap.push(Point3::new(x, y, 1.0 - (0.04f64.powi(2) - x * x - y * y).sqrt()));
    ///         flat.push(Point3::new(x, y, 0.965 + if (i + j) % 2 == 0 { 0.003 } else { 0.0 }));
    ///     }
    /// }
    /// let check = CurvatureCheck::default();
    /// assert!(check.admits(&Shape::Sphere(ball), &cap));
    /// assert!(!check.admits(&Shape::Sphere(ball), &flat));
    /// ```
    pub fn admits(&self, shape: &Shape, inliers: &[Point3<f64>]) -> bool {
        if shape.center().z <= self.from_depth_m || inliers.len() < 4 {
            return true;
        }
        let shape_rms = rms(inliers, |p| shape.signed_distance(p));
        if shape_rms <= 0.0 {
            return true;
        }
        let Some(plane) = Plane::fit_least_squares(inliers) else {
            return true;
        };
        rms(inliers, |p| plane.signed_distance(p)) >= self.min_plane_to_shape_rms * shape_rms
    }
}

/// Root mean square of `distance` over `points` (0 without points).
pub(crate) fn rms(points: &[Point3<f64>], distance: impl Fn(&Point3<f64>) -> f64) -> f64 {
    let sum: f64 = points.iter().map(|p| distance(p).powi(2)).sum();
    (sum / points.len().max(1) as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_consensus::nalgebra::{Unit, Vector3};
    use pomona_consensus::{Cylinder, Sphere};

    fn jitter(i: usize) -> f64 {
        // Deterministic ±1 mm noise.
        (((i * 7919) % 13) as f64 / 6.0 - 1.0) * 0.001
    }

    #[test]
    fn noisy_caps_pass_and_noisy_planes_do_not() {
        let check = CurvatureCheck::default();
        let sphere = Sphere {
            center: Point3::new(0.1, -0.05, 1.2),
            radius_m: 0.035,
        };
        let (mut cap, mut flat) = (Vec::new(), Vec::new());
        for i in 0..400 {
            let (u, v) = ((i % 20) as f64 - 9.5, (i / 20) as f64 - 9.5);
            let (x, y) = (u * 0.0025, v * 0.0025);
            let z = (sphere.radius_m.powi(2) - x * x - y * y).sqrt();
            let n = jitter(i);
            cap.push(sphere.center + Vector3::new(x, y, -z - n));
            flat.push(Point3::new(0.1 + x, -0.05 + y, 1.17 + n));
        }
        assert!(check.admits(&Shape::Sphere(sphere), &cap));
        assert!(!check.admits(&Shape::Sphere(sphere), &flat));
        // A limit of 0 admits everything; too few points are admitted.
        let none = CurvatureCheck {
            min_plane_to_shape_rms: 0.0,
            ..check
        };
        assert!(none.admits(&Shape::Sphere(sphere), &flat));
        assert!(check.admits(&Shape::Sphere(sphere), &flat[..3]));
        // Only shapes centred beyond `from_depth_m` are checked.
        let far_only = |d| CurvatureCheck {
            from_depth_m: d,
            ..check
        };
        assert!(far_only(1.25).admits(&Shape::Sphere(sphere), &flat));
        assert!(!far_only(1.15).admits(&Shape::Sphere(sphere), &flat));
    }

    #[test]
    fn a_cylinder_side_passes() {
        let cylinder = Cylinder {
            axis_point: Point3::new(0.0, 0.0, 0.8),
            axis: Unit::new_normalize(Vector3::y()),
            radius_m: 0.03,
            extent_m: Some((-0.06, 0.06)),
        };
        let side: Vec<_> = (0..300)
            .map(|i| {
                let angle = ((i % 15) as f64 / 14.0 - 0.5) * 2.4;
                let y = (i / 15) as f64 * 0.005 - 0.05;
                let r = 0.03 + jitter(i);
                Point3::new(r * angle.sin(), y, 0.8 - r * angle.cos())
            })
            .collect();
        assert!(CurvatureCheck::default().admits(&Shape::Cylinder(cylinder), &side));
    }

    #[test]
    fn unusable_limits_are_named() {
        for v in [f64::NAN, -0.1, f64::INFINITY] {
            let check = CurvatureCheck {
                min_plane_to_shape_rms: v,
                from_depth_m: 0.0,
            };
            assert_eq!(
                check.invalid_reason().map(|r| r.0),
                Some("curvature.min_plane_to_shape_rms")
            );
            let check = CurvatureCheck {
                from_depth_m: v,
                ..CurvatureCheck::default()
            };
            assert_eq!(
                check.invalid_reason().map(|r| r.0),
                Some("curvature.from_depth_m")
            );
        }
        assert!(CurvatureCheck::default().invalid_reason().is_none());
    }
}
