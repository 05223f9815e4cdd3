//! Merging arcs that belong to one circle (not in seed 004).
//!
//! The paper closes a group of centre estimates "when a sharp variation in the position of the
//! estimated center is detected". Where the colour mask follows only part of a fruit — its
//! sunlit side, with the shaded side or a highlight left out, or an outline broken by a leaf or
//! a twig — one fruit gives several groups, each a circle of part of it, often smaller than the
//! fruit and off its centre; the overlap pruning then keeps one of them. Here two arcs are merged
//! when their contour points, together, lie on one circle: the geometric least-squares circle of
//! the union ([`crate::fit_circle`] refined by [`crate::refine_circle`]) has a root-mean-square
//! distance of at most `max_rms` times its radius. Candidates are pairs of which one circle's
//! centre lies inside the other circle (pieces of one fruit give circles around its centre;
//! neighbouring fruit give circles about two radii apart); the pair that fits best is merged
//! first, and merging repeats until no pair fits.
//!
//! Two touching fruit do not merge: the union of their outer arcs is not one circle (for two
//! equal fruit side by side the best circle through both arcs misses them by about a fifth of
//! its radius). `max_rms = 0` merges nothing (the paper's behaviour).
//!
//! Nor does a merge make a circle larger than `max_radius_px`, the largest fruit the size test
//! could accept: the fit quality is relative to the radius, so nearly straight outlines (a
//! branch, the edge of a sunlit patch of leaves) pass it as ever larger circles. On a real
//! 1920×1080 orchard frame seen by a model trained on oranges, 64 such arcs merged one by one
//! into a circle of 1247 px radius, every merge refitting the growing set against every other
//! arc: 143 000 least-squares fits, 4.7 s for the frame.

use pomona_core::nalgebra::{Point2, Vector2};

use crate::circle_least_squares::{refine_circle_with_cost, solve3};
use crate::contour_circles::{step_points, step_support};
use crate::hough_circles::coverage;
use crate::{fit_circle, fit_ellipse, Contour, ContourArc, ContourCircle, EdgeFitParams};

/// Gauss–Newton steps of the geometric refinement of a merged circle.
const REFINE_ITERATIONS: usize = 10;

/// How far above `max_rms` the screening fit of a pair may lie and still be fitted: the
/// algebraic circle's distances bound the geometric optimum's from above but can be several
/// times larger on short arcs.
const SCREEN: f64 = 3.0;

/// Pieces of contour: (contour index, that contour's covered steps).
type Pieces = Vec<(usize, Vec<usize>)>;

/// A set of arcs (contour index, that contour's covered steps) with their common circle.
#[derive(Debug, Clone)]
struct Merged {
    pieces: Pieces,
    circle: ContourCircle,
    /// Sums over the pieces' points for the screening fit ([`Moments`]).
    moments: Moments,
}

/// The sums that give a set's algebraic (Kåsa) circle and its residual without visiting the
/// points again, so that a pair is screened in constant time: n, Σx, Σy, Σx², Σxy, Σy², Σxs,
/// Σys, Σs, Σs² with s = x² + y², in coordinates relative to a common origin. Added over the
/// pieces of a pair, points that two pieces of one contour share count twice (screening only).
#[derive(Debug, Clone, Copy, Default)]
struct Moments([f64; 10]);

impl Moments {
    fn of(points: &[Point2<f64>], origin: Point2<f64>) -> Self {
        let mut m = [0.0; 10];
        for p in points {
            let (x, y) = (p.x - origin.x, p.y - origin.y);
            let s = x * x + y * y;
            for (acc, v) in
                m.iter_mut()
                    .zip([1.0, x, y, x * x, x * y, y * y, x * s, y * s, s, s * s])
            {
                *acc += v;
            }
        }
        Self(m)
    }

    /// The mean of the points, relative to the common origin.
    fn mean(&self) -> Option<Vector2<f64>> {
        let [n, sx, sy, ..] = self.0;
        (n > 0.0).then(|| Vector2::new(sx / n, sy / n))
    }

