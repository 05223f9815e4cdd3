//! Pomona detections as ROS messages: one `vision_msgs/Detection3DArray` and one RViz
//! `MarkerArray` per frame, both stamped with the colour image's header so a planner can look up
//! the camera pose at the exposure time.
//!
//! Per detection: `results[0].hypothesis.class_id` is the fruit kind (or `"fruit"` when the
//! method does not tell kinds apart), `score` the calibrated confidence (the raw classifier score
//! for a model without calibration), `bbox.center.position` and `results[0].pose` the centre in
//! metres in the colour camera's optical frame; `bbox.size` is the diameter on every axis (0
//! when the method does not measure size); an elongated fruit's box is turned so that its z runs
//! along `fruit_axis`. `id` is the detection's index in the frame.

use pomona_core::Detection;
use pomona_recording::Header;

use crate::geometry_msgs::{Point, Pose, PoseWithCovariance, Quaternion, Vector3};
use crate::vision_msgs::{
    BoundingBox3D, Detection3D, Detection3DArray, ObjectHypothesis, ObjectHypothesisWithPose,
};
use crate::visualization_msgs::{ColorRgba, Marker, MarkerArray};

/// `class_id` of a detection whose method does not tell fruit kinds apart.
pub const GENERIC_CLASS: &str = "fruit";

/// Drawn size of a detection without a measured diameter, metres (markers only; its box size
/// stays 0).
pub const UNSIZED_MARKER_M: f64 = 0.05;

/// Marker namespace of the fruit shapes and of their labels.
pub const MARKER_NAMESPACES: [&str; 2] = ["pomona_fruit", "pomona_label"];

/// The value published as the hypothesis score: the calibrated confidence when the model has
/// one, else the raw score.
pub fn published_score(detection: &Detection) -> f64 {
    detection.confidence.unwrap_or(detection.score)
}

fn pose_of(detection: &Detection) -> Pose {
    Pose {
        position: Point::from(detection.center_m),
        orientation: detection
            .fruit_axis
            .as_ref()
            .map(Quaternion::z_onto)
            .unwrap_or_default(),
    }
}

/// The detections of one frame as a `Detection3DArray` stamped `header`.
pub fn detection_array(header: &Header, detections: &[Detection]) -> Detection3DArray {
    let detections = detections
        .iter()
        .enumerate()
        .map(|(i, d)| {
            let pose = pose_of(d);
            Detection3D {
                header: header.clone(),
                results: vec![ObjectHypothesisWithPose {
                    hypothesis: ObjectHypothesis {
                        class_id: d.kind.clone().unwrap_or_else(|| GENERIC_CLASS.to_owned()),
                        score: published_score(d),
                    },
                    pose: PoseWithCovariance {
                        pose,
                        ..PoseWithCovariance::default()
                    },
                }],
                bbox: BoundingBox3D {
                    center: pose,
                    size: Vector3::uniform(d.diameter_m.unwrap_or(0.0)),
                },
                id: i.to_string(),
            }
        })
        .collect();
    Detection3DArray {
        header: header.clone(),
        detections,
    }
}

