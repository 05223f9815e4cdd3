//! Detect on labelled frames and score the detections against their truth: the loop every
//! experiment, test and benchmark of a detector runs, written once.
//!
//! Frames are loaded one per task and processed in parallel (results in frame order, so the
//! report does not depend on the number of threads); per-stage times are merged over frames.

use std::time::{Duration, Instant};

use pomona_eval::{evaluate, EvalConfig, EvalReport, FrameInput};
use rayon::prelude::*;

use crate::{Detector, FrameSource, PipelineError, StageTimings};

/// What [`detect_and_evaluate`] found.
#[derive(Debug, Clone)]
pub struct DetectionEvaluation {
    /// AP, precision/recall, localisation and size errors over all frames.
    pub report: EvalReport,
    /// Each frame's truth and detections, in frame order (for per-frame checks or printing).
    pub frames: Vec<FrameInput>,
    /// Stage times merged over frames.
    pub timings: StageTimings,
    /// Sum over frames of the time `Detector::detect` took (loading excluded).
    pub detect_time: Duration,
}

impl DetectionEvaluation {
    /// Mean detection milliseconds per frame (`None` without frames).
    pub fn ms_per_frame(&self) -> Option<f64> {
        let n = self.frames.len();
        (n > 0).then(|| 1e3 * self.detect_time.as_secs_f64() / n as f64)
    }
}

/// Runs `detector` on every frame of `frames` and evaluates the detections with `config`
/// (2D-box truth is projected with the first frame's camera).
///
/// # Errors
/// A frame that will not load, a detection error, or an evaluation error (for example
/// [`pomona_eval::EvalError::MissingConfidence`] when `config` thresholds confidence and the
/// detector has no calibration).
pub fn detect_and_evaluate(
    detector: &dyn Detector,
    frames: &dyn FrameSource,
    config: &EvalConfig,
) -> Result<DetectionEvaluation, PipelineError> {
    let per_frame = (0..frames.len())
        .into_par_iter()
        .map(|i| {
            let labelled = frames.load(i)?;
            let mut timings = StageTimings::default();
            let started = Instant::now();
            let detections = detector.detect(&labelled.frame, &mut timings)?;
            let elapsed = started.elapsed();
            let camera = *labelled.frame.camera();
            let input = FrameInput {
                frame: labelled.name,
                truth: labelled.truth,
                detections,
            };
            Ok((input, timings, elapsed, camera))
        })
        .collect::<Result<Vec<_>, PipelineError>>()?;
    let camera = per_frame.first().map(|f| f.3);
    let mut timings = StageTimings::default();
    let mut detect_time = Duration::ZERO;
    let mut inputs = Vec::with_capacity(per_frame.len());
    for (input, t, elapsed, _) in per_frame {
        timings.merge(&t);
        detect_time += elapsed;
        inputs.push(input);
    }
    let report = match camera {
        Some(camera) => evaluate(&inputs, &camera, config)?,
        None => {
            return Err(PipelineError::InvalidParameter {
                name: "frames".into(),
                reason: "no frames to evaluate on".into(),
            })
        }
    };
    Ok(DetectionEvaluation {
        report,
        frames: inputs,
        timings,
        detect_time,
    })
}
