//! A recording — a ROS 2 MCAP file, a ROS 1 bag, or a RealSense SDK bag — opened as a sequence
//! of synchronised RGB-D frames.
//!
//! The format is chosen by the file's first bytes, not its name: `\x89MCAP0` is MCAP (messages
//! in CDR), `#ROSBAG V2.0` a ROS 1 bag (ROS 1 serialisation; `bag_recording.rs`). A ROS 1 bag
//! opened without topic choices whose RealSense-driver topics are absent but which has
//! `/device_*` streams is read in the RealSense SDK layout (`realsense.rs`), whose raw depth is
//! registered to the colour camera when a frame is loaded (`depth_registration.rs`).
//!
//! Opening reads the file once: every message of the colour, depth and camera-info topics is
//! kept (its CDR payload, not yet decoded into pixels) with its header stamp, and the frames are
//! matched by approximate time (`sync.rs`). Pixels are decoded per frame by
//! [`Recording::load_frame`], which takes `&self`, so frames can be loaded in parallel. Memory is
//! about the size of the three topics' messages (the rest of the file is dropped after opening).
//!
//! Colour messages without a depth message within the tolerance are not frames; they are
//! counted and their stamps kept ([`Recording::unmatched_color_ns`]) so callers report them.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use pomona_core::{DepthImage, RgbdFrame};

use crate::realsense::RealSenseCalibration;
use crate::sync::{latest_at_or_before, nearest_within};
use crate::{
    CameraInfo, Header, Image, RecordingError, RecordingTopics, Serialization, TopicRequest,
    CAMERA_INFO_SCHEMA, IMAGE_SCHEMA,
};

/// The first bytes of an MCAP file.
const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// What kind of file a recording is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordingFormat {
    /// ROS 2 MCAP (CDR messages).
    Mcap,
    /// ROS 1 bag with depth registered to colour (ROS 1 driver topics or chosen ones).
    Ros1Bag,
    /// RealSense SDK bag: raw depth, registered to colour on loading.
    RealSenseBag,
}

impl RecordingFormat {
    /// A short name for messages: `MCAP`, `ROS 1 bag`, `RealSense bag`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Mcap => "MCAP",
            Self::Ros1Bag => "ROS 1 bag",
            Self::RealSenseBag => "RealSense bag",
        }
    }
}

/// The default depth-to-colour stamp tolerance: 20 ms.
pub const DEFAULT_SYNC_TOLERANCE_NS: u64 = 20_000_000;

/// How a recording is read: which topics, and how far apart colour and depth stamps may be.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RecordingOptions {
    /// The topics asked for; the others are the format's defaults.
    pub topics: TopicRequest,
    /// Largest |depth stamp − colour stamp| of one frame, nanoseconds.
    pub sync_tolerance_ns: u64,
}

impl Default for RecordingOptions {
    fn default() -> Self {
        Self {
            topics: TopicRequest::default(),
            sync_tolerance_ns: DEFAULT_SYNC_TOLERANCE_NS,
        }
    }
}

/// One topic of a recording, for messages that list what a recording has.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicSummary {
    /// Topic name.
    pub topic: String,
    /// Schema name (`sensor_msgs/msg/Image`, ...; empty without a schema).
    pub schema: String,
    /// Messages on the topic.
    pub messages: u64,
}

/// One message kept from the file: its header stamp and its payload.
#[derive(Debug, Clone)]
pub(crate) struct Stamped {
    pub(crate) stamp_ns: u64,
    pub(crate) frame_id: String,
    pub(crate) payload: Vec<u8>,
}

/// The messages one synchronised frame is made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct FrameParts {
    color: usize,
    depth: usize,
    info: usize,
}

/// A synchronised frame: the colour stamp, its frame id and the RGB-D frame.
#[derive(Debug, Clone, PartialEq)]
pub struct SyncedFrame {
    /// The colour image's header stamp, nanoseconds since the epoch.
    pub stamp_ns: u64,
    /// The colour image's coordinate frame.
    pub frame_id: String,
    /// Colour, depth (metres) and the camera from the camera info's K.
    pub frame: RgbdFrame,
}

/// A recording opened for reading frames.
#[derive(Debug, Clone)]
pub struct Recording {
    path: PathBuf,
    options: RecordingOptions,
    format: RecordingFormat,
    topics_used: RecordingTopics,
    realsense: Option<RealSenseCalibration>,
    color: Vec<Stamped>,
    depth: Vec<Stamped>,
    info: Vec<(u64, CameraInfo)>,
    frames: Vec<FrameParts>,
    unmatched_color_ns: Vec<u64>,
    duplicate_color: usize,
    topics: Vec<TopicSummary>,
}

