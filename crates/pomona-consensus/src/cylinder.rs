//! Cylinders: the model, the two-oriented-point estimator of Schnabel et al. (2007) that seed 002
//! uses, and a least-squares refit.
//!
//! Construction from `(p₁, n₁)`, `(p₂, n₂)`: on a cylinder every normal is perpendicular to the
//! axis, so the axis direction is `a = n₁ × n₂`. Projected onto the plane `aᵀp = 0`, the two
//! normal lines `pᵢ + t nᵢ` both pass through the axis, so their intersection is the axis point
//! `o`; the radius is the mean in-plane distance of the two points from `o`. Parallel normals
//! (a plane, or both points on one generator line) give no axis and the sample is rejected.
//!
//! Departure from seed 002 (documented in docs/learning-and-evaluation.md): the paper, after
//! Schnabel et al., sets the radius to the first point's distance from `o`. Averaging both
//! points is symmetric in the sample order and halves the noise of one hypothesis; MSAC's
//! refit on the inliers sets the radius a model is reported with, so only which hypotheses are
//! tried differs.
//!
//! Schnabel et al. accept a point when it is within ε of the surface *and* its normal is within α
//! of the surface normal. The geometric [`Cylinder`] only knows the distance; the angular test
//! lives in [`CylinderEstimator::residual`] (an infinite residual when the normal deviates by more
//! than α), so MSAC treats such points as outliers.
//!
//! An optional extent records the inliers' span along the axis, so a detector can report the
//! fruit's midpoint and length.

use crate::damped_step::damped_step;
use nalgebra::{Matrix2, Point3, SMatrix, SVector, Unit, Vector2, Vector3};
use serde::{Deserialize, Serialize};

use crate::consensus::check_positive;
use crate::radial_prior::RadialPrior;
use crate::{ConsensusError, Estimator, Model, Positioned};

/// An infinite circular cylinder (optionally with the span its inliers cover), metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Cylinder {
    /// A point on the axis.
    pub axis_point: Point3<f64>,
    /// Axis direction (its sign carries no meaning).
    pub axis: Unit<Vector3<f64>>,
    /// Radius, metres.
    pub radius_m: f64,
    /// `(min, max)` of `(p − axis_point) · axis` over the inliers, metres, once known.
    pub extent_m: Option<(f64, f64)>,
}

/// `|n₁ × n₂|` below this (≈ 0.6°) means the normals are parallel and give no axis.
const MIN_NORMAL_CROSS: f64 = 1e-2;

impl Cylinder {
    /// The cylinder through two points with their surface normals (Schnabel et al. 2007), or
    /// `None` for parallel normals, non-finite input or a degenerate intersection.
    pub fn from_two_oriented_points(
        p1: &Point3<f64>,
        n1: &Unit<Vector3<f64>>,
        p2: &Point3<f64>,
        n2: &Unit<Vector3<f64>>,
    ) -> Option<Self> {
        let cross = n1.cross(n2);
        let cross_norm = cross.norm();
        if cross_norm.is_nan() || cross_norm <= MIN_NORMAL_CROSS {
            return None;
        }
        let axis = Unit::new_normalize(cross);
        // Work relative to p1 so far-away clusters stay well conditioned.
        let project = |v: Vector3<f64>| v - axis.into_inner() * axis.dot(&v);
        let q1 = Vector3::zeros();
        let q2 = project(p2 - p1);
        let m1 = project(n1.into_inner());
        let m2 = project(n2.into_inner());
        // q1 + t1 m1 = q2 + t2 m2 in the least-squares sense (exact in the plane).
        let m12 = m1.dot(&m2);
        let a = Matrix2::new(m1.norm_squared(), -m12, -m12, m2.norm_squared());
        let dq = q2 - q1;
        let b = Vector2::new(m1.dot(&dq), -m2.dot(&dq));
        let t = a.lu().solve(&b)?;
        let o = ((q1 + m1 * t[0]) + (q2 + m2 * t[1])) * 0.5;
        let radius_m = 0.5 * ((q1 - o).norm() + (q2 - o).norm());
        let cyl = Self {
            axis_point: p1 + o,
            axis,
            radius_m,
            extent_m: None,
        };
        cyl.is_finite().then_some(cyl)
    }

    /// Whether every parameter is finite.
    pub fn is_finite(&self) -> bool {
        self.axis_point.iter().all(|c| c.is_finite())
            && self.axis.iter().all(|c| c.is_finite())
            && self.radius_m.is_finite()
    }

    /// Component of `p − axis_point` perpendicular to the axis.
    pub fn radial_vector(&self, p: &Point3<f64>) -> Vector3<f64> {
        let d = p - self.axis_point;
        d - self.axis.into_inner() * self.axis.dot(&d)
    }

