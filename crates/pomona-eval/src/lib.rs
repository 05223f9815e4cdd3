//! # pomona-eval
//!
//! One trustworthy implementation of how Pomona scores a detector, so results are comparable
//! across methods and with the seed papers:
//!
//! * [`match_frame`] — per frame, detections in decreasing score order are matched greedily to the
//!   nearest not-yet-matched truth fruit within a 3D centre tolerance (seed 000: 50 mm); truth
//!   with only a 2D box is matched by the detection's projected centre; truth below a visibility
//!   threshold is *ignored* (neither rewarded nor penalised);
//! * [`PrCurve`] — precision/recall over score thresholds, PASCAL VOC 11-point interpolated AP
//!   (seed 000's definition) and all-point AP;
//! * [`evaluate`] — the whole report for a set of frames ([`EvalReport`], JSON with stable keys and
//!   a Markdown summary). It takes frames already in memory, so an experiment can call it once per
//!   train/test split; [`load_detections`] reads a detection folder against a dataset;
//! * [`SplitSummary`] — mean ± sd of the figures over repeated splits and the average curve;
//! * [`write_pr_plot`] — the precision-recall curve as a PNG, rendered in pure Rust (font shipped
//!   as bytes; no system fonts needed).

mod detection_dir;
mod error;
mod eval_config;
mod evaluation;
mod frame_matching;
#[doc(hidden)]
pub mod fuzzing;
mod pr_curve;
mod pr_plot;
mod report;
mod split_summary;

pub use detection_dir::{
    detection_file_frame, failures_file, load_detections, DetectionSet, FAILURES_FILE,
};
pub use error::EvalError;
pub use eval_config::EvalConfig;
pub use evaluation::{evaluate, FrameInput};
pub use frame_matching::{match_frame, ranking_values, DetectionOutcome, FrameMatch, TruthStatus};
pub use pr_curve::{PrCurve, PrPoint};
pub use pr_plot::write_pr_plot;
pub use report::{
    CenterError, DiameterError, EvalReport, FrameReport, MissedFruit, ScoreAndConfidence,
};
pub use split_summary::{MeanSd, SplitSummary};
