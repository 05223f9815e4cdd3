//! The joint ranges of the arm: what it can reach.

use serde::{Deserialize, Serialize};

use crate::{ArmError, ArmJoints};

/// Closed joint ranges; defaults are seed 004's robot: α ∈ [−40°, 40°], θ ∈ [60°, 120°],
/// r ∈ [0.3, 1.3] m.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ArmLimits {
    /// Azimuth range, radians.
    pub alpha_rad: (f64, f64),
    /// Elevation range, radians.
    pub theta_rad: (f64, f64),
    /// Extension range, metres.
    pub r_m: (f64, f64),
}

impl Default for ArmLimits {
    fn default() -> Self {
        Self {
            alpha_rad: (-40f64.to_radians(), 40f64.to_radians()),
            theta_rad: (60f64.to_radians(), 120f64.to_radians()),
            r_m: (0.3, 1.3),
        }
    }
}

impl ArmLimits {
    /// Checks that every range is finite and not empty.
    ///
    /// # Errors
    /// [`ArmError::InvalidParameter`] naming the first bad range.
    pub fn validate(&self) -> Result<(), ArmError> {
        for (name, (lo, hi)) in [
            ("alpha_rad", self.alpha_rad),
            ("theta_rad", self.theta_rad),
            ("r_m", self.r_m),
        ] {
            if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                return Err(ArmError::InvalidParameter {
                    name,
                    value: lo,
                    reason: "a range must be finite with min ≤ max",
                });
            }
        }
        Ok(())
    }

    /// Whether the arm can take the pose `q`.
    pub fn allows(&self, q: &ArmJoints) -> bool {
        let within = |v: f64, (lo, hi): (f64, f64)| (lo..=hi).contains(&v);
        within(q.alpha_rad, self.alpha_rad)
            && within(q.theta_rad, self.theta_rad)
            && within(q.r_m, self.r_m)
    }
}
