//! Writing ROS 2 MCAP recordings of RGB-D frames, as `ros2 bag record` would store the
//! RealSense driver's topics: `sensor_msgs/msg/Image` and `sensor_msgs/msg/CameraInfo` in CDR,
//! with their `ros2msg` schemas, zstd-compressed chunks and the summary index.
//!
//! Used to build test fixtures from synthetic or real datasets (no recording is ever
//! downloaded) and by the `dataset_to_mcap` example. The file is written to a temporary file
//! beside the destination and renamed by [`RecordingWriter::finish`], so a failed write never
//! leaves half a recording.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use pomona_core::RgbdFrame;
use tempfile::NamedTempFile;

use crate::{
    CameraInfo, Header, Image, RecordingError, RecordingTopics, CAMERA_INFO_SCHEMA, IMAGE_SCHEMA,
};

/// The `ros2msg` definitions of `std_msgs/Header` and `builtin_interfaces/Time`, which both
/// messages depend on (a macro, so `concat!` can join them into constants).
macro_rules! header_definitions {
    () => {
        "================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"
    };
}

/// The `ros2msg` schema text of `sensor_msgs/msg/Image` with its dependencies.
const IMAGE_DEFINITION: &str = concat!(
    "std_msgs/Header header
uint32 height
uint32 width
string encoding
uint8 is_bigendian
uint32 step
uint8[] data
",
    header_definitions!()
);

/// The `ros2msg` schema text of `sensor_msgs/msg/CameraInfo` with its dependencies.
const CAMERA_INFO_DEFINITION: &str = concat!(
    "std_msgs/Header header
uint32 height
uint32 width
string distortion_model
float64[] d
float64[9] k
float64[9] r
float64[12] p
uint32 binning_x
uint32 binning_y
sensor_msgs/RegionOfInterest roi
",
    header_definitions!(),
    "================================================================================
MSG: sensor_msgs/RegionOfInterest
uint32 x_offset
uint32 y_offset
uint32 height
uint32 width
bool do_rectify
"
);

/// How a frame's images are encoded in the recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FrameEncodings {
    /// Colour as `bgr8` (the RealSense driver's choice on some setups) instead of `rgb8`.
    pub bgr: bool,
    /// Depth as `32FC1` metres instead of `16UC1` millimetres.
    pub float_depth: bool,
}

/// An MCAP recording being written.
pub struct RecordingWriter {
    path: PathBuf,
    temp: NamedTempFile,
    writer: mcap::Writer<BufWriter<File>>,
    channels: BTreeMap<String, u16>,
    sequence: u32,
}

impl std::fmt::Debug for RecordingWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RecordingWriter")
            .field("path", &self.path)
            .field("channels", &self.channels)
            .finish_non_exhaustive()
    }
}

impl RecordingWriter {
    /// Starts a recording at `path` (written on [`RecordingWriter::finish`]).
    ///
    /// # Errors
    /// [`RecordingError::Io`] when the temporary file cannot be created beside `path`;
    /// [`RecordingError::Mcap`] when the MCAP header cannot be written.
    pub fn create(path: impl AsRef<Path>) -> Result<Self, RecordingError> {
        let path = path.as_ref().to_owned();
        let (temp, file) = partial_file_beside(&path)?;
        let writer = mcap::WriteOptions::new()
            .profile("ros2")
            .create(BufWriter::new(file))
            .map_err(|source| RecordingError::Mcap {
                path: path.clone(),
                source,
            })?;
        Ok(Self {
            path,
            temp,
            writer,
            channels: BTreeMap::new(),
            sequence: 0,
        })
    }

    fn mcap_error(&self, source: mcap::McapError) -> RecordingError {
        RecordingError::Mcap {
            path: self.path.clone(),
            source,
        }
    }

