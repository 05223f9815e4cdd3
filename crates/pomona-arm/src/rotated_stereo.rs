//! The rotated-camera stereo rig of seed 004 §4.2 as geometry: one camera on the arm takes two
//! shots turned by ±β about the arm's hub, and a fruit seen in both is located in 3D — by the
//! paper's closed form (Eqs. 17–18) or by calibrated triangulation.
//!
//! # Frames (the same convention as `pomona synth --stereo`, `rig.json`)
//! * **Primary camera frame** (OpenCV: x right, y down, z forward, metres): the first shot.
//! * The **pivot** is the arm's hub, `(0, 0, −d)` in the primary frame, `d` =
//!   [`RotatedStereo::pivot_distance_m`]; the rotation axis is vertical (camera y).
//! * The **stereo view** is the primary camera turned by `2β` about that axis towards +x:
//!   `X_stereo = R_y(−2β)·(X_primary − pivot) + pivot`. Baseline `2·d·sin β`.
//! * The **hub frame** is the arm's hub frame of [`crate::ArmJoints`]: origin at the pivot,
//!   y down, z along the bisector of the two optical axes (the primary axis turned by β
//!   towards +x), x to its right: `X_primary = pivot + R_y(β)·X_hub`.
//!
//! # The paper's equations in this convention
//! The seed's image x grows the other way and its depth is measured from the lens towards the
//! hub, so with mirrored normalised coordinates `x = −(u − cx) / fx` (focal length 1) and
//! `f + Z0 = d`, the primary view is the seed's left image, the stereo view its right image,
//! and (X, Z) of Eq. 17 are the hub-frame x and z:
//!
//! ```text
//! x_l = (X cos β + Z sin β) / (d − Z cos β + X sin β)
//! x_r = (X cos β − Z sin β) / (d − Z cos β − X sin β)                 (17)
//! Z   = d (x_r A − x_l B) / (C − D)                                    (18)
//! A = cos β − x_l sin β,  B = cos β + x_r sin β,
//! C = (sin β − x_r cos β)(x_l sin β − cos β),  D = (x_l cos β + sin β)(cos β + x_r sin β)
//! ```
//!
//! X then follows from the left equation of (17) and Y (which the paper leaves out) from the
//! image rows of the two views at their known depths. Both methods take pixel coordinates of
//! the same fruit in the two views, pass them through [`PinholeCamera::normalised`] (which
//! undistorts when the camera records lens distortion; a camera without distortion gives the
//! paper's uncorrected equations) and return the point in the primary camera frame.
//!
//! Triangulation instead turns the stereo view's ray into the primary frame and takes the
//! midpoint of the shortest segment between the two rays; on exact projections both agree.

use nalgebra::{Isometry3, Point2, Point3, Translation3, UnitQuaternion, Vector2, Vector3};
use pomona_core::PinholeCamera;
use serde::{Deserialize, Serialize};

use crate::ArmError;

/// One camera on the arm, shot twice at ±β about the hub: the rig's geometry and intrinsics.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RotatedStereo {
    /// Half the angle between the two shots, `β`, radians.
    pub beta_rad: f64,
    /// Distance from the primary camera centre back to the pivot (the hub), `d`, metres.
    pub pivot_distance_m: f64,
    /// Intrinsics shared by both shots.
    pub camera: PinholeCamera,
}

