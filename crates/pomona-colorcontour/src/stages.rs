//! The stages of the detector, each behind [`pomona_pipeline::Stage`] so it can be timed,
//! benchmarked or replaced alone: colour lookup → mask cleaning → (with depth, optionally, the
//! depth cut) → contours → edge fitting (and, from the cleaned mask, the Hough circles,
//! optionally the ray circles and, with depth, the circles of spheres fitted to the depth) →
//! circles to fruit.

use pomona_core::nalgebra::Point2;
use pomona_core::{Detection, PinholeCamera, PixelBox, RgbdFrame};
use pomona_pipeline::{PipelineError, Stage};

use crate::disc_share::disc_share;
use crate::{
    close_mask, contour_arcs, cut_at_depth_steps, depth_sphere_circles, hough_circles,
    hysteresis_mask, merge_arcs, prune_overlapping, quantise_probability, ray_circles, smooth_mask,
    sphere_from_depth, sphere_from_size, trace_contours, ColorContourParams, Contour, ContourArc,
    ContourCircle, DepthCutParams, DepthSphereParams, EdgeFitParams, HSigmaLut, HoughCircleParams,
    RayCircleParams, PIPELINE_NAME,
};

/// Per pixel: the lookup table's value at or above the threshold (§3.1), or, with a lower
/// `grow_threshold`, grown into weaker neighbours by [`crate::hysteresis_mask`].
#[derive(Debug, Clone)]
pub struct ColorClassStage {
    /// The compiled perceptron.
    pub lut: HSigmaLut,
    /// Table value (0–255) from which a pixel is fruit.
    pub threshold: u8,
    /// Table value from which a pixel joined to fruit is fruit too (`>= threshold`: off).
    pub grow_threshold: u8,
    /// Smallest confident region, pixels, from which the mask grows.
    pub grow_seed_px: usize,
}

impl Stage<&RgbdFrame, Vec<bool>> for ColorClassStage {
    fn name(&self) -> &'static str {
        "hsigma-lut"
    }

    fn run(&self, frame: &RgbdFrame) -> Result<Vec<bool>, PipelineError> {
        let color = frame.color().ok_or(PipelineError::MissingColor {
            pipeline: PIPELINE_NAME,
        })?;
        let camera = frame.camera();
        Ok(self.classify(
            color.pixels(),
            camera.width as usize,
            camera.height as usize,
        ))
    }
}

impl ColorClassStage {
    /// The stage with the detector's settings: `threshold` from the model's colour table, the
    /// hysteresis from `color_grow_fraction` and `color_grow_seed_px` (off at 1).
    pub fn from_params(lut: HSigmaLut, threshold: u8, params: &ColorContourParams) -> Self {
        let grow_threshold = if params.color_grow_fraction < 1.0 {
            quantise_probability(params.color_threshold * params.color_grow_fraction).min(threshold)
        } else {
            threshold
        };
        Self {
            lut,
            threshold,
            grow_threshold,
            grow_seed_px: params.color_grow_seed_px,
        }
    }

    /// The mask of `pixels`, row-major, `width` × `height` (a whole frame, or a region of one:
    /// the local re-detection of the tracker classifies a window around the fruit).
    pub fn classify(
        &self,
        pixels: impl Iterator<Item = [u8; 3]>,
        width: usize,
        height: usize,
    ) -> Vec<bool> {
        if self.grow_threshold >= self.threshold {
            return pixels
                .map(|rgb| self.lut.value(rgb) >= self.threshold)
                .collect();
        }
        let values: Vec<u8> = pixels.map(|rgb| self.lut.value(rgb)).collect();
        hysteresis_mask(
            &values,
            width,
            height,
            (self.threshold, self.grow_threshold),
            self.grow_seed_px,
        )
    }
}

/// The mask the outlines are read from: optional closing ([`crate::close_mask`]), then the
/// 5×5 Gaussian and threshold of §3.2 ([`crate::smooth_mask`]).
#[derive(Debug, Clone)]
pub struct MaskCleaningStage {
    /// Half-width of the closing square, pixels (0: no closing).
    pub closing_px: usize,
    /// Image width, pixels (the mask is row-major).
    pub width: usize,
}

