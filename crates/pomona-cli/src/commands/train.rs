//! `pomona train`: train a detector (any registered pipeline) on the labelled frames of one or
//! more datasets and write its versioned model file.
//!
//! The command knows nothing about the method: it gathers every frame that has truth
//! (`DatasetFrames`, loaded lazily), hands them to `Pipeline::train` with the seed and
//! cross-validation options, and saves the result atomically with `ModelFile::save`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use pomona_eval::EvalConfig;
use pomona_io::Dataset;
use pomona_learn::OperatingPoint;
use pomona_pipeline::{
    train_calibrated, CalibrationParams, DatasetFrames, FrameSource, Pipeline, TrainOptions,
};

use crate::detection_run::{check_inputs, thread_pool};
use crate::progress::{counter, progress_bar};

/// Arguments of `pomona train`.
#[derive(Debug, Clone, clap::Args)]
pub struct TrainArgs {
    /// Pipeline (detection method) to train, e.g. `shape-fit`.
    #[arg(long, value_name = "NAME")]
    pub pipeline: String,
    /// Labelled dataset folder (frames with truth/<frame>.json are used); repeat for several.
    #[arg(long = "data", value_name = "DIR", required = true)]
    pub data: Vec<PathBuf>,
    /// Where to write the model file (JSON).
    #[arg(long, value_name = "MODEL")]
    pub out: PathBuf,
    /// Seed of every random choice in training (sampling, folds, consensus).
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// Cross-validation folds of the classifier's grid search.
    #[arg(long, value_name = "K", default_value_t = 5,
          value_parser = clap::value_parser!(u64).range(2..=100))]
    pub folds: u64,
    /// Search LIBSVM's full (C, γ) grid instead of the pipeline's narrower default (slow).
    #[arg(long)]
    pub full_grid: bool,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Folds of the confidence calibration (0: none, the model reports raw scores only). Each
    /// fold trains a model on the other folds and detects on it; the held-out detections fit
    /// the score → confidence map and the operating threshold stored in the model.
    #[arg(long, value_name = "K", default_value_t = 3,
          value_parser = clap::value_parser!(u64).range(0..=100))]
    pub calibration_folds: u64,
    /// Fit the confidence to the held-out detections' geometric cues beside their score
    /// (coverage of the disc, depth, seen curvature, elongation; as `pomona calibrate --cues`),
    /// which can reorder detections; without it, Platt's sigmoid of the score. The cues are
    /// only as general as the cameras of the training frames (docs/results.md).
    #[arg(long)]
    pub cues: bool,
    /// Choose the operating confidence as the lowest reaching this held-out precision (0–1]
    /// instead of the one with the best F1.
    #[arg(long, value_name = "P")]
    pub operating_precision: Option<f64>,
    /// Override a training parameter of the pipeline, KEY=VALUE (dotted path); repeat.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<pomona::ParamOverride>,
}

impl TrainArgs {
    /// The pipeline-independent training options.
    pub fn options(&self) -> TrainOptions {
        TrainOptions {
            seed: self.seed,
            folds: self.folds as usize,
            full_grid: self.full_grid,
        }
    }

    /// The confidence calibration options.
    pub fn calibration(&self) -> CalibrationParams {
        CalibrationParams {
            folds: self.calibration_folds as usize,
            cues: self.cues,
            operating_point: operating_point(self.operating_precision),
            ..CalibrationParams::default()
        }
    }
}

/// The operating point of `--operating-precision P`: the lowest confidence reaching precision P,
/// or the best F1 without it.
pub fn operating_point(precision: Option<f64>) -> OperatingPoint {
    precision.map_or(OperatingPoint::MaxF1, OperatingPoint::Precision)
}

/// What a training run did.
#[derive(Debug, Clone, PartialEq)]
pub struct TrainSummary {
    /// Pipeline name.
    pub pipeline: String,
    /// Labelled frames trained on.
    pub frames: usize,
    /// Wall time of training, seconds.
    pub seconds: f64,
    /// Support vectors of the trained classifier.
    pub support_vectors: usize,
}

