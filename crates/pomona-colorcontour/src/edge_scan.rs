//! The position check of seed 004 §3.3: from a point inside the fruit, scan the image in four
//! directions (left, right, up, down) until the fruit's boundary, and fit a circle to the four
//! boundary points; its centre is the new estimate of the fruit's centre.
//!
//! For a disc, any circle through the two ends of the horizontal chord has its centre on the
//! chord's perpendicular bisector, and likewise for the vertical chord, so four boundary points
//! give the disc's centre exactly from any start inside it.
//!
//! The paper fits "a circle" to the four points. Here ([`circle_from_boundaries`]) the fit
//! allows for one occluded direction: a leaf in front of the fruit ends a scan early, so its
//! point lies inside the fruit's circle, never outside it. The circle is therefore the smallest
//! circumcircle of three of the points that contains the fourth (within a pixel and a half);
//! for four points on one circle that is their circle, and with one scan cut short it is the
//! circle of the other three. Three points give their circumcircle. [`crate::fit_circle`] is the plain
//! algebraic least-squares circle (Kåsa), the fallback.
//!
//! Choices where the paper is silent, documented in [`EdgeScanParams`]: a boundary is the first
//! of `gap_px` consecutive pixels that are not fruit-coloured (so a single misclassified pixel
//! does not end the scan); a scan that reaches the image border, or goes farther than
//! `max_scan_px` without a boundary (it has run into a touching neighbour), gives no boundary
//! point; three boundary points still define the circle, fewer fail the check.

use pomona_core::nalgebra::Point2;
use serde::{Deserialize, Serialize};

use crate::fit_circle;

/// How the four-direction scan decides it has left the fruit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EdgeScanParams {
    /// A boundary is this many consecutive non-fruit pixels (its first pixel is the boundary).
    pub gap_px: u32,
}

impl Default for EdgeScanParams {
    fn default() -> Self {
        Self { gap_px: 2 }
    }
}

/// Where one scan ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ScanEnd {
    /// The fruit's boundary, at this pixel (the first non-fruit pixel).
    Boundary(Point2<f64>),
    /// The image border was reached inside the fruit.
    ImageBorder,
    /// No boundary within the allowed length.
    TooFar,
}

impl ScanEnd {
    /// The boundary pixel, if the scan found one.
    pub fn boundary(&self) -> Option<Point2<f64>> {
        match self {
            ScanEnd::Boundary(p) => Some(*p),
            ScanEnd::ImageBorder | ScanEnd::TooFar => None,
        }
    }
}

/// The four directions of the scan: left, right, up, down.
pub const SCAN_DIRECTIONS: [(i64, i64); 4] = [(-1, 0), (1, 0), (0, -1), (0, 1)];

/// Scans from `start` in the four [`SCAN_DIRECTIONS`] over a `width` × `height` image whose
/// pixel `(x, y)` is fruit when `is_fruit(x, y)`, for at most `max_scan_px` pixels each.
pub fn scan_four_directions(
    is_fruit: &mut dyn FnMut(i64, i64) -> bool,
    start: (i64, i64),
    (width, height): (u32, u32),
    max_scan_px: u32,
    params: &EdgeScanParams,
) -> [ScanEnd; 4] {
    let gap = i64::from(params.gap_px.max(1));
    let (w, h) = (i64::from(width), i64::from(height));
    SCAN_DIRECTIONS.map(|(dx, dy)| {
        let mut run = 0;
        for k in 1..=i64::from(max_scan_px) + gap {
            let (x, y) = (start.0 + k * dx, start.1 + k * dy);
            if x < 0 || y < 0 || x >= w || y >= h {
                return ScanEnd::ImageBorder;
            }
            if is_fruit(x, y) {
                if k > i64::from(max_scan_px) {
                    return ScanEnd::TooFar;
                }
                run = 0;
                continue;
            }
            run += 1;
            if run == gap {
                let first = k - gap + 1;
                return ScanEnd::Boundary(Point2::new(
                    (start.0 + first * dx) as f64,
                    (start.1 + first * dy) as f64,
                ));
            }
        }
        ScanEnd::TooFar
    })
}

