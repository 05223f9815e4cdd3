//! Stage `refine` (ours, not in seeds 000/001/003): moves each merged detection off the sliding
//! box's stride grid and gives it a size.
//!
//! The papers report a detection at the centre of its winning box, so the centre is only as
//! good as the stride (30 mm: up to 26 mm off even for a perfect classifier) and there is no
//! diameter. Here a sphere is fitted by MSAC ([`pomona_consensus::Msac`], seed 002's 4-point
//! sphere estimator with its fruit-size prior and a geometric least-squares refit on the
//! inliers) to the scene points within `search_radius_m` of the merged box centre — with
//! `facing_camera`, only spheres whose four samples and inliers lie on the side facing the
//! camera, as a convex fruit seen from outside does (the ball also holds leaves and neighbours,
//! and a sphere fitted inside out through them can have the most inliers). The fit
//! replaces the centre and gives the diameter only when it is believable:
//! * at least `min_inliers` points and `min_inlier_fraction` of the gathered points lie within
//!   `inlier_threshold_m` of the sphere (leaves and neighbours in the search ball are outliers);
//! * the radius stays in `radius_range_m` after the refit;
//! * the centre lies behind the visible cap (farther from the camera than its inliers, as the
//!   centre of any convex fruit seen from outside is), and at most `max_shift_m` from the box
//!   centre (farther means the fit found another object than the box's).
//!
//! Otherwise the detection keeps its box centre and no diameter.
//!
//! A sphere fitted to the visible cap pins the radius poorly, and real depth at the silhouette
//! biases it upwards (on the Azure Kinect apples the free fits come out 30–50 mm too large in
//! diameter, and the centre 15–20 mm too far). Training therefore learns a
//! [`RadiusCalibration`] (`radius_calibration`) from the accepted fits that lie inside an
//! annotated fruit, as `shape-fit` does for its candidates; detection then replaces the fitted
//! radius by the calibrated one and refits the centre to the inliers at that radius. The score is never changed, so
//! the ranking (and thus which detections match at a given threshold) changes only through the
//! centres. Fruit are not spheres (peppers are blocky, eggplants long): the sphere is the
//! simplest model whose centre lies *behind* the visible surface, which a centroid of the
//! visible points does not. Every random choice takes `seed`; the result does not depend on the
//! thread count.

use nalgebra::Point3;
use pomona_consensus::{
    Acceptance, Consensus, MsacParams, RadiusCalibration, Sphere, SphereEstimatorParams,
};
use pomona_pipeline::{PipelineError, Stage};
use serde::{Deserialize, Serialize};

use crate::{SceneCloud, ScoredBox, SymmetryError};

/// Parameters of [`CentreRefinement`] (stored in the model as `refinement`; keys missing from the
/// block read the defaults, a model without the block runs with refinement off, as before).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CentreRefinementParams {
    /// Whether detections are refined at all (`false`: box centres, no diameter, as the papers).
    pub enabled: bool,
    /// Scene points within this distance of the merged box centre are fitted, metres (a fruit
    /// radius plus the largest grid offset of a box centre).
    pub search_radius_m: f64,
    /// Points gathered per detection at most (the pixel grid is thinned evenly).
    pub max_points: usize,
    /// Accepted sphere radii `(min, max)`, metres: the fruit-size prior (at most half the 12 cm
    /// box, which is sized to hold the largest fruit; larger spheres were fits to a fruit with
    /// the leaves around it and moved borderline detections off their fruit).
    pub radius_range_m: (f64, f64),
    /// A point within this distance of the sphere is an inlier, metres.
    pub inlier_threshold_m: f64,
    /// MSAC hypotheses per detection.
    pub iterations: usize,
    /// A fit needs at least this many inliers.
    pub min_inliers: usize,
    /// A fit needs at least this share of the gathered points as inliers.
    pub min_inlier_fraction: f64,
    /// A fitted centre farther than this from the box centre is rejected, metres.
    pub max_shift_m: f64,
    /// Whether the sphere is fitted to the side the camera sees only (the camera at the cloud's
    /// origin): every MSAC sample and every inlier must face the camera
    /// ([`SphereEstimatorParams::visible_from`]). The ball gathered around a box holds leaves
    /// and neighbours as well as the fruit; without the test the sphere with most inliers can be
    /// one fitted inside out through them, its centre in front of the points — refused by the
    /// centre-behind test, or, when it passes, off the fruit. Absent in model files from before
    /// it existed: `false`, as they were trained (new training: `true`).
    #[serde(default)]
    pub facing_camera: bool,
    /// Seed of the MSAC samples.
    pub seed: u64,
    /// Fitted radius → fruit radius, learnt by training from the fits inside annotated fruit
    /// (see the module docs); `None` (fewer than five such fits, or older model files): the
    /// fitted radius and centre as they are.
    pub radius_calibration: Option<RadiusCalibration>,
}

