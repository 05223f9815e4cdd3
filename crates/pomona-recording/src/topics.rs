//! Which topics of a recording hold the colour image, the aligned depth image and the colour
//! camera's intrinsics. The defaults depend on the recording's format: those of the RealSense
//! ROS 2 driver (`realsense2_camera` with `align_depth.enable:=true`, namespace and node both
//! `camera`) for MCAP files, those of the RealSense ROS 1 driver (`rs_camera.launch
//! align_depth:=true`) for ROS 1 bags. A [`TopicRequest`] names the topics a user chose; the
//! others take the format's default.

use serde::{Deserialize, Serialize};

/// The RealSense ROS 2 driver's colour topic.
pub const DEFAULT_COLOR_TOPIC: &str = "/camera/camera/color/image_raw";
/// The RealSense ROS 2 driver's depth-aligned-to-colour topic.
pub const DEFAULT_DEPTH_TOPIC: &str = "/camera/camera/aligned_depth_to_color/image_raw";
/// The RealSense ROS 2 driver's colour camera-info topic.
pub const DEFAULT_INFO_TOPIC: &str = "/camera/camera/color/camera_info";

/// The RealSense ROS 1 driver's colour topic.
pub const ROS1_COLOR_TOPIC: &str = "/camera/color/image_raw";
/// The RealSense ROS 1 driver's depth-aligned-to-colour topic.
pub const ROS1_DEPTH_TOPIC: &str = "/camera/aligned_depth_to_color/image_raw";
/// The RealSense ROS 1 driver's colour camera-info topic.
pub const ROS1_INFO_TOPIC: &str = "/camera/color/camera_info";

/// The three topics a frame is built from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RecordingTopics {
    /// `sensor_msgs/Image`, `rgb8` or `bgr8`.
    pub color: String,
    /// `sensor_msgs/Image` registered to the colour camera, `16UC1` or `32FC1`.
    pub depth: String,
    /// `sensor_msgs/CameraInfo` of the colour camera.
    pub camera_info: String,
}

impl Default for RecordingTopics {
    /// The RealSense ROS 2 driver's topics.
    fn default() -> Self {
        Self {
            color: DEFAULT_COLOR_TOPIC.to_owned(),
            depth: DEFAULT_DEPTH_TOPIC.to_owned(),
            camera_info: DEFAULT_INFO_TOPIC.to_owned(),
        }
    }
}

impl RecordingTopics {
    /// The RealSense ROS 1 driver's topics.
    pub fn ros1() -> Self {
        Self {
            color: ROS1_COLOR_TOPIC.to_owned(),
            depth: ROS1_DEPTH_TOPIC.to_owned(),
            camera_info: ROS1_INFO_TOPIC.to_owned(),
        }
    }
}

/// The topics asked for: each `None` takes the recording format's default.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct TopicRequest {
    /// Colour topic.
    pub color: Option<String>,
    /// Depth topic.
    pub depth: Option<String>,
    /// Camera-info topic.
    pub camera_info: Option<String>,
}

impl TopicRequest {
    /// Whether no topic was named (so a ROS 1 bag may be read in the RealSense SDK layout).
    pub fn is_empty(&self) -> bool {
        self.color.is_none() && self.depth.is_none() && self.camera_info.is_none()
    }

    /// The topics asked for, `defaults` where none was named.
    pub fn resolve(&self, defaults: RecordingTopics) -> RecordingTopics {
        RecordingTopics {
            color: self.color.clone().unwrap_or(defaults.color),
            depth: self.depth.clone().unwrap_or(defaults.depth),
            camera_info: self.camera_info.clone().unwrap_or(defaults.camera_info),
        }
    }
}

impl From<RecordingTopics> for TopicRequest {
    fn from(topics: RecordingTopics) -> Self {
        Self {
            color: Some(topics.color),
            depth: Some(topics.depth),
            camera_info: Some(topics.camera_info),
        }
    }
}
