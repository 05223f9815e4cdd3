//! Writing ROS 1 bags (format 2.0), as `rosbag record` would: chunks of message and connection
//! records (uncompressed, bz2 or lz4), each followed by its index-data records, then the index
//! section (connection and chunk-info records) and the bag header rewritten with its position.
//!
//! Used for test fixtures (ROS 1 and RealSense layouts; no bag is ever downloaded) and by the
//! `dataset_to_bag` example. Like [`crate::RecordingWriter`], the bag is written to a temporary
//! file beside the destination and renamed by [`BagWriter::finish`].

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use pomona_core::RgbdFrame;
use tempfile::NamedTempFile;

use crate::bag::BAG_MAGIC;
use crate::recording_writer::{partial_file_beside, persist};
use crate::{CameraInfo, FrameEncodings, Header, Image, RecordingError, RecordingTopics};

/// How chunks are compressed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BagCompression {
    /// Stored as is (`rosbag record`'s default).
    #[default]
    None,
    /// bzip2 (`rosbag record --bz2`).
    Bz2,
    /// LZ4 frame (`rosbag record --lz4`).
    Lz4,
}

impl BagCompression {
    fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Bz2 => "bz2",
            Self::Lz4 => "lz4",
        }
    }
}

/// A ROS 1 message type as a connection record names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ros1MessageType {
    /// `package/Name`.
    pub name: &'static str,
    /// The MD5 of its definition, as `genmsg` computes it.
    pub md5sum: &'static str,
    /// The full definition text (with dependencies).
    pub definition: &'static str,
}

/// The definition of `std_msgs/Header`, which Image and CameraInfo depend on (a macro so
/// `concat!` can append it).
macro_rules! ros1_header_definition {
    () => {
        "================================================================================
MSG: std_msgs/Header
uint32 seq
time stamp
string frame_id
"
    };
}

/// `sensor_msgs/Image`.
pub const ROS1_IMAGE: Ros1MessageType = Ros1MessageType {
    name: "sensor_msgs/Image",
    md5sum: "060021388200f6f0f447d0fcd9c64743",
    definition: concat!(
        "Header header
uint32 height
uint32 width
string encoding
uint8 is_bigendian
uint32 step
uint8[] data
",
        ros1_header_definition!()
    ),
};

/// `sensor_msgs/CameraInfo`.
pub const ROS1_CAMERA_INFO: Ros1MessageType = Ros1MessageType {
    name: "sensor_msgs/CameraInfo",
    md5sum: "c9a58c1b0b154e0e6da7578cb991d214",
    definition: concat!(
        "Header header
uint32 height
uint32 width
string distortion_model
float64[] D
float64[9] K
float64[9] R
float64[12] P
uint32 binning_x
uint32 binning_y
RegionOfInterest roi
",
        ros1_header_definition!(),
        "================================================================================
MSG: sensor_msgs/RegionOfInterest
uint32 x_offset
uint32 y_offset
uint32 height
uint32 width
bool do_rectify
"
    ),
};

/// `geometry_msgs/Transform` (RealSense extrinsics).
pub const ROS1_TRANSFORM: Ros1MessageType = Ros1MessageType {
    name: "geometry_msgs/Transform",
    md5sum: "ac9eff44abf714214112b05d54a3cf9b",
    definition: "Vector3 translation
Quaternion rotation
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
================================================================================
MSG: geometry_msgs/Quaternion
float64 x
float64 y
float64 z
float64 w
",
};

/// `std_msgs/Float32` (RealSense sensor options).
pub const ROS1_FLOAT32: Ros1MessageType = Ros1MessageType {
    name: "std_msgs/Float32",
    md5sum: "73fcbf46b49191e672908e50842a83d4",
    definition: "float32 data\n",
};

/// Uncompressed chunk size at which a chunk is closed (`rosbag record`'s default, 768 KiB).
const CHUNK_THRESHOLD: usize = 768 * 1024;
/// The bag-header record is padded to this many bytes so it can be rewritten in place.
const BAG_HEADER_LEN: usize = 4096;

/// A connection: its id, topic and type.
#[derive(Debug, Clone)]
struct Connection {
    id: u32,
    topic: String,
    message_type: Ros1MessageType,
}

