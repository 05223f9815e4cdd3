//! # pomona-pipeline
//!
//! The small framework every detector is built on, so that detectors are interchangeable in the
//! CLI, in experiments and in a robot's code:
//!
//! * [`Stage`]: one step of a detector (colour mask, region growing, shape fit, features,
//!   classifier...). A detector holds its stages as trait objects, so a stage can be replaced,
//!   removed or benchmarked alone — the papers call their stages plug-and-play; this makes it so.
//! * [`StageTimings`]: wall time per stage, filled in by [`run_stage`], reported by `--timings`.
//! * [`Detector`]: a trained detector: frame in, detections out.
//! * [`Pipeline`]: a method by name: trains a [`ModelFile`] from labelled frames and loads a
//!   [`Detector`] from one.
//! * [`train_calibrated`] / [`load_detector`]: any pipeline's training with a confidence
//!   calibrated on held-out frames and an operating threshold, and the detector that reports it.
//! * [`detect_and_evaluate`]: a detector run over labelled frames and scored against their truth.
//! * [`FreeSpaceCheck`]: the geometric test any detector with depth can apply to a detection —
//!   the camera must not see through the fruit's centre; [`DoubleCurvatureCheck`]: the seen
//!   surface must bend away from the camera in both directions, as a solid's does and a leaf's
//!   does not; [`DetectionFilter`]: either as a stage over a detector's detections.
//! * [`FrameSource`]: labelled frames for training, loaded lazily from datasets
//!   ([`DatasetFrames`]) or rendered on demand (`SyntheticFrames`, with the `synth` feature).

mod calibration;
mod detection_cues;
mod detection_evaluation;
mod detection_filter;
mod detector;
mod double_curvature;
mod error;
mod frame_source;
mod free_space;
mod stage;
#[cfg(feature = "synth")]
mod synthetic_frames;
mod timings;
mod train_params;
mod untagged_fruit;

pub use calibration::{
    load_detector, recalibrate, train_calibrated, CalibratedDetector, CalibratedTraining,
    CalibrationParams, CUE_CURVATURE_PATCH_RADII,
};
pub use detection_cues::detection_cues;
pub use detection_evaluation::{detect_and_evaluate, DetectionEvaluation};
pub use detection_filter::{DetectionFilter, FruitCheck};
pub use detector::{complete_with_defaults, Detector, Pipeline, TrainOptions};
pub use double_curvature::{DoubleCurvatureCheck, DoubleCurvatureFilter, SeenCurvature};
pub use error::PipelineError;
pub use frame_source::{ChainedFrames, DatasetFrames, FrameSource, LabelledFrame};
pub use free_space::{FreeSpaceCheck, FreeSpaceFilter, SeenSurface};
pub use pomona_learn::ModelFile;
pub use stage::{run_stage, Stage};
#[cfg(feature = "synth")]
pub use synthetic_frames::SyntheticFrames;
pub use timings::StageTimings;
pub use train_params::{params_from_json, params_to_json};
pub use untagged_fruit::{may_have_untagged_fruit, untagged_fruit_circles};
