//! # pomona-recording
//!
//! Robot recordings as Pomona frames. A harvesting robot's camera is usually recorded with
//! `ros2 bag record` into an MCAP file; this crate reads such a file as a sequence of
//! synchronised RGB-D frames ([`Recording`]), so every detector runs on a recording as on a
//! dataset folder — without a ROS installation.
//!
//! * [`Recording`]: colour (`rgb8`, `bgr8`), aligned depth (`16UC1` mm, `32FC1` m) and camera
//!   info on [`RecordingTopics`] (the RealSense ROS 2 driver's by default), matched by
//!   approximate time; each [`SyncedFrame`] carries the colour stamp and frame id.
//! * The messages, [`Image`], [`CameraInfo`] and [`Header`], decoded from CDR by a compact
//!   reader ([`cdr`]) that checks every length before it allocates.
//! * [`RecordingWriter`]: the same messages written as MCAP, for fixtures and conversions.
//! * [`dataset_depth_unit_m`]: the depth unit that keeps a recording's depth when it is
//!   extracted into the dataset layout.
//!
//! The recording format is described in `docs/formats.md`.

mod camera_info;
pub mod cdr;
mod depth_unit;
mod error;
mod header;
mod image_message;
mod recording;
mod recording_writer;
mod sync;
mod topics;

pub use camera_info::{CameraInfo, CameraInfoError, RegionOfInterest, CAMERA_INFO_SCHEMA};
pub use cdr::CdrError;
pub use depth_unit::{dataset_depth_unit_m, finest_unit_m, FLOAT_DEPTH_UNITS_M};
pub use error::RecordingError;
pub use header::Header;
pub use image_message::{Image, ImageError, DEPTH_16UC1_UNIT_M, IMAGE_SCHEMA};
pub use recording::{
    frame_stem, Recording, RecordingOptions, SyncedFrame, TopicSummary, DEFAULT_SYNC_TOLERANCE_NS,
};
pub use recording_writer::{FrameEncodings, RecordingWriter};
pub use topics::{RecordingTopics, DEFAULT_COLOR_TOPIC, DEFAULT_DEPTH_TOPIC, DEFAULT_INFO_TOPIC};
