//! The serde structs this crate publishes and subscribes with are encoded by `ros2-client` in
//! CDR through serde. These tests check that encoding against Pomona's own field-by-field CDR
//! codec (`pomona-recording`, which reads real ROS 2 recordings) for the `sensor_msgs` the node
//! receives, and the byte layout of the messages it sends.

#![allow(clippy::unwrap_used)]

use byteorder::LittleEndian;
use pomona_recording::{CameraInfo, Header, Image};
use pomona_ros::geometry_msgs::{Point, Pose, Quaternion, Vector3};
use pomona_ros::vision_msgs::{
    BoundingBox3D, Detection3D, Detection3DArray, ObjectHypothesis, ObjectHypothesisWithPose,
};
use pomona_ros::visualization_msgs::{Marker, MarkerArray};

/// Serde CDR bytes of `value`, little endian, without the 4-byte encapsulation header.
fn serde_cdr<T: serde::Serialize>(value: &T) -> Vec<u8> {
    cdr_encoding::to_vec::<T, LittleEndian>(value).unwrap()
}

fn from_serde_cdr<T: serde::de::DeserializeOwned>(bytes: &[u8]) -> T {
    cdr_encoding::from_bytes::<T, LittleEndian>(bytes)
        .unwrap()
        .0
}

#[test]
fn image_and_camera_info_encode_as_pomonas_own_cdr_codec_does() {
    let image = Image {
        header: Header::at(1_700_000_000_123_456_789, "camera_color_optical_frame"),
        height: 2,
        width: 3,
        encoding: "rgb8".into(),
        is_bigendian: 0,
        step: 9,
        data: (0..18).collect(),
    };
    let own = image.to_cdr();
    assert_eq!(serde_cdr(&image), own[4..]);
    assert_eq!(from_serde_cdr::<Image>(&own[4..]), image);

    let mut info = CameraInfo {
        header: Header::at(42, "cam"),
        height: 424,
        width: 512,
        distortion_model: "plumb_bob".into(),
        d: vec![0.1, -0.2, 0.0, 0.0, 0.01],
        ..CameraInfo::default()
    };
    info.k = [365.0, 0.0, 256.0, 0.0, 365.0, 212.0, 0.0, 0.0, 1.0];
    info.p[0] = 365.0;
    info.roi.width = 512;
    info.roi.do_rectify = true;
    let own = info.to_cdr();
    assert_eq!(serde_cdr(&info), own[4..]);
    assert_eq!(from_serde_cdr::<CameraInfo>(&own[4..]), info);
}

#[test]
fn detection_array_has_the_ros_layout() {
    let header = Header::at(3_000_000_007, "cam");
    let pose = Pose {
        position: Point {
            x: 0.1,
            y: 0.2,
            z: 0.7,
        },
        orientation: Quaternion::default(),
    };
    let array = Detection3DArray {
        header: header.clone(),
        detections: vec![Detection3D {
            header,
            results: vec![ObjectHypothesisWithPose {
                hypothesis: ObjectHypothesis {
                    class_id: "apple".into(),
                    score: 0.75,
                },
                pose: pomona_ros::geometry_msgs::PoseWithCovariance {
                    pose,
                    ..Default::default()
                },
            }],
            bbox: BoundingBox3D {
                center: pose,
                size: Vector3::uniform(0.08),
            },
            id: "0".into(),
        }],
    };
    let bytes = serde_cdr(&array);
    assert_eq!(from_serde_cdr::<Detection3DArray>(&bytes), array);
    // Header: sec, nanosec, frame_id "cam\0" (length 4) = 16 bytes; detection count 4 → 20.
    assert_eq!(&bytes[..4], &3i32.to_le_bytes());
    assert_eq!(&bytes[4..8], &7u32.to_le_bytes());
    assert_eq!(&bytes[8..12], &4u32.to_le_bytes());
    assert_eq!(&bytes[12..16], b"cam\0");
    assert_eq!(&bytes[16..20], &1u32.to_le_bytes());
    // The detection's header again (16), one result (4), class_id "apple\0" (4 + 6, then 6
    // bytes of padding to align the f64 score at 8): score at 20 + 16 + 4 + 10 + 6 = 56.
    assert_eq!(&bytes[56..64], &0.75f64.to_le_bytes());
    // Pose (7 f64) and 36 covariance values follow without a length; then the box pose (7)
    // and size (3) and the id string: 64 + 8 × (7 + 36 + 7 + 3) = 488.
    assert_eq!(&bytes[64..72], &0.1f64.to_le_bytes());
    assert_eq!(&bytes[488..492], &2u32.to_le_bytes(), "id length");
    assert_eq!(&bytes[492..494], b"0\0");
    assert_eq!(bytes.len(), 494);
}

#[test]
fn markers_round_trip() {
    let markers = MarkerArray {
        markers: vec![
            Marker {
                action: Marker::DELETE_ALL,
                ..Marker::default()
            },
            Marker {
                ns: "pomona_fruit".into(),
                id: 3,
                kind: Marker::SPHERE,
                text: "apple 0.90".into(),
                ..Marker::default()
            },
        ],
    };
    assert_eq!(from_serde_cdr::<MarkerArray>(&serde_cdr(&markers)), markers);
}