/// A closed chunk, for its chunk-info record.
#[derive(Debug, Clone)]
struct ChunkInfo {
    position: u64,
    start_ns: u64,
    end_ns: u64,
    counts: BTreeMap<u32, u32>,
}

/// A ROS 1 bag being written.
pub struct BagWriter {
    path: PathBuf,
    temp: NamedTempFile,
    out: BufWriter<File>,
    position: u64,
    compression: BagCompression,
    connections: Vec<Connection>,
    by_topic: BTreeMap<String, u32>,
    chunk: Vec<u8>,
    /// Per connection in the open chunk: (time, offset in the chunk) of each message.
    chunk_index: BTreeMap<u32, Vec<(u64, u32)>>,
    chunk_times: Option<(u64, u64)>,
    chunks: Vec<ChunkInfo>,
}

impl std::fmt::Debug for BagWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BagWriter")
            .field("path", &self.path)
            .field("compression", &self.compression)
            .field("connections", &self.connections.len())
            .finish_non_exhaustive()
    }
}

/// Appends one record (header fields, data) to `out`.
fn record(out: &mut Vec<u8>, fields: &[(&str, &[u8])], data: &[u8]) {
    let header_len: usize = fields.iter().map(|(k, v)| 4 + k.len() + 1 + v.len()).sum();
    push_len(out, header_len);
    for (name, value) in fields {
        push_len(out, name.len() + 1 + value.len());
        out.extend_from_slice(name.as_bytes());
        out.push(b'=');
        out.extend_from_slice(value);
    }
    push_len(out, data.len());
    out.extend_from_slice(data);
}

fn push_len(out: &mut Vec<u8>, len: usize) {
    // Records over 4 GiB cannot be stored; saturating makes a reader refuse them.
    out.extend_from_slice(&u32::try_from(len).unwrap_or(u32::MAX).to_le_bytes());
}

/// ROS time as a bag stores it: `u32` seconds then `u32` nanoseconds.
fn time_bytes(ns: u64) -> [u8; 8] {
    let sec = u32::try_from(ns / 1_000_000_000).unwrap_or(u32::MAX);
    let nsec = (ns % 1_000_000_000) as u32;
    let mut b = [0; 8];
    b[..4].copy_from_slice(&sec.to_le_bytes());
    b[4..].copy_from_slice(&nsec.to_le_bytes());
    b
}

/// The connection record of `c` (header: op, conn, topic; data: its connection header).
fn connection_record(out: &mut Vec<u8>, c: &Connection) {
    let mut data = Vec::new();
    for (name, value) in [
        ("topic", c.topic.as_str()),
        ("type", c.message_type.name),
        ("md5sum", c.message_type.md5sum),
        ("message_definition", c.message_type.definition),
    ] {
        push_len(&mut data, name.len() + 1 + value.len());
        data.extend_from_slice(name.as_bytes());
        data.push(b'=');
        data.extend_from_slice(value.as_bytes());
    }
    record(
        out,
        &[
            ("op", &[0x07]),
            ("conn", &c.id.to_le_bytes()),
            ("topic", c.topic.as_bytes()),
        ],
        &data,
    );
}

/// The bag-header record padded to [`BAG_HEADER_LEN`] bytes.
fn bag_header(index_pos: u64, connections: u32, chunks: u32) -> Vec<u8> {
    let fields: [(&str, &[u8]); 4] = [
        ("op", &[0x03]),
        ("index_pos", &index_pos.to_le_bytes()),
        ("conn_count", &connections.to_le_bytes()),
        ("chunk_count", &chunks.to_le_bytes()),
    ];
    let mut out = Vec::new();
    record(&mut out, &fields, &[]);
    let padding = BAG_HEADER_LEN.saturating_sub(out.len());
    out.clear();
    record(&mut out, &fields, &vec![b' '; padding]);
    out
}

