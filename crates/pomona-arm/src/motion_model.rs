//! How long the arm takes: joints move at fixed rates, simultaneously, so a move lasts as long as
//! its slowest joint; every pick adds a fixed time.

use serde::{Deserialize, Serialize};

use crate::{ArmError, ArmJoints};

/// Joint rates and pick time; defaults are the planning issue's: 60°/s for both angles,
/// 0.5 m/s for the link, 2.0 s per pick.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MotionModel {
    /// Azimuth rate, radians per second.
    pub alpha_rate_rad_s: f64,
    /// Elevation rate, radians per second.
    pub theta_rate_rad_s: f64,
    /// Link rate, metres per second.
    pub r_rate_m_s: f64,
    /// Time to pick one fruit once there, seconds.
    pub pick_s: f64,
}

impl Default for MotionModel {
    fn default() -> Self {
        Self {
            alpha_rate_rad_s: 60f64.to_radians(),
            theta_rate_rad_s: 60f64.to_radians(),
            r_rate_m_s: 0.5,
            pick_s: 2.0,
        }
    }
}

impl MotionModel {
    /// Checks that rates are finite and positive and the pick time finite and not negative.
    ///
    /// # Errors
    /// [`ArmError::InvalidParameter`] naming the first bad value.
    pub fn validate(&self) -> Result<(), ArmError> {
        for (name, v) in [
            ("alpha_rate_rad_s", self.alpha_rate_rad_s),
            ("theta_rate_rad_s", self.theta_rate_rad_s),
            ("r_rate_m_s", self.r_rate_m_s),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(ArmError::InvalidParameter {
                    name,
                    value: v,
                    reason: "must be finite and > 0",
                });
            }
        }
        if !(self.pick_s.is_finite() && self.pick_s >= 0.0) {
            return Err(ArmError::InvalidParameter {
                name: "pick_s",
                value: self.pick_s,
                reason: "must be finite and ≥ 0",
            });
        }
        Ok(())
    }

    /// Seconds to move from `a` to `b` (symmetric; zero for the same pose).
    ///
    /// ```
    /// use pomona_arm::{ArmJoints, MotionModel};
    /// let a = ArmJoints::home();
    /// let b = ArmJoints { alpha_rad: 30f64.to_radians(), r_m: 0.55, ..a };
    /// // 30° at 60°/s = 0.5 s; 0.25 m at 0.5 m/s = 0.5 s.
    /// assert!((MotionModel::default().move_s(&a, &b) - 0.5).abs() < 1e-12);
    /// ```
    pub fn move_s(&self, a: &ArmJoints, b: &ArmJoints) -> f64 {
        let alpha = (a.alpha_rad - b.alpha_rad).abs() / self.alpha_rate_rad_s;
        let theta = (a.theta_rad - b.theta_rad).abs() / self.theta_rate_rad_s;
        let r = (a.r_m - b.r_m).abs() / self.r_rate_m_s;
        alpha.max(theta).max(r)
    }
}