    /// Distance of `p` from the axis line, metres.
    pub fn distance_to_axis(&self, p: &Point3<f64>) -> f64 {
        self.radial_vector(p).norm()
    }

    /// Signed distance of `p` from the surface, positive outside, metres.
    pub fn signed_distance(&self, p: &Point3<f64>) -> f64 {
        self.distance_to_axis(p) - self.radius_m
    }

    /// The same cylinder with `extent_m` set to the span of `points` along the axis (left
    /// unchanged when no point is finite).
    pub fn with_extent<'a>(mut self, points: impl IntoIterator<Item = &'a Point3<f64>>) -> Self {
        let mut span: Option<(f64, f64)> = None;
        for p in points {
            let s = self.axis.dot(&(p - self.axis_point));
            if s.is_finite() {
                span = Some(span.map_or((s, s), |(lo, hi)| (lo.min(s), hi.max(s))));
            }
        }
        if span.is_some() {
            self.extent_m = span;
        }
        self
    }

    /// The same cylinder with `extent_m` set to the contiguous run of `points` along the axis that
    /// contains their median projection: walking outwards from the median, the extent stops at
    /// the first gap longer than `max_gap_m`. Stray inliers beyond the fruit's ends (clutter
    /// within the distance threshold) are thereby ignored. Unchanged when no point is finite.
    pub fn with_contiguous_extent<'a>(
        mut self,
        points: impl IntoIterator<Item = &'a Point3<f64>>,
        max_gap_m: f64,
    ) -> Self {
        let mut s: Vec<f64> = points
            .into_iter()
            .map(|p| self.axis.dot(&(p - self.axis_point)))
            .filter(|s| s.is_finite())
            .collect();
        if s.is_empty() {
            return self;
        }
        s.sort_by(f64::total_cmp);
        let mid = s.len() / 2;
        let mut lo = mid;
        while lo > 0 && s[lo] - s[lo - 1] <= max_gap_m {
            lo -= 1;
        }
        let mut hi = mid;
        while hi + 1 < s.len() && s[hi + 1] - s[hi] <= max_gap_m {
            hi += 1;
        }
        self.extent_m = Some((s[lo], s[hi]));
        self
    }

    /// Middle of the extent on the axis (the axis point when no extent is known).
    pub fn midpoint(&self) -> Point3<f64> {
        match self.extent_m {
            Some((lo, hi)) => self.axis_point + self.axis.into_inner() * (0.5 * (lo + hi)),
            None => self.axis_point,
        }
    }

    /// Length of the extent, metres, when known.
    pub fn length_m(&self) -> Option<f64> {
        self.extent_m.map(|(lo, hi)| hi - lo)
    }

    /// Damped Gauss–Newton on the geometric distance `Σ (dist-to-axis − r)²`, starting from
    /// `self`, over five parameters (axis tilt ×2, axis shift ×2, radius). The extent is dropped.
    /// `None` with fewer than five points.
    pub fn refined_geometric(&self, points: &[Point3<f64>], max_iterations: usize) -> Option<Self> {
        if points.len() < 5 {
            return None;
        }
        let sse = |c: &Cylinder| -> f64 {
            points
                .iter()
                .map(|p| {
                    let e = c.signed_distance(p);
                    e * e
                })
                .sum()
        };
        let mut current = Cylinder {
            extent_m: None,
            ..*self
        };
        let mut current_sse = sse(&current);
        let mut lambda = 1e-4;
        for _ in 0..max_iterations {
            // Local frame: u, v ⟂ axis.
            let a = current.axis.into_inner();
            let helper = if a.x.abs() < 0.9 {
                Vector3::x()
            } else {
                Vector3::y()
            };
            let u = a.cross(&helper).normalize();
            let v = a.cross(&u);
            let apply = |d: &SVector<f64, 5>| -> Cylinder {
                Cylinder {
                    axis_point: current.axis_point + u * d[2] + v * d[3],
                    axis: Unit::new_normalize(a + u * d[0] + v * d[1]),
                    radius_m: current.radius_m + d[4],
                    extent_m: None,
                }
            };
            let mut jtj = SMatrix::<f64, 5, 5>::zeros();
            let mut jtr = SVector::<f64, 5>::zeros();
            for p in points {
                let (r, j) = current.residual_and_jacobian(p, &u, &v);
                jtj += j * j.transpose();
                jtr += j * r;
            }
            match damped_step(
                &jtj,
                &jtr,
                current_sse,
                &mut lambda,
                apply,
                |c| c.is_finite() && c.radius_m > 0.0,
                sse,
            ) {
                Some((next, next_sse, moved)) => {
                    current = next;
                    current_sse = next_sse;
                    if !moved {
                        break;
                    }
                }
                None => break,
            }
        }
        Some(current)
    }

    /// `signed_distance(p)` and its gradient with respect to the refinement's five parameters at
    /// zero (axis tilt towards `u` and `v`, axis shift along `u` and `v`, radius), for `u`, `v`
    /// orthonormal and perpendicular to the axis. With `q = p − axis_point`, `t = q·a` and the
    /// radial vector `w` of length `ρ`: tilting the axis by `δ u` moves `w` by `−δ (t u + (q·u) a)`,
    /// shifting it by `δ u` moves `w` by `−δ u`, so the derivatives are `−t (q·u)/ρ`,
    /// `−t (q·v)/ρ`, `−(q·u)/ρ`, `−(q·v)/ρ` and `−1` (only the radius term on the axis itself).
    fn residual_and_jacobian(
        &self,
        p: &Point3<f64>,
        u: &Vector3<f64>,
        v: &Vector3<f64>,
    ) -> (f64, SVector<f64, 5>) {
        let q = p - self.axis_point;
        let rho = self.radial_vector(p).norm();
        let residual = rho - self.radius_m;
        if rho.is_nan() || rho <= 0.0 {
            return (residual, SVector::<f64, 5>::new(0.0, 0.0, 0.0, 0.0, -1.0));
        }
        let t = q.dot(&self.axis);
        let (qu, qv) = (q.dot(u) / rho, q.dot(v) / rho);
        (
            residual,
            SVector::<f64, 5>::new(-t * qu, -t * qv, -qu, -qv, -1.0),
        )
    }
}

