//! Leave-one-frame-out on the real Azure Kinect orchard frames (`../shared/data/ak-apples`):
//! train shape-fit (spheres) on two frames, evaluate on the third, all three ways. Truth is
//! incomplete there, so only recall, centre error and diameter error are meaningful.
//!
//! ```sh
//! cargo run --release -p pomona-shapefit --example ak_apples -- ../shared/data/ak-apples
//! ```
//!
//! Knobs (environment): `RIM_PX`, `RADIUS_MM=lo,hi`, `COST_MM`, `REFINE_MM`, `INLIER_MM`,
//! `EARLY_STOP` (a confidence, or anything else for none), `POMONA_DEBUG=1` (each located apple
//! against its nearest detection), `AK_DIAG=1` (first, a free-radius sphere fitted to the depth
//! points of each truth box's inner 60 %, the points the truth centres were derived from: how
//! large the data says the apples are).

use pomona_eval::{evaluate, EvalConfig, FrameInput};
use pomona_io::Dataset;
use pomona_pipeline::{DatasetFrames, FrameSource, Pipeline, StageTimings, TrainOptions};
use pomona_shapefit::ShapeFitPipeline;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let root = args
        .next()
        .unwrap_or_else(|| "../shared/data/ak-apples".into());
    if let Some(extra) = args.next() {
        return Err(format!("unexpected argument `{extra}`; usage: ak_apples [DATASET]").into());
    }
    let all = DatasetFrames::new(vec![Dataset::open(&root)?]);
    let mut pipeline = ShapeFitPipeline::default();
    pipeline.params.shapes.shapes = pomona_consensus::ShapeChoice::Sphere;
    // The trees stand 1–2 m from the camera; the paper's 1.5 m reach would cut most apples.
    pipeline.params.max_depth_m = 2.5;
    // Apples: 55–90 mm; Azure Kinect depth is less noisy than Kinect v2.
    pipeline.params.shapes.sphere.radius_range_m = (0.025, 0.05);
    // Azure Kinect normals are clean enough to require inliers' normals to point along the
    // sphere's radius (within 0.6 rad), which keeps spheres from swelling over neighbouring
    // leaves; on noisy time-of-flight synthetic data the same check hurts.
    pipeline.params.shapes.sphere.max_normal_deviation_rad = Some(0.6);
    if let Ok(r) = std::env::var("RIM_PX") {
        pipeline.params.regions.rim_px = r.parse()?;
    }
    if let Ok(r) = std::env::var("RADIUS_MM") {
        let (lo, hi) = r.split_once(',').ok_or("RADIUS_MM=lo,hi")?;
        pipeline.params.shapes.sphere.radius_range_m =
            (lo.parse::<f64>()? / 1000.0, hi.parse::<f64>()? / 1000.0);
    }
    if let Ok(t) = std::env::var("COST_MM") {
        pipeline.params.shapes.msac.cost_threshold_m = t.parse::<f64>()? / 1000.0;
    }
    if let Ok(t) = std::env::var("REFINE_MM") {
        pipeline.params.shapes.msac.refine_threshold_m = Some(t.parse::<f64>()? / 1000.0);
    }
    if let Ok(c) = std::env::var("EARLY_STOP") {
        pipeline.params.shapes.msac.early_stop_confidence = c.parse::<f64>().ok();
    }
    if let Ok(t) = std::env::var("INLIER_MM") {
        pipeline.params.shapes.msac.inlier_threshold_m = t.parse::<f64>()? / 1000.0;
    }
    if std::env::var_os("AK_DIAG").is_some() {
        sphere_fits_on_truth_boxes(&all)?;
    }
    let mut inputs = Vec::new();
    let mut timings = StageTimings::default();
    for test in 0..all.len() {
        let train: Vec<usize> = (0..all.len()).filter(|&i| i != test).collect();
        let model = pipeline.train(
            &all.subset(&train),
            &TrainOptions {
                seed: 1,
                ..TrainOptions::default()
            },
            &|_, _| {},
        )?;
        let detector = pipeline.load(&model)?;
        let lf = all.load(test)?;
        let detections = detector.detect(&lf.frame, &mut timings)?;
        println!("{}: {} detections", lf.name, detections.len());
        if std::env::var_os("POMONA_DEBUG").is_some() {
            // Each located truth apple against its nearest detection with a positive score.
            for t in &lf.truth.fruits {
                let Some(c) = t.center_m else { continue };
                let nearest = detections
                    .iter()
                    .filter(|d| d.score >= 0.0)
                    .min_by(|a, b| (a.center_m - c).norm().total_cmp(&(b.center_m - c).norm()));
                if let Some(d) = nearest.filter(|d| (d.center_m - c).norm() < 0.05) {
                    let e = d.center_m - c;
                    println!(
                        "  {} d {:.1} mm → {:.1} mm, z {:.2} m, err [{:+.1} {:+.1} {:+.1}] mm",
                        t.id,
                        1e3 * t.diameter_m.unwrap_or(0.0),
                        1e3 * d.diameter_m.unwrap_or(0.0),
                        c.z,
                        1e3 * e.x,
                        1e3 * e.y,
                        1e3 * e.z
                    );
                }
            }
        }
        // The issue's measure is recall of annotated *apples*: the two reference balls (kind
        // `reference_ball`, white spheres of 60 and 120 mm) are not fruit and are left out.
        let mut truth = lf.truth;
        truth.keep_kinds(&["apple"]);
        inputs.push(FrameInput {
            frame: lf.name,
            truth,
            detections,
        });
    }
    let camera = *all.frame_ref(0).ok_or("no frames")?.0.camera();
    let report = evaluate(
        &inputs,
        &camera,
        &EvalConfig {
            min_visibility: 0.0,
            ..EvalConfig::default()
        },
    )?;
    println!("{}", report.to_markdown());
    println!("{}", timings.table());
    Ok(())
}

