//! Joint coordinates of the two-angle telescopic arm and their relation to a point in the hub
//! frame (x right, y down, z forward, metres), seed 004 §4.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

/// The arm's three joints.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ArmJoints {
    /// Azimuth α = atan2(x, z), radians (positive to the right).
    pub alpha_rad: f64,
    /// Elevation θ = acos(−y / r), radians: 0 straight up, π/2 level, π straight down.
    pub theta_rad: f64,
    /// Extension of the telescopic link, the distance from the hub, metres.
    pub r_m: f64,
}

impl ArmJoints {
    /// The arm's home pose of seed 004's robot: α 0°, θ 90°, r 0.3 m.
    pub fn home() -> Self {
        Self {
            alpha_rad: 0.0,
            theta_rad: std::f64::consts::FRAC_PI_2,
            r_m: 0.3,
        }
    }

    /// The joints that put the end of the link at `point_in_hub`; `None` at the hub itself or
    /// for a non-finite point.
    ///
    /// ```
    /// use pomona_arm::ArmJoints;
    /// use pomona_core::nalgebra::Point3;
    /// let q = ArmJoints::reaching(&Point3::new(0.0, -0.5, 0.5)).unwrap();
    /// assert!((q.theta_rad.to_degrees() - 45.0).abs() < 1e-9); // up at 45°
    /// assert!((q.to_point_in_hub() - Point3::new(0.0, -0.5, 0.5)).norm() < 1e-12);
    /// ```
    pub fn reaching(point_in_hub: &Point3<f64>) -> Option<Self> {
        let r = point_in_hub.coords.norm();
        if !(r.is_finite() && r > 0.0) {
            return None;
        }
        Some(Self {
            alpha_rad: point_in_hub.x.atan2(point_in_hub.z),
            theta_rad: (-point_in_hub.y / r).clamp(-1.0, 1.0).acos(),
            r_m: r,
        })
    }

    /// Where the end of the link is, in the hub frame (the inverse of [`ArmJoints::reaching`]).
    pub fn to_point_in_hub(&self) -> Point3<f64> {
        let level = self.r_m * self.theta_rad.sin();
        Point3::new(
            level * self.alpha_rad.sin(),
            -self.r_m * self.theta_rad.cos(),
            level * self.alpha_rad.cos(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinematics_round_trip_over_the_workspace() {
        for a in -8..=8 {
            for t in 1..=17 {
                for r in [0.3, 0.7, 1.3] {
                    let q = ArmJoints {
                        alpha_rad: (f64::from(a) * 10.0).to_radians(),
                        theta_rad: (f64::from(t) * 10.0).to_radians(),
                        r_m: r,
                    };
                    let back = ArmJoints::reaching(&q.to_point_in_hub()).unwrap();
                    assert!(
                        (back.alpha_rad - q.alpha_rad).abs() < 1e-12,
                        "{q:?} {back:?}"
                    );
                    assert!((back.theta_rad - q.theta_rad).abs() < 1e-12);
                    assert!((back.r_m - q.r_m).abs() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn level_forward_is_home_direction_and_the_hub_has_no_joints() {
        let q = ArmJoints::reaching(&Point3::new(0.0, 0.0, 0.3)).unwrap();
        assert!((q.alpha_rad - ArmJoints::home().alpha_rad).abs() < 1e-12);
        assert!((q.theta_rad - ArmJoints::home().theta_rad).abs() < 1e-12);
        assert!(ArmJoints::reaching(&Point3::origin()).is_none());
        assert!(ArmJoints::reaching(&Point3::new(f64::NAN, 0.0, 1.0)).is_none());
    }
}