impl<D: Positioned> Model<D> for Cylinder {
    /// `|dist-to-axis − r|`, metres.
    fn distance(&self, datum: &D) -> f64 {
        self.signed_distance(&datum.position()).abs()
    }
}

/// Parameters of [`CylinderEstimator`]; validate with [`CylinderEstimatorParams::check`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CylinderEstimatorParams {
    /// Accepted radii `(min, max)`, metres: the fruit-size prior (default 20–80 mm). `max` may be
    /// infinite.
    pub radius_range_m: (f64, f64),
    /// Schnabel's α: a datum whose normal deviates from the cylinder's radial direction by more
    /// than this (sign ignored) gets an infinite residual, radians. `None` (default, as the paper)
    /// uses distances only.
    pub max_normal_deviation_rad: Option<f64>,
    /// Largest gap along the axis inside the reported extent, metres (default 10 mm); see
    /// [`Cylinder::with_contiguous_extent`].
    pub extent_max_gap_m: f64,
}

impl Default for CylinderEstimatorParams {
    fn default() -> Self {
        Self {
            radius_range_m: (0.02, 0.08),
            max_normal_deviation_rad: None,
            extent_max_gap_m: 0.01,
        }
    }
}

impl CylinderEstimatorParams {
    /// Validates into a [`CylinderEstimator`].
    ///
    /// # Errors
    /// [`ConsensusError::InvalidParameter`] when the radius range is not `0 ≤ min < max`, the
    /// angle is not in `(0, π/2]` or the gap is not finite and positive.
    pub fn check(self) -> Result<CylinderEstimator, ConsensusError> {
        check_positive("extent_max_gap_m", self.extent_max_gap_m)?;
        let prior = RadialPrior::check(self.radius_range_m, self.max_normal_deviation_rad)?;
        Ok(CylinderEstimator {
            params: self,
            prior,
        })
    }
}

/// Cylinder hypotheses from two oriented points, with radius priors; build with
/// [`CylinderEstimatorParams::check`]. Data without a normal are skipped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CylinderEstimator {
    params: CylinderEstimatorParams,
    prior: RadialPrior,
}

impl CylinderEstimator {
    /// The validated parameters.
    pub fn params(&self) -> &CylinderEstimatorParams {
        &self.params
    }
}

impl<D: Positioned> Estimator<D> for CylinderEstimator {
    type Model = Cylinder;

    fn min_samples(&self) -> usize {
        2
    }

    fn estimate(&self, sample: &[&D]) -> Option<Cylinder> {
        let [a, b] = sample else {
            return None;
        };
        let c = Cylinder::from_two_oriented_points(
            &a.position(),
            &a.normal()?,
            &b.position(),
            &b.normal()?,
        )?;
        <Self as Estimator<D>>::is_model_valid(self, &c).then_some(c)
    }

    fn is_datum_valid(&self, datum: &D) -> bool {
        datum.has_finite_position() && datum.normal().is_some()
    }

    fn is_model_valid(&self, model: &Cylinder) -> bool {
        self.prior.admits(model.is_finite(), model.radius_m)
    }