impl BagWriter {
    /// Starts a bag at `path` (written on [`BagWriter::finish`]).
    ///
    /// # Errors
    /// [`RecordingError::Io`] when the temporary file cannot be created or written.
    pub fn create(
        path: impl AsRef<Path>,
        compression: BagCompression,
    ) -> Result<Self, RecordingError> {
        let path = path.as_ref().to_owned();
        let (temp, file) = partial_file_beside(&path)?;
        let mut writer = Self {
            path: path.clone(),
            temp,
            out: BufWriter::new(file),
            position: 0,
            compression,
            connections: Vec::new(),
            by_topic: BTreeMap::new(),
            chunk: Vec::new(),
            chunk_index: BTreeMap::new(),
            chunk_times: None,
            chunks: Vec::new(),
        };
        writer.emit(BAG_MAGIC)?;
        writer.emit(&bag_header(0, 0, 0))?;
        Ok(writer)
    }

    fn io(&self, source: std::io::Error) -> RecordingError {
        RecordingError::Io {
            path: self.path.clone(),
            source,
        }
    }

    fn emit(&mut self, bytes: &[u8]) -> Result<(), RecordingError> {
        self.out.write_all(bytes).map_err(|e| self.io(e))?;
        self.position += bytes.len() as u64;
        Ok(())
    }

    /// Writes one message on `topic` of `message_type`, recorded at `time_ns` (adding the
    /// connection the first time the topic is seen).
    ///
    /// # Errors
    /// [`RecordingError::Io`] when a chunk cannot be written; [`RecordingError::BagTopicType`]
    /// when `topic` was first written with another type.
    pub fn write(
        &mut self,
        topic: &str,
        message_type: Ros1MessageType,
        time_ns: u64,
        payload: &[u8],
    ) -> Result<(), RecordingError> {
        let id = match self.by_topic.get(topic) {
            Some(&id) => {
                let first = self.connections[id as usize].message_type.name;
                if first != message_type.name {
                    return Err(RecordingError::BagTopicType {
                        path: self.path.clone(),
                        topic: topic.to_owned(),
                        first: first.to_owned(),
                        now: message_type.name.to_owned(),
                    });
                }
                id
            }
            None => {
                let id = self.connections.len() as u32;
                let connection = Connection {
                    id,
                    topic: topic.to_owned(),
                    message_type,
                };
                connection_record(&mut self.chunk, &connection);
                self.connections.push(connection);
                self.by_topic.insert(topic.to_owned(), id);
                id
            }
        };
        let offset = u32::try_from(self.chunk.len()).unwrap_or(u32::MAX);
        record(
            &mut self.chunk,
            &[
                ("op", &[0x02]),
                ("conn", &id.to_le_bytes()),
                ("time", &time_bytes(time_ns)),
            ],
            payload,
        );
        self.chunk_index
            .entry(id)
            .or_default()
            .push((time_ns, offset));
        self.chunk_times = Some(match self.chunk_times {
            Some((start, end)) => (start.min(time_ns), end.max(time_ns)),
            None => (time_ns, time_ns),
        });
        if self.chunk.len() >= CHUNK_THRESHOLD {
            self.close_chunk()?;
        }
        Ok(())
    }

    /// Writes the open chunk and its index-data records.
    fn close_chunk(&mut self) -> Result<(), RecordingError> {
        let Some((start_ns, end_ns)) = self.chunk_times.take() else {
            return Ok(());
        };
        let records = std::mem::take(&mut self.chunk);
        let compressed = match self.compression {
            BagCompression::None => records.clone(),
            BagCompression::Bz2 => {
                let mut e = bzip2::write::BzEncoder::new(Vec::new(), bzip2::Compression::default());
                e.write_all(&records)
                    .and_then(|()| e.finish())
                    .map_err(|e| self.io(e))?
            }
            BagCompression::Lz4 => {
                let mut e = lz4::EncoderBuilder::new()
                    .build(Vec::new())
                    .map_err(|e| self.io(e))?;
                e.write_all(&records).map_err(|e| self.io(e))?;
                let (bytes, result) = e.finish();
                result.map_err(|e| self.io(e))?;
                bytes
            }
        };
        let mut out = Vec::new();
        let size = u32::try_from(records.len()).unwrap_or(u32::MAX);
        record(
            &mut out,
            &[
                ("op", &[0x05]),
                ("compression", self.compression.name().as_bytes()),
                ("size", &size.to_le_bytes()),
            ],
            &compressed,
        );
        let mut counts = BTreeMap::new();
        for (id, entries) in std::mem::take(&mut self.chunk_index) {
            let mut data = Vec::with_capacity(entries.len() * 12);
            for (time, offset) in &entries {
                data.extend_from_slice(&time_bytes(*time));
                data.extend_from_slice(&offset.to_le_bytes());
            }
            let count = entries.len() as u32;
            record(
                &mut out,
                &[
                    ("op", &[0x04]),
                    ("ver", &1u32.to_le_bytes()),
                    ("conn", &id.to_le_bytes()),
                    ("count", &count.to_le_bytes()),
                ],
                &data,
            );
            counts.insert(id, count);
        }
        self.chunks.push(ChunkInfo {
            position: self.position,
            start_ns,
            end_ns,
            counts,
        });
        self.emit(&out)
    }

