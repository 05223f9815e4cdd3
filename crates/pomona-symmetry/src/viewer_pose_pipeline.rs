//! The `viewer-pose` pipeline (seed 001): the same box scan as `symmetry` with a reference frame
//! built from the box centre and the viewing direction, seed 001's normal-angle histograms, and
//! mean-shift merging. The detector is the shared [`BoxDetector`].

use pomona_learn::ModelFile;
use pomona_pipeline::{
    params_from_json, params_to_json, Detector, FrameSource, Pipeline, PipelineError, TrainOptions,
};

use crate::training::train;
use crate::{BoxDetector, StageParams};

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

impl Pipeline for ViewerPosePipeline {
    fn name(&self) -> &'static str {
        VIEWER_POSE
    }

    fn train_params(&self) -> serde_json::Value {
        params_to_json(&self.params)
    }

    fn with_train_params(
        &self,
        params: serde_json::Value,
    ) -> Result<Box<dyn Pipeline>, PipelineError> {
        Ok(Box::new(Self {
            params: params_from_json(params)?,
        }))
    }

    fn needs_color(&self) -> bool {
        false
    }

    fn train(
        &self,
        frames: &dyn FrameSource,
        options: &TrainOptions,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<ModelFile, PipelineError> {
        train(VIEWER_POSE, &self.params, frames, options, progress)
    }

    /// `models/viewer-pose.json`, trained by `examples/train_symmetry_defaults.rs` (same frames
    /// as the `symmetry` default).
    fn default_model(&self) -> Option<&'static str> {
        Some(include_str!("../models/viewer-pose.json")).filter(|s| !s.trim().is_empty())
    }

    fn load(&self, model: &ModelFile) -> Result<Box<dyn Detector>, PipelineError> {
        Ok(Box::new(BoxDetector::from_model(VIEWER_POSE, model)?))
    }
}