    /// Writes one message on `topic` (adding its schema and channel the first time).
    fn write_message(
        &mut self,
        topic: &str,
        schema: &str,
        definition: &str,
        payload: &[u8],
        log_time_ns: u64,
    ) -> Result<(), RecordingError> {
        let channel_id = match self.channels.get(topic) {
            Some(&id) => id,
            None => {
                let id = self
                    .writer
                    .add_schema(schema, "ros2msg", definition.as_bytes())
                    .and_then(|schema_id| {
                        self.writer
                            .add_channel(schema_id, topic, "cdr", &BTreeMap::new())
                    })
                    .map_err(|e| self.mcap_error(e))?;
                self.channels.insert(topic.to_owned(), id);
                id
            }
        };
        self.sequence += 1;
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: self.sequence,
            log_time: log_time_ns,
            publish_time: log_time_ns,
        };
        self.writer
            .write_to_known_channel(&header, payload)
            .map_err(|e| self.mcap_error(e))
    }

    /// Writes an image message on `topic`, logged at its header stamp.
    ///
    /// # Errors
    /// [`RecordingError::Mcap`] when the message cannot be written.
    pub fn write_image(&mut self, topic: &str, image: &Image) -> Result<(), RecordingError> {
        let log_time = image.header.stamp_ns().unwrap_or(0);
        self.write_message(
            topic,
            IMAGE_SCHEMA,
            IMAGE_DEFINITION,
            &image.to_cdr(),
            log_time,
        )
    }

    /// Writes a camera-info message on `topic`, logged at its header stamp.
    ///
    /// # Errors
    /// [`RecordingError::Mcap`] when the message cannot be written.
    pub fn write_camera_info(
        &mut self,
        topic: &str,
        info: &CameraInfo,
    ) -> Result<(), RecordingError> {
        let log_time = info.header.stamp_ns().unwrap_or(0);
        self.write_message(
            topic,
            CAMERA_INFO_SCHEMA,
            CAMERA_INFO_DEFINITION,
            &info.to_cdr(),
            log_time,
        )
    }

    /// Writes `frame` as the driver would publish it: camera info, colour and depth, all stamped
    /// `stamp_ns` in `frame_id`, on `topics`.
    ///
    /// # Errors
    /// [`RecordingError::NoColor`] for a frame without colour; [`RecordingError::Mcap`] when a
    /// message cannot be written.
    pub fn write_frame(
        &mut self,
        topics: &RecordingTopics,
        stamp_ns: u64,
        frame_id: &str,
        frame: &RgbdFrame,
        encodings: FrameEncodings,
    ) -> Result<(), RecordingError> {
        let header = Header::at(stamp_ns, frame_id);
        let (info, color, depth) = frame_messages(&self.path, topics, header, frame, encodings)?;
        self.write_camera_info(&topics.camera_info, &info)?;
        self.write_image(&topics.color, &color)?;
        self.write_image(&topics.depth, &depth)
    }

    /// Finishes the MCAP file (summary, footer) and moves it to its path.
    ///
    /// # Errors
    /// [`RecordingError::Mcap`] / [`RecordingError::Io`] when the end cannot be written or the
    /// file not renamed.
    pub fn finish(mut self) -> Result<(), RecordingError> {
        self.writer.finish().map_err(|e| self.mcap_error(e))?;
        let path = self.path;
        let io = |source| RecordingError::Io {
            path: path.clone(),
            source,
        };
        self.writer
            .into_inner()
            .into_inner()
            .map_err(|e| io(e.into_error()))?
            .sync_all()
            .map_err(io)?;
        persist(self.temp, &path)
    }
}

/// The camera info, colour and depth messages of `frame`, all with `header`, as a driver
/// publishes them (shared by the MCAP and the bag writer).
pub(crate) fn frame_messages(
    path: &Path,
    topics: &RecordingTopics,
    header: Header,
    frame: &RgbdFrame,
    encodings: FrameEncodings,
) -> Result<(CameraInfo, Image, Image), RecordingError> {
    let stamp_ns = header.stamp_ns().unwrap_or(0);
    let Some(color) = frame.color() else {
        return Err(RecordingError::NoColor {
            path: path.to_owned(),
            stamp_ns,
        });
    };
    let info = CameraInfo::from_camera(header.clone(), frame.camera());
    let color = Image::from_color(header.clone(), color, encodings.bgr);
    let depth = if encodings.float_depth {
        Image::from_depth_32fc1(header, frame.depth())
    } else {
        Image::from_depth_16uc1(header, frame.depth()).map_err(|source| RecordingError::Image {
            path: path.to_owned(),
            topic: topics.depth.clone(),
            stamp_ns,
            source: Box::new(source),
        })?
    };
    Ok((info, color, depth))
}

/// Gives the finished temporary file ordinary permissions and renames it to `path`.
/// A temporary `.pomona-*.partial` file in `path`'s folder and a second handle to write it
/// through (shared by the MCAP and the bag writer); [`persist`] renames it to `path`.
pub(crate) fn partial_file_beside(path: &Path) -> Result<(NamedTempFile, File), RecordingError> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
        _ => PathBuf::from("."),
    };
    let io = |source| RecordingError::Io {
        path: path.to_owned(),
        source,
    };
    let temp = tempfile::Builder::new()
        .prefix(".pomona-")
        .suffix(".partial")
        .tempfile_in(&dir)
        .map_err(io)?;
    let file = temp.as_file().try_clone().map_err(io)?;
    Ok((temp, file))
}

pub(crate) fn persist(temp: NamedTempFile, path: &Path) -> Result<(), RecordingError> {
    let io = |source| RecordingError::Io {
        path: path.to_owned(),
        source,
    };
    // Temporary files are created owner-only; a recording is ordinary output (rw-r--r--).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        temp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(io)?;
    }
    temp.persist(path).map_err(|e| io(e.error))?;
    Ok(())
}
