//! `visualization_msgs` (ROS 2 Jazzy layout, with the texture and mesh fields added in Humble):
//! the markers RViz draws. Only spheres, cylinders, text and "delete all" are used here, but
//! every field is present: DDS readers decode by layout, not by name.

use pomona_recording::Header;
use serde::{Deserialize, Serialize};

use crate::geometry_msgs::{Point, Pose, Vector3};

/// `std_msgs/msg/ColorRGBA`, components in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ColorRgba {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
    /// Opacity.
    pub a: f32,
}

/// `builtin_interfaces/msg/Duration`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Duration {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds (`< 1e9`).
    pub nanosec: u32,
}

/// `sensor_msgs/msg/CompressedImage` (a marker's texture).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct CompressedImage {
    /// Stamp and frame.
    pub header: Header,
    /// `jpeg` or `png`.
    pub format: String,
    /// The compressed bytes.
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/UVCoordinate`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct UvCoordinate {
    /// u.
    pub u: f32,
    /// v.
    pub v: f32,
}

/// `visualization_msgs/msg/MeshFile`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct MeshFile {
    /// File name (its extension tells the format).
    pub filename: String,
    /// The file's bytes.
    pub data: Vec<u8>,
}

/// `visualization_msgs/msg/Marker`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Marker {
    /// Stamp and frame the pose is in.
    pub header: Header,
    /// Namespace; with `id` it names the marker.
    pub ns: String,
    /// Identifier within the namespace.
    pub id: i32,
    /// Shape ([`Marker::SPHERE`], [`Marker::CYLINDER`], [`Marker::TEXT_VIEW_FACING`], ...).
    #[serde(rename = "type")]
    pub kind: i32,
    /// [`Marker::ADD`] or [`Marker::DELETE_ALL`].
    pub action: i32,
    /// Pose of the shape.
    pub pose: Pose,
    /// Size along x, y, z (text: z is the letter height).
    pub scale: Vector3,
    /// Colour.
    pub color: ColorRgba,
    /// How long the marker stays (0: until replaced or deleted).
    pub lifetime: Duration,
    /// Whether the marker follows its frame when the frame moves.
    pub frame_locked: bool,
    /// Points of line and list markers.
    pub points: Vec<Point>,
    /// Per-point colours.
    pub colors: Vec<ColorRgba>,
    /// Texture resource (unused).
    pub texture_resource: String,
    /// Texture (unused).
    pub texture: CompressedImage,
    /// Texture coordinates (unused).
    pub uv_coordinates: Vec<UvCoordinate>,
    /// Text of text markers.
    pub text: String,
    /// Mesh resource (unused).
    pub mesh_resource: String,
    /// Embedded mesh (unused).
    pub mesh_file: MeshFile,
    /// Whether a mesh uses its own materials.
    pub mesh_use_embedded_materials: bool,
}

impl Marker {
    /// `type`: a sphere (scale: the diameters).
    pub const SPHERE: i32 = 2;
    /// `type`: a cylinder along the pose's z (scale: two diameters and the length).
    pub const CYLINDER: i32 = 3;
    /// `type`: text that faces the viewer.
    pub const TEXT_VIEW_FACING: i32 = 9;
    /// `action`: add or replace.
    pub const ADD: i32 = 0;
    /// `action`: delete every marker of this publisher (namespace-wide in RViz 2).
    pub const DELETE_ALL: i32 = 3;
}

/// `visualization_msgs/msg/MarkerArray`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct MarkerArray {
    /// The markers, applied in order.
    pub markers: Vec<Marker>,
}
