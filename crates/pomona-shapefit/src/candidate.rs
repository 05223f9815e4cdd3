//! A fruit candidate: one shape found by MSAC in one cluster, with the pixels that support it.

use pomona_consensus::nalgebra::{Point3, Unit, Vector3};
use pomona_consensus::Shape;

/// A shape and its inliers.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// The fitted sphere or cylinder (camera frame, metres).
    pub shape: Shape,
    /// Row-major pixel indices of the inliers.
    pub pixels: Vec<usize>,
    /// Inlier positions, camera frame.
    pub points: Vec<Point3<f64>>,
    /// Inlier normals (towards the camera), where defined, when the shape stage estimated them
    /// (its estimators read normals: cylinders, or a sphere normal-angle test); `None`
    /// otherwise, and the descriptor estimates only the normals it samples.
    pub normals: Option<Vec<Option<Unit<Vector3<f64>>>>>,
}
