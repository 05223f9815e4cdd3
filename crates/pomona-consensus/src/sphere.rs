//! Spheres: the model, the 4-point estimator of seed 002 Eq. 6, and least-squares refits.
//!
//! Eq. 6 writes a sphere as `x² + y² + z² − 2ax − 2by − 2cz + d = 0`, linear in `(a, b, c, d)`,
//! so four points determine it. Subtracting the equation of the first point removes `d` and leaves
//! a 3×3 linear system for the centre; we solve it in coordinates relative to that first point,
//! which keeps it well conditioned far from the camera. Four coplanar (or collinear, or repeated)
//! points make the system singular — every sphere through their circle fits — so such samples are
//! rejected, as are spheres outside the fruit-size radius prior.
//!
//! The refit (not in the paper) minimises the geometric distance `Σ (‖pᵢ − c‖ − r)²` by damped
//! Gauss–Newton from the MSAC model; [`Sphere::fit_least_squares`] provides the algebraic
//! (Kåsa) fit as a starting point when there is no model yet.

use crate::damped_step::damped_step;
use nalgebra::{Matrix3, Matrix4, Point3, Vector3, Vector4};
use serde::{Deserialize, Serialize};

use crate::radial_prior::RadialPrior;
use crate::{ConsensusError, Estimator, Model, Positioned};

/// A sphere, metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Sphere {
    /// Centre.
    pub center: Point3<f64>,
    /// Radius, metres.
    pub radius_m: f64,
}

/// Relative volume below which four points count as coplanar: `|q₁·(q₂×q₃)| / (‖q₁‖‖q₂‖‖q₃‖)`.
const COPLANAR_TOLERANCE: f64 = 1e-4;

impl Sphere {
    /// The sphere through four points (seed 002 Eq. 6), or `None` when they are coplanar,
    /// collinear, repeated or not finite.
    pub fn from_four_points(p: [&Point3<f64>; 4]) -> Option<Self> {
        let q1 = p[1] - p[0];
        let q2 = p[2] - p[0];
        let q3 = p[3] - p[0];
        let scale = q1.norm() * q2.norm() * q3.norm();
        let det = q1.dot(&q2.cross(&q3));
        if !(scale > 0.0 && scale.is_finite() && det.abs() > COPLANAR_TOLERANCE * scale) {
            return None;
        }
        // 2 qᵢ · c' = ‖qᵢ‖², centre c = p₀ + c'.
        let a = Matrix3::from_rows(&[q1.transpose(), q2.transpose(), q3.transpose()]);
        let b = Vector3::new(q1.norm_squared(), q2.norm_squared(), q3.norm_squared()) * 0.5;
        let c_rel = a.lu().solve(&b)?;
        let sphere = Self {
            center: p[0] + c_rel,
            radius_m: c_rel.norm(),
        };
        sphere.is_finite().then_some(sphere)
    }

    /// Whether centre and radius are finite.
    pub fn is_finite(&self) -> bool {
        self.center.iter().all(|c| c.is_finite()) && self.radius_m.is_finite()
    }

    /// Signed distance of `p` from the surface, positive outside, metres.
    pub fn signed_distance(&self, p: &Point3<f64>) -> f64 {
        (p - self.center).norm() - self.radius_m
    }

    /// Algebraic least-squares sphere (Kåsa fit of Eq. 6 to all points), then geometric
    /// refinement. Non-finite points are skipped. `None` with fewer than four usable points or a
    /// degenerate configuration.
    pub fn fit_least_squares(points: &[Point3<f64>]) -> Option<Self> {
        let pts: Vec<Point3<f64>> = points
            .iter()
            .filter(|p| p.has_finite_position())
            .copied()
            .collect();
        if pts.len() < 4 {
            return None;
        }
        let mean = pts.iter().fold(Vector3::zeros(), |acc, p| acc + p.coords) / pts.len() as f64;
        // Unknowns (c'ₓ, c'ᵧ, c'_z, k) with 2 q·c' + k = ‖q‖², k = r² − ‖c'‖².
        let mut ata = Matrix4::<f64>::zeros();
        let mut atb = Vector4::<f64>::zeros();
        for p in &pts {
            let q = p.coords - mean;
            let row = Vector4::new(2.0 * q.x, 2.0 * q.y, 2.0 * q.z, 1.0);
            ata += row * row.transpose();
            atb += row * q.norm_squared();
        }
        let x = ata.cholesky()?.solve(&atb);
        let c_rel = Vector3::new(x[0], x[1], x[2]);
        let r2 = x[3] + c_rel.norm_squared();
        if r2.is_nan() || r2 <= 0.0 {
            return None;
        }
        let init = Self {
            center: Point3::from(mean + c_rel),
            radius_m: r2.sqrt(),
        };
        if !init.is_finite() {
            return None;
        }
        Some(init.refined_geometric(&pts, 20).unwrap_or(init))
    }

