//! # pomona-learn
//!
//! The classifier every Pomona detector uses to accept or reject candidate regions: a C-SVC with
//! an RBF kernel that behaves like LIBSVM (the library the seed papers trained with), plus what
//! goes around it in practice:
//!
//! * [`MinMaxScaler`] — per-feature scaling to `[-1, 1]` as LIBSVM's `svm-scale` does, stored with
//!   the model so prediction scales exactly as training did;
//! * [`SvmParams`] → [`SvmParams::check`] → [`ValidSvmParams::fit`] → [`SvmClassifier`] — the
//!   linfa-style "unchecked parameters, validated parameters, fitted model" flow. Training is an
//!   own SMO solver with LIBSVM's second-order working-set selection (WSS3, Fan, Chen & Lin 2005),
//!   LIBSVM's shrinking heuristic, a kernel-column cache and per-class penalties `C₊`, `C₋` for
//!   imbalanced data. On the golden cases of `tests/svm_golden.rs` its decision values equal
//!   scikit-learn's (LIBSVM's) to 1e-13;
//! * decision values as detection scores (one sample, or a detector's candidates in parallel
//!   blocks with [`SvmClassifier::decision_values`], the batched RBF kernel every detector uses), optional Platt probabilities (the improved algorithm of
//!   Lin, Lin & Weng 2007, as in LIBSVM);
//! * [`GridSearchParams`] — stratified k-fold cross-validated search over `log2 C` × `log2 γ`
//!   (LIBSVM's `grid.py` defaults, then a finer pass around the best cell), deterministic for a
//!   seed and independent of the thread count;
//! * [`ScoreCalibration`] — raw score → confidence in `[0, 1]` (Platt on held-out detections) and
//!   the operating confidence a detector reports at by default;
//! * [`ModelFile`] — one versioned JSON file per trained detector; loading a file made for another
//!   pipeline or format version is a typed error, and floats round-trip bit-exactly.
//!
//! ```
//! use pomona_learn::{SvmParams, TrainingSet};
//! // Two clusters on a line.
//! let rows: Vec<Vec<f64>> = (0..20).map(|i| vec![i as f64]).collect();
//! let labels: Vec<bool> = (0..20).map(|i| i >= 10).collect();
//! let data = TrainingSet::from_rows(&rows, labels).unwrap();
//! let model = SvmParams::default().c(10.0).gamma(1.0).check().unwrap().fit(&data).unwrap();
//! assert_eq!(model.predict_one(&[2.0]).unwrap(), false);
//! assert_eq!(model.predict_one(&[17.0]).unwrap(), true);
//! ```

mod batched_decision;
mod cue_logistic;
mod error;
mod folds;
#[doc(hidden)]
pub mod fuzzing;
mod grid_search;
mod kernel_cache;
mod model_file;
mod model_head;
mod platt;
mod samples;
mod scaler;
mod score_calibration;
mod smo;
mod svm;

pub use batched_decision::{BatchedClassifier, DECISION_BLOCK};
pub use cue_logistic::{CueLogistic, CueVector, DetectionCues};
pub use error::{LearnError, ModelFileError};
pub use folds::stratified_folds;
pub use grid_search::{
    CellSelection, CvMetric, GridAxis, GridCell, GridSearchParams, GridSearchResult,
    ValidGridSearch,
};
pub use model_file::{
    ModelFile, MAX_MODEL_FILE_BYTES, MAX_STAGE_PARAMS_BYTES, MODEL_FORMAT, MODEL_VERSION,
};
pub use platt::PlattSigmoid;
pub use samples::{Samples, TrainingSet};
pub use scaler::MinMaxScaler;
pub use score_calibration::{CalibrationEvidence, OperatingPoint, ScoreCalibration};
pub use svm::{ClassWeights, RbfSvm, SvmClassifier, SvmParams, TrainingInfo, ValidSvmParams};
