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
use pomona_core::{Detection, RgbdFrame};
use pomona_pipeline::{Detector, ModelFile, Pipeline, StageTimings};
use rayon::prelude::*;

use crate::params::{self, ParamOverride};

/// Where a model came from, for messages and reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ModelSource {
    /// A model file given with `--model`.
    File(std::path::PathBuf),
    /// The model compiled into the binary.
    BuiltIn,
}

impl std::fmt::Display for ModelSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::File(p) => write!(f, "{}", p.display()),
            Self::BuiltIn => f.write_str("the built-in model"),
        }
    }
}

/// Reads the model for `pipeline`: `model` when given, otherwise the pipeline's built-in one
/// (its depth-only built-in model when the data has no colour and the pipeline ships one).
///
/// # Errors
/// An unreadable model or one made for another pipeline or format version (naming the file), or
/// no `model` for a pipeline without a built-in one.
pub fn read_model(
    pipeline: &dyn Pipeline,
    model: Option<&Path>,
    has_color: bool,
) -> Result<(ModelFile, ModelSource)> {
    let name = pipeline.name();
    match model {
        Some(path) => {
            let m = ModelFile::load(path, name)?;
            Ok((m, ModelSource::File(path.to_owned())))
        }
        None => {
            let built_in = if has_color {
                pipeline.default_model()
            } else {
                pipeline
                    .default_depth_only_model()
                    .or_else(|| pipeline.default_model())
            };
            let Some(text) = built_in else {
                bail!(
                    "pipeline `{name}` has no built-in model yet; train one with \
                     `pomona train --pipeline {name} --data DIR --out MODEL` and pass it with --model MODEL"
                );
            };
            let label = format!("<built-in model of {name}>");
            let m = ModelFile::from_json(text, Path::new(&label), name)?;
            Ok((m, ModelSource::BuiltIn))
        }
    }
}

/// Builds the detector of `model`, after applying `--set` overrides to its stage parameters; its
/// detections carry a calibrated confidence when the model has a calibration.
///
/// # Errors
/// A bad override (unknown key, wrong type) or stage parameters the pipeline rejects.
pub fn build_detector(
    pipeline: &dyn Pipeline,
    mut model: ModelFile,
    source: &ModelSource,
    overrides: &[ParamOverride],
) -> Result<Box<dyn Detector>> {
    let what = format!("the model of `{}` ({source})", pipeline.name());
    params::apply(&mut model.stage_params, overrides, &what)?;
    pomona_pipeline::load_detector(pipeline, &model).with_context(|| {
        format!(
            "cannot build a `{}` detector from {source}",
            pipeline.name()
        )
    })
}

/// The confidence threshold of a detection run: `--min-confidence` when given (checked against
/// the model: an uncalibrated model has no confidences to threshold), else the model's operating
/// confidence, else none (every detection is kept, as for models trained before calibration).
///
/// # Errors
/// `--min-confidence` outside `[0, 1]` or given for a model without calibration.
pub fn min_confidence(detector: &dyn Detector, requested: Option<f64>) -> Result<Option<f64>> {
    match (requested, detector.operating_confidence()) {
        (Some(c), _) if !(0.0..=1.0).contains(&c) => {
            bail!("--min-confidence must be in [0, 1], got {c}")
        }
        (Some(_), None) => bail!(
            "--min-confidence needs a model with a confidence calibration; this model has none \
             (retrain it with `pomona train`, which calibrates by default)"
        ),
        (Some(c), Some(_)) => Ok(Some(c)),
        (None, operating) => Ok(operating),
    }
}

/// Refuses a colour-less dataset for a pipeline that needs colour, with a message saying so.
///
/// # Errors
/// As described.
pub fn check_color(pipeline: &dyn Pipeline, has_color: bool, data: &Path) -> Result<()> {
    if pipeline.needs_color() && !has_color {
        bail!(
            "{} has no colour images (no color/ folder), and pipeline `{}` needs colour; \
             use a dataset with colour or a depth-only pipeline",
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

/// Runs `detector` on frames `0..n` in parallel: `load(i)` reads frame `i` with a name for
/// messages and anything else the caller wants back with the result (such as its truth),
/// `done(i, &result)` consumes its result (for example writes its file) and `tick` is called once
/// per finished frame (progress). Results are also returned in frame order.
///
/// # Errors
/// The first failing frame in frame order: loading, detection (naming the frame) or `done`.
pub fn detect_frames<X, L, D>(
    detector: &dyn Detector,
    n: usize,
    load: L,
    done: D,
    tick: &(dyn Fn() + Sync),
) -> Result<(Vec<(FrameResult, X)>, RunTotals)>
where
    X: Send,
    L: Fn(usize) -> Result<(String, RgbdFrame, X)> + Sync,
    D: Fn(usize, &FrameResult) -> Result<()> + Sync,
{
    let results: Vec<Result<(FrameResult, X)>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let (name, frame, extra) = load(i)?;
            let mut timings = StageTimings::default();
            let start = Instant::now();
            let detections = detector
                .detect(&frame, &mut timings)
                .with_context(|| format!("detecting in frame {name}"))?;
            let result = FrameResult {
                detections,
                timings,
                elapsed: start.elapsed(),
            };
            drop(frame);
            done(i, &result)?;
            tick();
            Ok((result, extra))
        })
        .collect();
    let mut totals = RunTotals::default();
    let mut out = Vec::with_capacity(n);
    for r in results {
        let (r, extra) = r?;
        totals.frames += 1;
        totals.detections += r.detections.len();
        totals.timings.merge(&r.timings);
        totals.detect_time += r.elapsed;
        out.push((r, extra));
    }
    Ok((out, totals))
}
