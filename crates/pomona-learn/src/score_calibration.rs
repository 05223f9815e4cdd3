//! From a detector's raw score to a confidence that means the same everywhere, and the operating
//! threshold on that confidence.
//!
//! A raw SVM decision value has no fixed meaning: its zero sits wherever the training
//! distribution put the margin, and on scenes unlike the training ones a detector can report
//! dozens of false detections per frame above it. A [`ScoreCalibration`] is fitted to detections
//! made on frames the model did *not* train on (cross-fitted folds, see
//! `pomona_pipeline::calibration`), each labelled true or false by matching it to the truth:
//!
//! * the confidence is Platt's sigmoid of the score ([`PlattSigmoid`], LIBSVM's regularised
//!   Newton fit), so it is a held-out estimate of "this detection is a fruit", in `[0, 1]` and
//!   non-decreasing in the score (a fit that comes out decreasing is refused: the scores then
//!   carry no usable signal);
//! * the operating confidence is the threshold that maximises F1 on the same held-out
//!   detections, where recall counts the truth fruit that could have been found
//!   ([`OperatingPoint::MaxF1`]), or the lowest threshold reaching a target precision
//!   ([`OperatingPoint::Precision`]).
//!
//! Both travel in the model file, so `pomona detect` can keep only detections at or above the
//! operating confidence without the user having to guess a score.

use serde::{Deserialize, Serialize};

use crate::cue_logistic::{one_label_each, true_and_false};
use crate::{CueLogistic, DetectionCues, LearnError, PlattSigmoid};

/// How the operating threshold is chosen on held-out detections.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OperatingPoint {
    /// The threshold with the highest F1 (harmonic mean of precision and recall).
    #[default]
    MaxF1,
    /// The lowest threshold whose precision is at least this value (falls back to the highest
    /// precision reachable when none is).
    Precision(f64),
}

/// What the calibration was fitted on, and how it performed there (held-out figures).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CalibrationEvidence {
    /// Held-out detections used (true and false; ignored ones are not counted).
    pub detections: usize,
    /// Of which true positives.
    pub true_positives: usize,
    /// Truth fruit that could have been found in the held-out frames.
    pub truth_fruit: usize,
    /// Precision at the operating confidence on the held-out detections.
    pub precision: f64,
    /// Recall at the operating confidence on the held-out detections.
    pub recall: f64,
}

/// A fitted score → confidence map and the operating confidence.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ScoreCalibration {
    /// Platt sigmoid of the raw score (`a < 0`).
    pub sigmoid: PlattSigmoid,
    /// Detections with a confidence at or above this are reported by default.
    pub operating_confidence: f64,
    /// How the operating confidence was chosen.
    pub operating_point: OperatingPoint,
    /// Held-out data behind the fit.
    pub evidence: CalibrationEvidence,
    /// When set, the confidence is this regression over the score and the detection's
    /// geometric cues instead of the sigmoid of the score alone, and the operating confidence
    /// is on its scale (`pomona calibrate --cues`; absent in older files and by default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cues: Option<CueLogistic>,
}

impl ScoreCalibration {
    /// Checks what a model file could carry wrong: a sigmoid that is not finite or does not
    /// rise with the score (`a < 0`, as every fit is), or an operating confidence outside
    /// `[0, 1]` (which would keep every detection or none).
    ///
    /// # Errors
    /// [`LearnError::InconsistentModel`] saying which.
    pub fn validate(&self) -> Result<(), LearnError> {
        let PlattSigmoid { a, b } = self.sigmoid;
        if !(a.is_finite() && b.is_finite() && a < 0.0) {
            return Err(LearnError::InconsistentModel(format!(
                "calibration sigmoid a = {a}, b = {b}: both must be finite and a negative (the \
                 confidence rises with the score)"
            )));
        }
        if !(0.0..=1.0).contains(&self.operating_confidence) {
            return Err(LearnError::InconsistentModel(format!(
                "calibration operating_confidence {} must lie in [0, 1]",
                self.operating_confidence
            )));
        }
        self.cues.as_ref().map_or(Ok(()), CueLogistic::validate)
    }

