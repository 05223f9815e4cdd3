//! Trains the models embedded in the binary as the defaults of `symmetry`
//! (`models/symmetry.json`) and `viewer-pose` (`models/viewer-pose.json`): synthetic Kinect v2
//! frames of every fruit kind (one kind per frame, as `pomona demo` renders them), time-of-flight
//! noise, green fraction 0.5, dataset seed 1000 (reserved for default models; tests and
//! benchmarks use other seeds), training seed 1. Both pipelines use their default parameters
//! (highlight pruning on; it is skipped with a message on frames without colour).
//!
//! Mixed fruit rather than peppers only: the detectors are shape-only, with one 12 cm box that
//! holds every kind the scene generator makes, and the demo renders mixed fruit; the crate
//! README gives the mixed-fruit and pepper-only figures behind this choice.
//!
//! Model size: each support vector is 168 numbers, and the `symmetry` model holds two SVMs (the
//! main one and its cascade's fixed-frame one, see `CascadeParams`), so the training set is
//! capped ([`FRAMES`] frames, the pipelines' 40 negatives per frame) to keep each file under
//! 2 MB (`ModelFile::save` writes compact JSON). Rerun after changing the pipeline:
//!
//! ```sh
//! cargo run --release -p pomona-symmetry --example train_symmetry_defaults -- crates/pomona-symmetry/models
//! ```

use pomona_learn::ModelFile;
use pomona_pipeline::SyntheticFrames;
use pomona_pipeline::{Pipeline, TrainOptions};
use pomona_symmetry::{SymmetryPipeline, ViewerPosePipeline};
use pomona_synth::{CameraPreset, FruitChoice, NoiseModel, SceneSpec};

/// Frames rendered for training (the cap on the model size).
const FRAMES: usize = 32;
/// Dataset seed reserved for the default models.
const DATASET_SEED: u64 = 1000;
/// Seed of the training (sampling of negatives and jitters, cross-validation folds).
const TRAIN_SEED: u64 = 1;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "crates/pomona-symmetry/models".into()),
    );
    let spec = SceneSpec {
        fruit: FruitChoice::Mixed,
        camera: CameraPreset::KinectV2.camera(),
        noise: NoiseModel::Tof,
        green_fraction: 0.5,
        ..SceneSpec::default()
    };
    let frames = SyntheticFrames {
        spec,
        seed: DATASET_SEED,
        first: 0,
        count: FRAMES,
    };
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
        let model = pipeline.train(&frames, &options, &progress)?;
        eprintln!();
        let out = dir.join(name);
        model.save(&out)?;
        let bytes = std::fs::metadata(&out)?.len();
        // The file must load back as this pipeline's model.
        ModelFile::load(&out, pipeline.name())?;
        let cascade = model.stage_params["cascade"]["classifier"]["svm"]["coef"]
            .as_array()
            .map_or(0, Vec::len);
        println!(
            "wrote {} ({:.2} MB): {} support vectors (+ {cascade} in the cascade), {:.1} s",
            out.display(),
            bytes as f64 / 1e6,
            model.svm.n_support(),
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