impl RotatedStereo {
    /// A validated rig: `0 < β < 45°`, `d` finite and positive, a valid camera.
    ///
    /// # Errors
    /// [`ArmError::InvalidParameter`] for β or d out of range or invalid intrinsics.
    pub fn new(
        beta_rad: f64,
        pivot_distance_m: f64,
        camera: PinholeCamera,
    ) -> Result<Self, ArmError> {
        if !(beta_rad > 0.0 && beta_rad < std::f64::consts::FRAC_PI_4) {
            return Err(ArmError::InvalidParameter {
                name: "beta_rad",
                value: beta_rad,
                reason: "must be in (0, π/4)",
            });
        }
        if !(pivot_distance_m.is_finite() && pivot_distance_m > 0.0) {
            return Err(ArmError::InvalidParameter {
                name: "pivot_distance_m",
                value: pivot_distance_m,
                reason: "must be finite and positive",
            });
        }
        if camera.validate().is_err() {
            return Err(ArmError::InvalidParameter {
                name: "camera",
                value: camera.fx,
                reason: "intrinsics must be valid (positive sizes and focal lengths)",
            });
        }
        Ok(Self {
            beta_rad,
            pivot_distance_m,
            camera,
        })
    }

    /// The pivot (the arm's hub) in the primary camera frame.
    pub fn pivot_in_camera(&self) -> Point3<f64> {
        Point3::new(0.0, 0.0, -self.pivot_distance_m)
    }

    /// Distance between the two camera centres, `2·d·sin β`, metres.
    pub fn baseline_m(&self) -> f64 {
        2.0 * self.pivot_distance_m * self.beta_rad.sin()
    }

    /// Rigid motion taking a point in the primary camera frame into the stereo camera frame.
    pub fn stereo_from_camera(&self) -> Isometry3<f64> {
        self.about_pivot(-2.0 * self.beta_rad)
    }

