//! # pomona
//!
//! Fruit detection in 3D for harvesting robots, as a library: load a detector (built-in or
//! trained with `pomona train`), give it an RGB-D frame, get each fruit's centre in the camera
//! frame (metres), its diameter and, where the method estimates them, its axis and a calibrated
//! confidence.
//!
//! This crate is the facade over the workspace's layers (data model, file formats, detectors):
//! one error type, the pipeline registry and the choice of built-in model live here, so a robot
//! program depends on `pomona` alone. The `pomona` command-line tool is built on it.
//!
//! ## Detect on a dataset frame
//! ```no_run
//! # fn main() -> Result<(), pomona::Error> {
//! let dataset = pomona::Dataset::open("orchard-run")?;
//! let detector = pomona::Detector::builtin("shape-fit")?;
//! for stem in dataset.frames() {
//!     let frame = dataset.load_frame(stem)?;
//!     for fruit in detector.detect(&frame)?.iter().filter(|d| detector.keeps(d)) {
//!         println!("{stem}: {} m, {:?} m across", fruit.center_m, fruit.diameter_m);
//!     }
//! }
//! # Ok(())
//! # }
//! ```
//! `examples/detect_frame.rs` is the same as a program.
//!
//! ## Detect on your own buffers
//! Frames are built from a camera and images in memory, for example straight from a driver:
//! ```
//! # fn main() -> Result<(), pomona::Error> {
//! use pomona::{ColorImage, DepthImage, PinholeCamera, RgbdFrame};
//!
//! let (w, h) = (64, 48);
//! let camera = PinholeCamera::new(w, h, 60.0, 60.0, 31.5, 23.5)?;
//! let depth = DepthImage::from_meters(w, h, vec![0.8; (w * h) as usize])?;
//! let color = ColorImage::from_rgb(w, h, vec![90; (3 * w * h) as usize])?;
//! let frame = RgbdFrame::new(camera, depth, Some(color))?;
//!
//! let detector = pomona::Detector::builtin("symmetry")?;
//! let (detections, timings) = detector.detect_with_timings(&frame)?;
//! assert!(detections.is_empty(), "a flat grey wall holds no fruit");
//! assert!(!timings.table().is_empty());
//! # Ok(())
//! # }
//! ```
//!
//! ## Writing the detection files of a run
//! A batch runner (`pomona detect`, the Python package's Dask runner) writes one detection file
//! per frame ([`Detector::frame_record`]) into a folder prepared by [`prepare_detection_folder`]
//! (which refuses another run's files, removes temporaries a killed run left, and returns the
//! frames already done, to skip on resume) and lists failed frames with [`write_failures`]; so
//! every front end accepts, refuses and resumes the same folders.
//!
//! ## Follow one fruit while the arm closes in
//! [`Tracker`] is seed 004's approach tracker (§3.3) with the `color-contour` model's colour
//! table: [`Tracker::start`] from the chosen fruit's circle (a detection's
//! [`Detection::image_circle`]), then [`Track::update`] every frame: a few tenths of a
//! millisecond on average, as `pomona track` measures it on approach sequences (which it also
//! runs on your own frames). `examples/track_fruit.rs` detects once and follows the chosen fruit
//! through a dataset.
//!
//! ## Fruit in 3D from two colour shots
//! [`StereoLocator`] is seed 004's stereo from a rotating camera (§4.1–4.2): the `color-contour`
//! detector on both shots of a [`RotatedStereo`] rig, matched and located with the defaults of
//! `pomona stereo` ([`StereoSettings`]), each located fruit a [`Detection`] in the primary
//! camera frame; [`StereoFrame`] also says which circles were paired and how.
//! `examples/locate_stereo.rs` locates the fruit of a `pomona synth --stereo` dataset.
//!
//! ## What a detection holds
//! See [`Detection`]: `center_m` (camera frame: x right, y down, z forward), `score` (raw
//! classifier value), `confidence` (calibrated, comparable across models), `diameter_m`, and
//! pipeline-specific fields. [`Detector::detect`] applies no threshold; [`Detector::keeps`]
//! applies the model's operating confidence, as `pomona detect` does by default.

mod detection_folder;
mod detector;
mod error;
mod failures_list;
mod frame_record;
mod model_choice;
mod model_info;
mod param_override;
mod registry;
mod stereo_locator;
mod tracker;

pub use detection_folder::{prepare_detection_folder, RunIdentity};
pub use detector::{Detector, DetectorBuilder};
pub use error::Error;
pub use failures_list::{write_failures, FailedFrame};
pub use frame_record::KeepRule;
pub use model_choice::load_model;
pub use model_info::{ModelInfo, ModelSource};
pub use param_override::{apply_overrides, overrides_to_json, settable_keys, ParamOverride};
pub use registry::{find_pipeline, pipeline, pipeline_names, pipelines};
pub use stereo_locator::{LocatedPair, StereoFrame, StereoLocator, StereoMethod, StereoSettings};
pub use tracker::{Track, Tracker, TrackerBuilder};

pub use pomona_arm::{
    BetterElsewhere, DisparityRefinement, EvidenceOutcome, LeftoverPairing, MatchingWindows,
    PairEvidence, PairScore, RefinementOutcome, RotatedStereo,
};
pub use pomona_colorcontour::{TrackEstimate, TrackParams, TrackStatus};
pub use pomona_core::{
    nalgebra, ColorImage, DepthImage, Detection, FrameDetections, FrameTruth, FruitTruth,
    ImageCircle, PinholeCamera, PixelBox, RgbdFrame,
};
pub use pomona_io::Dataset;
pub use pomona_learn::ModelFile;
pub use pomona_pipeline::{Pipeline, StageTimings};
