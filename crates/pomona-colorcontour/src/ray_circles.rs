//! Circles from rays cast out of the mask's inscribed discs (not in seed 004; off unless a
//! model asks for it).
//!
//! The edge fit ([`crate::contour_circles`]) reads curvature along outlines. Where fruit touch
//! in a row or overlap, each fruit's share of the common outline is a short arc between two
//! notches, too short for its windows, while the outer arcs of the neighbours fit one large
//! circle together; such fruit get no circle of their own, though the mask shows them whole.
//! Their centres are still plain in the mask's distance transform
//! ([`crate::squared_distance_to_background`]): each fruit has its own inscribed disc, a local
//! maximum. From each such centre this stage casts `rays` rays, each stopping where the mask
//! ends. The ends that lie on the fruit's own outline fit one circle; rays that slip into a
//! neighbour through the neck, stop short at a leaf, reach the image border or run too far give
//! no edge or an outlier. The circle is the one with the most ray ends on it among the circles
//! through three ends spread around the centre (ends `i`, `i + k`, `i + 2k`, for spans `k` of
//! 45°, 60°, 90° and 120°: a fixed set of hypotheses, so no sampling and no seed), refitted by
//! least squares on those ends; its support is the fraction of rays that ended on it — the
//! fraction of directions in which the outline agrees, the counterpart of the edge fit's arc
//! fraction, so both kinds of circle go through the same size test, scoring and pruning.
//!
//! This is the tracker's scan of seed 004 §3.3 (edges found by scanning outwards from a point
//! of fruit, and a circle through them; [`crate::scan_four_directions`]) in more directions,
//! with a robust fit, started from every inscribed-disc centre instead of the tracked one.

use pomona_core::nalgebra::{Point2, Vector2};
use serde::{Deserialize, Serialize};

use crate::local_maxima::local_maxima;
use crate::{fit_circle, refine_circle, squared_distance_to_background, ContourCircle};

/// Settings of the ray circles (a model file may leave any of them out: the default is used).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RayCircleParams {
    /// Rays cast from each centre, evenly spread (at least 8).
    pub rays: usize,
    /// Inscribed discs smaller than this radius, pixels, cast no rays (leaf slivers, noise).
    pub min_inscribed_px: f64,
    /// A centre is a pixel whose distance to the background is the largest within this many
    /// pixels in x and y (a `2w + 1` square; ties go to the first in raster order).
    pub peak_half_window_px: usize,
    /// A ray that runs farther than this many inscribed radii without leaving the mask gives
    /// no edge (it crossed into a neighbour).
    pub max_reach: f64,
    /// A ray end is on a circle when within this many pixels of it, or within
    /// `inlier_fraction` of the radius if that is larger.
    pub inlier_px: f64,
    /// See `inlier_px`.
    pub inlier_fraction: f64,
    /// Circles larger than this many inscribed radii are not hypotheses (the inscribed disc of
    /// a half-hidden fruit is about half its circle, of a lone one all of it).
    pub max_radius_ratio: f64,
    /// Rays that must end on a circle for it to be kept.
    pub min_inliers: usize,
}

impl Default for RayCircleParams {
    fn default() -> Self {
        Self {
            rays: 32,
            min_inscribed_px: 6.0,
            peak_half_window_px: 3,
            max_reach: 3.0,
            inlier_px: 1.5,
            inlier_fraction: 0.08,
            max_radius_ratio: 2.5,
            min_inliers: 16,
        }
    }
}