    /// Rigid motion taking a point in the primary camera frame into the hub frame.
    pub fn hub_from_camera(&self) -> Isometry3<f64> {
        let turn = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -self.beta_rad);
        Isometry3::from_parts(Translation3::identity(), turn)
            * Translation3::from(-self.pivot_in_camera().coords)
    }

    /// `point_in_camera` (primary camera frame) expressed in the hub frame.
    pub fn point_in_hub(&self, point_in_camera: &Point3<f64>) -> Point3<f64> {
        self.hub_from_camera() * point_in_camera
    }

    /// Pixel coordinates of `point_in_camera` in the primary and the stereo view (through the
    /// camera's projection, so with its distortion if any); `None` when behind either view.
    pub fn project_pair(
        &self,
        point_in_camera: &Point3<f64>,
    ) -> Option<(Point2<f64>, Point2<f64>)> {
        let primary = self.camera.project(point_in_camera)?;
        let stereo = self
            .camera
            .project(&(self.stereo_from_camera() * point_in_camera))?;
        Some((primary, stereo))
    }

    /// The seed's rotated-camera depth (Eq. 18) with X from Eq. 17 and Y from the image rows:
    /// the fruit seen at `pixel_primary` and `pixel_stereo`, in the primary camera frame.
    ///
    /// # Errors
    /// [`ArmError::NoStereoPoint`] when the pixels are not finite, Eq. 18 is singular, or the
    /// point lies behind either view.
    pub fn locate_paper(
        &self,
        pixel_primary: &Point2<f64>,
        pixel_stereo: &Point2<f64>,
    ) -> Result<Point3<f64>, ArmError> {
        let fail = || no_stereo_point("paper", pixel_primary, pixel_stereo);
        let (in_plane, in_stereo) = self.horizontal_solution(pixel_primary, pixel_stereo)?;
        let (left, right) = (
            self.camera.normalised(pixel_primary),
            self.camera.normalised(pixel_stereo),
        );
        // Y is shared by both frames (the rotation is about it): average the two rows' estimates.
        let y = 0.5 * (left.y * in_plane.z + right.y * in_stereo.z);
        if !y.is_finite() {
            return Err(fail());
        }
        Ok(Point3::new(in_plane.x, y, in_plane.z))
    }

    /// How far, in stereo-view rows, `pixel_stereo` lies from where the primary view's row puts
    /// the fruit that the two columns locate (Eq. 18): `v_stereo − v_predicted`. Zero for exact
    /// projections of one point; the epipolar constraint that the seed's global vertical window
    /// (Eq. 10's `ΔY_M`, the largest offset anywhere in the image) only bounds.
    ///
    /// # Errors
    /// As [`RotatedStereo::locate_paper`].
    pub fn row_residual_px(
        &self,
        pixel_primary: &Point2<f64>,
        pixel_stereo: &Point2<f64>,
    ) -> Result<f64, ArmError> {
        let (in_plane, in_stereo) = self.horizontal_solution(pixel_primary, pixel_stereo)?;
        let y = self.camera.normalised(pixel_primary).y * in_plane.z;
        self.camera
            .project(&Point3::new(in_stereo.x, y, in_stereo.z))
            .map(|predicted| pixel_stereo.y - predicted.y)
            .filter(|r| r.is_finite())
            .ok_or_else(|| no_stereo_point("paper", pixel_primary, pixel_stereo))
    }

    /// Eqs. 17–18 on the two columns alone: the fruit in the horizontal plane through the lenses
    /// (y = 0), in the primary and the stereo camera frames.
    fn horizontal_solution(
        &self,
        pixel_primary: &Point2<f64>,
        pixel_stereo: &Point2<f64>,
    ) -> Result<(Point3<f64>, Point3<f64>), ArmError> {
        let fail = || no_stereo_point("paper", pixel_primary, pixel_stereo);
        let left = self.camera.normalised(pixel_primary);
        let right = self.camera.normalised(pixel_stereo);
        // Mirrored x: the seed's image x.
        let (xl, xr) = (-left.x, -right.x);
        let (sb, cb) = self.beta_rad.sin_cos();
        let d = self.pivot_distance_m;
        let a = cb - xl * sb;
        let b = cb + xr * sb;
        let c = (sb - xr * cb) * (xl * sb - cb);
        let dd = (xl * cb + sb) * (cb + xr * sb);
        let z_hub = d * (xr * a - xl * b) / (c - dd);
        let x_hub = (z_hub * sb + xl * (z_hub * cb - d)) / (xl * sb - cb);
        let in_plane = self.hub_from_camera().inverse() * Point3::new(x_hub, 0.0, z_hub);
        let in_stereo = self.stereo_from_camera() * in_plane;
        if !(in_plane.z > 0.0 && in_stereo.z > 0.0 && in_plane.coords.iter().all(|v| v.is_finite()))
        {
            return Err(fail());
        }
        Ok((in_plane, in_stereo))
    }

    /// Calibrated triangulation: both views' rays in the primary camera frame, and the midpoint
    /// of their closest approach.
    ///
    /// # Errors
    /// [`ArmError::NoStereoPoint`] when the pixels are not finite, the rays are parallel, or the
    /// closest approach lies behind either view.
    pub fn triangulate(
        &self,
        pixel_primary: &Point2<f64>,
        pixel_stereo: &Point2<f64>,
    ) -> Result<Point3<f64>, ArmError> {
        let fail = || no_stereo_point("triangulate", pixel_primary, pixel_stereo);
        let ray = |n: Vector2<f64>| Vector3::new(n.x, n.y, 1.0);
        let camera_from_stereo = self.stereo_from_camera().inverse();
        let (o1, d1) = (Point3::origin(), ray(self.camera.normalised(pixel_primary)));
        let o2 = camera_from_stereo * Point3::origin();
        let d2 = camera_from_stereo.rotation * ray(self.camera.normalised(pixel_stereo));
        // Closest approach of o1 + s·d1 and o2 + t·d2.
        let w = o1 - o2;
        let (a, b, c) = (d1.dot(&d1), d1.dot(&d2), d2.dot(&d2));
        let (dw1, dw2) = (d1.dot(&w), d2.dot(&w));
        let det = a * c - b * b;
        if !(det.is_finite() && det > 1e-15 * a * c) {
            return Err(fail());
        }
        let s = (b * dw2 - c * dw1) / det;
        let t = (a * dw2 - b * dw1) / det;
        if !(s > 0.0 && t > 0.0) {
            return Err(fail());
        }
        let midpoint = Point3::from(((o1 + d1 * s).coords + (o2 + d2 * t).coords) * 0.5);
        if midpoint.coords.iter().all(|v| v.is_finite()) {
            Ok(midpoint)
        } else {
            Err(fail())
        }
    }

    /// The rotation by `angle_rad` about the vertical axis through the pivot, as a motion of
    /// points.
    fn about_pivot(&self, angle_rad: f64) -> Isometry3<f64> {
        let p = self.pivot_in_camera().coords;
        Translation3::from(p)
            * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), angle_rad)
            * Translation3::from(-p)
    }
}

