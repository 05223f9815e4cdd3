//! Least-squares circles through points: the algebraic fit (Kåsa: minimise the residual of
//! `x² + y² + D x + E y + F = 0`, one linear solve) and its geometric refinement (Gauss–Newton
//! on the distances of the points from the circle, what "refined against the edge" means here).
//!
//! The algebraic fit is exact for points on a circle but, on a short noisy arc, is pulled
//! towards a smaller circle; the geometric fit removes that bias, which matters for fruit of
//! which only a piece of outline is seen. Both are used by the tracker's four-point fit and by
//! the per-group circle of the contour fitting ([`crate::contour_circles`]).

use pomona_core::nalgebra::{Point2, Vector2};

/// The algebraic least-squares circle through `points` (at least three, not collinear):
/// `(centre, radius)`, or `None` when they do not determine one.
pub fn fit_circle(points: &[Point2<f64>]) -> Option<(Point2<f64>, f64)> {
    if points.len() < 3 {
        return None;
    }
    // Centre the points for conditioning, then solve x² + y² + D x + E y + F = 0.
    let mean = centroid(points);
    let mut a = [[0.0f64; 3]; 3];
    let mut b = [0.0f64; 3];
    for p in points {
        let (x, y) = (p.x - mean.x, p.y - mean.y);
        let row = [x, y, 1.0];
        let rhs = -(x * x + y * y);
        for i in 0..3 {
            for j in 0..3 {
                a[i][j] += row[i] * row[j];
            }
            b[i] += row[i] * rhs;
        }
    }
    let [d, e, f] = solve3(a, b)?;
    let (cx, cy) = (-0.5 * d, -0.5 * e);
    let r2 = cx * cx + cy * cy - f;
    (r2 > 0.0 && r2.is_finite()).then(|| (Point2::new(cx + mean.x, cy + mean.y), r2.sqrt()))
}

/// The mean of `points` (the origin for none): the centre that the least-squares fits move the
/// points to for conditioning.
pub(crate) fn centroid(points: &[Point2<f64>]) -> Point2<f64> {
    let n = points.len() as f64;
    points
        .iter()
        .fold(Point2::origin(), |m, p| m + p.coords / n)
}

/// The geometric least-squares circle (minimum sum of squared distances of `points` from it),
/// by at most `iterations` Gauss–Newton steps from `start`. Steps that do not lower the sum are
/// refused (the start is kept); `None` for fewer than three points or a non-finite start.
pub fn refine_circle(
    points: &[Point2<f64>],
    start: (Point2<f64>, f64),
    iterations: usize,
) -> Option<(Point2<f64>, f64)> {
    refine_circle_with_cost(points, start, iterations).map(|(circle, _)| circle)
}

/// As [`refine_circle`], with the sum of squared distances of `points` from the circle
/// returned (what [`rms_distance`] would compute again for it).
pub(crate) fn refine_circle_with_cost(
    points: &[Point2<f64>],
    start: (Point2<f64>, f64),
    iterations: usize,
) -> Option<((Point2<f64>, f64), f64)> {
    let (mut center, mut radius) = start;
    if points.len() < 3 || !(radius.is_finite() && radius > 0.0) || !center.x.is_finite() {
        return None;
    }
    // One pass over the points per step: the sum that decides whether a step is taken and the
    // normal equations of the next step are read off the same distances.
    let mut here = GaussNewtonPass::at(points, center, radius);
    for _ in 0..iterations {
        let Some([dx, dy, dr]) = solve3(here.a, here.b) else {
            break;
        };
        let (c2, r2) = (center + Vector2::new(dx, dy), radius + dr);
        if !(r2.is_finite() && r2 > 0.0) {
            break;
        }
        let there = GaussNewtonPass::at(points, c2, r2);
        if there.cost >= here.cost {
            break;
        }
        let converged = dx.abs().max(dy.abs()).max(dr.abs()) < 1e-6 * radius.max(1.0);
        (center, radius, here) = (c2, r2, there);
        if converged {
            break;
        }
    }
    Some(((center, radius), here.cost))
}

/// The points' sum of squared distances from a circle and the normal equations `a · step = b`
/// of a Gauss–Newton step from it.
struct GaussNewtonPass {
    a: [[f64; 3]; 3],
    b: [f64; 3],
    cost: f64,
}

