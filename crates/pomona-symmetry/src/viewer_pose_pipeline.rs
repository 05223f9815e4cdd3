//! The `viewer-pose` pipeline (seed 001): the same box scan as `symmetry` with a reference frame
//! built from the box centre and the viewing direction, seed 001's normal-angle histograms, and
//! mean-shift merging. The detector is the shared [`crate::BoxDetector`].

use crate::box_pipeline::box_pipeline;
use crate::StageParams;

/// Seed 001's detector: viewer-based frame, its normal-angle histograms, SVM, mean shift.
#[derive(Debug, Clone, PartialEq)]
pub struct ViewerPosePipeline {
    /// Stage parameters (stored in the model).
    pub params: StageParams,
}

impl Default for ViewerPosePipeline {
    fn default() -> Self {
        Self {
            params: StageParams::viewer_pose(),
        }
    }
}

impl ViewerPosePipeline {
    /// The pipeline with the given parameters.
    pub fn with_params(params: StageParams) -> Self {
        Self { params }
    }
}

/// Pipeline name of [`ViewerPosePipeline`].
pub const VIEWER_POSE: &str = "viewer-pose";

box_pipeline!(
    ViewerPosePipeline,
    VIEWER_POSE,
    "../models/viewer-pose.json",
    "`models/viewer-pose.json`, trained by `examples/train_symmetry_defaults.rs` (same frames as the `symmetry` default)."
);
