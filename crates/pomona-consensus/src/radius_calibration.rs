//! Radius calibration: how well a fitted sphere's radius predicts the caliper radius, learnt on
//! the training fits that match an annotated fruit, and the fixed-radius centre refit that uses
//! it. Shared by the detectors that fit spheres to fruit (`shape-fit`'s candidates, the box
//! detectors' centre refinement), hence here beside [`Sphere`].
//!
//! A sphere fitted to the visible cap of a fruit pins the radius poorly, and depth at the
//! silhouette (flying pixels, depth registered to a larger colour image) biases it upwards: on
//! the Azure Kinect apples free fits come out about 10 mm too large in diameter, and the centre
//! is pushed away from the camera with it. Training regresses the true radius on the fitted one
//! over its positive sphere fits (ordinary least squares, slope clamped to `[0, 1]`: from
//! "the fit says nothing, use the training mean" to "trust the fit"); detection replaces each
//! sphere's radius by the calibrated one (clamped to the radius range) and refits the centre
//! with the radius held fixed, by Gauss–Newton on the candidate's inliers — how the truth
//! centres of `ak-apples` were derived from the caliper radius. Cylinders are left as fitted.

use nalgebra::{Matrix3, Point3, Vector3};
use serde::{Deserialize, Serialize};

use crate::{Shape, Sphere};

/// Fewest matched candidates a calibration is learnt from.
pub const MIN_CALIBRATION_SAMPLES: usize = 5;

/// `true radius ≈ intercept_m + slope · fitted radius`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RadiusCalibration {
    /// Intercept, metres.
    pub intercept_m: f64,
    /// Slope, in `[0, 1]`.
    pub slope: f64,
    /// Candidates it was learnt from.
    pub samples: usize,
}

impl RadiusCalibration {
    /// Least-squares fit to `(fitted, true)` radius pairs, metres; `None` with fewer than
    /// [`MIN_CALIBRATION_SAMPLES`] finite pairs.
    pub fn fit(pairs: &[(f64, f64)]) -> Option<Self> {
        let pairs: Vec<(f64, f64)> = pairs
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .collect();
        if pairs.len() < MIN_CALIBRATION_SAMPLES {
            return None;
        }
        let n = pairs.len() as f64;
        let mx = pairs.iter().map(|p| p.0).sum::<f64>() / n;
        let my = pairs.iter().map(|p| p.1).sum::<f64>() / n;
        let sxx: f64 = pairs.iter().map(|p| (p.0 - mx).powi(2)).sum();
        let sxy: f64 = pairs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let slope = if sxx > 1e-12 {
            (sxy / sxx).clamp(0.0, 1.0)
        } else {
            0.0
        };
        Some(Self {
            intercept_m: my - slope * mx,
            slope,
            samples: pairs.len(),
        })
    }

    /// The calibrated radius of a fitted one, clamped to `range_m`.
    pub fn radius_m(&self, fitted_m: f64, range_m: (f64, f64)) -> f64 {
        (self.intercept_m + self.slope * fitted_m).clamp(range_m.0, range_m.1)
    }

    /// `shape` with the calibrated radius and its centre refitted to `points` at that radius
    /// (spheres only; the centre is kept when the refit fails or moves it by more than the
    /// radius).
    pub fn apply(&self, shape: &Shape, points: &[Point3<f64>], range_m: (f64, f64)) -> Shape {
        match shape {
            Shape::Sphere(s) => Shape::Sphere(self.apply_to_sphere(s, points, range_m)),
            Shape::Cylinder(_) => *shape,
        }
    }

    /// `sphere` with the calibrated radius and its centre refitted to `points` at that radius
    /// (the centre is kept when the refit fails or moves it by more than the radius).
    pub fn apply_to_sphere(
        &self,
        sphere: &Sphere,
        points: &[Point3<f64>],
        range_m: (f64, f64),
    ) -> Sphere {
        let radius_m = self.radius_m(sphere.radius_m, range_m);
        let center = fit_center_fixed_radius(points, sphere.center, radius_m)
            .filter(|c| (c - sphere.center).norm() <= radius_m)
            .unwrap_or(sphere.center);
        Sphere { center, radius_m }
    }
}

/// The centre minimising `Σ (‖p − c‖ − r)²` from `start` (Gauss–Newton, at most 20 steps);
/// `None` with fewer than 4 points or a singular system.
pub fn fit_center_fixed_radius(
    points: &[Point3<f64>],
    start: Point3<f64>,
    radius_m: f64,
) -> Option<Point3<f64>> {
    if points.len() < 4 {
        return None;
    }
    let mut c = start;
    for _ in 0..20 {
        let mut jtj = Matrix3::zeros();
        let mut jtr = Vector3::zeros();
        for p in points {
            let d = p - c;
            let norm = d.norm();
            if norm < 1e-9 {
                continue;
            }
            let j = -d / norm;
            jtj += j * j.transpose();
            jtr += j * (norm - radius_m);
        }
        let step = jtj.lu().solve(&(-jtr))?;
        if !step.iter().all(|v| v.is_finite()) {
            return None;
        }
        c += step;
        if step.norm() < 1e-7 {
            break;
        }
    }
    Some(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn calibration_shrinks_towards_the_mean_and_refits_the_centre() {
        // Fitted radii carry no information: the calibration is the mean true radius.
        let none = RadiusCalibration::fit(&[
            (0.04, 0.03),
            (0.045, 0.04),
            (0.04, 0.04),
            (0.045, 0.03),
            (0.0425, 0.035),
        ])
        .unwrap();
        assert!(none.slope.abs() < 1e-12);
        assert!((none.radius_m(0.05, (0.0, 1.0)) - 0.035).abs() < 1e-12);
        // Exact fits with a bias: slope 1, intercept −5 mm; the range clamps.
        let pairs: Vec<(f64, f64)> = (0..6)
            .map(|k| 0.03 + 0.002 * k as f64)
            .map(|r| (r + 0.005, r))
            .collect();
        let biased = RadiusCalibration::fit(&pairs).unwrap();
        assert!((biased.slope - 1.0).abs() < 1e-9);
        assert!((biased.intercept_m + 0.005).abs() < 1e-9);
        assert!((biased.radius_m(0.1, (0.02, 0.05)) - 0.05).abs() < 1e-12);
        assert!(RadiusCalibration::fit(&pairs[..4]).is_none());

        // A cap of a 35 mm sphere at (0, 0, 1) seen from the origin; a fit that swelled to
        // 45 mm and moved 10 mm back is pulled back to the true centre at the true radius.
        let truth = Point3::new(0.0, 0.0, 1.0);
        let mut cap = Vec::new();
        for i in 0..20 {
            for j in 0..20 {
                let (theta, phi) = (0.05 * i as f64, std::f64::consts::TAU * j as f64 / 20.0);
                let n = Vector3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    -theta.cos(),
                );
                cap.push(truth + 0.035 * n);
            }
        }
        let swollen = Shape::Sphere(Sphere {
            center: Point3::new(0.0, 0.0, 1.01),
            radius_m: 0.045,
        });
        let cal = RadiusCalibration {
            intercept_m: 0.035,
            slope: 0.0,
            samples: 10,
        };
        let Shape::Sphere(fixed) = cal.apply(&swollen, &cap, (0.02, 0.05)) else {
            panic!("not a sphere")
        };
        assert!((fixed.radius_m - 0.035).abs() < 1e-12);
        assert!((fixed.center - truth).norm() < 1e-6, "{}", fixed.center);
    }
}