    /// Confidence in `[0, 1]` of a detection with raw `score` by the score alone (the sigmoid);
    /// non-decreasing in `score`. A calibration with cues rates detections by
    /// [`ScoreCalibration::confidence_of`].
    pub fn confidence(&self, score: f64) -> f64 {
        self.sigmoid.probability(score)
    }

    /// Confidence in `[0, 1]` of a detection with `cues`: the cue regression's when the
    /// calibration has one, else the sigmoid of the score.
    pub fn confidence_of(&self, cues: &DetectionCues) -> f64 {
        match &self.cues {
            Some(m) => m.probability(cues),
            None => self.confidence(cues.score),
        }
    }

    /// As [`ScoreCalibration::fit`], and a [`CueLogistic`] over `cues` (their curvature measured
    /// over `curvature_patch_radii` fruit radii) that then gives the confidences and the
    /// operating confidence; the sigmoid of the score is fitted too and kept beside it.
    ///
    /// # Errors
    /// As [`ScoreCalibration::fit`] and [`CueLogistic::fit`].
    pub fn fit_with_cues(
        cues: &[DetectionCues],
        is_true: &[bool],
        truth_fruit: usize,
        operating_point: OperatingPoint,
        curvature_patch_radii: f64,
    ) -> Result<Self, LearnError> {
        let scores: Vec<f64> = cues.iter().map(|c| c.score).collect();
        let (sigmoid, positives) = fit_sigmoid(&scores, is_true, truth_fruit, operating_point)?;
        let model = CueLogistic::fit(cues, is_true, curvature_patch_radii)?;
        let confidences = cues.iter().map(|c| model.probability(c));
        Ok(Self::at_operating_point(
            sigmoid,
            Some(model),
            confidences,
            is_true,
            (positives, truth_fruit),
            operating_point,
        ))
    }

    /// Fits the calibration to held-out detections: `scores[i]` with `is_true[i]` (whether it
    /// matched a truth fruit), out of `truth_fruit` findable fruit.
    ///
    /// # Errors
    /// [`LearnError::InvalidSamples`] when the inputs disagree in length, a score is not finite,
    /// there is no true or no false detection, `truth_fruit` is smaller than the true detections,
    /// or the fitted sigmoid decreases with the score; [`LearnError::InvalidParameter`] for a
    /// target precision outside `(0, 1]`.
    ///
    /// ```
    /// use pomona_learn::{OperatingPoint, ScoreCalibration};
    /// let scores = [-2.0, -1.5, -1.0, -0.4, 0.1, 0.3, 0.8, 1.2, 1.9, 2.5];
    /// let is_true = [false, false, false, true, false, true, true, false, true, true];
    /// let c = ScoreCalibration::fit(&scores, &is_true, 6, OperatingPoint::MaxF1).unwrap();
    /// assert!(c.confidence(2.0) > c.confidence(0.0));
    /// assert!((0.0..=1.0).contains(&c.operating_confidence));
    /// ```
    pub fn fit(
        scores: &[f64],
        is_true: &[bool],
        truth_fruit: usize,
        operating_point: OperatingPoint,
    ) -> Result<Self, LearnError> {
        let (sigmoid, positives) = fit_sigmoid(scores, is_true, truth_fruit, operating_point)?;
        let confidences = scores.iter().map(|&s| sigmoid.probability(s));
        Ok(Self::at_operating_point(
            sigmoid,
            None,
            confidences,
            is_true,
            (positives, truth_fruit),
            operating_point,
        ))
    }

    /// The calibration that rates detections by `confidences` (the sigmoid's, or the cue
    /// regression's when `cues` is set), its operating confidence chosen over them, out of
    /// `true_positives` true detections and `truth_fruit` findable fruit.
    fn at_operating_point(
        sigmoid: PlattSigmoid,
        cues: Option<CueLogistic>,
        confidences: impl Iterator<Item = f64>,
        is_true: &[bool],
        (true_positives, truth_fruit): (usize, usize),
        operating_point: OperatingPoint,
    ) -> Self {
        let (confidence, precision, recall) =
            threshold_of(confidences, is_true, truth_fruit, operating_point);
        Self {
            sigmoid,
            cues,
            operating_confidence: confidence,
            operating_point,
            evidence: CalibrationEvidence {
                detections: is_true.len(),
                true_positives,
                truth_fruit,
                precision,
                recall,
            },
        }
    }
}