impl Stage<&[bool], Vec<bool>> for MaskCleaningStage {
    fn name(&self) -> &'static str {
        "mask-cleaning"
    }

    fn run(&self, mask: &[bool]) -> Result<Vec<bool>, PipelineError> {
        let w = self.width.max(1);
        let h = mask.len() / w;
        Ok(smooth_mask(&close_mask(mask, w, h, self.closing_px), w, h))
    }
}

/// Outer borders of the cleaned mask's components, smoothed (see [`crate::Contour`]).
#[derive(Debug, Clone)]
pub struct ContourStage {
    /// Smallest component traced, pixels.
    pub min_component_px: usize,
    /// Moving-average half-width applied to each contour.
    pub smoothing_half_window: usize,
    /// Image width, pixels (the mask is row-major).
    pub width: usize,
}

impl Stage<&[bool], Vec<Contour>> for ContourStage {
    fn name(&self) -> &'static str {
        "contours"
    }

    fn run(&self, mask: &[bool]) -> Result<Vec<Contour>, PipelineError> {
        let w = self.width.max(1);
        let h = mask.len() / w;
        Ok(trace_contours(mask, w, h, self.min_component_px)
            .iter()
            .map(|c| c.smoothed(self.smoothing_half_window))
            .collect())
    }
}

/// The cleaned mask cut at depth steps ([`crate::cut_at_depth_steps`]; not in the paper).
#[derive(Debug, Clone)]
pub struct DepthCutStage {
    /// The cut's settings.
    pub params: DepthCutParams,
    /// Mask width in pixels.
    pub width: usize,
}

/// Input: the mask and the frame's depth, metres per pixel (`NaN` without a reading).
impl Stage<(&[bool], &[f32]), Vec<bool>> for DepthCutStage {
    fn name(&self) -> &'static str {
        "depth-cut"
    }

    fn run(&self, (mask, depth_m): (&[bool], &[f32])) -> Result<Vec<bool>, PipelineError> {
        Ok(cut_at_depth_steps(mask, depth_m, self.width, &self.params))
    }
}

/// Circles of spheres fitted to the depth of each mask component
/// ([`crate::depth_sphere_circles`]; not in the paper).
#[derive(Debug, Clone)]
pub struct DepthSphereStage {
    /// The fit's settings.
    pub params: DepthSphereParams,
    /// The frame's camera (back-projection and projection).
    pub camera: PinholeCamera,
    /// Radii a sphere may have, metres (the size test's).
    pub radius_range_m: (f64, f64),
}

/// Input: the cleaned (and cut) mask and the frame's depth, metres per pixel.
impl Stage<(&[bool], &[f32]), Vec<ContourCircle>> for DepthSphereStage {
    fn name(&self) -> &'static str {
        "depth-spheres"
    }

    fn run(&self, (mask, depth_m): (&[bool], &[f32])) -> Result<Vec<ContourCircle>, PipelineError> {
        Ok(depth_sphere_circles(
            mask,
            depth_m,
            &self.camera,
            self.radius_range_m,
            &self.params,
        ))
    }
}

/// Circles from every contour (Eq. 8, adaptive windows, grouping at centre jumps), then arcs of
/// one circle merged ([`crate::merge_arcs`]).
#[derive(Debug, Clone)]
pub struct EdgeFitStage {
    /// Fitting parameters.
    pub params: EdgeFitParams,
}

/// Input: the contours and the largest circle radius, in the mask's pixels, that merging may
/// produce (see [`crate::merge_arcs`]; `f64::INFINITY` for no limit).
impl Stage<(&[Contour], f64), Vec<ContourCircle>> for EdgeFitStage {
    fn name(&self) -> &'static str {
        "edge-fit"
    }

    fn run(
        &self,
        (contours, max_radius_px): (&[Contour], f64),
    ) -> Result<Vec<ContourCircle>, PipelineError> {
        let arcs: Vec<(usize, ContourArc)> = contours
            .iter()
            .enumerate()
            .flat_map(|(k, c)| {
                contour_arcs(c, &self.params)
                    .into_iter()
                    .map(move |a| (k, a))
            })
            .collect();
        Ok(merge_arcs(contours, arcs, &self.params, max_radius_px))
    }
}

/// Circles from rays cast out of the cleaned mask's inscribed discs ([`crate::ray_circles`];
/// not in the paper), added to the edge fit's.
#[derive(Debug, Clone)]
pub struct RayCircleStage {
    /// Ray settings.
    pub params: RayCircleParams,
    /// Image width, pixels (the mask is row-major).
    pub width: usize,
}

