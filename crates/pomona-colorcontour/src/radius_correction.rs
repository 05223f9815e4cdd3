//! Correcting the bias of fitted circle radii (not in seed 004).
//!
//! The circles of §3.2 are fitted to the outline of the colour mask, and that outline does not
//! sit exactly on the fruit's silhouette. Pixels where fruit and background blend may pass the
//! colour test (more of them with the colour hysteresis, [`crate::hysteresis_mask`]), which
//! moves the mask's edge outwards. The traced outline runs through the centres of the mask's
//! outer pixels, half a pixel inside that edge. A radius that is off matters twice: the size test
//! (§3.2, 25–55 mm at the measured depth) rejects fruit, and in the overlap pruning an oversized
//! circle covers its neighbour.
//!
//! Measured on the synthetic oranges (docs/results.md, "Circle size and the overlap pruning"),
//! the two effects nearly cancel. Against the outline's half-width across the viewing ray
//! ([`sphere_outline_circle`]), the circles are within a pixel. No correction improved
//! detection, so the default is none.
//!
//! The correction is affine in the fitted radius, `r' = scale · r − offset_px`: a fixed offset
//! models a boundary displaced by a constant distance (blur, threshold, pixel-centre tracing),
//! the scale a bias that grows with the fruit (wider blended rims on larger, closer fruit).
//! [`RadiusCorrection::fit`] learns both from pairs of fitted and true radii (least squares of
//! the true radius on the fitted one). [`RadiusCorrection::NONE`] (scale 1, offset 0) is the
//! paper's behaviour and what model files without the setting mean.

use pomona_core::nalgebra::Point3;
use pomona_core::{ImageCircle, PinholeCamera};
use serde::{Deserialize, Serialize};

use crate::ContourCircle;

/// `r' = scale · r − offset_px`, applied to every fitted circle before the size test, the
/// score and the overlap pruning ([`crate::stages::FruitStage`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RadiusCorrection {
    /// Factor on the fitted radius (1: none).
    pub scale: f64,
    /// Pixels taken off after scaling (0: none; negative grows the circle).
    pub offset_px: f64,
}

impl Default for RadiusCorrection {
    fn default() -> Self {
        Self::NONE
    }
}

/// Fewer matched pairs than this and [`RadiusCorrection::fit`] keeps the radii as they are.
const MIN_PAIRS: usize = 20;

impl RadiusCorrection {
    /// No correction (seed 004's behaviour).
    pub const NONE: Self = Self {
        scale: 1.0,
        offset_px: 0.0,
    };

    /// The corrected radius, pixels; `None` when it is not positive (the circle is dropped).
    pub fn apply(&self, radius_px: f64) -> Option<f64> {
        let r = self.scale * radius_px - self.offset_px;
        (r.is_finite() && r > 0.0).then_some(r)
    }

    /// Whether the correction can be applied: finite, with a positive scale.
    pub fn is_valid(&self) -> bool {
        self.scale.is_finite() && self.scale > 0.0 && self.offset_px.is_finite()
    }

    /// The least-squares line from fitted to true radius over `(fitted_px, truth_px)` pairs
    /// (pairs that are not finite and positive are skipped). When the fitted radii spread over
    /// less than a pixel (standard deviation), or the line's scale is not positive, only a scale
    /// is fitted: the median of true over fitted radius. `None` with fewer than 20 pairs.
    pub fn fit(pairs: &[(f64, f64)]) -> Option<Self> {
        let pairs: Vec<(f64, f64)> = pairs
            .iter()
            .copied()
            .filter(|&(f, t)| f.is_finite() && t.is_finite() && f > 0.0 && t > 0.0)
            .collect();
        if pairs.len() < MIN_PAIRS {
            return None;
        }
        let n = pairs.len() as f64;
        let (mf, mt) = pairs
            .iter()
            .fold((0.0, 0.0), |(a, b), &(f, t)| (a + f / n, b + t / n));
        let (sff, sft) = pairs.iter().fold((0.0, 0.0), |(a, b), &(f, t)| {
            (a + (f - mf) * (f - mf), b + (f - mf) * (t - mt))
        });
        // Fitted radii spread over less than a pixel (standard deviation): a slope is noise.
        let line = (sff / n >= 1.0).then(|| {
            let scale = sft / sff;
            Self {
                scale,
                offset_px: scale * mf - mt,
            }
        });
        let corrected = match line {
            Some(c) if c.is_valid() => c,
            _ => {
                let mut ratios: Vec<f64> = pairs.iter().map(|&(f, t)| t / f).collect();
                let mid = ratios.len() / 2;
                let (_, m, _) = ratios.select_nth_unstable_by(mid, f64::total_cmp);
                Self {
                    scale: *m,
                    offset_px: 0.0,
                }
            }
        };
        corrected.is_valid().then_some(corrected)
    }
}

