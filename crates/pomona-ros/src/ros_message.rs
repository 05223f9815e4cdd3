//! The ROS type of each message the node sends or receives, named once: DDS matches a publisher
//! and a subscription by topic name *and* type name (`sensor_msgs::msg::dds_::Image_`), so every
//! participant — the node, the tests, the latency example — must spell it the same way. The
//! `sensor_msgs` names are the schema names `pomona-recording` already uses for MCAP channels.

use pomona_recording::{CameraInfo, Image, CAMERA_INFO_SCHEMA, IMAGE_SCHEMA};
use ros2_client::MessageTypeName;
use serde::{de::DeserializeOwned, Serialize};

use crate::vision_msgs::Detection3DArray;
use crate::visualization_msgs::MarkerArray;

/// A message with a ROS type, `package/msg/Name`.
pub trait RosMessage: Serialize + DeserializeOwned + 'static {
    /// The ROS type, e.g. `sensor_msgs/msg/Image`.
    const ROS_TYPE: &'static str;

    /// The type as `ros2-client` takes it (package and name; the `msg` part is implied).
    fn type_name() -> MessageTypeName {
        let package = Self::ROS_TYPE.split('/').next().unwrap_or_default();
        let name = Self::ROS_TYPE.rsplit('/').next().unwrap_or_default();
        MessageTypeName::new(package, name)
    }
}

impl RosMessage for Image {
    const ROS_TYPE: &'static str = IMAGE_SCHEMA;
}

impl RosMessage for CameraInfo {
    const ROS_TYPE: &'static str = CAMERA_INFO_SCHEMA;
}

impl RosMessage for Detection3DArray {
    const ROS_TYPE: &'static str = "vision_msgs/msg/Detection3DArray";
}

impl RosMessage for MarkerArray {
    const ROS_TYPE: &'static str = "visualization_msgs/msg/MarkerArray";
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn package_and_name_from_the_ros_type() {
        let t = Image::type_name();
        assert_eq!((t.package_name(), t.type_name()), ("sensor_msgs", "Image"));
        let t = Detection3DArray::type_name();
        assert_eq!(
            (t.package_name(), t.type_name()),
            ("vision_msgs", "Detection3DArray")
        );
    }
}