/// Fits a free-radius sphere to the depth points of each truth box's inner 60 % and prints its
/// diameter against the caliper's: the bias any sphere fit on this depth inherits.
fn sphere_fits_on_truth_boxes(all: &DatasetFrames) -> Result<(), Box<dyn std::error::Error>> {
    let mut errors = Vec::new();
    for i in 0..all.len() {
        let lf = all.load(i)?;
        let camera = *lf.frame.camera();
        for t in &lf.truth.fruits {
            let (Some(b), Some(d)) = (t.bbox_px, t.diameter_m) else {
                continue;
            };
            let (cu, cv) = ((b.xmin + b.xmax) / 2.0, (b.ymin + b.ymax) / 2.0);
            let (hu, hv) = (0.3 * b.width(), 0.3 * (b.ymax - b.ymin));
            let mut points = Vec::new();
            for v in (cv - hv).ceil() as u32..=(cv + hv).floor() as u32 {
                for u in (cu - hu).ceil() as u32..=(cu + hu).floor() as u32 {
                    if let Some(z) = lf.frame.depth().get(u, v).filter(|z| z.is_finite()) {
                        points.push(camera.back_project(u as f64, v as f64, f64::from(z)));
                    }
                }
            }
            if let Some(s) = pomona_consensus::Sphere::fit_least_squares(&points) {
                println!(
                    "  {} {}: caliper {:.1} mm, free fit {:.1} mm over {} points",
                    lf.name,
                    t.id,
                    1e3 * d,
                    2e3 * s.radius_m,
                    points.len()
                );
                errors.push(2.0 * s.radius_m - d);
            }
        }
    }
    errors.sort_by(f64::total_cmp);
    if !errors.is_empty() {
        println!(
            "free-fit diameter minus caliper: median {:+.1} mm over {} boxes",
            1e3 * errors[errors.len() / 2],
            errors.len()
        );
    }
    Ok(())
}
