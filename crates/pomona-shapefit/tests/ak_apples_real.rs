//! Real data: training on two of the Azure Kinect orchard frames (`../shared/data/ak-apples`,
//! incomplete truth) learns the size prior from the annotated apples alone and finds the
//! apples of the third frame. Skips with a message when the data folder is absent; fails
//! instead when `POMONA_REQUIRE_DATA=1`.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

use std::path::PathBuf;

use pomona_consensus::ShapeChoice;
use pomona_eval::EvalConfig;
use pomona_io::Dataset;
use pomona_pipeline::{detect_and_evaluate, DatasetFrames, FrameSource, Pipeline, TrainOptions};
use pomona_shapefit::{ShapeFitPipeline, ShapeFitStageParams};

fn shared_data(rel: &str) -> Option<PathBuf> {
    pomona_test_support::shared_data(rel, "pomona-shapefit/tests/ak_apples_real.rs")
}

#[test]
fn learns_the_apple_size_prior_and_finds_the_held_out_apples() {
    let Some(root) = shared_data("ak-apples") else {
        return;
    };
    let all = DatasetFrames::new(vec![Dataset::open(&root).unwrap()]);
    assert_eq!(all.len(), 3);
    let pipeline = ShapeFitPipeline::default();
    let model = pipeline
        .train(&all.subset(&[0, 1]), &TrainOptions::default(), &|_, _| {})
        .unwrap();
    let stage: ShapeFitStageParams = serde_json::from_value(model.stage_params.clone()).unwrap();
    let p = &stage.params;
    // 2 frames × 26 apples; the reference balls (60 and 120 mm) are left out.
    let prior = p.learnt_size_prior.as_ref().unwrap();
    assert_eq!((prior.fruits, prior.round, prior.elongated), (52, 52, 0));
    let (lo, hi) = prior.sphere_radius_m.unwrap();
    assert!((lo - 0.029095).abs() < 1e-9 && (hi - 0.04139).abs() < 1e-9);
    assert_eq!(p.shapes.shapes, ShapeChoice::Sphere);
    assert!((p.shapes.sphere.radius_range_m.1 - 1.1 * 0.04139).abs() < 1e-9);
    assert!(
        p.max_depth_m > 1.86 && p.max_depth_m < 2.2,
        "{}",
        p.max_depth_m
    );
    assert!(p.regions.min_fruit_area.is_some());
    assert!(p.radius_calibration.is_some());

    let detector = pipeline.load(&model).unwrap();
    let mut held_out = all.load(2).unwrap();
    held_out.truth.keep_kinds(&["apple"]);
    let report = detect_and_evaluate(detector.as_ref(), &vec![held_out], &EvalConfig::default())
        .unwrap()
        .report;
    let recall = report.recall.unwrap();
    let center = report.center_error_m.median.unwrap();
    let diameter = report.diameter_error_m.mean_abs.unwrap();
    eprintln!("recall {recall:.3}, centre median {center:.4} m, diameter MAE {diameter:.4} m");
    // The CLI leave-one-out (scripts/ak_apples_loo.sh) gets 0.885 / 5.4 mm / 4.6 mm here.
    assert!(recall >= 0.8, "recall {recall}");
    assert!(center <= 0.012, "centre error {center}");
    assert!(diameter <= 0.010, "diameter error {diameter}");
}