impl CentreRefinementParams {
    /// The defaults with refinement off: what a model without a `refinement` block, and the
    /// `viewer-pose` pipeline, run with.
    pub fn disabled() -> Self {
        Self {
            enabled: false,
            ..Self::default()
        }
    }
}

impl Default for CentreRefinementParams {
    fn default() -> Self {
        Self {
            enabled: true,
            search_radius_m: 0.07,
            max_points: 600,
            radius_range_m: (0.015, 0.06),
            inlier_threshold_m: 0.005,
            iterations: 300,
            min_inliers: 30,
            min_inlier_fraction: 0.25,
            max_shift_m: 0.04,
            facing_camera: true,
            seed: 0,
            radius_calibration: None,
        }
    }
}

/// Stage `refine`: sphere-fitted centre and diameter per merged box (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CentreRefinement {
    params: CentreRefinementParams,
    msac: pomona_consensus::Msac,
    estimator: pomona_consensus::SphereEstimator,
}

/// An accepted sphere and its support.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FittedSphere {
    /// The sphere (radius calibrated when the parameters hold a calibration).
    pub sphere: Sphere,
    /// Its inliers counted in image pixels (each gathered point stands for the `step × step`
    /// pixels of the thinned grid it was read on), as shape-fit counts its support.
    pub support_px: usize,
}

/// A merged box after refinement: its centre (fitted, or the box centre) and, when the fit was
/// accepted, the fitted sphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefinedBox {
    /// The merged box (score and symmetry-plane normal unchanged; centre as merged).
    pub merged: ScoredBox,
    /// The accepted fit, if any.
    pub fitted: Option<FittedSphere>,
}

impl RefinedBox {
    /// The accepted sphere, if any.
    pub fn sphere(&self) -> Option<Sphere> {
        self.fitted.map(|f| f.sphere)
    }

    /// The accepted sphere's support in image pixels ([`FittedSphere::support_px`]).
    pub fn support_px(&self) -> Option<usize> {
        self.fitted.map(|f| f.support_px)
    }

    /// The detection centre: the sphere's when accepted, otherwise the box centre.
    pub fn center(&self) -> Point3<f64> {
        self.sphere().map_or(self.merged.center, |s| s.center)
    }

    /// The diameter, metres, when the sphere was accepted.
    pub fn diameter_m(&self) -> Option<f64> {
        self.sphere().map(|s| 2.0 * s.radius_m)
    }
}

