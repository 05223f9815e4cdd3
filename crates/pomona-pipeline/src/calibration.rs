//! Training with a calibrated confidence and an operating threshold, for any pipeline.
//!
//! A detector's raw score is only meaningful relative to the data it was trained on. To give
//! every model a confidence whose threshold means the same everywhere, [`train_calibrated`]
//! cross-fits: the labelled frames are split into `folds` parts (seeded shuffle); for each part a
//! model is trained on the other parts and run on it, and every held-out detection is labelled
//! true or false by matching it to the truth with the evaluation's rules
//! ([`pomona_eval::match_frame`]: 50 mm centre tolerance, fruit under 50 % visible ignored). A
//! [`ScoreCalibration`] (Platt sigmoid + operating confidence) is fitted to the pooled held-out
//! detections, and the model trained on *all* frames carries it. Held-out, because a model's
//! scores on its own training frames are over-confident.
//!
//! Frames whose truth is incomplete (`"complete": false`) contribute their true detections and
//! their findable fruit, but not their unmatched detections: those may be unannotated fruit.
//!
//! Caveat, written down: the final model is retrained on all frames, and its classifier's grid
//! search may settle on slightly different hyperparameters than the fold models; the calibration
//! assumes their score scales agree (as LIBSVM's own Platt scaling does with its internal
//! cross-validation).
//!
//! [`CalibratedDetector`] wraps a loaded detector and fills each detection's `confidence`;
//! [`load_detector`] is what every caller should use to turn a model file into a detector.

use pomona_core::{Detection, RgbdFrame};
use pomona_eval::{match_frame, DetectionOutcome, EvalConfig};
use pomona_learn::{DetectionCues, ModelFile, OperatingPoint, ScoreCalibration};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::{
    detection_cues, Detector, FrameSource, LabelledFrame, Pipeline, PipelineError, StageTimings,
    TrainOptions,
};

/// Fruit radii round a detection's centre over which a cue calibration measures the seen
/// curvature (shape-fit's built-in double-curvature check uses the same).
pub const CUE_CURVATURE_PATCH_RADII: f64 = 1.2;

/// How the confidence calibration is fitted.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CalibrationParams {
    /// Cross-fitting folds (0 = no calibration: the model reports raw scores only).
    pub folds: usize,
    /// Largest centre distance, metres, at which a held-out detection counts as true.
    pub tolerance_m: f64,
    /// Truth fruit less visible than this are neither findable nor false when detected.
    pub min_visibility: f64,
    /// When set, held-out detections are matched in the image instead, as
    /// [`EvalConfig::radius_fraction_2d`] (`tolerance_m` then unused).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_fraction_2d: Option<f64>,
    /// How the operating confidence is chosen.
    pub operating_point: OperatingPoint,
    /// Fit the confidence to the detections' geometric cues beside their score
    /// ([`pomona_learn::CueLogistic`]) instead of to the score alone.
    #[serde(default)]
    pub cues: bool,
}

impl Default for CalibrationParams {
    fn default() -> Self {
        let eval = EvalConfig::default();
        Self {
            folds: 3,
            tolerance_m: eval.tolerance_m,
            min_visibility: eval.min_visibility,
            radius_fraction_2d: eval.radius_fraction_2d,
            operating_point: OperatingPoint::MaxF1,
            cues: false,
        }
    }
}

/// A detector whose detections carry the calibrated `confidence` of their score.
pub struct CalibratedDetector {
    inner: Box<dyn Detector>,
    calibration: ScoreCalibration,
}

impl CalibratedDetector {
    /// Wraps `inner` with `calibration`.
    pub fn new(inner: Box<dyn Detector>, calibration: ScoreCalibration) -> Self {
        Self { inner, calibration }
    }
}

impl Detector for CalibratedDetector {
    fn pipeline(&self) -> &'static str {
        self.inner.pipeline()
    }

    fn detect(
        &self,
        frame: &RgbdFrame,
        timings: &mut StageTimings,
    ) -> Result<Vec<Detection>, PipelineError> {
        let mut detections = self.inner.detect(frame, timings)?;
        let patch = self.calibration.cues.map(|c| c.curvature_patch_radii);
        let started = std::time::Instant::now();
        for d in &mut detections {
            let cues = cues_of(d, frame, patch);
            d.confidence = Some(self.calibration.confidence_of(&cues));
        }
        if patch.is_some() {
            // Measuring the cues takes time worth seeing; the sigmoid alone does not.
            timings.add("confidence", started.elapsed());
        }
        Ok(detections)
    }

    fn operating_confidence(&self) -> Option<f64> {
        Some(self.calibration.operating_confidence)
    }
}