/// The circle of a sphere's outline across its viewing ray: centred on the projected centre,
/// with the outline's smallest half-width, f R / √(z² − R²) for a centre at depth z (the minor
/// semi-axis of the outline's ellipse). This is the radius [`crate::sphere_from_depth`] turns
/// back into metres, so it is what the correction is fitted against. The 2D evaluation's truth
/// circle ([`ImageCircle::of_sphere`], the mean of the outline ellipse's semi-axes) equals it on
/// the optical axis only; off-axis the outline is about 1 / cos θ wider than on the axis across
/// the ray and 1 / cos² θ along it (θ the angle off the axis: 10 % and 22 % at 25°), so the
/// truth circle is the wider one, by about 5 % at 25°. `None` when the centre is not in front
/// of the camera or the camera is inside the sphere.
pub fn sphere_outline_circle(
    camera: &PinholeCamera,
    center_m: &Point3<f64>,
    radius_m: f64,
) -> Option<ImageCircle> {
    let z2 = center_m.z * center_m.z;
    let r2 = radius_m * radius_m;
    if !(radius_m > 0.0 && center_m.z > 0.0 && z2 > r2) {
        return None;
    }
    Some(ImageCircle {
        center_px: camera.project(center_m)?,
        radius_px: camera.mean_focal_px() * radius_m / (z2 - r2).sqrt(),
    })
}

/// A fitted circle is paired with a true one when its centre is within this fraction of the
/// true radius (half the 2D evaluation's reach: a circle that far off is not of that fruit's
/// outline alone).
const PAIR_REACH: f64 = 0.25;

