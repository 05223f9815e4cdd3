//! How far the tracked fruit's neighbourhood moved between two frames (not in seed 004): the
//! grey patch around the last estimate, sampled on a coarse grid, is searched for in the next
//! frame by the smallest mean absolute difference, first on the grid's own step and then to the
//! pixel around the best coarse offset.
//!
//! Why: the seed's tracker starts each frame's checks at the last estimate. While the arm turns
//! to centre its target the whole image slides by up to about one fruit radius a frame, so the
//! 5×5 check lands beside the fruit and the spiral search takes whatever fruit it meets first —
//! often a touching neighbour. The patch's shift says where to start instead. It is measured on
//! the image, not extrapolated from the track's own past centres (a constant-velocity model of
//! those was measured and did not pay: docs/results.md, "Targets in view, and where tracks
//! start"), so a lagging or jittery estimate does not feed back into the prediction.
//!
//! The patch is the fruit and a rim of its surroundings: under the camera's turn both move
//! together; on a swaying fruit the fruit dominates. Sampling on a grid of at most
//! `samples_per_side`² points keeps the cost independent of the fruit's size.

use pomona_core::nalgebra::{Point2, Vector2};
use pomona_core::ColorImage;
use serde::{Deserialize, Serialize};

/// The patch and search of [`PatchTemplate`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PatchShiftParams {
    /// Half the patch's side, in fruit radii.
    pub half_side_radii: f64,
    /// Largest shift searched, in fruit radii (either axis; default 2, the reach of the
    /// tracker's bounded spiral search, [`crate::TrackParams::max_search_radii`]).
    pub search_radii: f64,
    /// Grid points per side of the patch, at most (the step is at least one pixel).
    pub samples_per_side: u32,
    /// Share of the patch's grid points that must fall inside both images.
    pub min_inside_share: f64,
    /// The tracker does not take a circle whose centre lies further than this many radii from
    /// where the patch moved (see [`crate::TrackParams::patch_shift`]).
    pub max_offset_radii: f64,
}

impl Default for PatchShiftParams {
    fn default() -> Self {
        Self {
            half_side_radii: 1.5,
            search_radii: 2.0,
            samples_per_side: 13,
            min_inside_share: 0.5,
            max_offset_radii: 0.5,
        }
    }
}

impl PatchShiftParams {
    /// Why the parameters are unusable, if they are.
    pub fn invalid_reason(&self) -> Option<&'static str> {
        if !(self.half_side_radii > 0.0 && self.half_side_radii.is_finite()) {
            Some("patch_shift.half_side_radii must be positive and finite")
        } else if !(self.search_radii >= 0.0 && self.search_radii.is_finite()) {
            Some("patch_shift.search_radii must be finite and not negative")
        } else if self.samples_per_side < 3 {
            Some("patch_shift.samples_per_side must be at least 3")
        } else if !(self.min_inside_share > 0.0 && self.min_inside_share <= 1.0) {
            Some("patch_shift.min_inside_share must lie in (0, 1]")
        } else if self.max_offset_radii.is_nan() || self.max_offset_radii <= 0.0 {
            Some("patch_shift.max_offset_radii must be positive")
        } else {
            None
        }
    }
}

/// The grey values of one frame's patch around a fruit, sampled on a square grid.
///
/// ```
/// use pomona_colorcontour::{PatchShiftParams, PatchTemplate};
/// use pomona_core::nalgebra::{Point2, Vector2};
/// use pomona_core::ColorImage;
///
/// // A bright fruit on a left-to-right ramp of shade, and the same view slid 9 px right.
/// let view = |slide_px: f64| {
///     let mut rgb = Vec::new();
///     for y in 0..80 {
///         for x in 0..120 {
///             let (u, v) = (f64::from(x) - slide_px, f64::from(y));
///             let on_fruit = (u - 50.0).hypot(v - 40.0) < 12.0;
///             let g = if on_fruit { 250 } else { (u.max(0.0) * 1.5) as u8 };
///             rgb.extend([g, g, g]);
///         }
///     }
///     ColorImage::from_rgb(120, 80, rgb).unwrap()
/// };
/// let params = PatchShiftParams::default();
/// let patch = PatchTemplate::sample(&view(0.0), Point2::new(50.0, 40.0), 12.0, &params).unwrap();
/// assert_eq!(patch.shift_in(&view(9.0)), Some(Vector2::new(9.0, 0.0)));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct PatchTemplate {
    center: (i64, i64),
    step: i64,
    half: i64,
    /// Row-major grey values (sum of the three channels), `None` outside the image.
    values: Vec<Option<u16>>,
    search_px: i64,
    min_inside: usize,
}

