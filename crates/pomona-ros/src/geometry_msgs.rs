//! `geometry_msgs` types the detection and marker messages are made of, laid out field for
//! field as ROS 2 defines them, so serde's CDR encoding (what `ros2-client` puts on the wire) is
//! the one every ROS 2 node expects.

use pomona_core::nalgebra::{Point3, Unit, UnitQuaternion, Vector3 as NaVector3};
use serde::de::{Error as _, SeqAccess, Visitor};
use serde::ser::SerializeTuple;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// `geometry_msgs/msg/Point`: a position, metres.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Point {
    /// x (camera optical frame: right).
    pub x: f64,
    /// y (down).
    pub y: f64,
    /// z (forward).
    pub z: f64,
}

impl From<Point3<f64>> for Point {
    fn from(p: Point3<f64>) -> Self {
        Self {
            x: p.x,
            y: p.y,
            z: p.z,
        }
    }
}

/// `geometry_msgs/msg/Vector3`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

impl Vector3 {
    /// The same value on all three axes (a sphere's box or marker scale).
    pub fn uniform(v: f64) -> Self {
        Self { x: v, y: v, z: v }
    }
}

/// `geometry_msgs/msg/Quaternion` (x, y, z, w; identity is w = 1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Self {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

impl Quaternion {
    /// The rotation taking the frame's z axis onto `axis` (the smallest such rotation): how a
    /// box or cylinder marker whose length runs along its z is oriented along a fruit's axis.
    pub fn z_onto(axis: &Unit<NaVector3<f64>>) -> Self {
        let q = UnitQuaternion::rotation_between(&NaVector3::z(), axis.as_ref()).unwrap_or_else(
            // Opposite to z: half a turn about x.
            || UnitQuaternion::from_axis_angle(&NaVector3::x_axis(), std::f64::consts::PI),
        );
        Self {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        }
    }
}

/// `geometry_msgs/msg/Pose`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Pose {
    /// Position, metres.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

/// A row-major 6×6 covariance of x, y, z and the rotations about them: a fixed-size `float64[36]`,
/// 36 values without a length on the wire (serde derives arrays only up to 32 elements).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Covariance6(pub [f64; 36]);

impl Default for Covariance6 {
    fn default() -> Self {
        Self([0.0; 36])
    }
}

impl Serialize for Covariance6 {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut tuple = serializer.serialize_tuple(36)?;
        for v in &self.0 {
            tuple.serialize_element(v)?;
        }
        tuple.end()
    }
}

impl<'de> Deserialize<'de> for Covariance6 {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Values;
        impl<'de> Visitor<'de> for Values {
            type Value = Covariance6;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("36 float64 values")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Covariance6, A::Error> {
                let mut values = [0.0; 36];
                for (i, v) in values.iter_mut().enumerate() {
                    *v = seq
                        .next_element()?
                        .ok_or_else(|| A::Error::invalid_length(i, &self))?;
                }
                Ok(Covariance6(values))
            }
        }
        deserializer.deserialize_tuple(36, Values)
    }
}

/// `geometry_msgs/msg/PoseWithCovariance`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct PoseWithCovariance {
    /// The pose.
    pub pose: Pose,
    /// Its covariance (all zero: Pomona does not estimate one).
    pub covariance: Covariance6,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rotate_z(q: Quaternion) -> NaVector3<f64> {
        let q = UnitQuaternion::new_normalize(pomona_core::nalgebra::Quaternion::new(
            q.w, q.x, q.y, q.z,
        ));
        q * NaVector3::z()
    }

    #[test]
    fn z_onto_takes_z_to_the_axis_including_the_opposite_one() {
        for axis in [
            NaVector3::new(1.0, 0.0, 0.0),
            NaVector3::new(0.3, -0.5, 0.8),
            NaVector3::new(0.0, 0.0, 1.0),
            NaVector3::new(0.0, 0.0, -1.0),
        ] {
            let axis = Unit::new_normalize(axis);
            let turned = rotate_z(Quaternion::z_onto(&axis));
            assert!(
                (turned - axis.into_inner()).norm() < 1e-12,
                "{axis:?} → {turned:?}"
            );
        }
    }
}
