//! The pinhole camera model shared by colour and depth (they are registered).
//!
//! Split out because every stage — back-projection, projection of detections for overlays, 2D
//! truth matching, synthetic rendering — needs exactly this and nothing else of a frame.

use nalgebra::{Point2, Point3, Vector2};
use serde::{Deserialize, Serialize};

use crate::{CoreError, RadialDistortion};

/// Pinhole intrinsics in pixels, with optional radial lens distortion.
///
/// Projection applies the distortion to normalised coordinates before the intrinsics;
/// back-projection ([`PinholeCamera::back_project`], [`PinholeCamera::normalised`]) removes it,
/// so callers that go through these methods handle distorted images unchanged. Camera files
/// without `distortion` load as undistorted.
///
/// Invariants (checked by [`PinholeCamera::new`] and on deserialisation through `pomona-io`):
/// `width`, `height` > 0, `fx`, `fy` finite and > 0, `cx`, `cy` finite.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PinholeCamera {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x (column), pixels.
    pub cx: f64,
    /// Principal point y (row), pixels.
    pub cy: f64,
    /// Radial lens distortion, if the lens has any worth modelling.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distortion: Option<RadialDistortion>,
}

impl PinholeCamera {
    /// Builds a validated camera.
    ///
    /// # Errors
    /// [`CoreError::InvalidCameraParameter`] when a size is zero, a focal length is not finite and
    /// positive, or a principal-point coordinate is not finite.
    ///
    /// ```
    /// use pomona_core::PinholeCamera;
    /// let cam = PinholeCamera::new(640, 480, 525.0, 525.0, 319.5, 239.5).unwrap();
    /// assert!(PinholeCamera::new(640, 480, f64::NAN, 525.0, 319.5, 239.5).is_err());
    /// # let _ = cam;
    /// ```
    pub fn new(
        width: u32,
        height: u32,
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
    ) -> Result<Self, CoreError> {
        let cam = Self {
            width,
            height,
            fx,
            fy,
            cx,
            cy,
            distortion: None,
        };
        cam.validate()?;
        Ok(cam)
    }

    /// The same intrinsics with `distortion`.
    ///
    /// # Errors
    /// [`CoreError::InvalidCameraParameter`] for a non-finite coefficient.
    pub fn with_distortion(self, distortion: Option<RadialDistortion>) -> Result<Self, CoreError> {
        let cam = Self { distortion, ..self };
        cam.validate()?;
        Ok(cam)
    }

