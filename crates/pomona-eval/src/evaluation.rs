//! Evaluating a set of frames: matching, pooling, AP, operating point and errors.
//!
//! Frames are passed in memory ([`FrameInput`]) rather than read here, so the same function
//! scores a whole dataset (`pomona eval`) or one test split of an experiment.

use std::collections::BTreeMap;

use pomona_core::{median, Detection, FrameTruth, PinholeCamera};

use crate::frame_matching::ranking_of;
use crate::report::{CenterError, DiameterError, FrameReport, MissedFruit, ScoreAndConfidence};
use crate::{
    match_frame, DetectionOutcome, EvalConfig, EvalError, EvalReport, FrameMatch, PrCurve,
    TruthStatus,
};

/// One frame to evaluate.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameInput {
    /// Frame stem.
    pub frame: String,
    /// Its ground truth.
    pub truth: FrameTruth,
    /// Its detections (empty when the detector found nothing or wrote no file).
    pub detections: Vec<Detection>,
}

fn mean(values: &[f64]) -> Option<f64> {
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

fn ratio(num: usize, den: usize) -> Option<f64> {
    (den > 0).then(|| num as f64 / den as f64)
}

/// Evaluates `frames` seen by `camera` (used to project detections for 2D-box truth).
///
/// # Errors
/// [`EvalError::InvalidParameter`] for an invalid `config`; [`EvalError::MissingConfidence`]
/// when `config` thresholds confidence and a detection has none.
pub fn evaluate(
    frames: &[FrameInput],
    camera: &PinholeCamera,
    config: &EvalConfig,
) -> Result<EvalReport, EvalError> {
    config.validate()?;
    if config.min_confidence.is_some() {
        if let Some(f) = frames
            .iter()
            .find(|f| f.detections.iter().any(|d| d.confidence.is_none()))
        {
            return Err(EvalError::MissingConfidence {
                frame: f.frame.clone(),
            });
        }
    }
    let mut tally = Tally::default();
    for input in frames {
        tally.add(input, camera, config);
    }
    Ok(tally.into_report(config))
}

/// The counted fruit of `input` that no detection at the threshold found in `m`.
fn missed_fruit(input: &FrameInput, m: &FrameMatch, config: &EvalConfig) -> Vec<MissedFruit> {
    let dets = &input.detections;
    input
        .truth
        .fruits
        .iter()
        .zip(&m.truth)
        .filter_map(|(fruit, status)| {
            let below_threshold = match *status {
                TruthStatus::Ignored => return None,
                TruthStatus::Found { by } if config.keeps(&dets[by]) => return None,
                TruthStatus::Found { by } => Some(ScoreAndConfidence {
                    score: dets[by].score,
                    confidence: dets[by].confidence,
                }),
                TruthStatus::Missed => None,
            };
            let nearest_detection_m = fruit.center_m.and_then(|c| {
                dets.iter()
                    .map(|d| (d.center_m - c).norm())
                    .min_by(f64::total_cmp)
            });
            Some(MissedFruit {
                id: fruit.id.clone(),
                kind: fruit.kind.clone(),
                below_threshold,
                nearest_detection_m,
            })
        })
        .collect()
}

/// Counts over frames, before they become a report.
#[derive(Default)]
struct Tally {
    per_frame: Vec<FrameReport>,
    /// Every matched or unmatched detection's score, confidence and whether it is a true
    /// positive (the PR curve ranks all of them, whatever the threshold: by confidence when
    /// every detection has one, else by score: `ranking_of`).
    scored: Vec<(f64, Option<f64>, bool)>,
    center_errors: Vec<f64>,
    center_errors_radii: Vec<f64>,
    diameter_errors: Vec<f64>,
    fruits: usize,
    ignored: usize,
    tp: usize,
    fp: usize,
    /// Frames whose truth is incomplete.
    incomplete: Vec<String>,
}

impl Tally {
    /// Matches one frame and adds its counts.
    fn add(&mut self, input: &FrameInput, camera: &PinholeCamera, config: &EvalConfig) {
        let m = match_frame(&input.truth, &input.detections, camera, config);
        let counted = m.counted_truth();
        let (mut tp, mut fp) = (0, 0);
        for (det, outcome) in input.detections.iter().zip(&m.detections) {
            match *outcome {
                DetectionOutcome::TruePositive {
                    center_error_m,
                    center_error_radii,
                    diameter_error_m,
                    ..
                } => {
                    self.scored.push((det.score, det.confidence, true));
                    if config.keeps(det) {
                        tp += 1;
                        self.center_errors.extend(center_error_m);
                        self.center_errors_radii.extend(center_error_radii);
                        self.diameter_errors.extend(diameter_error_m);
                    }
                }
                DetectionOutcome::FalsePositive => {
                    self.scored.push((det.score, det.confidence, false));
                    fp += usize::from(config.keeps(det));
                }
                DetectionOutcome::Ignored => {}
            }
        }
        if !input.truth.complete {
            self.incomplete.push(input.frame.clone());
        }
        self.fruits += counted;
        self.ignored += m.truth.len() - counted;
        self.tp += tp;
        self.fp += fp;
        self.per_frame.push(FrameReport {
            frame: input.frame.clone(),
            complete: input.truth.complete,
            fruits: counted,
            ignored: m.truth.len() - counted,
            detections: input.detections.len(),
            true_positives: tp,
            false_positives: fp,
            precision: if input.truth.complete {
                ratio(tp, tp + fp)
            } else {
                None
            },
            recall: ratio(tp, counted),
            missed: missed_fruit(input, &m, config),
        });
    }

    /// Why precision (and AP) cannot be measured: some truth is incomplete.
    fn incomplete_reason(&self) -> Option<String> {
        if self.incomplete.is_empty() {
            return None;
        }
        let shown: Vec<&str> = self.incomplete.iter().take(5).map(String::as_str).collect();
        let more = if self.incomplete.len() > 5 {
            ", ..."
        } else {
            ""
        };
        Some(format!(
            "{} frame(s) have incomplete truth (\"complete\": false), so unannotated fruit \
             would count as false positives: {}{more}",
            self.incomplete.len(),
            shown.join(", ")
        ))
    }

    /// The report, with a reason for every figure that is `None`.
    fn into_report(mut self, config: &EvalConfig) -> EvalReport {
        let mut null_reasons = BTreeMap::new();
        let incomplete = self.incomplete_reason();
        let precision = match &incomplete {
            Some(r) => {
                null_reasons.insert("precision".into(), r.clone());
                None
            }
            None => {
                let p = ratio(self.tp, self.tp + self.fp);
                if p.is_none() {
                    null_reasons.insert(
                        "precision".into(),
                        format!(
                            "no detection reaches the operating threshold ({})",
                            config.operating_point()
                        ),
                    );
                }
                p
            }
        };
        let curve = match (&incomplete, self.fruits) {
            (Some(r), _) => {
                null_reasons.insert("ap".into(), r.clone());
                None
            }
            (None, 0) => {
                null_reasons.insert("ap".into(), "no counted truth fruit".into());
                None
            }
            (None, n) => {
                let rank = ranking_of(self.scored.iter().map(|&(s, c, _)| (s, c)));
                let ranked: Vec<(f64, bool)> = rank
                    .into_iter()
                    .zip(self.scored.iter().map(|s| s.2))
                    .collect();
                Some(PrCurve::new(&ranked, n))
            }
        };
        let recall = ratio(self.tp, self.fruits);
        if recall.is_none() {
            null_reasons.insert("recall".into(), "no counted truth fruit".into());
        }
        let center_mean = mean(&self.center_errors);
        let center_median = median(&mut self.center_errors);
        let center_error_radii = config.radius_fraction_2d.map(|_| CenterError {
            mean: mean(&self.center_errors_radii),
            median: median(&mut self.center_errors_radii),
        });
        if center_error_radii.is_some_and(|e| e.median.is_none()) {
            null_reasons.insert(
                "center_error_radii".into(),
                "no true positive at the threshold".into(),
            );
        }
        if center_mean.is_none() {
            null_reasons.insert(
                "center_error_m".into(),
                if config.radius_fraction_2d.is_some() {
                    "a 2D evaluation measures the centre error in truth radii".into()
                } else {
                    "no true positive with a 3D truth centre at the threshold".into()
                },
            );
        }
        let diameter = mean(&self.diameter_errors);
        if diameter.is_none() {
            null_reasons.insert(
                "diameter_error_m".into(),
                "no true positive where both detection and truth have a diameter".into(),
            );
        }
        EvalReport {
            frames: self.per_frame.len(),
            fruits: self.fruits,
            ignored: self.ignored,
            tolerance_m: config.tolerance_m,
            ap_voc11: curve.as_ref().map(PrCurve::ap_voc11),
            ap: curve.as_ref().map(PrCurve::ap_all_points),
            precision,
            recall,
            threshold: config.threshold,
            min_confidence: config.min_confidence,
            radius_fraction_2d: config.radius_fraction_2d,
            center_error_m: CenterError {
                median: center_median,
                mean: center_mean,
            },
            center_error_radii,
            diameter_error_m: DiameterError { mean_abs: diameter },
            per_frame: self.per_frame,
            min_visibility: config.min_visibility,
            depth_range_m: config.depth_range_m,
            true_positives: self.tp,
            false_positives: self.fp,
            null_reasons,
            pr_curve: curve,
        }
    }
}