impl GaussNewtonPass {
    fn at(points: &[Point2<f64>], center: Point2<f64>, radius: f64) -> Self {
        let mut a = [[0.0f64; 3]; 3];
        let mut b = [0.0f64; 3];
        let mut cost = 0.0;
        for p in points {
            let v: Vector2<f64> = p - center;
            let dist = v.norm();
            let residual = dist - radius;
            cost += residual.powi(2);
            if dist <= f64::EPSILON {
                continue;
            }
            // Residual d_i = |p_i − c| − r; its gradient in (cx, cy, r) is (−u_x, −u_y, −1)
            // with u the unit vector from c to p_i.
            let u = v / dist;
            let row = [-u.x, -u.y, -1.0];
            for i in 0..3 {
                for j in 0..3 {
                    a[i][j] += row[i] * row[j];
                }
                b[i] -= row[i] * residual;
            }
        }
        Self { a, b, cost }
    }
}

/// Root-mean-square distance of `points` from the circle; 0 for no points.
pub fn rms_distance(points: &[Point2<f64>], center: Point2<f64>, radius: f64) -> f64 {
    if points.is_empty() {
        return 0.0;
    }
    (squared_distances(points, center, radius) / points.len() as f64).sqrt()
}

fn squared_distances(points: &[Point2<f64>], center: Point2<f64>, radius: f64) -> f64 {
    points
        .iter()
        .map(|p| ((p - center).norm() - radius).powi(2))
        .sum()
}

/// Solves a 3×3 linear system by Cramer's rule; `None` when it is (nearly) singular.
pub(crate) fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&a);
    let scale = a.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
    // Also refuses a NaN determinant.
    if d.is_nan() || d.abs() <= 1e-12 * scale.powi(3) {
        return None;
    }
    Some(std::array::from_fn(|k| {
        let mut m = a;
        for (row, rhs) in m.iter_mut().zip(b) {
            row[k] = rhs;
        }
        det(&m) / d
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_fit_is_exact_for_three_points_and_refuses_collinear_ones() {
        let (c, r) = (Point2::new(3.0, -2.0), 5.0);
        let on = |a: f64| Point2::new(c.x + r * a.cos(), c.y + r * a.sin());
        let (fc, fr) = fit_circle(&[on(0.1), on(1.9), on(4.0)]).unwrap();
        assert!((fc - c).norm() < 1e-9 && (fr - r).abs() < 1e-9);
        let line = [
            Point2::new(0.0, 0.0),
            Point2::new(1.0, 1.0),
            Point2::new(2.0, 2.0),
        ];
        assert!(fit_circle(&line).is_none());
        assert!(fit_circle(&line[..2]).is_none());
    }

    /// Points on a quarter circle with alternating radial noise of ±`noise`.
    fn noisy_arc(c: Point2<f64>, r: f64, noise: f64) -> Vec<Point2<f64>> {
        (0..40)
            .map(|i| {
                let a = 0.3 + i as f64 * (std::f64::consts::FRAC_PI_2 / 39.0);
                let rr = r + if i % 2 == 0 { noise } else { -noise };
                Point2::new(c.x + rr * a.cos(), c.y + rr * a.sin())
            })
            .collect()
    }

    #[test]
    fn geometric_refinement_lowers_the_distances_and_stays_exact_on_a_circle() {
        let (c, r) = (Point2::new(10.0, 20.0), 30.0);
        let exact = noisy_arc(c, r, 0.0);
        let (fc, fr) = refine_circle(&exact, (c + Vector2::new(3.0, -2.0), 25.0), 20).unwrap();
        assert!((fc - c).norm() < 1e-6 && (fr - r).abs() < 1e-6, "{fc} {fr}");
        let noisy = noisy_arc(c, r, 1.0);
        let kasa = fit_circle(&noisy).unwrap();
        let geo = refine_circle(&noisy, kasa, 20).unwrap();
        assert!(rms_distance(&noisy, geo.0, geo.1) <= rms_distance(&noisy, kasa.0, kasa.1));
        assert!(
            (geo.0 - c).norm() < 1.5 && (geo.1 - r).abs() < 1.5,
            "{geo:?}"
        );
        // The cost returned with the circle is the points' sum of squared distances from it.
        let (circle, cost) = refine_circle_with_cost(&noisy, kasa, 20).unwrap();
        assert_eq!(circle, geo);
        let rms = rms_distance(&noisy, geo.0, geo.1);
        assert_eq!((cost / noisy.len() as f64).sqrt(), rms);
        assert!(refine_circle(&noisy[..2], kasa, 5).is_none());
        assert!(refine_circle(&noisy, (c, f64::NAN), 5).is_none());
        assert_eq!(rms_distance(&[], c, r), 0.0);
    }
}
