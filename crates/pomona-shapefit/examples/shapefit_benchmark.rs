//! Trains shape-fit on synthetic frames and evaluates it on frames rendered with other seeds.
//!
//! ```sh
//! cargo run --release -p pomona-shapefit --example shapefit_benchmark -- pepper 40 20 tof
//! ```
//! Arguments: fruit (pepper|eggplant|guava|apple|orange|mixed), training frames, test frames,
//! noise (none|low|tof). Prints the evaluation summary and per-stage timings.
//!
//! Environment knobs for experiments: `EARLY_STOP=C` (MSAC early-stop confidence; the default
//! parameters' 0.99 when unset), `GPCD_POINTS=N` (descriptor subsample size), `LABEL_RULE=mask-majority` (training labels), `CLASS_WEIGHTS=equal` (unweighted SVM,
//! accuracy as the grid-search criterion), `RIM_PX=N` (cluster rim dropped before fitting),
//! `MAX_SHAPES=N` (shapes extracted per cluster), `POMONA_DEBUG=1` (print each positive
//! detection against its nearest truth fruit; add `POMONA_DEBUG_ALL=1` for every detection).

use std::time::Instant;

use pomona_consensus::ShapeChoice;
use pomona_core::Detection;
use pomona_eval::{evaluate, EvalConfig, FrameInput};
use pomona_pipeline::{FrameSource, Pipeline, StageTimings, TrainOptions};
use pomona_pipeline::{LabelledFrame, SyntheticFrames};
use pomona_shapefit::ShapeFitPipeline;
use pomona_synth::{FruitChoice, FruitKind, NoiseModel, SceneSpec};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut pipeline_early_stop = None;
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or_else(|| default.to_owned());
    let fruit: FruitChoice = arg(0, "pepper").parse()?;
    let noise: NoiseModel = arg(3, "tof").parse()?;
    if args.len() > 4 {
        return Err(format!("unexpected arguments after the fourth: {:?}", &args[4..]).into());
    }
    if let Ok(c) = std::env::var("EARLY_STOP") {
        pipeline_early_stop = Some(c.parse::<f64>()?);
    }
    let max_points: Option<usize> = match std::env::var("GPCD_POINTS") {
        Ok(s) => Some(s.parse().map_err(|e| format!("GPCD_POINTS={s}: {e}"))?),
        Err(_) => None,
    };
    let n_train: usize = arg(1, "40").parse()?;
    let n_test: usize = arg(2, "20").parse()?;
    let spec = SceneSpec {
        fruit,
        noise,
        ..SceneSpec::default()
    };
    let train = SyntheticFrames {
        spec: spec.clone(),
        seed: 1,
        first: 0,
        count: n_train,
    };
    let test = SyntheticFrames {
        spec: spec.clone(),
        seed: 2,
        first: 0,
        count: n_test,
    };

    // One shape model per crop, as the paper does; both for mixed crops.
    let mut pipeline = ShapeFitPipeline::default();
    pipeline.params.shapes.shapes = match fruit {
        FruitChoice::Only(FruitKind::Eggplant) => ShapeChoice::Cylinder,
        FruitChoice::Only(_) => ShapeChoice::Sphere,
        _ => ShapeChoice::Both,
    };
    if pipeline_early_stop.is_some() {
        pipeline.params.shapes.msac.early_stop_confidence = pipeline_early_stop;
    }
    match std::env::var("LABEL_RULE").as_deref() {
        Err(_) => {}
        Ok("mask-majority") => {
            pipeline.params.label_rule = pomona_shapefit::LabelRule::MaskMajority
        }
        Ok(other) => {
            return Err(format!("LABEL_RULE={other}: only `mask-majority` is known").into())
        }
    }
    match std::env::var("CLASS_WEIGHTS").as_deref() {
        Err(_) => {}
        Ok("equal") => {
            pipeline.params.class_weights = pomona_learn::ClassWeights::Fixed {
                positive: 1.0,
                negative: 1.0,
            };
            pipeline.params.cv_metric = pomona_learn::CvMetric::Accuracy;
        }
        Ok(other) => return Err(format!("CLASS_WEIGHTS={other}: only `equal` is known").into()),
    }
    if let Ok(m) = std::env::var("MAX_SHAPES") {
        pipeline.params.shapes.limits.max_shapes = m.parse()?;
    }
    if let Ok(r) = std::env::var("RIM_PX") {
        pipeline.params.regions.rim_px = r.parse()?;
    }
    if let Some(m) = max_points {
        pipeline.params.gpcd.max_points = m;
    }
    let t0 = Instant::now();
    let model = pipeline.train(
        &train,
        &TrainOptions {
            seed: 7,
            ..TrainOptions::default()
        },
        &|_, _| {},
    )?;
    println!(
        "trained on {n_train} frames in {:.1} s ({} support vectors)",
        t0.elapsed().as_secs_f64(),
        model.svm.n_support()
    );

    let detector = pipeline.load(&model)?;
    let mut timings = StageTimings::default();
    let mut frames = Vec::new();
    for i in 0..test.len() {
        let lf = test.load(i)?;
        let detections = detector.detect(&lf.frame, &mut timings)?;
        if std::env::var_os("POMONA_DEBUG").is_some() {
            print_debug(&lf, &detections);
        }
        frames.push(FrameInput {
            frame: lf.name,
            truth: lf.truth,
            detections,
        });
    }
    let report = evaluate(&frames, &spec.camera, &EvalConfig::default())?;
    println!("{}", report.to_markdown());
    println!("{}", timings.table());
    println!(
        "mean per frame: {:.1} ms",
        1e3 * timings.total().as_secs_f64() / n_test.max(1) as f64
    );
    Ok(())
}

/// `POMONA_DEBUG`: each positive detection (every one with `POMONA_DEBUG_ALL`) against its
/// nearest truth fruit.
fn print_debug(lf: &LabelledFrame, detections: &[Detection]) {
    let all = std::env::var_os("POMONA_DEBUG_ALL").is_some();
    for d in detections.iter().filter(|d| d.score > 0.0 || all) {
        let nearest = lf
            .truth
            .fruits
            .iter()
            .filter_map(|t| t.center_m.map(|c| (t, c)))
            .min_by(|a, b| {
                (a.1 - d.center_m)
                    .norm()
                    .total_cmp(&(b.1 - d.center_m).norm())
            });
        if let Some((t, c)) = nearest {
            let e = d.center_m - c;
            println!(
                "{} truth {} d {:.3} vis {:.2} det score {:.2} d {:.3} err [{:+.3} {:+.3} {:+.3}]",
                lf.name,
                t.id,
                t.diameter_m.unwrap_or(0.0),
                t.visibility.unwrap_or(0.0),
                d.score,
                d.diameter_m.unwrap_or(0.0),
                e.x,
                e.y,
                e.z
            );
        }
    }
}