    fn residual(&self, model: &Cylinder, datum: &D) -> f64 {
        let radial = model.radial_vector(&datum.position());
        self.prior.residual(&radial, datum.normal(), model.radius_m)
    }

    fn refine(&self, model: &Cylinder, data: &[D], inliers: &[usize]) -> Option<Cylinder> {
        let pts: Vec<Point3<f64>> = inliers.iter().map(|&i| data[i].position()).collect();
        model.refined_geometric(&pts, 20)
    }

    fn finish(&self, model: Cylinder, data: &[D], inliers: &[usize]) -> Cylinder {
        let pts: Vec<Point3<f64>> = inliers.iter().map(|&i| data[i].position()).collect();
        model.with_contiguous_extent(&pts, self.params.extent_max_gap_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn residual_jacobian_matches_finite_differences() {
        let c = Cylinder {
            axis_point: Point3::new(0.01, -0.02, 0.9),
            axis: Unit::new_normalize(Vector3::new(0.2, 1.0, -0.3)),
            radius_m: 0.03,
            extent_m: None,
        };
        let a = c.axis.into_inner();
        let u = a.cross(&Vector3::x()).normalize();
        let v = a.cross(&u);
        // The refinement's parameterisation.
        let apply = |d: &SVector<f64, 5>| Cylinder {
            axis_point: c.axis_point + u * d[2] + v * d[3],
            axis: Unit::new_normalize(a + u * d[0] + v * d[1]),
            radius_m: c.radius_m + d[4],
            extent_m: None,
        };
        for p in [
            Point3::new(0.04, 0.05, 0.92),
            Point3::new(-0.03, -0.1, 0.85),
            Point3::new(0.0, 0.2, 1.0),
        ] {
            let (r, j) = c.residual_and_jacobian(&p, &u, &v);
            assert_eq!(r, c.signed_distance(&p));
            for k in 0..5 {
                let h = 1e-6;
                let mut d = SVector::<f64, 5>::zeros();
                d[k] = h;
                let plus = apply(&d).signed_distance(&p);
                d[k] = -h;
                let numeric = (plus - apply(&d).signed_distance(&p)) / (2.0 * h);
                assert!((j[k] - numeric).abs() < 1e-6, "d{k}: {} vs {numeric}", j[k]);
            }
        }
    }

    #[test]
    fn two_exact_oriented_points_recover_the_cylinder() {
        let axis = Unit::new_normalize(Vector3::new(0.3, 1.0, 0.2));
        let o = Point3::new(0.05, -0.1, 0.8);
        let r = 0.031;
        let u = axis.cross(&Vector3::x()).normalize();
        let v = axis.cross(&u);
        let on = |angle: f64, s: f64| {
            let radial = u * angle.cos() + v * angle.sin();
            (
                o + axis.into_inner() * s + radial * r,
                Unit::new_normalize(radial),
            )
        };
        let (p1, n1) = on(0.3, 0.02);
        let (p2, n2) = on(1.9, -0.05);
        let c = Cylinder::from_two_oriented_points(&p1, &n1, &p2, &n2).unwrap();
        assert!(c.axis.dot(&axis).abs() > 1.0 - 1e-12);
        assert!(c.distance_to_axis(&o) < 1e-9);
        assert!((c.radius_m - r).abs() < 1e-9);
        // Flipped normals give the same cylinder.
        let c2 = Cylinder::from_two_oriented_points(&p1, &-n1, &p2, &n2).unwrap();
        assert!((c2.radius_m - r).abs() < 1e-9);
        assert!(c2.distance_to_axis(&o) < 1e-9);
    }

    #[test]
    fn parallel_normals_are_rejected() {
        let n = Unit::new_normalize(Vector3::new(0.0, 0.0, -1.0));
        let p1 = Point3::new(0.0, 0.0, 1.0);
        let p2 = Point3::new(0.05, 0.0, 1.0);
        assert!(Cylinder::from_two_oriented_points(&p1, &n, &p2, &n).is_none());
    }

    #[test]
    fn normal_deviation_makes_an_outlier() {
        let est = CylinderEstimatorParams {
            max_normal_deviation_rad: Some(0.3),
            ..Default::default()
        }
        .check()
        .unwrap();
        let c = Cylinder {
            axis_point: Point3::origin(),
            axis: Vector3::z_axis(),
            radius_m: 0.03,
            extent_m: None,
        };
        let good = crate::OrientedPoint::new(Point3::new(0.03, 0.0, 0.1), Vector3::x());
        let bad = crate::OrientedPoint::new(Point3::new(0.03, 0.0, 0.1), Vector3::z());
        assert!(est.residual(&c, &good) < 1e-12);
        assert!(est.residual(&c, &bad).is_infinite());
    }
}
