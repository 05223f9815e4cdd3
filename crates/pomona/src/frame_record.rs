//! What a detection file records for one frame (`<out>/<frame>.json`, docs/formats.md), and the
//! threshold it is written at: the one rule `pomona detect`, the ROS node, the Python package and
//! its Dask runner share, so each writes byte-identical files for the same frame and model.
//!
//! The threshold ([`KeepRule`]) is the confidence asked for, else the model's operating
//! confidence; a model without calibration (trained on incompletely annotated frames, or before
//! calibration existed) keeps what its classifier accepts, score ≥ 0, since its detections carry
//! no confidence to compare. Asking for a confidence above 0 of such a model is an error;
//! asking for 0 keeps every detection of any model.

use pomona_core::{Detection, FrameDetections};

use crate::{Detector, Error};

/// Which detections a run keeps and its detection files hold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum KeepRule {
    /// Calibrated confidence at least this (by default the model's operating confidence; 0
    /// keeps every detection of a calibrated model).
    Confidence(f64),
    /// Raw score at least this: a model without calibration keeps what its classifier accepts
    /// (score ≥ 0, the SVM's decision boundary).
    Score(f64),
    /// Every detection (`min_confidence` 0 on a model without calibration).
    All,
}

impl KeepRule {
    /// Whether `detection` is kept (a detection without a confidence never reaches a
    /// confidence threshold).
    pub fn keeps(&self, detection: &Detection) -> bool {
        match *self {
            KeepRule::Confidence(c) => detection.confidence_at_least(c),
            KeepRule::Score(s) => detection.score >= s,
            KeepRule::All => true,
        }
    }

    /// The confidence threshold, when the rule is one.
    pub fn min_confidence(&self) -> Option<f64> {
        match *self {
            KeepRule::Confidence(c) => Some(c),
            KeepRule::Score(_) | KeepRule::All => None,
        }
    }

    /// The score threshold, when the rule is one.
    pub fn min_score(&self) -> Option<f64> {
        match *self {
            KeepRule::Score(s) => Some(s),
            KeepRule::Confidence(_) | KeepRule::All => None,
        }
    }

    /// The rule in words, e.g. `confidence ≥ 0.31`, `score ≥ 0`, `every detection`.
    pub fn describe(&self) -> String {
        match *self {
            KeepRule::Confidence(c) => format!("confidence ≥ {c:.2}"),
            KeepRule::Score(s) => format!("score ≥ {s}"),
            KeepRule::All => "every detection".to_owned(),
        }
    }
}

impl Detector {
    /// The rule detection files are written at: confidence ≥ `requested` when given (`Some(0.0)`
    /// keeps everything, also of a model without calibration), else the model's operating
    /// confidence, else (no calibration) score ≥ 0.
    ///
    /// ```
    /// # fn main() -> Result<(), pomona::Error> {
    /// use pomona::KeepRule;
    /// let detector = pomona::Detector::builtin("shape-fit")?;
    /// let operating = detector.operating_confidence().expect("the built-in model is calibrated");
    /// assert_eq!(detector.keep_rule_for(None)?, KeepRule::Confidence(operating));
    /// assert_eq!(detector.keep_rule_for(Some(0.0))?, KeepRule::Confidence(0.0));
    /// assert!(detector.keep_rule_for(Some(1.5)).is_err());
    /// # Ok(())
    /// # }
    /// ```
    ///
    /// # Errors
    /// [`Error::MinConfidence`] for a value outside `[0, 1]`, or above 0 for a model without
    /// calibration.
    pub fn keep_rule_for(&self, requested: Option<f64>) -> Result<KeepRule, Error> {
        match (requested, self.operating_confidence()) {
            (Some(c), _) if !(0.0..=1.0).contains(&c) => Err(Error::MinConfidence {
                value: c,
                reason: "it must be in [0, 1]".into(),
            }),
            (Some(0.0), None) => Ok(KeepRule::All),
            (Some(c), None) => Err(Error::MinConfidence {
                value: c,
                reason: format!(
                    "the model of `{}` has no confidence calibration (retrain it with \
                     `pomona train`, which calibrates by default when the truth is complete); \
                     0 keeps every detection, and by default it keeps score ≥ 0",
                    self.pipeline()
                ),
            }),
            (Some(c), Some(_)) => Ok(KeepRule::Confidence(c)),
            (None, _) => Ok(self.default_keep_rule()),
        }
    }

    /// The rule when none is asked for: the model's operating confidence, else (no
    /// calibration) score ≥ 0.
    pub(crate) fn default_keep_rule(&self) -> KeepRule {
        match self.operating_confidence() {
            Some(op) => KeepRule::Confidence(op),
            None => KeepRule::Score(0.0),
        }
    }

    /// The detection file of frame `stem`: `detections` (found in a frame with or without
    /// colour, `has_color`) kept by `keep` (from [`Detector::keep_rule_for`]), with the
    /// pipeline, the model's identity, its operating confidence and the threshold.
    pub fn frame_record(
        &self,
        stem: &str,
        has_color: bool,
        detections: &[Detection],
        keep: KeepRule,
    ) -> FrameDetections {
        let model = self.model_for_color(has_color);
        FrameDetections {
            frame: stem.to_owned(),
            pipeline: self.pipeline().to_owned(),
            detections: detections
                .iter()
                .filter(|d| keep.keeps(d))
                .cloned()
                .collect(),
            operating_confidence: model.operating_confidence,
            min_confidence: keep.min_confidence(),
            min_score: keep.min_score(),
            model_id: Some(model.id.clone()),
            stamp_ns: None,
            frame_id: None,
        }
    }
}
