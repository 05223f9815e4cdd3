//! # pomona-core
//!
//! The data model every other Pomona crate speaks: a pinhole camera, colour and depth images, a
//! registered RGB-D frame, point clouds, and the records that describe fruit (ground truth) and
//! what a detector found (detections).
//!
//! This crate has no I/O and no algorithms beyond the geometry that *defines* the types
//! (back-projection and projection) and the colour space the detectors share (RGB → HSV and
//! circular hue statistics, [`rgb_to_hsv`]), plus the one cloud reduction every stage may want
//! ([`voxel_downsample`]). Reading files lives in `pomona-io`; detectors live above it.
//! Keeping the bottom layer small means every algorithm crate can depend on it without pulling in
//! image codecs or file formats.
//!
//! ## Conventions
//! * Camera frame: OpenCV convention — x right, y down, z forward (optical axis), metres.
//! * Pixel coordinates: `u` is the column, `v` the row; integer pixel `(u, v)` is the *centre* of
//!   that pixel, so the principal point `(cx, cy)` is in the same units OpenCV calibration yields.
//! * Missing depth is `NaN` in memory (0 in 16-bit files); invalid cloud points are all-`NaN`.

mod camera;
mod cloud;
mod color_image;
mod depth_image;
mod detection;
mod error;
mod frame;
mod hsv;
mod image_circle;
mod instance_mask;
mod pixel_box;
mod quantile;
mod radial_distortion;
mod range_checked;
mod truth;
mod voxel_grid;

pub use camera::PinholeCamera;
pub use cloud::{CloudLayout, PointCloud};
pub use color_image::ColorImage;
pub use depth_image::DepthImage;
pub use detection::{Detection, FrameDetections, SYMMETRY_PLANE_PIPELINES};
pub use error::CoreError;
pub use frame::RgbdFrame;
pub use hsv::{circular_mean_hue, hue_difference, rgb_to_hsv};
pub use image_circle::ImageCircle;
pub use instance_mask::InstanceMask;
pub use pixel_box::PixelBox;
pub use quantile::{median, quantile};
pub use radial_distortion::{RadialDistortion, UNDISTORT_ITERATIONS};
pub use truth::{FrameTruth, FruitTruth};
pub use voxel_grid::voxel_downsample;

/// Re-exported so downstream crates name the same nalgebra version.
pub use nalgebra;