    fn plus(&self, other: &Self) -> Self {
        Self(std::array::from_fn(|k| self.0[k] + other.0[k]))
    }

    /// The algebraic circle's radius and its root-mean-square distance over that radius,
    /// approximated from the algebraic residual (|p − c|² − r² ≈ 2r (|p − c| − r) near the
    /// circle).
    fn screen(&self) -> Option<(f64, f64)> {
        let [n, sx, sy, sxx, sxy, syy, sxs, sys, ss, sss] = self.0;
        if n < 3.0 {
            return None;
        }
        let [d, e, f] = solve3(
            [[sxx, sxy, sx], [sxy, syy, sy], [sx, sy, n]],
            [-sxs, -sys, -ss],
        )?;
        let r2 = (d * d + e * e) / 4.0 - f;
        if r2.is_nan() || r2 <= 0.0 {
            return None;
        }
        let residual = sss
            + d * d * sxx
            + e * e * syy
            + f * f * n
            + 2.0 * (d * sxs + e * sys + f * ss + d * e * sxy + d * f * sx + e * f * sy);
        let r = r2.sqrt();
        Some((r, (residual.max(0.0) / n).sqrt() / (2.0 * r * r)))
    }
}

/// The circles of `arcs` (each with the index of its contour in `contours`) after merging those
/// that lie on one circle of radius at most `max_radius_px` (see the module docs), with the
/// merge settings of `params` (`merge_max_rms` is the module docs' `max_rms`). Arcs are
/// returned unchanged, in their order, when `max_rms <= 0`; merged circles take the place of
/// the first of their arcs. With `merge_ellipse_min_axis_ratio > 0`, the circles of pairs left
/// apart that lie on one ellipse follow (`ellipse_circle` below); the pair's own circles stay.
pub fn merge_arcs(
    contours: &[Contour],
    arcs: Vec<(usize, ContourArc)>,
    params: &EdgeFitParams,
    max_radius_px: f64,
) -> Vec<ContourCircle> {
    let (max_rms, min_ellipse_axis_ratio) =
        (params.merge_max_rms, params.merge_ellipse_min_axis_ratio);
    let arcs: Vec<(usize, ContourArc)> = arcs
        .into_iter()
        .filter(|(c, _)| *c < contours.len())
        .collect();
    let origin = arcs
        .first()
        .and_then(|(c, _)| contours[*c].points.first().copied())
        .unwrap_or_else(Point2::origin);
    let mut sets: Vec<Option<Merged>> = arcs
        .into_iter()
        .map(|(c, a)| {
            let points = step_points(&contours[c].points, &a.step_indices);
            Some(Merged {
                moments: Moments::of(&points, origin),
                pieces: vec![(c, a.step_indices)],
                circle: a.circle,
            })
        })
        .collect();
    if max_rms > 0.0 {
        // Qualifying pairs only (most pairs fail the centre test), as (quality, i, j, merged).
        let mut candidates: Vec<(f64, usize, usize, Merged)> = Vec::new();
        for i in 0..sets.len() {
            for j in i + 1..sets.len() {
                if let Some((q, m)) = pair_fit(contours, &sets, (i, j), max_rms, max_radius_px) {
                    candidates.push((q, i, j, m));
                }
            }
        }
        while let Some(best) = candidates
            .iter()
            .enumerate()
            .min_by(|a, b| a.1 .0.total_cmp(&b.1 .0).then(a.0.cmp(&b.0)))
            .map(|(k, _)| k)
        {
            let (_, i, j, merged) = candidates.swap_remove(best);
            sets[i] = Some(merged);
            sets[j] = None;
            candidates.retain(|c| c.1 != i && c.2 != i && c.1 != j && c.2 != j);
            for other in 0..sets.len() {
                if other != i {
                    let (lo, hi) = (other.min(i), other.max(i));
                    if let Some((q, m)) =
                        pair_fit(contours, &sets, (lo, hi), max_rms, max_radius_px)
                    {
                        candidates.push((q, lo, hi, m));
                    }
                }
            }
        }
    }
    let mut circles: Vec<ContourCircle> = sets.iter().flatten().map(|m| m.circle).collect();
    if max_rms > 0.0 && min_ellipse_axis_ratio > 0.0 {
        let left: Vec<&Merged> = sets.iter().flatten().collect();
        for (k, a) in left.iter().enumerate() {
            for b in &left[k + 1..] {
                circles.extend(ellipse_circle(
                    contours,
                    origin,
                    (a, b),
                    max_rms,
                    min_ellipse_axis_ratio,
                    max_radius_px,
                ));
            }
        }
    }
    circles
}

