//! The RealSense SDK's bag layout: what the RealSense Viewer (librealsense `ros_writer`,
//! file version 3) records. A ROS 1 bag whose topics are named per device, sensor and stream:
//!
//! * `/device_0/sensor_1/Color_0/image/data` and `/device_0/sensor_0/Depth_0/image/data`:
//!   `sensor_msgs/Image` (colour `rgb8`/`bgr8`/`rgba8`/`bgra8`; depth `mono16`, raw Z16 units);
//! * `<stream>/info/camera_info`: `sensor_msgs/CameraInfo` of each stream (K, and librealsense's
//!   distortion names: `Brown Conrady`, `Inverse Brown Conrady`, ...);
//! * `<stream>/tf/<ref>`: `geometry_msgs/Transform`, the extrinsics from the device's reference
//!   stream (group `<ref>`) to the stream: `p_stream = R p_ref + t` (librealsense
//!   `device::get_extrinsics`); on a D400 the reference is the depth stream, so `Depth_0/tf/0` is
//!   the identity and `Color_0/tf/0` is depth→colour;
//! * `/device_0/sensor_<depth>/option/Depth Units/value`: `std_msgs/Float32`, metres per Z16
//!   unit (recent writers also append a `float32 depth_units` to every depth image, which is
//!   used when present and positive).
//!
//! Depth is NOT registered to colour in these files; [`crate::Recording`] registers it
//! (`depth_registration.rs`). Sensor and device indices differ between cameras, so the streams
//! are found by pattern: the first `Color_*` and the first `Depth_*` image stream of the lowest
//! device.

use pomona_core::nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use pomona_core::PinholeCamera;

use crate::message_fields::{FieldReader, FieldWriter};
use crate::ros1::{Ros1Reader, Ros1Writer};
use crate::{CdrError, RecordingTopics};

/// Metres per Z16 unit when a recording states none (every D400 camera's default).
pub const DEFAULT_DEPTH_UNIT_M: f64 = 0.001;

/// One stream of a RealSense bag: `/device_<d>/sensor_<s>/<Kind>_<i>`.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub struct RealSenseStream {
    /// Device index.
    pub device: u32,
    /// Sensor index.
    pub sensor: u32,
    /// Stream index.
    pub index: u32,
    /// `Color` or `Depth`.
    pub kind: String,
}

impl RealSenseStream {
    /// Parses an image-data topic `/device_<d>/sensor_<s>/<Kind>_<i>/image/data`.
    pub fn from_image_topic(topic: &str) -> Option<Self> {
        let parts: Vec<&str> = topic.split('/').collect();
        let ["", device, sensor, stream, "image", "data"] = parts.as_slice() else {
            return None;
        };
        let (kind, index) = stream.rsplit_once('_')?;
        Some(Self {
            device: device.strip_prefix("device_")?.parse().ok()?,
            sensor: sensor.strip_prefix("sensor_")?.parse().ok()?,
            index: index.parse().ok()?,
            kind: kind.to_owned(),
        })
    }

    /// `/device_<d>/sensor_<s>/<Kind>_<i>`.
    pub fn prefix(&self) -> String {
        format!(
            "/device_{}/sensor_{}/{}_{}",
            self.device, self.sensor, self.kind, self.index
        )
    }

    /// The stream's image topic.
    pub fn image_topic(&self) -> String {
        format!("{}/image/data", self.prefix())
    }

    /// The stream's camera-info topic.
    pub fn info_topic(&self) -> String {
        format!("{}/info/camera_info", self.prefix())
    }

    /// The stream's extrinsics topic relative to reference group `reference`.
    pub fn tf_topic(&self, reference: u32) -> String {
        format!("{}/tf/{reference}", self.prefix())
    }

    /// Whether `topic` is one of the stream's extrinsics topics; its reference group if so.
    pub fn tf_reference(&self, topic: &str) -> Option<u32> {
        topic
            .strip_prefix(&self.prefix())?
            .strip_prefix("/tf/")?
            .parse()
            .ok()
    }

    /// The depth-units option of the stream's sensor.
    pub fn depth_units_topic(&self) -> String {
        format!(
            "/device_{}/sensor_{}/option/Depth Units/value",
            self.device, self.sensor
        )
    }
}

/// The colour and depth streams of a RealSense bag.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RealSenseLayout {
    /// The colour stream.
    pub color: RealSenseStream,
    /// The depth stream.
    pub depth: RealSenseStream,
}

