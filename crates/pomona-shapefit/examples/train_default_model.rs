//! Trains the model embedded in the binary as shape-fit's default (`models/default.json`):
//! synthetic Kinect v2 frames of every fruit kind (one kind per frame), time-of-flight noise,
//! spheres and cylinders, fixed seeds. Rerun after changing the pipeline:
//!
//! ```sh
//! cargo run --release -p pomona-shapefit --example train_default_model -- crates/pomona-shapefit/models/default.json
//! ```

use pomona_pipeline::{Pipeline, TrainOptions};
use pomona_shapefit::{ShapeFitPipeline, SyntheticFrames};
use pomona_synth::{FruitChoice, NoiseModel, SceneSpec};

/// Frames rendered for training; seed 1000 is reserved for the default model (tests and
/// benchmarks use other seeds).
const FRAMES: usize = 60;
const DATASET_SEED: u64 = 1000;
const TRAIN_SEED: u64 = 1;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "crates/pomona-shapefit/models/default.json".into());
    let spec = SceneSpec {
        fruit: FruitChoice::Mixed,
        noise: NoiseModel::Tof,
        green_fraction: 0.2,
        ..SceneSpec::default()
    };
    let frames = SyntheticFrames {
        spec,
        seed: DATASET_SEED,
        first: 0,
        count: FRAMES,
    };
    let mut pipeline = ShapeFitPipeline::default();
    pipeline.params.shapes.shapes = pomona_consensus::ShapeChoice::Both;
    let start = std::time::Instant::now();
    let model = pipeline.train(
        &frames,
        &TrainOptions {
            seed: TRAIN_SEED,
            ..TrainOptions::default()
        },
        &|done, total| {
            eprint!("\rframes {done}/{total}");
        },
    )?;
    eprintln!();
    model.save(&out)?;
    println!(
        "wrote {out}: {} support vectors, {:.1} s",
        model.svm.n_support(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