/// Directions around an ellipse's centre in which a pair's coverage is counted.
const ELLIPSE_BINS: usize = 64;

/// Two arcs face each other when the directions in which they bulge are at least 120° apart
/// (cosine at most −0.5).
const FACING_COS: f64 = 0.5;

/// The fruit circle of two sets that do not lie on one circle but, together, on one ellipse:
/// one's centre inside the other's circle (as for a circle merge), the ellipse's shorter axis at
/// least `min_axis_ratio` of its longer, its root-mean-square distance from the points at most
/// `max_rms` of the shorter semi-axis, and the points covering at least half the directions
/// around its centre (arcs on opposite sides of one fruit; one arc alone fixes no ellipse). The
/// circle is centred on the ellipse with the semi-axis nearer the image rows as radius — the
/// width of a hanging fruit, oblate or long — and at most `max_radius_px`.
fn ellipse_circle(
    contours: &[Contour],
    origin: Point2<f64>,
    (a, b): (&Merged, &Merged),
    max_rms: f64,
    min_axis_ratio: f64,
    max_radius_px: f64,
) -> Option<ContourCircle> {
    if !one_centre_inside_the_other(a, b) {
        return None;
    }
    // Arcs on opposite sides of one fruit face each other: each bulges away from its circle's
    // centre, the two in opposite directions (checked on the sums, before any point is read).
    let bulge = |m: &Merged| Some(m.moments.mean()? - (m.circle.center_px - origin));
    let (ua, ub) = (bulge(a)?, bulge(b)?);
    if ua.dot(&ub) > -FACING_COS * ua.norm() * ub.norm() {
        return None;
    }
    let (pieces, points) = joined(contours, a, b);
    let fit = fit_ellipse(&points)?;
    let e = fit.ellipse;
    let short = e.semi_axes_px.0.min(e.semi_axes_px.1);
    let radius_px = e.horizontal_semi_axis_px();
    if e.axis_ratio() < min_axis_ratio || fit.rms_px > max_rms * short || radius_px > max_radius_px
    {
        return None;
    }
    if coverage(&points, e.center_px, ELLIPSE_BINS) < 0.5 {
        return None;
    }
    let support = support_of(contours, &pieces, radius_px);
    Some(ContourCircle {
        center_px: e.center_px,
        radius_px,
        support,
    })
}

/// The merged set of `sets[i]` and `sets[j]` and its root-mean-square distance over its radius,
/// when both exist, one's centre lies inside the other's circle, that distance is at most
/// `max_rms` and the merged radius at most `max_radius_px`.
fn pair_fit(
    contours: &[Contour],
    sets: &[Option<Merged>],
    (i, j): (usize, usize),
    max_rms: f64,
    max_radius_px: f64,
) -> Option<(f64, Merged)> {
    let (a, b) = (sets[i].as_ref()?, sets[j].as_ref()?);
    if !one_centre_inside_the_other(a, b) {
        return None;
    }
    // Screening on the summed moments (constant time) before the points are visited.
    let (screen_radius, screen_rms) = a.moments.plus(&b.moments).screen()?;
    debug_assert!(screen_rms >= 0.0);
    if screen_rms.is_nan() || screen_rms > SCREEN * max_rms {
        return None;
    }
    // The algebraic circle of a set far beyond the cap is not refined (its geometric circle
    // would be refused below anyway, unless the two differ by more than a factor SCREEN).
    if screen_radius > SCREEN * max_radius_px {
        return None;
    }
    let (pieces, points) = joined(contours, a, b);
    let ((center_px, radius_px), cost) = fit_circle(&points)
        .and_then(|start| refine_circle_with_cost(&points, start, REFINE_ITERATIONS))?;
    if radius_px > max_radius_px {
        return None;
    }
    // The root-mean-square distance (as `rms_distance`) over the radius.
    let quality = (cost / points.len() as f64).sqrt() / radius_px;
    if quality.is_nan() || quality > max_rms {
        return None;
    }
    let support = support_of(contours, &pieces, radius_px);
    Some((
        quality,
        Merged {
            moments: a.moments.plus(&b.moments),
            pieces,
            circle: ContourCircle {
                center_px,
                radius_px,
                support,
            },
        },
    ))
}

