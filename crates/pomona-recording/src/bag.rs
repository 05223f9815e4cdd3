//! The ROS 1 bag container, format 2.0, read from bytes.
//!
//! A bag is the magic line `#ROSBAG V2.0\n` and a sequence of records. Each record is a header
//! (`u32` length, then fields `u32 len` + `name=value`, with `op` naming the record type) and data
//! (`u32` length, the bytes). The bag-header record gives `index_pos`, where the index section
//! starts; before it come chunk records, each a block of message-data and connection records
//! (uncompressed, bz2 or lz4 frame) followed by index-data records; the index section holds one
//! connection record per topic (topic, message type, md5sum, definition) and one chunk-info
//! record per chunk (how many messages of each connection it holds).
//!
//! [`Bag::open`] checks the magic and the header and reads the index section;
//! [`Bag::read_messages`] walks every chunk once and keeps the messages of the connections asked
//! for. Every length and offset is checked against the bytes it lies in; a chunk must inflate to
//! exactly the size it declares; the messages found must be those the chunk infos count. A bag
//! left unindexed (a recording killed before it closed: `index_pos` 0) is refused with the
//! `rosbag reindex` hint rather than half read.

use std::collections::BTreeMap;
use std::io::Read;

/// The first 13 bytes of every bag this reader reads.
pub const BAG_MAGIC: &[u8] = b"#ROSBAG V2.0\n";

const OP_MESSAGE: u8 = 0x02;
const OP_BAG_HEADER: u8 = 0x03;
const OP_INDEX_DATA: u8 = 0x04;
const OP_CHUNK: u8 = 0x05;
const OP_CHUNK_INFO: u8 = 0x06;
const OP_CONNECTION: u8 = 0x07;

/// Why bytes are not a readable ROS 1 bag (the caller adds the file name).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BagError {
    /// The file does not start with `#ROSBAG V2.0`.
    #[error("not a ROS 1 bag of format 2.0 (starts with {found:?}, expected \"#ROSBAG V2.0\")")]
    Magic {
        /// The first bytes, lossily as text.
        found: String,
    },
    /// The file ends inside a record.
    #[error("truncated: {what} at byte {offset} needs {needed} bytes, the file has {len}")]
    Truncated {
        /// What was being read.
        what: &'static str,
        /// Where.
        offset: u64,
        /// Bytes it needs from there.
        needed: u64,
        /// Bytes available in the file (or chunk).
        len: u64,
    },
    /// A record or field that breaks the format.
    #[error("corrupt at byte {offset}: {what}")]
    Corrupt {
        /// Where.
        offset: u64,
        /// What is wrong.
        what: String,
    },
    /// The bag was never closed, so it has no index.
    #[error(
        "the bag has no index (index_pos 0: recording interrupted?); `rosbag reindex` it first"
    )]
    Unindexed,
    /// A chunk compression this reader does not know.
    #[error("chunk at byte {offset} uses compression `{compression}` (supported: none, bz2, lz4)")]
    Compression {
        /// Where.
        offset: u64,
        /// The compression named.
        compression: String,
    },
}

/// One connection (topic) of a bag.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BagConnection {
    /// The connection id messages refer to.
    pub id: u32,
    /// Topic name.
    pub topic: String,
    /// Message type (`sensor_msgs/Image`, ...).
    pub message_type: String,
}

/// One message kept by [`Bag::read_messages`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BagMessage {
    /// Its connection id.
    pub connection: u32,
    /// The time it was recorded, ns since the epoch.
    pub time_ns: u64,
    /// Its ROS 1 serialised payload.
    pub data: Vec<u8>,
}

/// Messages read from a bag: those asked for, and the count of every connection's messages.
#[derive(Debug, Clone, Default)]
pub struct BagMessages {
    /// The kept messages, in file order.
    pub kept: Vec<BagMessage>,
    /// Messages per connection id (all connections).
    pub counts: BTreeMap<u32, u64>,
}

/// An opened bag: its bytes, connections and the chunk infos' message counts.
#[derive(Debug)]
pub struct Bag<'a> {
    bytes: &'a [u8],
    records_start: usize,
    index_pos: usize,
    connections: BTreeMap<u32, BagConnection>,
    expected_counts: BTreeMap<u32, u64>,
}

