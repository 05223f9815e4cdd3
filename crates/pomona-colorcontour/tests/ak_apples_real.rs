//! Real data: the built-in colour-contour model (trained on synthetic oranges) on the Azure
//! Kinect orchard frames (`../shared/data/ak-apples`) places the apples it finds within about
//! 12 mm (median) once each circle's 3D centre is refitted to the fruit pixels' points, nearer
//! than the centre on the circle's ray. Skips with a message when the data
//! folder is absent; fails instead when `POMONA_REQUIRE_DATA=1`.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside test functions

use pomona_colorcontour::ColorContourPipeline;
use pomona_eval::EvalConfig;
use pomona_io::Dataset;
use pomona_learn::ModelFile;
use pomona_pipeline::{detect_and_evaluate, DatasetFrames, FrameSource, Pipeline};

/// Centre error median (metres) and true positives of `model` over `frames`, every detection
/// kept.
fn centre_error(model: &ModelFile, frames: &dyn FrameSource) -> (f64, usize) {
    let detector = ColorContourPipeline::default().load(model).unwrap();
    let config = EvalConfig {
        threshold: f64::NEG_INFINITY,
        ..EvalConfig::default()
    };
    let report = detect_and_evaluate(detector.as_ref(), frames, &config)
        .unwrap()
        .report;
    (report.center_error_m.median.unwrap(), report.true_positives)
}

#[test]
fn built_in_model_places_real_apples_from_their_points() {
    let Some(root) = pomona_test_support::shared_data(
        "ak-apples",
        "pomona-colorcontour/tests/ak_apples_real.rs",
    ) else {
        return;
    };
    let mut frames = DatasetFrames::new(vec![Dataset::open(&root).unwrap()])
        .load_all()
        .unwrap();
    for lf in &mut frames {
        lf.truth.keep_kinds(&["apple"]);
    }
    let text = ColorContourPipeline::default().default_model().unwrap();
    let model = ModelFile::from_json(text, "built-in".as_ref(), "color-contour").unwrap();
    let mut on_ray = model.clone();
    on_ray.stage_params["params"]["depth_refit_tolerance_m"] = serde_json::json!(0.0);
    let (refit, found) = centre_error(&model, &frames);
    let (ray, found_on_ray) = centre_error(&on_ray, &frames);
    eprintln!(
        "centre median: refitted {refit:.4} m ({found} apples), on the ray {ray:.4} m ({found_on_ray})"
    );
    // Measured: 11.6 mm against 14.7 mm, 77 apples either way, since the circles of spheres
    // fitted to the fruit's depth (whose centres already lie on the fruit's points:
    // docs/results.md, "Circles from the fruit's surface in depth"); 12.6 against 20.3 mm and
    // 69 apples before them; 9.7 against 20.2 mm and 63 apples before the radius tolerance,
    // whose six more apples are placed 15–29 mm off ("Radius tolerance").
    assert!(refit <= 0.013, "refitted {refit}");
    assert!(ray >= refit + 0.002, "on the ray {ray}, refitted {refit}");
    assert!(found + 2 >= found_on_ray, "{found} against {found_on_ray}");
}
