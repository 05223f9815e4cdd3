//! A fruit as a circle in the image: what a colour-only detector finds and what 2D evaluation
//! compares.
//!
//! Truth and detections may state the circle directly (`center_px`, `radius_px`), or it follows
//! from what they do state, in this order of preference: the 3D sphere projected with the camera,
//! then the inscribed circle of the pixel box. Keeping the derivation here gives truth and
//! detections one rule, so a 2D score never depends on which side had which keys.

use nalgebra::{Point2, Point3};

use crate::{PinholeCamera, PixelBox};

/// A circle on the image plane, pixels (x right, y down; pixel centres at integers).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageCircle {
    /// Centre, pixels.
    pub center_px: Point2<f64>,
    /// Radius, pixels.
    pub radius_px: f64,
}

impl ImageCircle {
    /// The circle a sphere of `radius_m` centred at `center_in_camera` images to: centred on the
    /// projected centre, radius f·R / √(D² − R²) for a centre at distance D (the cone of rays
    /// tangent to the sphere, measured at the principal point; off-axis the true outline is a
    /// slightly larger ellipse, under 2 % larger at 25° off-axis). `None` when the centre is not
    /// in front of the camera or the camera is inside the sphere.
    ///
    /// ```
    /// use pomona_core::{nalgebra::Point3, ImageCircle, PinholeCamera};
    /// let cam = PinholeCamera::new(640, 480, 500.0, 500.0, 320.0, 240.0).unwrap();
    /// let c = ImageCircle::of_sphere(&cam, &Point3::new(0.0, 0.0, 1.0), 0.04).unwrap();
    /// assert!((c.radius_px - 20.016).abs() < 1e-3);
    /// ```
    pub fn of_sphere(
        camera: &PinholeCamera,
        center_in_camera: &Point3<f64>,
        radius_m: f64,
    ) -> Option<Self> {
        let center_px = camera.project(center_in_camera)?;
        let distance_sq = center_in_camera.coords.norm_squared();
        let r_sq = radius_m * radius_m;
        if !(radius_m > 0.0 && distance_sq > r_sq) {
            return None;
        }
        let focal_px = camera.mean_focal_px();
        Some(Self {
            center_px,
            radius_px: focal_px * radius_m / (distance_sq - r_sq).sqrt(),
        })
    }

    /// The circle inscribed in a box's shorter side, at the box centre.
    pub fn in_box(bbox: &PixelBox) -> Self {
        Self {
            center_px: bbox.center(),
            radius_px: 0.5 * bbox.width().min(bbox.height()),
        }
    }

    /// The circle from whichever description is available: an explicit centre and radius, the
    /// sphere `center_m` ⌀ `diameter_m` projected, or the box (see the module docs). `None` when
    /// none is complete.
    pub fn from_parts(
        camera: &PinholeCamera,
        center_px: Option<Point2<f64>>,
        radius_px: Option<f64>,
        sphere: Option<(Point3<f64>, f64)>,
        bbox: Option<&PixelBox>,
    ) -> Option<Self> {
        if let (Some(center_px), Some(radius_px)) = (center_px, radius_px) {
            if radius_px > 0.0 && center_px.coords.iter().all(|v| v.is_finite()) {
                return Some(Self {
                    center_px,
                    radius_px,
                });
            }
        }
        sphere
            .and_then(|(c, d)| Self::of_sphere(camera, &c, 0.5 * d))
            .or_else(|| bbox.map(Self::in_box))
    }

    /// Distance between the two centres, pixels.
    pub fn center_distance_px(&self, other: &ImageCircle) -> f64 {
        (self.center_px - other.center_px).norm()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> PinholeCamera {
        PinholeCamera::new(640, 480, 600.0, 600.0, 319.5, 239.5).unwrap()
    }

    #[test]
    fn sphere_on_axis_matches_the_tangent_cone() {
        // R = 0.05, D = 0.5: tan(asin(0.1)) = 0.1 / √0.99 = 0.100504 → 60.30 px.
        let c = ImageCircle::of_sphere(&cam(), &Point3::new(0.0, 0.0, 0.5), 0.05).unwrap();
        assert!((c.radius_px - 60.302).abs() < 1e-3, "{}", c.radius_px);
        assert!((c.center_px - Point2::new(319.5, 239.5)).norm() < 1e-9);
    }

    #[test]
    fn behind_camera_or_inside_sphere_has_no_circle() {
        assert!(ImageCircle::of_sphere(&cam(), &Point3::new(0.0, 0.0, -1.0), 0.05).is_none());
        assert!(ImageCircle::of_sphere(&cam(), &Point3::new(0.0, 0.0, 0.03), 0.05).is_none());
    }

    #[test]
    fn explicit_circle_wins_then_sphere_then_box() {
        let bbox = PixelBox::new(10.0, 20.0, 50.0, 80.0).unwrap();
        let sphere = Some((Point3::new(0.0, 0.0, 1.0), 0.08));
        let explicit = ImageCircle::from_parts(
            &cam(),
            Some(Point2::new(5.0, 6.0)),
            Some(7.0),
            sphere,
            Some(&bbox),
        )
        .unwrap();
        assert_eq!(explicit.radius_px, 7.0);
        let projected = ImageCircle::from_parts(&cam(), None, Some(7.0), sphere, Some(&bbox));
        assert!((projected.unwrap().radius_px - 24.019).abs() < 1e-3);
        let boxed = ImageCircle::from_parts(&cam(), None, None, None, Some(&bbox)).unwrap();
        assert_eq!(boxed.radius_px, 20.0);
        assert_eq!(boxed.center_px, Point2::new(30.0, 50.0));
        assert!(ImageCircle::from_parts(&cam(), None, None, None, None).is_none());
    }
}