impl RayCircleParams {
    /// Why the settings cannot run, or `None`.
    pub fn problem(&self) -> Option<(&'static str, &'static str)> {
        if self.rays < 8 {
            return Some(("ray_circles.rays", "must be at least 8"));
        }
        if !(self.min_inscribed_px.is_finite() && self.min_inscribed_px >= 1.0) {
            return Some(("ray_circles.min_inscribed_px", "must be at least 1"));
        }
        if !(self.max_reach.is_finite() && self.max_reach > 1.0) {
            return Some(("ray_circles.max_reach", "must be finite and above 1"));
        }
        if !(self.inlier_px.is_finite() && self.inlier_px > 0.0) {
            return Some(("ray_circles.inlier_px", "must be positive"));
        }
        if !(self.inlier_fraction.is_finite() && self.inlier_fraction >= 0.0) {
            return Some(("ray_circles.inlier_fraction", "must be 0 or positive"));
        }
        if !(self.max_radius_ratio.is_finite() && self.max_radius_ratio >= 1.0) {
            return Some(("ray_circles.max_radius_ratio", "must be at least 1"));
        }
        if !(3..=self.rays).contains(&self.min_inliers) {
            return Some(("ray_circles.min_inliers", "must lie in [3, rays]"));
        }
        None
    }
}

/// The ray circles of a row-major `width`-wide fruit mask (see the module docs), one per
/// inscribed-disc centre that gives one.
pub fn ray_circles(mask: &[bool], width: usize, params: &RayCircleParams) -> Vec<ContourCircle> {
    let width = width.max(1);
    let height = mask.len() / width;
    let squared = squared_distance_to_background(mask, width, height);
    inscribed_centers(&squared, width, height, params)
        .into_iter()
        .filter_map(|(center, inscribed)| {
            let ends = ray_ends(mask, width, height, center, inscribed, params);
            circle_through_ends(&ends, center, inscribed, params)
        })
        .collect()
}

/// Local maxima of the distance transform (`squared`, pixels²) at least `min_inscribed_px`
/// deep: `(centre, inscribed radius)`.
fn inscribed_centers(
    squared: &[f32],
    width: usize,
    height: usize,
    params: &RayCircleParams,
) -> Vec<(Point2<f64>, f64)> {
    let min_sq = (params.min_inscribed_px * params.min_inscribed_px) as f32;
    let width = width.max(1);
    local_maxima(
        &squared[..width * height],
        width,
        params.peak_half_window_px,
        |v| v >= min_sq && v.is_finite(),
    )
    .into_iter()
    .map(|k| {
        let center = Point2::new((k % width) as f64, (k / width) as f64);
        (center, f64::from(squared[k].sqrt()))
    })
    .collect()
}

/// Where each ray from `center` leaves the mask (`None`: it reached the image border or
/// `max_reach` inscribed radii first).
fn ray_ends(
    mask: &[bool],
    width: usize,
    height: usize,
    center: Point2<f64>,
    inscribed: f64,
    params: &RayCircleParams,
) -> Vec<Option<Point2<f64>>> {
    const STEP_PX: f64 = 0.5;
    let reach = params.max_reach * inscribed;
    (0..params.rays)
        .map(|i| {
            let angle = std::f64::consts::TAU * i as f64 / params.rays as f64;
            let dir = Vector2::new(angle.cos(), angle.sin());
            // Every pixel nearer than the inscribed radius is fruit.
            let mut d = (inscribed - 1.0).max(0.0);
            loop {
                let next = d + STEP_PX;
                if next > reach {
                    return None;
                }
                let p = center + dir * next;
                let (px, py) = (p.x.round(), p.y.round());
                if px < 0.0 || py < 0.0 || px >= width as f64 || py >= height as f64 {
                    return None;
                }
                if !mask[py as usize * width + px as usize] {
                    // The outline lies between the last fruit sample and the first other one.
                    return Some(center + dir * (d + 0.5 * STEP_PX));
                }
                d = next;
            }
        })
        .collect()
}

