//! # pomona-symmetry
//!
//! Shape-only fruit detectors for RGB-D frames, after seeds 000 (colour-agnostic shape-based
//! detection with highlights and reflection symmetry), 003 (the general symmetry-frame detector)
//! and 001 (viewer-based pose frame):
//!
//! * [`SymmetryPipeline`] (`symmetry`): highlight pruning → 3D sliding box → best reflection
//!   symmetry plane per box → normal histograms in the plane's frame → RBF C-SVC → 3D NMS.
//!   Detections carry the symmetry-plane normal as `symmetry_plane_normal` (perpendicular to
//!   the fruit axis; no fruit axis is estimated).
//! * [`ViewerPosePipeline`] (`viewer-pose`): the same box scan with a frame built from the box
//!   centre and the viewing direction, seed 001's histograms, and mean-shift merging.
//!
//! The reference frame is a swappable stage ([`ReferenceFrame`]: [`SymmetryFrame`],
//! [`FixedFrame`], [`ViewerFrame`]); the fixed frame is seed 000's "without symmetry" ablation.
//! Every stage implements [`pomona_pipeline::Stage`] and is timed per frame. All parameters live
//! in [`StageParams`], stored in the model file.
//!
//! Both pipelines then refine each merged detection's centre off the box grid with a sphere fit
//! and report its diameter when the fit is believable ([`CentreRefinement`], ours).
//!
//! One concept per file: the two pipelines (`symmetry_pipeline.rs`, `viewer_pose_pipeline.rs`),
//! the shared [`Stages`], the trained [`BoxDetector`] and its [`FrameResult`], the `cascade`,
//! `classifier`, `merge` and `refine` stages, `training.rs` and `hard_negative_mining.rs`.
//!
//! Frames without colour run with pruning off and say so ([`PruningState::NoColor`], plus one
//! line on stderr per detector).

mod box_detector;
mod box_pipeline;
mod cascade;
mod centre_refinement;
mod classify;
mod error;
mod frame_result;
mod hard_negative_mining;
mod highlight;
mod mean_shift;
mod merge;
mod nearest;
mod nms;
mod normal_histogram;
mod params;
mod reference_frame;
mod scene_cloud;
mod sliding_box;
mod stages;
mod symmetry_pipeline;
mod symmetry_plane;
mod training;
mod viewer_features;
mod viewer_pose_pipeline;

pub use box_detector::BoxDetector;
pub use centre_refinement::{CentreRefinement, CentreRefinementParams, FittedSphere, RefinedBox};
pub use error::SymmetryError;
pub use frame_result::{FrameResult, PruningState};
pub use highlight::{orientation_map, HighlightDetector, Highlights, PruningMask};
pub use mean_shift::mean_shift;
pub use nearest::PointGrid;
pub use nms::{non_maximum_suppression, ScoredBox};
pub use normal_histogram::{normal_histogram, BinnedHistograms, FeatureStage};
pub use params::{
    CascadeClassifier, CascadeParams, FrameKind, HighlightParams, HistogramParams, MergeKind,
    MergeParams, SlidingBoxParams, StageParams, SymmetryPlaneParams, TrainingParams, WorkingRange,
};
pub use reference_frame::{
    plane_frame, up, FixedFrame, FrameStage, LocalFrame, ReferenceFrame, SymmetryFrame, ViewerFrame,
};
pub use scene_cloud::{NormalStage, PixelNormals, SceneCloud};
pub use sliding_box::{BoxCandidate, BoxPatch, SlidingBox};
pub use stages::Stages;
pub use symmetry_pipeline::{SymmetryPipeline, SYMMETRY};
pub use symmetry_plane::{
    canonical, is_visible, plane_normal, reflect_normal, reflect_point, SymmetryPlane,
    SymmetryPlaneSearch,
};
pub use viewer_features::viewer_features;
pub use viewer_pose_pipeline::{ViewerPosePipeline, VIEWER_POSE};
