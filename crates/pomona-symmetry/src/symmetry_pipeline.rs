//! The `symmetry` pipeline (seed 000, with seed 003's symmetry frame): highlight pruning, 3D
//! sliding box, best reflection-symmetry plane per box, normal histograms in the plane's frame,
//! RBF C-SVC, 3D NMS, then each detection's centre refined off the box grid (see
//! [`crate::CentreRefinement`]). The detector itself is the shared [`BoxDetector`]; training is
//! described in `training.rs`.

use pomona_learn::ModelFile;
use pomona_pipeline::{
    params_from_json, params_to_json, Detector, FrameSource, Pipeline, PipelineError, TrainOptions,
};

use crate::training::train;
use crate::{BoxDetector, FrameKind, StageParams};

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

impl Pipeline for SymmetryPipeline {
    fn name(&self) -> &'static str {
        SYMMETRY
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

    /// `models/symmetry.json`, trained by `examples/train_symmetry_defaults.rs` (synthetic
    /// Kinect v2 frames of mixed fruit, `tof` noise, dataset seed 1000).
    fn default_model(&self) -> Option<&'static str> {
        Some(include_str!("../models/symmetry.json")).filter(|s| !s.trim().is_empty())
    }

    fn train(
        &self,
        frames: &dyn FrameSource,
        options: &TrainOptions,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<ModelFile, PipelineError> {
        train(SYMMETRY, &self.params, frames, options, progress)
    }

    fn load(&self, model: &ModelFile) -> Result<Box<dyn Detector>, PipelineError> {
        Ok(Box::new(BoxDetector::from_model(SYMMETRY, model)?))
    }
}