/// A record: its header fields and data, and where it started.
struct Record<'a> {
    offset: u64,
    fields: BTreeMap<&'a str, &'a [u8]>,
    data: &'a [u8],
}

impl Record<'_> {
    fn op(&self) -> Result<u8, BagError> {
        match self.fields.get("op") {
            Some([op]) => Ok(*op),
            _ => Err(self.corrupt("record without a one-byte `op` field".to_owned())),
        }
    }

    fn corrupt(&self, what: String) -> BagError {
        BagError::Corrupt {
            offset: self.offset,
            what,
        }
    }

    fn field(&self, name: &'static str) -> Result<&[u8], BagError> {
        self.fields
            .get(name)
            .copied()
            .ok_or_else(|| self.corrupt(format!("record lacks the `{name}` field")))
    }

    fn u32(&self, name: &'static str) -> Result<u32, BagError> {
        let v = self.field(name)?;
        <[u8; 4]>::try_from(v)
            .map(u32::from_le_bytes)
            .map_err(|_| self.corrupt(format!("field `{name}` is {} bytes, not 4", v.len())))
    }

    fn u64(&self, name: &'static str) -> Result<u64, BagError> {
        let v = self.field(name)?;
        <[u8; 8]>::try_from(v)
            .map(u64::from_le_bytes)
            .map_err(|_| self.corrupt(format!("field `{name}` is {} bytes, not 8", v.len())))
    }

    fn text(&self, name: &'static str) -> Result<String, BagError> {
        String::from_utf8(self.field(name)?.to_vec())
            .map_err(|_| self.corrupt(format!("field `{name}` is not UTF-8")))
    }

    /// A ROS time field (`u32` seconds, `u32` nanoseconds) in ns.
    fn time_ns(&self, name: &'static str) -> Result<u64, BagError> {
        let raw = self.u64(name)?;
        let (sec, nsec) = (raw & 0xFFFF_FFFF, raw >> 32);
        Ok(sec * 1_000_000_000 + nsec)
    }
}

/// Walks the records of `bytes` (a file or an inflated chunk) from `start` to `end`; offsets in
/// errors are `base` + the position in `bytes`.
struct Records<'a> {
    bytes: &'a [u8],
    position: usize,
    end: usize,
    base: u64,
}

impl<'a> Records<'a> {
    fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], BagError> {
        let left = self.end - self.position;
        if n > left {
            return Err(BagError::Truncated {
                what,
                offset: self.base + self.position as u64,
                needed: n as u64,
                len: self.base + self.end as u64,
            });
        }
        let s = &self.bytes[self.position..self.position + n];
        self.position += n;
        Ok(s)
    }

    fn u32(&mut self, what: &'static str) -> Result<u32, BagError> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn next_record(&mut self) -> Result<Option<Record<'a>>, BagError> {
        if self.position >= self.end {
            return Ok(None);
        }
        let offset = self.base + self.position as u64;
        let header_len = self.u32("record header length")? as usize;
        let mut header = self.take(header_len, "record header")?;
        let data_len = self.u32("record data length")? as usize;
        let data = self.take(data_len, "record data")?;
        let mut fields = BTreeMap::new();
        while !header.is_empty() {
            let corrupt = |what: &str| BagError::Corrupt {
                offset,
                what: what.to_owned(),
            };
            let Some((len, rest)) = header.split_first_chunk::<4>() else {
                return Err(corrupt("record header ends inside a field length"));
            };
            let len = u32::from_le_bytes(*len) as usize;
            if len > rest.len() {
                return Err(corrupt("a header field runs past its record header"));
            }
            let (field, rest) = rest.split_at(len);
            let Some(eq) = field.iter().position(|&b| b == b'=') else {
                return Err(corrupt("a header field has no `=`"));
            };
            let name = std::str::from_utf8(&field[..eq])
                .map_err(|_| corrupt("a header field name is not UTF-8"))?;
            fields.insert(name, &field[eq + 1..]);
            header = rest;
        }
        Ok(Some(Record {
            offset,
            fields,
            data,
        }))
    }
}