/// The detector of `model`, with confidences when the model carries a calibration.
///
/// # Errors
/// As [`Pipeline::load`].
pub fn load_detector(
    pipeline: &dyn Pipeline,
    model: &ModelFile,
) -> Result<Box<dyn Detector>, PipelineError> {
    let inner = pipeline.load(model)?;
    Ok(match model.calibration {
        Some(c) => Box::new(CalibratedDetector::new(inner, c)),
        None => inner,
    })
}

/// A view of some frames of another source, by index.
struct FrameSubset<'a> {
    source: &'a dyn FrameSource,
    indices: Vec<usize>,
}

impl FrameSubset<'_> {
    /// The index in the source of the subset's frame `i`.
    fn source_index(&self, i: usize) -> Result<usize, PipelineError> {
        self.indices
            .get(i)
            .copied()
            .ok_or_else(|| PipelineError::InvalidParameter {
                name: "frame index".into(),
                reason: format!(
                    "{i} is past the {} frames of the subset",
                    self.indices.len()
                ),
            })
    }
}

impl FrameSource for FrameSubset<'_> {
    fn len(&self) -> usize {
        self.indices.len()
    }

    fn load(&self, i: usize) -> Result<LabelledFrame, PipelineError> {
        self.source.load(self.source_index(i)?)
    }

    fn truth(&self, i: usize) -> Result<pomona_core::FrameTruth, PipelineError> {
        self.source.truth(self.source_index(i)?)
    }
}

/// Fold (0-based) of each of `n` frames: a seeded shuffle dealt round-robin, so fold sizes
/// differ by at most one.
fn fold_of_frames(n: usize, folds: usize, seed: u64) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xCA11_B4A7_E000_0000);
    order.shuffle(&mut rng);
    let mut fold = vec![0; n];
    for (rank, &i) in order.iter().enumerate() {
        fold[i] = rank % folds;
    }
    fold
}

/// The cues of `detection` in `frame` with its curvature measured over `curvature_patch_radii`
/// fruit radii, or only its score when that is `None` (a calibration by the score alone).
fn cues_of(
    detection: &Detection,
    frame: &RgbdFrame,
    curvature_patch_radii: Option<f64>,
) -> DetectionCues {
    match curvature_patch_radii {
        Some(patch) => detection_cues(detection, frame, patch),
        None => DetectionCues::score_only(detection.score),
    }
}

/// Held-out evidence of one frame.
struct HeldOut {
    /// `(cues, is_true)` per detection whose truth status is known (only the score is measured
    /// unless the calibration fits cues).
    labelled: Vec<(DetectionCues, bool)>,
    /// Truth fruit that could have been found.
    findable: usize,
    /// Whether the frame's truth is complete.
    complete: bool,
}

/// Labels one frame's held-out detections by matching them to its truth.
fn held_out_labels(
    frame: &LabelledFrame,
    detections: &[Detection],
    params: &CalibrationParams,
) -> HeldOut {
    let config = EvalConfig {
        tolerance_m: params.tolerance_m,
        min_visibility: params.min_visibility,
        radius_fraction_2d: params.radius_fraction_2d,
        ..EvalConfig::default()
    };
    let m = match_frame(&frame.truth, detections, frame.frame.camera(), &config);
    let patch = params.cues.then_some(CUE_CURVATURE_PATCH_RADII);
    let measured = |d: &Detection| cues_of(d, &frame.frame, patch);
    let labelled = detections
        .iter()
        .zip(&m.detections)
        .filter_map(|(d, outcome)| match outcome {
            DetectionOutcome::TruePositive { .. } => Some((measured(d), true)),
            DetectionOutcome::FalsePositive if frame.truth.complete => Some((measured(d), false)),
            _ => None,
        })
        .collect();
    HeldOut {
        labelled,
        findable: m.counted_truth(),
        complete: frame.truth.complete,
    }
}