/// The error of a pixel pair that locates no point in front of both views.
fn no_stereo_point(
    method: &'static str,
    pixel_primary: &Point2<f64>,
    pixel_stereo: &Point2<f64>,
) -> ArmError {
    ArmError::NoStereoPoint {
        method,
        primary: [pixel_primary.x, pixel_primary.y],
        stereo: [pixel_stereo.x, pixel_stereo.y],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ArmJoints;

    fn rig(beta_deg: f64, d: f64) -> RotatedStereo {
        let camera = PinholeCamera::new(640, 480, 525.0, 525.0, 319.5, 239.5).unwrap();
        RotatedStereo::new(beta_deg.to_radians(), d, camera).unwrap()
    }

    /// Points over the working volume, in the primary camera frame, seen by both views.
    fn working_volume(rig: &RotatedStereo) -> Vec<Point3<f64>> {
        let mut points = Vec::new();
        for x in [-0.25, -0.1, 0.0, 0.12, 0.3] {
            for y in [-0.2, 0.0, 0.15] {
                for z in [0.5, 0.8, 1.1, 1.5] {
                    let p = Point3::new(x, y, z);
                    if let Some((a, b)) = rig.project_pair(&p) {
                        if rig.camera.contains(&a) && rig.camera.contains(&b) {
                            points.push(p);
                        }
                    }
                }
            }
        }
        points
    }

    #[test]
    fn equation_18_round_trips_exact_projections_below_a_micrometre() {
        for (beta, d) in [(4.0, 0.3), (2.0, 0.3), (8.0, 0.25), (12.0, 0.5)] {
            let rig = rig(beta, d);
            let points = working_volume(&rig);
            assert!(points.len() > 10, "β {beta}: only {} points", points.len());
            for p in points {
                let (a, b) = rig.project_pair(&p).unwrap();
                let paper = rig.locate_paper(&a, &b).unwrap();
                assert!((paper - p).norm() < 1e-6, "β {beta}: {paper} vs {p}");
                let tri = rig.triangulate(&a, &b).unwrap();
                assert!((tri - p).norm() < 1e-6, "β {beta}: {tri} vs {p}");
            }
        }
    }

    #[test]
    fn the_row_residual_is_zero_for_one_point_and_follows_a_row_shift() {
        for (beta, d) in [(4.0, 0.3), (8.0, 1.0)] {
            let rig = rig(beta, d);
            for p in working_volume(&rig) {
                let (a, b) = rig.project_pair(&p).unwrap();
                assert!(rig.row_residual_px(&a, &b).unwrap().abs() < 1e-9, "{p}");
                let moved = Point2::new(b.x, b.y + 5.0);
                assert!((rig.row_residual_px(&a, &moved).unwrap() - 5.0).abs() < 1e-9);
            }
        }
        // The raw offset v_stereo − v_primary of one point is not zero off the centre row (the
        // views see it at different depths): the residual is the tighter test.
        let rig = rig(8.0, 1.0);
        let (a, b) = rig.project_pair(&Point3::new(0.3, 0.25, 0.6)).unwrap();
        assert!((b.y - a.y).abs() > 1.0, "{a} {b}");
    }

    #[test]
    fn the_paper_method_matches_equation_17_in_the_hub_frame() {
        let rig = rig(6.0, 0.25);
        let (sb, cb) = rig.beta_rad.sin_cos();
        let d = rig.pivot_distance_m;
        for (x, z) in [(0.05, 0.9), (-0.2, 1.1), (0.1, 0.6)] {
            let p = rig.hub_from_camera().inverse() * Point3::new(x, 0.02, z);
            let (a, b) = rig.project_pair(&p).unwrap();
            let xl = -(a.x - rig.camera.cx) / rig.camera.fx;
            let xr = -(b.x - rig.camera.cx) / rig.camera.fx;
            assert!((xl - (x * cb + z * sb) / (d - z * cb + x * sb)).abs() < 1e-12);
            assert!((xr - (x * cb - z * sb) / (d - z * cb - x * sb)).abs() < 1e-12);
            let hub = rig.point_in_hub(&rig.locate_paper(&a, &b).unwrap());
            assert!((hub - Point3::new(x, 0.02, z)).norm() < 1e-9);
        }
    }

    #[test]
    fn hub_frame_is_the_bisector_frame_at_the_pivot() {
        let rig = rig(5.0, 0.3);
        assert!(rig.point_in_hub(&rig.pivot_in_camera()).coords.norm() < 1e-12);
        // A point on the bisector is straight ahead of the hub and projects symmetrically.
        let on_bisector = rig.hub_from_camera().inverse() * Point3::new(0.0, 0.0, 1.0);
        let q = ArmJoints::reaching(&rig.point_in_hub(&on_bisector)).unwrap();
        assert!(q.alpha_rad.abs() < 1e-12 && (q.r_m - 1.0).abs() < 1e-12);
        let (a, b) = rig.project_pair(&on_bisector).unwrap();
        assert!(((a.x - rig.camera.cx) + (b.x - rig.camera.cx)).abs() < 1e-9);
        assert!(
            a.x > rig.camera.cx,
            "the bisector lies right of the primary axis"
        );
        // The stereo camera's centre is a baseline away.
        let centre = rig.stereo_from_camera().inverse() * Point3::origin();
        assert!((centre.coords.norm() - rig.baseline_m()).abs() < 1e-12);
    }

    #[test]
    fn disparity_grows_as_fruit_come_closer_and_pixel_noise_shifts_depth() {
        let rig = rig(4.0, 0.3);
        let near = rig.project_pair(&Point3::new(0.0, 0.0, 0.6)).unwrap();
        let far = rig.project_pair(&Point3::new(0.0, 0.0, 1.4)).unwrap();
        // Divergent views: the fruit moves left in the stereo view, more when closer.
        assert!((near.0.x - near.1.x) > (far.0.x - far.1.x));
        // One pixel of disparity error moves the depth but keeps the point in front.
        let shifted = Point2::new(far.1.x + 1.0, far.1.y);
        let p = rig.locate_paper(&far.0, &shifted).unwrap();
        let t = rig.triangulate(&far.0, &shifted).unwrap();
        assert!((p.z - 1.4).abs() > 1e-3 && (t.z - 1.4).abs() > 1e-3);
        assert!((p - t).norm() < 0.01, "{p} {t}");
    }

    #[test]
    fn impossible_pairs_are_errors_and_bad_rigs_are_rejected() {
        let rig = rig(4.0, 0.3);
        let c = Point2::new(rig.camera.cx, rig.camera.cy);
        // Same pixel in both views: the rays diverge, meeting only behind the cameras.
        assert!(rig.triangulate(&c, &c).is_err());
        assert!(rig.locate_paper(&c, &c).is_err());
        let nan = Point2::new(f64::NAN, 1.0);
        assert!(rig.locate_paper(&nan, &c).is_err());
        assert!(rig.triangulate(&nan, &c).is_err());
        assert!(RotatedStereo::new(0.0, 0.3, rig.camera).is_err());
        assert!(RotatedStereo::new(0.1, -0.3, rig.camera).is_err());
        assert!(RotatedStereo::new(0.1, f64::NAN, rig.camera).is_err());
    }
}
