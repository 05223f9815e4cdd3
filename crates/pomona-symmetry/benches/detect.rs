//! Criterion bench of the detectors on one synthetic Kinect v2 frame (512×424, `tof` noise),
//! single-threaded (a one-thread rayon pool), per pipeline variant (`symmetry+pruning+cascade`
//! is the default `symmetry` pipeline; without `+cascade` every box gets the symmetry search,
//! as in seed 000), plus the symmetry-plane
//! search on one box and the normal estimators (window vs kd-tree) on the whole frame; and the
//! built-in `symmetry` and `viewer-pose` models on one `wide` frame from each camera (Kinect v2,
//! D435, SR4000; mixed fruit, each camera's own depth noise, seeds 621–623, never trained on)
//! and on the third real 1920×1080 Azure Kinect frame of `../shared/data/ak-apples` (skipped
//! with a message when the folder is absent, a failure with `POMONA_REQUIRE_DATA=1`).
//!
//! `cargo bench -p pomona-symmetry --bench detect`
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use pomona_consensus::{KnnNormalParams, WindowNormalParams};
use pomona_core::nalgebra::Point3;
use pomona_io::Dataset;
use pomona_learn::ModelFile;
use pomona_pipeline::DatasetFrames;
use pomona_pipeline::{
    FrameSource, LabelledFrame, Pipeline, StageTimings, SyntheticFrames, TrainOptions,
};
use pomona_symmetry::{
    BoxDetector, FrameKind, StageParams, SymmetryPipeline, SymmetryPlaneSearch, ViewerPosePipeline,
};
use pomona_synth::{CameraPreset, Domain, NoiseModel, SceneSpec};

fn frames(n: usize) -> Vec<LabelledFrame> {
    let spec = SceneSpec {
        camera: CameraPreset::KinectV2.camera(),
        noise: NoiseModel::Tof,
        green_fraction: 0.5,
        ..SceneSpec::default()
    };
    SyntheticFrames {
        spec,
        seed: 11,
        first: 0,
        count: n,
    }
    .load_all()
    .unwrap()
}

fn bench(c: &mut Criterion) {
    let mut all = frames(7);
    let test = all.pop().unwrap();
    let train = all;
    let options = TrainOptions {
        seed: 1,
        folds: 3,
        full_grid: false,
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut group = c.benchmark_group("detect-kinect-v2-1-thread");
    group.sample_size(10);
    let symmetry = |pruning: bool, cascade: bool| -> Box<dyn Pipeline> {
        let mut p = StageParams::symmetry();
        p.highlight.enabled = pruning;
        p.cascade.enabled = cascade;
        Box::new(SymmetryPipeline::with_params(p))
    };
    let variants: Vec<(&str, Box<dyn Pipeline>)> = vec![
        (
            "symmetry+pruning+cascade",
            Box::new(SymmetryPipeline::default()),
        ),
        ("symmetry+cascade", symmetry(false, true)),
        ("symmetry+pruning", symmetry(true, false)),
        ("symmetry", symmetry(false, false)),
        ("fixed+pruning", Box::new(SymmetryPipeline::fixed())),
        ("fixed", {
            let mut p = StageParams::symmetry();
            p.frame = FrameKind::Fixed;
            p.highlight.enabled = false;
            Box::new(SymmetryPipeline::with_params(p))
        }),
        (
            "viewer-pose+pruning",
            Box::new(ViewerPosePipeline::default()),
        ),
    ];
    for (name, pipeline) in variants {
        let model = pipeline.train(&train, &options, &|_, _| {}).unwrap();
        let detector = BoxDetector::from_model(pipeline.name(), &model).unwrap();
        group.bench_function(name, |b| {
            b.iter(|| {
                one.install(|| {
                    detector
                        .detect_frame(&test.frame, &mut StageTimings::default())
                        .unwrap()
                })
            })
        });
    }
    group.finish();

    let mut group = c.benchmark_group("builtin-wide-1-thread");
    group.sample_size(10);
    let cameras = [
        ("kinect-v2", CameraPreset::KinectV2, 621),
        ("d435", CameraPreset::D435, 622),
        ("sr4000", CameraPreset::Sr4000, 623),
    ];
    let builtin: [Box<dyn Pipeline>; 2] = [
        Box::new(SymmetryPipeline::default()),
        Box::new(ViewerPosePipeline::default()),
    ];
    let real = pomona_test_support::shared_data("ak-apples", "pomona-symmetry/benches/detect.rs")
        .map(|root| {
            DatasetFrames::new(vec![Dataset::open(&root).unwrap()])
                .load(2)
                .unwrap()
                .frame
        });
    for pipeline in &builtin {
        let json = pipeline.default_model().unwrap();
        let path = std::path::Path::new("default.json");
        let model = ModelFile::from_json(json, path, pipeline.name()).unwrap();
        let detector = BoxDetector::from_model(pipeline.name(), &model).unwrap();
        let synthetic = cameras.map(|(camera, preset, seed)| {
            let frame = SyntheticFrames::mixed_fruit(Domain::Wide, preset, 0.2, seed, 1)
                .load(0)
                .unwrap()
                .frame;
            (camera, frame)
        });
        let frames = synthetic
            .into_iter()
            .chain(real.clone().map(|f| ("real azure-kinect 1920x1080", f)));
        for (camera, frame) in frames {
            group.bench_function(format!("{} {camera}", pipeline.name()), |b| {
                b.iter(|| {
                    one.install(|| {
                        detector
                            .detect_frame(&frame, &mut StageTimings::default())
                            .unwrap()
                    })
                })
            });
        }
    }
    group.finish();

    let params = StageParams::symmetry();
    let stages = pomona_symmetry::Stages::new(&params).unwrap();
    let cloud = stages.normal_stage().cloud(&test.frame).unwrap();
    let fruit = test
        .truth
        .fruits
        .iter()
        .filter_map(|f| f.center_m)
        .find_map(|c| stages.sliding_box().patch(&cloud, c))
        .unwrap();
    let search = SymmetryPlaneSearch::new(params.symmetry);
    c.bench_function("symmetry-plane-one-box", |b| {
        b.iter(|| search.best(&fruit, &Point3::origin()))
    });

    let mut group = c.benchmark_group("normals-kinect-v2-1-thread");
    group.sample_size(10);
    let pc = test.frame.to_cloud();
    let window = WindowNormalParams::default().check().unwrap();
    let knn = KnnNormalParams::default().check().unwrap();
    group.bench_function("window-5x5", |b| {
        b.iter(|| one.install(|| window.estimate(&pc).unwrap()))
    });
    group.bench_function("kd-tree-knn", |b| {
        b.iter(|| one.install(|| knn.estimate_cloud(&pc)))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
