//! The parser entry point of the `model_file` fuzz target in the repository's `fuzz/` folder,
//! and a seed input for it.
//!
//! The fuzz target and the replay test (`tests/fuzz_replay.rs`) both call [`model_json`], so the
//! code fuzzed and the code replayed on the stable toolchain cannot drift apart. Not part of the
//! supported API.

use std::path::Path;

use crate::{ModelFile, OperatingPoint, ScoreCalibration, SvmParams, TrainingSet};

/// Name of the fuzz target, as in `fuzz/Cargo.toml`.
pub const TARGET: &str = "model_file";

/// Pipeline name the fuzzed model files are loaded for (the seed's).
pub const PIPELINE: &str = "shape-fit";

/// Largest feature count the target scores a sample of (a model that declares more is still
/// parsed and validated, but not run).
const MAX_SCORED_FEATURES: usize = 4096;

/// Parses `data` as a model file for [`PIPELINE`]; a model that loads must score a sample of
/// its feature count and map the score to a confidence without error.
///
/// # Panics
/// When a model that loaded cannot score a sample of the right length (a bug).
pub fn model_json(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(model) = ModelFile::from_json(text, Path::new("fuzz/model.json"), PIPELINE) else {
        return;
    };
    let classifier = model.classifier();
    let n = classifier.n_features();
    if n <= MAX_SCORED_FEATURES {
        let score = classifier
            .decision_value(&vec![0.5; n])
            .unwrap_or_else(|e| panic!("a loaded model cannot score a sample: {e}"));
        if let Some(calibration) = &model.calibration {
            let _ = calibration.confidence(score);
        }
    }
}

/// A small valid model file for [`PIPELINE`] (two features, scaled, calibrated).
///
/// # Panics
/// Never for these fixed training rows (a training failure would be a bug).
pub fn seed() -> String {
    let rows: Vec<Vec<f64>> = (0..20)
        .map(|i| vec![f64::from(i), f64::from(i % 3)])
        .collect();
    let labels: Vec<bool> = (0..20).map(|i| i >= 10).collect();
    let fail = |e: &dyn std::fmt::Display| -> ! { panic!("seed model: {e}") };
    let data = TrainingSet::from_rows(&rows, labels).unwrap_or_else(|e| fail(&e));
    let classifier = SvmParams::default()
        .c(10.0)
        .gamma(0.5)
        .check()
        .and_then(|p| p.fit(&data))
        .unwrap_or_else(|e| fail(&e));
    let mut model = ModelFile::new(PIPELINE, serde_json::json!({"window": 3}), &classifier);
    let scores: Vec<f64> = (0..20)
        .map(|i| f64::from(i) - 9.5 + f64::from(i % 4))
        .collect();
    let is_true: Vec<bool> = (0..20).map(|i| i >= 10).collect();
    let calibration = ScoreCalibration::fit(&scores, &is_true, 10, OperatingPoint::MaxF1);
    model.calibration = Some(calibration.unwrap_or_else(|e| fail(&e)));
    serde_json::to_string(&model).unwrap_or_else(|e| fail(&e))
}
