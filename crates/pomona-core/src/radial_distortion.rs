//! Radial lens distortion (the k1, k2 terms of the Brown–Conrady model), the part of a lens's
//! error that matters for seed 004's wide-angle arm cameras.
//!
//! A ray with undistorted normalised image coordinates `p = (x/z, y/z)` lands at
//! `p · (1 + k1 r² + k2 r⁴)`, `r² = |p|²`. [`PinholeCamera`](crate::PinholeCamera) applies it in
//! projection and removes it in back-projection, so every stage that goes through the camera
//! handles distorted images without knowing.

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::CoreError;

/// Iterations of the fixed-point inversion in [`RadialDistortion::undistort`].
pub const UNDISTORT_ITERATIONS: usize = 50;

/// Radial distortion coefficients (dimensionless, for normalised coordinates).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RadialDistortion {
    /// Second-order coefficient (negative: barrel).
    pub k1: f64,
    /// Fourth-order coefficient.
    pub k2: f64,
}

impl RadialDistortion {
    /// Checks that both coefficients are finite.
    ///
    /// # Errors
    /// [`CoreError::InvalidCameraParameter`] naming the coefficient.
    pub fn validate(&self) -> Result<(), CoreError> {
        for (name, value) in [("k1", self.k1), ("k2", self.k2)] {
            if !value.is_finite() {
                return Err(CoreError::InvalidCameraParameter { name, value });
            }
        }
        Ok(())
    }

    /// Whether [`RadialDistortion::undistort`] undoes the distortion at the distorted point `q`
    /// and everywhere nearer the centre: the radial map `ρ ↦ ρ (1 + k1 ρ² + k2 ρ⁴)` rises all the
    /// way out to the undistorted point (it does not fold back), and distorting that point gives
    /// `q` again.
    pub fn inverts(&self, q: Vector2<f64>) -> bool {
        let p = self.undistort(q);
        // The map's slope is g(x) = 1 + 3 k1 x + 5 k2 x² in x = ρ²: a parabola, lowest over
        // [0, |p|²] at an end or at its vertex.
        let slope = |x: f64| 1.0 + 3.0 * self.k1 * x + 5.0 * self.k2 * x * x;
        let end = p.norm_squared();
        let vertex = -3.0 * self.k1 / (10.0 * self.k2);
        let lowest = [0.0, end, vertex]
            .into_iter()
            .filter(|x| (0.0..=end).contains(x))
            .map(slope)
            .fold(f64::INFINITY, f64::min);
        lowest > 0.0 && (self.distort(p) - q).norm() <= 1e-9 * q.norm().max(1.0)
    }

    fn factor(&self, r_sq: f64) -> f64 {
        1.0 + self.k1 * r_sq + self.k2 * r_sq * r_sq
    }

    /// Where the undistorted normalised point `p` lands.
    pub fn distort(&self, p: Vector2<f64>) -> Vector2<f64> {
        p * self.factor(p.norm_squared())
    }

    /// The undistorted normalised point that lands at `q` (the inverse of
    /// [`RadialDistortion::distort`], by fixed-point iteration `p ← q / factor(|p|²)`, which
    /// converges for the moderate distortion of real lenses within the image).
    pub fn undistort(&self, q: Vector2<f64>) -> Vector2<f64> {
        let mut p = q;
        for _ in 0..UNDISTORT_ITERATIONS {
            let next = q / self.factor(p.norm_squared());
            let done = (next - p).norm() < 1e-15;
            p = next;
            if done {
                break;
            }
        }
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn undistort_inverts_distort_over_a_wide_field() {
        for (k1, k2) in [(-0.2, 0.05), (0.1, -0.02), (-0.35, 0.12), (0.0, 0.0)] {
            let d = RadialDistortion { k1, k2 };
            for i in -8..=8 {
                for j in -6..=6 {
                    let p = Vector2::new(f64::from(i) * 0.08, f64::from(j) * 0.08);
                    let back = d.undistort(d.distort(p));
                    assert!((back - p).norm() < 1e-10, "{k1} {k2}: {p} → {back}");
                }
            }
        }
    }

    #[test]
    fn barrel_distortion_pulls_points_in_and_keeps_the_centre() {
        let d = RadialDistortion { k1: -0.2, k2: 0.0 };
        let p = Vector2::new(0.5, 0.0);
        assert!((d.distort(p).x - 0.5 * (1.0 - 0.2 * 0.25)).abs() < 1e-15);
        assert_eq!(d.distort(Vector2::zeros()), Vector2::zeros());
        assert!(RadialDistortion {
            k1: f64::NAN,
            k2: 0.0
        }
        .validate()
        .is_err());
    }
}