/// Checks held-out `scores` labelled `is_true` (see [`ScoreCalibration::fit`]'s errors) and fits
/// Platt's sigmoid to them; also returns the number of true detections.
fn fit_sigmoid(
    scores: &[f64],
    is_true: &[bool],
    truth_fruit: usize,
    operating_point: OperatingPoint,
) -> Result<(PlattSigmoid, usize), LearnError> {
    let bad = |reason: String| Err(LearnError::InvalidSamples(reason));
    one_label_each(scores.len(), is_true.len(), "scores")?;
    if let Some(s) = scores.iter().find(|s| !s.is_finite()) {
        return bad(format!("a held-out score is not finite ({s})"));
    }
    if let OperatingPoint::Precision(p) = operating_point {
        if !(p > 0.0 && p <= 1.0) {
            return Err(LearnError::InvalidParameter {
                name: "operating_point.precision",
                value: p,
                reason: "must be in (0, 1]",
            });
        }
    }
    let positives = true_and_false(
        is_true,
        "calibration needs true and false held-out detections",
    )?;
    if truth_fruit < positives {
        return bad(format!(
            "{positives} true detections but only {truth_fruit} findable fruit"
        ));
    }
    let sigmoid = PlattSigmoid::fit(scores, is_true);
    if sigmoid.a >= 0.0 {
        return bad(format!(
            "held-out scores do not rank true detections above false ones (sigmoid slope \
             {:.3} ≤ 0 over {} detections)",
            -sigmoid.a,
            scores.len()
        ));
    }
    Ok((sigmoid, positives))
}

/// `operating confidence 0.271 (held-out precision 0.868, recall 0.709 over 251 fruit)`.
impl std::fmt::Display for ScoreCalibration {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let e = &self.evidence;
        write!(
            f,
            "operating confidence {:.3} (held-out precision {:.3}, recall {:.3} over {} fruit)",
            self.operating_confidence, e.precision, e.recall, e.truth_fruit
        )
    }
}

/// `(threshold, precision, recall)` for detections with `confidences` labelled `is_true`: ranks
/// them by decreasing confidence, then [`choose_threshold`].
fn threshold_of(
    confidences: impl Iterator<Item = f64>,
    is_true: &[bool],
    truth_fruit: usize,
    operating_point: OperatingPoint,
) -> (f64, f64, f64) {
    let mut ranked: Vec<(f64, bool)> = confidences.zip(is_true.iter().copied()).collect();
    ranked.sort_by(|a, b| b.0.total_cmp(&a.0));
    choose_threshold(&ranked, truth_fruit, operating_point)
}

