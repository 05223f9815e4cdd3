//! The least-squares ellipse through points (not in seed 004): Fitzgibbon, Pilu and Fisher's
//! direct fit, in the numerically stable form of Halíř and Flusser (1998).
//!
//! Seed 004 fits circles, and so does the rest of this crate; a fruit's outline is a circle
//! only when the fruit is round. An oblate fruit hanging on its stem shows an outline about
//! 0.8 as tall as it is wide; when its neighbours hide its sides, its top and bottom arcs are
//! flatter than its width and each fits a circle far too large for a fruit, and the two do not
//! lie on one circle. They lie on one ellipse. [`crate::merge_arcs`] uses this fit to join such
//! arcs into one fruit.
//!
//! The fit minimises the algebraic residual of the conic `A x² + B xy + C y² + D x + E y + F =
//! 0` under `4AC − B² = 1`, which always gives an ellipse (one 3×3 eigenproblem, no iteration);
//! the distances it reports are Sampson's first-order approximation of the points' geometric
//! distances from the curve.

use pomona_core::nalgebra::{Matrix3, Point2, Vector2, Vector3};

use crate::circle_least_squares::centroid;

/// An ellipse in the image: centre, semi-axes and the direction of the first semi-axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipse {
    /// Centre, pixels.
    pub center_px: Point2<f64>,
    /// The two semi-axes, pixels: `semi_axes_px.0` along `first_axis`, `.1` across it.
    pub semi_axes_px: (f64, f64),
    /// Unit direction of the first semi-axis.
    pub first_axis: Vector2<f64>,
}

impl Ellipse {
    /// The semi-axis whose direction lies nearer the image's rows: the width of a fruit that
    /// hangs upright, whichever of its axes is the longer.
    pub fn horizontal_semi_axis_px(&self) -> f64 {
        if self.first_axis.x.abs() >= self.first_axis.y.abs() {
            self.semi_axes_px.0
        } else {
            self.semi_axes_px.1
        }
    }

    /// The shorter semi-axis over the longer, in (0, 1].
    pub fn axis_ratio(&self) -> f64 {
        let (a, b) = self.semi_axes_px;
        a.min(b) / a.max(b)
    }
}

/// An ellipse fitted to points, with its root-mean-square (Sampson) distance from them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EllipseFit {
    /// The fitted ellipse.
    pub ellipse: Ellipse,
    /// Root-mean-square first-order distance of the points from it, pixels.
    pub rms_px: f64,
}