/// The frame stem of a colour stamp: its nanoseconds, 19 digits zero-padded (so stems sort in
/// time order as text).
pub fn frame_stem(stamp_ns: u64) -> String {
    format!("{stamp_ns:019}")
}

/// Which of the three topics a message belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Color,
    Depth,
    Info,
}

impl Recording {
    /// Opens `path` with the default topics and tolerance.
    ///
    /// # Errors
    /// As [`Recording::open_with`].
    pub fn open(path: impl AsRef<Path>) -> Result<Self, RecordingError> {
        Self::open_with(path, &RecordingOptions::default())
    }

    /// Opens `path` (MCAP or ROS 1 bag, by its first bytes), reads the three topics' messages
    /// and synchronises them.
    ///
    /// # Errors
    /// [`RecordingError::Io`] for an unreadable file; [`RecordingError::UnknownFormat`] for
    /// neither format; [`RecordingError::Mcap`] / [`RecordingError::Bag`] for a truncated or
    /// corrupt one; [`RecordingError::RealSense`] for a RealSense bag without usable
    /// calibration; [`RecordingError::MissingTopic`] (listing the recording's topics) when a
    /// topic has no messages; [`RecordingError::WrongSchema`] for a topic of another type;
    /// [`RecordingError::Cdr`] / [`RecordingError::BadStamp`] for a header that cannot be read;
    /// [`RecordingError::CameraInfo`] for unsupported intrinsics.
    pub fn open_with(
        path: impl AsRef<Path>,
        options: &RecordingOptions,
    ) -> Result<Self, RecordingError> {
        let path = path.as_ref().to_owned();
        let bytes = std::fs::read(&path).map_err(|source| RecordingError::Io {
            path: path.clone(),
            source,
        })?;
        let opened = if bytes.starts_with(b"#ROSBAG") {
            crate::bag_recording::read(&path, &bytes, &options.topics)?
        } else if bytes.starts_with(MCAP_MAGIC) {
            let topics = options.topics.resolve(RecordingTopics::default());
            OpenedMessages {
                messages: TopicMessages::read(&path, &bytes, &topics)?,
                format: RecordingFormat::Mcap,
                topics,
                realsense: None,
            }
        } else {
            let start = &bytes[..bytes.len().min(12)];
            return Err(RecordingError::UnknownFormat {
                path,
                start: String::from_utf8_lossy(start).into_owned(),
            });
        };
        drop(bytes);
        let OpenedMessages {
            messages,
            format,
            topics,
            realsense,
        } = opened;
        messages.require_all(&path, &topics)?;
        let mut recording = Self {
            path,
            options: options.clone(),
            format,
            topics_used: topics,
            realsense,
            color: messages.color,
            depth: messages.depth,
            info: messages.info,
            frames: Vec::new(),
            unmatched_color_ns: Vec::new(),
            duplicate_color: 0,
            topics: messages.topics,
        };
        recording.synchronise();
        recording.check_cameras()?;
        Ok(recording)
    }

    /// Sorts each topic by stamp and matches every colour message to depth and camera info.
    fn synchronise(&mut self) {
        // Stable sorts: messages with equal stamps keep file order.
        self.color.sort_by_key(|m| m.stamp_ns);
        self.depth.sort_by_key(|m| m.stamp_ns);
        self.info.sort_by_key(|(s, _)| *s);
        let depth_ns: Vec<u64> = self.depth.iter().map(|m| m.stamp_ns).collect();
        let info_ns: Vec<u64> = self.info.iter().map(|(s, _)| *s).collect();
        let mut previous = None;
        for (color, message) in self.color.iter().enumerate() {
            let stamp_ns = message.stamp_ns;
            if previous == Some(stamp_ns) {
                // A second colour image with the same stamp would get the same frame stem.
                self.duplicate_color += 1;
                continue;
            }
            previous = Some(stamp_ns);
            let depth = nearest_within(&depth_ns, stamp_ns, self.options.sync_tolerance_ns);
            let info = latest_at_or_before(&info_ns, stamp_ns);
            match (depth, info) {
                (Some(depth), Some(info)) => self.frames.push(FrameParts { color, depth, info }),
                _ => self.unmatched_color_ns.push(stamp_ns),
            }
        }
    }

    /// Checks that every camera info used by a frame gives a Pomona camera, so a bad
    /// calibration is reported on opening rather than once per frame.
    fn check_cameras(&self) -> Result<(), RecordingError> {
        let mut used: Vec<usize> = self.frames.iter().map(|f| f.info).collect();
        used.dedup();
        used.into_iter()
            .try_for_each(|i| self.camera_of(i).map(|_| ()))
    }

