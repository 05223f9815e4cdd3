//! The one error type of the facade: everything that can go wrong between "I have a model name
//! or file" and "here are the detections" (or a tracked fruit), and in the output folder a
//! detection run writes them to, each variant naming the file, model or frame at fault.

use std::path::PathBuf;

use pomona_io::DatasetError;
use pomona_learn::ModelFileError;
use pomona_pipeline::PipelineError;

/// Why a detector could not be built or could not detect, or a detection run's output folder
/// cannot be used. Every message names the pipeline, model file, parameter, dataset or output
/// file at fault.
///
/// ```
/// match pomona::Detector::builtin("apple-finder") {
///     Err(pomona::Error::UnknownPipeline { known, .. }) => assert!(known.contains("shape-fit")),
///     other => panic!("expected an unknown-pipeline error, got {other:?}"),
/// }
/// ```
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// No pipeline has this name.
    #[error("unknown pipeline `{name}`; known pipelines: {known}")]
    UnknownPipeline {
        /// The name asked for.
        name: String,
        /// The registered names, comma-separated.
        known: String,
    },
    /// The pipeline ships no built-in model, so a model file is needed.
    #[error(
        "pipeline `{pipeline}` has no built-in model yet; train one with \
         `pomona train --pipeline {pipeline} --data DIR --out MODEL` and load that file"
    )]
    NoBuiltInModel {
        /// Pipeline name.
        pipeline: String,
    },
    /// A model file is unreadable, not a model, or made for another pipeline or version.
    #[error(transparent)]
    ModelFile(#[from] ModelFileError),
    /// The model's stage parameters are rejected by its pipeline.
    #[error("cannot build a `{pipeline}` detector from {model}: {source}")]
    Load {
        /// Pipeline name.
        pipeline: String,
        /// Where the model came from (a path or "the built-in model").
        model: String,
        /// The pipeline's reason.
        source: Box<PipelineError>,
    },
    /// A parameter override names a key the model does not have.
    #[error("{owner} has no parameter `{key}`; {known}")]
    UnknownParameter {
        /// The dotted key given.
        key: String,
        /// Whose parameters (for example "the model of `symmetry` (the built-in model)").
        owner: String,
        /// The keys there are.
        known: String,
    },
    /// A parameter override has another JSON type than the value it replaces.
    #[error("parameter `{key}` of {owner} expects {expected} (currently {current}), got {got}")]
    ParameterType {
        /// The dotted key given.
        key: String,
        /// Whose parameters.
        owner: String,
        /// The JSON type expected.
        expected: &'static str,
        /// The current value.
        current: String,
        /// The value given.
        got: String,
    },
    /// Detection failed on a frame (for example a colour pipeline on a frame without colour).
    #[error("`{pipeline}` detection failed: {source}")]
    Detect {
        /// Pipeline name.
        pipeline: &'static str,
        /// The stage's reason.
        source: Box<PipelineError>,
    },
    /// A tracker's parameters or start circle are refused.
    #[error("cannot track with {model}: {source}")]
    Track {
        /// Where the tracker's model came from (a path or "the built-in model").
        model: String,
        /// The tracker's reason.
        source: Box<PipelineError>,
    },
    /// A confidence threshold that cannot be applied.
    #[error("cannot keep detections at confidence {value}: {reason}")]
    MinConfidence {
        /// The threshold asked for.
        value: f64,
        /// Why not (out of range, or the model has no calibration).
        reason: String,
    },
    /// [`crate::StereoLocator`] needs a detector that gives image circles (`color-contour`).
    #[error(
        "stereo needs a `color-contour` detector (its image circles are matched), not `{pipeline}`"
    )]
    StereoDetector {
        /// The detector's pipeline.
        pipeline: &'static str,
    },
    /// Stereo matching or locating refused its settings or images ([`crate::StereoLocator`]).
    #[error("stereo: {0}")]
    Stereo(#[from] pomona_arm::ArmError),
    /// A frame built in memory is inconsistent (image sizes, camera parameters).
    #[error("invalid frame: {0}")]
    Frame(#[from] pomona_core::CoreError),
    /// A dataset or one of its frames could not be read, or an output file written.
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// A detection run's output folder, or a file in it, cannot be created, listed, read or
    /// removed.
    #[error("cannot {action} {}: {source}", path.display())]
    OutputIo {
        /// What was tried, e.g. "create output folder" or "remove stale".
        action: &'static str,
        /// The folder or file.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// A `<frame>.json` in a detection run's output folder is not a detection file, so the run
    /// will not overwrite it.
    #[error(
        "{} is not a detection file; refusing to overwrite it (move it or choose another \
         output folder): {source}",
        path.display()
    )]
    NotDetectionFile {
        /// The file.
        path: PathBuf,
        /// Why it does not parse as one.
        source: serde_json::Error,
    },
    /// A detection run's output folder holds a detection file made by another pipeline, model
    /// or confidence threshold, so the two runs would mix.
    #[error(
        "{} holds detections made with {difference}; refusing to mix two runs in one folder \
         (choose another output folder or remove the old files)",
        path.display()
    )]
    ForeignDetections {
        /// The file.
        path: PathBuf,
        /// What differs, e.g. "pipeline `symmetry` (this run: `shape-fit`)".
        difference: String,
    },
}
