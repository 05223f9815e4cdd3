//! Evaluating a set of frames: matching, pooling, AP, operating point and errors.
//!
//! Frames are passed in memory ([`FrameInput`]) rather than read here, so the same function
//! scores a whole dataset (`pomona eval`) or one test split of an experiment.

use std::collections::BTreeMap;

use pomona_core::{Detection, FrameTruth, PinholeCamera};

use crate::report::{CenterError, DiameterError, FrameReport};
use crate::{match_frame, DetectionOutcome, EvalConfig, EvalError, EvalReport, PrCurve};

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

fn median(values: &mut [f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    Some(if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    })
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
/// [`EvalError::InvalidParameter`] for an invalid `config`.
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
    let mut per_frame = Vec::with_capacity(frames.len());
    let mut scored = Vec::new();
    let mut center_errors = Vec::new();
    let mut diameter_errors = Vec::new();
    let (mut fruits, mut ignored, mut tp_total, mut fp_total) = (0, 0, 0, 0);
    let mut incomplete = Vec::new();

    for input in frames {
        let m = match_frame(&input.truth, &input.detections, camera, config);
        let counted = m.counted_truth();
        let (mut tp, mut fp) = (0, 0);
        for (det, outcome) in input.detections.iter().zip(&m.detections) {
            match *outcome {
                DetectionOutcome::TruePositive {
                    center_error_m,
                    diameter_error_m,
                    ..
                } => {
                    scored.push((det.score, true));
                    if config.keeps(det) {
                        tp += 1;
                        center_errors.extend(center_error_m);
                        diameter_errors.extend(diameter_error_m);
                    }
                }
                DetectionOutcome::FalsePositive => {
                    scored.push((det.score, false));
                    fp += usize::from(config.keeps(det));
                }
                DetectionOutcome::Ignored => {}
            }
        }
        if !input.truth.complete {
            incomplete.push(input.frame.clone());
        }
        fruits += counted;
        ignored += m.truth.len() - counted;
        tp_total += tp;
        fp_total += fp;
        per_frame.push(FrameReport {
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
        });
    }

    let mut null_reasons = BTreeMap::new();
    let precision_reason = if !incomplete.is_empty() {
        let shown: Vec<&str> = incomplete.iter().take(5).map(String::as_str).collect();
        let more = if incomplete.len() > 5 { ", ..." } else { "" };
        Some(format!(
            "{} frame(s) have incomplete truth (\"complete\": false), so unannotated fruit \
             would count as false positives: {}{more}",
            incomplete.len(),
            shown.join(", ")
        ))
    } else {
        None
    };
    let precision = match &precision_reason {
        Some(r) => {
            null_reasons.insert("precision".into(), r.clone());
            None
        }
        None => {
            let p = ratio(tp_total, tp_total + fp_total);
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
    let curve = match (&precision_reason, fruits) {
        (Some(r), _) => {
            null_reasons.insert("ap".into(), r.clone());
            None
        }
        (None, 0) => {
            null_reasons.insert("ap".into(), "no counted truth fruit".into());
            None
        }
        (None, n) => Some(PrCurve::new(&scored, n)),
    };
    let recall = ratio(tp_total, fruits);
    if recall.is_none() {
        null_reasons.insert("recall".into(), "no counted truth fruit".into());
    }
    let center_mean = mean(&center_errors);
    let center_median = median(&mut center_errors);
    if center_mean.is_none() {
        null_reasons.insert(
            "center_error_m".into(),
            "no true positive with a 3D truth centre at the threshold".into(),
        );
    }
    let diameter = mean(&diameter_errors);
    if diameter.is_none() {
        null_reasons.insert(
            "diameter_error_m".into(),
            "no true positive where both detection and truth have a diameter".into(),
        );
    }
    Ok(EvalReport {
        frames: frames.len(),
        fruits,
        ignored,
        tolerance_m: config.tolerance_m,
        ap_voc11: curve.as_ref().map(PrCurve::ap_voc11),
        ap: curve.as_ref().map(PrCurve::ap_all_points),
        precision,
        recall,
        threshold: config.threshold,
        min_confidence: config.min_confidence,
        center_error_m: CenterError {
            median: center_median,
            mean: center_mean,
        },
        diameter_error_m: DiameterError { mean_abs: diameter },
        per_frame,
        min_visibility: config.min_visibility,
        true_positives: tp_total,
        false_positives: fp_total,
        null_reasons,
        pr_curve: curve,
    })
}