/// The direct least-squares ellipse through `points` (at least five, not on one line or
/// conic other than an ellipse), or `None` when they determine none.
///
/// ```
/// use pomona_colorcontour::fit_ellipse;
/// use pomona_core::nalgebra::Point2;
/// // The upper and lower thirds of an ellipse 30 px wide and 24 px tall, centred at (50, 40).
/// let points: Vec<Point2<f64>> = (0..120)
///     .map(|i| i as f64 * std::f64::consts::TAU / 120.0)
///     .filter(|t| t.sin().abs() > 0.5)
///     .map(|t| Point2::new(50.0 + 30.0 * t.cos(), 40.0 + 24.0 * t.sin()))
///     .collect();
/// let fit = fit_ellipse(&points).unwrap();
/// assert!((fit.ellipse.center_px - Point2::new(50.0, 40.0)).norm() < 1e-6);
/// assert!((fit.ellipse.horizontal_semi_axis_px() - 30.0).abs() < 1e-6);
/// assert!(fit.rms_px < 1e-6);
/// ```
pub fn fit_ellipse(points: &[Point2<f64>]) -> Option<EllipseFit> {
    if points.len() < 5 {
        return None;
    }
    // Centre and scale the points for conditioning.
    let n = points.len() as f64;
    let mean = centroid(points).coords;
    let spread = (points
        .iter()
        .map(|p| (p.coords - mean).norm_squared())
        .sum::<f64>()
        / n)
        .sqrt();
    if !(spread.is_finite() && spread > 0.0) {
        return None;
    }
    let scaled = |p: &Point2<f64>| (p.coords - mean) / spread;
    // Scatter of the quadratic (x², xy, y²) and linear (x, y, 1) parts.
    let (mut s1, mut s2, mut s3) = (Matrix3::zeros(), Matrix3::zeros(), Matrix3::zeros());
    for p in points {
        let q = scaled(p);
        let quad = Vector3::new(q.x * q.x, q.x * q.y, q.y * q.y);
        let lin = Vector3::new(q.x, q.y, 1.0);
        s1 += quad * quad.transpose();
        s2 += quad * lin.transpose();
        s3 += lin * lin.transpose();
    }
    let t = -s3.try_inverse()? * s2.transpose();
    let m = s1 + s2 * t;
    // Premultiplied by the inverse of the constraint matrix of 4AC − B².
    let reduced = Matrix3::from_rows(&[m.row(2) / 2.0, -m.row(1), m.row(0) / 2.0]);
    let quadratic = reduced
        .complex_eigenvalues()
        .iter()
        .filter(|l| l.im.abs() <= 1e-9 * (1.0 + l.re.abs()))
        .filter_map(|l| null_vector(&(reduced - Matrix3::identity() * l.re)))
        .find(|v| 4.0 * v.x * v.z - v.y * v.y > 0.0)?;
    let linear = t * quadratic;
    let conic = [
        quadratic.x,
        quadratic.y,
        quadratic.z,
        linear.x,
        linear.y,
        linear.z,
    ];
    let ellipse = ellipse_of(conic)?;
    let sum_sq: f64 = points
        .iter()
        .map(|p| sampson_squared(&conic, scaled(p)))
        .sum();
    let rms_px = (sum_sq / n).sqrt() * spread;
    Some(EllipseFit {
        ellipse: Ellipse {
            center_px: Point2::from(ellipse.center_px.coords * spread + mean),
            semi_axes_px: (
                ellipse.semi_axes_px.0 * spread,
                ellipse.semi_axes_px.1 * spread,
            ),
            first_axis: ellipse.first_axis,
        },
        rms_px,
    })
    .filter(|f| f.rms_px.is_finite())
}

/// A non-zero vector `v` with `a v ≈ 0` for a singular 3×3 `a`: the largest cross product of
/// two of its rows.
fn null_vector(a: &Matrix3<f64>) -> Option<Vector3<f64>> {
    let rows = [
        a.row(0).transpose(),
        a.row(1).transpose(),
        a.row(2).transpose(),
    ];
    [
        rows[0].cross(&rows[1]),
        rows[0].cross(&rows[2]),
        rows[1].cross(&rows[2]),
    ]
    .into_iter()
    .max_by(|u, v| u.norm_squared().total_cmp(&v.norm_squared()))
    .filter(|v| v.norm_squared() > 0.0)
}

/// The ellipse of the conic `[A, B, C, D, E, F]`, when it is a real one.
fn ellipse_of([a, b, c, d, e, f]: [f64; 6]) -> Option<Ellipse> {
    // Centre: the gradient vanishes.
    let det = 4.0 * a * c - b * b;
    if !(det.is_finite() && det > 0.0) {
        return None;
    }
    let x0 = (b * e - 2.0 * c * d) / det;
    let y0 = (b * d - 2.0 * a * e) / det;
    // The conic about its centre: q(u) = f0 with q the quadratic part.
    let f0 = -(a * x0 * x0 + b * x0 * y0 + c * y0 * y0 + d * x0 + e * y0 + f);
    // Eigen-decomposition of [[A, B/2], [B/2, C]].
    let half_diff = 0.5 * (a - c);
    let root = half_diff.hypot(0.5 * b);
    let (l1, l2) = (0.5 * (a + c) + root, 0.5 * (a + c) - root);
    let angle = 0.5 * b.atan2(a - c);
    let first_axis = Vector2::new(angle.cos(), angle.sin());
    let (s1, s2) = (f0 / l1, f0 / l2);
    (s1 > 0.0 && s2 > 0.0 && s1.is_finite() && s2.is_finite()).then(|| Ellipse {
        center_px: Point2::new(x0, y0),
        semi_axes_px: (s1.sqrt(), s2.sqrt()),
        first_axis,
    })
}