fn grey(image: &ColorImage, x: i64, y: i64) -> Option<u16> {
    let (Ok(u), Ok(v)) = (u32::try_from(x), u32::try_from(y)) else {
        return None;
    };
    image
        .get(u, v)
        .map(|[r, g, b]| u16::from(r) + u16::from(g) + u16::from(b))
}

impl PatchTemplate {
    /// The patch of `image` around the circle (`center`, `radius_px`); `None` for a radius that
    /// is not positive, or a patch that would lie wholly outside the image or be larger than
    /// a thousand images (no pixel arithmetic can then overflow).
    pub fn sample(
        image: &ColorImage,
        center: Point2<f64>,
        radius_px: f64,
        params: &PatchShiftParams,
    ) -> Option<Self> {
        let half_side = params.half_side_radii * radius_px;
        let (w, h) = (f64::from(image.width()), f64::from(image.height()));
        let reachable = |v: f64, size: f64| v >= -half_side && v <= size + half_side;
        if !(radius_px > 0.0
            && half_side <= 1000.0 * w.max(h)
            && reachable(center.x, w)
            && reachable(center.y, h))
        {
            return None;
        }
        let half_steps = i64::from(params.samples_per_side / 2).max(1);
        let step = ((half_side / half_steps as f64).round() as i64).max(1);
        let half = ((half_side / step as f64).round() as i64).clamp(1, half_steps);
        let center = (center.x.round() as i64, center.y.round() as i64);
        let mut values = Vec::with_capacity(((2 * half + 1) * (2 * half + 1)) as usize);
        for j in -half..=half {
            for i in -half..=half {
                values.push(grey(image, center.0 + i * step, center.1 + j * step));
            }
        }
        let points = values.len() as f64;
        Some(Self {
            center,
            step,
            half,
            values,
            search_px: (params.search_radii * radius_px).round() as i64,
            min_inside: (params.min_inside_share * points).ceil() as usize,
        })
    }

    /// Mean absolute grey difference with `image` at offset `(dx, dy)`; `None` when fewer than
    /// the required share of grid points lie inside both images.
    fn cost(&self, image: &ColorImage, (dx, dy): (i64, i64)) -> Option<f64> {
        let side = 2 * self.half + 1;
        let (mut sum, mut n) = (0u64, 0usize);
        for j in 0..side {
            let y = self.center.1 + dy + (j - self.half) * self.step;
            for i in 0..side {
                let Some(t) = self.values[(j * side + i) as usize] else {
                    continue;
                };
                let x = self.center.0 + dx + (i - self.half) * self.step;
                if let Some(g) = grey(image, x, y) {
                    sum += u64::from(t.abs_diff(g));
                    n += 1;
                }
            }
        }
        (n >= self.min_inside && n > 0).then(|| sum as f64 / n as f64)
    }

