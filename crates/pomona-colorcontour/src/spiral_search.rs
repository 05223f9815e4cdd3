//! The rectangular "spiral" search of seed 004 §3.3: when the tracked fruit is not under the
//! expected position, probe positions are visited ring by ring on square rings around it, first
//! with a small step and then, if necessary, with larger steps until the rings enclose the whole
//! image. A fruit displaced a little (by wind, say) is found after a few probes; one anywhere in
//! the image is still found, at the price of a coarser grid far away.
//!
//! The paper gives neither the step sizes nor when the step grows. Choices, documented in
//! [`SpiralParams`]: the step starts at `first_step_px`, is kept for `rings_per_step` rings and
//! then doubles, up to `max_step_px`, which is kept until the image is covered. Every ring is a
//! multiple of the current step away from the centre, so probes lie on a square lattice whose
//! spacing is the local step: every pixel of the image lies within half of `max_step_px`
//! (Chebyshev distance) of a probe, so any fruit wider than about `max_step_px` + 5 px is hit
//! by a probe whose 5×5 check lands inside it. Probes less than a step outside the image are
//! moved onto its border (a few are then visited twice), farther ones are skipped; within a
//! ring they are visited clockwise from the top-left corner, which is the order a rectangular
//! spiral walks them.

use serde::{Deserialize, Serialize};

/// Step sizes of the spiral search.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SpiralParams {
    /// Step between probes in the first rings, pixels (the paper: "a small step size").
    pub first_step_px: u32,
    /// Rings searched at each step size before the step doubles.
    pub rings_per_step: u32,
    /// Largest step, pixels; kept until the rings enclose the image.
    pub max_step_px: u32,
}

impl Default for SpiralParams {
    fn default() -> Self {
        Self {
            first_step_px: 2,
            rings_per_step: 4,
            max_step_px: 8,
        }
    }
}

impl SpiralParams {
    /// Whether the steps are usable: `1 ≤ first_step_px ≤ max_step_px` and at least one ring
    /// per step.
    pub fn is_valid(&self) -> bool {
        self.first_step_px >= 1
            && self.first_step_px <= self.max_step_px
            && self.rings_per_step >= 1
    }
}

/// Probe positions of the spiral around `center` (which is not itself visited), inside a
/// `width` × `height` image, nearest rings first. Ends once a ring encloses the whole image.
/// Invalid parameters (see [`SpiralParams::is_valid`]) are clamped to the nearest valid ones.
pub fn spiral_points(
    center: (i64, i64),
    width: u32,
    height: u32,
    params: &SpiralParams,
) -> impl Iterator<Item = (i64, i64)> {
    let first = i64::from(params.first_step_px.max(1));
    let max_step = i64::from(params.max_step_px).max(first);
    let rings_per_step = i64::from(params.rings_per_step.max(1));
    let (w, h) = (i64::from(width), i64::from(height));
    let (cx, cy) = center;
    // Chebyshev distance from the centre to the farthest image corner.
    let reach = (cx.abs().max((w - 1 - cx).abs())).max(cy.abs().max((h - 1 - cy).abs()));
    let mut step = first;
    let mut ring_at_step = 0;
    let mut radius = 0;
    std::iter::from_fn(move || {
        if radius >= reach || w <= 0 || h <= 0 {
            return None;
        }
        if ring_at_step == rings_per_step && step < max_step {
            step = (2 * step).min(max_step);
            ring_at_step = 0;
        }
        radius += step;
        ring_at_step += 1;
        // Probes just beyond the border (less than a step) move onto it, so the border rows and
        // columns are covered as densely as the inside; farther ones are dropped.
        let s = step;
        Some(ring(cx, cy, radius, step).filter_map(move |(x, y)| {
            let outside = (-x).max(x - (w - 1)).max((-y).max(y - (h - 1)));
            (outside < s).then(|| (x.clamp(0, w - 1), y.clamp(0, h - 1)))
        }))
    })
    .flatten()
}

/// The probes of the square ring at Chebyshev `radius` around `(cx, cy)`, `step` apart,
/// clockwise from the top-left corner.
fn ring(cx: i64, cy: i64, radius: i64, step: i64) -> impl Iterator<Item = (i64, i64)> {
    let n = (2 * radius + step - 1) / step; // probes per side (corner shared with the next)
    let side = move |k: i64| (-radius + k * step).min(radius);
    let top = (0..n).map(move |k| (cx + side(k), cy - radius));
    let right = (0..n).map(move |k| (cx + radius, cy + side(k)));
    let bottom = (0..n).map(move |k| (cx - side(k), cy + radius));
    let left = (0..n).map(move |k| (cx - radius, cy - side(k)));
    top.chain(right).chain(bottom).chain(left)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Chebyshev distance from every pixel to its nearest probe (the centre counts as probed).
    fn worst_gap(center: (i64, i64), w: u32, h: u32, params: &SpiralParams) -> i64 {
        let mut probes: Vec<(i64, i64)> = spiral_points(center, w, h, params).collect();
        probes.push(center);
        let mut worst = 0;
        for y in 0..i64::from(h) {
            for x in 0..i64::from(w) {
                let d = probes
                    .iter()
                    .map(|&(px, py)| (px - x).abs().max((py - y).abs()))
                    .min()
                    .unwrap();
                worst = worst.max(d);
            }
        }
        worst
    }

    #[test]
    fn spiral_search_covers_the_image_from_anywhere() {
        let params = SpiralParams::default();
        for (center, w, h) in [
            ((50, 40), 100, 80),
            ((0, 0), 97, 61),
            ((96, 60), 97, 61),
            ((10, 70), 120, 75),
            ((-30, 200), 64, 48), // a centre outside the image still covers it
        ] {
            let gap = worst_gap(center, w, h, &params);
            assert!(
                gap <= i64::from(params.max_step_px) / 2,
                "{center:?} in {w}x{h}: a pixel is {gap} px from every probe"
            );
        }
        // A coarser grid leaves larger gaps, but still bounded by half its step.
        let coarse = SpiralParams {
            first_step_px: 3,
            rings_per_step: 2,
            max_step_px: 16,
        };
        assert!(worst_gap((40, 30), 90, 70, &coarse) <= 8);
    }

    #[test]
    fn probes_start_near_the_centre_with_the_small_step_and_stay_inside() {
        let params = SpiralParams::default();
        let probes: Vec<(i64, i64)> = spiral_points((50, 50), 200, 150, &params).collect();
        // First ring: the 8 neighbours at distance 2, clockwise from the top-left.
        assert_eq!(
            probes[..8],
            [
                (48, 48),
                (50, 48),
                (52, 48),
                (52, 50),
                (52, 52),
                (50, 52),
                (48, 52),
                (48, 50)
            ]
        );
        let cheb = |&(x, y): &(i64, i64)| (x - 50).abs().max((y - 50).abs());
        // Rings never shrink (probes moved onto the border aside), and the early rings use the
        // small step.
        let inner: Vec<(i64, i64)> = probes
            .iter()
            .copied()
            .filter(|&(x, y)| x > 0 && y > 0 && x < 199 && y < 149)
            .collect();
        assert!(inner.windows(2).all(|p| cheb(&p[0]) <= cheb(&p[1])));
        assert!(probes.iter().take(40).all(|p| cheb(p) <= 8));
        assert!(probes
            .iter()
            .all(|&(x, y)| (0..200).contains(&x) && (0..150).contains(&y)));
        // Far fewer probes than pixels: the grid coarsens away from the centre.
        assert!(probes.len() < 200 * 150 / 40, "{}", probes.len());
    }
}
