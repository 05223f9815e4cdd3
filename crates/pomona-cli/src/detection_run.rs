//! What `detect`, `experiment` and `demo` share: choosing the model, checking the data suits the
//! pipeline, and running a detector over many frames in parallel.
//!
//! Frames are loaded inside the parallel loop, one per task, so memory stays flat however large
//! the dataset; each frame's result is handed to a callback (which writes its file) as soon as it
//! is ready. Detection time is measured per frame around `Detector::detect` only (not loading or
//! writing), so the reported ms/frame is single-threaded cost and does not depend on `--threads`.

use std::path::Path;
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context, Result};
use pomona::{Detection, Detector, ModelInfo, ParamOverride, Pipeline, RgbdFrame, StageTimings};
use pomona_io::Dataset;
use rayon::prelude::*;

/// The detector of `pipeline`: the model file `model` when given, otherwise the pipeline's
/// built-in model(s) (the depth-only one for frames without colour), with `overrides` applied to
/// the stage parameters; its detections carry a calibrated confidence when the model has a
/// calibration.
///
/// # Errors
/// An unreadable model or one made for another pipeline or format version (naming the file), no
/// `model` for a pipeline without a built-in one, a bad override (unknown key, wrong type) or
/// stage parameters the pipeline rejects.
pub fn load_detector(
    pipeline: &dyn Pipeline,
    model: Option<&Path>,
    overrides: &[ParamOverride],
) -> Result<Detector> {
    let mut builder = Detector::builder_for(pipeline).overrides(overrides.iter().cloned());
    if let Some(path) = model {
        builder = builder.model_file(path);
    }
    builder.build().map_err(with_model_hint)
}

/// A library error as the CLI reports it: a pipeline without a built-in model is told which
/// commands make one and which option passes it.
pub fn with_model_hint(e: pomona::Error) -> anyhow::Error {
    match e {
        pomona::Error::NoBuiltInModel { pipeline } => anyhow!(
            "pipeline `{pipeline}` has no built-in model yet; train one with \
             `pomona train --pipeline {pipeline} --data DIR --out MODEL` and pass it with --model MODEL"
        ),
        other => other.into(),
    }
}

/// The threshold of a detection run: `--min-confidence` when given, else the model's operating
/// confidence, else score ≥ 0 ([`Detector::keep_rule_for`]).
///
/// # Errors
/// `--min-confidence` outside `[0, 1]`, or above 0 for a model without calibration.
pub fn keep_rule(detector: &Detector, requested: Option<f64>) -> Result<pomona::KeepRule> {
    detector
        .keep_rule_for(requested)
        .context("bad --min-confidence")
}

/// Checks that the dataset has the images the pipeline needs: colour for colour methods, depth
/// for every method but those that work from colour alone.
///
/// # Errors
/// Naming the dataset folder and what is missing.
pub fn check_inputs(pipeline: &dyn Pipeline, dataset: &Dataset) -> Result<()> {
    let data = dataset.root();
    if pipeline.needs_color() && !dataset.has_color() {
        bail!(
            "{} has no colour images (no color/ folder), and pipeline `{}` needs colour; \
             use a dataset with colour or a depth-only pipeline",
            data.display(),
            pipeline.name()
        );
    }
    if pipeline.needs_depth() && !dataset.has_depth() {
        bail!(
            "{} has no depth images (no depth/ folder), and pipeline `{}` needs depth; \
             on colour-only data use `color-contour`",
            data.display(),
            pipeline.name()
        );
    }
    Ok(())
}

/// A rayon pool of `threads` workers (`None`: one per core).
///
/// # Errors
/// If the pool cannot start.
pub fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        if n == 0 {
            bail!("--threads must be at least 1");
        }
        builder = builder.num_threads(n);
    }
    builder
        .build()
        .map_err(|e| anyhow!("cannot start {threads:?} worker threads: {e}"))
}

/// One frame's detections and costs.
#[derive(Debug, Clone)]
pub struct FrameResult {
    /// What the detector found.
    pub detections: Vec<Detection>,
    /// Per-stage times of this frame.
    pub timings: StageTimings,
    /// Wall time of `Detector::detect` on this frame.
    pub elapsed: Duration,
    /// The model that detected (the depth-only one for a frame without colour).
    pub model: ModelInfo,
}

