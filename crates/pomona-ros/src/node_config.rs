//! What a [`crate::FruitNode`] subscribes to and publishes, and how it filters: everything a
//! launch file would set. The defaults are the RealSense ROS 2 driver's topics (namespace and
//! node both `camera`, `align_depth.enable:=true`) and Pomona's output under the node's private
//! namespace.

use pomona_recording::RecordingTopics;

use crate::RosError;

/// Settings of the node.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeConfig {
    /// The node's name (`pomona`).
    pub node_name: String,
    /// The node's namespace (`/`).
    pub namespace: String,
    /// DDS domain (`ROS_DOMAIN_ID`), 0–232.
    pub domain_id: u16,
    /// Colour image, aligned depth image and colour camera-info topics.
    pub input: RecordingTopics,
    /// `vision_msgs/Detection3DArray` output (`~/detections`).
    pub detections_topic: String,
    /// `visualization_msgs/MarkerArray` output for RViz (`~/markers`); `None` publishes none.
    pub markers_topic: Option<String>,
    /// Largest difference between the colour and depth stamps of one frame, nanoseconds (20 ms).
    pub sync_tolerance_ns: u64,
    /// Lowest calibrated confidence published (`None`: the model's operating confidence, or
    /// score ≥ 0 for a model without calibration; `Some(0.0)`: every detection).
    pub min_confidence: Option<f64>,
    /// How many frame timings [`crate::NodeStats::recent`] keeps (1000).
    pub timing_window: usize,
}

impl Default for NodeConfig {
    fn default() -> Self {
        Self {
            node_name: "pomona".into(),
            namespace: "/".into(),
            domain_id: 0,
            input: RecordingTopics::default(),
            detections_topic: "~/detections".into(),
            markers_topic: Some("~/markers".into()),
            sync_tolerance_ns: 20_000_000,
            min_confidence: None,
            timing_window: 1000,
        }
    }
}

/// The largest DDS domain id ROS 2 allows with the default port mapping.
pub const MAX_DOMAIN_ID: u16 = 232;

impl NodeConfig {
    /// Checks the values that the middleware would otherwise reject with a vague message.
    ///
    /// # Errors
    /// [`RosError::Config`] for a domain id above [`MAX_DOMAIN_ID`], a confidence outside
    /// [0, 1] or an empty timing window.
    pub fn validate(&self) -> Result<(), RosError> {
        if self.domain_id > MAX_DOMAIN_ID {
            return Err(RosError::Config {
                setting: "domain id",
                reason: format!("{} is above {MAX_DOMAIN_ID}", self.domain_id),
            });
        }
        if let Some(c) = self.min_confidence {
            if !(0.0..=1.0).contains(&c) {
                return Err(RosError::Config {
                    setting: "minimum confidence",
                    reason: format!("{c} is not in [0, 1]"),
                });
            }
        }
        if self.timing_window == 0 {
            return Err(RosError::Config {
                setting: "timing window",
                reason: "must keep at least one frame".into(),
            });
        }
        Ok(())
    }
}
