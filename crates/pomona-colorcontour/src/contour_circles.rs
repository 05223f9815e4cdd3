//! Circles from the curvature of pieces of contour (seed 004 §3.2, "adaptive edge fitting").
//!
//! At every point of a closed contour a window of contour points spans an arc of length `a` with
//! chord `c`; Eq. 8 ([`crate::arc_radius`]) turns them into a radius r, and the window is
//! resized until its arc length is about `arc_per_radius` × r ("adjusted recursively until the
//! length of the arc is near to the value of the radius"). The centre lies at r cos θ from the
//! chord's midpoint, on the side away from the arc. The window then moves one point along the
//! contour. Consecutive centre estimates that stay together belong to one fruit; "when a sharp
//! variation in the position of the estimated center is detected", the estimates gathered so far
//! become one circle — centre and radius are means weighted by the window's point count — and a
//! new group begins.
//!
//! Departures, documented: estimates from concave windows (the notch between two touching
//! fruit) or straight ones (c/a ≥ 1) are not centres of anything and end the current group; a
//! jump is a centre more than `jump_fraction` × the group's mean radius from the group's running
//! mean (the paper gives no number); the first and last groups of a closed contour are joined
//! when they continue each other; a group needs `min_estimates` estimates; and its score is its
//! *support fraction* — the arc length it spans over 2πr, capped at 1 — which the pruning and the
//! detector's score use (the paper's "score accumulated during the edge-fitting process").
//!
//! Two further departures, each off by a setting: the group's circle may be the least-squares
//! circle of the contour points its windows cover ([`GroupCircle::LeastSquares`]: algebraic fit
//! refined geometrically, [`crate::refine_circle`]) instead of the weighted mean of its Eq. 8
//! estimates ([`GroupCircle::WeightedMean`], the paper's). The windows at the ends of a piece of
//! outline straddle its corners and give small circles, which pull the mean radius down and the
//! centre towards the piece; a fit on the points themselves does not. Groups whose points fit one
//! circle together are then merged ([`crate::merge_arcs`]).

use pomona_core::nalgebra::{Point2, Vector2};
use serde::{Deserialize, Serialize};

use crate::contour::next_around;
use crate::{arc_half_angle, fit_circle, refine_circle, Contour};

/// Settings of the adaptive edge fitting.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EdgeFitParams {
    /// Target arc length of a window in radii (paper: the arc is "near to the value of the
    /// radius", i.e. 1).
    pub arc_per_radius: f64,
    /// Relative tolerance on `arc ≈ arc_per_radius × r` before the window stops adapting.
    pub arc_tolerance: f64,
    /// Resizing rounds per window position.
    pub max_adapt_steps: usize,
    /// Smallest window, in contour points.
    pub min_window: usize,
    /// A centre farther than this many mean radii from its group's mean starts a new group.
    pub jump_fraction: f64,
    /// Estimates a group needs to become a circle.
    pub min_estimates: usize,
    /// Half-width of the moving average applied to contour points before fitting.
    pub smoothing_half_window: usize,
    /// How a group of estimates becomes a circle (see [`GroupCircle`]; model files from before
    /// this setting mean the paper's weighted mean).
    #[serde(default)]
    pub group_circle: GroupCircle,
    /// Arcs (groups, on one contour or on neighbouring ones) are merged when their points fit one
    /// circle with a root-mean-square distance of at most this fraction of its radius
    /// ([`crate::merge_arcs`]); 0 = never (the paper's behaviour, and what model files from
    /// before this setting mean).
    #[serde(default)]
    pub merge_max_rms: f64,
    /// Two arcs that fail to lie on one circle are also joined, as one fruit, when their points
    /// fit one ellipse ([`crate::fit_ellipse`]) within `merge_max_rms` of its shorter semi-axis
    /// whose shorter axis is at least this fraction of its longer one, and cover half the
    /// directions around its centre (the top and bottom of an oblate fruit whose sides are
    /// hidden; not in the paper). 0 = never: the default and what model files from before this
    /// setting mean; measured at 0.55 and not adopted (docs/results.md, "Oblate fruit as
    /// ellipses").
    #[serde(default)]
    pub merge_ellipse_min_axis_ratio: f64,
}