/// Opens `data` folders as one lazily loaded frame source, checking each has the images `pipeline` needs.
///
/// # Errors
/// A dataset that cannot be opened (naming it), colour or depth missing for a pipeline that needs it, or no
/// frame with truth.
pub fn open_frames(pipeline: &dyn Pipeline, data: &[PathBuf]) -> Result<DatasetFrames> {
    let mut datasets = Vec::with_capacity(data.len());
    for dir in data {
        let ds =
            Dataset::open(dir).with_context(|| format!("cannot open dataset {}", dir.display()))?;
        check_inputs(pipeline, &ds)?;
        datasets.push(ds);
    }
    let frames = DatasetFrames::new(datasets);
    if frames.is_empty() {
        let dirs: Vec<String> = data.iter().map(|d| d.display().to_string()).collect();
        bail!(
            "no frame has a truth file (truth/<frame>.json) in {}; training, calibrating and \
             testing need labelled frames",
            dirs.join(", ")
        );
    }
    Ok(frames)
}

/// Runs `pomona train` with the registered pipelines.
///
/// # Errors
/// See [`run_with`].
pub fn run(args: &TrainArgs) -> Result<()> {
    run_with(&pomona::pipelines(), args).map(|_| ())
}

/// Runs `pomona train` choosing the pipeline from `pipelines` (tests pass their own).
///
/// # Errors
/// Unknown pipeline (listing the known ones), unreadable data, training failures, an unwritable
/// model file (naming it).
pub fn run_with(pipelines: &[Box<dyn Pipeline>], args: &TrainArgs) -> Result<TrainSummary> {
    let found = pomona::find_pipeline(pipelines, &args.pipeline)?;
    let configured = crate::params::configured(found, &args.set)?;
    let pipeline = configured.as_deref().unwrap_or(found);
    let frames = open_frames(pipeline, &args.data)?;
    let mut calibration = args.calibration();
    // Held-out detections are judged as `pomona eval` judges them on this data.
    calibration.radius_fraction_2d = EvalConfig::default()
        .for_data(frames.has_depth())
        .radius_fraction_2d;
    if calibration.radius_fraction_2d.is_some() && calibration.folds > 0 {
        eprintln!("note: the data has no depth, so calibration matches detections in the image");
    }
    let pool = thread_pool(args.threads.map(|n| n as usize))?;
    let bar = progress_bar(frames.len(), "training");
    let started = Instant::now();
    let progress = counter(&bar);
    let trained = pool
        .install(|| train_calibrated(pipeline, &frames, &args.options(), &calibration, &progress))
        .with_context(|| format!("training `{}`", pipeline.name()))?;
    let model = trained.model;
    let seconds = started.elapsed().as_secs_f64();
    bar.finish_and_clear();
    model.save(&args.out)?;
    let summary = TrainSummary {
        pipeline: pipeline.name().to_owned(),
        frames: frames.len(),
        seconds,
        support_vectors: model.svm.n_support(),
    };
    // Methods without an SVM (color-contour's perceptron) store an empty one: say nothing of it.
    let classifier = match summary.support_vectors {
        0 => String::new(),
        n => format!(
            " The classifier keeps {n} support vectors (γ = {:.4}).",
            model.svm.gamma
        ),
    };
    println!(
        "Trained `{}` on {} labelled frame(s) from {} dataset(s) in {:.1} s ({:.0} ms/frame; \
         seed {}, {}-fold cross-validation{}).{classifier} Model written to {}.",
        summary.pipeline,
        summary.frames,
        args.data.len(),
        seconds,
        1e3 * seconds / summary.frames.max(1) as f64,
        args.seed,
        args.folds,
        if args.full_grid { ", full grid" } else { "" },
        args.out.display()
    );
    match &model.calibration {
        Some(c) => println!(
            "Confidence calibrated on {} held-out detections ({} true, {} folds): {c}; \
             `pomona detect` keeps detections at or above it by default.",
            c.evidence.detections, c.evidence.true_positives, args.calibration_folds,
        ),
        None => println!(
            "No confidence calibration ({}): detections carry raw scores only.",
            trained.not_calibrated.as_deref().unwrap_or("none fitted")
        ),
    }
    Ok(summary)
}