/// `(fitted, true)` radius pairs of one frame for [`RadiusCorrection::fit`]: each true circle
/// takes the best-supported fitted circle whose centre lies within a quarter of its radius.
/// `truth` should hold only well-visible fruit, whose outline is mostly their silhouette.
pub fn radius_pairs(circles: &[ContourCircle], truth: &[ImageCircle]) -> Vec<(f64, f64)> {
    truth
        .iter()
        .filter_map(|t| {
            circles
                .iter()
                .filter(|c| (c.center_px - t.center_px).norm() <= PAIR_REACH * t.radius_px)
                .max_by(|a, b| a.support.total_cmp(&b.support))
                .map(|c| (c.radius_px, t.radius_px))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{contour_circles, smooth_mask, trace_contours, EdgeFitParams};
    use pomona_core::nalgebra::Point2;

    /// A disc rendered with anti-aliasing (coverage of each pixel by the disc, 8×8 subsamples)
    /// and thresholded at `min_coverage`, as a colour test passes blended rim pixels.
    fn rendered_disc(
        w: usize,
        h: usize,
        (cx, cy, r): (f64, f64, f64),
        min_coverage: f64,
    ) -> Vec<bool> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                let mut inside = 0;
                for a in 0..8 {
                    for b in 0..8 {
                        let (sx, sy) = (
                            x - 0.5 + (a as f64 + 0.5) / 8.0,
                            y - 0.5 + (b as f64 + 0.5) / 8.0,
                        );
                        inside += usize::from((sx - cx).powi(2) + (sy - cy).powi(2) <= r * r);
                    }
                }
                inside as f64 / 64.0 >= min_coverage
            })
            .collect()
    }

    /// The best-supported circle of the pipeline's contour stage and edge fit on `mask`.
    fn fitted_radius(mask: &[bool], w: usize, h: usize, center: Point2<f64>) -> f64 {
        let params = EdgeFitParams::default();
        let smooth = smooth_mask(mask, w, h);
        trace_contours(&smooth, w, h, 20)
            .iter()
            .flat_map(|c| contour_circles(&c.smoothed(params.smoothing_half_window), &params))
            .filter(|c| (c.center_px - center).norm() < 2.0)
            .max_by(|a, b| a.support.total_cmp(&b.support))
            .map(|c| c.radius_px)
            .unwrap_or(f64::NAN)
    }

    #[test]
    fn a_fitted_correction_recovers_rendered_disc_radii_within_a_third_of_a_pixel() {
        let (w, h) = (140, 140);
        // How much of a pixel the disc must cover for the colour test to pass it: a fifth (a
        // blended rim passes), a half, four fifths (only nearly pure fruit pixels pass).
        for coverage in [0.2, 0.5, 0.8] {
            let mut pairs = Vec::new();
            for k in 0..24 {
                let r = 10.0 + 1.3 * k as f64;
                let (cx, cy) = (69.6 + 0.13 * k as f64, 70.2 - 0.07 * k as f64);
                let mask = rendered_disc(w, h, (cx, cy, r), coverage);
                pairs.push((fitted_radius(&mask, w, h, Point2::new(cx, cy)), r));
            }
            let worst = pairs.iter().map(|(f, t)| (f - t).abs()).fold(0.0, f64::max);
            // The outline runs through the centres of the mask's outer pixels, inside its edge:
            // the circles come out small unless blended pixels pass.
            if coverage >= 0.5 {
                assert!(
                    worst > 0.3,
                    "coverage {coverage}: no bias to correct: {pairs:?}"
                );
            }
            let c = RadiusCorrection::fit(&pairs).unwrap();
            // On discs not used in the fit.
            for (r, (cx, cy)) in [
                (13.7, (70.3, 69.8)),
                (27.2, (68.9, 70.6)),
                (38.5, (70.1, 70.4)),
            ] {
                let mask = rendered_disc(w, h, (cx, cy, r), coverage);
                let fitted = fitted_radius(&mask, w, h, Point2::new(cx, cy));
                let corrected = c.apply(fitted).unwrap();
                assert!(
                    (corrected - r).abs() < 0.3,
                    "coverage {coverage}, r {r}: fitted {fitted}, corrected {corrected} with {c:?}"
                );
            }
        }
    }

    #[test]
    fn the_outline_circle_is_the_evaluation_circle_on_axis_and_narrower_off_axis() {
        let cam = PinholeCamera::new(640, 480, 500.0, 500.0, 320.0, 240.0).unwrap();
        let on = Point3::new(0.0, 0.0, 1.0);
        let a = sphere_outline_circle(&cam, &on, 0.04).unwrap();
        let b = ImageCircle::of_sphere(&cam, &on, 0.04).unwrap();
        assert!((a.radius_px - b.radius_px).abs() < 1e-9);
        // 25° off the axis: the outline's half-width across the ray, from the tangent cone.
        let t = 25f64.to_radians();
        let off = Point3::new(t.sin(), 0.0, t.cos());
        let a = sphere_outline_circle(&cam, &off, 0.04).unwrap();
        let b = ImageCircle::of_sphere(&cam, &off, 0.04).unwrap();
        let alpha = (0.04f64).asin();
        // The cone's extreme rays across the ray (in the y direction) hit the image at
        // y = f tan α / cos θ, to first order.
        let across = 500.0 * alpha.tan() / t.cos();
        assert!(
            (a.radius_px - across).abs() < 0.05 * across * 0.04,
            "{} vs {across}",
            a.radius_px
        );
        // The evaluation circle is the mean of the outline ellipse's semi-axes: wider still, by
        // half the stretch along the ray (1.22 against 1.10 at 25°).
        let ratio = b.radius_px / a.radius_px;
        assert!((1.04..1.07).contains(&ratio), "{ratio}");
        assert!(sphere_outline_circle(&cam, &Point3::new(0.0, 0.0, -1.0), 0.04).is_none());
    }

    #[test]
    fn each_true_circle_takes_the_best_supported_circle_near_its_centre() {
        let circle = |x: f64, r: f64, support: f64| ContourCircle {
            center_px: Point2::new(x, 50.0),
            radius_px: r,
            support,
        };
        let truth = [
            ImageCircle {
                center_px: Point2::new(40.0, 50.0),
                radius_px: 20.0,
            },
            ImageCircle {
                center_px: Point2::new(200.0, 50.0),
                radius_px: 20.0,
            },
        ];
        let circles = [
            circle(44.0, 21.0, 0.6), // within a quarter radius (5 px)
            circle(43.0, 12.0, 0.3), // nearer, less support
            circle(47.0, 25.0, 0.9), // best support, but 7 px off
        ];
        assert_eq!(radius_pairs(&circles, &truth), vec![(21.0, 20.0)]);
    }

    #[test]
    fn none_is_the_identity_and_bad_fits_are_refused() {
        assert_eq!(RadiusCorrection::NONE.apply(17.25), Some(17.25));
        assert_eq!(RadiusCorrection::default(), RadiusCorrection::NONE);
        let shrink = RadiusCorrection {
            scale: 1.0,
            offset_px: 2.0,
        };
        assert_eq!(shrink.apply(1.5), None);
        // Too few pairs.
        assert_eq!(RadiusCorrection::fit(&[(10.0, 9.0); 5]), None);
        // Fitted radii all alike: only a scale, the median ratio.
        let c = RadiusCorrection::fit(&[(20.0, 19.0); 30]).unwrap();
        assert!(
            (c.scale - 0.95).abs() < 1e-12 && c.offset_px == 0.0,
            "{c:?}"
        );
        // An exact line is found.
        let pairs: Vec<(f64, f64)> = (0..30)
            .map(|k| {
                let f = 10.0 + k as f64;
                (f, 0.96 * f - 0.7)
            })
            .collect();
        let c = RadiusCorrection::fit(&pairs).unwrap();
        assert!(
            (c.scale - 0.96).abs() < 1e-9 && (c.offset_px - 0.7).abs() < 1e-9,
            "{c:?}"
        );
        // Model files without the setting mean no correction.
        let old: RadiusCorrection =
            serde_json::from_value(serde_json::json!({"scale": 1.0, "offset_px": 0.0})).unwrap();
        assert_eq!(old, RadiusCorrection::NONE);
    }
}
