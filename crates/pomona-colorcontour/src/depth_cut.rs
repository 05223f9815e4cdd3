//! Outlines where one fruit hides another: the colour mask cut at depth steps (not in seed 004,
//! whose cameras have no depth).
//!
//! Two fruit of the fruit's colour, one in front of the other, are one region of the colour
//! mask: the front fruit's outline runs on where it meets the background but stops where it
//! meets the fruit behind, and the contour and Hough stages only see a mask's outline. In a
//! frame with depth that hidden stretch of outline is a depth step: the front fruit's rim lies
//! centimetres nearer than the surface behind it. Here a mask pixel is taken out of the mask
//! when a mask pixel within `reach_px` (a square window) lies more than `step_m` nearer, which
//! leaves a gap along every step, so that the outline stages see the two fruit apart.
//!
//! Depths are compared robustly: each pixel's depth is the median of the fruit readings on
//! every other row and column of the `2 median_half_window_px + 1` square around the pixel at
//! even coordinates at or before it (a quarter of the pixels, a sixteenth of the samples).
//! Time-of-flight cameras read dim and shadowed fruit pixels too far (multipath) and mix fruit
//! and background at silhouettes (flying pixels); single readings compared this way shredded
//! the masks of single fruit (docs/results.md, "Fruit in front of fruit"). A median window
//! across a step takes the side that fills most of it, so the gap can fall on the front
//! fruit's rim instead of behind it, a pixel or two from the true outline; either way the
//! mask is split where the fruit meet. The rim of a single fruit also falls away steeply, so
//! `step_m` must exceed what a fruit's own surface drops within the reach of its edge (for a
//! 50 mm orange at 0.7 m on a 365 px Kinect v2, about 20 mm within 2 px). Pixels without a
//! reading are kept. The mask is cut after its cleaning (closing and smoothing would fill a
//! narrow gap again) and before the contours.

/// Settings of the depth cut (a model file may leave either out: the default is used).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct DepthCutParams {
    /// A mask pixel is cut when a mask pixel nearer than it by more than this lies within
    /// `reach_px`, metres.
    pub step_m: f64,
    /// Half the side of the square window searched for a nearer pixel, pixels (the width of the
    /// gap left behind a step).
    pub reach_px: usize,
    /// Each pixel's depth is first the median of the fruit readings in a square this many
    /// pixels either side (see the module docs; 0: the reading alone).
    pub median_half_window_px: usize,
}

impl Default for DepthCutParams {
    fn default() -> Self {
        Self {
            step_m: 0.03,
            reach_px: 2,
            median_half_window_px: 3,
        }
    }
}

impl DepthCutParams {
    /// Why the settings cannot run, as (name, reason), or `None`.
    pub fn problem(&self) -> Option<(&'static str, &'static str)> {
        if !(self.step_m.is_finite() && self.step_m > 0.0) {
            return Some(("depth_cut.step_m", "must be finite and positive"));
        }
        if self.reach_px == 0 {
            return Some(("depth_cut.reach_px", "must be at least 1"));
        }
        None
    }
}

