//! Morphological closing of the fruit mask (dilation, then erosion, by a square of side
//! `2r + 1`) before the contour stage. Not in seed 004: where a leaf's shadow, a specular
//! highlight or a thin twig crosses a fruit, the colour table leaves a gap, and the contour then
//! runs into the fruit along the gap, so the pieces of a circle either side no longer belong to
//! one outline. Closing bridges gaps narrower than `2r + 1` pixels without moving the outer
//! outline (what closing adds lies inside the concavities it fills). Off (`r = 0`) by default.
//!
//! Both passes are separable window reductions ([`crate::window_reduce`]: any pixel of the
//! window set for the dilation, all of them for the erosion). Their cost grows with `r`;
//! closings are a few pixels wide (2 in the built-in model). Pixels outside the image are
//! ignored by either pass (a fruit cut by the image border keeps its border pixels).

use std::borrow::Cow;

use crate::window_reduce::window_reduce;

/// The mask closed by a `(2 radius_px + 1)²` square; `mask` itself, not a copy, for
/// `radius_px == 0` (the paper's path) or a mask whose length is not `width · height`.
pub fn close_mask(mask: &[bool], width: usize, height: usize, radius_px: usize) -> Cow<'_, [bool]> {
    if radius_px == 0 || width == 0 || height == 0 || mask.len() != width * height {
        return Cow::Borrowed(mask);
    }
    let dilated = window_reduce(mask, width, radius_px, |a, b| a | b);
    Cow::Owned(window_reduce(&dilated, width, radius_px, |a, b| a & b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Dilation then erosion as written down: any, then all, of the pixels of the square
    /// window that lie inside the image.
    fn closed_by_definition(mask: &[bool], w: usize, h: usize, r: usize) -> Vec<bool> {
        let window = |m: &[bool], i: usize, all: bool| {
            let (x, y) = (i % w, i / w);
            let mut inside = (y.saturating_sub(r)..(y + r + 1).min(h)).flat_map(|yy| {
                (x.saturating_sub(r)..(x + r + 1).min(w)).map(move |xx| yy * w + xx)
            });
            if all {
                inside.all(|j| m[j])
            } else {
                inside.any(|j| m[j])
            }
        };
        let dilated: Vec<bool> = (0..w * h).map(|i| window(mask, i, false)).collect();
        (0..w * h).map(|i| window(&dilated, i, true)).collect()
    }

    #[test]
    fn the_shifted_passes_close_as_the_definition_does() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..300 {
            let (w, h) = (rng.gen_range(1..20), rng.gen_range(1..20));
            let density = rng.gen_range(0.0..1.0);
            let mask: Vec<bool> = (0..w * h).map(|_| rng.gen_bool(density)).collect();
            for r in 1..6 {
                assert_eq!(
                    close_mask(&mask, w, h, r).into_owned(),
                    closed_by_definition(&mask, w, h, r),
                    "{w}×{h}, radius {r}"
                );
            }
        }
    }

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