    fn camera_of(&self, info: usize) -> Result<pomona_core::PinholeCamera, RecordingError> {
        let (stamp_ns, camera_info) = &self.info[info];
        camera_info
            .to_camera()
            .map_err(|source| RecordingError::CameraInfo {
                path: self.path.clone(),
                topic: self.topics_used.camera_info.clone(),
                stamp_ns: *stamp_ns,
                source: Box::new(source),
            })
    }

    /// The recording file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The topics and tolerance it was opened with.
    pub fn options(&self) -> &RecordingOptions {
        &self.options
    }

    /// The file's format.
    pub fn format(&self) -> RecordingFormat {
        self.format
    }

    /// The colour, depth and camera-info topics frames are read from (the requested ones, the
    /// rest the format's defaults; a RealSense bag's colour, raw depth and colour info).
    pub fn selected_topics(&self) -> &RecordingTopics {
        &self.topics_used
    }

    /// The depth calibration of a RealSense bag (`None` for other formats).
    pub fn realsense_calibration(&self) -> Option<&RealSenseCalibration> {
        self.realsense.as_ref()
    }

    /// Every topic in the recording with its schema and message count, sorted by name.
    pub fn topics(&self) -> &[TopicSummary] {
        &self.topics
    }

    /// Number of synchronised frames.
    pub fn frame_count(&self) -> usize {
        self.frames.len()
    }

    /// The colour stamp of each synchronised frame, in time order.
    pub fn frame_stamps_ns(&self) -> Vec<u64> {
        self.frames
            .iter()
            .map(|f| self.color[f.color].stamp_ns)
            .collect()
    }

    /// The colour stamp and frame id of synchronised frame `index` (`None` past the end), without
    /// decoding its pixels.
    pub fn frame_header(&self, index: usize) -> Option<(u64, &str)> {
        let message = &self.color[self.frames.get(index)?.color];
        Some((message.stamp_ns, &message.frame_id))
    }

    /// The frame stems ([`frame_stem`]) of the synchronised frames, in time order.
    pub fn frame_stems(&self) -> Vec<String> {
        self.frame_stamps_ns().into_iter().map(frame_stem).collect()
    }

    /// Stamps of the colour messages that found no depth message within the tolerance.
    pub fn unmatched_color_ns(&self) -> &[u64] {
        &self.unmatched_color_ns
    }

    /// Colour messages skipped because an earlier one had the same stamp.
    pub fn duplicate_color(&self) -> usize {
        self.duplicate_color
    }

    /// Messages read on the colour, depth and camera-info topics.
    pub fn message_counts(&self) -> (usize, usize, usize) {
        (self.color.len(), self.depth.len(), self.info.len())
    }

    /// Decodes synchronised frame `index`.
    ///
    /// # Errors
    /// [`RecordingError::NoSuchFrame`] past the end; [`RecordingError::Cdr`] for a malformed
    /// image message; [`RecordingError::Image`] for an unsupported encoding or inconsistent
    /// size (naming topic and stamp); [`RecordingError::Frame`] when colour, depth and camera
    /// differ in size.
    pub fn load_frame(&self, index: usize) -> Result<SyncedFrame, RecordingError> {
        let parts = self
            .frames
            .get(index)
            .ok_or_else(|| RecordingError::NoSuchFrame {
                path: self.path.clone(),
                index,
                count: self.frames.len(),
            })?;
        let topics = &self.topics_used;
        let color_msg = self.image(&self.color[parts.color], &topics.color)?;
        let stamp_ns = self.color[parts.color].stamp_ns;
        let image_error = |topic: &str, stamp_ns, source| RecordingError::Image {
            path: self.path.clone(),
            topic: topic.to_owned(),
            stamp_ns,
            source: Box::new(source),
        };
        let color = color_msg
            .to_color()
            .map_err(|e| image_error(&topics.color, stamp_ns, e))?;
        let camera = self.camera_of(parts.info)?;
        let depth = self.depth_of(parts.depth, &camera)?;
        let frame =
            RgbdFrame::new(camera, depth, Some(color)).map_err(|source| RecordingError::Frame {
                path: self.path.clone(),
                stamp_ns,
                source,
            })?;
        Ok(SyncedFrame {
            stamp_ns,
            frame_id: color_msg.header.frame_id,
            frame,
        })
    }

    fn serialization(&self) -> Serialization {
        match self.format {
            RecordingFormat::Mcap => Serialization::Cdr,
            RecordingFormat::Ros1Bag | RecordingFormat::RealSenseBag => Serialization::Ros1,
        }
    }