impl Stage<&[bool], Vec<ContourCircle>> for RayCircleStage {
    fn name(&self) -> &'static str {
        "ray-circles"
    }

    fn run(&self, mask: &[bool]) -> Result<Vec<ContourCircle>, PipelineError> {
        Ok(ray_circles(mask, self.width, &self.params))
    }
}

/// Circles voted for by the cleaned mask's outline ([`crate::hough_circles`]; not in the
/// paper), added to the edge fit's.
#[derive(Debug, Clone)]
pub struct HoughCircleStage {
    /// Hough settings.
    pub params: HoughCircleParams,
    /// Image width, pixels (the mask is row-major).
    pub width: usize,
    /// Largest radius searched, pixels (the size test's largest circle; infinite: the
    /// settings' own bound).
    pub max_radius_px: f64,
}

impl Stage<&[bool], Vec<ContourCircle>> for HoughCircleStage {
    fn name(&self) -> &'static str {
        "hough-circles"
    }

    fn run(&self, mask: &[bool]) -> Result<Vec<ContourCircle>, PipelineError> {
        Ok(hough_circles(
            mask,
            self.width,
            self.max_radius_px,
            &self.params,
        ))
    }
}

/// Fraction of the circle's pixels (a grid of at most about 400 inside the image) that are
/// fruit-coloured.
fn color_purity(fruit: &[bool], width: usize, height: usize, c: &ContourCircle) -> f64 {
    let step = (c.radius_px / 10.0).max(1.0);
    let half_steps = (c.radius_px / step).ceil() as i64;
    disc_share(
        c.center_px,
        c.radius_px,
        (step, half_steps),
        (width, height),
        |x, y| fruit[y * width + x],
    )
}

/// From circles to detections: support check, size check, score, overlap pruning, 3D.
///
/// * score = support (arc spanned over circumference) × colour purity (fraction of the circle
///   that is fruit-coloured): a confidence-like value in [0, 1];
/// * size (§3.2): with depth inside the circle, the fruit radius in metres must lie in
///   `radius_range_m` widened by `radius_tolerance`; without, the pixel radius must lie in the range those radii give over
///   `working_distance_m`. Checked *before* the overlap pruning (the paper does it after),
///   so an implausible circle cannot remove a plausible one;
/// * overlap (§3.2): see [`crate::prune_overlapping`], circles ranked by `prune_rank`
///   ([`crate::PruneRank`]), pairs tested by [`crate::clash`] with `prune_center_reach`;
/// * 3D: [`crate::sphere_from_depth`] (centre refitted to the fruit points unless
///   `depth_refit_tolerance_m` is 0), or [`crate::sphere_from_size`] with `prior_radius_m`
///   when the circle has no depth (then `diameter_m` is `None`: it was not measured); in a
///   frame with depth such a circle must lie within the working distance
///   (`depthless_within_reach`).
///
/// `bbox_px` is the square around the circle (not clipped to the image), so the image circle is
/// its centre and half its width.
#[derive(Debug, Clone)]
pub struct FruitStage {
    /// The detector's parameters.
    pub params: ColorContourParams,
}

/// A circle with what the fruit stage measured on it.
struct Measured {
    circle: ContourCircle,
    score: f64,
    center_m: pomona_core::nalgebra::Point3<f64>,
    diameter_m: Option<f64>,
}

