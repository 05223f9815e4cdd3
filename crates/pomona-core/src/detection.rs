//! What a detector reports: one record per fruit found, one file per frame.

use nalgebra::{Point3, Unit, Vector3};
use serde::{Deserialize, Serialize};

use crate::PixelBox;

/// A detected fruit. Higher `score` means more confident; scores are comparable only within one
/// model (they are SVM decision values or similar, not probabilities). `confidence`, when
/// present, is the calibrated probability-like value to threshold on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Detection {
    /// Estimated fruit centre in the camera frame, metres.
    pub center_m: Point3<f64>,
    /// Confidence; higher is more confident.
    pub score: f64,
    /// Estimated diameter, metres, when the method measures size.
    #[serde(default)]
    pub diameter_m: Option<f64>,
    /// Estimated symmetry axis, when the method estimates one.
    #[serde(default, with = "crate::truth::unit_axis")]
    pub axis: Option<Unit<Vector3<f64>>>,
    /// Image-space box, when the method has one.
    #[serde(default)]
    pub bbox_px: Option<PixelBox>,
    /// Fruit kind, when the method distinguishes kinds.
    #[serde(default)]
    pub kind: Option<String>,
    /// For methods that fit a shape: the number of points supporting it (its inliers).
    #[serde(default)]
    pub support_points: Option<usize>,
    /// For methods that fit a shape: RMS distance, metres, of the supporting points from the
    /// fitted surface — a fit-quality signal (a grasp planner may distrust a loose fit).
    #[serde(default)]
    pub fit_rms_m: Option<f64>,
    /// Calibrated confidence in `[0, 1]` that this is a fruit, when the model carries a score
    /// calibration (fitted on held-out frames; non-decreasing in `score`). Comparable across
    /// pipelines and models, unlike `score`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub confidence: Option<f64>,
}

impl Detection {
    /// Whether the detection has a calibrated confidence of at least `min_confidence` (one
    /// without a confidence never has).
    pub fn confidence_at_least(&self, min_confidence: f64) -> bool {
        self.confidence.is_some_and(|c| c >= min_confidence)
    }
}

/// All detections of one frame (`<out>/<frame>.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameDetections {
    /// Frame stem the detections belong to.
    pub frame: String,
    /// Name of the pipeline that produced them.
    pub pipeline: String,
    /// The detections, in any order.
    pub detections: Vec<Detection>,
    /// The model's operating confidence, when it has one: `pomona detect` kept detections at or
    /// above `min_confidence` (see below), and `pomona eval` reports its operating point here.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub operating_confidence: Option<f64>,
    /// The lowest confidence kept in this file (`None`: every detection was kept).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_confidence: Option<f64>,
    /// Identity of the model that produced the detections (a hash of the model file after
    /// parameter overrides), so `pomona detect --resume` never mixes two models' output.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model_id: Option<String>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_through_json() {
        let d = FrameDetections {
            frame: "000001".into(),
            pipeline: "shape-fit".into(),
            detections: vec![Detection {
                center_m: Point3::new(0.1, -0.2, 0.7),
                score: 1.25,
                diameter_m: Some(0.08),
                axis: Some(Vector3::y_axis()),
                bbox_px: Some(PixelBox::new(1.0, 2.0, 3.0, 4.0).unwrap()),
                kind: None,
                support_points: None,
                fit_rms_m: None,
                confidence: Some(0.75),
            }],
            operating_confidence: Some(0.5),
            min_confidence: None,
            model_id: Some("0123456789abcdef".into()),
        };
        let json = serde_json::to_string(&d).unwrap();
        assert!(json.contains(r#""center_m":[0.1,-0.2,0.7]"#));
        assert_eq!(serde_json::from_str::<FrameDetections>(&json).unwrap(), d);
    }
}