    /// Damped Gauss–Newton on the geometric distance, starting from `self`. `None` when the
    /// normal equations are singular from the start or fewer than four points are given.
    pub fn refined_geometric(&self, points: &[Point3<f64>], max_iterations: usize) -> Option<Self> {
        if points.len() < 4 {
            return None;
        }
        let sse = |s: &Sphere| -> f64 {
            points
                .iter()
                .map(|p| {
                    let e = s.signed_distance(p);
                    e * e
                })
                .sum()
        };
        let mut current = *self;
        let mut current_sse = sse(&current);
        let mut lambda = 1e-6;
        for _ in 0..max_iterations {
            let mut jtj = Matrix4::<f64>::zeros();
            let mut jtr = Vector4::<f64>::zeros();
            for p in points {
                let d = p - current.center;
                let n = d.norm();
                if n <= f64::EPSILON {
                    continue;
                }
                let u = d / n;
                let j = Vector4::new(-u.x, -u.y, -u.z, -1.0);
                let r = n - current.radius_m;
                jtj += j * j.transpose();
                jtr += j * r;
            }
            match damped_step(
                &jtj,
                &jtr,
                current_sse,
                &mut lambda,
                |delta: &Vector4<f64>| Sphere {
                    center: current.center + Vector3::new(delta[0], delta[1], delta[2]),
                    radius_m: current.radius_m + delta[3],
                },
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
}

impl<D: Positioned> Model<D> for Sphere {
    /// `|‖p − c‖ − r|`, metres.
    fn distance(&self, datum: &D) -> f64 {
        self.signed_distance(&datum.position()).abs()
    }
}

/// Parameters of [`SphereEstimator`]; validate with [`SphereEstimatorParams::check`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SphereEstimatorParams {
    /// Accepted radii `(min, max)`, metres: the fruit-size prior (default 20–80 mm). `max` may be
    /// infinite.
    pub radius_range_m: (f64, f64),
    /// When set and a datum has a normal, the datum counts as an outlier (infinite residual) if
    /// its normal deviates from the sphere's radial direction by more than this angle (sign
    /// ignored), radians. Default `None` (the paper uses distances only).
    pub max_normal_deviation_rad: Option<f64>,
    /// When set, the sphere is seen from this point (the camera centre, in the data's frame):
    /// only its facing side is visible, so a datum whose radial direction points away from the
    /// viewpoint (more than [`FACING_SLACK`] past the rim) is an outlier, and a hypothesis whose
    /// four samples are not all on the facing side is refused. A convex fruit seen from outside
    /// shows only that side; without the test a sphere fitted inside out — through a fruit's
    /// edge and the leaves beside it, its centre in front of them — can win on inlier count.
    /// Default `None` (the paper uses distances only; absent in older files).
    #[serde(default)]
    pub visible_from: Option<Point3<f64>>,
}

/// How far past the rim a datum still counts as facing the viewpoint: the cosine between its
/// radial direction and its direction to the viewpoint may fall to `-FACING_SLACK` (about 6°
/// past the silhouette, where depth sensors place rim points too far).
pub const FACING_SLACK: f64 = 0.1;

/// Whether the datum at `point`, whose radial vector from the shape is `radial`, faces
/// `viewpoint` (see [`SphereEstimatorParams::visible_from`]).
fn faces(radial: &Vector3<f64>, point: &Point3<f64>, viewpoint: &Point3<f64>) -> bool {
    let to_view = viewpoint - point;
    let dot = radial.dot(&to_view);
    // `dot > -FACING_SLACK · |radial| · |to_view|`, without square roots: every datum of a
    // hypothesis's scoring passes here, and most face the viewpoint outright.
    dot > 0.0
        || dot * dot < FACING_SLACK * FACING_SLACK * radial.norm_squared() * to_view.norm_squared()
}

impl Default for SphereEstimatorParams {
    fn default() -> Self {
        Self {
            radius_range_m: (0.02, 0.08),
            max_normal_deviation_rad: None,
            visible_from: None,
        }
    }
}

impl SphereEstimatorParams {
    /// Validates into a [`SphereEstimator`].
    ///
    /// # Errors
    /// [`ConsensusError::InvalidParameter`] when the radius range is not `0 ≤ min < max`, the
    /// angle is not in `(0, π/2]` or the viewpoint is not finite.
    pub fn check(self) -> Result<SphereEstimator, ConsensusError> {
        if let Some(value) = self
            .visible_from
            .and_then(|v| v.coords.iter().copied().find(|c| !c.is_finite()))
        {
            return Err(ConsensusError::InvalidParameter {
                name: "visible_from",
                value,
                reason: "must be a finite point",
            });
        }
        let prior = RadialPrior::check(self.radius_range_m, self.max_normal_deviation_rad)?;
        Ok(SphereEstimator {
            params: self,
            prior,
        })
    }
}

/// Sphere hypotheses from four points, with radius priors; build with
/// [`SphereEstimatorParams::check`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereEstimator {
    params: SphereEstimatorParams,
    prior: RadialPrior,
}

impl SphereEstimator {
    /// The validated parameters.
    pub fn params(&self) -> &SphereEstimatorParams {
        &self.params
    }
}

impl<D: Positioned> Estimator<D> for SphereEstimator {
    type Model = Sphere;