/// `(threshold, precision, recall)` chosen over detections sorted by decreasing confidence;
/// thresholds are the distinct confidences (keeping every detection at or above one).
fn choose_threshold(
    ranked: &[(f64, bool)],
    truth_fruit: usize,
    operating_point: OperatingPoint,
) -> (f64, f64, f64) {
    let mut best: Option<(f64, f64, f64, f64)> = None; // (key, threshold, precision, recall)
    let (mut tp, mut kept) = (0usize, 0usize);
    for (i, &(conf, t)) in ranked.iter().enumerate() {
        tp += usize::from(t);
        kept += 1;
        // Only at the last detection of a run of equal confidences is the set well defined.
        if ranked.get(i + 1).is_some_and(|next| next.0 == conf) {
            continue;
        }
        let precision = tp as f64 / kept as f64;
        let recall = tp as f64 / truth_fruit.max(1) as f64;
        let key = match operating_point {
            OperatingPoint::MaxF1 => {
                if tp == 0 {
                    0.0
                } else {
                    2.0 * precision * recall / (precision + recall)
                }
            }
            // Meeting the target ranks by recall (lower thresholds come later and win ties
            // only when they add recall); missing it ranks below any success, by precision.
            OperatingPoint::Precision(p) if precision >= p => 1.0 + recall,
            OperatingPoint::Precision(_) => precision - 1.0,
        };
        if best.is_none_or(|b| key > b.0) {
            best = Some((key, conf, precision, recall));
        }
    }
    best.map_or((1.0, 0.0, 0.0), |(_, c, p, r)| (c, p, r))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (Vec<f64>, Vec<bool>) {
        // Scores rise with truth: most true above 0, most false below.
        let scores: Vec<f64> = (0..40).map(|i| -2.0 + 0.1 * i as f64).collect();
        let is_true = (0..40).map(|i| (i * 7) % 40 < i).collect();
        (scores, is_true)
    }

    #[test]
    fn confidence_is_monotone_and_bounded() {
        let (s, t) = sample();
        let c = ScoreCalibration::fit(&s, &t, 30, OperatingPoint::MaxF1).unwrap();
        let mut last = -1.0;
        for i in -100..100 {
            let v = c.confidence(0.1 * i as f64);
            assert!((0.0..=1.0).contains(&v));
            assert!(v >= last, "{v} < {last}");
            last = v;
        }
        assert!(c.confidence(-10.0) < 0.2 && c.confidence(10.0) > 0.8);
    }

    #[test]
    fn max_f1_threshold_is_the_best_cut() {
        let (s, t) = sample();
        let c = ScoreCalibration::fit(&s, &t, 30, OperatingPoint::MaxF1).unwrap();
        let f1_at = |thr: f64| {
            let tp = s
                .iter()
                .zip(&t)
                .filter(|(&x, &y)| y && c.confidence(x) >= thr)
                .count() as f64;
            let kept = s.iter().filter(|&&x| c.confidence(x) >= thr).count() as f64;
            let (p, r) = (tp / kept.max(1.0), tp / 30.0);
            2.0 * p * r / (p + r).max(1e-12)
        };
        let best = f1_at(c.operating_confidence);
        for &x in &s {
            assert!(f1_at(c.confidence(x)) <= best + 1e-12);
        }
        let e = c.evidence;
        assert!((2.0 * e.precision * e.recall / (e.precision + e.recall) - best).abs() < 1e-12);
    }

    #[test]
    fn precision_target_is_met_at_the_lowest_threshold() {
        let (s, t) = sample();
        let c = ScoreCalibration::fit(&s, &t, 30, OperatingPoint::Precision(0.9)).unwrap();
        assert!(c.evidence.precision >= 0.9);
        let loose = ScoreCalibration::fit(&s, &t, 30, OperatingPoint::MaxF1).unwrap();
        assert!(c.operating_confidence >= loose.operating_confidence);
    }

    #[test]
    fn unusable_inputs_are_refused() {
        let fit = |s: &[f64], t: &[bool]| ScoreCalibration::fit(s, t, 10, OperatingPoint::MaxF1);
        assert!(fit(&[1.0, 2.0], &[true]).is_err());
        assert!(fit(&[1.0, 2.0], &[true, true]).is_err());
        assert!(fit(&[1.0, f64::NAN], &[true, false]).is_err());
        // Anti-correlated scores: higher score, more often false.
        let s: Vec<f64> = (0..20).map(f64::from).collect();
        let t: Vec<bool> = (0..20).map(|i| i < 10).collect();
        let err = fit(&s, &t).unwrap_err().to_string();
        assert!(err.contains("do not rank"), "{err}");
        assert!(ScoreCalibration::fit(
            &[0.0, 1.0],
            &[false, true],
            1,
            OperatingPoint::Precision(1.5)
        )
        .is_err());
    }

    #[test]
    fn round_trips_through_json() {
        let (s, t) = sample();
        let c = ScoreCalibration::fit(&s, &t, 30, OperatingPoint::Precision(0.8)).unwrap();
        let json = serde_json::to_string(&c).unwrap();
        assert!(
            json.contains(r#""operating_point":{"precision":0.8}"#),
            "{json}"
        );
        assert_eq!(serde_json::from_str::<ScoreCalibration>(&json).unwrap(), c);
    }
}
