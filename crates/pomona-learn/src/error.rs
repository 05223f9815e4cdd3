//! Errors of training, prediction and model files. Model-file errors name the file, so a user
//! with a folder of detectors knows which one is stale.

use std::path::PathBuf;

/// Why data, parameters or a model were rejected.
#[derive(Debug, thiserror::Error)]
pub enum LearnError {
    /// A parameter is out of its valid range.
    #[error("invalid parameter `{name}` = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// What it must satisfy.
        reason: &'static str,
    },
    /// The sample matrix is malformed (length not a multiple of the feature count, no features).
    #[error("invalid samples: {0}")]
    InvalidSamples(String),
    /// A feature value is NaN or infinite.
    #[error("sample {row}, feature {feature} is not finite ({value})")]
    NonFiniteFeature {
        /// Row index.
        row: usize,
        /// Feature index.
        feature: usize,
        /// The value.
        value: f64,
    },
    /// Labels and samples disagree in number.
    #[error("{samples} samples but {labels} labels")]
    LabelCount {
        /// Number of samples.
        samples: usize,
        /// Number of labels.
        labels: usize,
    },
    /// Training needs both classes (and cross-validation needs each class in every fold).
    #[error(
        "training data needs both classes: {positives} positive and {negatives} negative samples"
    )]
    OneClass {
        /// Positive samples.
        positives: usize,
        /// Negative samples.
        negatives: usize,
    },
    /// Samples given to a model have a different number of features than it was trained on.
    #[error("model expects {expected} features, samples have {found}")]
    FeatureCount {
        /// Features the model was trained on.
        expected: usize,
        /// Features given.
        found: usize,
    },
    /// Probabilities were asked of a model trained without them.
    #[error("the model was trained without probability estimates")]
    NoProbability,
    /// A model's arrays are inconsistent (a hand-edited or corrupted model file).
    #[error("inconsistent model: {0}")]
    InconsistentModel(String),
}

/// Why a model file could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum ModelFileError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The model file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The file could not be written (the error names the file).
    #[error(transparent)]
    Write(#[from] pomona_io::DatasetError),
    /// The file is not JSON, or a field has the wrong type.
    #[error("{path}: invalid model JSON: {source}")]
    Json {
        /// The model file.
        path: PathBuf,
        /// The parser's explanation.
        source: serde_json::Error,
    },
    /// The file is JSON but not a Pomona model (`format` is missing or different).
    #[error("{path}: not a Pomona model file (format is {found:?}, expected \"pomona-model\")")]
    NotAModel {
        /// The file.
        path: PathBuf,
        /// The `format` value found, if any.
        found: Option<String>,
    },
    /// The file was written by a format version this build cannot read.
    #[error("{path}: model format version {found} is not supported (this build reads version {supported}); retrain or convert the model")]
    Version {
        /// The file.
        path: PathBuf,
        /// Version in the file.
        found: u64,
        /// Version this build reads.
        supported: u32,
    },
    /// The model was trained for another pipeline.
    #[error("{path}: model was trained for pipeline `{found}`, not `{expected}`")]
    Pipeline {
        /// The file.
        path: PathBuf,
        /// Pipeline in the file.
        found: String,
        /// Pipeline that tried to load it.
        expected: String,
    },
    /// The model's contents are inconsistent.
    #[error("{path}: {source}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        source: LearnError,
    },
}