    fn min_samples(&self) -> usize {
        4
    }

    fn estimate(&self, sample: &[&D]) -> Option<Sphere> {
        let [a, b, c, d] = sample else {
            return None;
        };
        let (pa, pb, pc, pd) = (a.position(), b.position(), c.position(), d.position());
        let s = Sphere::from_four_points([&pa, &pb, &pc, &pd])?;
        let facing = |p: &Point3<f64>| {
            self.params
                .visible_from
                .is_none_or(|v| faces(&(p - s.center), p, &v))
        };
        (<Self as Estimator<D>>::is_model_valid(self, &s) && [pa, pb, pc, pd].iter().all(facing))
            .then_some(s)
    }

    fn is_datum_valid(&self, datum: &D) -> bool {
        datum.has_finite_position()
    }

    fn is_model_valid(&self, model: &Sphere) -> bool {
        self.prior.admits(model.is_finite(), model.radius_m)
    }

    fn residual(&self, model: &Sphere, datum: &D) -> f64 {
        let p = datum.position();
        let radial = p - model.center;
        if let Some(v) = self.params.visible_from {
            if !faces(&radial, &p, &v) {
                return f64::INFINITY;
            }
        }
        self.prior.residual(&radial, datum.normal(), model.radius_m)
    }

    fn refine(&self, model: &Sphere, data: &[D], inliers: &[usize]) -> Option<Sphere> {
        let pts: Vec<Point3<f64>> = inliers.iter().map(|&i| data[i].position()).collect();
        model.refined_geometric(&pts, 20)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_exact_points_recover_the_sphere() {
        let c = Point3::new(0.1, -0.2, 0.9);
        let r = 0.037;
        let dirs = [
            Vector3::new(1.0, 0.2, -0.3),
            Vector3::new(-0.4, 1.0, 0.1),
            Vector3::new(0.3, -0.5, -1.0),
            Vector3::new(-0.7, -0.7, 0.2),
        ];
        let p: Vec<Point3<f64>> = dirs.iter().map(|d| c + d.normalize() * r).collect();
        let s = Sphere::from_four_points([&p[0], &p[1], &p[2], &p[3]]).unwrap();
        assert!((s.center - c).norm() < 1e-9, "{s:?}");
        assert!((s.radius_m - r).abs() < 1e-9);
    }

    #[test]
    fn degenerate_samples_are_rejected() {
        let coplanar = [
            Point3::new(0.0, 0.0, 1.0),
            Point3::new(0.05, 0.0, 1.0),
            Point3::new(0.0, 0.05, 1.0),
            Point3::new(0.05, 0.05, 1.0),
        ];
        assert!(
            Sphere::from_four_points([&coplanar[0], &coplanar[1], &coplanar[2], &coplanar[3]])
                .is_none()
        );
        let repeated = [coplanar[0], coplanar[0], coplanar[1], coplanar[2]];
        assert!(
            Sphere::from_four_points([&repeated[0], &repeated[1], &repeated[2], &repeated[3]])
                .is_none()
        );
        let collinear: Vec<_> = (0..4)
            .map(|i| Point3::new(i as f64 * 0.01, 0.0, 1.0))
            .collect();
        assert!(Sphere::from_four_points([
            &collinear[0],
            &collinear[1],
            &collinear[2],
            &collinear[3]
        ])
        .is_none());
        let nan = Point3::new(f64::NAN, 0.0, 0.0);
        assert!(
            Sphere::from_four_points([&nan, &coplanar[1], &coplanar[2], &coplanar[3]]).is_none()
        );
    }

    #[test]
    fn radius_prior_rejects_models() {
        let est = SphereEstimatorParams::default().check().unwrap();
        let big = [
            Point3::new(0.5, 0.0, 0.0),
            Point3::new(-0.5, 0.0, 0.0),
            Point3::new(0.0, 0.5, 0.0),
            Point3::new(0.0, 0.0, 0.5),
        ];
        let refs: Vec<&Point3<f64>> = big.iter().collect();
        assert!(Estimator::<Point3<f64>>::estimate(&est, &refs).is_none());
        assert!(SphereEstimatorParams {
            radius_range_m: (0.1, 0.05),
            ..Default::default()
        }
        .check()
        .is_err());
    }

    /// `n` points spread evenly over `sphere` (a Fibonacci spiral), those whose radial direction
    /// faces the origin when `facing`, the others when not.
    fn side_of(sphere: &Sphere, n: usize, facing: bool) -> Vec<Point3<f64>> {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let s = (1.0 - z * z).sqrt();
                let t = golden * i as f64;
                sphere.center + Vector3::new(s * t.cos(), s * t.sin(), z) * sphere.radius_m
            })
            .filter(|p| ((p - sphere.center).dot(&(-p.coords)) > 0.0) == facing)
            .collect()
    }

