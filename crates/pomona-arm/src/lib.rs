//! The harvesting arm of seed 004 §4 in numbers, and planning the picks of two such arms.
//!
//! Each arm is a two-angle arm with a telescopic link: in its hub frame (x right, y down,
//! z forward, metres) a target `p` is reached at azimuth α = atan2(x, z), elevation
//! θ = acos(−y / ‖p‖) (90° = level) and extension r = ‖p‖ ([`ArmJoints`]), within joint limits
//! ([`ArmLimits`]). Moves take the slowest joint's time at fixed joint rates, and each pick a
//! fixed time ([`MotionModel`]). Two arms side by side ([`TwoArmCell`]) share the fruit both can
//! reach.
//!
//! Planning ([`PlanProblem`]) gives each reachable target to one arm and orders each arm's
//! picks so that the later of the two arms finishes as early as possible (the makespan). The
//! paper states its objective as total time plus load imbalance, T_A + T_B + |T_A − T_B|, which
//! is exactly twice max(T_A, T_B), so the two agree. [`plan_heuristic`] (cheapest insertion,
//! then 2-opt and moves of targets between arms) is what the CLI runs; [`plan_exact`]
//! (every split of the shared targets × Held–Karp per arm) is the reference for small problems.
//!
//! Each arm's camera takes two shots turned by ±β about the hub ([`RotatedStereo`]): fruit
//! centres are paired between them by the seed's relaxation ([`match_centres`] within the
//! Eq. 10 windows of [`MatchingWindows`]) and located by Eq. 18 or by triangulation.
//!
//! The split into files follows the concepts: joints and limits (geometry of one arm), motion
//! (time), the cell (two arms), the problem and its plans, and the two planners.

mod arm_joints;
mod arm_limits;
mod error;
mod exact_planner;
mod heuristic_planner;
mod matching_windows;
mod motion_model;
mod plan_problem;
mod random_targets;
mod rotated_stereo;
mod stereo_matching;
mod two_arm_cell;

pub use arm_joints::ArmJoints;
pub use arm_limits::ArmLimits;
pub use error::ArmError;
pub use exact_planner::{plan_exact, MAX_EXACT_TARGETS};
pub use heuristic_planner::plan_heuristic;
pub use matching_windows::{MatchingWindows, WORKING_VOLUME_GRID_PX};
pub use motion_model::MotionModel;
pub use plan_problem::{Arm, PickPlan, PlanFile, PlanProblem, Target, TargetList};
pub use random_targets::random_targets;
pub use rotated_stereo::RotatedStereo;
pub use stereo_matching::{
    match_centres, DisparityMatrix, RelaxationParams, RelaxationStop, StereoMatching, StereoPair,
};
pub use two_arm_cell::TwoArmCell;
