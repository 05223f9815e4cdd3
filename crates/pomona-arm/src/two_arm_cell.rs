//! Two arms side by side (seed 004's robot has two): where arm B's hub is in arm A's hub frame,
//! and which arm reaches a target.

use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

use crate::{ArmJoints, ArmLimits};

/// The cell: arm B's hub at `b_hub_in_a` with the same orientation as arm A; both arms share
/// the same limits.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TwoArmCell {
    /// Arm B's hub in arm A's hub frame, metres; default (0.6, 0.02, 0).
    pub b_hub_in_a: Vector3<f64>,
    /// Joint limits of each arm.
    pub limits: ArmLimits,
}

impl Default for TwoArmCell {
    fn default() -> Self {
        Self {
            b_hub_in_a: Vector3::new(0.6, 0.02, 0.0),
            limits: ArmLimits::default(),
        }
    }
}

impl TwoArmCell {
    /// The joints with which arm A and arm B reach `point_in_a` (a point in arm A's hub frame),
    /// each `None` when that arm cannot reach it.
    pub fn reach(&self, point_in_a: &Point3<f64>) -> [Option<ArmJoints>; 2] {
        let point_in_b = point_in_a - self.b_hub_in_a;
        [*point_in_a, point_in_b].map(|p| ArmJoints::reaching(&p).filter(|q| self.limits.allows(q)))
    }
}
