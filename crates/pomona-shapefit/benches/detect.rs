//! Shape-fit end to end with the embedded default model on frames held in memory (fixed seeds),
//! in a one-thread rayon pool:
//!
//! * `narrow kinect-v2`: one narrow crop-row frame of peppers (time-of-flight noise), the
//!   scene seed 002 describes;
//! * `wide kinect-v2` and `wide d435`: three `wide` frames each (mixed fruit, a fifth green,
//!   each camera's own depth noise; seeds 601 and 602, never used for training), the worlds the
//!   built-in model is judged on; one iteration detects all three, so divide by three for a
//!   frame;
//! * `real azure-kinect 1920x1080`: the third real orchard frame of `../shared/data/ak-apples`
//!   with a model trained (default parameters, learnt size prior) on the other two, as
//!   `pomona experiment --leave-one-out` does; skipped with a message when the data folder is
//!   absent (and a failure with `POMONA_REQUIRE_DATA=1`).
//!
//! `cargo bench -p pomona-shapefit --bench detect`

#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use pomona_core::RgbdFrame;
use pomona_io::Dataset;
use pomona_learn::ModelFile;
use pomona_pipeline::SyntheticFrames;
use pomona_pipeline::{DatasetFrames, Detector, FrameSource, Pipeline, StageTimings, TrainOptions};
use pomona_shapefit::ShapeFitPipeline;
use pomona_synth::{CameraPreset, Domain, FruitChoice, FruitKind, NoiseModel, SceneSpec};

fn load(frames: SyntheticFrames) -> Vec<RgbdFrame> {
    (0..frames.count)
        .map(|i| frames.load(i).unwrap_or_else(|e| panic!("{e}")).frame)
        .collect()
}

/// The third ak-apples frame and a detector trained on the other two, when the data is there.
fn real_orchard_frame() -> Option<(Box<dyn Detector>, RgbdFrame)> {
    let root = pomona_test_support::shared_data("ak-apples", "pomona-shapefit/benches/detect.rs")?;
    let all = DatasetFrames::new(vec![Dataset::open(&root).unwrap_or_else(|e| panic!("{e}"))]);
    let pipeline = ShapeFitPipeline::default();
    let model = pipeline
        .train(&all.subset(&[0, 1]), &TrainOptions::default(), &|_, _| {})
        .unwrap_or_else(|e| panic!("{e}"));
    let detector = pipeline.load(&model).unwrap_or_else(|e| panic!("{e}"));
    let frame = all.load(2).unwrap_or_else(|e| panic!("{e}")).frame;
    Some((detector, frame))
}

fn detect(c: &mut Criterion) {
    let pipeline = ShapeFitPipeline::default();
    let json = pipeline
        .default_model()
        .unwrap_or_else(|| panic!("no embedded model"));
    let model = ModelFile::from_json(json, std::path::Path::new("default.json"), "shape-fit")
        .unwrap_or_else(|e| panic!("{e}"));
    let detector = pipeline.load(&model).unwrap_or_else(|e| panic!("{e}"));
    let narrow = load(SyntheticFrames {
        spec: SceneSpec {
            fruit: FruitChoice::Only(FruitKind::Pepper),
            noise: NoiseModel::Tof,
            ..SceneSpec::default()
        },
        seed: 77,
        first: 0,
        count: 1,
    });
    let sets = [
        ("shape-fit detect narrow kinect-v2 frame", narrow),
        (
            "shape-fit detect 3 wide kinect-v2 frames",
            load(SyntheticFrames::mixed_fruit(
                Domain::Wide,
                CameraPreset::KinectV2,
                0.2,
                601,
                3,
            )),
        ),
        (
            "shape-fit detect 3 wide d435 frames",
            load(SyntheticFrames::mixed_fruit(
                Domain::Wide,
                CameraPreset::D435,
                0.2,
                602,
                3,
            )),
        ),
    ];
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap_or_else(|e| panic!("{e}"));
    let run = |detector: &dyn Detector, frames: &[RgbdFrame]| {
        one.install(|| {
            for frame in frames {
                let found = detector.detect(frame, &mut StageTimings::default());
                criterion::black_box(found.unwrap_or_else(|e| panic!("{e}")));
            }
        })
    };
    for (name, frames) in &sets {
        c.bench_function(name, |b| b.iter(|| run(detector.as_ref(), frames)));
    }
    // The same model with the opt-in joining of pieces of one fruit among the depth proposals.
    let mut joined = model.clone();
    joined.stage_params["params"]["depth_proposals"]["join_pieces"] =
        serde_json::json!({ "gap_radii": 0.5 });
    let joined = pipeline.load(&joined).unwrap_or_else(|e| panic!("{e}"));
    for (name, frames) in sets.iter().skip(1) {
        c.bench_function(&format!("{name}, pieces joined"), |b| {
            b.iter(|| run(joined.as_ref(), frames))
        });
    }
    if let Some((trained, frame)) = real_orchard_frame() {
        let frames = [frame];
        c.bench_function("shape-fit detect real azure-kinect 1920x1080 frame", |b| {
            b.iter(|| run(trained.as_ref(), &frames))
        });
    }
}

criterion_group!(benches, detect);
criterion_main!(benches);
