//! Local contour re-detection for the approach tracker (not in seed 004): in a square window
//! around the position the track predicts, run the detector's own colour mask, contours and
//! adaptive edge fit ([`crate::ColorContourDetector::fitted_circles_in`]) and keep the circle
//! most consistent with the track — centre near the predicted centre, radius near the predicted
//! radius.
//!
//! Why: the paper's position check fits a circle to the first boundary pixels of four scans
//! from one point. Where the tracked orange touches another of the same colour, a scan runs on
//! into the neighbour and the circle grows over the pair; where a leaf cuts the fruit in two or
//! its far side is shaded, the scans see one piece and the circle fits that piece. The edge fit
//! works on the curvature of pieces of outline: the outline of two touching fruit is two arcs
//! meeting at a concave notch, which it keeps apart, and the arcs of a fruit either side of a
//! leaf lie on the fruit's circle, which it finds from either piece. Among the circles of the
//! window, the track (where the fruit was, how large, and how fast it grows as the camera
//! closes in) tells which is the target.
//!
//! Cost: the window is a square of side `2 half_side_radii` × the predicted radius, clipped to
//! the image and sampled every k-th pixel so that its side has at most `max_side_samples`
//! samples (k = 1 while the fruit is small); the fitted circles are scaled back to image pixels.
//! Its cost is therefore bounded whatever the fruit's size — about `max_side_samples`² pixel
//! classifications and the mask's contour work — instead of a full frame.
//!
//! Choosing among the circles ([`most_consistent_circle`]): a circle is a candidate when its
//! support (arc over circumference) reaches `min_support`, its centre lies within
//! `max_center_shift_radii` predicted radii of the predicted centre and its radius within a
//! factor `max_radius_ratio` of the predicted one; the candidate of least
//! `shift / r_pred + radius_weight · |ln(r / r_pred)|` is taken. None is a miss: the tracker then
//! falls back to the paper's check and spiral search.

use pomona_core::nalgebra::Point2;
use pomona_core::ColorImage;
use serde::{Deserialize, Serialize};

use crate::ContourCircle;

/// When the tracker runs the local re-detection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Redetect {
    /// Never: the paper's tracker (what track parameters from before this setting mean).
    #[default]
    Off,
    /// Every frame; the paper's check and search only when it finds no consistent circle.
    Always,
    /// Only when the paper's position check fails or gives a circle inconsistent with the
    /// prediction (see [`LocalRedetectParams::doubt_center_radii`] and
    /// [`LocalRedetectParams::doubt_radius_ratio`]).
    OnDoubt,
}

/// Settings of the local re-detection (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LocalRedetectParams {
    /// Half the side of the window, in predicted radii.
    pub half_side_radii: f64,
    /// Largest number of samples along a side of the window; larger windows are sampled every
    /// k-th pixel.
    pub max_side_samples: u32,
    /// Circles need at least this support (arc over circumference).
    pub min_support: f64,
    /// Largest distance of a candidate's centre from the predicted centre, predicted radii.
    pub max_center_shift_radii: f64,
    /// Largest ratio (either way) of a candidate's radius to the predicted radius.
    pub max_radius_ratio: f64,
    /// Weight of `|ln(r / r_pred)|` against the centre shift in predicted radii.
    pub radius_weight: f64,
    /// With [`Redetect::OnDoubt`]: the paper's circle is doubted when its centre lies more than
    /// this many predicted radii from the predicted centre …
    pub doubt_center_radii: f64,
    /// … or its radius differs from the predicted radius by more than this factor.
    pub doubt_radius_ratio: f64,
}

impl Default for LocalRedetectParams {
    fn default() -> Self {
        Self {
            half_side_radii: 2.5,
            max_side_samples: 128,
            min_support: 0.15,
            max_center_shift_radii: 0.8,
            max_radius_ratio: 1.3,
            radius_weight: 1.0,
            doubt_center_radii: 0.15,
            doubt_radius_ratio: 1.1,
        }
    }
}

