//! What a detector reports: one record per fruit found, one file per frame.
//!
//! Two direction fields say different things and never share one key: `fruit_axis` is the
//! fruit's long axis (shape-fit's cylinders), `symmetry_plane_normal` the normal of the fruit's
//! reflection-symmetry plane (symmetry pipeline), which is perpendicular to the fruit axis.
//!
//! ## Files written before the split
//! Older detection files carry a single `axis` whose meaning depended on the pipeline that wrote
//! it: `shape-fit` wrote the cylinder axis, `symmetry` the symmetry-plane normal (`viewer-pose`
//! wrote none). A detection alone cannot tell which, so the mapping is done when a whole
//! [`FrameDetections`] is read, from its recorded `pipeline`: files of the pipelines named in
//! [`SYMMETRY_PLANE_PIPELINES`] read `axis` as `symmetry_plane_normal`, every other file
//! (shape-fit, or a detector outside Pomona following the old documentation, "symmetry axis")
//! as `fruit_axis`. A new key present beside `axis` wins. New files never write `axis`.

use nalgebra::{Point2, Point3, Unit, Vector3};
use serde::{Deserialize, Serialize};

use crate::truth::unit_axis;
use crate::{ImageCircle, PinholeCamera, PixelBox};

/// Pipelines whose detection files written before `fruit_axis`/`symmetry_plane_normal` existed
/// stored the symmetry-plane normal under `axis` (see the module docs).
pub const SYMMETRY_PLANE_PIPELINES: [&str; 2] = ["symmetry", "viewer-pose"];

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
    /// The fruit's long axis (unit; sign arbitrary), when the method estimates one (shape-fit:
    /// the fitted cylinder's axis).
    #[serde(default, with = "unit_axis", skip_serializing_if = "Option::is_none")]
    pub fruit_axis: Option<Unit<Vector3<f64>>>,
    /// Normal (unit; sign arbitrary) of the fruit's reflection-symmetry plane, perpendicular to
    /// the fruit axis, when the method estimates one (symmetry pipeline).
    #[serde(default, with = "unit_axis", skip_serializing_if = "Option::is_none")]
    pub symmetry_plane_normal: Option<Unit<Vector3<f64>>>,
    /// Image-space box, when the method has one.
    #[serde(default)]
    pub bbox_px: Option<PixelBox>,
    /// Centre of the fruit's circle in the image, pixels, when the method finds circles
    /// (color-contour).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center_px: Option<Point2<f64>>,
    /// Radius of that circle, pixels.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_px: Option<f64>,
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
    /// pipelines and models, unlike `score`. A file with another value is refused.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::range_checked::confidence"
    )]
    pub confidence: Option<f64>,
}

impl Detection {
    /// A detection with only a centre and a score; every optional field is `None` (set the ones
    /// the method estimates with struct update syntax).
    ///
    /// ```
    /// use pomona_core::{nalgebra::Point3, Detection};
    /// let d = Detection {
    ///     diameter_m: Some(0.08),
    ///     ..Detection::new(Point3::new(0.0, 0.1, 0.7), 1.5)
    /// };
    /// assert_eq!(d.fruit_axis, None);
    /// ```
    pub fn new(center_m: Point3<f64>, score: f64) -> Self {
        Self {
            center_m,
            score,
            diameter_m: None,
            fruit_axis: None,
            symmetry_plane_normal: None,
            bbox_px: None,
            center_px: None,
            radius_px: None,
            kind: None,
            support_points: None,
            fit_rms_m: None,
            confidence: None,
        }
    }

    /// The detection's circle in the image: `center_px`/`radius_px` when the method reports
    /// them, else the sphere `center_m` ⌀ `diameter_m` projected, else the box's inscribed
    /// circle ([`ImageCircle::from_parts`]).
    pub fn image_circle(&self, camera: &PinholeCamera) -> Option<ImageCircle> {
        ImageCircle::from_parts(
            camera,
            self.center_px,
            self.radius_px,
            self.diameter_m.map(|d| (self.center_m, d)),
            self.bbox_px.as_ref(),
        )
    }

