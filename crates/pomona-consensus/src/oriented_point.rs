//! The data the shape estimators consume: a 3D position, optionally with a surface normal.
//!
//! Sphere fitting needs positions only; cylinder fitting (Schnabel et al. 2007) needs a normal per
//! point. One datum type with an optional normal lets one cluster feed both estimators, and the
//! [`Positioned`] trait lets the sphere estimator also run on bare `Point3<f64>` slices.

use nalgebra::{Point3, Unit, Vector3};
use pomona_core::PointCloud;
use serde::{Deserialize, Serialize};

/// Anything with a 3D position (metres) and possibly a unit surface normal.
pub trait Positioned {
    /// Position, metres.
    fn position(&self) -> Point3<f64>;

    /// Unit surface normal, when known.
    fn normal(&self) -> Option<Unit<Vector3<f64>>> {
        None
    }

    /// Whether the position is finite (invalid points are skipped by every algorithm here).
    fn has_finite_position(&self) -> bool {
        self.position().iter().all(|c| c.is_finite())
    }
}

impl Positioned for Point3<f64> {
    fn position(&self) -> Point3<f64> {
        *self
    }
}

/// A point with an optional unit surface normal, in one frame (usually the camera's), metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OrientedPoint {
    /// Position, metres.
    pub position: Point3<f64>,
    /// Unit surface normal, `None` where it could not be estimated.
    pub normal: Option<Unit<Vector3<f64>>>,
}

impl OrientedPoint {
    /// A point with a normal; a zero or non-finite `normal` is stored as `None`.
    pub fn new(position: Point3<f64>, normal: Vector3<f64>) -> Self {
        let normal = if normal.iter().all(|c| c.is_finite()) {
            Unit::try_new(normal, 1e-12)
        } else {
            None
        };
        Self { position, normal }
    }

    /// A point without a normal.
    pub fn without_normal(position: Point3<f64>) -> Self {
        Self {
            position,
            normal: None,
        }
    }

    /// One datum per cloud point, in cloud order (so indices match), converted to `f64`; normals
    /// come from the cloud's normal attribute when present (`NaN` normals become `None`).
    /// Invalid points stay in place as non-finite positions, which every algorithm here skips.
    pub fn from_cloud(cloud: &PointCloud) -> Vec<Self> {
        let normals = cloud.normals();
        cloud
            .points()
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let position = p.cast::<f64>();
                match normals.and_then(|n| n.get(i)) {
                    Some(n) => Self::new(position, n.cast::<f64>()),
                    None => Self::without_normal(position),
                }
            })
            .collect()
    }

    /// Pairs positions with normals as produced by [`crate::normals`] (`None` stays `None`).
    ///
    /// Extra entries of the longer slice are ignored.
    pub fn zip(points: &[Point3<f64>], normals: &[Option<Unit<Vector3<f64>>>]) -> Vec<Self> {
        points
            .iter()
            .zip(normals)
            .map(|(p, n)| Self {
                position: *p,
                normal: *n,
            })
            .collect()
    }
}

impl Positioned for OrientedPoint {
    fn position(&self) -> Point3<f64> {
        self.position
    }

    fn normal(&self) -> Option<Unit<Vector3<f64>>> {
        self.normal
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_cloud_keeps_indices_and_drops_nan_normals() {
        let cloud = PointCloud::unorganized(vec![
            Point3::new(0.0, 0.0, 1.0),
            Point3::new(f32::NAN, f32::NAN, f32::NAN),
            Point3::new(0.1, 0.0, 1.0),
        ])
        .with_normals(vec![
            Vector3::new(0.0, 0.0, -2.0),
            Vector3::repeat(f32::NAN),
            Vector3::repeat(f32::NAN),
        ])
        .unwrap();
        let data = OrientedPoint::from_cloud(&cloud);
        assert_eq!(data.len(), 3);
        assert_eq!(
            data[0].normal.unwrap().into_inner(),
            Vector3::new(0.0, 0.0, -1.0)
        );
        assert!(!data[1].has_finite_position());
        assert!(data[2].normal.is_none() && data[2].has_finite_position());
        let bare = OrientedPoint::from_cloud(&PointCloud::unorganized(vec![Point3::origin()]));
        assert!(bare[0].normal.is_none());
    }
}
