//! Real data: `symmetry` trained on two of the Azure Kinect orchard frames
//! (`../shared/data/ak-apples`, incomplete truth) widens its box range to the farthest annotated
//! apple, learns the refinement's radius calibration from the annotated apples, and finds and
//! sizes the apples of the third frame. Skips with a message when the data folder is absent;
//! fails instead when `POMONA_REQUIRE_DATA=1`.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

use pomona_eval::EvalConfig;
use pomona_io::Dataset;
use pomona_pipeline::{detect_and_evaluate, DatasetFrames, FrameSource, Pipeline, TrainOptions};
use pomona_symmetry::{StageParams, SymmetryPipeline};

#[test]
fn learns_range_and_radius_from_real_apples_and_finds_the_held_out_ones() {
    let Some(root) =
        pomona_test_support::shared_data("ak-apples", "pomona-symmetry/tests/ak_apples_real.rs")
    else {
        return;
    };
    let all = DatasetFrames::new(vec![Dataset::open(&root).unwrap()]);
    assert_eq!(all.len(), 3);
    let pipeline = SymmetryPipeline::default();
    let model = pipeline
        .train(&all.subset(&[0, 1]), &TrainOptions::default(), &|_, _| {})
        .unwrap();
    let params: StageParams = serde_json::from_value(model.stage_params.clone()).unwrap();
    // The farthest annotated apple centre of the two frames is 1.94 m away.
    let range = params.boxes.max_range_m;
    assert!(range > 1.9 && range < 1.95, "{range}");
    // Free fits on the real apples are far too large; the calibration pulls them to the
    // apples' 58–83 mm.
    let calibration = params.refinement.radius_calibration.unwrap();
    assert!(calibration.samples >= 20, "{calibration:?}");
    assert!(
        (0.028..0.042).contains(&calibration.radius_m(0.055, (0.0, 1.0))),
        "{calibration:?}"
    );

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
    // Before the working range and the calibration: recall about 0.6, centre 19 mm, diameter
    // 29 mm (docs/results.md, "Real apples, leave-one-out").
    assert!(recall >= 0.7, "recall {recall}");
    assert!(center <= 0.015, "centre error {center}");
    assert!(diameter <= 0.010, "diameter error {diameter}");
}