/// The held-out evidence of `frames`' frames `indices` under `detector`, in their order;
/// `frame_done` is called after each frame.
fn held_out(
    detector: &dyn Detector,
    frames: &dyn FrameSource,
    indices: &[usize],
    params: &CalibrationParams,
    frame_done: &(dyn Fn() + Sync),
) -> Result<Vec<HeldOut>, PipelineError> {
    indices
        .par_iter()
        .map(|&i| {
            let frame = frames.load(i)?;
            let detections = detector.detect(&frame.frame, &mut StageTimings::default())?;
            let h = held_out_labels(&frame, &detections, params);
            frame_done();
            Ok(h)
        })
        .collect()
}

/// A trained model and, when it carries no calibration, why.
#[derive(Debug, Clone)]
pub struct CalibratedTraining {
    /// The model trained on all frames (with `calibration` set unless `not_calibrated`).
    pub model: ModelFile,
    /// Why the model has no calibration: turned off, or incomplete truth left no held-out
    /// detection known to be false.
    pub not_calibrated: Option<String>,
}

/// Trains `pipeline` on `frames` and, unless `params.folds` is 0, attaches a
/// [`ScoreCalibration`] fitted on cross-fitted held-out detections (see the module docs).
/// When incomplete truth leaves no held-out detection known to be false, the model stays
/// uncalibrated and [`CalibratedTraining::not_calibrated`] says so. `progress` receives
/// (training frames processed, total) over all the training passes.
///
/// # Errors
/// Training or detection errors of the pipeline; [`PipelineError::NotEnoughTrainingData`] when
/// there are fewer than two frames or the held-out detections cannot be calibrated (no true
/// or no false detection, or scores that do not rank true above false).
pub fn train_calibrated(
    pipeline: &dyn Pipeline,
    frames: &dyn FrameSource,
    options: &TrainOptions,
    params: &CalibrationParams,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<CalibratedTraining, PipelineError> {
    if params.folds == 0 {
        return Ok(CalibratedTraining {
            model: pipeline.train(frames, options, progress)?,
            not_calibrated: Some("calibration was turned off (0 folds)".into()),
        });
    }
    let n = frames.len();
    let not_enough = |reason: String| PipelineError::NotEnoughTrainingData {
        pipeline: pipeline.name(),
        reason,
    };
    // Fewer frames than folds: one frame per fold (leave-one-frame-out).
    let folds = params.folds.min(n);
    if folds < 2 {
        return Err(not_enough(format!(
            "confidence calibration needs at least 2 folds of labelled frames, got {n} frame(s) \
             and {} fold(s); set 0 calibration folds for none",
            params.folds
        )));
    }
    let fold = fold_of_frames(n, folds, options.seed);
    // Training passes: each fold model sees n − |fold| frames, the final one n.
    let total = (folds - 1) * n + n;
    let mut done = 0;
    let mut evidence = Evidence::over(n);
    for k in 0..folds {
        let (held, train): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| fold[i] == k);
        let train_set = FrameSubset {
            source: frames,
            indices: train,
        };
        let offset = done;
        let fold_options = TrainOptions {
            seed: options.seed.wrapping_add(1 + k as u64),
            ..*options
        };
        let model = pipeline.train(&train_set, &fold_options, &|d, _| {
            progress(offset + d, total);
        })?;
        done += train_set.len();
        let detector = pipeline.load(&model)?;
        evidence.add(held_out(&*detector, frames, &held, params, &|| {})?);
    }
    let offset = done;
    let mut model = pipeline.train(frames, options, &|d, _| progress(offset + d, total))?;
    match evidence.calibration(params) {
        Ok(calibration) => {
            model.calibration = Some(calibration);
            Ok(CalibratedTraining {
                model,
                not_calibrated: None,
            })
        }
        Err(Uncalibrated::NoFalseDetection(why)) => Ok(CalibratedTraining {
            model,
            not_calibrated: Some(why),
        }),
        Err(Uncalibrated::Unfit(e)) => Err(not_enough(format!(
            "cannot calibrate confidences on the held-out detections of {folds} folds: {e}"
        ))),
    }
}