impl<'a> Bag<'a> {
    /// Checks the magic and the bag header and reads the index section (connections, chunk
    /// infos).
    ///
    /// # Errors
    /// [`BagError::Magic`], [`BagError::Truncated`] (including an index past the end of the
    /// file), [`BagError::Corrupt`], [`BagError::Unindexed`].
    pub fn open(bytes: &'a [u8]) -> Result<Self, BagError> {
        if !bytes.starts_with(BAG_MAGIC) {
            let head = &bytes[..bytes.len().min(BAG_MAGIC.len())];
            return Err(BagError::Magic {
                found: String::from_utf8_lossy(head).trim_end().to_owned(),
            });
        }
        let mut records = Records {
            bytes,
            position: BAG_MAGIC.len(),
            end: bytes.len(),
            base: 0,
        };
        let header = records.next_record()?.ok_or(BagError::Truncated {
            what: "bag header record",
            offset: BAG_MAGIC.len() as u64,
            needed: 8,
            len: bytes.len() as u64,
        })?;
        if header.op()? != OP_BAG_HEADER {
            return Err(header.corrupt("the first record is not the bag header".to_owned()));
        }
        let index_pos = header.u64("index_pos")?;
        if index_pos == 0 {
            return Err(BagError::Unindexed);
        }
        if index_pos > bytes.len() as u64 || index_pos < records.position as u64 {
            return Err(BagError::Truncated {
                what: "index section",
                offset: index_pos,
                needed: 1,
                len: bytes.len() as u64,
            });
        }
        let index_pos = index_pos as usize;
        let mut bag = Self {
            bytes,
            records_start: records.position,
            index_pos,
            connections: BTreeMap::new(),
            expected_counts: BTreeMap::new(),
        };
        let mut index = Records {
            bytes,
            position: index_pos,
            end: bytes.len(),
            base: 0,
        };
        while let Some(record) = index.next_record()? {
            match record.op()? {
                OP_CONNECTION => {
                    let connection = connection_of(&record)?;
                    bag.connections.insert(connection.id, connection);
                }
                OP_CHUNK_INFO => bag.add_chunk_info(&record)?,
                _ => {}
            }
        }
        if let Some(id) = bag
            .expected_counts
            .keys()
            .find(|id| !bag.connections.contains_key(id))
        {
            return Err(BagError::Corrupt {
                offset: index_pos as u64,
                what: format!(
                    "chunk infos count messages of connection {id}, which has no connection record"
                ),
            });
        }
        Ok(bag)
    }

    fn add_chunk_info(&mut self, record: &Record<'_>) -> Result<(), BagError> {
        let count = record.u32("count")? as usize;
        if record.data.len() != count.saturating_mul(8) {
            return Err(record.corrupt(format!(
                "chunk info lists {count} connections in {} bytes",
                record.data.len()
            )));
        }
        for entry in record.data.chunks_exact(8) {
            let id = u32::from_le_bytes([entry[0], entry[1], entry[2], entry[3]]);
            let n = u32::from_le_bytes([entry[4], entry[5], entry[6], entry[7]]);
            *self.expected_counts.entry(id).or_default() += u64::from(n);
        }
        Ok(())
    }

    /// The connections, by id.
    pub fn connections(&self) -> &BTreeMap<u32, BagConnection> {
        &self.connections
    }

    /// Walks every chunk and keeps the messages of the connections `keep` accepts.
    ///
    /// # Errors
    /// [`BagError::Truncated`] / [`BagError::Corrupt`] for a record that breaks the format, a
    /// chunk that does not inflate to its declared size, a message of an unknown connection, or
    /// message counts that differ from the chunk infos'; [`BagError::Compression`] for an
    /// unknown compression.
    pub fn read_messages(&self, keep: impl Fn(u32) -> bool) -> Result<BagMessages, BagError> {
        let mut out = BagMessages::default();
        let mut records = Records {
            bytes: self.bytes,
            position: self.records_start,
            end: self.index_pos,
            base: 0,
        };
        while let Some(record) = records.next_record()? {
            match record.op()? {
                OP_CHUNK => {
                    let inflated = inflate(&record)?;
                    let mut inner = Records {
                        bytes: &inflated,
                        position: 0,
                        end: inflated.len(),
                        base: 0,
                    };
                    while let Some(r) = inner.next_record().map_err(|e| in_chunk(e, &record))? {
                        self.message(&r, &keep, &mut out)
                            .map_err(|e| in_chunk(e, &record))?;
                    }
                }
                OP_MESSAGE => self.message(&record, &keep, &mut out)?,
                OP_INDEX_DATA | OP_CONNECTION | OP_CHUNK_INFO | OP_BAG_HEADER => {}
                op => {
                    return Err(record.corrupt(format!("unknown record op {op:#04x}")));
                }
            }
        }
        if out.counts != self.expected_counts {
            return Err(BagError::Corrupt {
                offset: self.index_pos as u64,
                what: format!(
                    "the chunks hold {} messages, the index counts {}",
                    out.counts.values().sum::<u64>(),
                    self.expected_counts.values().sum::<u64>()
                ),
            });
        }
        Ok(out)
    }

