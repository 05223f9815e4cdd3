//! Morphological closing of the fruit mask (dilation, then erosion, by a square of side
//! `2r + 1`) before the contour stage. Not in seed 004: where a leaf's shadow, a specular
//! highlight or a thin twig crosses a fruit, the colour table leaves a gap, and the contour then
//! runs into the fruit along the gap, so the pieces of a circle either side no longer belong to
//! one outline. Closing bridges gaps narrower than `2r + 1` pixels without moving the outer
//! outline (what closing adds lies inside the concavities it fills). Off (`r = 0`) by default.
//!
//! Both passes are separable running counts over rows and then columns, so the cost does not
//! grow with `r`. Pixels outside the image are ignored by either pass (a fruit cut by the image
//! border keeps its border pixels).

use std::borrow::Cow;

/// The mask closed by a `(2 radius_px + 1)²` square; `mask` itself, not a copy, for
/// `radius_px == 0` (the paper's path) or a mask whose length is not `width · height`.
pub fn close_mask(mask: &[bool], width: usize, height: usize, radius_px: usize) -> Cow<'_, [bool]> {
    if radius_px == 0 || width == 0 || height == 0 || mask.len() != width * height {
        return Cow::Borrowed(mask);
    }
    let dilated = pass(mask, width, height, radius_px, |count, _| count > 0);
    Cow::Owned(pass(&dilated, width, height, radius_px, |count, window| {
        count == window
    }))
}

/// One separable square pass: along rows, then along columns, a pixel becomes
/// `keep(set pixels in the window, pixels of the window inside the image)`.
fn pass(
    mask: &[bool],
    width: usize,
    height: usize,
    radius: usize,
    keep: impl Fn(usize, usize) -> bool + Copy,
) -> Vec<bool> {
    let rows = run_rows(mask, width, radius, keep);
    run_columns(&rows, width, height, radius, keep)
}

/// Pixels of the window `[k − radius, k + radius]` inside `0..length`.
fn window_len(k: usize, radius: usize, length: usize) -> usize {
    (k + radius).min(length - 1) + 1 - k.saturating_sub(radius)
}

/// The running-window pass along every row.
fn run_rows(
    mask: &[bool],
    width: usize,
    radius: usize,
    keep: impl Fn(usize, usize) -> bool,
) -> Vec<bool> {
    let mut out = vec![false; mask.len()];
    for (row, out_row) in mask.chunks_exact(width).zip(out.chunks_exact_mut(width)) {
        // Count the set pixels of the window incrementally.
        let mut count = row[..radius.min(width)].iter().filter(|&&m| m).count();
        for k in 0..width {
            if k + radius < width && row[k + radius] {
                count += 1;
            }
            if k > radius && row[k - radius - 1] {
                count -= 1;
            }
            out_row[k] = keep(count, window_len(k, radius, width));
        }
    }
    out
}

/// The running-window pass along every column, swept row by row with one count per column
/// (memory is read in order, not with a stride of one row per step).
fn run_columns(
    mask: &[bool],
    width: usize,
    height: usize,
    radius: usize,
    keep: impl Fn(usize, usize) -> bool,
) -> Vec<bool> {
    let row = |y: usize| &mask[y * width..(y + 1) * width];
    let mut counts = vec![0usize; width];
    for y in 0..radius.min(height) {
        for (c, &m) in counts.iter_mut().zip(row(y)) {
            *c += usize::from(m);
        }
    }
    let mut out = vec![false; mask.len()];
    for (y, out_row) in out.chunks_exact_mut(width).enumerate() {
        if y + radius < height {
            for (c, &m) in counts.iter_mut().zip(row(y + radius)) {
                *c += usize::from(m);
            }
        }
        if y > radius {
            for (c, &m) in counts.iter_mut().zip(row(y - radius - 1)) {
                *c -= usize::from(m);
            }
        }
        let window = window_len(y, radius, height);
        for (o, &c) in out_row.iter_mut().zip(&counts) {
            *o = keep(c, window);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A disc of radius 20 px cut by a vertical gap `gap` px wide through its centre.
    fn cut_disc(gap: usize) -> (Vec<bool>, usize, usize) {
        let (w, h) = (60, 60);
        let mask = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64 - 30.0, (i / w) as f64 - 30.0);
                let in_gap = (x + gap as f64 / 2.0 >= 0.0) && (x < gap as f64 / 2.0);
                x * x + y * y <= 400.0 && !in_gap
            })
            .collect();
        (mask, w, h)
    }

    #[test]
    fn closing_bridges_narrow_gaps_only_and_never_removes_pixels() {
        for (gap, radius, bridged) in [(2, 2, true), (4, 2, true), (6, 2, false), (6, 3, true)] {
            let (mask, w, h) = cut_disc(gap);
            let closed = close_mask(&mask, w, h, radius);
            assert!(
                mask.iter().zip(closed.iter()).all(|(&m, &c)| !m || c),
                "closing is extensive"
            );
            // The centre pixel lies in the gap.
            assert_eq!(closed[30 * w + 30], bridged, "gap {gap}, radius {radius}");
        }
    }

    #[test]
    fn the_outline_of_a_convex_shape_and_the_image_border_stay() {
        let (mask, w, h) = cut_disc(0);
        assert_eq!(close_mask(&mask, w, h, 3), mask);
        // A block touching the image corner keeps its border pixels.
        let block: Vec<bool> = (0..w * h).map(|i| i % w < 10 && i / w < 10).collect();
        assert_eq!(close_mask(&block, w, h, 4), block);
        assert_eq!(close_mask(&block, w, h, 0), block);
    }
}
