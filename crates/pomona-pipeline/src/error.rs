//! Errors a detector can raise while training, loading or detecting.

use pomona_io::DatasetError;
use pomona_learn::{LearnError, ModelFileError};

/// Why a pipeline could not train, load or detect.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// Reading training or test data failed.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// A model file is unreadable or made for another pipeline or version.
    #[error(transparent)]
    ModelFile(#[from] ModelFileError),
    /// Training the classifier failed.
    #[error("training the classifier: {0}")]
    Learn(#[from] LearnError),
    /// The pipeline needs colour and the frame has none.
    #[error("pipeline `{pipeline}` needs colour images, and the frame has none")]
    MissingColor {
        /// Pipeline name.
        pipeline: &'static str,
    },
    /// A stage parameter is out of range (named, with the reason).
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter {
        /// Parameter name as in the model's `stage_params`.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// Training data gave nothing to learn from (for example no positive candidates).
    #[error("cannot train `{pipeline}`: {reason}")]
    NotEnoughTrainingData {
        /// Pipeline name.
        pipeline: &'static str,
        /// What was missing.
        reason: String,
    },
    /// Scoring detections against truth failed.
    #[error("evaluating detections: {0}")]
    Evaluation(#[from] pomona_eval::EvalError),
    /// The model's stage parameters could not be read back.
    #[error("model stage parameters: {0}")]
    StageParams(String),
}