/// The detections of one frame as RViz markers: a "delete all" that clears the previous frame's,
/// then per detection a translucent sphere (a cylinder along the fruit axis when there is one)
/// and a label with the class and published score above it.
pub fn marker_array(header: &Header, detections: &[Detection]) -> MarkerArray {
    let [shape_ns, label_ns] = MARKER_NAMESPACES;
    let mut markers = vec![Marker {
        header: header.clone(),
        action: Marker::DELETE_ALL,
        ..Marker::default()
    }];
    for (i, d) in detections.iter().enumerate() {
        let id = i32::try_from(i).unwrap_or(i32::MAX);
        let size_m = d.diameter_m.unwrap_or(UNSIZED_MARKER_M);
        let pose = pose_of(d);
        markers.push(Marker {
            header: header.clone(),
            ns: shape_ns.to_owned(),
            id,
            kind: if d.fruit_axis.is_some() {
                Marker::CYLINDER
            } else {
                Marker::SPHERE
            },
            action: Marker::ADD,
            pose,
            scale: Vector3::uniform(size_m),
            color: ColorRgba {
                r: 1.0,
                g: 0.45,
                b: 0.0,
                a: 0.6,
            },
            ..Marker::default()
        });
        let mut label_pose = Pose {
            orientation: Quaternion::default(),
            ..pose
        };
        // Above the fruit: −y is up in the optical frame.
        label_pose.position.y -= 0.5 * size_m + 0.02;
        markers.push(Marker {
            header: header.clone(),
            ns: label_ns.to_owned(),
            id,
            kind: Marker::TEXT_VIEW_FACING,
            action: Marker::ADD,
            pose: label_pose,
            scale: Vector3 {
                x: 0.0,
                y: 0.0,
                z: 0.03,
            },
            color: ColorRgba {
                r: 1.0,
                g: 1.0,
                b: 1.0,
                a: 1.0,
            },
            text: format!(
                "{} {:.2}",
                d.kind.as_deref().unwrap_or(GENERIC_CLASS),
                published_score(d)
            ),
            ..Marker::default()
        });
    }
    MarkerArray { markers }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::nalgebra::{Point3, Unit, Vector3 as NaVector3};

    fn detections() -> Vec<Detection> {
        vec![
            Detection {
                diameter_m: Some(0.08),
                kind: Some("apple".into()),
                confidence: Some(0.9),
                ..Detection::new(Point3::new(0.1, -0.05, 0.7), 2.5)
            },
            Detection {
                fruit_axis: Some(Unit::new_normalize(NaVector3::new(1.0, 0.0, 0.0))),
                ..Detection::new(Point3::new(-0.2, 0.0, 0.9), -0.4)
            },
        ]
    }

    #[test]
    fn array_carries_header_kind_score_centre_size_and_axis() {
        let header = Header::at(1_700_000_000_123_456_789, "camera_color_optical_frame");
        let array = detection_array(&header, &detections());
        assert_eq!(array.header, header);
        assert_eq!(array.detections.len(), 2);
        let [a, b] = [&array.detections[0], &array.detections[1]];
        assert_eq!(a.header, header);
        assert_eq!(a.results[0].hypothesis.class_id, "apple");
        assert_eq!(
            a.results[0].hypothesis.score, 0.9,
            "confidence when calibrated"
        );
        assert_eq!(
            a.bbox.center.position,
            Point {
                x: 0.1,
                y: -0.05,
                z: 0.7
            }
        );
        assert_eq!(a.results[0].pose.pose, a.bbox.center);
        assert_eq!(a.bbox.size, Vector3::uniform(0.08));
        assert_eq!(a.bbox.center.orientation, Quaternion::default());
        assert_eq!(b.results[0].hypothesis.class_id, GENERIC_CLASS);
        assert_eq!(b.results[0].hypothesis.score, -0.4, "raw score otherwise");
        assert_eq!(b.bbox.size, Vector3::uniform(0.0));
        // z onto +x: a quarter turn about y.
        let q = b.bbox.center.orientation;
        let half = std::f64::consts::FRAC_1_SQRT_2;
        assert!(
            (q.y - half).abs() < 1e-12 && (q.w - half).abs() < 1e-12,
            "{q:?}"
        );
        assert_eq!([a.id.as_str(), b.id.as_str()], ["0", "1"]);
    }

    #[test]
    fn markers_clear_then_draw_a_shape_and_a_label_per_detection() {
        let header = Header::at(5, "cam");
        let markers = marker_array(&header, &detections()).markers;
        assert_eq!(markers.len(), 5);
        assert_eq!(markers[0].action, Marker::DELETE_ALL);
        assert_eq!(markers[1].kind, Marker::SPHERE);
        assert_eq!(markers[1].scale, Vector3::uniform(0.08));
        assert_eq!(markers[2].kind, Marker::TEXT_VIEW_FACING);
        assert_eq!(markers[2].text, "apple 0.90");
        assert!(
            markers[2].pose.position.y < markers[1].pose.position.y,
            "label above"
        );
        assert_eq!(markers[3].kind, Marker::CYLINDER);
        assert_eq!(markers[3].scale, Vector3::uniform(UNSIZED_MARKER_M));
        assert!(markers.iter().all(|m| m.header == header));
        assert_eq!(
            marker_array(&header, &[]).markers.len(),
            1,
            "an empty frame clears"
        );
    }
}
