//! Trains the models embedded in the binary as shape-fit's defaults: synthetic Kinect v2 frames
//! of every fruit kind (one kind per frame), time-of-flight noise, spheres and cylinders, fixed
//! seeds; `models/default.json` with colour and `models/default-depth.json` from the same
//! frames without colour (used for depth-only datasets). Rerun after changing the pipeline:
//!
//! ```sh
//! cargo run --release -p pomona-shapefit --example train_default_model -- crates/pomona-shapefit/models
//! ```

use pomona_core::RgbdFrame;
use pomona_pipeline::SyntheticFrames;
use pomona_pipeline::{FrameSource, LabelledFrame, Pipeline, PipelineError, TrainOptions};
use pomona_shapefit::ShapeFitPipeline;
use pomona_synth::{FruitChoice, NoiseModel, SceneSpec};

/// Frames rendered for training; seed 1000 is reserved for the default model (tests and
/// benchmarks use other seeds).
const FRAMES: usize = 60;
const DATASET_SEED: u64 = 1000;
const TRAIN_SEED: u64 = 1;

/// The same frames without their colour images.
struct WithoutColor(SyntheticFrames);

impl FrameSource for WithoutColor {
    fn len(&self) -> usize {
        self.0.len()
    }

    fn load(&self, i: usize) -> Result<LabelledFrame, PipelineError> {
        let mut lf = self.0.load(i)?;
        lf.frame =
            RgbdFrame::new(*lf.frame.camera(), lf.frame.depth().clone(), None).map_err(|e| {
                PipelineError::InvalidParameter {
                    name: "frame".into(),
                    reason: e.to_string(),
                }
            })?;
        Ok(lf)
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "crates/pomona-shapefit/models".into()),
    );
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
    let options = TrainOptions {
        seed: TRAIN_SEED,
        ..TrainOptions::default()
    };
    let progress = |done: usize, total: usize| eprint!("\rframes {done}/{total}");
    let depth_only = WithoutColor(frames.clone());
    let sources: [(&str, &dyn FrameSource); 2] = [
        ("default.json", &frames),
        ("default-depth.json", &depth_only),
    ];
    for (name, source) in sources {
        let start = std::time::Instant::now();
        let model = pipeline.train(source, &options, &progress)?;
        eprintln!();
        let out = dir.join(name);
        model.save(&out)?;
        println!(
            "wrote {}: {} support vectors, {:.1} s",
            out.display(),
            model.svm.n_support(),
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
