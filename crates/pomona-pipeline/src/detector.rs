//! A method by name ([`Pipeline`]) and its trained form ([`Detector`]).
//!
//! Both are object-safe so the CLI keeps a list of `Box<dyn Pipeline>` and `pomona train`,
//! `detect` and `experiment` work for every method without knowing any of them.

use pomona_core::{Detection, RgbdFrame};
use pomona_learn::ModelFile;

use crate::{FrameSource, PipelineError, StageTimings};

/// A trained detector.
pub trait Detector: Send + Sync {
    /// Name of the pipeline that made it (written into detection files).
    fn pipeline(&self) -> &'static str;

    /// Finds fruit in one frame; stage times are added to `timings`.
    ///
    /// # Errors
    /// [`PipelineError::MissingColor`] when the method needs colour the frame lacks; stage
    /// errors otherwise.
    fn detect(
        &self,
        frame: &RgbdFrame,
        timings: &mut StageTimings,
    ) -> Result<Vec<Detection>, PipelineError>;

    /// The calibrated confidence at or above which detections are reported by default, when the
    /// model carries a score calibration (see [`crate::CalibratedDetector`]).
    fn operating_confidence(&self) -> Option<f64> {
        None
    }
}

/// Options shared by every pipeline's training.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TrainOptions {
    /// Seed for every random choice (sampling, folds, consensus).
    pub seed: u64,
    /// Cross-validation folds for the classifier's grid search (default 5; seed 002 used 10, see
    /// docs/learning-and-evaluation.md for why the default stays 5).
    pub folds: usize,
    /// Whether to run the full LIBSVM grid search (slow) or a narrower default grid.
    pub full_grid: bool,
}

impl Default for TrainOptions {
    fn default() -> Self {
        Self {
            seed: 0,
            folds: 5,
            full_grid: false,
        }
    }
}

/// A detection method: trains a model and turns a model back into a [`Detector`].
pub trait Pipeline: Send + Sync {
    /// The method's name on the command line and in model files, e.g. `"shape-fit"`.
    fn name(&self) -> &'static str;

    /// Whether frames must have colour.
    fn needs_color(&self) -> bool;

    /// Whether frames must have depth. A method that also works from colour alone (giving
    /// detections placed by a size prior) returns `false` and can run on colour-only datasets.
    fn needs_depth(&self) -> bool {
        true
    }

    /// Trains a model from labelled frames. `progress` is called with (frames done, total).
    ///
    /// # Errors
    /// Data errors, [`PipelineError::NotEnoughTrainingData`], classifier errors.
    fn train(
        &self,
        frames: &dyn FrameSource,
        options: &TrainOptions,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<ModelFile, PipelineError>;

    /// The parameters training would use, as JSON (for `--set key=value` overrides); `Null` when
    /// the pipeline has none.
    fn train_params(&self) -> serde_json::Value {
        serde_json::Value::Null
    }

    /// The same pipeline with other training parameters (the JSON of
    /// [`Pipeline::train_params`], edited).
    ///
    /// # Errors
    /// [`PipelineError::InvalidParameter`] when the JSON does not describe valid parameters or
    /// the pipeline has none.
    fn with_train_params(
        &self,
        params: serde_json::Value,
    ) -> Result<Box<dyn Pipeline>, PipelineError> {
        let _ = params;
        Err(PipelineError::InvalidParameter {
            name: "--set".into(),
            reason: format!("`{}` has no settable training parameters", self.name()),
        })
    }

    /// The model compiled into the binary (JSON text of a [`ModelFile`]), if the project ships
    /// one for this pipeline; `pomona detect` without `--model` uses it.
    fn default_model(&self) -> Option<&'static str> {
        None
    }

    /// A built-in model for frames without colour, for pipelines whose default model uses
    /// colour; `pomona detect` without `--model` picks it for depth-only datasets.
    fn default_depth_only_model(&self) -> Option<&'static str> {
        None
    }

    /// Builds a detector from a model made by [`Pipeline::train`].
    ///
    /// # Errors
    /// [`PipelineError::StageParams`] when the model's stage parameters do not parse or are
    /// invalid.
    fn load(&self, model: &ModelFile) -> Result<Box<dyn Detector>, PipelineError>;

    /// A model's stage parameters with every key this version knows, defaults filled in for
    /// those the model was saved without (parameters added later), so a parameter override can
    /// name any of them. The default keeps them as they are; pipelines with typed parameters
    /// round-trip them with [`complete_with_defaults`].
    ///
    /// # Errors
    /// [`PipelineError::StageParams`] when they do not parse.
    fn complete_stage_params(
        &self,
        stage_params: &serde_json::Value,
    ) -> Result<serde_json::Value, PipelineError> {
        Ok(stage_params.clone())
    }
}

/// `stage_params` parsed as `T` (serde defaults filling missing keys) and written back: the
/// usual [`Pipeline::complete_stage_params`].
///
/// # Errors
/// [`PipelineError::StageParams`] when they do not parse as `T`.
pub fn complete_with_defaults<T: serde::Serialize + serde::de::DeserializeOwned>(
    stage_params: &serde_json::Value,
) -> Result<serde_json::Value, PipelineError> {
    let typed: T = serde_json::from_value(stage_params.clone())
        .map_err(|e| PipelineError::StageParams(e.to_string()))?;
    serde_json::to_value(&typed).map_err(|e| PipelineError::StageParams(e.to_string()))
}