impl LocalRedetectParams {
    /// Why the settings are unusable, if they are.
    pub fn invalid_reason(&self) -> Option<&'static str> {
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if !positive(self.half_side_radii) {
            Some("local_redetect.half_side_radii must be positive")
        } else if self.max_side_samples < 16 {
            Some("local_redetect.max_side_samples must be at least 16")
        } else if !(self.min_support.is_finite() && self.min_support >= 0.0) {
            Some("local_redetect.min_support must be 0 or positive")
        } else if !positive(self.max_center_shift_radii) {
            Some("local_redetect.max_center_shift_radii must be positive")
        } else if !(self.max_radius_ratio.is_finite() && self.max_radius_ratio >= 1.0) {
            Some("local_redetect.max_radius_ratio must be at least 1")
        } else if !(self.radius_weight.is_finite() && self.radius_weight >= 0.0) {
            Some("local_redetect.radius_weight must be 0 or positive")
        } else if !(self.doubt_center_radii.is_finite() && self.doubt_center_radii >= 0.0) {
            Some("local_redetect.doubt_center_radii must be 0 or positive")
        } else if !(self.doubt_radius_ratio.is_finite() && self.doubt_radius_ratio >= 1.0) {
            Some("local_redetect.doubt_radius_ratio must be at least 1")
        } else {
            None
        }
    }

    /// Whether the circle `(center, radius)` is far enough from the prediction to be doubted.
    pub fn doubts(
        &self,
        (center, radius): (Point2<f64>, f64),
        predicted: (Point2<f64>, f64),
    ) -> bool {
        let (pc, pr) = predicted;
        (center - pc).norm() > self.doubt_center_radii * pr
            || (radius / pr).ln().abs() > self.doubt_radius_ratio.ln()
    }
}

/// A window of an image sampled on a square grid: sample `(i, j)` is image pixel
/// `(x0 + i·step, y0 + j·step)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampledRegion {
    x0: u32,
    y0: u32,
    step: u32,
    cols: usize,
    rows: usize,
}

impl SampledRegion {
    /// The square of half-side `half_px` around `center`, clipped to a `width` × `height`
    /// image, sampled every k-th pixel with the least k that keeps both sides at or below
    /// `max_side_samples` samples; `None` when the clipped window is empty or the inputs are not
    /// finite.
    pub fn around(
        center: Point2<f64>,
        half_px: f64,
        (width, height): (u32, u32),
        max_side_samples: u32,
    ) -> Option<Self> {
        if !(center.x.is_finite() && center.y.is_finite() && half_px.is_finite() && half_px > 0.0) {
            return None;
        }
        let clip = |v: f64, n: u32| v.clamp(0.0, f64::from(n)) as u32;
        let (x0, x1) = (
            clip((center.x - half_px).floor(), width),
            clip((center.x + half_px).ceil() + 1.0, width),
        );
        let (y0, y1) = (
            clip((center.y - half_px).floor(), height),
            clip((center.y + half_px).ceil() + 1.0, height),
        );
        let side = (x1 - x0).max(y1 - y0);
        if x1 <= x0 || y1 <= y0 {
            return None;
        }
        let step = side.div_ceil(max_side_samples.max(1)).max(1);
        Some(Self {
            x0,
            y0,
            step,
            cols: (x1 - x0).div_ceil(step) as usize,
            rows: (y1 - y0).div_ceil(step) as usize,
        })
    }

    /// Samples across and down.
    pub fn size(&self) -> (usize, usize) {
        (self.cols, self.rows)
    }

    /// Image pixels between samples.
    pub fn step(&self) -> u32 {
        self.step
    }

