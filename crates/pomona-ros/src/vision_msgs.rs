//! `vision_msgs` (ROS 2, version 4 as in Humble and Jazzy): the standard 3D detection messages a
//! robot's planner subscribes to. Fields in ROS order; see [`crate::detection_messages`] for how a
//! Pomona detection fills them.

use pomona_recording::Header;
use serde::{Deserialize, Serialize};

use crate::geometry_msgs::{Pose, PoseWithCovariance, Vector3};

/// `vision_msgs/msg/ObjectHypothesis`: a class and its score.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ObjectHypothesis {
    /// Class name (`"apple"`, or `"fruit"` when the method does not tell kinds apart).
    pub class_id: String,
    /// Score of the class.
    pub score: f64,
}

/// `vision_msgs/msg/ObjectHypothesisWithPose`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ObjectHypothesisWithPose {
    /// Class and score.
    pub hypothesis: ObjectHypothesis,
    /// Pose of the object under this hypothesis.
    pub pose: PoseWithCovariance,
}

/// `vision_msgs/msg/BoundingBox3D`: a box centred on a pose.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct BoundingBox3D {
    /// Centre and orientation of the box.
    pub center: Pose,
    /// Edge lengths along the box's x, y and z, metres.
    pub size: Vector3,
}

/// `vision_msgs/msg/Detection3D`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Detection3D {
    /// Stamp and frame of the image the object was found in.
    pub header: Header,
    /// Class hypotheses, best first.
    pub results: Vec<ObjectHypothesisWithPose>,
    /// The object's box.
    pub bbox: BoundingBox3D,
    /// An identifier of the detection (unique within its array).
    pub id: String,
}

/// `vision_msgs/msg/Detection3DArray`: every object found in one frame.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Detection3DArray {
    /// Stamp and frame of the image.
    pub header: Header,
    /// The detections (empty when the frame held none).
    pub detections: Vec<Detection3D>,
}
