//! End to end: train color-contour on synthetic oranges, detect on frames rendered with another
//! seed, and check that it finds them, that training is deterministic, that a model survives
//! its JSON round trip, and that frames without colour are refused by name.

use pomona_colorcontour::{ColorContourParams, ColorContourPipeline};
use pomona_core::RgbdFrame;
use pomona_eval::EvalConfig;
use pomona_learn::ModelFile;
use pomona_pipeline::{
    detect_and_evaluate, FrameSource, Pipeline, PipelineError, StageTimings, SyntheticFrames,
    TrainOptions,
};
use pomona_synth::{CameraPreset, FruitChoice, FruitKind, NoiseModel, SceneSpec};

fn frames(seed: u64, count: usize) -> SyntheticFrames {
    SyntheticFrames {
        spec: SceneSpec {
            fruit: FruitChoice::Only(FruitKind::Orange),
            camera: CameraPreset::D435.camera().scaled(0.5),
            noise: NoiseModel::Tof,
            ..SceneSpec::default()
        },
        seed,
        first: 0,
        count,
    }
}

#[test]
fn trains_and_finds_oranges() {
    let pipeline = ColorContourPipeline::default();
    let options = TrainOptions {
        seed: 5,
        ..TrainOptions::default()
    };
    let model = pipeline
        .train(&frames(21, 6), &options, &|_, _| {})
        .unwrap();
    let detector = pipeline.load(&model).unwrap();
    let run =
        detect_and_evaluate(detector.as_ref(), &frames(22, 4), &EvalConfig::default()).unwrap();
    let recall = run.report.recall.unwrap();
    let ap = run.report.ap_voc11.unwrap();
    assert!(recall > 0.5 && ap > 0.4, "recall {recall}, AP {ap}");
    // Every diameter passed the size test: the fruit range widened by the radius tolerance.
    let (r_lo, r_hi) = ColorContourParams::default().accepted_radius_range_m();
    for d in run.frames.iter().flat_map(|f| &f.detections) {
        assert!(d.score > 0.0 && d.score <= 1.0, "{d:?}");
        let diameter = d.diameter_m.unwrap();
        assert!((2.0 * r_lo..=2.0 * r_hi).contains(&diameter), "{d:?}");
        let b = d.bbox_px.unwrap();
        assert!((b.width() - b.height()).abs() < 1e-9, "{d:?}");
    }

    // Same seed → the same model; the JSON round trip gives the same detections.
    assert_eq!(
        pipeline
            .train(&frames(21, 6), &options, &|_, _| {})
            .unwrap(),
        model
    );
    let json = serde_json::to_string(&model).unwrap();
    let reloaded =
        ModelFile::from_json(&json, std::path::Path::new("mem.json"), "color-contour").unwrap();
    let test = frames(22, 1).load(0).unwrap();
    let a = detector
        .detect(&test.frame, &mut StageTimings::default())
        .unwrap();
    let b = pipeline
        .load(&reloaded)
        .unwrap()
        .detect(&test.frame, &mut StageTimings::default())
        .unwrap();
    assert_eq!(a, b);

    // Without colour the method cannot run, and says so.
    let f = &test.frame;
    let depth_only = RgbdFrame::new(*f.camera(), f.depth().clone(), None).unwrap();
    let err = detector.detect(&depth_only, &mut StageTimings::default());
    assert!(matches!(err, Err(PipelineError::MissingColor { .. })));
}