impl<'a> Stage<(&'a RgbdFrame, &'a [bool], &'a [ContourCircle]), Vec<Detection>> for FruitStage {
    fn name(&self) -> &'static str {
        "circles-to-fruit"
    }

    fn run(
        &self,
        (frame, fruit, circles): (&'a RgbdFrame, &'a [bool], &'a [ContourCircle]),
    ) -> Result<Vec<Detection>, PipelineError> {
        let p = &self.params;
        let camera = frame.camera();
        let (w, h) = (camera.width as usize, camera.height as usize);
        let (r_lo, r_hi) = p.accepted_radius_range_m();
        let px_range = p.radius_px_range(camera.mean_focal_px());
        let gate_depthless = p.depthless_within_reach && frame.depth().has_readings();
        let measured: Vec<Measured> = circles
            .iter()
            .filter(|c| c.support >= p.min_support)
            .filter_map(|c| {
                let (center_m, diameter_m) = match sphere_from_depth(
                    frame,
                    fruit,
                    c.center_px,
                    c.radius_px,
                    p.depth_core_fraction,
                    p.depth_refit_tolerance_m,
                ) {
                    Some(s) => {
                        if s.radius_m < r_lo || s.radius_m > r_hi {
                            return None;
                        }
                        (s.center_m, Some(2.0 * s.radius_m))
                    }
                    None => {
                        if c.radius_px < px_range.0 || c.radius_px > px_range.1 {
                            return None;
                        }
                        let s =
                            sphere_from_size(camera, c.center_px, c.radius_px, p.prior_radius_m);
                        if gate_depthless && s.center_m.z > p.working_distance_m.1 {
                            return None;
                        }
                        (s.center_m, None)
                    }
                };
                let score = c.support * color_purity(fruit, w, h, c);
                Some(Measured {
                    circle: *c,
                    score,
                    center_m,
                    diameter_m,
                })
            })
            .collect();
        let discs: Vec<(Point2<f64>, f64)> = measured
            .iter()
            .map(|m| (m.circle.center_px, m.circle.radius_px))
            .collect();
        let ranks: Vec<f64> = measured
            .iter()
            .map(|m| p.prune_rank.key(m.score, m.circle.radius_px))
            .collect();
        Ok(
            prune_overlapping(&discs, &ranks, p.max_overlap, p.prune_center_reach)
                .into_iter()
                .map(|i| {
                    let m = &measured[i];
                    let (c, r) = (m.circle.center_px, m.circle.radius_px);
                    let mut d = Detection::new(m.center_m, m.score);
                    d.diameter_m = m.diameter_m;
                    d.bbox_px = PixelBox::new(c.x - r, c.y - r, c.x + r, c.y + r).ok();
                    d.center_px = Some(c);
                    d.radius_px = Some(r);
                    d
                })
                .collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::{DepthImage, PinholeCamera};

    /// A 200×160 frame whose depth is 1 m everywhere except a hole of radius 12 px at
    /// (100, 80), or no depth at all; the fruit mask is that disc.
    fn frame_with_hole(depth_elsewhere: bool) -> (RgbdFrame, Vec<bool>) {
        let (w, h) = (200u32, 160u32);
        let camera = PinholeCamera::new(w, h, 300.0, 300.0, 99.5, 79.5).unwrap();
        let in_disc = |k: usize| {
            let (u, v) = ((k % w as usize) as f64, (k / w as usize) as f64);
            (u - 100.0).hypot(v - 80.0) <= 12.0
        };
        let depth: Vec<f32> = (0..(w * h) as usize)
            .map(|k| {
                if depth_elsewhere && !in_disc(k) {
                    1.0
                } else {
                    f32::NAN
                }
            })
            .collect();
        let fruit = (0..(w * h) as usize).map(in_disc).collect();
        let frame =
            RgbdFrame::new(camera, DepthImage::from_meters(w, h, depth).unwrap(), None).unwrap();
        (frame, fruit)
    }

    #[test]
    fn a_depthless_circle_beyond_reach_is_dropped_only_in_frames_with_depth() {
        // The prior (40 mm) places a 5 px circle at 300 · 0.04 / 5 = 2.4 m, beyond the 2 m
        // working distance, and an 8 px one at 1.5 m.
        let circle = |radius_px| ContourCircle {
            center_px: Point2::new(100.0, 80.0),
            radius_px,
            support: 0.9,
        };
        let circles = [circle(5.0)];
        let on = FruitStage {
            params: ColorContourParams::default(),
        };
        assert!(on.params.depthless_within_reach);
        let off = FruitStage {
            params: ColorContourParams {
                depthless_within_reach: false,
                ..ColorContourParams::default()
            },
        };
        let (with_depth, fruit) = frame_with_hole(true);
        let kept = |stage: &FruitStage, frame: &RgbdFrame, circles: &[ContourCircle]| {
            stage.run((frame, fruit.as_slice(), circles)).unwrap().len()
        };
        assert_eq!(kept(&on, &with_depth, &circles), 0);
        assert_eq!(kept(&off, &with_depth, &circles), 1);
        assert_eq!(kept(&on, &with_depth, &[circle(8.0)]), 1);
        // Colour-only data: no depth anywhere says nothing about the circle.
        let (colour_only, _) = frame_with_hole(false);
        assert_eq!(kept(&on, &colour_only, &circles), 1);
    }
}
