//! The knobs of an evaluation: match tolerance (a 3D distance, or in the image a fraction of the
//! fruit's radius), which truth counts (visibility, and optionally a band of depths, e.g. an
//! arm's reach), and the operating point (a raw score threshold, or a calibrated confidence
//! threshold).

use serde::{Deserialize, Serialize};

use crate::EvalError;

/// Evaluation parameters. Defaults follow seed 000: 50 mm centre tolerance, fruit less than 50 %
/// visible ignored, threshold 0 (an SVM's decision boundary).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EvalConfig {
    /// Largest centre distance, metres, at which a detection matches a truth fruit.
    pub tolerance_m: f64,
    /// Truth with `visibility` below this is ignored; truth without a visibility is counted.
    pub min_visibility: f64,
    /// Detections scoring at least this form the reported operating point (unless
    /// `min_confidence` is set).
    pub threshold: f64,
    /// When set, the operating point is the detections whose calibrated `confidence` is at
    /// least this (a model's operating confidence), and `threshold` is not used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_confidence: Option<f64>,
    /// When set, match in the image instead of in 3D (`pomona eval --2d`, seed 004): a detection
    /// matches a fruit when its circle's centre is within this fraction of the fruit's image
    /// radius from the fruit's circle centre (0.5 in `--2d`); `tolerance_m` is then not used.
    /// Circles come from [`pomona_core::ImageCircle::from_parts`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_fraction_2d: Option<f64>,
    /// When set, `(near, far)` metres: only truth fruit whose centre lies at a depth `z` with
    /// `near ≤ z < far` count; the others (and truth without a 3D centre) are ignored, and a
    /// detection that matches no counted fruit and lies outside the band is ignored too rather
    /// than a false positive. Scores a detector on one distance band, e.g. an arm's reach.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_range_m: Option<(f64, f64)>,
}

impl Default for EvalConfig {
    fn default() -> Self {
        Self {
            tolerance_m: 0.05,
            min_visibility: 0.5,
            threshold: 0.0,
            min_confidence: None,
            radius_fraction_2d: None,
            depth_range_m: None,
        }
    }
}

impl EvalConfig {
    /// The configuration of `pomona eval --2d`: the defaults, matched in the image at half the
    /// fruit's radius.
    pub fn image_2d() -> Self {
        Self {
            radius_fraction_2d: Some(0.5),
            ..Self::default()
        }
    }

    /// This configuration for data with or without depth: data without depth is always matched
    /// in the image (a colour-only detector's 3D centre is only a size-prior guess), at the
    /// [`EvalConfig::image_2d`] fraction unless one is set already.
    pub fn for_data(self, has_depth: bool) -> Self {
        match (has_depth, self.radius_fraction_2d) {
            (false, None) => Self {
                radius_fraction_2d: Self::image_2d().radius_fraction_2d,
                ..self
            },
            _ => self,
        }
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`EvalError::InvalidParameter`] for a tolerance that is not finite and positive, a
    /// visibility outside `[0, 1]`, a NaN threshold, a 2D radius fraction that is not finite
    /// and positive, or a depth band that is not `0 ≤ near < far` (far may be infinite).
    pub fn validate(&self) -> Result<(), EvalError> {
        if !(self.tolerance_m.is_finite() && self.tolerance_m > 0.0) {
            return Err(EvalError::InvalidParameter {
                name: "tolerance_m",
                value: self.tolerance_m,
                reason: "must be finite and > 0",
            });
        }
        if !(0.0..=1.0).contains(&self.min_visibility) {
            return Err(EvalError::InvalidParameter {
                name: "min_visibility",
                value: self.min_visibility,
                reason: "must be in [0, 1]",
            });
        }
        if self.threshold.is_nan() {
            return Err(EvalError::InvalidParameter {
                name: "threshold",
                value: self.threshold,
                reason: "must not be NaN",
            });
        }
        if let Some(f) = self.radius_fraction_2d {
            if !(f.is_finite() && f > 0.0) {
                return Err(EvalError::InvalidParameter {
                    name: "radius_fraction_2d",
                    value: f,
                    reason: "must be finite and > 0",
                });
            }
        }
        if let Some((near, far)) = self.depth_range_m {
            if !(near.is_finite() && near >= 0.0 && far > near) {
                return Err(EvalError::InvalidParameter {
                    name: "depth_range_m",
                    value: if near.is_finite() && near >= 0.0 {
                        far
                    } else {
                        near
                    },
                    reason: "must be 0 <= near < far, metres",
                });
            }
        }
        if let Some(c) = self.min_confidence {
            if !(0.0..=1.0).contains(&c) {
                return Err(EvalError::InvalidParameter {
                    name: "min_confidence",
                    value: c,
                    reason: "must be in [0, 1]",
                });
            }
        }
        Ok(())
    }

    /// Whether a point `depth_m` deep lies in the depth band (always, without one).
    pub fn in_depth_range(&self, depth_m: f64) -> bool {
        self.depth_range_m
            .is_none_or(|(near, far)| near <= depth_m && depth_m < far)
    }

    /// Whether `detection` belongs to the operating point: its confidence reaches
    /// `min_confidence` when that is set (a detection without a confidence never does), its
    /// score reaches `threshold` otherwise.
    pub fn keeps(&self, detection: &pomona_core::Detection) -> bool {
        match self.min_confidence {
            Some(c) => detection.confidence_at_least(c),
            None => detection.score >= self.threshold,
        }
    }

    /// Where the operating point sits on a precision-recall curve over scores: the threshold
    /// itself, or, for a confidence threshold, the lowest score it keeps in `frames` (confidence
    /// is non-decreasing in score).
    pub fn operating_score(&self, frames: &[crate::FrameInput]) -> f64 {
        match self.min_confidence {
            Some(_) => frames
                .iter()
                .flat_map(|f| &f.detections)
                .filter(|d| self.keeps(d))
                .map(|d| d.score)
                .reduce(f64::min)
                .unwrap_or(self.threshold),
            None => self.threshold,
        }
    }

    /// The operating point in words, e.g. `score ≥ 0` or `confidence ≥ 0.42`.
    pub fn operating_point(&self) -> String {
        match self.min_confidence {
            Some(c) => format!("confidence ≥ {c:.3}"),
            None => format!("score ≥ {}", self.threshold),
        }
    }
}