    /// Depth message `index` in metres on the colour camera `camera`'s pixels: as stored, or
    /// registered to colour for a RealSense bag.
    fn depth_of(
        &self,
        index: usize,
        camera: &pomona_core::PinholeCamera,
    ) -> Result<DepthImage, RecordingError> {
        let message = &self.depth[index];
        let topic = &self.topics_used.depth;
        let image_error = |source| RecordingError::Image {
            path: self.path.clone(),
            topic: topic.clone(),
            stamp_ns: message.stamp_ns,
            source: Box::new(source),
        };
        match &self.realsense {
            None => self.image(message, topic)?.to_depth().map_err(image_error),
            Some(calibration) => {
                crate::bag_recording::registered_depth(&message.payload, calibration, camera)
                    .map_err(|e| match e {
                        crate::bag_recording::RawDepthError::Cdr(source) => RecordingError::Cdr {
                            path: self.path.clone(),
                            topic: topic.clone(),
                            log_time_ns: message.stamp_ns,
                            source,
                        },
                        crate::bag_recording::RawDepthError::Image(source) => image_error(source),
                    })
            }
        }
    }

    fn image(&self, message: &Stamped, topic: &str) -> Result<Image, RecordingError> {
        Image::read_as(&message.payload, self.serialization()).map_err(|source| {
            RecordingError::Cdr {
                path: self.path.clone(),
                topic: topic.to_owned(),
                log_time_ns: message.stamp_ns,
                source,
            }
        })
    }

    /// The largest depth of any synchronised frame in metres (`None` when no frame has depth),
    /// decoding every depth image once. For choosing a depth unit before writing a dataset.
    ///
    /// # Errors
    /// As [`Recording::load_frame`] for the depth images.
    pub fn max_depth_m(&self) -> Result<Option<f32>, RecordingError> {
        let mut max: Option<f32> = None;
        let mut used: Vec<(usize, usize)> = self.frames.iter().map(|f| (f.depth, f.info)).collect();
        used.dedup();
        for (depth, info) in used {
            let camera = self.camera_of(info)?;
            if let Some((_, far)) = self.depth_of(depth, &camera)?.range_m() {
                max = Some(max.map_or(far, |m| m.max(far)));
            }
        }
        Ok(max)
    }

    /// Whether every depth message of the frames is `16UC1` (millimetres), so a dataset with a
    /// 1 mm unit holds it exactly (never for a RealSense bag: registration moves depth off
    /// whole millimetres).
    ///
    /// # Errors
    /// [`RecordingError::Cdr`] for a malformed depth message.
    pub fn depth_is_millimetres(&self) -> Result<bool, RecordingError> {
        if self.realsense.is_some() {
            return Ok(false);
        }
        for f in &self.frames {
            let message = &self.depth[f.depth];
            let (_, encoding) = Image::read_encoding(&message.payload, self.serialization())
                .map_err(|source| RecordingError::Cdr {
                    path: self.path.clone(),
                    topic: self.topics_used.depth.clone(),
                    log_time_ns: message.stamp_ns,
                    source,
                })?;
            if encoding != "16UC1" {
                return Ok(false);
            }
        }
        Ok(true)
    }
}

/// The messages of the colour, depth and camera-info topics in file order (image payloads kept
/// undecoded, headers read), and what every topic of the file holds.
pub(crate) struct TopicMessages {
    pub(crate) color: Vec<Stamped>,
    pub(crate) depth: Vec<Stamped>,
    pub(crate) info: Vec<(u64, CameraInfo)>,
    pub(crate) topics: Vec<TopicSummary>,
}

/// A file's messages with what was learnt opening it.
pub(crate) struct OpenedMessages {
    pub(crate) messages: TopicMessages,
    pub(crate) format: RecordingFormat,
    pub(crate) topics: RecordingTopics,
    pub(crate) realsense: Option<RealSenseCalibration>,
}