    /// A fruit's camera-facing cap beside a bowl (the far side of a larger sphere, as leaves
    /// curled round a fruit can be): the bowl holds more points and wins by inlier count; seen
    /// from the camera only the cap is the visible side of a sphere.
    #[test]
    fn a_sphere_seen_from_the_camera_shows_its_facing_side() {
        use crate::{Acceptance, Consensus, MsacParams};
        let fruit = Sphere {
            center: Point3::new(0.05, 0.0, 1.0),
            radius_m: 0.035,
        };
        let bowl = Sphere {
            center: Point3::new(-0.09, 0.0, 0.95),
            radius_m: 0.05,
        };
        let mut data = side_of(&fruit, 160, true);
        data.extend(side_of(&bowl, 400, false));
        let msac = MsacParams {
            cost_threshold_m: 0.004,
            acceptance: Acceptance::Always,
            iterations: 400,
            early_stop_confidence: None,
            inlier_threshold_m: 0.002,
            refine_threshold_m: Some(0.002),
            ..MsacParams::default()
        }
        .check()
        .unwrap();
        let estimator = |visible_from| {
            SphereEstimatorParams {
                visible_from,
                ..Default::default()
            }
            .check()
            .unwrap()
        };
        let fit = |visible_from| {
            msac.fit_seeded(&estimator(visible_from), &data, 7)
                .unwrap()
                .unwrap()
                .model
        };
        let blind = fit(None);
        assert!((blind.center - bowl.center).norm() < 1e-3, "{blind:?}");
        let seen = fit(Some(Point3::origin()));
        assert!((seen.center - fruit.center).norm() < 1e-3, "{seen:?}");
        assert!((seen.radius_m - fruit.radius_m).abs() < 1e-3, "{seen:?}");
        // Four samples of the bowl's far side make no hypothesis when it is seen from the camera.
        let far_side = side_of(&bowl, 400, false);
        let sample: Vec<&Point3<f64>> = far_side.iter().step_by(50).take(4).collect();
        let estimate =
            |visible_from| Estimator::<Point3<f64>>::estimate(&estimator(visible_from), &sample);
        assert!(estimate(None).is_some());
        assert!(estimate(Some(Point3::origin())).is_none());
        let nowhere = SphereEstimatorParams {
            visible_from: Some(Point3::new(0.0, f64::NAN, 0.0)),
            ..Default::default()
        };
        assert!(nowhere.check().is_err());
    }

    #[test]
    fn least_squares_fit_recovers_exact_sphere() {
        let c = Point3::new(0.0, 0.05, 0.7);
        let r = 0.04;
        let pts: Vec<Point3<f64>> = (0..200)
            .map(|i| {
                let t = i as f64 * 0.37;
                let z = -(i as f64 / 200.0);
                let s = (1.0 - z * z).sqrt();
                c + Vector3::new(s * t.cos(), s * t.sin(), z) * r
            })
            .collect();
        let s = Sphere::fit_least_squares(&pts).unwrap();
        assert!((s.center - c).norm() < 1e-9);
        assert!((s.radius_m - r).abs() < 1e-9);
    }
}