/// `mask` (row-major, `width` wide) without the pixels that lie more than `params.step_m`
/// behind a mask pixel within `params.reach_px` (see the module docs); `depth_m` holds the
/// frame's depth per pixel, `NaN` (or any non-finite value) without a reading; pixels past the
/// end of a shorter `depth_m` have none.
///
/// ```
/// use pomona_colorcontour::{cut_at_depth_steps, DepthCutParams};
/// // A row of fruit pixels: two at 0.60 m in front of four at 0.70 m.
/// let mask = [true; 6];
/// let depth = [0.60, 0.60, 0.70, 0.70, 0.70, 0.70];
/// let params = DepthCutParams { step_m: 0.03, reach_px: 2, median_half_window_px: 0 };
/// let cut = cut_at_depth_steps(&mask, &depth, 6, &params);
/// assert_eq!(cut, [true, true, false, false, true, true]);
/// ```
pub fn cut_at_depth_steps(
    mask: &[bool],
    depth_m: &[f32],
    width: usize,
    params: &DepthCutParams,
) -> Vec<bool> {
    let width = width.max(1);
    let height = mask.len() / width;
    let fruit = |k: usize| mask[k] && depth_m.get(k).is_some_and(|d| d.is_finite() && *d > 0.0);
    // The fruit pixels with a reading, in raster order. Fruit covers a small part of most
    // frames, so every later step visits these and their neighbours only: a stretch of row
    // without fruit costs one OR over its pixels. (Listing them from the mask's runs,
    // `Runs::passing`, made the stage 39–57 % slower: it classifies every pixel first.)
    const STRETCH: usize = 32;
    let mut fruit_pixels: Vec<(usize, usize)> = Vec::new();
    for (y, row) in mask.chunks_exact(width).enumerate() {
        for (s, stretch) in row.chunks(STRETCH).enumerate() {
            if !stretch.iter().fold(false, |any, &m| any | m) {
                continue;
            }
            let x0 = s * STRETCH;
            fruit_pixels.extend(
                (x0..x0 + stretch.len())
                    .filter(|&x| fruit(y * width + x))
                    .map(|x| (x, y)),
            );
        }
    }
    if fruit_pixels.is_empty() {
        return mask.to_vec();
    }
    // Each fruit pixel's robust depth, as the bit pattern of a positive depth (which orders as
    // the depths do): its own reading without a median, else the median of its 2 × 2 block's
    // window, computed once per block (`u32::MAX`: not yet).
    let half = params.median_half_window_px;
    let grid_w = width.div_ceil(2);
    let mut grid = Vec::new();
    if half > 0 {
        grid = vec![u32::MAX; grid_w * height.div_ceil(2)];
        let mut window: Vec<u32> = Vec::with_capacity((half + 1).pow(2));
        for &(x, y) in &fruit_pixels {
            let g = (y / 2) * grid_w + x / 2;
            if grid[g] != u32::MAX {
                continue;
            }
            let (cx, cy) = (x & !1, y & !1);
            let (x0, y0) = (cx.saturating_sub(half), cy.saturating_sub(half));
            window.clear();
            for yy in (y0..(cy + half + 1).min(height)).step_by(2) {
                let row = yy * width;
                window.extend(
                    (row + x0..row + (cx + half + 1).min(width))
                        .step_by(2)
                        .filter(|&j| fruit(j))
                        .map(|j| depth_m[j].to_bits()),
                );
            }
            // The block's first fruit pixel stands in when the sampled window holds no reading.
            if window.is_empty() {
                window.push(depth_m[y * width + x].to_bits());
            }
            // A full sort of these few values is quicker than a selection (measured).
            window.sort_unstable();
            grid[g] = window[window.len() / 2];
        }
    }
    // The robust depths as an image (`INFINITY` off the fruit, never nearer than anything):
    // a fruit pixel is behind a step when one within the reach is nearer by more than it.
    let mut robust_at = vec![f32::INFINITY; mask.len()];
    for &(x, y) in &fruit_pixels {
        let k = y * width + x;
        robust_at[k] = if half == 0 {
            depth_m[k]
        } else {
            f32::from_bits(grid[(y / 2) * grid_w + x / 2])
        };
    }
    let (reach, step) = (params.reach_px, params.step_m as f32);
    let mut out = mask.to_vec();
    for &(x, y) in &fruit_pixels {
        let d = robust_at[y * width + x];
        let (x0, x1) = (x.saturating_sub(reach), (x + reach + 1).min(width));
        let behind = (y.saturating_sub(reach)..(y + reach + 1).min(height)).any(|yy| {
            robust_at[yy * width + x0..yy * width + x1]
                .iter()
                .any(|&n| d - n > step)
        });
        if behind {
            out[y * width + x] = false;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame 60 × 40 of two discs of fruit: a near one (radius 10 at (25, 20), 0.6 m) in
    /// front of a far one (radius 12 at (36, 20), 0.7 m), each a sphere in depth.
    fn two_fruit() -> (Vec<bool>, Vec<f32>, usize) {
        let (w, h) = (60usize, 40usize);
        let mut mask = vec![false; w * h];
        let mut depth = vec![f32::NAN; w * h];
        for k in 0..w * h {
            let (x, y) = ((k % w) as f64, (k / w) as f64);
            let near = (x - 25.0).hypot(y - 20.0);
            let far = (x - 36.0).hypot(y - 20.0);
            // Pixel size 2 mm: the spheres' surfaces in metres.
            let sphere = |rho: f64, r: f64, z: f64| z - 0.002 * (r * r - rho * rho).max(0.0).sqrt();
            if near <= 10.0 {
                mask[k] = true;
                depth[k] = sphere(near, 10.0, 0.6) as f32;
            } else if far <= 12.0 {
                mask[k] = true;
                depth[k] = sphere(far, 12.0, 0.7) as f32;
            }
        }
        (mask, depth, w)
    }

    /// The rule without medians, pixel by pixel: cut when a fruit reading within `reach` is
    /// nearer by more than `step`.
    fn by_definition(mask: &[bool], depth: &[f32], w: usize, step: f32, reach: i64) -> Vec<bool> {
        let h = mask.len() / w;
        (0..mask.len())
            .map(|k| {
                let (x, y) = ((k % w) as i64, (k / w) as i64);
                let fruit = |j: usize| mask[j] && depth[j].is_finite();
                if !mask[k] {
                    return false;
                }
                if !fruit(k) {
                    return true;
                }
                let nearer = (-reach..=reach)
                    .flat_map(|dy| (-reach..=reach).map(move |dx| (x + dx, y + dy)))
                    .filter(|&(u, v)| u >= 0 && v >= 0 && u < w as i64 && v < h as i64)
                    .map(|(u, v)| v as usize * w + u as usize)
                    .filter(|&j| fruit(j) && depth[k] - depth[j] > step)
                    .count();
                nearer == 0
            })
            .collect()
    }

    #[test]
    fn the_fruit_behind_loses_a_band_along_the_front_fruits_rim() {
        let (mask, depth, w) = two_fruit();
        for (step_m, reach_px) in [(0.03, 2), (0.03, 4), (0.05, 1), (0.2, 2)] {
            let params = DepthCutParams {
                step_m,
                reach_px,
                median_half_window_px: 0,
            };
            let cut = cut_at_depth_steps(&mask, &depth, w, &params);
            assert_eq!(
                cut,
                by_definition(&mask, &depth, w, step_m as f32, reach_px as i64)
            );
            for k in 0..mask.len() {
                let (x, y) = ((k % w) as f64, (k / w) as f64);
                if (x - 25.0).hypot(y - 20.0) <= 10.0 {
                    // The front fruit keeps every pixel, its steep rim included.
                    assert!(cut[k], "front pixel ({x}, {y}) cut");
                } else if (x - 25.0).hypot(y - 20.0) > 11.0 + reach_px as f64 * 2f64.sqrt() {
                    // The fruit behind keeps what lies beyond the reach (a square window).
                    assert_eq!(cut[k], mask[k]);
                }
            }
            let lost = mask.iter().zip(&cut).filter(|(m, c)| **m && !**c).count();
            if step_m < 0.1 {
                assert!(lost > 5, "{lost} pixels cut at {step_m} m, {reach_px} px");
            } else {
                assert_eq!(lost, 0);
            }
        }
    }

    /// The rule with medians, pixel by pixel: each fruit pixel's depth is its reading without a
    /// median window, else the median of the fruit readings on every other row and column of
    /// the window around its 2 × 2 block's even corner (the reading of the block's first fruit
    /// pixel in raster order when there are none), and it is cut when a fruit pixel within
    /// `reach` has a depth nearer by more than `step`.
    fn by_definition_with_medians(
        mask: &[bool],
        depth: &[f32],
        w: usize,
        params: &DepthCutParams,
    ) -> Vec<bool> {
        let h = mask.len() / w;
        let fruit = |x: usize, y: usize| {
            let k = y * w + x;
            mask[k] && depth.get(k).is_some_and(|d| d.is_finite() && *d > 0.0)
        };
        let half = params.median_half_window_px;
        let robust = |x: usize, y: usize| -> f32 {
            if half == 0 {
                return depth[y * w + x];
            }
            let (cx, cy) = (x - x % 2, y - y % 2);
            let mut window: Vec<f32> = Vec::new();
            for yy in (cy.saturating_sub(half)..=(cy + half).min(h - 1)).step_by(2) {
                for xx in (cx.saturating_sub(half)..=(cx + half).min(w - 1)).step_by(2) {
                    if fruit(xx, yy) {
                        window.push(depth[yy * w + xx]);
                    }
                }
            }
            if window.is_empty() {
                let block = [(cx, cy), (cx + 1, cy), (cx, cy + 1), (cx + 1, cy + 1)];
                let first = block.iter().find(|&&(u, v)| u < w && v < h && fruit(u, v));
                window.extend(first.map(|&(u, v)| depth[v * w + u]));
            }
            window.sort_by(f32::total_cmp);
            window[window.len() / 2]
        };
        let reach = params.reach_px;
        (0..w * h)
            .map(|k| {
                let (x, y) = (k % w, k / w);
                if !fruit(x, y) {
                    return mask[k];
                }
                let d = robust(x, y);
                let ys = y.saturating_sub(reach)..=(y + reach).min(h - 1);
                !ys.flat_map(|v| {
                    (x.saturating_sub(reach)..=(x + reach).min(w - 1)).map(move |u| (u, v))
                })
                .any(|(u, v)| fruit(u, v) && d - robust(u, v) > params.step_m as f32)
            })
            .collect()
    }

    #[test]
    fn the_cut_with_medians_is_its_rule_written_pixel_by_pixel_on_random_frames() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(61);
        for _ in 0..300 {
            let (w, h): (usize, usize) = (rng.gen_range(1..45), rng.gen_range(1..45));
            let density = rng.gen_range(0.05..1.0);
            let mask: Vec<bool> = (0..w * h).map(|_| rng.gen_bool(density)).collect();
            // Two depth layers with noise, some pixels without a reading, sometimes a depth
            // image shorter than the mask.
            let depth: Vec<f32> = (0..w * h)
                .map(|k| match rng.gen_range(0..10) {
                    0 => f32::NAN,
                    1 => 0.0,
                    _ if (k % w) < w / 2 => rng.gen_range(0.55..0.65),
                    _ => rng.gen_range(0.6..0.75),
                })
                .collect();
            let depth = &depth[..if rng.gen_bool(0.1) {
                rng.gen_range(0..=w * h)
            } else {
                w * h
            }];
            let params = DepthCutParams {
                step_m: rng.gen_range(0.01..0.1),
                reach_px: rng.gen_range(1..4),
                median_half_window_px: rng.gen_range(0..5),
            };
            assert_eq!(
                cut_at_depth_steps(&mask, depth, w, &params),
                by_definition_with_medians(&mask, depth, w, &params),
                "{w}×{h}, {params:?}"
            );
        }
    }

    #[test]
    fn pixels_without_depth_are_kept_and_frames_without_depth_are_unchanged() {
        let (mask, mut depth, w) = two_fruit();
        let single = DepthCutParams {
            median_half_window_px: 0,
            ..DepthCutParams::default()
        };
        let behind = 20 * w + 36;
        assert!(!cut_at_depth_steps(&mask, &depth, w, &single)[behind]);
        depth[behind] = f32::NAN;
        assert!(cut_at_depth_steps(&mask, &depth, w, &single)[behind]);
        let no_depth = vec![f32::NAN; mask.len()];
        assert_eq!(
            cut_at_depth_steps(&mask, &no_depth, w, &DepthCutParams::default()),
            mask
        );
        // A depth image of another size is read as far as it goes, never past its end.
        for short in [0, 1, 20 * w + 30, mask.len() - 1] {
            let cut = cut_at_depth_steps(&mask, &depth[..short], w, &DepthCutParams::default());
            assert_eq!(cut.len(), mask.len());
        }
        assert_eq!(
            cut_at_depth_steps(&mask, &depth, 0, &DepthCutParams::default()).len(),
            mask.len()
        );
    }

    #[test]
    fn scattered_far_readings_on_one_fruit_are_not_steps() {
        // One fruit, every seventh reading 0.2 m too far (multipath on a time-of-flight camera).
        let (w, h) = (40usize, 40usize);
        let mask: Vec<bool> = (0..w * h)
            .map(|k| ((k % w) as f64 - 20.0).hypot((k / w) as f64 - 20.0) <= 15.0)
            .collect();
        let depth: Vec<f32> = (0..w * h)
            .map(|k| if k % 7 == 0 { 0.9 } else { 0.7 })
            .collect();
        let median = cut_at_depth_steps(&mask, &depth, w, &DepthCutParams::default());
        assert_eq!(median, mask);
        let single = DepthCutParams {
            median_half_window_px: 0,
            ..DepthCutParams::default()
        };
        let raw = cut_at_depth_steps(&mask, &depth, w, &single);
        assert!(raw.iter().filter(|c| **c).count() < mask.iter().filter(|c| **c).count());
        // The two fruit of the other tests are still told apart through the median.
        let (two, depth, w) = two_fruit();
        let cut = cut_at_depth_steps(&two, &depth, w, &DepthCutParams::default());
        assert!(
            (33..=39).any(|x| !cut[20 * w + x]),
            "nothing cut where the fruit meet"
        );
        assert!(cut[20 * w + 44] && cut[20 * w + 25]);
    }

    #[test]
    fn settings_that_cannot_run_are_named() {
        assert_eq!(DepthCutParams::default().problem(), None);
        let bad = |step_m, reach_px| {
            DepthCutParams {
                step_m,
                reach_px,
                ..DepthCutParams::default()
            }
            .problem()
            .map(|p| p.0)
        };
        assert_eq!(bad(0.0, 2), Some("depth_cut.step_m"));
        assert_eq!(bad(f64::NAN, 2), Some("depth_cut.step_m"));
        assert_eq!(bad(0.03, 0), Some("depth_cut.reach_px"));
    }
}