/// How the estimates of one group become its circle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GroupCircle {
    /// Centre and radius are the means of the Eq. 8 estimates, weighted by window size (§3.2).
    #[default]
    WeightedMean,
    /// The geometric least-squares circle of the contour points the group's windows cover,
    /// started from the algebraic (Kåsa) fit; the weighted mean where the fit fails.
    LeastSquares,
}

impl EdgeFitParams {
    /// Why the settings cannot run, as (name, reason), or `None` (`merge_max_rms` is checked
    /// with the detector's other settings).
    pub fn problem(&self) -> Option<(&'static str, &'static str)> {
        if !(self.arc_per_radius.is_finite() && self.arc_per_radius > 0.0) {
            return Some(("edge_fit.arc_per_radius", "must be finite and positive"));
        }
        if !(self.arc_tolerance.is_finite() && self.arc_tolerance >= 0.0) {
            return Some(("edge_fit.arc_tolerance", "must be finite and 0 or more"));
        }
        if !(self.jump_fraction.is_finite() && self.jump_fraction > 0.0) {
            return Some(("edge_fit.jump_fraction", "must be finite and positive"));
        }
        if self.min_window < 2 {
            return Some(("edge_fit.min_window", "must be at least 2 contour points"));
        }
        if self.min_estimates == 0 {
            return Some(("edge_fit.min_estimates", "must be at least 1"));
        }
        if !(0.0..=1.0).contains(&self.merge_ellipse_min_axis_ratio) {
            return Some((
                "edge_fit.merge_ellipse_min_axis_ratio",
                "must be 0 (off) or in (0, 1]",
            ));
        }
        None
    }
}

impl Default for EdgeFitParams {
    fn default() -> Self {
        Self {
            arc_per_radius: 1.0,
            arc_tolerance: 0.2,
            max_adapt_steps: 4,
            min_window: 6,
            jump_fraction: 0.3,
            min_estimates: 4,
            smoothing_half_window: 2,
            group_circle: GroupCircle::LeastSquares,
            merge_max_rms: 0.04,
            merge_ellipse_min_axis_ratio: 0.0,
        }
    }
}

/// A circle found on a contour, in pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContourCircle {
    /// Centre, pixel coordinates.
    pub center_px: Point2<f64>,
    /// Radius, pixels.
    pub radius_px: f64,
    /// Arc length the group spans divided by the circumference, in (0, 1] (for ray circles,
    /// the fraction of rays ending on the circle).
    pub support: f64,
}

/// A circle with the piece of contour it was fitted on, what [`crate::merge_arcs`] merges.
#[derive(Debug, Clone, PartialEq)]
pub struct ContourArc {
    /// The group's circle.
    pub circle: ContourCircle,
    /// The contour steps covered by the group's windows, increasing (step `i` joins point `i`
    /// to point `i + 1`, the last one back to point 0).
    pub step_indices: Vec<usize>,
}

/// One centre estimate of a window.
#[derive(Debug, Clone, Copy)]
struct Estimate {
    center: Point2<f64>,
    radius: f64,
    weight: f64,
    /// Contour index at which the window starts and its point count.
    start: usize,
    len: usize,
}

/// A closed contour's arc-length prefix sums, for O(1) window lengths.
struct ArcTable<'a> {
    points: &'a [Point2<f64>],
    /// `cumulative[i]` is the length from point 0 to point `i` (index `n` closes the loop).
    cumulative: Vec<f64>,
}

impl<'a> ArcTable<'a> {
    fn new(points: &'a [Point2<f64>]) -> Self {
        let n = points.len();
        let mut cumulative = Vec::with_capacity(n + 1);
        let mut s = 0.0;
        cumulative.push(0.0);
        for i in 0..n {
            s += (points[next_around(i, n)] - points[i]).norm();
            cumulative.push(s);
        }
        Self { points, cumulative }
    }

    fn total(&self) -> f64 {
        self.cumulative[self.points.len()]
    }

    /// Arc length from point `i` over `len` steps (wrapping).
    fn arc(&self, i: usize, len: usize) -> f64 {
        let n = self.points.len();
        let j = i + len;
        if j <= n {
            self.cumulative[j] - self.cumulative[i]
        } else {
            self.total() - self.cumulative[i] + self.cumulative[j - n]
        }
    }

