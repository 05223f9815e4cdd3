//! Pomona on a ROS 2 robot, in pure Rust: no ROS installation is needed to build, test or run
//! it (the DDS middleware is RustDDS, through `ros2-client`), yet it speaks to ROS 2 nodes on the
//! same domain like any other node.
//!
//! [`FruitNode`] subscribes to a camera's colour image, depth image aligned to colour and colour
//! camera info (`sensor_msgs`), pairs them by stamp ([`live_sync`]), runs a [`pomona::Detector`]
//! on the newest frame ([`latest_frame`]) and publishes `vision_msgs/Detection3DArray` and RViz
//! markers ([`detection_messages`]). The messages are plain serde structs laid out as in ROS
//! ([`geometry_msgs`], [`vision_msgs`], [`visualization_msgs`]; `sensor_msgs` Image and
//! CameraInfo come from `pomona-recording`, which reads the same messages from recordings), so the
//! frames a node builds are exactly those `pomona detect --recording` builds from a recording of
//! the same topics.
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let detector = pomona::Detector::builtin("shape-fit")?;
//! let node = pomona_ros::FruitNode::start(detector, pomona_ros::NodeConfig::default())?;
//! std::thread::sleep(std::time::Duration::from_secs(60));
//! let stats = node.shutdown()?;
//! println!("{} frames published", stats.published);
//! # Ok(())
//! # }
//! ```

pub mod detection_messages;
mod error;
mod fruit_node;
pub mod geometry_msgs;
mod latency_summary;
pub mod latest_frame;
pub mod live_sync;
mod node_config;
mod ros_message;
mod topic_name;
pub mod vision_msgs;
pub mod visualization_msgs;

pub use error::RosError;
pub use fruit_node::{decode_frame, FrameTiming, FruitNode, NodeStats, NodeTopics};
pub use latency_summary::LatencySummary;
pub use node_config::{NodeConfig, MAX_DOMAIN_ID};
pub use ros_message::RosMessage;
pub use topic_name::resolve_topic;