    /// Checks the invariants of a camera built field by field (for example by serde).
    ///
    /// # Errors
    /// As [`PinholeCamera::new`].
    pub fn validate(&self) -> Result<(), CoreError> {
        let bad = |name, value| Err(CoreError::InvalidCameraParameter { name, value });
        if self.width == 0 {
            return bad("width", 0.0);
        }
        if self.height == 0 {
            return bad("height", 0.0);
        }
        for (name, value) in [("fx", self.fx), ("fy", self.fy)] {
            if !(value.is_finite() && value > 0.0) {
                return bad(name, value);
            }
        }
        for (name, value) in [("cx", self.cx), ("cy", self.cy)] {
            if !value.is_finite() {
                return bad(name, value);
            }
        }
        if let Some(d) = &self.distortion {
            d.validate()?;
            // Every pixel must back-project: the inversion has to hold out to the corners.
            let (w, h) = (f64::from(self.width - 1), f64::from(self.height - 1));
            for (u, v) in [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)] {
                let q = Vector2::new((u - self.cx) / self.fx, (v - self.cy) / self.fy);
                if !d.inverts(q) {
                    return Err(CoreError::DistortionNotInvertible {
                        k1: d.k1,
                        k2: d.k2,
                        radius: q.norm(),
                    });
                }
            }
        }
        Ok(())
    }

    /// Number of pixels, `width * height`.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Horizontal field of view in radians.
    pub fn horizontal_fov_rad(&self) -> f64 {
        2.0 * (self.width as f64 / (2.0 * self.fx)).atan()
    }

    /// Back-projects pixel `(u, v)` at depth `depth_m` (z, metres) to a point in the camera frame.
    ///
    /// ```
    /// use pomona_core::PinholeCamera;
    /// let cam = PinholeCamera::new(4, 4, 2.0, 2.0, 1.5, 1.5).unwrap();
    /// let p = cam.back_project(3.5, 1.5, 2.0);
    /// assert_eq!((p.x, p.y, p.z), (2.0, 0.0, 2.0));
    /// ```
    pub fn back_project(&self, u: f64, v: f64, depth_m: f64) -> Point3<f64> {
        match &self.distortion {
            // Without distortion, the arithmetic every earlier figure was computed with.
            None => Point3::new(
                (u - self.cx) * depth_m / self.fx,
                (v - self.cy) * depth_m / self.fy,
                depth_m,
            ),
            Some(_) => {
                let n = self.normalised(&Point2::new(u, v));
                Point3::new(n.x * depth_m, n.y * depth_m, depth_m)
            }
        }
    }

    /// The normalised image coordinates `(x/z, y/z)` of the ray through continuous pixel
    /// coordinates `pixel`: the point on that ray at depth 1 m (undistorted).
    ///
    /// ```
    /// use pomona_core::{nalgebra::Point2, PinholeCamera};
    /// let cam = PinholeCamera::new(4, 4, 2.0, 2.0, 1.5, 1.5).unwrap();
    /// let n = cam.normalised(&Point2::new(3.5, 0.5));
    /// assert_eq!((n.x, n.y), (1.0, -0.5));
    /// ```
    pub fn normalised(&self, pixel: &Point2<f64>) -> Vector2<f64> {
        let seen = Vector2::new((pixel.x - self.cx) / self.fx, (pixel.y - self.cy) / self.fy);
        match &self.distortion {
            Some(d) => d.undistort(seen),
            None => seen,
        }
    }

    /// Projects a point in the camera frame to continuous pixel coordinates `(u, v)`.
    ///
    /// Returns `None` for points on or behind the image plane (`z <= 0`) or not finite. The result
    /// may lie outside the image; use [`PinholeCamera::contains`] to test.
    pub fn project(&self, point_in_camera: &Point3<f64>) -> Option<Point2<f64>> {
        let p = point_in_camera;
        if !(p.z > 0.0 && p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
            return None;
        }
        let Some(d) = &self.distortion else {
            // Without distortion, the arithmetic every earlier figure was computed with.
            return Some(Point2::new(
                self.fx * p.x / p.z + self.cx,
                self.fy * p.y / p.z + self.cy,
            ));
        };
        let n = d.distort(Vector2::new(p.x / p.z, p.y / p.z));
        Some(Point2::new(
            self.fx * n.x + self.cx,
            self.fy * n.y + self.cy,
        ))
    }

    /// The mean of the two focal lengths, pixels: the scale between a length across the view
    /// at depth `z` and its size in the image (`size_px ≈ mean_focal_px · size_m / z`).
    pub fn mean_focal_px(&self) -> f64 {
        0.5 * (self.fx + self.fy)
    }

    /// Whether continuous pixel coordinates fall on a pixel of the image (pixel centres are
    /// integers, so the image spans `[-0.5, width - 0.5)`).
    pub fn contains(&self, pixel: &Point2<f64>) -> bool {
        pixel.x >= -0.5
            && pixel.y >= -0.5
            && pixel.x < self.width as f64 - 0.5
            && pixel.y < self.height as f64 - 0.5
    }

    /// The integer pixel `(u, v)` that contains continuous coordinates, if inside the image.
    pub fn pixel_of(&self, pixel: &Point2<f64>) -> Option<(u32, u32)> {
        self.contains(pixel).then(|| {
            (
                (pixel.x + 0.5).floor() as u32,
                (pixel.y + 0.5).floor() as u32,
            )
        })
    }

    /// The same camera for an image scaled by `factor` (for example 0.5 for half resolution).
    pub fn scaled(&self, factor: f64) -> Self {
        Self {
            width: ((self.width as f64 * factor).round() as u32).max(1),
            height: ((self.height as f64 * factor).round() as u32).max(1),
            fx: self.fx * factor,
            fy: self.fy * factor,
            cx: (self.cx + 0.5) * factor - 0.5,
            cy: (self.cy + 0.5) * factor - 0.5,
            distortion: self.distortion,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinect() -> PinholeCamera {
        PinholeCamera::new(512, 424, 365.0, 365.0, 256.0, 212.0).unwrap()
    }

    #[test]
    fn back_projection_matches_hand_computation() {
        // u = 356, v = 112, z = 0.73: x = 100 * 0.73 / 365 = 0.2, y = -100 * 0.73 / 365 = -0.2.
        let p = kinect().back_project(356.0, 112.0, 0.73);
        assert!((p.x - 0.2).abs() < 1e-12);
        assert!((p.y + 0.2).abs() < 1e-12);
        assert_eq!(p.z, 0.73);
    }

    #[test]
    fn projection_matches_hand_computation() {
        // (0.1, 0.05, 0.5): u = 365 * 0.2 + 256 = 329, v = 365 * 0.1 + 212 = 248.5.
        let px = kinect().project(&Point3::new(0.1, 0.05, 0.5)).unwrap();
        assert!((px.x - 329.0).abs() < 1e-9);
        assert!((px.y - 248.5).abs() < 1e-9);
        assert_eq!(kinect().pixel_of(&px), Some((329, 249)));
    }

    #[test]
    fn projection_inverts_back_projection() {
        let cam = kinect();
        for (u, v, z) in [(0.0, 0.0, 0.4), (511.0, 423.0, 2.5), (100.25, 300.75, 1.0)] {
            let px = cam.project(&cam.back_project(u, v, z)).unwrap();
            assert!((px.x - u).abs() < 1e-9 && (px.y - v).abs() < 1e-9);
        }
    }

    #[test]
    fn points_behind_camera_do_not_project() {
        assert!(kinect().project(&Point3::new(0.0, 0.0, -1.0)).is_none());
        assert!(kinect().project(&Point3::new(0.0, 0.0, 0.0)).is_none());
        assert!(kinect().project(&Point3::new(f64::NAN, 0.0, 1.0)).is_none());
    }

    #[test]
    fn invalid_parameters_are_rejected() {
        assert!(PinholeCamera::new(0, 1, 1.0, 1.0, 0.0, 0.0).is_err());
        assert!(PinholeCamera::new(1, 1, -1.0, 1.0, 0.0, 0.0).is_err());
        assert!(PinholeCamera::new(1, 1, 1.0, f64::INFINITY, 0.0, 0.0).is_err());
        assert!(PinholeCamera::new(1, 1, 1.0, 1.0, f64::NAN, 0.0).is_err());
    }

    #[test]
    fn a_distortion_that_folds_back_inside_the_image_is_refused() {
        // Strong barrel: ρ (1 − ρ²) turns back at ρ = 0.58, inside the Kinect v2's corners (0.9).
        let folded = kinect().with_distortion(Some(RadialDistortion { k1: -1.0, k2: 0.0 }));
        let err = folded.expect_err("folds back").to_string();
        assert!(err.contains("cannot be inverted over the image"), "{err}");
        // A strong pincushion makes the inversion diverge at the corners.
        assert!(kinect()
            .with_distortion(Some(RadialDistortion { k1: 3.0, k2: 2.0 }))
            .is_err());
        // Real lenses' coefficients (and those `pomona synth --distortion` and the arm draw) pass.
        for (k1, k2) in [(-0.2, 0.05), (-0.1, 0.02), (0.1, -0.02), (-0.35, 0.12)] {
            assert!(
                kinect()
                    .with_distortion(Some(RadialDistortion { k1, k2 }))
                    .is_ok(),
                "{k1} {k2}"
            );
        }
    }

    #[test]
    fn distorted_projection_and_back_projection_invert_each_other() {
        let cam = kinect()
            .with_distortion(Some(RadialDistortion {
                k1: -0.18,
                k2: 0.04,
            }))
            .unwrap();
        for (u, v, z) in [(0.0, 0.0, 0.4), (511.0, 423.0, 2.5), (100.25, 300.75, 1.0)] {
            let p = cam.back_project(u, v, z);
            let px = cam.project(&p).unwrap();
            assert!((px.x - u).abs() < 1e-6 && (px.y - v).abs() < 1e-6, "{px}");
        }
        // Barrel: a corner ray lands nearer the centre than the pinhole puts it.
        let p = Point3::new(0.5, 0.4, 1.0);
        let (d, ideal) = (cam.project(&p).unwrap(), kinect().project(&p).unwrap());
        assert!((d.x - cam.cx).abs() < (ideal.x - cam.cx).abs());
        // Old camera files (no `distortion`) load undistorted; new ones round-trip.
        let old = r#"{"width":4,"height":3,"fx":1.0,"fy":1.0,"cx":1.5,"cy":1.0}"#;
        let read: PinholeCamera = serde_json::from_str(old).unwrap();
        assert_eq!(read.distortion, None);
        let json = serde_json::to_string(&cam).unwrap();
        assert_eq!(serde_json::from_str::<PinholeCamera>(&json).unwrap(), cam);
        assert!(!serde_json::to_string(&kinect())
            .unwrap()
            .contains("distortion"));
        let bad = RadialDistortion {
            k1: f64::INFINITY,
            k2: 0.0,
        };
        assert!(kinect().with_distortion(Some(bad)).is_err());
    }

    #[test]
    fn scaling_keeps_rays() {
        let cam = kinect();
        let half = cam.scaled(0.5);
        let p = Point3::new(0.1, -0.07, 0.8);
        let a = cam.project(&p).unwrap();
        let b = half.project(&p).unwrap();
        assert!(((a.x + 0.5) * 0.5 - 0.5 - b.x).abs() < 1e-9);
        assert!(((a.y + 0.5) * 0.5 - 0.5 - b.y).abs() < 1e-9);
    }
}