    /// Point `i`, wrapping once past the end (windows start before it and span at most half
    /// the contour, so `i` < 2n): a subtraction where `i % n` would divide, three times a window.
    fn point(&self, i: usize) -> Point2<f64> {
        let n = self.points.len();
        debug_assert!(i < 2 * n);
        self.points[if i >= n { i - n } else { i }]
    }
}

/// The estimate of the window starting at `i` with `len` steps: `None` for straight or concave
/// pieces. `orientation` is the sign of the contour's signed area.
fn window_estimate(t: &ArcTable, i: usize, len: usize, orientation: f64) -> Option<Estimate> {
    let (p, q) = (t.point(i), t.point(i + len));
    let chord = q - p;
    let c = chord.norm();
    let m = t.point(i + len / 2);
    let bulge = chord.perp(&(m - p));
    // Convex (bulging outwards) pieces turn against the contour's orientation. Tested before
    // Eq. 8 is solved: about half the windows of a real orchard mask fail here.
    if bulge * orientation >= 0.0 || c == 0.0 {
        return None;
    }
    let a = t.arc(i, len);
    let theta = arc_half_angle(c / a)?;
    let r = a / (2.0 * theta);
    // Unit normal of the chord towards the bulge; the centre is on the other side.
    let mut normal = Vector2::new(-chord.y, chord.x) / c;
    if normal.dot(&(m - p)) < 0.0 {
        normal = -normal;
    }
    let mid = p + chord / 2.0;
    Some(Estimate {
        center: mid - normal * (r * theta.cos()),
        radius: r,
        weight: len as f64,
        start: i,
        len,
    })
}

/// Every circle the adaptive edge fitting finds on `contour` (already smoothed).
pub fn contour_circles(contour: &Contour, params: &EdgeFitParams) -> Vec<ContourCircle> {
    contour_arcs(contour, params)
        .into_iter()
        .map(|a| a.circle)
        .collect()
}

/// Every circle the adaptive edge fitting finds on `contour` (already smoothed), with the
/// piece of contour each was fitted on.
pub fn contour_arcs(contour: &Contour, params: &EdgeFitParams) -> Vec<ContourArc> {
    let n = contour.points.len();
    let min_window = params.min_window.max(2);
    if n < 2 * min_window {
        return Vec::new();
    }
    let orientation = contour.signed_area2().signum();
    let table = ArcTable::new(&contour.points);
    let max_window = n / 2;
    let mut len = min_window;
    let mut estimates: Vec<Option<Estimate>> = Vec::with_capacity(n);
    for i in 0..n {
        let mut est = None;
        for _ in 0..=params.max_adapt_steps {
            est = window_estimate(&table, i, len, orientation);
            let Some(e) = est else { break };
            let target = params.arc_per_radius * e.radius;
            let a = table.arc(i, len);
            if (a - target).abs() <= params.arc_tolerance * target {
                break;
            }
            let resized =
                ((len as f64 * target / a).round() as usize).clamp(min_window, max_window);
            if resized == len {
                break;
            }
            len = resized;
        }
        if est.is_none() {
            len = min_window;
        }
        estimates.push(est);
    }
    let mut groups = group_estimates(&estimates, params.jump_fraction);
    join_wrapping_groups(&mut groups, n, params.jump_fraction);
    groups
        .iter()
        .filter(|g| g.len() >= params.min_estimates.max(1))
        .filter_map(|g| arc_of_group(g, &table, params.group_circle))
        .collect()
}

/// Splits the sequence into runs of valid estimates whose centres stay within `jump` mean radii
/// of the run's running mean.
fn group_estimates(estimates: &[Option<Estimate>], jump: f64) -> Vec<Vec<Estimate>> {
    let mut groups: Vec<Vec<Estimate>> = Vec::new();
    let mut current: Vec<Estimate> = Vec::new();
    for e in estimates {
        match e {
            Some(e) => {
                if let Some((c, r)) = weighted_mean(&current) {
                    if (e.center - c).norm() > jump * r {
                        groups.push(std::mem::take(&mut current));
                    }
                }
                current.push(*e);
            }
            None => {
                if !current.is_empty() {
                    groups.push(std::mem::take(&mut current));
                }
            }
        }
    }
    if !current.is_empty() {
        groups.push(current);
    }
    groups
}

