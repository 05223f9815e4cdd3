//! `pomona calibrate`: refit a model's confidence calibration (and operating confidence) on
//! labelled frames it was not trained on — the built-in model on frames of your own
//! greenhouse, or a trained model on a domain it never saw — without retraining its classifier.
//!
//! With `--cues` the confidence becomes a regression over the score and the detection's
//! geometry (coverage of its disc, depth, seen curvature, elongation; see
//! `pomona_learn::CueLogistic`), which can reorder detections; without it, Platt's sigmoid of
//! the score, which cannot.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use pomona_eval::EvalConfig;
use pomona_pipeline::{recalibrate, CalibrationParams, FrameSource, Pipeline};

use crate::commands::train::{open_frames, operating_point};
use crate::detection_run::{thread_pool, with_model_hint};
use crate::progress::{counter, progress_bar};

/// Arguments of `pomona calibrate`.
#[derive(Debug, Clone, clap::Args)]
pub struct CalibrateArgs {
    /// Pipeline whose model is calibrated, e.g. `shape-fit`.
    #[arg(long, value_name = "NAME")]
    pub pipeline: String,
    /// Model file to calibrate (default: the pipeline's built-in model).
    #[arg(long, value_name = "MODEL")]
    pub model: Option<PathBuf>,
    /// Labelled dataset folder the model did not train on; repeat for several.
    #[arg(long = "data", value_name = "DIR", required = true)]
    pub data: Vec<PathBuf>,
    /// Where to write the calibrated model file (JSON).
    #[arg(long, value_name = "MODEL")]
    pub out: PathBuf,
    /// Fit the confidence to the detections' geometric cues beside their score.
    #[arg(long)]
    pub cues: bool,
    /// Choose the operating confidence as the lowest reaching this precision (0–1] on the
    /// calibration frames instead of the one with the best F1.
    #[arg(long, value_name = "P")]
    pub operating_precision: Option<f64>,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
}

/// Runs `pomona calibrate`.
///
/// # Errors
/// Unknown pipeline, a pipeline without a built-in model and no `--model`, an unreadable model
/// or dataset (naming it), frames that cannot be calibrated on (no detection known to be
/// false, or scores that do not rank fruit above the rest), an unwritable output.
pub fn run(args: &CalibrateArgs) -> Result<()> {
    run_with(&pomona::pipelines(), args)
}

/// Runs `pomona calibrate` choosing the pipeline from `pipelines` (tests pass their own).
///
/// # Errors
/// As [`run`].
pub fn run_with(pipelines: &[Box<dyn Pipeline>], args: &CalibrateArgs) -> Result<()> {
    let pipeline = pomona::find_pipeline(pipelines, &args.pipeline)?;
    let (model, _) =
        pomona::load_model(pipeline, args.model.as_deref()).map_err(with_model_hint)?;
    let frames = open_frames(pipeline, &args.data)?;
    let params = CalibrationParams {
        cues: args.cues,
        operating_point: operating_point(args.operating_precision),
        radius_fraction_2d: EvalConfig::default()
            .for_data(frames.has_depth())
            .radius_fraction_2d,
        ..CalibrationParams::default()
    };
    let pool = thread_pool(args.threads.map(|n| n as usize))?;
    let bar = progress_bar(frames.len(), "calibrating");
    let started = Instant::now();
    let progress = counter(&bar);
    let calibrated = pool
        .install(|| recalibrate(pipeline, &model, &frames, &params, &progress))
        .with_context(|| format!("calibrating `{}`", pipeline.name()))?;
    bar.finish_and_clear();
    calibrated.save(&args.out)?;
    if let Some(c) = &calibrated.calibration {
        println!(
            "Calibrated `{}` on {} detections ({} true) of {} labelled frame(s) in {:.1} s{}: {c}. \
             Model written to {}.",
            pipeline.name(),
            c.evidence.detections,
            c.evidence.true_positives,
            frames.len(),
            started.elapsed().as_secs_f64(),
            if args.cues {
                " with the score and the detections' cues"
            } else {
                " by the score alone"
            },
            args.out.display()
        );
    }
    Ok(())
}
