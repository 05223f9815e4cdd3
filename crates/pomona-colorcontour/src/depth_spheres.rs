//! Circles from the fruit's surface in depth (not in seed 004, whose cameras have no depth).
//!
//! The edge fit and the Hough circles read the mask's outline. A fruit that a leaf in front
//! crosses, or whose outline the depth cut notches, keeps most of its surface in view but
//! little of its outline: its arcs are too short, or too many pieces, for a circle. Its depth
//! readings still lie on a sphere. Here each 8-connected component of the fruit mask is
//! back-projected and spheres are extracted from it by MSAC (seed 002's fit, the estimator
//! the shape-fit detector uses, refusing spheres seen inside out), up to `max_spheres` per
//! component; each sphere becomes the image circle of its centre and radius.
//!
//! Its support, the counterpart of the edge fit's arc fraction and the Hough coverage, is the
//! share of `coverage_bins` directions around the circle's centre that hold an inlier reading
//! in the circle's outer half (radius 0.5 to 1.1): a fully seen fruit covers every direction,
//! one half behind a leaf about half of them. So every circle goes through the same size
//! test, scoring and pruning. Samples are drawn with `seed`, so the circles are the same on
//! every run.

use pomona_consensus::{
    extract_repeated, Acceptance, CostFunction, MsacParams, Plane, RepeatLimits, Sphere,
    SphereEstimatorParams, UniformSampler,
};
use pomona_core::nalgebra::{Point2, Point3};
use pomona_core::PinholeCamera;
use serde::{Deserialize, Serialize};

use crate::hough_circles::coverage;
use crate::mask_runs::Runs;
use crate::ContourCircle;

/// The most the extent may enlarge a sphere's projected radius
/// ([`DepthSphereParams::extent_quantile`]): beyond it the inliers run onto a neighbour.
pub const MAX_EXTENT_RATIO: f64 = 1.3;

/// Settings of the depth-sphere circles (a model file may leave any of them out).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DepthSphereParams {
    /// Components with fewer depth readings than this are skipped, and a sphere needs this
    /// many inliers.
    pub min_points: usize,
    /// At most this many readings of a component are fitted (an even stride over them).
    pub max_points: usize,
    /// Spheres extracted per component.
    pub max_spheres: usize,
    /// MSAC hypotheses per sphere.
    pub iterations: usize,
    /// A reading within this distance of a sphere is its inlier, metres.
    pub inlier_m: f64,
    /// The circle's radius is at least this quantile of its inlier pixels' distances from its
    /// centre (plus half a pixel), at most [`MAX_EXTENT_RATIO`] times the sphere's own projected
    /// radius; 0: the sphere's own. A sphere fitted to the visible cap of a fruit comes out small
    /// (time-of-flight cameras read its dim rim too far; on the tuning sets the circles' radii
    /// had a median of 0.89 of the truth's, 0.97 with the extent).
    pub extent_quantile: f64,
    /// Directions around a circle in which its support is counted.
    pub coverage_bins: usize,
    /// A sphere is kept only when its inliers' RMS distance to their least-squares plane is at
    /// least this many times their RMS distance to the sphere: a curved surface, not a patch
    /// of soil or a leaf that a small sphere also fits within the noise (0: no test).
    pub min_plane_to_sphere_rms: f64,
    /// Seed of the samples.
    pub seed: u64,
}

impl Default for DepthSphereParams {
    fn default() -> Self {
        Self {
            min_points: 30,
            max_points: 600,
            max_spheres: 3,
            iterations: 200,
            inlier_m: 0.004,
            extent_quantile: 0.95,
            coverage_bins: 32,
            min_plane_to_sphere_rms: 1.5,
            seed: 1,
        }
    }
}