/// Joins the last group into the first when the first starts at point 0, the last ends at the
/// end of the contour, and their means agree (one fruit across the contour's starting point).
fn join_wrapping_groups(groups: &mut Vec<Vec<Estimate>>, n: usize, jump: f64) {
    if groups.len() < 2 {
        return;
    }
    let (first, last) = (&groups[0], &groups[groups.len() - 1]);
    let wraps = first.first().is_some_and(|e| e.start == 0)
        && last.last().is_some_and(|e| e.start + 1 == n);
    let agree = match (weighted_mean(first), weighted_mean(last)) {
        (Some((a, ra)), Some((b, rb))) => (a - b).norm() <= jump * ra.max(rb),
        _ => false,
    };
    if wraps && agree {
        if let Some(last) = groups.pop() {
            groups[0].extend(last);
        }
    }
}

fn weighted_mean(group: &[Estimate]) -> Option<(Point2<f64>, f64)> {
    let w: f64 = group.iter().map(|e| e.weight).sum();
    if w <= 0.0 {
        return None;
    }
    let c = group
        .iter()
        .fold(Vector2::zeros(), |s, e| s + e.center.coords * e.weight)
        / w;
    let r = group.iter().map(|e| e.radius * e.weight).sum::<f64>() / w;
    Some((Point2::from(c), r))
}

/// Gauss–Newton steps of the geometric refinement of a group's circle.
const REFINE_ITERATIONS: usize = 10;

/// A least-squares radius more than this factor from the group's Eq. 8 mean radius (either
/// way) is not trusted: on a short, noisy piece of outline the fit can run off to a much larger
/// or smaller circle, while the mean of the window estimates stays bounded by them.
const MAX_FIT_TO_MEAN_RADIUS: f64 = 1.5;

fn arc_of_group(group: &[Estimate], table: &ArcTable, mode: GroupCircle) -> Option<ContourArc> {
    let (mean_center, mean_radius) = weighted_mean(group)?;
    // Arc covered: the union of the windows' steps (step i joins point i to point i + 1).
    let step_indices = steps_covered(group.iter().map(|e| (e.start, e.len)), table.points.len());
    let (center_px, radius_px) = match mode {
        GroupCircle::WeightedMean => (mean_center, mean_radius),
        GroupCircle::LeastSquares => {
            let points = step_points(table.points, &step_indices);
            fit_circle(&points)
                .and_then(|start| refine_circle(&points, start, REFINE_ITERATIONS))
                .filter(|&(_, r)| {
                    r <= MAX_FIT_TO_MEAN_RADIUS * mean_radius
                        && r * MAX_FIT_TO_MEAN_RADIUS >= mean_radius
                })
                .unwrap_or((mean_center, mean_radius))
        }
    };
    let support = step_support(table.points, &step_indices, radius_px);
    (radius_px.is_finite() && radius_px > 0.0).then_some(ContourArc {
        circle: ContourCircle {
            center_px,
            radius_px,
            support,
        },
        step_indices,
    })
}

/// The steps (step `i` joins point `i` to `i + 1`) that windows `(start, len)` of a closed
/// contour of `n` points cover, in order, each once: each window is a span of steps (two where
/// it wraps past the contour's end), and their union is read off the sorted spans — no pass
/// over the whole contour per group of windows.
fn steps_covered(windows: impl Iterator<Item = (usize, usize)>, n: usize) -> Vec<usize> {
    let mut spans: Vec<(usize, usize)> = Vec::new();
    for (start, len) in windows {
        let end = start + len.min(n);
        if end <= n {
            spans.push((start, end));
        } else {
            spans.push((start, n));
            spans.push((0, end - n));
        }
    }
    spans.sort_unstable();
    let mut steps = Vec::new();
    let mut next = 0;
    for (lo, hi) in spans {
        steps.extend(lo.max(next)..hi);
        next = next.max(hi);
    }
    steps
}

