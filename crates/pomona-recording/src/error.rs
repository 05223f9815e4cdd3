//! Everything that can go wrong reading or writing a recording. Every message names the
//! recording file; message-level errors also name the topic and the header stamp.

use std::path::PathBuf;

use crate::{CameraInfoError, CdrError, ImageError};

/// A recording that could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// The file could not be opened, read, created or renamed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The recording.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The MCAP container is truncated or corrupt (or could not be written).
    #[error("{} is not a readable MCAP file (truncated or corrupt?): {source}", path.display())]
    Mcap {
        /// The recording.
        path: PathBuf,
        /// What the MCAP reader or writer reported.
        source: mcap::McapError,
    },
    /// The ROS 1 bag container is truncated or corrupt, or not format 2.0.
    #[error("{} is not a readable ROS 1 bag: {source}", path.display())]
    Bag {
        /// The recording.
        path: PathBuf,
        /// What is wrong.
        source: crate::BagError,
    },
    /// The file is neither an MCAP recording nor a ROS 1 bag.
    #[error(
        "{} is neither an MCAP recording (magic \\x89MCAP0) nor a ROS 1 bag (#ROSBAG V2.0); \
         it starts with {start:?}",
        path.display()
    )]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// Its first bytes, lossily as text.
        start: String,
    },
    /// A RealSense bag whose calibration cannot be used (missing camera info or extrinsics,
    /// bad depth units).
    #[error("{}: RealSense recording: {what}", path.display())]
    RealSense {
        /// The recording.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
    /// A bag being written got a second message type on one topic.
    #[error("{}: topic `{topic}` was written as `{first}`, now `{now}`", path.display())]
    BagTopicType {
        /// The bag being written.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// The type it was first written with.
        first: String,
        /// The type now.
        now: String,
    },
    /// A requested topic has no messages in the recording.
    #[error(
        "{} has no messages on the {role} topic `{topic}` (choose another with {flag}); \
         its topics: {available}",
        path.display()
    )]
    MissingTopic {
        /// The recording.
        path: PathBuf,
        /// "colour", "depth" or "camera info".
        role: &'static str,
        /// The topic asked for.
        topic: String,
        /// The command-line flag that chooses it.
        flag: &'static str,
        /// Every topic of the recording with its schema name and message count.
        available: String,
    },
    /// A requested topic carries another message type or encoding.
    #[error(
        "{}: topic `{topic}` carries `{schema}` in `{encoding}` encoding, expected `{expected}` \
         in `{expected_encoding}`",
        path.display()
    )]
    WrongSchema {
        /// The recording.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// Its schema name.
        schema: String,
        /// Its message encoding.
        encoding: String,
        /// The schema name expected.
        expected: &'static str,
        /// The message encoding expected (`cdr`, `ros1`).
        expected_encoding: crate::Serialization,
    },
    /// A message payload is not valid CDR (or ROS 1 serialisation) of its type.
    #[error("{}: message on `{topic}` logged at {log_time_ns} ns: {source}", path.display())]
    Cdr {
        /// The recording.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// The message's log time (its header could not be read).
        log_time_ns: u64,
        /// What is wrong.
        source: CdrError,
    },
    /// A header stamp before the epoch or with nanoseconds out of range.
    #[error("{}: message on `{topic}` has an invalid header stamp {sec} s {nanosec} ns", path.display())]
    BadStamp {
        /// The recording.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// Seconds.
        sec: i32,
        /// Nanoseconds.
        nanosec: u32,
    },
    /// An image's pixels could not be converted (encoding, size).
    #[error("{}: image on `{topic}` stamped {stamp_ns} ns: {source}", path.display())]
    Image {
        /// The recording.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// The header stamp.
        stamp_ns: u64,
        /// What is wrong.
        source: Box<ImageError>,
    },
    /// Camera info that gives no Pomona camera.
    #[error("{}: camera info on `{topic}` stamped {stamp_ns} ns: {source}", path.display())]
    CameraInfo {
        /// The recording.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// The header stamp.
        stamp_ns: u64,
        /// What is wrong.
        source: Box<CameraInfoError>,
    },
    /// Colour, depth and camera info of one synchronised frame disagree (in size).
    #[error("{}: frame stamped {stamp_ns} ns: {source}", path.display())]
    Frame {
        /// The recording.
        path: PathBuf,
        /// The colour stamp.
        stamp_ns: u64,
        /// What is wrong.
        source: pomona_core::CoreError,
    },
    /// A frame index past the end.
    #[error("{}: no synchronised frame {index} (the recording has {count})", path.display())]
    NoSuchFrame {
        /// The recording.
        path: PathBuf,
        /// The index asked for.
        index: usize,
        /// Synchronised frames.
        count: usize,
    },
    /// The frame to write has no colour.
    #[error("{}: frame stamped {stamp_ns} ns has no colour image to record", path.display())]
    NoColor {
        /// The recording being written.
        path: PathBuf,
        /// The stamp.
        stamp_ns: u64,
    },
}

impl RecordingError {
    /// The recording file the error is about.
    pub fn path(&self) -> &std::path::Path {
        match self {
            Self::Io { path, .. }
            | Self::Mcap { path, .. }
            | Self::Bag { path, .. }
            | Self::UnknownFormat { path, .. }
            | Self::RealSense { path, .. }
            | Self::BagTopicType { path, .. }
            | Self::MissingTopic { path, .. }
            | Self::WrongSchema { path, .. }
            | Self::Cdr { path, .. }
            | Self::BadStamp { path, .. }
            | Self::Image { path, .. }
            | Self::CameraInfo { path, .. }
            | Self::Frame { path, .. }
            | Self::NoSuchFrame { path, .. }
            | Self::NoColor { path, .. } => path,
        }
    }
}
