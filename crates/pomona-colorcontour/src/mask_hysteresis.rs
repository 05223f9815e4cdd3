//! Hysteresis on the colour table's values (not in seed 004): a pixel is fruit when its value
//! reaches the threshold, or when it reaches a lower one and is joined to such a pixel through
//! pixels that reach the lower one (8-connected), as in Canny's edge hysteresis.
//!
//! Why: one threshold on the table cuts a fruit where its colour weakens — the shaded side away
//! from the sun, the pale rim of a highlight, a yellow-green fruit — so the mask and its outline
//! follow only the sunlit part, and the circles fitted to that outline are too small and off
//! centre. Weak pixels are taken only where they touch a confident region, so background of a
//! weakly fruit-like colour (dry leaves, soil) stays out unless it touches a fruit. Only
//! confident regions of at least `min_seed_px` pixels (8-connected) seed the growth: a sunlit
//! leaf of a yellow-green tint has a few confident pixels, and grown from them it would become a
//! fruit-sized blob. With the low threshold equal to the high one this is the plain threshold
//! (the paper's).

use crate::mask_runs::{touching, Runs};

/// The mask of `values` (row-major, `width` × `height`) with hysteresis thresholds `high` and
/// `low`, grown from confident regions of at least `min_seed_px` pixels (see the module docs).
/// A `low` at or above `high`, or a length that is not `width · height`, gives the plain
/// threshold at `high`.
///
/// The regions are labelled as runs of pixels along rows, not pixel by pixel: the confident
/// runs (value ≥ `high`) are joined into 8-connected regions and sized; the weak runs (`low`
/// ≤ value < `high`) are joined among themselves, and a weak region joins the mask when one of
/// its runs touches a run of a seeding region. That is the set a pixel-by-pixel growth from the
/// seeds through weak pixels reaches, at a cost that grows with the number of runs.
pub fn hysteresis_mask(
    values: &[u8],
    width: usize,
    height: usize,
    (high, low): (u8, u8),
    min_seed_px: usize,
) -> Vec<bool> {
    let mut mask: Vec<bool> = values.iter().map(|&v| v >= high).collect();
    if low >= high || width == 0 || values.len() != width * height {
        return mask;
    }
    let (strong, weak) = Runs::strong_and_weak(values, width, (high, low));
    let mut strong_sets = strong.regions();
    let size = strong.region_areas(&mut strong_sets);
    let seeds: Vec<bool> = (0..strong.runs.len())
        .map(|k| size[strong_sets.find(k)] >= min_seed_px)
        .collect();
    let mut weak_sets = weak.regions();
    let mut grown = vec![false; weak.runs.len()];
    for y in 0..weak.rows() {
        for near in [y.checked_sub(1), Some(y), Some(y + 1)]
            .into_iter()
            .flatten()
        {
            if near < strong.rows() {
                touching(weak.row(y), strong.row(near), |a, b| {
                    if seeds[b] {
                        grown[weak_sets.find(a)] = true;
                    }
                });
            }
        }
    }
    for (k, run) in weak.runs.iter().enumerate() {
        if grown[weak_sets.find(k)] {
            mask[run.y * width + run.x0..run.y * width + run.x1].fill(true);
        }
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngCore, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::collections::VecDeque;

    /// The growth pixel by pixel, as the module docs state it (the implementation before the
    /// runs): label the confident components, then a breadth-first walk from the seeding ones
    /// into weak pixels.
    fn pixel_by_pixel(
        values: &[u8],
        width: usize,
        height: usize,
        (high, low): (u8, u8),
        min_seed_px: usize,
    ) -> Vec<bool> {
        let mut mask: Vec<bool> = values.iter().map(|&v| v >= high).collect();
        let neighbours = |i: usize| {
            let (x, y) = ((i % width) as i64, (i / width) as i64);
            (-1..=1)
                .flat_map(move |dy| (-1..=1).map(move |dx| (x + dx, y + dy)))
                .filter(|&(nx, ny)| nx >= 0 && ny >= 0 && nx < width as i64 && ny < height as i64)
                .map(|(nx, ny)| ny as usize * width + nx as usize)
                .collect::<Vec<_>>()
        };
        let mut seen = vec![false; mask.len()];
        let mut queue = VecDeque::new();
        for start in 0..mask.len() {
            if !mask[start] || seen[start] {
                continue;
            }
            let (mut component, mut stack) = (Vec::new(), vec![start]);
            seen[start] = true;
            while let Some(i) = stack.pop() {
                component.push(i);
                for j in neighbours(i) {
                    if mask[j] && !seen[j] {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
            if component.len() >= min_seed_px {
                queue.extend(component);
            }
        }
        while let Some(i) = queue.pop_front() {
            for j in neighbours(i) {
                if !mask[j] && values[j] >= low {
                    mask[j] = true;
                    queue.push_back(j);
                }
            }
        }
        mask
    }

    #[test]
    fn the_runs_reach_what_the_pixel_by_pixel_growth_reaches() {
        // Random images of three levels (none, weak, strong) in blobs and speckle, of many
        // shapes, against the pixel-by-pixel definition.
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut next = move || rng.next_u64();
        for case in 0..400 {
            let (width, height) = (1 + (next() % 23) as usize, 1 + (next() % 17) as usize);
            let (p_strong, p_weak) = (next() % 60, next() % 60);
            let values: Vec<u8> = (0..width * height)
                .map(|_| {
                    let r = next() % 100;
                    if r < p_strong {
                        200
                    } else if r < p_strong + p_weak {
                        120
                    } else {
                        (next() % 100) as u8
                    }
                })
                .collect();
            let min_seed_px = 1 + (next() % 6) as usize;
            assert_eq!(
                hysteresis_mask(&values, width, height, (180, 100), min_seed_px),
                pixel_by_pixel(&values, width, height, (180, 100), min_seed_px),
                "case {case}: {width}×{height}, seeds of {min_seed_px}"
            );
        }
    }

    #[test]
    fn weak_pixels_join_only_where_they_touch_strong_ones() {
        // Row 0: strong, weak, weak, none, weak.  Row 1: none, none, weak (diagonal link),
        // none, none.
        let values = [200, 120, 110, 10, 150, 0, 0, 130, 0, 0];
        let mask = hysteresis_mask(&values, 5, 2, (180, 100), 1);
        assert_eq!(
            mask,
            [true, true, true, false, false, false, false, true, false, false]
        );
        // A seed smaller than `min_seed_px` stays but does not grow.
        let small = hysteresis_mask(&values, 5, 2, (180, 100), 2);
        assert_eq!(small, values.map(|v| v >= 180));
        // Two confident pixels side by side seed at `min_seed_px = 2`.
        let pair = [200, 200, 120, 10, 0, 0];
        assert_eq!(
            hysteresis_mask(&pair, 3, 2, (180, 100), 2),
            [true, true, true, false, false, false]
        );
        // Equal thresholds: the plain threshold.
        let plain = hysteresis_mask(&values, 5, 2, (180, 180), 1);
        assert_eq!(plain, values.map(|v| v >= 180));
        // A wrong length never grows.
        assert_eq!(
            hysteresis_mask(&values, 4, 2, (180, 100), 1),
            values.map(|v| v >= 180)
        );
    }
}
