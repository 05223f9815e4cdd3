//! Shape-fit end to end on one Kinect v2 frame held in memory (time-of-flight noise, peppers,
//! fixed seeds), with the embedded default model. Run single-threaded for the paper comparison:
//! `RAYON_NUM_THREADS=1 cargo bench -p pomona-shapefit --bench detect`.

#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use pomona_learn::ModelFile;
use pomona_pipeline::SyntheticFrames;
use pomona_pipeline::{FrameSource, Pipeline, StageTimings};
use pomona_shapefit::ShapeFitPipeline;
use pomona_synth::{FruitChoice, FruitKind, NoiseModel, SceneSpec};

fn detect(c: &mut Criterion) {
    let pipeline = ShapeFitPipeline::default();
    let json = pipeline
        .default_model()
        .unwrap_or_else(|| panic!("no embedded model"));
    let model = ModelFile::from_json(json, std::path::Path::new("default.json"), "shape-fit")
        .unwrap_or_else(|e| panic!("{e}"));
    let detector = pipeline.load(&model).unwrap_or_else(|e| panic!("{e}"));
    let spec = SceneSpec {
        fruit: FruitChoice::Only(FruitKind::Pepper),
        noise: NoiseModel::Tof,
        ..SceneSpec::default()
    };
    let frames = SyntheticFrames {
        spec,
        seed: 77,
        first: 0,
        count: 1,
    };
    let frame = frames.load(0).unwrap_or_else(|e| panic!("{e}")).frame;
    c.bench_function("shape-fit detect kinect-v2 frame", |b| {
        b.iter(|| detector.detect(&frame, &mut StageTimings::default()))
    });
}

criterion_group!(benches, detect);
criterion_main!(benches);