/// Slack, pixels, with which the fourth point must lie inside a three-point circle.
const INSIDE_SLACK_PX: f64 = 1.5;

/// The circle of the scan's boundary points, allowing one of four to be cut short by an
/// occluder (see the module docs): `(centre, radius)`, or `None` for fewer than three points
/// or degenerate ones.
pub fn circle_from_boundaries(points: &[Point2<f64>]) -> Option<(Point2<f64>, f64)> {
    if points.len() != 4 {
        return fit_circle(points);
    }
    (0..4)
        .filter_map(|skip| {
            let triple: Vec<Point2<f64>> =
                (0..4).filter(|&i| i != skip).map(|i| points[i]).collect();
            let (c, r) = fit_circle(&triple)?;
            ((points[skip] - c).norm() <= r + INSIDE_SLACK_PX).then_some((c, r))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .or_else(|| fit_circle(points))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc(cx: f64, cy: f64, r: f64) -> impl FnMut(i64, i64) -> bool {
        move |x, y| (x as f64 - cx).powi(2) + (y as f64 - cy).powi(2) <= r * r
    }

    #[test]
    fn four_boundary_points_give_the_disc_centre_from_any_start_inside() {
        let (cx, cy, r) = (60.3, 47.8, 21.0);
        for start in [(60, 48), (45, 40), (75, 60), (62, 30)] {
            let ends = scan_four_directions(
                &mut disc(cx, cy, r),
                start,
                (140, 100),
                80,
                &EdgeScanParams::default(),
            );
            let points: Vec<Point2<f64>> = ends.iter().filter_map(ScanEnd::boundary).collect();
            assert_eq!(points.len(), 4, "{start:?}: {ends:?}");
            let (c, fitted_r) = fit_circle(&points).unwrap();
            // Boundary pixels lie just outside the disc: within a pixel of the truth.
            assert!(
                (c.x - cx).abs() < 1.0 && (c.y - cy).abs() < 1.0,
                "{start:?}: {c}"
            );
            assert!((fitted_r - r).abs() < 1.5, "{fitted_r}");
        }
    }

    #[test]
    fn scans_report_the_border_a_long_run_and_ignore_single_holes() {
        // A disc cut by the left image border, with a one-pixel hole right of the start.
        let mut inside = disc(5.0, 30.0, 20.0);
        let mut holed = |x: i64, y: i64| (x, y) != (8, 30) && inside(x, y);
        let ends = scan_four_directions(
            &mut holed,
            (6, 30),
            (80, 60),
            60,
            &EdgeScanParams::default(),
        );
        assert_eq!(ends[0], ScanEnd::ImageBorder);
        assert_eq!(ends[1], ScanEnd::Boundary(Point2::new(26.0, 30.0)));
        // Too short a scan cannot reach the boundary.
        let ends = scan_four_directions(
            &mut disc(40.0, 30.0, 25.0),
            (40, 30),
            (80, 60),
            10,
            &EdgeScanParams::default(),
        );
        assert!(ends.iter().all(|e| *e == ScanEnd::TooFar), "{ends:?}");
    }

    #[test]
    fn a_scan_cut_short_by_a_leaf_does_not_move_the_circle() {
        let (c, r) = (Point2::new(50.0, 40.0), 20.0);
        let on = |a: f64| Point2::new(c.x + r * a.cos(), c.y + r * a.sin());
        let all = [on(0.3), on(1.7), on(3.3), on(4.9)];
        let (fc, fr) = circle_from_boundaries(&all).unwrap();
        assert!((fc - c).norm() < 1e-9 && (fr - r).abs() < 1e-9);
        for cut in 0..4 {
            // That scan stopped at 60 % of the way from the centre.
            let mut pts = all;
            pts[cut] = c + (pts[cut] - c) * 0.6;
            let (fc, fr) = circle_from_boundaries(&pts).unwrap();
            assert!(
                (fc - c).norm() < 1e-9 && (fr - r).abs() < 1e-9,
                "cut {cut}: {fc} {fr}"
            );
            // The plain least-squares fit is pulled towards the cut point.
            let (lc, _) = fit_circle(&pts).unwrap();
            assert!((lc - c).norm() > 1.0);
        }
    }
}