impl TopicMessages {
    /// One pass over the file's messages.
    fn read(path: &Path, bytes: &[u8], topics: &RecordingTopics) -> Result<Self, RecordingError> {
        let mcap_error = |source| RecordingError::Mcap {
            path: path.to_owned(),
            source,
        };
        let mut stream = mcap::read::RawMessageStream::new(bytes).map_err(mcap_error)?;
        let mut summary: BTreeMap<String, (String, u64)> = BTreeMap::new();
        let (mut color, mut depth, mut info) = (Vec::new(), Vec::new(), Vec::new());
        while let Some(message) = stream.next() {
            let message = message.map_err(mcap_error)?;
            let channel_id = message.header.channel_id;
            let Some(channel) = stream.get_channel(channel_id) else {
                return Err(mcap_error(mcap::McapError::UnknownChannel(
                    message.header.sequence,
                    channel_id,
                )));
            };
            let schema = channel.schema.as_ref().map_or("", |s| s.name.as_str());
            let entry = summary
                .entry(channel.topic.clone())
                .or_insert_with(|| (schema.to_owned(), 0));
            entry.1 += 1;
            let Some(role) = Role::of(&channel.topic, topics) else {
                continue;
            };
            let expected = match role {
                Role::Info => CAMERA_INFO_SCHEMA,
                Role::Color | Role::Depth => IMAGE_SCHEMA,
            };
            if schema != expected || channel.message_encoding != "cdr" {
                return Err(RecordingError::WrongSchema {
                    path: path.to_owned(),
                    topic: channel.topic.clone(),
                    schema: schema.to_owned(),
                    encoding: channel.message_encoding.clone(),
                    expected,
                    expected_encoding: Serialization::Cdr,
                });
            }
            let cdr_error = |source| RecordingError::Cdr {
                path: path.to_owned(),
                topic: channel.topic.clone(),
                log_time_ns: message.header.log_time,
                source,
            };
            let payload = message.data.into_owned();
            match role {
                Role::Info => {
                    let camera_info = CameraInfo::read(&payload).map_err(cdr_error)?;
                    let stamp_ns = stamp(path, &channel.topic, &camera_info.header)?;
                    info.push((stamp_ns, camera_info));
                }
                Role::Color | Role::Depth => {
                    let (header, _) =
                        Image::read_encoding(&payload, Serialization::Cdr).map_err(cdr_error)?;
                    let stamp_ns = stamp(path, &channel.topic, &header)?;
                    let list = if role == Role::Color {
                        &mut color
                    } else {
                        &mut depth
                    };
                    list.push(Stamped {
                        stamp_ns,
                        frame_id: header.frame_id,
                        payload,
                    });
                }
            }
        }
        let topics = summary
            .into_iter()
            .map(|(topic, (schema, messages))| TopicSummary {
                topic,
                schema,
                messages,
            })
            .collect();
        Ok(Self {
            color,
            depth,
            info,
            topics,
        })
    }

    /// [`RecordingError::MissingTopic`] (listing the file's topics) for the first of the three
    /// requested topics without messages.
    pub(crate) fn require_all(
        &self,
        path: &Path,
        topics: &RecordingTopics,
    ) -> Result<(), RecordingError> {
        let requested = [
            (
                "colour",
                &topics.color,
                "--color-topic",
                self.color.is_empty(),
            ),
            (
                "depth",
                &topics.depth,
                "--depth-topic",
                self.depth.is_empty(),
            ),
            (
                "camera info",
                &topics.camera_info,
                "--info-topic",
                self.info.is_empty(),
            ),
        ];
        match requested.into_iter().find(|r| r.3) {
            Some((role, topic, flag, _)) => Err(RecordingError::MissingTopic {
                path: path.to_owned(),
                role,
                topic: topic.clone(),
                flag,
                available: list_topics(&self.topics),
            }),
            None => Ok(()),
        }
    }
}

impl Role {
    /// The role of `topic` among the requested ones, `None` for any other topic.
    fn of(topic: &str, topics: &RecordingTopics) -> Option<Self> {
        if topic == topics.color {
            Some(Self::Color)
        } else if topic == topics.depth {
            Some(Self::Depth)
        } else if topic == topics.camera_info {
            Some(Self::Info)
        } else {
            None
        }
    }
}

/// The header's stamp in nanoseconds, or an error naming the topic.
pub(crate) fn stamp(path: &Path, topic: &str, header: &Header) -> Result<u64, RecordingError> {
    header.stamp_ns().ok_or_else(|| RecordingError::BadStamp {
        path: path.to_owned(),
        topic: topic.to_owned(),
        sec: header.stamp_sec,
        nanosec: header.stamp_nanosec,
    })
}

/// `topic (schema, N messages), ...`, or a note that there are none.
fn list_topics(topics: &[TopicSummary]) -> String {
    if topics.is_empty() {
        return "none (the recording has no messages)".to_owned();
    }
    topics
        .iter()
        .map(|t| {
            let schema = if t.schema.is_empty() {
                "no schema"
            } else {
                &t.schema
            };
            format!("{} ({schema}, {} messages)", t.topic, t.messages)
        })
        .collect::<Vec<_>>()
        .join(", ")
}