/// Totals of a detection run.
#[derive(Debug, Clone, Default)]
pub struct RunTotals {
    /// Frames processed.
    pub frames: usize,
    /// Detections over all frames.
    pub detections: usize,
    /// Stage times merged over frames (in frame order, so stage order is deterministic).
    pub timings: StageTimings,
    /// Sum of per-frame detection times.
    pub detect_time: Duration,
}

impl RunTotals {
    /// Mean detection milliseconds per frame (`None` without frames).
    pub fn ms_per_frame(&self) -> Option<f64> {
        (self.frames > 0).then(|| 1e3 * self.detect_time.as_secs_f64() / self.frames as f64)
    }
}

/// A frame that could not be processed: its index and why.
#[derive(Debug)]
pub struct FrameFailure {
    /// Index of the frame in the run.
    pub index: usize,
    /// What went wrong (loading, detecting or the `done` callback), with context.
    pub error: anyhow::Error,
}

impl FrameFailure {
    /// The file at fault, when the error names one (a dataset file that would not load, or the
    /// recording a frame could not be decoded from).
    pub fn file(&self) -> Option<&Path> {
        self.error.chain().find_map(|cause| {
            cause
                .downcast_ref::<pomona_io::DatasetError>()
                .or_else(|| match cause.downcast_ref::<pomona::Error>() {
                    Some(pomona::Error::Dataset(e)) => Some(e),
                    _ => None,
                })
                .map(pomona_io::DatasetError::path)
                .or_else(|| {
                    cause
                        .downcast_ref::<pomona_recording::RecordingError>()
                        .map(pomona_recording::RecordingError::path)
                })
        })
    }
}

/// What a batch did: the frames done (in frame order, with what `load` returned beside each),
/// those that failed, and totals over the frames done.
#[derive(Debug)]
pub struct Batch<X> {
    /// Results of the frames that succeeded, in frame order.
    pub done: Vec<(usize, FrameResult, X)>,
    /// The frames that failed, in frame order.
    pub failed: Vec<FrameFailure>,
    /// Totals over `done`.
    pub totals: RunTotals,
}

impl<X> Batch<X> {
    /// Every frame's result, for callers that need all of them (evaluation over a whole set).
    ///
    /// # Errors
    /// The first failed frame's error.
    pub fn all_or_first_error(self) -> Result<(Vec<(FrameResult, X)>, RunTotals)> {
        if let Some(first) = self.failed.into_iter().next() {
            return Err(first.error);
        }
        let done = self.done.into_iter().map(|(_, r, x)| (r, x)).collect();
        Ok((done, self.totals))
    }
}

/// Runs `detector` on frames `0..n` in parallel: `load(i)` reads frame `i` with a name for
/// messages and anything else the caller wants back with the result (such as its truth),
/// `done(i, &result)` consumes its result (for example writes its file) and `tick` is called once
/// per finished frame, failed or not (progress). A failing frame does not stop the others.
pub fn detect_frames<X, L, D>(
    detector: &Detector,
    n: usize,
    load: L,
    done: D,
    tick: &(dyn Fn() + Sync),
) -> Batch<X>
where
    X: Send,
    L: Fn(usize) -> Result<(String, RgbdFrame, X)> + Sync,
    D: Fn(usize, &FrameResult) -> Result<()> + Sync,
{
    let one = |i: usize| -> Result<(FrameResult, X)> {
        let (name, frame, extra) = load(i)?;
        let start = Instant::now();
        let (detections, timings) = detector
            .detect_with_timings(&frame)
            .with_context(|| format!("detecting in frame {name}"))?;
        let result = FrameResult {
            detections,
            timings,
            elapsed: start.elapsed(),
            model: detector.model_for(&frame).clone(),
        };
        drop(frame);
        done(i, &result)?;
        Ok((result, extra))
    };
    let results: Vec<Result<(FrameResult, X)>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let r = one(i);
            tick();
            r
        })
        .collect();
    let mut batch = Batch {
        done: Vec::with_capacity(n),
        failed: Vec::new(),
        totals: RunTotals::default(),
    };
    for (index, r) in results.into_iter().enumerate() {
        match r {
            Ok((r, extra)) => {
                batch.totals.frames += 1;
                batch.totals.detections += r.detections.len();
                batch.totals.timings.merge(&r.timings);
                batch.totals.detect_time += r.elapsed;
                batch.done.push((index, r, extra));
            }
            Err(error) => batch.failed.push(FrameFailure { index, error }),
        }
    }
    batch
}