    /// Whether the detection has a calibrated confidence of at least `min_confidence` (one
    /// without a confidence never has).
    pub fn confidence_at_least(&self, min_confidence: f64) -> bool {
        self.confidence.is_some_and(|c| c >= min_confidence)
    }
}

/// All detections of one frame (`<out>/<frame>.json`). Reading accepts the older single `axis`
/// key (see the module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "FrameDetectionsFile")]
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
    /// The lowest confidence kept in this file (`None`: no confidence threshold).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_confidence: Option<f64>,
    /// The lowest score kept in this file, for a model without calibration (0: what its
    /// classifier accepts); `None`: no score threshold. Neither threshold: every detection.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_score: Option<f64>,
    /// Identity of the model that produced the detections (a hash of the model file after
    /// parameter overrides), so `pomona detect --resume` never mixes two models' output.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model_id: Option<String>,
    /// The colour image's header stamp, nanoseconds since the epoch, when the frame came from a
    /// robot recording (`pomona detect --recording`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stamp_ns: Option<u64>,
    /// The colour image's coordinate frame (ROS `frame_id`), when the frame came from a robot
    /// recording.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame_id: Option<String>,
}

/// A detection as read from a file: the current fields plus the older `axis`.
#[derive(Deserialize)]
struct DetectionFile {
    #[serde(flatten)]
    detection: Detection,
    #[serde(default, with = "unit_axis")]
    axis: Option<Unit<Vector3<f64>>>,
}

/// [`FrameDetections`] as read from a file.
#[derive(Deserialize)]
struct FrameDetectionsFile {
    frame: String,
    pipeline: String,
    detections: Vec<DetectionFile>,
    #[serde(default)]
    operating_confidence: Option<f64>,
    #[serde(default)]
    min_confidence: Option<f64>,
    #[serde(default)]
    min_score: Option<f64>,
    #[serde(default)]
    model_id: Option<String>,
    #[serde(default)]
    stamp_ns: Option<u64>,
    #[serde(default)]
    frame_id: Option<String>,
}

