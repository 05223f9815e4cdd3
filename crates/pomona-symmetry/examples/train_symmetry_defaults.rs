//! Trains the models embedded in the binary as the defaults of `symmetry`
//! (`models/symmetry.json`) and `viewer-pose` (`models/viewer-pose.json`): 32 synthetic frames of
//! every fruit kind (one kind per frame): 20 of the `wide` domain (randomised leaves,
//! backgrounds, light, distances 0.3–1.6 m) from three cameras with their own depth noise (12
//! Kinect v2, 4 D435, 4 SR4000) and 12 of the `narrow` crop row (Kinect v2, `tof`; trained on
//! wide frames alone, the models lost AP on narrow scenes and gained none on wide ones, see
//! docs/results.md), green fraction 0.5, dataset seeds 1000–1003 (reserved for
//! default models; tests and benchmarks use other seeds), training seed 1. Both pipelines use
//! their default parameters (highlight pruning on; it is skipped with a message on frames
//! without colour), and each model carries a confidence calibration and operating threshold
//! fitted on 3 held-out folds (`pomona_pipeline::train_calibrated`).
//!
//! Mixed fruit rather than peppers only: the detectors are shape-only, with one 12 cm box that
//! holds every kind the scene generator makes, and the demo renders mixed fruit; the crate
//! README gives the mixed-fruit and pepper-only figures behind this choice.
//!
//! Model size: each support vector is 168 numbers, and the `symmetry` model holds two SVMs (the
//! main one and its cascade's fixed-frame one, see `CascadeParams`), so the training set is
//! capped (32 frames, the pipelines' 40 negatives per frame) to keep each file under
//! 2 MB (`ModelFile::save` writes compact JSON). Rerun after changing the pipeline:
//!
//! ```sh
//! cargo run --release -p pomona-symmetry --example train_symmetry_defaults -- crates/pomona-symmetry/models
//! ```

use pomona_learn::ModelFile;
use pomona_pipeline::{
    train_calibrated, CalibrationParams, ChainedFrames, FrameSource, Pipeline, SyntheticFrames,
    TrainOptions,
};
use pomona_symmetry::{SymmetryPipeline, ViewerPosePipeline};
use pomona_synth::{CameraPreset, Domain};

/// Frames rendered for training per domain and camera (32 in all: the cap on the model size) and the
/// dataset seeds reserved for the default models.
const CAMERAS: [(Domain, CameraPreset, usize, u64); 4] = [
    (Domain::Narrow, CameraPreset::KinectV2, 12, 1003),
    (Domain::Wide, CameraPreset::KinectV2, 12, 1000),
    (Domain::Wide, CameraPreset::D435, 4, 1001),
    (Domain::Wide, CameraPreset::Sr4000, 4, 1002),
];

/// Seed of the training (sampling of negatives and jitters, cross-validation folds).
const TRAIN_SEED: u64 = 1;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "crates/pomona-symmetry/models".into()),
    );
    let rendered = ChainedFrames(
        CAMERAS
            .iter()
            .map(|&(domain, camera, count, seed)| {
                SyntheticFrames::mixed_fruit(domain, camera, 0.5, seed, count)
            })
            .collect(),
    );
    // Rendered once, trained on by every fold and both pipelines.
    let frames = rendered.load_all()?;
    let options = TrainOptions {
        seed: TRAIN_SEED,
        ..TrainOptions::default()
    };
    let progress = |done: usize, total: usize| eprint!("\rframes {done}/{total}");
    let pipelines: [(&str, Box<dyn Pipeline>); 2] = [
        ("symmetry.json", Box::new(SymmetryPipeline::default())),
        ("viewer-pose.json", Box::new(ViewerPosePipeline::default())),
    ];
    for (name, pipeline) in pipelines {
        let start = std::time::Instant::now();
        let trained = train_calibrated(
            pipeline.as_ref(),
            &frames,
            &options,
            &CalibrationParams::default(),
            &progress,
        )?;
        eprintln!();
        let model = trained.model;
        let calibration = match &model.calibration {
            Some(c) => c.to_string(),
            None => format!(
                "no calibration: {}",
                trained.not_calibrated.unwrap_or_default()
            ),
        };
        let out = dir.join(name);
        model.save(&out)?;
        let bytes = std::fs::metadata(&out)?.len();
        // The file must load back as this pipeline's model.
        ModelFile::load(&out, pipeline.name())?;
        let cascade = model.stage_params["cascade"]["classifier"]["svm"]["coef"]
            .as_array()
            .map_or(0, Vec::len);
        println!(
            "wrote {} ({:.2} MB): {} support vectors (+ {cascade} in the cascade), {calibration}, \
             {:.1} s",
            out.display(),
            bytes as f64 / 1e6,
            model.svm.n_support(),
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
