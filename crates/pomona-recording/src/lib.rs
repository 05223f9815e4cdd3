//! # pomona-recording
//!
//! Robot recordings as Pomona frames. A harvesting robot's camera is usually recorded with
//! `ros2 bag record` into an MCAP file, with `rosbag record` into a ROS 1 bag, or with the
//! RealSense Viewer into a RealSense `.bag`; this crate reads any of them as a sequence of
//! synchronised RGB-D frames ([`Recording`], the format chosen by the file's magic), so every
//! detector runs on a recording as on a dataset folder — without a ROS installation.
//!
//! * [`Recording`]: colour (`rgb8`, `bgr8`), aligned depth (`16UC1` mm, `32FC1` m) and camera
//!   info on [`RecordingTopics`] (the RealSense ROS 2 driver's by default), matched by
//!   approximate time; each [`SyncedFrame`] carries the colour stamp and frame id.
//! * The messages, [`Image`], [`CameraInfo`] and [`Header`], decoded from CDR by a compact
//!   reader ([`cdr`]) that checks every length before it allocates.
//! * ROS 1 bags ([`bag`], format 2.0, chunks uncompressed, bz2 or lz4) with messages in ROS 1
//!   serialisation ([`ros1`]); RealSense SDK bags ([`realsense`]), whose raw depth is
//!   registered to the colour camera ([`register_depth`]).
//! * [`RecordingWriter`]: the same messages written as MCAP, and [`BagWriter`] as a ROS 1 bag,
//!   for fixtures and conversions.
//! * [`dataset_depth_unit_m`]: the depth unit that keeps a recording's depth when it is
//!   extracted into the dataset layout.
//!
//! The recording format is described in `docs/formats.md`.

pub mod bag;
mod bag_recording;
mod bag_writer;
mod camera_info;
pub mod cdr;
mod depth_registration;
mod depth_unit;
mod error;
mod header;
mod image_message;
pub mod message_fields;
pub mod realsense;
mod recording;
mod recording_writer;
pub mod ros1;
mod sync;
mod topics;

pub use bag::{Bag, BagConnection, BagError, BagMessage, BagMessages, BAG_MAGIC};
pub use bag_writer::{
    BagCompression, BagWriter, Ros1MessageType, ROS1_CAMERA_INFO, ROS1_FLOAT32, ROS1_IMAGE,
    ROS1_TRANSFORM,
};
pub use camera_info::{CameraInfo, CameraInfoError, RegionOfInterest, CAMERA_INFO_SCHEMA};
pub use cdr::CdrError;
pub use depth_registration::register_depth;
pub use depth_unit::{dataset_depth_unit_m, finest_unit_m, FLOAT_DEPTH_UNITS_M};
pub use error::RecordingError;
pub use header::Header;
pub use image_message::{Image, ImageError, Serialization, DEPTH_16UC1_UNIT_M, IMAGE_SCHEMA};
pub use recording::{
    frame_stem, Recording, RecordingFormat, RecordingOptions, SyncedFrame, TopicSummary,
    DEFAULT_SYNC_TOLERANCE_NS,
};
pub use recording_writer::{FrameEncodings, RecordingWriter};
pub use topics::{
    RecordingTopics, TopicRequest, DEFAULT_COLOR_TOPIC, DEFAULT_DEPTH_TOPIC, DEFAULT_INFO_TOPIC,
    ROS1_COLOR_TOPIC, ROS1_DEPTH_TOPIC, ROS1_INFO_TOPIC,
};