impl From<FrameDetectionsFile> for FrameDetections {
    fn from(file: FrameDetectionsFile) -> Self {
        let plane_normal = SYMMETRY_PLANE_PIPELINES.contains(&file.pipeline.as_str());
        let detections = file
            .detections
            .into_iter()
            .map(
                |DetectionFile {
                     mut detection,
                     axis,
                 }| {
                    let slot = if plane_normal {
                        &mut detection.symmetry_plane_normal
                    } else {
                        &mut detection.fruit_axis
                    };
                    if slot.is_none() {
                        *slot = axis;
                    }
                    detection
                },
            )
            .collect();
        Self {
            frame: file.frame,
            pipeline: file.pipeline,
            detections,
            operating_confidence: file.operating_confidence,
            min_confidence: file.min_confidence,
            min_score: file.min_score,
            model_id: file.model_id,
            stamp_ns: file.stamp_ns,
            frame_id: file.frame_id,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_confidence_outside_zero_to_one_is_refused_by_name() {
        let read = |c: &str| {
            serde_json::from_str::<Detection>(&format!(
                r#"{{"center_m": [0, 0, 1], "score": 1, "confidence": {c}}}"#
            ))
        };
        for bad in ["1.5", "-0.01"] {
            let err = read(bad).expect_err(bad).to_string();
            assert!(
                err.contains("confidence must lie in [0, 1]"),
                "{bad}: {err}"
            );
        }
        assert_eq!(read("1").unwrap().confidence, Some(1.0));
        assert_eq!(read("null").unwrap().confidence, None);
    }

    #[test]
    fn round_trips_through_json() {
        let d = FrameDetections {
            frame: "000001".into(),
            pipeline: "shape-fit".into(),
            detections: vec![Detection {
                center_m: Point3::new(0.1, -0.2, 0.7),
                score: 1.25,
                diameter_m: Some(0.08),
                fruit_axis: Some(Vector3::y_axis()),
                symmetry_plane_normal: None,
                bbox_px: Some(PixelBox::new(1.0, 2.0, 3.0, 4.0).unwrap()),
                center_px: None,
                radius_px: None,
                kind: None,
                support_points: None,
                fit_rms_m: None,
                confidence: Some(0.75),
            }],
            operating_confidence: Some(0.5),
            min_confidence: None,
            min_score: Some(0.0),
            model_id: Some("0123456789abcdef".into()),
            stamp_ns: None,
            frame_id: None,
        };
        let json = serde_json::to_string(&d).unwrap();
        assert!(json.contains(r#""center_m":[0.1,-0.2,0.7]"#));
        assert!(!json.contains("symmetry_plane_normal") && !json.contains(r#""axis""#));
        assert_eq!(serde_json::from_str::<FrameDetections>(&json).unwrap(), d);
        assert!(json.contains(r#""min_score":0.0"#));
        // Recording fields are written only when present, so dataset files stay as they were.
        assert!(!json.contains("stamp_ns") && !json.contains("frame_id"));
        let recorded = FrameDetections {
            stamp_ns: Some(1_700_000_000_000_000_000),
            frame_id: Some("camera_color_optical_frame".into()),
            ..d
        };
        let json = serde_json::to_string(&recorded).unwrap();
        assert!(json.contains(r#""stamp_ns":1700000000000000000"#), "{json}");
        assert_eq!(
            serde_json::from_str::<FrameDetections>(&json).unwrap(),
            recorded
        );
    }

    /// An old file of `pipeline` with one detection whose `axis` is `[0, 2, 0]`.
    fn old_file(pipeline: &str, extra: &str) -> FrameDetections {
        serde_json::from_str(&format!(
            r#"{{"frame": "7", "pipeline": "{pipeline}", "detections": [{{"center_m": [0, 0, 1],
                "score": 1.0, "diameter_m": null, "axis": [0, 2, 0], "bbox_px": null,
                "kind": null, "support_points": null, "fit_rms_m": null{extra}}}]}}"#
        ))
        .unwrap()
    }

    #[test]
    fn old_axis_key_maps_by_the_recorded_pipeline() {
        let y = Some(Vector3::y_axis());
        for pipeline in ["shape-fit", "someone-elses-detector"] {
            let d = &old_file(pipeline, "").detections[0];
            assert_eq!(
                (d.fruit_axis, d.symmetry_plane_normal),
                (y, None),
                "{pipeline}"
            );
        }
        for pipeline in SYMMETRY_PLANE_PIPELINES {
            let d = &old_file(pipeline, "").detections[0];
            assert_eq!(
                (d.fruit_axis, d.symmetry_plane_normal),
                (None, y),
                "{pipeline}"
            );
        }
        // A new key beside the old one wins; the old one fills only the pipeline's own slot.
        let d = &old_file("symmetry", r#", "symmetry_plane_normal": [1, 0, 0]"#).detections[0];
        assert_eq!(d.symmetry_plane_normal, Some(Vector3::x_axis()));
        assert_eq!(d.fruit_axis, None);
        // Re-written, the file carries only the new key.
        let json = serde_json::to_string(&old_file("symmetry", "")).unwrap();
        assert!(
            json.contains(r#""symmetry_plane_normal":[0.0,1.0,0.0]"#),
            "{json}"
        );
        assert!(
            !json.contains(r#""axis""#) && !json.contains("fruit_axis"),
            "{json}"
        );
    }

    #[test]
    fn old_zero_axis_is_still_rejected() {
        let text = r#"{"frame": "7", "pipeline": "shape-fit", "detections": [{"center_m": [0, 0, 1],
            "score": 1.0, "axis": [0, 0, 0]}]}"#;
        assert!(serde_json::from_str::<FrameDetections>(text).is_err());
    }
}