/// Squared Sampson distance of `p` from the conic: Q(p)² / |∇Q(p)|².
fn sampson_squared([a, b, c, d, e, f]: &[f64; 6], p: Vector2<f64>) -> f64 {
    let (x, y) = (p.x, p.y);
    let q = a * x * x + b * x * y + c * y * y + d * x + e * y + f;
    let gx = 2.0 * a * x + b * y + d;
    let gy = b * x + 2.0 * c * y + e;
    let g2 = gx * gx + gy * gy;
    if g2 > 0.0 {
        q * q / g2
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn on_ellipse(
        c: (f64, f64),
        (a, b): (f64, f64),
        tilt: f64,
        angles: impl Iterator<Item = f64>,
    ) -> Vec<Point2<f64>> {
        let (ct, st) = (tilt.cos(), tilt.sin());
        angles
            .map(|t| {
                let (u, v) = (a * t.cos(), b * t.sin());
                Point2::new(c.0 + ct * u - st * v, c.1 + st * u + ct * v)
            })
            .collect()
    }

    #[test]
    fn tilted_ellipses_are_recovered_from_arcs() {
        for (tilt_deg, (a, b)) in [
            (0.0, (30.0, 24.0)),
            (35.0, (20.0, 26.0)),
            (80.0, (40.0, 40.0)),
        ] {
            let tilt = f64::to_radians(tilt_deg);
            // Two opposite arcs, each a third of the way round.
            let angles = (0..90)
                .map(|i| i as f64 * std::f64::consts::TAU / 90.0)
                .filter(|t| t.sin().abs() > 0.5);
            let points = on_ellipse((100.0, 60.0), (a, b), tilt, angles);
            let fit = fit_ellipse(&points).unwrap();
            let e = fit.ellipse;
            assert!(
                (e.center_px - Point2::new(100.0, 60.0)).norm() < 1e-6,
                "{e:?}"
            );
            let (mut got, mut want) = ([e.semi_axes_px.0, e.semi_axes_px.1], [a, b]);
            got.sort_by(f64::total_cmp);
            want.sort_by(f64::total_cmp);
            assert!((got[0] - want[0]).abs() < 1e-6 && (got[1] - want[1]).abs() < 1e-6);
            assert!(fit.rms_px < 1e-6);
            if a != b {
                // The axis along the (tilted) x direction is the one reported as the width
                // while the tilt is under 45°.
                let width = if tilt_deg < 45.0 { a } else { b };
                assert!((e.horizontal_semi_axis_px() - width).abs() < 1e-6, "{e:?}");
            }
        }
    }

    #[test]
    fn noisy_points_give_their_scatter_as_distance() {
        // ±0.5 px alternating radial offsets: about 0.5 px root-mean-square.
        let points: Vec<Point2<f64>> = (0..200)
            .map(|i| {
                let t = i as f64 * std::f64::consts::TAU / 200.0;
                let r = if i % 2 == 0 { 0.5 } else { -0.5 };
                Point2::new((30.0 + r) * t.cos(), (20.0 + r) * t.sin())
            })
            .collect();
        let fit = fit_ellipse(&points).unwrap();
        assert!((fit.rms_px - 0.5).abs() < 0.05, "{}", fit.rms_px);
        assert!((fit.ellipse.axis_ratio() - 20.0 / 30.0).abs() < 0.01);
    }

    #[test]
    fn degenerate_points_give_no_ellipse() {
        assert!(fit_ellipse(&[Point2::new(0.0, 0.0); 4]).is_none());
        assert!(fit_ellipse(&[Point2::new(1.0, 1.0); 20]).is_none());
        let line: Vec<Point2<f64>> = (0..20)
            .map(|i| Point2::new(i as f64, 2.0 * i as f64))
            .collect();
        assert!(fit_ellipse(&line).is_none());
        let nan = vec![Point2::new(f64::NAN, 0.0); 10];
        assert!(fit_ellipse(&nan).is_none());
    }
}