/// The contour points at either end of the steps `steps` (sorted, distinct), each once.
pub(crate) fn step_points(points: &[Point2<f64>], steps: &[usize]) -> Vec<Point2<f64>> {
    let n = points.len();
    let mut out = Vec::with_capacity(steps.len() + 1);
    for (k, &i) in steps.iter().enumerate() {
        out.push(points[i]);
        let next = next_around(i, n);
        let next_listed =
            steps.get(k + 1) == Some(&next) || (next == 0 && steps.first() == Some(&0));
        if !next_listed {
            out.push(points[next]);
        }
    }
    out
}

/// Length of the steps `steps` of the closed contour `points` over the circumference
/// `2π radius`, capped at 1 (the support fraction).
pub(crate) fn step_support(points: &[Point2<f64>], steps: &[usize], radius: f64) -> f64 {
    let n = points.len();
    let arc: f64 = steps
        .iter()
        .map(|&i| (points[next_around(i, n)] - points[i]).norm())
        .sum();
    (arc / (2.0 * std::f64::consts::PI * radius)).min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{smooth_mask, trace_contours};
    use rand::{Rng, SeedableRng};

    #[test]
    fn edge_fit_settings_that_cannot_run_are_named() {
        assert_eq!(EdgeFitParams::default().problem(), None);
        let bad = |p: EdgeFitParams| p.problem().map(|(name, _)| name);
        let d = EdgeFitParams::default();
        assert_eq!(
            bad(EdgeFitParams {
                arc_per_radius: -1.0,
                ..d
            }),
            Some("edge_fit.arc_per_radius")
        );
        assert_eq!(
            bad(EdgeFitParams {
                jump_fraction: f64::NAN,
                ..d
            }),
            Some("edge_fit.jump_fraction")
        );
        assert_eq!(
            bad(EdgeFitParams { min_window: 1, ..d }),
            Some("edge_fit.min_window")
        );
    }

    /// A disc of radius `r` at `(cx, cy)` with the pixels for which `hidden` holds removed.
    fn partial_disc(
        w: usize,
        h: usize,
        (cx, cy, r): (f64, f64, f64),
        hidden: impl Fn(f64, f64) -> bool,
    ) -> Vec<bool> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                (x - cx).powi(2) + (y - cy).powi(2) <= r * r && !hidden(x, y)
            })
            .collect()
    }

    fn circles(mask: &[bool], w: usize, h: usize) -> Vec<ContourCircle> {
        circles_with(mask, w, h, &EdgeFitParams::default())
    }

    fn circles_with(
        mask: &[bool],
        w: usize,
        h: usize,
        params: &EdgeFitParams,
    ) -> Vec<ContourCircle> {
        let smooth = smooth_mask(mask, w, h);
        trace_contours(&smooth, w, h, 20)
            .iter()
            .flat_map(|c| contour_circles(&c.smoothed(params.smoothing_half_window), params))
            .collect()
    }

    fn best(found: &[ContourCircle]) -> ContourCircle {
        *found
            .iter()
            .max_by(|a, b| a.support.total_cmp(&b.support))
            .unwrap()
    }

    #[test]
    fn a_whole_disc_gives_its_circle() {
        let (w, h) = (120, 100);
        for r in [12.0, 25.0, 40.0] {
            let found = circles(&partial_disc(w, h, (60.3, 49.6, r), |_, _| false), w, h);
            let c = best(&found);
            let err = (c.center_px - Point2::new(60.3, 49.6)).norm();
            assert!(err < 0.1 * r, "r {r}: centre off by {err}");
            assert!((c.radius_px - r).abs() < 0.12 * r, "r {r}: {}", c.radius_px);
            assert!(c.support > 0.8, "support {}", c.support);
        }
    }

    #[test]
    fn covered_steps_are_the_union_of_the_windows_wrapping_past_the_end() {
        // Against marking every step of every window in an array of the contour's steps.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        for _ in 0..300 {
            let n = rng.gen_range(1..60);
            let windows: Vec<(usize, usize)> = (0..rng.gen_range(0..8))
                .map(|_| (rng.gen_range(0..n), rng.gen_range(1..=n)))
                .collect();
            let mut covered = vec![false; n];
            for &(start, len) in &windows {
                for k in 0..len {
                    covered[(start + k) % n] = true;
                }
            }
            let expected: Vec<usize> = (0..n).filter(|&i| covered[i]).collect();
            assert_eq!(
                steps_covered(windows.iter().copied(), n),
                expected,
                "{windows:?} of {n}"
            );
        }
    }

    #[test]
    fn a_whole_disc_is_one_arc_over_every_step_across_the_contour_start() {
        // Its windows near the contour's end wrap past point 0, and the group joins across it:
        // the arc's steps are every step of the contour, once each, in order.
        let (w, h) = (120, 100);
        let params = EdgeFitParams::default();
        let mask = smooth_mask(&partial_disc(w, h, (60.3, 49.6, 25.0), |_, _| false), w, h);
        let contour = trace_contours(&mask, w, h, 20)[0].smoothed(params.smoothing_half_window);
        let arcs = contour_arcs(&contour, &params);
        let all: Vec<usize> = (0..contour.points.len()).collect();
        assert_eq!(arcs.len(), 1);
        assert_eq!(arcs[0].step_indices, all);
    }

    #[test]
    fn a_disc_with_a_third_hidden_keeps_its_centre() {
        let (w, h) = (140, 120);
        let (cx, cy, r) = (70.0, 60.0, 35.0);
        // A leaf (band) covers the right third of the fruit.
        let mask = partial_disc(w, h, (cx, cy, r), |x, _| x > cx + r / 3.0);
        let c = best(&circles(&mask, w, h));
        let err = (c.center_px - Point2::new(cx, cy)).norm();
        assert!(err < 0.1 * r, "centre off by {err}: {c:?}");
        assert!((c.radius_px - r).abs() < 0.12 * r, "{c:?}");
        assert!(c.support > 0.4 && c.support < 0.9, "{c:?}");
    }

    #[test]
    fn two_touching_discs_give_two_circles() {
        let (w, h) = (160, 100);
        let a = partial_disc(w, h, (50.0, 50.0, 28.0), |_, _| false);
        let b = partial_disc(w, h, (100.0, 52.0, 26.0), |_, _| false);
        let mask: Vec<bool> = a.iter().zip(&b).map(|(x, y)| *x || *y).collect();
        let found = circles(&mask, w, h);
        for (cx, cy, r) in [(50.0, 50.0, 28.0), (100.0, 52.0, 26.0)] {
            let hit = found.iter().any(|c| {
                (c.center_px - Point2::new(cx, cy)).norm() < 0.15 * r
                    && (c.radius_px - r).abs() < 0.15 * r
            });
            assert!(hit, "no circle at ({cx}, {cy}): {found:?}");
        }
    }

    #[test]
    fn least_squares_circles_of_a_sunlit_half_are_the_fruit_and_the_paper_mode_stays() {
        // The lower half of a fruit (the sunlit part; the shaded top is missing from the mask):
        // its outline is a half circle closed by a straight terminator.
        let (w, h) = (140, 120);
        let (cx, cy, r) = (70.0, 50.0, 30.0);
        let mask = partial_disc(w, h, (cx, cy, r), |_, y| y < cy);
        let paper = EdgeFitParams {
            group_circle: GroupCircle::WeightedMean,
            merge_max_rms: 0.0,
            ..EdgeFitParams::default()
        };
        let fitted = EdgeFitParams {
            group_circle: GroupCircle::LeastSquares,
            ..paper
        };
        let truth = Point2::new(cx, cy);
        let mean = best(&circles_with(&mask, w, h, &paper));
        let lsq = best(&circles_with(&mask, w, h, &fitted));
        let (mean_err, lsq_err) = (
            (mean.center_px - truth).norm(),
            (lsq.center_px - truth).norm(),
        );
        assert!(lsq_err < 0.1 * r, "least squares off by {lsq_err}: {lsq:?}");
        assert!((lsq.radius_px - r).abs() < 0.1 * r, "{lsq:?}");
        assert!(
            lsq_err < mean_err,
            "{lsq_err} vs {mean_err}: {lsq:?} {mean:?}"
        );
        // Model files without the new settings mean the paper's behaviour.
        let old: EdgeFitParams = serde_json::from_value(serde_json::json!({
            "arc_per_radius": 1.0, "arc_tolerance": 0.2, "max_adapt_steps": 4, "min_window": 6,
            "jump_fraction": 0.3, "min_estimates": 4, "smoothing_half_window": 2
        }))
        .unwrap();
        assert_eq!(old, paper);
    }
}
