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

use std::collections::VecDeque;

/// The mask of `values` (row-major, `width` × `height`) with hysteresis thresholds `high` and
/// `low`, grown from confident regions of at least `min_seed_px` pixels (see the module docs).
/// A `low` at or above `high`, or a length that is not `width · height`, gives the plain
/// threshold at `high`.
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
    // Confident components large enough to seed (component labelling by a stack walk).
    let mut seen = vec![false; mask.len()];
    let mut seeds: VecDeque<usize> = VecDeque::new();
    let mut stack = Vec::new();
    let mut component = Vec::new();
    for start in 0..mask.len() {
        if !mask[start] || seen[start] {
            continue;
        }
        component.clear();
        seen[start] = true;
        stack.push(start);
        while let Some(i) = stack.pop() {
            component.push(i);
            for j in neighbours(i, width, height) {
                if mask[j] && !seen[j] {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
        if component.len() >= min_seed_px {
            seeds.extend(component.iter().copied());
        }
    }
    let mut queue = seeds;
    while let Some(i) = queue.pop_front() {
        for j in neighbours(i, width, height) {
            if !mask[j] && values[j] >= low {
                mask[j] = true;
                queue.push_back(j);
            }
        }
    }
    mask
}

/// The 8-neighbours of pixel `i` inside the image (and `i` itself, which callers skip by their
/// own test).
fn neighbours(i: usize, width: usize, height: usize) -> impl Iterator<Item = usize> {
    let (x, y) = (i % width, i / width);
    (y.saturating_sub(1)..=(y + 1).min(height - 1)).flat_map(move |ny| {
        (x.saturating_sub(1)..=(x + 1).min(width - 1)).map(move |nx| ny * width + nx)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