    fn message(
        &self,
        record: &Record<'_>,
        keep: &impl Fn(u32) -> bool,
        out: &mut BagMessages,
    ) -> Result<(), BagError> {
        if record.op()? != OP_MESSAGE {
            return Ok(());
        }
        let id = record.u32("conn")?;
        if !self.connections.contains_key(&id) {
            return Err(record.corrupt(format!("message of unknown connection {id}")));
        }
        *out.counts.entry(id).or_default() += 1;
        if keep(id) {
            out.kept.push(BagMessage {
                connection: id,
                time_ns: record.time_ns("time")?,
                data: record.data.to_vec(),
            });
        }
        Ok(())
    }
}

/// The connection record's id, topic and type (from its data, a connection header).
fn connection_of(record: &Record<'_>) -> Result<BagConnection, BagError> {
    let id = record.u32("conn")?;
    let topic = record.text("topic")?;
    // The data is a connection header: `u32 len` + `name=value` fields.
    let mut message_type = None;
    let mut rest = record.data;
    while !rest.is_empty() {
        let Some((len, tail)) = rest.split_first_chunk::<4>() else {
            break;
        };
        let len = u32::from_le_bytes(*len) as usize;
        if len > tail.len() {
            break;
        }
        let (field, tail) = tail.split_at(len);
        if let Some(value) = field.strip_prefix(b"type=") {
            message_type = Some(String::from_utf8_lossy(value).into_owned());
        }
        rest = tail;
    }
    match message_type {
        Some(message_type) if rest.is_empty() => Ok(BagConnection {
            id,
            topic,
            message_type,
        }),
        _ => Err(record.corrupt(format!(
            "connection {id} ({topic}) has a malformed header or no `type`"
        ))),
    }
}

/// The chunk's records, inflated and checked against the declared size.
fn inflate(record: &Record<'_>) -> Result<Vec<u8>, BagError> {
    let size = record.u32("size")? as usize;
    let compression = record.text("compression")?;
    let limit = size as u64 + 1;
    // The declared size, up to 64 MiB (rosbag's chunks are 768 KiB): a corrupt size cannot
    // allocate more before the data proves it.
    let mut out = Vec::with_capacity(size.min(64 << 20));
    let result = match compression.as_str() {
        "none" => {
            out = record.data.to_vec();
            Ok(out.len())
        }
        "bz2" => bzip2::read::BzDecoder::new(record.data)
            .take(limit)
            .read_to_end(&mut out),
        "lz4" => lz4::Decoder::new(record.data).and_then(|d| d.take(limit).read_to_end(&mut out)),
        _ => {
            return Err(BagError::Compression {
                offset: record.offset,
                compression,
            })
        }
    };
    match result {
        Ok(n) if n == size => Ok(out),
        Ok(n) => Err(record.corrupt(format!(
            "{compression} chunk inflates to {n}{} bytes, it declares {size}",
            if n > size { "+" } else { "" }
        ))),
        Err(e) => Err(record.corrupt(format!("{compression} chunk does not inflate: {e}"))),
    }
}

/// An error inside a chunk, placed at the chunk's offset in the file.
fn in_chunk(error: BagError, chunk: &Record<'_>) -> BagError {
    match error {
        BagError::Truncated { what, offset, .. } => BagError::Corrupt {
            offset: chunk.offset,
            what: format!("chunk ends inside {what} (at byte {offset} of its records)"),
        },
        BagError::Corrupt { offset, what } => BagError::Corrupt {
            offset: chunk.offset,
            what: format!("{what} (at byte {offset} of the chunk's records)"),
        },
        other => other,
    }
}