    /// Writes an image on `topic`, recorded at its header stamp.
    ///
    /// # Errors
    /// As [`BagWriter::write`].
    pub fn write_image(&mut self, topic: &str, image: &Image) -> Result<(), RecordingError> {
        let time = image.header.stamp_ns().unwrap_or(0);
        self.write(topic, ROS1_IMAGE, time, &image.to_ros1())
    }

    /// Writes camera info on `topic`, recorded at its header stamp.
    ///
    /// # Errors
    /// As [`BagWriter::write`].
    pub fn write_camera_info(
        &mut self,
        topic: &str,
        info: &CameraInfo,
    ) -> Result<(), RecordingError> {
        let time = info.header.stamp_ns().unwrap_or(0);
        self.write(topic, ROS1_CAMERA_INFO, time, &info.to_ros1())
    }

    /// Writes `frame` as the RealSense ROS 1 driver would publish it (camera info, colour,
    /// aligned depth, stamped `stamp_ns` in `frame_id`) on `topics`.
    ///
    /// # Errors
    /// [`RecordingError::NoColor`] for a frame without colour; [`RecordingError::Io`].
    pub fn write_frame(
        &mut self,
        topics: &RecordingTopics,
        stamp_ns: u64,
        frame_id: &str,
        frame: &RgbdFrame,
        encodings: FrameEncodings,
    ) -> Result<(), RecordingError> {
        let header = Header::at(stamp_ns, frame_id);
        let (info, color, depth) =
            crate::recording_writer::frame_messages(&self.path, topics, header, frame, encodings)?;
        self.write_camera_info(&topics.camera_info, &info)?;
        self.write_image(&topics.color, &color)?;
        self.write_image(&topics.depth, &depth)
    }

    /// Closes the last chunk, writes the index section, rewrites the bag header and moves the
    /// file to its path.
    ///
    /// # Errors
    /// [`RecordingError::Io`].
    pub fn finish(mut self) -> Result<(), RecordingError> {
        self.close_chunk()?;
        let index_pos = self.position;
        let mut out = Vec::new();
        for c in &self.connections {
            connection_record(&mut out, c);
        }
        for chunk in &self.chunks {
            let mut data = Vec::new();
            for (id, n) in &chunk.counts {
                data.extend_from_slice(&id.to_le_bytes());
                data.extend_from_slice(&n.to_le_bytes());
            }
            record(
                &mut out,
                &[
                    ("op", &[0x06]),
                    ("ver", &1u32.to_le_bytes()),
                    ("chunk_pos", &chunk.position.to_le_bytes()),
                    ("start_time", &time_bytes(chunk.start_ns)),
                    ("end_time", &time_bytes(chunk.end_ns)),
                    ("count", &(chunk.counts.len() as u32).to_le_bytes()),
                ],
                &data,
            );
        }
        self.emit(&out)?;
        let header = bag_header(
            index_pos,
            self.connections.len() as u32,
            self.chunks.len() as u32,
        );
        let path = self.path.clone();
        let io = |source| RecordingError::Io {
            path: path.clone(),
            source,
        };
        self.out
            .seek(SeekFrom::Start(BAG_MAGIC.len() as u64))
            .map_err(io)?;
        self.out.write_all(&header).map_err(io)?;
        self.out
            .into_inner()
            .map_err(|e| io(e.into_error()))?
            .sync_all()
            .map_err(io)?;
        persist(self.temp, &path)
    }
}
