//! Errors of the arm model and planners.

use std::path::PathBuf;

use thiserror::Error;

/// What can go wrong building or solving a planning problem, simulating the arm, or reading and
/// writing an arm model file.
#[derive(Debug, Error)]
pub enum ArmError {
    /// A target's position is not finite.
    #[error("target `{id}`: center_m must be three finite numbers")]
    NonFiniteTarget {
        /// The target's id.
        id: String,
    },
    /// Two targets share an id.
    #[error("target id `{id}` appears more than once")]
    DuplicateId {
        /// The repeated id.
        id: String,
    },
    /// A model parameter is out of range.
    #[error("invalid parameter {name} = {value}: {reason}")]
    InvalidParameter {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// The exact planner was given more reachable targets than it can enumerate.
    #[error("the exact planner handles at most {max} reachable targets, got {got}")]
    TooManyForExact {
        /// Reachable targets in the problem.
        got: usize,
        /// The limit.
        max: usize,
    },
    /// Two pixels do not locate a point in front of both views of the stereo rig.
    #[error(
        "stereo ({method}): pixels {primary:?} (primary view) and {stereo:?} (stereo view) do not \
         locate a point in front of both views"
    )]
    NoStereoPoint {
        /// The method: `paper` (Eq. 18) or `triangulate`.
        method: &'static str,
        /// The pixel in the primary view.
        primary: [f64; 2],
        /// The pixel in the stereo view.
        stereo: [f64; 2],
    },
    /// An image handed to the stereo refinement is not the size of the rig's camera.
    #[error("{view} view image is {found:?} pixels, the rig camera {expected:?}")]
    ImageSize {
        /// `primary` or `stereo`.
        view: &'static str,
        /// The image's width and height.
        found: [u32; 2],
        /// The camera's width and height.
        expected: [u32; 2],
    },
    /// An arm model file could not be read.
    #[error("{path}: cannot read the arm model: {source}")]
    ModelRead {
        /// The model file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// An arm model file is not valid JSON or has a wrong or missing field.
    #[error("{path}: not an arm model file: {source}")]
    ModelJson {
        /// The model file.
        path: PathBuf,
        /// The parser's explanation, with line and column.
        source: serde_json::Error,
    },
    /// An arm model file has another `format` or an unsupported `version`.
    #[error("{path}: expected format \"{expected}\" version {supported}, found {found}")]
    ModelVersion {
        /// The model file.
        path: PathBuf,
        /// What the file declares (format and version).
        found: String,
        /// The format this build reads.
        expected: &'static str,
        /// The version this build reads.
        supported: u32,
    },
    /// An arm model file parsed but holds impossible values.
    #[error("{path}: invalid arm model: {source}")]
    ModelInvalid {
        /// The model file.
        path: PathBuf,
        /// What is wrong.
        source: Box<ArmError>,
    },
    /// An arm model file could not be written.
    #[error("cannot write the arm model: {source}")]
    ModelWrite {
        /// The writer's error (it names the file).
        source: pomona_io::DatasetError,
    },
}