    /// The samples' colours, row-major (black for a sample outside `image`, which a region
    /// made for an image of its size never has).
    pub fn pixels<'a>(&self, image: &'a ColorImage) -> impl Iterator<Item = [u8; 3]> + 'a {
        let Self {
            x0,
            y0,
            step,
            cols,
            rows,
        } = *self;
        (0..rows as u32).flat_map(move |j| {
            (0..cols as u32)
                .map(move |i| image.get(x0 + i * step, y0 + j * step).unwrap_or([0, 0, 0]))
        })
    }

    /// A circle in sample coordinates as a circle in image pixels.
    pub fn circle_to_image(&self, c: ContourCircle) -> ContourCircle {
        let s = f64::from(self.step);
        ContourCircle {
            center_px: Point2::new(
                f64::from(self.x0) + s * c.center_px.x,
                f64::from(self.y0) + s * c.center_px.y,
            ),
            radius_px: s * c.radius_px,
            ..c
        }
    }
}

/// Of `circles`, the one most consistent with the predicted circle `(center, radius)` (see the
/// module docs), or `None` when none is a candidate.
pub fn most_consistent_circle(
    circles: &[ContourCircle],
    (center, radius): (Point2<f64>, f64),
    params: &LocalRedetectParams,
) -> Option<ContourCircle> {
    let max_log = params.max_radius_ratio.ln();
    circles
        .iter()
        .filter(|c| c.support >= params.min_support && c.radius_px > 0.0)
        .filter_map(|c| {
            let shift = (c.center_px - center).norm() / radius;
            let log_ratio = (c.radius_px / radius).ln().abs();
            (shift <= params.max_center_shift_radii && log_ratio <= max_log)
                .then_some((shift + params.radius_weight * log_ratio, c))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, c)| *c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_large_window_is_sampled_and_circles_map_back() {
        let r = SampledRegion::around(Point2::new(100.0, 50.0), 150.0, (640, 480), 128).unwrap();
        // x from 0 to 251, y from 0 to 201: side 252 → step 2.
        assert_eq!(r.step(), 2);
        assert_eq!(r.size(), (126, 101));
        let c = r.circle_to_image(ContourCircle {
            center_px: Point2::new(10.0, 20.0),
            radius_px: 5.0,
            support: 0.5,
        });
        assert_eq!((c.center_px, c.radius_px), (Point2::new(20.0, 40.0), 10.0));
        let small =
            SampledRegion::around(Point2::new(320.0, 240.0), 20.0, (640, 480), 128).unwrap();
        assert_eq!((small.step(), small.size()), (1, (41, 41)));
        let img = ColorImage::filled(640, 480, [1, 2, 3]);
        assert_eq!(small.pixels(&img).count(), 41 * 41);
        assert!(SampledRegion::around(Point2::new(-100.0, 50.0), 20.0, (640, 480), 128).is_none());
        assert!(
            SampledRegion::around(Point2::new(f64::NAN, 50.0), 20.0, (640, 480), 128).is_none()
        );
    }

    #[test]
    fn the_circle_nearest_the_prediction_in_place_and_size_is_chosen() {
        let circle = |x: f64, r: f64, support: f64| ContourCircle {
            center_px: Point2::new(x, 0.0),
            radius_px: r,
            support,
        };
        let p = LocalRedetectParams::default();
        let predicted = (Point2::new(0.0, 0.0), 20.0);
        let circles = [
            circle(30.0, 20.0, 0.5), // a neighbour: too far
            circle(0.0, 40.0, 0.5),  // the pair: too large
            circle(4.0, 21.0, 0.1),  // too little support
            circle(6.0, 19.0, 0.3),
            circle(2.0, 22.0, 0.3),
        ];
        let best = most_consistent_circle(&circles, predicted, &p).unwrap();
        assert_eq!(best.center_px.x, 2.0);
        assert!(most_consistent_circle(&circles[..3], predicted, &p).is_none());
        assert!(p.doubts((Point2::new(5.0, 0.0), 20.0), predicted));
        assert!(p.doubts((Point2::new(0.0, 0.0), 24.0), predicted));
        assert!(!p.doubts((Point2::new(1.0, 0.0), 21.0), predicted));
    }
}