impl CentreRefinement {
    /// The stage with validated parameters.
    ///
    /// # Errors
    /// [`SymmetryError::InvalidParameter`] when a distance is not finite and positive, the
    /// radius range is not `0 ≤ min < max`, the inlier fraction is outside `(0, 1]` or a count is
    /// zero.
    pub fn new(params: CentreRefinementParams) -> Result<Self, SymmetryError> {
        let invalid = |name: &'static str, value: f64, reason: &'static str| {
            SymmetryError::InvalidParameter {
                name,
                value,
                reason,
            }
        };
        let bad = |name, value, reason| Err(invalid(name, value, reason));
        for (name, v) in [
            ("refinement.search_radius_m", params.search_radius_m),
            ("refinement.inlier_threshold_m", params.inlier_threshold_m),
            ("refinement.max_shift_m", params.max_shift_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(name, v, "must be finite and > 0");
            }
        }
        let f = params.min_inlier_fraction;
        if !(f > 0.0 && f <= 1.0) {
            return bad("refinement.min_inlier_fraction", f, "must lie in (0, 1]");
        }
        for (name, n) in [
            ("refinement.max_points", params.max_points),
            ("refinement.iterations", params.iterations),
            ("refinement.min_inliers", params.min_inliers),
        ] {
            if n < 4 {
                return bad(name, n as f64, "must be at least 4");
            }
        }
        if let Some(c) = params.radius_calibration {
            if !c.intercept_m.is_finite() {
                return bad(
                    "refinement.radius_calibration.intercept_m",
                    c.intercept_m,
                    "must be finite",
                );
            }
            if !(0.0..=1.0).contains(&c.slope) {
                return bad(
                    "refinement.radius_calibration.slope",
                    c.slope,
                    "must lie in [0, 1]",
                );
            }
        }
        let (lo, hi) = params.radius_range_m;
        let estimator = SphereEstimatorParams {
            radius_range_m: params.radius_range_m,
            max_normal_deviation_rad: None,
            visible_from: params.facing_camera.then(Point3::origin),
        }
        .check()
        .map_err(|_| {
            invalid(
                "refinement.radius_range_m",
                lo,
                "must satisfy 0 <= min < max",
            )
        })?;
        if !hi.is_finite() {
            return bad("refinement.radius_range_m", hi, "max must be finite");
        }
        let msac = MsacParams {
            cost_threshold_m: 2.0 * params.inlier_threshold_m,
            acceptance: Acceptance::Always,
            iterations: params.iterations,
            early_stop_confidence: None,
            inlier_threshold_m: params.inlier_threshold_m,
            refine_threshold_m: Some(params.inlier_threshold_m),
            ..MsacParams::default()
        }
        .check()
        .map_err(|_| {
            invalid(
                "refinement.inlier_threshold_m",
                params.inlier_threshold_m,
                "must be finite and > 0",
            )
        })?;
        Ok(Self {
            params,
            msac,
            estimator,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &CentreRefinementParams {
        &self.params
    }

    /// The scene points within `search_radius_m` of `center`, read on an even pixel grid thinned
    /// to at most about `max_points`, and the grid's pixel step.
    fn gather(&self, cloud: &SceneCloud, center: &Point3<f64>) -> (Vec<Point3<f64>>, usize) {
        let cam = &cloud.camera;
        let r = self.params.search_radius_m;
        let Some(px) = cam.project(center).filter(|_| center.z > r) else {
            return (Vec::new(), 1);
        };
        // Pixel half-width of the ball at its nearest depth.
        let half_px = cam.fx.max(cam.fy) * r / (center.z - r);
        let (w, h) = (cloud.width() as f64, cloud.height() as f64);
        let clamp = |x: f64, n: f64| x.round().clamp(0.0, n - 1.0) as usize;
        let (u0, u1) = (clamp(px.x - half_px, w), clamp(px.x + half_px, w));
        let (v0, v1) = (clamp(px.y - half_px, h), clamp(px.y + half_px, h));
        let area = ((u1 - u0 + 1) * (v1 - v0 + 1)) as f64;
        let step = ((area / self.params.max_points as f64).sqrt().ceil() as usize).max(1);
        let r2 = r * r;
        let mut points = Vec::new();
        for v in (v0..=v1).step_by(step) {
            for u in (u0..=u1).step_by(step) {
                let p = cloud.point(v * cloud.width() + u);
                if (p - center).norm_squared() <= r2 {
                    points.push(p); // NaN fails the test above
                }
            }
        }
        (points, step)
    }

    /// The accepted sphere of the points around `center`, its radius calibrated when the
    /// parameters hold a calibration, with its support, or `None` (see the module docs).
    pub fn fit(&self, cloud: &SceneCloud, center: &Point3<f64>) -> Option<FittedSphere> {
        let p = &self.params;
        let (points, step) = self.gather(cloud, center);
        if points.len() < p.min_inliers {
            return None;
        }
        let fit = self
            .msac
            .fit_seeded(&self.estimator, &points, p.seed)
            .ok()??;
        let sphere = fit.model;
        let inliers = fit.inliers.len();
        let (lo, hi) = p.radius_range_m;
        let mean_range_m = fit
            .inliers
            .iter()
            .map(|&i| points[i].coords.norm())
            .sum::<f64>()
            / inliers.max(1) as f64;
        let believable = inliers >= p.min_inliers
            && inliers as f64 >= p.min_inlier_fraction * points.len() as f64
            && sphere.is_finite()
            && (lo..=hi).contains(&sphere.radius_m)
            && sphere.center.coords.norm() > mean_range_m
            && (sphere.center - center).norm() <= p.max_shift_m;
        if !believable {
            return None;
        }
        let sphere = match &p.radius_calibration {
            Some(c) => {
                let inlier_points: Vec<Point3<f64>> =
                    fit.inliers.iter().map(|&i| points[i]).collect();
                c.apply_to_sphere(&sphere, &inlier_points, p.radius_range_m)
            }
            None => sphere,
        };
        Some(FittedSphere {
            sphere,
            support_px: inliers * step * step,
        })
    }

    /// Every merged box, refined when enabled (boxes in, same order out).
    pub fn refine(&self, cloud: &SceneCloud, merged: &[ScoredBox]) -> Vec<RefinedBox> {
        merged
            .iter()
            .map(|&b| RefinedBox {
                merged: b,
                fitted: self
                    .params
                    .enabled
                    .then(|| self.fit(cloud, &b.center))
                    .flatten(),
            })
            .collect()
    }
}

impl Stage<(&SceneCloud, &[ScoredBox]), Vec<RefinedBox>> for CentreRefinement {
    fn name(&self) -> &'static str {
        "refine"
    }

    fn run(
        &self,
        (cloud, merged): (&SceneCloud, &[ScoredBox]),
    ) -> Result<Vec<RefinedBox>, PipelineError> {
        Ok(self.refine(cloud, merged))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::{PinholeCamera, PointCloud};

    /// A scene of one sphere of radius `r_m` at `c` in front of a far wall, ray-cast exactly.
    fn scene(c: Point3<f64>, r_m: f64) -> SceneCloud {
        let camera = PinholeCamera::new(320, 240, 300.0, 300.0, 159.5, 119.5).unwrap();
        let mut points = Vec::new();
        for v in 0..240 {
            for u in 0..320 {
                let d = camera
                    .back_project(u as f64, v as f64, 1.0)
                    .coords
                    .normalize();
                // |t d − c|² = r²
                let b = d.dot(&c.coords);
                let disc = b * b - (c.coords.norm_squared() - r_m * r_m);
                let t = if disc >= 0.0 {
                    b - disc.sqrt()
                } else {
                    2.0 / d.z
                };
                points.push(Point3::from(d * t).cast::<f32>());
            }
        }
        let cloud = PointCloud::organized(320, 240, points).unwrap();
        SceneCloud::new(camera, cloud).unwrap()
    }

    fn boxed(center: Point3<f64>) -> ScoredBox {
        ScoredBox {
            center,
            score: 1.0,
            symmetry_plane_normal: None,
        }
    }

    #[test]
    fn off_grid_box_moves_to_the_fruit_centre_with_its_diameter() {
        let c = Point3::new(0.03, -0.02, 0.8);
        let cloud = scene(c, 0.04);
        let stage = CentreRefinement::new(CentreRefinementParams::default()).unwrap();
        let off = c + nalgebra::Vector3::new(0.012, -0.015, -0.02);
        let refined = stage.refine(&cloud, &[boxed(off)]);
        let sphere = refined[0].sphere().expect("fit accepted");
        assert!((refined[0].center() - c).norm() < 1e-3, "{sphere:?}");
        assert!((refined[0].diameter_m().unwrap() - 0.08).abs() < 1e-3);
        assert_eq!(refined[0].merged, boxed(off));
    }

    #[test]
    fn support_counts_the_sphere_pixels_whatever_the_thinning() {
        // A 40 mm ball at 0.8 m on a 300 px focal: its disc is π (300 · 0.04 / 0.8)² ≈ 707
        // pixels; the fit sees almost all of it inside the search ball.
        let c = Point3::new(0.0, 0.0, 0.8);
        let cloud = scene(c, 0.04);
        let disc_px = std::f64::consts::PI * (300.0_f64 * 0.04 / 0.8).powi(2);
        for max_points in [300, 600, 5000] {
            let stage = CentreRefinement::new(CentreRefinementParams {
                max_points,
                ..CentreRefinementParams::default()
            })
            .unwrap();
            let refined = stage.refine(&cloud, &[boxed(c)]);
            let support = refined[0].support_px().expect("fit accepted") as f64;
            assert!(
                (0.7 * disc_px..=1.3 * disc_px).contains(&support),
                "max_points {max_points}: {support} against {disc_px:.0}"
            );
        }
        // No sphere, no support.
        let off = CentreRefinement::new(CentreRefinementParams::disabled()).unwrap();
        assert_eq!(off.refine(&cloud, &[boxed(c)])[0].support_px(), None);
    }

    #[test]
    fn a_calibration_sets_the_radius_and_refits_the_centre_at_it() {
        let c = Point3::new(0.03, -0.02, 0.8);
        let cloud = scene(c, 0.04);
        let with = |radius_calibration| {
            CentreRefinement::new(CentreRefinementParams {
                radius_calibration,
                ..Default::default()
            })
            .unwrap()
        };
        let free = with(None).fit(&cloud, &c).expect("fit accepted").sphere;
        // Trusting the fit entirely changes nothing.
        let identity = with(Some(RadiusCalibration {
            intercept_m: 0.0,
            slope: 1.0,
            samples: 9,
        }))
        .fit(&cloud, &c)
        .unwrap()
        .sphere;
        assert!((identity.center - free.center).norm() < 1e-9);
        assert!((identity.radius_m - free.radius_m).abs() < 1e-12);
        // "Fruit here are 35 mm": the radius is set and the centre moves towards the visible
        // cap (by about the radius change: 6.6 mm for 5 mm here, the cap's rim pulls sideways).
        let shrunk = with(Some(RadiusCalibration {
            intercept_m: 0.035,
            slope: 0.0,
            samples: 9,
        }))
        .fit(&cloud, &c)
        .unwrap()
        .sphere;
        assert!((shrunk.radius_m - 0.035).abs() < 1e-12);
        let towards_camera = (free.center - shrunk.center).dot(&c.coords.normalize());
        assert!(
            towards_camera > 0.004 && towards_camera < 0.01,
            "{shrunk:?}"
        );
    }

    #[test]
    fn unbelievable_fits_keep_the_box_centre() {
        let c = Point3::new(0.0, 0.0, 0.8);
        let cloud = scene(c, 0.04);
        let stage = CentreRefinement::new(CentreRefinementParams::default()).unwrap();
        // Only the wall in reach: a plane is no sphere of fruit size.
        let on_wall = Point3::new(0.4, 0.3, 2.0);
        // The fruit more than `max_shift_m` away from the box.
        let far = c + nalgebra::Vector3::new(0.05, 0.0, 0.0);
        for b in [on_wall, far] {
            let r = stage.refine(&cloud, &[boxed(b)]);
            assert_eq!((r[0].center(), r[0].diameter_m()), (b, None), "{b:?}");
        }
        let off = CentreRefinement::new(CentreRefinementParams {
            enabled: false,
            ..Default::default()
        })
        .unwrap();
        assert_eq!(off.refine(&cloud, &[boxed(c)])[0].sphere(), None);
    }

    #[test]
    fn files_from_before_the_facing_test_fit_as_they_were_trained() {
        assert!(CentreRefinementParams::default().facing_camera);
        let older: CentreRefinementParams = serde_json::from_str(r#"{"enabled": true}"#).unwrap();
        assert!(!older.facing_camera);
        let json = serde_json::to_string(&CentreRefinementParams::default()).unwrap();
        let back: CentreRefinementParams = serde_json::from_str(&json).unwrap();
        assert_eq!(back, CentreRefinementParams::default());
    }

    #[test]
    fn invalid_parameters_are_rejected() {
        let d = CentreRefinementParams::default();
        for p in [
            CentreRefinementParams {
                search_radius_m: 0.0,
                ..d
            },
            CentreRefinementParams {
                radius_range_m: (0.05, 0.02),
                ..d
            },
            CentreRefinementParams {
                min_inlier_fraction: 1.5,
                ..d
            },
            CentreRefinementParams { iterations: 0, ..d },
            CentreRefinementParams {
                radius_calibration: Some(RadiusCalibration {
                    intercept_m: f64::NAN,
                    slope: 0.5,
                    samples: 9,
                }),
                ..d
            },
            CentreRefinementParams {
                radius_calibration: Some(RadiusCalibration {
                    intercept_m: 0.01,
                    slope: 1.5,
                    samples: 9,
                }),
                ..d
            },
        ] {
            assert!(CentreRefinement::new(p).is_err(), "{p:?}");
        }
    }
}
