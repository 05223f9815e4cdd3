//! Errors of the arm model and planners.

use thiserror::Error;

/// What can go wrong building or solving a planning problem.
#[derive(Debug, Error)]
pub enum ArmError {
    /// A target's position is not finite.
    #[error("target `{id}`: center_m must be three finite numbers")]
    NonFiniteTarget {
        /// The target's id.
        id: String,
    },
    /// Two targets share an id.
    #[error("target id `{id}` appears more than once")]
    DuplicateId {
        /// The repeated id.
        id: String,
    },
    /// A model parameter is out of range.
    #[error("invalid parameter {name} = {value}: {reason}")]
    InvalidParameter {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// The exact planner was given more reachable targets than it can enumerate.
    #[error("the exact planner handles at most {max} reachable targets, got {got}")]
    TooManyForExact {
        /// Reachable targets in the problem.
        got: usize,
        /// The limit.
        max: usize,
    },
    /// Two pixels do not locate a point in front of both views of the stereo rig.
    #[error(
        "stereo ({method}): pixels {primary:?} (primary view) and {stereo:?} (stereo view) do not \
         locate a point in front of both views"
    )]
    NoStereoPoint {
        /// The method: `paper` (Eq. 18) or `triangulate`.
        method: &'static str,
        /// The pixel in the primary view.
        primary: [f64; 2],
        /// The pixel in the stereo view.
        stereo: [f64; 2],
    },
}