impl RealSenseLayout {
    /// The layout of a bag with these topics: the first colour and depth image streams of the
    /// lowest device that has both; `None` when there is none.
    pub fn find<'t>(topics: impl IntoIterator<Item = &'t str>) -> Option<Self> {
        let mut streams: Vec<RealSenseStream> = topics
            .into_iter()
            .filter_map(RealSenseStream::from_image_topic)
            .collect();
        streams.sort();
        streams.dedup();
        let mut devices: Vec<u32> = streams.iter().map(|s| s.device).collect();
        devices.dedup();
        devices.into_iter().find_map(|device| {
            let first = |kind: &str| {
                streams
                    .iter()
                    .find(|s| s.device == device && s.kind == kind)
                    .cloned()
            };
            Some(Self {
                color: first("Color")?,
                depth: first("Depth")?,
            })
        })
    }

    /// The three topics frames are built from: colour image, (raw) depth image, colour info.
    pub fn topics(&self) -> RecordingTopics {
        RecordingTopics {
            color: self.color.image_topic(),
            depth: self.depth.image_topic(),
            camera_info: self.color.info_topic(),
        }
    }
}

/// What registering a RealSense depth image to colour needs.
#[derive(Debug, Clone, PartialEq)]
pub struct RealSenseCalibration {
    /// The depth stream's camera.
    pub depth_camera: PinholeCamera,
    /// Depth camera frame → colour camera frame.
    pub color_from_depth: Isometry3<f64>,
    /// Metres per Z16 unit from the sensor option (or [`DEFAULT_DEPTH_UNIT_M`]); a depth image's
    /// own `depth_units` takes precedence.
    pub depth_unit_m: f64,
}

/// Reads a ROS 1 `geometry_msgs/Transform` (translation x, y, z; rotation x, y, z, w).
///
/// # Errors
/// [`CdrError::Truncated`]; [`CdrError::BadQuaternion`] for a zero or non-finite rotation.
pub fn decode_transform(payload: &[u8]) -> Result<Isometry3<f64>, CdrError> {
    let mut r = Ros1Reader::new(payload);
    let [tx, ty, tz, qx, qy, qz, qw] = r.f64_array::<7>("transform")?;
    let q = Quaternion::new(qw, qx, qy, qz);
    let norm = q.norm();
    if !(norm.is_finite() && norm > 1e-9 && [tx, ty, tz].iter().all(|v| v.is_finite())) {
        return Err(CdrError::BadQuaternion([qx, qy, qz, qw]));
    }
    Ok(Isometry3::from_parts(
        Translation3::new(tx, ty, tz),
        UnitQuaternion::from_quaternion(q),
    ))
}

/// The ROS 1 payload of a `geometry_msgs/Transform`.
pub fn encode_transform(transform: &Isometry3<f64>) -> Vec<u8> {
    let t = transform.translation.vector;
    let q = transform.rotation.quaternion();
    let mut w = Ros1Writer::new();
    w.f64_array(&[t.x, t.y, t.z, q.i, q.j, q.k, q.w]);
    w.into_bytes()
}

/// Reads a ROS 1 `std_msgs/Float32`.
///
/// # Errors
/// [`CdrError::Truncated`].
pub fn decode_float32(payload: &[u8]) -> Result<f32, CdrError> {
    Ros1Reader::new(payload).f32("data")
}

/// The ROS 1 payload of a `std_msgs/Float32`.
pub fn encode_float32(value: f32) -> Vec<u8> {
    let mut w = Ros1Writer::new();
    w.f32(value);
    w.into_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_found_by_pattern() {
        let topics = [
            "/file_version",
            "/device_0/sensor_0/Depth_0/image/data",
            "/device_0/sensor_0/Infrared_1/image/data",
            "/device_0/sensor_1/Color_0/image/data",
            "/device_0/sensor_0/Depth_0/tf/0",
        ];
        let layout = RealSenseLayout::find(topics).unwrap();
        assert_eq!(layout.color.prefix(), "/device_0/sensor_1/Color_0");
        assert_eq!(
            layout.topics().camera_info,
            "/device_0/sensor_1/Color_0/info/camera_info"
        );
        assert_eq!(
            layout.depth.depth_units_topic(),
            "/device_0/sensor_0/option/Depth Units/value"
        );
        assert_eq!(
            layout.depth.tf_reference("/device_0/sensor_0/Depth_0/tf/0"),
            Some(0)
        );
        assert_eq!(
            layout.color.tf_reference("/device_0/sensor_0/Depth_0/tf/0"),
            None
        );
        assert!(RealSenseLayout::find(["/device_0/sensor_0/Depth_0/image/data"]).is_none());
    }

    #[test]
    fn transforms_round_trip_and_bad_rotations_fail() {
        let t = Isometry3::from_parts(
            Translation3::new(0.015, -0.001, 0.0005),
            UnitQuaternion::from_euler_angles(0.01, -0.02, 0.003),
        );
        let back = decode_transform(&encode_transform(&t)).unwrap();
        assert!((back.to_homogeneous() - t.to_homogeneous()).norm() < 1e-12);
        let mut zero = encode_transform(&t);
        zero[24..].fill(0);
        assert!(matches!(
            decode_transform(&zero),
            Err(CdrError::BadQuaternion(_))
        ));
        assert!(decode_transform(&zero[..20]).is_err());
        assert_eq!(decode_float32(&encode_float32(0.0001)).unwrap(), 0.0001);
    }
}
