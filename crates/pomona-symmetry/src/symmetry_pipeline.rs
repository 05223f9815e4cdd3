//! The `symmetry` pipeline (seed 000, with seed 003's symmetry frame): highlight pruning, 3D
//! sliding box, best reflection-symmetry plane per box, normal histograms in the plane's frame,
//! RBF C-SVC, 3D NMS, then each detection's centre refined off the box grid (see
//! [`crate::CentreRefinement`]). The detector itself is the shared [`crate::BoxDetector`]; training is
//! described in `training.rs`.

use crate::box_pipeline::box_pipeline;
use crate::{FrameKind, StageParams};

/// Seed 000's detector: highlight pruning, symmetry frame, normal histograms, SVM, 3D NMS.
/// Set `params.frame = FrameKind::Fixed` (or use [`SymmetryPipeline::fixed`]) for the
/// "without symmetry" ablation and `params.highlight.enabled = false` for "without pruning".
#[derive(Debug, Clone, PartialEq)]
pub struct SymmetryPipeline {
    /// Stage parameters (stored in the model).
    pub params: StageParams,
}

impl Default for SymmetryPipeline {
    fn default() -> Self {
        Self {
            params: StageParams::symmetry(),
        }
    }
}

impl SymmetryPipeline {
    /// The pipeline with the given parameters.
    pub fn with_params(params: StageParams) -> Self {
        Self { params }
    }

    /// The ablation without symmetry: a fixed frame instead of the symmetry plane.
    pub fn fixed() -> Self {
        let mut params = StageParams::symmetry();
        params.frame = FrameKind::Fixed;
        Self { params }
    }
}

/// Pipeline name of [`SymmetryPipeline`].
pub const SYMMETRY: &str = "symmetry";

box_pipeline!(
    SymmetryPipeline,
    SYMMETRY,
    "../models/symmetry.json",
    "`models/symmetry.json`, trained by `examples/train_symmetry_defaults.rs` (synthetic Kinect v2 frames of mixed fruit, `tof` noise, dataset seed 1000)."
);
