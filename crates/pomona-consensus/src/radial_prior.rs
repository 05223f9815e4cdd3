//! What the sphere and cylinder estimators share: the fruit-size prior on a hypothesis's radius
//! and the normal gate on each datum's residual (Schnabel et al.'s α).
//!
//! Both shapes measure a point by its *radial vector* — from the sphere's centre, or square to
//! the cylinder's axis — whose length is compared with the radius and whose direction, when the
//! datum carries a normal, with that normal. Only how the radial vector is found differs, so the
//! rest lives here once.

use nalgebra::{Unit, Vector3};

use crate::consensus::check_positive;
use crate::ConsensusError;

/// A validated radius range and normal gate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RadialPrior {
    radius_range_m: (f64, f64),
    /// Cosine of the largest normal deviation; `None`: distances only.
    min_normal_cos: Option<f64>,
}

impl RadialPrior {
    /// The prior of a radius range `(min, max)` in metres and an optional largest deviation of a
    /// datum's normal from its radial direction, radians.
    ///
    /// # Errors
    /// [`ConsensusError::InvalidParameter`] when the range is not `0 ≤ min < max` with `min`
    /// finite, or the angle is not in `(0, π/2]`.
    pub(crate) fn check(
        radius_range_m: (f64, f64),
        max_normal_deviation_rad: Option<f64>,
    ) -> Result<Self, ConsensusError> {
        let (lo, hi) = radius_range_m;
        if !(lo.is_finite() && lo >= 0.0 && hi > lo) {
            return Err(ConsensusError::InvalidParameter {
                name: "radius_range_m",
                value: lo,
                reason: "must satisfy 0 <= min < max with min finite",
            });
        }
        let min_normal_cos = match max_normal_deviation_rad {
            Some(a) => {
                check_positive("max_normal_deviation_rad", a)?;
                if a > std::f64::consts::FRAC_PI_2 {
                    return Err(ConsensusError::InvalidParameter {
                        name: "max_normal_deviation_rad",
                        value: a,
                        reason: "must not exceed pi/2",
                    });
                }
                Some(a.cos())
            }
            None => None,
        };
        Ok(Self {
            radius_range_m,
            min_normal_cos,
        })
    }

    /// Whether a finite hypothesis of this radius is admitted.
    pub(crate) fn admits(&self, is_finite: bool, radius_m: f64) -> bool {
        let (lo, hi) = self.radius_range_m;
        is_finite && radius_m >= lo && radius_m <= hi
    }

    /// `| |radial| − radius_m |`, or infinite when the datum's normal deviates from the radial
    /// direction by more than the gate allows (sign ignored).
    pub(crate) fn residual(
        &self,
        radial: &Vector3<f64>,
        normal: Option<Unit<Vector3<f64>>>,
        radius_m: f64,
    ) -> f64 {
        let n = radial.norm();
        if let (Some(min_cos), Some(normal)) = (self.min_normal_cos, normal) {
            if n > 0.0 && (normal.dot(radial) / n).abs() < min_cos {
                return f64::INFINITY;
            }
        }
        (n - radius_m).abs()
    }
}
