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
//! Eq. 10 windows of [`MatchingWindows`]) and located by Eq. 18 or by triangulation. Beyond
//! the seed, [`DisparityRefinement`] refines a matched pair's stereo-view centre to sub-pixel
//! by finding the primary view's patch of the fruit in the stereo image (NCC over a sphere
//! sweep), since the two circle centres' independent errors dominate the depth error, and
//! [`PairEvidence`] can give the relaxation more evidence than disparity (the same sweep's NCC of
//! every candidate pair, and the agreement of the two radii), as a floor or a cost.
//! [`LeftoverPairing`] then pairs circles the relaxation left unpaired where the primary
//! patch, swept along its whole ray, lands on an unclaimed stereo circle.
//!
//! Seeing and reaching (§4.2): [`ArmSimulation`] is the robot in numbers — the camera on the
//! arm takes two shots rotated ±β about the hub, a target projects to pixel coordinates in both,
//! and the encoder readings that reach it carry hidden [`CalibrationErrors`] (encoder offsets,
//! camera mounting, lens distortion). [`JointNetwork`] is the seed's 4-8-3 network mapping the
//! two image positions straight to encoder readings (Eq. 19), trained on a regular grid
//! ([`train_joint_network`]) and stored in an [`ArmModelFile`]; [`EndPositionError`] measures
//! how far the true robot's end lands from the target, beside [`NominalMapping`] (Eq. 18 +
//! exact kinematics of the nominal model).
//!
//! The split into files follows the concepts: joints and limits (geometry of one arm), motion
//! (time), the cell (two arms), the problem and its plans, the two planners; the simulated robot,
//! its calibration errors, the network, its training, its file, and the end-position error.

mod arm_joints;
mod arm_limits;
mod arm_model_file;
mod arm_simulation;
mod calibration_errors;
mod disparity_refinement;
mod end_position_error;
mod error;
mod exact_planner;
mod heuristic_planner;
mod joint_network;
mod leftover_pairing;
mod matching_windows;
mod motion_model;
mod network_training;
mod nominal_mapping;
mod pair_evidence;
mod plan_problem;
mod random_targets;
mod rotated_stereo;
mod stereo_matching;
#[cfg(test)]
mod test_scenes;
mod two_arm_cell;

pub use arm_joints::ArmJoints;
pub use arm_limits::ArmLimits;
pub use arm_model_file::{ArmModelFile, ARM_MODEL_FORMAT, ARM_MODEL_VERSION};
pub use arm_simulation::{ArmRig, ArmSample, ArmSimulation, Shot, ShotPixels};
pub use calibration_errors::{CalibrationErrors, CalibrationMagnitudes};
pub use disparity_refinement::{
    DisparityRefinement, FallbackReason, RefinementOutcome, MIN_CHROMA_SUM,
};
pub use end_position_error::EndPositionError;
pub use error::ArmError;
pub use exact_planner::{plan_exact, MAX_EXACT_TARGETS};
pub use heuristic_planner::plan_heuristic;
pub use joint_network::{JointNetwork, LinearScaling, NETWORK_INPUTS, NETWORK_OUTPUTS};
pub use leftover_pairing::LeftoverPairing;
pub use matching_windows::{MatchingWindows, WORKING_VOLUME_GRID_PX};
pub use motion_model::MotionModel;
pub use network_training::{train_joint_network, NetworkTraining, TrainingReport};
pub use nominal_mapping::NominalMapping;
pub use pair_evidence::{BetterElsewhere, EvidenceOutcome, PairEvidence, PairScore};
pub use plan_problem::{Arm, PickPlan, PlanFile, PlanProblem, Target, TargetList};
pub use random_targets::random_targets;
pub use rotated_stereo::RotatedStereo;
pub use stereo_matching::{
    match_centres, DisparityMatrix, RelaxationParams, RelaxationStop, StereoMatching, StereoPair,
};
pub use two_arm_cell::TwoArmCell;
