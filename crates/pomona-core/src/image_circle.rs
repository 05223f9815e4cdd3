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
    /// The circle a sphere of `radius_m` centred at `center_in_camera` images to. The sphere's
    /// outline is the image of the cone of rays tangent to it, an ellipse: on the optical axis a
    /// circle of radius f·R / √(D² − R²) (D the distance to the centre), off the axis stretched
    /// along the line to the principal point by about 1/cos²θ and across it by 1/cosθ, and
    /// centred slightly outward of the projected centre (θ the angle off the axis: at 25° the
    /// outline is 22 % and 10 % larger than on the axis). The circle is the ellipse's centre
    /// and the mean of its two semi-axes — what a circle fitted to the outline finds. Computed
    /// in undistorted coordinates, then mapped through the camera's lens model. `None` when the
    /// centre is not in front of the camera, the camera is inside the sphere, or the tangent
    /// cone reaches 90° off the axis (no bounded outline).
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
        let distance = center_in_camera.coords.norm();
        if !(radius_m > 0.0 && distance > radius_m && center_in_camera.z > 0.0) {
            return None;
        }
        let half_cone = (radius_m / distance).asin();
        let (x, y) = (center_in_camera.x, center_in_camera.y);
        let off_axis = x.hypot(y).atan2(center_in_camera.z);
        if off_axis + half_cone >= std::f64::consts::FRAC_PI_2 {
            return None;
        }
        // Extremes along the radial line, and the half-width across it, at depth 1.
        let (near, far) = ((off_axis - half_cone).tan(), (off_axis + half_cone).tan());
        let radial = 0.5 * (far - near);
        let across = half_cone.sin() / (off_axis.cos().powi(2) - half_cone.sin().powi(2)).sqrt();
        let middle = 0.5 * (far + near);
        let norm = x.hypot(y);
        let (dx, dy) = if norm > 0.0 {
            (x / norm, y / norm)
        } else {
            (0.0, 0.0)
        };
        let center_px = camera.project(&Point3::new(middle * dx, middle * dy, 1.0))?;
        Some(Self {
            center_px,
            radius_px: camera.mean_focal_px() * 0.5 * (radial + across),
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

    /// Whether pixel position `p` lies on or inside the circle.
    pub fn contains(&self, p: &Point2<f64>) -> bool {
        (p - self.center_px).norm_squared() <= self.radius_px * self.radius_px
    }

    /// The fraction of the disc's area inside an image of `width` × `height` pixels (pixel
    /// centres are integers, so the image spans −0.5 to `width − 0.5` across, as
    /// [`PinholeCamera::contains`]): 1 for a disc wholly in view, ½ for one centred on an edge, 0
    /// outside or for a radius that is not positive. The disc is cut into 256
    /// strips of equal width, each clipped to the image's rows (error below 10⁻³).
    ///
    /// ```
    /// use pomona_core::{nalgebra::Point2, ImageCircle};
    /// let on_corner = ImageCircle { center_px: Point2::new(-0.5, -0.5), radius_px: 10.0 };
    /// assert!((on_corner.fraction_inside(640.0, 480.0) - 0.25).abs() < 1e-3);
    /// ```
    pub fn fraction_inside(&self, width: f64, height: f64) -> f64 {
        const STRIPS: usize = 256;
        let r = self.radius_px;
        if !(r > 0.0 && r.is_finite()) {
            return 0.0;
        }
        // Shifted so that the image spans 0..width and 0..height.
        let (cx, cy) = (self.center_px.x + 0.5, self.center_px.y + 0.5);
        let strip = 2.0 * r / STRIPS as f64;
        let (mut inside, mut whole) = (0.0, 0.0);
        for i in 0..STRIPS {
            let u = -r + (i as f64 + 0.5) * strip;
            let half = (r * r - u * u).max(0.0).sqrt();
            whole += half;
            if (0.0..=width).contains(&(cx + u)) {
                inside += ((cy + half).min(height) - (cy - half).max(0.0)).max(0.0) / 2.0;
            }
        }
        if whole > 0.0 {
            (inside / whole).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> PinholeCamera {
        PinholeCamera::new(640, 480, 600.0, 600.0, 319.5, 239.5).unwrap()
    }

    #[test]
    fn the_fraction_inside_the_image_is_the_area_in_view() {
        let at = |x, y, r| ImageCircle {
            center_px: Point2::new(x, y),
            radius_px: r,
        };
        let inside = |c: ImageCircle| c.fraction_inside(640.0, 480.0);
        assert_eq!(inside(at(320.0, 240.0, 50.0)), 1.0);
        assert!((inside(at(-0.5, 240.0, 50.0)) - 0.5).abs() < 1e-3);
        assert!((inside(at(320.0, 479.5, 50.0)) - 0.5).abs() < 1e-3);
        assert!((inside(at(639.5, -0.5, 50.0)) - 0.25).abs() < 1e-3);
        assert_eq!(inside(at(-60.0, 240.0, 50.0)), 0.0);
        assert_eq!(inside(at(320.0, 240.0, 0.0)), 0.0);
        // A cap of height h = r/2 outside: the segment's area is r²(θ − sin θ cos θ) with
        // cos θ = 1/2, so π/3 − √3/4 of r² out of πr².
        let theta = std::f64::consts::FRAC_PI_3;
        let outside = (theta - theta.sin() * theta.cos()) / std::f64::consts::PI;
        assert!((inside(at(320.0, 24.5, 50.0)) - (1.0 - outside)).abs() < 1e-3);
    }

    #[test]
    fn sphere_on_axis_matches_the_tangent_cone() {
        // R = 0.05, D = 0.5: tan(asin(0.1)) = 0.1 / √0.99 = 0.100504 → 60.30 px.
        let c = ImageCircle::of_sphere(&cam(), &Point3::new(0.0, 0.0, 0.5), 0.05).unwrap();
        assert!((c.radius_px - 60.302).abs() < 1e-3, "{}", c.radius_px);
        assert!((c.center_px - Point2::new(319.5, 239.5)).norm() < 1e-9);
    }

    /// The sphere's outline by brute force: the circle where the tangent rays touch it,
    /// projected.
    fn outline(cam: &PinholeCamera, c: &Point3<f64>, r: f64) -> Vec<Point2<f64>> {
        let d2 = c.coords.norm_squared();
        let touch_centre = c.coords * (1.0 - r * r / d2);
        let touch_radius = r * (1.0 - r * r / d2).sqrt();
        let w = c.coords.normalize();
        let u = w.cross(&nalgebra::Vector3::x()).normalize();
        let v = w.cross(&u);
        (0..720)
            .map(|k| {
                let t = k as f64 * std::f64::consts::PI / 360.0;
                let p = touch_centre + touch_radius * (t.cos() * u + t.sin() * v);
                cam.project(&Point3::from(p)).unwrap()
            })
            .collect()
    }

    #[test]
    fn off_axis_the_circle_is_the_outline_ellipses_centre_and_mean_semi_axis() {
        let cam = cam();
        // 25° off the axis, up and to the right, 0.6 m away.
        let dir = nalgebra::Vector3::new(0.8, -0.6, 0.0) * 25f64.to_radians().tan();
        let c = Point3::from((dir + nalgebra::Vector3::z()).normalize() * 0.6);
        let circle = ImageCircle::of_sphere(&cam, &c, 0.04).unwrap();
        let pts = outline(&cam, &c, 0.04);
        let n = pts.len() as f64;
        let mean = pts
            .iter()
            .fold(nalgebra::Vector2::zeros(), |a, p| a + p.coords)
            / n;
        // The outline is symmetric about its centre, so the centroid of evenly spread touch
        // points is near it; the extreme distances along and across the radial line are the
        // semi-axes.
        let radial = (Point2::from(mean) - Point2::new(319.5, 239.5)).normalize();
        let across = nalgebra::Vector2::new(-radial.y, radial.x);
        let extent = |axis: nalgebra::Vector2<f64>| {
            let proj: Vec<f64> = pts.iter().map(|p| p.coords.dot(&axis)).collect();
            let (lo, hi) = proj
                .iter()
                .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
            (0.5 * (hi - lo), 0.5 * (hi + lo))
        };
        let ((a, mid_a), (b, mid_b)) = (extent(radial), extent(across));
        let want_centre = radial * mid_a + across * mid_b;
        assert!(
            (circle.center_px.coords - want_centre).norm() < 0.05,
            "{circle:?} {want_centre}"
        );
        assert!(
            (circle.radius_px - 0.5 * (a + b)).abs() < 0.05,
            "{circle:?} {a} {b}"
        );
        // Larger than the on-axis formula by 22 % and 10 % on the two axes.
        let on_axis = 600.0 * 0.04 / (0.36f64 - 0.0016).sqrt();
        assert!((a / on_axis - 1.22).abs() < 0.02 && (b / on_axis - 1.10).abs() < 0.02);
        // The projected centre lies inside, nearer the principal point than the outline's centre.
        let projected = cam.project(&c).unwrap();
        let outward = (circle.center_px - projected).dot(&radial);
        assert!(
            outward > 0.0 && outward < 0.1 * circle.radius_px,
            "{outward}"
        );
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
