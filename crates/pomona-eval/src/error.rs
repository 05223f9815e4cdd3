//! Errors of evaluation: every variant names the file or folder at fault.

use std::path::PathBuf;

/// Why an evaluation could not be run.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// The dataset (camera, frames, truth) could not be read.
    #[error(transparent)]
    Dataset(#[from] pomona_io::DatasetError),
    /// A folder or file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A detection file is not valid detection JSON.
    #[error("{path}: invalid detection JSON: {source}")]
    DetectionJson {
        /// The detection file.
        path: PathBuf,
        /// The parser's explanation.
        source: serde_json::Error,
    },
    /// A detection file names a frame the dataset does not have.
    #[error("{path}: frame `{frame}` is not in the dataset")]
    UnknownFrame {
        /// The detection file.
        path: PathBuf,
        /// The frame it is for.
        frame: String,
    },
    /// A detection file's `frame` field disagrees with its file name.
    #[error("{path}: file is for frame `{stem}` but says \"frame\": \"{frame}\"")]
    FrameMismatch {
        /// The detection file.
        path: PathBuf,
        /// Its file stem.
        stem: String,
        /// Its `frame` field.
        frame: String,
    },
    /// A detection has a non-finite score or centre.
    #[error("{path}: detection {index} has a non-finite score or centre")]
    NonFiniteDetection {
        /// The detection file.
        path: PathBuf,
        /// Index of the detection in the file.
        index: usize,
    },
    /// A confidence threshold was asked for detections that have no confidence.
    #[error(
        "frame `{frame}`: a detection has no calibrated confidence (its model has no score \
         calibration), so the operating point cannot be a confidence threshold; use a score \
         threshold instead"
    )]
    MissingConfidence {
        /// Frame whose detections lack confidences.
        frame: String,
    },
    /// An evaluation parameter is out of range.
    #[error("invalid evaluation parameter `{name}` = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// What it must satisfy.
        reason: &'static str,
    },
    /// The PR plot could not be drawn.
    #[error("{path}: cannot draw plot: {message}")]
    Plot {
        /// The PNG being written.
        path: PathBuf,
        /// The drawing library's explanation.
        message: String,
    },
}