    /// Where the patch moved to in `image` (the next frame): the offset of smallest mean
    /// absolute difference within the search range, on the grid's step and then to the pixel
    /// around the best one; `None` when no offset keeps enough of the patch in the image, or
    /// when the best coarse offset lies on the edge of the range (the motion may be larger).
    pub fn shift_in(&self, image: &ColorImage) -> Option<Vector2<f64>> {
        // The first of equally good offsets wins, so the coarse best keeps its place on a tie.
        let best = |offsets: &mut dyn Iterator<Item = (i64, i64)>| {
            offsets
                .filter_map(|o| Some((o, self.cost(image, o)?)))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(o, _)| o)
        };
        let (coarse, step, reach) = (self.search_px / self.step, self.step, self.search_px);
        let (bx, by) = best(
            &mut (-coarse..=coarse)
                .flat_map(|j| (-coarse..=coarse).map(move |i| (i * step, j * step))),
        )?;
        // A best match on the edge of the range may be the nearest of a larger motion: no
        // shift is known then.
        let edge = coarse * step;
        if coarse > 0 && (bx.abs() == edge || by.abs() == edge) {
            return None;
        }
        let fine = (by - step + 1..by + step)
            .flat_map(|dy| (bx - step + 1..bx + step).map(move |dx| (dx, dy)))
            .filter(|&(dx, dy)| dx.abs() <= reach && dy.abs() <= reach);
        let (dx, dy) = best(&mut std::iter::once((bx, by)).chain(fine))?;
        Some(Vector2::new(dx as f64, dy as f64))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A textured image (so that every shift is visible) with a bright disc at (cx, cy).
    fn scene(cx: f64, cy: f64, r: f64) -> ColorImage {
        let (w, h) = (160u32, 120u32);
        let mut rgb = Vec::with_capacity((w * h * 3) as usize);
        for y in 0..h {
            for x in 0..w {
                let (fx, fy) = (f64::from(x), f64::from(y));
                let inside = (fx - cx).hypot(fy - cy) <= r;
                let (dx, dy) = (fx - cx, fy - cy);
                let texture = 90.0
                    + 35.0 * (0.13 * dx + 0.07 * dy).sin()
                    + 25.0 * (0.05 * dx - 0.11 * dy).sin()
                    + 15.0 * (0.031 * dx * dy.signum() + 0.017 * dy).cos();
                let v = if inside { 230.0 } else { texture };
                rgb.extend([v as u8, (v * 0.8) as u8, 40]);
            }
        }
        ColorImage::from_rgb(w, h, rgb).unwrap()
    }

    #[test]
    fn the_shift_of_a_moved_scene_is_found_to_the_pixel() {
        let params = PatchShiftParams {
            search_radii: 1.5,
            ..PatchShiftParams::default()
        };
        let before = scene(60.0, 50.0, 15.0);
        let template = PatchTemplate::sample(&before, Point2::new(60.0, 50.0), 15.0, &params)
            .expect("a valid circle");
        // Moved by 17 px right and 6 px up: more than one grid step, within 1.5 radii.
        let after = scene(77.0, 44.0, 15.0);
        let shift = template.shift_in(&after).expect("inside the image");
        assert_eq!(shift, Vector2::new(17.0, -6.0));
        // Unmoved: no shift.
        assert_eq!(template.shift_in(&before), Some(Vector2::zeros()));
        // Moved by 27 px, beyond the 22 px searched: the best match lies on the edge of the
        // range, and no shift is claimed.
        assert_eq!(template.shift_in(&scene(87.0, 50.0, 15.0)), None);
    }

    #[test]
    fn a_patch_mostly_outside_the_image_gives_no_shift() {
        let params = PatchShiftParams {
            search_radii: 0.0,
            min_inside_share: 0.9,
            ..PatchShiftParams::default()
        };
        let image = scene(2.0, 2.0, 15.0);
        let template = PatchTemplate::sample(&image, Point2::new(2.0, 2.0), 15.0, &params)
            .expect("a valid circle");
        assert_eq!(template.shift_in(&image), None);
        // No patch of a circle without radius, far outside the image or of absurd size.
        for (x, r) in [
            (2.0, 0.0),
            (1e18, 15.0),
            (-1e18, 15.0),
            (2.0, 1e300),
            (f64::NAN, 15.0),
        ] {
            assert!(PatchTemplate::sample(&image, Point2::new(x, 2.0), r, &params).is_none());
        }
    }
}