/// Labelled detections pooled over frames a model did not train on.
struct Evidence {
    labelled: Vec<(DetectionCues, bool)>,
    truth_fruit: usize,
    incomplete: usize,
    frames: usize,
}

/// Why no calibration came out of the evidence.
enum Uncalibrated {
    /// Incomplete truth left no detection known to be false (the message says so).
    NoFalseDetection(String),
    /// The fit failed.
    Unfit(pomona_learn::LearnError),
}

impl Evidence {
    /// No evidence yet, to come from `frames` frames.
    fn over(frames: usize) -> Self {
        Self {
            labelled: Vec::new(),
            truth_fruit: 0,
            incomplete: 0,
            frames,
        }
    }

    /// Adds frames' held-out evidence.
    fn add(&mut self, per_frame: Vec<HeldOut>) {
        for h in per_frame {
            self.labelled.extend(h.labelled);
            self.truth_fruit += h.findable;
            self.incomplete += usize::from(!h.complete);
        }
    }

    fn calibration(self, params: &CalibrationParams) -> Result<ScoreCalibration, Uncalibrated> {
        let (cues, is_true): (Vec<DetectionCues>, Vec<bool>) = self.labelled.into_iter().unzip();
        if !is_true.contains(&false) && self.incomplete > 0 {
            // Every detection matched an annotated fruit and the rest may be unannotated
            // fruit: nothing tells true from false, so the model stays uncalibrated.
            return Err(Uncalibrated::NoFalseDetection(format!(
                "no held-out detection is known to be false ({} of {} frames have incomplete \
                 truth, where unmatched detections may be unannotated fruit); the model reports \
                 raw scores",
                self.incomplete, self.frames
            )));
        }
        let fitted = if params.cues {
            ScoreCalibration::fit_with_cues(
                &cues,
                &is_true,
                self.truth_fruit,
                params.operating_point,
                CUE_CURVATURE_PATCH_RADII,
            )
        } else {
            let scores: Vec<f64> = cues.iter().map(|c| c.score).collect();
            ScoreCalibration::fit(&scores, &is_true, self.truth_fruit, params.operating_point)
        };
        fitted.map_err(Uncalibrated::Unfit)
    }
}

/// Refits `model`'s confidence calibration on labelled `frames` it was not trained on: the
/// model's detector (without its old calibration) runs on every frame, each detection is
/// labelled by the evaluation's rules, and a new [`ScoreCalibration`] (with cues when
/// `params.cues`) replaces the old one. The classifier and stage parameters are untouched.
/// `progress` receives (frames done, total).
///
/// # Errors
/// Detection errors of the pipeline; [`PipelineError::NotEnoughTrainingData`] when the frames
/// leave no detection known to be false or the detections cannot be calibrated.
pub fn recalibrate(
    pipeline: &dyn Pipeline,
    model: &ModelFile,
    frames: &dyn FrameSource,
    params: &CalibrationParams,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<ModelFile, PipelineError> {
    let detector = pipeline.load(model)?;
    let n = frames.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let all: Vec<usize> = (0..n).collect();
    let mut evidence = Evidence::over(n);
    evidence.add(held_out(&*detector, frames, &all, params, &|| {
        progress(
            1 + done.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            n,
        );
    })?);
    let not_enough = |reason: String| PipelineError::NotEnoughTrainingData {
        pipeline: pipeline.name(),
        reason,
    };
    let calibration = evidence.calibration(params).map_err(|e| match e {
        Uncalibrated::NoFalseDetection(why) => not_enough(why),
        Uncalibrated::Unfit(e) => not_enough(format!(
            "cannot calibrate confidences on the detections of {n} frames: {e}"
        )),
    })?;
    Ok(ModelFile {
        calibration: Some(calibration),
        ..model.clone()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folds_are_balanced_deterministic_and_seeded() {
        let f = fold_of_frames(10, 3, 7);
        assert_eq!(f, fold_of_frames(10, 3, 7));
        assert_ne!(f, fold_of_frames(10, 3, 8));
        let mut sizes = [0; 3];
        for &k in &f {
            sizes[k] += 1;
        }
        assert_eq!(sizes.iter().sum::<usize>(), 10);
        assert!(sizes.iter().all(|&s| (3..=4).contains(&s)), "{sizes:?}");
    }
}