impl DepthSphereParams {
    /// Why the settings cannot run, as (name, reason), or `None`.
    pub fn problem(&self) -> Option<(&'static str, &'static str)> {
        if self.min_points < 4 {
            return Some(("depth_spheres.min_points", "must be at least 4"));
        }
        if self.max_points < self.min_points {
            return Some(("depth_spheres.max_points", "must be at least min_points"));
        }
        if self.iterations == 0 || self.max_spheres == 0 || self.coverage_bins == 0 {
            return Some((
                "depth_spheres",
                "iterations, max_spheres and coverage_bins must be positive",
            ));
        }
        if !(self.min_plane_to_sphere_rms.is_finite() && self.min_plane_to_sphere_rms >= 0.0) {
            return Some((
                "depth_spheres.min_plane_to_sphere_rms",
                "must be 0 (off) or positive",
            ));
        }
        if !(0.0..=1.0).contains(&self.extent_quantile) {
            return Some(("depth_spheres.extent_quantile", "must lie in [0, 1]"));
        }
        if !(self.inlier_m.is_finite() && self.inlier_m > 0.0) {
            return Some(("depth_spheres.inlier_m", "must be finite and positive"));
        }
        None
    }
}

/// The circles of spheres fitted to the depth readings of each component of `mask`
/// (row-major, the camera's width), radii limited to `radius_range_m`; `depth_m` holds the
/// frame's depth per pixel (non-finite or non-positive: no reading).
pub fn depth_sphere_circles(
    mask: &[bool],
    depth_m: &[f32],
    camera: &PinholeCamera,
    radius_range_m: (f64, f64),
    params: &DepthSphereParams,
) -> Vec<ContourCircle> {
    let width = camera.width as usize;
    if width == 0 || mask.len() != depth_m.len() {
        return Vec::new();
    }
    let Ok(estimator) = (SphereEstimatorParams {
        radius_range_m,
        max_normal_deviation_rad: None,
        visible_from: Some(Point3::origin()),
    })
    .check() else {
        return Vec::new();
    };
    let Ok(msac) = (MsacParams {
        cost_threshold_m: 2.0 * params.inlier_m,
        acceptance: Acceptance::Always,
        iterations: params.iterations,
        early_stop_confidence: Some(0.99),
        cost: CostFunction::TruncatedLinear,
        inlier_threshold_m: params.inlier_m,
        refine_threshold_m: Some(params.inlier_m),
        max_scored_points: Some(256),
    })
    .check() else {
        return Vec::new();
    };
    let limits = RepeatLimits {
        min_points: params.min_points,
        min_inliers: params.min_points,
        max_shapes: params.max_spheres,
    };
    // Each component's pixels with a reading, through the mask's runs.
    let runs = Runs::passing(mask, width, |m| m);
    let mut regions = runs.regions();
    let mut pixels_of: Vec<Vec<(usize, usize)>> = vec![Vec::new(); runs.runs.len()];
    for k in 0..runs.runs.len() {
        let root = regions.find(k);
        let run = &runs.runs[k];
        pixels_of[root].extend(
            (run.x0..run.x1)
                .filter(|&x| {
                    let d = depth_m[run.y * width + x];
                    d.is_finite() && d > 0.0
                })
                .map(|x| (x, run.y)),
        );
    }
    let mut out = Vec::new();
    for (component, pixels) in pixels_of.iter().enumerate() {
        if pixels.len() < params.min_points {
            continue;
        }
        let stride = pixels.len().div_ceil(params.max_points);
        let chosen: Vec<(usize, usize)> = pixels.iter().copied().step_by(stride).collect();
        let points: Vec<Point3<f64>> = chosen
            .iter()
            .map(|&(x, y)| camera.back_project(x as f64, y as f64, depth_m[y * width + x] as f64))
            .collect();
        let seed = params.seed ^ (component as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let Ok(spheres) = extract_repeated(&msac, &estimator, &points, &limits, |round| {
            UniformSampler::new(seed.wrapping_add(round as u64))
        }) else {
            continue;
        };
        for s in spheres {
            let inliers: Vec<Point3<f64>> = s.inliers.iter().map(|&i| points[i]).collect();
            if !is_curved(&inliers, &s.model, params.min_plane_to_sphere_rms) {
                continue;
            }
            let c = s.model.center;
            let Some(center_px) = camera.project(&c) else {
                continue;
            };
            let mut radius_px = camera.mean_focal_px() * s.model.radius_m / c.z;
            if !(radius_px.is_finite() && radius_px > 0.0) {
                continue;
            }
            if params.extent_quantile > 0.0 {
                let mut reach: Vec<f64> = s
                    .inliers
                    .iter()
                    .map(|&i| (pixel_of(chosen[i]) - center_px).norm())
                    .collect();
                reach.sort_by(f64::total_cmp);
                let k = ((reach.len() - 1) as f64 * params.extent_quantile.min(1.0)) as usize;
                let extent = reach[k] + 0.5;
                radius_px = radius_px.max(extent.min(MAX_EXTENT_RATIO * radius_px));
            }
            let outer: Vec<Point2<f64>> = s
                .inliers
                .iter()
                .map(|&i| pixel_of(chosen[i]))
                .filter(|p| {
                    let d = (p - center_px).norm();
                    d >= 0.5 * radius_px && d <= 1.1 * radius_px
                })
                .collect();
            out.push(ContourCircle {
                center_px,
                radius_px,
                support: coverage(&outer, center_px, params.coverage_bins),
            });
        }
    }
    out
}

/// The pixel `(x, y)` as a point.
fn pixel_of((x, y): (usize, usize)) -> Point2<f64> {
    Point2::new(x as f64, y as f64)
}

/// Whether `points` lie on `sphere` at least `ratio` times more closely (RMS) than on their
/// least-squares plane.
fn is_curved(points: &[Point3<f64>], sphere: &Sphere, ratio: f64) -> bool {
    if ratio <= 0.0 {
        return true;
    }
    let Some(plane) = Plane::fit_least_squares(points) else {
        return false;
    };
    let mean_square = |f: &dyn Fn(&Point3<f64>) -> f64| {
        points.iter().map(|p| f(p).powi(2)).sum::<f64>() / points.len() as f64
    };
    let to_plane = mean_square(&|p| plane.signed_distance(p));
    let to_sphere = mean_square(&|p| sphere.signed_distance(p));
    to_plane >= ratio * ratio * to_sphere
}

#[cfg(test)]
mod tests {
    use super::*;

    const RANGE: (f64, f64) = (0.0227, 0.0605);

    fn camera() -> PinholeCamera {
        PinholeCamera::new(200, 160, 300.0, 300.0, 99.5, 79.5).unwrap()
    }

    /// Depth of a sphere (`center`, `radius_m`) seen by `camera()` in front of a wall at
    /// `wall_m`, and the mask of the sphere's pixels for which `keep(x, y)` holds.
    fn scene(
        center: Point3<f64>,
        radius_m: f64,
        wall_m: f32,
        keep: impl Fn(usize, usize) -> bool,
    ) -> (Vec<bool>, Vec<f32>) {
        let cam = camera();
        let (w, h) = (cam.width as usize, cam.height as usize);
        let mut mask = vec![false; w * h];
        let mut depth = vec![wall_m; w * h];
        for y in 0..h {
            for x in 0..w {
                // The ray through the pixel, z = 1: the nearer root of |t·ray − c|² = r².
                let ray = camera().back_project(x as f64, y as f64, 1.0).coords;
                let (a, b) = (ray.norm_squared(), ray.dot(&center.coords));
                let disc = b * b - a * (center.coords.norm_squared() - radius_m * radius_m);
                if disc < 0.0 {
                    continue;
                }
                let t = (b - disc.sqrt()) / a;
                depth[y * w + x] = t as f32;
                mask[y * w + x] = keep(x, y);
            }
        }
        (mask, depth)
    }

    #[test]
    fn a_fruit_a_leaf_crosses_gets_its_circle_from_its_surface() {
        let center = Point3::new(0.02, -0.01, 0.8);
        let cam = camera();
        let expected = cam.project(&center).unwrap();
        let expected_r = 300.0 * 0.04 / 0.8;
        // A leaf 8 px wide across the middle, and the fruit's lower third behind another.
        let (mask, depth) = scene(center, 0.04, 1.2, |x, y| {
            !(x as f64 - expected.x).abs().lt(&4.0) && (y as f64) < expected.y + 5.0
        });
        let circles =
            depth_sphere_circles(&mask, &depth, &cam, RANGE, &DepthSphereParams::default());
        assert_eq!(circles.len(), 2, "one per side of the leaf: {circles:?}");
        for c in &circles {
            assert!((c.center_px - expected).norm() < 0.5, "{c:?}");
            assert!((c.radius_px / expected_r - 1.0).abs() < 0.05, "{c:?}");
            // Each piece covers about a quarter of the directions around the centre.
            assert!(c.support > 0.2 && c.support < 0.5, "{c:?}");
        }
        // The same fruit whole: one circle, covering every direction.
        let (mask, depth) = scene(center, 0.04, 1.2, |_, _| true);
        let circles =
            depth_sphere_circles(&mask, &depth, &cam, RANGE, &DepthSphereParams::default());
        assert_eq!(circles.len(), 1);
        assert!((circles[0].center_px - expected).norm() < 0.5);
        assert!(circles[0].support > 0.95);
    }

    #[test]
    fn a_flat_patch_gives_no_circle_and_the_same_input_the_same_circles() {
        let cam = camera();
        let (w, h) = (200usize, 160usize);
        // A tilted plane 0.9–1.0 m away, its readings rippled by a millimetre.
        let depth: Vec<f32> = (0..w * h)
            .map(|k| {
                (0.9 + 0.1 * (k % w) as f64 / w as f64 + 0.001 * ((k * 7919) % 13) as f64 / 13.0)
                    as f32
            })
            .collect();
        let mask: Vec<bool> = (0..w * h)
            .map(|k| ((k % w) as f64 - 100.0).hypot((k / w) as f64 - 80.0) < 12.0)
            .collect();
        let params = DepthSphereParams::default();
        assert!(depth_sphere_circles(&mask, &depth, &cam, RANGE, &params).is_empty());
        let center = Point3::new(-0.03, 0.02, 0.7);
        let (mask, depth) = scene(center, 0.035, 1.0, |_, _| true);
        let once = depth_sphere_circles(&mask, &depth, &cam, RANGE, &params);
        assert_eq!(
            once,
            depth_sphere_circles(&mask, &depth, &cam, RANGE, &params)
        );
        assert_eq!(once.len(), 1);
    }

    #[test]
    fn bad_settings_are_named() {
        let bad = |p: DepthSphereParams| p.problem().map(|(name, _)| name);
        let ok = DepthSphereParams::default();
        assert_eq!(bad(ok), None);
        assert_eq!(
            bad(DepthSphereParams {
                min_points: 3,
                ..ok
            }),
            Some("depth_spheres.min_points")
        );
        assert_eq!(
            bad(DepthSphereParams {
                max_points: 10,
                ..ok
            }),
            Some("depth_spheres.max_points")
        );
        assert_eq!(
            bad(DepthSphereParams {
                inlier_m: f64::NAN,
                ..ok
            }),
            Some("depth_spheres.inlier_m")
        );
        assert_eq!(
            bad(DepthSphereParams {
                extent_quantile: 1.5,
                ..ok
            }),
            Some("depth_spheres.extent_quantile")
        );
        assert_eq!(
            bad(DepthSphereParams {
                min_plane_to_sphere_rms: -1.0,
                ..ok
            }),
            Some("depth_spheres.min_plane_to_sphere_rms")
        );
    }
}