/// The best circle through the ends of the rays cast from `center` (inscribed radius
/// `inscribed`), in ray order (see the module docs).
fn circle_through_ends(
    ends: &[Option<Point2<f64>>],
    center: Point2<f64>,
    inscribed: f64,
    params: &RayCircleParams,
) -> Option<ContourCircle> {
    let n = ends.len();
    let edges: Vec<Point2<f64>> = ends.iter().flatten().copied().collect();
    if edges.len() < params.min_inliers {
        return None;
    }
    let tolerance = |r: f64| params.inlier_px.max(params.inlier_fraction * r);
    let is_on =
        |(c, r): (Point2<f64>, f64), p: &Point2<f64>| ((p - c).norm() - r).abs() <= tolerance(r);
    let count_on = |circle: (Point2<f64>, f64)| edges.iter().filter(|p| is_on(circle, p)).count();
    let plausible = |(c, r): (Point2<f64>, f64)| {
        r >= inscribed * 0.9 && r <= params.max_radius_ratio * inscribed && (center - c).norm() < r
    };
    let mut best: Option<((Point2<f64>, f64), usize)> = None;
    'spans: for span in [8, 6, 4, 3].map(|parts| (n / parts).max(1)) {
        for i in 0..n {
            // A hypothesis on every end cannot be beaten (later ones must do strictly better).
            if best.is_some_and(|(_, b)| b == edges.len()) {
                break 'spans;
            }
            let (Some(a), Some(b), Some(c)) =
                (ends[i], ends[(i + span) % n], ends[(i + 2 * span) % n])
            else {
                continue;
            };
            let Some(circle) = fit_circle(&[a, b, c]).filter(|&c| plausible(c)) else {
                continue;
            };
            let count = count_on(circle);
            if best.is_none_or(|(_, b)| count > b) {
                best = Some((circle, count));
            }
        }
    }
    let (hypothesis, count) = best?;
    let inliers: Vec<Point2<f64>> = edges
        .iter()
        .filter(|p| is_on(hypothesis, p))
        .copied()
        .collect();
    // Refit on the ends the hypothesis explains; keep the refit only if it explains as many.
    let (circle, count) = refine_circle(&inliers, hypothesis, 10)
        .filter(|&c| plausible(c))
        .map(|c| (c, count_on(c)))
        .filter(|&(_, k)| k >= count)
        .unwrap_or((hypothesis, count));
    (count >= params.min_inliers).then(|| ContourCircle {
        center_px: circle.0,
        radius_px: circle.1,
        support: count as f64 / n as f64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_shapes::{assert_each_disc_found, mask_of, mask_of_discs, near};

    #[test]
    fn three_touching_discs_in_a_row_each_get_their_circle() {
        // A middle disc smaller than its neighbours: its outline is two short arcs between
        // notches, the case the edge fit misses.
        let discs = [(30.0, 40.0, 16.0), (56.0, 40.0, 11.0), (81.0, 40.0, 15.0)];
        let mask = mask_of_discs(110, 80, &discs);
        let circles = ray_circles(&mask, 110, &RayCircleParams::default());
        assert_each_disc_found(&circles, &discs, 1.5);
    }

    #[test]
    fn a_disc_cut_by_a_leaf_band_keeps_its_circle_from_the_rays_that_reach_its_edge() {
        let mask = mask_of(100, 100, |x, y| {
            (x - 50.0).hypot(y - 50.0) <= 25.0 && !(55.0..62.0).contains(&x)
        });
        let circles = ray_circles(&mask, 100, &RayCircleParams::default());
        let best = circles
            .iter()
            .max_by(|a, b| a.support.total_cmp(&b.support))
            .expect("a circle");
        assert!(near(best, 50.0, 50.0, 25.0, 1.5), "{best:?}");
        assert!(best.support > 0.5, "{best:?}");
    }

    #[test]
    fn a_straight_band_gives_no_circle_and_bad_settings_are_named() {
        let band = mask_of(120, 60, |_, y| (20.0..34.0).contains(&y));
        assert!(ray_circles(&band, 120, &RayCircleParams::default()).is_empty());
        assert!(RayCircleParams::default().problem().is_none());
        let bad = RayCircleParams {
            min_inliers: 2,
            ..RayCircleParams::default()
        };
        assert_eq!(bad.problem().map(|p| p.0), Some("ray_circles.min_inliers"));
        assert!(ray_circles(&[], 0, &RayCircleParams::default()).is_empty());
    }
}
