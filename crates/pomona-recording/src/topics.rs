//! Which topics of a recording hold the colour image, the aligned depth image and the colour
//! camera's intrinsics. The defaults are those of the RealSense ROS 2 driver (`realsense2_camera`
//! with `align_depth.enable:=true`), whose namespace and node are both `camera`.

use serde::{Deserialize, Serialize};

/// The RealSense ROS 2 driver's colour topic.
pub const DEFAULT_COLOR_TOPIC: &str = "/camera/camera/color/image_raw";
/// The RealSense ROS 2 driver's depth-aligned-to-colour topic.
pub const DEFAULT_DEPTH_TOPIC: &str = "/camera/camera/aligned_depth_to_color/image_raw";
/// The RealSense ROS 2 driver's colour camera-info topic.
pub const DEFAULT_INFO_TOPIC: &str = "/camera/camera/color/camera_info";

/// The three topics a frame is built from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RecordingTopics {
    /// `sensor_msgs/msg/Image`, `rgb8` or `bgr8`.
    pub color: String,
    /// `sensor_msgs/msg/Image` registered to the colour camera, `16UC1` or `32FC1`.
    pub depth: String,
    /// `sensor_msgs/msg/CameraInfo` of the colour camera.
    pub camera_info: String,
}

impl Default for RecordingTopics {
    fn default() -> Self {
        Self {
            color: DEFAULT_COLOR_TOPIC.to_owned(),
            depth: DEFAULT_DEPTH_TOPIC.to_owned(),
            camera_info: DEFAULT_INFO_TOPIC.to_owned(),
        }
    }
}