/// Whether one set's centre lies inside the other's circle (pieces of one fruit), the test a
/// pair passes before it is fitted.
fn one_centre_inside_the_other(a: &Merged, b: &Merged) -> bool {
    let (ca, cb) = (&a.circle, &b.circle);
    (ca.center_px - cb.center_px).norm() <= ca.radius_px.max(cb.radius_px)
}

/// The pieces of two sets together ([`union_pieces`]) and their contour points.
fn joined(contours: &[Contour], a: &Merged, b: &Merged) -> (Pieces, Vec<Point2<f64>>) {
    let pieces = union_pieces(&a.pieces, &b.pieces);
    let points = pieces
        .iter()
        .flat_map(|(c, steps)| step_points(&contours[*c].points, steps))
        .collect();
    (pieces, points)
}

/// The support of a circle of `radius_px` on `pieces`: their arc length over its
/// circumference, at most 1.
fn support_of(contours: &[Contour], pieces: &[(usize, Vec<usize>)], radius_px: f64) -> f64 {
    pieces
        .iter()
        .map(|(c, steps)| step_support(&contours[*c].points, steps, radius_px))
        .sum::<f64>()
        .min(1.0)
}

/// The pieces of both sets, steps of one contour joined into one sorted list without repeats.
fn union_pieces(a: &[(usize, Vec<usize>)], b: &[(usize, Vec<usize>)]) -> Pieces {
    let mut out: Pieces = a.to_vec();
    for (c, steps) in b {
        match out.iter_mut().find(|(oc, _)| oc == c) {
            Some((_, existing)) => {
                existing.extend_from_slice(steps);
                existing.sort_unstable();
                existing.dedup();
            }
            None => out.push((*c, steps.clone())),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The edge fit's settings with these two merge settings.
    fn merging(merge_max_rms: f64, merge_ellipse_min_axis_ratio: f64) -> EdgeFitParams {
        EdgeFitParams {
            merge_max_rms,
            merge_ellipse_min_axis_ratio,
            ..EdgeFitParams::default()
        }
    }

    /// A closed contour: `n` points on a circle.
    fn ring(c: (f64, f64), r: f64, n: usize) -> Contour {
        Contour {
            points: (0..n)
                .map(|i| {
                    let a = i as f64 * std::f64::consts::TAU / n as f64;
                    Point2::new(c.0 + r * a.cos(), c.1 + r * a.sin())
                })
                .collect(),
            area_px: 0,
        }
    }

    fn arc(steps: std::ops::Range<usize>, center: (f64, f64), r: f64) -> ContourArc {
        ContourArc {
            circle: ContourCircle {
                center_px: Point2::new(center.0, center.1),
                radius_px: r,
                support: 0.1,
            },
            step_indices: steps.collect(),
        }
    }

    #[test]
    fn two_pieces_of_one_circle_merge_into_it() {
        let c = ring((50.0, 40.0), 30.0, 200);
        // Two arcs of the same circle whose own circles came out small and off-centre.
        let arcs = vec![
            (0, arc(0..40, (55.0, 45.0), 18.0)),
            (0, arc(90..130, (45.0, 38.0), 17.0)),
        ];
        let merged = merge_arcs(
            std::slice::from_ref(&c),
            arcs.clone(),
            &merging(0.04, 0.0),
            f64::INFINITY,
        );
        assert_eq!(merged.len(), 1, "{merged:?}");
        let m = merged[0];
        assert!(
            (m.center_px - Point2::new(50.0, 40.0)).norm() < 1e-6,
            "{m:?}"
        );
        assert!((m.radius_px - 30.0).abs() < 1e-6);
        assert!((m.support - 80.0 / 200.0).abs() < 0.01, "{}", m.support);
        // Off: the arcs stay as they were.
        let kept = merge_arcs(&[c], arcs, &merging(0.0, 0.0), f64::INFINITY);
        assert_eq!(kept.len(), 2);
        assert_eq!(kept[0].radius_px, 18.0);
    }

    /// Pieces of a wide outline lie on one circle larger than any fruit; the cap keeps them
    /// apart, while pieces of a fruit-sized circle still merge under the same cap.
    #[test]
    fn no_merge_makes_a_circle_larger_than_the_cap() {
        let huge = ring((0.0, 250.0), 250.0, 1000);
        let arcs = vec![
            (0, arc(100..250, (0.0, 240.0), 240.0)),
            (0, arc(300..450, (0.0, 260.0), 260.0)),
        ];
        let free = merge_arcs(
            std::slice::from_ref(&huge),
            arcs.clone(),
            &merging(0.04, 0.0),
            f64::INFINITY,
        );
        assert_eq!(free.len(), 1, "{free:?}");
        assert!((free[0].radius_px - 250.0).abs() < 1e-3);
        let capped = merge_arcs(
            std::slice::from_ref(&huge),
            arcs,
            &merging(0.04, 0.0),
            150.0,
        );
        assert_eq!(capped.len(), 2, "{capped:?}");
        let fruit = ring((50.0, 40.0), 30.0, 200);
        let pieces = vec![
            (0, arc(0..40, (55.0, 45.0), 18.0)),
            (0, arc(90..130, (45.0, 38.0), 17.0)),
        ];
        assert_eq!(
            merge_arcs(&[fruit], pieces, &merging(0.04, 0.0), 150.0).len(),
            1
        );
    }

    #[test]
    fn arcs_of_two_touching_circles_stay_apart() {
        let (a, b) = (ring((30.0, 30.0), 20.0, 120), ring((70.0, 30.0), 20.0, 120));
        // The left half of a and the right half of b, each with its own circle.
        let mut right = arc(0..30, (70.0, 30.0), 20.0);
        right.step_indices.extend(90..120);
        let arcs = vec![(0, arc(30..90, (30.0, 30.0), 20.0)), (1, right)];
        let merged = merge_arcs(&[a, b], arcs, &merging(0.04, 0.0), f64::INFINITY);
        assert_eq!(merged.len(), 2, "{merged:?}");
        // Circles that neither touch nor overlap are never candidates.
        let far = vec![
            (0, arc(0..40, (30.0, 30.0), 20.0)),
            (1, arc(0..40, (300.0, 30.0), 20.0)),
        ];
        let far_contours = [ring((30.0, 30.0), 20.0, 120), ring((30.0, 30.0), 20.0, 120)];
        assert_eq!(
            merge_arcs(&far_contours, far, &merging(0.5, 0.0), f64::INFINITY).len(),
            2
        );
    }

    #[test]
    fn a_fruit_cut_in_two_by_a_branch_gives_one_circle() {
        // A disc of radius 30 px crossed by a 6 px band (a branch): two components, two
        // contours, each with a circle of part of the fruit.
        let (w, h, cx, cy, r) = (140usize, 120usize, 70.0, 60.0, 30.0);
        let mask: Vec<bool> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                (x - cx).powi(2) + (y - cy).powi(2) <= r * r && !(x - y - 10.0).abs().lt(&4.0)
            })
            .collect();
        let params = crate::EdgeFitParams::default();
        let (contours, arcs) = arcs_of_mask(&mask, w, &params);
        assert_eq!(contours.len(), 2);
        assert!(arcs.len() >= 2, "{arcs:?}");
        let merged = merge_arcs(
            &contours,
            arcs,
            &merging(params.merge_max_rms, 0.0),
            f64::INFINITY,
        );
        let best = merged
            .iter()
            .max_by(|a, b| a.support.total_cmp(&b.support))
            .unwrap();
        assert!(
            (best.center_px - Point2::new(cx, cy)).norm() < 0.1 * r,
            "{merged:?}"
        );
        assert!((best.radius_px - r).abs() < 0.1 * r, "{merged:?}");
        assert!(best.support > 0.6, "{merged:?}");
    }

    /// The edge fit's arcs of a row-major mask, traced and smoothed as the stages do.
    fn arcs_of_mask(
        mask: &[bool],
        w: usize,
        params: &crate::EdgeFitParams,
    ) -> (Vec<Contour>, Vec<(usize, ContourArc)>) {
        let h = mask.len() / w;
        let contours: Vec<Contour> =
            crate::trace_contours(&crate::smooth_mask(mask, w, h), w, h, 20)
                .iter()
                .map(|c| c.smoothed(params.smoothing_half_window))
                .collect();
        let arcs = contours
            .iter()
            .enumerate()
            .flat_map(|(k, c)| {
                crate::contour_arcs(c, params)
                    .into_iter()
                    .map(move |a| (k, a))
            })
            .collect();
        (contours, arcs)
    }

    #[test]
    fn an_oblate_fruit_between_two_neighbours_gets_its_circle_from_its_ellipse() {
        // A fruit 60 px wide and 48 px tall whose sides touch two round neighbours: its outline
        // is its top and bottom arcs, each flatter than its width.
        let (w, h, cx, cy) = (220usize, 120usize, 110.0, 60.0);
        let mask: Vec<bool> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                ((x - cx) / 30.0).powi(2) + ((y - cy) / 24.0).powi(2) <= 1.0
                    || (x - cx + 52.0).hypot(y - cy) <= 25.0
                    || (x - cx - 52.0).hypot(y - cy) <= 25.0
            })
            .collect();
        let params = crate::EdgeFitParams {
            merge_ellipse_min_axis_ratio: 0.55,
            ..crate::EdgeFitParams::default()
        };
        let (contours, arcs) = arcs_of_mask(&mask, w, &params);
        let found = |ratio: f64| {
            merge_arcs(
                &contours,
                arcs.clone(),
                &merging(params.merge_max_rms, ratio),
                100.0,
            )
            .into_iter()
            .filter(|c| (c.center_px - Point2::new(cx, cy)).norm() < 0.2 * 30.0)
            .filter(|c| (c.radius_px - 30.0).abs() < 0.15 * 30.0)
            .collect::<Vec<_>>()
        };
        let with = found(params.merge_ellipse_min_axis_ratio);
        assert!(
            !with.is_empty(),
            "{:?}",
            merge_arcs(&contours, arcs.clone(), &merging(0.04, 0.55), 100.0)
        );
        assert!(found(0.0).is_empty(), "{:?}", found(0.0));
    }

    #[test]
    fn two_touching_round_fruit_make_no_ellipse() {
        let (w, h) = (200usize, 100usize);
        let mask: Vec<bool> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                (x - 75.0).hypot(y - 50.0) <= 25.0 || (x - 123.0).hypot(y - 50.0) <= 25.0
            })
            .collect();
        let params = crate::EdgeFitParams {
            merge_ellipse_min_axis_ratio: 0.55,
            ..crate::EdgeFitParams::default()
        };
        let (contours, arcs) = arcs_of_mask(&mask, w, &params);
        let circles = merge_arcs(&contours, arcs.clone(), &params, 100.0);
        // Nothing between the two fruit, and nothing more than without the ellipses.
        assert_eq!(
            circles,
            merge_arcs(&contours, arcs, &merging(params.merge_max_rms, 0.0), 100.0)
        );
    }
}
